//! Piecewise motion of the cabin and exact crossing times (docs/lift-plant.md "events exact in time";
//! the contract is stated in the crate documentation).
//!
//! Between two changes the cabin moves with constant acceleration (a converter ramp, the
//! brake) or constant velocity (steady running, the hand crank), so its position is
//! `x(t) = x0 + v0·τ + a·τ²/2` with `τ = t − t0` from the segment's anchor. A segment never
//! reverses: a reversal is two segments, split where the velocity is zero. The position at any
//! nanosecond is always evaluated from the anchor by [`Segment::position_at`], never integrated
//! step by step, so the caller's step size cannot change it.
//!
//! **Rounding rule.** A boundary crossing happens at the first integer nanosecond `T` at which
//! [`Segment::position_at`]`(T)` is past the boundary (by [`Boundary::passed`]). The analytic
//! root of the quadratic gives a candidate (rounded up); a short search around it makes the
//! result agree with the evaluated position bit for bit, so the level reported at the event
//! time is already the new one and the level one nanosecond earlier is still the old one.

use asi_phy::{SimDuration, SimTime};

use crate::shaft::Boundary;

/// How a segment ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum SegmentEnd {
    /// The converter reached its target speed `v_end` (not zero).
    RampEnd { v_end: f64 },
    /// The cabin came to rest (ramp to zero, brake).
    Stop,
    /// The hand crank has turned the distance asked for.
    CrankDone,
}

/// One piece of motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Segment {
    pub t0: SimTime,
    pub x0: f64,
    pub v0: f64,
    pub a: f64,
    /// When and how it ends; `None` for rest or steady running.
    pub end: Option<(SimTime, SegmentEnd)>,
}

impl Segment {
    /// At rest at `x` from `t0`.
    pub fn rest(t0: SimTime, x: f64) -> Segment {
        Segment {
            t0,
            x0: x,
            v0: 0.0,
            a: 0.0,
            end: None,
        }
    }

    /// Steady velocity `v`, possibly ending after `duration_s` seconds with `end`.
    pub fn steady(t0: SimTime, x0: f64, v0: f64, end: Option<(f64, SegmentEnd)>) -> Segment {
        Segment {
            t0,
            x0,
            v0,
            a: 0.0,
            end: end.map(|(s, how)| (t0 + ceil_nanos(s), how)),
        }
    }

    /// Constant acceleration `a` from `v0` until the velocity is `v_end`, which ends the
    /// segment with `how`. The end is the first nanosecond at or after the exact instant.
    pub fn ramp(t0: SimTime, x0: f64, v0: f64, a: f64, v_end: f64, how: SegmentEnd) -> Segment {
        let duration_s = (v_end - v0) / a;
        Segment {
            t0,
            x0,
            v0,
            a,
            end: Some((t0 + ceil_nanos(duration_s), how)),
        }
    }

    fn tau(&self, t: SimTime) -> f64 {
        // The integer is exact below 2^53 ns (104 days after the anchor), and one correctly
        // rounded division keeps whole seconds and other exact values exact.
        (t - self.t0).as_nanos() as f64 / 1e9
    }

    /// The position in mm at `t` (at or after the anchor).
    pub fn position_at(&self, t: SimTime) -> f64 {
        let tau = self.tau(t);
        self.x0 + tau * (self.v0 + 0.5 * self.a * tau)
    }

    /// The velocity in mm/s at `t` (at or after the anchor).
    pub fn velocity_at(&self, t: SimTime) -> f64 {
        self.v0 + self.a * self.tau(t)
    }

    /// +1 moving up, −1 moving down, 0 at rest. Constant over the segment.
    pub fn direction(&self) -> i8 {
        let sense = if self.v0 != 0.0 { self.v0 } else { self.a };
        if sense > 0.0 {
            1
        } else if sense < 0.0 {
            -1
        } else {
            0
        }
    }

