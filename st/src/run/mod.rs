//! A checked program compiled to a flat form and run scan by scan, as a PLC runs it.
//!
//! Every variable has a fixed place in one memory (the program's, the globals', every
//! function block instance's nested in its owner, and one frame per function: a PLC program
//! has no recursion, [`crate::typeck`]), so nothing is allocated while the program runs. A scan
//! is counted in operations (the PLC's watchdog, [`Budget`]): deterministic, whatever the
//! machine. A division by zero, an index out of range or a scan past its budget stops the PLC
//! ([`Fault`]) with the place in the source, as a real PLC goes to STOP.
//!
//! The process image is the caller's ([`Image`]): located variables read and write it at
//! their words and bits (seed 003, table 4.1).

use std::collections::HashMap;

use crate::ast::{
    self, BinOp, CaseLabel, Expr, ExprKind, Lit, PouKind, Stmt, StmtKind, UnOp, VarKind,
};
use crate::check::{Checked, Location, StdFb, Type, Var};
use crate::lexer::{Area, Size};
use crate::source::Span;
use crate::stdfb;
use crate::types::Elem;

/// The process image a program reads and writes: words of 16 bits.
pub trait Image {
    /// Input word `w` (0 past the image).
    fn input(&self, w: u32) -> u16;
    /// Output word `w` as last written (0 past the image).
    fn output(&self, w: u32) -> u16;
    /// Writes output word `w` (nothing past the image).
    fn set_output(&mut self, w: u32, value: u16);
}

/// How many operations a scan may take before the watchdog stops the PLC.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget(pub u64);

impl Default for Budget {
    /// A million operations: some thousand times what a lift program's scan takes.
    fn default() -> Self {
        Budget(1_000_000)
    }
}

/// Why the PLC stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fault {
    /// Where in the source.
    pub span: Span,
    /// What happened.
    pub cause: FaultCause,
}

/// What stopped the PLC.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaultCause {
    /// An integer division or MOD by zero.
    DivisionByZero,
    /// An array index outside its bounds.
    IndexOutOfRange {
        /// The index.
        index: i64,
        /// The least index.
        lo: i64,
        /// The greatest index.
        hi: i64,
    },
    /// The scan took more operations than its budget.
    Watchdog(u64),
    /// An entry of the agreed event buffer (1-based) holds what no event can (a floor past
    /// 255, a reason that is not its kind's): found by the controller that reads the buffer.
    BadEvent(i64),
}

impl std::fmt::Display for FaultCause {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FaultCause::DivisionByZero => f.write_str("division by zero"),
            FaultCause::IndexOutOfRange { index, lo, hi } => {
                write!(f, "index {index} outside the array's {lo}..{hi}")
            }
            FaultCause::Watchdog(n) => {
                write!(f, "the scan took more than {n} operations (the watchdog)")
            }
            FaultCause::BadEvent(k) => write!(
                f,
                "entry {k} of the event buffer holds no event (a floor past 255, or a reason \
                 not its kind's)"
            ),
        }
    }
}

/// A value in memory.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// BOOL.
    Bool(bool),
    /// A signed integer, an enumeration, or TIME (nanoseconds).
    Int(i64),
    /// An unsigned integer or a bit string.
    Uint(u64),
    /// REAL or LREAL.
    Real(f64),
}

impl Value {
    fn int(self) -> i64 {
        match self {
            Value::Bool(b) => i64::from(b),
            Value::Int(i) => i,
            Value::Uint(u) => u as i64,
            Value::Real(r) => r as i64,
        }
    }

    fn uint(self) -> u64 {
        match self {
            Value::Bool(b) => u64::from(b),
            Value::Int(i) => i as u64,
            Value::Uint(u) => u,
            Value::Real(r) => r as u64,
        }
    }

    fn real(self) -> f64 {
        match self {
            Value::Bool(b) => f64::from(u8::from(b)),
            Value::Int(i) => i as f64,
            Value::Uint(u) => u as f64,
            Value::Real(r) => r,
        }
    }

    fn bool(self) -> bool {
        match self {
            Value::Bool(b) => b,
            Value::Int(i) => i != 0,
            Value::Uint(u) => u != 0,
            Value::Real(r) => r != 0.0,
        }
    }
}

