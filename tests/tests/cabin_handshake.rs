//! The cabin button handshake of table 4.7 of the lift thesis on the whole rig: K in the PLC's
//! request, echoed by the panel (docs/lab-bus.md). The first word after power-on needs no
//! resynchronisation, no torn word is taken while the panel is off the bus, and words resume as
//! soon as it is back.

use asi_lift_tests::scenario;
use asi_phy::{SimDuration, SimTime};
use rig::rig::Rig;

fn at(s: f64) -> SimTime {
    SimTime::ZERO + SimDuration::from_secs_f64(s).expect("time")
}

/// Words the PLC took and dropped, and words it abandoned after a stall.
fn counts(rig: &Rig) -> (u32, u32, u32) {
    let p = rig.plc().expect("the built-in program").cabin_panel();
    (p.words().good(), p.words().bad(), p.restarts())
}

/// Runs the rig to `until`; returns the first moment at which `done` held, if any.
fn run_to(rig: &mut Rig, until: SimTime, mut done: impl FnMut(&Rig) -> bool) -> Option<SimTime> {
    let mut first = None;
    while let Some(t) = rig.step_until(until) {
        if first.is_none() && done(rig) {
            first = Some(t);
        }
    }
    first
}

#[test]
fn the_panel_word_survives_power_on_and_a_slave_drop_out() {
    let mut rig = Rig::new(scenario("lost-cabin-slave")).expect("rig");
    // Power-on: the PLC starts with the K that differs from the D3 it sees, so the first word
    // is the first 14 steps (one per 10 ms scan) after the bus runs, with no stall.
    let first = run_to(&mut rig, at(19.9), |r| counts(r).0 >= 1).expect("a first word");
    assert!(first < at(0.2), "first word at {first}");
    let (good, bad, restarts) = counts(&rig);
    assert_eq!((bad, restarts), (0, 0));
    // One word per 140 ms from then on.
    assert!((138..=142).contains(&good), "{good} words by 19.9 s");

    // The panel is off the bus from 20 s to 40 s: the master zeroes its input nibble, which
    // looks like an echo of K = 0 every other request, yet no word completes.
    run_to(&mut rig, at(40.0), |_| false);
    let (good_before, bad, restarts_off) = counts(&rig);
    assert_eq!(bad, 0, "a torn word was taken while the panel was away");
    assert!(restarts_off > 0, "the PLC kept asking");

    // Back at 40 s (re-admitted about 85 ms later): the PLC starts a new word at the
    // configuration flag's change and the words come again, whole and right.
    let back = run_to(&mut rig, at(41.0), |r| counts(r).0 > good_before).expect("words again");
    assert!(back < at(40.3), "words resumed at {back}");
    let (_, bad, restarts) = counts(&rig);
    // (The stall count starts again when the PLC starts the new word.)
    assert_eq!((bad, restarts), (0, 0), "no stall after the return");
    let signals = *rig.lab().cabin_panel().expect("panel").signals();
    assert_eq!(
        rig.plc()
            .expect("the built-in program")
            .cabin_panel()
            .state(),
        Some(signals)
    );
}
