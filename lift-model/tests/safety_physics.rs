//! Safety-relevant physics (docs/lift-plant.md, §6; §6.3 of the lift thesis): K1 and the brake, EDM
//! through the mirror contact, the hand crank, overtravel trips and crashes into the mechanical
//! ends.

use crate::common::*;
use asi_phy::{SimDuration, SimTime};
use lift_model::{DriveConfig, End, LiftConfig, PlantError, PlantEventKind, VaneSensor};

fn near(x: f64, expected: f64) -> bool {
    (x - expected).abs() < 1e-6
}

/// Steady cabin speed at `setpoint` (table 6.6 of the lift thesis), mm/s.
fn speed(setpoint: u16) -> f64 {
    DriveConfig::default().setpoint_velocity_mm_s(setpoint)
}

/// The lift running up at `setpoint` at constant speed, at the end of its ramp.
fn running_up(setpoint: u16, config: LiftConfig) -> lift_model::Lift {
    let mut lift = driving_with(config, true, setpoint);
    run_to(&mut lift, |k| matches!(k, PlantEventKind::RampEnd { .. }));
    lift
}

#[test]
fn k1_opening_stops_the_cabin_within_the_brake_distance() {
    for (setpoint, brake) in [(11_000u16, 500.0), (10_000, 500.0), (11_000, 250.0)] {
        let config = {
            let mut config = LiftConfig::default();
            config.drive = {
                let mut cfg = DriveConfig::default();
                cfg.brake_decel_mm_s2 = brake;
                cfg
            };
            config
        };
        let mut lift = running_up(setpoint, config);
        let t = lift.now() + SimDuration::from_millis(1234);
        advance(&mut lift, t);
        let (x, v) = (lift.position_mm(), lift.velocity_mm_s());
        ok(lift.set_contactor(t, false));
        assert!(!lift.converter_ready() && lift.acceleration_mm_s2() == -brake);
        let stop = run_to(&mut lift, |k| matches!(k, PlantEventKind::Stopped { .. }));
        let distance = lift.position_mm() - x;
        // v²/2a: 4.733 mm from 68.797 mm/s at 500 mm/s².
        assert!(near(distance, v * v / (2.0 * brake)), "{distance}");
        let seconds = (stop.at - t).as_secs_f64();
        assert!((seconds - v / brake).abs() < 1e-9, "{seconds}");
        assert_eq!(lift.velocity_mm_s(), 0.0);
        // At rest without power nothing more happens.
        assert_eq!(lift.next_event(), None);
    }
}

#[test]
fn k1_closing_mid_brake_catches_the_motor_without_a_jump() {
    let mut lift = running_up(11_000, LiftConfig::default());
    let t_open = lift.now() + SimDuration::from_millis(500);
    advance(&mut lift, t_open);
    ok(lift.set_contactor(t_open, false));
    let t_close = t_open + SimDuration::from_millis(40);
    advance(&mut lift, t_close);
    let v = lift.velocity_mm_s();
    assert!(near(v, speed(11_000) - 500.0 * 0.040), "{v}");
    ok(lift.set_contactor(t_close, true));
    assert_eq!(lift.velocity_mm_s(), v);
    assert!(lift.converter_ready());
    let back = run_to(&mut lift, |k| matches!(k, PlantEventKind::RampEnd { .. }));
    // From 48.8 mm/s back to 68.8 mm/s on the 50 Hz/s ramp.
    let ramp = DriveConfig::default().ramp_mm_s2();
    let expected = (speed(11_000) - v) / ramp;
    assert!(((back.at - t_close).as_secs_f64() - expected).abs() < 1e-6);
}

#[test]
fn the_k1_aux_mirror_contact_reports_a_weld_to_edm() {
    let mut lift = lift_at(0.0);
    let t = SimTime::ZERO;
    // Released: main open, mirror NC aux closed (EDM reads 1).
    assert!(!lift.k1_closed() && lift.k1_aux_closed());
    ok(lift.set_contactor(t, true));
    assert!(lift.k1_closed() && !lift.k1_aux_closed());
    ok(lift.set_converter(t, true, true, 10_000));
    // The contacts weld while closed; the coil drops but power stays and the cabin runs on.
    let t1 = secs(1.0);
    ok(lift.set_contactor_welded(t1, true));
    ok(lift.set_contactor(t1, false));
    assert!(lift.k1_closed() && !lift.k1_aux_closed());
    assert!(lift.converter_ready());
    advance(&mut lift, secs(2.0));
    assert_eq!(lift.velocity_mm_s(), speed(10_000));
    // Repaired, the contacts follow the coil (off): power gone, the brake acts.
    ok(lift.set_contactor_welded(secs(2.0), false));
    assert!(!lift.k1_closed() && lift.k1_aux_closed());
    assert!(lift.acceleration_mm_s2() < 0.0);
}

