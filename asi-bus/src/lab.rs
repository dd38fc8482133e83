//! The lab lift's bus, ready-made (docs/lab-bus.md table; table 3.1 of the lift thesis).
//!
//! | address | device |
//! |---|---|
//! | 1..4 | floor stations ([`FloorStation`]) |
//! | 5 | cabin display ([`CabinDisplay`]) |
//! | 6 | cabin panel: buttons and sensors ([`CabinPanel`]) |
//! | 7 | converter I/O ([`Converter`]) |
//! | 8 | load sensor ([`LoadSensor`]) |
//! | 10 | current-loop output, channel 1 = speed set-point Rychlost ([`AnalogOutput`]) |
//! | 11 | bottom overtravel safety sensor ([`SafetySensor`]) |
//! | 12 | top overtravel safety sensor ([`SafetySensor`]) |
//!
//! The projected configuration is exactly this set (protected mode), every slave with
//! parameter 1111. A passive [`SafetyMonitor`] watches addresses 11 and 12.

use crate::bus::{Bus, MonitorId, SlaveId};
use asi_master::config::{ConfigError, MasterConfig, ProjectedConfig, ProjectedSlave};
use asi_phy::{Address, Nibble, SlaveAddr, SlaveCodes};
use asi_slaves::devices::{
    AnalogOutput, CabinDisplay, CabinPanel, Converter, FloorStation, IoModule, LoadSensor,
    SafetySensor, AC2258, AC2618, AC2726, GG505S, IG5886,
};
use asi_slaves::monitor::{CodeTable, MonitorConfig, SafetyMonitor};
use asi_slaves::slave::{Peripheral, Slave};
use lab::address::{
    CABIN_DISPLAY, CABIN_PANEL, CONVERTER, FREE, LOAD_SENSOR, SAFETY_BOTTOM, SAFETY_TOP,
    SPEED_SETPOINT,
};

/// Serial numbers that seed the two safety sensors' code tables.
pub const SAFETY_SERIALS: [u64; 2] = [0x0505_0011, 0x0505_0012];

/// The lab lift's slave list: address, name and codes.
pub const LAB_SLAVES: [(u8, &str, SlaveCodes); 11] = [
    (1, "floor 1", AC2726),
    (2, "floor 2", AC2726),
    (3, "floor 3", AC2726),
    (4, "floor 4", AC2726),
    (CABIN_DISPLAY, "cabin display", AC2726),
    (CABIN_PANEL, "cabin panel", AC2726),
    (CONVERTER, "converter I/O", AC2258),
    (LOAD_SENSOR, "load sensor", IG5886),
    (SPEED_SETPOINT, "current loop", AC2618),
    (SAFETY_BOTTOM, "bottom overtravel", GG505S),
    (SAFETY_TOP, "top overtravel", GG505S),
];

fn extra_addresses(n: u8) -> Result<&'static [u8], ConfigError> {
    FREE.get(..n as usize).ok_or_else(|| ConfigError::Setting {
        field: "extra I/O modules",
        value: n.to_string(),
        rule: "must be 0..=20 (the addresses the lab leaves free)",
    })
}

/// The lab lift's bus with typed access to its devices.
#[derive(Clone, Debug)]
pub struct LabLift {
    /// The bus.
    pub(crate) bus: Bus,
    /// The slaves by address (index = address; `None` where the lab has no slave).
    ids: [Option<SlaveId>; 32],
    /// The Safety-at-Work monitor of addresses 11 and 12.
    monitor: MonitorId,
}

/// A device that drives the plant, and what it drives as one number to compare (see
/// [`Driving`]).
trait Drives: Peripheral + Clone {
    fn drive(&self) -> u32;
}

/// A display word as a number to compare: the word, or 2^16 while blank.
fn display_code(d: Option<u16>) -> u32 {
    d.map_or(1 << 16, u32::from)
}

impl Drives for FloorStation {
    fn drive(&self) -> u32 {
        display_code(self.display())
    }
}

