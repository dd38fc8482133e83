//! The agreed variables through which a Structured Text program tells the rig what the
//! built-in program tells it: its state, floor and target, the calls it holds, and what it did
//! (an event buffer, drained after each scan as a PLC's diagnostic buffer is read). Each is
//! optional; a program that declares one with a wrong type is refused before the run, at the
//! declaration, with the type it must have.
//!
//! The types are the library's (`controllers/lab.st`): `LiftState`, `LiftEventKind`,
//! `CallSource`, `LiftReason` and the structure `LiftEvent`. They are checked by their shape,
//! not their names: an enumeration's values are matched by name against the agreed ones, so a
//! program may declare its own copy with only the values it uses.

use crate::dispatch::{Algorithm, HallDir, ServedCall, Source};
use crate::program::ControllerConfig;
use crate::program::{HaltReason, InitStart, LostReason, ProgramEventKind, State};
use asi_phy::SimTime;
use st::check::{Checked, Type, Var};
use st::run::{Plc, Value};
use st::source::{Diagnostic, Span};
use st::types::Elem;

/// Set before each scan: the safety logic's EStopOut (`TRUE`: no STOP demand). BOOL.
pub const ESTOP_OUT: &str = "EStopOut";
/// Read after each scan: the restart of the STOP circuit. BOOL.
pub const RESTART: &str = "Restart";
/// Read after each scan: the load's overload signal to the safety logic. BOOL.
pub const OVERLOADED: &str = "Overloaded";
/// Set before each scan: the PLC's clock, the time since the run began. TIME or LTIME.
pub const NOW: &str = "Now";
/// Set once, before the first scan: the floors the scenario's lift serves (`[controller]
/// floors`, 2 to 4 on the lab bus). An integer, not a CONSTANT.
pub const FLOORS: &str = "Floors";
/// Set once, before the first scan: the scenario's control algorithm (`[controller]
/// algorithm`), an enumeration of the values of [`ALGORITHM_VALUES`], not a CONSTANT.
pub const ALGORITHM: &str = "Algorithm";
/// Read for the report: the program's state, an enumeration of the values of [`STATE_VALUES`].
pub const STATE: &str = "State";
/// Read for the report: the floor the program counts the cabin at. An integer.
pub const FLOOR: &str = "Floor";
/// Read for the report: the floor the program goes to. An integer.
pub const TARGET: &str = "Target";
/// The cabin calls held, in the program's order: `ARRAY [a..b] OF` an integer, the first
/// [`CABIN_CALL_COUNT`] of them.
pub const CABIN_CALLS: &str = "CabinCalls";
/// How many of [`CABIN_CALLS`] hold a call. An integer.
pub const CABIN_CALL_COUNT: &str = "CabinCallCount";
/// The hall calls held, as [`CABIN_CALLS`].
pub const HALL_CALLS: &str = "HallCalls";
/// How many of [`HALL_CALLS`] hold a call.
pub const HALL_CALL_COUNT: &str = "HallCallCount";
/// The event buffer: `ARRAY [a..b] OF LiftEvent`, the first [`EVENT_COUNT`] of them written in
/// this scan, oldest first.
pub const EVENTS: &str = "Events";
/// How many events [`EVENTS`] holds; set to 0 by the rig after it read them. An integer.
pub const EVENT_COUNT: &str = "EventCount";

/// The values of the state's enumeration and the states they name.
pub const STATE_VALUES: [(&str, State); 10] = [
    ("WaitingForInputs", State::WaitingForInputs),
    ("Initialising", State::Initialising),
    ("BusFault", State::BusFault),
    ("AtFloor", State::AtFloor),
    ("OverloadFault", State::OverloadFault),
    ("MovingUp", State::MovingUp),
    ("MovingDown", State::MovingDown),
    ("Braking", State::Braking),
    ("StopFault", State::StopFault),
    ("Halted", State::Halted),
];

