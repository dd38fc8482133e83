//! Stand scenario files (TOML, documented in README.md, "The teaching stand"): which function
//! the student selects on the HMI, the speed typed into the drive's field, and what the student
//! does when: the drive switched on or off, a new speed, the light curtain broken, the Reset.
//!
//! Read with the lift scenarios' machinery (`scenario::read`): every error names the file, the
//! line and the field; unknown keys are errors.

use crate::scenario::read::{duration, Locator};
use crate::scenario::ScenarioError;
use asi_phy::{SimDuration, SimTime};
use safety::drive::{Function, SlsLevel};
use serde::Deserialize;
use toml::Spanned;

/// The longest stand scenario: an hour of simulated time.
pub const MAX_DURATION: SimDuration = SimDuration::from_secs(3600);
/// The highest speed the stand's HMI accepts, rev/s (3000 min⁻¹, a small servomotor's rated
/// speed; the SafeMOTION thesis does not give the motor's data).
pub const MAX_SPEED: f64 = 50.0;
/// How long a hand stays in the light curtain's field unless `hold` says otherwise.
pub const DEFAULT_HOLD: SimDuration = SimDuration::from_millis(500);

/// The functions that have a page and a Zap/Vyp button on the stand's HMI (§4.2.1 of the SafeMOTION
/// thesis, `Function_Sel` 1..9), in that order.
pub const SELECTABLE: [Function; 9] = [
    Function::Sto,
    Function::Sos,
    Function::Ss1,
    Function::Ss2,
    Function::Sls(SlsLevel::L1),
    Function::Sls(SlsLevel::L2),
    Function::Sli,
    Function::SdiPos,
    Function::SdiNeg,
];

/// The name of `f` in a stand file (`sdi-p`), lower case.
pub fn function_name(f: Function) -> String {
    f.to_string().to_lowercase()
}

/// A stand scenario, checked.
#[derive(Clone, Debug, PartialEq)]
pub struct StandScenario {
    /// Its name, for the report.
    pub name: String,
    /// The function selected on the HMI (its Zap/Vyp button pressed): the light curtain
    /// requests it.
    pub function: Function,
    /// How long to simulate.
    pub duration: SimDuration,
    /// The drive page's speed field at the start, rev/s (signed: positive = Zap - P).
    pub speed: f64,
    /// The standard motion control also brakes to the safe drive's `speed_command_limit`. Off on
    /// the SafeMOTION thesis' stand, whose motion program knows nothing of the safety limits (§4).
    pub follows_limit: bool,
    /// The motor has a holding brake, applied whenever the torque is off. The SafeMOTION thesis'
    /// stand realises no SBC: without one the axis coasts.
    pub brake: bool,
    /// The events, in time order.
    pub events: Vec<StandEvent>,
}

/// One thing the student does.
#[derive(Clone, Debug, PartialEq)]
pub struct StandEvent {
    /// When.
    pub at: SimTime,
    /// What.
    pub action: StandAction,
    /// The line of the `[[event]]` in the file.
    pub line: usize,
}

