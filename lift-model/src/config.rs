//! What the plant is built from: floors, vanes, trip zones, ends, drive (docs/lift-plant.md), and the
//! checks that reject a configuration the lift could not run with.

use serde::{Deserialize, Serialize};

use crate::drive::DriveConfig;
use crate::sensor::{End, VaneSensor};

/// The fewest floors a lift has.
pub const MIN_FLOORS: u8 = 2;
/// The most floors: the display word carries floor numbers 1..24 (docs/lab-bus.md, table 4.2 of the
/// lift thesis).
pub const MAX_FLOORS: u8 = lab::display::MAX_FLOOR;
/// The longest length this model accepts, in mm (100 m): keeps every time and position
/// computation far from overflow.
pub const MAX_LENGTH_MM: f64 = 100_000.0;
/// How far from a floor's level the cabin may stand and still be level at that floor, mm
/// (either way): the window in which the rig counts an arrival and the tests judge a stop.
pub const LEVEL_WINDOW_MM: f64 = 10.0;

/// The lift as built (docs/lift-plant.md geometry; §6.3, §6.4 of the lift thesis). All lengths in
/// mm, positions of the cabin measured upward from the level of floor 1.
///
/// Defaults are docs/lift-plant.md's decisions for the lab lift: 4 floors 400 mm apart, vanes with a
/// ±40 mm long and a ±10 mm short sensor track, overtravel trip 60 mm beyond the end floors,
/// mechanical ends 80 mm beyond the trip points, the cabin starting level with floor 1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
#[non_exhaustive]
pub struct LiftConfig {
    /// Number of floors, 2..=24.
    pub floors: u8,
    /// Distance between the levels of adjacent floors; floor f is level at (f − 1) · pitch.
    pub floor_pitch_mm: f64,
    /// Half length of the long sensor track of a vane: the track covers level ± this.
    pub long_track_half_mm: f64,
    /// Half length of the short sensor track of a vane (the level zone): level ± this.
    pub short_track_half_mm: f64,
    /// How far below floor 1 and above the top floor the overtravel sensors trip.
    pub trip_beyond_floor_mm: f64,
    /// How far beyond each trip point the mechanical end (buffer) is.
    pub end_beyond_trip_mm: f64,
    /// Where the cabin is when the simulation starts.
    pub initial_position_mm: f64,
    /// How fast a person turns the cabin with the hand crank on the motor, in mm/s. Default
    /// 10 mm/s: about one turn of the motor per second (one turn moves the cabin
    /// π · 79 / 25 = 9.9 mm).
    pub crank_speed_mm_s: f64,
    /// Motor, gearbox, sprocket, converter ramp and brake.
    pub drive: DriveConfig,
}

impl Default for LiftConfig {
    fn default() -> Self {
        LiftConfig {
            floors: 4,
            floor_pitch_mm: 400.0,
            long_track_half_mm: 40.0,
            short_track_half_mm: 10.0,
            trip_beyond_floor_mm: 60.0,
            end_beyond_trip_mm: 80.0,
            initial_position_mm: 0.0,
            crank_speed_mm_s: 10.0,
            drive: DriveConfig::default(),
        }
    }
}

