//! The bus's fault hooks: unplugging and replugging slaves, the supply voltage, line faults.

use super::*;

impl Bus {
    /// Takes slave `id` off the bus (unplugged: it hears nothing, answers nothing, loses power).
    pub fn detach(&mut self, id: SlaveId) {
        self.release_held();
        // The reset may change what the device drives.
        self.drives_may_move();
        if let Some(s) = self.slaves.get_mut(id.0) {
            if s.attached {
                s.attached = false;
                // Unplugged, it has no power: its outputs are off at once.
                s.slave.reset();
                self.leave(id.0);
            }
        }
    }

    /// Puts slave `id` back on the bus: it powers up (reset) with a fresh receiver.
    pub fn attach(&mut self, id: SlaveId) {
        self.release_held();
        self.drives_may_move();
        let powered = self.slaves_powered;
        if let Some(s) = self.slaves.get_mut(id.0) {
            if !s.attached {
                s.attached = true;
                s.slave.reset();
                self.last_out = [NO_OUTPUT; 32];
                if powered {
                    self.join(id.0);
                }
                self.reindex();
            }
        }
    }

    /// `true` if slave `id` is on the bus.
    pub fn is_attached(&self, id: SlaveId) -> bool {
        self.slaves.get(id.0).is_some_and(|s| s.attached)
    }

    /// The AS-i supply voltage from now on. Below the master's APF threshold the master sets
    /// APF and goes offline; below [`SLAVE_MIN_VOLTS`] the slaves lose power and reset when it
    /// returns.
    pub fn set_supply_voltage(&mut self, volts: f64) {
        self.release_held();
        let volts = if volts.is_finite() {
            volts.max(0.0)
        } else {
            0.0
        };
        self.volts = volts;
        self.last_out = [NO_OUTPUT; 32];
        self.drives_may_move();
        let now = self.now;
        let slaves_ok = volts >= SLAVE_MIN_VOLTS;
        if !slaves_ok && self.slaves_powered {
            self.slaves_powered = false;
            self.groups.clear();
            // Without power a slave's outputs are off (the converter's run bit, the set-point
            // loop, the displays), not frozen at their last value.
            for s in self.slaves.iter_mut().filter(|s| s.attached) {
                s.slave.reset();
            }
        } else if slaves_ok && !self.slaves_powered {
            self.slaves_powered = true;
            let mut members = 0u64;
            for (i, s) in self.slaves.iter_mut().enumerate() {
                if s.attached {
                    s.slave.reset();
                    members |= 1 << i;
                }
            }
            if members != 0 {
                self.groups.push(Group {
                    listener: Listener::new(&self.timing.receiver(Expect::Both)),
                    members,
                });
            }
            self.reindex();
        }
        let master_ok = volts >= self.master.config().apf_threshold_volts;
        let was_ok = self.master.power_ok();
        self.master.set_power(now, master_ok);
        if !master_ok && was_ok {
            self.cur = None;
            self.medium.reset();
            self.master_rx = Listener::new(&self.timing.receiver(Expect::Responses));
            self.state = State::Idle;
        }
        if self.state == State::Idle {
            self.reschedule_idle();
        }
        // A power fail takes the master out of normal operation now, not at its next call.
        self.note_master(now);
    }

    /// The AS-i supply voltage.
    pub fn supply_voltage(&self) -> f64 {
        self.volts
    }

    /// Random line faults from now on, seeded (`FaultRates::NONE` switches them off).
    pub fn set_line_faults(&mut self, seed: u64, rates: FaultRates) {
        self.release_held();
        self.medium.set_faults(Some(FaultInjector::new(
            seed,
            rates,
            self.timing.half_bit(),
        )));
        self.line_changed();
    }

    /// Pulse-exact (`true`): every telegram goes through the pulse decoder, without the
    /// line's fast path for clean telegrams (asi-phy `Wire::set_pulse_exact`). Every outcome
    /// is the same either way; the exact path is the reference for tests and benchmarks.
    pub fn set_pulse_exact(&mut self, on: bool) {
        self.release_held();
        self.medium.set_pulse_exact(on);
        self.line_changed();
    }

    /// The line fault rates in force.
    pub fn line_fault_rates(&self) -> FaultRates {
        self.medium.fault_rates()
    }

    /// Exact pulse faults on the next telegram put on the line (asi-phy `PulseFault`, indices
    /// into its pulses).
    pub fn corrupt_next_telegram(&mut self, faults: Vec<PulseFault>) {
        self.release_held();
        self.medium.corrupt_next(faults);
        self.line_changed();
    }

    /// Pulse faults injected so far.
    pub fn faults_injected(&self) -> u64 {
        self.medium.faults_injected()
    }
}
