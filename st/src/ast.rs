//! The syntax of a Structured Text source (IEC 61131-3, 3rd edition): program organisation
//! units, data types, variable declarations, statements and expressions, each with its place.

use crate::lexer::Direct;
use crate::source::Span;

/// A name and its place. Names are case-insensitive: [`Ident::key`] is the one to compare.
#[derive(Clone, Debug, PartialEq)]
pub struct Ident {
    /// As written.
    pub text: String,
    /// Where.
    pub span: Span,
}

impl Ident {
    /// The name to compare (upper case).
    pub fn key(&self) -> String {
        self.text.to_ascii_uppercase()
    }
}

/// A whole source: its declarations in order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Unit {
    /// The declarations.
    pub items: Vec<Item>,
}

/// A declaration at the top of a source.
#[derive(Clone, Debug, PartialEq)]
pub enum Item {
    /// `TYPE … END_TYPE`: one or more data types.
    Types(Vec<TypeDecl>),
    /// `VAR_GLOBAL … END_VAR`.
    Globals(VarBlock),
    /// A program, function or function block.
    Pou(Box<Pou>),
}

/// What kind of program organisation unit.
#[derive(Clone, Debug, PartialEq)]
pub enum PouKind {
    /// `PROGRAM`.
    Program,
    /// `FUNCTION name : type`.
    Function(TypeRef),
    /// `FUNCTION_BLOCK`.
    FunctionBlock,
}

/// A program organisation unit.
#[derive(Clone, Debug, PartialEq)]
pub struct Pou {
    /// Program, function (with its result type) or function block.
    pub kind: PouKind,
    /// Its name.
    pub name: Ident,
    /// Its variable blocks.
    pub vars: Vec<VarBlock>,
    /// Its body.
    pub body: Vec<Stmt>,
    /// From its first keyword to its last.
    pub span: Span,
}

/// The kind of a variable block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VarKind {
    /// `VAR`.
    Local,
    /// `VAR_INPUT`.
    Input,
    /// `VAR_OUTPUT`.
    Output,
    /// `VAR_IN_OUT`.
    InOut,
    /// `VAR_TEMP`.
    Temp,
    /// `VAR_GLOBAL`.
    Global,
    /// `VAR_EXTERNAL`.
    External,
}

/// A variable block.
#[derive(Clone, Debug, PartialEq)]
pub struct VarBlock {
    /// Which kind.
    pub kind: VarKind,
    /// `CONSTANT`.
    pub constant: bool,
    /// `RETAIN`.
    pub retain: bool,
    /// Its declarations.
    pub decls: Vec<VarDecl>,
    /// From its keyword to `END_VAR`.
    pub span: Span,
}

/// `a, b AT %IX0.1 : type := init;`
#[derive(Clone, Debug, PartialEq)]
pub struct VarDecl {
    /// The names declared.
    pub names: Vec<Ident>,
    /// `AT` a direct variable, and its place.
    pub at: Option<(Direct, Span)>,
    /// The type.
    pub ty: TypeRef,
    /// The initial value.
    pub init: Option<Init>,
    /// The declaration.
    pub span: Span,
}

/// A type as a declaration names or spells it.
#[derive(Clone, Debug, PartialEq)]
pub enum TypeRef {
    /// A named type: elementary, declared, or a function block.
    Named(Ident),
    /// `ARRAY [lo..hi, …] OF elem`.
    Array {
        /// The bounds of each dimension.
        dims: Vec<(Expr, Expr)>,
        /// The element type.
        elem: Box<TypeRef>,
        /// Where.
        span: Span,
    },
    /// `base (lo..hi)`.
    Subrange {
        /// The integer type it restricts.
        base: Ident,
        /// The least value.
        lo: Expr,
        /// The greatest value.
        hi: Expr,
        /// Where.
        span: Span,
    },
    /// `(a, b := 3, c)`: an enumeration spelt in place.
    Enum {
        /// Its values, with their numbers where given.
        values: Vec<(Ident, Option<Expr>)>,
        /// Where.
        span: Span,
    },
    /// `STRUCT … END_STRUCT` (in a `TYPE` declaration).
    Struct {
        /// Its fields.
        fields: Vec<VarDecl>,
        /// Where.
        span: Span,
    },
}

impl TypeRef {
    /// Where.
    pub fn span(&self) -> Span {
        match self {
            TypeRef::Named(i) => i.span,
            TypeRef::Array { span, .. }
            | TypeRef::Subrange { span, .. }
            | TypeRef::Enum { span, .. }
            | TypeRef::Struct { span, .. } => *span,
        }
    }
}

/// `name : type := init;` in a `TYPE` block.
#[derive(Clone, Debug, PartialEq)]
pub struct TypeDecl {
    /// The type's name.
    pub name: Ident,
    /// What it is.
    pub ty: TypeRef,
    /// Its initial value.
    pub init: Option<Init>,
    /// The declaration.
    pub span: Span,
}

/// An initial value.
#[derive(Clone, Debug, PartialEq)]
pub enum Init {
    /// An expression.
    Expr(Expr),
    /// `[a, b, n(c)]`: an array's elements, `n(c)` repeating `c` `n` times.
    Array(Vec<(Option<Expr>, Init)>, Span),
    /// `(a := x, b := y)`: a structure's fields.
    Struct(Vec<(Ident, Init)>, Span),
}

