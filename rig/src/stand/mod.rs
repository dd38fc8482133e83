//! The teaching stand of the SafeMOTION thesis as a second built-in plant (docs/drive-safety.md
//! §5): one servo axis, its standard motion control, the light curtain that requests the function
//! selected on the HMI, the safe drive ([`SafeDrive`] with [`DriveSafetyConfig::demo`]) and the HMI
//! page a student watches, on simulated time.
//!
//! Sans-IO: [`Stand::step`] takes the scan's time and advances everything by one scan period;
//! [`run`] plays a [`StandScenario`] and returns what happened as a [`StandReport`].
//!
//! **Decisions** where the SafeMOTION thesis is silent (docs/drive-safety.md §5):
//!
//! - The safe drive and the programs are scanned every [`SCAN`] (10 ms); an event acts in the
//!   first scan at or after its time; the light curtain, the safe drive and the HMI see it in
//!   that same scan.
//! - The motion control ramps the speed to the speed field at [`MOTION_RAMP`] (10 rev/s², the
//!   "Pohon - Decelerace" field of figure A.3) both ways. It does not know the safety limits (§4 of
//!   the SafeMOTION thesis), unless the scenario's `follows_limit` makes it brake to the safe
//!   drive's `speed_command_limit`.
//! - Torque off: the axis coasts down at [`FRICTION_DECEL`] (2 rev/s²); with a holding brake
//!   (`brake = true`, applied whenever the torque is off) at [`BRAKE_DECEL`] (50 rev/s²).
//! - Torque off puts the motion control in error (§4.1 of the SafeMOTION thesis, "Deenergetizace
//!   pohonu"): the drive shows "Vypnuto" and starts again only after the Reset and a new "Zap".
//! - The light curtain (SF_ESPE, §4.2.2, figure 5.4 of the SafeMOTION thesis) has a restart
//!   interlock: its output falls when the field is broken and rises only on the operator's Reset
//!   with the field clear. The scenario begins after the guides' step 2 (the curtain acknowledged).
//! - The Reset button is one scan TRUE: S_Control_Reset of the safe drive, the curtain's reset
//!   and the motion control's error reset at once.

pub mod builtin;
pub mod scenario;
#[cfg(test)]
mod tests;

pub use scenario::{StandAction, StandEvent, StandScenario};

use asi_phy::{SimDuration, SimTime};
use safety::drive::{
    AxisFeedback, ControlBits, DriveEventKind, DriveSafetyConfig, DriveSafetyInputs, Function,
    SafeDrive, SlsLevel,
};
use serde::Serialize;
use std::fmt;

/// The scan period of the safe drive, the safety program and the HMI.
pub const SCAN: SimDuration = SimDuration::from_millis(10);
/// The motion control's acceleration and deceleration, rev/s² (figure A.3: "Pohon -
/// Decelerace" 10.0 ot/s²).
pub const MOTION_RAMP: f64 = 10.0;
/// How fast the axis coasts down without torque, rev/s² (friction of the unloaded motor).
pub const FRICTION_DECEL: f64 = 2.0;
/// How fast the holding brake stops the axis, rev/s².
pub const BRAKE_DECEL: f64 = 50.0;
/// The stopwatch's timer (§4.2.4, figure 4.5 of the SafeMOTION thesis: a TP with PT = T#15s).
pub const STOPWATCH_LIMIT: SimDuration = SimDuration::from_secs(15);

/// The state of a function's page as the student sees it under its Zap/Vyp button (§4.2.3,
/// figure 4.4 of the SafeMOTION thesis, and the guides of its appendix A).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum HmiState {
    /// "Neaktivní", grey: the function is not selected.
    NotSelected,
    /// "Neaktivní", green: selected, the curtain's field intact, ready.
    Ready,
    /// "Del+Decel", orange: requested, the enable delay and the ramp window run.
    DelDecel,
    /// "OK", green: requested and its safe state reached.
    Ok,
    /// "Aktivní", red: STO requested, the torque off (guide A.2 step 5).
    Active,
    /// "NOK", red: the drive de-energised: a violation, or SS1's stop (guide A.4 step 5).
    Nok,
    /// "Chyba", red: the safe drive's function block is not ready (SafetyRdy = 0).
    Error,
}