#[test]
fn a_weld_set_while_open_takes_hold_at_the_next_closing() {
    let mut lift = lift_at(0.0);
    ok(lift.set_contactor_welded(SimTime::ZERO, true));
    assert!(!lift.k1_closed() && lift.k1_aux_closed());
    ok(lift.set_contactor(secs(1.0), true));
    ok(lift.set_contactor(secs(2.0), false));
    assert!(lift.k1_closed() && !lift.k1_aux_closed());
}

#[test]
fn the_crank_moves_the_cabin_only_without_power() {
    let mut lift = lift_at(200.0);
    ok(lift.set_contactor(SimTime::ZERO, true));
    assert_eq!(
        lift.crank(secs(1.0), 50.0),
        Err(PlantError::CrankWhilePowered)
    );
    assert_eq!(lift.next_event(), None);
    assert_eq!(lift.position_mm(), 200.0);
    // A welded K1 is power too.
    ok(lift.set_contactor_welded(secs(1.0), true));
    ok(lift.set_contactor(secs(1.0), false));
    assert_eq!(
        lift.crank(secs(1.0), 50.0),
        Err(PlantError::CrankWhilePowered)
    );
    ok(lift.set_contactor_welded(secs(1.0), false));
    // Without power: 200 mm up at 10 mm/s takes 20 s and meets floor 2's vane on the way.
    ok(lift.crank(secs(2.0), 200.0));
    let right = run_to(&mut lift, |k| {
        matches!(k, PlantEventKind::Vane { on: true, .. })
    });
    assert_eq!(
        right.kind,
        PlantEventKind::Vane {
            sensor: VaneSensor::Right,
            on: true
        }
    );
    assert_eq!(right.at, secs(2.0 + 16.0)); // 360 mm reached exactly
    let stop = run_to(&mut lift, |k| matches!(k, PlantEventKind::Stopped { .. }));
    assert_eq!(stop.at, secs(22.0));
    assert_eq!(lift.position_mm(), 400.0);
    assert!(lift.in_level_zone());
}

#[test]
fn the_crank_is_refused_while_the_cabin_moves_or_for_a_nonsense_distance() {
    let mut lift = running_up(10_000, LiftConfig::default());
    let t = lift.now();
    ok(lift.set_contactor(t, false));
    assert!(matches!(
        lift.crank(t, 10.0),
        Err(PlantError::CrankWhileMoving { .. })
    ));
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let err = lift.crank(t, bad);
        assert!(
            matches!(err, Err(PlantError::CrankDistance { .. })),
            "{err:?}"
        );
    }
    let err = lift.crank(t, f64::NAN).err().map(|e| e.to_string());
    assert_eq!(
        err.as_deref(),
        Some("crank distance NaN mm is not a finite number")
    );
}

#[test]
fn closing_k1_ends_a_crank_turn_where_the_cabin_is() {
    let mut lift = lift_at(0.0);
    ok(lift.crank(SimTime::ZERO, 100.0));
    ok(lift.set_contactor(secs(3.0), true));
    // Flying restart from the crank speed, then a ramp to rest: the converter is not running.
    assert_eq!(lift.velocity_mm_s(), 10.0);
    run_to(&mut lift, |k| matches!(k, PlantEventKind::Stopped { .. }));
    assert!(lift.position_mm() > 30.0 && lift.position_mm() < 30.3);
    assert_eq!(lift.next_event(), None);
}