/// The values of the algorithm's enumeration (`LiftAlgorithm`) and the algorithms they name.
pub const ALGORITHM_VALUES: [(&str, Algorithm); 2] = [
    ("Fifo", Algorithm::Fifo),
    ("Collective", Algorithm::Collective),
];

/// The event kinds (`LiftEvent.Kind`), as [`ProgramEventKind`] names them.
pub const KIND_VALUES: [&str; 21] = [
    "InitStarted",
    "Initialised",
    "CallStored",
    "CallLost",
    "Departed",
    "Passed",
    "Braking",
    "Arrived",
    "Served",
    "StopDemanded",
    "StopFault",
    "Resumed",
    "OverloadFault",
    "OverloadCleared",
    "Halted",
    "Continued",
    "BusFault",
    "BusRestored",
    "InitHeld",
    "PositionLost",
    "None",
];

/// A call's source (`LiftEvent.Source`).
pub const SOURCE_VALUES: [&str; 3] = ["Cabin", "HallUp", "HallDown"];

/// The reasons (`LiftEvent.Reason`): a hold's ([`HaltReason`]), a lost count's
/// ([`LostReason`]), an initialisation's start ([`InitStart`]); `NoVane` is both a hold's and
/// a lost count's, which the kind tells apart.
pub const REASON_VALUES: [&str; 16] = [
    "NoReason",
    "DoorOpen",
    "Overload",
    "ConverterFault",
    "NoPower",
    "Stop",
    "NoVane",
    "MovedByHand",
    "WrongVane",
    "BeyondEndFloor",
    "MissedLevel",
    "StuckSensor",
    "ThesisRoutine",
    "Floor1Track",
    "Level",
    "BelowFloor1",
];

/// The fields of `LiftEvent`, each with what its type must be.
const FIELDS: [(&str, FieldTy); 6] = [
    ("Kind", FieldTy::Enum(&KIND_VALUES)),
    ("Floor", FieldTy::Int),
    ("Other", FieldTy::Int),
    ("Source", FieldTy::Enum(&SOURCE_VALUES)),
    ("Reason", FieldTy::Enum(&REASON_VALUES)),
    ("StoredAt", FieldTy::Time),
];

#[derive(Clone, Copy)]
enum FieldTy {
    Int,
    Time,
    Enum(&'static [&'static str]),
}

/// An enumeration's numbers mapped to the agreed values' indices.
type EnumMap = Vec<(i64, usize)>;

/// Where the agreed variables are in the program's memory, and how to read them.
#[derive(Clone, Debug, Default)]
pub(super) struct Agreed {
    pub(super) estop_out: Option<u32>,
    pub(super) restart: Option<u32>,
    pub(super) overloaded: Option<u32>,
    pub(super) now: Option<(u32, Elem)>,
    floors: Option<(u32, Elem)>,
    algorithm: Option<(u32, EnumMap)>,
    state: Option<(u32, EnumMap)>,
    floor: Option<u32>,
    target: Option<u32>,
    cabin_calls: Option<Calls>,
    hall_calls: Option<Calls>,
    events: Option<Buffer>,
}

#[derive(Clone, Debug)]
struct Calls {
    base: u32,
    len: u32,
    count: u32,
}

#[derive(Clone, Debug)]
struct Buffer {
    base: u32,
    len: u32,
    stride: u32,
    count: (u32, Elem),
    /// Each field's offset in an element, in [`FIELDS`]' order, and the enumerations' maps.
    offsets: [u32; 6],
    kinds: EnumMap,
    sources: EnumMap,
    reasons: EnumMap,
    /// The buffer's declaration: where a wrong event is reported.
    pub(super) span: Span,
}

/// An event in the buffer that says what no event can (a floor past 255, a reason that is
/// not the kind's): the PLC goes to STOP, as for a fault.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct BadEvent {
    pub(super) span: Span,
    pub(super) entry: i64,
}

/// The declaration of `name` in the program or the globals.
fn find<'a>(c: &'a Checked, name: &str) -> Option<&'a Var> {
    let program = c.program()?;
    program
        .vars
        .iter()
        .chain(c.globals.iter())
        .find(|v| v.name.eq_ignore_ascii_case(name) && v.at.is_none())
}

