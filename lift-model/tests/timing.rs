//! Edges exact in time (docs/lift-plant.md): each vane edge and trip comes at the analytic crossing time,
//! rounded up to the first nanosecond at which the new level holds, for steady speed, ramps
//! and braking, and whatever step the caller takes.

use crate::common::*;
use asi_phy::{SimDuration, SimTime};
use lift_model::{DriveConfig, Lift, LiftConfig, PlantEvent, PlantEventKind, VaneSensor};
use proptest::prelude::*;

/// Asserts that `at` is the first nanosecond at or after the exact instant `exact_ns`
/// (allowing the float error of the test's own arithmetic, far below a nanosecond).
fn assert_rounded_up(at: SimTime, exact_ns: f64) {
    let at = at.as_nanos() as f64;
    assert!(
        at >= exact_ns - 1e-3 && at < exact_ns + 1.0 + 1e-3,
        "edge at {at} ns, exact crossing {exact_ns} ns"
    );
}

/// The sensor level an edge is about.
fn level(lift: &Lift, kind: &PlantEventKind) -> Option<bool> {
    match *kind {
        PlantEventKind::Vane { sensor, .. } => Some(lift.vane(sensor)),
        PlantEventKind::Overtravel { end, .. } => Some(!lift.overtravel_free(end)),
        _ => None,
    }
}

fn new_level(kind: &PlantEventKind) -> Option<bool> {
    match *kind {
        PlantEventKind::Vane { on, .. } => Some(on),
        PlantEventKind::Overtravel { tripped, .. } => Some(tripped),
        _ => None,
    }
}

#[test]
fn at_steady_speed_every_edge_is_the_rounded_up_crossing_time() {
    let mut lift = driving(0.0, true, 10_000);
    let ramp = run_to(&mut lift, |k| matches!(k, PlantEventKind::RampEnd { .. }));
    let (t_r, x_r) = (ramp.at.as_nanos() as f64, lift.position_mm());
    let v = DriveConfig::default().setpoint_velocity_mm_s(10_000);
    // Every edge from floor 1 to the top trip point, with the boundary it must lie on.
    let boundaries = [
        10.0, 40.0, 360.0, 390.0, 410.0, 440.0, 760.0, 790.0, 810.0, 840.0, 1160.0, 1190.0, 1210.0,
        1240.0, 1260.0,
    ];
    let trace = trace_until(&mut lift, secs(22.0));
    assert_eq!(trace.len(), boundaries.len());
    for ((e, _), b) in trace.iter().zip(boundaries) {
        assert_rounded_up(e.at, t_r + (b - x_r) / v * 1e9);
    }
}

/// A lift with a converter ramp of `ramp_hz_per_s`, at `position_mm`, driving up or down at
/// Rychlost 10000; with the cabin acceleration of that ramp in mm/s².
fn slow_ramp(ramp_hz_per_s: f64, position_mm: f64, up: bool) -> (Lift, f64) {
    let drive = {
        let mut cfg = DriveConfig::default();
        cfg.ramp_hz_per_s = ramp_hz_per_s;
        cfg
    };
    let a = drive.ramp_mm_s2();
    let config = {
        let mut cfg = LiftConfig::default();
        cfg.drive = drive;
        cfg.initial_position_mm = position_mm;
        cfg
    };
    (driving_with(config, up, 10_000), a)
}

#[test]
fn during_a_ramp_the_edges_solve_the_quadratic() {
    // A slow ramp (5 Hz/s) so that floor 1's tracks are left while accelerating:
    // x = a t² / 2 from rest, so x = b at t = √(2b/a).
    let (mut lift, a) = slow_ramp(5.0, 0.0, true);
    // The ramp to 13.3 Hz takes 2.66 s and 79 mm: both edges fall inside it.
    let right = run_to(&mut lift, |k| {
        matches!(k, PlantEventKind::Vane { on: false, .. })
    });
    assert_eq!(
        right.kind,
        PlantEventKind::Vane {
            sensor: VaneSensor::Right,
            on: false
        }
    );
    assert_rounded_up(right.at, (2.0 * 10.0 / a).sqrt() * 1e9);
    let left = run_to(&mut lift, |k| {
        matches!(k, PlantEventKind::Vane { on: false, .. })
    });
    assert_eq!(
        left.kind,
        PlantEventKind::Vane {
            sensor: VaneSensor::Left,
            on: false
        }
    );
    assert_rounded_up(left.at, (2.0 * 40.0 / a).sqrt() * 1e9);
}

