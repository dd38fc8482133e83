//! A configuration the lift could not run with is rejected at construction, with an error
//! that names the field and the cause (docs/lift-plant.md: geometry all configurable, 2..24 floors).

use lift_model::{DriveConfig, Lift, LiftConfig, LiftConfigError, VaneSensor};

/// The error for `config`, which must be rejected, with its message.
fn rejected(config: LiftConfig) -> (LiftConfigError, String) {
    match Lift::new(config) {
        Ok(_) => panic!("configuration accepted"),
        Err(e) => {
            let message = e.to_string();
            (e, message)
        }
    }
}

fn with_drive(drive: DriveConfig) -> LiftConfig {
    {
        let mut cfg = LiftConfig::default();
        cfg.drive = drive;
        cfg
    }
}

#[test]
fn the_defaults_are_the_lab_lift_and_valid() {
    let config = LiftConfig::default();
    assert_eq!(config.validate(), Ok(()));
    assert_eq!(config.floors, 4);
    assert_eq!(config.floor_level_mm(4), Some(1200.0));
    assert_eq!(config.floor_level_mm(5), None);
    assert_eq!(
        config.vane_track_mm(VaneSensor::Left, 1),
        Some((-40.0, 40.0))
    );
    assert_eq!(
        config.vane_track_mm(VaneSensor::Right, 1),
        Some((-10.0, 10.0))
    );
    assert_eq!(
        config.vane_track_mm(VaneSensor::Left, 3),
        Some((790.0, 810.0))
    );
    assert_eq!(
        config.vane_track_mm(VaneSensor::Right, 3),
        Some((760.0, 840.0))
    );
    assert_eq!(config.trip_position_mm(lift_model::End::Top), 1260.0);
    assert_eq!(config.end_position_mm(lift_model::End::Bottom), -140.0);
}

#[test]
fn zero_one_or_too_many_floors_are_rejected() {
    for floors in [0u8, 1, 25, 255] {
        let (e, message) = rejected({
            let mut cfg = LiftConfig::default();
            cfg.floors = floors;
            cfg
        });
        assert_eq!(e, LiftConfigError::FloorCount { floors });
        assert!(message.starts_with(&format!("floors = {floors}: the lift needs 2 to 24 floors")));
    }
    for floors in [2u8, 24] {
        let config = {
            let mut cfg = LiftConfig::default();
            cfg.floors = floors;
            cfg
        };
        assert!(Lift::new(config).is_ok(), "{floors}");
    }
}

#[test]
fn a_negative_or_zero_pitch_is_rejected() {
    for pitch in [-400.0, 0.0, -0.0] {
        let (e, message) = rejected({
            let mut cfg = LiftConfig::default();
            cfg.floor_pitch_mm = pitch;
            cfg
        });
        assert_eq!(
            e,
            LiftConfigError::NotPositive {
                field: "floor_pitch_mm",
                value: pitch
            }
        );
        assert_eq!(
            message,
            format!("floor_pitch_mm = {pitch:?}: must be greater than zero")
        );
    }
}

#[test]
fn a_number_that_is_not_finite_is_rejected() {
    let (e, message) = rejected({
        let mut cfg = LiftConfig::default();
        cfg.long_track_half_mm = f64::NAN;
        cfg
    });
    assert!(matches!(
        e,
        LiftConfigError::NotFinite {
            field: "long_track_half_mm",
            ..
        }
    ));
    assert_eq!(message, "long_track_half_mm = NaN: not a finite number");
    let (_, message) = rejected({
        let mut cfg = LiftConfig::default();
        cfg.initial_position_mm = f64::INFINITY;
        cfg
    });
    assert_eq!(message, "initial_position_mm = inf: not a finite number");
    let (_, message) = rejected(with_drive({
        let mut cfg = DriveConfig::default();
        cfg.slip = f64::NAN;
        cfg
    }));
    assert_eq!(message, "drive.slip = NaN: not a finite number");
}

/// A change that breaks one field of a valid configuration.
type Breakage = fn(&mut LiftConfig);

#[test]
fn every_length_speed_and_rate_must_be_positive() {
    let cases: [(Breakage, &str); 9] = [
        (|c| c.short_track_half_mm = -10.0, "short_track_half_mm"),
        (|c| c.trip_beyond_floor_mm = 0.0, "trip_beyond_floor_mm"),
        (|c| c.end_beyond_trip_mm = -1.0, "end_beyond_trip_mm"),
        (|c| c.crank_speed_mm_s = 0.0, "crank_speed_mm_s"),
        (|c| c.drive.gear_ratio = 0.0, "drive.gear_ratio"),
        (
            |c| c.drive.sprocket_diameter_mm = -79.0,
            "drive.sprocket_diameter_mm",
        ),
        (|c| c.drive.ramp_hz_per_s = 0.0, "drive.ramp_hz_per_s"),
        (
            |c| c.drive.brake_decel_mm_s2 = -500.0,
            "drive.brake_decel_mm_s2",
        ),
        (|c| c.drive.pole_pairs = 0, "drive.pole_pairs"),
    ];
    for (break_it, field) in cases {
        let mut config = LiftConfig::default();
        break_it(&mut config);
        let (e, message) = rejected(config);
        assert!(
            matches!(e, LiftConfigError::NotPositive { field: f, .. } if f == field),
            "{e:?}"
        );
        assert!(message.starts_with(field) && message.ends_with("must be greater than zero"));
    }
}

