//! Table 6.6 of the lift thesis (and §6.4 for 11000): set-point → frequency → motor → sprocket →
//! cabin velocity, one test per row, on the formulas and on the running plant.

use crate::common::*;
use asi_phy::SimTime;
use lift_model::{converter_frequency_hz, DriveConfig, PlantEventKind, VaneSensor};

/// `value` printed with as many decimals as the lift thesis' `table` text has.
fn as_in_table(value: f64, table: &str) -> String {
    let decimals = table.split_once('.').map_or(0, |(_, d)| d.len());
    format!("{value:.decimals$}")
}

/// One row: the formulas give the lift thesis' numbers, and the plant, run up from floor 1 at
/// this set-point, reaches and holds the lift thesis' velocity.
fn check_row(setpoint_ua: u16, f_hz: &str, n1: &str, n2: &str, v_mm_s: &str) {
    let drive = DriveConfig::default();
    let f = converter_frequency_hz(setpoint_ua);
    assert_eq!(as_in_table(f, f_hz), f_hz, "f for {setpoint_ua}");
    assert_eq!(as_in_table(drive.motor_rev_per_s(f), n1), n1, "n1");
    assert_eq!(as_in_table(drive.sprocket_rev_per_s(f), n2), n2, "n2");
    assert_eq!(
        as_in_table(drive.cabin_velocity_mm_s(f), v_mm_s),
        v_mm_s,
        "v"
    );

    let mut lift = driving(0.0, true, setpoint_ua);
    let end = run_to(&mut lift, |k| matches!(k, PlantEventKind::RampEnd { .. }));
    // The ramp takes f / 50 Hz/s, rounded up to the nanosecond.
    assert_eq!(
        end.at,
        SimTime::from_nanos((f / 50.0 * 1e9).ceil() as u64),
        "ramp time"
    );
    assert_eq!(as_in_table(lift.velocity_mm_s(), v_mm_s), v_mm_s);
    assert_eq!(as_in_table(lift.converter_frequency_hz(), f_hz), f_hz);

    // Measured on the shaft, as one would with a stopwatch: the right sensor's 80 mm track
    // at floor 2 (360..440 mm) takes 80 / v seconds to pass at constant speed.
    let on = run_to(&mut lift, |k| {
        *k == PlantEventKind::Vane {
            sensor: VaneSensor::Right,
            on: true,
        }
    });
    let off = run_to(&mut lift, |k| {
        *k == PlantEventKind::Vane {
            sensor: VaneSensor::Right,
            on: false,
        }
    });
    let seconds = (off.at.as_nanos() - on.at.as_nanos()) as f64 / 1e9;
    assert_eq!(
        as_in_table(80.0 / seconds, v_mm_s),
        v_mm_s,
        "v on the shaft"
    );
}

#[test]
fn table_6_6_row_4000_is_standstill() {
    let drive = DriveConfig::default();
    assert_eq!(converter_frequency_hz(4000), 0.0);
    assert_eq!(drive.cabin_velocity_mm_s(0.0), 0.0);
    let mut lift = driving(0.0, true, 4000);
    // Running at 4000 µA the converter holds 0 Hz: nothing will ever happen.
    assert_eq!(lift.next_event(), None);
    assert!(advance(&mut lift, secs(10.0)).is_empty());
    assert_eq!(lift.velocity_mm_s(), 0.0);
    assert_eq!(lift.position_mm(), 0.0);
    assert!(lift.converter_ready());
}

#[test]
fn table_6_6_row_6000() {
    check_row(6000, "4.600", "2.070", "0.083", "20.550");
}

#[test]
fn table_6_6_row_10000() {
    check_row(10000, "13.300", "5.985", "0.239", "59.416");
}

#[test]
fn section_6_4_row_11000() {
    check_row(11000, "15.400", "6.930", "0.2772", "68.797");
    // §6.4 equations (3) and (5) print four decimals: 6.9300 rev/s and 68.7971 mm/s.
    let drive = DriveConfig::default();
    assert_eq!(format!("{:.4}", drive.motor_rev_per_s(15.4)), "6.9300");
    assert_eq!(format!("{:.4}", drive.cabin_velocity_mm_s(15.4)), "68.7971");
}

#[test]
fn between_the_measured_points_the_frequency_is_linear() {
    assert_eq!(converter_frequency_hz(5000), 2.3);
    assert!((converter_frequency_hz(8000) - 8.95).abs() < 1e-12);
    assert!((converter_frequency_hz(10500) - 14.35).abs() < 1e-12);
}

#[test]
fn outside_the_measured_points_the_decisions_hold() {
    // Below the 4 mA live zero: standstill, never reverse.
    assert_eq!(converter_frequency_hz(0), 0.0);
    assert_eq!(converter_frequency_hz(3999), 0.0);
    // Above 11 mA the last slope (2.1 Hz/mA) continues to 20 mA ...
    assert!((converter_frequency_hz(12000) - 17.5).abs() < 1e-12);
    assert!((converter_frequency_hz(20000) - 34.3).abs() < 1e-12);
    // ... and the loop cannot drive more than 20 mA.
    assert_eq!(
        converter_frequency_hz(u16::MAX),
        converter_frequency_hz(20000)
    );
}