impl HmiState {
    /// The text on the page.
    pub fn text(self) -> &'static str {
        match self {
            HmiState::NotSelected | HmiState::Ready => "Neaktivní",
            HmiState::DelDecel => "Del+Decel",
            HmiState::Ok => "OK",
            HmiState::Active => "Aktivní",
            HmiState::Nok => "NOK",
            HmiState::Error => "Chyba",
        }
    }

    /// The lamp's colour.
    pub fn colour(self) -> &'static str {
        match self {
            HmiState::NotSelected => "grey",
            HmiState::Ready | HmiState::Ok => "green",
            HmiState::DelDecel => "orange",
            HmiState::Active | HmiState::Nok | HmiState::Error => "red",
        }
    }
}

impl fmt::Display for HmiState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", self.text(), self.colour())
    }
}

/// The page's state of `function` (figure 4.4 of the SafeMOTION thesis, in its order):
/// `ready` = SafetyRdy, `selected` = its `<f>_On`, `curtain_ok` = ESPE_OUT,
/// `status` = S_Status_&lt;f&gt;, `not_err` = S_Status_NotErrFunc. STO's safe state shows "Aktivní"
/// and SS1's "NOK", as the guides A.2 and A.4 say (for SS1 the safe state is the de-energised
/// drive).
pub fn hmi_state(
    function: Function,
    ready: bool,
    selected: bool,
    curtain_ok: bool,
    status: bool,
    not_err: bool,
) -> HmiState {
    if !ready {
        HmiState::Error
    } else if !selected {
        HmiState::NotSelected
    } else if curtain_ok {
        HmiState::Ready
    } else if status {
        match function {
            Function::Sto => HmiState::Active,
            Function::Ss1 => HmiState::Nok,
            _ => HmiState::Ok,
        }
    } else if not_err {
        HmiState::DelDecel
    } else {
        HmiState::Nok
    }
}

/// `true` for the functions whose page has the stopwatch (§4.2.4 of the SafeMOTION thesis:
/// `Function_Sel` 3..6, SS1, SS2, SLS1 and SLS2).
pub fn has_stopwatch(f: Function) -> bool {
    matches!(
        f,
        Function::Ss1 | Function::Ss2 | Function::Sls(SlsLevel::L1) | Function::Sls(SlsLevel::L2)
    )
}

/// The drive's state under Zap/Vyp Pohon.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum DriveState {
    /// "Vypnuto": off (or in error after a de-energisation).
    Off,
    /// "Zap - P": on, positive direction.
    OnPositive,
    /// "Zap - N": on, negative direction.
    OnNegative,
}

impl fmt::Display for DriveState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DriveState::Off => "Vypnuto",
            DriveState::OnPositive => "Zap - P",
            DriveState::OnNegative => "Zap - N",
        })
    }
}

/// One line of the stand's log.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StandLogLine {
    /// Simulated time, ms.
    pub at_ms: u64,
    /// Who: `student`, `curtain`, `hmi`, `drive`, `safety`, `axis`, `stopwatch`.
    pub who: &'static str,
    /// What happened.
    pub text: String,
    /// The axis's speed then, rev/s.
    pub speed: f64,
    /// The axis's position then, rev.
    pub position: f64,
}

/// A change of the selected function's page.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct HmiChange {
    /// Simulated time, ms.
    pub at_ms: u64,
    /// The new state.
    pub state: HmiState,
    /// Its text.
    pub text: &'static str,
    /// Its lamp.
    pub colour: &'static str,
}

