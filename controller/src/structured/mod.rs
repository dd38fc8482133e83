//! A PLC programmer's own lift program in IEC 61131-3 Structured Text as the controller
//! ([`StProgram`]): the program reads and writes the master's process image through its
//! located variables (`%IX<word>.<bit>`, `%IW<word>`, `%QX<word>.<bit>`, `%QW<word>`, seed 003
//! table 4.1) and exchanges the standard signals with the safety logic through variables of
//! agreed names ([`ESTOP_OUT`], [`RESTART`], [`OVERLOADED`]).
//!
//! A fault at run time (a division by zero, an index out of range, a scan past its budget)
//! puts the PLC into STOP as a real one goes: the output image is zeroed, the fault is
//! reported with its place, and the signals to the safety logic take their safe values (no
//! restart, overloaded), so the safety logic holds the lift.

mod agreed;

pub use agreed::{
    ALGORITHM, ALGORITHM_VALUES, CABIN_CALLS, CABIN_CALL_COUNT, EVENTS, EVENT_COUNT, FLOOR, FLOORS,
    HALL_CALLS, HALL_CALL_COUNT, KIND_VALUES, NOW, REASON_VALUES, SOURCE_VALUES, STATE,
    STATE_VALUES, TARGET,
};
pub use agreed::{ESTOP_OUT, OVERLOADED, RESTART};

use crate::contract::{Controller, PendingCalls, Status};
use crate::plc::{FromSafety, ToSafety};
use crate::program::{ControllerConfig, Event, ProgramEventKind};
use agreed::Agreed;
use asi_master::image::IMAGE_WORDS;
use asi_master::{PlcLink, ProcessImage};
use asi_phy::{SimDuration, SimTime};
use st::run::{Fault, FaultCause, Image, Plc, Value};
use st::source::Source;
use std::any::Any;

/// The PLC's scan period when the program does not say otherwise (§6.2 of the lift thesis:
/// the built-in program scans every 10 ms).
pub const SCAN: SimDuration = SimDuration::from_millis(10);

/// A Structured Text program refused before the run: every error, rendered.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{rendered}")]
pub struct ProgramError {
    /// The errors as `file:line:column: error: cause`, the line and a caret, one after
    /// another.
    pub rendered: String,
    /// How many.
    pub count: usize,
}

/// A Structured Text program as the lab's PLC.
#[derive(Clone, Debug)]
pub struct StProgram {
    name: String,
    source: Source,
    plc: Plc,
    scan: SimDuration,
    stopped: Option<Fault>,
    events: Vec<Event>,
    agreed: Agreed,
}

impl StProgram {
    /// The program in `text` (named `name` in messages), parsed and checked; every error at
    /// once if it is refused.
    pub fn compile(name: &str, text: &str) -> Result<StProgram, ProgramError> {
        StProgram::compile_with(&[], name, text)
    }

    /// The program in `text` (named `name`) compiled together with the libraries
    /// `libraries` (each a file's name and text: function blocks, types and globals the
    /// program uses), as one program; every error at once, each naming its own file.
    pub fn compile_with(
        libraries: &[(&str, &str)],
        name: &str,
        text: &str,
    ) -> Result<StProgram, ProgramError> {
        let source = Source::files(libraries.iter().copied().chain([(name, text)]));
        let refuse = |errors: Vec<st::source::Diagnostic>, source: &Source| ProgramError {
            rendered: source.render_all(&errors),
            count: errors.len(),
        };
        let (unit, errors) = st::parser::parse(&source);
        if !errors.is_empty() {
            return Err(refuse(errors, &source));
        }
        let (checked, errors) = st::check::check(&unit);
        if !errors.is_empty() {
            return Err(refuse(errors, &source));
        }
        let errors = st::typeck::typecheck(&checked);
        if !errors.is_empty() {
            return Err(refuse(errors, &source));
        }
        let plc = Plc::new(&checked);
        let agreed = Agreed::find(&checked, &plc).map_err(|e| refuse(e, &source))?;
        Ok(StProgram {
            agreed,
            name: name.to_owned(),
            plc,
            scan: SCAN,
            source,
            stopped: None,
            events: Vec::new(),
        })
    }

    /// The program scanned every `scan` (a scenario's `[controller] scan`) instead of every
    /// [`SCAN`].
    pub fn with_scan(mut self, scan: SimDuration) -> StProgram {
        self.scan = scan;
        self
    }

    /// The program's name (its file's, as given).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Why the PLC is in STOP, with the place as `file:line:column`, if it is.
    pub fn stopped(&self) -> Option<String> {
        self.stopped.map(|f| {
            let (line, column, _) = self.source.locate(f.span.start);
            let file = self.source.file_at(f.span.start);
            format!("{file}:{line}:{column}: {}", f.cause)
        })
    }

