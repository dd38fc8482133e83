//! The projected configuration and the master's settings (docs/master.md, docs/asi.md
//! §5.1, §6.1; §2.2.3 of the lift thesis).

use crate::lists::SlaveList;
use asi_phy::{BusTiming, Nibble, SimDuration, SlaveAddr, SlaveCodes};

/// Protected or configuration mode (docs/asi.md §5.1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Only projected slaves whose codes match are activated.
    #[default]
    Protected,
    /// Every detected slave is activated.
    Configuration,
}

/// One projected slave: its codes and the parameter written at activation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ProjectedSlave {
    /// Address (A or standard, or B).
    pub addr: SlaveAddr,
    /// The codes it must have.
    pub codes: SlaveCodes,
    /// The parameter written at activation (PP).
    pub parameter: Nibble,
}

/// The projected configuration: LPS, the projected codes (PCD) and parameters (PP).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ProjectedConfig {
    lps: SlaveList,
    codes: [SlaveCodes; 64],
    params: [Nibble; 64],
}

impl Default for ProjectedConfig {
    fn default() -> Self {
        ProjectedConfig {
            lps: SlaveList::EMPTY,
            codes: [SlaveCodes::new(0xF, 0xF, 0xF, 0xF); 64],
            params: [Nibble::ALL; 64],
        }
    }
}

/// A configuration item that does not fit, naming the item.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ConfigError {
    /// Address 0 cannot be projected (docs/asi.md §5.2).
    #[error("projected slave {0}: address 0 cannot be projected")]
    AddressZero(SlaveAddr),
    /// The same address is projected twice.
    #[error("projected slave {0}: projected twice")]
    Duplicate(SlaveAddr),
    /// A B address for a slave that is not an A/B slave, or a standard slave whose B half is
    /// projected too.
    #[error("projected slave {addr}: {why}")]
    AddressKind {
        /// The address.
        addr: SlaveAddr,
        /// What is wrong.
        why: &'static str,
    },
    /// A master setting out of range.
    #[error("master setting {field} = {value}: {rule}")]
    Setting {
        /// The setting.
        field: &'static str,
        /// Its value as text.
        value: String,
        /// The rule it breaks.
        rule: &'static str,
    },
    /// A slave device setting out of range.
    #[error("slave {name}: {why}")]
    Slave {
        /// The slave's name.
        name: String,
        /// What is wrong.
        why: String,
    },
    /// More devices than the bus model holds.
    #[error("bus: {0} devices, at most 64 can be attached")]
    TooManyDevices(usize),
}

impl ProjectedConfig {
    /// A projected configuration from a list of slaves; checks every item.
    pub fn new<I: IntoIterator<Item = ProjectedSlave>>(
        slaves: I,
    ) -> Result<ProjectedConfig, ConfigError> {
        let mut c = ProjectedConfig::default();
        for s in slaves {
            c.insert(s)?;
        }
        Ok(c)
    }

    /// Adds one projected slave, checking it against those already there.
    pub fn insert(&mut self, s: ProjectedSlave) -> Result<(), ConfigError> {
        let a = s.addr;
        if a.number() == 0 {
            return Err(ConfigError::AddressZero(a));
        }
        if self.lps.contains(a) {
            return Err(ConfigError::Duplicate(a));
        }
        let other = match a.select {
            asi_phy::Select::A => SlaveAddr::b(a.number()),
            asi_phy::Select::B => SlaveAddr::a(a.number()),
        };
        if a.select == asi_phy::Select::B && !s.codes.is_ab() {
            return Err(ConfigError::AddressKind {
                addr: a,
                why: "only an A/B slave (ID code A) can have a B address",
            });
        }
        if let Some(o) = other {
            if self.lps.contains(o) && (!s.codes.is_ab() || !self.codes[o.index() as usize].is_ab())
            {
                return Err(ConfigError::AddressKind {
                    addr: a,
                    why: "a standard slave occupies both halves of its address",
                });
            }
        }
        self.lps.set(a, true);
        self.codes[a.index() as usize] = s.codes;
        self.params[a.index() as usize] = s.parameter;
        Ok(())
    }

    /// Removes `a` from the projection.
    pub fn remove(&mut self, a: SlaveAddr) {
        self.lps.set(a, false);
    }

    /// LPS.
    pub fn lps(&self) -> SlaveList {
        self.lps
    }

    /// The projected codes of `a` (PCD).
    pub fn codes(&self, a: SlaveAddr) -> SlaveCodes {
        self.codes[a.index() as usize]
    }

    /// The projected parameter of `a` (PP).
    pub fn parameter(&self, a: SlaveAddr) -> Nibble {
        self.params[a.index() as usize]
    }

