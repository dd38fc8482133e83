//! The order of the vane sensors' edges (docs/lift-plant.md; §6.4 and tables 6.3–6.5 of the lift
//! thesis): the floor-1 vane is turned so the left sensor meets its long track first going down, at
//! every other floor the right sensor does; going up the order mirrors; both on is the level zone.

use crate::common::*;
use asi_phy::SimDuration;
use lift_model::{LiftConfig, PlantEventKind, VaneSensor};

use VaneSensor::{Left, Right};

/// Within a millionth of a millimetre: an edge lies on its boundary to the travel of 1 ns.
fn near(x: f64, expected: f64) -> bool {
    (x - expected).abs() < 1e-6
}

/// The rising edges only, as `(sensor, position)`.
fn rising(edges: &[(VaneSensor, bool, f64)]) -> Vec<(VaneSensor, f64)> {
    edges
        .iter()
        .filter(|e| e.1)
        .map(|&(s, _, x)| (s, x))
        .collect()
}

fn assert_edges(actual: &[(VaneSensor, f64)], expected: &[(VaneSensor, f64)]) {
    assert_eq!(actual.len(), expected.len(), "{actual:?}");
    for (a, e) in actual.iter().zip(expected) {
        assert!(a.0 == e.0 && near(a.1, e.1), "{actual:?} vs {expected:?}");
    }
}

#[test]
fn down_onto_floor_1_the_left_sensor_rises_first_and_the_right_within_2_s_at_6000() {
    let mut lift = driving(400.0, false, 6000);
    let left = run_to(&mut lift, |k| {
        *k == PlantEventKind::Vane {
            sensor: Left,
            on: true,
        }
    });
    assert!(near(lift.position_mm(), 40.0));
    assert!(!lift.vane_right());
    let right = run_to(&mut lift, |k| {
        *k == PlantEventKind::Vane {
            sensor: Right,
            on: true,
        }
    });
    assert!(near(lift.position_mm(), 10.0));
    let gap = right.at - left.at;
    // 30 mm at 20.550 mm/s: 1.46 s, inside the lift thesis' 2 s timer.
    assert!(gap < SimDuration::from_secs(2), "{gap}");
    assert!((gap.as_secs_f64() - 30.0 / 20.550).abs() < 1e-3, "{gap}");
    assert!(lift.in_level_zone());
}

#[test]
fn the_thesis_initialisation_finds_floor_1_within_its_2_s_timer() {
    // Table 6.3 of the lift thesis: run down at 11000; on the left sensor rising, 6000 and a 2 s
    // timer; the right sensor rising while the timer runs means floor 1. Here the controller reacts
    // 50 ms late (AS-i handshake and PLC scan), then 6000 ramps down from 68.8 mm/s.
    let mut lift = driving(1000.0, false, 11_000);
    // Passing floors 3 and 2 the right sensor (long track) rises first, so the lift thesis'
    // routine does not mistake them for floor 1.
    for floor_level in [800.0, 400.0] {
        let first = run_to(&mut lift, |k| {
            matches!(k, PlantEventKind::Vane { on: true, .. })
        });
        assert_eq!(
            first.kind,
            PlantEventKind::Vane {
                sensor: Right,
                on: true
            }
        );
        assert!(near(lift.position_mm(), floor_level + 40.0));
        run_to(&mut lift, |k| {
            *k == PlantEventKind::Vane {
                sensor: Left,
                on: true,
            }
        });
    }
    let left = run_to(&mut lift, |k| {
        matches!(k, PlantEventKind::Vane { on: true, .. })
    });
    assert_eq!(
        left.kind,
        PlantEventKind::Vane {
            sensor: Left,
            on: true
        }
    );
    let react = left.at + SimDuration::from_millis(50);
    advance(&mut lift, react);
    ok(lift.set_setpoint(react, 6000));
    let right = run_to(&mut lift, |k| {
        *k == PlantEventKind::Vane {
            sensor: Right,
            on: true,
        }
    });
    assert!(right.at - left.at < SimDuration::from_secs(2));
    assert!(lift.vane_left() && lift.vane_right());
}

#[test]
fn down_through_every_floor_the_long_track_leads() {
    let mut lift = driving(1200.0, false, 10_000);
    // Stop once past floor 1's vane, before the overtravel zone.
    let trace = trace_until(&mut lift, secs(21.2));
    let edges = vane_edges(&trace);
    assert_edges(
        &rising(&edges),
        &[
            (Right, 840.0),
            (Left, 810.0),
            (Right, 440.0),
            (Left, 410.0),
            (Left, 40.0),
            (Right, 10.0),
        ],
    );
    // And every track is left at its lower end.
    let falling: Vec<(VaneSensor, f64)> = edges
        .iter()
        .filter(|e| !e.1)
        .map(|&(s, _, x)| (s, x))
        .collect();
    assert_edges(
        &falling,
        &[
            (Left, 1190.0),
            (Right, 1160.0),
            (Left, 790.0),
            (Right, 760.0),
            (Left, 390.0),
            (Right, 360.0),
            (Right, -10.0),
            (Left, -40.0),
        ],
    );
}

