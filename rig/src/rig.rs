//! The rig: the AS-i bus with the lab lift's slaves, the lift plant, the PLC and the safety
//! logic on one simulated clock (SPEC §0), driven by a scenario.
//!
//! A discrete-event loop: the next moment is the earliest of the next bus event, the plant's
//! next edge, the next PLC scan, the next safety scan, the next scenario event and the end of
//! the run. At each moment the plant is brought up to it first (its edges are exact), its
//! signals are handed to the slaves' peripheral inputs, the bus runs, and what the slaves drive
//! (converter run and direction, the speed set-point, the display words) goes to the plant at
//! that same moment. So a slave samples the plant exactly when its transaction completes, and
//! the plant sees a new output exactly when the slave takes it. Nothing reads the wall clock;
//! the only random source is the bus's line noise, seeded from the scenario.

use crate::report::{
    Arrival, Availability, BusReport, CycleTimes, ErrorCounts, FinalState, LogLine, MonitorTrip,
    Passenger, Report, SafetyReport, Served, SlaveDropouts, Trip, Violation,
};
use crate::scenario::{load_name, needs_rescue, Action, Fault, Scenario, ScenarioEvent};
use crate::waves::{RigSample, WaveOutputs, Waves};
use asi_bus::lab::LabLift;
use asi_phy::fault::FaultRates;
use asi_phy::{Check, SimDuration, SimTime};
use asi_slaves::monitor::NotReleased;
use asi_trace::trace::{write_record, TraceFormat};
use controller::plc::{addr, FromSafety, Plc, ToSafety};
use controller::{ControllerConfig, EventKind as Ctl, HallDir, Source};
use lift_model::{Button, DisplayId, EventKind as Plant, Lift, LiftConfig, LoadLevel, SensorFault};
use safety::{LiftSafety, LiftSafetyConfig, LiftSafetyInputs, SafeLink, SAFETY_SCAN_PERIOD};