#[test]
fn the_overtravel_sensors_trip_at_their_zones() {
    // Down from floor 1 at 6000 with nothing to stop it: the bottom trips at −60 mm.
    let mut lift = driving(0.0, false, 6000);
    assert!(lift.overtravel_bottom_free() && lift.overtravel_top_free());
    let trip = run_to(&mut lift, |k| {
        matches!(k, PlantEventKind::Overtravel { .. })
    });
    assert_eq!(
        trip.kind,
        PlantEventKind::Overtravel {
            end: End::Bottom,
            tripped: true
        }
    );
    assert!(lift.position_mm() <= -60.0 && near(lift.position_mm(), -60.0));
    assert!(!lift.overtravel_bottom_free() && lift.overtravel_top_free());

    // Up from floor 4 at 6000: the top trips at 1200 + 60 mm.
    let mut lift = driving(1200.0, true, 6000);
    let trip = run_to(&mut lift, |k| {
        matches!(k, PlantEventKind::Overtravel { .. })
    });
    assert_eq!(
        trip.kind,
        PlantEventKind::Overtravel {
            end: End::Top,
            tripped: true
        }
    );
    assert!(lift.position_mm() >= 1260.0 && near(lift.position_mm(), 1260.0));
    assert!(!lift.overtravel_top_free());
}

#[test]
fn k1_dropping_at_the_trip_stops_the_cabin_short_of_the_buffer() {
    // docs/safety.md: the overtravel trip drops K1 at once (here with no reaction delay).
    let mut lift = driving(0.0, false, 11_000);
    run_to(&mut lift, |k| {
        matches!(k, PlantEventKind::Overtravel { .. })
    });
    let t = lift.now();
    ok(lift.set_contactor(t, false));
    run_to(&mut lift, |k| matches!(k, PlantEventKind::Stopped { .. }));
    // 68.797² / 1000 = 4.733 mm past the trip point, 75 mm short of the buffer.
    assert!(near(
        lift.position_mm(),
        -60.0 - speed(11_000).powi(2) / 1000.0
    ));
    assert!(lift.crashes().is_empty());
}

#[test]
fn a_drive_into_the_bottom_end_is_a_recorded_crash_and_trips_the_converter() {
    let mut lift = driving(0.0, false, 6000);
    let crash = run_to(&mut lift, |k| matches!(k, PlantEventKind::Crash { .. }));
    let PlantEventKind::Crash { end, impact_mm_s } = crash.kind else {
        unreachable!()
    };
    assert_eq!(end, End::Bottom);
    assert!(near(impact_mm_s, speed(6000)), "{impact_mm_s}");
    assert_eq!(lift.position_mm(), -140.0);
    assert_eq!(lift.velocity_mm_s(), 0.0);
    assert_eq!(lift.crashes().len(), 1);
    assert!(lift.crashes()[0].powered);
    // Under power the converter trips (stall) and stays tripped while powered ...
    assert!(lift.converter_fault() && !lift.converter_ready());
    assert_eq!(lift.next_event(), None);
    let t = lift.now() + SimDuration::from_secs(1);
    ok(lift.set_converter(t, true, true, 6000));
    assert_eq!(lift.velocity_mm_s(), 0.0);
    // ... until K1 drops. Then only the crank gets the cabin out (§6.3 of the lift thesis).
    ok(lift.set_contactor(t, false));
    assert!(!lift.converter_fault());
    assert_eq!(
        lift.crank(t, -5.0),
        Err(PlantError::CrankBlocked { end: End::Bottom })
    );
    ok(lift.crank(t, 100.0));
    let free = run_to(&mut lift, |k| {
        matches!(k, PlantEventKind::Overtravel { .. })
    });
    assert_eq!(
        free.kind,
        PlantEventKind::Overtravel {
            end: End::Bottom,
            tripped: false
        }
    );
    // From −140 to just past −60 at 10 mm/s.
    assert_eq!(free.at, t + SimDuration::from_nanos(8_000_000_001));
}