/// `v` as a value of `e`: integers wrap to its width, reals round to its precision.
#[inline]
fn coerce(v: Value, e: Elem) -> Value {
    match e {
        Elem::Bool => Value::Bool(v.bool()),
        Elem::Sint => Value::Int(i64::from(v.int() as i8)),
        Elem::Int => Value::Int(i64::from(v.int() as i16)),
        Elem::Dint => Value::Int(i64::from(v.int() as i32)),
        Elem::Lint | Elem::Time | Elem::Ltime => Value::Int(v.int()),
        Elem::Usint | Elem::Byte => Value::Uint(u64::from(v.uint() as u8)),
        Elem::Uint | Elem::Word => Value::Uint(u64::from(v.uint() as u16)),
        Elem::Udint | Elem::Dword => Value::Uint(u64::from(v.uint() as u32)),
        Elem::Ulint | Elem::Lword => Value::Uint(v.uint()),
        Elem::Real => Value::Real(f64::from(v.real() as f32)),
        Elem::Lreal => Value::Real(v.real()),
    }
}

/// A place in memory or in the image.
#[derive(Clone, Debug)]
enum Place {
    /// An address within the running block's frame.
    Mem(u32),
    /// An absolute address (a global, a function's frame).
    Abs(u32),
    /// A fixed offset from a place (a field, a pin, an instance's variable).
    Offset(Box<Place>, u32),
    /// An element: `base` plus each index's offset, checked against its bounds.
    Indexed {
        base: Box<Place>,
        terms: Vec<(Ix, i64, i64, u32)>,
        span: Span,
    },
    /// Bit `n` of the bit string at the place.
    Bit(Box<Place>, u32, Elem),
    /// Input image bit.
    InBit(u32, u32),
    /// Input image word.
    InWord(u32),
    /// Output image bit.
    OutBit(u32, u32),
    /// Output image word.
    OutWord(u32),
}

/// An index expression.
type Ix = Box<IExpr>;

/// An expression, compiled: each operation with the type it computes in.
#[derive(Clone, Debug)]
enum IExpr {
    Const(Value),
    Read(Place, Elem),
    Neg(Box<IExpr>, Elem),
    Not(Box<IExpr>, Elem),
    Bin(BinOp, Elem, Box<IExpr>, Box<IExpr>, Span),
    /// A comparison of two values of one type.
    Cmp(BinOp, Elem, Box<IExpr>, Box<IExpr>),
    Conv(Elem, Box<IExpr>),
    /// A function's call: its frame (start, length) reset to its initial values, its inputs
    /// (absolute addresses) written, its code run, its result read.
    Call(usize, (u32, u32), Vec<(u32, Elem, IExpr)>, u32, Elem),
    Std(StdFn, Elem, Vec<IExpr>),
}

#[derive(Clone, Copy, Debug)]
enum StdFn {
    Abs,
    Sqrt,
    Min,
    Max,
    Limit,
    Sel,
    Mux,
    Shl,
    Shr,
    Rol,
    Ror,
}

/// A CASE arm: its labels' ranges and its statements.
type CaseArm = (Vec<(i64, i64)>, Vec<IStmt>);

/// A statement, compiled.
#[derive(Clone, Debug)]
enum IStmt {
    Assign(Place, Elem, IExpr),
    /// A block instance's call: inputs written into its frame (at offsets), the body run on
    /// it, outputs read from it.
    CallFb {
        fb: FbKind,
        instance: Place,
        inputs: Vec<(u32, Elem, IExpr)>,
        outputs: Vec<(u32, Elem, Place)>,
    },
    /// An array's or a structure's copy: `n` values.
    Copy(Place, Place, u32),
    /// A function called for its effect, its result dropped.
    Eval(IExpr),
    If(Vec<(IExpr, Vec<IStmt>)>, Vec<IStmt>),
    Case(IExpr, Vec<CaseArm>, Vec<IStmt>),
    For {
        var: Place,
        elem: Elem,
        from: IExpr,
        to: IExpr,
        by: IExpr,
        body: Vec<IStmt>,
        span: Span,
    },
    While(IExpr, Vec<IStmt>, Span),
    Repeat(Vec<IStmt>, IExpr, Span),
    Exit,
    Continue,
    Return,
}

#[derive(Clone, Copy, Debug)]
enum FbKind {
    /// A block of the program: its code's index.
    User(usize),
    /// A standard block: its frame holds its state's index, then its pins.
    Std(StdFb),
}

