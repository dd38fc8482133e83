//! The statements and expressions of a checked program typed (IEC 61131-3, 3rd edition,
//! §7.3): names found in their scope, operators on the types they take, implicit conversions
//! only where they widen ([`Elem::widens_to`]), literals without a type taking their context's
//! where they fit, assignments only to what may be written, calls with their inputs and
//! outputs, loops' `EXIT`. Every error is reported at its place, and an expression already
//! found wrong does not report again through the expressions around it.

use std::collections::HashMap;

use crate::ast::{
    Arg, BinOp, CaseLabel, Expr, ExprKind, Lit, PouKind, Stmt, StmtKind, UnOp, VarKind,
};
use crate::check::{Checked, Location, Type, Var};
use crate::lexer::{Area, Size};
use crate::source::{Diagnostic, Span};
use crate::types::Elem;

/// The type of an expression.
#[derive(Clone, Debug, PartialEq)]
pub enum Ty {
    /// A declared type.
    Known(Type),
    /// An integer literal without a type: it takes the type its context needs, if it fits.
    IntLit(i128),
    /// A real literal without a type: REAL or LREAL as its context needs.
    RealLit,
    /// Already found wrong (reported): nothing more is said about it.
    Wrong,
}

impl Ty {
    fn elem(e: Elem) -> Ty {
        Ty::Known(Type::Elem(e))
    }

    /// The elementary type a value of this type computes in (a subrange's base).
    fn as_elem(&self) -> Option<Elem> {
        match self {
            Ty::Known(Type::Elem(e)) | Ty::Known(Type::Subrange(e, _, _)) => Some(*e),
            _ => None,
        }
    }
}

/// Every error in the statements of `checked`'s blocks.
pub fn typecheck(checked: &Checked) -> Vec<Diagnostic> {
    let mut errors = Vec::new();
    // Who calls which function, and where.
    let mut calls: Vec<(usize, usize, Span)> = Vec::new();
    for (index, pou) in checked.pous.iter().enumerate() {
        let mut t = Typer {
            c: checked,
            pou: index,
            locals: pou
                .vars
                .iter()
                .map(|v| (v.name.to_ascii_uppercase(), v))
                .collect(),
            errors: Vec::new(),
            loops: 0,
            calls: Vec::new(),
            counting: Vec::new(),
        };
        for v in &pou.vars {
            t.initial(v);
        }
        t.stmts(&pou.body);
        errors.append(&mut t.errors);
        calls.extend(t.calls.into_iter().map(|(to, at)| (index, to, at)));
    }
    let mut t = Typer {
        c: checked,
        pou: usize::MAX,
        locals: HashMap::new(),
        errors: Vec::new(),
        loops: 0,
        calls: Vec::new(),
        counting: Vec::new(),
    };
    for v in &checked.globals {
        t.initial(v);
    }
    errors.append(&mut t.errors);
    errors.extend(recursion(checked, &calls));
    errors.sort_by_key(|d| d.span.start);
    errors
}

/// The calls through which a function calls itself: a PLC program has no recursion (its
/// memory is fixed before it runs), so each such call is an error.
fn recursion(c: &Checked, calls: &[(usize, usize, Span)]) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    for &(from, to, at) in calls {
        // Does `to` reach `from` again?
        let mut seen = vec![false; c.pous.len()];
        let mut stack = vec![to];
        let mut back = false;
        while let Some(f) = stack.pop() {
            if f == from {
                back = true;
                break;
            }
            if std::mem::replace(&mut seen[f], true) {
                continue;
            }
            stack.extend(calls.iter().filter(|c| c.0 == f).map(|c| c.1));
        }
        if back {
            let (a, b) = (&c.pous[from].name, &c.pous[to].name);
            let how = if from == to {
                format!("`{a}` calls itself")
            } else {
                format!("`{a}` calls `{b}`, which calls `{a}` again")
            };
            out.push(Diagnostic::error(
                at,
                format!(
                    "{how}: a PLC program has no recursion (its memory is fixed before it runs)"
                ),
            ));
        }
    }
    out
}

struct Typer<'a> {
    c: &'a Checked,
    pou: usize,
    locals: HashMap<String, &'a Var>,
    errors: Vec<Diagnostic>,
    /// How many loops the statement is in (for EXIT and CONTINUE).
    loops: u32,
    /// The functions this block calls, and where.
    calls: Vec<(usize, Span)>,
    /// The control variables of the FOR loops the statement is in.
    counting: Vec<String>,
}

/// What a name is.
enum Found<'a> {
    Var(&'a Var),
    EnumValue(usize),
    Pou(usize),
    Nothing,
}

/// The name `e` is, through parentheses, if it is a bare name.
pub(crate) fn bare_name(e: &Expr) -> Option<&crate::ast::Ident> {
    match &e.kind {
        ExprKind::Name(i) => Some(i),
        ExprKind::Paren(x) => bare_name(x),
        _ => None,
    }
}

