//! The checked program compiled to the flat form `Plc` runs: every variable's place in the
//! one memory, initial values, and each statement and expression with the type it computes in.

use super::*;

/// The zero value of elementary type `e`.
fn zero(e: Elem) -> Value {
    match e {
        Elem::Bool => Value::Bool(false),
        e if e.is_real() => Value::Real(0.0),
        e if e.is_bits() || e.int_range().is_some_and(|(lo, _)| lo == 0) => Value::Uint(0),
        _ => Value::Int(0),
    }
}

/// What an expression computes, as the compiler sees it.
#[derive(Clone, Debug, PartialEq)]
enum CTy {
    Known(Type),
    IntLit(i128),
    RealLit,
}

impl CTy {
    fn elem(&self) -> Option<Elem> {
        match self {
            CTy::Known(Type::Elem(e)) | CTy::Known(Type::Subrange(e, _, _)) => Some(*e),
            CTy::Known(Type::Enum(_)) => Some(Elem::Dint),
            _ => None,
        }
    }
}

/// The scope of the block being compiled.
struct Scope {
    /// The block's index (`usize::MAX` for the globals' initial values).
    pou: usize,
    /// Its variables: offset in its frame (or absolute, for a function), type, location.
    vars: HashMap<String, (u32, Type, Option<Location>)>,
    /// `true` for a function: its variables are absolute addresses.
    absolute: bool,
}

pub(super) struct Compiler<'a> {
    c: &'a Checked,
    /// Per block: each variable's offset in its frame, and the frame's size.
    frames: Vec<(HashMap<String, u32>, u32)>,
    /// The globals' addresses.
    globals: HashMap<String, (u32, Type, Option<Location>)>,
    /// Each function's frame (start, length).
    function_frames: HashMap<usize, (u32, u32)>,
    memory: Vec<Value>,
    std: Vec<StdState>,
    code: Vec<Vec<IStmt>>,
    names: Vec<(String, u32, Elem)>,
    /// Every variable of the program and every global (not located), elementary or not.
    places: Vec<(String, u32)>,
    program_index: usize,
}

impl<'a> Compiler<'a> {
    pub(super) fn new(c: &'a Checked) -> Self {
        Compiler {
            c,
            frames: Vec::new(),
            globals: HashMap::new(),
            function_frames: HashMap::new(),
            memory: Vec::new(),
            std: Vec::new(),
            code: Vec::new(),
            names: Vec::new(),
            places: Vec::new(),
            program_index: 0,
        }
    }

    /// How many memory values a value of `t` takes.
    fn size(&self, t: &Type) -> u32 {
        let n = match t {
            Type::Array(a) => {
                let count: u64 = a
                    .dims
                    .iter()
                    .map(|&(lo, hi)| (hi - lo + 1) as u64)
                    .product();
                count.saturating_mul(u64::from(self.size(&a.elem)))
            }
            Type::Struct(i) => self.c.structs[*i]
                .fields
                .iter()
                .map(|f| u64::from(self.size(&f.ty)))
                .sum(),
            Type::StdFb(f) => 1 + f.pins().len() as u64,
            Type::Fb(i) => u64::from(self.frames.get(*i).map_or(0, |f| f.1)),
            _ => 1,
        };
        u32::try_from(n).unwrap_or(u32::MAX)
    }

    /// Frames for every block, function blocks before the blocks that hold them.
    fn layout(&mut self) {
        self.frames = vec![(HashMap::new(), 0); self.c.pous.len()];
        // A block's size needs its instances' sizes: repeat until none changes (the
        // checker refused blocks that hold themselves, so this ends).
        for _ in 0..=self.c.pous.len() {
            let mut changed = false;
            for (i, p) in self.c.pous.iter().enumerate() {
                let mut offsets = HashMap::new();
                let mut at = 0u32;
                for v in &p.vars {
                    if v.at.is_some() {
                        continue;
                    }
                    offsets.insert(v.name.to_ascii_uppercase(), at);
                    at = at.saturating_add(self.size(&v.ty));
                }
                if self.frames[i].1 != at {
                    changed = true;
                }
                self.frames[i] = (offsets, at);
            }
            if !changed {
                break;
            }
        }
    }