/// A standard block's state.
#[derive(Clone, Copy, Debug)]
enum StdState {
    Sr(stdfb::Sr),
    Rs(stdfb::Rs),
    RTrig(stdfb::RTrig),
    FTrig(stdfb::FTrig),
    Ctu(stdfb::Ctu),
    Ctd(stdfb::Ctd),
    Ctud(stdfb::Ctud),
    Tp(stdfb::Tp),
    Ton(stdfb::Ton),
    Tof(stdfb::Tof),
}

/// How a statement list ended.
enum Flow {
    Next,
    Exit,
    Continue,
    Return,
}

/// A program ready to run: its code, its memory, and the standard blocks' states.
#[derive(Clone, Debug)]
pub struct Plc {
    /// The code of each block, compiled once per block (a function block's code is shared
    /// by its instances, which run it on their own frames).
    code: Vec<Vec<IStmt>>,
    /// The program's block.
    program: usize,
    memory: Vec<Value>,
    initial: Vec<Value>,
    std: Vec<StdState>,
    std_initial: Vec<StdState>,
    /// The variables' names and places, for a watch list.
    names: Vec<(String, u32, Elem)>,
    /// Every variable of the program and every global (not located) and its address.
    places: Vec<(String, u32)>,
    budget: Budget,
}

impl Plc {
    /// `checked` compiled (it has been type-checked without errors, [`crate::typeck`]).
    pub fn new(checked: &Checked) -> Plc {
        let mut c = Compiler::new(checked);
        c.compile();
        c.finish()
    }

    /// Sets the watchdog's budget per scan.
    pub fn set_budget(&mut self, budget: Budget) {
        self.budget = budget;
    }

    /// Back to the initial values, as a PLC's cold start.
    pub fn reset(&mut self) {
        self.memory.clone_from(&self.initial);
        self.std.clone_from(&self.std_initial);
    }

    /// The program's and the globals' variables of elementary type and their values now.
    pub fn watch(&self) -> Vec<(&str, Value)> {
        self.names
            .iter()
            .map(|(n, a, _)| (n.as_str(), self.memory[*a as usize]))
            .collect()
    }

    /// As [`Plc::watch`], each value written as a literal of its type, as a PLC's online mode
    /// shows it: `TRUE`, `-12`, `16#00FF` for bit strings, `1.5`, `T#1s200ms`.
    pub fn watch_text(&self) -> Vec<(&str, String)> {
        self.names
            .iter()
            .map(|(n, a, e)| (n.as_str(), literal(self.memory[*a as usize], *e)))
            .collect()
    }

    /// The value of the program's or a global variable `name`, if elementary.
    pub fn get(&self, name: &str) -> Option<Value> {
        self.names
            .iter()
            .find(|(n, _, _)| n.eq_ignore_ascii_case(name))
            .map(|(_, a, _)| self.memory[*a as usize])
    }

    /// Sets the program's or a global variable `name` (elementary) to `value`, converted to
    /// its type; `false` if there is no such variable.
    pub fn set(&mut self, name: &str, value: Value) -> bool {
        match self
            .names
            .iter()
            .find(|(n, _, _)| n.eq_ignore_ascii_case(name))
        {
            Some(&(_, a, e)) => {
                self.memory[a as usize] = coerce(value, e);
                true
            }
            None => false,
        }
    }

    /// The address in memory of the program's or a global variable `name` (not located),
    /// elementary or not: an array's elements follow one another from it, a structure's
    /// fields in their order, each as many values as its type holds.
    pub fn address(&self, name: &str) -> Option<u32> {
        self.places
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .map(|&(_, a)| a)
    }

    /// The value at `address` (see [`Plc::address`]); `None` past the memory.
    pub fn read(&self, address: u32) -> Option<Value> {
        self.memory.get(address as usize).copied()
    }

    /// Writes `value` at `address`, converted to `elem` (the type of the variable there);
    /// nothing past the memory.
    pub fn write(&mut self, address: u32, value: Value, elem: Elem) {
        if let Some(m) = self.memory.get_mut(address as usize) {
            *m = coerce(value, elem);
        }
    }

    /// One scan at `now` (nanoseconds on the PLC's clock) over `image`.
    pub fn scan(&mut self, now: i64, image: &mut dyn Image) -> Result<(), Fault> {
        let code = std::mem::take(&mut self.code);
        let mut m = Machine {
            memory: &mut self.memory,
            initial: &self.initial,
            std: &mut self.std,
            code: &code,
            image,
            now,
            left: self.budget.0,
            budget: self.budget.0,
            at: Span::default(),
        };
        let r = m.stmts(&code[self.program], 0).map(|_| ()).map_err(|f| *f);
        self.code = code;
        r
    }
}