/// Why a [`LiftConfig`] was rejected; each message names the field and the cause.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LiftConfigError {
    /// Fewer than 2 or more than 24 floors.
    #[error("floors = {floors}: the lift needs 2 to 24 floors (the display word carries floor numbers 1..24; see the asi-lift guide, chapter \"The handshakes and displays\")")]
    FloorCount {
        /// The number given.
        floors: u8,
    },
    /// A number is NaN or infinite.
    #[error("{field} = {value:?}: not a finite number")]
    NotFinite {
        /// The field, as named in the configuration.
        field: &'static str,
        /// The value given.
        value: f64,
    },
    /// A length, speed, ratio or rate is zero or negative.
    #[error("{field} = {value:?}: must be greater than zero")]
    NotPositive {
        /// The field, as named in the configuration.
        field: &'static str,
        /// The value given.
        value: f64,
    },
    /// A value beyond what this model accepts.
    #[error("{field} = {value:?}: larger than the {max:?} this model accepts")]
    TooLarge {
        /// The field, as named in the configuration.
        field: &'static str,
        /// The value given.
        value: f64,
        /// The largest accepted value.
        max: f64,
    },
    /// The motor slip is outside 0 ≤ s < 1.
    #[error("drive.slip = {slip:?}: the slip of an induction motor is at least 0 and below 1")]
    Slip {
        /// The value given.
        slip: f64,
    },
    /// The short track is not shorter than the long one.
    #[error("short_track_half_mm = {short_mm:?} must be less than long_track_half_mm = {long_mm:?}: floor 1 is recognised by its long track rising first (the lift thesis, §6.4)")]
    TrackLengths {
        /// The short half length given.
        short_mm: f64,
        /// The long half length given.
        long_mm: f64,
    },
    /// Two tracks of one sensor touch or overlap, so the sensor would not drop between floors.
    #[error("vanes overlap: the {sensor} tracks of floors {lower_floor} and {upper_floor} touch or overlap (floor {lower_floor} ends at {lower_top_mm:?} mm, floor {upper_floor} starts at {upper_bottom_mm:?} mm); the sensor must drop between floors or the controller's floor counting (the lift thesis, tables 6.4 and 6.5) misses one: raise floor_pitch_mm or shorten the tracks")]
    VanesOverlap {
        /// The sensor whose tracks collide.
        sensor: VaneSensor,
        /// The lower of the two floors.
        lower_floor: u8,
        /// The upper of the two floors.
        upper_floor: u8,
        /// Where the lower floor's track ends.
        lower_top_mm: f64,
        /// Where the upper floor's track starts.
        upper_bottom_mm: f64,
    },
    /// An overtravel trip point lies within the vane tracks of an end floor.
    #[error("trip_beyond_floor_mm = {trip_mm:?} must exceed long_track_half_mm = {track_mm:?}: the overtravel trip zones would overlap the vane tracks of the end floors")]
    TripZoneOverlapsFloor {
        /// The trip distance given.
        trip_mm: f64,
        /// The long half track it must exceed.
        track_mm: f64,
    },
    /// The cabin would start outside the mechanical ends.
    #[error("initial_position_mm = {position_mm:?} is outside the shaft: the mechanical ends are at {lowest_mm:?} mm and {highest_mm:?} mm")]
    InitialPosition {
        /// The position given.
        position_mm: f64,
        /// The bottom mechanical end.
        lowest_mm: f64,
        /// The top mechanical end.
        highest_mm: f64,
    },
}

