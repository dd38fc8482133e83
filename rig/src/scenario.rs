//! Scenario files: what happens to the lift, and when (TOML; documented in README.md).
//!
//! A malformed file gets an error that names the file, the line and the field at fault;
//! unknown keys are errors, not silently ignored.

use asi_phy::{SimDuration, SimTime};
use controller::Algorithm;
use lift_model::{Button, End, LiftConfig, LoadLevel, SensorFault, VaneSensor};
use serde::Deserialize;
use std::fmt;
use std::fmt::Write as _;
use std::ops::{Range, RangeInclusive};
use toml::Spanned;

/// A scenario, checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    /// Its name, for the report.
    pub name: String,
    /// The seed of every random choice (line noise).
    pub seed: u64,
    /// How long to simulate.
    pub duration: SimDuration,
    /// The controller's algorithm.
    pub algorithm: Algorithm,
    /// Floors, 2..=24.
    pub floors: u8,
    /// Cabin height at power-on above the floor-1 level, mm.
    pub start_mm: f64,
    /// Load at power-on.
    pub load: LoadLevel,
    /// Door closed at power-on.
    pub door_closed: bool,
    /// Probability that a pulse on the line is corrupted.
    pub pulse_error_rate: f64,
    /// Plain I/O modules added to the lab bus at its free addresses (0..=20): the lift on a
    /// fuller bus.
    pub extra_slaves: u8,
    /// The PLC scan period.
    pub plc_scan: SimDuration,
    /// Whether the operator presses the safety reset once after power-on, as at the lab
    /// (the overtravel monitor needs a manual reset before K1 can close).
    pub power_on_reset: bool,
    /// The events, in time order.
    pub events: Vec<ScenarioEvent>,
}

/// One scheduled action.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioEvent {
    /// When.
    pub at: SimTime,
    /// What.
    pub action: Action,
    /// The line of the `[[event]]` in the file (0 for built-in scenarios).
    pub line: usize,
}

/// What a scenario event does.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// A button is pressed and held.
    Press {
        /// Which.
        button: Button,
        /// For how long.
        hold: SimDuration,
    },
    /// The load changes.
    Load(LoadLevel),
    /// The door is moved by hand.
    Door {
        /// `true` = closed.
        closed: bool,
    },
    /// The hand crank on the motor moves the cabin (only without power).
    Crank {
        /// Millimetres, positive up.
        mm: f64,
    },
    /// The operator's safety reset button (overtravel recovery).
    Reset,
    /// The operator's overtravel rescue (README, "Start heights"): if the cabin stands where
    /// initialisation cannot find floor 1 by itself ([`needs_rescue`]: on or beyond an
    /// overtravel sensor, or below floor 1's vane) and K1 is open, the operator cranks it to
    /// the level of the nearer end floor; otherwise nothing.
    Rescue,
    /// The operator's acknowledge of a safety group error (ERR_ACK).
    Ack,
    /// A fault is injected.
    Fault(Fault),
}

/// An injected fault.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// A slave is taken off the bus.
    SlaveOffline {
        /// Its address.
        slave: u8,
    },
    /// A slave is put back.
    SlaveOnline {
        /// Its address.
        slave: u8,
    },
    /// The AS-i supply fails for a while.
    PowerFail {
        /// How long.
        duration: SimDuration,
    },
    /// The safe connection of the cabin STOP terminal delivers nothing for a while.
    SafeLinkDrop {
        /// How long.
        duration: SimDuration,
    },
    /// A vane sensor's output fails (stuck on or off) or is repaired.
    Vane {
        /// Which sensor.
        sensor: VaneSensor,
        /// Its fault from now on (`SensorFault::None` = repaired).
        fault: SensorFault,
    },
}

/// The PLC scan periods the program works with. The cabin's 32-bit word takes 14 handshake
/// steps of one scan each (seed 003 tables 4.6/4.7), so its inputs are up to about 15 scans
/// old: at 20 ms a 300 ms press is always seen and initialisation sees floor 1's vane in time;
/// at 25 ms some press phases are lost, at 30 ms initialisation can miss floor 1's level
/// (measured; README, Scenario files).
pub const PLC_SCAN_RANGE: std::ops::RangeInclusive<SimDuration> =
    SimDuration::from_millis(1)..=SimDuration::from_millis(20);

/// What the default press lasts: a person's push.
pub const DEFAULT_HOLD: SimDuration = SimDuration::from_millis(300);

/// Why a scenario cannot be used: where and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScenarioError {
    /// The file (or `<built-in>`).
    pub file: String,
    /// 1-based line, 0 if unknown.
    pub line: usize,
    /// 1-based column, 0 if unknown.
    pub column: usize,
    /// The field at fault, e.g. `event[3].press` or `lift.start_mm`.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.line, self.field.is_empty()) {
            (0, true) => write!(f, "{}: {}", self.file, self.message),
            (0, false) => write!(f, "{}: {}: {}", self.file, self.field, self.message),
            (l, true) => write!(f, "{}:{l}:{}: {}", self.file, self.column, self.message),
            (l, false) => write!(
                f,
                "{}:{l}:{}: {}: {}",
                self.file, self.column, self.field, self.message
            ),
        }
    }
}