#[test]
fn up_through_every_floor_the_order_mirrors() {
    // From just above the bottom trip point, so floor 1 is met going up too.
    let mut lift = driving(-50.0, true, 10_000);
    let trace = trace_until(&mut lift, secs(21.2));
    assert_edges(
        &rising(&vane_edges(&trace)),
        &[
            (Left, -40.0),
            (Right, -10.0),
            (Right, 360.0),
            (Left, 390.0),
            (Right, 760.0),
            (Left, 790.0),
            (Right, 1160.0),
            (Left, 1190.0),
        ],
    );
}

#[test]
fn the_level_zone_is_where_both_sensors_are_on() {
    // Passing floor 3 down at a steady 59.416 mm/s: both on from 810 to 790 mm inclusive.
    let mut lift = driving(1200.0, false, 10_000);
    let trace = trace_until(&mut lift, secs(10.0));
    let mut in_zone = false;
    let mut zone = Vec::new();
    let (mut left, mut right) = (false, false);
    for (e, x) in &trace {
        if let PlantEventKind::Vane { sensor, on } = e.kind {
            match sensor {
                Left => left = on,
                Right => right = on,
            }
            if (left && right) != in_zone {
                in_zone = left && right;
                zone.push((e.at, *x));
            }
        }
    }
    assert_eq!(zone.len(), 2, "{zone:?}");
    assert!(near(zone[0].1, 810.0) && near(zone[1].1, 790.0 - 1e-7));
    let seconds = (zone[1].0 - zone[0].0).as_secs_f64();
    assert!((seconds - 20.0 / 59.416).abs() < 1e-4, "{seconds}");
}

#[test]
fn stopping_on_both_sensors_at_6000_ends_inside_the_level_zone() {
    // Table 6.4 of the lift thesis "Dobrždění → Aktuální patro": braking at 6000, then 4000 when
    // both sensors are on. Ramping down from 20.55 mm/s at 50 Hz/s covers under 1 mm.
    let mut lift = driving(800.0, false, 6000);
    run_to(&mut lift, |k| {
        *k == PlantEventKind::Vane {
            sensor: Left,
            on: true,
        }
    });
    assert!(lift.in_level_zone());
    let now = lift.now();
    ok(lift.set_setpoint(now, 4000));
    run_to(&mut lift, |k| matches!(k, PlantEventKind::Stopped { .. }));
    let x = lift.position_mm();
    assert!(x < 410.0 && x > 390.0, "{x}");
    assert!(lift.in_level_zone());
}

#[test]
fn any_number_of_floors_from_2_to_24_is_counted_the_same_way() {
    for floors in [2u8, 7, 24] {
        let config = {
            let mut cfg = LiftConfig::default();
            cfg.floors = floors;
            cfg
        };
        let mut lift = driving_with(config, true, 11_000);
        let top = f64::from(floors - 1) * 400.0;
        // Up from floor 1 at 68.797 mm/s until just past the top trip point.
        let trace = trace_until(&mut lift, secs((top + 70.0) / 68.797 + 0.3));
        let rises = rising(&vane_edges(&trace));
        // One pair per floor above floor 1, the right sensor (long track) first.
        let firsts: Vec<VaneSensor> = rises.iter().step_by(2).map(|r| r.0).collect();
        assert_eq!(firsts, vec![Right; usize::from(floors) - 1], "{floors}");
        let trips: Vec<f64> = trace
            .iter()
            .filter(|(e, _)| matches!(e.kind, PlantEventKind::Overtravel { tripped: true, .. }))
            .map(|(_, x)| *x)
            .collect();
        assert_eq!(trips.len(), 1, "{floors}");
        assert!(near(trips[0], top + 60.0), "{floors}: {trips:?}");
    }
}

#[test]
fn a_stuck_sensor_reads_its_stuck_value_and_reports_no_edges() {
    use lift_model::SensorFault;
    // Up from floor 1 at travel speed past floor 2 with the right sensor's wire broken.
    let mut lift = driving(0.0, true, 10_000);
    let now = lift.now();
    lift.set_vane_fault(now, Right, SensorFault::StuckOff)
        .expect("fault");
    assert!(
        !lift.vane_right(),
        "reads off at once, although level at floor 1"
    );
    assert!(
        lift.in_level_zone(),
        "the cabin is still level: the zone is physical"
    );
    let mut edges = Vec::new();
    let end = lift.now() + SimDuration::from_secs(10);
    while lift.now() < end {
        let next = lift.next_event().unwrap_or(end).min(end);
        for e in lift.advance_to(next).expect("advance") {
            if let PlantEventKind::Vane { sensor, on } = e.kind {
                edges.push((sensor, on));
            }
        }
        assert!(!lift.vane_right());
    }
    // Floor 1's left track ends, floor 2's left track begins: only the left sensor's edges.
    assert!(edges.iter().all(|(s, _)| *s == Left), "{edges:?}");
    assert!(edges.contains(&(Left, true)), "{edges:?}");
    // Repaired: it follows the vane again.
    let now = lift.now();
    lift.set_vane_fault(now, Right, SensorFault::None)
        .expect("repair");
    assert_eq!(lift.vane_right(), lift.vane(Right));
}
