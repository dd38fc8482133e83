//! The rig: the AS-i bus with the lab lift's slaves, the lift plant, the PLC and the safety
//! logic on one simulated clock (docs/architecture.md), driven by a scenario.
//!
//! A discrete-event loop: the next moment is the earliest of the next bus event, the plant's
//! next edge, the next PLC scan, the next safety scan, the next scenario event and the end of
//! the run. At each moment the plant is brought up to it first (its edges are exact), its
//! signals are handed to the slaves' peripheral inputs, the bus runs, and what the slaves drive
//! (converter run and direction, the speed set-point, the display words) goes to the plant at
//! that same moment. So a slave samples the plant exactly when its transaction completes, and
//! the plant sees a new output exactly when the slave takes it. Nothing reads the wall clock;
//! the only random source is the bus's line noise, seeded from the scenario.

mod actions;
mod drive;
mod fork;
mod invariants;
mod las;
mod log_bound;
mod operator;
mod outputs;
mod passengers;
mod plant;
mod riders;
mod scans;
mod wiring;
mod words;

pub use outputs::TransactionObserver;

use crate::report::{
    round3, Actor, Arrival, CabinAt, FinalState, LogEvent, LogLine, MonitorTrip, OvertravelReached,
    PlantLog, Report, RigNote, SlaveDropouts, Trip, TripCause, TripKind, Violation, ViolationKind,
};
use crate::scenario::{Action, Fault, Scenario, ScenarioEvent};
use crate::waves::{RigSample, WaveOutputs, Waves};
use asi_bus::bus::NOMINAL_VOLTS;
use asi_bus::lab::LabLift;
use asi_bus::Stop;
use asi_phy::fault::{FaultRates, PulseErrorRate};
use asi_phy::{SimDuration, SimTime};
use asi_trace::trace::TraceFormat;
use controller::plc::{FromSafety, Plc, ToSafety};
use controller::{Controller, Outside};
use controller::{ControllerConfig, ProgramEventKind as Ctl};
use invariants::{Finding, InvariantWatch, Observed, Quiet};
use lab::address::{SAFETY_BOTTOM, SAFETY_TOP};
use lab::setpoint::STANDSTILL_UA;
use las::LasWatch;
use lift_model::{Lift, LiftConfig, LoadLevel, PlantEventKind as Plant};
use operator::{
    Attendant, Rescue, ATTENDANT_ACK_AFTER, ATTENDANT_NOTICE, ATTENDANT_RESET_AFTER, OPERATOR_PULSE,
};
use outputs::Outputs;
use passengers::Passengers;
use riders::Riders;
use safety::lift::LiftEventKind;
use safety::{LiftSafety, LiftSafetyConfig, LiftSafetyInputs, SafeLink, SAFETY_SCAN_PERIOD};
use wiring::Applied;