/// What a run of the stand showed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StandReport {
    /// The scenario's name.
    pub scenario: String,
    /// The function selected.
    pub function: String,
    /// The scan period, ms.
    pub scan_ms: u64,
    /// The run's length, ms.
    pub duration_ms: u64,
    /// Everything that happened, in order.
    pub log: Vec<StandLogLine>,
    /// The page's states, from the first scan on.
    pub hmi: Vec<HmiChange>,
    /// Every reading the stopwatch stopped at, ms.
    pub stopwatch_ms: Vec<u64>,
    /// The violations the safe drive found: time (ms) and what.
    pub trips: Vec<(u64, String)>,
    /// The page's state at the end.
    pub final_state: HmiState,
    /// The axis's speed at the end, rev/s.
    pub final_speed: f64,
    /// The axis's position at the end, rev.
    pub final_position: f64,
}

impl StandReport {
    /// The readable log and a summary, as a student at the stand would note it.
    pub fn to_text(&self) -> String {
        use fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "stand: {} — {} selected, demo parameters (the SafeMOTION thesis), scan {} ms",
            self.scenario, self.function, self.scan_ms
        );
        let _ = writeln!(
            s,
            "{:>11}  {:<9}  {:>12}  {:>11}  what",
            "time", "who", "speed", "position"
        );
        for l in &self.log {
            let _ = writeln!(
                s,
                "{:>9.3} s  {:<9}  {:>6.2} rev/s  {:>7.2} rev  {}",
                l.at_ms as f64 / 1000.0,
                l.who,
                l.speed,
                l.position,
                l.text
            );
        }
        let _ = writeln!(s, "\n{} page:", self.function);
        for h in &self.hmi {
            let _ = writeln!(s, "{:>9.3} s  {}", h.at_ms as f64 / 1000.0, h.state);
        }
        for w in &self.stopwatch_ms {
            let _ = writeln!(s, "stopwatch: {w} ms");
        }
        let _ = writeln!(
            s,
            "at the end ({:.3} s): {}, axis {:.2} rev/s at {:.2} rev",
            self.duration_ms as f64 / 1000.0,
            self.final_state,
            self.final_speed,
            self.final_position
        );
        s
    }

    /// The report as JSON.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }

    /// The time (ms) the page first showed `state`, if it did.
    pub fn first(&self, state: HmiState) -> Option<u64> {
        self.hmi.iter().find(|h| h.state == state).map(|h| h.at_ms)
    }
}

/// The stand: axis, motion control, light curtain, safe drive and HMI.
#[derive(Clone, Debug)]
pub struct Stand {
    function: Function,
    follows_limit: bool,
    brake: bool,
    drive: SafeDrive,
    // The axis.
    speed: f64,
    position: f64,
    // The motion control (MpAxisBasic).
    speed_field: f64,
    drive_on: bool,
    motion_error: bool,
    // The light curtain: the field broken until, and SF_ESPE's output.
    field_broken_until: Option<SimTime>,
    curtain_ok: bool,
    reset: bool,
    // What the drive gave back in the last scan.
    torque: bool,
    brake_released: bool,
    speed_limit: Option<f64>,
    // The HMI.
    hmi: Option<HmiState>,
    stopwatch_from: Option<SimTime>,
    drive_state: DriveState,
    log: Vec<StandLogLine>,
    hmi_changes: Vec<HmiChange>,
    stopwatch: Vec<u64>,
    trips: Vec<(u64, String)>,
}