/// Why a rig cannot be built for a scenario.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// The lift plant rejects its configuration.
    #[error("lift: {0}")]
    Lift(#[from] lift_model::ConfigError),
    /// The bus cannot be built.
    #[error("bus: {0}")]
    Bus(#[from] asi_master::ConfigError),
    /// The controller rejects its configuration.
    #[error("{0}")]
    Controller(#[from] controller::ControllerConfigError),
    /// The safety project cannot be built.
    #[error("safety: {0}")]
    Safety(#[from] safety::lift::LiftSafetyError),
    /// The plant refuses the scenario's initial state.
    #[error("lift: {0}")]
    Plant(#[from] lift_model::PlantError),
}

/// How long an operator holds the reset or acknowledge button.
const OPERATOR_PULSE: SimDuration = SimDuration::from_millis(100);
/// When the operator presses the safety reset after power-on.
const POWER_ON_RESET_AT: SimTime = SimTime::from_millis(500);
/// The AS-i supply's nominal voltage.
const ASI_VOLTS: f64 = 30.0;

/// Reaction budgets of the invariants (see README "Violations").
const DOOR_BUDGET: SimDuration = SimDuration::from_millis(1000);
const OVERLOAD_BUDGET: SimDuration = SimDuration::from_millis(1000);
const OVERTRAVEL_BUDGET: SimDuration = SimDuration::from_millis(50);
const STOP_MARGIN: SimDuration = SimDuration::from_millis(200);

/// Receives every bus transaction of a run ([`Rig::on_transaction`]).
pub type TransactionObserver = Box<dyn FnMut(&asi_master::record::TransactionRecord)>;

/// Something the rig does at a fixed time besides the scenario's events.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Timer {
    OperatorReset(bool),
    ErrAck(bool),
    PowerBack,
}

/// A passenger's press of a call button.
#[derive(Clone, Copy, Debug)]
struct Press {
    at: SimTime,
    button: Button,
    /// When a stop answered it.
    served: Option<SimTime>,
    /// Its call was the target STOP dropped: not the request of a later call.
    dropped: bool,
}

/// What the rig last handed the plant from the slaves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
struct Applied {
    run: bool,
    up: bool,
    setpoint_ua: u16,
    displays: [Option<u16>; 5],
}

/// Watches the invariants.
#[derive(Clone, Debug, Default)]
struct Watch {
    door_open_since: Option<SimTime>,
    overloaded_since: Option<SimTime>,
    overtravel_k1_since: Option<SimTime>,
    /// STOP pressed at, and whether K1 has opened since.
    stop_since: Option<(SimTime, bool)>,
    /// The cabin moves by the hand crank (from the turn's start to the next rest).
    by_hand: bool,
    reported: [bool; 4],
}

/// Watches the master's LAS in normal operation: drop-outs and time out of LAS per address.
#[derive(Clone, Debug, Default)]
struct LasWatch {
    /// The LAS (A slots) last seen in normal operation, `None` outside it.
    las: Option<u32>,
    /// Since when each address is out of LAS.
    out_since: [Option<SimTime>; 32],
    /// Drop-outs per address.
    count: [u32; 32],
    /// Time out of LAS per address, closed intervals.
    out: [SimDuration; 32],
}

impl LasWatch {
    /// The LAS at `t` (`None` when the master is not in normal operation); returns the
    /// addresses that left and that came back.
    fn update(&mut self, t: SimTime, las: Option<u32>) -> (u32, u32) {
        let Some(now) = las else {
            // Offline (power fail, start-up): no drop-outs, close the open absences.
            self.close(t);
            self.las = None;
            return (0, 0);
        };
        let Some(before) = self.las.replace(now) else {
            return (0, 0);
        };
        let left = before & !now;
        let mut back = now & !before;
        for i in 0..32 {
            if left & (1 << i) != 0 {
                self.count[i] += 1;
                self.out_since[i] = Some(t);
            }
            if back & (1 << i) != 0 {
                match self.out_since[i].take() {
                    Some(s) => self.out[i] += t - s,
                    // Joined for the first time (start-up): not a return.
                    None => back &= !(1 << i),
                }
            }
        }
        (left, back)
    }

    fn close(&mut self, t: SimTime) {
        for i in 0..32 {
            if let Some(s) = self.out_since[i].take() {
                self.out[i] += t - s;
            }
        }
    }
}

/// The whole rig.
pub struct Rig {
    sc: Scenario,
    lab: LabLift,
    lift: Lift,
    plc: Plc,
    safety: LiftSafety,
    estop_delay: SimDuration,
    now: SimTime,
    end: SimTime,
    next_plc: SimTime,
    next_safety: SimTime,
    next_event: usize,
    timers: Vec<(SimTime, Timer)>,
    applied: Applied,
    plant_dirty: bool,
    from_safety: FromSafety,
    to_safety: ToSafety,
    k1: bool,
    operator_reset: bool,
    err_ack: bool,
    /// Every press of a call button, for the passengers' waits and the served calls' requests.
    presses: Vec<Press>,
    watch: Watch,
    report: Report,
    /// Where the bus's transaction trace goes, if anywhere, and in which form.
    trace: Option<(Box<dyn std::io::Write>, TraceFormat)>,
    trace_error: Option<String>,
    /// The VCD and line-voltage outputs, if wanted.
    waves: Option<Waves>,
    /// Who else wants every transaction.
    observer: Option<TransactionObserver>,
    /// The safety logic's last outputs, for the VCD.
    safety_out: Option<safety::lift::LiftSafetyDiag>,
    /// Drop-outs from LAS.
    las_watch: LasWatch,
    /// Since when the controller holds the cabin for a bus fault.
    bus_fault_since: Option<SimTime>,
}

impl Rig {
    /// A rig at power-on for `sc`.
    pub fn new(sc: Scenario) -> Result<Rig, RigError> {
        let lift = Lift::new(LiftConfig {
            floors: sc.floors,
            initial_position_mm: sc.start_mm,
            ..LiftConfig::default()
        })?;
        let mut lab = LabLift::with_extra(asi_master::MasterConfig::default(), sc.extra_slaves)?;
        // The slaves whose outputs drive the plant: the floor displays, the cabin display,
        // the converter I/O and the speed set-point.
        let drives_plant = [
            1,
            2,
            3,
            4,
            addr::CABIN_DISPLAY,
            addr::CONVERTER,
            addr::SPEED,
        ];
        lab.bus
            .watch_outputs(drives_plant.iter().fold(0, |m, a| m | 1 << a));
        lab.bus.enable_trace(0);
        if sc.pulse_error_rate > 0.0 {
            lab.bus
                .set_line_faults(sc.seed, FaultRates::uniform(sc.pulse_error_rate));
        }
        let plc = Plc::new(ControllerConfig {
            floors: sc.floors,
            algorithm: sc.algorithm,
            scan: sc.plc_scan,
            ..ControllerConfig::default()
        })?;
        let safety_cfg = LiftSafetyConfig::default();
        let estop_delay = safety_cfg.estop_delay;
        let safety = LiftSafety::new(safety_cfg)?;
        let mut timers = Vec::new();
        if sc.power_on_reset {
            timers.push((POWER_ON_RESET_AT, Timer::OperatorReset(true)));
        }
        let report = Report {
            scenario: sc.name.clone(),
            seed: sc.seed,
            simulated_s: 0.0,
            initialised_at_s: None,
            arrivals: Vec::new(),
            served: Vec::new(),
            passengers: Vec::new(),
            final_state: FinalState {
                floor: 1,
                position_mm: sc.start_mm,
                state: String::new(),
                moving: false,
                contactor_closed: false,
                k1_open_cause: None,
                fifo_cabin: Vec::new(),
                fifo_hall: Vec::new(),
            },
            bus: BusReport {
                transactions: 0,
                repeats: 0,
                errors: ErrorCounts::default(),
                cycle_us: CycleTimes {
                    min: 0.0,
                    mean: 0.0,
                    max: 0.0,
                },
                dropouts: Vec::new(),
            },
            safety: SafetyReport {
                trips: Vec::new(),
                monitor: Vec::new(),
            },
            violations: Vec::new(),
            availability: Availability::default(),
            log: Vec::new(),
        };
        let mut rig = Rig {
            end: SimTime::ZERO + sc.duration,
            lab,
            lift,
            plc,
            safety,
            estop_delay,
            now: SimTime::ZERO,
            next_plc: SimTime::ZERO,
            next_safety: SimTime::ZERO,
            next_event: 0,
            timers,
            applied: Applied::default(),
            plant_dirty: true,
            from_safety: FromSafety::default(),
            to_safety: ToSafety::default(),
            k1: false,
            operator_reset: false,
            err_ack: false,
            presses: Vec::new(),
            watch: Watch::default(),
            report,
            trace: None,
            trace_error: None,
            waves: None,
            observer: None,
            safety_out: None,
            las_watch: LasWatch::default(),
            bus_fault_since: None,
            sc,
        };
        rig.lift.set_load(SimTime::ZERO, rig.sc.load)?;
        rig.lift.set_door(SimTime::ZERO, rig.sc.door_closed)?;
        rig.log(
            "rig",
            format!(
                "power on: cabin at {:.1} mm, load {}, door {}, {} control, line error rate {}",
                rig.sc.start_mm,
                load_name(rig.sc.load),
                if rig.sc.door_closed { "closed" } else { "open" },
                match rig.sc.algorithm {
                    controller::Algorithm::Fifo => "FIFO",
                    controller::Algorithm::Collective => "collective",
                },
                rig.sc.pulse_error_rate
            ),
        );
        Ok(rig)
    }

    /// Streams every bus transaction, one line each in `format`, to `out` (drained from the
    /// master's trace ring at every PLC scan and at the end).
    pub fn trace_to(&mut self, out: Box<dyn std::io::Write>, format: TraceFormat) {
        self.enable_trace_ring();
        self.trace = Some((out, format));
    }

    /// Writes the VCD and the line-voltage CSV of the run (see [`crate::waves`]).
    pub fn waves_to(&mut self, out: WaveOutputs) {
        self.enable_trace_ring();
        self.lab.bus.record_line(true);
        self.waves = Some(Waves::new(out, self.lab.bus.timing()));
    }

    /// Hands every bus transaction to `f` (at every PLC scan and at the end, in order).
    pub fn on_transaction(&mut self, f: TransactionObserver) {
        self.enable_trace_ring();
        self.observer = Some(f);
    }

    fn enable_trace_ring(&mut self) {
        // A PLC scan spans about 65 transactions of the lab bus; the ring holds far more.
        self.lab.bus.enable_trace(1 << 16);
    }

    /// The first error writing the trace or the waveforms, if any.
    pub fn trace_error(&self) -> Option<&str> {
        self.trace_error
            .as_deref()
            .or_else(|| self.waves.as_ref().and_then(|w| w.error()))
    }

    /// Hands the transactions and line pulses since the last call to the trace and the
    /// waveform outputs.
    fn flush_trace(&mut self) {
        if self.trace.is_none() && self.waves.is_none() && self.observer.is_none() {
            return;
        }
        let records = self.lab.bus.drain_trace();
        if let Some(f) = self.observer.as_mut() {
            records.iter().for_each(f);
        }
        if let Some((out, format)) = self.trace.as_mut() {
            for r in &records {
                if let Err(e) = write_record(out, r, *format) {
                    self.trace_error.get_or_insert_with(|| e.to_string());
                    self.trace = None;
                    break;
                }
            }
        }
        if let Some(w) = self.waves.as_mut() {
            w.pulses(&self.lab.bus.take_line_pulses());
            for r in &records {
                w.transaction(r);
            }
            w.flush(self.now);
        }
    }

    /// The rig's state for the VCD.
    fn sample(&self) -> RigSample {
        let l = &self.lift;
        let p = self.plc.program();
        let diag = self.safety_out.as_ref();
        RigSample {
            position_mm: l.position_mm(),
            velocity_mm_s: l.velocity_mm_s(),
            vane_left: l.vane_left(),
            vane_right: l.vane_right(),
            overtravel_bottom_free: l.overtravel_bottom_free(),
            overtravel_top_free: l.overtravel_top_free(),
            k1: l.k1_closed(),
            door_closed: l.door_closed(),
            converter_run: self.applied.run,
            converter_up: self.applied.up,
            setpoint_ua: self.applied.setpoint_ua,
            controller_state: p.state_name(),
            floor: p.current_floor(),
            target_floor: p.target(),
            fifo_cabin: p.fifo_cabin().len() as u8,
            fifo_hall: p.fifo_hall().len() as u8,
            estop_out: self.from_safety.estop_out,
            group_state: diag.map_or("STOP", |d| d.group.state.name()),
            fb_err: diag.is_some_and(|d| d.group.errors.fb_err),
            com_err: diag.is_some_and(|d| d.group.errors.com_err),
            out_err: diag.is_some_and(|d| d.group.errors.out_err),
            supply_v: self.lab.bus.supply_voltage(),
        }
    }

    /// Runs until `until` (at most the scenario's duration) and returns the report.
    pub fn run(self, until: Option<SimDuration>) -> Report {
        self.run_observed(until, &mut |_, _| {})
    }

    /// As [`Rig::run`], telling `progress` the simulated time and the end after every PLC
    /// scan (for a progress indicator; the simulation does not depend on it).
    pub fn run_observed(
        mut self,
        until: Option<SimDuration>,
        progress: &mut dyn FnMut(SimTime, SimTime),
    ) -> Report {
        if let Some(u) = until {
            self.end = self.end.min(SimTime::ZERO + u);
        }
        let mut scans = self.next_plc;
        while let Some(t) = self.advance(self.end) {
            if self.next_plc != scans {
                scans = self.next_plc;
                progress(t, self.end);
            }
            if t == self.end {
                break;
            }
        }
        self.finish()
    }

    fn next_moment(&self) -> SimTime {
        let mut t = self.end;
        if let Some(e) = self.lift.next_event() {
            t = t.min(e);
        }
        t = t.min(self.next_plc).min(self.next_safety);
        if let Some(e) = self.sc.events.get(self.next_event) {
            t = t.min(e.at);
        }
        if let Some((at, _)) = self.timers.iter().min_by_key(|(at, _)| *at) {
            t = t.min(*at);
        }
        t.max(self.now)
    }

    /// Handles the rig's next moment, or a slave's new output before it, if it comes no later
    /// than `limit`; returns its time. The bus runs on its own up to the rig's next moment and
    /// stops where a slave takes a new output for the plant, which gets it at that moment.
    fn advance(&mut self, limit: SimTime) -> Option<SimTime> {
        let t = self.next_moment();
        if t > limit {
            return None;
        }
        if let Some(at) = self.lab.bus.advance_before(t) {
            self.output_taken(at);
            return Some(at);
        }
        self.step(t);
        Some(t)
    }

    /// A slave took a new output at `t` (before the rig's next moment): the plant gets it.
    fn output_taken(&mut self, t: SimTime) {
        self.now = t;
        self.advance_plant(t);
        self.slaves_to_plant(t);
        if self.plant_dirty {
            self.plant_to_slaves();
        }
        self.check_invariants(t);
        if self.waves.is_some() {
            let sample = self.sample();
            if let Some(w) = self.waves.as_mut() {
                w.sample(t, &sample);
            }
        }
    }

    fn step(&mut self, t: SimTime) {
        self.now = t;
        self.advance_plant(t);
        while let Some(ev) = self
            .sc
            .events
            .get(self.next_event)
            .filter(|e| e.at <= t)
            .cloned()
        {
            self.next_event += 1;
            self.apply(t, &ev);
        }
        self.fire_timers(t);
        if self.plant_dirty {
            self.plant_to_slaves();
        }
        self.lab.bus.advance_to(t);
        self.slaves_to_plant(t);
        if t >= self.next_safety {
            self.safety_scan(t);
            self.next_safety = t + SAFETY_SCAN_PERIOD;
        }
        if t >= self.next_plc {
            self.plc_scan(t);
            self.next_plc = t + self.sc.plc_scan;
            self.flush_trace();
        }
        self.check_invariants(t);
        if self.waves.is_some() {
            let sample = self.sample();
            if let Some(w) = self.waves.as_mut() {
                w.sample(t, &sample);
            }
        }
    }

    fn advance_plant(&mut self, t: SimTime) {
        let events: Result<Vec<_>, _> = self.lift.advance_to(t).map(|ev| ev.collect());
        let events = match events {
            Ok(ev) => ev,
            Err(e) => {
                self.log("plant", format!("error: {e}"));
                return;
            }
        };
        if events.is_empty() {
            return;
        }
        self.plant_dirty = true;
        for e in events {
            match e.kind {
                Plant::Stopped { position_mm } => self.stopped(e.at, position_mm),
                Plant::Crash { end, impact_mm_s } => {
                    let text =
                        format!("crash into the mechanical end ({end:?}) at {impact_mm_s:.1} mm/s");
                    self.log_at(e.at, "plant", text.clone());
                    self.violation(e.at, "mechanical-end", text);
                }
                Plant::Overtravel { end, tripped } => {
                    let text = if tripped {
                        format!(
                            "overtravel sensor ({end:?}) tripped at {:.1} mm",
                            self.lift.position_mm()
                        )
                    } else {
                        format!("overtravel sensor ({end:?}) free again")
                    };
                    self.log_at(e.at, "plant", text);
                }
                Plant::ConverterFault { fault } => {
                    self.log_at(e.at, "plant", format!("converter fault: {fault:?}"));
                }
                _ => {}
            }
        }
    }

    /// The cabin came to rest: an arrival if it stands level at a floor with the drive
    /// commanded to stand still.
    fn stopped(&mut self, at: SimTime, position_mm: f64) {
        if self.applied.run && self.applied.setpoint_ua > 4000 {
            return;
        }
        let pitch = 400.0;
        let floor = (position_mm / pitch).round() + 1.0;
        if !(1.0..=self.sc.floors as f64).contains(&floor) {
            return;
        }
        let level = (floor - 1.0) * pitch;
        if (position_mm - level).abs() <= 10.0 {
            self.report.arrivals.push(Arrival {
                floor: floor as u8,
                at_s: at.as_secs_f64(),
                position_mm: round3(position_mm),
            });
            self.log_at(
                at,
                "plant",
                format!(
                    "cabin at rest level at floor {floor} ({:+.1} mm)",
                    position_mm - level
                ),
            );
        }
    }

    fn apply(&mut self, t: SimTime, ev: &ScenarioEvent) {
        let what = describe(&ev.action);
        self.log("scenario", what);
        let result = match &ev.action {
            Action::Press { button, hold } => {
                if button_floor(button).is_some() {
                    self.presses.push(Press {
                        at: t,
                        button: *button,
                        served: None,
                        dropped: false,
                    });
                }
                self.lift.press(t, *button, *hold)
            }
            Action::Load(l) => self.lift.set_load(t, *l),
            Action::Door { closed } => self.lift.set_door(t, *closed),
            Action::Crank { mm } => self.lift.crank(t, *mm),
            Action::Reset => {
                self.operator_reset = true;
                self.timers
                    .push((t + OPERATOR_PULSE, Timer::OperatorReset(false)));
                Ok(())
            }
            Action::Rescue => self.rescue(t),
            Action::Ack => {
                self.err_ack = true;
                self.timers.push((t + OPERATOR_PULSE, Timer::ErrAck(false)));
                Ok(())
            }
            Action::Fault(f) => {
                self.fault(t, *f);
                Ok(())
            }
        };
        if let Err(e) = result {
            self.log("scenario", format!("refused by the plant: {e}"));
        }
        self.plant_dirty = true;
    }

    /// The operator's overtravel rescue: crank a cabin that stands where initialisation cannot
    /// find floor 1 by itself (on or beyond an overtravel sensor, below floor 1's vane) to the
    /// nearer end floor's level; only with K1 open, nothing to do otherwise.
    fn rescue(&mut self, t: SimTime) -> Result<(), lift_model::PlantError> {
        let x = self.lift.position_mm();
        if !needs_rescue(self.sc.floors, x) {
            self.log("scenario", "the cabin needs no rescue".into());
            return Ok(());
        }
        let cfg = self.lift.config();
        let end_floor = if x < 0.0 { 1 } else { self.sc.floors };
        let Some(to) = cfg.floor_level_mm(end_floor) else {
            return Ok(());
        };
        if self.lift.k1_closed() {
            self.log("scenario", "K1 is closed: no rescue by hand".into());
            return Ok(());
        }
        self.log("scenario", format!("hand crank {:+.1} mm", to - x));
        self.lift.crank(t, to - x)
    }

    fn fault(&mut self, t: SimTime, f: Fault) {
        match f {
            Fault::SlaveOffline { slave } | Fault::SlaveOnline { slave } => {
                let Some(id) = self.lab.slave_id(slave) else {
                    self.log(
                        "scenario",
                        format!("no slave at address {slave} on the lab bus"),
                    );
                    return;
                };
                if matches!(f, Fault::SlaveOffline { .. }) {
                    self.lab.bus.detach(id);
                } else {
                    self.lab.bus.attach(id);
                    self.plant_dirty = true;
                }
            }
            Fault::PowerFail { duration } => {
                self.lab.bus.set_supply_voltage(0.0);
                self.timers.push((t + duration, Timer::PowerBack));
            }
            Fault::SafeLinkDrop { duration } => {
                self.safety.drop_link(SafeLink::CabinStop, t, duration)
            }
            Fault::Vane { sensor, fault } => {
                if let Err(e) = self.lift.set_vane_fault(t, sensor, fault) {
                    self.log("plant", format!("error: {e}"));
                }
                self.plant_dirty = true;
            }
        }
    }

    fn fire_timers(&mut self, t: SimTime) {
        let mut due: Vec<Timer> = Vec::new();
        self.timers.retain(|(at, timer)| {
            if *at <= t {
                due.push(*timer);
                false
            } else {
                true
            }
        });
        for timer in due {
            match timer {
                Timer::OperatorReset(on) => {
                    self.operator_reset = on;
                    if on {
                        self.log(
                            "rig",
                            "operator presses the safety reset after power-on".into(),
                        );
                        self.timers
                            .push((t + OPERATOR_PULSE, Timer::OperatorReset(false)));
                    }
                }
                Timer::ErrAck(on) => self.err_ack = on,
                Timer::PowerBack => {
                    self.lab.bus.set_supply_voltage(ASI_VOLTS);
                    self.log("rig", "AS-i power back".into());
                    self.plant_dirty = true;
                }
            }
        }
    }

    /// The plant's signals on the slaves' peripheral inputs.
    fn plant_to_slaves(&mut self) {
        self.plant_dirty = false;
        let l = &self.lift;
        let floors = self.sc.floors;
        for f in 1..=floors.min(addr::FLOOR_STATIONS) {
            let up = l.is_pressed(Button::HallUp(f));
            let down = l.is_pressed(Button::HallDown(f));
            if let Some(st) = self.lab.floor_mut(f) {
                st.set_buttons(up, down);
            }
        }
        let cabin: Vec<bool> = (1..=floors)
            .map(|f| l.is_pressed(Button::Cabin(f)))
            .collect();
        let (bell, stop, door, left, right) = (
            l.is_pressed(Button::Bell),
            l.stop_pressed(),
            l.door_closed(),
            l.vane_left(),
            l.vane_right(),
        );
        let (ready, fault, load) = (l.converter_ready(), l.converter_fault(), l.load().code());
        let (bottom, top) = (l.overtravel_bottom_free(), l.overtravel_top_free());
        if let Some(p) = self.lab.cabin_panel_mut() {
            for (i, on) in cabin.iter().enumerate() {
                p.set_floor_button(i as u8 + 1, *on);
            }
            p.set_bell(bell);
            p.set_stop(stop);
            p.set_door_closed(door);
            p.set_vane_left(left);
            p.set_vane_right(right);
        }
        if let Some(c) = self.lab.converter_mut() {
            c.set_ready(ready);
            c.set_fault(fault);
        }
        if let Some(s) = self.lab.load_sensor_mut() {
            s.set_level(load);
        }
        if let Some(s) = self.lab.safety_sensor_mut(11) {
            s.set_free(bottom);
        }
        if let Some(s) = self.lab.safety_sensor_mut(12) {
            s.set_free(top);
        }
    }

    /// What the slaves drive, to the plant, at the moment they drive it.
    fn slaves_to_plant(&mut self, t: SimTime) {
        let (run, up) = self
            .lab
            .converter()
            .map_or((false, false), |c| (c.run(), c.direction_up()));
        let ua = self.lab.analog_output().map_or(0, |a| a.current_ua(1));
        let mut displays = [None; 5];
        for f in 1..=addr::FLOOR_STATIONS {
            displays[f as usize - 1] = self
                .lab
                .floor(f)
                .and_then(|s| s.display())
                .map(|w| w.bits());
        }
        displays[4] = self
            .lab
            .cabin_display()
            .and_then(|d| d.display())
            .map(|w| w.bits());
        let mut result = Ok(());
        if (run, up) != (self.applied.run, self.applied.up) {
            result = result.and(self.lift.set_run_direction(t, run, up));
        }
        if ua != self.applied.setpoint_ua {
            result = result.and(self.lift.set_setpoint(t, ua));
        }
        for (i, d) in displays.iter().enumerate() {
            if *d != self.applied.displays[i] {
                if let Some(raw) = d {
                    let id = if i < 4 {
                        DisplayId::Floor(i as u8 + 1)
                    } else {
                        DisplayId::Cabin
                    };
                    if i < 4 && i as u8 >= self.sc.floors {
                        continue;
                    }
                    result = result.and(self.lift.set_display(t, id, *raw));
                }
            }
        }
        if let Err(e) = result {
            self.log("plant", format!("error: {e}"));
        }
        let new = Applied {
            run,
            up,
            setpoint_ua: ua,
            displays,
        };
        // What the plant shows the slaves can change with what it is given.
        self.plant_dirty |= new != self.applied;
        self.applied = new;
    }

    /// The master's LAS and the safety monitor's drops since the last look, to the report
    /// and the log (every safety scan, 1 ms).
    fn watch_bus(&mut self, t: SimTime) {
        let m = self.lab.bus.master();
        let las = (m.phase() == asi_master::Phase::NormalOperation).then(|| m.las().bits() as u32);
        let (left, back) = self.las_watch.update(t, las);
        for i in 1..32u8 {
            if left & (1 << i) != 0 {
                self.log_at(t, "bus", format!("slave {i} dropped out of LAS"));
            }
            if back & (1 << i) != 0 {
                self.log_at(t, "bus", format!("slave {i} back in LAS"));
            }
        }
        let id = self.lab.monitor;
        let drops = self
            .lab
            .bus
            .monitor_mut(id)
            .map(|m| m.take_drops())
            .unwrap_or_default();
        for d in drops {
            let (cause, text) = match d.why {
                NotReleased::Tripped => ("0000", "the sensor sends 0000".to_string()),
                NotReleased::WrongCode { expected, got } => (
                    "wrong-code",
                    format!("wrong code {got:04b} (expected {expected:04b})"),
                ),
                NotReleased::Frozen { code } => ("frozen-code", format!("frozen code {code:04b}")),
                _ => (
                    "silence",
                    "no valid code within the tolerance time".to_string(),
                ),
            };
            let address = d.address.get();
            self.log_at(
                d.at,
                "monitor",
                format!("safety sensor {address} not released: {text}"),
            );
            self.report.safety.monitor.push(MonitorTrip {
                at_s: d.at.as_secs_f64(),
                address,
                cause: cause.into(),
            });
        }
    }

    fn safety_scan(&mut self, t: SimTime) {
        self.watch_bus(t);
        let [ch1, ch2] = self.lift.stop_channels();
        let inputs = LiftSafetyInputs {
            stop_ch1: ch1,
            stop_ch2: ch2,
            overtravel_bottom_released: self.lab.released(11),
            overtravel_top_released: self.lab.released(12),
            overloaded: self.to_safety.overloaded,
            k1_aux: self.lift.k1_aux_closed(),
            operator_reset: self.operator_reset,
            err_ack: self.err_ack,
            controller_restart: self.to_safety.restart,
        };
        let out = self.safety.scan(t, &inputs);
        for e in &out.events {
            if e.is_trip() {
                self.report.safety.trips.push(Trip {
                    at_s: e.at_s(),
                    cause: e.cause.clone(),
                });
            }
            self.report.log.push(LogLine {
                at_s: e.at_s(),
                who: "safety",
                text: e.cause.clone(),
            });
        }
        self.from_safety = FromSafety {
            estop_out: out.estop_out,
        };
        self.safety_out = Some(out.diag);
        if out.k1 != self.k1 {
            self.k1 = out.k1;
            if let Err(e) = self.lift.set_contactor(t, out.k1) {
                self.log("plant", format!("error: {e}"));
            }
            self.plant_dirty = true;
        }
    }

    fn plc_scan(&mut self, t: SimTime) {
        self.to_safety = self.plc.scan(t, self.lab.bus.image_mut(), self.from_safety);
        let held = self.plc.program().state_name() == "bus fault";
        match (self.bus_fault_since, held) {
            (None, true) => {
                self.bus_fault_since = Some(t);
                self.report.availability.bus_fault_holds += 1;
            }
            (Some(s), false) => {
                self.report.availability.bus_fault_s += (t - s).as_secs_f64();
                self.bus_fault_since = None;
            }
            _ => {}
        }
        let events: Vec<_> = self.plc.program_mut().drain_events().collect();
        for e in events {
            match e.kind {
                Ctl::Initialised if self.report.initialised_at_s.is_none() => {
                    self.report.initialised_at_s = Some(e.at.as_secs_f64());
                }
                Ctl::StopDemanded {
                    dropped: Some(f), ..
                } => {
                    // The dropped target's presses are not the request of a later call.
                    for p in &mut self.presses {
                        if button_floor(&p.button) == Some(f) && p.at <= e.at && p.served.is_none()
                        {
                            p.dropped = true;
                        }
                    }
                }
                Ctl::Served(s) => {
                    // The request: the earliest pending press of the served button up to the
                    // time the call was stored (else the storing time). Every pending press of
                    // that button until now is answered by this stop.
                    let calls = |p: &Press| {
                        p.served.is_none()
                            && match (s.hall, p.button) {
                                (None, Button::Cabin(f)) => f == s.floor,
                                (Some(HallDir::Up), Button::HallUp(f)) => f == s.floor,
                                (Some(HallDir::Down), Button::HallDown(f)) => f == s.floor,
                                _ => false,
                            }
                    };
                    let requested = self
                        .presses
                        .iter()
                        .filter(|p| calls(p) && !p.dropped && p.at <= s.stored_at)
                        .map(|p| p.at)
                        .min()
                        .unwrap_or(s.stored_at);
                    for p in &mut self.presses {
                        if calls(p) && p.at <= e.at {
                            p.served = Some(e.at);
                        }
                    }
                    self.report.served.push(Served {
                        floor: s.floor,
                        source: match s.source {
                            Source::Cabin => "cabin".into(),
                            Source::Hall => "hall".into(),
                        },
                        direction: s.hall.map(|d| match d {
                            HallDir::Up => "up".into(),
                            HallDir::Down => "down".into(),
                        }),
                        requested_at_s: requested.as_secs_f64(),
                        served_at_s: e.at.as_secs_f64(),
                    });
                }
                _ => {}
            }
            self.log_at(e.at, "controller", e.kind.to_string());
        }
    }

    fn check_invariants(&mut self, t: SimTime) {
        // Motion by the hand crank (K1 open, the operator at the motor) is the operator's, not
        // the drive's, until the cabin is at rest again (a turn that K1 ends still brakes): the
        // door and overload invariants judge the drive.
        let velocity = self.lift.velocity_mm_s();
        self.watch.by_hand = velocity != 0.0 && (self.watch.by_hand || self.lift.hand_cranking());
        let moving = velocity != 0.0 && !self.watch.by_hand;
        let door_open = !self.lift.door_closed();
        let overloaded = self.lift.load() == LoadLevel::Overloaded;
        let tripped = !self.lift.overtravel_bottom_free() || !self.lift.overtravel_top_free();
        let k1 = self.lift.k1_closed();
        let stop = self.lift.stop_channels() != [true, true];

        self.watch.door_open_since = if door_open {
            self.watch.door_open_since.or(Some(t))
        } else {
            None
        };
        self.watch.overloaded_since = if overloaded {
            self.watch.overloaded_since.or(Some(t))
        } else {
            None
        };
        self.watch.overtravel_k1_since = if tripped && k1 {
            self.watch.overtravel_k1_since.or(Some(t))
        } else {
            None
        };
        match (&mut self.watch.stop_since, stop) {
            (None, true) => self.watch.stop_since = Some((t, !k1)),
            (Some((_, opened)), _) => *opened |= !k1,
            _ => {}
        }

        let over =
            |since: Option<SimTime>, budget: SimDuration| since.is_some_and(|s| t - s > budget);
        if moving && over(self.watch.door_open_since, DOOR_BUDGET) {
            self.violation_once(
                0,
                t,
                "door-open-moving",
                format!("the cabin moves with the door open for more than {DOOR_BUDGET}"),
            );
        }
        if moving && over(self.watch.overloaded_since, OVERLOAD_BUDGET) {
            self.violation_once(
                1,
                t,
                "overloaded-moving",
                format!("the cabin moves overloaded for more than {OVERLOAD_BUDGET}"),
            );
        }
        if over(self.watch.overtravel_k1_since, OVERTRAVEL_BUDGET) {
            self.violation_once(
                2,
                t,
                "k1-in-overtravel",
                format!(
                    "K1 closed with an overtravel sensor tripped for more than {OVERTRAVEL_BUDGET}"
                ),
            );
        }
        if let Some((since, opened)) = self.watch.stop_since {
            if t - since > self.estop_delay + STOP_MARGIN {
                if !opened {
                    self.violation(
                        t,
                        "stop-ignored",
                        format!(
                            "K1 still closed {} after STOP",
                            self.estop_delay + STOP_MARGIN
                        ),
                    );
                }
                self.watch.stop_since = None;
            }
        }
        if !door_open {
            self.watch.reported[0] = false;
        }
        if !overloaded {
            self.watch.reported[1] = false;
        }
        if !(tripped && k1) {
            self.watch.reported[2] = false;
        }
    }

    fn violation_once(&mut self, slot: usize, t: SimTime, kind: &str, detail: String) {
        if !self.watch.reported[slot] {
            self.watch.reported[slot] = true;
            self.violation(t, kind, detail);
        }
    }

    fn violation(&mut self, t: SimTime, kind: &str, detail: String) {
        self.log_at(t, "rig", format!("VIOLATION {kind}: {detail}"));
        self.report.violations.push(Violation {
            at_s: t.as_secs_f64(),
            kind: kind.into(),
            detail,
        });
    }

    fn log(&mut self, who: &'static str, text: String) {
        self.log_at(self.now, who, text);
    }

    fn log_at(&mut self, at: SimTime, who: &'static str, text: String) {
        self.report.log.push(LogLine {
            at_s: at.as_secs_f64(),
            who,
            text,
        });
    }

    fn finish(mut self) -> Report {
        self.flush_trace();
        if let Some((out, _)) = self.trace.as_mut() {
            if let Err(e) = out.flush() {
                self.trace_error.get_or_insert_with(|| e.to_string());
            }
        }
        if let Some(w) = self.waves.as_mut() {
            w.finish(self.now);
        }
        if let Some(e) = self.trace_error().map(str::to_owned) {
            let text = format!("the bus trace could not be written: {e}");
            self.log("rig", text);
        }
        let now = self.now;
        self.watch_bus(now);
        self.las_watch.close(now);
        if let Some(s) = self.bus_fault_since.take() {
            self.report.availability.bus_fault_s += (now - s).as_secs_f64();
        }
        self.report.availability.bus_fault_s = round3(self.report.availability.bus_fault_s);
        let dropouts: Vec<SlaveDropouts> = (1..32u8)
            .filter(|&i| self.las_watch.count[i as usize] > 0)
            .map(|i| SlaveDropouts {
                address: i,
                count: self.las_watch.count[i as usize],
                out_of_las_s: round3(self.las_watch.out[i as usize].as_secs_f64()),
            })
            .collect();
        let p = self.plc.program();
        let stats = self.lab.bus.stats();
        let (min, mean, max) = stats.cycle_time_us();
        self.report.simulated_s = self.now.as_secs_f64();
        self.report.final_state = FinalState {
            floor: p.current_floor(),
            position_mm: round3(self.lift.position_mm()),
            state: p.state_name().into(),
            moving: self.lift.velocity_mm_s() != 0.0,
            contactor_closed: self.lift.k1_closed(),
            k1_open_cause: self
                .safety_out
                .as_ref()
                .and_then(|d| d.k1_open_cause)
                .filter(|_| !self.lift.k1_closed())
                .map(|c| self.k1_cause_text(c)),
            fifo_cabin: p.fifo_cabin(),
            fifo_hall: p.fifo_hall(),
        };
        self.report.bus = BusReport {
            transactions: stats.transactions,
            repeats: stats.repeats,
            errors: ErrorCounts {
                start_bit: stats.errors(Check::StartBit),
                alternation: stats.errors(Check::Alternation),
                pause: stats.errors(Check::Pause),
                information: stats.errors(Check::Information),
                parity: stats.errors(Check::Parity),
                end_bit: stats.errors(Check::EndBit),
                length: stats.errors(Check::Length),
                no_response: stats.no_response,
            },
            cycle_us: CycleTimes {
                min: round3(min),
                mean: round3(mean),
                max: round3(max),
            },
            dropouts,
        };
        self.report.passengers = self
            .presses
            .iter()
            .map(|p| Passenger {
                button: match p.button {
                    Button::Cabin(f) => format!("cabin:{f}"),
                    Button::HallUp(f) => format!("hall-up:{f}"),
                    Button::HallDown(f) => format!("hall-down:{f}"),
                    Button::Bell => "bell".into(),
                    Button::Stop => "stop".into(),
                },
                pressed_at_s: p.at.as_secs_f64(),
                served_at_s: p.served.map(|s| s.as_secs_f64()),
            })
            .collect();
        // Lines from different sources come in scan order; keep them in time order.
        self.report.log.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
        self.report
    }

    /// Why K1 is open, in words; an overtravel sensor the monitor does not release is told
    /// apart: tripped (0000) or not heard.
    fn k1_cause_text(&self, c: safety::lift::K1Cause) -> String {
        let safety::lift::K1Cause::Overtravel { bottom, top } = c else {
            return c.to_string();
        };
        let monitor = self.lab.monitor();
        let why = |address: u8| {
            let state =
                asi_phy::Address::new(address).and_then(|a| monitor.and_then(|m| m.state(a)));
            match state {
                Some(Err(NotReleased::Tripped)) => "tripped",
                Some(Err(NotReleased::Missing)) => "not heard for the monitor's tolerance time",
                Some(Err(NotReleased::WrongCode { .. } | NotReleased::Frozen { .. })) => {
                    "sending a wrong code sequence"
                }
                _ => "not yet released again by the monitor",
            }
        };
        let mut parts = Vec::new();
        if bottom {
            parts.push(format!("overtravel bottom sensor (11) {}", why(11)));
        }
        if top {
            parts.push(format!("overtravel top sensor (12) {}", why(12)));
        }
        parts.join("; ")
    }

    // ----- probes: stepping and state for timing studies (`asi-lift timing`) ----------------

    /// Runs the next moment of the rig if it comes no later than `until` and before the
    /// scenario's end; returns its time. A caller can look at the rig between moments and
    /// [`Rig::schedule`] actions in reaction to what it sees.
    pub fn step_until(&mut self, until: SimTime) -> Option<SimTime> {
        if self.next_moment() >= self.end {
            return None;
        }
        self.advance(until)
    }

    /// Schedules `action` at `at` as if the scenario had it (a time before the next moment
    /// takes effect at the next moment).
    pub fn schedule(&mut self, at: SimTime, action: Action) {
        let later = &self.sc.events[self.next_event..];
        let pos = self.next_event + later.partition_point(|e| e.at <= at);
        self.sc.events.insert(
            pos,
            ScenarioEvent {
                at,
                action,
                line: 0,
            },
        );
    }

    /// The simulated time reached.
    pub fn now(&self) -> SimTime {
        self.now
    }

    /// The lab bus and its devices.
    pub fn lab(&self) -> &LabLift {
        &self.lab
    }

    /// The lab bus, mutable (to trace it).
    pub fn lab_mut(&mut self) -> &mut LabLift {
        &mut self.lab
    }

    /// The PLC.
    pub fn plc(&self) -> &Plc {
        &self.plc
    }

    /// The lift plant.
    pub fn lift(&self) -> &Lift {
        &self.lift
    }

    /// The safety logic's EStopOut as the controller last got it (`true` = no STOP demand).
    pub fn estop_out(&self) -> bool {
        self.from_safety.estop_out
    }
}

/// The floor a call button belongs to.
fn button_floor(b: &Button) -> Option<u8> {
    match b {
        Button::Cabin(f) | Button::HallUp(f) | Button::HallDown(f) => Some(*f),
        Button::Bell | Button::Stop => None,
    }
}

/// `x` rounded to three decimals (reports and waveforms).
pub(crate) fn round3(x: f64) -> f64 {
    (x * 1000.0).round() / 1000.0
}

fn describe(a: &Action) -> String {
    match a {
        Action::Press { button, hold } => format!("{button} pressed for {hold}"),
        Action::Load(l) => format!("load becomes {}", load_name(*l)),
        Action::Door { closed } => format!("door {}", if *closed { "closed" } else { "opened" }),
        Action::Crank { mm } => format!("hand crank {mm:+.1} mm"),
        Action::Reset => "operator presses the safety reset".into(),
        Action::Rescue => "operator's overtravel rescue".into(),
        Action::Ack => "operator acknowledges the safety group error".into(),
        Action::Fault(f) => match f {
            Fault::SlaveOffline { slave } => format!("fault: slave {slave} taken off the bus"),
            Fault::SlaveOnline { slave } => format!("fault cleared: slave {slave} back on the bus"),
            Fault::PowerFail { duration } => format!("fault: AS-i power fails for {duration}"),
            Fault::SafeLinkDrop { duration } => {
                format!("fault: the cabin STOP safe link is silent for {duration}")
            }
            Fault::Vane { sensor, fault } => match fault {
                SensorFault::None => format!("fault cleared: the {sensor} vane sensor works again"),
                SensorFault::StuckOn => format!("fault: the {sensor} vane sensor is stuck on"),
                SensorFault::StuckOff => format!("fault: the {sensor} vane sensor is stuck off"),
            },
        },
    }
}
