//! The invariant watch: the judge of every run (README "Violations"). It sees the plant as it
//! is at each moment and says when the guarded lift is unsafe: the cabin moving with the door
//! open or overloaded, K1 closed with an overtravel sensor tripped, STOP not opening K1.

use crate::report::ViolationKind;
use asi_phy::{SimDuration, SimTime};

/// Reaction budgets of the invariants (see README "Violations").
const DOOR_BUDGET: SimDuration = SimDuration::from_millis(1000);
const OVERLOAD_BUDGET: SimDuration = SimDuration::from_millis(1000);
const OVERTRAVEL_BUDGET: SimDuration = SimDuration::from_millis(50);
const STOP_MARGIN: SimDuration = SimDuration::from_millis(200);

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
}

/// Watches the invariants.
#[derive(Clone, Debug, Default)]
pub(super) struct InvariantWatch {
    door_open_since: Option<SimTime>,
    overloaded_since: Option<SimTime>,
    overtravel_k1_since: Option<SimTime>,
    /// STOP pressed at, and whether K1 has opened since.
    stop_since: Option<(SimTime, bool)>,
    /// The cabin moves by the hand crank (from the turn's start to the next rest).
    by_hand: bool,
    /// Reported once per episode: door, overload, overtravel.
    reported: [bool; 3],
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
        if moving && over(self.door_open_since, DOOR_BUDGET) {
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
        for (slot, on) in [o.door_open, o.overloaded, tripped_k1]
            .into_iter()
            .enumerate()
        {
            if !on {
                self.reported[slot] = false;
            }
        }
        found
    }
}
