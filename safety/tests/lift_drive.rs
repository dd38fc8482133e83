//! `safety::lift_drive`: the lab lift's safe drive — the safety logic's requests, the lab
//! parameters in the lift's units, and what each function does to a car that the test moves
//! (docs/drive-safety.md §6).

use asi_phy::{SimDuration, SimTime};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use safety::drive::{DriveEventKind, Function, SlsLevel, Violation};
use safety::lift_drive::{LiftDriveConfig, LiftDriveInputs, LiftDriveSafety};

/// The lab lift: π · 79 mm / 25 per motor revolution; overtravel sensors 60 mm beyond floors
/// 1 and 4 (floor 4 at 1200 mm).
const MM_PER_REV: f64 = std::f64::consts::PI * 79.0 / 25.0;
const OVERTRAVEL: (f64, f64) = (-60.0, 1260.0);
/// The safety scan.
const SCAN_MS: u64 = 1;

fn lab() -> LiftDriveConfig {
    LiftDriveConfig::lab(MM_PER_REV, OVERTRAVEL)
}

fn idle() -> LiftDriveInputs {
    LiftDriveInputs {
        estop_out: true,
        door_closed: true,
        initialising: false,
        init_down: false,
        creeping: false,
        reset: false,
        encoder: Some((400.0, 0.0)),
    }
}

/// A car the test moves at a velocity it sets, integrated per 1 ms scan, under the monitor.
struct Car {
    safety: LiftDriveSafety,
    now_ms: u64,
    position_mm: f64,
    velocity_mm_s: f64,
    inputs: LiftDriveInputs,
    torque_off_at: Option<u64>,
    trips: Vec<(u64, Violation)>,
}

impl Car {
    fn at(position_mm: f64) -> Car {
        Car {
            safety: LiftDriveSafety::new(lab()).expect("the lab parameters are valid"),
            now_ms: 0,
            position_mm,
            velocity_mm_s: 0.0,
            inputs: idle(),
            torque_off_at: None,
            trips: Vec::new(),
        }
    }

    /// One scan; the car moves on at its velocity unless the torque is off, when the brake
    /// stops it at 500 mm/s².
    fn scan(&mut self) {
        self.inputs.encoder = Some((self.position_mm, self.velocity_mm_s));
        let now = SimTime::from_millis(self.now_ms);
        let out = self.safety.scan(now, &self.inputs).clone();
        for e in &out.events {
            if let DriveEventKind::Tripped(v) = e.kind {
                self.trips.push((self.now_ms, v));
            }
        }
        if !out.torque_enabled {
            self.torque_off_at.get_or_insert(self.now_ms);
            let dv = 500.0 * SCAN_MS as f64 / 1000.0;
            self.velocity_mm_s = if self.velocity_mm_s > 0.0 {
                (self.velocity_mm_s - dv).max(0.0)
            } else {
                (self.velocity_mm_s + dv).min(0.0)
            };
        }
        self.position_mm += self.velocity_mm_s * SCAN_MS as f64 / 1000.0;
        self.now_ms += SCAN_MS;
    }

    fn run_ms(&mut self, ms: u64) {
        for _ in 0..ms / SCAN_MS {
            self.scan();
        }
    }

    fn torque(&self) -> bool {
        self.safety.outputs().is_some_and(|o| o.torque_enabled)
    }
}

#[test]
fn the_lab_parameters_in_the_lifts_units() {
    let c = lab();
    assert!((c.mm_per_rev - 9.927).abs() < 1e-3);
    // The initialisation run (68.797 mm/s) is 6.93 rev/s, under SLS1's 7.5 rev/s; the creep
    // (20.550 mm/s) is 2.07 rev/s, under SLS2's 2.5 rev/s.
    assert!((c.rev(68.797) - 6.930).abs() < 1e-3);
    assert!((c.rev(20.550) - 2.070).abs() < 1e-3);
    assert_eq!(c.drive.sls[SlsLevel::L1.index()].speed_limit, 7.5);
    assert_eq!(c.drive.sls[SlsLevel::L2.index()].speed_limit, 2.5);
    // SLP 10 mm inside the sensors: −50 mm and 1250 mm.
    assert!((c.drive.slp.lower * MM_PER_REV + 50.0).abs() < 1e-9);
    assert!((c.drive.slp.upper * MM_PER_REV - 1250.0).abs() < 1e-9);
    // Standstill 0.5 rev = 4.96 mm, 0.2 rev/s = 1.99 mm/s.
    assert!((c.drive.standstill_position_tolerance * MM_PER_REV - 4.964).abs() < 1e-3);
    assert!(LiftDriveSafety::new(c).is_ok());
    let bad = {
        let mut cfg = lab();
        cfg.mm_per_rev = 0.0;
        cfg
    };
    let e = LiftDriveSafety::new(bad).expect_err("no scale");
    assert_eq!(e.field, "mm_per_rev");
}

