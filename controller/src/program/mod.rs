//! The PLC program of §6 of the lift thesis as a scan-driven state machine: read inputs, safety
//! checks, initialisation once, the automat, write outputs (figure 6.1 of the lift thesis).
//!
//! This module is the program's logic over plain inputs and outputs; [`crate::plc`] connects it
//! to the AS-i master's process image and runs the handshakes of tables 4.2–4.7 of the lift thesis.
//!
//! - this file: the [`Program`], its scan, reading the inputs, the restart pulses and the
//!   displays;
//! - `config`: the settings ([`ControllerConfig`]);
//! - `io`: the inputs and outputs of a scan, the vane sensor edges;
//! - `events`: [`ProgramEventKind`] and the reasons it carries, with their words;
//! - `state`: the phases and steps, and the [`State`] shown;
//! - `init`: initialisation (table 6.3 of the lift thesis);
//! - `automat`: the automat (tables 6.4/6.5 of the lift thesis);
//! - `position`: the floor count, its checks, and a lost position;
//! - `bus_fault`: holding the cabin while the bus is not healthy, and what follows.

mod automat;
mod bus_fault;
mod config;
mod events;
mod init;
mod io;
mod position;
mod state;

pub use config::{ControllerConfig, ControllerConfigError};
pub use events::{Event, HaltReason, InitStart, LostReason, ProgramEventKind, NO_VANE_RETRY};
pub use io::{CabinWord, Inputs, Outputs};
pub use state::State;

use crate::dispatch::{Dir, Dispatcher, HallDir, ServedCall, Source, Stored};
use asi_phy::{SimDuration, SimTime};
use io::{floors, overloaded, Edges};
use lab::DisplayWord;
use state::{Phase, Step};

/// The lift's PLC program.
#[derive(Clone, Debug)]
pub struct Program {
    cfg: ControllerConfig,
    phase: Phase,
    /// Aktualni_Patro.
    current: u8,
    /// Cil.
    target: u8,
    /// The direction of the present or last trip.
    dir: Option<Dir>,
    /// STOP was pressed during this trip.
    stop_pending: bool,
    /// A cabin request came in the STOP fault: restart pulses are due.
    restart_wanted: bool,
    /// This scan's STOP demand: EStopOut off or the cabin's STOP button pressed. No run
    /// starts while it lasts (§6.3 of the lift thesis), whatever routine would start one.
    stop_demand: bool,
    cabin: CabinWord,
    last_cabin_at: Option<SimTime>,
    restart_high: bool,
    next_restart: SimTime,
    initialised_at: Option<SimTime>,
    /// No departure before this time (dwell after an arrival).
    depart_after: SimTime,
    /// No run starts before this time: the door opened during the last one
    /// ([`DOOR_LOCKOUT`]).
    door_lockout_until: SimTime,
    dispatch: Dispatcher,
    /// The floor number on the displays (Cislo_Patra): set at departure, on arrival and at the
    /// start of initialisation only (see `Program::update_display`).
    shown_floor: u8,
    /// The direction arrow on the displays, set and cleared with `shown_floor`.
    shown_dir: Option<Dir>,
    out: Outputs,
    events: Vec<Event>,
    served: Vec<ServedCall>,
    /// Initialisation is held for this reason; it starts again when the reason is gone.
    init_held: Option<HaltReason>,
    /// When the program last took the drive off (a halt, an arrival, a bus fault): vane edges
    /// within [`COAST`] of it are the cabin coming to rest, later ones are a hand's work.
    drive_off_at: SimTime,
    /// The floor count is not trusted: initialise before the next journey.
    lost: bool,
    /// At the last vane counted: whether the left sensor rose first.
    vane_shape: Option<bool>,
    /// A cabin that shows no vane now is just below floor 1's vane: initialisation last moved
    /// it down inside that vane, or up towards it from below.
    in_floor1_vane: bool,
    /// When the cabin last made progress the program can see: a departure, a vane reached, a
    /// step of initialisation (for the watchdogs).
    progress_at: SimTime,
    /// The floor whose vane the cabin is leaving since its departure: the first sensor to
    /// fall tells whether it is floor 1's turned vane.
    leaving: Option<u8>,
    /// Initialisation held for want of vane edges since: any edge ends it.
    no_vane_since: Option<SimTime>,
    /// Since when each vane sensor (left, right) is on, as the cabin words show it.
    on_since: [Option<SimTime>; 2],
    /// When the present run at the travel or initialisation speed began.
    running_since: SimTime,
    /// The left vane sensor rose during this initialisation: it is not stuck on.
    left_proven: bool,
}