impl Drives for CabinDisplay {
    fn drive(&self) -> u32 {
        display_code(self.display())
    }
}

impl Drives for Converter {
    fn drive(&self) -> u32 {
        self.outputs().get().into()
    }
}

impl Drives for AnalogOutput {
    fn drive(&self) -> u32 {
        u32::from(self.current_ua(1)) | u32::from(self.current_ua(2)) << 16
    }
}

/// A lab device whose outputs drive the plant (a floor or cabin display, the converter's run
/// and direction, the speed set-point), with a count of the changes of what it drives
/// ([`Peripheral::drive_changes`]): the rig reads the devices' outputs only when the bus's sum
/// of the counts has moved ([`LabLift::drive_changes`]), instead of at every moment.
///
/// What it drives can change only through the device's [`Peripheral`] methods, all of which
/// go through this wrapper: after `exchange`, `write_parameter` and `reset` it compares what
/// the device drives with what it drove and counts a change; `as_any_mut` (the application's
/// typed access, which may change anything) counts one at once and forgets what the device
/// drove, so that the next call counts one too. Typed access sees the device itself
/// (`as_any` and `as_any_mut` hand out the wrapped device), and `Debug` shows it as it is.
/// The count is the device's own, so a copy of the bus counts on by itself.
#[derive(Clone)]
struct Driving<T> {
    device: T,
    /// What the device drove after the last call, `None` after typed mutable access.
    last: Option<u32>,
    changes: u64,
}

impl<T: Drives> Driving<T> {
    fn boxed(device: T) -> Box<dyn Peripheral> {
        Box::new(Driving {
            last: Some(device.drive()),
            device,
            changes: 0,
        })
    }

    /// Counts a change if what the device drives is not what it drove; `true` if it did.
    fn note(&mut self) -> bool {
        let now = self.device.drive();
        let moved = self.last != Some(now);
        if moved {
            self.last = Some(now);
            self.changes += 1;
        }
        moved
    }
}

impl<T: Peripheral> core::fmt::Debug for Driving<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.device.fmt(f)
    }
}

impl<T: Drives> Peripheral for Driving<T> {
    fn exchange(&mut self, now: asi_phy::SimTime, outputs: Nibble) -> Nibble {
        self.exchange_noted(now, outputs).0
    }
    fn exchange_noted(&mut self, now: asi_phy::SimTime, outputs: Nibble) -> (Nibble, bool) {
        let inputs = self.device.exchange(now, outputs);
        (inputs, self.note())
    }
    fn write_parameter(&mut self, now: asi_phy::SimTime, parameter: Nibble) -> Nibble {
        let echo = self.device.write_parameter(now, parameter);
        self.note();
        echo
    }
    fn reset(&mut self) {
        self.device.reset();
        self.note();
    }
    fn periphery_fault(&self) -> bool {
        self.device.periphery_fault()
    }
    fn drive_changes(&self) -> Option<u64> {
        Some(self.changes)
    }
    fn as_any(&self) -> &dyn core::any::Any {
        self.device.as_any()
    }
    fn as_any_mut(&mut self) -> &mut dyn core::any::Any {
        self.last = None;
        self.changes += 1;
        self.device.as_any_mut()
    }
}

fn addr(n: u8) -> Result<Address, ConfigError> {
    Address::new(n).ok_or_else(|| ConfigError::Slave {
        name: format!("address {n}"),
        why: "out of range 0..=31".into(),
    })
}

impl LabLift {
    /// The lab bus with the default master settings.
    pub fn new() -> Result<LabLift, ConfigError> {
        LabLift::with_config(MasterConfig::default())
    }

    /// The projected configuration of the lab lift.
    pub fn projected() -> Result<ProjectedConfig, ConfigError> {
        LabLift::projected_with(0)
    }