    pub(super) fn compile(&mut self) {
        self.layout();
        let program = self
            .c
            .pous
            .iter()
            .position(|p| p.kind == PouKind::Program)
            .unwrap_or(0);
        // Memory: the program's frame at 0, then the globals, then each function's frame.
        let program_size = self.frames.get(program).map_or(0, |f| f.1);
        self.memory = vec![Value::Int(0); program_size as usize];
        self.instantiate(program, 0);
        for g in &self.c.globals {
            let at = self.memory.len() as u32;
            let size = self.size(&g.ty);
            self.memory
                .extend(std::iter::repeat_n(Value::Int(0), size as usize));
            self.init_var(g, at);
            self.globals
                .insert(g.name.to_ascii_uppercase(), (at, g.ty.clone(), g.at));
            if g.at.is_none() {
                self.places.push((g.name.clone(), at));
            }
            if let Type::Elem(e) | Type::Subrange(e, _, _) = g.ty {
                self.names.push((g.name.clone(), at, e));
            }
        }
        for (i, p) in self.c.pous.iter().enumerate() {
            if matches!(p.kind, PouKind::Function(_)) {
                let start = self.memory.len() as u32;
                let size = self.frames[i].1 + 1;
                self.memory
                    .extend(std::iter::repeat_n(Value::Int(0), size as usize));
                self.instantiate(i, start);
                if let Some(Type::Elem(e) | Type::Subrange(e, _, _)) = &p.result {
                    self.memory[(start + size - 1) as usize] = zero(*e);
                }
                self.function_frames.insert(i, (start, size));
            }
        }
        if let Some(p) = self.c.pous.get(program) {
            for v in &p.vars {
                if let Some(&off) = self.frames[program].0.get(&v.name.to_ascii_uppercase()) {
                    self.places.push((v.name.clone(), off));
                }
                if let (Some(&off), Type::Elem(e) | Type::Subrange(e, _, _)) = (
                    self.frames[program].0.get(&v.name.to_ascii_uppercase()),
                    &v.ty,
                ) {
                    self.names.push((v.name.clone(), off, *e));
                }
            }
        }
        self.code = (0..self.c.pous.len()).map(|i| self.block(i)).collect();
        self.program_index = program;
    }
}

