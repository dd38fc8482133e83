//! The automat (tables 6.4/6.5 of the lift thesis): standing at a floor, departing, travelling,
//! braking, arriving and serving calls; STOP, overload and the holds between floors.

use super::events::{HaltReason, LostReason, ProgramEventKind};
use super::io::{overloaded, Edges, Inputs};
use super::state::{Phase, Step};
use super::{Program, COAST, DOOR_LOCKOUT};
use crate::dispatch::Dir;
use asi_phy::SimTime;

impl Program {
    /// Why the cabin itself forbids motion: the door open, or overloaded (or its load unknown;
    /// `out.overloaded` is this scan's).
    pub(super) fn cabin_blocks_motion(&self) -> Option<HaltReason> {
        if !self.cabin.door_closed {
            Some(HaltReason::DoorOpen)
        } else if self.out.overloaded {
            Some(HaltReason::Overload)
        } else {
            None
        }
    }

    /// Motor off: run cleared, standstill set-point.
    pub(super) fn hold(&mut self) {
        self.out.run = false;
        self.out.setpoint_ua = self.cfg.standstill_ua;
    }

    /// One scan of the automat; returns whether restart pulses are wanted.
    pub(super) fn service(
        &mut self,
        now: SimTime,
        step: Step,
        e: Edges,
        inp: &Inputs,
        stop_demand: bool,
    ) -> bool {
        if self.restart_wanted && inp.estop_ok && !self.cabin.stop {
            // The STOP circuit runs again after a cabin request: service resumes.
            self.restart_wanted = false;
            self.stop_pending = false;
            self.event(now, ProgramEventKind::Resumed);
            if step == Step::StopFault {
                self.phase = Phase::Service(Step::AtFloor);
                return false;
            }
        }
        let want_restart = self.restart_wanted && !inp.estop_ok;
        let settled = now.saturating_duration_since(self.drive_off_at) > COAST;
        if matches!(step, Step::AtFloor | Step::Overload | Step::StopFault)
            && settled
            && (e.vane_rise || e.vane_fall)
        {
            self.mark_lost(now, LostReason::MovedByHand);
        }
        self.step_service(now, step, e, inp, stop_demand);
        // After this scan's count: the count or a sensor is wrong if the sensors show what the
        // counted floor's vane cannot; stop now if moving, else before the next journey.
        if let Phase::Service(step) = self.phase {
            if self.vane_contradicts_floor() {
                if matches!(step, Step::Travel | Step::Braking) {
                    self.lose_now(now, LostReason::WrongVane);
                } else {
                    self.mark_lost(now, LostReason::WrongVane);
                }
            }
        }
        want_restart
    }

    /// The automat's step for this scan (tables 6.4/6.5 of the lift thesis).
    pub(super) fn step_service(
        &mut self,
        now: SimTime,
        step: Step,
        e: Edges,
        inp: &Inputs,
        stop_demand: bool,
    ) {
        let door_closed = self.cabin.door_closed;
        let overloaded = overloaded(inp);
        let both = self.cabin.vane_left && self.cabin.vane_right;
        let settled = now.saturating_duration_since(self.drive_off_at) > COAST;
        match step {
            Step::AtFloor => {
                if stop_demand {
                    self.enter(now, Step::StopFault);
                } else if self.lost {
                    if door_closed && !overloaded && inp.converter_ready && !inp.converter_fault {
                        // Find the position again before any journey; the calls wait.
                        self.start_init(now);
                    }
                } else if overloaded {
                    self.event(now, ProgramEventKind::OverloadFault);
                    self.phase = Phase::Service(Step::Overload);
                } else {
                    self.choose_target(now);
                    if self.target != self.current
                        && now >= self.depart_after
                        && now >= self.door_lockout_until
                        && door_closed
                        && inp.converter_ready
                        && !inp.converter_fault
                    {
                        self.depart(now);
                    }
                }
            }
            Step::Overload => {
                if !overloaded {
                    self.event(now, ProgramEventKind::OverloadCleared);
                    self.phase = Phase::Service(Step::AtFloor);
                }
            }
            Step::Travel | Step::Braking => {
                let braking = step == Step::Braking;
                if stop_demand && !self.stop_pending {
                    self.stop_demanded(now, braking);
                }
                let halt = if let Some(r) = self.cabin_blocks_motion() {
                    Some(r)
                } else if inp.converter_fault {
                    Some(HaltReason::ConverterFault)
                } else if !inp.converter_ready {
                    Some(HaltReason::NoPower)
                } else {
                    None
                };
                if let Some(reason) = halt {
                    self.hold();
                    self.drive_off_at = now;
                    self.door_halt(now, reason);
                    self.event(now, ProgramEventKind::Halted(reason));
                    self.phase = Phase::Service(Step::Halted { reason, braking });
                    // The edges of this scan still count.
                    self.coast(now, e, braking);
                } else if braking {
                    if both {
                        self.arrive(now);
                    } else if e.vane_fall
                        || now.saturating_duration_since(self.progress_at) > self.cfg.level_watchdog
                    {
                        self.lose_now(now, LostReason::MissedLevel);
                    }
                } else if self.stuck_on(now) {
                    self.lose_now(now, LostReason::StuckSensor);
                } else if self.left_wrong_vane(e) {
                    // Leaving the departure floor's vane, the short track ends first: the right
                    // one at floor 1 (its vane is turned), the left one elsewhere.
                    self.lose_now(now, LostReason::WrongVane);
                } else if e.vane_rise {
                    self.pass_floor(now, e);
                } else if now.saturating_duration_since(self.progress_at) > self.cfg.travel_watchdog
                {
                    self.lose_now(now, LostReason::NoVane);
                }
            }
            Step::Halted { reason, braking } => {
                if stop_demand && !self.stop_pending {
                    self.stop_demanded(now, braking);
                }
                if settled {
                    if e.vane_rise || e.vane_fall {
                        self.mark_lost(now, LostReason::MovedByHand);
                    }
                } else {
                    self.coast(now, e, braking);
                }
                let braking = match self.phase {
                    Phase::Service(Step::Halted { braking, .. }) => braking,
                    _ => braking,
                };
                let cleared = match reason {
                    HaltReason::DoorOpen => door_closed,
                    HaltReason::Overload => !overloaded,
                    HaltReason::Stop => inp.estop_ok,
                    // Not a reason to halt in service (initialisation only).
                    HaltReason::NoVane => true,
                    HaltReason::ConverterFault | HaltReason::NoPower => {
                        !inp.converter_fault && inp.converter_ready
                    }
                };
                let cleared = cleared && now >= self.door_lockout_until;
                if cleared && door_closed && !overloaded && inp.estop_ok && self.lost {
                    if inp.converter_ready && !inp.converter_fault {
                        // The count is not trusted: find floor 1 first, then the target.
                        self.dispatch.requeue(self.target);
                        self.start_init(now);
                    }
                } else if cleared && door_closed && !overloaded && inp.estop_ok {
                    self.event(now, ProgramEventKind::Continued);
                    self.progress_at = now;
                    self.running_since = now;
                    self.out.run = true;
                    self.out.up = self.dir == Some(Dir::Up);
                    self.out.setpoint_ua = if braking {
                        self.cfg.creep_ua
                    } else {
                        self.cfg.travel_ua
                    };
                    self.phase = Phase::Service(if braking { Step::Braking } else { Step::Travel });
                }
            }
            Step::StopFault => {}
        }
    }