/// What a step of the machine gives: the fault boxed, so that the result of every step stays
/// small (a fault comes once, at the end of a scan).
type Run<T> = Result<T, Box<Fault>>;

/// A call's inputs up to this many are held on the stack while they are evaluated.
const ARGS_ON_STACK: usize = 8;

struct Machine<'a> {
    memory: &'a mut Vec<Value>,
    initial: &'a [Value],
    std: &'a mut Vec<StdState>,
    code: &'a [Vec<IStmt>],
    image: &'a mut dyn Image,
    now: i64,
    left: u64,
    budget: u64,
    /// The loop running, the watchdog's place.
    at: Span,
}

impl Machine<'_> {
    fn tick(&mut self, span: Span) -> Run<()> {
        if self.left == 0 {
            // Where nothing finer is known, the loop that ran out of the budget.
            let span = if span == Span::default() {
                self.at
            } else {
                span
            };
            return Err(Box::new(Fault {
                span,
                cause: FaultCause::Watchdog(self.budget),
            }));
        }
        self.left -= 1;
        Ok(())
    }

    /// The address of `p` (a memory place), with `base` the frame's start.
    fn addr(&mut self, p: &Place, base: u32) -> Run<u32> {
        match p {
            Place::Mem(a) => Ok(base.wrapping_add(*a)),
            Place::Abs(a) => Ok(*a),
            Place::Offset(p, k) => Ok(self.addr(p, base)? + k),
            Place::Indexed {
                base: b,
                terms,
                span,
            } => {
                let mut a = self.addr(b, base)?;
                for (ix, lo, hi, stride) in terms {
                    let i = self.eval(ix, base)?.int();
                    if i < *lo || i > *hi {
                        return Err(Box::new(Fault {
                            span: *span,
                            cause: FaultCause::IndexOutOfRange {
                                index: i,
                                lo: *lo,
                                hi: *hi,
                            },
                        }));
                    }
                    a += (i - lo) as u32 * stride;
                }
                Ok(a)
            }
            _ => Ok(0),
        }
    }

    fn read(&mut self, p: &Place, e: Elem, base: u32) -> Run<Value> {
        Ok(match p {
            // The most frequent places first, without the address's detour.
            Place::Mem(a) => self.memory[base.wrapping_add(*a) as usize],
            Place::Abs(a) => self.memory[*a as usize],
            Place::InBit(w, b) => Value::Bool(self.image.input(*w) >> b & 1 == 1),
            Place::InWord(w) => coerce(Value::Uint(u64::from(self.image.input(*w))), e),
            Place::OutBit(w, b) => Value::Bool(self.image.output(*w) >> b & 1 == 1),
            Place::OutWord(w) => coerce(Value::Uint(u64::from(self.image.output(*w))), e),
            Place::Bit(inner, n, of) => {
                let v = self.read(inner, *of, base)?;
                Value::Bool(v.uint() >> n & 1 == 1)
            }
            _ => {
                let a = self.addr(p, base)?;
                self.memory[a as usize]
            }
        })
    }

    fn write(&mut self, p: &Place, e: Elem, v: Value, base: u32) -> Run<()> {
        let v = coerce(v, e);
        match p {
            Place::OutBit(w, b) => {
                let old = self.image.output(*w);
                let new = if v.bool() {
                    old | 1 << b
                } else {
                    old & !(1 << b)
                };
                self.image.set_output(*w, new);
            }
            Place::OutWord(w) => self.image.set_output(*w, v.uint() as u16),
            Place::InBit(..) | Place::InWord(_) => {}
            Place::Bit(inner, n, of) => {
                let old = self.read(inner, *of, base)?.uint();
                let new = if v.bool() {
                    old | 1 << n
                } else {
                    old & !(1 << n)
                };
                self.write(inner, *of, Value::Uint(new), base)?;
            }
            _ => {
                let a = self.addr(p, base)?;
                self.memory[a as usize] = v;
            }
        }
        Ok(())
    }

    fn stmts(&mut self, ss: &[IStmt], base: u32) -> Run<Flow> {
        for s in ss {
            match self.stmt(s, base)? {
                Flow::Next => {}
                other => return Ok(other),
            }
        }
        Ok(Flow::Next)
    }

    fn stmt(&mut self, s: &IStmt, base: u32) -> Run<Flow> {
        self.tick(Span::default())?;
        match s {
            IStmt::Assign(p, e, x) => {
                let v = self.eval(x, base)?;
                match p {
                    Place::Mem(a) => self.memory[base.wrapping_add(*a) as usize] = coerce(v, *e),
                    Place::Abs(a) => self.memory[*a as usize] = coerce(v, *e),
                    _ => self.write(p, *e, v, base)?,
                }
            }
            IStmt::CallFb {
                fb,
                instance,
                inputs,
                outputs,
            } => {
                let frame = self.addr(instance, base)?;
                for (offset, e, x) in inputs {
                    let v = self.eval(x, base)?;
                    self.memory[(frame + offset) as usize] = coerce(v, *e);
                }
                match fb {
                    FbKind::User(block) => {
                        // A RETURN in the block ends its call, not the caller's.
                        let code = self.code;
                        self.stmts(&code[*block], frame)?;
                    }
                    FbKind::Std(kind) => {
                        let state = self.memory[frame as usize].uint() as usize;
                        self.std_call(*kind, state, frame + 1);
                    }
                }
                for (offset, e, dst) in outputs {
                    let v = self.memory[(frame + offset) as usize];
                    self.write(dst, *e, v, base)?;
                }
            }
            IStmt::Eval(x) => {
                self.eval(x, base)?;
            }
            IStmt::Copy(dst, src, n) => {
                let (d, s) = (self.addr(dst, base)?, self.addr(src, base)?);
                for k in 0..*n {
                    self.memory[(d + k) as usize] = self.memory[(s + k) as usize];
                }
            }
            IStmt::If(arms, otherwise) => {
                for (c, body) in arms {
                    if self.eval(c, base)?.bool() {
                        return self.stmts(body, base);
                    }
                }
                return self.stmts(otherwise, base);
            }
            IStmt::Case(sel, arms, otherwise) => {
                let v = self.eval(sel, base)?.int();
                for (labels, body) in arms {
                    if labels.iter().any(|&(lo, hi)| lo <= v && v <= hi) {
                        return self.stmts(body, base);
                    }
                }
                return self.stmts(otherwise, base);
            }
            IStmt::For {
                var,
                elem,
                from,
                to,
                by,
                body,
                span,
            } => {
                let outer = std::mem::replace(&mut self.at, *span);
                let (from, to, by) = (
                    self.eval(from, base)?.int(),
                    self.eval(to, base)?.int(),
                    self.eval(by, base)?.int(),
                );
                let mut i = from;
                loop {
                    if by >= 0 && i > to || by < 0 && i < to {
                        break;
                    }
                    self.write(var, *elem, Value::Int(i), base)?;
                    match self.stmts(body, base)? {
                        Flow::Exit => break,
                        Flow::Return => return Ok(Flow::Return),
                        Flow::Next | Flow::Continue => {}
                    }
                    // The standard's loop: the variable as the body left it, plus the step.
                    i = self.read(var, *elem, base)?.int().saturating_add(by);
                    if by == 0 {
                        self.tick(Span::default())?;
                    }
                }
                self.at = outer;
            }
            IStmt::While(c, body, span) => {
                let outer = std::mem::replace(&mut self.at, *span);
                while self.eval(c, base)?.bool() {
                    match self.stmts(body, base)? {
                        Flow::Exit => break,
                        Flow::Return => return Ok(Flow::Return),
                        _ => {}
                    }
                }
                self.at = outer;
            }
            IStmt::Repeat(body, until, span) => {
                let outer = std::mem::replace(&mut self.at, *span);
                loop {
                    match self.stmts(body, base)? {
                        Flow::Exit => break,
                        Flow::Return => return Ok(Flow::Return),
                        _ => {}
                    }
                    if self.eval(until, base)?.bool() {
                        break;
                    }
                }
                self.at = outer;
            }
            IStmt::Exit => return Ok(Flow::Exit),
            IStmt::Continue => return Ok(Flow::Continue),
            IStmt::Return => return Ok(Flow::Return),
        }
        Ok(Flow::Next)
    }
}

