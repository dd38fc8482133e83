//! The plant and the slaves at a moment: the plant brought to it with its edges, what the
//! plant shows handed to the slaves' inputs, and what the slaves drive handed to the plant.

use super::*;
use lift_model::{Events, PlantError, PlantEvent};

impl Rig {
    /// Brings the plant to `t` and handles its edges on the way.
    #[inline(always)]
    pub(super) fn advance_plant(&mut self, t: SimTime) {
        let edges = match self.lift.advance_to(t) {
            // No edge at almost every moment: nothing to hand on then.
            Ok(edges) if edges.len() == 0 => return,
            r => gather(r),
        };
        self.plant_edges(edges);
    }

    #[cold]
    #[inline(never)]
    pub(super) fn plant_error(&mut self, e: lift_model::PlantError) {
        self.log(Actor::Plant, LogEvent::PlantError(e));
    }

    /// The plant's edges on its way to the moment it has reached (or why it could not go).
    #[inline(never)]
    pub(super) fn plant_edges(&mut self, edges: Result<Vec<PlantEvent>, PlantError>) {
        let events = match edges {
            Ok(events) => events,
            Err(e) => return self.plant_error(e),
        };
        self.wiring.plant_dirty = true;
        for e in events {
            match e.kind {
                Plant::Stopped { position_mm } => self.stopped(e.at, position_mm),
                Plant::Crash { end, impact_mm_s } => {
                    let crash = PlantLog::Crash { end, impact_mm_s };
                    self.log_at(e.at, Actor::Plant, LogEvent::Plant(crash));
                    self.violation(e.at, ViolationKind::MechanicalEnd, crash.to_string());
                }
                Plant::Overtravel { end, tripped } => {
                    let p = if tripped {
                        PlantLog::OvertravelTripped {
                            end,
                            position_mm: self.lift.position_mm(),
                        }
                    } else {
                        PlantLog::OvertravelFree { end }
                    };
                    self.log_at(e.at, Actor::Plant, LogEvent::Plant(p));
                }
                Plant::ConverterFault { fault } => {
                    let p = PlantLog::ConverterFault { fault };
                    self.log_at(e.at, Actor::Plant, LogEvent::Plant(p));
                }
                _ => {}
            }
        }
    }

    /// The drive is commanded to move (the converter's run bit with a set-point above
    /// standstill).
    fn drive_commanded(&self) -> bool {
        self.wiring.applied.run && self.wiring.applied.setpoint_ua > STANDSTILL_UA
    }

    /// The floor the cabin stands level at, at rest with the drive commanded to stand still,
    /// if it does.
    pub(super) fn standing_at(&self) -> Option<u8> {
        if self.drive_commanded() || self.lift.velocity_mm_s() != 0.0 {
            return None;
        }
        self.lift.config().level_floor(self.lift.position_mm())
    }

    /// A call pressed at `floor` at `at`: where no program tells which call a stop serves,
    /// a cabin standing level at that floor answers it at once (the passenger is there).
    pub(super) fn call_pressed(&mut self, floor: u8, at: SimTime) {
        if self.controller.names_served_calls() || self.standing_at() != Some(floor) {
            return;
        }
        let served = self.people.passengers.arrived(floor, at);
        self.report.served.extend(served);
        self.riders_answered();
    }

    /// The cabin came to rest: an arrival if it stands level at a floor with the drive
    /// commanded to stand still.
    pub(super) fn stopped(&mut self, at: SimTime, position_mm: f64) {
        if self.drive_commanded() {
            return;
        }
        let cfg = self.lift.config();
        let Some(floor) = cfg.level_floor(position_mm) else {
            return;
        };
        let level = cfg.floor_level_mm(floor).unwrap_or_default();
        self.report.arrivals.push(Arrival {
            floor,
            at_s: at.as_secs_f64(),
            position_mm: round3(position_mm),
        });
        let rest = PlantLog::AtRest {
            floor,
            offset_mm: position_mm - level,
        };
        self.log_at(at, Actor::Plant, LogEvent::Plant(rest));
        if !self.controller.names_served_calls() {
            // No program tells which call a stop serves: a stop at a floor answers every
            // call waiting there.
            let served = self.people.passengers.arrived(floor, at);
            self.report.served.extend(served);
            self.riders_answered();
        }
    }

    /// The plant's signals on the slaves' peripheral inputs.
    pub(super) fn plant_to_slaves(&mut self) {
        self.wiring.plant_dirty = false;
        wiring::plant_to_slaves(&self.lift, &mut self.lab, self.sc.floors);
    }

    /// What the slaves drive, to the plant, at the moment they drive it.
    ///
    /// The slaves' outputs are read only when the lab's count of drive changes has moved
    /// since the last reading: until then they are what was read, which the plant has
    /// (checked against a fresh reading at every moment in the rig's tests).
    #[inline]
    pub(super) fn slaves_to_plant(&mut self, t: SimTime) {
        let changes = self.lab.drive_changes();
        if self.wiring.drives_seen == Some(changes) {
            #[cfg(test)]
            assert_eq!(
                wiring::slave_outputs(&self.lab),
                self.wiring.applied,
                "the slaves drive something new at {t} without a drive change counted"
            );
            return;
        }
        self.read_slaves(t, changes);
    }

    /// Reads what the slaves drive (the lab's count of drive changes is `changes` now) and
    /// hands the plant what changed.
    #[inline(never)]
    pub(super) fn read_slaves(&mut self, t: SimTime, changes: u64) {
        self.wiring.drives_seen = Some(changes);
        let new = wiring::slave_outputs(&self.lab);
        // At most moments the slaves drive what they drove: the plant is handed only what
        // changed, so nothing then.
        if new == self.wiring.applied {
            return;
        }
        let result = wiring::apply_to_plant(
            &mut self.lift,
            t,
            &self.wiring.applied,
            &new,
            self.sc.floors,
        );
        if let Err(e) = result {
            self.log(Actor::Plant, LogEvent::PlantError(e));
        }
        // What the plant shows the slaves can change with what it is given.
        self.wiring.plant_dirty = true;
        self.wiring.applied = new;
    }
}

/// The plant's edges, taken out of its queue.
#[inline(never)]
fn gather(edges: Result<Events<'_>, PlantError>) -> Result<Vec<PlantEvent>, PlantError> {
    edges.map(Iterator::collect)
}