#[test]
fn while_ramping_down_and_braking_the_edges_solve_the_quadratic() {
    // Down at 10000 with a slow ramp (10 Hz/s, 44.7 mm/s²); when the right sensor rises at
    // 440 mm (floor 2's long track) the set-point drops to 4000 and the cabin ramps to rest
    // over 39.5 mm, the left sensor rising at 410 mm on the way.
    let (mut lift, a) = slow_ramp(10.0, 600.0, false);
    run_to(&mut lift, |k| {
        matches!(k, PlantEventKind::Vane { on: true, .. })
    });
    let (t0, x0, v0) = (lift.now(), lift.position_mm(), lift.velocity_mm_s());
    assert!((x0 - 440.0).abs() < 1e-6 && v0 < 0.0);
    ok(lift.set_setpoint(t0, 4000));
    let left = run_to(&mut lift, |k| {
        matches!(k, PlantEventKind::Vane { on: true, .. })
    });
    assert_eq!(
        left.kind,
        PlantEventKind::Vane {
            sensor: VaneSensor::Left,
            on: true
        }
    );
    // x0 + v0 τ + a τ²/2 = 410 with v0 < 0 < a (slowing a downward run): the earlier root.
    let d = 410.0 - x0;
    let tau = (-v0 - (v0 * v0 + 2.0 * a * d).sqrt()) / a;
    assert_rounded_up(left.at, t0.as_nanos() as f64 + tau * 1e9);
    let stop = run_to(&mut lift, |k| matches!(k, PlantEventKind::Stopped { .. }));
    assert_rounded_up(stop.at, t0.as_nanos() as f64 + -v0 / a * 1e9);

    // Now the brake: K1 opens at full speed 2 mm above the left track's end at 1190.
    let mut lift = driving(0.0, true, 10_000);
    let v = DriveConfig::default().setpoint_velocity_mm_s(10_000);
    run_to(&mut lift, |k| matches!(k, PlantEventKind::RampEnd { .. }));
    let x = lift.position_mm();
    let t_open = lift.now() + SimDuration::from_secs_f64((1188.0 - x) / v).unwrap_or_default();
    advance(&mut lift, t_open);
    let x_open = lift.position_mm();
    ok(lift.set_contactor(t_open, false));
    let brake = 500.0;
    let edge = run_to(&mut lift, |k| matches!(k, PlantEventKind::Vane { .. }));
    assert_eq!(
        edge.kind,
        PlantEventKind::Vane {
            sensor: VaneSensor::Left,
            on: true
        }
    );
    let d = 1190.0 - x_open;
    let tau = (v - (v * v - 2.0 * brake * d).sqrt()) / brake;
    assert_rounded_up(edge.at, t_open.as_nanos() as f64 + tau * 1e9);
}

#[test]
fn at_each_edge_the_new_level_holds_and_one_nanosecond_earlier_the_old_one() {
    // The whole scenario below, jumping from edge to edge: ramps, steady running, braking,
    // a crash and a crank.
    let mut lift = lift_at(0.0);
    let inputs = inputs();
    let mut next_input = 0;
    let mut edges = 0;
    loop {
        while let Some(&(_, apply)) = inputs.get(next_input).filter(|i| i.0 == lift.now()) {
            let now = lift.now();
            apply(&mut lift, now);
            next_input += 1;
        }
        let due = [lift.next_event(), inputs.get(next_input).map(|i| i.0)];
        let Some(t) = due.into_iter().flatten().min().filter(|&t| t <= secs(50.0)) else {
            break;
        };
        let before = lift.clone();
        for e in advance(&mut lift, t) {
            let Some(new) = new_level(&e.kind) else {
                continue;
            };
            assert_eq!(level(&lift, &e.kind), Some(new), "{e}");
            if t > before.now() {
                let mut earlier = before.clone();
                advance(&mut earlier, t - SimDuration::from_nanos(1));
                assert_eq!(level(&earlier, &e.kind), Some(!new), "{e} 1 ns early");
            }
            edges += 1;
        }
    }
    assert_eq!(next_input, inputs.len());
    assert_eq!(edges, 18);
}

/// An input of the scenario, applied at its time.
type Input = fn(&mut Lift, SimTime);

