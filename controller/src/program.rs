//! The PLC program of seed 003 §6 as a scan-driven state machine: read inputs, safety checks,
//! initialisation once, the automat, write outputs (seed figure 6.1).
//!
//! This module is the program's logic over plain inputs and outputs; [`crate::plc`] connects it
//! to the AS-i master's process image and runs the handshakes of seed tables 4.2–4.7.

use crate::dispatch::{Algorithm, Dir, Dispatcher, HallDir, ServedCall, Source, Stored};
use asi_phy::{SimDuration, SimTime};
use core::fmt;

/// The program's settings. Defaults: the seed's set-points (µA of the current loop) and timer,
/// a 10 ms scan (SPEC §5).
#[derive(Clone, Debug, PartialEq)]
pub struct ControllerConfig {
    /// Floors served, 2..=24.
    pub floors: u8,
    /// FIFO (seed) or collective selective.
    pub algorithm: Algorithm,
    /// The PLC scan period.
    pub scan: SimDuration,
    /// Travel set-point (seed tables 6.4/6.5: 10000 µA, 59.4 mm/s).
    pub travel_ua: u16,
    /// Braking (creep) set-point (6000 µA, 20.6 mm/s).
    pub creep_ua: u16,
    /// Standstill set-point (4000 µA = 4 mA).
    pub standstill_ua: u16,
    /// Initialisation set-point (seed table 6.3: 11000 µA, 68.8 mm/s).
    pub init_ua: u16,
    /// The initialisation timer (seed §6.4: 2 s).
    pub init_timer: SimDuration,
    /// How often the restart pulse is repeated while the STOP circuit is not yet running again.
    pub restart_every: SimDuration,
    /// A cabin word older than this means the cabin slave is lost.
    pub stale_after: SimDuration,
    /// How long the cabin stands at a floor after arriving before it departs again.
    ///
    /// **Decision**: 2 s. The seed's automat departs in the scan after it arrives, so an
    /// intermediate stop would never come to rest; a lift stands for its passengers.
    pub dwell: SimDuration,
    /// Travel without reaching a vane for longer than this means a vane sensor lies: the
    /// cabin stops and the position is found again. Default 9 s: the vanes are 400 mm apart,
    /// 6.7 s at the travel speed (59.4 mm/s), 5.8 s at the initialisation speed.
    pub travel_watchdog: SimDuration,
    /// A creep inside a vane (braking to level, initialisation's probes) that does not reach
    /// its edge within this means a vane sensor lies. Default 6 s: the long track is 80 mm,
    /// 3.9 s at the creep speed (20.6 mm/s).
    pub creep_watchdog: SimDuration,
    /// A vane sensor on for longer than this while the cabin runs at the travel or the
    /// initialisation speed is stuck on. Default 3 s: the long track (80 mm) passes in 1.35 s
    /// at the travel speed and 1.16 s at the initialisation speed; 3 s leave room for the
    /// ramp and two cabin words.
    pub stuck_on_after: SimDuration,
}

impl Default for ControllerConfig {
    fn default() -> Self {
        ControllerConfig {
            floors: 4,
            algorithm: Algorithm::Fifo,
            scan: SimDuration::from_millis(10),
            travel_ua: 10_000,
            creep_ua: 6_000,
            standstill_ua: 4_000,
            init_ua: 11_000,
            init_timer: SimDuration::from_secs(2),
            restart_every: SimDuration::from_millis(500),
            stale_after: SimDuration::from_secs(1),
            dwell: SimDuration::from_secs(2),
            travel_watchdog: SimDuration::from_secs(9),
            creep_watchdog: SimDuration::from_secs(6),
            stuck_on_after: SimDuration::from_secs(3),
        }
    }
}

/// A setting the program cannot run with.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("controller: {field} = {value}: {rule}")]
pub struct ControllerConfigError {
    /// The setting.
    pub field: &'static str,
    /// Its value.
    pub value: String,
    /// What it must be.
    pub rule: &'static str,
}

impl ControllerConfig {
    /// Checks the settings.
    pub fn check(&self) -> Result<(), ControllerConfigError> {
        let err = |field, value: &dyn fmt::Display, rule| {
            Err(ControllerConfigError {
                field,
                value: value.to_string(),
                rule,
            })
        };
        if !(2..=24).contains(&self.floors) {
            return err(
                "floors",
                &self.floors,
                "must be 2..=24 (the display word carries 5 bits)",
            );
        }
        if self.scan.is_zero() {
            return err("scan", &self.scan, "must be positive");
        }
        if self.standstill_ua >= self.creep_ua
            || self.creep_ua > self.travel_ua
            || self.travel_ua > 20_000
        {
            return err(
                "set-points",
                &format!(
                    "{}/{}/{} µA",
                    self.standstill_ua, self.creep_ua, self.travel_ua
                ),
                "need standstill < creep <= travel <= 20000 µA",
            );
        }
        if self.init_ua <= self.creep_ua || self.init_ua > 20_000 {
            return err(
                "init_ua",
                &self.init_ua,
                "must lie above the creep set-point, up to 20000 µA",
            );
        }
        Ok(())
    }
}

/// The cabin's 32-bit word (seed table 4.6), as the PLC assembles it from the two halves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CabinWord {
    /// Floor buttons, bit `f − 1` for floor `f` (1..=24).
    pub buttons: u32,
    /// The bell button.
    pub bell: bool,
    /// The STOP button's standard contact (pressed).
    pub stop: bool,
    /// SnZavD: the door is closed.
    pub door_closed: bool,
    /// Snimac_1, the left vane sensor.
    pub vane_left: bool,
    /// Snimac_2, the right vane sensor.
    pub vane_right: bool,
}

