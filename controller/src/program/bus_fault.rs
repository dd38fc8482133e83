//! Bus faults: the cabin slave's word going stale, the slaves the cabin needs leaving the bus,
//! or an AS-i power fail hold the cabin; the journey resumes if the program kept sight of the
//! cabin, else initialisation finds it again.

use super::events::{HaltReason, ProgramEventKind};
use super::io::{Edges, Inputs};
use super::state::{Phase, Step};
use super::{Program, COAST};
use crate::dispatch::Dir;
use asi_phy::SimTime;

impl Program {
    pub(super) fn bus_fault(&mut self, now: SimTime, resume: Option<Step>, blind: bool) {
        self.hold();
        self.drive_off_at = now;
        self.phase = Phase::BusFault { resume, blind };
        self.event(now, ProgramEventKind::BusFault);
    }

    /// A scan while the bus is not healthy: the cabin is held; when the bus is back, the journey
    /// resumes if the program kept sight of the cabin, else initialisation finds it again.
    pub(super) fn while_bus_fault(
        &mut self,
        now: SimTime,
        edges: Edges,
        inp: &Inputs,
        fresh: bool,
        resume: Option<Step>,
        blind: bool,
    ) {
        let bus_ok = inp.bus_ok && inp.power_ok && fresh;
        self.hold();
        let settled = now.saturating_duration_since(self.drive_off_at) > COAST;
        let moved = settled && (edges.vane_rise || edges.vane_fall);
        let mut blind = blind || !fresh || !inp.power_ok || moved;
        let mut resume = resume;
        // The cabin coasting to rest may reach the next vane: count it, as in a halt.
        if !settled && !blind {
            match (resume, self.dir) {
                (Some(Step::Travel), Some(dir)) if edges.vane_rise => {
                    match self.count_vane(dir, edges) {
                        Ok(floor) => {
                            self.current = floor;
                            if floor == self.target {
                                resume = Some(Step::Braking);
                            }
                        }
                        Err(_) => blind = true,
                    }
                }
                (Some(Step::Braking), _) if edges.vane_fall => blind = true,
                _ => {}
            }
        }
        self.phase = Phase::BusFault { resume, blind };
        let journey = matches!(
            resume,
            Some(Step::Travel | Step::Braking | Step::Halted { .. })
        );
        match resume {
            Some(step) if bus_ok && !blind => {
                self.event(now, ProgramEventKind::BusRestored);
                self.resume(now, step);
            }
            // Initialisation chooses its way from the vane sensors: only a cabin word
            // that completed since the bus came back shows where the cabin is now.
            _ if bus_ok && inp.cabin.is_some() => {
                self.event(now, ProgramEventKind::BusRestored);
                if journey || self.target != self.current {
                    self.dispatch.requeue(self.target);
                }
                self.start_init(now);
                if self.stop_demand && inp.converter_ready {
                    // STOP came during the bus fault and the drive still has power (the STOP
                    // delay runs): the cabin at rest starts no run until the circuit is
                    // restarted (initialisation's hold, as for any reason). Without power the
                    // next scan's hold comes before anything can move.
                    self.hold();
                    self.init_held = Some(HaltReason::Stop);
                    self.drive_off_at = now;
                    self.event(now, ProgramEventKind::InitHeld(HaltReason::Stop));
                }
            }
            _ => {}
        }
    }

    /// Back to `step` after a bus fault in which the program kept sight of the cabin.
    pub(super) fn resume(&mut self, now: SimTime, step: Step) {
        self.phase = Phase::Service(step);
        self.progress_at = now;
        self.running_since = now;
        let braking = step == Step::Braking;
        let reason = if self.stop_demand {
            Some(HaltReason::Stop)
        } else {
            self.cabin_blocks_motion()
        };
        if let (Some(reason), Step::Travel | Step::Braking) = (reason, step) {
            // STOP came, the door opened or the cabin was loaded during the bus fault: held,
            // not resumed (a cabin at rest under STOP starts no run).
            self.drive_off_at = now;
            self.event(now, ProgramEventKind::Halted(reason));
            self.phase = Phase::Service(Step::Halted { reason, braking });
            return;
        }
        let speed = match step {
            Step::Travel => self.cfg.travel_ua,
            Step::Braking => self.cfg.creep_ua,
            _ => return,
        };
        self.out.run = true;
        self.out.up = self.dir == Some(Dir::Up);
        self.out.setpoint_ua = speed;
    }
}