    /// The projected configuration of the lab lift with `extra` plain I/O modules at the
    /// addresses the lab leaves free ([`FREE`], in that order).
    pub fn projected_with(extra: u8) -> Result<ProjectedConfig, ConfigError> {
        let extra = extra_addresses(extra)?;
        let lab = LAB_SLAVES.iter().map(|&(n, _, codes)| (n, codes));
        let io = extra.iter().map(|&n| (n, AC2726));
        ProjectedConfig::new(lab.chain(io).map(|(n, codes)| ProjectedSlave {
            addr: SlaveAddr {
                address: Address::new(n).unwrap_or_default(),
                select: asi_phy::Select::A,
            },
            codes,
            parameter: Nibble::ALL,
        }))
    }

    /// A fresh device for lab address `n`.
    pub fn device_for(n: u8) -> Option<Box<dyn Peripheral>> {
        LabLift::device(n, false)
    }

    /// A fresh device for lab address `n`; one whose outputs drive the plant (the floor
    /// stations, the cabin display, the converter I/O, the current-loop output) counts the
    /// changes of what it drives if `counted` ([`LabLift::drive_changes`]).
    fn device(n: u8, counted: bool) -> Option<Box<dyn Peripheral>> {
        fn driving<T: Drives>(device: T, counted: bool) -> Box<dyn Peripheral> {
            if counted {
                Driving::boxed(device)
            } else {
                Box::new(device)
            }
        }
        Some(match n {
            1..=4 => driving(FloorStation::new(), counted),
            CABIN_DISPLAY => driving(CabinDisplay::new(), counted),
            CABIN_PANEL => Box::new(CabinPanel::new()),
            CONVERTER => driving(Converter::new(), counted),
            LOAD_SENSOR => Box::new(LoadSensor::new()),
            SPEED_SETPOINT => driving(AnalogOutput::new(), counted),
            SAFETY_BOTTOM => Box::new(SafetySensor::new(CodeTable::from_serial(SAFETY_SERIALS[0]))),
            SAFETY_TOP => Box::new(SafetySensor::new(CodeTable::from_serial(SAFETY_SERIALS[1]))),
            _ => return None,
        })
    }

    /// The lab bus with master settings `cfg`.
    pub fn with_config(cfg: MasterConfig) -> Result<LabLift, ConfigError> {
        LabLift::with_extra(cfg, 0)
    }

    /// The lab bus with master settings `cfg` and `extra` (0..=20) plain 4I/4O modules
    /// (AC2726, all pins low) at the free addresses [`FREE`], projected too: the
    /// lab lift on a fuller bus, for cycle-time and latency studies (docs/timing.md).
    pub fn with_extra(cfg: MasterConfig, extra: u8) -> Result<LabLift, ConfigError> {
        let timing = cfg.timing;
        let extra = extra_addresses(extra)?;
        let mut bus = Bus::new(cfg, LabLift::projected_with(extra.len() as u8)?, Vec::new())?;
        let mut ids = [None; 32];
        for &(n, name, codes) in &LAB_SLAVES {
            let device = LabLift::device(n, true).ok_or_else(|| ConfigError::Slave {
                name: name.into(),
                why: "no device".into(),
            })?;
            let id = bus.add_slave(Slave::new(name, addr(n)?, codes, device))?;
            ids[n as usize] = Some(id);
        }
        for &n in extra {
            let id = bus.add_slave(Slave::new(
                format!("io {n}"),
                addr(n)?,
                AC2726,
                Box::new(IoModule::new()),
            ))?;
            ids[n as usize] = Some(id);
        }
        let monitor = bus.add_monitor(SafetyMonitor::new(
            &timing,
            MonitorConfig::default(),
            &[addr(SAFETY_BOTTOM)?, addr(SAFETY_TOP)?],
        ));
        Ok(LabLift { bus, ids, monitor })
    }

    /// The bus.
    pub fn bus(&self) -> &Bus {
        &self.bus
    }

    /// The bus, mutable.
    pub fn bus_mut(&mut self) -> &mut Bus {
        &mut self.bus
    }

    /// The bus alone, without the lab's typed access to its devices.
    pub fn into_bus(self) -> Bus {
        self.bus
    }

    /// The Safety-at-Work monitor of addresses 11 and 12, on the bus ([`Bus::monitor`]).
    pub fn monitor_id(&self) -> MonitorId {
        self.monitor
    }