/// What the program reads at the start of a scan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Inputs {
    /// A cabin word completed since the last scan, if any.
    pub cabin: Option<CabinWord>,
    /// Hall up calls received since the last scan, bit `f − 1`.
    pub hall_up: u32,
    /// Hall down calls received since the last scan, bit `f − 1`.
    pub hall_down: u32,
    /// Zatizeni_Kabiny: 0 empty, 1 loaded, 2 full, 3 overloaded.
    pub load: u8,
    /// The load cannot be read (the load sensor is off the bus or not ready): it counts as
    /// overloaded, its unsafe value.
    pub load_lost: bool,
    /// The safety logic's EStopOut: `true` = no STOP demand.
    pub estop_ok: bool,
    /// The converter reports ready (it has power and no fault).
    pub converter_ready: bool,
    /// The converter reports a fault.
    pub converter_fault: bool,
    /// The slaves the cabin cannot move without are on the bus (in LAS; see
    /// [`crate::plc`]).
    pub bus_ok: bool,
    /// No AS-i power fail (flag F1 of word 0).
    pub power_ok: bool,
}

/// What a passenger sees on the floor and cabin displays (seed tables 4.2/4.4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DisplayState {
    /// Cislo_Patra, 1..=24.
    pub floor: u8,
    /// Smer_Nahoru.
    pub up: bool,
    /// Smer_Dolu.
    pub down: bool,
    /// Pojezd: the cabin is commanded to move.
    pub moving: bool,
    /// Porucha: a fault state.
    pub fault: bool,
}

/// What the program writes at the end of a scan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outputs {
    /// Start1: the converter's run input.
    pub run: bool,
    /// Smer_Motoru: 1 up, 0 down.
    pub up: bool,
    /// Rychlost, the speed set-point in µA.
    pub setpoint_ua: u16,
    /// The display word content.
    pub display: DisplayState,
    /// The Restart input of the safety logic's STOP circuit (pulsed).
    pub restart: bool,
    /// The overload signal for the safety logic's AND input.
    pub overloaded: bool,
}

/// Why the program holds the cabin where it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HaltReason {
    /// The door opened during travel.
    DoorOpen,
    /// The cabin became overloaded during travel.
    Overload,
    /// The converter reported a fault.
    ConverterFault,
    /// The converter lost its power (K1 open).
    NoPower,
    /// STOP is demanded (initialisation only; in service STOP has its own states).
    Stop,
    /// The vane sensors showed no edge where one was due (initialisation only): held until a
    /// sensor changes, or for [`NO_VANE_RETRY`] at most.
    NoVane,
}

/// How long initialisation waits after its watchdog before it tries again without a vane
/// sensor edge.
pub const NO_VANE_RETRY: SimDuration = SimDuration::from_secs(10);

impl fmt::Display for HaltReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            HaltReason::DoorOpen => "door open",
            HaltReason::Overload => "overloaded",
            HaltReason::ConverterFault => "converter fault",
            HaltReason::NoPower => "no drive power (K1 open)",
            HaltReason::Stop => "STOP circuit open",
            HaltReason::NoVane => "no vane edge where one was due (a vane sensor fault?)",
        })
    }
}

/// Something the program did, for the log and the report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EventKind {
    /// Initialisation began, from the sensor state seen.
    InitStarted {
        /// What the vane sensors showed.
        start: InitStart,
    },
    /// The cabin stands at floor 1 and the automat takes over.
    Initialised,
    /// A call was stored.
    CallStored {
        /// The floor.
        floor: u8,
        /// Cabin or hall.
        source: Source,
    },
    /// A call was lost because its memory was full.
    CallLost {
        /// The floor.
        floor: u8,
        /// Cabin or hall.
        source: Source,
    },
    /// The cabin leaves for a target.
    Departed {
        /// The floor it leaves.
        from: u8,
        /// Where it goes.
        to: u8,
    },
    /// The cabin passed a floor's first vane edge.
    Passed {
        /// The floor.
        floor: u8,
    },
    /// The cabin creeps into its stop floor.
    Braking {
        /// The floor.
        floor: u8,
    },
    /// The cabin stopped level at a floor.
    Arrived {
        /// The floor.
        floor: u8,
    },
    /// A call was served by a stop.
    Served(ServedCall),
    /// STOP in the cabin: the target becomes the next floor in the direction of travel.
    StopDemanded {
        /// The target given up (FIFO: the request is dropped, as in the seed).
        dropped: Option<u8>,
        /// The floor the cabin will stop at.
        stop_at: u8,
    },
    /// The cabin stands in the STOP fault.
    StopFault,
    /// A cabin request after STOP resumes service.
    Resumed,
    /// Overload at a floor: no departure.
    OverloadFault,
    /// The load is back to normal.
    OverloadCleared,
    /// The cabin is held between floors.
    Halted(HaltReason),
    /// The hold is over; travel continues.
    Continued,
    /// The cabin slave or the bus is lost: the cabin stops.
    BusFault,
    /// The bus is back; the program initialises again.
    BusRestored,
    /// Initialisation is held (the cabin does not move) until the reason is gone; then it
    /// starts again from what the vane sensors show.
    InitHeld(HaltReason),
    /// The vane sensors contradict the counted floor, or changed while the program did not
    /// move the cabin (a hand crank): the position is not trusted and is found again by
    /// initialisation before the next journey.
    PositionLost {
        /// What gave it away.
        why: LostReason,
    },
}

