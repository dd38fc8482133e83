//! The declarations of a program, checked and resolved: the data types of `TYPE` blocks, the
//! program organisation units, and every variable with its type, its kind and, for a located
//! variable, its place in the master's process image (seed 003, table 4.1: the input and the
//! output image are words, `%IW<word>`/`%IX<word>.<bit>` and `%QW<word>`/`%QX<word>.<bit>`).
//!
//! Every error is reported at its place, and checking goes on after it, as the parser does.
//! Sizes are bounded ([`MAX_ELEMENTS`]): a hostile declaration is refused, never allocated.

use std::collections::HashMap;

use crate::ast::{self, Expr, ExprKind, Ident, Item, Lit, PouKind, TypeRef, UnOp, VarKind};
use crate::lexer::{Area, Size};
use crate::source::{Diagnostic, Span};
use crate::types::Elem;

/// The most elements a variable (an array, a structure, all nested) may have: far beyond a
/// lift program's few hundred, and small enough that every variable fits in memory at once.
pub const MAX_ELEMENTS: u64 = 1 << 20;

/// The words of the input and of the output image (seed 003, §4: 244 words for a master of
/// revision 1.3 or later).
pub const IMAGE_WORDS: u32 = 244;

/// A standard function block (IEC 61131-3, 3rd edition, §6.6.3.5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[allow(missing_docs)]
pub enum StdFb {
    Ton,
    Tof,
    Tp,
    RTrig,
    FTrig,
    Sr,
    Rs,
    Ctu,
    Ctd,
    Ctud,
}

impl StdFb {
    /// Its inputs and outputs, in order (IEC 61131-3, 3rd edition, §6.6.3.5): name, type,
    /// and whether it is an output. A standard block's frame holds them in this order.
    pub fn pins(self) -> &'static [(&'static str, Elem, bool)] {
        use Elem::{Bool, Int, Time};
        match self {
            StdFb::Ton | StdFb::Tof | StdFb::Tp => &[
                ("IN", Bool, false),
                ("PT", Time, false),
                ("Q", Bool, true),
                ("ET", Time, true),
            ],
            StdFb::RTrig | StdFb::FTrig => &[("CLK", Bool, false), ("Q", Bool, true)],
            StdFb::Sr => &[("S1", Bool, false), ("R", Bool, false), ("Q1", Bool, true)],
            StdFb::Rs => &[("S", Bool, false), ("R1", Bool, false), ("Q1", Bool, true)],
            StdFb::Ctu => &[
                ("CU", Bool, false),
                ("R", Bool, false),
                ("PV", Int, false),
                ("Q", Bool, true),
                ("CV", Int, true),
            ],
            StdFb::Ctd => &[
                ("CD", Bool, false),
                ("LD", Bool, false),
                ("PV", Int, false),
                ("Q", Bool, true),
                ("CV", Int, true),
            ],
            StdFb::Ctud => &[
                ("CU", Bool, false),
                ("CD", Bool, false),
                ("R", Bool, false),
                ("LD", Bool, false),
                ("PV", Int, false),
                ("QU", Bool, true),
                ("QD", Bool, true),
                ("CV", Int, true),
            ],
        }
    }

    /// The block named `name` (any case).
    pub fn of(name: &str) -> Option<StdFb> {
        Some(match name.to_ascii_uppercase().as_str() {
            "TON" => StdFb::Ton,
            "TOF" => StdFb::Tof,
            "TP" => StdFb::Tp,
            "R_TRIG" => StdFb::RTrig,
            "F_TRIG" => StdFb::FTrig,
            "SR" => StdFb::Sr,
            "RS" => StdFb::Rs,
            "CTU" => StdFb::Ctu,
            "CTD" => StdFb::Ctd,
            "CTUD" => StdFb::Ctud,
            _ => return None,
        })
    }
}

/// A resolved type.
#[derive(Clone, Debug, PartialEq)]
pub enum Type {
    /// An elementary type.
    Elem(Elem),
    /// A subrange of an integer type: `base (lo..hi)`.
    Subrange(Elem, i128, i128),
    /// An enumeration: its index in [`Checked::enums`].
    Enum(usize),
    /// A structure: its index in [`Checked::structs`].
    Struct(usize),
    /// An array.
    Array(Box<Array>),
    /// An instance of a standard function block.
    StdFb(StdFb),
    /// An instance of a function block of the program: its index in [`Checked::pous`].
    Fb(usize),
}

