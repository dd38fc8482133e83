//! The invariant watch: the judge of every run (the book, "Violations", docs/safety.md "What the
//! judge calls a hazard"). It sees the plant as it is at each moment, whatever the controller,
//! the safety logic or a flag says, and says when the guarded lift is unsafe: powered motion
//! with the door open or overloaded, K1 closed with an overtravel sensor tripped, a controller
//! that drives on after STOP, STOP not opening K1, and (with the safe drive) the car moving at
//! a floor with the door open. It also counts the contained faults a judge of a controller
//! wants to see: an overtravel sensor reached under power.

use crate::report::ViolationKind;
use asi_phy::{SimDuration, SimTime};
use std::collections::VecDeque;

/// The sliding window over which the door and load budgets add up (docs/safety.md).
pub(super) const WINDOW: SimDuration = SimDuration::from_secs(10);
/// Reaction budgets of the invariants (see the book, "Violations").
const DOOR_BUDGET: SimDuration = SimDuration::from_millis(1000);
const OVERLOAD_BUDGET: SimDuration = SimDuration::from_millis(1000);
const OVERTRAVEL_BUDGET: SimDuration = SimDuration::from_millis(50);
const STOP_MARGIN: SimDuration = SimDuration::from_millis(200);
/// How far the car may move at a floor with the door open before the watch calls it a
/// violation (with the safe drive; the book, "Violations"): the safe drive's SOS holds it within
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
    /// The safety logic's EStopOut as the controller gets it (`false`: stop at the next
    /// floor and start no run until the circuit is restarted).
    pub estop_out: bool,
    /// The controller's command to run the converter as it last wrote it into the output
    /// image (before the bus carries it to the slave): read only when STOP comes, to tell a
    /// run commanded before it from one started after it.
    pub run_commanded: bool,
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

/// What a check finds.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Finding {
    /// An invariant broken, with the evidence in words.
    Violation(ViolationKind, String),
    /// The cabin reached an overtravel sensor under power (K1 closed): contained by the
    /// safety logic, not a violation, but a failure of the controller (docs/safety.md).
    OvertravelReached,
}

/// How long a condition held within the last [`WINDOW`]: the spans it held, kept while they
/// may still overlap the window, and the span it holds now.
///
/// The spans change only when the condition does, so a check that sees the condition as the
/// last one did changes nothing (what [`InvariantWatch::quiet_through`] relies on).
#[derive(Clone, Debug, Default, PartialEq)]
struct Window {
    /// Closed spans `(start, end)`, oldest first, disjoint.
    spans: VecDeque<(SimTime, SimTime)>,
    /// Since when the condition holds, while it does.
    open: Option<SimTime>,
    /// Reported; armed again only when the condition starts after a whole window without it.
    reported: bool,
}

impl Window {
    /// The condition holds (`on`) at `t`; returns whether it has now held for more than
    /// `budget` within the window ending at `t`, not reported yet (it is reported now).
    fn see(&mut self, t: SimTime, on: bool, budget: SimDuration) -> bool {
        match (self.open, on) {
            (None, true) => {
                if self.reported && self.spans.back().is_none_or(|&(_, end)| t - end >= WINDOW) {
                    self.reported = false;
                }
                self.prune(t);
                self.open = Some(t);
            }
            (Some(start), false) => {
                self.spans.push_back((start, t));
                self.open = None;
                self.prune(t);
            }
            _ => {}
        }
        if !self.reported && self.held(t) > budget {
            self.reported = true;
            return true;
        }
        false
    }

    /// Drops the spans that ended a whole window before `t`.
    fn prune(&mut self, t: SimTime) {
        while self
            .spans
            .front()
            .is_some_and(|&(_, end)| t - end >= WINDOW)
        {
            self.spans.pop_front();
        }
    }