fn int_elem(t: &Type) -> Option<Elem> {
    match t {
        Type::Elem(e) | Type::Subrange(e, _, _) if e.is_int() => Some(*e),
        _ => None,
    }
}

fn enum_map(c: &Checked, t: &Type, agreed: &[&str]) -> Result<EnumMap, String> {
    let Type::Enum(i) = t else {
        return Err(format!(
            "must be an enumeration of some of the values {}",
            agreed.join(", ")
        ));
    };
    let mut map = Vec::new();
    for (name, n) in &c.enums[*i].values {
        let Some(k) = agreed.iter().position(|a| a.eq_ignore_ascii_case(name)) else {
            return Err(format!(
                "its enumeration has the value {name}, which is not one of {}",
                agreed.join(", ")
            ));
        };
        map.push((i64::try_from(*n).unwrap_or(i64::MAX), k));
    }
    Ok(map)
}

impl Agreed {
    /// The agreed variables `checked` declares, with the program's memory `plc`; every
    /// declaration of a wrong type as an error at its place.
    pub(super) fn find(checked: &Checked, plc: &Plc) -> Result<Agreed, Vec<Diagnostic>> {
        let mut errors = Vec::new();
        let mut a = Agreed::default();
        let mut wrong = |v: &Var, what: &str| {
            errors.push(Diagnostic::error(
                v.span,
                format!(
                    "`{}` is a variable the rig reads or sets (the agreed interface): it {what}",
                    v.name
                ),
            ));
        };
        let addr = |v: &Var| plc.address(&v.name);
        for (name, slot) in [
            (ESTOP_OUT, &mut a.estop_out),
            (RESTART, &mut a.restart),
            (OVERLOADED, &mut a.overloaded),
        ] {
            if let Some(v) = find(checked, name) {
                if v.ty == Type::Elem(Elem::Bool) {
                    *slot = addr(v);
                } else {
                    wrong(v, "must be a BOOL");
                }
            }
        }
        if let Some(v) = find(checked, NOW) {
            match v.ty {
                Type::Elem(e @ (Elem::Time | Elem::Ltime)) => a.now = addr(v).map(|at| (at, e)),
                _ => wrong(v, "must be a TIME or an LTIME"),
            }
        }
        for name in [FLOORS, ALGORITHM] {
            let Some(v) = find(checked, name) else {
                continue;
            };
            if v.constant {
                wrong(
                    v,
                    "is set from the scenario before the first scan, so it cannot be a CONSTANT",
                );
            } else if name == FLOORS {
                match int_elem(&v.ty) {
                    Some(e) => a.floors = addr(v).map(|at| (at, e)),
                    None => wrong(v, "must be of an integer type"),
                }
            } else {
                let names = ALGORITHM_VALUES.map(|(n, _)| n);
                match enum_map(checked, &v.ty, &names) {
                    Ok(m) => a.algorithm = addr(v).map(|at| (at, m)),
                    Err(e) => wrong(v, &e),
                }
            }
        }
        if let Some(v) = find(checked, STATE) {
            let names = STATE_VALUES.map(|(n, _)| n);
            match enum_map(checked, &v.ty, &names) {
                Ok(m) => a.state = addr(v).map(|at| (at, m)),
                Err(e) => wrong(v, &e),
            }
        }
        for (name, slot) in [(FLOOR, &mut a.floor), (TARGET, &mut a.target)] {
            if let Some(v) = find(checked, name) {
                if int_elem(&v.ty).is_some() {
                    *slot = addr(v);
                } else {
                    wrong(v, "must be of an integer type");
                }
            }
        }
        for (list, count, slot) in [
            (CABIN_CALLS, CABIN_CALL_COUNT, &mut a.cabin_calls),
            (HALL_CALLS, HALL_CALL_COUNT, &mut a.hall_calls),
        ] {
            let (l, n) = (find(checked, list), find(checked, count));
            let array = l.and_then(|v| match &v.ty {
                Type::Array(arr) if arr.dims.len() == 1 && int_elem(&arr.elem).is_some() => {
                    Some((arr.dims[0].1 - arr.dims[0].0 + 1) as u32)
                }
                _ => None,
            });
            if let (Some(v), None) = (l, array) {
                wrong(v, "must be a one-dimensional ARRAY of an integer type");
            }
            if let Some(v) = n {
                if int_elem(&v.ty).is_none() {
                    wrong(v, "must be of an integer type");
                }
            }
            match (l, n) {
                (Some(lv), Some(nv)) => {
                    if let (Some(len), Some(base), Some(count), Some(_)) =
                        (array, addr(lv), addr(nv), int_elem(&nv.ty))
                    {
                        *slot = Some(Calls { base, len, count });
                    }
                }
                (Some(v), None) => wrong(v, &format!("needs `{count}` beside it")),
                (None, Some(v)) => wrong(v, &format!("needs `{list}` beside it")),
                (None, None) => {}
            }
        }
        let (ev, n) = (find(checked, EVENTS), find(checked, EVENT_COUNT));
        match (ev, n) {
            (Some(v), Some(nv)) => match (Self::buffer(checked, plc, v), int_elem(&nv.ty)) {
                (Ok(mut b), Some(e)) => {
                    if let Some(at) = addr(nv) {
                        b.count = (at, e);
                        a.events = Some(b);
                    }
                }
                (Err(e), _) => wrong(v, &e),
                (Ok(_), None) => wrong(nv, "must be of an integer type"),
            },
            (Some(v), None) => wrong(v, &format!("needs `{EVENT_COUNT}` beside it")),
            (None, Some(v)) => wrong(v, &format!("needs `{EVENTS}` beside it")),
            (None, None) => {}
        }
        if errors.is_empty() {
            Ok(a)
        } else {
            Err(errors)
        }
    }