fn type_name(c: &Checked, t: &Type) -> String {
    match t {
        Type::Elem(e) => e.name().to_owned(),
        Type::Subrange(e, lo, hi) => format!("{e} ({lo}..{hi})"),
        Type::Enum(i) => match c.enums.get(*i).map(|e| e.name.as_str()) {
            Some("") | None => "an enumeration".to_owned(),
            Some(n) => n.to_owned(),
        },
        Type::Struct(i) => c.structs.get(*i).map_or("?".into(), |s| s.name.clone()),
        Type::Array(a) => format!("ARRAY OF {}", type_name(c, &a.elem)),
        Type::StdFb(f) => format!("{f:?}").to_ascii_uppercase(),
        Type::Fb(i) => c.pous.get(*i).map_or("?".into(), |p| p.name.clone()),
    }
}

impl<'a> Typer<'a> {
    fn error(&mut self, span: Span, message: impl Into<String>) {
        self.errors.push(Diagnostic::error(span, message));
    }

    fn name_of(&self, t: &Ty) -> String {
        match t {
            Ty::Known(t) => type_name(self.c, t),
            Ty::IntLit(_) => "an integer".into(),
            Ty::RealLit => "a real".into(),
            Ty::Wrong => "?".into(),
        }
    }

    /// What `key` names: a local, a global, the function's own result (inside it), an
    /// enumeration's value, a block; the first of these that has the name.
    fn find(&self, key: &str) -> Found<'a> {
        if let Some(v) = self.locals.get(key) {
            return Found::Var(v);
        }
        if let Some(v) = self
            .c
            .globals
            .iter()
            .find(|v| v.name.eq_ignore_ascii_case(key))
        {
            return Found::Var(v);
        }
        // Inside a function its name is its result, whatever enumeration has the name too.
        if self.c.pous.get(self.pou).is_some_and(|p| {
            matches!(p.kind, PouKind::Function(_)) && p.name.eq_ignore_ascii_case(key)
        }) {
            return Found::Pou(self.pou);
        }
        let mut in_enums = self
            .c
            .enums
            .iter()
            .enumerate()
            .filter(|(_, e)| e.values.iter().any(|(k, _)| k == key));
        if let Some((i, _)) = in_enums.next() {
            return Found::EnumValue(i);
        }
        if let Some(i) = self
            .c
            .pous
            .iter()
            .position(|p| p.name.eq_ignore_ascii_case(key))
        {
            return Found::Pou(i);
        }
        Found::Nothing
    }

    /// `v`'s initial value against its type.
    fn initial(&mut self, v: &Var) {
        if let Some(init) = &v.init {
            self.init_into(init, &v.ty);
        }
    }

    fn init_into(&mut self, init: &crate::ast::Init, ty: &Type) {
        use crate::ast::Init;
        match (init, ty) {
            (Init::Expr(e), _) => {
                let want = Ty::Known(ty.clone());
                let t = self.expr_into(e, &want);
                self.expect_into(&t, &want, e.span);
            }
            (Init::Array(elems, span), Type::Array(a)) => {
                let capacity =
                    self.c.elements(&Type::Array(a.clone())) / self.c.elements(&a.elem).max(1);
                let mut given: u64 = 0;
                for (count, value) in elems {
                    let n = match count {
                        Some(e) => match self.expr(e) {
                            Ty::IntLit(n) if n >= 0 => u64::try_from(n).unwrap_or(u64::MAX),
                            _ => {
                                self.error(
                                    e.span,
                                    "a repetition's count is a non-negative integer",
                                );
                                1
                            }
                        },
                        None => 1,
                    };
                    given = given.saturating_add(n);
                    self.init_into(value, &a.elem);
                }
                if given > capacity {
                    self.error(
                        *span,
                        format!("{given} initial values for an array of {capacity} elements"),
                    );
                }
            }
            (Init::Struct(fields, _), Type::Struct(i)) => {
                for (name, value) in fields {
                    let field = self.c.structs[*i]
                        .fields
                        .iter()
                        .find(|f| f.name.eq_ignore_ascii_case(&name.text))
                        .map(|f| f.ty.clone());
                    match field {
                        Some(t) => self.init_into(value, &t),
                        None => {
                            let n = self.c.structs[*i].name.clone();
                            self.error(name.span, format!("`{n}` has no field `{}`", name.text));
                        }
                    }
                }
            }
            (Init::Array(_, span), _) => self.error(*span, "`[…]` initialises an array"),
            (Init::Struct(_, span), _) => {
                self.error(*span, "`(field := …)` initialises a structure")
            }
        }
    }

    // ----- statements -----------------------------------------------------------------

    fn stmts(&mut self, stmts: &[Stmt]) {
        for s in stmts {
            self.stmt(s);
        }
    }

    fn stmt(&mut self, s: &Stmt) {
        match &s.kind {
            StmtKind::Assign { target, value } => {
                if let ExprKind::Name(i) = &target.kind {
                    if self.counting.contains(&i.key()) {
                        self.error(
                            i.span,
                            format!("`{}` counts the FOR loop around: its body does not assign it (use WHILE to step freely)", i.text),
                        );
                    }
                }
                let to = self.place(target);
                let from = self.expr_into(value, &to);
                self.expect_into(&from, &to, value.span);
            }
            StmtKind::Call(e) => {
                if let ExprKind::Call(callee, args) = &e.kind {
                    self.call(callee, args, e.span, true);
                }
            }
            StmtKind::If { arms, otherwise } => {
                for (cond, body) in arms {
                    self.condition(cond);
                    self.stmts(body);
                }
                self.stmts(otherwise);
            }
            StmtKind::Case {
                selector,
                arms,
                otherwise,
            } => {
                let sel = self.expr(selector);
                let ok = match &sel {
                    Ty::Wrong => false,
                    Ty::IntLit(_) => true,
                    Ty::Known(Type::Enum(_)) => true,
                    t => t.as_elem().is_some_and(Elem::is_int),
                };
                if !ok {
                    let n = self.name_of(&sel);
                    self.error(
                        selector.span,
                        format!("CASE selects on an integer or an enumeration, not {n}"),
                    );
                }
                // The labels' values seen so far, as ranges, to find one given twice.
                let mut seen: Vec<(i128, i128)> = Vec::new();
                for (labels, body) in arms {
                    for l in labels {
                        let values: Vec<&Expr> = match l {
                            CaseLabel::Value(v) => vec![v],
                            CaseLabel::Range(a, b) => vec![a, b],
                        };
                        let mut bounds = Vec::new();
                        for v in &values {
                            let t = self.expr_into(v, &sel);
                            if ok {
                                self.expect_into(&t, &sel, v.span);
                            }
                            bounds.push(self.label_value(v, &t));
                        }
                        let span = values[0].span.to(values[values.len() - 1].span);
                        if let [Some(lo), Some(hi)] | [Some(lo @ hi)] = bounds.as_slice() {
                            let (lo, hi) = (*lo, *hi);
                            if seen.iter().any(|&(a, b)| lo <= b && a <= hi) {
                                self.error(span, "this label's value is given above already");
                            }
                            seen.push((lo, hi));
                        }
                    }
                    self.stmts(body);
                }
                self.stmts(otherwise);
            }
            StmtKind::For {
                var,
                from,
                to,
                by,
                body,
            } => {
                let key = var.key();
                let control = match self.find(&key) {
                    Found::Var(v) if v.ty.as_int().is_some() && !v.constant => {
                        Ty::Known(v.ty.clone())
                    }
                    Found::Var(_) => {
                        self.error(
                            var.span,
                            format!("`{}` is no integer variable to count with", var.text),
                        );
                        Ty::Wrong
                    }
                    _ => {
                        self.error(var.span, format!("no variable is named `{}`", var.text));
                        Ty::Wrong
                    }
                };
                for e in [Some(from), Some(to), by.as_ref()].into_iter().flatten() {
                    let t = self.expr(e);
                    self.expect_into(&t, &control, e.span);
                }
                self.loops += 1;
                self.counting.push(key);
                self.stmts(body);
                self.counting.pop();
                self.loops -= 1;
            }
            StmtKind::While { cond, body } => {
                self.condition(cond);
                self.loops += 1;
                self.stmts(body);
                self.loops -= 1;
            }
            StmtKind::Repeat { body, until } => {
                self.loops += 1;
                self.stmts(body);
                self.loops -= 1;
                self.condition(until);
            }
            StmtKind::Exit | StmtKind::Continue => {
                if self.loops == 0 {
                    self.error(
                        s.span,
                        "EXIT and CONTINUE belong in a FOR, WHILE or REPEAT loop",
                    );
                }
            }
            StmtKind::Return | StmtKind::Empty => {}
        }
    }

    /// The number of a CASE label of type `t` (an integer literal, a signed one, or an
    /// enumeration's value), if it is a constant.
    fn label_value(&self, e: &Expr, t: &Ty) -> Option<i128> {
        match (&e.kind, t) {
            (_, Ty::IntLit(n)) => Some(*n),
            (ExprKind::Name(i), Ty::Known(Type::Enum(n))) => self.c.enums[*n]
                .values
                .iter()
                .find(|(k, _)| *k == i.key())
                .map(|&(_, v)| v),
            (ExprKind::Lit(Lit::Enum(_, v)), Ty::Known(Type::Enum(n))) => self.c.enums[*n]
                .values
                .iter()
                .find(|(k, _)| *k == v.key())
                .map(|&(_, v)| v),
            _ => None,
        }
    }

    fn condition(&mut self, e: &Expr) {
        let t = self.expr(e);
        if !matches!(t, Ty::Wrong) && t.as_elem() != Some(Elem::Bool) {
            let n = self.name_of(&t);
            self.error(e.span, format!("a condition is a BOOL, not {n}"));
        }
    }

    /// `true` (reported otherwise) if a value of type `from` may be stored into `to`.
    fn expect_into(&mut self, from: &Ty, to: &Ty, span: Span) -> bool {
        let fits = match (from, to) {
            (Ty::Wrong, _) | (_, Ty::Wrong) => return true,
            (Ty::IntLit(n), Ty::Known(Type::Subrange(_, lo, hi))) => (lo..=hi).contains(&n),
            (Ty::IntLit(n), t) => t.as_elem().is_some_and(|e| e.holds(*n) || e.is_real()),
            (Ty::RealLit, t) => t.as_elem().is_some_and(Elem::is_real),
            (Ty::Known(a), Ty::Known(b)) if a == b => true,
            (f, t) => match (f.as_elem(), t.as_elem()) {
                (Some(a), Some(b)) => a.widens_to(b),
                _ => false,
            },
        };
        if !fits {
            let (f, t) = (self.name_of(from), self.name_of(to));
            let hint = match (from.as_elem(), to.as_elem()) {
                (Some(a), Some(b)) if a != b => format!(" (convert it: {a}_TO_{b})"),
                _ => String::new(),
            };
            let what = match from {
                Ty::IntLit(n) => format!("{n} does not fit {t}"),
                _ => format!("a value of {f} cannot be stored into {t} without a conversion{hint}"),
            };
            self.error(span, what);
        }
        fits
    }

    /// The type of `e` as a place that is written to (reported if it cannot be).
    fn place(&mut self, e: &Expr) -> Ty {
        match &e.kind {
            ExprKind::Name(i) => match self.find(&i.key()) {
                Found::Var(v) if v.constant => {
                    self.error(i.span, format!("`{}` is a CONSTANT", i.text));
                    Ty::Wrong
                }
                Found::Var(v)
                    if matches!(v.at, Some(Location::InputBit(..) | Location::InputWord(_))) =>
                {
                    self.error(
                        i.span,
                        format!("`{}` is an input of the process image, read only", i.text),
                    );
                    Ty::Wrong
                }
                Found::Var(v) => Ty::Known(v.ty.clone()),
                Found::Pou(p)
                    if p == self.pou && matches!(self.c.pous[p].kind, PouKind::Function(_)) =>
                {
                    // A function's result is written under its name.
                    self.c.pous[p].result.clone().map_or(Ty::Wrong, Ty::Known)
                }
                _ => self.expr(e),
            },
            ExprKind::Direct(d) if d.area == Area::Input => {
                self.error(
                    e.span,
                    format!("`{d}` is an input of the process image, read only"),
                );
                Ty::Wrong
            }
            ExprKind::Paren(_)
            | ExprKind::Lit(_)
            | ExprKind::Call(..)
            | ExprKind::Unary(..)
            | ExprKind::Binary(..) => {
                self.error(
                    e.span,
                    "only a variable, a field, an element or a bit can be assigned to",
                );
                Ty::Wrong
            }
            _ => self.expr(e),
        }
    }

    // ----- expressions ----------------------------------------------------------------

    fn expr(&mut self, e: &Expr) -> Ty {
        match &e.kind {
            ExprKind::Lit(l) => self.lit(l, e.span),
            ExprKind::Paren(x) => self.expr(x),
            ExprKind::Name(i) => match self.find(&i.key()) {
                Found::Var(v) => Ty::Known(v.ty.clone()),
                Found::EnumValue(n) => Ty::Known(Type::Enum(n)),
                Found::Pou(p)
                    if p == self.pou && matches!(self.c.pous[p].kind, PouKind::Function(_)) =>
                {
                    self.c.pous[p].result.clone().map_or(Ty::Wrong, Ty::Known)
                }
                Found::Pou(_) => {
                    self.error(i.span, format!("`{}` is a block, not a value", i.text));
                    Ty::Wrong
                }
                Found::Nothing => {
                    self.error(i.span, format!("no variable is named `{}`", i.text));
                    Ty::Wrong
                }
            },
            ExprKind::Direct(d) => {
                if self
                    .c
                    .pous
                    .get(self.pou)
                    .is_none_or(|p| p.kind != PouKind::Program)
                {
                    self.error(
                        e.span,
                        "the process image is read and written in the PROGRAM",
                    );
                    return Ty::Wrong;
                }
                match (d.size, d.path.len()) {
                    (Size::Bit, 2) => Ty::elem(Elem::Bool),
                    (Size::Word, 1) => Ty::elem(Elem::Word),
                    _ => {
                        self.error(
                            e.span,
                            format!("`{d}`: the image is read as %IX<word>.<bit> or %IW<word>"),
                        );
                        Ty::Wrong
                    }
                }
            }
            ExprKind::Field(base, f) => {
                let b = self.expr(base);
                self.field(&b, f)
            }
            ExprKind::Bit(base, n) => {
                let b = self.expr(base);
                match b.as_elem().and_then(Elem::bits) {
                    Some(bits) if bits > 1 && *n < bits => Ty::elem(Elem::Bool),
                    Some(bits) if bits > 1 => {
                        self.error(e.span, format!("bit {n} of a {}-bit string", bits));
                        Ty::Wrong
                    }
                    _ if b == Ty::Wrong => Ty::Wrong,
                    _ => {
                        let t = self.name_of(&b);
                        self.error(
                            e.span,
                            format!("only a bit string (BYTE, WORD, …) has bits, not {t}"),
                        );
                        Ty::Wrong
                    }
                }
            }
            ExprKind::Index(base, idx) => {
                let b = self.expr(base);
                for i in idx {
                    let t = self.expr(i);
                    let int = matches!(t, Ty::IntLit(_) | Ty::Wrong)
                        || t.as_elem().is_some_and(Elem::is_int);
                    if !int {
                        let n = self.name_of(&t);
                        self.error(i.span, format!("an index is an integer, not {n}"));
                    }
                }
                match b {
                    Ty::Known(Type::Array(a)) => {
                        if a.dims.len() != idx.len() {
                            self.error(
                                e.span,
                                format!(
                                    "the array has {} dimensions, indexed with {}",
                                    a.dims.len(),
                                    idx.len()
                                ),
                            );
                        }
                        Ty::Known(a.elem.clone())
                    }
                    Ty::Wrong => Ty::Wrong,
                    other => {
                        let n = self.name_of(&other);
                        self.error(base.span, format!("only an array is indexed, not {n}"));
                        Ty::Wrong
                    }
                }
            }
            ExprKind::Call(callee, args) => self.call(callee, args, e.span, false),
            ExprKind::Unary(op, x) => {
                let t = self.expr(x);
                match (op, &t) {
                    (_, Ty::Wrong) => Ty::Wrong,
                    (UnOp::Neg | UnOp::Plus, Ty::IntLit(n)) => {
                        Ty::IntLit(if *op == UnOp::Neg { -n } else { *n })
                    }
                    (UnOp::Neg | UnOp::Plus, Ty::RealLit) => Ty::RealLit,
                    (UnOp::Neg | UnOp::Plus, t)
                        if t.as_elem().is_some_and(|e| e.is_num() || e.is_duration()) =>
                    {
                        let elem = t.as_elem().unwrap_or(Elem::Int);
                        if *op == UnOp::Neg && elem.int_range().is_some_and(|(lo, _)| lo == 0) {
                            self.error(
                                x.span,
                                format!("an unsigned {elem} has no negative values"),
                            );
                        }
                        Ty::elem(elem)
                    }
                    (UnOp::Not, t) if t.as_elem().is_some_and(Elem::is_bits) => {
                        Ty::elem(t.as_elem().unwrap_or(Elem::Bool))
                    }
                    (UnOp::Not, Ty::IntLit(_)) => {
                        self.error(e.span, "NOT takes a BOOL or a bit string; write the literal with its type (e.g. WORD#16#FF)");
                        Ty::Wrong
                    }
                    (op, t) => {
                        let n = self.name_of(t);
                        let what = if *op == UnOp::Not {
                            "a BOOL or a bit string"
                        } else {
                            "a number or a duration"
                        };
                        self.error(e.span, format!("this operator takes {what}, not {n}"));
                        Ty::Wrong
                    }
                }
            }
            ExprKind::Binary(op, a, b) => {
                // A bare enumeration value takes the other side's enumeration.
                let value = |t: &Self, x: &Expr| {
                    bare_name(x).is_some_and(|i| matches!(t.find(&i.key()), Found::EnumValue(_)))
                };
                let (ta, tb) = if value(self, a) && !value(self, b) {
                    let tb = self.expr(b);
                    (self.expr_into(a, &tb), tb)
                } else {
                    let ta = self.expr(a);
                    let tb = self.expr_into(b, &ta);
                    (ta, tb)
                };
                self.binary(*op, ta, tb, e.span)
            }
        }
    }

    /// `e` typed where a value of `want` is expected: a bare name that is no variable and is
    /// a value of `want`'s enumeration is that enumeration's (a value of two enumerations
    /// takes the one the context expects); anything else as [`Typer::expr`] types it.
    fn expr_into(&mut self, e: &Expr, want: &Ty) -> Ty {
        if let (Some(i), Ty::Known(Type::Enum(n))) = (bare_name(e), want) {
            let key = i.key();
            if matches!(self.find(&key), Found::EnumValue(_))
                && self.c.enums[*n].values.iter().any(|(k, _)| *k == key)
            {
                return Ty::Known(Type::Enum(*n));
            }
        }
        self.expr(e)
    }

    fn lit(&mut self, l: &Lit, span: Span) -> Ty {
        match l {
            Lit::Int(n, None) => Ty::IntLit(i128::from(*n)),
            Lit::Int(n, Some(ty)) => match Elem::of(&ty.key()) {
                Some(e) if e.is_int() || e.is_bits() => {
                    if !e.holds(i128::from(*n)) {
                        self.error(span, format!("{n} does not fit {e}"));
                        return Ty::Wrong;
                    }
                    Ty::elem(e)
                }
                Some(e) if e.is_real() => Ty::elem(e),
                _ => {
                    self.error(ty.span, format!("`{}#` names no integer type", ty.text));
                    Ty::Wrong
                }
            },
            Lit::Real(_, None) => Ty::RealLit,
            Lit::Real(_, Some(ty)) => match Elem::of(&ty.key()).filter(|e| e.is_real()) {
                Some(e) => Ty::elem(e),
                None => {
                    self.error(ty.span, format!("`{}#` names no real type", ty.text));
                    Ty::Wrong
                }
            },
            Lit::Bool(_) => Ty::elem(Elem::Bool),
            Lit::Time(_) => Ty::elem(Elem::Time),
            Lit::Str(_) => {
                self.error(span, "strings are not part of the language asi-lift runs");
                Ty::Wrong
            }
            Lit::Enum(ty, v) => {
                let found = self
                    .c
                    .enums
                    .iter()
                    .position(|e| e.name.eq_ignore_ascii_case(&ty.text));
                match found {
                    Some(i) if self.c.enums[i].values.iter().any(|(k, _)| *k == v.key()) => {
                        Ty::Known(Type::Enum(i))
                    }
                    Some(_) => {
                        self.error(v.span, format!("`{}` has no value `{}`", ty.text, v.text));
                        Ty::Wrong
                    }
                    None => {
                        self.error(ty.span, format!("no enumeration is named `{}`", ty.text));
                        Ty::Wrong
                    }
                }
            }
        }
    }

    /// `base.f`: a structure's field, or a block instance's input or output.
    fn field(&mut self, base: &Ty, f: &crate::ast::Ident) -> Ty {
        let key = f.key();
        match base {
            Ty::Wrong => Ty::Wrong,
            Ty::Known(Type::Struct(i)) => match self.c.structs[*i]
                .fields
                .iter()
                .find(|v| v.name.eq_ignore_ascii_case(&key))
            {
                Some(v) => Ty::Known(v.ty.clone()),
                None => {
                    let n = self.c.structs[*i].name.clone();
                    self.error(f.span, format!("`{n}` has no field `{}`", f.text));
                    Ty::Wrong
                }
            },
            Ty::Known(Type::StdFb(b)) => match b.pins().iter().find(|(n, _, _)| *n == key) {
                Some((_, e, _)) => Ty::elem(*e),
                None => {
                    self.error(
                        f.span,
                        format!(
                            "{} has no input or output `{}`",
                            type_name(self.c, &Type::StdFb(*b)),
                            f.text
                        ),
                    );
                    Ty::Wrong
                }
            },
            Ty::Known(Type::Fb(p)) => {
                let pou = &self.c.pous[*p];
                match pou.vars.iter().find(|v| v.name.eq_ignore_ascii_case(&key)) {
                    Some(v)
                        if matches!(v.kind, VarKind::Input | VarKind::Output | VarKind::InOut) =>
                    {
                        Ty::Known(v.ty.clone())
                    }
                    Some(_) => {
                        self.error(f.span, format!("`{}` is inside `{}`: only its inputs and outputs are seen from outside", f.text, pou.name));
                        Ty::Wrong
                    }
                    None => {
                        self.error(
                            f.span,
                            format!("`{}` has no input or output `{}`", pou.name, f.text),
                        );
                        Ty::Wrong
                    }
                }
            }
            other => {
                let n = self.name_of(other);
                self.error(f.span, format!("{n} has no fields"));
                Ty::Wrong
            }
        }
    }

    fn binary(&mut self, op: BinOp, a: Ty, b: Ty, span: Span) -> Ty {
        use BinOp::*;
        if a == Ty::Wrong || b == Ty::Wrong {
            return Ty::Wrong;
        }
        // Two enumeration values compare for equality when they are of one enumeration.
        if let (Ty::Known(Type::Enum(x)), Ty::Known(Type::Enum(y))) = (&a, &b) {
            if matches!(op, Eq | Ne) && x == y {
                return Ty::elem(Elem::Bool);
            }
        }
        // Durations: TIME ± TIME, TIME * or / a number, and comparisons.
        let time = |t: &Ty| t.as_elem().is_some_and(Elem::is_duration);
        let num = |t: &Ty| {
            matches!(t, Ty::IntLit(_) | Ty::RealLit) || t.as_elem().is_some_and(Elem::is_num)
        };
        if time(&a) || time(&b) {
            let ok = match op {
                Add | Sub | Lt | Gt | Le | Ge | Eq | Ne => time(&a) && time(&b),
                Mul | Div => time(&a) && num(&b),
                _ => false,
            };
            if !ok {
                let (x, y) = (self.name_of(&a), self.name_of(&b));
                self.error(span, format!("`{}` does not take {x} and {y}", op.text()));
                return Ty::Wrong;
            }
            return match op {
                Lt | Gt | Le | Ge | Eq | Ne => Ty::elem(Elem::Bool),
                _ => Ty::elem(a.as_elem().unwrap_or(Elem::Time)),
            };
        }
        let common = self.common(&a, &b);
        let Some(t) = common else {
            let (x, y) = (self.name_of(&a), self.name_of(&b));
            self.error(
                span,
                format!(
                    "`{}` has no common type for {x} and {y}: convert one of them",
                    op.text()
                ),
            );
            return Ty::Wrong;
        };
        let kind_ok = match op {
            Add | Sub | Mul | Div | Power => {
                matches!(t, Ty::IntLit(_) | Ty::RealLit) || t.as_elem().is_some_and(Elem::is_num)
            }
            Mod => matches!(t, Ty::IntLit(_)) || t.as_elem().is_some_and(Elem::is_int),
            And | Or | Xor => t.as_elem().is_some_and(Elem::is_bits),
            Lt | Gt | Le | Ge | Eq | Ne => true,
        };
        if !kind_ok {
            let n = self.name_of(&t);
            self.error(span, format!("`{}` does not take {n}", op.text()));
            return Ty::Wrong;
        }
        match op {
            Lt | Gt | Le | Ge | Eq | Ne => Ty::elem(Elem::Bool),
            Power => match t {
                Ty::IntLit(_) | Ty::RealLit => Ty::elem(Elem::Real),
                t if t.as_elem().is_some_and(Elem::is_real) => t,
                _ => Ty::elem(Elem::Real),
            },
            _ => t,
        }
    }

    /// The type two operands meet in, literals taking the other side's type where they fit.
    fn common(&mut self, a: &Ty, b: &Ty) -> Option<Ty> {
        match (a, b) {
            (Ty::IntLit(x), Ty::IntLit(y)) => Some(Ty::IntLit((*x).max(*y))),
            (Ty::RealLit, Ty::RealLit)
            | (Ty::RealLit, Ty::IntLit(_))
            | (Ty::IntLit(_), Ty::RealLit) => Some(Ty::RealLit),
            (Ty::IntLit(n), t) | (t, Ty::IntLit(n)) => {
                let e = t.as_elem()?;
                if e.holds(*n) || e.is_real() {
                    return Some(Ty::elem(e));
                }
                // A literal the other side cannot hold has the least type that holds it
                // (`i + 100000` with `i : INT` is a DINT), if the two meet.
                let own = [Elem::Sint, Elem::Int, Elem::Dint, Elem::Lint, Elem::Ulint]
                    .into_iter()
                    .find(|l| l.holds(*n))?;
                e.is_int()
                    .then(|| Elem::common(e, own))
                    .flatten()
                    .map(Ty::elem)
            }
            (Ty::RealLit, t) | (t, Ty::RealLit) => {
                t.as_elem().filter(|e| e.is_real()).map(Ty::elem)
            }
            _ => {
                let (x, y) = (a.as_elem()?, b.as_elem()?);
                Elem::common(x, y).map(Ty::elem)
            }
        }
    }

    /// A call of `callee` with `args`; `statement`: as a statement (a block instance may be
    /// called only so).
    fn call(&mut self, callee: &Expr, args: &[Arg], span: Span, statement: bool) -> Ty {
        let ExprKind::Name(name) = &callee.kind else {
            // A field or an element that is a block instance.
            let t = self.expr(callee);
            return self.instance_call(&t, args, span, statement);
        };
        let key = name.key();
        if let Some((from, to)) = Elem::conversion(&key) {
            return self.builtin_args(args, span, &[Some(from)], Ty::elem(to));
        }
        match key.as_str() {
            "ABS" | "MOVE" | "SQRT" => {
                let t = self.one_arg(args, span);
                let ok = matches!(t, Ty::IntLit(_) | Ty::RealLit | Ty::Wrong)
                    || t.as_elem().is_some_and(|e| e.is_num() || key == "MOVE");
                if !ok {
                    let n = self.name_of(&t);
                    self.error(span, format!("{key} takes a number, not {n}"));
                    return Ty::Wrong;
                }
                return t;
            }
            "MIN" | "MAX" | "LIMIT" | "SEL" | "MUX" => return self.select(&key, args, span),
            "SHL" | "SHR" | "ROL" | "ROR" => {
                let tys: Vec<Ty> = args.iter().map(|a| self.expr(&a.value)).collect();
                if tys.len() != 2 {
                    self.error(span, format!("{key}(IN, N) takes two inputs"));
                    return Ty::Wrong;
                }
                if !tys[0]
                    .as_elem()
                    .is_some_and(|e| e.is_bits() && e != Elem::Bool)
                    && tys[0] != Ty::Wrong
                {
                    let n = self.name_of(&tys[0]);
                    self.error(
                        args[0].value.span,
                        format!("{key} shifts a bit string (BYTE, WORD, …), not {n}"),
                    );
                    return Ty::Wrong;
                }
                return tys[0].clone();
            }
            _ => {}
        }
        // A called name is a function or a block instance, never an enumeration's value.
        let found = match self.find(&key) {
            Found::EnumValue(_) => self
                .c
                .pous
                .iter()
                .position(|p| p.name.eq_ignore_ascii_case(&key))
                .map_or(Found::Nothing, Found::Pou),
            f => f,
        };
        match found {
            Found::Pou(p) if matches!(self.c.pous[p].kind, PouKind::Function(_)) => {
                self.calls.push((p, span));
                let f = &self.c.pous[p];
                let inputs: Vec<&Var> =
                    f.vars.iter().filter(|v| v.kind == VarKind::Input).collect();
                self.pins(
                    args,
                    span,
                    &inputs
                        .iter()
                        .map(|v| (v.name.clone(), Ty::Known(v.ty.clone()), false))
                        .collect::<Vec<_>>(),
                );
                f.result.clone().map_or(Ty::Wrong, Ty::Known)
            }
            Found::Pou(_) => {
                self.error(
                    name.span,
                    format!("`{}` is a block type; call an instance of it", name.text),
                );
                Ty::Wrong
            }
            Found::Var(v) => {
                let t = Ty::Known(v.ty.clone());
                self.instance_call(&t, args, span, statement)
            }
            _ => {
                self.error(
                    name.span,
                    format!("no function or block instance is named `{}`", name.text),
                );
                for a in args {
                    self.expr(&a.value);
                }
                Ty::Wrong
            }
        }
    }

    fn instance_call(&mut self, t: &Ty, args: &[Arg], span: Span, statement: bool) -> Ty {
        let pins: Vec<(String, Ty, bool)> = match t {
            Ty::Known(Type::StdFb(b)) => b
                .pins()
                .iter()
                .map(|(n, e, out)| ((*n).to_owned(), Ty::elem(*e), *out))
                .collect(),
            Ty::Known(Type::Fb(p)) => self.c.pous[*p]
                .vars
                .iter()
                .filter(|v| matches!(v.kind, VarKind::Input | VarKind::Output | VarKind::InOut))
                .map(|v| {
                    (
                        v.name.to_ascii_uppercase(),
                        Ty::Known(v.ty.clone()),
                        v.kind == VarKind::Output,
                    )
                })
                .collect(),
            Ty::Wrong => return Ty::Wrong,
            other => {
                let n = self.name_of(other);
                self.error(
                    span,
                    format!("{n} is not called: only functions and function block instances are"),
                );
                return Ty::Wrong;
            }
        };
        if !statement {
            self.error(span, "a function block instance is called as a statement; read its outputs after the call");
            return Ty::Wrong;
        }
        for a in args {
            if a.name.is_none() {
                self.error(
                    a.value.span,
                    "a block instance's inputs are named: `IN := …`",
                );
            }
        }
        let named: Vec<(String, Ty, bool)> = pins;
        self.pins(args, span, &named);
        Ty::Wrong
    }

    /// Arguments `args` against `pins` (name, type, output).
    fn pins(&mut self, args: &[Arg], span: Span, pins: &[(String, Ty, bool)]) {
        let mut positional = pins.iter().filter(|p| !p.2);
        for a in args {
            let pin = match &a.name {
                Some(n) => match pins.iter().find(|p| p.0.eq_ignore_ascii_case(&n.text)) {
                    Some(p) => p,
                    None => {
                        self.error(
                            n.span,
                            format!("there is no input or output `{}` here", n.text),
                        );
                        self.expr(&a.value);
                        continue;
                    }
                },
                None => match positional.next() {
                    Some(p) => p,
                    None => {
                        self.error(a.value.span, "one argument too many");
                        continue;
                    }
                },
            };
            match (a.output, pin.2) {
                (true, true) => {
                    let to = self.place(&a.value);
                    self.expect_into(&pin.1, &to, a.value.span);
                }
                (false, false) => {
                    let from = self.expr_into(&a.value, &pin.1);
                    self.expect_into(&from, &pin.1, a.value.span);
                }
                (true, false) => self.error(
                    a.value.span,
                    format!("`{}` is an input: `{} := …`", pin.0, pin.0),
                ),
                (false, true) => self.error(
                    a.value.span,
                    format!("`{}` is an output: `{} => variable`", pin.0, pin.0),
                ),
            }
        }
        let _ = span;
    }

    fn one_arg(&mut self, args: &[Arg], span: Span) -> Ty {
        match args {
            [a] => self.expr(&a.value),
            _ => {
                self.error(span, "this function takes one input");
                Ty::Wrong
            }
        }
    }

    fn builtin_args(
        &mut self,
        args: &[Arg],
        span: Span,
        inputs: &[Option<Elem>],
        result: Ty,
    ) -> Ty {
        if args.len() != inputs.len() {
            self.error(
                span,
                format!("this function takes {} input(s)", inputs.len()),
            );
            return Ty::Wrong;
        }
        for (a, want) in args.iter().zip(inputs) {
            let t = self.expr(&a.value);
            if let Some(w) = want {
                let from_ok =
                    matches!(t, Ty::Wrong | Ty::IntLit(_) | Ty::RealLit) || t.as_elem() == Some(*w);
                if !from_ok {
                    let n = self.name_of(&t);
                    self.error(
                        a.value.span,
                        format!("this conversion takes a {w}, not {n}"),
                    );
                }
            }
        }
        result
    }

    /// MIN, MAX, LIMIT, SEL, MUX: the common type of the values chosen among.
    fn select(&mut self, key: &str, args: &[Arg], span: Span) -> Ty {
        let tys: Vec<Ty> = args.iter().map(|a| self.expr(&a.value)).collect();
        let (selector, values) = match key {
            "SEL" => (Some(Elem::Bool), 1),
            "MUX" => (None, 1),
            _ => (None, 0),
        };
        let least = match key {
            "LIMIT" => 3,
            "SEL" => 3,
            _ => 2,
        };
        if tys.len() < least || (key == "LIMIT" || key == "SEL") && tys.len() != least {
            self.error(
                span,
                format!(
                    "{key} takes {least}{} inputs",
                    if key == "LIMIT" || key == "SEL" {
                        ""
                    } else {
                        " or more"
                    }
                ),
            );
            return Ty::Wrong;
        }
        if values == 1 {
            let k = &tys[0];
            let ok = match selector {
                Some(Elem::Bool) => k.as_elem() == Some(Elem::Bool) || *k == Ty::Wrong,
                _ => {
                    matches!(k, Ty::IntLit(_) | Ty::Wrong) || k.as_elem().is_some_and(Elem::is_int)
                }
            };
            if !ok {
                let n = self.name_of(k);
                self.error(
                    args[0].value.span,
                    format!("{key}'s first input selects: not {n}"),
                );
            }
        }
        let mut t = tys[values].clone();
        for (u, a) in tys[values + 1..].iter().zip(&args[values + 1..]) {
            match self.common(&t, u) {
                Some(c) => t = c,
                None => {
                    let (x, y) = (self.name_of(&t), self.name_of(u));
                    self.error(
                        a.value.span,
                        format!("{key} chooses among values of one type: {x} and {y}"),
                    );
                    return Ty::Wrong;
                }
            }
        }
        t
    }
}

impl Type {
    /// The integer type of a value of this type (a subrange's base), if it is one.
    fn as_int(&self) -> Option<Elem> {
        match *self {
            Type::Elem(e) | Type::Subrange(e, _, _) if e.is_int() => Some(e),
            _ => None,
        }
    }
}
