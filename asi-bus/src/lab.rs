//! The lab lift's bus, ready-made (docs/lab-bus.md table; seed 003 table 3.1).
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
#[derive(Debug)]
pub struct LabLift {
    /// The bus.
    pub bus: Bus,
    /// The slaves by address (index = address; `None` where the lab has no slave).
    pub ids: [Option<SlaveId>; 32],
    /// The Safety-at-Work monitor of addresses 11 and 12.
    pub monitor: MonitorId,
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
        Some(match n {
            1..=4 => Box::new(FloorStation::new()),
            CABIN_DISPLAY => Box::new(CabinDisplay::new()),
            CABIN_PANEL => Box::new(CabinPanel::new()),
            CONVERTER => Box::new(Converter::new()),
            LOAD_SENSOR => Box::new(LoadSensor::new()),
            SPEED_SETPOINT => Box::new(AnalogOutput::new()),
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
            let device = LabLift::device_for(n).ok_or_else(|| ConfigError::Slave {
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
        match (self.monitor(), Address::new(address)) {
            (Some(m), Some(a)) => m.released(a),
            _ => false,
        }
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