impl Compiler<'_> {
    pub(super) fn finish(self) -> Plc {
        Plc {
            code: self.code,
            program: self.program_index,
            initial: self.memory.clone(),
            memory: self.memory,
            std_initial: self.std.clone(),
            std: self.std,
            names: self.names,
            places: self.places,
            budget: Budget::default(),
        }
    }

    /// Initial values of block `i`'s frame at `base`: zeros of each type, the declared
    /// initial values, nested instances, standard blocks' states.
    fn instantiate(&mut self, i: usize, base: u32) {
        let vars: Vec<Var> = self.c.pous[i].vars.clone();
        for v in &vars {
            let Some(&off) = self.frames[i].0.get(&v.name.to_ascii_uppercase()) else {
                continue;
            };
            self.init_var(v, base + off);
        }
    }

    fn init_var(&mut self, v: &Var, at: u32) {
        self.zero_into(&v.ty, at);
        if let Some(init) = &v.init {
            self.init_into(init, &v.ty, at);
        }
    }

    /// The zero value of `t` at `at` (a subrange's least value where 0 is not in it, an
    /// enumeration's first value).
    fn zero_into(&mut self, t: &Type, at: u32) {
        let at_us = at as usize;
        match t {
            Type::Elem(e) => self.memory[at_us] = zero(*e),
            Type::Subrange(e, lo, hi) => {
                let z = if (*lo..=*hi).contains(&0) { 0 } else { *lo };
                self.memory[at_us] = coerce(Value::Int(z as i64), *e);
            }
            Type::Enum(i) => {
                let first = self.c.enums[*i].values.first().map_or(0, |v| v.1);
                self.memory[at_us] = Value::Int(first as i64);
            }
            Type::Array(a) => {
                let n = self.size(t) / self.size(&a.elem).max(1);
                let stride = self.size(&a.elem);
                for k in 0..n {
                    self.zero_into(&a.elem, at + k * stride);
                }
            }
            Type::Struct(i) => {
                let fields = self.c.structs[*i].fields.clone();
                let mut off = 0;
                for f in &fields {
                    self.init_var(f, at + off);
                    off += self.size(&f.ty);
                }
            }
            Type::StdFb(f) => {
                self.memory[at_us] = Value::Uint(self.std.len() as u64);
                self.std.push(match f {
                    StdFb::Ton => StdState::Ton(Default::default()),
                    StdFb::Tof => StdState::Tof(Default::default()),
                    StdFb::Tp => StdState::Tp(Default::default()),
                    StdFb::RTrig => StdState::RTrig(Default::default()),
                    StdFb::FTrig => StdState::FTrig(Default::default()),
                    StdFb::Sr => StdState::Sr(Default::default()),
                    StdFb::Rs => StdState::Rs(Default::default()),
                    StdFb::Ctu => StdState::Ctu(Default::default()),
                    StdFb::Ctd => StdState::Ctd(Default::default()),
                    StdFb::Ctud => StdState::Ctud(Default::default()),
                });
                for (k, (_, e, _)) in f.pins().iter().enumerate() {
                    self.memory[at_us + 1 + k] = zero(*e);
                }
            }
            Type::Fb(i) => self.instantiate(*i, at),
        }
    }

    fn init_into(&mut self, init: &ast::Init, t: &Type, at: u32) {
        match (init, t) {
            (ast::Init::Expr(e), _) => {
                let v = self.enum_init(e, t).or_else(|| self.const_value(e));
                if let (Some(v), Some(el)) = (v, elem_of(t)) {
                    self.memory[at as usize] = coerce(v, el);
                }
            }
            (ast::Init::Array(elems, _), Type::Array(a)) => {
                let stride = self.size(&a.elem);
                let capacity = self.size(t) / stride.max(1);
                let mut k = 0u32;
                for (count, value) in elems {
                    let n = count
                        .as_ref()
                        .and_then(|c| self.const_value(c))
                        .map_or(1, |v| u32::try_from(v.int()).unwrap_or(0));
                    for _ in 0..n {
                        if k < capacity {
                            self.init_into(value, &a.elem, at + k * stride);
                        }
                        k += 1;
                    }
                }
            }
            (ast::Init::Struct(fields, _), Type::Struct(i)) => {
                let defs = self.c.structs[*i].fields.clone();
                for (name, value) in fields {
                    let mut off = 0;
                    for f in &defs {
                        if f.name.eq_ignore_ascii_case(&name.text) {
                            self.init_into(value, &f.ty, at + off);
                        }
                        off += self.size(&f.ty);
                    }
                }
            }
            _ => {}
        }
    }

    /// The value of `key` in the enumeration of `t`, if `t` is one and has it.
    fn enum_value(&self, t: &Type, key: &str) -> Option<Value> {
        let Type::Enum(n) = t else { return None };
        let (_, v) = self
            .c
            .enums
            .get(*n)?
            .values
            .iter()
            .find(|(k, _)| k == key)?;
        Some(Value::Int(i64::try_from(*v).ok()?))
    }

    /// An initial value `e` of a variable of type `t`: a bare name that is no CONSTANT and is
    /// a value of `t`'s enumeration, as the typer takes it (`typeck`'s `expr_into`).
    fn enum_init(&self, e: &Expr, t: &Type) -> Option<Value> {
        let key = crate::typeck::bare_name(e)?.key();
        if self
            .c
            .globals
            .iter()
            .any(|g| g.name.eq_ignore_ascii_case(&key))
        {
            return None;
        }
        self.enum_value(t, &key)
    }

    /// A constant expression's value (initial values: literals, constants, enumeration
    /// values, signs and arithmetic on them).
    fn const_value(&self, e: &Expr) -> Option<Value> {
        Some(match &e.kind {
            ExprKind::Lit(Lit::Int(n, _)) => Value::Int(i64::try_from(*n).ok()?),
            ExprKind::Lit(Lit::Real(r, _)) => Value::Real(*r),
            ExprKind::Lit(Lit::Bool(b)) => Value::Bool(*b),
            ExprKind::Lit(Lit::Time(t)) => Value::Int(*t),
            ExprKind::Lit(Lit::Enum(ty, v)) => {
                let en = self
                    .c
                    .enums
                    .iter()
                    .find(|en| en.name.eq_ignore_ascii_case(&ty.text))?;
                Value::Int(en.values.iter().find(|(k, _)| *k == v.key())?.1 as i64)
            }
            ExprKind::Name(i) => {
                let key = i.key();
                if let Some(g) = self
                    .c
                    .globals
                    .iter()
                    .find(|g| g.name.eq_ignore_ascii_case(&key) && g.constant)
                {
                    return self.const_value(match &g.init {
                        Some(ast::Init::Expr(x)) => x,
                        _ => return None,
                    });
                }
                let en = self
                    .c
                    .enums
                    .iter()
                    .find_map(|en| en.values.iter().find(|(k, _)| *k == key))?;
                Value::Int(en.1 as i64)
            }
            ExprKind::Paren(x) => self.const_value(x)?,
            ExprKind::Unary(UnOp::Neg, x) => match self.const_value(x)? {
                Value::Real(r) => Value::Real(-r),
                v => Value::Int(v.int().wrapping_neg()),
            },
            ExprKind::Binary(op, a, b) => {
                let (a, b) = (self.const_value(a)?, self.const_value(b)?);
                if matches!(a, Value::Real(_)) || matches!(b, Value::Real(_)) {
                    let (x, y) = (a.real(), b.real());
                    Value::Real(match op {
                        BinOp::Add => x + y,
                        BinOp::Sub => x - y,
                        BinOp::Mul => x * y,
                        BinOp::Div => x / y,
                        _ => return None,
                    })
                } else {
                    let (x, y) = (a.int(), b.int());
                    Value::Int(match op {
                        BinOp::Add => x.checked_add(y)?,
                        BinOp::Sub => x.checked_sub(y)?,
                        BinOp::Mul => x.checked_mul(y)?,
                        BinOp::Div => x.checked_div(y)?,
                        BinOp::Mod => x.checked_rem(y)?,
                        _ => return None,
                    })
                }
            }
            _ => return None,
        })
    }
}