#[test]
fn an_absurdly_large_value_is_rejected() {
    let (e, message) = rejected({
        let mut cfg = LiftConfig::default();
        cfg.floor_pitch_mm = 1e300;
        cfg
    });
    assert!(matches!(
        e,
        LiftConfigError::TooLarge {
            field: "floor_pitch_mm",
            ..
        }
    ));
    assert_eq!(
        message,
        "floor_pitch_mm = 1e300: larger than the 100000.0 this model accepts"
    );
}

#[test]
fn a_slip_of_one_or_more_is_rejected() {
    for slip in [1.0, 1.5, -0.1] {
        let (e, message) = rejected(with_drive({
            let mut cfg = DriveConfig::default();
            cfg.slip = slip;
            cfg
        }));
        assert_eq!(e, LiftConfigError::Slip { slip });
        assert!(message.contains("slip of an induction motor is at least 0 and below 1"));
    }
}

#[test]
fn a_short_track_not_shorter_than_the_long_one_is_rejected() {
    let (e, message) = rejected({
        let mut cfg = LiftConfig::default();
        cfg.short_track_half_mm = 40.0;
        cfg
    });
    assert_eq!(
        e,
        LiftConfigError::TrackLengths {
            short_mm: 40.0,
            long_mm: 40.0
        }
    );
    assert!(message.contains("floor 1 is recognised by its long track rising first"));
}

#[test]
fn overlapping_vanes_are_rejected() {
    // 80 mm pitch: floor 2's long right track (40..120) touches floor 3's (120..200).
    let (e, message) = rejected({
        let mut cfg = LiftConfig::default();
        cfg.floor_pitch_mm = 80.0;
        cfg
    });
    assert_eq!(
        e,
        LiftConfigError::VanesOverlap {
            sensor: VaneSensor::Right,
            lower_floor: 2,
            upper_floor: 3,
            lower_top_mm: 120.0,
            upper_bottom_mm: 120.0
        }
    );
    assert!(message.starts_with(
        "vanes overlap: the Snimac_2 (right) tracks of floors 2 and 3 touch or overlap"
    ));
    // With two floors only floor 1's long left track meets floor 2's short one: 45 mm pitch
    // leaves 40 + 10 − 45 = 5 mm of overlap.
    let (e, _) = rejected({
        let mut cfg = LiftConfig::default();
        cfg.floors = 2;
        cfg.floor_pitch_mm = 45.0;
        cfg.trip_beyond_floor_mm = 60.0;
        cfg
    });
    assert!(matches!(
        e,
        LiftConfigError::VanesOverlap {
            sensor: VaneSensor::Left,
            lower_floor: 1,
            upper_floor: 2,
            ..
        }
    ));
    // 81 mm is just enough for four floors.
    assert!(Lift::new({
        let mut cfg = LiftConfig::default();
        cfg.floor_pitch_mm = 81.0;
        cfg
    })
    .is_ok());
}

#[test]
fn trip_zones_overlapping_the_end_floors_are_rejected() {
    let (e, message) = rejected({
        let mut cfg = LiftConfig::default();
        cfg.trip_beyond_floor_mm = 40.0;
        cfg
    });
    assert_eq!(
        e,
        LiftConfigError::TripZoneOverlapsFloor {
            trip_mm: 40.0,
            track_mm: 40.0
        }
    );
    assert_eq!(
        message,
        "trip_beyond_floor_mm = 40.0 must exceed long_track_half_mm = 40.0: the overtravel trip zones would overlap the vane tracks of the end floors"
    );
}

#[test]
fn a_start_outside_the_mechanical_ends_is_rejected() {
    for position in [-140.5, 1340.5] {
        let (e, message) = rejected({
            let mut cfg = LiftConfig::default();
            cfg.initial_position_mm = position;
            cfg
        });
        assert_eq!(
            e,
            LiftConfigError::InitialPosition {
                position_mm: position,
                lowest_mm: -140.0,
                highest_mm: 1340.0
            }
        );
        assert!(message.contains("the mechanical ends are at -140.0 mm and 1340.0 mm"));
    }
    // On the ends themselves is allowed.
    for position in [-140.0, 1340.0] {
        let config = {
            let mut cfg = LiftConfig::default();
            cfg.initial_position_mm = position;
            cfg
        };
        assert!(Lift::new(config).is_ok());
    }
}

#[test]
fn a_scenario_file_reads_into_the_configuration_and_unknown_keys_are_refused() {
    // Missing fields take the lab defaults; a misspelt one is an error, not ignored.
    let text = r#"{ "floors": 6, "floor_pitch_mm": 350.0, "drive": { "ramp_hz_per_s": 25.0 } }"#;
    let config: LiftConfig = match serde_json::from_str(text) {
        Ok(c) => c,
        Err(e) => panic!("{e}"),
    };
    assert_eq!(config.floors, 6);
    assert_eq!(config.drive.ramp_hz_per_s, 25.0);
    assert_eq!(config.drive.gear_ratio, 25.0);
    assert_eq!(config.long_track_half_mm, 40.0);
    let err = serde_json::from_str::<LiftConfig>(r#"{ "flors": 6 }"#).err();
    assert!(err.is_some_and(|e| e.to_string().starts_with("unknown field `flors`")));
}
