//! Simulated time: the one clock every asi-lift component runs on (docs/architecture.md).
//!
//! Time is a value passed in, never read from the operating system. [`SimTime`] is a point on
//! the simulated clock and [`SimDuration`] a span, both in integer nanoseconds, so that the 3 µs
//! half-bit grid of AS-i, the 10 ms PLC scan and an hour of lift traffic are all exact and a run
//! with the same scenario and seed gives the same trace, byte for byte.
//!
//! Arithmetic saturates instead of overflowing: `u64` nanoseconds cover 584 years, so saturation
//! is never reached by a real run, and a fuzzed input that reaches it cannot panic.

use core::fmt;
use core::ops::{Add, AddAssign, Sub};
use core::str::FromStr;

/// A point on the simulated clock, in nanoseconds since the simulation started.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SimTime(u64);

/// A span of simulated time, in nanoseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SimDuration(u64);

impl SimTime {
    /// The start of the simulation.
    pub const ZERO: SimTime = SimTime(0);
    /// The last representable instant.
    pub const MAX: SimTime = SimTime(u64::MAX);

    /// The instant `ns` nanoseconds after the start.
    pub const fn from_nanos(ns: u64) -> Self {
        SimTime(ns)
    }

    /// The instant `us` microseconds after the start (saturating).
    pub const fn from_micros(us: u64) -> Self {
        SimTime(us.saturating_mul(1_000))
    }

    /// The instant `ms` milliseconds after the start (saturating).
    pub const fn from_millis(ms: u64) -> Self {
        SimTime(ms.saturating_mul(1_000_000))
    }

    /// Nanoseconds since the start.
    pub const fn as_nanos(self) -> u64 {
        self.0
    }

    /// Seconds since the start, as a float (for reports; never for decisions).
    pub fn as_secs_f64(self) -> f64 {
        self.0 as f64 / 1e9
    }

    /// The span from `earlier` to `self`, or zero if `earlier` is later.
    pub const fn saturating_duration_since(self, earlier: SimTime) -> SimDuration {
        SimDuration(self.0.saturating_sub(earlier.0))
    }

    /// The span from `earlier` to `self`, or `None` if `earlier` is later.
    pub const fn checked_duration_since(self, earlier: SimTime) -> Option<SimDuration> {
        match self.0.checked_sub(earlier.0) {
            Some(ns) => Some(SimDuration(ns)),
            None => None,
        }
    }

    /// `self + d`, or `None` past [`SimTime::MAX`].
    pub const fn checked_add(self, d: SimDuration) -> Option<SimTime> {
        match self.0.checked_add(d.0) {
            Some(ns) => Some(SimTime(ns)),
            None => None,
        }
    }

    /// `self - d`, or `None` before [`SimTime::ZERO`].
    pub const fn checked_sub(self, d: SimDuration) -> Option<SimTime> {
        match self.0.checked_sub(d.0) {
            Some(ns) => Some(SimTime(ns)),
            None => None,
        }
    }
}

impl SimDuration {
    /// No time at all.
    pub const ZERO: SimDuration = SimDuration(0);
    /// The longest representable span.
    pub const MAX: SimDuration = SimDuration(u64::MAX);

    /// A span of `ns` nanoseconds.
    pub const fn from_nanos(ns: u64) -> Self {
        SimDuration(ns)
    }

    /// A span of `us` microseconds (saturating).
    pub const fn from_micros(us: u64) -> Self {
        SimDuration(us.saturating_mul(1_000))
    }

    /// A span of `ms` milliseconds (saturating).
    pub const fn from_millis(ms: u64) -> Self {
        SimDuration(ms.saturating_mul(1_000_000))
    }

    /// A span of `s` seconds (saturating).
    pub const fn from_secs(s: u64) -> Self {
        SimDuration(s.saturating_mul(1_000_000_000))
    }

    /// A span of `s` seconds given as a float, rounded to the nearest nanosecond.
    ///
    /// `None` for a negative, NaN or too large value: durations that come from a user's file
    /// are checked, not clamped.
    pub fn from_secs_f64(s: f64) -> Option<Self> {
        let ns = s * 1e9;
        if ns.is_finite() && ns >= 0.0 && ns <= u64::MAX as f64 {
            Some(SimDuration(ns.round() as u64))
        } else {
            None
        }
    }

    /// The span in nanoseconds.
    pub const fn as_nanos(self) -> u64 {
        self.0
    }

    /// The span in seconds, as a float (for reports and physics, never for scheduling).
    pub fn as_secs_f64(self) -> f64 {
        self.0 as f64 / 1e9
    }