/// An array type: its bounds per dimension and its element type.
#[derive(Clone, Debug, PartialEq)]
pub struct Array {
    /// The least and the greatest index of each dimension.
    pub dims: Vec<(i128, i128)>,
    /// The elements' type.
    pub elem: Type,
}

/// An enumeration.
#[derive(Clone, Debug, PartialEq)]
pub struct EnumDef {
    /// Its name (as written; empty for one spelt in a variable's declaration).
    pub name: String,
    /// Its values' names (upper case) and numbers, in order.
    pub values: Vec<(String, i128)>,
}

/// A structure.
#[derive(Clone, Debug, PartialEq)]
pub struct StructDef {
    /// Its name.
    pub name: String,
    /// Its fields.
    pub fields: Vec<Var>,
}

/// Where a located variable is in the process image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// `%IX<word>.<bit>`.
    InputBit(u32, u32),
    /// `%IW<word>`.
    InputWord(u32),
    /// `%QX<word>.<bit>`.
    OutputBit(u32, u32),
    /// `%QW<word>`.
    OutputWord(u32),
}

/// A variable (or a structure's field).
#[derive(Clone, Debug, PartialEq)]
pub struct Var {
    /// Its name as written.
    pub name: String,
    /// Its kind.
    pub kind: VarKind,
    /// `CONSTANT`.
    pub constant: bool,
    /// Its type.
    pub ty: Type,
    /// Its place in the process image, if located.
    pub at: Option<Location>,
    /// Its initial value as declared.
    pub init: Option<ast::Init>,
    /// Its declaration's name.
    pub span: Span,
}

/// A program organisation unit with its variables resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct Pou {
    /// Its name as written.
    pub name: String,
    /// Program, function or function block.
    pub kind: PouKind,
    /// A function's result type.
    pub result: Option<Type>,
    /// Its variables, in declaration order.
    pub vars: Vec<Var>,
    /// Its statements.
    pub body: Vec<ast::Stmt>,
}

/// A program's declarations, checked.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Checked {
    /// The enumerations.
    pub enums: Vec<EnumDef>,
    /// The structures.
    pub structs: Vec<StructDef>,
    /// The global variables.
    pub globals: Vec<Var>,
    /// The programs, functions and function blocks.
    pub pous: Vec<Pou>,
}

impl Checked {
    /// The one program.
    pub fn program(&self) -> Option<&Pou> {
        self.pous.iter().find(|p| p.kind == PouKind::Program)
    }

    /// How many scalar elements a value of `ty` has (an array's or a structure's, nested);
    /// `u64::MAX` for a type nested beyond reason (a block that contains itself).
    pub fn elements(&self, ty: &Type) -> u64 {
        self.elements_within(ty, 0)
    }

    fn elements_within(&self, ty: &Type, depth: u32) -> u64 {
        if depth > 64 {
            return u64::MAX;
        }
        let elements = |t: &Type| self.elements_within(t, depth + 1);
        match ty {
            Type::Array(a) => {
                let n: u64 = a
                    .dims
                    .iter()
                    .map(|&(lo, hi)| u64::try_from(hi - lo + 1).unwrap_or(u64::MAX))
                    .fold(1u64, u64::saturating_mul);
                n.saturating_mul(elements(&a.elem))
            }
            Type::Struct(i) => self.structs.get(*i).map_or(1, |s| {
                s.fields
                    .iter()
                    .map(|f| elements(&f.ty))
                    .fold(0u64, u64::saturating_add)
            }),
            Type::Fb(i) => self.pous.get(*i).map_or(1, |p| {
                p.vars
                    .iter()
                    .map(|v| elements(&v.ty))
                    .fold(0u64, u64::saturating_add)
            }),
            _ => 1,
        }
    }
}

/// The declarations of `unit` checked and resolved, and every error found.
pub fn check(unit: &ast::Unit) -> (Checked, Vec<Diagnostic>) {
    let mut c = Checker {
        out: Checked::default(),
        errors: Vec::new(),
        type_decls: HashMap::new(),
        resolved: HashMap::new(),
        resolving: Vec::new(),
        pou_index: HashMap::new(),
        constants: HashMap::new(),
    };
    c.run(unit);
    let mut errors = c.errors;
    errors.sort_by_key(|d| d.span.start);
    (c.out, errors)
}