impl Stand {
    /// A stand with `function` selected, the speed field at `speed`, the drive off, the
    /// curtain acknowledged, the safe drive with the demo parameters.
    pub fn new(sc: &StandScenario) -> Self {
        let drive = match SafeDrive::new(DriveSafetyConfig::demo()) {
            Ok(d) => d,
            Err(e) => unreachable!("the demo parameters are valid: {e}"),
        };
        Stand {
            function: sc.function,
            follows_limit: sc.follows_limit,
            brake: sc.brake,
            drive,
            speed: 0.0,
            position: 0.0,
            speed_field: sc.speed,
            drive_on: false,
            motion_error: false,
            field_broken_until: None,
            curtain_ok: true,
            reset: false,
            torque: false,
            brake_released: false,
            speed_limit: None,
            hmi: None,
            stopwatch_from: None,
            drive_state: DriveState::Off,
            log: Vec::new(),
            hmi_changes: Vec::new(),
            stopwatch: Vec::new(),
            trips: Vec::new(),
        }
    }

    fn note(&mut self, now: SimTime, who: &'static str, text: impl Into<String>) {
        self.log.push(StandLogLine {
            at_ms: now.as_nanos() / 1_000_000,
            who,
            text: text.into(),
            speed: round(self.speed),
            position: round(self.position),
        });
    }

    /// The student's action at `now`; it takes effect in the scan at `now`.
    pub fn act(&mut self, now: SimTime, action: StandAction) {
        match action {
            StandAction::Drive(true) => {
                if self.motion_error {
                    self.note(
                        now,
                        "student",
                        "Zap Pohon: the drive does not start (de-energised; press Reset first)",
                    );
                } else {
                    self.drive_on = true;
                    self.note(
                        now,
                        "student",
                        format!("Zap Pohon at {} rev/s", self.speed_field),
                    );
                }
            }
            StandAction::Drive(false) => {
                self.drive_on = false;
                self.note(now, "student", "Vyp Pohon");
            }
            StandAction::Speed(v) => {
                self.speed_field = v;
                self.note(now, "student", format!("speed field set to {v} rev/s"));
            }
            StandAction::BreakCurtain { hold } => {
                self.field_broken_until = Some(now + hold);
                self.note(
                    now,
                    "student",
                    format!("a hand in the light curtain's field for {hold}"),
                );
            }
            StandAction::Reset => {
                self.reset = true;
                self.note(now, "student", "presses Reset");
            }
        }
    }

