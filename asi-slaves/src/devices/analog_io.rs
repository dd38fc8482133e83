//! S-7.3 analog devices: the IFM AC2618 current-loop output and a generic analog input (§2.3,
//! table 2.2 of the lift thesis). Both run the slave side of [`crate::analog_firmware`] in firmware
//! and answer within the Data_Exchange that brings the master's step.

use super::any_impls;
use crate::analog_firmware::{S73InputSlave, S73OutputSlave};
use crate::slave::Peripheral;
use asi_phy::handshake_words::AnalogValue;
use asi_phy::{Nibble, SimTime};

/// The highest set-point the AC2618 drives, in µA (0..20 mA, §3.1 of the lift thesis).
pub const AC2618_MAX_UA: u16 = 20_000;

/// The IFM AC2618 two-channel current-loop output at address 10 (S-7.3.5). Channel 1 carries
/// the lift's speed set-point Rychlost in µA (4000 = 4 mA = standstill, docs/lift-plant.md).
///
/// **Decisions**: the value is the current in µA; values above 20000 are driven as 20000 µA
/// and values with bit 15 set (negative) as 0; until the first valid value after power-up the
/// output is 0 µA.
#[derive(Clone, Debug)]
pub struct AnalogOutput {
    engine: S73OutputSlave,
}

impl Default for AnalogOutput {
    fn default() -> Self {
        Self::new()
    }
}

impl AnalogOutput {
    /// Two channels, both 0 µA.
    pub fn new() -> AnalogOutput {
        AnalogOutput {
            engine: S73OutputSlave::new(2),
        }
    }
    /// The current of `channel` (1..=2) in µA.
    pub fn current_ua(&self, channel: u8) -> u16 {
        match self.engine.value(channel) {
            Some(v) if v & 0x8000 != 0 => 0,
            Some(v) => v.min(AC2618_MAX_UA),
            None => 0,
        }
    }
    /// Values received so far.
    pub fn values_received(&self) -> u32 {
        self.engine.received()
    }
}

impl Peripheral for AnalogOutput {
    fn exchange(&mut self, _now: SimTime, outputs: Nibble) -> Nibble {
        self.engine.step(outputs)
    }
    fn reset(&mut self) {
        self.engine.reset();
    }
    any_impls!();
}

/// A generic S-7.3 analog input slave (S-7.3.D: two input channels).
#[derive(Clone, Debug)]
pub struct AnalogInput {
    engine: S73InputSlave,
}

impl AnalogInput {
    /// An input with `channels` (1..=4) channels, values invalid until set.
    pub fn new(channels: u8) -> AnalogInput {
        AnalogInput {
            engine: S73InputSlave::new(channels),
        }
    }
    /// The measured value of `channel` (1..=4).
    pub fn set_value(&mut self, channel: u8, value: AnalogValue) {
        self.engine.set_value(channel, value);
    }
}

impl Peripheral for AnalogInput {
    fn exchange(&mut self, _now: SimTime, outputs: Nibble) -> Nibble {
        self.engine.step(outputs)
    }
    fn reset(&mut self) {
        self.engine.reset();
    }
    any_impls!();
}
