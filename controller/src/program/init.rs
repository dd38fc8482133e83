//! Initialisation (table 6.3 of the lift thesis, extended for starts inside floor 1's vane, level
//! at a floor or just below floor 1): finds floor 1 and hands over to the automat.

use super::events::{HaltReason, InitStart, ProgramEventKind, NO_VANE_RETRY};
use super::io::{Edges, Inputs};
use super::state::{InitStep, Phase, Step};
use super::Program;
use crate::dispatch::Dir;
use asi_phy::SimTime;

impl Program {
    pub(super) fn start_init(&mut self, now: SimTime) {
        let start = match (self.cabin.vane_left, self.cabin.vane_right) {
            (true, true) => InitStart::Level,
            (true, false) => InitStart::Floor1Track,
            // Last seen inside floor 1's vane moving down, or below it moving up: below it.
            (false, false) if self.in_floor1_vane => InitStart::BelowFloor1,
            _ => InitStart::ThesisRoutine,
        };
        let step = match start {
            InitStart::Level => InitStep::Probe,
            InitStart::Floor1Track => InitStep::Floor1Down,
            InitStart::BelowFloor1 => InitStep::Floor1Up,
            InitStart::ThesisRoutine => InitStep::Run,
        };
        self.initialised_at = None;
        self.init_held = None;
        self.no_vane_since = None;
        self.progress_at = now;
        self.running_since = now;
        self.left_proven = false;
        self.lost = false;
        (self.shown_floor, self.shown_dir) = (1, Some(Dir::Down));
        self.event(now, ProgramEventKind::InitStarted { start });
        self.phase = Phase::Init(step);
        self.drive_init(step);
    }

    /// The outputs of an initialisation step (table 6.3 of the lift thesis: down, floor 1 and
    /// "down" shown).
    pub(super) fn drive_init(&mut self, step: InitStep) {
        let (ua, up) = match step {
            InitStep::Run => (self.cfg.init_ua, false),
            InitStep::Brake { .. } | InitStep::Floor1Down | InitStep::Probe => {
                (self.cfg.creep_ua, false)
            }
            InitStep::Floor1Up => (self.cfg.creep_ua, true),
        };
        self.current = 1;
        self.target = 1;
        self.dir = Some(if up { Dir::Up } else { Dir::Down });
        // Never a command to move with the door open, overloaded or STOP pressed, not even
        // for the one scan before the hold is seen (a start from a bus fault or a lost count).
        if self.cabin_blocks_motion().is_some() || self.cabin.stop {
            self.hold();
            return;
        }
        self.out.run = true;
        self.out.up = up;
        self.out.setpoint_ua = ua;
    }

