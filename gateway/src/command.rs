//! The commands of the live view's page (the book, "Live view in the browser"): one JSON object
//! with one action, in the words of a scenario file's `[[event]]` (`{"press": "cabin:3"}`,
//! `{"fault": {"kind": "slave-offline", "slave": 7}}`, `{"load": "full"}`, `{"crank_mm": -20}`
//! …) and checked by the scenario reader itself, so that the page can do what a scenario can
//! and nothing else; and the one setting a scenario has outside its events that a teacher
//! changes while the lift runs, `{"line_noise": 0.0001}` (the `bus.pulse_error_rate`).
//! Beside them the run's controls, which change how the live run goes and not what the
//! simulation does: `{"pause": true}` and `{"pause": false}`, `{"speed": 2}` or
//! `{"speed": "max"}` (the bounds of `--speed`), `{"restart": true}` ([`RunControl`]).
//!
//! A command has no time: it happens at the moment the simulation has reached.

use crate::speed::{Speed, MAX_SPEED, MIN_SPEED};
use asi_phy::fault::FaultRates;
use asi_phy::PulseErrorRate;
use rig::report::{Actor, ClientLog};
use rig::scenario::Action;
use rig::{Rig, Scenario};

/// The longest command the page may send, bytes of JSON text.
pub const MAX_COMMAND_BYTES: usize = 4096;

/// A command from the page, checked.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// What a scenario event does.
    Act(Action),
    /// The line noise from now on: the probability that a pulse is corrupted.
    LineNoise(f64),
    /// A change to how the live run goes, not to the rig.
    Run(RunControl),
}

/// The page's controls of the live run: they change its pacing on the wall clock, or start
/// it again, and never what the simulation does (the live loop does them, not [`apply`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RunControl {
    /// `{"pause": true}`: simulated time stands still; `{"pause": false}`: it goes on from
    /// where it stood.
    Pause(bool),
    /// `{"speed": 2}`, `{"speed": "max"}`: the speed from now on, within the bounds of
    /// `--speed` ([`Speed::factor`]).
    Speed(Speed),
    /// `{"restart": true}`: the scenario again from its beginning, with the same seed.
    Restart,
}

/// The keys of the run's controls.
const RUN_KEYS: [&str; 3] = ["pause", "speed", "restart"];

/// The run control `key` with the value `v`; the error names the key and what it takes.
fn run_control(key: &str, v: &serde_json::Value) -> Result<RunControl, String> {
    match key {
        "pause" => v.as_bool().map(RunControl::Pause).ok_or_else(|| {
            format!("pause: {v}: expected true (simulated time stands still) or false (it goes on)")
        }),
        "restart" => match v.as_bool() {
            Some(true) => Ok(RunControl::Restart),
            Some(false) => Err("restart: `false` does nothing; send {\"restart\": true}".into()),
            None => Err(format!(
                "restart: {v}: expected true (the scenario again from its beginning)"
            )),
        },
        _ => {
            let expected = || {
                format!(
                    "speed: {v}: expected a factor from {MIN_SPEED} to {MAX_SPEED} (simulated seconds per wall second) or \"max\""
                )
            };
            match v {
                serde_json::Value::String(s) if s == "max" => Ok(RunControl::Speed(Speed::Max)),
                serde_json::Value::Number(n) => n
                    .as_f64()
                    .and_then(|x| Speed::factor(x).ok())
                    .map(RunControl::Speed)
                    .ok_or_else(expected),
                _ => Err(expected()),
            }
        }
    }
}

/// The lift a command is checked for: what the scenario reader needs to know of it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LiftShape {
    /// Its floors.
    pub floors: u8,
    /// It has the safe drive (and so an encoder that can fail).
    pub safe_drive: bool,
}

impl LiftShape {
    /// The shape of the lift `rig` runs.
    pub fn of(rig: &Rig) -> LiftShape {
        LiftShape {
            floors: rig.lift().config().floors,
            safe_drive: rig.drive_sample().is_some(),
        }
    }
}