    fn buffer(c: &Checked, plc: &Plc, v: &Var) -> Result<Buffer, String> {
        let shape = "must be a one-dimensional ARRAY OF a structure with the fields Kind, \
                     Floor, Other, Source, Reason and StoredAt (the library's LiftEvent)";
        let Type::Array(arr) = &v.ty else {
            return Err(shape.to_owned());
        };
        let Type::Struct(si) = &arr.elem else {
            return Err(shape.to_owned());
        };
        if arr.dims.len() != 1 {
            return Err(shape.to_owned());
        }
        let s = &c.structs[*si];
        let mut offsets = [0u32; 6];
        let (mut kinds, mut sources, mut reasons) = (Vec::new(), Vec::new(), Vec::new());
        for (k, (name, want)) in FIELDS.iter().enumerate() {
            let Some(at) = s
                .fields
                .iter()
                .position(|f| f.name.eq_ignore_ascii_case(name))
            else {
                return Err(format!("{shape}: `{}` has no field {name}", s.name));
            };
            let f = &s.fields[at];
            let ok = match want {
                FieldTy::Int => int_elem(&f.ty).is_some(),
                FieldTy::Time => matches!(f.ty, Type::Elem(Elem::Time | Elem::Ltime)),
                FieldTy::Enum(values) => {
                    let m =
                        enum_map(c, &f.ty, values).map_err(|e| format!("its field {name} {e}"))?;
                    match k {
                        0 => kinds = m,
                        3 => sources = m,
                        _ => reasons = m,
                    }
                    true
                }
            };
            if !ok {
                return Err(format!(
                    "its field {name} must be {}",
                    match want {
                        FieldTy::Int => "of an integer type",
                        _ => "a TIME or an LTIME",
                    }
                ));
            }
            // Each field of the agreed ones is one value in memory.
            offsets[k] = at as u32;
        }
        if s.fields.len() != 6 {
            return Err(format!("{shape}, and no others"));
        }
        Ok(Buffer {
            base: plc.address(&v.name).unwrap_or(0),
            len: (arr.dims[0].1 - arr.dims[0].0 + 1) as u32,
            stride: 6,
            count: (0, Elem::Int),
            offsets,
            kinds,
            sources,
            reasons,
            span: v.span,
        })
    }

