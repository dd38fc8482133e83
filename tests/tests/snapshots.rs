//! Snapshots of whole runs: the readable log of the built-in demo and its JSON report. A change
//! in timing, in the bus or in the controller shows up here as a diff to review
//! (`INSTA_UPDATE=always cargo test -p asi-lift-tests --test snapshots`, then read the .snap).

use asi_lift_tests::{run, Shared};
use rig::report::{LogEvent, RigNote};
use rig::scenario::Scenario;

#[test]
fn demo_log() {
    insta::assert_snapshot!(run(Scenario::demo().expect("the demo")).to_text());
}

#[test]
fn demo_report_json() {
    insta::assert_snapshot!(run(Scenario::demo().expect("the demo"))
        .to_json()
        .expect("serialises"));
}

#[test]
fn demo_bus_trace_at_power_on() {
    use asi_phy::SimDuration;
    use rig::rig::Rig;
    let out = Shared::default();
    let mut rig = Rig::new(Scenario::demo().expect("the demo")).expect("rig");
    rig.trace_to(Box::new(out.clone()), asi_trace::trace::TraceFormat::Text);
    let report = rig.run(Some(SimDuration::from_millis(30)));
    assert!(report
        .log
        .iter()
        .all(|l| !matches!(l.event, LogEvent::Note(RigNote::TraceNotWritten(_)))));
    let text = String::from_utf8(out.bytes()).expect("utf-8");
    // Detection of all 32 addresses, activation of the 11 projected slaves, first cycles.
    assert!(text.lines().count() > 150, "{}", text.lines().count());
    insta::assert_snapshot!(text);
}
