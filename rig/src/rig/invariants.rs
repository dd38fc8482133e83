//! The invariant watch: the judge of every run (README "Violations"). It sees the plant as it
//! is at each moment and says when the guarded lift is unsafe: the cabin moving with the door
//! open or overloaded, K1 closed with an overtravel sensor tripped, STOP not opening K1, and
//! (with the safe drive) the car moving at a floor with the door open.

use crate::report::ViolationKind;
use asi_phy::{SimDuration, SimTime};

/// Reaction budgets of the invariants (see README "Violations").
const DOOR_BUDGET: SimDuration = SimDuration::from_millis(1000);
const OVERLOAD_BUDGET: SimDuration = SimDuration::from_millis(1000);
const OVERTRAVEL_BUDGET: SimDuration = SimDuration::from_millis(50);
const STOP_MARGIN: SimDuration = SimDuration::from_millis(200);
/// How far the car may move at a floor with the door open before the watch calls it a
/// violation (with the safe drive; README "Violations"): the safe drive's SOS holds it within
/// 0.5 motor revolutions (5.0 mm), and its brake needs a little more.
pub(super) const UNINTENDED_MOVEMENT_MM: f64 = 10.0;

/// What the watch looks at, at one moment.
#[derive(Clone, Copy, Debug)]
pub(super) struct Observed {
    /// The cabin's velocity, mm/s.
    pub velocity_mm_s: f64,
    /// The operator is turning the hand crank.
    pub hand_cranking: bool,
    pub door_open: bool,
    pub overloaded: bool,
    /// An overtravel sensor is tripped.
    pub overtravel_tripped: bool,
    pub k1_closed: bool,
    /// A STOP channel is open.
    pub stop: bool,
    /// The cabin's height, mm.
    pub position_mm: f64,
    /// The floor whose level window the cabin is in, if any. Only read when
    /// [`Observed::needs_level_floor`]; the rig leaves it `None` otherwise.
    pub level_floor: Option<u8>,
    /// Watch "unintended movement": a car at rest with the door open that moves (the safe
    /// drive is on).
    pub watch_unintended_movement: bool,
}

impl Observed {
    /// Whether [`InvariantWatch::check`] reads `level_floor`: only for the unintended-movement
    /// watch with the door open. The rig works the floor out only then (a division and a
    /// rounding at every moment otherwise).
    pub(super) const fn needs_level_floor(
        watch_unintended_movement: bool,
        door_open: bool,
    ) -> bool {
        watch_unintended_movement && door_open
    }
}

/// Watches the invariants.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct InvariantWatch {
    door_open_since: Option<SimTime>,
    overloaded_since: Option<SimTime>,
    overtravel_k1_since: Option<SimTime>,
    /// STOP pressed at, and whether K1 has opened since.
    stop_since: Option<(SimTime, bool)>,
    /// The cabin moves by the hand crank (from the turn's start to the next rest).
    by_hand: bool,
    /// Where the car stood at rest with the door open (its floor, if level at one; mm).
    door_open_at: Option<(Option<u8>, f64)>,
    /// Reported once per episode: door, overload, overtravel, unintended movement.
    reported: [bool; 4],
}

