//! Reading a scenario file: the TOML's shape (serde, with spans), then each section checked
//! in its own step, every error named by file, line and field.

use super::traffic::{Pattern, Traffic, MAX_PER_MINUTE};
use super::{
    start_range_mm, Action, Fault, Scenario, ScenarioError, ScenarioEvent, DEFAULT_HOLD,
    PLC_SCAN_RANGE,
};
use asi_phy::{PulseErrorRate, SimDuration, SimTime};
use controller::Algorithm;
use lift_model::config::{MAX_FLOORS, MIN_FLOORS};
use lift_model::{Button, LoadLevel, SensorFault, VaneSensor};
use serde::Deserialize;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

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
    drive: Option<RawDrive>,
    #[serde(default)]
    event: Vec<Spanned<RawEvent>>,
    #[serde(default)]
    traffic: Vec<Spanned<RawTraffic>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTraffic {
    pattern: Option<Spanned<String>>,
    per_minute: Option<Spanned<f64>>,
    seed: Option<u64>,
    start: Option<Spanned<String>>,
    duration: Option<Spanned<String>>,
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
    master_mode: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawController {
    scan: Option<Spanned<String>>,
    program: Option<Spanned<String>>,
    library: Option<Spanned<Vec<String>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSafety {
    power_on_reset: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDrive {
    safe: Option<bool>,
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
    attend: Option<Spanned<bool>>,
    fault: Option<Spanned<RawFault>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFault {
    kind: Spanned<String>,
    slave: Option<Spanned<i64>>,
    duration: Option<Spanned<String>>,
    sensor: Option<Spanned<String>>,
    direction: Option<Spanned<String>>,
    rate: Option<Spanned<f64>>,
}

/// Turns byte offsets into lines and columns, and names errors.
pub(crate) struct Locator<'a> {
    file: &'a str,
    text: &'a str,
    /// The byte offset where each line begins, so that a place is found by a binary search
    /// (a file of 100,000 events loads in linear time).
    line_starts: Vec<usize>,
}

impl<'a> Locator<'a> {
    pub(crate) fn new(file: &'a str, text: &'a str) -> Locator<'a> {
        let line_starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        Locator {
            file,
            text,
            line_starts,
        }
    }

    /// Line and column (both from 1; the column in characters) of a byte offset.
    pub(crate) fn position(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        let line = self.line_starts.partition_point(|&s| s <= offset);
        let start = self.line_starts[line.saturating_sub(1)];
        let column = self
            .text
            .get(start..offset)
            .map_or(0, |l| l.chars().count())
            + 1;
        (line, column)
    }

    pub(crate) fn error(
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
            message: shorten_quotes(&message.into()),
        }
    }

    /// The one action of event `n` (at `span`), or an error naming the event: none (`kinds`
    /// lists what it may hold) or more than one.
    pub(crate) fn one_action<T>(
        &self,
        mut actions: Vec<T>,
        span: Range<usize>,
        n: usize,
        kinds: &str,
    ) -> Result<T, ScenarioError> {
        match actions.len() {
            1 => Ok(actions.remove(0)),
            0 => Err(self.error(
                Some(span),
                format!("event[{n}]"),
                format!("no action: give one of {kinds}"),
            )),
            _ => Err(self.error(
                Some(span),
                format!("event[{n}]"),
                "more than one action: give each its own [[event]]",
            )),
        }
    }

    /// The key written on the line of `offset`, with its table (`lift.floors`,
    /// `event[3].press`), for errors the TOML reader reports without it.
    pub(crate) fn key_at(&self, offset: usize) -> String {
        let (line_no, _) = self.position(offset);
        let line_text = |n: usize| -> &str {
            let start = self.line_starts[n - 1];
            self.text[start..].lines().next().unwrap_or("")
        };
        let line = line_text(line_no);
        let key = match line.split_once('=') {
            // A key of thousands of characters (a binary file) is named by its start.
            Some((k, _)) if !line.trim_start().starts_with('[') => {
                asi_phy::waveform::excerpt(k.trim()).into_owned()
            }
            _ => return String::new(),
        };
        // The table it is in: the nearest header above it.
        // An array of tables (`[[event]]`, `[[traffic]]`) is named with its index: the count
        // of its headers up to here.
        let mut count = 0;
        let mut table: Option<&str> = None;
        for n in (1..line_no).rev() {
            let l = line_text(n).trim_start();
            if let Some(h) = l.strip_prefix("[[") {
                let name = h.split("]]").next().unwrap_or("").trim();
                match table {
                    None => {
                        table = Some(name);
                        count = 1;
                    }
                    Some(t) if t == name => count += 1,
                    Some(_) => {}
                }
            } else if let Some(h) = l.strip_prefix('[') {
                if table.is_none() {
                    let name = h.split(']').next().unwrap_or("").trim();
                    return format!("{name}.{key}");
                }
            }
        }
        match table {
            Some(t) => format!("{t}[{count}].{key}"),
            None => key,
        }
    }
}

/// A message with every quoted excerpt of the user's text (between backticks or double
/// quotes) cut to a short one: a value of thousands of characters is named, not repeated.
fn shorten_quotes(message: &str) -> String {
    const KEEP: usize = 40;
    let mut out = String::with_capacity(message.len().min(400));
    let mut rest = message;
    while let Some(open) = rest.find(['`', '"']) {
        let q = rest[open..].chars().next().unwrap_or('`');
        out.push_str(&rest[..=open]);
        let inner = &rest[open + 1..];
        let Some(close) = inner.find(q) else {
            rest = inner;
            break;
        };
        let quoted = &inner[..close];
        let n = quoted.chars().count();
        if n > KEEP {
            let head: String = quoted.chars().take(KEEP).collect();
            out.push_str(&format!("{head}… ({n} characters)"));
        } else {
            out.push_str(quoted);
        }
        out.push(q);
        rest = &inner[close + 1..];
    }
    out.push_str(rest);
    out
}

pub(crate) fn duration(
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
    LoadLevel::from_name(s.get_ref()).ok_or_else(|| {
        loc.error(
            Some(s.span()),
            field,
            format!(
                "unknown load `{}`: use empty, loaded, full or overloaded",
                s.get_ref()
            ),
        )
    })
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

fn fault(
    loc: &Locator<'_>,
    field: &str,
    f: &Spanned<RawFault>,
    safe_drive: bool,
) -> Result<Fault, ScenarioError> {
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
    if !kind.starts_with("converter-runaway") {
        unused(raw.direction.is_some(), "direction")?;
    }
    if kind != "line-noise" {
        unused(raw.rate.is_some(), "rate")?;
    }
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
        "converter-runaway" | "converter-repaired" => {
            unused(raw.slave.is_some(), "slave")?;
            unused(raw.duration.is_some(), "duration")?;
            unused(raw.sensor.is_some(), "sensor")?;
            if kind == "converter-repaired" {
                unused(raw.direction.is_some(), "direction")?;
                return Ok(Fault::ConverterRepaired);
            }
            let d = raw.direction.as_ref().ok_or_else(|| {
                loc.error(
                    Some(f.span()),
                    format!("{field}.direction"),
                    format!("`{kind}` needs `direction = \"up\"` or `\"down\"`"),
                )
            })?;
            let up = match d.get_ref().as_str() {
                "up" => true,
                "down" => false,
                other => {
                    return Err(loc.error(
                        Some(d.span()),
                        format!("{field}.direction"),
                        format!("unknown direction `{other}`: use up or down"),
                    ))
                }
            };
            Ok(Fault::ConverterRunaway { up })
        }
        "encoder-failed" | "encoder-repaired" => {
            unused(raw.slave.is_some(), "slave")?;
            unused(raw.duration.is_some(), "duration")?;
            unused(raw.sensor.is_some(), "sensor")?;
            unused(raw.direction.is_some(), "direction")?;
            if !safe_drive {
                return Err(loc.error(
                    Some(raw.kind.span()),
                    format!("{field}.kind"),
                    format!(
                        "`{kind}` needs `[drive] safe = true`: the lab lift's only encoder is \
                         the safe drive's"
                    ),
                ));
            }
            Ok(if kind == "encoder-failed" {
                Fault::EncoderFailed
            } else {
                Fault::EncoderRepaired
            })
        }
        "line-noise" => {
            unused(raw.slave.is_some(), "slave")?;
            unused(raw.sensor.is_some(), "sensor")?;
            let d = dur()?;
            let r = raw.rate.as_ref().ok_or_else(|| {
                loc.error(
                    Some(f.span()),
                    format!("{field}.rate"),
                    format!("`{kind}` needs `rate = P`, the probability that a pulse is corrupted"),
                )
            })?;
            let rate = *r.get_ref();
            if !(rate > 0.0 && rate <= 1.0) {
                return Err(loc.error(
                    Some(r.span()),
                    format!("{field}.rate"),
                    format!("{rate}: a burst's rate is a probability above 0 and at most 1"),
                ));
            }
            Ok(Fault::LineNoise { rate, duration: d })
        }
        other => Err(loc.error(
            Some(raw.kind.span()),
            format!("{field}.kind"),
            format!(
                "unknown fault `{other}`: use slave-offline, slave-online, power-fail, safe-link-drop, \
                 vane-stuck-on, vane-stuck-off, vane-repaired, converter-runaway, converter-repaired, \
                 encoder-failed, encoder-repaired or line-noise"
            ),
        )),
    }
}

impl Scenario {
    /// Reads a scenario from TOML `text`; `file` names it in errors.
    pub fn from_toml(file: &str, text: &str) -> Result<Scenario, ScenarioError> {
        let loc = Locator::new(file, text);
        let raw = parse(&loc)?;
        let mut sc = Scenario::defaults();
        read_top(&loc, &raw, &mut sc)?;
        if let Some(l) = &raw.lift {
            read_lift(&loc, l, &mut sc)?;
        }
        if let Some(b) = &raw.bus {
            read_bus(&loc, b, &mut sc)?;
        }
        if let Some(c) = &raw.controller {
            read_controller(&loc, c, &mut sc)?;
        }
        if let Some(r) = raw.safety.as_ref().and_then(|s| s.power_on_reset) {
            sc.power_on_reset = r;
        }
        if let Some(d) = raw.drive.as_ref().and_then(|d| d.safe) {
            sc.safe_drive = d;
        }
        for (i, ev) in raw.event.iter().enumerate() {
            let event = read_event(&loc, i + 1, ev, sc.floors, sc.safe_drive)?;
            sc.events.push(event);
        }
        // Stable: events at the same time keep the file's order.
        sc.events.sort_by_key(|e| e.at);
        for (i, t) in raw.traffic.iter().enumerate() {
            let template = read_traffic(&loc, i + 1, t, &sc)?;
            sc.traffic.push(template);
        }
        Ok(sc)
    }
}

/// The file's TOML, in its shape, or the TOML reader's error at its place.
fn parse(loc: &Locator<'_>) -> Result<RawScenario, ScenarioError> {
    toml::from_str(loc.text).map_err(|e| {
        let span = e.span();
        let field = span
            .clone()
            .map(|s| loc.key_at(s.start))
            .unwrap_or_default();
        loc.error(span, field, e.message().trim().to_owned())
    })
}

/// The top-level settings: name, seed, duration, algorithm.
fn read_top(loc: &Locator<'_>, raw: &RawScenario, sc: &mut Scenario) -> Result<(), ScenarioError> {
    if let Some(n) = raw.name.clone() {
        sc.name = n;
    }
    if let Some(s) = raw.seed {
        sc.seed = s;
    }
    if let Some(d) = &raw.duration {
        sc.duration = duration(loc, "duration", d)?;
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
    Ok(())
}

/// `[lift]`: floors, start height, load, door.
fn read_lift(loc: &Locator<'_>, l: &RawLift, sc: &mut Scenario) -> Result<(), ScenarioError> {
    if let Some(f) = &l.floors {
        let v = *f.get_ref();
        if !(i64::from(MIN_FLOORS)..=i64::from(MAX_FLOORS)).contains(&v) {
            return Err(loc.error(
                Some(f.span()),
                "lift.floors",
                format!("{v}: the lift has {MIN_FLOORS}..{MAX_FLOORS} floors"),
            ));
        }
        // The plant could have more floors, but the rig wires the lab bus, whose floor
        // stations stop at four: refused here, with the file and line, rather than by the
        // controller when the rig is built.
        let stations = lab::address::FLOOR_STATIONS;
        if v > i64::from(stations) {
            return Err(loc.error(
                Some(f.span()),
                "lift.floors",
                format!(
                    "{v}: the lab bus has floor stations for {MIN_FLOORS}..{stations} floors \
                     (addresses 1..{stations})"
                ),
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
                    "{} mm lies outside the shaft between the mechanical ends ({}..{} mm)",
                    asi_phy::short_number(v),
                    range.start(),
                    range.end()
                ),
            ));
        }
        sc.start_mm = v;
    }
    if let Some(s) = &l.load {
        sc.load = load_level(loc, "lift.load", s)?;
    }
    if let Some(s) = &l.door {
        sc.door_closed = door(loc, "lift.door", s)?;
    }
    Ok(())
}

/// `[bus]`: line noise, extra slaves and the master's mode.
fn read_bus(loc: &Locator<'_>, b: &RawBus, sc: &mut Scenario) -> Result<(), ScenarioError> {
    if let Some(r) = &b.pulse_error_rate {
        let rate = PulseErrorRate::new(*r.get_ref())
            .map_err(|e| loc.error(Some(r.span()), "bus.pulse_error_rate", e.to_string()))?;
        sc.pulse_error_rate = rate.get();
    }
    if let Some(n) = &b.extra_slaves {
        let v = *n.get_ref();
        sc.extra_slaves = u8::try_from(v)
            .ok()
            .filter(|v| *v as usize <= lab::address::FREE.len())
            .ok_or_else(|| {
                loc.error(
                    Some(n.span()),
                    "bus.extra_slaves",
                    format!("{v}: the lab bus has room for 0..=20 more slaves"),
                )
            })?;
    }
    if let Some(m) = &b.master_mode {
        sc.master_mode = match m.get_ref().as_str() {
            "protected" => asi_master::Mode::Protected,
            "configuration" => asi_master::Mode::Configuration,
            other => {
                return Err(loc.error(
                    Some(m.span()),
                    "bus.master_mode",
                    format!("{other:?}: \"protected\" or \"configuration\""),
                ))
            }
        };
    }
    Ok(())
}

/// `[controller]`: the PLC scan, and the program if not the built-in one (a Structured Text
/// file, its path relative to the scenario file's directory) with its libraries (`library`,
/// a list of such files), read and compiled here so that a program that cannot run is
/// refused with the scenario.
fn read_controller(
    loc: &Locator<'_>,
    c: &RawController,
    sc: &mut Scenario,
) -> Result<(), ScenarioError> {
    if let Some(s) = &c.scan {
        sc.plc_scan = duration(loc, "controller.scan", s)?;
        if !PLC_SCAN_RANGE.contains(&sc.plc_scan) {
            return Err(loc.error(
                Some(s.span()),
                "controller.scan",
                "must lie within 1..20 ms: the cabin word takes 14 scans, and beyond \
                 20 ms a 300 ms press or the vane edge initialisation needs can pass \
                 unseen",
            ));
        }
    }
    let dir = Path::new(loc.file).parent().unwrap_or(Path::new(""));
    let libraries: Vec<PathBuf> = c
        .library
        .iter()
        .flat_map(|l| l.get_ref())
        .map(|l| dir.join(l))
        .collect();
    match (&c.program, &c.library) {
        (Some(p), _) => {
            let path = dir.join(p.get_ref());
            let (line, column) = loc.position(p.span().start);
            // Not through `Locator::error`: the program's own messages quote its source
            // lines, which must be shown whole.
            sc.program = Some(
                super::program::ProgramFile::read(&path, &libraries).map_err(|message| {
                    ScenarioError {
                        file: loc.file.to_owned(),
                        line,
                        column,
                        field: "controller.program".into(),
                        message,
                    }
                })?,
            );
        }
        (None, Some(l)) => {
            return Err(loc.error(
                Some(l.span()),
                "controller.library",
                "a library goes with a program: give `program` too",
            ))
        }
        (None, None) => {}
    }
    Ok(())
}

/// The `n`-th `[[event]]` (1-based): its time and its one action.
fn read_event(
    loc: &Locator<'_>,
    n: usize,
    ev: &Spanned<RawEvent>,
    floors: u8,
    safe_drive: bool,
) -> Result<ScenarioEvent, ScenarioError> {
    let field = |name: &str| format!("event[{n}].{name}");
    let span = ev.span();
    let e = ev.get_ref();
    let at = SimTime::ZERO + duration(loc, &field("at"), &e.at)?;
    let mut actions = Vec::new();
    if let Some(p) = &e.press {
        let b = button(loc, &field("press"), p, floors)?;
        let hold = match &e.hold {
            Some(h) => duration(loc, &field("hold"), h)?,
            None => DEFAULT_HOLD,
        };
        if hold.is_zero() {
            let h = e.hold.as_ref().map(|h| h.span());
            return Err(loc.error(h, field("hold"), "a press lasts longer than zero"));
        }
        actions.push(Action::Press { button: b, hold });
    } else if let Some(h) = &e.hold {
        return Err(loc.error(Some(h.span()), field("hold"), "`hold` belongs to a `press`"));
    }
    if let Some(l) = &e.load {
        actions.push(Action::Load(load_level(loc, &field("load"), l)?));
    }
    if let Some(d) = &e.door {
        actions.push(Action::Door {
            closed: door(loc, &field("door"), d)?,
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
        (&e.attend, "attend", Action::Attend),
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
        actions.push(Action::Fault(fault(loc, &field("fault"), f, safe_drive)?));
    }
    let action = loc.one_action(
        actions,
        span.clone(),
        n,
        "press, load, door, crank_mm, reset, rescue, ack, attend, fault",
    )?;
    let (line, _) = loc.position(span.start);
    Ok(ScenarioEvent { at, action, line })
}

/// The `n`-th `[[traffic]]` (1-based): a template of passengers (`scenario::traffic`).
fn read_traffic(
    loc: &Locator<'_>,
    n: usize,
    t: &Spanned<RawTraffic>,
    sc: &Scenario,
) -> Result<Traffic, ScenarioError> {
    let field = |name: &str| format!("traffic[{n}].{name}");
    let span = t.span();
    let raw = t.get_ref();
    let p = raw.pattern.as_ref().ok_or_else(|| {
        loc.error(
            Some(span.clone()),
            field("pattern"),
            "a traffic template needs `pattern = \"up-peak\"`, `\"down-peak\"` or `\"interfloor\"`",
        )
    })?;
    let pattern = Pattern::from_name(p.get_ref()).ok_or_else(|| {
        loc.error(
            Some(p.span()),
            field("pattern"),
            format!(
                "unknown pattern `{}`: use up-peak, down-peak or interfloor",
                p.get_ref()
            ),
        )
    })?;
    let r = raw.per_minute.as_ref().ok_or_else(|| {
        loc.error(
            Some(span.clone()),
            field("per_minute"),
            "a traffic template needs `per_minute = …`, its mean arrivals per minute",
        )
    })?;
    let per_minute = *r.get_ref();
    if !(per_minute.is_finite() && per_minute > 0.0 && per_minute <= MAX_PER_MINUTE) {
        return Err(loc.error(
            Some(r.span()),
            field("per_minute"),
            format!(
                "{}: the mean arrivals per minute lie above 0 and up to {MAX_PER_MINUTE}",
                asi_phy::short_number(per_minute)
            ),
        ));
    }
    let start = match &raw.start {
        Some(s) => duration(loc, &field("start"), s)?,
        None => SimDuration::ZERO,
    };
    if start >= sc.duration {
        let s = raw.start.as_ref().map(|s| s.span());
        return Err(loc.error(
            s,
            field("start"),
            format!(
                "{start}: the traffic starts at or after the scenario's end ({})",
                sc.duration
            ),
        ));
    }
    let length = match &raw.duration {
        Some(d) => {
            let v = duration(loc, &field("duration"), d)?;
            if v.is_zero() {
                return Err(loc.error(
                    Some(d.span()),
                    field("duration"),
                    "must be longer than zero",
                ));
            }
            Some(v)
        }
        None => None,
    };
    let (line, _) = loc.position(span.start);
    Ok(Traffic {
        pattern,
        per_minute,
        seed: raw.seed,
        start,
        duration: length,
        line,
    })
}