    /// One scan at `now`, then the axis moves on by [`SCAN`].
    pub fn step(&mut self, now: SimTime) {
        // The light curtain (SF_ESPE with restart interlock).
        let broken = self.field_broken_until.is_some_and(|t| now < t);
        if self.field_broken_until.is_some() && !broken {
            self.field_broken_until = None;
            self.note(now, "curtain", "field clear again");
        }
        if broken && self.curtain_ok {
            self.curtain_ok = false;
            self.note(
                now,
                "curtain",
                format!("field broken: NOK (red), {} requested", self.function),
            );
        } else if !broken && !self.curtain_ok && self.reset {
            self.curtain_ok = true;
            self.note(now, "curtain", "acknowledged by Reset: OK (green)");
        }

        // The safe drive: the selected function's control bit is the curtain's output.
        let mut control = ControlBits::idle().with_reset(self.reset);
        if !self.curtain_ok {
            control = control.with_request(self.function);
        }
        let reset = std::mem::take(&mut self.reset);
        let out = self.drive.scan(
            now,
            &DriveSafetyInputs {
                control,
                feedback: Some(AxisFeedback {
                    position: self.position,
                    speed: self.speed,
                }),
                // The stand's HMI has no SLT page: SLT is never requested here.
                torque: None,
            },
        );
        for e in &out.events {
            let text = match e.kind {
                DriveEventKind::Requested(f) => format!("{f} requested (S_Control_{f} FALSE)"),
                DriveEventKind::SafeStateReached(f) => {
                    format!("{f} safe state reached (S_Status_{f} TRUE)")
                }
                DriveEventKind::Released(f) => format!("{f} no longer requested"),
                DriveEventKind::Tripped(v) => {
                    self.trips.push((now.as_nanos() / 1_000_000, v.to_string()));
                    format!("violation, de-energised: {v}")
                }
                DriveEventKind::TorqueOff => {
                    if self.brake {
                        "torque off, brake applied".to_owned()
                    } else {
                        "torque off, the axis coasts".to_owned()
                    }
                }
                DriveEventKind::TorqueOn => "torque on".to_owned(),
                DriveEventKind::Reset => "error acknowledged (S_Control_Reset)".to_owned(),
            };
            self.note(now, "safety", text);
        }
        if self.torque && !out.torque_enabled {
            // MpAxisBasic goes into error when the drive is de-energised (§4.1 of the SafeMOTION
            // thesis).
            self.motion_error = true;
            self.drive_on = false;
        }
        self.torque = out.torque_enabled;
        // The Reset clears the motion control's error once the torque is back.
        if reset && self.motion_error && self.torque {
            self.motion_error = false;
            self.note(now, "drive", "motion error acknowledged by Reset");
        }
        self.brake_released = out.brake_released;
        self.speed_limit = out.speed_command_limit;

        // The HMI: the page's state, the stopwatch, the drive's state.
        let status = out.status.of(self.function);
        let state = hmi_state(
            self.function,
            true,
            true,
            self.curtain_ok,
            status,
            out.status.not_err_func,
        );
        if self.hmi != Some(state) {
            self.hmi = Some(state);
            self.hmi_changes.push(HmiChange {
                at_ms: now.as_nanos() / 1_000_000,
                state,
                text: state.text(),
                colour: state.colour(),
            });
            self.note(now, "hmi", format!("{}: {state}", self.function));
        }
        self.stopwatch_scan(now, status, out.status.not_err_func);
        let ds = if !self.drive_on {
            DriveState::Off
        } else if self.speed_field < 0.0 {
            DriveState::OnNegative
        } else {
            DriveState::OnPositive
        };
        if ds != self.drive_state {
            self.drive_state = ds;
            self.note(now, "drive", format!("Zap/Vyp Pohon: {ds}"));
        }

        self.move_axis(now);
    }

    /// The stopwatch (§4.2.4 of the SafeMOTION thesis): runs from the request while UMSafetyOK
    /// holds (no safe state, no error), stops at the safe state or the trip, at most 15 s; zero
    /// again once the curtain is acknowledged.
    fn stopwatch_scan(&mut self, now: SimTime, status: bool, not_err: bool) {
        if !has_stopwatch(self.function) {
            return;
        }
        let safety_ok = self.curtain_ok || (not_err && !status);
        match self.stopwatch_from {
            None if !self.curtain_ok && safety_ok => {
                self.stopwatch_from = Some(now);
                self.note(now, "stopwatch", "starts");
            }
            Some(from) if !safety_ok => {
                let ms = now
                    .saturating_duration_since(from)
                    .min(STOPWATCH_LIMIT)
                    .as_nanos()
                    / 1_000_000;
                self.stopwatch.push(ms);
                self.stopwatch_from = None;
                self.note(now, "stopwatch", format!("stops at {ms} ms"));
            }
            Some(_) if self.curtain_ok => self.stopwatch_from = None,
            _ => {}
        }
    }