impl InvariantWatch {
    /// Looks at the plant at `t`; returns the invariants it breaks now. `estop_delay` is the
    /// safety logic's STOP delay (SS1), after which K1 must be open.
    pub(super) fn check(
        &mut self,
        t: SimTime,
        o: Observed,
        estop_delay: SimDuration,
    ) -> Vec<(ViolationKind, String)> {
        let mut found = Vec::new();
        // Motion by the hand crank (K1 open, the operator at the motor) is the operator's, not
        // the drive's, until the cabin is at rest again (a turn that K1 ends still brakes): the
        // door and overload invariants judge the drive.
        let velocity = o.velocity_mm_s;
        self.by_hand = velocity != 0.0 && (self.by_hand || o.hand_cranking);
        let moving = velocity != 0.0 && !self.by_hand;
        let tripped_k1 = o.overtravel_tripped && o.k1_closed;
        let since = |flag: bool, s: Option<SimTime>| if flag { s.or(Some(t)) } else { None };
        self.door_open_since = since(o.door_open, self.door_open_since);
        self.overloaded_since = since(o.overloaded, self.overloaded_since);
        self.overtravel_k1_since = since(tripped_k1, self.overtravel_k1_since);
        match (&mut self.stop_since, o.stop) {
            (None, true) => self.stop_since = Some((t, !o.k1_closed)),
            (Some((_, opened)), _) => *opened |= !o.k1_closed,
            _ => {}
        }

        let over =
            |since: Option<SimTime>, budget: SimDuration| since.is_some_and(|s| t - s > budget);
        let mut once = |slot: usize, kind: ViolationKind, detail: String| {
            if !self.reported[slot] {
                self.reported[slot] = true;
                found.push((kind, detail));
            }
        };
        // With the safe drive, a car that rested with the door open (at a floor or between
        // floors: SOS holds it wherever the door is open) is judged by how far it moves from
        // there (below), not by whether it moves at all.
        let judged_at_rest = o.watch_unintended_movement && self.door_open_at.is_some();
        if moving && !judged_at_rest && over(self.door_open_since, DOOR_BUDGET) {
            once(
                0,
                ViolationKind::DoorOpenMoving,
                format!("the cabin moves with the door open for more than {DOOR_BUDGET}"),
            );
        }
        if moving && over(self.overloaded_since, OVERLOAD_BUDGET) {
            once(
                1,
                ViolationKind::OverloadedMoving,
                format!("the cabin moves overloaded for more than {OVERLOAD_BUDGET}"),
            );
        }
        if over(self.overtravel_k1_since, OVERTRAVEL_BUDGET) {
            once(
                2,
                ViolationKind::K1InOvertravel,
                format!(
                    "K1 closed with an overtravel sensor tripped for more than {OVERTRAVEL_BUDGET}"
                ),
            );
        }
        if o.watch_unintended_movement && o.door_open && !self.by_hand && !o.hand_cranking {
            match self.door_open_at {
                None if velocity == 0.0 => {
                    self.door_open_at = Some((o.level_floor, o.position_mm));
                }
                Some((floor, x0)) if (o.position_mm - x0).abs() > UNINTENDED_MOVEMENT_MM => {
                    let place =
                        floor.map_or("between floors".to_string(), |f| format!("at floor {f}"));
                    once(
                        3,
                        ViolationKind::UnintendedMovement,
                        format!(
                            "the car moved {:+.1} mm {place} with the door open, more than {UNINTENDED_MOVEMENT_MM} mm",
                            o.position_mm - x0
                        ),
                    );
                }
                _ => {}
            }
        } else {
            // Closed, or moved by hand (the operator's deliberate move): a new reference
            // the next time the car rests with the door open.
            self.door_open_at = None;
        }
        if let Some((since, opened)) = self.stop_since {
            if t - since > estop_delay + STOP_MARGIN {
                if !opened {
                    found.push((
                        ViolationKind::StopIgnored,
                        format!("K1 still closed {} after STOP", estop_delay + STOP_MARGIN),
                    ));
                }
                self.stop_since = None;
            }
        }
        for (slot, on) in [
            o.door_open,
            o.overloaded,
            tripped_k1,
            self.door_open_at.is_some(),
        ]
        .into_iter()
        .enumerate()
        {
            if !on {
                self.reported[slot] = false;
            }
        }
        found
    }

