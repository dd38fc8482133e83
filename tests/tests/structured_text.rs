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
