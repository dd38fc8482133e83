//! The contract between the rig and a lift controller: a PLC scan over the AS-i master's
//! process image and the standard signals exchanged with the safety logic, at the
//! controller's scan period.
//!
//! The rig scans a controller at 0 and then every [`Controller::scan_period`], after the bus
//! has run up to that moment and the slaves have sampled the plant; what the scan writes into
//! the output image goes out with the master's next data exchanges, and the [`ToSafety`] it
//! returns reaches the safety logic at its next scan. That is the cycle of a PLC on the lab's
//! AS-i master (§6.2 of the lift thesis: read the image, run the program, write the image).
//!
//! Implementations: the built-in program of the lift thesis ([`Plc`]), and [`Outside`], the
//! controller outside the simulator (a Modbus TCP or TTK4145 client behind the gateway),
//! whose owner writes the output image itself between the rig's moments.

use crate::plc::{FromSafety, Plc, ToSafety};
use crate::program::{ControllerConfig, Event, State};
use asi_master::{PlcLink, ProcessImage};
use asi_phy::{SimDuration, SimTime};
use std::any::Any;

/// A lift controller on the lab bus: one PLC scan at a time.
///
/// A controller is `Clone` ([`ControllerClone`]), so that a rig can be copied with it (a
/// snapshot of a run goes on exactly as the original).
pub trait Controller: Send + 'static + ControllerClone {
    /// The time between two scans.
    fn scan_period(&self) -> SimDuration;

    /// One scan at `now`: reads the input image and the safety logic's signals `safety`,
    /// writes the output image, returns the signals for the safety logic.
    fn scan(&mut self, now: SimTime, image: &mut ProcessImage, safety: FromSafety) -> ToSafety;

    /// What the controller did since the last call, oldest first (for the run's log and
    /// report). None by default.
    fn drain_events(&mut self) -> Vec<Event> {
        Vec::new()
    }

    /// What the controller tells about itself now. Nothing by default.
    fn status(&self) -> Status {
        Status::default()
    }

    /// What the AS-i master sees of this PLC (its SYS and OK LEDs, seed 003 table 3.2):
    /// connected and in run mode. A controller the rig scans is both, by default.
    fn plc_link(&self) -> PlcLink {
        PlcLink::RUN
    }

    /// The calls the controller holds (cabin, hall), if it tells them.
    fn pending_calls(&self) -> Option<PendingCalls> {
        None
    }

    /// Whether its events name the calls each stop serves
    /// ([`crate::ProgramEventKind::Served`]). If not, the rig counts a stop level at a floor
    /// as serving every call waiting there.
    fn names_served_calls(&self) -> bool {
        false
    }

    /// The name of the controller's program, for the report, where it is not the built-in
    /// one (a Structured Text program's file). None by default.
    fn program_name(&self) -> Option<&str> {
        None
    }

    /// The scenario's controller settings (`[controller]`: the floors served, the control
    /// algorithm, the scan), given by the rig when the controller takes the built-in
    /// program's place, before its first scan. A controller with settings of its own ignores
    /// them (the default).
    fn configure(&mut self, _settings: &ControllerConfig) {}

    /// The controller as [`Any`], for a caller that wants its own type back.
    fn as_any(&self) -> &dyn Any;

    /// The controller as [`Any`], mutable.
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

/// What a controller tells about itself: each part absent when it does not tell it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct Status {
    /// The state, in the built-in program's terms.
    pub state: Option<State>,
    /// The floor it counts the cabin at.
    pub floor: Option<u8>,
    /// The floor it is going to.
    pub target: Option<u8>,
}

impl Status {
    /// Whether the controller is initialising (looking for floor 1).
    pub fn initialising(&self) -> bool {
        self.state == Some(State::Initialising)
    }

    /// Whether the controller holds the cabin for a fault of the bus.
    pub fn bus_fault(&self) -> bool {
        self.state == Some(State::BusFault)
    }
}

/// The calls a controller holds.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PendingCalls {
    /// Cabin calls, in the controller's order.
    pub cabin: Vec<u8>,
    /// Hall calls, in the controller's order.
    pub hall: Vec<u8>,
}

/// A copy of a [`Controller`] behind a box: any controller that is `Clone` has it.
pub trait ControllerClone {
    /// A copy of the controller, boxed.
    fn clone_box(&self) -> Box<dyn Controller>;
}

impl<T: Controller + Clone> ControllerClone for T {
    fn clone_box(&self) -> Box<dyn Controller> {
        Box::new(self.clone())
    }
}

impl Clone for Box<dyn Controller> {
    fn clone(&self) -> Self {
        (**self).clone_box()
    }
}

impl Controller for Plc {
    fn scan_period(&self) -> SimDuration {
        self.program().config().scan
    }

    fn scan(&mut self, now: SimTime, image: &mut ProcessImage, safety: FromSafety) -> ToSafety {
        Plc::scan(self, now, image, safety)
    }

    fn drain_events(&mut self) -> Vec<Event> {
        self.program_mut().drain_events().collect()
    }

    fn status(&self) -> Status {
        let p = self.program();
        Status {
            state: Some(p.state()),
            floor: Some(p.current_floor()),
            target: Some(p.target()),
        }
    }

    fn pending_calls(&self) -> Option<PendingCalls> {
        let p = self.program();
        Some(PendingCalls {
            cabin: p.fifo_cabin(),
            hall: p.fifo_hall(),
        })
    }

    fn names_served_calls(&self) -> bool {
        true
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// A controller outside the simulator (`asi-lift serve --controller external`): its owner
/// writes the output image between the rig's moments, as a client's request arrives, and
/// hands over the standard signals for the safety logic with [`Outside::set_signals`]; a
/// scan gives the safety logic the signals last handed over and leaves the image alone.
#[derive(Clone, Debug)]
pub struct Outside {
    scan: SimDuration,
    signals: ToSafety,
    link: PlcLink,
}

impl Outside {
    /// An outside controller whose signals the rig takes every `scan`.
    pub fn new(scan: SimDuration) -> Outside {
        Outside {
            scan,
            signals: ToSafety::default(),
            link: PlcLink::NONE,
        }
    }

    /// Whether a client is connected and runs the lift (its owner tells; no PLC until then):
    /// what the master's SYS and OK LEDs show.
    pub fn set_link(&mut self, link: PlcLink) {
        self.link = link;
    }

    /// The standard signals for the safety logic (the STOP circuit's restart, the overload),
    /// taken at the next scan.
    pub fn set_signals(&mut self, signals: ToSafety) {
        self.signals = signals;
    }
}

impl Controller for Outside {
    fn scan_period(&self) -> SimDuration {
        self.scan
    }

    fn scan(&mut self, _: SimTime, _: &mut ProcessImage, _: FromSafety) -> ToSafety {
        self.signals
    }

    fn plc_link(&self) -> PlcLink {
        self.link
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