/// Why the program stopped trusting its floor count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LostReason {
    /// A vane edge while the program did not move the cabin (moved by hand).
    MovedByHand,
    /// Floor 1's turned vane (the left sensor first) where the count expected another floor,
    /// or another floor's vane where it expected floor 1.
    WrongVane,
    /// A vane beyond the last floor in the direction of travel.
    BeyondEndFloor,
    /// The cabin left its stop floor's vane without ever standing level in it, or did not
    /// reach its level in time.
    MissedLevel,
    /// No vane within the travel watchdog.
    NoVane,
    /// A vane sensor stayed on for longer than a vane takes to pass.
    StuckSensor,
}

impl fmt::Display for LostReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LostReason::MovedByHand => "the cabin moved while the drive was off",
            LostReason::WrongVane => "the vane seen is not the floor counted",
            LostReason::BeyondEndFloor => "a vane beyond the end floor",
            LostReason::MissedLevel => "the stop floor's level was passed",
            LostReason::NoVane => "no vane where one was due",
            LostReason::StuckSensor => "a vane sensor stays on",
        })
    }
}

/// An event with the scan time it happened in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Event {
    /// The scan's time.
    pub at: SimTime,
    /// What happened.
    pub kind: EventKind,
}

/// The vane sensors at the start of initialisation, which decide how it proceeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InitStart {
    /// No vane, or only the right sensor: the seed's routine (down at 11000 µA).
    Seed,
    /// Only the left sensor: inside floor 1's long track, above or below level.
    Floor1Track,
    /// Both sensors: level at some floor; a slow probe tells floor 1 from the others.
    Level,
    /// No vane, but the cabin was last seen creeping down inside floor 1's vane (before a hold
    /// or a bus fault): it is just below floor 1 and creeps up to its level.
    BelowFloor1,
}

/// Initialisation steps (seed table 6.3, extended for a start at floor 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum InitStep {
    /// Jede: down at the initialisation speed.
    Run,
    /// Brzdí: creeping with the 2 s timer after the left sensor rose.
    Brake { until: SimTime },
    /// Inside floor 1's long track: creep down until the right sensor rises (level) or the
    /// left one falls (we were below level).
    Floor1Down,
    /// Level at an unknown floor: creep down; which sensor falls first tells the floor.
    Probe,
    /// Below floor 1's level: creep up until both sensors are on.
    Floor1Up,
}

/// Automat steps (seed tables 6.4/6.5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    /// Aktuální patro: standing at a floor.
    AtFloor,
    /// Porucha přetížení.
    Overload,
    /// Jede dolů / Jede nahoru.
    Travel,
    /// Dobrždění.
    Braking,
    /// Porucha Stop: stopped after STOP, waiting for a cabin request.
    StopFault,
    /// Held between floors; `braking` says which step to go back to.
    Halted { reason: HaltReason, braking: bool },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// Until the first cabin word arrives, nothing is known.
    WaitInputs,
    Init(InitStep),
    Service(Step),
    /// The bus is not healthy: the cabin is held. `resume` is the step to go back to if the
    /// program never lost sight of the cabin (`blind` = the cabin word went stale or the power
    /// failed, after which the program initialises again).
    BusFault {
        resume: Option<Step>,
        blind: bool,
    },
}

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
    cabin: CabinWord,
    last_cabin_at: Option<SimTime>,
    restart_high: bool,
    next_restart: SimTime,
    initialised_at: Option<SimTime>,
    /// No departure before this time (dwell after an arrival).
    depart_after: SimTime,
    dispatch: Dispatcher,
    /// The floor number on the displays (Cislo_Patra): set at departure, on arrival and at the
    /// start of initialisation only (see [`Program::update_display`]).
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

