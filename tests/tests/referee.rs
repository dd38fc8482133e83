//! The second referee against the invariant watch (docs/safety.md, "What the judge calls a
//! hazard"): on every scenario file and on runs made to break the invariants, the referee,
//! which samples the plant alone, names no hazard the watch missed, and running it beside the
//! rig changes nothing of the run.

use asi_lift_tests::*;
use asi_phy::SimDuration;
use rig::referee::Referee;
use rig::report::ViolationKind;
use rig::rig::Rig;
use rig::scenario::Scenario;

/// Runs `sc` (to `until`) with the referee; the report, the kinds the referee called, and the
/// disagreements. The report must be the one of a run without the referee.
fn refereed(sc: Scenario, until: Option<SimDuration>) -> (rig::Report, Vec<ViolationKind>) {
    let plain = Rig::new(sc.clone()).expect("rig").run(until);
    let (report, referee) = Referee::run(Rig::new(sc).expect("rig"), until);
    assert_eq!(
        serde_json::to_string(&report).expect("json"),
        serde_json::to_string(&plain).expect("json"),
        "the referee changed the run of {}",
        report.scenario
    );
    let disagreements = referee.disagreements(&report);
    assert!(
        disagreements.is_empty(),
        "{}: {disagreements:?}\n{}",
        report.scenario,
        report.to_text()
    );
    let called = referee.called().iter().map(|(k, _)| *k).collect();
    (report, called)
}

fn kinds(r: &rig::Report) -> Vec<ViolationKind> {
    r.violations.iter().map(|v| v.kind).collect()
}

#[test]
fn the_referee_agrees_with_the_watch_on_every_scenario_file() {
    for name in crate::fast_path::SCENARIOS {
        let (r, called) = refereed(scenario(name), Some(SimDuration::from_secs(30)));
        assert!(called.is_empty(), "{name}: {called:?}");
        assert!(r.violations.is_empty(), "{name}: {:?}", r.violations);
    }
}

/// A crank turn that K1 takes over (the operator's reset while the cabin moves by hand, a
/// converter running away down): the cabin runs 1.3 m with the door open under power. Motion
/// under power is never by hand: the watch names it, and so does the referee (a watch that
/// counted the turn as by hand until the cabin rests named nothing here).
#[test]
fn a_crank_turn_taken_over_by_power_is_judged_by_both() {
    let sc = Scenario::from_toml(
        "crank taken over",
        r#"
duration = "20s"
[lift]
start_mm = 1270.0
door = "open"
[safety]
power_on_reset = false
[[event]]
at = "1s"
fault = { kind = "converter-runaway", direction = "down" }
[[event]]
at = "2s"
crank_mm = -40.0
[[event]]
at = "4s"
reset = true
"#,
    )
    .expect("scenario");
    let (r, called) = refereed(sc, None);
    assert_eq!(kinds(&r), [ViolationKind::DoorOpenMoving]);
    assert_eq!(called, [ViolationKind::DoorOpenMoving]);
    assert_eq!(r.safety.overtravel_reached.len(), 1, "{}", r.to_text());
    assert_eq!(r.safety.overtravel_reached[0].end, "bottom");
}

/// A converter that runs away with the door open, and one that runs away under STOP: both
/// judges name the hazard.
#[test]
fn runaways_with_the_door_open_and_under_stop_are_called_by_both() {
    let body = |events: &str| format!("duration = \"30s\"\n[lift]\nstart_mm = 0.0\n{events}");
    let door = body(
        "[[event]]\nat = \"15s\"\ndoor = \"open\"\n[[event]]\nat = \"16s\"\nfault = { kind = \"converter-runaway\", direction = \"up\" }\n",
    );
    let (r, called) = refereed(Scenario::from_toml("door", &door).expect("scenario"), None);
    assert_eq!(kinds(&r), [ViolationKind::DoorOpenMoving]);
    assert_eq!(called, [ViolationKind::DoorOpenMoving]);
    let stop = body(
        "[[event]]\nat = \"15s\"\npress = \"stop\"\nhold = \"10s\"\n[[event]]\nat = \"16s\"\nfault = { kind = \"converter-runaway\", direction = \"up\" }\n",
    );
    let (r, called) = refereed(Scenario::from_toml("stop", &stop).expect("scenario"), None);
    assert_eq!(kinds(&r), [ViolationKind::StopOverrun]);
    assert_eq!(called, [ViolationKind::StopOverrun]);
}