    /// A count that moves whenever what the plant-driving devices drive may have changed:
    /// their display words, the converter I/O's outputs, the current-loop output's currents
    /// (and whenever the application takes one of them mutably, which may change anything).
    /// While it stands still, [`LabLift::floor`]'s `display`, [`LabLift::cabin_display`]'s
    /// `display`, [`LabLift::converter`]'s `outputs` and [`LabLift::analog_output`]'s
    /// `current_ua` say what they said, so the rig reads them only when it has moved.
    ///
    /// It is the bus's sum of the devices' counts ([`Bus::drive_count`]): a device put in
    /// their place through [`Bus::slave_mut`] is covered only if it counts too.
    pub fn drive_changes(&self) -> u64 {
        self.bus.drive_count().unwrap_or(0)
    }

    fn id(&self, n: u8) -> Option<SlaveId> {
        self.ids.get(n as usize).copied().flatten()
    }

    fn dev<T: Peripheral>(&self, n: u8) -> Option<&T> {
        self.bus.device(self.id(n)?)
    }

    fn dev_mut<T: Peripheral>(&mut self, n: u8) -> Option<&mut T> {
        let id = self.id(n)?;
        self.bus.device_mut(id)
    }

    /// The floor station of `floor` (1..=4).
    pub fn floor(&self, floor: u8) -> Option<&FloorStation> {
        (1..=4).contains(&floor).then(|| self.dev(floor)).flatten()
    }
    /// The floor station of `floor` (1..=4), mutable.
    pub fn floor_mut(&mut self, floor: u8) -> Option<&mut FloorStation> {
        if (1..=4).contains(&floor) {
            self.dev_mut(floor)
        } else {
            None
        }
    }
    /// The cabin display.
    pub fn cabin_display(&self) -> Option<&CabinDisplay> {
        self.dev(CABIN_DISPLAY)
    }
    /// The cabin panel.
    pub fn cabin_panel(&self) -> Option<&CabinPanel> {
        self.dev(CABIN_PANEL)
    }
    /// The cabin panel, mutable.
    pub fn cabin_panel_mut(&mut self) -> Option<&mut CabinPanel> {
        self.dev_mut(CABIN_PANEL)
    }
    /// The converter I/O.
    pub fn converter(&self) -> Option<&Converter> {
        self.dev(CONVERTER)
    }
    /// The converter I/O, mutable.
    pub fn converter_mut(&mut self) -> Option<&mut Converter> {
        self.dev_mut(CONVERTER)
    }
    /// The load sensor, mutable.
    pub fn load_sensor_mut(&mut self) -> Option<&mut LoadSensor> {
        self.dev_mut(LOAD_SENSOR)
    }
    /// The current-loop output.
    pub fn analog_output(&self) -> Option<&AnalogOutput> {
        self.dev(SPEED_SETPOINT)
    }
    /// The safety sensor at `address` (11 or 12).
    pub fn safety_sensor(&self, address: u8) -> Option<&SafetySensor> {
        matches!(address, SAFETY_BOTTOM | SAFETY_TOP)
            .then(|| self.dev(address))
            .flatten()
    }
    /// The safety sensor at `address` (11 or 12), mutable.
    pub fn safety_sensor_mut(&mut self, address: u8) -> Option<&mut SafetySensor> {
        if matches!(address, SAFETY_BOTTOM | SAFETY_TOP) {
            self.dev_mut(address)
        } else {
            None
        }
    }
    /// The safety monitor.
    pub fn monitor(&self) -> Option<&SafetyMonitor> {
        self.bus.monitor(self.monitor)
    }
    /// `true` if the monitor releases the safety sensor at `address`.
    pub fn released(&self, address: u8) -> bool {
        Address::new(address).is_some_and(|a| self.bus.monitor_releases(self.monitor, a))
    }
    /// The slave id at lab address `n` (the slave put there at construction, wherever it
    /// is now).
    pub fn slave_id(&self, n: u8) -> Option<SlaveId> {
        self.id(n)
    }
}

