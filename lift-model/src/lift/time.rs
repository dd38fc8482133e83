//! The event loop: edges in time order, the cabin crossing boundaries, crashes, and the
//! motion planned for the present goal.

use asi_phy::SimTime;

use super::{Events, Goal, Lift, PlantError};
use crate::controls::SensorFault;
use crate::event::{Crash, PlantEvent, PlantEventKind};
use crate::motion::{Segment, SegmentEnd};
use crate::sensor::End;

/// The earlier of two times, where `None` is never (the other one, if any).
fn earliest(a: Option<SimTime>, b: Option<SimTime>) -> Option<SimTime> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, None) => a,
        (None, b) => b,
    }
}

impl Lift {
    /// When the next edge happens under the present inputs (vane edge, overtravel trip or
    /// clear, end of a ramp, stop, mechanical end, button release); `None` when nothing will
    /// change until an input does. May equal [`Lift::now`] right after an input.
    pub fn next_event(&self) -> Option<SimTime> {
        // Asked at every moment of a run (here and by the rig): two plain comparisons of
        // the three times rather than an iterator over them.
        earliest(
            earliest(self.buttons.next_release(), self.next_crossing),
            self.motion.end.map(|(t, _)| t),
        )
    }

    /// Moves the plant to `t` and returns every edge since the last call (including those
    /// queued by inputs), in time order. Allocates nothing once the queue has grown to the
    /// largest burst.
    pub fn advance_to(&mut self, t: SimTime) -> Result<Events<'_>, PlantError> {
        self.catch_up(t)?;
        Ok(Events(self.events.drain(..)))
    }

    /// Moves the plant to `t`, handling every edge due by then in time order.
    ///
    /// At almost every moment of a run no edge is due: that is told by one look at
    /// [`Lift::next_event`], and the loop that handles edges ([`Lift::edges_until`], with
    /// [`Lift::step`] inlined into it) is entered only when one is.
    pub(super) fn catch_up(&mut self, t: SimTime) -> Result<(), PlantError> {
        if t < self.now {
            return Err(PlantError::TimeReversed {
                now: t,
                plant_time: self.now,
            });
        }
        if self.next_event().is_some_and(|next| next <= t) {
            self.edges_until(t);
        }
        self.now = t;
        Ok(())
    }

    /// Handles every edge due by `t` in time order, leaving [`Lift::now`] at the last one.
    #[inline(never)]
    fn edges_until(&mut self, t: SimTime) {
        while let Some(next) = self.next_event().filter(|&next| next <= t) {
            self.now = next;
            if !self.step() {
                // Unreachable: `next_event` is the earliest of the three `step` handles.
                // Stopping here rather than spinning keeps a logic slip from hanging a run.
                break;
            }
        }
    }

    /// Handles one edge due at `self.now`; `false` if none was due.
    pub(super) fn step(&mut self) -> bool {
        let now = self.now;
        if self.buttons.next_release() == Some(now) {
            let events = &mut self.events;
            self.buttons.release_due(now, |button| {
                events.push_back(PlantEvent {
                    at: now,
                    kind: PlantEventKind::Released { button },
                });
            });
        } else if self.next_crossing == Some(now) {
            self.cross();
        } else if let Some((_, how)) = self.motion.end.filter(|&(t, _)| t == now) {
            self.end_segment(how);
        } else {
            return false;
        }
        true
    }

    pub(super) fn emit(&mut self, kind: PlantEventKind) {
        // A failed sensor's output does not follow the vane: no edge to report.
        if let PlantEventKind::Vane { sensor, .. } = kind {
            if self.vane_faults[sensor as usize] != SensorFault::None {
                return;
            }
        }
        self.events.push_back(PlantEvent { at: self.now, kind });
    }

    /// The cabin passes the next boundary in its direction of travel.
    pub(super) fn cross(&mut self) {
        let up = self.motion.direction() > 0;
        let index = if up {
            Some(self.split)
        } else {
            self.split.checked_sub(1)
        };
        let Some(&b) = index.and_then(|i| self.shaft.boundaries.get(i)) else {
            self.next_crossing = None;
            return;
        };
        match self.levels.cross(&b, up) {
            Ok(kind) => {
                self.split = if up { self.split + 1 } else { self.split - 1 };
                self.emit(kind);
                self.search_from = self.now;
                self.next_crossing = self.find_crossing();
            }
            Err(end) => self.crash(end),
        }
    }

    /// The cabin hits a mechanical end: it stops there; under power the converter trips.
    pub(super) fn crash(&mut self, end: End) {
        let impact_mm_s = self.motion.velocity_at(self.now).abs();
        let powered = self.k1.main_closed;
        self.crashes.push(Crash {
            at: self.now,
            end,
            impact_mm_s,
            powered,
        });
        self.emit(PlantEventKind::Crash { end, impact_mm_s });
        self.crank_target_mm = None;
        if self.converter_driving() {
            self.converter.stalled = true;
            self.emit(PlantEventKind::ConverterFault { fault: true });
        }
        self.goal = self.compute_goal();
        self.start_motion(self.config.end_position_mm(end), 0.0);
    }

    pub(super) fn end_segment(&mut self, how: SegmentEnd) {
        let x = self.motion.position_at(self.now);
        let v = match how {
            SegmentEnd::RampEnd { v_end } => {
                self.emit(PlantEventKind::RampEnd {
                    velocity_mm_s: v_end,
                });
                v_end
            }
            SegmentEnd::Stop | SegmentEnd::CrankDone => {
                if how == SegmentEnd::CrankDone {
                    self.crank_target_mm = None;
                    self.goal = self.compute_goal();
                }
                self.emit(PlantEventKind::Stopped { position_mm: x });
                0.0
            }
        };
        self.start_motion(x, v);
    }

    /// The converter has power and no fault, so it drives the motor.
    pub(super) fn converter_driving(&self) -> bool {
        self.k1.main_closed && !self.converter.injected_fault && !self.converter.stalled
    }

    pub(super) fn compute_goal(&self) -> Goal {
        if let Some(target_mm) = self.crank_target_mm {
            return Goal::Crank { target_mm };
        }
        if !self.converter_driving() {
            return Goal::Brake;
        }
        let c = &self.converter;
        if let Some(up) = c.runaway {
            let speed = self
                .config
                .drive
                .setpoint_velocity_mm_s(crate::drive::MAX_SETPOINT_UA);
            let v_target = if up { speed } else { -speed };
            return Goal::Drive { v_target };
        }
        let speed = if c.run {
            self.config.drive.setpoint_velocity_mm_s(c.setpoint_ua)
        } else {
            0.0
        };
        let v_target = if speed == 0.0 || c.up { speed } else { -speed };
        Goal::Drive { v_target }
    }

    /// Re-plans the motion from the present state if the inputs changed what drives it.
    pub(super) fn update_goal(&mut self) {
        let goal = self.compute_goal();
        if goal != self.goal {
            self.goal = goal;
            let x = self.motion.position_at(self.now);
            let v = self.motion.velocity_at(self.now);
            self.start_motion(x, v);
        }
    }

    /// A new motion segment from position `x` and velocity `v` at `self.now`.
    pub(super) fn start_motion(&mut self, x: f64, v: f64) {
        let now = self.now;
        self.motion = match self.goal {
            Goal::Crank { target_mm } => {
                let speed = self.config.crank_speed_mm_s;
                let distance = target_mm - x;
                let v = if distance >= 0.0 { speed } else { -speed };
                let duration_s = distance.abs() / speed;
                Segment::steady(now, x, v, Some((duration_s, SegmentEnd::CrankDone)))
            }
            Goal::Drive { v_target } if v == v_target => Segment::steady(now, x, v, None),
            Goal::Drive { v_target } => {
                // A change of direction ramps through a momentary standstill.
                let reverses = v != 0.0 && (v_target == 0.0 || (v_target > 0.0) != (v > 0.0));
                let (v_end, how) = if reverses {
                    (0.0, SegmentEnd::Stop)
                } else {
                    (v_target, SegmentEnd::RampEnd { v_end: v_target })
                };
                let a = if v_end > v {
                    self.ramp_mm_s2
                } else {
                    -self.ramp_mm_s2
                };
                Segment::ramp(now, x, v, a, v_end, how)
            }
            Goal::Brake if v == 0.0 => Segment::rest(now, x),
            Goal::Brake => {
                let brake = self.config.drive.brake_decel_mm_s2;
                let a = if v > 0.0 { -brake } else { brake };
                Segment::ramp(now, x, v, a, 0.0, SegmentEnd::Stop)
            }
        };
        self.search_from = now;
        self.next_crossing = self.find_crossing();
    }

    pub(super) fn find_crossing(&self) -> Option<SimTime> {
        let (index, up) = match self.motion.direction() {
            1 => (self.split, true),
            -1 => (self.split.checked_sub(1)?, false),
            _ => return None,
        };
        let b = self.shaft.boundaries.get(index)?;
        self.motion.crossing(b, up, self.search_from)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn time(t: Option<u64>) -> Option<SimTime> {
        t.map(SimTime::from_nanos)
    }

    proptest! {
        /// `earliest` twice is the earliest of three optional times as the iterator took it
        /// (the reference for [`Lift::next_event`]).
        #[test]
        fn earliest_is_the_minimum_of_the_times_there_are(
            a in proptest::option::of(0u64..50),
            b in proptest::option::of(0u64..50),
            c in proptest::option::of(0u64..50),
        ) {
            let (a, b, c) = (time(a), time(b), time(c));
            let reference = [a, b, c].into_iter().flatten().min();
            prop_assert_eq!(earliest(earliest(a, b), c), reference);
        }
    }
}