    /// The scenario's settings into the program's `Floors` and `Algorithm`, where it
    /// declares them (an algorithm its enumeration has no value for is not written).
    pub(super) fn configure(&self, plc: &mut Plc, settings: &ControllerConfig) {
        if let Some((at, e)) = self.floors {
            plc.write(at, Value::Int(i64::from(settings.floors)), e);
        }
        if let Some((at, map)) = &self.algorithm {
            let k = ALGORITHM_VALUES
                .iter()
                .position(|(_, a)| *a == settings.algorithm);
            if let Some(&(n, _)) = map.iter().find(|(_, i)| Some(*i) == k) {
                // An enumeration's value is a DINT in the program's memory.
                plc.write(*at, Value::Int(n), Elem::Dint);
            }
        }
    }

    /// Whether the program names the calls each stop serves (it has the event buffer).
    pub(super) fn names_served_calls(&self) -> bool {
        self.events.is_some()
    }

    pub(super) fn state(&self, plc: &Plc) -> Option<State> {
        let (at, map) = self.state.as_ref()?;
        let Some(Value::Int(n)) = plc.read(*at) else {
            return None;
        };
        let k = map.iter().find(|(v, _)| *v == n)?.1;
        Some(STATE_VALUES[k].1)
    }

    pub(super) fn floor(&self, plc: &Plc) -> Option<u8> {
        small(plc, self.floor?)
    }

    pub(super) fn target(&self, plc: &Plc) -> Option<u8> {
        small(plc, self.target?)
    }

    /// The cabin and hall calls, if the program tells either.
    pub(super) fn calls(&self, plc: &Plc) -> Option<(Vec<u8>, Vec<u8>)> {
        if self.cabin_calls.is_none() && self.hall_calls.is_none() {
            return None;
        }
        let list = |c: &Option<Calls>| {
            let Some(c) = c else { return Vec::new() };
            let n = plc
                .read(c.count)
                .map_or(0, |v| v_int(v).clamp(0, i64::from(c.len)));
            (0..n as u32)
                .filter_map(|k| small(plc, c.base + k))
                .collect()
        };
        Some((list(&self.cabin_calls), list(&self.hall_calls)))
    }

    /// The events of this scan at `now`, oldest first, and the count set back to 0; an
    /// event that says what none can stops at it.
    pub(super) fn drain(
        &self,
        plc: &mut Plc,
        now: SimTime,
        out: &mut Vec<crate::program::Event>,
    ) -> Result<(), BadEvent> {
        let Some(b) = &self.events else {
            return Ok(());
        };
        let n = plc.read(b.count.0).map_or(0, v_int);
        plc.write(b.count.0, Value::Int(0), b.count.1);
        let n = n.clamp(0, i64::from(b.len)) as u32;
        for k in 0..n {
            let at = b.base + k * b.stride;
            let field = |f: usize| plc.read(at + b.offsets[f]).map_or(0, v_int);
            let bad = BadEvent {
                span: b.span,
                entry: i64::from(k) + 1,
            };
            let kind = event(b, &field).ok_or(bad)?;
            if let Some(kind) = kind {
                out.push(crate::program::Event { at: now, kind });
            }
        }
        Ok(())
    }
}

fn v_int(v: Value) -> i64 {
    match v {
        Value::Bool(b) => i64::from(b),
        Value::Int(i) => i,
        Value::Uint(u) => i64::try_from(u).unwrap_or(i64::MAX),
        Value::Real(r) => r as i64,
    }
}

fn small(plc: &Plc, at: u32) -> Option<u8> {
    u8::try_from(v_int(plc.read(at)?)).ok()
}

fn lookup(map: &EnumMap, n: i64) -> Option<usize> {
    map.iter().find(|(v, _)| *v == n).map(|&(_, k)| k)
}