/// The elementary type a value of `t` is stored as.
fn elem_of(t: &Type) -> Option<Elem> {
    match t {
        Type::Elem(e) | Type::Subrange(e, _, _) => Some(*e),
        Type::Enum(_) => Some(Elem::Dint),
        _ => None,
    }
}

/// `p` moved on by `k` values.
fn offset(p: Place, k: u32) -> Place {
    match p {
        Place::Mem(a) => Place::Mem(a + k),
        Place::Abs(a) => Place::Abs(a + k),
        Place::Offset(inner, j) => Place::Offset(inner, j + k),
        other if k == 0 => other,
        other => Place::Offset(Box::new(other), k),
    }
}

impl Compiler<'_> {
    fn scope(&self, i: usize) -> Scope {
        let pou = &self.c.pous[i];
        let absolute = matches!(pou.kind, PouKind::Function(_));
        let start = self.function_frames.get(&i).map_or(0, |f| f.0);
        let vars = pou
            .vars
            .iter()
            .map(|v| {
                let key = v.name.to_ascii_uppercase();
                let off = self.frames[i].0.get(&key).copied().unwrap_or(0);
                (
                    key,
                    (if absolute { start + off } else { off }, v.ty.clone(), v.at),
                )
            })
            .collect();
        Scope {
            pou: i,
            vars,
            absolute,
        }
    }

    fn block(&self, i: usize) -> Vec<IStmt> {
        let sc = self.scope(i);
        self.stmts(&sc, &self.c.pous[i].body)
    }

    fn stmts(&self, sc: &Scope, ss: &[Stmt]) -> Vec<IStmt> {
        ss.iter().filter_map(|s| self.stmt(sc, s)).collect()
    }

    fn stmt(&self, sc: &Scope, s: &Stmt) -> Option<IStmt> {
        Some(match &s.kind {
            StmtKind::Assign { target, value } => {
                let (place, ty) = self.place(sc, target)?;
                match elem_of(&ty) {
                    Some(e) => IStmt::Assign(place, e, self.expr_into(sc, value, &ty, e)),
                    None => {
                        let (src, _) = self.place(sc, value)?;
                        IStmt::Copy(place, src, self.size(&ty))
                    }
                }
            }
            StmtKind::Call(e) => {
                let ExprKind::Call(callee, args) = &e.kind else {
                    return None;
                };
                match self.place(sc, callee) {
                    Some((instance, Type::StdFb(f))) => {
                        let pins = f.pins();
                        let mut inputs = Vec::new();
                        let mut outputs = Vec::new();
                        for a in args {
                            let name = a.name.as_ref()?.key();
                            let k = pins.iter().position(|(n, _, _)| *n == name)?;
                            let el = pins[k].1;
                            if a.output {
                                outputs.push((1 + k as u32, el, self.place(sc, &a.value)?.0));
                            } else {
                                inputs.push((1 + k as u32, el, self.expr_as(sc, &a.value, el)));
                            }
                        }
                        IStmt::CallFb {
                            fb: FbKind::Std(f),
                            instance,
                            inputs,
                            outputs,
                        }
                    }
                    Some((instance, Type::Fb(b))) => {
                        let mut inputs = Vec::new();
                        let mut outputs = Vec::new();
                        for a in args {
                            let name = a.name.as_ref()?.key();
                            let v = self.c.pous[b]
                                .vars
                                .iter()
                                .find(|v| v.name.eq_ignore_ascii_case(&name))?;
                            let off = *self.frames[b].0.get(&name)?;
                            let el = elem_of(&v.ty)?;
                            if a.output {
                                outputs.push((off, el, self.place(sc, &a.value)?.0));
                            } else {
                                inputs.push((off, el, self.expr_into(sc, &a.value, &v.ty, el)));
                            }
                        }
                        IStmt::CallFb {
                            fb: FbKind::User(b),
                            instance,
                            inputs,
                            outputs,
                        }
                    }
                    _ => IStmt::Eval(self.expr(sc, e).0),
                }
            }
            StmtKind::If { arms, otherwise } => IStmt::If(
                arms.iter()
                    .map(|(c, body)| (self.expr_as(sc, c, Elem::Bool), self.stmts(sc, body)))
                    .collect(),
                self.stmts(sc, otherwise),
            ),
            StmtKind::Case {
                selector,
                arms,
                otherwise,
            } => {
                let (sel, st) = self.expr(sc, selector);
                let label = |v: &Expr| match &st {
                    CTy::Known(t) => self.enum_in(sc, v, t).or_else(|| self.const_value(v)),
                    _ => self.const_value(v),
                };
                let arms = arms
                    .iter()
                    .map(|(labels, body)| {
                        let ranges = labels
                            .iter()
                            .filter_map(|l| match l {
                                CaseLabel::Value(v) => {
                                    let n = label(v)?.int();
                                    Some((n, n))
                                }
                                CaseLabel::Range(a, b) => Some((label(a)?.int(), label(b)?.int())),
                            })
                            .collect();
                        (ranges, self.stmts(sc, body))
                    })
                    .collect();
                IStmt::Case(sel, arms, self.stmts(sc, otherwise))
            }
            StmtKind::For {
                var,
                from,
                to,
                by,
                body,
            } => {
                let name = ast::Ident {
                    text: var.text.clone(),
                    span: var.span,
                };
                let target = Expr {
                    kind: ExprKind::Name(name),
                    span: var.span,
                };
                let (place, ty) = self.place(sc, &target)?;
                let elem = elem_of(&ty)?;
                IStmt::For {
                    var: place,
                    elem,
                    from: self.expr_as(sc, from, elem),
                    to: self.expr_as(sc, to, elem),
                    by: by
                        .as_ref()
                        .map_or(IExpr::Const(Value::Int(1)), |b| self.expr_as(sc, b, elem)),
                    body: self.stmts(sc, body),
                    span: s.span,
                }
            }
            StmtKind::While { cond, body } => IStmt::While(
                self.expr_as(sc, cond, Elem::Bool),
                self.stmts(sc, body),
                s.span,
            ),
            StmtKind::Repeat { body, until } => IStmt::Repeat(
                self.stmts(sc, body),
                self.expr_as(sc, until, Elem::Bool),
                s.span,
            ),
            StmtKind::Exit => IStmt::Exit,
            StmtKind::Continue => IStmt::Continue,
            StmtKind::Return => IStmt::Return,
            StmtKind::Empty => return None,
        })
    }

    /// The place an expression names, and its type.
    fn place(&self, sc: &Scope, e: &Expr) -> Option<(Place, Type)> {
        match &e.kind {
            ExprKind::Name(i) => {
                let key = i.key();
                let found = sc
                    .vars
                    .get(&key)
                    .map(|v| (v, sc.absolute))
                    .or_else(|| self.globals.get(&key).map(|v| (v, true)));
                if let Some(((addr, ty, at), absolute)) = found {
                    if let Some(loc) = at {
                        return Some((image_place(*loc), ty.clone()));
                    }
                    let place = if absolute {
                        Place::Abs(*addr)
                    } else {
                        Place::Mem(*addr)
                    };
                    return Some((place, ty.clone()));
                }
                // A function's result, under its name.
                let p = self.c.pous.get(sc.pou)?;
                if p.name.eq_ignore_ascii_case(&key) {
                    let (start, size) = *self.function_frames.get(&sc.pou)?;
                    return Some((Place::Abs(start + size - 1), p.result.clone()?));
                }
                None
            }
            ExprKind::Direct(d) => {
                let place = match (d.area, d.size, d.path.as_slice()) {
                    (Area::Input, Size::Bit, [w, b]) => Place::InBit(*w, *b),
                    (Area::Input, Size::Word, [w]) => Place::InWord(*w),
                    (Area::Output, Size::Bit, [w, b]) => Place::OutBit(*w, *b),
                    (Area::Output, Size::Word, [w]) => Place::OutWord(*w),
                    _ => return None,
                };
                let e = if d.size == Size::Bit {
                    Elem::Bool
                } else {
                    Elem::Word
                };
                Some((place, Type::Elem(e)))
            }
            ExprKind::Paren(x) => self.place(sc, x),
            ExprKind::Field(base, f) => {
                let (p, t) = self.place(sc, base)?;
                let key = f.key();
                match t {
                    Type::Struct(i) => {
                        let mut off = 0;
                        for fd in &self.c.structs[i].fields {
                            if fd.name.eq_ignore_ascii_case(&key) {
                                return Some((offset(p, off), fd.ty.clone()));
                            }
                            off += self.size(&fd.ty);
                        }
                        None
                    }
                    Type::StdFb(b) => {
                        let k = b.pins().iter().position(|(n, _, _)| *n == key)?;
                        Some((offset(p, 1 + k as u32), Type::Elem(b.pins()[k].1)))
                    }
                    Type::Fb(b) => {
                        let v = self.c.pous[b]
                            .vars
                            .iter()
                            .find(|v| v.name.eq_ignore_ascii_case(&key))?;
                        Some((offset(p, *self.frames[b].0.get(&key)?), v.ty.clone()))
                    }
                    _ => None,
                }
            }
            ExprKind::Index(base, idx) => {
                let (p, t) = self.place(sc, base)?;
                let Type::Array(a) = t else { return None };
                let elem_size = self.size(&a.elem);
                let mut strides = Vec::new();
                let mut stride = elem_size;
                for &(lo, hi) in a.dims.iter().rev() {
                    strides.push(stride);
                    stride = stride.saturating_mul(u32::try_from(hi - lo + 1).unwrap_or(u32::MAX));
                }
                strides.reverse();
                let terms = idx
                    .iter()
                    .zip(&a.dims)
                    .zip(strides)
                    .map(|((x, &(lo, hi)), st)| {
                        (
                            Box::new(self.expr_as(sc, x, Elem::Lint)),
                            lo as i64,
                            hi as i64,
                            st,
                        )
                    })
                    .collect();
                Some((
                    Place::Indexed {
                        base: Box::new(p),
                        terms,
                        span: e.span,
                    },
                    a.elem.clone(),
                ))
            }
            ExprKind::Bit(base, n) => {
                let (p, t) = self.place(sc, base)?;
                let el = elem_of(&t)?;
                Some((Place::Bit(Box::new(p), *n, el), Type::Elem(Elem::Bool)))
            }
            _ => None,
        }
    }

    /// `e` as a value of `want` (a literal takes it; anything else computes in its own type).
    fn expr_as(&self, sc: &Scope, e: &Expr, want: Elem) -> IExpr {
        let (x, t) = self.expr(sc, e);
        match (&x, t) {
            (IExpr::Const(v), CTy::IntLit(_) | CTy::RealLit) => IExpr::Const(coerce(*v, want)),
            _ => x,
        }
    }

    /// The type two operands compute in.
    fn operands(&self, a: &CTy, b: &CTy) -> Elem {
        let least = |n: i128| {
            [Elem::Dint, Elem::Lint, Elem::Ulint]
                .into_iter()
                .find(|e| e.holds(n))
                .unwrap_or(Elem::Lint)
        };
        match (a, b) {
            // Literals alone compute at full precision; their destination rounds them.
            (CTy::RealLit | CTy::IntLit(_), CTy::RealLit | CTy::IntLit(_))
                if matches!(a, CTy::RealLit) || matches!(b, CTy::RealLit) =>
            {
                Elem::Lreal
            }
            (CTy::RealLit, _) | (_, CTy::RealLit) => match (a.elem(), b.elem()) {
                (Some(Elem::Lreal), _) | (_, Some(Elem::Lreal)) => Elem::Lreal,
                _ => Elem::Real,
            },
            (CTy::IntLit(x), CTy::IntLit(y)) => least((*x).max(*y)).max(least((*x).min(*y))),
            (CTy::IntLit(n), t) | (t, CTy::IntLit(n)) => match t.elem() {
                Some(e) if e.holds(*n) || e.is_real() || e.is_duration() => e,
                Some(e) => Elem::common(e, least(*n)).unwrap_or(Elem::Lint),
                None => least(*n),
            },
            _ => match (a.elem(), b.elem()) {
                (Some(x), Some(y)) => Elem::common(x, y).unwrap_or(x),
                (Some(x), None) | (None, Some(x)) => x,
                _ => Elem::Dint,
            },
        }
    }

    fn expr(&self, sc: &Scope, e: &Expr) -> (IExpr, CTy) {
        let konst = |v, t| (IExpr::Const(v), t);
        match &e.kind {
            ExprKind::Lit(Lit::Int(n, None)) => {
                konst(Value::Int(*n as i64), CTy::IntLit(i128::from(*n)))
            }
            ExprKind::Lit(Lit::Int(n, Some(t))) => {
                let el = Elem::of(&t.key()).unwrap_or(Elem::Dint);
                konst(coerce(Value::Uint(*n), el), CTy::Known(Type::Elem(el)))
            }
            ExprKind::Lit(Lit::Real(r, None)) => konst(Value::Real(*r), CTy::RealLit),
            ExprKind::Lit(Lit::Real(r, Some(t))) => {
                let el = Elem::of(&t.key()).unwrap_or(Elem::Real);
                konst(coerce(Value::Real(*r), el), CTy::Known(Type::Elem(el)))
            }
            ExprKind::Lit(Lit::Bool(b)) => {
                konst(Value::Bool(*b), CTy::Known(Type::Elem(Elem::Bool)))
            }
            ExprKind::Lit(Lit::Time(t)) => {
                konst(Value::Int(*t), CTy::Known(Type::Elem(Elem::Time)))
            }
            ExprKind::Lit(Lit::Enum(..)) => konst(
                self.const_value(e).unwrap_or(Value::Int(0)),
                CTy::Known(Type::Elem(Elem::Dint)),
            ),
            ExprKind::Lit(Lit::Str(_)) => konst(Value::Int(0), CTy::IntLit(0)),
            ExprKind::Paren(x) => self.expr(sc, x),
            ExprKind::Name(i) if self.place(sc, e).is_none() => {
                // An enumeration value.
                let v = self.const_value(e).unwrap_or(Value::Int(0));
                let _ = i;
                konst(v, CTy::Known(Type::Elem(Elem::Dint)))
            }
            ExprKind::Name(_)
            | ExprKind::Direct(_)
            | ExprKind::Field(..)
            | ExprKind::Index(..)
            | ExprKind::Bit(..) => match self.place(sc, e) {
                Some((p, t)) => {
                    let el = elem_of(&t).unwrap_or(Elem::Dint);
                    (IExpr::Read(p, el), CTy::Known(t))
                }
                None => konst(Value::Int(0), CTy::IntLit(0)),
            },
            ExprKind::Unary(op, x) => {
                let (a, t) = self.expr(sc, x);
                match (op, &t, &a) {
                    (UnOp::Neg, CTy::IntLit(n), IExpr::Const(_)) => {
                        konst(Value::Int(-(*n as i64)), CTy::IntLit(-n))
                    }
                    (UnOp::Neg, CTy::RealLit, IExpr::Const(v)) => {
                        konst(Value::Real(-v.real()), CTy::RealLit)
                    }
                    (UnOp::Plus, ..) => (a, t),
                    (UnOp::Neg, ..) => {
                        let el = t.elem().unwrap_or(Elem::Dint);
                        (IExpr::Neg(Box::new(a), el), t)
                    }
                    (UnOp::Not, ..) => {
                        let el = t.elem().unwrap_or(Elem::Bool);
                        (IExpr::Not(Box::new(a), el), t)
                    }
                }
            }
            ExprKind::Binary(op, x, y) => {
                let ((mut a, ta), (mut b, tb)) = (self.expr(sc, x), self.expr(sc, y));
                // A bare enumeration value takes the other side's enumeration.
                if let CTy::Known(t) = &tb {
                    if let Some(v) = self.enum_in(sc, x, t) {
                        a = IExpr::Const(v);
                    }
                }
                if let CTy::Known(t) = &ta {
                    if let Some(v) = self.enum_in(sc, y, t) {
                        b = IExpr::Const(v);
                    }
                }
                let el = self.operands(&ta, &tb);
                let fix = |x: IExpr, t: &CTy| match (x, t) {
                    (IExpr::Const(v), CTy::IntLit(_) | CTy::RealLit) => IExpr::Const(coerce(v, el)),
                    (x, _) => x,
                };
                let (a, b) = (fix(a, &ta), fix(b, &tb));
                use BinOp::*;
                match op {
                    Lt | Gt | Le | Ge | Eq | Ne => (
                        IExpr::Cmp(*op, el, Box::new(a), Box::new(b)),
                        CTy::Known(Type::Elem(Elem::Bool)),
                    ),
                    // A duration times or by a real computes in LREAL.
                    Mul | Div
                        if ta.elem().is_some_and(Elem::is_duration)
                            && tb.elem().is_some_and(Elem::is_real)
                            || matches!(tb, CTy::RealLit)
                                && ta.elem().is_some_and(Elem::is_duration) =>
                    {
                        (
                            IExpr::Conv(
                                Elem::Time,
                                Box::new(IExpr::Bin(
                                    *op,
                                    Elem::Lreal,
                                    Box::new(a),
                                    Box::new(b),
                                    e.span,
                                )),
                            ),
                            ta,
                        )
                    }
                    Power if !el.is_real() => (
                        IExpr::Bin(*op, Elem::Real, Box::new(a), Box::new(b), e.span),
                        CTy::Known(Type::Elem(Elem::Real)),
                    ),
                    _ => {
                        let t = if ta.elem().is_some_and(Elem::is_duration) {
                            ta
                        } else {
                            CTy::Known(Type::Elem(el))
                        };
                        let el = t.elem().unwrap_or(el);
                        (IExpr::Bin(*op, el, Box::new(a), Box::new(b), e.span), t)
                    }
                }
            }
            ExprKind::Call(callee, args) => self.call(sc, callee, args),
        }
    }

    /// `e` where a value of `want` is expected: a bare name that names no variable and is a
    /// value of `want`'s enumeration, as the typer takes it (`typeck`'s `expr_into`).
    fn enum_in(&self, sc: &Scope, e: &Expr, want: &Type) -> Option<Value> {
        let key = crate::typeck::bare_name(e)?.key();
        if self.place(sc, e).is_some() {
            return None;
        }
        self.enum_value(want, &key)
    }

    /// `e` as a value of `el`, the type of `want` (see [`Compiler::enum_in`]).
    fn expr_into(&self, sc: &Scope, e: &Expr, want: &Type, el: Elem) -> IExpr {
        match self.enum_in(sc, e, want) {
            Some(v) => IExpr::Const(v),
            None => self.expr_as(sc, e, el),
        }
    }

    fn call(&self, sc: &Scope, callee: &Expr, args: &[ast::Arg]) -> (IExpr, CTy) {
        let zero_out = (IExpr::Const(Value::Int(0)), CTy::IntLit(0));
        let ExprKind::Name(name) = &callee.kind else {
            return zero_out;
        };
        let key = name.key();
        if let Some((_, to)) = Elem::conversion(&key) {
            let Some(a) = args.first() else {
                return zero_out;
            };
            let (x, _) = self.expr(sc, &a.value);
            return (IExpr::Conv(to, Box::new(x)), CTy::Known(Type::Elem(to)));
        }
        let f = match key.as_str() {
            "ABS" => Some(StdFn::Abs),
            "SQRT" => Some(StdFn::Sqrt),
            "MIN" => Some(StdFn::Min),
            "MAX" => Some(StdFn::Max),
            "LIMIT" => Some(StdFn::Limit),
            "SEL" => Some(StdFn::Sel),
            "MUX" => Some(StdFn::Mux),
            "SHL" => Some(StdFn::Shl),
            "SHR" => Some(StdFn::Shr),
            "ROL" => Some(StdFn::Rol),
            "ROR" => Some(StdFn::Ror),
            "MOVE" => {
                let Some(a) = args.first() else {
                    return zero_out;
                };
                return self.expr(sc, &a.value);
            }
            _ => None,
        };
        if let Some(f) = f {
            let compiled: Vec<(IExpr, CTy)> =
                args.iter().map(|a| self.expr(sc, &a.value)).collect();
            // The values chosen among (after SEL's and MUX's selector) set the type.
            let skip = usize::from(matches!(f, StdFn::Sel | StdFn::Mux));
            let values: Vec<&CTy> = compiled.iter().skip(skip).map(|(_, t)| t).collect();
            let el = match f {
                StdFn::Shl | StdFn::Shr | StdFn::Rol | StdFn::Ror => compiled
                    .first()
                    .and_then(|c| c.1.elem())
                    .unwrap_or(Elem::Lword),
                StdFn::Sqrt => Elem::Lreal,
                _ => values
                    .iter()
                    .skip(1)
                    .fold(
                        values
                            .first()
                            .map(|t| (*t).clone())
                            .unwrap_or(CTy::IntLit(0)),
                        |acc, t| CTy::Known(Type::Elem(self.operands(&acc, t))),
                    )
                    .elem()
                    .unwrap_or(Elem::Dint),
            };
            let xs = compiled
                .into_iter()
                .map(|(x, t)| match (x, t) {
                    (IExpr::Const(v), CTy::IntLit(_) | CTy::RealLit) => IExpr::Const(coerce(v, el)),
                    (x, _) => x,
                })
                .collect();
            return (IExpr::Std(f, el, xs), CTy::Known(Type::Elem(el)));
        }
        // A function of the program.
        let Some(p) = self.c.pous.iter().position(|p| {
            p.name.eq_ignore_ascii_case(&key) && matches!(p.kind, PouKind::Function(_))
        }) else {
            return zero_out;
        };
        let Some(&(start, size)) = self.function_frames.get(&p) else {
            return zero_out;
        };
        let pou = &self.c.pous[p];
        let inputs: Vec<&Var> = pou
            .vars
            .iter()
            .filter(|v| v.kind == VarKind::Input)
            .collect();
        let mut positional = inputs.iter();
        let mut compiled = Vec::new();
        for a in args {
            let v = match &a.name {
                Some(n) => inputs.iter().find(|v| v.name.eq_ignore_ascii_case(&n.text)),
                None => positional.next(),
            };
            let Some(v) = v else { continue };
            let Some(&off) = self.frames[p].0.get(&v.name.to_ascii_uppercase()) else {
                continue;
            };
            let el = elem_of(&v.ty).unwrap_or(Elem::Dint);
            compiled.push((start + off, el, self.expr_into(sc, &a.value, &v.ty, el)));
        }
        let result = pou.result.clone().unwrap_or(Type::Elem(Elem::Dint));
        let el = elem_of(&result).unwrap_or(Elem::Dint);
        (
            IExpr::Call(p, (start, size), compiled, start + size - 1, el),
            CTy::Known(result),
        )
    }
}

fn image_place(l: Location) -> Place {
    match l {
        Location::InputBit(w, b) => Place::InBit(w, b),
        Location::InputWord(w) => Place::InWord(w),
        Location::OutputBit(w, b) => Place::OutBit(w, b),
        Location::OutputWord(w) => Place::OutWord(w),
    }
}