    /// The first nanosecond at or after `from` (and not after the segment's end) at which the
    /// cabin is past `b` moving `up`; `None` if it is not reached in this segment.
    pub fn crossing(&self, b: &Boundary, up: bool, from: SimTime) -> Option<SimTime> {
        let past = |t: SimTime| b.passed(self.position_at(t), up);
        if past(from) {
            return Some(from);
        }
        let last = self.end.map_or(SimTime::MAX, |(t, _)| t);
        let mut hi = match self.analytic_crossing(b.pos) {
            Some(s) => (self.t0 + ceil_nanos(s)).max(from).min(last),
            // Not reached in exact arithmetic; rounding may still touch it at the very end.
            None if self.end.is_some() && past(last) => last,
            None => return None,
        };
        // Gallop up to a passed instant (usually `hi` already is one).
        let mut lo = from;
        let mut step = 1u64;
        while !past(hi) {
            if hi == last {
                return None;
            }
            lo = hi;
            hi = (hi + SimDuration::from_nanos(step)).min(last);
            step = step.saturating_mul(2);
        }
        // Gallop down to an instant not yet passed (usually `hi − 1` is one).
        let mut step = 1u64;
        loop {
            let probe = (hi - SimDuration::from_nanos(step)).max(lo);
            if probe == lo || !past(probe) {
                lo = probe;
                break;
            }
            hi = probe;
            step = step.saturating_mul(2);
        }
        // `lo` not passed, `hi` passed: bisect to the first passed nanosecond.
        while hi.as_nanos() - lo.as_nanos() > 1 {
            let mid = SimTime::from_nanos(lo.as_nanos() + (hi.as_nanos() - lo.as_nanos()) / 2);
            if past(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Some(hi)
    }

    /// Seconds after the anchor at which the exact motion first reaches `pos`, if ever.
    fn analytic_crossing(&self, pos: f64) -> Option<f64> {
        let d = pos - self.x0;
        let dir = f64::from(self.direction());
        if self.a == 0.0 {
            let s = d / self.v0;
            return (s.is_finite() && s >= 0.0).then_some(s);
        }
        let disc = self.v0 * self.v0 + 2.0 * self.a * d;
        if disc < 0.0 {
            return None;
        }
        // The root nearer in time, in the form that does not cancel: 2d / (v0 + dir·√disc).
        let denom = self.v0 + dir * disc.sqrt();
        let s = if denom == 0.0 { 0.0 } else { 2.0 * d / denom };
        (s.is_finite() && s >= 0.0).then_some(s)
    }
}

/// `seconds` as a span rounded up to whole nanoseconds, saturating; NaN and negatives give 0.
pub(crate) fn ceil_nanos(seconds: f64) -> SimDuration {
    let ns = (seconds * 1e9).ceil();
    // `as` saturates at u64::MAX and maps NaN and negatives to 0.
    SimDuration::from_nanos(ns as u64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::VaneSensor;
    use crate::shaft::{Side, Signal};

    fn edge(pos: f64, side: Side) -> Boundary {
        Boundary {
            pos,
            side,
            signal: Signal::Vane(VaneSensor::Left),
        }
    }

    #[test]
    fn crossing_is_the_first_nanosecond_past_the_boundary() {
        // 3 mm/s from 0: x ≥ 1 mm first holds at 1/3 s, rounded up to 333_333_334 ns.
        let seg = Segment::steady(SimTime::ZERO, 0.0, 3.0, None);
        let t = seg.crossing(&edge(1.0, Side::Lower), true, SimTime::ZERO);
        assert_eq!(t, Some(SimTime::from_nanos(333_333_334)));
        let t = t.unwrap_or(SimTime::ZERO);
        assert!(seg.position_at(t) >= 1.0);
        assert!(seg.position_at(t - SimDuration::from_nanos(1)) < 1.0);
    }

    #[test]
    fn the_boundary_point_belongs_to_the_zone() {
        // 1 mm/s from 0 reaches exactly 1 mm at 1 s: entering (x ≥ 1) happens then, leaving
        // an upper edge at 1 (x > 1) one nanosecond later.
        let seg = Segment::steady(SimTime::ZERO, 0.0, 1.0, None);
        let enter = seg.crossing(&edge(1.0, Side::Lower), true, SimTime::ZERO);
        let leave = seg.crossing(&edge(1.0, Side::Upper), true, SimTime::ZERO);
        assert_eq!(enter, Some(SimTime::from_millis(1000)));
        assert_eq!(leave, Some(SimTime::from_nanos(1_000_000_001)));
    }

    #[test]
    fn braking_short_of_a_boundary_never_reaches_it() {
        // 10 mm/s braking at 100 mm/s² stops after 0.5 mm.
        let seg = Segment::ramp(SimTime::ZERO, 0.0, 10.0, -100.0, 0.0, SegmentEnd::Stop);
        assert_eq!(
            seg.crossing(&edge(0.6, Side::Lower), true, SimTime::ZERO),
            None
        );
        let t = seg.crossing(&edge(0.4, Side::Lower), true, SimTime::ZERO);
        // Exact: 0.4 = 10τ − 50τ² → τ = (10 − √20)/100 s.
        let exact_ns = (10.0 - 20f64.sqrt()) / 100.0 * 1e9;
        let t = t.map_or(0.0, |t| t.as_nanos() as f64);
        assert!(t >= exact_ns && t < exact_ns + 1.0, "{t} vs {exact_ns}");
    }

    #[test]
    fn ramp_end_is_rounded_up() {
        let seg = Segment::ramp(
            SimTime::ZERO,
            0.0,
            0.0,
            3.0,
            1.0,
            SegmentEnd::RampEnd { v_end: 1.0 },
        );
        assert_eq!(seg.end.map(|e| e.0), Some(SimTime::from_nanos(333_333_334)));
    }
}