struct Checker<'a> {
    out: Checked,
    errors: Vec<Diagnostic>,
    /// The `TYPE` declarations by name (upper case).
    type_decls: HashMap<String, &'a ast::TypeDecl>,
    /// The declared types resolved so far.
    resolved: HashMap<String, Type>,
    /// The declared types being resolved (to find a type that contains itself).
    resolving: Vec<String>,
    /// The function blocks and functions by name.
    pou_index: HashMap<String, usize>,
    /// The global constants' integer values, for bounds.
    constants: HashMap<String, i128>,
}

impl<'a> Checker<'a> {
    fn error(&mut self, span: Span, message: impl Into<String>) {
        self.errors.push(Diagnostic::error(span, message));
    }

    fn run(&mut self, unit: &'a ast::Unit) {
        // Names first, so that declarations may refer to each other in any order.
        let mut names: HashMap<String, Span> = HashMap::new();
        let mut declare = |c: &mut Checker<'a>, i: &Ident, what: &str| {
            let key = i.key();
            if Elem::of(&key).is_some() || StdFb::of(&key).is_some() {
                c.error(
                    i.span,
                    format!("`{}` is a standard {what}'s name already", i.text),
                );
                return false;
            }
            if let Some(first) = names.get(&key) {
                let _ = first;
                c.error(i.span, format!("`{}` is declared twice", i.text));
                return false;
            }
            names.insert(key, i.span);
            true
        };
        for item in &unit.items {
            match item {
                Item::Types(ts) => {
                    for t in ts {
                        if declare(self, &t.name, "type") {
                            self.type_decls.insert(t.name.key(), t);
                        }
                    }
                }
                Item::Pou(p) => {
                    if declare(self, &p.name, "block") {
                        // Placeholders, filled below, so that blocks may use each other.
                        self.pou_index.insert(p.name.key(), self.out.pous.len());
                        self.out.pous.push(Pou {
                            name: p.name.text.clone(),
                            kind: p.kind.clone(),
                            result: None,
                            vars: Vec::new(),
                            body: p.body.clone(),
                        });
                    }
                }
                Item::Globals(_) => {}
            }
        }
        let programs: Vec<&ast::Pou> = unit
            .items
            .iter()
            .filter_map(|i| match i {
                Item::Pou(p) if p.kind == PouKind::Program => Some(&**p),
                _ => None,
            })
            .collect();
        match programs.as_slice() {
            [] => self.error(
                Span::default(),
                "the source has no PROGRAM: the PLC needs one to run",
            ),
            [_] => {}
            [_, more @ ..] => {
                for p in more {
                    self.error(p.name.span, "a second PROGRAM: the PLC runs one program");
                }
            }
        }
        // The global integer constants, in order (one may use those before it), so that
        // types' bounds may use them.
        for item in &unit.items {
            let Item::Globals(b) = item else { continue };
            if !b.constant {
                continue;
            }
            for d in &b.decls {
                let int = matches!(&d.ty, TypeRef::Named(t) if Elem::of(&t.key()).is_some_and(Elem::is_int));
                if let (true, Some(ast::Init::Expr(e))) = (int, &d.init) {
                    if let Some(n) = self.const_int(e) {
                        for name in &d.names {
                            self.constants.insert(name.key(), n);
                        }
                    }
                }
            }
        }
        // In name order, so that the errors and the indices do not depend on a hash's order.
        let mut keys: Vec<String> = self.type_decls.keys().cloned().collect();
        keys.sort();
        for k in keys {
            self.resolve_declared(&k);
        }
        for item in &unit.items {
            if let Item::Globals(b) = item {
                let vars = self.vars(std::slice::from_ref(b), true);
                self.out.globals.extend(vars);
            }
        }
        for item in &unit.items {
            let Item::Pou(p) = item else { continue };
            let Some(&index) = self.pou_index.get(&p.name.key()) else {
                continue;
            };
            let is_program = p.kind == PouKind::Program;
            let result = match &p.kind {
                PouKind::Function(t) => self.resolve(t),
                _ => None,
            };
            let vars = self.vars(&p.vars, is_program);
            for v in &vars {
                let stateful = matches!(v.ty, Type::Fb(_) | Type::StdFb(_));
                if matches!(p.kind, PouKind::Function(_)) && stateful {
                    self.error(
                        v.span,
                        format!(
                            "`{}` is a function block instance in a FUNCTION, which keeps nothing between calls: declare it in a FUNCTION_BLOCK or the PROGRAM",
                            v.name
                        ),
                    );
                }
            }
            let pou = &mut self.out.pous[index];
            pou.result = result;
            pou.vars = vars;
        }
        // A block that holds an instance of itself, at any depth, has no size.
        for start in 0..self.out.pous.len() {
            let mut path = vec![start];
            if let Some(var) = self.cycle_from(start, &mut path) {
                let (pou, v) = var;
                let (span, name) = {
                    let v = &self.out.pous[pou].vars[v];
                    (v.span, v.name.clone())
                };
                let block = self.out.pous[start].name.clone();
                self.error(
                    span,
                    format!("`{name}` makes `{block}` hold an instance of itself"),
                );
                // Cut the cycle, so that nothing below walks it.
                self.out.pous[pou].vars.remove(v);
            }
        }
        // A variable too large to hold, counted once every block is known.
        let sizes: Vec<(Span, String, u64)> = self
            .out
            .pous
            .iter()
            .flat_map(|p| p.vars.iter())
            .chain(self.out.globals.iter())
            .map(|v| (v.span, v.name.clone(), self.out.elements(&v.ty)))
            .collect();
        for (span, name, n) in sizes {
            if n > MAX_ELEMENTS {
                self.error(
                    span,
                    format!("`{name}` has {n} elements: more than the {MAX_ELEMENTS} a variable may have"),
                );
            }
        }
    }

    /// A variable (block, index) on a path of instances from the block `path` ends with back
    /// to the block it starts with.
    fn cycle_from(&self, at: usize, path: &mut Vec<usize>) -> Option<(usize, usize)> {
        fn instances(t: &Type) -> Option<usize> {
            match t {
                Type::Fb(i) => Some(*i),
                Type::Array(a) => instances(&a.elem),
                _ => None,
            }
        }
        for (vi, v) in self.out.pous[at].vars.iter().enumerate() {
            let Some(next) = instances(&v.ty) else {
                continue;
            };
            if next == path[0] {
                return Some((at, vi));
            }
            if path.contains(&next) || path.len() > 64 {
                continue;
            }
            path.push(next);
            let found = self.cycle_from(next, path);
            path.pop();
            if found.is_some() {
                return found;
            }
        }
        None
    }

    /// The variables of `blocks`; `located`: `AT` is allowed (the program and the globals).
    fn vars(&mut self, blocks: &[ast::VarBlock], located: bool) -> Vec<Var> {
        let mut out: Vec<Var> = Vec::new();
        for b in blocks {
            if b.kind == VarKind::InOut {
                // Refused rather than run as a copy, which would not write back.
                self.error(
                    b.span,
                    "VAR_IN_OUT is not run by asi-lift yet: pass the value as a VAR_INPUT and read it back from a VAR_OUTPUT",
                );
                continue;
            }
            for d in &b.decls {
                let ty = self.resolve(&d.ty);
                let at = d.at.as_ref().and_then(|(direct, span)| {
                    if !located {
                        self.error(
                            *span,
                            "a located variable (AT) belongs in the PROGRAM or VAR_GLOBAL, not in a function or function block",
                        );
                        return None;
                    }
                    if d.names.len() > 1 {
                        self.error(*span, "one place in the image cannot hold several variables");
                        return None;
                    }
                    self.location(direct, *span, ty.as_ref())
                });
                for name in &d.names {
                    if out.iter().any(|v| v.name.eq_ignore_ascii_case(&name.text)) {
                        self.error(
                            name.span,
                            format!("`{}` is declared twice in this block", name.text),
                        );
                        continue;
                    }
                    let Some(ty) = ty.clone() else { continue };
                    out.push(Var {
                        name: name.text.clone(),
                        kind: b.kind,
                        constant: b.constant,
                        ty,
                        at,
                        init: d.init.clone(),
                        span: name.span,
                    });
                }
            }
        }
        out
    }

    /// `direct` (at `span`) as a place in the process image, for a variable of type `ty`.
    fn location(
        &mut self,
        direct: &crate::lexer::Direct,
        span: Span,
        ty: Option<&Type>,
    ) -> Option<Location> {
        let input = match direct.area {
            Area::Input => true,
            Area::Output => false,
            Area::Memory => {
                self.error(
                    span,
                    "asi-lift maps %I and %Q to the master's process image; %M has no place there",
                );
                return None;
            }
        };
        let (word, bit) = match (direct.size, direct.path.as_slice()) {
            (Size::Bit, [w, b]) => (*w, Some(*b)),
            (Size::Word, [w]) => (*w, None),
            (Size::Bit, _) => {
                self.error(
                    span,
                    format!("`{direct}`: a bit is %IX<word>.<bit> or %QX<word>.<bit>"),
                );
                return None;
            }
            (Size::Word, _) => {
                self.error(
                    span,
                    format!("`{direct}`: a word is %IW<word> or %QW<word>"),
                );
                return None;
            }
            _ => {
                self.error(span, format!("`{direct}`: the process image is mapped in words (%IW, %QW) and bits (%IX, %QX)"));
                return None;
            }
        };
        if word >= IMAGE_WORDS {
            self.error(
                span,
                format!("`{direct}`: the image has words 0 to {}", IMAGE_WORDS - 1),
            );
            return None;
        }
        if bit.is_some_and(|b| b > 15) {
            self.error(span, format!("`{direct}`: a word has bits 0 to 15"));
            return None;
        }
        let fits = match (bit.is_some(), ty) {
            (true, Some(Type::Elem(Elem::Bool))) => true,
            (false, Some(Type::Elem(e))) => matches!(e, Elem::Word | Elem::Int | Elem::Uint),
            (_, None) => return None,
            _ => false,
        };
        if !fits {
            let want = if bit.is_some() {
                "BOOL"
            } else {
                "WORD, INT or UINT"
            };
            self.error(span, format!("`{direct}` holds a {want}"));
            return None;
        }
        Some(match (input, bit) {
            (true, Some(b)) => Location::InputBit(word, b),
            (true, None) => Location::InputWord(word),
            (false, Some(b)) => Location::OutputBit(word, b),
            (false, None) => Location::OutputWord(word),
        })
    }

    /// The declared type named `key`, resolved once.
    fn resolve_declared(&mut self, key: &str) -> Option<Type> {
        if let Some(t) = self.resolved.get(key) {
            return Some(t.clone());
        }
        let decl = *self.type_decls.get(key)?;
        if self.resolving.iter().any(|k| k == key) {
            self.error(
                decl.name.span,
                format!("`{}` contains itself", decl.name.text),
            );
            return None;
        }
        self.resolving.push(key.to_owned());
        let ty = match &decl.ty {
            TypeRef::Enum { values, .. } => Some(self.enumeration(&decl.name.text, values)),
            TypeRef::Struct { fields, .. } => {
                let index = self.out.structs.len();
                self.out.structs.push(StructDef {
                    name: decl.name.text.clone(),
                    fields: Vec::new(),
                });
                // A field of the structure's own type is found on the stack of types being
                // resolved: a structure that contains itself has no size.
                let block = ast::VarBlock {
                    kind: VarKind::Local,
                    constant: false,
                    retain: false,
                    decls: fields.clone(),
                    span: decl.span,
                };
                let fields = self.vars(std::slice::from_ref(&block), false);
                self.out.structs[index].fields = fields;
                Some(Type::Struct(index))
            }
            other => self.resolve(other),
        };
        self.resolving.pop();
        if let Some(t) = &ty {
            self.resolved.insert(key.to_owned(), t.clone());
        }
        ty
    }

    fn enumeration(&mut self, name: &str, values: &[(Ident, Option<Expr>)]) -> Type {
        let mut out: Vec<(String, i128)> = Vec::new();
        let mut next = 0i128;
        for (v, value) in values {
            let n = match value {
                Some(e) => self.const_int(e).unwrap_or(next),
                None => next,
            };
            if out.iter().any(|(k, _)| *k == v.key()) {
                self.error(v.span, format!("`{}` is twice in this enumeration", v.text));
                continue;
            }
            out.push((v.key(), n));
            next = n + 1;
        }
        self.out.enums.push(EnumDef {
            name: name.to_owned(),
            values: out,
        });
        Type::Enum(self.out.enums.len() - 1)
    }

    /// The type `t` spells, or why not (reported).
    fn resolve(&mut self, t: &TypeRef) -> Option<Type> {
        match t {
            TypeRef::Named(i) => {
                let key = i.key();
                if let Some(e) = Elem::of(&key) {
                    return Some(Type::Elem(e));
                }
                if let Some(f) = StdFb::of(&key) {
                    return Some(Type::StdFb(f));
                }
                if self.type_decls.contains_key(&key) {
                    if self.resolving.contains(&key) {
                        self.error(i.span, format!("`{}` contains itself", i.text));
                        return None;
                    }
                    return self.resolve_declared(&key);
                }
                if let Some(&p) = self.pou_index.get(&key) {
                    if self.out.pous[p].kind == PouKind::FunctionBlock {
                        return Some(Type::Fb(p));
                    }
                    self.error(
                        i.span,
                        format!(
                            "`{}` is a {}, not a type",
                            i.text,
                            kind_name(&self.out.pous[p].kind)
                        ),
                    );
                    return None;
                }
                if [
                    "STRING",
                    "WSTRING",
                    "DATE",
                    "TOD",
                    "DT",
                    "TIME_OF_DAY",
                    "DATE_AND_TIME",
                ]
                .contains(&key.as_str())
                {
                    self.error(
                        i.span,
                        format!(
                            "`{}` is a type of the standard that asi-lift does not run",
                            i.text
                        ),
                    );
                    return None;
                }
                self.error(i.span, format!("no type is named `{}`", i.text));
                None
            }
            TypeRef::Subrange { base, lo, hi, span } => {
                let Some(b) = Elem::of(&base.key()).filter(|e| e.is_int()) else {
                    self.error(
                        base.span,
                        format!("a subrange restricts an integer type, not `{}`", base.text),
                    );
                    return None;
                };
                let (lo, hi) = (self.const_int(lo)?, self.const_int(hi)?);
                if lo > hi || !b.holds(lo) || !b.holds(hi) {
                    self.error(
                        *span,
                        format!("the subrange {lo}..{hi} is empty or not within {b}"),
                    );
                    return None;
                }
                Some(Type::Subrange(b, lo, hi))
            }
            TypeRef::Array { dims, elem, span } => {
                let mut bounds = Vec::new();
                for (lo, hi) in dims {
                    let (lo, hi) = (self.const_int(lo)?, self.const_int(hi)?);
                    if lo > hi {
                        self.error(
                            *span,
                            format!("the array's bounds {lo}..{hi} hold no element"),
                        );
                        return None;
                    }
                    bounds.push((lo, hi));
                }
                let elem = self.resolve(elem)?;
                Some(Type::Array(Box::new(Array { dims: bounds, elem })))
            }
            TypeRef::Enum { values, .. } => Some(self.enumeration("", values)),
            TypeRef::Struct { span, .. } => {
                self.error(*span, "a STRUCT is declared in a TYPE block and named");
                None
            }
        }
    }

    /// The value of a constant integer expression: literals, global constants, `+ - * / MOD`
    /// and signs (bounds and enumeration values); `None` (reported) otherwise.
    fn const_int(&mut self, e: &Expr) -> Option<i128> {
        let v = match &e.kind {
            ExprKind::Lit(Lit::Int(n, _)) => Some(i128::from(*n)),
            ExprKind::Paren(x) => self.const_int(x),
            ExprKind::Unary(UnOp::Neg, x) => self.const_int(x).map(|n| -n),
            ExprKind::Unary(UnOp::Plus, x) => self.const_int(x),
            ExprKind::Name(i) => {
                match self.constants.get(&i.key()) {
                    Some(&n) => Some(n),
                    None => {
                        self.error(i.span, format!("`{}` is no integer constant (a VAR_GLOBAL CONSTANT declared before)", i.text));
                        return None;
                    }
                }
            }
            ExprKind::Binary(op, a, b) => {
                let (a, b) = (self.const_int(a)?, self.const_int(b)?);
                use ast::BinOp::*;
                match op {
                    Add => a.checked_add(b),
                    Sub => a.checked_sub(b),
                    Mul => a.checked_mul(b),
                    Div | Mod if b == 0 => {
                        self.error(e.span, "division by zero in a constant");
                        return None;
                    }
                    Div => a.checked_div(b),
                    Mod => a.checked_rem(b),
                    _ => {
                        self.error(e.span, "a constant integer is built with + - * / MOD only");
                        return None;
                    }
                }
            }
            _ => {
                self.error(e.span, "a constant integer is expected here");
                return None;
            }
        };
        match v {
            Some(n) if (i128::from(i64::MIN)..=i128::from(u64::MAX)).contains(&n) => Some(n),
            _ => {
                self.error(e.span, "the constant is beyond 64 bits");
                None
            }
        }
    }
}

fn kind_name(k: &PouKind) -> &'static str {
    match k {
        PouKind::Program => "PROGRAM",
        PouKind::Function(_) => "FUNCTION",
        PouKind::FunctionBlock => "FUNCTION_BLOCK",
    }
}