    /// The projected slaves.
    pub fn iter(&self) -> impl Iterator<Item = ProjectedSlave> + '_ {
        self.lps.iter().map(|addr| ProjectedSlave {
            addr,
            codes: self.codes(addr),
            parameter: self.parameter(addr),
        })
    }
}

/// The master's settings. [`MasterConfig::check`] names the item at fault.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct MasterConfig {
    /// Bus timing (asi-phy).
    pub timing: BusTiming,
    /// Start in protected or configuration mode.
    pub mode: Mode,
    /// A slave that still fails after its repeat in this many consecutive cycles leaves LAS and
    /// LDS (docs/master.md decision: 3).
    pub max_failed_cycles: u8,
    /// The AS-i supply voltage below which APF is set and the master goes offline.
    /// **Decision**: 22.0 V (the AS-i supply delivers 29.5..31.6 V, §2.2.1 of the lift thesis).
    pub apf_threshold_volts: f64,
    /// Time from power return (or leaving offline) to the first detection call, while the
    /// slaves come out of reset. **Decision**: 5 ms.
    pub startup_delay: SimDuration,
    /// How long a slave's EEPROM write (after Address_Assignment or Write_Extended_ID1) keeps
    /// status bit S0 "volatile" set; the master waits this long before reading the slave again.
    /// Reference/asi.md §4: up to 15 ms.
    pub eeprom_write_time: SimDuration,
}

impl Default for MasterConfig {
    fn default() -> Self {
        MasterConfig {
            timing: BusTiming::default(),
            mode: Mode::Protected,
            max_failed_cycles: 3,
            apf_threshold_volts: 22.0,
            startup_delay: SimDuration::from_millis(5),
            eeprom_write_time: SimDuration::from_millis(15),
        }
    }
}

impl MasterConfig {
    /// Checks the settings, naming the first one at fault.
    pub fn check(&self) -> Result<(), ConfigError> {
        if self.max_failed_cycles == 0 {
            return Err(ConfigError::Setting {
                field: "max_failed_cycles",
                value: "0".into(),
                rule: "must be at least 1",
            });
        }
        if !(self.apf_threshold_volts.is_finite() && self.apf_threshold_volts > 0.0) {
            return Err(ConfigError::Setting {
                field: "apf_threshold_volts",
                value: format!("{}", self.apf_threshold_volts),
                rule: "must be a positive voltage",
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ps(addr: SlaveAddr, codes: SlaveCodes) -> ProjectedSlave {
        ProjectedSlave {
            addr,
            codes,
            parameter: Nibble::ALL,
        }
    }

    #[test]
    fn bad_projections_are_named() {
        let std = SlaveCodes::new(7, 0, 0xF, 0xF);
        let ab = SlaveCodes::new(7, 0xA, 7, 0xE);
        let a = |n| SlaveAddr::a(n).expect("a");
        let b = |n| SlaveAddr::b(n).expect("b");
        let e = ProjectedConfig::new([ps(a(0), std)]).expect_err("0");
        assert_eq!(
            e.to_string(),
            "projected slave 0A: address 0 cannot be projected"
        );
        let e = ProjectedConfig::new([ps(a(3), std), ps(a(3), std)]).expect_err("dup");
        assert_eq!(e, ConfigError::Duplicate(a(3)));
        let e = ProjectedConfig::new([ps(b(3), std)]).expect_err("B std");
        assert!(e.to_string().starts_with("projected slave 3B: only an A/B"));
        let e = ProjectedConfig::new([ps(a(3), std), ps(b(3), ab)]).expect_err("std + B");
        assert!(e.to_string().contains("occupies both halves"));
        let ok = ProjectedConfig::new([ps(a(3), ab), ps(b(3), ab)]).expect("A/B pair");
        assert_eq!(ok.lps().len(), 2);
        let bad = MasterConfig {
            max_failed_cycles: 0,
            ..MasterConfig::default()
        };
        assert_eq!(
            bad.check().expect_err("0 cycles").to_string(),
            "master setting max_failed_cycles = 0: must be at least 1"
        );
    }

    #[test]
    fn profiles_decode_as_reference_6_1_says() {
        let ac2618 = SlaveCodes::new(7, 3, 0xF, 5);
        assert!(ac2618.is_analog_7_3());
        assert!(!ac2618.analog_is_input());
        assert_eq!(ac2618.analog_channels(), 2);
        assert_eq!(ac2618.to_string(), "S-7.3.5 (ID1 F)");
        let ab_a = SlaveCodes::new(7, 0xA, 0x7, 0xE);
        let ab_b = SlaveCodes::new(7, 0xA, 0xF, 0xE);
        assert!(ab_a.matches(&ab_b), "the A/B select bit is not compared");
        assert!(!SlaveCodes::new(7, 0, 7, 0xF).matches(&SlaveCodes::new(7, 0, 0xF, 0xF)));
    }
}