/// A bus of `n` (1..=31) plain 4I/4O modules with `codes` at addresses 1..=n, all projected:
/// the reference bus of the cycle-time formulas (docs/timing.md) and of the benchmark.
pub fn io_bus(n: u8, codes: SlaveCodes) -> Result<Bus, ConfigError> {
    if !(1..=31).contains(&n) {
        return Err(ConfigError::Setting {
            field: "number of I/O modules",
            value: n.to_string(),
            rule: "must be 1..=31 (one per address)",
        });
    }
    let mut projected = Vec::new();
    let mut slaves = Vec::new();
    for k in 1..=n {
        let address = addr(k)?;
        projected.push(ProjectedSlave {
            addr: SlaveAddr {
                address,
                select: asi_phy::Select::A,
            },
            codes,
            parameter: Nibble::ALL,
        });
        slaves.push(Slave::new(
            format!("io {k}"),
            address,
            codes,
            Box::new(IoModule::new()),
        ));
    }
    Bus::new(
        MasterConfig::default(),
        ProjectedConfig::new(projected)?,
        slaves,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bus::{LookWatch, Stop};

    fn ms(n: u64) -> asi_phy::SimTime {
        asi_phy::SimTime::from_millis(n)
    }

    /// The converter's outputs and the set-point current as the rig reads them.
    fn drives(lab: &LabLift) -> (Nibble, u16) {
        let c = lab.converter().expect("the converter").outputs();
        (c, lab.analog_output().expect("the set-point").current_ua(1))
    }

    /// Steps the bus event by event to `until`; at every step, what the devices drive
    /// changed only where the count moved.
    fn watch(lab: &mut LabLift, until: u64) -> u64 {
        let mut moved = 0;
        while lab.bus.poll_at() <= ms(until) {
            let (count, seen) = (lab.drive_changes(), drives(lab));
            lab.bus.advance_to(lab.bus.poll_at());
            if lab.drive_changes() == count {
                assert_eq!(drives(lab), seen, "at {}", lab.bus.now());
            } else {
                moved += 1;
            }
        }
        moved
    }

    #[test]
    fn the_drive_count_moves_with_what_the_plant_driving_devices_drive() {
        let mut lab = LabLift::new().expect("the lab bus");
        let run = SlaveAddr {
            address: Address::new(CONVERTER).expect("7"),
            select: asi_phy::Select::A,
        };
        lab.bus
            .image_mut()
            .output
            .set_nibble(run, Nibble::from_low_bits(0b0011));
        lab.bus
            .image_mut()
            .output
            .set_analog(SPEED_SETPOINT, 1, 7000);
        assert!(watch(&mut lab, 200) > 0);
        assert_eq!(drives(&lab), (Nibble::from_low_bits(0b0011), 7000));
        // Unplugged, the converter's outputs go off at once: counted.
        let count = lab.drive_changes();
        let id = lab.slave_id(CONVERTER).expect("the converter");
        lab.bus.detach(id);
        assert_ne!(lab.drive_changes(), count);
        assert_eq!(drives(&lab).0, Nibble::ZERO);
        lab.bus.attach(id);
        watch(&mut lab, 400);
        // A power fail resets every slave: counted.
        let count = lab.drive_changes();
        lab.bus.set_supply_voltage(0.0);
        assert_ne!(lab.drive_changes(), count);
        assert_eq!(drives(&lab), (Nibble::ZERO, 0));
        lab.bus.set_supply_voltage(crate::bus::NOMINAL_VOLTS);
        watch(&mut lab, 800);
        assert_eq!(drives(&lab), (Nibble::from_low_bits(0b0011), 7000));
        // Typed mutable access may change anything: counted too.
        let count = lab.drive_changes();
        let _ = lab.converter_mut();
        assert_ne!(lab.drive_changes(), count);
        // Stepping stays exact after it, and the count stands still while nothing changes.
        watch(&mut lab, 900);
        let count = lab.drive_changes();
        watch(&mut lab, 1000);
        assert_eq!(lab.drive_changes(), count);
    }

    /// The lab bus with every address's outputs watched and 7000 µA asked of the set-point
    /// output: its analog transfer gives a new output nibble at nearly every cycle.
    fn analog_transfer() -> LabLift {
        let mut lab = LabLift::new().expect("the lab bus");
        watch_all(&mut lab);
        lab.bus
            .image_mut()
            .output
            .set_analog(SPEED_SETPOINT, 1, 7000);
        lab
    }

    /// `advance_to` hands the caller every output it took, so the next `advance_before`
    /// stops at the next new output, as it does from a bus that stopped at the last one.
    #[test]
    fn advance_to_leaves_no_output_behind_for_advance_before() {
        let lab = analog_transfer;
        let mut stops = lab();
        let mut at = Vec::new();
        while let Some(Stop::Output(t)) = stops.bus.advance_before(ms(300)) {
            at.push(t);
        }
        assert!(at.len() > 5, "{} new outputs", at.len());
        for w in at.windows(2) {
            let mut to = lab();
            to.bus.advance_to(w[0]);
            let next = to.bus.advance_before(ms(300));
            assert_eq!(next, Some(Stop::Output(w[1])), "after {}", w[0]);
        }
    }

    /// A new output nibble that moved no drive passes `advance_before` within the time given
    /// (inclusive), and only then; one that moved a drive ends it as before. The bus looks at
    /// the count at every new nibble, passed or not: the stops are those of a bus that
    /// stops at every new nibble, less the quiet ones within the time.
    #[test]
    fn quiet_outputs_pass_only_within_their_time_and_while_no_drive_moves() {
        let lab = analog_transfer;
        let mut every = lab();
        let mut stops = Vec::new();
        let mut count = every.drive_changes();
        while let Some(Stop::Output(t)) = every.bus.advance_before(ms(400)) {
            stops.push((t, every.drive_changes() != count));
            count = every.drive_changes();
        }
        let quiet = stops.iter().filter(|(_, moved)| !moved).count();
        assert!(
            quiet > 5 && quiet < stops.len(),
            "{quiet} of {}",
            stops.len()
        );
        // A quiet stop's own time: it passes (inclusive).
        let edge = stops
            .iter()
            .rev()
            .find(|(_, moved)| !moved)
            .map(|&(t, _)| t);
        for until in [ms(0), ms(150), ms(400)].into_iter().chain(edge) {
            let mut passing = lab();
            let mut w = passing.bus.watching();
            w.drives_only_through = Some(until);
            passing.bus.watch(w);
            let mut seen = Vec::new();
            while let Some(Stop::Output(t)) = passing.bus.advance_before(ms(400)) {
                seen.push(t);
            }
            let expected: Vec<asi_phy::SimTime> = stops
                .iter()
                .filter(|&&(t, moved)| moved || t > until)
                .map(|&(t, _)| t)
                .collect();
            assert_eq!(seen, expected, "quiet outputs pass until {until}");
            assert_eq!(passing.bus.stats(), every.bus.stats());
        }
    }

    /// What the look watch ([`crate::bus::Watch::look`]) stands for: an application that steps to each of
    /// its times (`advance_before` the time, then `advance_to` it) and looks at the bus there,
    /// then runs on to `until`. A new output at the time itself is what `advance_before` of
    /// the next nanosecond returns.
    fn look_by_steps(bus: &mut Bus, w: LookWatch, until: asi_phy::SimTime) -> Option<Stop> {
        let mut g = w.first;
        while g < until {
            let taken = bus.advance_before(g + asi_phy::SimDuration::from_nanos(1));
            match taken {
                Some(Stop::Output(at)) if at < g => return taken,
                _ => bus.advance_to(g),
            }
            if taken.is_some() || bus.look(w.monitor) != w.seen {
                return Some(Stop::Look(g));
            }
            g += w.period;
        }
        bus.advance_before(until)
    }

    /// Runs `lab` to `end` with the look watch from 1 ms every 1 ms (`by_steps`: as
    /// `look_by_steps`), each call to the next 10 ms and looking for the look the bus had
    /// at its start, going on after every stop as an application would (from a time it
    /// stopped at, the next one; from a new output, the time it did not pass); returns the
    /// stops.
    fn look_runs(lab: &mut LabLift, by_steps: bool, end: u64) -> Vec<Option<Stop>> {
        let period = asi_phy::SimDuration::from_millis(1);
        let monitor = lab.monitor_id();
        let mut runs = Vec::new();
        let mut g = ms(1);
        while g < ms(end) {
            let until = ms((g.as_nanos() / 10_000_000 + 1) * 10).min(ms(end));
            let w = LookWatch {
                monitor,
                first: g,
                period,
                seen: lab.bus.look(monitor),
            };
            let stop = if by_steps {
                look_by_steps(&mut lab.bus, w, until)
            } else {
                let mut watch = lab.bus.watching();
                watch.look = Some(w);
                lab.bus.watch(watch);
                let stop = lab.bus.advance_before(until);
                watch.look = None;
                lab.bus.watch(watch);
                stop
            };
            g = match stop {
                None => until,
                Some(Stop::Look(at)) => at + period,
                Some(Stop::Output(at)) => {
                    while g <= at {
                        g += period;
                    }
                    g
                }
            };
            runs.push(stop);
        }
        runs
    }

    /// Two copies of `lab()` run 300 ms with the look watch, one by the watch and one by
    /// steps: the same stops, transactions and statistics. Returns the stops, for the caller
    /// to check that they stop where it expects.
    fn look_runs_agree(lab: impl Fn() -> LabLift) -> Vec<Option<Stop>> {
        let (mut a, mut b) = (lab(), lab());
        let by_watch = look_runs(&mut a, false, 300);
        let by_steps = look_runs(&mut b, true, 300);
        assert_eq!(by_watch, by_steps);
        assert_eq!(a.bus.drain_trace(), b.bus.drain_trace());
        assert_eq!(a.bus.stats(), b.bus.stats());
        by_watch
    }

    /// Watches every address's outputs.
    fn watch_all(lab: &mut LabLift) {
        let mut w = lab.bus.watching();
        w.outputs = u32::MAX;
        lab.bus.watch(w);
    }

    /// The look watch stops where an application stepping to each of its times would: at a
    /// new output before a time, at a time where one came or where the look changed, and
    /// nowhere else; and the bus goes through the same transactions. Through the start-up
    /// from power-on (the look changes as slaves join the LAS and the monitor releases), and
    /// while the set-point's transfer hands out new nibbles that move the drive count, some
    /// of which pass ([`crate::bus::Watch::drives_only_through`]).
    #[test]
    fn the_look_watch_stops_where_steps_to_each_time_would() {
        let startup = || {
            let mut lab = LabLift::new().expect("the lab bus");
            watch_all(&mut lab);
            lab.bus.enable_trace(1 << 16);
            lab
        };
        let runs = look_runs_agree(startup);
        let looks = runs
            .iter()
            .filter(|r| matches!(r, Some(Stop::Look(_))))
            .count();
        assert!(looks > 0, "the look never changed: {runs:?}");

        let transfer = || {
            let mut lab = analog_transfer();
            lab.bus.enable_trace(1 << 16);
            let mut w = lab.bus.watching();
            w.drives_only_through = Some(ms(150));
            lab.bus.watch(w);
            lab
        };
        let runs = look_runs_agree(transfer);
        let outputs = runs
            .iter()
            .filter(|r| matches!(r, Some(Stop::Output(_))))
            .count();
        assert!(outputs > 0, "no new output stopped a run: {runs:?}");
    }

    #[test]
    fn an_io_bus_has_at_most_31_modules() {
        let std = SlaveCodes::new(7, 0, 0xF, 0xF);
        let e = io_bus(32, std).expect_err("32 modules");
        assert_eq!(
            e.to_string(),
            "master setting number of I/O modules = 32: must be 1..=31 (one per address)"
        );
    }
}