#[test]
fn each_signal_requests_its_function_and_slp_is_always_requested() {
    let requested = |i: LiftDriveInputs| {
        let c = LiftDriveSafety::requests(&i);
        Function::ALL
            .into_iter()
            .filter(|f| c.requested(*f))
            .collect::<Vec<_>>()
    };
    assert_eq!(requested(idle()), vec![Function::Slp]);
    let cases = [
        (
            LiftDriveInputs {
                estop_out: false,
                ..idle()
            },
            Function::Ss1,
        ),
        (
            LiftDriveInputs {
                door_closed: false,
                ..idle()
            },
            Function::Sos,
        ),
        (
            LiftDriveInputs {
                initialising: true,
                ..idle()
            },
            Function::Sls(SlsLevel::L1),
        ),
        (
            LiftDriveInputs {
                creeping: true,
                ..idle()
            },
            Function::Sls(SlsLevel::L2),
        ),
        (
            LiftDriveInputs {
                init_down: true,
                ..idle()
            },
            Function::SdiNeg,
        ),
    ];
    for (inputs, f) in cases {
        let mut want = vec![f, Function::Slp];
        want.sort_by_key(|f| f.index());
        assert_eq!(requested(inputs), want, "{f}");
    }
    assert!(
        LiftDriveSafety::requests(&LiftDriveInputs {
            reset: true,
            ..idle()
        })
        .reset
    );
}

#[test]
fn ss1_at_standstill_takes_the_torque_off_after_enable_delay_and_early_limit() {
    let mut car = Car::at(400.0);
    car.run_ms(1_000);
    assert!(car.torque());
    car.inputs.estop_out = false;
    car.run_ms(1_000);
    // 100 ms enable delay + 500 ms early limit: off 600 ms after the STOP.
    assert_eq!(car.torque_off_at, Some(1_600));
    assert!(car.trips.is_empty());
    let status = car.safety.outputs().expect("scanned").status;
    assert!(status.of(Function::Ss1) && status.not_err_func);
    assert!(car
        .safety
        .torque_off_cause()
        .is_some_and(|c| c.contains("SS1")));
    // The STOP circuit restarted: the torque is back.
    car.inputs.estop_out = true;
    car.run_ms(2);
    assert!(car.torque());
}

#[test]
fn ss1_waits_for_the_car_to_stand_at_the_next_floor_then_half_a_second() {
    // STOP at 1 s while the car runs at the travel speed (59.4 mm/s); the controller runs on
    // for 3 s to the next floor and brakes (the test's car stops at once): torque off 0.5 s
    // after it stands, 3.5 s after the STOP.
    let mut car = Car::at(100.0);
    car.velocity_mm_s = 59.416;
    car.run_ms(1_000);
    car.inputs.estop_out = false;
    car.run_ms(3_000);
    assert!(car.torque());
    car.velocity_mm_s = 0.0;
    car.run_ms(1_000);
    assert_eq!(car.torque_off_at, Some(4_500));
    assert!(car.trips.is_empty());
}

#[test]
fn ss1_takes_the_torque_off_at_9_1_s_even_if_the_car_still_moves() {
    let mut car = Car::at(0.0);
    car.velocity_mm_s = 20.55;
    car.inputs.estop_out = false;
    car.run_ms(10_000);
    // 100 ms + 9 s: the bound of the STOP circuit's delayed output; not a trip.
    assert_eq!(car.torque_off_at, Some(9_100));
    assert!(car.trips.is_empty());
}

#[test]
fn sos_with_the_door_open_trips_on_a_runaway_within_the_speed_tolerance() {
    let mut car = Car::at(800.0);
    car.inputs.door_closed = false;
    car.run_ms(1_000);
    assert!(car.torque());
    // The converter runs away up at its ramp, 223.4 mm/s² (22.5 rev/s²).
    for _ in 0..200 {
        if car.torque() {
            car.velocity_mm_s += 223.4 * SCAN_MS as f64 / 1000.0;
        }
        car.scan();
    }
    let (at, v) = car.trips[0];
    assert!(matches!(
        v,
        Violation::SpeedAbove {
            function: Function::Sos,
            ..
        }
    ));
    // 0.2 rev/s = 1.985 mm/s is passed in the 9th scan of the runaway (9 × 0.2234 mm/s).
    assert_eq!(at, 1_008);
    assert!(!car.torque());
    assert_eq!(car.velocity_mm_s, 0.0);
    let moved = car.position_mm - 800.0;
    assert!(moved > 0.0 && moved < 0.05, "{moved} mm");
    assert!(car
        .safety
        .torque_off_cause()
        .is_some_and(|c| c.contains("SOS")));
}

#[test]
fn sos_trips_on_a_slow_creep_beyond_half_a_revolution() {
    let mut car = Car::at(400.0);
    car.inputs.door_closed = false;
    car.velocity_mm_s = -1.0; // under 2 mm/s: only the position tolerance catches it
    car.run_ms(6_000);
    let (at, v) = car.trips[0];
    assert!(matches!(
        v,
        Violation::MovedTooFar {
            function: Function::Sos,
            ..
        }
    ));
    // 0.5 rev = 4.9637 mm at 1 mm/s: the reading of 4.964 mm trips.
    assert_eq!(at, 4_964);
}