/// A scenario with every kind of motion: ramp up, steady, a set-point change, a reversal
/// through zero, K1 opening (brake), K1 closing again mid-brake (flying restart), a crash
/// into the bottom end under power, K1 off, a crank back out, button presses.
fn inputs() -> Vec<(SimTime, Input)> {
    vec![
        (SimTime::ZERO, |l, t| {
            ok(l.set_contactor(t, true));
            ok(l.set_converter(t, true, true, 11_000));
            ok(l.press(
                t,
                lift_model::Button::Cabin(3),
                SimDuration::from_millis(250),
            ));
        }),
        (secs(7.3), |l, t| ok(l.set_setpoint(t, 6000))),
        (secs(9.1), |l, t| ok(l.set_run_direction(t, true, false))),
        (secs(12.0), |l, t| ok(l.set_setpoint(t, 11_000))),
        (secs(15.05), |l, t| ok(l.set_contactor(t, false))),
        (secs(15.1), |l, t| ok(l.set_contactor(t, true))),
        (secs(30.0), |l, t| ok(l.set_contactor(t, false))),
        (secs(31.0), |l, t| ok(l.crank(t, 150.0))),
        (secs(32.0), |l, t| {
            ok(l.press(t, lift_model::Button::Stop, SimDuration::from_secs(3)))
        }),
    ]
}

/// How a caller steps: a step length, and whether to land near the next edge instead.
#[derive(Clone, Copy, Debug)]
struct Step {
    ns: u64,
    /// 0: just the step; 1, 2, 3: land 1 ns before, exactly at, or 1 ns after the next
    /// edge, if that comes sooner.
    hug: u8,
}

/// Runs the scenario to 50 s, stepping by `steps` (cycled) between inputs, or from edge to
/// edge if `steps` is empty; returns every edge and the final state's bits.
fn run_scenario(steps: &[Step]) -> (Vec<PlantEvent>, u64, u64) {
    let mut lift = lift_at(0.0);
    let inputs = inputs();
    let end = secs(50.0);
    let mut events = Vec::new();
    let mut next_input = 0;
    let mut steps = steps.iter().cycle();
    loop {
        let now = lift.now();
        if let Some(&(_, apply)) = inputs.get(next_input).filter(|i| i.0 == now) {
            apply(&mut lift, now);
            next_input += 1;
            continue;
        }
        if now >= end {
            break;
        }
        let edge = lift.next_event().unwrap_or(end);
        let mut target = match steps.next() {
            None => edge,
            Some(step) => {
                let plain = now + SimDuration::from_nanos(step.ns);
                let near_edge = match step.hug {
                    1 => edge - SimDuration::from_nanos(1),
                    2 => edge,
                    3 => edge + SimDuration::from_nanos(1),
                    _ => plain,
                };
                plain.min(near_edge).max(now + SimDuration::from_nanos(1))
            }
        };
        if let Some(&(t, _)) = inputs.get(next_input) {
            target = target.min(t);
        }
        events.extend(advance(&mut lift, target.min(end)));
    }
    (
        events,
        lift.position_mm().to_bits(),
        lift.velocity_mm_s().to_bits(),
    )
}

#[test]
fn the_scenario_reaches_every_kind_of_edge() {
    let (events, _, _) = run_scenario(&[]);
    let has = |f: fn(&PlantEventKind) -> bool| events.iter().any(|e| f(&e.kind));
    assert!(has(|k| matches!(k, PlantEventKind::RampEnd { .. })));
    assert!(has(|k| matches!(k, PlantEventKind::Stopped { .. })));
    assert!(has(|k| matches!(k, PlantEventKind::Crash { .. })));
    assert!(has(|k| matches!(
        k,
        PlantEventKind::ConverterFault { fault: true }
    )));
    assert!(has(|k| matches!(
        k,
        PlantEventKind::Overtravel { tripped: true, .. }
    )));
    assert!(has(|k| matches!(
        k,
        PlantEventKind::Overtravel { tripped: false, .. }
    )));
    assert!(has(|k| matches!(k, PlantEventKind::Released { .. })));
    assert!(events.windows(2).all(|w| w[0].at <= w[1].at));
}

#[test]
fn one_big_step_gives_the_same_edges_as_jumping_from_edge_to_edge() {
    let reference = run_scenario(&[]);
    let big = Step {
        ns: u64::MAX / 4,
        hug: 0,
    };
    assert_eq!(run_scenario(&[big]), reference);
    let plc_scan = Step {
        ns: 10_000_000,
        hug: 0,
    };
    assert_eq!(run_scenario(&[plc_scan]), reference);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Any steps, from 0.1 ms to 3 s, some landing on, just before or just after an edge,
    /// give bit for bit the same edges, times and final state as jumping edge to edge.
    #[test]
    fn edges_do_not_depend_on_the_step_size(
        steps in prop::collection::vec(
            (
                prop_oneof![
                    100_000u64..1_000_000,
                    1_000_000u64..100_000_000,
                    100_000_000u64..3_000_000_000
                ],
                0u8..4
            )
                .prop_map(|(ns, hug)| Step { ns, hug }),
            1..20,
        )
    ) {
        let reference = run_scenario(&[]);
        prop_assert_eq!(run_scenario(&steps), reference);
    }
}
