//! The event loop: edges in time order, the cabin crossing boundaries, crashes, and the
//! motion planned for the present goal.

use asi_phy::SimTime;

use super::{Events, Goal, Lift, PlantError};
use crate::controls::SensorFault;
use crate::event::{Crash, PlantEvent, PlantEventKind};
use crate::motion::{Segment, SegmentEnd};
use crate::sensor::End;

/// The earlier of two times, where `None` is never (the other one, if any).
#[inline]
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
    #[inline]
    pub fn next_event(&self) -> Option<SimTime> {
        // Asked at every moment of a run, twice (here and by the rig): kept rather than
        // worked out each time, and checked against the working-out in debug builds.
        debug_assert_eq!(
            self.next,
            self.work_out_next_event(),
            "the plant's next edge is stale at {}",
            self.now
        );
        self.next
    }

    /// The earliest of the next button release, the next crossing and the end of the motion
    /// segment: what [`Lift::next_event`] keeps.
    fn work_out_next_event(&self) -> Option<SimTime> {
        // Two plain comparisons of the three times rather than an iterator over them.
        earliest(
            earliest(self.buttons.next_release(), self.next_crossing),
            self.motion.end.map(|(t, _)| t),
        )
    }

    /// Works the next edge out again after the buttons, the next crossing or the motion
    /// changed: at the end of [`Lift::start_motion`], after every edge handled and after a
    /// press or a release.
    pub(super) fn next_event_changed(&mut self) {
        self.next = self.work_out_next_event();
    }

    /// Moves the plant to `t` and returns every edge since the last call (including those
    /// queued by inputs), in time order. Allocates nothing once the queue has grown to the
    /// largest burst.
    pub fn advance_to(&mut self, t: SimTime) -> Result<Events<'_>, PlantError> {
        self.catch_up(t)?;
        if self.events.is_empty() {
            return Ok(Events(None));
        }
        Ok(Events(Some(self.events.drain(..))))
    }

    /// A count that moves at every input and at every handled edge: while it stays, the
    /// plant's state changes only by time passing within one motion segment, so every output
    /// but the position and the velocity stays as it is (K1, the converter, buttons, STOP,
    /// sensors, door, load, the hand crank, displays, crashes). A caller that watches some
    /// of those outputs at every moment looks again only when the count has moved.
    #[inline]
    pub fn changes(&self) -> u64 {
        self.changes
    }

    /// Brings the plant to `now` for an input at `now`, which changes its state
    /// ([`Lift::changes`]).
    pub(super) fn input_at(&mut self, now: SimTime) -> Result<(), PlantError> {
        self.catch_up(now)?;
        self.changes = self.changes.wrapping_add(1);
        Ok(())
    }

    /// Moves the plant to `t`, handling every edge due by then in time order.
    ///
    /// At almost every moment of a run no edge is due: that is told by one look at
    /// [`Lift::next_event`], and the loop that handles edges ([`Lift::edges_until`], with
    /// [`Lift::step`] inlined into it) is entered only when one is.
    #[inline]
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
        self.changes = self.changes.wrapping_add(1);
        while let Some(next) = self.next_event().filter(|&next| next <= t) {
            self.now = next;
            let stepped = self.step();
            self.next_event_changed();
            if !stepped {
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
        self.next_event_changed();
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

    use crate::controls::{Button, ContactFault, LoadLevel, SensorFault, StopChannel};
    use crate::display::DisplayId;
    use crate::sensor::VaneSensor;
    use crate::LiftConfig;
    use asi_phy::SimDuration;

    /// An input to the plant, or none.
    #[derive(Clone, Debug)]
    enum Input {
        None,
        Contactor(bool),
        Welded(bool),
        Converter(bool, bool, u16),
        ConverterFault(bool),
        Runaway(Option<bool>),
        Press(u8, u64),
        Release(u8),
        StopFault(bool, u8),
        VaneFault(bool, u8),
        Door(bool),
        Load(u8),
        Crank(f64),
        Display(u8, u16),
    }

    fn inputs() -> impl Strategy<Value = Vec<(u64, Input)>> {
        let input = prop_oneof![
            8 => Just(Input::None),
            2 => any::<bool>().prop_map(Input::Contactor),
            1 => any::<bool>().prop_map(Input::Welded),
            3 => (any::<bool>(), any::<bool>(), 4_000..20_000u16)
                .prop_map(|(r, u, s)| Input::Converter(r, u, s)),
            1 => any::<bool>().prop_map(Input::ConverterFault),
            1 => proptest::option::of(any::<bool>()).prop_map(Input::Runaway),
            2 => (0..16u8, 1..3_000_000_000u64).prop_map(|(b, d)| Input::Press(b, d)),
            1 => (0..16u8).prop_map(Input::Release),
            1 => (any::<bool>(), 0..3u8).prop_map(|(c, f)| Input::StopFault(c, f)),
            1 => (any::<bool>(), 0..3u8).prop_map(|(c, f)| Input::VaneFault(c, f)),
            1 => any::<bool>().prop_map(Input::Door),
            1 => (0..4u8).prop_map(Input::Load),
            1 => (-500.0..500.0f64).prop_map(Input::Crank),
            1 => (0..6u8, any::<u16>()).prop_map(|(d, w)| Input::Display(d, w)),
        ];
        let dt = prop_oneof![
            Just(0u64),
            1..1_000u64,
            1..5_000_000u64,
            1..2_000_000_000u64
        ];
        proptest::collection::vec((dt, input), 0..120)
    }

    fn button(b: u8) -> Button {
        match b {
            0..=3 => Button::Cabin(b + 1),
            4..=6 => Button::HallUp(b - 3),
            7..=9 => Button::HallDown(b - 5),
            10 => Button::Bell,
            _ => Button::Stop,
        }
    }

    /// Applies `input` at `t`; a refused input is as good as any for these tests.
    fn apply(lift: &mut Lift, t: SimTime, input: &Input) {
        let fault = |f: u8| {
            [
                ContactFault::None,
                ContactFault::StuckClosed,
                ContactFault::StuckOpen,
            ][usize::from(f)]
        };
        let sensor = |f: u8| {
            [
                SensorFault::None,
                SensorFault::StuckOn,
                SensorFault::StuckOff,
            ][usize::from(f)]
        };
        let _ = match *input {
            Input::None => Ok(()),
            Input::Contactor(on) => lift.set_contactor(t, on),
            Input::Welded(on) => lift.set_contactor_welded(t, on),
            Input::Converter(run, up, sp) => lift.set_converter(t, run, up, sp),
            Input::ConverterFault(on) => lift.set_converter_fault(t, on),
            Input::Runaway(r) => lift.set_converter_runaway(t, r),
            Input::Press(b, ns) => lift.press(t, button(b), SimDuration::from_nanos(ns)),
            Input::Release(b) => lift.release(t, button(b)),
            Input::StopFault(one, f) => {
                let channel = if one {
                    StopChannel::One
                } else {
                    StopChannel::Two
                };
                lift.set_stop_channel_fault(t, channel, fault(f))
            }
            Input::VaneFault(left, f) => {
                let v = if left {
                    VaneSensor::Left
                } else {
                    VaneSensor::Right
                };
                lift.set_vane_fault(t, v, sensor(f))
            }
            Input::Door(closed) => lift.set_door(t, closed),
            Input::Load(l) => lift.set_load(t, LoadLevel::ALL[usize::from(l)]),
            Input::Crank(mm) => lift.crank(t, mm),
            Input::Display(d, w) => {
                let id = if d == 0 {
                    DisplayId::Cabin
                } else {
                    DisplayId::Floor(d)
                };
                lift.set_display(t, id, w)
            }
        };
    }

    /// Everything the plant shows but the position and the velocity, with the motion
    /// segment and the next edge.
    fn outputs(lift: &Lift) -> String {
        let buttons: Vec<bool> = (0..16).map(|b| lift.is_pressed(button(b))).collect();
        let displays: Vec<_> = std::iter::once(DisplayId::Cabin)
            .chain((1..=lift.config.floors).map(DisplayId::Floor))
            .map(|d| lift.display(d))
            .collect();
        format!(
            "{:?}",
            (
                (
                    lift.k1_closed(),
                    lift.k1_aux_closed(),
                    lift.converter_ready(),
                    lift.converter_fault()
                ),
                (
                    lift.stop_channels(),
                    lift.stop_pressed(),
                    lift.door_closed(),
                    lift.load()
                ),
                (
                    lift.overtravel_bottom_free(),
                    lift.overtravel_top_free(),
                    lift.vane_left(),
                    lift.vane_right()
                ),
                (
                    lift.in_level_zone(),
                    lift.hand_cranking(),
                    lift.converter_runaway(),
                    lift.crashes().len()
                ),
                (buttons, displays, lift.motion, lift.next_event()),
            )
        )
    }

    proptest! {
        /// While [`Lift::changes`] stays, every output but the position and the velocity
        /// stays, and so do the motion segment and the next edge.
        #[test]
        fn while_the_count_of_changes_stays_only_time_passes(steps in inputs()) {
            let mut lift = Lift::new(LiftConfig { initial_position_mm: 20.0, ..LiftConfig::default() })
                .expect("a lift");
            let mut t = SimTime::ZERO;
            let mut last = (lift.changes(), outputs(&lift));
            for (dt, input) in &steps {
                t += SimDuration::from_nanos(*dt);
                apply(&mut lift, t, input);
                let _ = lift.advance_to(t).expect("forward").count();
                let now = (lift.changes(), outputs(&lift));
                if now.0 == last.0 {
                    prop_assert_eq!(&now.1, &last.1, "at {}", t);
                }
                last = now;
            }
        }
    }

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