    /// How long the condition held within the window `(t − WINDOW, t]`.
    fn held(&self, t: SimTime) -> SimDuration {
        let from = t.checked_sub(WINDOW).unwrap_or(SimTime::ZERO);
        let part = |start: SimTime, end: SimTime| end.saturating_duration_since(start.max(from));
        let closed = self
            .spans
            .iter()
            .fold(SimDuration::ZERO, |sum, &(s, e)| sum + part(s, e));
        closed + self.open.map_or(SimDuration::ZERO, |s| part(s, t))
    }

    /// While the condition goes on holding: the first time at which it has held for more
    /// than `budget` within the window, `None` if it does not hold or is reported.
    ///
    /// From the open span's start `s` the time held grows at one second per second, but for
    /// the stretches in which an older span slides out of the window: there it stays (the
    /// spans are disjoint and all end by `s`, so at most one slides out at a time).
    fn crossing(&self, budget: SimDuration) -> Option<SimTime> {
        let s = self.open.filter(|_| !self.reported)?;
        let budget = budget.as_nanos();
        let mut held = self.held(s).as_nanos();
        let mut at = s;
        for &(start, end) in &self.spans {
            let (out_from, out_to) = (start + WINDOW, end + WINDOW);
            if out_to <= at {
                continue;
            }
            let grows = out_from.max(at).saturating_duration_since(at).as_nanos();
            if held + grows > budget {
                break;
            }
            held += grows;
            at = out_to;
        }
        Some(at + SimDuration::from_nanos(budget.saturating_sub(held) + 1))
    }
}

/// The watch of one STOP: from EStopOut going off until it is on again (docs/safety.md,
/// `stop-overrun`; §6.3 of the lift thesis: the cabin stops at the nearest floor in its direction
/// of travel). Each rule allows a vane's half-length, so a cabin that levels at its floor, or a
/// fault that a safety function stops within that, is not an overrun.
#[derive(Clone, Debug, PartialEq)]
struct StopEpisode {
    /// The cabin's height when EStopOut went off, mm.
    from_mm: f64,
    /// A run was under way then: the cabin moved under power, or the controller had already
    /// commanded the converter to run (the cabin starts a little later: the bus, the
    /// set-point's transfer, the converter's ramp).
    under_way: bool,
    /// Up (`true`) or down, for a run under way when STOP came (or taken over from the
    /// crank), once the cabin moves.
    direction: Option<bool>,
    /// The next floor in that direction more than a vane's half-length ahead when STOP came,
    /// and the height the cabin may not pass: its level plus that half-length onward.
    limit: Option<(u8, f64)>,
    /// The farthest height reached in the direction of travel.
    far_mm: f64,
    /// Where the cabin rests (or rested before powered motion began): a run from here is a
    /// new run.
    rest_mm: Option<f64>,
    reported: bool,
}

/// Watches the invariants.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct InvariantWatch {
    /// The floors' levels, mm, from floor 1 up.
    levels_mm: Vec<f64>,
    /// A vane's half-length (its long track), mm: how far past a floor's level a cabin told to
    /// stop there may go.
    vane_half_mm: f64,
    door: Window,
    overload: Window,
    overtravel_k1_since: Option<SimTime>,
    /// STOP pressed at, and whether K1 has opened since.
    stop_since: Option<(SimTime, bool)>,
    stop_episode: Option<StopEpisode>,
    /// The cabin moves by the hand crank: K1 open, from the turn's start to the next rest.
    by_hand: bool,
    /// Where the car stood at rest with the door open (its floor, if level at one; mm).
    door_open_at: Option<(Option<u8>, f64)>,
    /// An overtravel sensor was tripped at the last check.
    overtravel_was: bool,
    /// Reported once per episode: overtravel with K1 closed, unintended movement.
    reported: [bool; 2],
}

impl InvariantWatch {
    /// A watch of a shaft with the floors' levels `levels_mm` (floor 1 first) and vanes of
    /// half-length `vane_half_mm`.
    pub(super) fn new(levels_mm: Vec<f64>, vane_half_mm: f64) -> InvariantWatch {
        InvariantWatch {
            levels_mm,
            vane_half_mm,
            door: Window::default(),
            overload: Window::default(),
            overtravel_k1_since: None,
            stop_since: None,
            stop_episode: None,
            by_hand: false,
            door_open_at: None,
            overtravel_was: false,
            reported: [false; 2],
        }
    }