/// The event an entry of the buffer holds (`None` inside for the kind `None`, which the
/// program may use for an entry it cleared); `None` outside for an entry no event can be.
fn event(b: &Buffer, field: &dyn Fn(usize) -> i64) -> Option<Option<ProgramEventKind>> {
    let kind = KIND_VALUES[lookup(&b.kinds, field(0))?];
    let floor = || u8::try_from(field(1)).ok();
    let other = || u8::try_from(field(2)).ok();
    let source = || lookup(&b.sources, field(3)).map(|k| SOURCE_VALUES[k]);
    let reason = || lookup(&b.reasons, field(4)).map(|k| REASON_VALUES[k]);
    let halt = || {
        Some(match reason()? {
            "DoorOpen" => HaltReason::DoorOpen,
            "Overload" => HaltReason::Overload,
            "ConverterFault" => HaltReason::ConverterFault,
            "NoPower" => HaltReason::NoPower,
            "Stop" => HaltReason::Stop,
            "NoVane" => HaltReason::NoVane,
            _ => return None,
        })
    };
    let call_source = || match source()? {
        "Cabin" => Some(Source::Cabin),
        _ => Some(Source::Hall),
    };
    use ProgramEventKind as K;
    Some(Some(match kind {
        "None" => return Some(None),
        "InitStarted" => K::InitStarted {
            start: match reason()? {
                "ThesisRoutine" => InitStart::ThesisRoutine,
                "Floor1Track" => InitStart::Floor1Track,
                "Level" => InitStart::Level,
                "BelowFloor1" => InitStart::BelowFloor1,
                _ => return None,
            },
        },
        "Initialised" => K::Initialised,
        "CallStored" => K::CallStored {
            floor: floor()?,
            source: call_source()?,
        },
        "CallLost" => K::CallLost {
            floor: floor()?,
            source: call_source()?,
        },
        "Departed" => K::Departed {
            from: floor()?,
            to: other()?,
        },
        "Passed" => K::Passed { floor: floor()? },
        "Braking" => K::Braking { floor: floor()? },
        "Arrived" => K::Arrived { floor: floor()? },
        "Served" => {
            let (source, hall) = match source()? {
                "Cabin" => (Source::Cabin, None),
                "HallUp" => (Source::Hall, Some(HallDir::Up)),
                _ => (Source::Hall, Some(HallDir::Down)),
            };
            K::Served(ServedCall {
                floor: floor()?,
                source,
                hall,
                stored_at: SimTime::from_nanos(u64::try_from(field(5)).ok()?),
            })
        }
        "StopDemanded" => K::StopDemanded {
            stop_at: floor()?,
            dropped: match other()? {
                0 => None,
                f => Some(f),
            },
        },
        "StopFault" => K::StopFault,
        "Resumed" => K::Resumed,
        "OverloadFault" => K::OverloadFault,
        "OverloadCleared" => K::OverloadCleared,
        "Halted" => K::Halted(halt()?),
        "Continued" => K::Continued,
        "BusFault" => K::BusFault,
        "BusRestored" => K::BusRestored,
        "InitHeld" => K::InitHeld(halt()?),
        "PositionLost" => K::PositionLost {
            why: match reason()? {
                "MovedByHand" => LostReason::MovedByHand,
                "WrongVane" => LostReason::WrongVane,
                "BeyondEndFloor" => LostReason::BeyondEndFloor,
                "MissedLevel" => LostReason::MissedLevel,
                "NoVane" => LostReason::NoVane,
                "StuckSensor" => LostReason::StuckSensor,
                _ => return None,
            },
        },
        _ => return None,
    }))
}

#[cfg(test)]
mod tests {
    use crate::structured::StProgram;

    const TYPES: &str = "TYPE
  LiftState : (AtFloor, MovingUp);
  LiftEventKind : (Departed, Served, None);
  CallSource : (Cabin, HallUp, HallDown);
  LiftReason : (NoReason, DoorOpen);
  LiftEvent : STRUCT Kind : LiftEventKind; Floor : INT; Other : INT; Source : CallSource;
    Reason : LiftReason; StoredAt : TIME; END_STRUCT;
END_TYPE
";