    /// The drive was taken off for `reason`: if the door opened during a run, no run starts
    /// for [`DOOR_LOCKOUT`].
    pub(super) fn door_halt(&mut self, now: SimTime, reason: HaltReason) {
        if reason == HaltReason::DoorOpen {
            self.door_lockout_until = now + DOOR_LOCKOUT;
        }
    }

    pub(super) fn enter(&mut self, now: SimTime, step: Step) {
        if step == Step::StopFault {
            self.hold();
            self.event(now, ProgramEventKind::StopFault);
        }
        self.phase = Phase::Service(step);
    }

    /// At a floor: unload the next target while current floor = target (§6.6 of the lift thesis); a
    /// call for the floor the cabin stands at is served at once.
    pub(super) fn choose_target(&mut self, now: SimTime) {
        for _ in 0..64 {
            if self.target != self.current {
                return;
            }
            match self.dispatch.next_target(self.current, self.dir) {
                Some(t) if t == self.current => self.serve(now, None),
                Some(t) if (1..=self.cfg.floors).contains(&t) => self.target = t,
                _ => return,
            }
        }
    }

    pub(super) fn depart(&mut self, now: SimTime) {
        let dir = Dir::between(self.current, self.target);
        self.dir = dir;
        self.progress_at = now;
        self.running_since = now;
        self.leaving = (self.cabin.vane_left || self.cabin.vane_right).then_some(self.current);
        self.stop_pending = false;
        self.out.run = true;
        self.out.up = dir == Some(Dir::Up);
        self.out.setpoint_ua = self.cfg.travel_ua;
        (self.shown_floor, self.shown_dir) = (self.current, dir);
        self.event(
            now,
            ProgramEventKind::Departed {
                from: self.current,
                to: self.target,
            },
        );
        self.phase = Phase::Service(Step::Travel);
    }

    /// STOP during travel: stop at the next floor in the direction of travel (§6.3 of the lift
    /// thesis, "Porucha Stop"); already braking, stop where it brakes.
    pub(super) fn stop_demanded(&mut self, now: SimTime, braking: bool) {
        self.stop_pending = true;
        let stop_at = match (braking, self.dir) {
            (false, Some(dir)) => dir.next(self.current).clamp(1, self.cfg.floors),
            _ => self.target,
        };
        let dropped = (stop_at != self.target).then_some(self.target);
        self.target = stop_at;
        self.event(now, ProgramEventKind::StopDemanded { dropped, stop_at });
    }

    pub(super) fn arrive(&mut self, now: SimTime) {
        self.hold();
        self.drive_off_at = now;
        let floor = self.current;
        // Level in a vane whose long track came first: the left one only at floor 1 (its vane is
        // turned, §6.4 of the lift thesis). A mismatch means the count is off: the calls of this
        // stop are served (the cabin stands level at a floor), and the position is found again
        // before the next journey. Checked only here, where both sensors are seen working.
        if self
            .vane_shape
            .is_some_and(|left_first| left_first != (floor == 1))
        {
            self.mark_lost(now, LostReason::WrongVane);
        }
        self.vane_shape = None;
        self.target = floor;
        self.depart_after = now + self.cfg.dwell;
        (self.shown_floor, self.shown_dir) = (floor, None);
        self.event(now, ProgramEventKind::Arrived { floor });
        self.serve(now, self.dir);
        if self.stop_pending {
            self.stop_pending = false;
            self.enter(now, Step::StopFault);
        } else {
            self.phase = Phase::Service(Step::AtFloor);
        }
    }

    pub(super) fn serve(&mut self, now: SimTime, dir: Option<Dir>) {
        let mut served = core::mem::take(&mut self.served);
        served.clear();
        self.dispatch.serve(self.current, dir, &mut served);
        for s in &served {
            self.event(now, ProgramEventKind::Served(*s));
        }
        self.served = served;
    }
}
