//! Scenario files: what happens to the lift, and when (TOML; documented in README.md).
//!
//! A malformed file gets an error that names the file, the line and the field at fault;
//! unknown keys are errors, not silently ignored.

use asi_phy::{SimDuration, SimTime};
use controller::Algorithm;
use lift_model::{Button, LoadLevel, SensorFault, VaneSensor};
use serde::Deserialize;
use std::fmt;
use std::ops::Range;
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
                let top = (sc.floors as f64 - 1.0) * 400.0;
                // The overtravel sensors trip 60 mm beyond the end floors (SPEC §4).
                if !v.is_finite() || v < -59.0 || v > top + 59.0 {
                    return Err(loc.error(
                        Some(s.span()),
                        "lift.start_mm",
                        format!("{v} mm lies outside the travel between the overtravel sensors (-59..{} mm)", top + 59.0),
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
                    .filter(|v| *v as usize <= asi_master::lab::EXTRA_ADDRESSES.len())
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
                if sc.plc_scan < SimDuration::from_millis(1)
                    || sc.plc_scan > SimDuration::from_secs(1)
                {
                    return Err(loc.error(
                        Some(s.span()),
                        "controller.scan",
                        "must lie within 1 ms..1 s",
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
                0 => {
                    return Err(loc.error(
                        Some(span),
                        format!("event[{}]", i + 1),
                        "no action: give one of press, load, door, crank_mm, reset, ack, fault",
                    ))
                }
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
    pub fn demo() -> Scenario {
        let text = include_str!("../scenarios/demo.toml");
        match Scenario::from_toml("<built-in demo>", text) {
            Ok(s) => s,
            // The demo is checked by a test; this branch only keeps a broken build from
            // panicking.
            Err(_) => Scenario::defaults(),
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
            "t.toml:4:12: lift.start_mm: 9000 mm lies outside the travel between the overtravel sensors (-59..1259 mm)"
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

    #[test]
    fn the_demo_is_valid() {
        let text = include_str!("../scenarios/demo.toml");
        let s = Scenario::from_toml("demo.toml", text).expect("demo");
        assert!(!s.events.is_empty());
        assert_eq!(Scenario::demo(), s);
    }
}