    fn refused(program: &str) -> String {
        match StProgram::compile("p.st", &format!("{TYPES}{program}")) {
            Err(e) => e.rendered,
            Ok(_) => panic!("accepted: {program}"),
        }
    }

    /// The agreed names declared with the agreed types are taken; with others, refused at
    /// the declaration with the type they must have.
    #[test]
    fn the_agreed_variables_are_type_checked_at_compile_time() {
        let ok = "PROGRAM P
VAR State : LiftState; Floor, Target : INT; Now : TIME;
  Events : ARRAY [1..8] OF LiftEvent; EventCount : INT;
  CabinCalls, HallCalls : ARRAY [1..4] OF INT; CabinCallCount, HallCallCount : INT;
END_VAR
END_PROGRAM";
        let p =
            StProgram::compile("p.st", &format!("{TYPES}{ok}")).unwrap_or_else(|e| panic!("{e}"));
        assert!(p.agreed.names_served_calls());
        let r =
            refused("PROGRAM P VAR Floor : REAL; Now : INT; Restart : INT; END_VAR END_PROGRAM");
        assert!(r.contains("p.st:9:15: error: `Floor` is a variable the rig reads or sets (the agreed interface): it must be of an integer type"), "{r}");
        assert!(r.contains("`Now` is a variable the rig reads or sets (the agreed interface): it must be a TIME or an LTIME"), "{r}");
        assert!(r.contains("`Restart` is a variable the rig reads or sets (the agreed interface): it must be a BOOL"), "{r}");
        let r = refused(
            "TYPE Mood : (Happy); END_TYPE PROGRAM P VAR State : Mood; END_VAR END_PROGRAM",
        );
        assert!(
            r.contains("its enumeration has the value HAPPY, which is not one of WaitingForInputs"),
            "{r}"
        );
        let r = refused(
            "PROGRAM P VAR Events : ARRAY [1..8] OF INT; EventCount : INT; END_VAR END_PROGRAM",
        );
        assert!(r.contains("`Events` is a variable the rig reads or sets (the agreed interface): it must be a one-dimensional ARRAY OF a structure"), "{r}");
        let r = refused("PROGRAM P VAR Events : ARRAY [1..8] OF LiftEvent; END_VAR END_PROGRAM");
        assert!(r.contains("needs `EventCount` beside it"), "{r}");
        let r = refused("PROGRAM P VAR CabinCallCount : INT; END_VAR END_PROGRAM");
        assert!(r.contains("needs `CabinCalls` beside it"), "{r}");
    }

    /// `Floors` and `Algorithm` take the scenario's settings before the first scan; a
    /// CONSTANT or a wrong type is refused at its declaration.
    #[test]
    fn the_scenario_settings_are_set_into_floors_and_algorithm() {
        use crate::contract::Controller;
        use crate::dispatch::Algorithm;
        use crate::program::ControllerConfig;
        use st::run::Value;
        let prog = "TYPE LiftAlgorithm : (Fifo, Collective); END_TYPE
PROGRAM P VAR Floors : INT := 4; Algorithm : LiftAlgorithm; END_VAR END_PROGRAM";
        let mut p = StProgram::compile("p.st", prog).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(p.value("Floors"), Some(Value::Int(4)));
        assert_eq!(p.value("Algorithm"), Some(Value::Int(0)));
        let settings = ControllerConfig {
            floors: 3,
            algorithm: Algorithm::Collective,
            ..ControllerConfig::default()
        };
        p.configure(&settings);
        assert_eq!(p.value("Floors"), Some(Value::Int(3)));
        assert_eq!(p.value("Algorithm"), Some(Value::Int(1)));
        // A program's own copy of the type with only FIFO keeps its value for collective.
        let prog = "TYPE Algo : (Fifo); END_TYPE
PROGRAM P VAR Floors : SINT; Algorithm : Algo; END_VAR END_PROGRAM";
        let mut p = StProgram::compile("p.st", prog).unwrap_or_else(|e| panic!("{e}"));
        p.configure(&settings);
        assert_eq!(p.value("Floors"), Some(Value::Int(3)));
        assert_eq!(p.value("Algorithm"), Some(Value::Int(0)));
        let r = refused("VAR_GLOBAL CONSTANT Floors : INT := 4; END_VAR PROGRAM P END_PROGRAM");
        assert!(r.contains("`Floors` is a variable the rig reads or sets (the agreed interface): it is set from the scenario before the first scan, so it cannot be a CONSTANT"), "{r}");
        let r = refused("PROGRAM P VAR Floors : REAL; Algorithm : INT; END_VAR END_PROGRAM");
        assert!(r.contains("`Floors` is a variable the rig reads or sets (the agreed interface): it must be of an integer type"), "{r}");
        assert!(r.contains("`Algorithm` is a variable the rig reads or sets (the agreed interface): it must be an enumeration of some of the values Fifo, Collective"), "{r}");
    }