/// A statement.
#[derive(Clone, Debug, PartialEq)]
pub struct Stmt {
    /// What.
    pub kind: StmtKind,
    /// Where.
    pub span: Span,
}

/// The statements.
#[derive(Clone, Debug, PartialEq)]
pub enum StmtKind {
    /// `target := value`.
    Assign {
        /// A variable, a field or an element.
        target: Expr,
        /// The value.
        value: Expr,
    },
    /// A call as a statement: a function block instance's or a function's.
    Call(Expr),
    /// `IF … THEN … ELSIF … ELSE … END_IF`.
    If {
        /// Each condition and its statements, `IF` first.
        arms: Vec<(Expr, Vec<Stmt>)>,
        /// `ELSE`.
        otherwise: Vec<Stmt>,
    },
    /// `CASE selector OF … ELSE … END_CASE`.
    Case {
        /// The selector.
        selector: Expr,
        /// Each arm's labels and statements.
        arms: Vec<(Vec<CaseLabel>, Vec<Stmt>)>,
        /// `ELSE`.
        otherwise: Vec<Stmt>,
    },
    /// `FOR v := from TO to BY by DO … END_FOR`.
    For {
        /// The control variable.
        var: Ident,
        /// Its first value.
        from: Expr,
        /// Its last value.
        to: Expr,
        /// The step (1 if absent).
        by: Option<Expr>,
        /// The body.
        body: Vec<Stmt>,
    },
    /// `WHILE cond DO … END_WHILE`.
    While {
        /// The condition.
        cond: Expr,
        /// The body.
        body: Vec<Stmt>,
    },
    /// `REPEAT … UNTIL cond END_REPEAT`.
    Repeat {
        /// The body.
        body: Vec<Stmt>,
        /// The condition that ends it.
        until: Expr,
    },
    /// `EXIT`.
    Exit,
    /// `CONTINUE`.
    Continue,
    /// `RETURN`.
    Return,
    /// `;` alone.
    Empty,
}

/// A label of a `CASE` arm.
#[derive(Clone, Debug, PartialEq)]
pub enum CaseLabel {
    /// One value.
    Value(Expr),
    /// `lo..hi`.
    Range(Expr, Expr),
}

/// An expression.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    /// What.
    pub kind: ExprKind,
    /// Where.
    pub span: Span,
}

/// The expressions.
#[derive(Clone, Debug, PartialEq)]
pub enum ExprKind {
    /// A literal.
    Lit(Lit),
    /// A name: a variable, a constant, an enumeration value.
    Name(Ident),
    /// A direct variable (`%IX1.2`).
    Direct(Direct),
    /// `base.field`, or `base.n` (a bit of a bit string).
    Field(Box<Expr>, Ident),
    /// `base.%Xn`, or `base.n`: bit `n` of a bit string.
    Bit(Box<Expr>, u32),
    /// `base[i, …]`.
    Index(Box<Expr>, Vec<Expr>),
    /// `name(args)`: a function's or a function block instance's call.
    Call(Box<Expr>, Vec<Arg>),
    /// `op operand`.
    Unary(UnOp, Box<Expr>),
    /// `left op right`.
    Binary(BinOp, Box<Expr>, Box<Expr>),
    /// `(inner)`.
    Paren(Box<Expr>),
}

/// An argument of a call.
#[derive(Clone, Debug, PartialEq)]
pub struct Arg {
    /// `name :=` (an input) or `name =>` (an output), `None` for a positional one.
    pub name: Option<Ident>,
    /// `=>`: an output written to `value`.
    pub output: bool,
    /// The value (for an output: where it goes).
    pub value: Expr,
}

/// A literal.
#[derive(Clone, Debug, PartialEq)]
pub enum Lit {
    /// An integer's magnitude, with its type where written (`INT#5`).
    Int(u64, Option<Ident>),
    /// A real, with its type where written.
    Real(f64, Option<Ident>),
    /// `TRUE`, `FALSE` (or `BOOL#1`).
    Bool(bool),
    /// A duration, nanoseconds.
    Time(i64),
    /// A string.
    Str(String),
    /// `Type#value`: an enumeration's value named with its type.
    Enum(Ident, Ident),
}

/// A unary operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UnOp {
    /// `-`.
    Neg,
    /// `+`.
    Plus,
    /// `NOT`.
    Not,
}

/// A binary operator, in the standard's order of precedence (table 71 of IEC 61131-3,
/// 3rd edition), weakest last.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum BinOp {
    Power,
    Mul,
    Div,
    Mod,
    Add,
    Sub,
    Lt,
    Gt,
    Le,
    Ge,
    Eq,
    Ne,
    And,
    Xor,
    Or,
}

impl BinOp {
    /// How it is written.
    pub fn text(self) -> &'static str {
        match self {
            BinOp::Power => "**",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Mod => "MOD",
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Lt => "<",
            BinOp::Gt => ">",
            BinOp::Le => "<=",
            BinOp::Ge => ">=",
            BinOp::Eq => "=",
            BinOp::Ne => "<>",
            BinOp::And => "AND",
            BinOp::Xor => "XOR",
            BinOp::Or => "OR",
        }
    }
}
