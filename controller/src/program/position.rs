//! The floor count ("Rozdil" counting on the vane sensors, tables 6.4/6.5 of the lift thesis) and
//! its checks: the vane's shape against the floor counted, stuck sensors, a cabin moved by hand;
//! and what happens when the count is lost.

use super::events::{LostReason, ProgramEventKind};
use super::io::Edges;
use super::state::{Phase, Step};
use super::Program;
use crate::dispatch::{Algorithm, Dir};
use asi_phy::SimTime;

impl Program {
    /// A rising vane edge during travel: the cabin reaches the next floor's vane (tables
    /// 6.4/6.5 of the lift thesis, "Rozdil" counting); at the target it brakes to the creep speed.
    pub(super) fn pass_floor(&mut self, now: SimTime, e: Edges) {
        let Some(dir) = self.dir else { return };
        let floor = match self.count_vane(dir, e) {
            Ok(f) => f,
            Err(why) => return self.lose_now(now, why),
        };
        self.current = floor;
        self.progress_at = now;
        if !self.stop_pending
            && self.dispatch.algorithm() == Algorithm::Collective
            && self.dispatch.should_stop(floor, dir)
        {
            self.target = floor;
        }
        if floor == self.target {
            self.out.setpoint_ua = self.cfg.creep_ua;
            self.event(now, ProgramEventKind::Braking { floor });
            self.phase = Phase::Service(Step::Braking);
        } else {
            self.event(now, ProgramEventKind::Passed { floor });
        }
    }

    /// The floor whose vane the cabin reaches moving `dir`: the next one counted, never one
    /// beyond the end floors. Which sensor came first is kept, to check the floor against the
    /// vane's shape when the cabin stands level in it (see [`Program::arrive`]).
    pub(super) fn count_vane(&mut self, dir: Dir, e: Edges) -> Result<u8, LostReason> {
        let next = match dir {
            Dir::Up => self.current.checked_add(1),
            Dir::Down => self.current.checked_sub(1),
        };
        self.vane_shape = e.floor1_vane;
        next.filter(|f| (1..=self.cfg.floors).contains(f))
            .ok_or(LostReason::BeyondEndFloor)
    }

    /// Whether the vane sensors show what no working pair can show in the vane of the
    /// floor counted: at floor 1 the right (short) track lies inside the left (long) one, at the
    /// other floors the left inside the right (§6.4 of the lift thesis), so the short sensor is
    /// never on alone.
    pub(super) fn vane_contradicts_floor(&self) -> bool {
        let (left, right) = (self.cabin.vane_left, self.cabin.vane_right);
        if self.current == 1 {
            right && !left
        } else {
            left && !right
        }
    }

    /// A vane sensor on for longer than a vane takes to pass while the cabin runs at speed.
    pub(super) fn stuck_on(&self, now: SimTime) -> bool {
        self.on_since.iter().flatten().any(|&on| {
            now.saturating_duration_since(on.max(self.running_since)) > self.cfg.stuck_on_after
        })
    }

    /// Whether the departure floor's vane, as the cabin leaves it, has the wrong shape for the
    /// floor counted; forgets the departure floor once its vane is left.
    pub(super) fn left_wrong_vane(&mut self, e: Edges) -> bool {
        let Some(floor) = self.leaving else {
            return false;
        };
        if e.vane_fall {
            self.leaving = None;
        }
        e.left_fell_first
            .is_some_and(|left_first| left_first != (floor != 1))
    }

    /// While the cabin comes to rest after a halt: a vane reached on the way is counted (the
    /// halt then continues as braking if it is the target's); leaving the stop floor's vane
    /// while braking means its level was passed.
    pub(super) fn coast(&mut self, now: SimTime, e: Edges, braking: bool) {
        if braking {
            if e.vane_fall {
                self.mark_lost(now, LostReason::MissedLevel);
            }
            return;
        }
        if !e.vane_rise {
            return;
        }
        let Some(dir) = self.dir else { return };
        match self.count_vane(dir, e) {
            Ok(floor) => {
                self.current = floor;
                if floor == self.target {
                    if let Phase::Service(Step::Halted { reason, .. }) = self.phase {
                        self.phase = Phase::Service(Step::Halted {
                            reason,
                            braking: true,
                        });
                    }
                }
            }
            Err(why) => self.mark_lost(now, why),
        }
    }

    /// The floor count is not trusted any more: initialise before the next journey.
    pub(super) fn mark_lost(&mut self, now: SimTime, why: LostReason) {
        if !self.lost {
            self.lost = true;
            self.event(now, ProgramEventKind::PositionLost { why });
        }
    }

    /// The count failed while the cabin travels: stop and find floor 1 again; the target is
    /// kept for afterwards.
    pub(super) fn lose_now(&mut self, now: SimTime, why: LostReason) {
        self.hold();
        self.mark_lost(now, why);
        // The journey did not end with an arrival: its target is still wanted.
        self.dispatch.requeue(self.target);
        self.start_init(now);
    }
}