    /// A program without the agreed variables runs, and tells nothing (the rig counts its
    /// stops as serving calls).
    #[test]
    fn a_program_without_the_interface_tells_nothing() {
        let p = StProgram::compile("p.st", "PROGRAM P VAR x : INT; END_VAR x := 1; END_PROGRAM")
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(!p.agreed.names_served_calls());
        assert!(p.agreed.calls(&p.plc).is_none());
        assert_eq!(p.agreed.state(&p.plc), None);
    }

    /// The buffer is read after each scan and emptied; an entry that says what no event can
    /// puts the PLC into STOP at the buffer's declaration.
    #[test]
    fn events_are_drained_after_each_scan_and_a_wrong_one_stops_the_plc() {
        use crate::contract::Controller;
        use crate::dispatch::{HallDir, ServedCall, Source};
        use crate::plc::FromSafety;
        use crate::program::ProgramEventKind as K;
        use asi_phy::SimTime;
        let prog = "PROGRAM P
VAR Now : TIME; Events : ARRAY [1..8] OF LiftEvent; EventCount : INT; n : INT; END_VAR
  n := n + 1;
  IF n = 1 THEN
    EventCount := 1; Events[1].Kind := Departed; Events[1].Floor := 1; Events[1].Other := 3;
  ELSIF n = 2 THEN
    EventCount := 1; Events[1].Kind := Served; Events[1].Floor := 3;
    Events[1].Source := HallDown; Events[1].StoredAt := Now - T#10ms;
  ELSE
    EventCount := 1; Events[1].Kind := Departed; Events[1].Floor := 300;
  END_IF;
END_PROGRAM";
        let mut p =
            StProgram::compile("p.st", &format!("{TYPES}{prog}")).unwrap_or_else(|e| panic!("{e}"));
        let mut image = asi_master::ProcessImage::default();
        let safety = FromSafety { estop_out: true };
        let kinds = |p: &mut StProgram| -> Vec<K> {
            p.drain_events().into_iter().map(|e| e.kind).collect()
        };
        p.scan(SimTime::from_millis(10), &mut image, safety);
        assert_eq!(kinds(&mut p), [K::Departed { from: 1, to: 3 }]);
        assert_eq!(p.value("EventCount"), Some(st::run::Value::Int(0)));
        p.scan(SimTime::from_millis(20), &mut image, safety);
        assert_eq!(
            kinds(&mut p),
            [K::Served(ServedCall {
                floor: 3,
                source: Source::Hall,
                hall: Some(HallDir::Down),
                stored_at: SimTime::from_millis(10),
            })]
        );
        p.scan(SimTime::from_millis(30), &mut image, safety);
        let k = kinds(&mut p);
        assert!(
            matches!(
                k[..],
                [K::PlcStopped {
                    line: 10,
                    cause: st::run::FaultCause::BadEvent(1),
                    ..
                }]
            ),
            "{k:?}"
        );
        assert!(p.stopped().is_some_and(|s| s.starts_with("p.st:10:")));
    }
}
