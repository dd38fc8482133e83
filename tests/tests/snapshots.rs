//! Snapshots of whole runs: the readable log of the built-in demo and its JSON report. A change
//! in timing, in the bus or in the controller shows up here as a diff to review
//! (`INSTA_UPDATE=always cargo test -p asi-lift-tests --test snapshots`, then read the .snap).

use asi_lift::scenario::Scenario;
use asi_lift_tests::run;

#[test]
fn demo_log() {
    insta::assert_snapshot!(run(Scenario::demo()).to_text());
}

#[test]
fn demo_report_json() {
    insta::assert_snapshot!(run(Scenario::demo()).to_json());
}