impl Machine<'_> {
    fn eval(&mut self, x: &IExpr, base: u32) -> Run<Value> {
        self.tick(Span::default())?;
        Ok(match x {
            IExpr::Const(v) => *v,
            IExpr::Read(Place::Mem(a), _) => self.memory[base.wrapping_add(*a) as usize],
            IExpr::Read(Place::Abs(a), _) => self.memory[*a as usize],
            IExpr::Read(p, e) => self.read(p, *e, base)?,
            IExpr::Neg(a, e) => {
                let v = self.eval(a, base)?;
                match v {
                    Value::Real(r) => coerce(Value::Real(-r), *e),
                    v => coerce(Value::Int(v.int().wrapping_neg()), *e),
                }
            }
            IExpr::Not(a, e) => {
                let v = self.eval(a, base)?;
                match e {
                    Elem::Bool => Value::Bool(!v.bool()),
                    _ => coerce(Value::Uint(!v.uint()), *e),
                }
            }
            IExpr::Conv(to, a) => {
                let v = self.eval(a, base)?;
                // A real to an integer rounds to the nearest (IEC 61131-3, §6.6.1.6: REAL_TO_INT
                // rounds); to BOOL, anything not zero is TRUE.
                let v = match (v, to.is_int() || to.is_bits() && *to != Elem::Bool) {
                    (Value::Real(r), true) => Value::Int(r.round() as i64),
                    (v, _) => v,
                };
                coerce(v, *to)
            }
            IExpr::Cmp(op, e, a, b) => {
                let (a, b) = (self.eval(a, base)?, self.eval(b, base)?);
                let ord = if e.is_real() {
                    a.real().partial_cmp(&b.real())
                } else if matches!(a, Value::Uint(_)) || matches!(b, Value::Uint(_)) {
                    Some(a.uint().cmp(&b.uint()))
                } else {
                    Some(a.int().cmp(&b.int()))
                };
                use std::cmp::Ordering::*;
                Value::Bool(match (op, ord) {
                    (_, None) => matches!(op, BinOp::Ne),
                    (BinOp::Eq, Some(o)) => o == Equal,
                    (BinOp::Ne, Some(o)) => o != Equal,
                    (BinOp::Lt, Some(o)) => o == Less,
                    (BinOp::Le, Some(o)) => o != Greater,
                    (BinOp::Gt, Some(o)) => o == Greater,
                    (BinOp::Ge, Some(o)) => o != Less,
                    _ => false,
                })
            }
            IExpr::Bin(op, e, a, b, span) => {
                let (a, b) = (self.eval(a, base)?, self.eval(b, base)?);
                self.binary(*op, *e, a, b, *span)?
            }
            IExpr::Call(block, (start, len), args, result, e) => {
                // The inputs are all evaluated before the frame is reset (an input may call
                // the same function); on the stack for the usual few, so a call allocates
                // nothing.
                let mut few = [Value::Int(0); ARGS_ON_STACK];
                let mut many = Vec::new();
                let values: &mut [Value] = if args.len() <= ARGS_ON_STACK {
                    &mut few[..args.len()]
                } else {
                    many.resize(args.len(), Value::Int(0));
                    &mut many
                };
                for (slot, (_, pe, x)) in values.iter_mut().zip(args) {
                    *slot = coerce(self.eval(x, base)?, *pe);
                }
                let range = *start as usize..(*start + *len) as usize;
                self.memory[range.clone()].copy_from_slice(&self.initial[range]);
                for ((addr, _, _), v) in args.iter().zip(values.iter()) {
                    self.memory[*addr as usize] = *v;
                }
                let code = self.code;
                self.stmts(&code[*block], 0)?;
                coerce(self.memory[*result as usize], *e)
            }
            IExpr::Std(f, e, args) => {
                let mut few = [Value::Int(0); ARGS_ON_STACK];
                let mut many = Vec::new();
                let vs: &mut [Value] = if args.len() <= ARGS_ON_STACK {
                    &mut few[..args.len()]
                } else {
                    many.resize(args.len(), Value::Int(0));
                    &mut many
                };
                for (slot, a) in vs.iter_mut().zip(args) {
                    *slot = self.eval(a, base)?;
                }
                std_fn(*f, *e, vs)
            }
        })
    }

    fn binary(&mut self, op: BinOp, e: Elem, a: Value, b: Value, span: Span) -> Run<Value> {
        use BinOp::*;
        if e.is_real() {
            let (x, y) = (a.real(), b.real());
            return Ok(coerce(
                Value::Real(match op {
                    Add => x + y,
                    Sub => x - y,
                    Mul => x * y,
                    Div => x / y,
                    Power => x.powf(y),
                    _ => 0.0,
                }),
                e,
            ));
        }
        if e == Elem::Bool {
            let (x, y) = (a.bool(), b.bool());
            return Ok(Value::Bool(match op {
                And => x && y,
                Or => x || y,
                Xor => x != y,
                _ => false,
            }));
        }
        if matches!(op, And | Or | Xor) {
            let (x, y) = (a.uint(), b.uint());
            return Ok(coerce(
                Value::Uint(match op {
                    And => x & y,
                    Or => x | y,
                    _ => x ^ y,
                }),
                e,
            ));
        }
        if matches!(op, Div | Mod) && b.int() == 0 && b.uint() == 0 {
            return Err(Box::new(Fault {
                span,
                cause: FaultCause::DivisionByZero,
            }));
        }
        let unsigned = e.int_range().is_some_and(|(lo, _)| lo == 0) || e.is_bits();
        let v = if unsigned {
            let (x, y) = (a.uint(), b.uint());
            Value::Uint(match op {
                Add => x.wrapping_add(y),
                Sub => x.wrapping_sub(y),
                Mul => x.wrapping_mul(y),
                Div => x / y,
                Mod => x % y,
                Power => x.wrapping_pow(u32::try_from(y).unwrap_or(u32::MAX)),
                _ => 0,
            })
        } else {
            let (x, y) = (a.int(), b.int());
            Value::Int(match op {
                Add => x.wrapping_add(y),
                Sub => x.wrapping_sub(y),
                Mul => x.wrapping_mul(y),
                Div => x.wrapping_div(y),
                Mod => x.wrapping_rem(y),
                Power => x.wrapping_pow(u32::try_from(y).unwrap_or(0)),
                _ => 0,
            })
        };
        Ok(coerce(v, e))
    }

    fn std_call(&mut self, kind: StdFb, state: usize, pins: u32) {
        let m = &mut *self.memory;
        let at = |k: u32| pins as usize + k as usize;
        let b = |m: &Vec<Value>, k: u32| m[at(k)].bool();
        let i = |m: &Vec<Value>, k: u32| m[at(k)].int();
        match (&mut self.std[state], kind) {
            (StdState::Ton(t), _) => {
                t.call(self.now, b(m, 0), i(m, 1));
                (m[at(2)], m[at(3)]) = (Value::Bool(t.q), Value::Int(t.et));
            }
            (StdState::Tof(t), _) => {
                t.call(self.now, b(m, 0), i(m, 1));
                (m[at(2)], m[at(3)]) = (Value::Bool(t.q), Value::Int(t.et));
            }
            (StdState::Tp(t), _) => {
                t.call(self.now, b(m, 0), i(m, 1));
                (m[at(2)], m[at(3)]) = (Value::Bool(t.q), Value::Int(t.et));
            }
            (StdState::RTrig(t), _) => {
                t.call(b(m, 0));
                m[at(1)] = Value::Bool(t.q);
            }
            (StdState::FTrig(t), _) => {
                t.call(b(m, 0));
                m[at(1)] = Value::Bool(t.q);
            }
            (StdState::Sr(t), _) => {
                t.call(b(m, 0), b(m, 1));
                m[at(2)] = Value::Bool(t.q1);
            }
            (StdState::Rs(t), _) => {
                t.call(b(m, 0), b(m, 1));
                m[at(2)] = Value::Bool(t.q1);
            }
            (StdState::Ctu(t), _) => {
                t.call(b(m, 0), b(m, 1), i(m, 2) as i16);
                (m[at(3)], m[at(4)]) = (Value::Bool(t.q), Value::Int(t.cv.into()));
            }
            (StdState::Ctd(t), _) => {
                t.call(b(m, 0), b(m, 1), i(m, 2) as i16);
                (m[at(3)], m[at(4)]) = (Value::Bool(t.q), Value::Int(t.cv.into()));
            }
            (StdState::Ctud(t), _) => {
                t.call(b(m, 0), b(m, 1), b(m, 2), b(m, 3), i(m, 4) as i16);
                (m[at(5)], m[at(6)], m[at(7)]) = (
                    Value::Bool(t.qu),
                    Value::Bool(t.qd),
                    Value::Int(t.cv.into()),
                );
            }
        }
    }
}