    /// The value of the program's or a global variable `name` of elementary type (or an
    /// enumeration's number) now.
    pub fn value(&self, name: &str) -> Option<Value> {
        self.plc.address(name).and_then(|a| self.plc.read(a))
    }

    /// The value `offset` places after the start of the program's or a global variable
    /// `name` (an array's element `offset` from its first, for an array of elementary type).
    pub fn element(&self, name: &str, offset: u32) -> Option<Value> {
        self.plc
            .address(name)
            .and_then(|a| self.plc.read(a.checked_add(offset)?))
    }

    /// The program's variables of elementary type and their values (a PLC's watch list).
    pub fn watch(&self) -> Vec<(&str, Value)> {
        self.plc.watch()
    }

    /// As [`StProgram::watch`], each value written as a literal of its type (`TRUE`,
    /// `16#00FF`, `T#1s200ms`), as a PLC's online mode shows it.
    pub fn watch_text(&self) -> Vec<(&str, String)> {
        self.plc.watch_text()
    }
}

impl StProgram {
    /// STOP for `fault`: the output image zeroed, the place reported, the safe signals.
    fn stop(&mut self, now: SimTime, image: &mut ProcessImage, fault: Fault) -> ToSafety {
        for w in 0..IMAGE_WORDS {
            image.output.set_word(w, 0);
        }
        let (line, column, _) = self.source.locate(fault.span.start);
        self.events.push(Event {
            at: now,
            kind: ProgramEventKind::PlcStopped {
                line: u32::try_from(line).unwrap_or(u32::MAX),
                column: u32::try_from(column).unwrap_or(u32::MAX),
                cause: fault.cause,
            },
        });
        self.stopped = Some(fault);
        SAFE
    }
}

/// The master's process image as the program sees it.
struct Words<'a>(&'a mut ProcessImage);

impl Image for Words<'_> {
    fn input(&self, w: u32) -> u16 {
        let w = w as usize;
        if w < IMAGE_WORDS {
            self.0.input.word(w)
        } else {
            0
        }
    }

    fn output(&self, w: u32) -> u16 {
        let w = w as usize;
        if w < IMAGE_WORDS {
            self.0.output.word(w)
        } else {
            0
        }
    }

    fn set_output(&mut self, w: u32, value: u16) {
        let w = w as usize;
        if w < IMAGE_WORDS {
            self.0.output.set_word(w, value);
        }
    }
}

/// What the safety logic gets from a PLC in STOP: no restart, and overloaded (the unsafe
/// value), so that K1 stays open.
const SAFE: ToSafety = ToSafety {
    restart: false,
    overloaded: true,
};

impl Controller for StProgram {
    fn scan_period(&self) -> SimDuration {
        self.scan
    }

    fn scan(&mut self, now: SimTime, image: &mut ProcessImage, safety: FromSafety) -> ToSafety {
        if self.stopped.is_some() {
            for w in 0..IMAGE_WORDS {
                image.output.set_word(w, 0);
            }
            return SAFE;
        }
        if let Some(at) = self.agreed.estop_out {
            self.plc
                .write(at, Value::Bool(safety.estop_out), st::types::Elem::Bool);
        }
        let now_ns = i64::try_from(now.as_nanos()).unwrap_or(i64::MAX);
        if let Some((at, e)) = self.agreed.now {
            self.plc.write(at, Value::Int(now_ns), e);
        }
        let ran = self.plc.scan(now_ns, &mut Words(image));
        let ran = ran.and_then(|()| {
            self.agreed
                .drain(&mut self.plc, now, &mut self.events)
                .map_err(|bad| Fault {
                    span: bad.span,
                    cause: FaultCause::BadEvent(bad.entry),
                })
        });
        match ran {
            Ok(()) => {
                let read =
                    |a: Option<u32>| a.and_then(|a| self.plc.read(a)) == Some(Value::Bool(true));
                ToSafety {
                    restart: read(self.agreed.restart),
                    overloaded: read(self.agreed.overloaded),
                }
            }
            Err(fault) => self.stop(now, image, fault),
        }
    }

    fn drain_events(&mut self) -> Vec<Event> {
        std::mem::take(&mut self.events)
    }

    fn status(&self) -> Status {
        Status {
            state: self.agreed.state(&self.plc),
            floor: self.agreed.floor(&self.plc),
            target: self.agreed.target(&self.plc),
        }
    }

    fn pending_calls(&self) -> Option<PendingCalls> {
        self.agreed
            .calls(&self.plc)
            .map(|(cabin, hall)| PendingCalls { cabin, hall })
    }

    fn names_served_calls(&self) -> bool {
        self.agreed.names_served_calls()
    }

    fn plc_link(&self) -> PlcLink {
        PlcLink {
            connected: true,
            run: self.stopped.is_none(),
        }
    }

    fn program_name(&self) -> Option<&str> {
        Some(&self.name)
    }

    fn configure(&mut self, settings: &ControllerConfig) {
        self.agreed.configure(&mut self.plc, settings);
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