    /// The span in microseconds, as a float.
    pub fn as_micros_f64(self) -> f64 {
        self.0 as f64 / 1e3
    }

    /// `self + other`, or `None` on overflow.
    pub const fn checked_add(self, other: SimDuration) -> Option<SimDuration> {
        match self.0.checked_add(other.0) {
            Some(ns) => Some(SimDuration(ns)),
            None => None,
        }
    }

    /// `self - other`, or zero if `other` is longer.
    pub const fn saturating_sub(self, other: SimDuration) -> SimDuration {
        SimDuration(self.0.saturating_sub(other.0))
    }

    /// `self · n`, saturating.
    pub const fn saturating_mul(self, n: u64) -> SimDuration {
        SimDuration(self.0.saturating_mul(n))
    }

    /// `true` for the zero span.
    pub const fn is_zero(self) -> bool {
        self.0 == 0
    }
}

impl Add<SimDuration> for SimTime {
    type Output = SimTime;
    /// Saturates at [`SimTime::MAX`].
    fn add(self, d: SimDuration) -> SimTime {
        SimTime(self.0.saturating_add(d.0))
    }
}

impl AddAssign<SimDuration> for SimTime {
    fn add_assign(&mut self, d: SimDuration) {
        *self = *self + d;
    }
}

impl Sub<SimDuration> for SimTime {
    type Output = SimTime;
    /// Saturates at [`SimTime::ZERO`].
    fn sub(self, d: SimDuration) -> SimTime {
        SimTime(self.0.saturating_sub(d.0))
    }
}

impl Sub<SimTime> for SimTime {
    type Output = SimDuration;
    /// The span between two instants; zero if `rhs` is later.
    fn sub(self, rhs: SimTime) -> SimDuration {
        self.saturating_duration_since(rhs)
    }
}

impl Add for SimDuration {
    type Output = SimDuration;
    /// Saturates at [`SimDuration::MAX`].
    fn add(self, rhs: SimDuration) -> SimDuration {
        SimDuration(self.0.saturating_add(rhs.0))
    }
}

impl AddAssign for SimDuration {
    fn add_assign(&mut self, rhs: SimDuration) {
        *self = *self + rhs;
    }
}

impl Sub for SimDuration {
    type Output = SimDuration;
    /// Saturates at zero.
    fn sub(self, rhs: SimDuration) -> SimDuration {
        self.saturating_sub(rhs)
    }
}

impl fmt::Display for SimTime {
    /// Seconds with nanosecond precision, e.g. `12.000154000 s`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}.{:09} s",
            self.0 / 1_000_000_000,
            self.0 % 1_000_000_000
        )
    }
}

impl fmt::Display for SimDuration {
    /// The largest unit that shows the span exactly: `154 µs`, `10 ms`, `1.5 s`, `42 ns`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const UNITS: [(u64, &str); 3] = [(1_000_000_000, "s"), (1_000_000, "ms"), (1_000, "µs")];
        for (scale, unit) in UNITS {
            if self.0 >= scale {
                let whole = self.0 / scale;
                let frac = self.0 % scale;
                if frac == 0 {
                    return write!(f, "{whole} {unit}");
                }
                let digits = scale.ilog10() as usize;
                let frac = format!("{frac:0digits$}");
                return write!(f, "{whole}.{} {unit}", frac.trim_end_matches('0'));
            }
        }
        write!(f, "{} ns", self.0)
    }
}

/// Why a duration text such as `"90s"` could not be read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ParseDurationError {
    /// Nothing but white space was given.
    #[error("empty duration: expected a number and a unit, e.g. \"90s\" or \"250ms\"")]
    Empty,
    /// The number part is missing or not a number.
    #[error("`{0}` is not a duration: expected a number and a unit, e.g. \"90s\" or \"250ms\"")]
    BadNumber(String),
    /// The unit is not one of ns, us, µs, ms, s, min, h.
    #[error("unknown unit `{unit}` in `{text}`: use ns, us, ms, s, min or h")]
    BadUnit {
        /// The whole text.
        text: String,
        /// The unit as written.
        unit: String,
    },
    /// The number is negative or too large for 584 years of nanoseconds.
    #[error("`{0}` is out of range: a duration is between 0 and 584 years")]
    OutOfRange(String),
}

impl FromStr for SimDuration {
    type Err = ParseDurationError;