#[test]
fn braking_into_the_buffer_and_cranking_into_it_are_crashes_too() {
    // A weak brake (20 mm/s²) from 68.8 mm/s needs 118 mm: opening K1 at the trip point is
    // not enough. The impact speed is √(v² − 2·a·80 mm).
    let config = {
        let mut config = LiftConfig::default();
        config.initial_position_mm = 0.0;
        config.drive = {
            let mut cfg = DriveConfig::default();
            cfg.brake_decel_mm_s2 = 20.0;
            cfg
        };
        config
    };
    let mut lift = driving_with(config, false, 11_000);
    run_to(&mut lift, |k| {
        matches!(k, PlantEventKind::Overtravel { .. })
    });
    let (t, x, v) = (lift.now(), lift.position_mm(), lift.velocity_mm_s());
    ok(lift.set_contactor(t, false));
    let crash = run_to(&mut lift, |k| matches!(k, PlantEventKind::Crash { .. }));
    let expected = (v * v - 2.0 * 20.0 * (x + 140.0)).sqrt();
    assert_eq!(
        crash.kind,
        PlantEventKind::Crash {
            end: End::Bottom,
            impact_mm_s: lift.crashes()[0].impact_mm_s
        }
    );
    assert!((lift.crashes()[0].impact_mm_s - expected).abs() < 1e-5);
    assert!(!lift.crashes()[0].powered && !lift.converter_fault());

    // Cranked 500 mm up from floor 4: it stops at the top buffer, the rest is dropped.
    let mut lift = lift_at(1200.0);
    ok(lift.crank(SimTime::ZERO, 500.0));
    let crash = run_to(&mut lift, |k| matches!(k, PlantEventKind::Crash { .. }));
    assert_eq!(
        crash.kind,
        PlantEventKind::Crash {
            end: End::Top,
            impact_mm_s: 10.0
        }
    );
    assert_eq!(crash.at, secs(14.0) + SimDuration::from_nanos(1));
    assert_eq!(lift.position_mm(), 1340.0);
    assert_eq!(lift.next_event(), None);
    assert_eq!(
        lift.crank(secs(20.0), 1.0),
        Err(PlantError::CrankBlocked { end: End::Top })
    );
}

#[test]
fn an_injected_converter_fault_brakes_the_cabin_and_survives_a_power_cycle() {
    let mut lift = running_up(10_000, LiftConfig::default());
    let t = lift.now();
    ok(lift.set_converter_fault(t, true));
    assert!(lift.converter_fault() && !lift.converter_ready());
    assert_eq!(lift.acceleration_mm_s2(), -500.0);
    ok(lift.set_contactor(t, false));
    assert!(!lift.converter_fault());
    ok(lift.set_contactor(t, true));
    assert!(lift.converter_fault());
    ok(lift.set_converter_fault(t, false));
    assert!(lift.converter_ready());
}

#[test]
fn a_runaway_converter_drives_against_its_commands_until_k1_opens() {
    // At rest at floor 2 with power and the converter told to stand still.
    let mut lift = lift_at(400.0);
    ok(lift.set_contactor(SimTime::ZERO, true));
    ok(lift.set_converter(SimTime::ZERO, false, true, 4_000));
    assert_eq!(lift.velocity_mm_s(), 0.0);
    ok(lift.set_converter_runaway(SimTime::ZERO, Some(false)));
    assert_eq!(lift.converter_runaway(), Some(false));
    // It ramps down at the converter's ramp (50 Hz/s: 223.4 mm/s²) to the 20 mA frequency
    // (34.3 Hz): 153.230 mm/s, and shows neither a fault nor a lost ready.
    let top = speed(20_000);
    assert!((top - 153.230).abs() < 0.001, "{top}");
    assert!(lift.converter_ready() && !lift.converter_fault());
    let ramp_end = run_to(&mut lift, |k| matches!(k, PlantEventKind::RampEnd { .. }));
    assert_eq!(
        ramp_end.kind,
        PlantEventKind::RampEnd {
            velocity_mm_s: -top
        }
    );
    let ramp_mm_s2 = DriveConfig::default().ramp_mm_s2();
    assert!(((ramp_end.at - SimTime::ZERO).as_secs_f64() - top / ramp_mm_s2).abs() < 1e-6);
    // Commands change nothing.
    let t = lift.now();
    ok(lift.set_converter(t, true, true, 6_000));
    assert_eq!(lift.velocity_mm_s(), -top);
    assert_eq!(lift.acceleration_mm_s2(), 0.0);
    // Power off: the brake stops it; power back: it runs away again.
    ok(lift.set_contactor(t, false));
    assert_eq!(lift.acceleration_mm_s2(), 500.0);
    run_to(&mut lift, |k| matches!(k, PlantEventKind::Stopped { .. }));
    let t = lift.now();
    ok(lift.set_contactor(t, true));
    assert_eq!(lift.acceleration_mm_s2(), -ramp_mm_s2);
    // Repaired: it follows its commands again (run up at 6000 µA).
    ok(lift.set_converter_runaway(t, None));
    assert!(lift.velocity_mm_s() == 0.0 && lift.acceleration_mm_s2() == ramp_mm_s2);
}