#[test]
fn slp_trips_just_inside_the_top_overtravel_sensor() {
    let mut car = Car::at(1_200.0);
    car.velocity_mm_s = 68.797;
    car.run_ms(2_000);
    let (at, v) = car.trips[0];
    assert!(matches!(v, Violation::OutsidePositionLimits { .. }));
    // 50 mm at 68.797 mm/s: 727 ms; the brake holds it 3.6 mm further, short of the sensor.
    assert_eq!(at, 727);
    assert!(car.position_mm < 1_260.0, "{}", car.position_mm);
    // A reset while the car is still outside trips again at once.
    car.inputs.reset = true;
    car.run_ms(2);
    assert_eq!(car.trips.len(), 2);
}

#[test]
fn sdi_n_trips_when_the_initialisation_run_goes_up() {
    let mut car = Car::at(600.0);
    car.inputs.initialising = true;
    car.inputs.init_down = true;
    car.velocity_mm_s = -68.797;
    car.run_ms(1_000);
    assert!(car.trips.is_empty());
    car.velocity_mm_s = 20.55;
    car.run_ms(1_000);
    let (at, v) = car.trips[0];
    assert!(matches!(
        v,
        Violation::WrongDirection {
            function: Function::SdiNeg,
            ..
        }
    ));
    // 4.964 mm up from the lowest point at 20.55 mm/s: 242 ms.
    assert_eq!(at, 1_242);
}

#[test]
fn sls_trips_above_the_creep_limit_after_its_window_and_reset_is_the_way_out() {
    let mut car = Car::at(400.0);
    car.inputs.creeping = true;
    car.velocity_mm_s = 20.55;
    car.run_ms(3_000);
    assert!(car.trips.is_empty());
    assert!(car
        .safety
        .outputs()
        .is_some_and(|o| o.status.of(Function::Sls(SlsLevel::L2))));
    car.velocity_mm_s = 30.0; // 3.02 rev/s > 2.5
    car.run_ms(10);
    assert_eq!(car.trips.len(), 1);
    assert!(matches!(
        car.trips[0].1,
        Violation::SpeedAbove {
            function: Function::Sls(SlsLevel::L2),
            ..
        }
    ));
    assert!(!car.torque());
    car.run_ms(1_000);
    assert!(!car.torque(), "latched until the reset");
    car.inputs.creeping = false;
    car.inputs.reset = true;
    car.run_ms(2);
    assert!(car.torque());
}

#[test]
fn an_encoder_that_cannot_be_read_trips() {
    let mut safety = LiftDriveSafety::new(lab()).expect("valid");
    let mut i = idle();
    safety.scan(SimTime::ZERO, &i);
    i.encoder = None;
    let out = safety.scan(SimTime::from_millis(1), &i);
    assert!(!out.torque_enabled);
    assert_eq!(safety.error(), Some(Violation::FeedbackLost));
    i.encoder = Some((f64::NAN, 0.0));
    i.reset = true;
    let out = safety.scan(SimTime::from_millis(2), &i);
    assert!(!out.torque_enabled, "a reading that is no number trips too");
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: RngSeed::Fixed(17),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// A car that runs at the lab's speeds inside the shaft, creeping where it creeps,
    /// standing where the door is open, never trips.
    #[test]
    fn normal_service_never_trips(
        legs in proptest::collection::vec((0u8..3, 200u64..3_000, proptest::bool::ANY), 1..12),
    ) {
        let mut car = Car::at(400.0);
        for (kind, ms, up) in legs {
            let sign = if up { 1.0 } else { -1.0 };
            car.inputs.door_closed = kind != 0;
            car.inputs.creeping = kind == 1;
            car.velocity_mm_s = match kind {
                0 => 0.0,
                1 => sign * 20.55,
                _ => sign * 59.416,
            };
            // Keep inside the shaft: turn back near the ends.
            let next = car.position_mm + car.velocity_mm_s * ms as f64 / 1000.0;
            if !(0.0..=1200.0).contains(&next) {
                car.velocity_mm_s = -car.velocity_mm_s;
            }
            car.run_ms(ms);
        }
        prop_assert!(car.trips.is_empty(), "{:?}", car.trips);
    }

    /// With the door open, any movement faster than 0.2 rev/s trips SOS in the first scan above.
    #[test]
    fn sos_trips_in_the_scan_the_speed_passes_the_tolerance(
        mm_s in 2.0f64..200.0, wait in 10u64..2_000,
    ) {
        let mut car = Car::at(400.0);
        car.inputs.door_closed = false;
        car.run_ms(wait);
        car.velocity_mm_s = mm_s;
        car.scan();
        prop_assert_eq!(car.trips.len(), 1);
        prop_assert_eq!(car.trips[0].0, wait);
    }
}

#[test]
fn scans_are_deterministic() {
    let run = || {
        let mut car = Car::at(400.0);
        car.inputs.door_closed = false;
        car.velocity_mm_s = 3.0;
        car.run_ms(100);
        (car.trips.clone(), car.position_mm.to_bits())
    };
    assert_eq!(run(), run());
    let _ = SimDuration::ZERO;
}
