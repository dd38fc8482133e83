//! What the application reads and sets of the bus between its calls: the line recording, the
//! master and its process image, the timing, the statistics and the trace, the slaves and
//! their devices, the monitors.

use super::*;
use asi_master::record::BusStats;

impl Bus {
    /// Starts (`true`) or stops recording the line: every pulse as it is on the line (after
    /// faults, colliding answers superimposed), for waveform and VCD export.
    pub fn record_line(&mut self, on: bool) {
        self.release_held();
        self.medium.record_pulses(on);
        self.line_changed();
    }

    /// Whether the line's pulses are recorded ([`Bus::record_line`]).
    pub fn records_line(&self) -> bool {
        self.medium.inner().is_recording()
    }

    /// The pulses put on the line since the last call, in the order they went on it (a
    /// pulse that a fault shifted may be slightly out of time order).
    pub fn take_line_pulses(&mut self) -> Vec<asi_phy::Pulse> {
        self.medium.take_pulses()
    }

    /// The master.
    pub fn master(&self) -> &Master {
        &self.master
    }

    /// What the application tells the master about its PLC from now on (the SYS and OK LEDs
    /// of seed 003 table 3.2, [`asi_master::leds`]); the bus's traffic does not depend on it.
    pub fn set_plc_link(&mut self, plc: asi_master::PlcLink) {
        self.master.set_plc_link(self.now, plc);
    }

    /// The process image (what the PLC reads and writes).
    pub fn image(&self) -> &asi_master::image::ProcessImage {
        self.master.image()
    }

    /// The process image for the PLC to write its outputs, host flags and mailbox jobs. An
    /// idle master (offline by host flag) looks at it again at the bus time.
    pub fn image_mut(&mut self) -> &mut asi_master::image::ProcessImage {
        if self.state == State::Idle && self.master.power_ok() {
            self.next_event = self.next_event.min(self.now);
        }
        self.master.image_mut()
    }

    /// The bus timing.
    pub fn timing(&self) -> &BusTiming {
        &self.timing
    }

    /// Cumulative statistics: transactions, repeats, errors by check class, no-response, cycle
    /// time, drop-outs.
    pub fn stats(&self) -> BusStats {
        let c = self.master.cycle_stats();
        BusStats {
            dropouts: c.dropouts,
            cycles: c.cycles,
            cycle_min: c.cycle_min,
            cycle_max: c.cycle_max,
            cycle_total: c.cycle_total,
            ..self.tally.totals()
        }
    }

    /// The statistics per slave as they are now (docs/master.md, "Statistics per slave"):
    /// calls, repeats, errors, drop-outs and time out of LAS up to now, the lights of the
    /// windows ended by now, and the codes seen in the traffic.
    pub fn slave_stats(&self) -> SlaveTable {
        let normal = self.master.phase() == Phase::NormalOperation;
        self.tally
            .at(self.now, self.master.las(), self.master.lps(), normal)
    }

    /// How the slaves' traffic lights are worked out, from the next light window on.
    pub fn set_light_rule(&mut self, rule: asi_master::LightRule) {
        self.tally.set_rule(rule);
    }

    /// Keeps the last `capacity` trace records for [`Bus::drain_trace`] (0 switches it off).
    pub fn enable_trace(&mut self, capacity: usize) {
        self.ring = (capacity > 0).then(|| TraceRing::new(capacity));
    }

    /// Takes the trace records kept so far, oldest first.
    pub fn drain_trace(&mut self) -> Vec<TransactionRecord> {
        self.ring
            .as_mut()
            .map_or_else(Vec::new, |r| r.drain().collect())
    }

    /// The trace ring (for `dropped()` and allocation-free draining).
    pub fn trace_ring_mut(&mut self) -> Option<&mut TraceRing> {
        self.ring.as_mut()
    }

    /// Calls `cb` with every trace record (`None` removes it).
    pub fn set_trace_callback(&mut self, cb: Option<TraceCallback>) {
        self.callback = Callback(cb);
    }

    /// Number of slaves added.
    pub fn slave_count(&self) -> usize {
        self.slaves.len()
    }

    /// The places of the bus's slaves, in the order they were added.
    pub fn slave_ids(&self) -> impl Iterator<Item = SlaveId> {
        (0..self.slaves.len()).map(SlaveId)
    }

    /// A slave.
    pub fn slave(&self, id: SlaveId) -> Option<&Slave> {
        self.slaves.get(id.0).map(|s| &s.slave)
    }

    /// A slave, mutable (for fault hooks such as [`Slave::set_nv_error`]).
    pub fn slave_mut(&mut self, id: SlaveId) -> Option<&mut Slave> {
        self.drives_may_move();
        self.slaves.get_mut(id.0).map(|s| &mut s.slave)
    }

    /// The attached slave currently at address `n` (A or standard), if any (first found).
    pub fn find(&self, n: u8) -> Option<SlaveId> {
        self.slaves
            .iter()
            .position(|s| s.attached && s.slave.addr().number() == n)
            .map(SlaveId)
    }

    /// The device of slave `id` as a `T`.
    pub fn device<T: Peripheral>(&self, id: SlaveId) -> Option<&T> {
        self.slave(id)?.device().as_any().downcast_ref()
    }

    /// The device of slave `id` as a `T`, mutable (to set its peripheral inputs).
    pub fn device_mut<T: Peripheral>(&mut self, id: SlaveId) -> Option<&mut T> {
        self.slave_mut(id)?.device_mut().as_any_mut().downcast_mut()
    }

    /// A monitor.
    pub fn monitor(&self, id: MonitorId) -> Option<&SafetyMonitor> {
        debug_assert!(self.unsettled.is_none(), "the bus is settled between calls");
        self.monitors.get(id.0)
    }

    /// `true` if monitor `id` releases the safety slave at `address` (`false` without that
    /// monitor). What the monitor releases is not its receiver's state: this may be asked
    /// while a run of clean transactions has not been written into the receivers
    /// ([`Bus::look`]).
    pub fn monitor_releases(&self, id: MonitorId, address: Address) -> bool {
        self.monitors.get(id.0).is_some_and(|m| m.released(address))
    }

    /// A monitor, mutable.
    pub fn monitor_mut(&mut self, id: MonitorId) -> Option<&mut SafetyMonitor> {
        // The application may put another monitor in its place.
        self.monitor_in_step = false;
        self.monitors.get_mut(id.0)
    }

    /// The releases monitor `id` dropped since the last call, in order
    /// ([`SafetyMonitor::take_drops`]); empty for no such monitor. Taking them leaves its
    /// receiver as it is, so a monitor in step with the slaves' receiver stays so (unlike
    /// [`Bus::monitor_mut`], after which the two are compared again).
    pub fn take_monitor_drops(&mut self, id: MonitorId) -> Vec<asi_slaves::monitor::MonitorDrop> {
        self.monitors
            .get_mut(id.0)
            .map(SafetyMonitor::take_drops)
            .unwrap_or_default()
    }

    /// `true` once the master is in normal operation.
    pub fn is_running(&self) -> bool {
        self.master.phase() == Phase::NormalOperation
    }
}