/// Why a rig cannot be built for a scenario.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// The lift plant rejects its configuration.
    #[error("lift: {0}")]
    Lift(#[from] lift_model::LiftConfigError),
    /// The bus cannot be built.
    #[error("bus: {0}")]
    Bus(#[from] asi_master::ConfigError),
    /// The controller rejects its configuration.
    #[error("{0}")]
    Controller(#[from] controller::ControllerConfigError),
    /// The safety project cannot be built.
    #[error("safety: {0}")]
    Safety(#[from] safety::lift::LiftSafetyError),
    /// The line noise is no probability.
    #[error("bus: {0}")]
    LineNoise(#[from] asi_phy::PulseErrorRateError),
    /// The plant refuses the scenario's initial state.
    #[error("lift: {0}")]
    Plant(#[from] lift_model::PlantError),
    /// The safe drive's parameters are refused.
    #[error("safe drive: {0}")]
    Drive(#[from] safety::drive::DriveConfigError),
}

/// When the operator presses the safety reset after power-on.
const POWER_ON_RESET_AT: SimTime = SimTime::from_millis(500);

/// Something the rig does at a fixed time besides the scenario's events.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Timer {
    OperatorReset(bool),
    ErrAck(bool),
    PowerBack,
    /// A burst of line noise is over.
    NoiseOver,
    /// The attendant's acknowledge or reset of a round.
    Attendant(Round),
}

/// The later steps of the attendant's round.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Round {
    Ack,
    Reset,
}

/// The whole rig.
///
/// A copy ([`Clone`], a snapshot) goes on exactly as the original from the moment it was
/// taken: the same report, the same transactions. It has none of the original's outputs
/// (the trace, the waveforms, the observers are writers of the rig they were given to); give
/// it its own ([`Rig::trace_to`], [`Rig::waves_to`], [`Rig::on_transaction`]).
#[derive(Clone)]
pub struct Rig {
    sc: Scenario,
    /// The bus with the lab's slaves.
    lab: LabLift,
    /// The plant.
    lift: Lift,
    /// The lift's PLC: the built-in program ([`Plc`]) unless [`Rig::with_controller`] put
    /// another in its place.
    controller: Box<dyn Controller>,
    /// The safety logic, its signals and the safe drive.
    safety: SafetySide,
    /// When the rig's own parts are next due.
    agenda: Agenda,
    /// What the slaves drive, as the plant has it.
    wiring: Wiring,
    /// The lift's passengers and its attendant.
    people: People,
    /// The invariant watch and what it watches besides the plant.
    judge: Judge,
    report: Report,
    /// The trace, the waveforms and the observer.
    outputs: Outputs,
    /// The sources whose log lines are bounded ([`Rig::bound_log`]).
    log_bounds: log_bound::LogBounds,
    /// Every moment is taken ([`Rig::set_pulse_exact`]): no new output passes the rig by.
    every_moment: bool,
    /// What the rig's tests look at inside.
    #[cfg(test)]
    probes: Probes,
}

/// When the rig's own parts are next due: the scans, the scenario's events and the timers
/// (the bus and the plant say when they are due themselves).
#[derive(Clone)]
struct Agenda {
    /// The moment reached.
    now: SimTime,
    /// The run's end.
    end: SimTime,
    next_plc: SimTime,
    next_safety: SimTime,
    /// The scenario's next event, as an index into its events.
    next_event: usize,
    timers: Vec<(SimTime, Timer)>,
    /// The earliest of the next PLC scan, the next safety scan, the next scenario event and
    /// the next timer ([`Rig::own_next_moment`]): what [`Rig::next_moment`] takes besides the
    /// plant's next edge and the end. Those change only in a step, in an action between
    /// moments and when an event is scheduled, so it is worked out again only then
    /// ([`Rig::own_moments_changed`]) rather than at every moment (checked at every moment in
    /// the rig's tests).
    next_own: SimTime,
}

/// The safety logic with the signals it exchanges, and the safe drive.
#[derive(Clone)]
struct SafetySide {
    logic: LiftSafety,
    estop_delay: SimDuration,
    /// What the logic gives the controller.
    from: FromSafety,
    /// What the controller gives the logic.
    to: ToSafety,
    k1: bool,
    operator_reset: bool,
    err_ack: bool,
    /// The logic's last outputs, for the VCD.
    out: Option<safety::lift::LiftSafetyDiag>,
    /// The safe drive (`[drive] safe = true`).
    drive: Option<drive::SafeDriveGuard>,
}

/// What the slaves drive, as the plant has it.
#[derive(Clone)]
struct Wiring {
    applied: Applied,
    /// The lab's count of drive changes when the rig last read what the slaves drive
    /// ([`asi_bus::lab::LabLift::drive_changes`]); `None` when it must read them again.
    drives_seen: Option<u64>,
    /// The plant may show the slaves something new.
    plant_dirty: bool,
}

/// The lift's passengers and its attendant.
#[derive(Clone)]
struct People {
    /// Every press of a call button, for the passengers' waits and the served calls'
    /// requests.
    passengers: Passengers,
    /// The passengers of the scenario's traffic templates.
    riders: Riders,
    /// The lift attendant, once a scenario's `attend` has started it.
    attendant: Attendant,
    /// The last safety scan left the attendant's watch with nothing to count (K1 closed, or
    /// open for a cause no round answers): a scan with the same outputs changes nothing in it
    /// ([`Attendant::watch`] of a K1 it does not watch only forgets since when it was open,
    /// which it has forgotten already).
    attendant_idle: bool,
}

/// The invariant watch, and what the rig watches on the bus and the controller for the report.
#[derive(Clone)]
struct Judge {
    watch: InvariantWatch,
    /// When the invariant watch's check may be skipped.
    quiet: Quiet,
    /// Drop-outs from LAS.
    las_watch: LasWatch,
    /// Since when the controller holds the cabin for a bus fault.
    bus_fault_since: Option<SimTime>,
}

/// What the rig's tests look at inside.
#[cfg(test)]
#[derive(Clone, Default)]
struct Probes {
    /// The outputs of the last safety scan the rig took from the logic (K1, EStopOut, the
    /// diagnosis), which a quiet scan gives again (checked in `Rig::safety_scan`).
    scanned: Option<(bool, bool, safety::lift::LiftSafetyDiag)>,
    /// The safety scans taken in stretches of quiet scans ([`Rig::quiet_scans`]).
    stretch_scans: u64,
}

/// The built-in program's settings from the scenario's `[controller]` table (the rest at
/// their defaults).
fn controller_settings(sc: &Scenario) -> ControllerConfig {
    let mut cfg = ControllerConfig::default();
    cfg.floors = sc.floors;
    cfg.algorithm = sc.algorithm;
    cfg.scan = sc.plc_scan;
    cfg
}

impl Rig {
    /// A rig at power-on for `sc`: its PLC runs the scenario's Structured Text program
    /// ([`Scenario::program`]) if it has one, else the built-in program.
    pub fn new(sc: Scenario) -> Result<Rig, RigError> {
        let lift = Lift::new({
            let mut cfg = LiftConfig::default();
            cfg.floors = sc.floors;
            cfg.initial_position_mm = sc.start_mm;
            cfg
        })?;
        let mut master = asi_master::MasterConfig::default();
        master.mode = sc.master_mode;
        let mut lab = LabLift::with_extra(master, sc.extra_slaves)?;
        lab.bus_mut().watch(asi_bus::Watch {
            outputs: wiring::drives_plant(),
            ..asi_bus::Watch::default()
        });
        lab.bus_mut().enable_trace(0);
        let rate = PulseErrorRate::new(sc.pulse_error_rate)?;
        if rate.get() > 0.0 {
            lab.bus_mut()
                .set_line_faults(sc.seed, FaultRates::uniform(rate));
        }
        let plc = Plc::new(controller_settings(&sc))?;
        let safety_cfg = LiftSafetyConfig::default();
        let estop_delay = safety_cfg.estop_delay;
        let safety = LiftSafety::new(safety_cfg)?;
        let mut timers = Vec::new();
        if sc.power_on_reset {
            timers.push((POWER_ON_RESET_AT, Timer::OperatorReset(true)));
        }
        let report = Report::at_power_on(&sc.name, sc.seed, sc.start_mm);
        let watch = InvariantWatch::new(
            (1..=sc.floors)
                .filter_map(|f| lift.config().floor_level_mm(f))
                .collect(),
            lift.config().long_track_half_mm,
        );
        let mut rig = Rig {
            agenda: Agenda {
                now: SimTime::ZERO,
                end: SimTime::ZERO + sc.duration,
                next_plc: SimTime::ZERO,
                next_safety: SimTime::ZERO,
                next_event: 0,
                timers,
                next_own: SimTime::ZERO,
            },
            lab,
            lift,
            controller: Box::new(plc),
            safety: SafetySide {
                logic: safety,
                estop_delay,
                from: FromSafety::default(),
                to: ToSafety::default(),
                k1: false,
                operator_reset: false,
                err_ack: false,
                out: None,
                drive: None,
            },
            wiring: Wiring {
                applied: Applied::default(),
                drives_seen: None,
                plant_dirty: true,
            },
            people: People {
                passengers: Passengers::default(),
                riders: Riders::of(&sc),
                attendant: Attendant::default(),
                attendant_idle: false,
            },
            judge: Judge {
                watch,
                quiet: Quiet::default(),
                las_watch: LasWatch::default(),
                bus_fault_since: None,
            },
            every_moment: false,
            #[cfg(test)]
            probes: Probes::default(),
            report,
            outputs: Outputs::default(),
            log_bounds: log_bound::LogBounds::default(),
            sc,
        };
        rig.lift.set_load(SimTime::ZERO, rig.sc.load)?;
        rig.lift.set_door(SimTime::ZERO, rig.sc.door_closed)?;
        rig.log(
            Actor::Rig,
            format!(
                "power on: cabin at {:.1} mm, load {}, door {}, {} control, line error rate {}",
                rig.sc.start_mm,
                rig.sc.load.name(),
                if rig.sc.door_closed { "closed" } else { "open" },
                match rig.sc.algorithm {
                    controller::Algorithm::Fifo => "FIFO",
                    controller::Algorithm::Collective => "collective",
                },
                rig.sc.pulse_error_rate
            ),
        );
        rig.own_moments_changed();
        if rig.sc.safe_drive {
            rig.safety.drive = Some(drive::SafeDriveGuard::new(&rig.lift)?);
            rig.log(
                Actor::Rig,
                "safe drive: encoder on the motor, drive safety monitor (SS1, SOS, SLS, SDI, SLP; STO through K1)".to_owned(),
            );
        }
        if let Some(p) = &rig.sc.program {
            let program = p.controller(rig.sc.plc_scan);
            rig = rig.with_controller(program);
        }
        Ok(rig)
    }

    /// Streams every bus transaction, one line each in `format`, to `out` (drained from the
    /// master's trace ring at every PLC scan and at the end).
    pub fn trace_to(&mut self, out: Box<dyn std::io::Write>, format: TraceFormat) {
        self.enable_trace_ring();
        self.outputs.trace = Some((out, format));
    }

    /// Runs the bus pulse-exact (`true`): every telegram through the pulse decoder, none of
    /// the fast paths. Reports, traces and wave outputs are the same either way (tested for
    /// every scenario and for random ones with faults); the exact path is what the speed of
    /// the fast one is measured against (`docs/dev/performance.md`).
    pub fn set_pulse_exact(&mut self, on: bool) {
        self.lab.bus_mut().set_pulse_exact(on);
        self.every_moment = on;
    }

    /// Writes the VCD and the line-voltage CSV of the run (see [`crate::waves`]). A copy of a
    /// rig ([`Clone`]) given them before it steps on goes on with the original's
    /// waveforms (and their windows) into these writers; otherwise they begin at the moment
    /// reached.
    pub fn waves_to(&mut self, out: WaveOutputs) {
        self.enable_trace_ring();
        self.lab.bus_mut().record_line(true);
        let waves = match self.outputs.copied_waves.take() {
            Some(copied) => copied.continue_into(out),
            None => {
                let waves = Waves::new(out, self.lab.bus().timing()).starting_at(self.agenda.now);
                match self.safety.drive {
                    Some(_) => waves.with_drive_safety(),
                    None => waves,
                }
            }
        };
        self.outputs.waves = Some(waves);
    }

    /// Hands every bus transaction to `f` (at every PLC scan and at the end, in order),
    /// besides the observers added before.
    pub fn on_transaction(&mut self, f: TransactionObserver) {
        self.enable_trace_ring();
        self.outputs.observers.push(f);
    }

    fn enable_trace_ring(&mut self) {
        // A copy of a rig keeps the records its original had not yet handed on: its new
        // outputs get them.
        if self.lab.bus_mut().trace_ring_mut().is_none() {
            // A PLC scan spans about 65 transactions of the lab bus; the ring holds far more.
            self.lab.bus_mut().enable_trace(1 << 16);
        }
    }

    /// The first error writing the trace or the waveforms, if any.
    pub fn trace_error(&self) -> Option<&str> {
        self.outputs.error()
    }

    /// Hands the transactions and line pulses since the last call to the trace and the
    /// waveform outputs.
    fn flush_trace(&mut self) {
        // A copy of a rig that had outputs keeps recording for the outputs it is given
        // before its first step ([`Rig::enable_trace_ring`], [`Rig::waves_to`]); given none,
        // nothing wants the records.
        if self.outputs.waves.is_none() && self.lab.bus().records_line() {
            self.lab.bus_mut().record_line(false);
        }
        if !self.outputs.wanted() {
            if self.lab.bus_mut().trace_ring_mut().is_some() {
                self.lab.bus_mut().enable_trace(0);
            }
            return;
        }
        let records = self.lab.bus_mut().drain_trace();
        let pulses = if self.outputs.waves.is_some() {
            self.lab.bus_mut().take_line_pulses()
        } else {
            Vec::new()
        };
        self.outputs
            .transactions(&records, &pulses, self.agenda.now);
    }

    /// The rig's state for the waveforms at `t`, if they are wanted.
    #[inline]
    fn sample_waves(&mut self, t: SimTime) {
        if self.outputs.waves.is_some() {
            self.sample_waves_now(t);
        }
    }

    #[inline(never)]
    fn sample_waves_now(&mut self, t: SimTime) {
        let sample = self.sample();
        self.outputs.sample(t, &sample);
    }

    /// The rig's state for the VCD.
    fn sample(&self) -> RigSample {
        let l = &self.lift;
        let status = self.controller.status();
        let calls = self.controller.pending_calls().unwrap_or_default();
        let diag = self.safety.out.as_ref();
        RigSample {
            position_mm: l.position_mm(),
            velocity_mm_s: l.velocity_mm_s(),
            vane_left: l.vane_left(),
            vane_right: l.vane_right(),
            overtravel_bottom_free: l.overtravel_bottom_free(),
            overtravel_top_free: l.overtravel_top_free(),
            k1: l.k1_closed(),
            door_closed: l.door_closed(),
            converter_run: self.wiring.applied.run,
            converter_up: self.wiring.applied.up,
            setpoint_ua: self.wiring.applied.setpoint_ua,
            // A controller that tells no state is the outside one of `serve`.
            controller_state: status.state.map_or("external", |s| s.name()),
            floor: status.floor.unwrap_or(0),
            target_floor: status.target.unwrap_or(0),
            fifo_cabin: calls.cabin.len() as u8,
            fifo_hall: calls.hall.len() as u8,
            estop_out: self.safety.from.estop_out,
            group_state: diag.map_or("STOP", |d| d.group.state.name()),
            fb_err: diag.is_some_and(|d| d.group.errors.fb_err),
            com_err: diag.is_some_and(|d| d.group.errors.com_err),
            out_err: diag.is_some_and(|d| d.group.errors.out_err),
            supply_v: self.lab.bus().supply_voltage(),
            drive: self.safety.drive.as_ref().map(|d| d.sample()),
            master_leds: self.lab.bus().master().leds(),
        }
    }

    /// Runs until `until` (at most the scenario's duration) and returns the report.
    pub fn run(self, until: Option<SimDuration>) -> Report {
        self.run_observed(until, &mut |_, _| std::ops::ControlFlow::Continue(()))
    }

    /// As [`Rig::run`], telling `progress` the simulated time and the end after every PLC
    /// scan (for a progress indicator; the simulation does not depend on it). A
    /// `ControlFlow::Break` ends the run there (the caller's reader has gone, say); the report
    /// then covers the run up to that moment.
    pub fn run_observed(
        mut self,
        until: Option<SimDuration>,
        progress: &mut dyn FnMut(SimTime, SimTime) -> std::ops::ControlFlow<()>,
    ) -> Report {
        if let Some(u) = until {
            self.agenda.end = self.agenda.end.min(SimTime::ZERO + u);
        }
        let mut scans = self.agenda.next_plc;
        while let Some(t) = self.advance_to_step(self.agenda.end) {
            if self.agenda.next_plc != scans {
                scans = self.agenda.next_plc;
                if progress(t, self.agenda.end).is_break() {
                    self.log(Actor::Rig, LogEvent::Note(RigNote::StoppedEarly));
                    break;
                }
            }
            if t == self.agenda.end {
                break;
            }
        }
        self.finish()
    }

    /// The rig's next moment: the earliest of the end, the plant's next edge and the rig's own
    /// next moment, and not before the moment reached.
    #[inline]
    fn next_moment(&self) -> SimTime {
        #[cfg(test)]
        assert_eq!(
            self.agenda.next_own,
            self.own_next_moment(),
            "the rig's own next moment is stale at {}",
            self.agenda.now
        );
        let mut t = self.agenda.end.min(self.agenda.next_own);
        if let Some(e) = self.lift.next_event() {
            t = t.min(e);
        }
        t.max(self.agenda.now)
    }

    /// The earliest of the next PLC scan, the next safety scan, the next scenario event and
    /// the next timer.
    fn own_next_moment(&self) -> SimTime {
        self.agenda.next_safety.min(self.own_next_but_safety())
    }

    /// The earliest of the next PLC scan, the next scenario event and the next timer.
    fn own_next_but_safety(&self) -> SimTime {
        let mut t = self.agenda.next_plc;
        if let Some(e) = self.sc.events.get(self.agenda.next_event) {
            t = t.min(e.at);
        }
        if let Some((at, _)) = self.agenda.timers.iter().min_by_key(|(at, _)| *at) {
            t = t.min(*at);
        }
        if let Some(at) = self.people.riders.next_at() {
            t = t.min(at);
        }
        t
    }

    /// Works [`Agenda::next_own`] out again, after a scan, a scenario event or a timer may have
    /// moved.
    fn own_moments_changed(&mut self) {
        self.agenda.next_own = self.own_next_moment();
    }

    /// Handles the rig's next moment, or a slave's new output before it, if it comes no later
    /// than `limit`; returns its time. The bus runs on its own up to the rig's next moment and
    /// stops where a slave takes a new output for the plant, which gets it at that moment.
    #[inline]
    fn advance(&mut self, limit: SimTime) -> Option<SimTime> {
        self.outputs.stepped();
        let t = self.next_moment();
        if t > limit {
            return None;
        }
        // No look watch is set here: every stop is a new output.
        if let Some(Stop::Output(at) | Stop::Look(at)) = self.lab.bus_mut().advance_before(t) {
            self.output_taken(at);
            return Some(at);
        }
        self.step(t);
        Some(t)
    }

    /// As [`Rig::advance`], but goes on through the slaves' new outputs to the rig's next
    /// moment, and returns only then (for [`Rig::run_observed`], which has nothing to do
    /// after a new output: it is before the end, and no PLC scan has run). About half the
    /// moments of a run are new outputs of the set-point slave's analog transfer.
    fn advance_to_step(&mut self, limit: SimTime) -> Option<SimTime> {
        self.outputs.stepped();
        loop {
            let t = self.next_moment();
            if t > limit {
                return None;
            }
            let quiet = self.outputs_pass_until();
            let bus = self.lab.bus_mut();
            let mut watch = bus.watching();
            watch.drives_only_through = quiet;
            bus.watch(watch);
            match self.quiet_scans(t, quiet, limit) {
                scans::Stretch::None => {}
                scans::Stretch::Went => continue,
                scans::Stretch::StepAt(at) => {
                    self.step(at);
                    return Some(at);
                }
            }
            match self.lab.bus_mut().advance_before(t) {
                Some(Stop::Output(at) | Stop::Look(at)) => self.output_taken(at),
                None => {
                    self.step(t);
                    return Some(t);
                }
            }
        }
    }

    /// Until when (inclusive) a slave's new output nibble that changes nothing it drives may
    /// pass the rig by ([`asi_bus::Watch::drives_only_through`]), `None`: never.
    ///
    /// Its moment ([`Rig::output_taken`]) would do nothing but move the rig's and the plant's
    /// time: the plant has no edge before the rig's next moment, the slaves drive what they
    /// drove (the count has not moved), the plant has nothing for the slaves (not dirty), the
    /// invariant watch's check is skipped (up to the time its quiet holds, for the plant as it
    /// is), and no waves are sampled. Nothing moves those before the next moment but the bus.
    /// The pulse-exact path takes every such moment, and the fast-path tests compare the two
    /// ([`Rig::run_observed`] only: the live mode's moments are the caller's).
    fn outputs_pass_until(&self) -> Option<SimTime> {
        if self.every_moment || self.wiring.plant_dirty || self.outputs.waves.is_some() {
            return None;
        }
        self.judge.quiet.through(self.plant_key())
    }

    /// A slave took a new output at `t` (before the rig's next moment): the plant gets it.
    fn output_taken(&mut self, t: SimTime) {
        self.agenda.now = t;
        self.advance_plant(t);
        self.slaves_to_plant(t);
        if self.wiring.plant_dirty {
            self.plant_to_slaves();
        }
        self.check_invariants(t);
        self.sample_waves(t);
    }

    fn step(&mut self, t: SimTime) {
        self.agenda.now = t;
        self.advance_plant(t);
        while let Some(ev) = self
            .sc
            .events
            .get(self.agenda.next_event)
            .filter(|e| e.at <= t)
            .cloned()
        {
            self.agenda.next_event += 1;
            self.apply(t, &ev);
        }
        self.riders_due(t);
        self.fire_timers(t);
        if self.wiring.plant_dirty {
            self.plant_to_slaves();
        }
        self.lab.bus_mut().advance_to(t);
        self.slaves_to_plant(t);
        if t >= self.agenda.next_safety {
            self.safety_scan(t);
            self.agenda.next_safety = t + SAFETY_SCAN_PERIOD;
        }
        if t >= self.agenda.next_plc {
            self.plc_scan(t);
            self.agenda.next_plc = t + self.controller.scan_period();
            self.flush_trace();
        }
        self.own_moments_changed();
        self.check_invariants(t);
        self.sample_waves(t);
    }

    /// What the invariant watch's skipping keys on ([`invariants::Quiet`]): the plant's count of
    /// changes and whether it moves.
    #[inline]
    fn plant_key(&self) -> invariants::PlantKey {
        (
            self.lift.changes(),
            self.lift.velocity_mm_s() != 0.0,
            self.safety.from.estop_out,
        )
    }

    /// The invariant watch at `t`. Skipped while the watch would see what it saw at its last
    /// check and no budget runs out ([`invariants::Quiet`]); in the rig's tests every skipped
    /// check is run on a copy of the watch, which must find nothing and stay as it is.
    #[inline]
    fn check_invariants(&mut self, t: SimTime) {
        let key = self.plant_key();
        if self.judge.quiet.holds(key, t) {
            #[cfg(test)]
            self.assert_quiet(t);
        } else {
            self.check_invariants_now(t, key);
        }
    }

    /// What the shortcut replaces: the check at `t`, on a copy of the watch, which must find
    /// nothing and leave the copy as the watch is.
    #[cfg(test)]
    fn assert_quiet(&self, t: SimTime) {
        let mut full = self.judge.watch.clone();
        let found = full.check(t, self.observed(), self.safety.estop_delay);
        assert!(
            found.is_empty() && full == self.judge.watch,
            "a check skipped at {t} finds {found:?} or changes the watch"
        );
    }

    /// The invariant watch's check at `t` of the plant with `key`.
    #[inline(never)]
    fn check_invariants_now(&mut self, t: SimTime, key: invariants::PlantKey) {
        let seen = self.observed();
        for found in self.judge.watch.check(t, seen, self.safety.estop_delay) {
            match found {
                Finding::Violation(kind, detail) => self.violation(t, kind, detail),
                Finding::OvertravelReached => self.overtravel_reached(t),
            }
        }
        self.judge
            .quiet
            .after_check(&self.judge.watch, key, &seen, self.safety.estop_delay);
    }

    /// What the invariant watch looks at now.
    fn observed(&self) -> Observed {
        let l = &self.lift;
        Observed {
            velocity_mm_s: l.velocity_mm_s(),
            hand_cranking: l.hand_cranking(),
            door_open: !l.door_closed(),
            overloaded: l.load() == LoadLevel::Overloaded,
            overtravel_tripped: !l.overtravel_bottom_free() || !l.overtravel_top_free(),
            k1_closed: l.k1_closed(),
            stop: l.stop_channels() != [true, true],
            estop_out: self.safety.from.estop_out,
            run_commanded: wiring::run_commanded(&self.lab),
            position_mm: l.position_mm(),
            level_floor: Observed::needs_level_floor(self.safety.drive.is_some(), !l.door_closed())
                .then(|| l.config().level_floor(l.position_mm()))
                .flatten(),
            watch_unintended_movement: self.safety.drive.is_some(),
        }
    }

    fn violation(&mut self, t: SimTime, kind: ViolationKind, detail: String) {
        let e = LogEvent::Violation {
            kind,
            detail: detail.clone(),
        };
        self.log_at(t, Actor::Judge, e);
        self.report.violations.push(Violation {
            at_s: t.as_secs_f64(),
            kind,
            detail,
        });
    }

    /// The cabin reached an overtravel sensor under power: contained by the safety logic, but
    /// a failure of the controller that a judge of it wants counted (docs/safety.md).
    fn overtravel_reached(&mut self, t: SimTime) {
        let end = if self.lift.overtravel_top_free() {
            "bottom"
        } else {
            "top"
        };
        let position_mm = self.lift.position_mm();
        let note = RigNote::OvertravelReached {
            top: end == "top",
            position_mm,
        };
        self.log_at(t, Actor::Rig, LogEvent::Note(note));
        self.report
            .safety
            .overtravel_reached
            .push(OvertravelReached {
                at_s: t.as_secs_f64(),
                end: end.to_string(),
                position_mm: round3(position_mm),
            });
    }

    fn log(&mut self, who: Actor, event: impl Into<LogEvent>) {
        self.log_at(self.agenda.now, who, event);
    }

    fn log_at(&mut self, at: SimTime, who: Actor, event: impl Into<LogEvent>) {
        let line = LogLine::new(at.as_secs_f64(), who, event.into());
        if let Some(line) = self.log_bounds.take(line) {
            self.report.log.push(line);
        }
    }

    /// Ends the run at the moment reached and returns its report (what [`Rig::run`] does at
    /// the end; for callers that step the rig themselves).
    pub fn finish(mut self) -> Report {
        self.flush_trace();
        self.outputs.finish(self.agenda.now);
        if let Some(e) = self.trace_error().map(str::to_owned) {
            let note = RigNote::TraceNotWritten(e.clone());
            self.log(Actor::Rig, LogEvent::Note(note));
            self.report.output_error = Some(e);
        }
        let now = self.agenda.now;
        self.watch_bus(now);
        self.judge.las_watch.close(now);
        if let Some(s) = self.judge.bus_fault_since.take() {
            self.report.availability.bus_fault_s += (now - s).as_secs_f64();
        }
        self.report.availability.bus_fault_s = round3(self.report.availability.bus_fault_s);
        let dropouts: Vec<SlaveDropouts> = self
            .judge
            .las_watch
            .dropouts()
            .map(|(address, count, out)| SlaveDropouts {
                address,
                count,
                out_of_las_s: round3(out.as_secs_f64()),
            })
            .collect();
        let status = self.controller.status();
        let calls = self.controller.pending_calls();
        let stats = self.lab.bus().stats();
        self.report.simulated_s = self.agenda.now.as_secs_f64();
        self.report.final_state = FinalState {
            floor: status.floor,
            position_mm: round3(self.lift.position_mm()),
            cabin_at: CabinAt::of(self.lift.config(), self.lift.position_mm()),
            state: status.state,
            moving: self.lift.velocity_mm_s() != 0.0,
            contactor_closed: self.lift.k1_closed(),
            k1_open_cause: self
                .safety
                .out
                .as_ref()
                .and_then(|d| d.k1_open_cause)
                .filter(|_| !self.lift.k1_closed())
                .map(|c| words::k1_open_cause(c, self.lab.monitor()))
                .or_else(|| {
                    let d = self
                        .safety
                        .drive
                        .as_ref()
                        .filter(|_| !self.lift.k1_closed())?;
                    d.torque_off_cause()
                }),
            fifo_cabin: calls.as_ref().map(|c| c.cabin.clone()),
            fifo_hall: calls.map(|c| c.hall),
        };
        self.report.bus = words::bus_report(stats, dropouts);
        self.report.bus.slaves = words::slave_reports(self.lab.bus());
        self.report.bus.master_leds = crate::report::MasterLedsReport::of(
            self.lab.bus().master().led_watch(),
            self.lab.bus().now(),
        );
        self.report.passengers = self.people.passengers.report();
        self.report.traffic = self.traffic_report();
        if let Some(d) = self.safety.drive.as_mut() {
            self.report.safety.drive = Some(d.finish());
        }
        let held_back = self.log_bounds.drain();
        self.report.log.extend(held_back);
        // Lines from different sources come in scan order; keep them in time order.
        self.report.log.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
        self.report
    }

    // ----- probes: stepping and state for timing studies (`asi-lift timing`) ----------------

    /// Runs the next moment of the rig if it comes no later than `until` and before the
    /// scenario's end; returns its time. A caller can look at the rig between moments and
    /// [`Rig::schedule`] actions in reaction to what it sees.
    pub fn step_until(&mut self, until: SimTime) -> Option<SimTime> {
        if self.next_moment() >= self.agenda.end {
            return None;
        }
        self.advance(until)
    }

    /// Schedules `action` at `at` as if the scenario had it (a time before the next moment
    /// takes effect at the next moment).
    pub fn schedule(&mut self, at: SimTime, action: Action) {
        let later = &self.sc.events[self.agenda.next_event..];
        let pos = self.agenda.next_event + later.partition_point(|e| e.at <= at);
        self.sc.events.insert(
            pos,
            ScenarioEvent {
                at,
                action,
                line: 0,
            },
        );
        self.own_moments_changed();
    }

    /// Puts `controller` in the built-in program's place, with the scenario's controller
    /// settings ([`Controller::configure`]): the rig scans it every
    /// [`Controller::scan_period`] from the moment reached. Bus, slaves, plant, safety logic
    /// and invariant watch run as before.
    pub fn with_controller(mut self, mut controller: impl Controller) -> Rig {
        controller.configure(&controller_settings(&self.sc));
        self.report.controller = controller.program_name().map(str::to_owned);
        self.controller = Box::new(controller);
        self.agenda.next_plc = self.agenda.next_plc.max(self.agenda.now);
        self.own_moments_changed();
        self
    }

    /// Turns the built-in PLC program off for an outside controller (`asi-lift serve
    /// --controller external`, [`Outside`]): it writes the output image between moments
    /// through [`Rig::lab_mut`] and gives the safety logic its standard signals through
    /// [`Outside::set_signals`] ([`Rig::controller_mut`]). A stop level at a floor counts as
    /// serving every call waiting there.
    pub fn with_external_controller(self) -> Rig {
        let scan = self.sc.plc_scan;
        let mut rig = self.with_controller(Outside::new(scan));
        rig.log(
            Actor::Rig,
            "controller: external (the built-in PLC program is off)".to_owned(),
        );
        rig
    }

    /// The controller, if it is a `C`.
    pub fn controller<C: Controller>(&self) -> Option<&C> {
        self.controller.as_any().downcast_ref()
    }

    /// The controller, mutable, if it is a `C` (an [`Outside`] controller's signals, say).
    pub fn controller_mut<C: Controller>(&mut self) -> Option<&mut C> {
        self.controller.as_any_mut().downcast_mut()
    }

    /// What the controller tells about itself now.
    pub fn controller_status(&self) -> controller::Status {
        self.controller.status()
    }

    /// The calls the controller holds, if it tells them.
    pub fn controller_calls(&self) -> Option<controller::PendingCalls> {
        self.controller.pending_calls()
    }

    /// Does `action` now, as a scenario event would; `who` names the actor in the log.
    pub fn act_now(&mut self, who: Actor, action: &Action) {
        self.act(self.agenda.now, who, action);
        self.own_moments_changed();
    }

    /// Adds a line to the run's log at the moment reached.
    pub fn log_now(&mut self, who: Actor, event: impl Into<LogEvent>) {
        self.log(who, event);
    }

    /// When the run ends (the scenario's duration, or the `until` of [`Rig::set_end`]).
    pub fn end(&self) -> SimTime {
        self.agenda.end
    }

    /// Moves the end of the run (to run open-ended, or to stop early); never before the
    /// moment reached.
    pub fn set_end(&mut self, end: SimTime) {
        self.agenda.end = end.max(self.agenda.now);
    }

    /// The safety logic's last outputs (absent before its first scan).
    pub fn safety_diag(&self) -> Option<&safety::lift::LiftSafetyDiag> {
        self.safety.out.as_ref()
    }

    /// The run's log so far (lines from different sources in the order they were written;
    /// the report sorts them by time at the end), without the lines a bounded source holds
    /// back ([`Rig::bound_log`]).
    pub fn log_lines(&self) -> &[LogLine] {
        &self.report.log
    }

    /// The latest `n` lines of the run's log, those a bounded source holds back included,
    /// oldest first.
    pub fn recent_log(&self, n: usize) -> Vec<&LogLine> {
        let log = &self.report.log;
        let mut lines: Vec<&LogLine> = log[log.len().saturating_sub(n)..].iter().collect();
        lines.extend(self.log_bounds.tails(n));
        lines.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
        let skip = lines.len().saturating_sub(n);
        lines.split_off(skip)
    }

    /// Keeps only the first `first` and the last `last` log lines of `who` (a live run's
    /// clients, which may send a command any number of times); the report says how many
    /// lines between them were left out, at the time of the first.
    pub fn bound_log(&mut self, who: Actor, first: usize, last: usize) {
        self.log_bounds.set(who, first, last);
    }

    /// The violations found so far.
    pub fn violations(&self) -> &[Violation] {
        &self.report.violations
    }

    /// The simulated time reached.
    pub fn now(&self) -> SimTime {
        self.agenda.now
    }

    /// The lab bus and its devices.
    pub fn lab(&self) -> &LabLift {
        &self.lab
    }

    /// The lab bus, mutable (to trace it). The rig reads the slaves' outputs afresh at its
    /// next moment, whatever the caller changes.
    pub fn lab_mut(&mut self) -> &mut LabLift {
        self.wiring.drives_seen = None;
        &mut self.lab
    }

    /// The built-in PLC program, unless another controller took its place.
    pub fn plc(&self) -> Option<&Plc> {
        self.controller()
    }

    /// The safe drive's control and status bits now (`[drive] safe = true`), as the VCD's
    /// scope `rig.drive_safety` has them; `None` without the safe drive.
    pub fn drive_sample(&self) -> Option<crate::waves::DriveSample> {
        self.safety.drive.as_ref().map(|d| d.sample())
    }

    /// The lift plant.
    pub fn lift(&self) -> &Lift {
        &self.lift
    }

    /// Whether the controller commands the converter to run: the run bit (slave 7, D0) in the
    /// output image as it last wrote it, before the bus carries it to the slave.
    pub fn run_commanded(&self) -> bool {
        wiring::run_commanded(&self.lab)
    }

    /// The safety logic's STOP delay (SS1): how long K1 may stay closed after STOP.
    pub fn estop_delay(&self) -> SimDuration {
        self.safety.estop_delay
    }

    /// The safety logic's EStopOut as the controller last got it (`true` = no STOP demand).
    pub fn estop_out(&self) -> bool {
        self.safety.from.estop_out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::generate::generate;
    use crate::campaign::profile::Profile;
    use crate::scenario::builtin::BUILTINS;

    /// Runs `sc` to its end; in the rig's tests every moment that skips reading the slaves'
    /// outputs checks them against a fresh reading ([`Rig::slaves_to_plant`]).
    fn run(sc: Scenario) -> Report {
        Rig::new(sc).expect("a rig for the scenario").run(None)
    }

    /// What [`Rig::run`] did before it went through the slaves' new outputs in one call
    /// ([`Rig::advance_to_step`]): one [`Rig::advance`] per moment, new outputs included.
    fn run_moment_by_moment(sc: Scenario) -> Report {
        let mut rig = Rig::new(sc).expect("a rig for the scenario");
        let mut scans = rig.agenda.next_plc;
        let mut progress_at = Vec::new();
        while let Some(t) = rig.advance(rig.agenda.end) {
            if rig.agenda.next_plc != scans {
                scans = rig.agenda.next_plc;
                progress_at.push(t);
            }
            if t == rig.agenda.end {
                break;
            }
        }
        let mut report = rig.finish();
        report.log.push(LogLine::new(
            0.0,
            Actor::Rig,
            LogEvent::Text(format!("{progress_at:?}")),
        ));
        report
    }

    /// [`Rig::run_observed`] with the progress it reports, as in `run_moment_by_moment`.
    fn run_observed_with_progress(sc: Scenario) -> Report {
        let mut progress_at = Vec::new();
        let mut report =
            Rig::new(sc)
                .expect("a rig for the scenario")
                .run_observed(None, &mut |t, _| {
                    progress_at.push(t);
                    std::ops::ControlFlow::Continue(())
                });
        report.log.push(LogLine::new(
            0.0,
            Actor::Rig,
            LogEvent::Text(format!("{progress_at:?}")),
        ));
        report
    }

    /// Going through the slaves' new outputs in one call gives the report, and the
    /// progress at the same moments, that a call per moment gives: for random campaign runs
    /// with faults (slaves off and on the bus, power fails, noise, the safe drive).
    #[test]
    fn a_run_through_the_new_outputs_is_a_run_moment_by_moment() {
        let mut scenarios = Vec::new();
        for name in ["default", "noisy", "safe-drive"] {
            let profile = Profile::built_in(name).expect("a built-in profile");
            // One run of each profile: each run is simulated twice in a debug build, and the
            // workspace's tests should stay near three minutes.
            scenarios.push(generate(11, 0, &profile).scenario);
        }
        for sc in scenarios {
            let name = sc.name.clone();
            assert_eq!(
                run_observed_with_progress(sc.clone()),
                run_moment_by_moment(sc),
                "{name}"
            );
        }
    }

    /// Most safety scans of a run are taken in stretches of quiet scans
    /// ([`Rig::quiet_scans`]): those of 30 s from power-on with the initialisation run and a
    /// call served (the comparisons above would hold with no stretch at all).
    #[test]
    fn most_safety_scans_are_taken_in_stretches_of_quiet_scans() {
        let sc = Scenario {
            duration: SimDuration::from_secs(30),
            events: vec![ScenarioEvent {
                at: SimTime::from_millis(13_000),
                action: Action::Press {
                    button: lift_model::Button::Cabin(3),
                    hold: SimDuration::from_millis(300),
                },
                line: 0,
            }],
            ..Scenario::defaults()
        };
        let mut rig = Rig::new(sc).expect("a rig for the scenario");
        while rig
            .advance_to_step(rig.agenda.end)
            .is_some_and(|t| t < rig.agenda.end)
        {}
        // 30,000 scans, one in ten with a PLC scan.
        assert!(
            rig.probes.stretch_scans > 24_000,
            "{} scans in stretches",
            rig.probes.stretch_scans
        );
        assert_eq!(rig.report.served.len(), 1, "the call is served");
    }

    /// The drive-change count covers every way the slaves' outputs change in the built-in
    /// scenarios: handshakes and set-points, a slave off and back on the bus, a power fail,
    /// line noise.
    #[test]
    fn the_slaves_outputs_are_read_whenever_they_change_in_the_builtin_scenarios() {
        for b in BUILTINS {
            let sc = b.scenario().expect("a built-in scenario");
            let report = run(sc);
            assert!(report.simulated_s > 0.0, "{}", b.name);
        }
    }

    /// As above, for random campaign runs with faults (slaves off and on the bus, power
    /// fails, noise, the safe drive).
    #[test]
    fn the_slaves_outputs_are_read_whenever_they_change_in_campaign_runs() {
        for name in ["default", "noisy", "safe-drive"] {
            let profile = Profile::built_in(name).expect("a built-in profile");
            for index in 0..4 {
                let sc = generate(7, index, &profile).scenario;
                run(sc);
            }
        }
    }
}