/// Checks one command (a JSON object) for a lift of `shape`; the error says which key is at
/// fault and why, in the scenario reader's words.
pub fn parse(value: &serde_json::Value, shape: LiftShape) -> Result<Command, String> {
    let obj = value
        .as_object()
        .ok_or("a command is a JSON object with one action, such as {\"press\": \"cabin:3\"}")?;
    if let Some((key, v)) = RUN_KEYS.iter().find_map(|k| obj.get(*k).map(|v| (*k, v))) {
        if obj.len() > 1 {
            return Err(format!("{key}: give it alone, without other keys"));
        }
        return run_control(key, v).map(Command::Run);
    }
    if let Some(v) = obj.get("line_noise") {
        if obj.len() > 1 {
            return Err("line_noise: give it alone, without other keys".into());
        }
        let rate = v
            .as_f64()
            .ok_or("line_noise: a number, the probability that a pulse is corrupted (0..1)")?;
        return PulseErrorRate::new(rate)
            .map(|r| Command::LineNoise(r.get()))
            .map_err(|e| format!("line_noise: {e}"));
    }
    if obj.contains_key("at") {
        return Err("at: a command from the page happens now; it takes no time".into());
    }
    // The scenario reader checks the event: as a file of one event for a lift of `floors`.
    let event = toml::Value::try_from(value).map_err(|e| toml_value_error(&e))?;
    let mut table = toml::Table::new();
    table.insert("at".into(), toml::Value::String("0s".into()));
    if let toml::Value::Table(t) = event {
        table.extend(t);
    }
    let mut lift = toml::Table::new();
    lift.insert(
        "floors".into(),
        toml::Value::Integer(i64::from(shape.floors)),
    );
    let mut drive = toml::Table::new();
    drive.insert("safe".into(), toml::Value::Boolean(shape.safe_drive));
    let mut file = toml::Table::new();
    file.insert("lift".into(), toml::Value::Table(lift));
    file.insert("drive".into(), toml::Value::Table(drive));
    file.insert(
        "event".into(),
        toml::Value::Array(vec![toml::Value::Table(table)]),
    );
    let text = toml::to_string(&file).map_err(|e| e.to_string())?;
    let sc = Scenario::from_toml("command", &text).map_err(|e| {
        let field = e.field.strip_prefix("event[1].").unwrap_or(&e.field);
        let field = if field == "event[1]" { "" } else { field };
        if field.is_empty() {
            e.message
        } else {
            format!("{field}: {}", e.message)
        }
    })?;
    let event = sc
        .events
        .into_iter()
        .next()
        .ok_or("a command with no action: give one of press, load, door, crank_mm, reset, rescue, ack, attend, fault, line_noise, pause, speed, restart")?;
    Ok(Command::Act(event.action))
}

/// A JSON value TOML cannot hold (a `null`): said in the page's words.
fn toml_value_error(e: &toml::ser::Error) -> String {
    let text = e.to_string();
    if text.contains("None") || text.contains("null") || text.contains("unit") {
        "a command has no null values".into()
    } else {
        format!("not a command: {text}")
    }
}