    /// After a [`InvariantWatch::check`] that saw `o`: the last time through which another
    /// check that sees the same finds nothing and changes nothing, or `None` if the next one
    /// may. "The same" is every field of `o` but the velocity's magnitude (its being zero or
    /// not is the same), the position and the level floor: the watch reads those only while
    /// the door is open with the safe drive's watch on, and then this is `None`.
    ///
    /// Another check with the same booleans repeats what this one did (each field follows
    /// them, or is set once and kept), except for what depends on the time: a budget running
    /// out ([`DOOR_BUDGET`], [`OVERLOAD_BUDGET`], [`OVERTRAVEL_BUDGET`], each only while its
    /// episode is not reported yet), the STOP watch ending, and a STOP still held after it
    /// ended (which starts the next one).
    pub(super) fn quiet_through(&self, o: &Observed, estop_delay: SimDuration) -> Option<SimTime> {
        if o.watch_unintended_movement && o.door_open {
            return None;
        }
        if o.stop && self.stop_since.is_none() {
            return None;
        }
        let moving = o.velocity_mm_s != 0.0 && !self.by_hand;
        let mut through = SimTime::MAX;
        for (since, budget, slot, judged) in [
            (self.door_open_since, DOOR_BUDGET, 0, moving),
            (self.overloaded_since, OVERLOAD_BUDGET, 1, moving),
            (self.overtravel_k1_since, OVERTRAVEL_BUDGET, 2, true),
        ] {
            if let Some(s) = since.filter(|_| judged && !self.reported[slot]) {
                through = through.min(s + budget);
            }
        }
        if let Some((since, _)) = self.stop_since {
            through = through.min(since + (estop_delay + STOP_MARGIN));
        }
        Some(through)
    }
}

/// What tells, at a moment, that the watch would see what it saw at its last check (in
/// the sense of [`InvariantWatch::quiet_through`]): the plant's count of changes
/// ([`lift_model::Lift::changes`]) and whether the cabin moves.
pub(super) type PlantKey = (u64, bool);

/// The checks the rig may skip: while the plant's key is the one of the last check and the
/// time is not past what [`InvariantWatch::quiet_through`] said then, a check would find
/// nothing and change nothing. Almost every moment of a run is such a one.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Quiet(Option<(PlantKey, SimTime)>);

impl Quiet {
    /// Whether the check at `t` of a plant with `key` can be skipped.
    #[inline]
    pub(super) fn holds(&self, key: PlantKey, t: SimTime) -> bool {
        self.0.is_some_and(|(k, through)| k == key && t <= through)
    }

    /// The last time a check of the plant with `key` may be skipped ([`Quiet::holds`] up to
    /// it), `None` if none may.
    #[inline]
    pub(super) fn through(&self, key: PlantKey) -> Option<SimTime> {
        self.0
            .and_then(|(k, through)| (k == key).then_some(through))
    }