impl std::error::Error for ScenarioError {}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScenario {
    name: Option<String>,
    seed: Option<u64>,
    duration: Option<Spanned<String>>,
    algorithm: Option<Spanned<String>>,
    lift: Option<RawLift>,
    bus: Option<RawBus>,
    controller: Option<RawController>,
    safety: Option<RawSafety>,
    #[serde(default)]
    event: Vec<Spanned<RawEvent>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLift {
    floors: Option<Spanned<i64>>,
    start_mm: Option<Spanned<f64>>,
    load: Option<Spanned<String>>,
    door: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBus {
    pulse_error_rate: Option<Spanned<f64>>,
    extra_slaves: Option<Spanned<i64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawController {
    scan: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSafety {
    power_on_reset: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEvent {
    at: Spanned<String>,
    press: Option<Spanned<String>>,
    hold: Option<Spanned<String>>,
    load: Option<Spanned<String>>,
    door: Option<Spanned<String>>,
    crank_mm: Option<Spanned<f64>>,
    reset: Option<Spanned<bool>>,
    rescue: Option<Spanned<bool>>,
    ack: Option<Spanned<bool>>,
    fault: Option<Spanned<RawFault>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFault {
    kind: Spanned<String>,
    slave: Option<Spanned<i64>>,
    duration: Option<Spanned<String>>,
    sensor: Option<Spanned<String>>,
}

/// Turns byte offsets into lines and columns, and names errors.
struct Locator<'a> {
    file: &'a str,
    text: &'a str,
}

impl Locator<'_> {
    fn position(&self, offset: usize) -> (usize, usize) {
        let upto = &self.text[..offset.min(self.text.len())];
        let line = upto.matches('\n').count() + 1;
        let column = upto.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        (line, column)
    }

    fn error(
        &self,
        span: Option<Range<usize>>,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> ScenarioError {
        let (line, column) = span.map_or((0, 0), |s| self.position(s.start));
        ScenarioError {
            file: self.file.to_owned(),
            line,
            column,
            field: field.into(),
            message: message.into(),
        }
    }

    /// The key written on the line of `offset`, for errors the TOML reader reports without it.
    fn key_at(&self, offset: usize) -> String {
        let start = self.text[..offset.min(self.text.len())]
            .rfind('\n')
            .map_or(0, |i| i + 1);
        let line = self.text[start..].lines().next().unwrap_or("");
        match line.split_once('=') {
            Some((k, _)) if !line.trim_start().starts_with('[') => k.trim().to_owned(),
            _ => String::new(),
        }
    }
}

fn duration(
    loc: &Locator<'_>,
    field: &str,
    s: &Spanned<String>,
) -> Result<SimDuration, ScenarioError> {
    s.get_ref()
        .parse::<SimDuration>()
        .map_err(|e| loc.error(Some(s.span()), field, e.to_string()))
}

fn load_level(
    loc: &Locator<'_>,
    field: &str,
    s: &Spanned<String>,
) -> Result<LoadLevel, ScenarioError> {
    match s.get_ref().as_str() {
        "empty" => Ok(LoadLevel::Empty),
        "loaded" => Ok(LoadLevel::Loaded),
        "full" => Ok(LoadLevel::Full),
        "overloaded" => Ok(LoadLevel::Overloaded),
        other => Err(loc.error(
            Some(s.span()),
            field,
            format!("unknown load `{other}`: use empty, loaded, full or overloaded"),
        )),
    }
}

fn door(loc: &Locator<'_>, field: &str, s: &Spanned<String>) -> Result<bool, ScenarioError> {
    match s.get_ref().as_str() {
        "closed" => Ok(true),
        "open" => Ok(false),
        other => Err(loc.error(
            Some(s.span()),
            field,
            format!("unknown door state `{other}`: use open or closed"),
        )),
    }
}

/// Reads `press = "cabin:3"` and its kin.
fn button(
    loc: &Locator<'_>,
    field: &str,
    s: &Spanned<String>,
    floors: u8,
) -> Result<Button, ScenarioError> {
    let text = s.get_ref().as_str();
    let bad = |m: String| loc.error(Some(s.span()), field, m);
    let floor = |n: &str| -> Result<u8, ScenarioError> {
        match n.parse::<u8>() {
            Ok(f) if (1..=floors).contains(&f) => Ok(f),
            _ => Err(bad(format!(
                "floor `{n}` does not exist: the lift has floors 1..{floors}"
            ))),
        }
    };
    match text.split_once(':') {
        None if text == "stop" => Ok(Button::Stop),
        None if text == "bell" => Ok(Button::Bell),
        Some(("cabin", n)) => Ok(Button::Cabin(floor(n)?)),
        Some(("hall-up", n)) => {
            let f = floor(n)?;
            if f == floors {
                return Err(bad(format!("the top floor ({floors}) has no up button")));
            }
            Ok(Button::HallUp(f))
        }
        Some(("hall-down", n)) => {
            let f = floor(n)?;
            if f == 1 {
                return Err(bad("floor 1 has no down button".into()));
            }
            Ok(Button::HallDown(f))
        }
        _ => Err(bad(format!(
            "unknown button `{text}`: use cabin:N, hall-up:N, hall-down:N, stop or bell"
        ))),
    }
}

/// The legal cabin heights at power-on (`lift.start_mm`) for a lift of `floors` floors, mm
/// above the floor-1 level: the whole shaft between the mechanical ends (SPEC §4: the
/// overtravel sensors trip 60 mm beyond the end floors, the ends are 80 mm further), because
/// a power-on after an overrun finds the cabin on or beyond a sensor; it is recovered by hand
/// (README, Scenario files). The one place that says so: the scenario reader checks
/// `start_mm` against it and the campaign generator draws start positions from it.
pub fn start_range_mm(floors: u8) -> RangeInclusive<f64> {
    let shaft = LiftConfig {
        floors,
        ..LiftConfig::default()
    };
    shaft.end_position_mm(End::Bottom)..=shaft.end_position_mm(End::Top)
}

/// Whether a cabin standing at `position_mm` needs the operator's rescue before initialisation
/// can find floor 1 by itself (README, "Start heights"). It does not from the bottom of floor
/// 1's vane up to the top overtravel sensor; below that (beyond the bottom sensor, or between
/// it and the vane, where the run down ends on the sensor) and beyond the top sensor it does.
pub fn needs_rescue(floors: u8, position_mm: f64) -> bool {
    let shaft = LiftConfig {
        floors,
        ..LiftConfig::default()
    };
    let vane_bottom = shaft
        .vane_track_mm(VaneSensor::Left, 1)
        .map_or(shaft.trip_position_mm(End::Bottom), |(lo, _)| lo);
    position_mm < vane_bottom || position_mm >= shaft.trip_position_mm(End::Top)
}

impl Scenario {
    /// Reads a scenario from TOML `text`; `file` names it in errors.
    pub fn from_toml(file: &str, text: &str) -> Result<Scenario, ScenarioError> {
        let loc = Locator { file, text };
        let raw: RawScenario = toml::from_str(text).map_err(|e| {
            let span = e.span();
            let field = span
                .clone()
                .map(|s| loc.key_at(s.start))
                .unwrap_or_default();
            loc.error(span, field, e.message().trim().to_owned())
        })?;
        let mut sc = Scenario::defaults();
        if let Some(n) = raw.name {
            sc.name = n;
        }
        if let Some(s) = raw.seed {
            sc.seed = s;
        }
        if let Some(d) = &raw.duration {
            sc.duration = duration(&loc, "duration", d)?;
            if sc.duration.is_zero() {
                return Err(loc.error(Some(d.span()), "duration", "must be longer than zero"));
            }
        }
        if let Some(a) = &raw.algorithm {
            sc.algorithm = match a.get_ref().as_str() {
                "fifo" => Algorithm::Fifo,
                "collective" => Algorithm::Collective,
                other => {
                    return Err(loc.error(
                        Some(a.span()),
                        "algorithm",
                        format!("unknown algorithm `{other}`: use fifo or collective"),
                    ))
                }
            };
        }
        if let Some(l) = &raw.lift {
            if let Some(f) = &l.floors {
                let v = *f.get_ref();
                if !(2..=24).contains(&v) {
                    return Err(loc.error(
                        Some(f.span()),
                        "lift.floors",
                        format!("{v}: the lift has 2..24 floors"),
                    ));
                }
                sc.floors = v as u8;
            }
            if let Some(s) = &l.start_mm {
                let v = *s.get_ref();
                let range = start_range_mm(sc.floors);
                if !v.is_finite() || !range.contains(&v) {
                    return Err(loc.error(
                        Some(s.span()),
                        "lift.start_mm",
                        format!(
                            "{v} mm lies outside the shaft between the mechanical ends ({}..{} mm)",
                            range.start(),
                            range.end()
                        ),
                    ));
                }
                sc.start_mm = v;
            }
            if let Some(s) = &l.load {
                sc.load = load_level(&loc, "lift.load", s)?;
            }
            if let Some(s) = &l.door {
                sc.door_closed = door(&loc, "lift.door", s)?;
            }
        }
        if let Some(b) = &raw.bus {
            if let Some(r) = &b.pulse_error_rate {
                let v = *r.get_ref();
                if !(0.0..=1.0).contains(&v) {
                    return Err(loc.error(
                        Some(r.span()),
                        "bus.pulse_error_rate",
                        format!("{v}: a probability is 0..1"),
                    ));
                }
                sc.pulse_error_rate = v;
            }
            if let Some(n) = &b.extra_slaves {
                let v = *n.get_ref();
                sc.extra_slaves = u8::try_from(v)
                    .ok()
                    .filter(|v| *v as usize <= asi_bus::lab::EXTRA_ADDRESSES.len())
                    .ok_or_else(|| {
                        loc.error(
                            Some(n.span()),
                            "bus.extra_slaves",
                            format!("{v}: the lab bus has room for 0..=20 more slaves"),
                        )
                    })?;
            }
        }
        if let Some(c) = &raw.controller {
            if let Some(s) = &c.scan {
                sc.plc_scan = duration(&loc, "controller.scan", s)?;
                if !PLC_SCAN_RANGE.contains(&sc.plc_scan) {
                    return Err(loc.error(
                        Some(s.span()),
                        "controller.scan",
                        "must lie within 1..20 ms: the cabin word takes 14 scans, and beyond \
                         20 ms a 300 ms press or the vane edge initialisation needs can pass \
                         unseen (README, Scenario files)",
                    ));
                }
            }
        }
        if let Some(s) = &raw.safety {
            if let Some(r) = s.power_on_reset {
                sc.power_on_reset = r;
            }
        }
        for (i, ev) in raw.event.iter().enumerate() {
            let field = |name: &str| format!("event[{}].{name}", i + 1);
            let span = ev.span();
            let e = ev.get_ref();
            let at = SimTime::ZERO + duration(&loc, &field("at"), &e.at)?;
            let mut actions = Vec::new();
            if let Some(p) = &e.press {
                let b = button(&loc, &field("press"), p, sc.floors)?;
                let hold = match &e.hold {
                    Some(h) => duration(&loc, &field("hold"), h)?,
                    None => DEFAULT_HOLD,
                };
                if hold.is_zero() {
                    let h = e.hold.as_ref().map(|h| h.span());
                    return Err(loc.error(h, field("hold"), "a press lasts longer than zero"));
                }
                actions.push(Action::Press { button: b, hold });
            } else if let Some(h) = &e.hold {
                return Err(loc.error(
                    Some(h.span()),
                    field("hold"),
                    "`hold` belongs to a `press`",
                ));
            }
            if let Some(l) = &e.load {
                actions.push(Action::Load(load_level(&loc, &field("load"), l)?));
            }
            if let Some(d) = &e.door {
                actions.push(Action::Door {
                    closed: door(&loc, &field("door"), d)?,
                });
            }
            if let Some(c) = &e.crank_mm {
                let mm = *c.get_ref();
                if !mm.is_finite() || mm == 0.0 || mm.abs() > 10_000.0 {
                    return Err(loc.error(
                        Some(c.span()),
                        field("crank_mm"),
                        format!("{mm}: crank by a non-zero distance up to 10 m"),
                    ));
                }
                actions.push(Action::Crank { mm });
            }
            for (flag, name, action) in [
                (&e.reset, "reset", Action::Reset),
                (&e.rescue, "rescue", Action::Rescue),
                (&e.ack, "ack", Action::Ack),
            ] {
                if let Some(v) = flag {
                    if !*v.get_ref() {
                        return Err(loc.error(
                            Some(v.span()),
                            field(name),
                            format!("`{name} = false` does nothing; write `{name} = true`"),
                        ));
                    }
                    actions.push(action);
                }
            }
            if let Some(f) = &e.fault {
                actions.push(Action::Fault(fault(&loc, &field("fault"), f)?));
            }
            let action = match actions.len() {
                1 => actions.remove(0),
                0 => return Err(loc.error(
                    Some(span),
                    format!("event[{}]", i + 1),
                    "no action: give one of press, load, door, crank_mm, reset, rescue, ack, fault",
                )),
                _ => {
                    return Err(loc.error(
                        Some(span),
                        format!("event[{}]", i + 1),
                        "more than one action: give each its own [[event]]",
                    ))
                }
            };
            let (line, _) = loc.position(span.start);
            sc.events.push(ScenarioEvent { at, action, line });
        }
        // Stable: events at the same time keep the file's order.
        sc.events.sort_by_key(|e| e.at);
        Ok(sc)
    }

    /// The scenario as a scenario file that [`Scenario::from_toml`] reads back to an equal
    /// scenario, but for the events' `line`s: every setting is written (defaults too),
    /// durations exactly in the largest unit that divides them (`"1500ms"`), numbers in their
    /// shortest exact form, and the events in time order (stable, as the reader sorts them;
    /// so a scenario whose events are in time order comes back unchanged).
    pub fn to_toml(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "name = {}", toml_string(&self.name));
        let _ = writeln!(s, "seed = {}", self.seed);
        let _ = writeln!(s, "duration = \"{}\"", exact_duration(self.duration));
        let _ = writeln!(
            s,
            "algorithm = \"{}\"",
            match self.algorithm {
                Algorithm::Fifo => "fifo",
                Algorithm::Collective => "collective",
            }
        );
        let _ = writeln!(s, "\n[lift]\nfloors = {}", self.floors);
        let _ = writeln!(s, "start_mm = {}", toml_float(self.start_mm));
        let _ = writeln!(s, "load = \"{}\"", load_name(self.load));
        let _ = writeln!(
            s,
            "door = \"{}\"",
            if self.door_closed { "closed" } else { "open" }
        );
        let _ = writeln!(
            s,
            "\n[bus]\npulse_error_rate = {}",
            toml_float(self.pulse_error_rate)
        );
        let _ = writeln!(s, "extra_slaves = {}", self.extra_slaves);
        let _ = writeln!(
            s,
            "\n[controller]\nscan = \"{}\"",
            exact_duration(self.plc_scan)
        );
        let _ = writeln!(s, "\n[safety]\npower_on_reset = {}", self.power_on_reset);
        let mut events: Vec<&ScenarioEvent> = self.events.iter().collect();
        events.sort_by_key(|e| e.at);
        for e in events {
            let at = exact_duration(e.at.saturating_duration_since(SimTime::ZERO));
            let _ = writeln!(s, "\n[[event]]\nat = \"{at}\"");
            let _ = match &e.action {
                Action::Press { button, hold } => {
                    let _ = writeln!(s, "press = \"{}\"", button_text(*button));
                    if *hold != DEFAULT_HOLD {
                        let _ = writeln!(s, "hold = \"{}\"", exact_duration(*hold));
                    }
                    Ok(())
                }
                Action::Load(l) => writeln!(s, "load = \"{}\"", load_name(*l)),
                Action::Door { closed } => {
                    writeln!(s, "door = \"{}\"", if *closed { "closed" } else { "open" })
                }
                Action::Crank { mm } => writeln!(s, "crank_mm = {}", toml_float(*mm)),
                Action::Reset => writeln!(s, "reset = true"),
                Action::Rescue => writeln!(s, "rescue = true"),
                Action::Ack => writeln!(s, "ack = true"),
                Action::Fault(f) => writeln!(s, "fault = {}", fault_text(f)),
            };
        }
        s
    }

    /// A scenario with nothing in it: the defaults every file starts from.
    pub fn defaults() -> Scenario {
        Scenario {
            name: "unnamed".into(),
            seed: 1,
            duration: SimDuration::from_secs(60),
            algorithm: Algorithm::Fifo,
            floors: 4,
            start_mm: 650.0,
            load: LoadLevel::Empty,
            door_closed: true,
            pulse_error_rate: 0.0,
            extra_slaves: 0,
            plc_scan: SimDuration::from_millis(10),
            power_on_reset: true,
            events: Vec::new(),
        }
    }

    /// The built-in demo: power-on between floors 2 and 3, initialisation, a cabin call, a
    /// hall call stored meanwhile, and one more cabin call.
    pub fn demo() -> Result<Scenario, ScenarioError> {
        Scenario::from_toml("<built-in demo>", include_str!("../../scenarios/demo.toml"))
    }
}

/// A TOML basic string: quoted, with `"`, `\\` and control characters escaped.
fn toml_string(text: &str) -> String {
    let mut s = String::with_capacity(text.len() + 2);
    s.push('"');
    for c in text.chars() {
        match c {
            '"' => s.push_str("\\\""),
            '\\' => s.push_str("\\\\"),
            '\n' => s.push_str("\\n"),
            '\t' => s.push_str("\\t"),
            '\r' => s.push_str("\\r"),
            c if c.is_control() => {
                let _ = write!(s, "\\u{:04X}", c as u32);
            }
            c => s.push(c),
        }
    }
    s.push('"');
    s
}

/// A finite number as TOML reads it back exactly: Rust's shortest round-trip form, which
/// always has a decimal point or an exponent (`650.0`, `0.001`, `1e-5`).
fn toml_float(v: f64) -> String {
    format!("{v:?}")
}

/// A duration in the largest unit that divides it, so that it reads back exactly.
fn exact_duration(d: SimDuration) -> String {
    let ns = d.as_nanos();
    for (scale, unit) in [(1_000_000_000, "s"), (1_000_000, "ms"), (1_000, "us")] {
        if ns % scale == 0 {
            return format!("{}{unit}", ns / scale);
        }
    }
    format!("{ns}ns")
}

/// The scenario file's name of a load level (also the rig's log).
pub(crate) fn load_name(l: LoadLevel) -> &'static str {
    match l {
        LoadLevel::Empty => "empty",
        LoadLevel::Loaded => "loaded",
        LoadLevel::Full => "full",
        LoadLevel::Overloaded => "overloaded",
    }
}

/// A button as a scenario file names it: `cabin:3`, `hall-up:2`, `stop`.
pub fn button_text(b: Button) -> String {
    match b {
        Button::Cabin(f) => format!("cabin:{f}"),
        Button::HallUp(f) => format!("hall-up:{f}"),
        Button::HallDown(f) => format!("hall-down:{f}"),
        Button::Bell => "bell".into(),
        Button::Stop => "stop".into(),
    }
}

fn fault_text(f: &Fault) -> String {
    let side = |s: &VaneSensor| match s {
        VaneSensor::Left => "left",
        VaneSensor::Right => "right",
    };
    match f {
        Fault::SlaveOffline { slave } => format!("{{ kind = \"slave-offline\", slave = {slave} }}"),
        Fault::SlaveOnline { slave } => format!("{{ kind = \"slave-online\", slave = {slave} }}"),
        Fault::PowerFail { duration } => format!(
            "{{ kind = \"power-fail\", duration = \"{}\" }}",
            exact_duration(*duration)
        ),
        Fault::SafeLinkDrop { duration } => format!(
            "{{ kind = \"safe-link-drop\", duration = \"{}\" }}",
            exact_duration(*duration)
        ),
        Fault::Vane { sensor, fault } => {
            let kind = match fault {
                SensorFault::StuckOn => "vane-stuck-on",
                SensorFault::StuckOff => "vane-stuck-off",
                SensorFault::None => "vane-repaired",
            };
            format!("{{ kind = \"{kind}\", sensor = \"{}\" }}", side(sensor))
        }
    }
}

fn fault(loc: &Locator<'_>, field: &str, f: &Spanned<RawFault>) -> Result<Fault, ScenarioError> {
    let raw = f.get_ref();
    let kind = raw.kind.get_ref().as_str();
    let slave = || -> Result<u8, ScenarioError> {
        let s = raw.slave.as_ref().ok_or_else(|| {
            loc.error(
                Some(f.span()),
                format!("{field}.slave"),
                format!("`{kind}` needs `slave = N`"),
            )
        })?;
        match *s.get_ref() {
            v @ 1..=31 => Ok(v as u8),
            v => Err(loc.error(
                Some(s.span()),
                format!("{field}.slave"),
                format!("{v}: a slave address is 1..31"),
            )),
        }
    };
    let dur = || -> Result<SimDuration, ScenarioError> {
        let d = raw.duration.as_ref().ok_or_else(|| {
            loc.error(
                Some(f.span()),
                format!("{field}.duration"),
                format!("`{kind}` needs `duration = \"…\"`"),
            )
        })?;
        duration(loc, &format!("{field}.duration"), d)
    };
    let unused = |present: bool, name: &str| -> Result<(), ScenarioError> {
        if present {
            Err(loc.error(
                Some(f.span()),
                format!("{field}.{name}"),
                format!("`{kind}` takes no `{name}`"),
            ))
        } else {
            Ok(())
        }
    };
    match kind {
        "slave-offline" | "slave-online" => {
            unused(raw.duration.is_some(), "duration")?;
            unused(raw.sensor.is_some(), "sensor")?;
            let s = slave()?;
            Ok(if kind == "slave-offline" {
                Fault::SlaveOffline { slave: s }
            } else {
                Fault::SlaveOnline { slave: s }
            })
        }
        "power-fail" | "safe-link-drop" => {
            unused(raw.slave.is_some(), "slave")?;
            unused(raw.sensor.is_some(), "sensor")?;
            let d = dur()?;
            Ok(if kind == "power-fail" {
                Fault::PowerFail { duration: d }
            } else {
                Fault::SafeLinkDrop { duration: d }
            })
        }
        "vane-stuck-on" | "vane-stuck-off" | "vane-repaired" => {
            unused(raw.slave.is_some(), "slave")?;
            unused(raw.duration.is_some(), "duration")?;
            let s = raw.sensor.as_ref().ok_or_else(|| {
                loc.error(Some(f.span()), format!("{field}.sensor"), format!("`{kind}` needs `sensor = \"left\"` or `\"right\"`"))
            })?;
            let sensor = match s.get_ref().as_str() {
                "left" => VaneSensor::Left,
                "right" => VaneSensor::Right,
                other => {
                    return Err(loc.error(
                        Some(s.span()),
                        format!("{field}.sensor"),
                        format!("unknown sensor `{other}`: use left (Snimac_1) or right (Snimac_2)"),
                    ))
                }
            };
            let fault = match kind {
                "vane-stuck-on" => SensorFault::StuckOn,
                "vane-stuck-off" => SensorFault::StuckOff,
                _ => SensorFault::None,
            };
            Ok(Fault::Vane { sensor, fault })
        }
        other => Err(loc.error(
            Some(raw.kind.span()),
            format!("{field}.kind"),
            format!(
                "unknown fault `{other}`: use slave-offline, slave-online, power-fail, safe-link-drop, \
                 vane-stuck-on, vane-stuck-off or vane-repaired"
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        Scenario::from_toml("t.toml", text)
            .expect_err("must fail")
            .to_string()
    }

    #[test]
    fn reads_the_example_of_the_issue() {
        let s = Scenario::from_toml(
            "cabin.toml",
            r#"
name = "cabin call"
seed = 1
duration = "90s"
algorithm = "fifo"
[lift]
floors = 4
start_mm = 650.0
load = "empty"
door = "closed"
[bus]
pulse_error_rate = 0.0
[[event]]
at = "20s"
press = "cabin:3"
[[event]]
at = "1.5min"
press = "stop"
hold = "2s"
[[event]]
at = "25s"
fault = { kind = "safe-link-drop", duration = "300ms" }
"#,
        )
        .expect("valid");
        assert_eq!(s.name, "cabin call");
        assert_eq!(s.duration, SimDuration::from_secs(90));
        assert_eq!(
            s.events.iter().map(|e| (e.at, e.line)).collect::<Vec<_>>(),
            [
                (SimTime::from_millis(20_000), 13),
                (SimTime::from_millis(25_000), 20),
                (SimTime::from_millis(90_000), 16)
            ]
        );
        assert_eq!(
            s.events[0].action,
            Action::Press {
                button: Button::Cabin(3),
                hold: DEFAULT_HOLD
            }
        );
    }

    #[test]
    fn errors_name_the_file_the_line_and_the_field() {
        assert_eq!(
            err("name = \"x\"\n[lift]\nfloors = 4\nstart_mm = 9000.0\n"),
            "t.toml:4:12: lift.start_mm: 9000 mm lies outside the shaft between the mechanical ends (-140..1340 mm)"
        );
        assert_eq!(
            err("[[event]]\nat = \"5s\"\npress = \"cabin:7\"\n"),
            "t.toml:3:9: event[1].press: floor `7` does not exist: the lift has floors 1..4"
        );
        assert_eq!(
            err("[[event]]\nat = \"5 parsecs\"\nreset = true\n"),
            "t.toml:2:6: event[1].at: unknown unit `parsecs` in `5 parsecs`: use ns, us, ms, s, min or h"
        );
        assert!(err("[[event]]\nat = \"5s\"\n").starts_with("t.toml:1:1: event[1]: no action"));
        assert!(err("[[event]]\nat = \"5s\"\nreset = true\nack = true\n")
            .contains("more than one action"));
        assert!(err("[[event]]\nat = \"5s\"\npress = \"hall-down:1\"\n")
            .contains("floor 1 has no down button"));
        assert!(
            err("[[event]]\nat = \"5s\"\nfault = { kind = \"slave-offline\" }\n")
                .contains("needs `slave = N`")
        );
        assert_eq!(
            err("[bus]\nextra_slaves = 21\n"),
            "t.toml:2:16: bus.extra_slaves: 21: the lab bus has room for 0..=20 more slaves"
        );
        assert!(err("algorithm = \"scan\"\n")
            .contains("t.toml:1:13: algorithm: unknown algorithm `scan`"));
    }

    #[test]
    fn unknown_keys_are_errors() {
        let e = err("name = \"x\"\n[lift]\nfloor = 4\n");
        assert!(
            e.starts_with("t.toml:3:1: floor: unknown field `floor`"),
            "{e}"
        );
        let e = err("speed = 3\n");
        assert!(
            e.starts_with("t.toml:1:1: speed: unknown field `speed`"),
            "{e}"
        );
        let e = err("[[event]]\nat = \"1s\"\npress = \"stop\"\nduration = \"2s\"\n");
        assert!(e.contains("unknown field `duration`"), "{e}");
    }

    #[test]
    fn a_wrong_type_names_its_key() {
        let e = err("[lift]\nstart_mm = \"high\"\n");
        assert!(e.starts_with("t.toml:2:12: start_mm:"), "{e}");
    }

    mod round_trip {
        use super::*;
        use proptest::prelude::*;

        fn duration_ns(max: u64) -> impl Strategy<Value = SimDuration> {
            // Whole seconds, milliseconds and microseconds as well as odd nanoseconds.
            prop_oneof![
                (1..=max / 1_000_000_000).prop_map(SimDuration::from_secs),
                (1..=max / 1_000_000).prop_map(SimDuration::from_millis),
                (1..=max / 1_000).prop_map(SimDuration::from_micros),
                (1..=max).prop_map(SimDuration::from_nanos),
            ]
        }

        fn button(floors: u8) -> impl Strategy<Value = Button> {
            prop_oneof![
                (1..=floors).prop_map(Button::Cabin),
                (1..floors).prop_map(Button::HallUp),
                (2..=floors).prop_map(Button::HallDown),
                Just(Button::Stop),
                Just(Button::Bell),
            ]
        }

        fn load() -> impl Strategy<Value = LoadLevel> {
            prop_oneof![
                Just(LoadLevel::Empty),
                Just(LoadLevel::Loaded),
                Just(LoadLevel::Full),
                Just(LoadLevel::Overloaded),
            ]
        }

        fn action(floors: u8) -> impl Strategy<Value = Action> {
            let sensor = prop_oneof![Just(VaneSensor::Left), Just(VaneSensor::Right)];
            let sensor_fault = prop_oneof![
                Just(SensorFault::None),
                Just(SensorFault::StuckOn),
                Just(SensorFault::StuckOff)
            ];
            prop_oneof![
                (button(floors), duration_ns(10_000_000_000))
                    .prop_map(|(button, hold)| Action::Press { button, hold }),
                load().prop_map(Action::Load),
                any::<bool>().prop_map(|closed| Action::Door { closed }),
                (-10_000.0..=10_000.0f64)
                    .prop_filter("non-zero", |mm| *mm != 0.0)
                    .prop_map(|mm| Action::Crank { mm }),
                Just(Action::Reset),
                Just(Action::Rescue),
                Just(Action::Ack),
                (1..=31u8).prop_map(|slave| Action::Fault(Fault::SlaveOffline { slave })),
                (1..=31u8).prop_map(|slave| Action::Fault(Fault::SlaveOnline { slave })),
                duration_ns(60_000_000_000)
                    .prop_map(|duration| Action::Fault(Fault::PowerFail { duration })),
                duration_ns(60_000_000_000)
                    .prop_map(|duration| Action::Fault(Fault::SafeLinkDrop { duration })),
                (sensor, sensor_fault)
                    .prop_map(|(sensor, fault)| Action::Fault(Fault::Vane { sensor, fault })),
            ]
        }

        prop_compose! {
            fn event(floors: u8)(at in 0..=3_600_000_000_000u64, action in action(floors))
                -> ScenarioEvent {
                ScenarioEvent { at: SimTime::from_nanos(at), action, line: 0 }
            }
        }

        prop_compose! {
            fn lift()(floors in 2..=24u8)(
                floors in Just(floors),
                start in start_range_mm(floors),
                events in proptest::collection::vec(event(floors), 0..12),
            ) -> (u8, f64, Vec<ScenarioEvent>) {
                (floors, start, events)
            }
        }

        prop_compose! {
            fn scenario()(
                name in any::<String>(),
                seed in any::<u64>(),
                duration in duration_ns(36_000_000_000_000),
                collective in any::<bool>(),
                (floors, start_mm, events) in lift(),
                load in load(),
                door_closed in any::<bool>(),
                pulse_error_rate in prop_oneof![Just(0.0), Just(1.0), 0.0..=1.0f64],
                extra_slaves in 0..=20u8,
                scan in PLC_SCAN_RANGE.start().as_nanos()..=PLC_SCAN_RANGE.end().as_nanos(),
                power_on_reset in any::<bool>(),
            ) -> Scenario {
                Scenario {
                    name,
                    seed,
                    duration,
                    algorithm: if collective { Algorithm::Collective } else { Algorithm::Fifo },
                    floors,
                    start_mm,
                    load,
                    door_closed,
                    pulse_error_rate,
                    extra_slaves,
                    plc_scan: SimDuration::from_nanos(scan),
                    power_on_reset,
                    events,
                }
            }
        }

        proptest! {
            #[test]
            fn to_toml_reads_back_to_an_equal_scenario(sc in scenario()) {
                let text = sc.to_toml();
                let mut back = match Scenario::from_toml("written.toml", &text) {
                    Ok(b) => b,
                    Err(e) => return Err(TestCaseError::fail(format!("{e}\n{text}"))),
                };
                back.events.iter_mut().for_each(|e| e.line = 0);
                let mut expected = sc;
                expected.events.sort_by_key(|e| e.at);
                prop_assert_eq!(back, expected, "{}", text);
            }
        }

        #[test]
        fn the_written_scenario_files_are_readable() {
            let sc = Scenario::from_toml("demo.toml", include_str!("../../scenarios/demo.toml"))
                .expect("demo");
            let text = sc.to_toml();
            assert!(
                text.contains("[[event]]\nat = \"15s\"\npress = \"cabin:3\"\n"),
                "{text}"
            );
            assert!(text.starts_with("name = \"demo\"\nseed = 1\n"), "{text}");
            let back = Scenario::from_toml("w.toml", &text).expect("back");
            assert_eq!(back.events.len(), sc.events.len());
        }
    }

    #[test]
    fn the_start_range_is_the_shaft_between_the_mechanical_ends() {
        // Sensors 60 mm beyond the end floors, the ends 80 mm further (SPEC §4).
        assert_eq!(start_range_mm(4), -140.0..=1340.0);
        assert_eq!(start_range_mm(2), -140.0..=540.0);
        let at = |mm: f64| format!("[lift]\nfloors = 2\nstart_mm = {mm:?}\n");
        assert!(Scenario::from_toml("t.toml", &at(540.0)).is_ok());
        assert!(Scenario::from_toml("t.toml", &at(-140.0)).is_ok());
        assert!(
            Scenario::from_toml("t.toml", &at(-70.0)).is_ok(),
            "beyond the sensor"
        );
        assert!(err(&at(540.5)).contains("(-140..540 mm)"));
        assert!(err(&at(-140.5)).contains("lift.start_mm"));
    }

    #[test]
    fn the_demo_is_valid() {
        let text = include_str!("../../scenarios/demo.toml");
        let s = Scenario::from_toml("demo.toml", text).expect("demo");
        assert!(!s.events.is_empty());
        assert_eq!(Scenario::demo(), Ok(s));
    }
}