    pub(super) fn init(
        &mut self,
        now: SimTime,
        step: InitStep,
        e: Edges,
        inp: &Inputs,
        stop_demand: bool,
    ) {
        // The cabin never moves with the door open, overloaded or under STOP, not even to find
        // floor 1. A hold (these, or the drive losing power, as when the run reaches an
        // overtravel sensor) ends when every reason is gone and the drive has power again;
        // then initialisation starts afresh from what the sensors show, because the edges the
        // steps wait for may have passed during the hold.
        if let Some(since) = self.no_vane_since {
            if e.any || now.saturating_duration_since(since) > NO_VANE_RETRY {
                self.no_vane_since = None;
            }
        }
        let reason = if stop_demand {
            Some(HaltReason::Stop)
        } else if let Some(r) = self.cabin_blocks_motion() {
            Some(r)
        } else if inp.converter_fault {
            Some(HaltReason::ConverterFault)
        } else if !inp.converter_ready {
            Some(HaltReason::NoPower)
        } else if self.no_vane_since.is_some() {
            Some(HaltReason::NoVane)
        } else {
            None
        };
        match (self.init_held, reason) {
            (None, Some(r)) => {
                if self.out.run {
                    self.door_halt(now, r);
                }
                self.hold();
                self.init_held = Some(r);
                self.drive_off_at = now;
                self.event(now, ProgramEventKind::InitHeld(r));
                return;
            }
            (Some(held), Some(r)) => {
                self.hold();
                if held != r {
                    self.init_held = Some(r);
                    self.event(now, ProgramEventKind::InitHeld(r));
                }
                return;
            }
            (Some(_), None) if now < self.door_lockout_until => {
                self.hold();
                return;
            }
            (Some(_), None) => {
                self.init_held = None;
                self.start_init(now);
                return;
            }
            (None, None) => {}
        }
        let c = self.cabin;
        self.left_proven |= e.left_rise;
        // The watchdog: the run must reach a vane, a creep the edge it waits for, in the time
        // the geometry allows; only while the drive has power.
        let limit = match step {
            InitStep::Run => self.cfg.travel_watchdog,
            _ => self.cfg.creep_watchdog,
        };
        if e.vane_rise || !inp.converter_ready {
            self.progress_at = now;
        }
        let stuck = step == InitStep::Run && self.stuck_on(now);
        if stuck || now.saturating_duration_since(self.progress_at) > limit {
            self.hold();
            // A sensor lies: what it showed of floor 1's vane is no guide either.
            self.in_floor1_vane = false;
            self.no_vane_since = Some(now);
            self.init_held = Some(HaltReason::NoVane);
            self.drive_off_at = now;
            self.event(now, ProgramEventKind::InitHeld(HaltReason::NoVane));
            return;
        }
        let next = match step {
            InitStep::Run if e.left_rise => {
                // The left sensor first, the right one off: floor 1's turned vane.
                self.in_floor1_vane = !c.vane_right;
                Some(InitStep::Brake {
                    until: now + self.cfg.init_timer,
                })
            }
            InitStep::Brake { .. } if e.right_rise => return self.initialised(now),
            // Out of floor 1's vane at the bottom without seeing its level (the cabin word came
            // too late): creep back up to it rather than run on into the overtravel sensor.
            InitStep::Brake { .. } if e.left_fall && self.in_floor1_vane => {
                Some(InitStep::Floor1Up)
            }
            InitStep::Brake { until } if now >= until => Some(InitStep::Run),
            // Level at floor 1, once its left sensor has shown a rise in this initialisation (a
            // sensor stuck on would make every vane look like floor 1's long track).
            InitStep::Floor1Down if e.right_rise && self.left_proven => {
                return self.initialised(now)
            }
            InitStep::Floor1Down if e.left_fall => Some(InitStep::Floor1Up),
            // Floor 1's short track ended first: below floor 1's level. Down out of the long
            // track too, then up into it, so that the left sensor shows it works.
            InitStep::Probe if e.right_fall && c.vane_left => Some(InitStep::Floor1Down),
            InitStep::Probe if e.left_fall => Some(InitStep::Run),
            // Up into a vane whose right sensor comes first: not floor 1.
            InitStep::Floor1Up if e.vane_rise && e.floor1_vane == Some(false) => {
                return self.start_init(now)
            }
            InitStep::Floor1Up if c.vane_left && c.vane_right => return self.initialised(now),
            // Out of the long track without ever standing level: the sensors disagree with the
            // floor-1 vane's shape; start again from what they show now.
            InitStep::Floor1Up if e.left_fall => return self.start_init(now),
            _ => None,
        };
        if next.is_some_and(|n| n != step) {
            self.progress_at = now;
            self.running_since = now;
        }
        let step = next.unwrap_or(step);
        match step {
            InitStep::Floor1Down => self.in_floor1_vane = true,
            InitStep::Brake { .. } => {}
            // Below the vane until its left sensor shows; inside it, moving up, the cabin can
            // only leave it upwards.
            InitStep::Floor1Up => self.in_floor1_vane = !c.vane_left,
            InitStep::Run | InitStep::Probe => self.in_floor1_vane = false,
        }
        self.phase = Phase::Init(step);
        self.drive_init(step);
    }

    pub(super) fn initialised(&mut self, now: SimTime) {
        self.hold();
        self.in_floor1_vane = false;
        self.current = 1;
        self.target = 1;
        self.dir = None;
        self.stop_pending = false;
        self.initialised_at = Some(now);
        self.depart_after = now + self.cfg.dwell;
        self.event(now, ProgramEventKind::Initialised);
        self.phase = Phase::Service(Step::AtFloor);
    }
}
