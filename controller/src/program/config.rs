//! The program's settings and their check.

use crate::dispatch::Algorithm;
use asi_phy::SimDuration;
use core::fmt;

/// The program's settings. Defaults: the lift thesis' set-points (µA of the current loop) and
/// timer, a 10 ms scan (docs/controller.md).
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct ControllerConfig {
    /// Floors served, 2..=24.
    pub floors: u8,
    /// FIFO (the lift thesis') or collective selective.
    pub algorithm: Algorithm,
    /// The PLC scan period.
    pub scan: SimDuration,
    /// Travel set-point (tables 6.4/6.5 of the lift thesis: 10000 µA, 59.4 mm/s).
    pub travel_ua: u16,
    /// Braking (creep) set-point (6000 µA, 20.6 mm/s).
    pub creep_ua: u16,
    /// Standstill set-point (4000 µA = 4 mA).
    pub standstill_ua: u16,
    /// Initialisation set-point (table 6.3 of the lift thesis: 11000 µA, 68.8 mm/s).
    pub init_ua: u16,
    /// The initialisation timer (§6.4 of the lift thesis: 2 s).
    pub init_timer: SimDuration,
    /// How often the restart pulse is repeated while the STOP circuit is not yet running again.
    pub restart_every: SimDuration,
    /// A cabin word older than this means the cabin slave is lost.
    pub stale_after: SimDuration,
    /// How long the cabin stands at a floor after arriving before it departs again.
    ///
    /// **Decision**: 2 s. The lift thesis' automat departs in the scan after it arrives, so an
    /// intermediate stop would never come to rest; a lift stands for its passengers.
    pub dwell: SimDuration,
    /// Travel without reaching a vane for longer than this means a vane sensor lies: the
    /// cabin stops and the position is found again. Default 9 s: the vanes are 400 mm apart,
    /// 6.7 s at the travel speed (59.4 mm/s), 5.8 s at the initialisation speed.
    pub travel_watchdog: SimDuration,
    /// A creep inside a vane (braking to level, initialisation's probes) that does not reach
    /// its edge within this means a vane sensor lies. Default 6 s: the long track is 80 mm,
    /// 3.9 s at the creep speed (20.6 mm/s).
    pub creep_watchdog: SimDuration,
    /// Braking to a floor's level that has not reached it this long after the vane began
    /// means the level sensor lies: the cabin stops inside the vane instead of running on
    /// to its far end. Default 2.5 s: the level comes 40 mm after the vane's start, 1.8 s on
    /// (the ramp from the travel to the creep speed takes 0.25 s and 10 mm, then 30 mm at
    /// 20.6 mm/s; a cabin word later, 1.9 s); after 2.5 s the cabin stands about 15 mm past
    /// the level, within the vane's half-length that the judge allows a cabin stopping for
    /// STOP (docs/safety.md).
    pub level_watchdog: SimDuration,
    /// A vane sensor on for longer than this while the cabin runs at the travel or the
    /// initialisation speed is stuck on. Default 3 s: the long track (80 mm) passes in 1.35 s
    /// at the travel speed and 1.16 s at the initialisation speed; 3 s leave room for the
    /// ramp and two cabin words.
    pub stuck_on_after: SimDuration,
}

impl Default for ControllerConfig {
    fn default() -> Self {
        ControllerConfig {
            floors: 4,
            algorithm: Algorithm::Fifo,
            scan: SimDuration::from_millis(10),
            travel_ua: 10_000,
            creep_ua: 6_000,
            standstill_ua: lab::setpoint::STANDSTILL_UA,
            init_ua: 11_000,
            init_timer: SimDuration::from_secs(2),
            restart_every: SimDuration::from_millis(500),
            stale_after: SimDuration::from_secs(1),
            dwell: SimDuration::from_secs(2),
            travel_watchdog: SimDuration::from_secs(9),
            creep_watchdog: SimDuration::from_secs(6),
            level_watchdog: SimDuration::from_millis(2_500),
            stuck_on_after: SimDuration::from_secs(3),
        }
    }
}

/// A setting the program cannot run with.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("controller: {field} = {value}: {rule}")]
pub struct ControllerConfigError {
    /// The setting.
    pub field: &'static str,
    /// Its value.
    pub value: String,
    /// What it must be.
    pub rule: &'static str,
}

impl ControllerConfig {
    /// Checks the settings.
    pub fn check(&self) -> Result<(), ControllerConfigError> {
        let err = |field, value: &dyn fmt::Display, rule| {
            Err(ControllerConfigError {
                field,
                value: value.to_string(),
                rule,
            })
        };
        if !(2..=24).contains(&self.floors) {
            return err(
                "floors",
                &self.floors,
                "must be 2..=24 (the display word carries 5 bits)",
            );
        }
        if self.scan.is_zero() {
            return err("scan", &self.scan, "must be positive");
        }
        if self.standstill_ua >= self.creep_ua
            || self.creep_ua > self.travel_ua
            || self.travel_ua > 20_000
        {
            return err(
                "set-points",
                &format!(
                    "{}/{}/{} µA",
                    self.standstill_ua, self.creep_ua, self.travel_ua
                ),
                "need standstill < creep <= travel <= 20000 µA",
            );
        }
        if self.init_ua <= self.creep_ua || self.init_ua > 20_000 {
            return err(
                "init_ua",
                &self.init_ua,
                "must lie above the creep set-point, up to 20000 µA",
            );
        }
        Ok(())
    }
}