/// How long the cabin may go on moving after the program took the drive off: the converter
/// ramps 15.4 Hz down at 50 Hz/s in 0.31 s, the brake stops it in 0.12 s without power; the
/// cabin word that shows the last edge can come a word time (140 ms at a 10 ms scan) later.
const COAST: SimDuration = SimDuration::from_secs(1);

/// After the door opened during travel, no run starts for this long after the halt. The judge
/// adds up the time the cabin moves with the door open over any 10 s and allows 1 s
/// (docs/safety.md); each opening costs up to about 0.6 s of motion (the cabin word, a scan,
/// the converter's ramp), so two openings in one journey could add up to more. With the run
/// after the halt [`COAST`] and 10 s later, no two such spans share a 10 s window.
const DOOR_LOCKOUT: SimDuration = SimDuration::from_secs(11);

impl Program {
    /// A program that has just been loaded and set to RUN.
    pub fn new(cfg: ControllerConfig) -> Result<Program, ControllerConfigError> {
        cfg.check()?;
        let dispatch = Dispatcher::new(cfg.algorithm, cfg.floors);
        Ok(Program {
            phase: Phase::WaitInputs,
            current: 1,
            target: 1,
            dir: None,
            stop_pending: false,
            restart_wanted: false,
            stop_demand: false,
            cabin: CabinWord::default(),
            last_cabin_at: None,
            restart_high: false,
            next_restart: SimTime::ZERO,
            initialised_at: None,
            depart_after: SimTime::ZERO,
            door_lockout_until: SimTime::ZERO,
            dispatch,
            shown_floor: 1,
            shown_dir: None,
            out: Outputs {
                setpoint_ua: cfg.standstill_ua,
                display: DisplayWord {
                    floor: 1,
                    ..DisplayWord::default()
                },
                ..Outputs::default()
            },
            cfg,
            events: Vec::new(),
            served: Vec::new(),
            init_held: None,
            drive_off_at: SimTime::ZERO,
            lost: false,
            vane_shape: None,
            in_floor1_vane: false,
            progress_at: SimTime::ZERO,
            leaving: None,
            no_vane_since: None,
            on_since: [None; 2],
            running_since: SimTime::ZERO,
            left_proven: false,
        })
    }

    /// The settings.
    pub fn config(&self) -> &ControllerConfig {
        &self.cfg
    }

    /// One scan: reads `inp`, runs the routines, returns the outputs to write.
    pub fn scan(&mut self, now: SimTime, inp: &Inputs) -> Outputs {
        let edges = self.read_inputs(now, inp);
        self.out.overloaded = overloaded(inp);
        let stop_demand = !inp.estop_ok || self.cabin.stop;
        self.stop_demand = stop_demand;
        let fresh = self
            .last_cabin_at
            .is_some_and(|t| now.saturating_duration_since(t) <= self.cfg.stale_after);
        let bus_ok = inp.bus_ok && inp.power_ok && fresh;
        let mut want_restart = false;
        match self.phase {
            Phase::WaitInputs => {
                if bus_ok {
                    self.start_init(now);
                    // Power-on: the STOP circuit needs one Restart before K1 can close.
                    want_restart = true;
                }
            }
            Phase::Init(step) => {
                if !bus_ok {
                    self.bus_fault(now, None, true);
                } else {
                    if self.restart_wanted && inp.estop_ok {
                        self.restart_wanted = false;
                    }
                    want_restart = self.restart_wanted && !inp.estop_ok;
                    self.init(now, step, edges, inp, stop_demand);
                }
            }
            Phase::Service(step) => {
                if !bus_ok {
                    self.bus_fault(now, Some(step), !fresh || !inp.power_ok);
                } else {
                    want_restart = self.service(now, step, edges, inp, stop_demand);
                }
            }
            Phase::BusFault { resume, blind } => {
                self.while_bus_fault(now, edges, inp, fresh, resume, blind)
            }
        }
        self.pulse_restart(now, want_restart);
        self.update_display();
        self.out
    }