fn std_fn(f: StdFn, e: Elem, vs: &[Value]) -> Value {
    let lt = |a: Value, b: Value| {
        if e.is_real() {
            a.real() < b.real()
        } else if matches!(a, Value::Uint(_)) {
            a.uint() < b.uint()
        } else {
            a.int() < b.int()
        }
    };
    let v = match f {
        StdFn::Abs => match vs[0] {
            Value::Real(r) => Value::Real(r.abs()),
            Value::Int(i) => Value::Int(i.wrapping_abs()),
            v => v,
        },
        StdFn::Sqrt => Value::Real(vs[0].real().sqrt()),
        StdFn::Min => vs
            .iter()
            .copied()
            .reduce(|a, b| if lt(b, a) { b } else { a })
            .unwrap_or(Value::Int(0)),
        StdFn::Max => vs
            .iter()
            .copied()
            .reduce(|a, b| if lt(a, b) { b } else { a })
            .unwrap_or(Value::Int(0)),
        StdFn::Limit => {
            let (mn, x, mx) = (vs[0], vs[1], vs[2]);
            if lt(x, mn) {
                mn
            } else if lt(mx, x) {
                mx
            } else {
                x
            }
        }
        StdFn::Sel => {
            if vs[0].bool() {
                vs[2]
            } else {
                vs[1]
            }
        }
        StdFn::Mux => {
            // An index past the inputs selects the last (the standard leaves it open).
            let k = usize::try_from(vs[0].int()).unwrap_or(0).min(vs.len() - 2);
            vs[1 + k]
        }
        StdFn::Shl | StdFn::Shr | StdFn::Rol | StdFn::Ror => {
            let bits = e.bits().unwrap_or(64);
            let x = vs[0].uint();
            let n = u32::try_from(vs[1].int().max(0)).unwrap_or(u32::MAX);
            let mask = if bits == 64 {
                u64::MAX
            } else {
                (1u64 << bits) - 1
            };
            Value::Uint(match f {
                StdFn::Shl => x.checked_shl(n).unwrap_or(0) & mask,
                StdFn::Shr => x.checked_shr(n).unwrap_or(0),
                StdFn::Rol => {
                    let n = n % bits;
                    ((x << n) | x.checked_shr(bits - n).unwrap_or(0)) & mask
                }
                _ => {
                    let n = n % bits;
                    (x >> n | x.checked_shl(bits - n).unwrap_or(0)) & mask
                }
            })
        }
    };
    coerce(v, e)
}