/// What a stand event does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StandAction {
    /// Zap/Vyp Pohon: the drive on (`true`) or off.
    Drive(bool),
    /// A new value in the speed field, rev/s.
    Speed(f64),
    /// A hand in the light curtain's field for `hold`.
    BreakCurtain {
        /// How long the field stays broken.
        hold: SimDuration,
    },
    /// The lit Reset button.
    Reset,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStandScenario {
    name: Option<String>,
    function: Spanned<String>,
    duration: Spanned<String>,
    speed: Option<Spanned<f64>>,
    stand: Option<RawStand>,
    #[serde(default)]
    event: Vec<Spanned<RawEvent>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStand {
    follows_limit: Option<bool>,
    brake: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEvent {
    at: Spanned<String>,
    drive: Option<Spanned<String>>,
    speed: Option<Spanned<f64>>,
    curtain: Option<Spanned<String>>,
    hold: Option<Spanned<String>>,
    reset: Option<Spanned<bool>>,
}

fn speed(loc: &Locator<'_>, field: &str, s: &Spanned<f64>) -> Result<f64, ScenarioError> {
    let v = *s.get_ref();
    if v.is_finite() && v.abs() <= MAX_SPEED {
        Ok(v)
    } else {
        Err(loc.error(
            Some(s.span()),
            field,
            format!(
                "{} rev/s: the stand's speed field takes -{MAX_SPEED}..{MAX_SPEED} rev/s",
                asi_phy::short_number(v)
            ),
        ))
    }
}

impl StandScenario {
    /// Reads a stand scenario from TOML `text`; `file` names it in errors.
    pub fn from_toml(file: &str, text: &str) -> Result<StandScenario, ScenarioError> {
        let loc = Locator::new(file, text);
        let raw: RawStandScenario = toml::from_str(text).map_err(|e| {
            let span = e.span();
            let field = span
                .clone()
                .map(|s| loc.key_at(s.start))
                .unwrap_or_default();
            loc.error(span, field, e.message().trim().to_owned())
        })?;
        let f = &raw.function;
        let function = SELECTABLE
            .into_iter()
            .find(|s| function_name(*s) == f.get_ref().to_lowercase())
            .ok_or_else(|| {
                let names: Vec<String> = SELECTABLE.into_iter().map(function_name).collect();
                loc.error(
                    Some(f.span()),
                    "function",
                    format!(
                        "unknown function `{}`: the stand's HMI has {}",
                        f.get_ref(),
                        names.join(", ")
                    ),
                )
            })?;
        let d = duration(&loc, "duration", &raw.duration)?;
        if d.is_zero() || d > MAX_DURATION {
            return Err(loc.error(
                Some(raw.duration.span()),
                "duration",
                "must be longer than zero and at most 1 h",
            ));
        }
        let mut sc = StandScenario {
            name: raw.name.unwrap_or_else(|| file.to_owned()),
            function,
            duration: d,
            speed: match &raw.speed {
                Some(s) => speed(&loc, "speed", s)?,
                None => 0.0,
            },
            follows_limit: raw.stand.as_ref().and_then(|s| s.follows_limit) == Some(true),
            brake: raw.stand.as_ref().and_then(|s| s.brake) == Some(true),
            events: Vec::new(),
        };
        for (i, ev) in raw.event.iter().enumerate() {
            sc.events.push(read_event(&loc, i + 1, ev)?);
        }
        // Stable: events at the same time keep the file's order.
        sc.events.sort_by_key(|e| e.at);
        Ok(sc)
    }
}

/// The `n`-th `[[event]]` (1-based): its time and its one action.
fn read_event(
    loc: &Locator<'_>,
    n: usize,
    ev: &Spanned<RawEvent>,
) -> Result<StandEvent, ScenarioError> {
    let field = |name: &str| format!("event[{n}].{name}");
    let span = ev.span();
    let e = ev.get_ref();
    let at = SimTime::ZERO + duration(loc, &field("at"), &e.at)?;
    let mut actions = Vec::new();
    if let Some(d) = &e.drive {
        actions.push(StandAction::Drive(match d.get_ref().as_str() {
            "on" => true,
            "off" => false,
            other => {
                return Err(loc.error(
                    Some(d.span()),
                    field("drive"),
                    format!("unknown drive command `{other}`: use on or off (Zap/Vyp Pohon)"),
                ))
            }
        }));
    }
    if let Some(s) = &e.speed {
        actions.push(StandAction::Speed(speed(loc, &field("speed"), s)?));
    }
    if let Some(c) = &e.curtain {
        if c.get_ref() != "break" {
            return Err(loc.error(
                Some(c.span()),
                field("curtain"),
                format!(
                    "unknown curtain action `{}`: use break (a hand in the field; `hold` says how long)",
                    c.get_ref()
                ),
            ));
        }
        let hold = match &e.hold {
            Some(h) => duration(loc, &field("hold"), h)?,
            None => DEFAULT_HOLD,
        };
        if hold.is_zero() {
            let h = e.hold.as_ref().map(|h| h.span());
            return Err(loc.error(h, field("hold"), "a hand stays longer than zero"));
        }
        actions.push(StandAction::BreakCurtain { hold });
    } else if let Some(h) = &e.hold {
        return Err(loc.error(
            Some(h.span()),
            field("hold"),
            "`hold` belongs to `curtain = \"break\"`",
        ));
    }
    if let Some(r) = &e.reset {
        if !*r.get_ref() {
            return Err(loc.error(
                Some(r.span()),
                field("reset"),
                "`reset = false` does nothing; write `reset = true`",
            ));
        }
        actions.push(StandAction::Reset);
    }
    let action = loc.one_action(actions, span.clone(), n, "drive, speed, curtain, reset")?;
    let (line, _) = loc.position(span.start);
    Ok(StandEvent { at, action, line })
}
