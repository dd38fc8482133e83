//! A Structured Text program as the lab's PLC on the whole rig (`controller::structured`):
//! it reads and writes the process image through its located variables, and a hostile
//! program stops the PLC without hanging or crashing the simulator, the lift held safe.

use asi_lift_tests::{assert_no_violations, scenario};
use asi_phy::SimDuration;
use controller::structured::StProgram;
use controller::ProgramEventKind;
use rig::report::LogEvent;
use rig::{Report, Rig};
use st::run::FaultCause;

fn run(program: &str, seconds: u64) -> Report {
    let p = StProgram::compile("lift.st", program).unwrap_or_else(|e| panic!("{e}"));
    let mut sc = scenario("demo");
    sc.duration = SimDuration::from_secs(seconds);
    Rig::new(sc).expect("the rig").with_controller(p).run(None)
}

fn stopped(r: &Report) -> Option<(u32, FaultCause)> {
    r.log.iter().find_map(|l| match l.event {
        LogEvent::Controller(ProgramEventKind::PlcStopped { line, cause, .. }) => {
            Some((line, cause))
        }
        _ => None,
    })
}

/// A program that pulses the STOP circuit's restart every second through its agreed
/// variable and never moves the cabin: a run of 20 s with the demo's calls, no violation,
/// and the PLC never stops.
#[test]
fn a_program_runs_as_the_plc_without_faults() {
    let r = run(
        "PROGRAM Lift
VAR_GLOBAL END_VAR
VAR
  EStopOut : BOOL;
  Restart : BOOL;
  Overloaded : BOOL;
  scans : DINT;
  t : TON;
END_VAR
  scans := scans + 1;
  t(IN := NOT t.Q, PT := T#500ms);
  Restart := t.Q;
  Overloaded := FALSE;
END_PROGRAM",
        20,
    );
    assert_no_violations(&r);
    assert_eq!(stopped(&r), None);
    // It does not serve calls: it is no lift program.
    assert!(r.served.is_empty());
}

/// Hostile programs at their first scan: a division by zero and an endless loop stop the
/// PLC (outputs zero, the place reported), and the run goes on to its end, the lift safe.
#[test]
fn a_faulting_program_stops_the_plc_and_the_lift_stays_safe() {
    let r = run(
        "PROGRAM Lift
VAR n, z : INT; END_VAR
  n := 10 / z;
END_PROGRAM",
        10,
    );
    assert_no_violations(&r);
    assert_eq!(stopped(&r), Some((3, FaultCause::DivisionByZero)));

    let r = run(
        "PROGRAM Lift
VAR n : DINT; END_VAR
  WHILE TRUE DO n := n + 1; END_WHILE;
END_PROGRAM",
        10,
    );
    assert_no_violations(&r);
    assert!(matches!(stopped(&r), Some((_, FaultCause::Watchdog(_)))));
}

/// Hostile programs refused before the run: a huge array, recursion.
#[test]
fn hostile_programs_are_refused_before_the_run() {
    let huge = StProgram::compile(
        "huge.st",
        "PROGRAM P VAR a : ARRAY [1..100000, 1..100000] OF LREAL; END_VAR END_PROGRAM",
    )
    .expect_err("refused");
    assert!(huge.rendered.contains("more than the 1048576"), "{huge}");
    let deep = StProgram::compile(
        "deep.st",
        "FUNCTION F : INT VAR_INPUT n : INT; END_VAR F := F(n + 1); END_FUNCTION
PROGRAM P VAR x : INT; END_VAR x := F(0); END_PROGRAM",
    )
    .expect_err("refused");
    assert!(deep.rendered.contains("no recursion"), "{deep}");
}

/// A program that drives the converter through the image: run and up (slave 7, `%QX1.0`,
/// `%QX1.1`) with the travel set-point on slave 10 (`%QW68`) from 3 s to 4 s, then the
/// standstill set-point and no run: the cabin rises from where it stood, comes to rest, and no
/// invariant breaks.
#[test]
fn a_program_moves_the_cabin_through_the_image() {
    let r = run(
        "PROGRAM Lift
VAR
  EStopOut : BOOL;
  Restart : BOOL;
  run AT %QX1.0 : BOOL;
  up AT %QX1.1 : BOOL;
  speed AT %QW68 : WORD;
  pulse, start, travel : TON;
END_VAR
  pulse(IN := NOT pulse.Q, PT := T#1s);
  Restart := pulse.Q AND NOT EStopOut;
  start(IN := TRUE, PT := T#3s);
  travel(IN := start.Q, PT := T#1s);
  run := start.Q AND NOT travel.Q;
  up := run;
  IF run THEN speed := 10000; ELSE speed := 4000; END_IF;
END_PROGRAM",
        8,
    );
    assert_no_violations(&r);
    assert_eq!(stopped(&r), None);
    let moved = r.final_state.position_mm - 650.0;
    assert!(moved > 20.0, "the cabin rose {moved} mm");
    assert!(!r.final_state.moving, "and came to rest");
}

/// The guide's worked program (`examples/st/shuttle.st` on `controllers/lab.st`, run by
/// `examples/st/shuttle.toml`): four journeys between floors 1 and 2, held with the door open,
/// STOP dropping the call until a new press restarts the circuit; the displays show the
/// floor the cabin stands at; no violation.
#[test]
fn the_worked_shuttle_program_serves_its_calls_and_shows_its_floor() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let path = root.join("examples/st/shuttle.toml");
    let text = std::fs::read_to_string(&path).expect("the scenario");
    let sc = rig::Scenario::from_toml(&path.display().to_string(), &text)
        .unwrap_or_else(|e| panic!("{e}"));
    let mut rig = Rig::new(sc).expect("the rig");
    // At 15 s the cabin stands at floor 2: both stations and the cabin show floor 2.
    while rig
        .step_until(asi_phy::SimTime::from_millis(15_000))
        .is_some()
    {}
    for id in [
        lift_model::DisplayId::Floor(1),
        lift_model::DisplayId::Floor(2),
        lift_model::DisplayId::Cabin,
    ] {
        match rig.lift().display(id) {
            Some(lift_model::DisplayState::Showing(w)) => {
                assert_eq!((w.floor, w.moving, w.fault), (2, false, false), "{id:?}")
            }
            other => panic!("{id:?} shows {other:?}"),
        }
    }
    let r = rig.run(None);
    assert_no_violations(&r);
    let floors: Vec<u8> = r.arrivals.iter().map(|a| a.floor).collect();
    assert_eq!(floors, [2, 1, 2, 1]);
    // Held with the door open from 22 s to 25 s: at floor 1 only after 25 s.
    assert!(r.arrivals[1].at_s > 25.0, "{:?}", r.arrivals[1]);
    // STOP at 42 s: K1 opens once; the cabin reaches floor 2 only after the press at 55 s.
    assert_eq!(r.safety.trips.first().map(|t| t.at_s), Some(42.0));
    assert!(
        r.safety
            .trips
            .iter()
            .all(|t| (42.0..=51.1).contains(&t.at_s)),
        "only the STOP and its K1: {:?}",
        r.safety.trips
    );
    assert!(r.arrivals[2].at_s > 55.0, "{:?}", r.arrivals[2]);
    assert_eq!(
        r.controller.as_deref(),
        Some(root.join("examples/st/shuttle.st").to_str().expect("UTF-8"))
    );
}

/// `asi-lift timing --controller`: the reference program timed on the lab bus gives the
/// built-in program's figures, latency by latency (the study reads the state, floor, target
/// and calls every controller may tell), but the cabin panel's word, which only the built-in
/// program counts; a program that does not tell its state is refused with the reason.
#[test]
fn the_timing_study_times_the_reference_program_as_the_built_in_one() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let program = rig::scenario::program::ProgramFile::read(
        &root.join("controllers/lift.st"),
        &[root.join("controllers/lab.st")],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let opts = |program| {
        let mut o = rig::timing::TimingOptions::default();
        o.duration = SimDuration::from_secs(5);
        o.samples = 4;
        o.program = program;
        o
    };
    let builtin = rig::timing::analyse(&opts(None)).expect("the built-in program timed");
    let st = rig::timing::analyse(&opts(Some(program))).expect("lift.st timed");
    let (mut b, s) = (builtin.lab.expect("lab"), st.lab.expect("lab"));
    assert_eq!(b.latencies.hall.len(), 4);
    assert_eq!(s.cabin_panel_word_ms.samples, 0);
    b.cabin_panel_word_ms = s.cabin_panel_word_ms.clone();
    assert_eq!(format!("{b:?}"), format!("{s:?}"));

    let silent = rig::scenario::program::ProgramFile::from_text(
        std::path::Path::new("idle.st"),
        "PROGRAM P\nVAR Restart : BOOL; END_VAR\n  Restart := TRUE;\nEND_PROGRAM\n",
    )
    .expect("compiles");
    let err = rig::timing::analyse(&opts(Some(silent))).expect_err("never ready");
    assert!(err.to_string().contains("does not tell its state"), "{err}");
}