/// Does `cmd` on `rig` now, or says why it cannot be done in the rig's state (the hand crank
/// with K1 closed). `seed` seeds the line noise.
pub fn apply(rig: &mut Rig, cmd: &Command, seed: u64) -> Result<(), String> {
    match cmd {
        Command::Act(action) => {
            if let Action::Crank { .. } = action {
                if rig.lift().k1_closed() {
                    return Err(
                        "crank_mm: K1 is closed: the hand crank turns only while the drive has no power"
                            .into(),
                    );
                }
            }
            rig.act_now(Actor::Web, action);
            Ok(())
        }
        Command::LineNoise(rate) => {
            let rates = match PulseErrorRate::new(*rate) {
                Ok(r) if r.get() > 0.0 => FaultRates::uniform(r),
                _ => FaultRates::NONE,
            };
            rig.lab_mut().bus_mut().set_line_faults(seed, rates);
            rig.log_now(Actor::Web, ClientLog::LineNoise(*rate));
            Ok(())
        }
        Command::Run(_) => Err(
            "pause, speed and restart change the live run, not the rig: the live loop does them"
                .into(),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lift_model::Button;
    use rig::scenario::Fault;
    use serde_json::json;

    /// The lab lift without the safe drive.
    const FOUR: LiftShape = LiftShape {
        floors: 4,
        safe_drive: false,
    };

    #[test]
    fn the_encoder_fails_only_on_a_lift_with_the_safe_drive() {
        let failed = json!({"fault": {"kind": "encoder-failed"}});
        let safe = LiftShape {
            safe_drive: true,
            ..FOUR
        };
        assert_eq!(
            parse(&failed, safe),
            Ok(Command::Act(Action::Fault(Fault::EncoderFailed)))
        );
        assert_eq!(
            parse(&failed, FOUR),
            Err("fault.kind: `encoder-failed` needs `[drive] safe = true`: the lab lift's only encoder is the safe drive's".into())
        );
    }

    #[test]
    fn commands_are_scenario_events() {
        assert_eq!(
            parse(&json!({"press": "cabin:3"}), FOUR),
            Ok(Command::Act(Action::Press {
                button: Button::Cabin(3),
                hold: rig::scenario::DEFAULT_HOLD
            }))
        );
        assert_eq!(
            parse(
                &json!({"fault": {"kind": "slave-offline", "slave": 7}}),
                FOUR
            ),
            Ok(Command::Act(Action::Fault(Fault::SlaveOffline {
                slave: 7
            })))
        );
        assert_eq!(
            parse(&json!({"line_noise": 0.001}), FOUR),
            Ok(Command::LineNoise(0.001))
        );
    }

    #[test]
    fn bad_commands_say_what_is_wrong() {
        let err = |v| parse(&v, FOUR).expect_err("an error");
        assert_eq!(
            err(json!({"press": "cabin:9"})),
            "press: floor `9` does not exist: the lift has floors 1..4"
        );
        assert!(err(json!({"jump": 1})).contains("unknown field `jump`"));
        assert!(err(json!({"press": "stop", "load": "full"})).contains("more than one action"));
        assert!(err(json!({})).contains("no action"));
        assert!(err(json!([1, 2])).contains("JSON object"));
        assert!(err(json!({"press": null})).contains("null"));
        assert!(err(json!({"at": "1s", "reset": true})).starts_with("at:"));
        assert!(err(json!({"line_noise": 2.0})).starts_with("line_noise:"));
        assert!(err(json!({"fault": {"kind": "slave-offline", "slave": 40}})).contains("1..31"));
    }

    #[test]
    fn the_run_controls_are_parsed_with_the_bounds_of_the_command_line() {
        let ok = |v| parse(&v, FOUR).expect("a command");
        assert_eq!(
            ok(json!({"pause": true})),
            Command::Run(RunControl::Pause(true))
        );
        assert_eq!(
            ok(json!({"pause": false})),
            Command::Run(RunControl::Pause(false))
        );
        assert_eq!(
            ok(json!({"restart": true})),
            Command::Run(RunControl::Restart)
        );
        assert_eq!(
            ok(json!({"speed": "max"})),
            Command::Run(RunControl::Speed(Speed::Max))
        );
        for x in [MIN_SPEED, 0.1, 0.5, 1.0, 2.0, 5.0, 10.0, MAX_SPEED] {
            assert_eq!(
                ok(json!({ "speed": x })),
                Command::Run(RunControl::Speed(Speed::Factor(x)))
            );
        }
        assert_eq!(
            ok(json!({"speed": 3})),
            Command::Run(RunControl::Speed(Speed::Factor(3.0)))
        );
    }

    #[test]
    fn bad_run_controls_say_which_key_and_what_it_takes() {
        let err = |v| parse(&v, FOUR).expect_err("an error");
        for bad in [
            json!(0),
            json!(-1),
            json!(0.0001),
            json!(1000.5),
            json!(1e300),
            json!("fast"),
            json!("2"),
            json!("MAX"),
            json!(null),
            json!(true),
            json!([1]),
            json!({"x": 1}),
        ] {
            let e = err(json!({ "speed": bad.clone() }));
            assert!(
                e.starts_with(&format!(
                    "speed: {bad}: expected a factor from 0.001 to 1000"
                )),
                "{bad}: {e}"
            );
        }
        for bad in [json!(1), json!("yes"), json!(null), json!({})] {
            assert!(err(json!({ "pause": bad })).starts_with("pause: "));
        }
        assert!(err(json!({"restart": false})).contains("does nothing"));
        assert!(err(json!({"restart": 1})).starts_with("restart: 1: expected true"));
        assert_eq!(
            err(json!({"pause": true, "speed": 2})),
            "pause: give it alone, without other keys"
        );
        assert_eq!(
            err(json!({"speed": 2, "press": "cabin:1"})),
            "speed: give it alone, without other keys"
        );
        assert!(err(json!({"resume": true})).contains("unknown field `resume`"));
        let mut rig = Rig::new(Scenario::defaults()).expect("a rig");
        assert!(apply(&mut rig, &Command::Run(RunControl::Restart), 0).is_err());
    }
}