    /// Reads `"90s"`, `"1.5 min"`, `"250ms"`, `"154us"`, `"154µs"`, `"42ns"`, `"2h"`.
    ///
    /// A unit is required: a bare number is ambiguous in a scenario file. Integer values are
    /// converted exactly; fractional values are rounded to the nearest nanosecond.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let t = text.trim();
        if t.is_empty() {
            return Err(ParseDurationError::Empty);
        }
        let split = t
            .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == '+'))
            .unwrap_or(t.len());
        let (num, unit) = t.split_at(split);
        let unit = unit.trim();
        let scale: u64 = match unit {
            "ns" => 1,
            "us" | "µs" | "μs" => 1_000,
            "ms" => 1_000_000,
            "s" => 1_000_000_000,
            "min" => 60_000_000_000,
            "h" => 3_600_000_000_000,
            _ => {
                return Err(ParseDurationError::BadUnit {
                    text: t.to_owned(),
                    unit: unit.to_owned(),
                })
            }
        };
        if num.is_empty() {
            return Err(ParseDurationError::BadNumber(t.to_owned()));
        }
        if let Ok(whole) = num.parse::<u64>() {
            return whole
                .checked_mul(scale)
                .map(SimDuration)
                .ok_or_else(|| ParseDurationError::OutOfRange(t.to_owned()));
        }
        let value: f64 = num
            .parse()
            .map_err(|_| ParseDurationError::BadNumber(t.to_owned()))?;
        let ns = value * scale as f64;
        if !ns.is_finite() || ns < 0.0 || ns > u64::MAX as f64 {
            return Err(ParseDurationError::OutOfRange(t.to_owned()));
        }
        Ok(SimDuration(ns.round() as u64))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_unit_exactly() {
        let cases = [
            ("42ns", 42),
            ("154us", 154_000),
            ("154 µs", 154_000),
            ("10ms", 10_000_000),
            ("90s", 90_000_000_000),
            ("1.5min", 90_000_000_000),
            ("2h", 7_200_000_000_000),
            ("0.25 s", 250_000_000),
        ];
        for (text, ns) in cases {
            assert_eq!(text.parse::<SimDuration>(), Ok(SimDuration(ns)), "{text}");
        }
    }

    #[test]
    fn rejects_bad_durations_with_the_cause() {
        assert_eq!("".parse::<SimDuration>(), Err(ParseDurationError::Empty));
        assert!(matches!(
            "90".parse::<SimDuration>(),
            Err(ParseDurationError::BadUnit { .. })
        ));
        assert!(matches!(
            "5 fortnights".parse::<SimDuration>(),
            Err(ParseDurationError::BadUnit { .. })
        ));
        assert!(matches!(
            "s".parse::<SimDuration>(),
            Err(ParseDurationError::BadNumber(_))
        ));
        assert!(matches!(
            "-1s".parse::<SimDuration>(),
            Err(ParseDurationError::BadNumber(_) | ParseDurationError::OutOfRange(_))
        ));
        assert!(matches!(
            "1e30s".parse::<SimDuration>(),
            Err(ParseDurationError::BadUnit { .. } | ParseDurationError::OutOfRange(_))
        ));
        assert!(matches!(
            "99999999999h".parse::<SimDuration>(),
            Err(ParseDurationError::OutOfRange(_))
        ));
    }

    #[test]
    fn displays_in_the_largest_exact_unit() {
        assert_eq!(SimDuration::from_micros(154).to_string(), "154 µs");
        assert_eq!(SimDuration::from_millis(1500).to_string(), "1.5 s");
        assert_eq!(SimDuration::from_nanos(4_928_000).to_string(), "4.928 ms");
        assert_eq!(SimDuration::from_nanos(7).to_string(), "7 ns");
        assert_eq!(
            SimTime::from_micros(12_000_154).to_string(),
            "12.000154000 s"
        );
    }

    #[test]
    fn arithmetic_saturates_instead_of_panicking() {
        assert_eq!(SimTime::MAX + SimDuration::from_secs(1), SimTime::MAX);
        assert_eq!(SimTime::ZERO - SimDuration::from_secs(1), SimTime::ZERO);
        assert_eq!(SimTime::ZERO - SimTime::from_millis(1), SimDuration::ZERO);
        assert_eq!(SimTime::ZERO.checked_sub(SimDuration::from_nanos(1)), None);
        assert_eq!(
            SimTime::from_millis(3) - SimTime::from_millis(1),
            SimDuration::from_millis(2)
        );
        assert_eq!(SimDuration::from_secs_f64(-1.0), None);
        assert_eq!(SimDuration::from_secs_f64(f64::NAN), None);
        assert_eq!(
            SimDuration::from_secs_f64(0.000_154),
            Some(SimDuration::from_micros(154))
        );
    }
}