/// Edges seen in this scan's inputs.
#[derive(Clone, Copy, Debug, Default)]
struct Edges {
    left_rise: bool,
    right_rise: bool,
    left_fall: bool,
    right_fall: bool,
    /// "Left OR right in log. 1" rose: the cabin reaches a floor's vane (tables 6.4/6.5).
    vane_rise: bool,
    /// "Left OR right" fell: the cabin leaves a vane.
    vane_fall: bool,
    /// At a vane rise: `Some(true)` if the left sensor came first (floor 1's turned vane, seed
    /// 003 §6.4), `Some(false)` if the right one did (floors 2..), `None` if both came in one
    /// word.
    floor1_vane: Option<bool>,
    /// One sensor fell while the other stayed on: `Some(true)` for the left one.
    left_fell_first: Option<bool>,
    /// Any sensor changed.
    any: bool,
}

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
            cabin: CabinWord::default(),
            last_cabin_at: None,
            restart_high: false,
            next_restart: SimTime::ZERO,
            initialised_at: None,
            depart_after: SimTime::ZERO,
            dispatch,
            shown_floor: 1,
            shown_dir: None,
            out: Outputs {
                setpoint_ua: cfg.standstill_ua,
                display: DisplayState {
                    floor: 1,
                    ..DisplayState::default()
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
                self.hold();
                let settled = now.saturating_duration_since(self.drive_off_at) > COAST;
                let moved = settled && (edges.vane_rise || edges.vane_fall);
                let mut blind = blind || !fresh || !inp.power_ok || moved;
                let mut resume = resume;
                // The cabin coasting to rest may reach the next vane: count it, as in a halt.
                if !settled && !blind {
                    match (resume, self.dir) {
                        (Some(Step::Travel), Some(dir)) if edges.vane_rise => {
                            match self.count_vane(dir, edges) {
                                Ok(floor) => {
                                    self.current = floor;
                                    if floor == self.target {
                                        resume = Some(Step::Braking);
                                    }
                                }
                                Err(_) => blind = true,
                            }
                        }
                        (Some(Step::Braking), _) if edges.vane_fall => blind = true,
                        _ => {}
                    }
                }
                self.phase = Phase::BusFault { resume, blind };
                let journey = matches!(
                    resume,
                    Some(Step::Travel | Step::Braking | Step::Halted { .. })
                );
                match resume {
                    Some(step) if bus_ok && !blind => {
                        self.event(now, EventKind::BusRestored);
                        self.resume(now, step);
                    }
                    // Initialisation chooses its way from the vane sensors: only a cabin word
                    // that completed since the bus came back shows where the cabin is now.
                    _ if bus_ok && inp.cabin.is_some() => {
                        self.event(now, EventKind::BusRestored);
                        if journey || self.target != self.current {
                            self.dispatch.requeue(self.target);
                        }
                        self.start_init(now);
                    }
                    _ => {}
                }
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
                // The cabin request that ends a STOP (seed §6.3) also restarts the STOP circuit.
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
            Stored::New => self.event(now, EventKind::CallStored { floor, source }),
            Stored::Full => self.event(now, EventKind::CallLost { floor, source }),
            Stored::Duplicate => {}
        }
    }

    fn start_init(&mut self, now: SimTime) {
        let start = match (self.cabin.vane_left, self.cabin.vane_right) {
            (true, true) => InitStart::Level,
            (true, false) => InitStart::Floor1Track,
            // Last seen inside floor 1's vane moving down, or below it moving up: below it.
            (false, false) if self.in_floor1_vane => InitStart::BelowFloor1,
            _ => InitStart::Seed,
        };
        let step = match start {
            InitStart::Level => InitStep::Probe,
            InitStart::Floor1Track => InitStep::Floor1Down,
            InitStart::BelowFloor1 => InitStep::Floor1Up,
            InitStart::Seed => InitStep::Run,
        };
        self.initialised_at = None;
        self.init_held = None;
        self.no_vane_since = None;
        self.progress_at = now;
        self.running_since = now;
        self.left_proven = false;
        self.lost = false;
        (self.shown_floor, self.shown_dir) = (1, Some(Dir::Down));
        self.event(now, EventKind::InitStarted { start });
        self.phase = Phase::Init(step);
        self.drive_init(step);
    }

    /// The outputs of an initialisation step (seed table 6.3: down, floor 1 and "down" shown).
    fn drive_init(&mut self, step: InitStep) {
        let (ua, up) = match step {
            InitStep::Run => (self.cfg.init_ua, false),
            InitStep::Brake { .. } | InitStep::Floor1Down | InitStep::Probe => {
                (self.cfg.creep_ua, false)
            }
            InitStep::Floor1Up => (self.cfg.creep_ua, true),
        };
        self.current = 1;
        self.target = 1;
        self.dir = Some(if up { Dir::Up } else { Dir::Down });
        // Never a command to move with the door open, overloaded or STOP pressed, not even
        // for the one scan before the hold is seen (a start from a bus fault or a lost count).
        if self.cabin_blocks_motion().is_some() || self.cabin.stop {
            self.hold();
            return;
        }
        self.out.run = true;
        self.out.up = up;
        self.out.setpoint_ua = ua;
    }

    fn init(&mut self, now: SimTime, step: InitStep, e: Edges, inp: &Inputs, stop_demand: bool) {
        // The cabin never moves with the door open, overloaded or under STOP, not even to find
        // floor 1. A hold (these, or the drive losing power, as when the run reaches an
        // overtravel sensor) ends when every reason is gone and the drive has power again;
        // then initialisation starts afresh from what the sensors show, because the edges the
        // steps wait for may have passed during the hold.
        if let Some(since) = self.no_vane_since {
            if e.any || now.saturating_duration_since(since) > NO_VANE_RETRY {
                self.no_vane_since = None;
            }
        }
        let reason = if stop_demand {
            Some(HaltReason::Stop)
        } else if let Some(r) = self.cabin_blocks_motion() {
            Some(r)
        } else if inp.converter_fault {
            Some(HaltReason::ConverterFault)
        } else if !inp.converter_ready {
            Some(HaltReason::NoPower)
        } else if self.no_vane_since.is_some() {
            Some(HaltReason::NoVane)
        } else {
            None
        };
        match (self.init_held, reason) {
            (None, Some(r)) => {
                self.hold();
                self.init_held = Some(r);
                self.drive_off_at = now;
                self.event(now, EventKind::InitHeld(r));
                return;
            }
            (Some(held), Some(r)) => {
                self.hold();
                if held != r {
                    self.init_held = Some(r);
                    self.event(now, EventKind::InitHeld(r));
                }
                return;
            }
            (Some(_), None) => {
                self.init_held = None;
                self.start_init(now);
                return;
            }
            (None, None) => {}
        }
        let c = self.cabin;
        self.left_proven |= e.left_rise;
        // The watchdog: the run must reach a vane, a creep the edge it waits for, in the time
        // the geometry allows; only while the drive has power.
        let limit = match step {
            InitStep::Run => self.cfg.travel_watchdog,
            _ => self.cfg.creep_watchdog,
        };
        if e.vane_rise || !inp.converter_ready {
            self.progress_at = now;
        }
        let stuck = step == InitStep::Run && self.stuck_on(now);
        if stuck || now.saturating_duration_since(self.progress_at) > limit {
            self.hold();
            // A sensor lies: what it showed of floor 1's vane is no guide either.
            self.in_floor1_vane = false;
            self.no_vane_since = Some(now);
            self.init_held = Some(HaltReason::NoVane);
            self.drive_off_at = now;
            self.event(now, EventKind::InitHeld(HaltReason::NoVane));
            return;
        }
        let next = match step {
            InitStep::Run if e.left_rise => {
                // The left sensor first, the right one off: floor 1's turned vane.
                self.in_floor1_vane = !c.vane_right;
                Some(InitStep::Brake {
                    until: now + self.cfg.init_timer,
                })
            }
            InitStep::Brake { .. } if e.right_rise => return self.initialised(now),
            // Out of floor 1's vane at the bottom without seeing its level (the cabin word came
            // too late): creep back up to it rather than run on into the overtravel sensor.
            InitStep::Brake { .. } if e.left_fall && self.in_floor1_vane => {
                Some(InitStep::Floor1Up)
            }
            InitStep::Brake { until } if now >= until => Some(InitStep::Run),
            // Level at floor 1, once its left sensor has shown a rise in this initialisation (a
            // sensor stuck on would make every vane look like floor 1's long track).
            InitStep::Floor1Down if e.right_rise && self.left_proven => {
                return self.initialised(now)
            }
            InitStep::Floor1Down if e.left_fall => Some(InitStep::Floor1Up),
            // Floor 1's short track ended first: below floor 1's level. Down out of the long
            // track too, then up into it, so that the left sensor shows it works.
            InitStep::Probe if e.right_fall && c.vane_left => Some(InitStep::Floor1Down),
            InitStep::Probe if e.left_fall => Some(InitStep::Run),
            // Up into a vane whose right sensor comes first: not floor 1.
            InitStep::Floor1Up if e.vane_rise && e.floor1_vane == Some(false) => {
                return self.start_init(now)
            }
            InitStep::Floor1Up if c.vane_left && c.vane_right => return self.initialised(now),
            // Out of the long track without ever standing level: the sensors disagree with the
            // floor-1 vane's shape; start again from what they show now.
            InitStep::Floor1Up if e.left_fall => return self.start_init(now),
            _ => None,
        };
        if next.is_some_and(|n| n != step) {
            self.progress_at = now;
            self.running_since = now;
        }
        let step = next.unwrap_or(step);
        match step {
            InitStep::Floor1Down => self.in_floor1_vane = true,
            InitStep::Brake { .. } => {}
            // Below the vane until its left sensor shows; inside it, moving up, the cabin can
            // only leave it upwards.
            InitStep::Floor1Up => self.in_floor1_vane = !c.vane_left,
            InitStep::Run | InitStep::Probe => self.in_floor1_vane = false,
        }
        self.phase = Phase::Init(step);
        self.drive_init(step);
    }

    fn initialised(&mut self, now: SimTime) {
        self.hold();
        self.in_floor1_vane = false;
        self.current = 1;
        self.target = 1;
        self.dir = None;
        self.stop_pending = false;
        self.initialised_at = Some(now);
        self.depart_after = now + self.cfg.dwell;
        self.event(now, EventKind::Initialised);
        self.phase = Phase::Service(Step::AtFloor);
    }

    fn bus_fault(&mut self, now: SimTime, resume: Option<Step>, blind: bool) {
        self.hold();
        self.drive_off_at = now;
        self.phase = Phase::BusFault { resume, blind };
        self.event(now, EventKind::BusFault);
    }

    /// Back to `step` after a bus fault in which the program kept sight of the cabin.
    fn resume(&mut self, now: SimTime, step: Step) {
        self.phase = Phase::Service(step);
        self.progress_at = now;
        self.running_since = now;
        let braking = step == Step::Braking;
        if let (Some(reason), Step::Travel | Step::Braking) = (self.cabin_blocks_motion(), step) {
            // The door opened or the cabin was loaded during the bus fault: held, not resumed.
            self.drive_off_at = now;
            self.event(now, EventKind::Halted(reason));
            self.phase = Phase::Service(Step::Halted { reason, braking });
            return;
        }
        let speed = match step {
            Step::Travel => self.cfg.travel_ua,
            Step::Braking => self.cfg.creep_ua,
            _ => return,
        };
        self.out.run = true;
        self.out.up = self.dir == Some(Dir::Up);
        self.out.setpoint_ua = speed;
    }

    /// Why the cabin itself forbids motion: the door open, or overloaded (or its load unknown;
    /// `out.overloaded` is this scan's).
    fn cabin_blocks_motion(&self) -> Option<HaltReason> {
        if !self.cabin.door_closed {
            Some(HaltReason::DoorOpen)
        } else if self.out.overloaded {
            Some(HaltReason::Overload)
        } else {
            None
        }
    }

    /// Motor off: run cleared, standstill set-point.
    fn hold(&mut self) {
        self.out.run = false;
        self.out.setpoint_ua = self.cfg.standstill_ua;
    }

    /// One scan of the automat; returns whether restart pulses are wanted.
    fn service(
        &mut self,
        now: SimTime,
        step: Step,
        e: Edges,
        inp: &Inputs,
        stop_demand: bool,
    ) -> bool {
        if self.restart_wanted && inp.estop_ok && !self.cabin.stop {
            // The STOP circuit runs again after a cabin request: service resumes.
            self.restart_wanted = false;
            self.stop_pending = false;
            self.event(now, EventKind::Resumed);
            if step == Step::StopFault {
                self.phase = Phase::Service(Step::AtFloor);
                return false;
            }
        }
        let want_restart = self.restart_wanted && !inp.estop_ok;
        let settled = now.saturating_duration_since(self.drive_off_at) > COAST;
        if matches!(step, Step::AtFloor | Step::Overload | Step::StopFault)
            && settled
            && (e.vane_rise || e.vane_fall)
        {
            self.mark_lost(now, LostReason::MovedByHand);
        }
        self.step_service(now, step, e, inp, stop_demand);
        // After this scan's count: the count or a sensor is wrong if the sensors show what the
        // counted floor's vane cannot; stop now if moving, else before the next journey.
        if let Phase::Service(step) = self.phase {
            if self.vane_contradicts_floor() {
                if matches!(step, Step::Travel | Step::Braking) {
                    self.lose_now(now, LostReason::WrongVane);
                } else {
                    self.mark_lost(now, LostReason::WrongVane);
                }
            }
        }
        want_restart
    }

    /// The automat's step for this scan (seed tables 6.4/6.5).
    fn step_service(
        &mut self,
        now: SimTime,
        step: Step,
        e: Edges,
        inp: &Inputs,
        stop_demand: bool,
    ) {
        let door_closed = self.cabin.door_closed;
        let overloaded = overloaded(inp);
        let both = self.cabin.vane_left && self.cabin.vane_right;
        let settled = now.saturating_duration_since(self.drive_off_at) > COAST;
        match step {
            Step::AtFloor => {
                if stop_demand {
                    self.enter(now, Step::StopFault);
                } else if self.lost {
                    if door_closed && !overloaded && inp.converter_ready && !inp.converter_fault {
                        // Find the position again before any journey; the calls wait.
                        self.start_init(now);
                    }
                } else if overloaded {
                    self.event(now, EventKind::OverloadFault);
                    self.phase = Phase::Service(Step::Overload);
                } else {
                    self.choose_target(now);
                    if self.target != self.current
                        && now >= self.depart_after
                        && door_closed
                        && inp.converter_ready
                        && !inp.converter_fault
                    {
                        self.depart(now);
                    }
                }
            }
            Step::Overload => {
                if !overloaded {
                    self.event(now, EventKind::OverloadCleared);
                    self.phase = Phase::Service(Step::AtFloor);
                }
            }
            Step::Travel | Step::Braking => {
                let braking = step == Step::Braking;
                if stop_demand && !self.stop_pending {
                    self.stop_demanded(now, braking);
                }
                let halt = if let Some(r) = self.cabin_blocks_motion() {
                    Some(r)
                } else if inp.converter_fault {
                    Some(HaltReason::ConverterFault)
                } else if !inp.converter_ready {
                    Some(HaltReason::NoPower)
                } else {
                    None
                };
                if let Some(reason) = halt {
                    self.hold();
                    self.drive_off_at = now;
                    self.event(now, EventKind::Halted(reason));
                    self.phase = Phase::Service(Step::Halted { reason, braking });
                    // The edges of this scan still count.
                    self.coast(now, e, braking);
                } else if braking {
                    if both {
                        self.arrive(now);
                    } else if e.vane_fall
                        || now.saturating_duration_since(self.progress_at) > self.cfg.creep_watchdog
                    {
                        self.lose_now(now, LostReason::MissedLevel);
                    }
                } else if self.stuck_on(now) {
                    self.lose_now(now, LostReason::StuckSensor);
                } else if self.left_wrong_vane(e) {
                    // Leaving the departure floor's vane, the short track ends first: the right
                    // one at floor 1 (its vane is turned), the left one elsewhere.
                    self.lose_now(now, LostReason::WrongVane);
                } else if e.vane_rise {
                    self.pass_floor(now, e);
                } else if now.saturating_duration_since(self.progress_at) > self.cfg.travel_watchdog
                {
                    self.lose_now(now, LostReason::NoVane);
                }
            }
            Step::Halted { reason, braking } => {
                if stop_demand && !self.stop_pending {
                    self.stop_demanded(now, braking);
                }
                if settled {
                    if e.vane_rise || e.vane_fall {
                        self.mark_lost(now, LostReason::MovedByHand);
                    }
                } else {
                    self.coast(now, e, braking);
                }
                let braking = match self.phase {
                    Phase::Service(Step::Halted { braking, .. }) => braking,
                    _ => braking,
                };
                let cleared = match reason {
                    HaltReason::DoorOpen => door_closed,
                    HaltReason::Overload => !overloaded,
                    HaltReason::Stop => inp.estop_ok,
                    // Not a reason to halt in service (initialisation only).
                    HaltReason::NoVane => true,
                    HaltReason::ConverterFault | HaltReason::NoPower => {
                        !inp.converter_fault && inp.converter_ready
                    }
                };
                if cleared && door_closed && !overloaded && inp.estop_ok && self.lost {
                    if inp.converter_ready && !inp.converter_fault {
                        // The count is not trusted: find floor 1 first, then the target.
                        self.dispatch.requeue(self.target);
                        self.start_init(now);
                    }
                } else if cleared && door_closed && !overloaded && inp.estop_ok {
                    self.event(now, EventKind::Continued);
                    self.progress_at = now;
                    self.running_since = now;
                    self.out.run = true;
                    self.out.up = self.dir == Some(Dir::Up);
                    self.out.setpoint_ua = if braking {
                        self.cfg.creep_ua
                    } else {
                        self.cfg.travel_ua
                    };
                    self.phase = Phase::Service(if braking { Step::Braking } else { Step::Travel });
                }
            }
            Step::StopFault => {}
        }
    }

    fn enter(&mut self, now: SimTime, step: Step) {
        if step == Step::StopFault {
            self.hold();
            self.event(now, EventKind::StopFault);
        }
        self.phase = Phase::Service(step);
    }

    /// At a floor: unload the next target while current floor = target (seed §6.6); a call for
    /// the floor the cabin stands at is served at once.
    fn choose_target(&mut self, now: SimTime) {
        for _ in 0..64 {
            if self.target != self.current {
                return;
            }
            match self.dispatch.next_target(self.current, self.dir) {
                Some(t) if t == self.current => self.serve(now, None),
                Some(t) if (1..=self.cfg.floors).contains(&t) => self.target = t,
                _ => return,
            }
        }
    }

    fn depart(&mut self, now: SimTime) {
        let dir = Dir::between(self.current, self.target);
        self.dir = dir;
        self.progress_at = now;
        self.running_since = now;
        self.leaving = (self.cabin.vane_left || self.cabin.vane_right).then_some(self.current);
        self.stop_pending = false;
        self.out.run = true;
        self.out.up = dir == Some(Dir::Up);
        self.out.setpoint_ua = self.cfg.travel_ua;
        (self.shown_floor, self.shown_dir) = (self.current, dir);
        self.event(
            now,
            EventKind::Departed {
                from: self.current,
                to: self.target,
            },
        );
        self.phase = Phase::Service(Step::Travel);
    }

    /// A rising vane edge during travel: the cabin reaches the next floor's vane (seed tables
    /// 6.4/6.5, "Rozdil" counting); at the target it brakes to the creep speed.
    fn pass_floor(&mut self, now: SimTime, e: Edges) {
        let Some(dir) = self.dir else { return };
        let floor = match self.count_vane(dir, e) {
            Ok(f) => f,
            Err(why) => return self.lose_now(now, why),
        };
        self.current = floor;
        self.progress_at = now;
        if !self.stop_pending
            && self.dispatch.algorithm() == Algorithm::Collective
            && self.dispatch.should_stop(floor, dir)
        {
            self.target = floor;
        }
        if floor == self.target {
            self.out.setpoint_ua = self.cfg.creep_ua;
            self.event(now, EventKind::Braking { floor });
            self.phase = Phase::Service(Step::Braking);
        } else {
            self.event(now, EventKind::Passed { floor });
        }
    }

    /// The floor whose vane the cabin reaches moving `dir`: the next one counted, never one
    /// beyond the end floors. Which sensor came first is kept, to check the floor against the
    /// vane's shape when the cabin stands level in it (see [`Program::arrive`]).
    fn count_vane(&mut self, dir: Dir, e: Edges) -> Result<u8, LostReason> {
        let next = match dir {
            Dir::Up => self.current.checked_add(1),
            Dir::Down => self.current.checked_sub(1),
        };
        self.vane_shape = e.floor1_vane;
        next.filter(|f| (1..=self.cfg.floors).contains(f))
            .ok_or(LostReason::BeyondEndFloor)
    }

    /// Whether the vane sensors show what no working pair can show in the vane of the floor
    /// counted: at floor 1 the right (short) track lies inside the left (long) one, at the
    /// other floors the left inside the right (seed 003 §6.4), so the short sensor is never on
    /// alone.
    fn vane_contradicts_floor(&self) -> bool {
        let (left, right) = (self.cabin.vane_left, self.cabin.vane_right);
        if self.current == 1 {
            right && !left
        } else {
            left && !right
        }
    }

    /// A vane sensor on for longer than a vane takes to pass while the cabin runs at speed.
    fn stuck_on(&self, now: SimTime) -> bool {
        self.on_since.iter().flatten().any(|&on| {
            now.saturating_duration_since(on.max(self.running_since)) > self.cfg.stuck_on_after
        })
    }

    /// Whether the departure floor's vane, as the cabin leaves it, has the wrong shape for the
    /// floor counted; forgets the departure floor once its vane is left.
    fn left_wrong_vane(&mut self, e: Edges) -> bool {
        let Some(floor) = self.leaving else {
            return false;
        };
        if e.vane_fall {
            self.leaving = None;
        }
        e.left_fell_first
            .is_some_and(|left_first| left_first != (floor != 1))
    }

    /// While the cabin comes to rest after a halt: a vane reached on the way is counted (the
    /// halt then continues as braking if it is the target's); leaving the stop floor's vane
    /// while braking means its level was passed.
    fn coast(&mut self, now: SimTime, e: Edges, braking: bool) {
        if braking {
            if e.vane_fall {
                self.mark_lost(now, LostReason::MissedLevel);
            }
            return;
        }
        if !e.vane_rise {
            return;
        }
        let Some(dir) = self.dir else { return };
        match self.count_vane(dir, e) {
            Ok(floor) => {
                self.current = floor;
                if floor == self.target {
                    if let Phase::Service(Step::Halted { reason, .. }) = self.phase {
                        self.phase = Phase::Service(Step::Halted {
                            reason,
                            braking: true,
                        });
                    }
                }
            }
            Err(why) => self.mark_lost(now, why),
        }
    }

    /// The floor count is not trusted any more: initialise before the next journey.
    fn mark_lost(&mut self, now: SimTime, why: LostReason) {
        if !self.lost {
            self.lost = true;
            self.event(now, EventKind::PositionLost { why });
        }
    }

    /// The count failed while the cabin travels: stop and find floor 1 again; the target is
    /// kept for afterwards.
    fn lose_now(&mut self, now: SimTime, why: LostReason) {
        self.hold();
        self.mark_lost(now, why);
        // The journey did not end with an arrival: its target is still wanted.
        self.dispatch.requeue(self.target);
        self.start_init(now);
    }

    /// STOP during travel: stop at the next floor in the direction of travel (seed §6.3, "Porucha
    /// Stop"); already braking, stop where it brakes.
    fn stop_demanded(&mut self, now: SimTime, braking: bool) {
        self.stop_pending = true;
        let stop_at = match (braking, self.dir) {
            (false, Some(dir)) => dir.next(self.current).clamp(1, self.cfg.floors),
            _ => self.target,
        };
        let dropped = (stop_at != self.target).then_some(self.target);
        self.target = stop_at;
        self.event(now, EventKind::StopDemanded { dropped, stop_at });
    }

    fn arrive(&mut self, now: SimTime) {
        self.hold();
        self.drive_off_at = now;
        let floor = self.current;
        // Level in a vane whose long track came first: the left one only at floor 1 (its vane
        // is turned, seed 003 §6.4). A mismatch means the count is off: the calls of this stop
        // are served (the cabin stands level at a floor), and the position is found again
        // before the next journey. Checked only here, where both sensors are seen working.
        if self
            .vane_shape
            .is_some_and(|left_first| left_first != (floor == 1))
        {
            self.mark_lost(now, LostReason::WrongVane);
        }
        self.vane_shape = None;
        self.target = floor;
        self.depart_after = now + self.cfg.dwell;
        (self.shown_floor, self.shown_dir) = (floor, None);
        self.event(now, EventKind::Arrived { floor });
        self.serve(now, self.dir);
        if self.stop_pending {
            self.stop_pending = false;
            self.enter(now, Step::StopFault);
        } else {
            self.phase = Phase::Service(Step::AtFloor);
        }
    }

    fn serve(&mut self, now: SimTime, dir: Option<Dir>) {
        let mut served = core::mem::take(&mut self.served);
        served.clear();
        self.dispatch.serve(self.current, dir, &mut served);
        for s in &served {
            self.event(now, EventKind::Served(*s));
        }
        self.served = served;
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

    /// The display word content (seed 003 tables 4.2/4.4), by the rows of tables 6.3–6.5 that
    /// say what is shown. The floor number and the arrow are latched: they change only at
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
        self.out.display = DisplayState {
            floor: self.shown_floor,
            up: self.shown_dir == Some(Dir::Up),
            down: self.shown_dir == Some(Dir::Down),
            moving,
            fault,
        };
    }

    fn event(&mut self, at: SimTime, kind: EventKind) {
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

    /// The program's state in words, as the report shows it.
    pub fn state_name(&self) -> &'static str {
        match self.phase {
            Phase::WaitInputs => "waiting for inputs",
            Phase::Init(_) => "initialising",
            Phase::BusFault { .. } => "bus fault",
            Phase::Service(step) => match step {
                Step::AtFloor => "at floor",
                Step::Overload => "overload fault",
                Step::Travel if self.dir == Some(Dir::Up) => "moving up",
                Step::Travel => "moving down",
                Step::Braking => "braking",
                Step::StopFault => "STOP fault",
                Step::Halted { .. } => "halted",
            },
        }
    }
}

