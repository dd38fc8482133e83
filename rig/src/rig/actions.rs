//! What the rig does for the scenario's actions, the operator's and the attendant's: presses,
//! loads, doors, the hand crank, resets and rescues, faults, and the timers that end them.

use super::*;

/// Mixed into the scenario's seed for a burst of line noise, with the burst's start: each
/// burst draws its own faults.
const NOISE_BURST_SEED: u64 = 0x6e6f_6973_655f_6275;

impl Rig {
    pub(super) fn apply(&mut self, t: SimTime, ev: &ScenarioEvent) {
        self.act(t, Actor::Scenario, &ev.action);
    }

    /// `who` (the scenario or the attendant) does `action` at `t`.
    pub(super) fn act(&mut self, t: SimTime, who: Actor, action: &Action) {
        self.log(who, LogEvent::Action(action.clone()));
        let result = match action {
            Action::Press { button, hold } => {
                self.people.passengers.press(t, *button);
                if let Some(floor) = button.floor() {
                    self.call_pressed(floor, t);
                }
                self.lift.press(t, *button, *hold)
            }
            Action::Load(l) => self.lift.set_load(t, *l),
            Action::Door { closed } => self.lift.set_door(t, *closed),
            Action::Crank { mm } => self.lift.crank(t, *mm),
            Action::Reset => {
                self.safety.operator_reset = true;
                self.agenda
                    .timers
                    .push((t + OPERATOR_PULSE, Timer::OperatorReset(false)));
                Ok(())
            }
            Action::Rescue => self.rescue(t, who),
            Action::Attend => {
                self.people.attendant.start(t);
                Ok(())
            }
            Action::Ack => {
                self.safety.err_ack = true;
                self.agenda
                    .timers
                    .push((t + OPERATOR_PULSE, Timer::ErrAck(false)));
                Ok(())
            }
            Action::Fault(f) => {
                self.fault(t, *f);
                Ok(())
            }
        };
        if let Err(e) = result {
            self.log(who, LogEvent::Refused(e));
        }
        self.wiring.plant_dirty = true;
    }

    /// The operator's overtravel rescue ([`operator::rescue`]).
    pub(super) fn rescue(&mut self, t: SimTime, who: Actor) -> Result<(), lift_model::PlantError> {
        let rescue = match operator::rescue(&self.lift, self.sc.floors) {
            Rescue::NotNeeded => self
                .safety
                .drive
                .as_ref()
                .and_then(|d| d.slp_rescue_mm(&self.lift, self.sc.floors))
                .map_or(Rescue::NotNeeded, Rescue::Crank),
            r => r,
        };
        self.log(who, LogEvent::Rescue(rescue));
        match rescue {
            Rescue::NotNeeded | Rescue::K1Closed => Ok(()),
            Rescue::Crank(mm) => self.lift.crank(t, mm),
        }
    }

    pub(super) fn fault(&mut self, t: SimTime, f: Fault) {
        match f {
            Fault::SlaveOffline { slave } | Fault::SlaveOnline { slave } => {
                let Some(id) = self.lab.slave_id(slave) else {
                    self.log(Actor::Scenario, LogEvent::Note(RigNote::NoSlave(slave)));
                    return;
                };
                if matches!(f, Fault::SlaveOffline { .. }) {
                    self.lab.bus_mut().detach(id);
                } else {
                    self.lab.bus_mut().attach(id);
                    self.wiring.plant_dirty = true;
                }
            }
            Fault::PowerFail { duration } => {
                self.lab.bus_mut().set_supply_voltage(0.0);
                self.agenda.timers.push((t + duration, Timer::PowerBack));
            }
            Fault::SafeLinkDrop { duration } => {
                self.safety
                    .logic
                    .drop_link(SafeLink::CabinStop, t, duration)
            }
            Fault::Vane { sensor, fault } => {
                if let Err(e) = self.lift.set_vane_fault(t, sensor, fault) {
                    self.log(Actor::Plant, LogEvent::PlantError(e));
                }
                self.wiring.plant_dirty = true;
            }
            Fault::ConverterRunaway { .. } | Fault::ConverterRepaired => {
                let runaway = match f {
                    Fault::ConverterRunaway { up } => Some(up),
                    _ => None,
                };
                if let Err(e) = self.lift.set_converter_runaway(t, runaway) {
                    self.log(Actor::Plant, LogEvent::PlantError(e));
                }
                self.wiring.plant_dirty = true;
            }
            Fault::LineNoise { rate, duration } => {
                // The reader and the catalogue take only probabilities; a bad one is a note.
                match PulseErrorRate::new(rate) {
                    Ok(r) => {
                        let seed = self.sc.seed ^ NOISE_BURST_SEED ^ t.as_nanos();
                        self.lab
                            .bus_mut()
                            .set_line_faults(seed, FaultRates::uniform(r));
                        self.agenda.timers.push((t + duration, Timer::NoiseOver));
                    }
                    Err(e) => self.log(
                        Actor::Scenario,
                        LogEvent::Note(RigNote::NoNoise(e.to_string())),
                    ),
                }
            }
            Fault::EncoderFailed | Fault::EncoderRepaired => {
                // The scenario reader takes these only with the safe drive.
                match self.safety.drive.as_mut() {
                    Some(d) => d.set_encoder_failed(matches!(f, Fault::EncoderFailed)),
                    None => self.log(Actor::Scenario, LogEvent::Note(RigNote::NoEncoder)),
                }
            }
        }
    }

    pub(super) fn fire_timers(&mut self, t: SimTime) {
        // None due at almost every step (no timer at all, mostly).
        if self.agenda.timers.iter().all(|(at, _)| *at > t) {
            return;
        }
        let mut due: Vec<Timer> = Vec::new();
        self.agenda.timers.retain(|(at, timer)| {
            if *at <= t {
                due.push(*timer);
                false
            } else {
                true
            }
        });
        for timer in due {
            match timer {
                Timer::OperatorReset(on) => {
                    self.safety.operator_reset = on;
                    if on {
                        self.log(Actor::Rig, LogEvent::Note(RigNote::ResetAfterPowerOn));
                        self.agenda
                            .timers
                            .push((t + OPERATOR_PULSE, Timer::OperatorReset(false)));
                    }
                }
                Timer::ErrAck(on) => self.safety.err_ack = on,
                Timer::Attendant(Round::Ack) => self.act(t, Actor::Attendant, &Action::Ack),
                Timer::Attendant(Round::Reset) => self.act(t, Actor::Attendant, &Action::Reset),
                // The line's own noise again, once no other burst goes on.
                Timer::NoiseOver
                    if !self
                        .agenda
                        .timers
                        .iter()
                        .any(|(_, k)| *k == Timer::NoiseOver) =>
                {
                    let rates = PulseErrorRate::new(self.sc.pulse_error_rate)
                        .map_or(FaultRates::NONE, FaultRates::uniform);
                    self.lab.bus_mut().set_line_faults(self.sc.seed, rates);
                    self.log(Actor::Rig, LogEvent::Note(RigNote::NoiseOver));
                }
                Timer::NoiseOver => {}
                Timer::PowerBack => {
                    self.lab.bus_mut().set_supply_voltage(NOMINAL_VOLTS);
                    self.log(Actor::Rig, LogEvent::Note(RigNote::PowerBack));
                    self.wiring.plant_dirty = true;
                }
            }
        }
    }
}