    /// The next floor more than a vane's half-length beyond `x` going up (or down), and the
    /// height past which a cabin stopping there has overrun it.
    fn limit_from(&self, x: f64, up: bool) -> Option<(u8, f64)> {
        let h = self.vane_half_mm;
        let floor = |i: usize| (i + 1) as u8;
        if up {
            let i = self.levels_mm.iter().position(|&l| l - x > h)?;
            Some((floor(i), self.levels_mm[i] + h))
        } else {
            let i = self.levels_mm.iter().rposition(|&l| x - l > h)?;
            Some((floor(i), self.levels_mm[i] - h))
        }
    }

    /// Looks at the plant at `t`; returns what it finds now. `estop_delay` is the safety
    /// logic's STOP delay (SS1), after which K1 must be open.
    pub(super) fn check(
        &mut self,
        t: SimTime,
        o: Observed,
        estop_delay: SimDuration,
    ) -> Vec<Finding> {
        let mut found = Vec::new();
        let mut violation = |kind: ViolationKind, detail: String| {
            found.push(Finding::Violation(kind, detail));
        };
        // Motion by the hand crank is the operator's, not the drive's, until the cabin is at
        // rest again (a turn that ends still brakes); but only while K1 is open: once K1
        // closes the converter takes the moving cabin over, and motion under power is always
        // judged.
        let velocity = o.velocity_mm_s;
        let was_by_hand = self.by_hand;
        self.by_hand = velocity != 0.0 && !o.k1_closed && (self.by_hand || o.hand_cranking);
        let moving = velocity != 0.0 && !self.by_hand;
        let tripped_k1 = o.overtravel_tripped && o.k1_closed;
        self.overtravel_k1_since = if tripped_k1 {
            self.overtravel_k1_since.or(Some(t))
        } else {
            None
        };
        match (&mut self.stop_since, o.stop) {
            (None, true) => self.stop_since = Some((t, !o.k1_closed)),
            (Some((_, opened)), _) => *opened |= !o.k1_closed,
            _ => {}
        }

        // With the safe drive, a car that rested with the door open (at a floor or between
        // floors: SOS holds it wherever the door is open) is judged by how far it moves from
        // there (below), not by whether it moves at all.
        let judged_at_rest = o.watch_unintended_movement && self.door_open_at.is_some();
        if self
            .door
            .see(t, o.door_open && moving && !judged_at_rest, DOOR_BUDGET)
        {
            violation(
                ViolationKind::DoorOpenMoving,
                format!(
                    "the cabin has moved with the door open for more than {DOOR_BUDGET} within {WINDOW}"
                ),
            );
        }
        if self
            .overload
            .see(t, o.overloaded && moving, OVERLOAD_BUDGET)
        {
            violation(
                ViolationKind::OverloadedMoving,
                format!("the cabin has moved overloaded for more than {OVERLOAD_BUDGET} within {WINDOW}"),
            );
        }
        if !self.reported[0]
            && self
                .overtravel_k1_since
                .is_some_and(|s| t - s > OVERTRAVEL_BUDGET)
        {
            self.reported[0] = true;
            violation(
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
                Some((floor, x0))
                    if !self.reported[1] && (o.position_mm - x0).abs() > UNINTENDED_MOVEMENT_MM =>
                {
                    self.reported[1] = true;
                    let place =
                        floor.map_or("between floors".to_string(), |f| format!("at floor {f}"));
                    violation(
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
        // Power taking over a cabin the crank moves (K1 closing during the turn) starts no
        // run: the cabin was under way.
        let taken_over = was_by_hand && moving;
        if let Some(detail) = self.stop_overrun(&o, moving, taken_over) {
            violation(ViolationKind::StopOverrun, detail);
        }
        if let Some((since, opened)) = self.stop_since {
            if t - since > estop_delay + STOP_MARGIN {
                if !opened {
                    violation(
                        ViolationKind::StopIgnored,
                        format!("K1 still closed {} after STOP", estop_delay + STOP_MARGIN),
                    );
                }
                self.stop_since = None;
            }
        }
        for (slot, on) in [tripped_k1, self.door_open_at.is_some()]
            .into_iter()
            .enumerate()
        {
            if !on {
                self.reported[slot] = false;
            }
        }
        if o.overtravel_tripped && !self.overtravel_was && o.k1_closed {
            found.push(Finding::OvertravelReached);
        }
        self.overtravel_was = o.overtravel_tripped;
        found
    }

    /// The STOP watch: from EStopOut going off until it is on again, a run under way may go
    /// on to the next floor in its direction of travel that was more than a vane's
    /// half-length ahead, and that half-length past it; it may not go back more than that
    /// half-length, and a cabin at rest may not start a run of more than that half-length.
    /// Returns the overrun, once per STOP.
    fn stop_overrun(&mut self, o: &Observed, moving: bool, taken_over: bool) -> Option<String> {
        if o.estop_out {
            self.stop_episode = None;
            return None;
        }
        let x = o.position_mm;
        let e = self.stop_episode.get_or_insert(StopEpisode {
            from_mm: x,
            under_way: moving || o.run_commanded,
            direction: None,
            limit: None,
            far_mm: x,
            rest_mm: None,
            reported: false,
        });
        if !moving {
            // At rest: the place a new run would start from (but for a run commanded before
            // STOP that has not begun yet); moved by hand: a new place once the crank leaves
            // it.
            let waiting = e.under_way && e.direction.is_none();
            e.rest_mm = if o.velocity_mm_s == 0.0 && !waiting {
                e.rest_mm.or(Some(x))
            } else {
                None
            };
            return None;
        }
        let up = o.velocity_mm_s > 0.0;
        if e.direction.is_none() && ((e.under_way && e.rest_mm.is_none()) || taken_over) {
            let from = if taken_over { x } else { e.from_mm };
            e.direction = Some(up);
            e.far_mm = from;
            e.rest_mm = None;
            let limit = self.limit_from(from, up);
            self.stop_episode.as_mut()?.limit = limit;
        }
        let half = self.vane_half_mm;
        let e = self.stop_episode.as_mut()?;
        if e.rest_mm.is_none() && e.direction.is_none() {
            // Powered motion with no run under way and no rest seen: it starts here.
            e.rest_mm = Some(x);
        }
        if e.reported {
            return None;
        }
        if let Some(d) = e.direction {
            e.far_mm = if d { e.far_mm.max(x) } else { e.far_mm.min(x) };
        }
        let back = |d: bool| if d { e.far_mm - x } else { x - e.far_mm };
        let passed = |d: bool, limit: f64| if d { x > limit } else { x < limit };
        let why = match (e.rest_mm, e.direction, e.limit) {
            (Some(rest), _, _) if (x - rest).abs() > half => format!(
                "the cabin starts a run after STOP: {:+.1} mm from where it rested at {rest:.1} mm",
                x - rest
            ),
            (_, Some(d), _) if back(d) > half => format!(
                "the cabin reverses after STOP: {:.1} mm back from {:.1} mm",
                back(d),
                e.far_mm
            ),
            (_, Some(d), Some((floor, limit))) if passed(d, limit) => format!(
                "the cabin passes floor {floor}, the next in its direction when STOP came, by more than {half} mm"
            ),
            _ => return None,
        };
        e.reported = true;
        Some(why)
    }

    /// After a [`InvariantWatch::check`] that saw `o`: the last time through which another
    /// check that sees the same finds nothing and changes nothing, or `None` if the next one
    /// may. "The same" is every field of `o` but the velocity's magnitude (its being zero or
    /// not is the same), the position and the level floor: the watch reads those only while
    /// the door is open with the safe drive's watch on, or while a STOP's watch follows a
    /// cabin in powered motion, and then this is `None`.
    ///
    /// Another check with the same booleans repeats what this one did (each field follows
    /// them, or is set once and kept, and the windows' spans change only when their
    /// condition does), except for what depends on the time: a budget running out (the
    /// windows' [`DOOR_BUDGET`] and [`OVERLOAD_BUDGET`], [`OVERTRAVEL_BUDGET`], each only while
    /// not reported yet), the STOP watch ending, and a STOP still held after it ended (which
    /// starts the next one).
    pub(super) fn quiet_through(&self, o: &Observed, estop_delay: SimDuration) -> Option<SimTime> {
        if o.watch_unintended_movement && o.door_open {
            return None;
        }
        if o.stop && self.stop_since.is_none() {
            return None;
        }
        let moving = o.velocity_mm_s != 0.0 && !self.by_hand;
        if moving && self.stop_episode.as_ref().is_some_and(|e| !e.reported) {
            return None;
        }
        let mut through = SimTime::MAX;
        let one = SimDuration::from_nanos(1);
        for (w, budget) in [(&self.door, DOOR_BUDGET), (&self.overload, OVERLOAD_BUDGET)] {
            if let Some(at) = w.crossing(budget) {
                through = through.min(at - one);
            }
        }
        if let Some(s) = self.overtravel_k1_since.filter(|_| !self.reported[0]) {
            through = through.min(s + OVERTRAVEL_BUDGET);
        }
        if let Some((since, _)) = self.stop_since {
            through = through.min(since + (estop_delay + STOP_MARGIN));
        }
        Some(through)
    }
}

/// What tells, at a moment, that the watch would see what it saw at its last check (in
/// the sense of [`InvariantWatch::quiet_through`]): the plant's count of changes
/// ([`lift_model::Lift::changes`]), whether the cabin moves, and the safety logic's EStopOut.
pub(super) type PlantKey = (u64, bool, bool);

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
            estop_out: true,
            run_commanded: false,
            position_mm,
            level_floor: ((390.0..=410.0).contains(&position_mm)).then_some(2),
            watch_unintended_movement: true,
        }
    }

    /// A watch of the lab shaft: four floors 400 mm apart, vanes of ±40 mm.
    fn lab() -> InvariantWatch {
        InvariantWatch::new(vec![0.0, 400.0, 800.0, 1200.0], 40.0)
    }

    /// Feeds `path` (ms, what the watch sees) to a watch; the violations' kinds it reports.
    fn watch(path: &[(u64, Observed)]) -> Vec<ViolationKind> {
        findings(path)
            .into_iter()
            .filter_map(|f| match f {
                Finding::Violation(k, _) => Some(k),
                Finding::OvertravelReached => None,
            })
            .collect()
    }

    /// Feeds `path` to a watch; everything it finds.
    fn findings(path: &[(u64, Observed)]) -> Vec<Finding> {
        let mut w = lab();
        path.iter()
            .flat_map(|(ms, o)| w.check(SimTime::from_millis(*ms), *o, DELAY))
            .collect()
    }

    /// Any moment of a lift near floor 2, with small steps in time and position.
    fn observed() -> impl proptest::strategy::Strategy<Value = Observed> {
        use proptest::prelude::*;
        (
            (prop_oneof![Just(0.0), -30.0..30.0f64], any::<[bool; 10]>()),
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
                estop_out: b[8],
                run_commanded: b[9],
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
            let (mut every, mut needed) = (lab(), lab());
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
            let (mut every, mut skipping) = (lab(), lab());
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
                let key = (changes, o.velocity_mm_s != 0.0, o.estop_out);
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
        let found = watch(&[
            (0, off(seen(400.0, 0.0))),
            (2_000, off(seen(420.0, 5.0))),
            (3_001, off(seen(425.0, 5.0))),
        ]);
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

    /// A cabin in the lab shaft without the safe drive: at `position_mm`, moving at
    /// `velocity_mm_s`, door closed, K1 closed, no STOP.
    fn cabin(position_mm: f64, velocity_mm_s: f64) -> Observed {
        Observed {
            door_open: false,
            watch_unintended_movement: false,
            level_floor: None,
            ..seen(position_mm, velocity_mm_s)
        }
    }

    fn door_open(mut o: Observed) -> Observed {
        o.door_open = true;
        o
    }

    /// A turn of the crank that K1 takes over (the operator's reset closes it while the cabin
    /// moves): the converter drives the moving cabin on and its velocity never reaches zero.
    /// Motion under power is never "by hand" (docs/safety.md), for the door and the load.
    #[test]
    fn a_crank_turn_that_k1_takes_over_hides_no_powered_motion() {
        let crank = |mut o: Observed| {
            o.hand_cranking = true;
            o.k1_closed = false;
            o
        };
        let overloaded = |mut o: Observed| {
            o.overloaded = true;
            o
        };
        for (condition, kind) in [
            (
                door_open as fn(Observed) -> Observed,
                ViolationKind::DoorOpenMoving,
            ),
            (overloaded, ViolationKind::OverloadedMoving),
        ] {
            let found = watch(&[
                (0, condition(cabin(760.0, 0.0))),
                (100, crank(condition(cabin(760.0, 10.0)))),
                (600, condition(cabin(765.0, 10.0))),
                (3_000, condition(cabin(1_000.0, 100.0))),
            ]);
            assert_eq!(found, [kind]);
        }
        // With K1 open the same turn is the operator's.
        let found = watch(&[
            (0, door_open(cabin(760.0, 0.0))),
            (100, crank(door_open(cabin(760.0, 10.0)))),
            (3_000, crank(door_open(cabin(790.0, 10.0)))),
        ]);
        assert!(found.is_empty(), "{found:?}");
    }

    /// Opening the door 950 ms of every second while the cabin moves: 9.5 s of every 10 s with
    /// the door open, judged though no single opening lasts a second (a sliding window).
    #[test]
    fn toggling_the_door_does_not_reset_its_budget() {
        let mut path = vec![(0, cabin(100.0, 30.0))];
        for s in 0..5u64 {
            path.push((s * 1_000 + 1, door_open(cabin(100.0, 30.0))));
            path.push((s * 1_000 + 951, cabin(100.0, 30.0)));
        }
        let found = findings(&path);
        assert!(
            matches!(
                &found[..],
                [Finding::Violation(ViolationKind::DoorOpenMoving, _)]
            ),
            "{found:?}"
        );
        // Found at the second opening's first moment past 1 s in all: 950 ms + 51 ms.
        let mut w = lab();
        let at: Vec<u64> = path
            .iter()
            .filter(|(ms, o)| !w.check(SimTime::from_millis(*ms), *o, DELAY).is_empty())
            .map(|(ms, _)| *ms)
            .collect();
        assert_eq!(at, [1_951]);
    }

    #[test]
    fn openings_a_window_apart_are_not_added_up() {
        let found = watch(&[
            (0, door_open(cabin(100.0, 30.0))),
            (900, cabin(100.0, 30.0)),
            (10_950, door_open(cabin(100.0, 30.0))),
            (11_850, cabin(100.0, 30.0)),
        ]);
        assert!(found.is_empty(), "{found:?}");
        let found = watch(&[
            (0, door_open(cabin(100.0, 30.0))),
            (900, cabin(100.0, 30.0)),
            (9_000, door_open(cabin(100.0, 30.0))),
            (9_150, door_open(cabin(100.0, 30.0))),
        ]);
        assert_eq!(found, [ViolationKind::DoorOpenMoving]);
    }

    /// The window's crossing is the first nanosecond at which the time held exceeds the
    /// budget: checked against the time held one nanosecond before and at it, with spans
    /// sliding out of the window meanwhile.
    #[test]
    fn the_window_crossing_is_exact() {
        let ms = SimTime::from_millis;
        let mut w = Window::default();
        for (t, on) in [
            (0, true),
            (400, false),
            (9_000, true),
            (9_300, false),
            (9_700, true),
        ] {
            assert!(!w.see(ms(t), on, DOOR_BUDGET));
        }
        let at = w.crossing(DOOR_BUDGET).expect("open and not reported");
        let before = at - SimDuration::from_nanos(1);
        assert_eq!(w.held(before), DOOR_BUDGET);
        assert!(w.held(at) > DOOR_BUDGET);
        // 700 ms held at 9.7 s, 1.0 s at 10.0 s; then the first span slides out of the window
        // until 10.4 s and the time held stays 1.0 s: exceeded from 10.4 s and 1 ns.
        assert_eq!(before, ms(10_400));
        assert!(!w.see(before, true, DOOR_BUDGET));
        assert!(w.see(at, true, DOOR_BUDGET));
    }

    fn stopped(mut o: Observed) -> Observed {
        o.estop_out = false;
        o
    }

    /// §6.3 of the lift thesis: after STOP the cabin stops at the nearest floor in its direction of
    /// travel; the watch allows the next floor more than a vane's half-length ahead and that
    /// half-length beyond it.
    #[test]
    fn a_cabin_that_drives_on_after_stop_is_judged_before_the_stop_delay_ends() {
        // Going up from 420 mm: floor 3 (800 mm) is the next one, 840 mm the limit.
        let found = findings(&[
            (0, cabin(420.0, 100.0)),
            (10, stopped(cabin(421.0, 100.0))),
            (4_000, stopped(cabin(820.0, 100.0))),
            (4_300, stopped(cabin(841.0, 100.0))),
        ]);
        assert!(
            matches!(&found[..], [Finding::Violation(ViolationKind::StopOverrun, d)] if d.contains("floor 3")),
            "{found:?}"
        );
        // 30 mm below floor 3 when STOP came: floor 3 is too close, floor 4 is the next.
        let found = watch(&[
            (0, stopped(cabin(770.0, 100.0))),
            (300, stopped(cabin(800.0, 100.0))),
            (900, stopped(cabin(860.0, 100.0))),
            (4_000, stopped(cabin(1_200.0, 0.0))),
        ]);
        assert!(found.is_empty(), "{found:?}");
        // Going down from 1000 mm: floor 3 the next, 760 mm the limit.
        let found = watch(&[
            (0, stopped(cabin(1_000.0, -100.0))),
            (2_000, stopped(cabin(770.0, -100.0))),
            (2_200, stopped(cabin(759.0, -100.0))),
        ]);
        assert_eq!(found, [ViolationKind::StopOverrun]);
    }

    #[test]
    fn after_stop_a_cabin_may_not_reverse_nor_start_again() {
        // Each rule allows a vane's half-length (40 mm): levelling, or a fault a safety
        // function stops within it.
        let reverses = |back_mm: f64| {
            watch(&[
                (0, stopped(cabin(500.0, 100.0))),
                (100, stopped(cabin(510.0, -100.0))),
                (2_000, stopped(cabin(510.0 - back_mm, -100.0))),
            ])
        };
        assert!(reverses(39.0).is_empty());
        assert_eq!(reverses(41.0), [ViolationKind::StopOverrun]);
        let restarts = |to_mm: f64| {
            watch(&[
                (0, stopped(cabin(500.0, 100.0))),
                (1_000, stopped(cabin(800.0, 0.0))),
                (3_000, stopped(cabin(800.0, 10.0))),
                (6_000, stopped(cabin(to_mm, 10.0))),
            ])
        };
        assert!(restarts(839.0).is_empty());
        assert_eq!(restarts(841.0), [ViolationKind::StopOverrun]);
        let at_rest = watch(&[
            (0, stopped(cabin(400.0, 0.0))),
            (3_000, stopped(cabin(400.0, -10.0))),
            (7_000, stopped(cabin(359.0, -10.0))),
        ]);
        assert_eq!(at_rest, [ViolationKind::StopOverrun]);
        // A run the controller commanded before STOP (the image's run bit on when EStopOut
        // went off) that starts just after it was under way: it may go on to the next floor
        // (floor 2's vane, from floor 1), and no further.
        let commanded = |until_mm: f64| {
            let mut at_stop = stopped(cabin(5.0, 0.0));
            at_stop.run_commanded = true;
            watch(&[
                (0, at_stop),
                (16, stopped(cabin(5.0, 10.0))),
                (8_000, stopped(cabin(until_mm, 10.0))),
            ])
        };
        assert!(commanded(430.0).is_empty());
        assert_eq!(commanded(441.0), [ViolationKind::StopOverrun]);
        // A run started after STOP, however soon (the controller saw EStopOut go off and
        // then commanded it), is a new run.
        let after = watch(&[
            (0, stopped(cabin(5.0, 0.0))),
            (1, stopped(cabin(5.0, 10.0))),
            (5_000, stopped(cabin(46.0, 10.0))),
        ]);
        assert_eq!(after, [ViolationKind::StopOverrun]);
        // Restarted (EStopOut on again): a new run is the controller's to make.
        let restarted = watch(&[
            (0, stopped(cabin(500.0, 100.0))),
            (1_000, stopped(cabin(800.0, 0.0))),
            (2_000, cabin(800.0, 0.0)),
            (3_000, cabin(800.0, -100.0)),
        ]);
        assert!(restarted.is_empty(), "{restarted:?}");
        // K1 closing during a crank turn under STOP (the operator's reset): the converter
        // takes the moving cabin over; it may go on to the next floor, no further.
        let turn = |x: f64, k1: bool| {
            let mut o = stopped(cabin(x, 10.0));
            o.hand_cranking = !k1;
            o.k1_closed = k1;
            o
        };
        let taken = |until_mm: f64| {
            watch(&[
                (0, stopped(cabin(0.0, 0.0))),
                (600, turn(6.0, false)),
                (1_400, turn(8.0, true)),
                (1_500, stopped(cabin(8.0, 0.0))),
                (9_000, stopped(cabin(until_mm, 0.0))),
            ])
        };
        assert!(taken(8.0).is_empty());
        let found = watch(&[
            (0, stopped(cabin(0.0, 0.0))),
            (600, turn(6.0, false)),
            (1_400, turn(8.0, true)),
            (9_000, stopped(cabin(441.0, 10.0))),
        ]);
        assert_eq!(found, [ViolationKind::StopOverrun]);
        // A crank turn (K1 open) during STOP is the operator's.
        let mut crank = stopped(cabin(500.0, 10.0));
        crank.hand_cranking = true;
        crank.k1_closed = false;
        let cranked = watch(&[(0, stopped(cabin(500.0, 0.0))), (1_000, crank)]);
        assert!(cranked.is_empty(), "{cranked:?}");
    }

    #[test]
    fn an_overtravel_sensor_reached_under_power_is_counted_not_judged() {
        let tripped = |mut o: Observed, k1: bool| {
            o.overtravel_tripped = true;
            o.k1_closed = k1;
            o
        };
        let found = findings(&[
            (0, cabin(1_250.0, 100.0)),
            (10, tripped(cabin(1_261.0, 100.0), true)),
            (20, tripped(cabin(1_262.0, 50.0), false)),
            (2_000, tripped(cabin(1_265.0, 0.0), false)),
        ]);
        assert_eq!(found, [Finding::OvertravelReached]);
        // Reached by the crank (K1 open): nothing to count.
        let mut crank = tripped(cabin(-61.0, -10.0), false);
        crank.hand_cranking = true;
        assert!(findings(&[(0, cabin(-50.0, 0.0)), (10, crank)]).is_empty());
    }
}