/// Overloaded, or the load cannot be read: its unsafe value.
fn overloaded(inp: &Inputs) -> bool {
    inp.load >= 3 || inp.load_lost
}

/// The floors whose bits are set, ascending.
fn floors(bits: u32, n: u8) -> impl Iterator<Item = u8> {
    (1..=n).filter(move |f| bits & (1 << (f - 1)) != 0)
}

impl fmt::Display for EventKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let src = |s: &Source| match s {
            Source::Cabin => "cabin",
            Source::Hall => "hall",
        };
        match self {
            EventKind::InitStarted { start } => write!(
                f,
                "initialisation: {}",
                match start {
                    InitStart::Seed => "running down to find floor 1",
                    InitStart::Floor1Track => "inside floor 1's vane, creeping to level",
                    InitStart::Level => "level at a floor, probing which one",
                    InitStart::BelowFloor1 => "just below floor 1's vane, creeping up",
                }
            ),
            EventKind::Initialised => f.write_str("initialised at floor 1"),
            EventKind::CallStored { floor, source } => {
                write!(f, "{} call to floor {floor} stored", src(source))
            }
            EventKind::CallLost { floor, source } => {
                write!(f, "{} call to floor {floor} lost: memory full", src(source))
            }
            EventKind::Departed { from, to } => write!(f, "departs floor {from} for floor {to}"),
            EventKind::Passed { floor } => write!(f, "passes floor {floor}"),
            EventKind::Braking { floor } => write!(f, "brakes for floor {floor}"),
            EventKind::Arrived { floor } => write!(f, "arrives at floor {floor}"),
            EventKind::Served(s) => {
                write!(f, "{} call to floor {} served", src(&s.source), s.floor)
            }
            EventKind::StopDemanded { dropped, stop_at } => match dropped {
                Some(d) => write!(f, "STOP: stops at floor {stop_at}, target {d} dropped"),
                None => write!(f, "STOP: stops at floor {stop_at}"),
            },
            EventKind::StopFault => f.write_str("STOP fault: waiting for a cabin request"),
            EventKind::Resumed => f.write_str("cabin request after STOP: service resumes"),
            EventKind::OverloadFault => f.write_str("overloaded: no departure"),
            EventKind::OverloadCleared => f.write_str("load back to normal"),
            EventKind::Halted(r) => write!(f, "halted between floors: {r}"),
            EventKind::Continued => f.write_str("continues travel"),
            EventKind::BusFault => f.write_str("cabin slave or bus lost: cabin stopped"),
            EventKind::BusRestored => f.write_str("bus restored: initialising again"),
            EventKind::InitHeld(r) => write!(f, "initialisation held: {r}"),
            EventKind::PositionLost { why } => {
                write!(f, "floor count not trusted ({why}): initialising again")
            }
        }
    }
}