    fn read_inputs(&mut self, now: SimTime, inp: &Inputs) -> Edges {
        let mut e = Edges::default();
        if let Some(w) = inp.cabin {
            let old = self.cabin;
            let first = self.last_cabin_at.is_none();
            e.vane_rise =
                (w.vane_left || w.vane_right) && !(old.vane_left || old.vane_right) && !first;
            e.left_rise = w.vane_left && !old.vane_left && !first;
            e.right_rise = w.vane_right && !old.vane_right && !first;
            e.left_fall = !w.vane_left && old.vane_left;
            e.right_fall = !w.vane_right && old.vane_right;
            e.vane_fall = !(w.vane_left || w.vane_right) && (old.vane_left || old.vane_right);
            for (since, on) in self.on_since.iter_mut().zip([w.vane_left, w.vane_right]) {
                *since = if on { since.or(Some(now)) } else { None };
            }
            if e.vane_rise && w.vane_left != w.vane_right {
                e.floor1_vane = Some(w.vane_left);
            }
            if e.left_fall && w.vane_right {
                e.left_fell_first = Some(true);
            } else if e.right_fall && w.vane_left {
                e.left_fell_first = Some(false);
            }
            e.any = e.left_rise || e.right_rise || e.left_fall || e.right_fall;
            let pressed = if first {
                w.buttons
            } else {
                w.buttons & !old.buttons
            };
            self.cabin = w;
            self.last_cabin_at = Some(now);
            for f in floors(pressed, self.cfg.floors) {
                self.store(now, f, Source::Cabin, None);
                // The cabin request that ends a STOP (§6.3 of the lift thesis) also restarts the
                // STOP circuit.
                let stopped = !inp.estop_ok
                    || self.stop_pending
                    || self.phase == Phase::Service(Step::StopFault);
                if matches!(self.phase, Phase::Service(_) | Phase::Init(_)) && stopped {
                    self.restart_wanted = true;
                }
            }
        }
        for f in floors(inp.hall_up, self.cfg.floors) {
            self.store(now, f, Source::Hall, Some(HallDir::Up));
        }
        for f in floors(inp.hall_down, self.cfg.floors) {
            self.store(now, f, Source::Hall, Some(HallDir::Down));
        }
        e
    }

    fn store(&mut self, now: SimTime, floor: u8, source: Source, hall: Option<HallDir>) {
        let stored = match hall {
            None => self.dispatch.cabin_call(floor, now),
            Some(d) => self.dispatch.hall_call(floor, d, now),
        };
        match stored {
            Stored::New => self.event(now, ProgramEventKind::CallStored { floor, source }),
            Stored::Full => self.event(now, ProgramEventKind::CallLost { floor, source }),
            Stored::Duplicate => {}
        }
    }

    fn pulse_restart(&mut self, now: SimTime, want: bool) {
        if self.restart_high {
            self.restart_high = false;
        } else if want && now >= self.next_restart {
            self.restart_high = true;
            self.next_restart = now + self.cfg.restart_every;
        }
        self.out.restart = self.restart_high;
    }