mod compile;
use compile::Compiler;

/// `v` written as a literal of type `e` (IEC 61131-3 §6.3.3: bit strings in base 16 with
/// their width's digits, durations as `T#` with their units from days down to nanoseconds).
fn literal(v: Value, e: Elem) -> String {
    let hex = |digits: usize| format!("16#{:0digits$X}", v.int() as u64 & mask(digits * 4));
    match e {
        Elem::Bool => if v.int() != 0 { "TRUE" } else { "FALSE" }.to_owned(),
        Elem::Byte => hex(2),
        Elem::Word => hex(4),
        Elem::Dword => hex(8),
        Elem::Lword => hex(16),
        Elem::Usint | Elem::Uint | Elem::Udint | Elem::Ulint => match v {
            Value::Uint(u) => u.to_string(),
            other => (other.int() as u64).to_string(),
        },
        Elem::Sint | Elem::Int | Elem::Dint | Elem::Lint => v.int().to_string(),
        Elem::Real | Elem::Lreal => match v {
            Value::Real(r) => format!("{r:?}"),
            other => format!("{:?}", other.int() as f64),
        },
        Elem::Time | Elem::Ltime => duration_literal(v.int()),
    }
}

/// The mask of the low `bits` bits.
fn mask(bits: usize) -> u64 {
    if bits >= 64 {
        u64::MAX
    } else {
        (1u64 << bits) - 1
    }
}

/// Nanoseconds as a `T#` literal: `T#0s`, `T#1s200ms`, `T#-2m`, `T#1d2h3m4s5ms6us7ns`.
fn duration_literal(ns: i64) -> String {
    const UNITS: [(&str, u128); 7] = [
        ("d", 86_400_000_000_000),
        ("h", 3_600_000_000_000),
        ("m", 60_000_000_000),
        ("s", 1_000_000_000),
        ("ms", 1_000_000),
        ("us", 1_000),
        ("ns", 1),
    ];
    if ns == 0 {
        return "T#0s".into();
    }
    let mut out = String::from(if ns < 0 { "T#-" } else { "T#" });
    let mut rest = u128::from(ns.unsigned_abs());
    for (unit, size) in UNITS {
        if rest >= size {
            out.push_str(&format!("{}{unit}", rest / size));
            rest %= size;
        }
    }
    out
}