    /// After a check of the plant with `key` that saw `o`.
    pub(super) fn after_check(
        &mut self,
        watch: &InvariantWatch,
        key: PlantKey,
        o: &Observed,
        estop_delay: SimDuration,
    ) {
        self.0 = watch.quiet_through(o, estop_delay).map(|t| (key, t));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DELAY: SimDuration = SimDuration::from_millis(9_100);

    /// The car at `position_mm` (floor 2 is at 400 mm), `velocity_mm_s`, door open, the watch
    /// of the safe drive on.
    fn seen(position_mm: f64, velocity_mm_s: f64) -> Observed {
        Observed {
            velocity_mm_s,
            hand_cranking: false,
            door_open: true,
            overloaded: false,
            overtravel_tripped: false,
            k1_closed: true,
            stop: false,
            position_mm,
            level_floor: ((390.0..=410.0).contains(&position_mm)).then_some(2),
            watch_unintended_movement: true,
        }
    }

    /// Feeds `path` (ms, position, velocity) to a watch; the kinds it reports.
    fn watch(path: &[(u64, Observed)]) -> Vec<ViolationKind> {
        let mut w = InvariantWatch::default();
        path.iter()
            .flat_map(|(ms, o)| w.check(SimTime::from_millis(*ms), *o, DELAY))
            .map(|(k, _)| k)
            .collect()
    }

    /// Any moment of a lift near floor 2, with small steps in time and position.
    fn observed() -> impl proptest::strategy::Strategy<Value = Observed> {
        use proptest::prelude::*;
        (
            (prop_oneof![Just(0.0), -30.0..30.0f64], any::<[bool; 8]>()),
            prop_oneof![Just(400.0), 370.0..430.0f64],
        )
            .prop_map(|((velocity_mm_s, b), position_mm)| Observed {
                velocity_mm_s,
                hand_cranking: b[0],
                door_open: b[1],
                overloaded: b[2],
                overtravel_tripped: b[3],
                k1_closed: b[4],
                stop: b[5],
                position_mm,
                level_floor: b[6].then_some(2),
                watch_unintended_movement: b[7],
            })
    }

    proptest::proptest! {
        /// The watch says and remembers the same whether it is given the level floor at every
        /// moment or only when it needs it (as the rig gives it).
        #[test]
        fn the_level_floor_matters_only_when_the_watch_needs_it(
            path in proptest::collection::vec((1..400u64, observed()), 0..120)
        ) {
            let (mut every, mut needed) = (InvariantWatch::default(), InvariantWatch::default());
            let mut ms = 0;
            for (dt, o) in path {
                ms += dt;
                let t = SimTime::from_millis(ms);
                let mut only = o;
                if !Observed::needs_level_floor(o.watch_unintended_movement, o.door_open) {
                    only.level_floor = None;
                }
                proptest::prop_assert_eq!(every.check(t, o, DELAY), needed.check(t, only, DELAY));
                proptest::prop_assert_eq!(format!("{every:?}"), format!("{needed:?}"));
            }
        }
    }

    /// One moment of a run for the skipping watch: how far time moves, and what the plant
    /// shows then.
    #[derive(Clone, Debug)]
    enum Moment {
        /// `ms` and `ns` later, a plant that changed (a new key), showing this.
        Changed(u64, u64, Observed),
        /// `ms` and `ns` later, the plant unchanged: a new velocity if it moves (same
        /// direction of zero), and then a new position and level floor too.
        Same(u64, u64, f64, f64, bool),
        /// Exactly at the end of the last quiet span, or one nanosecond after it, the plant
        /// unchanged.
        AtQuietEnd(bool),
    }

    fn moments() -> impl proptest::strategy::Strategy<Value = Vec<Moment>> {
        use proptest::prelude::*;
        let ns = prop_oneof![Just(0u64), Just(1), 0..1_000_000u64];
        let ms = prop_oneof![0..60u64, 0..1_200u64, Just(50), Just(1_000), Just(9_300)];
        proptest::collection::vec(
            prop_oneof![
                2 => (ms.clone(), ns.clone(), observed())
                    .prop_map(|(ms, ns, o)| Moment::Changed(ms, ns, o)),
                6 => (ms, ns, 1.0..30.0f64, 370.0..430.0f64, any::<bool>())
                    .prop_map(|(ms, ns, v, x, f)| Moment::Same(ms, ns, v, x, f)),
                2 => any::<bool>().prop_map(Moment::AtQuietEnd),
            ],
            0..150,
        )
    }

    proptest::proptest! {
        /// The watch that skips the checks [`Quiet`] allows finds what the watch that checks
        /// at every moment finds, at the same moments, and is in the same state after every
        /// moment: with repeated observations, budgets running out to the nanosecond, STOP
        /// watches ending and starting again, the safe drive's watch on and off.
        #[test]
        fn skipping_the_quiet_checks_changes_nothing(path in moments()) {
            let (mut every, mut skipping) = (InvariantWatch::default(), InvariantWatch::default());
            let mut quiet = Quiet::default();
            let mut t = SimTime::ZERO;
            let mut o = seen(400.0, 0.0);
            let mut changes = 0u64;
            for m in path {
                match m {
                    Moment::Changed(ms, ns, new) => {
                        t += SimDuration::from_nanos(ms * 1_000_000 + ns);
                        o = new;
                        changes += 1;
                    }
                    Moment::Same(ms, ns, v, x, floor) => {
                        t += SimDuration::from_nanos(ms * 1_000_000 + ns);
                        if o.velocity_mm_s != 0.0 {
                            o.velocity_mm_s = v;
                            o.position_mm = x;
                            o.level_floor = floor.then_some(2);
                        }
                    }
                    Moment::AtQuietEnd(after) => {
                        if let Some((_, through)) = quiet.0.filter(|(_, e)| *e != SimTime::MAX) {
                            t = t.max(through + SimDuration::from_nanos(u64::from(after)));
                        }
                    }
                }
                let key = (changes, o.velocity_mm_s != 0.0);
                let reference = every.check(t, o, DELAY);
                let found = if quiet.holds(key, t) {
                    Vec::new()
                } else {
                    let found = skipping.check(t, o, DELAY);
                    quiet.after_check(&skipping, key, &o, DELAY);
                    found
                };
                proptest::prop_assert_eq!(found, reference, "at {}", t);
                proptest::prop_assert_eq!(&skipping, &every, "at {}", t);
            }
        }
    }

    #[test]
    fn a_car_that_moves_more_than_10_mm_at_a_floor_with_the_door_open_is_a_violation() {
        let found = watch(&[
            (0, seen(400.0, 0.0)),
            (2_000, seen(405.0, 5.0)),
            (2_500, seen(410.5, 5.0)),
            (3_000, seen(412.0, 5.0)),
        ]);
        assert_eq!(found, [ViolationKind::UnintendedMovement]);
    }

    #[test]
    fn within_10_mm_it_is_not_and_the_door_budget_does_not_judge_it() {
        // Moving with the door open for more than 1 s would be door-open-moving; at a floor
        // the safe drive's watch judges the distance instead.
        let found = watch(&[
            (0, seen(400.0, 0.0)),
            (2_000, seen(400.01, 2.0)),
            (2_010, seen(409.9, 0.0)),
        ]);
        assert!(found.is_empty(), "{found:?}");
    }

    #[test]
    fn without_the_safe_drive_the_watch_is_as_it_was() {
        let off = |mut o: Observed| {
            o.watch_unintended_movement = false;
            o
        };
        let found = watch(&[(0, off(seen(400.0, 0.0))), (2_000, off(seen(420.0, 5.0)))]);
        assert_eq!(found, [ViolationKind::DoorOpenMoving]);
    }

    #[test]
    fn a_hand_crank_and_a_car_between_floors_are_not_judged_by_the_floor_watch() {
        let crank = |mut o: Observed| {
            o.hand_cranking = true;
            o.k1_closed = false;
            o
        };
        let found = watch(&[
            (0, seen(400.0, 0.0)),
            (1_000, crank(seen(400.0, 10.0))),
            (3_000, crank(seen(420.0, 10.0))),
            (3_100, seen(421.0, 0.0)),
        ]);
        assert!(found.is_empty(), "{found:?}");
    }

    /// SOS holds the car wherever the door is open, so a car at rest between floors with the
    /// door open (a power-on there, a door opened by hand) is judged by how far it moves too
    /// (campaign 18 of the safe-drive profile, runs 49 and 206: a runaway stopped by SOS
    /// after 0.1 mm was judged by `door-open-moving`, any movement at all).
    #[test]
    fn a_car_at_rest_between_floors_with_the_door_open_is_judged_by_how_far_it_moves() {
        let found = watch(&[
            (0, seen(250.0, 0.0)),
            (2_000, seen(250.0, 3.0)),
            (2_100, seen(250.2, 0.0)),
        ]);
        assert!(found.is_empty(), "{found:?}");
        let found = watch(&[(0, seen(250.0, 0.0)), (2_000, seen(262.0, 20.0))]);
        assert_eq!(found, [ViolationKind::UnintendedMovement]);
    }

    #[test]
    fn reported_once_per_door_opening() {
        let mut closed = seen(400.0, 0.0);
        closed.door_open = false;
        let found = watch(&[
            (0, seen(400.0, 0.0)),
            (100, seen(415.0, 1.0)),
            (200, seen(430.0, 1.0)),
            (300, closed),
            (400, seen(400.0, 0.0)),
            (500, seen(389.0, -1.0)),
        ]);
        assert_eq!(
            found,
            [
                ViolationKind::UnintendedMovement,
                ViolationKind::UnintendedMovement
            ]
        );
    }
}