impl LiftConfig {
    /// Checks every rule; the first one broken is returned. [`crate::Lift::new`] calls this.
    pub fn validate(&self) -> Result<(), LiftConfigError> {
        if !(MIN_FLOORS..=MAX_FLOORS).contains(&self.floors) {
            return Err(LiftConfigError::FloorCount {
                floors: self.floors,
            });
        }
        let d = &self.drive;
        // (field, value, largest accepted): every one must be finite, positive and not absurd.
        let positive: [(&'static str, f64, f64); 10] = [
            ("floor_pitch_mm", self.floor_pitch_mm, MAX_LENGTH_MM),
            ("long_track_half_mm", self.long_track_half_mm, MAX_LENGTH_MM),
            (
                "short_track_half_mm",
                self.short_track_half_mm,
                MAX_LENGTH_MM,
            ),
            (
                "trip_beyond_floor_mm",
                self.trip_beyond_floor_mm,
                MAX_LENGTH_MM,
            ),
            ("end_beyond_trip_mm", self.end_beyond_trip_mm, MAX_LENGTH_MM),
            ("crank_speed_mm_s", self.crank_speed_mm_s, 10_000.0),
            ("drive.gear_ratio", d.gear_ratio, 10_000.0),
            (
                "drive.sprocket_diameter_mm",
                d.sprocket_diameter_mm,
                10_000.0,
            ),
            ("drive.ramp_hz_per_s", d.ramp_hz_per_s, 10_000.0),
            ("drive.brake_decel_mm_s2", d.brake_decel_mm_s2, 1.0e6),
        ];
        for (field, value, max) in positive {
            check_finite(field, value)?;
            if value <= 0.0 {
                return Err(LiftConfigError::NotPositive { field, value });
            }
            if value > max {
                return Err(LiftConfigError::TooLarge { field, value, max });
            }
        }
        check_finite("drive.slip", d.slip)?;
        check_finite("initial_position_mm", self.initial_position_mm)?;
        if d.pole_pairs == 0 {
            return Err(LiftConfigError::NotPositive {
                field: "drive.pole_pairs",
                value: 0.0,
            });
        }
        if !(0.0..1.0).contains(&d.slip) {
            return Err(LiftConfigError::Slip { slip: d.slip });
        }
        if self.short_track_half_mm >= self.long_track_half_mm {
            return Err(LiftConfigError::TrackLengths {
                short_mm: self.short_track_half_mm,
                long_mm: self.long_track_half_mm,
            });
        }
        for sensor in [VaneSensor::Left, VaneSensor::Right] {
            for lower in 1..self.floors {
                let (_, lower_top_mm) = self.track(sensor, lower);
                let (upper_bottom_mm, _) = self.track(sensor, lower + 1);
                if lower_top_mm >= upper_bottom_mm {
                    return Err(LiftConfigError::VanesOverlap {
                        sensor,
                        lower_floor: lower,
                        upper_floor: lower + 1,
                        lower_top_mm,
                        upper_bottom_mm,
                    });
                }
            }
        }
        if self.trip_beyond_floor_mm <= self.long_track_half_mm {
            return Err(LiftConfigError::TripZoneOverlapsFloor {
                trip_mm: self.trip_beyond_floor_mm,
                track_mm: self.long_track_half_mm,
            });
        }
        let (lowest_mm, highest_mm) = (
            self.end_position_mm(End::Bottom),
            self.end_position_mm(End::Top),
        );
        if !(lowest_mm..=highest_mm).contains(&self.initial_position_mm) {
            return Err(LiftConfigError::InitialPosition {
                position_mm: self.initial_position_mm,
                lowest_mm,
                highest_mm,
            });
        }
        Ok(())
    }

    /// The level of floor `floor` (1-based) in mm: (floor − 1) · pitch (docs/lift-plant.md); `None` for
    /// a floor the lift does not have.
    pub fn floor_level_mm(&self, floor: u8) -> Option<f64> {
        (1..=self.floors)
            .contains(&floor)
            .then(|| self.level(floor))
    }

    /// The floor the cabin stands level at when it is at `position_mm`: within
    /// [`LEVEL_WINDOW_MM`] of a floor's level; `None` between floors.
    pub fn level_floor(&self, position_mm: f64) -> Option<u8> {
        let nearest = (position_mm / self.floor_pitch_mm).round() + 1.0;
        if !(1.0..=f64::from(self.floors)).contains(&nearest) {
            return None;
        }
        let floor = nearest as u8;
        ((position_mm - self.level(floor)).abs() <= LEVEL_WINDOW_MM).then_some(floor)
    }

    /// The track `(from, to)` in mm, both ends inclusive, on which `sensor` is on at `floor`;
    /// `None` for a floor the lift does not have.
    ///
    /// docs/lift-plant.md, §6.4 of the lift thesis: at floors 2..N the right sensor (Snimac_2) has
    /// the long track and the left (Snimac_1) the short one; the floor-1 vane is turned 90° to the
    /// left, so there the left sensor has the long track.
    pub fn vane_track_mm(&self, sensor: VaneSensor, floor: u8) -> Option<(f64, f64)> {
        (1..=self.floors)
            .contains(&floor)
            .then(|| self.track(sensor, floor))
    }

    /// Where the overtravel sensor at `end` trips: 60 mm (by default) below floor 1 or above
    /// the top floor (docs/lift-plant.md). The sensor is tripped at this point and beyond.
    pub fn trip_position_mm(&self, end: End) -> f64 {
        match end {
            End::Bottom => self.level(1) - self.trip_beyond_floor_mm,
            End::Top => self.level(self.floors) + self.trip_beyond_floor_mm,
        }
    }

    /// Where the mechanical end (buffer) at `end` is: 80 mm (by default) beyond the trip point
    /// (docs/lift-plant.md). The cabin can reach it but not pass it.
    pub fn end_position_mm(&self, end: End) -> f64 {
        match end {
            End::Bottom => self.trip_position_mm(end) - self.end_beyond_trip_mm,
            End::Top => self.trip_position_mm(end) + self.end_beyond_trip_mm,
        }
    }

    fn level(&self, floor: u8) -> f64 {
        f64::from(floor.saturating_sub(1)) * self.floor_pitch_mm
    }

    fn track(&self, sensor: VaneSensor, floor: u8) -> (f64, f64) {
        let long = match sensor {
            VaneSensor::Left => floor == 1,
            VaneSensor::Right => floor != 1,
        };
        let half = if long {
            self.long_track_half_mm
        } else {
            self.short_track_half_mm
        };
        let level = self.level(floor);
        (level - half, level + half)
    }
}

fn check_finite(field: &'static str, value: f64) -> Result<(), LiftConfigError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(LiftConfigError::NotFinite { field, value })
    }
}
