//! Controllers in the built-in program's place (`Rig::with_controller`): the contract of
//! `controller::Controller` as the rig keeps it.

use asi_lift_tests::{scenario, Shared};
use asi_phy::SimDuration;
use controller::plc::Plc;
use controller::{ControllerConfig, Outside};
use rig::{Rig, Scenario};

/// The scenario `name` shortened to `seconds`.
fn shortened(name: &str, seconds: u64) -> Scenario {
    let mut sc = scenario(name);
    sc.duration = SimDuration::from_secs(seconds);
    sc
}

/// The run's report and its bus trace as text.
fn run(mut rig: Rig) -> (rig::Report, Vec<u8>) {
    let trace = Shared::default();
    rig.trace_to(Box::new(trace.clone()), asi_trace::trace::TraceFormat::Text);
    (rig.run(None), trace.bytes())
}

/// The built-in program handed over as a controller runs exactly as the rig's own: the same
/// report and the same bus trace, on a scenario with calls and line noise.
#[test]
fn the_built_in_program_as_a_controller_is_the_rigs_own() {
    let name = "noise";
    let sc = shortened(name, 90);
    let cfg = {
        let mut cfg = ControllerConfig::default();
        cfg.floors = sc.floors;
        cfg.algorithm = sc.algorithm;
        cfg.scan = sc.plc_scan;
        cfg
    };
    let own = run(Rig::new(sc.clone()).expect("a rig"));
    let handed = run(Rig::new(sc)
        .expect("a rig")
        .with_controller(Plc::new(cfg).expect("a PLC")));
    assert!(own.0.arrivals.len() > 1, "{name}: {:?}", own.0.arrivals);
    assert_eq!(own.0, handed.0, "{name}");
    assert!(own.1 == handed.1, "{name}: the traces differ");
}

/// An outside controller that writes nothing leaves the cabin where it was powered on, and
/// the report tells no state of it; the rig finds it again as the controller it was given.
#[test]
fn an_outside_controller_that_does_nothing_moves_nothing() {
    let mut rig = Rig::new(shortened("demo", 20))
        .expect("a rig")
        .with_external_controller();
    assert!(rig.controller_mut::<Outside>().is_some());
    assert!(rig.plc().is_none());
    let report = rig.run(None);
    assert!(report.arrivals.is_empty(), "{:?}", report.arrivals);
    assert_eq!(report.final_state.state, None);
    assert_eq!(report.final_state.fifo_cabin, None);
    assert!((report.final_state.position_mm - 650.0).abs() < 1e-9);
    assert!(report.violations.is_empty(), "{:?}", report.violations);
}

/// A controller that does not tell which calls it serves (an outside one here) is judged by
/// the lift: a call pressed where the cabin stands level at rest is served at once; one
/// pressed at another floor is not served while the cabin does not go there.
#[test]
fn a_call_pressed_where_the_cabin_stands_is_served_at_once() {
    let text = "name = \"here\"\nduration = \"6s\"\n[lift]\nstart_mm = 0.0\n\
                [[event]]\nat = \"2s\"\npress = \"cabin:1\"\n\
                [[event]]\nat = \"3s\"\npress = \"hall-down:2\"\n";
    let sc = Scenario::from_toml("here.toml", text).expect("a scenario");
    let r = Rig::new(sc)
        .expect("a rig")
        .with_external_controller()
        .run(None);
    let served: Vec<(u8, f64, f64)> = r
        .served
        .iter()
        .map(|s| (s.floor, s.requested_at_s, s.served_at_s))
        .collect();
    assert_eq!(served, [(1, 2.0, 2.0)]);
}