    /// The axis over one scan: the motion control's ramp with torque, friction or brake
    /// without; the position by the trapezoid rule.
    fn move_axis(&mut self, now: SimTime) {
        let dt = SCAN.as_secs_f64();
        let v0 = self.speed;
        // A step of `a · dt` toward `target`, landing on it exactly, on a grid of 1e-9 rev/s:
        // ten steps of 0.1 rev/s from 1 rev/s make 2 rev/s, not 2.0000000000000004, which
        // SOS would take for a speed above its 2 rev/s.
        let toward = |v: f64, target: f64, a: f64| {
            let next = if v < target { v + a * dt } else { v - a * dt };
            let next = (next * 1e9).round() / 1e9;
            if (next - target).abs() < 1e-9 || (v < target) != (next < target) {
                target
            } else {
                next
            }
        };
        let target = if self.torque {
            let mut target = if self.drive_on { self.speed_field } else { 0.0 };
            if self.follows_limit {
                if let Some(l) = self.speed_limit {
                    target = target.clamp(-l, l);
                }
            }
            self.speed = toward(v0, target, MOTION_RAMP);
            target
        } else {
            let decel = if self.brake && !self.brake_released {
                BRAKE_DECEL
            } else {
                FRICTION_DECEL
            };
            self.speed = toward(v0, 0.0, decel);
            0.0
        };
        self.position += (v0 + self.speed) / 2.0 * dt;
        if v0 != target && self.speed == target {
            let what = if target == 0.0 {
                "axis at standstill".to_owned()
            } else {
                format!("axis at {target} rev/s")
            };
            self.note(now + SCAN, "axis", what);
        }
    }

    /// What the stand shows at `now`, after a scan.
    pub fn sample(&self, now: SimTime) -> StandSample {
        StandSample {
            t_s: now.as_secs_f64(),
            speed: self.speed,
            position: self.position,
            torque: self.torque,
            field_broken: self.field_broken_until.is_some_and(|t| now < t),
            hmi: self.hmi,
            speed_limit: self.speed_limit,
        }
    }

    /// The report so far, ending at `end`.
    pub fn report(&self, name: &str, end: SimTime) -> StandReport {
        StandReport {
            scenario: name.to_owned(),
            function: self.function.to_string(),
            scan_ms: SCAN.as_nanos() / 1_000_000,
            duration_ms: end.as_nanos() / 1_000_000,
            log: self.log.clone(),
            hmi: self.hmi_changes.clone(),
            stopwatch_ms: self.stopwatch.clone(),
            trips: self.trips.clone(),
            final_state: self.hmi.unwrap_or(HmiState::Ready),
            final_speed: round(self.speed),
            final_position: round(self.position),
        }
    }
}

/// `v` to the µ-unit: a report's numbers do not show the last bits of a float sum.
fn round(v: f64) -> f64 {
    let r = (v * 1e6).round() / 1e6;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

/// Plays `sc` on a fresh stand: every scan from 0 to the scenario's end.
pub fn run(sc: &StandScenario) -> StandReport {
    play(sc, |_, _| {})
}

/// [`run`], and what the stand showed after each scan, for a plot.
pub fn run_sampled(sc: &StandScenario) -> (StandReport, Vec<StandSample>) {
    let mut samples = Vec::new();
    let report = play(sc, |stand, at| samples.push(stand.sample(at)));
    (report, samples)
}

/// Plays `sc`, handing the stand to `after_scan` after every scan with the time the axis has
/// reached.
fn play(sc: &StandScenario, mut after_scan: impl FnMut(&Stand, SimTime)) -> StandReport {
    let mut stand = Stand::new(sc);
    let end = SimTime::ZERO + sc.duration;
    let mut events = sc.events.iter().peekable();
    let mut now = SimTime::ZERO;
    while now < end {
        while let Some(e) = events.next_if(|e| e.at <= now) {
            stand.act(now, e.action);
        }
        stand.step(now);
        now += SCAN;
        after_scan(&stand, now);
    }
    stand.report(&sc.name, end)
}

/// What the stand shows at a moment: the axis, the torque, the curtain, the page.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StandSample {
    /// Simulated time, s.
    pub t_s: f64,
    /// The axis's speed, rev/s.
    pub speed: f64,
    /// The axis's position, rev.
    pub position: f64,
    /// The drive gives torque.
    pub torque: bool,
    /// A hand is in the light curtain's field.
    pub field_broken: bool,
    /// The page's state of the selected function (`None` before the first scan).
    pub hmi: Option<HmiState>,
    /// The speed limit the safe drive commands, rev/s, while one holds.
    pub speed_limit: Option<f64>,
}
