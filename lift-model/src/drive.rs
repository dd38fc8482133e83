//! The drive chain: current-loop set-point → converter frequency → motor → gearbox → sprocket →
//! cabin velocity (docs/lift-plant.md; the lift thesis, §6.4, equations (2)–(5) and table 6.6).

use serde::{Deserialize, Serialize};

/// The largest set-point the current loop can drive: 20000 µA = 20 mA (§3.1 of the lift thesis,
/// AC2618 output 0–20 mA). Larger values are clamped to it.
pub const MAX_SETPOINT_UA: u16 = 20000;

/// The converter's measured characteristic, `(Rychlost in µA, output frequency in Hz)`: the rows of
/// table 6.6 of the lift thesis (and §6.4 for 11000 → 15.4 Hz), plus 4000 → 0 Hz for standstill.
pub const CONVERTER_CHARACTERISTIC: [(u16, f64); 4] =
    [(4000, 0.0), (6000, 4.6), (10000, 13.3), (11000, 15.4)];

/// The converter's output frequency in Hz for a current-loop set-point `Rychlost` in µA.
///
/// Linear interpolation between the measured points of [`CONVERTER_CHARACTERISTIC`]
/// (docs/lift-plant.md). Outside the measured range (a decision; the lift thesis is silent):
/// - below 4000 µA the converter stands still (0 Hz): 0–4 mA is below the live zero of a
///   4–20 mA input, which a converter treats as "no speed", not as reverse;
/// - above 11000 µA the last measured slope (2.1 Hz per mA, 10→11 mA) continues up to
///   20000 µA (34.3 Hz), and values above 20000 µA are clamped there, as the loop cannot
///   drive more than 20 mA.
pub fn converter_frequency_hz(setpoint_ua: u16) -> f64 {
    let sp = setpoint_ua.min(MAX_SETPOINT_UA);
    let points = &CONVERTER_CHARACTERISTIC;
    if sp <= points[0].0 {
        return 0.0;
    }
    // The segment whose upper point is at or above the set-point; past the table, the last one.
    let upper = points
        .iter()
        .position(|&(ua, _)| ua >= sp)
        .unwrap_or(points.len() - 1);
    let (ua0, f0) = points[upper - 1];
    let (ua1, f1) = points[upper];
    f0 + (f1 - f0) * f64::from(sp - ua0) / f64::from(ua1 - ua0)
}

/// Motor, gearbox, sprocket, converter ramp and brake (docs/lift-plant.md; §6.4 of the lift
/// thesis).
///
/// Defaults are the lab lift's: motor 1LA7063-4AB12 (p = 2 pole pairs, slip s = 0.1 from 1350 rpm
/// at 50 Hz, equation (2) of the lift thesis), gearbox i = 25, sprocket d = 79 mm, converter ramp
/// 50 Hz/s and brake deceleration 500 mm/s² (docs/lift-plant.md decisions).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
#[non_exhaustive]
pub struct DriveConfig {
    /// Pole pairs p of the motor (§6.4 of the lift thesis: the "4" in 1LA7063-4AB12 means 4 poles).
    pub pole_pairs: u8,
    /// Motor slip s, 0 ≤ s < 1 (equation (2) of the lift thesis: 0.1).
    pub slip: f64,
    /// Gearbox ratio i (equation (4) of the lift thesis: 25).
    pub gear_ratio: f64,
    /// Diameter d of the chain sprocket in mm (equation (5) of the lift thesis: 79 mm).
    pub sprocket_diameter_mm: f64,
    /// Converter ramp in Hz/s, for acceleration and deceleration alike (docs/lift-plant.md: 50 Hz/s).
    pub ramp_hz_per_s: f64,
    /// Deceleration of the brake when the drive has no power, in mm/s² (docs/lift-plant.md: 500 mm/s²).
    pub brake_decel_mm_s2: f64,
}

impl Default for DriveConfig {
    fn default() -> Self {
        DriveConfig {
            pole_pairs: 2,
            slip: 0.1,
            gear_ratio: 25.0,
            sprocket_diameter_mm: 79.0,
            ramp_hz_per_s: 50.0,
            brake_decel_mm_s2: 500.0,
        }
    }
}

impl DriveConfig {
    /// Motor speed n1 = f / p · (1 − s) in rev/s (equation (3) of the lift thesis).
    pub fn motor_rev_per_s(&self, frequency_hz: f64) -> f64 {
        frequency_hz / f64::from(self.pole_pairs) * (1.0 - self.slip)
    }

    /// Sprocket speed n2 = n1 / i in rev/s (equation (4) of the lift thesis).
    pub fn sprocket_rev_per_s(&self, frequency_hz: f64) -> f64 {
        self.motor_rev_per_s(frequency_hz) / self.gear_ratio
    }

    /// Cabin velocity v = n2 · π · d in mm/s (equation (5) of the lift thesis).
    pub fn cabin_velocity_mm_s(&self, frequency_hz: f64) -> f64 {
        self.sprocket_rev_per_s(frequency_hz) * core::f64::consts::PI * self.sprocket_diameter_mm
    }

    /// Steady cabin speed in mm/s for a set-point `Rychlost` in µA (table 6.6 of the lift thesis).
    pub fn setpoint_velocity_mm_s(&self, setpoint_ua: u16) -> f64 {
        self.cabin_velocity_mm_s(converter_frequency_hz(setpoint_ua))
    }

    /// Cabin acceleration in mm/s² while the converter ramps its frequency: the ramp in Hz/s
    /// times the cabin velocity per Hz (the chain is linear in f).
    pub fn ramp_mm_s2(&self) -> f64 {
        self.cabin_velocity_mm_s(self.ramp_hz_per_s)
    }
}