    /// The display word content (tables 4.2/4.4 of the lift thesis), by the rows of tables 6.3–6.5
    /// that say what is shown. The floor number and the arrow are latched: they change only at
    /// these rows, not while floors are passed.
    ///
    /// - Table 6.3, state "Jede" (set in `start_init`): floor 1 and "down" from the start of
    ///   initialisation, through every step of it ("Brzdí", and the creeping steps asi-lift
    ///   adds for a start at floor 1, whatever the motor's direction there).
    /// - Table 6.3, "Brzdí → 1. Patro": "Zobrazení směru jízdy dolů": floor 1 and "down" stay
    ///   after initialisation, until the automat's first departure.
    /// - Tables 6.4/6.5, "Aktuální patro → Jede dolů/nahoru" (set in `depart`): the current
    ///   floor, the arrow of the direction of travel, the other arrow off. Passing a floor
    ///   ("Jede → Jede") and starting to brake ("Jede → Dobrždění") change nothing shown.
    /// - Tables 6.4/6.5, "Dobrždění → Aktuální patro" (set in `arrive`): the current floor, no
    ///   arrow. A STOP ends this way too ("Porucha Stop → Dobrždění → Aktuální patro").
    /// - Tables 6.4/6.5, "Aktuální patro ↔ Porucha přetížení": the floor number, no arrow.
    ///
    /// D3 "Jede / stojí" is set while the drive is commanded to move; D2 "Porucha" in the
    /// fault states (overload, STOP fault, a hold between floors, a bus fault). The tables say
    /// nothing of the display in a bus fault or a hold: **Decision**: the floor and arrow shown
    /// stay as they were (a trip that resumes keeps its arrow), with D3 = 0 and D2 = 1.
    fn update_display(&mut self) {
        let (moving, fault) = match self.phase {
            Phase::WaitInputs => (false, false),
            Phase::Init(_) => (self.out.run, false),
            Phase::BusFault { .. } => (false, true),
            Phase::Service(step) => match step {
                Step::AtFloor => (false, false),
                Step::Travel | Step::Braking => (true, false),
                Step::Overload | Step::StopFault | Step::Halted { .. } => (false, true),
            },
        };
        if self.phase == Phase::Service(Step::Overload) {
            (self.shown_floor, self.shown_dir) = (self.current, None);
        }
        self.out.display = DisplayWord {
            floor: self.shown_floor,
            up: self.shown_dir == Some(Dir::Up),
            down: self.shown_dir == Some(Dir::Down),
            moving,
            fault,
        };
    }

    fn event(&mut self, at: SimTime, kind: ProgramEventKind) {
        self.events.push(Event { at, kind });
    }

    /// Takes the events since the last call.
    pub fn drain_events(&mut self) -> impl Iterator<Item = Event> + '_ {
        self.events.drain(..)
    }

    /// The outputs of the last scan.
    pub fn outputs(&self) -> Outputs {
        self.out
    }

    /// Aktualni_Patro.
    pub fn current_floor(&self) -> u8 {
        self.current
    }

    /// Cil.
    pub fn target(&self) -> u8 {
        self.target
    }

    /// Rozdil = Aktualni_Patro − Cil.
    pub fn rozdil(&self) -> i32 {
        self.current as i32 - self.target as i32
    }

    /// When initialisation finished (the last time, after a bus fault).
    pub fn initialised_at(&self) -> Option<SimTime> {
        self.initialised_at
    }

    /// `true` once the automat runs.
    pub fn is_initialised(&self) -> bool {
        matches!(self.phase, Phase::Service(_))
    }

    /// The pending cabin calls (FIFO_Kabina).
    pub fn fifo_cabin(&self) -> Vec<u8> {
        self.dispatch.cabin_calls()
    }

    /// The pending hall calls (FIFO_Patra).
    pub fn fifo_hall(&self) -> Vec<u8> {
        self.dispatch.hall_calls()
    }

    /// The program's state, as the report shows it.
    pub fn state(&self) -> State {
        self.phase.state(self.dir)
    }
}
