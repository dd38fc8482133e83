//! Plain digital modules: a generic 4DI/4DO module, the converter I/O and the load sensor.

use super::any_impls;
use crate::slave::Peripheral;
use asi_phy::{Nibble, SimTime};

/// A plain 4-input/4-output module (IFM AC2726, AC2258 or any S-7.x.x I/O slave): the inputs
/// are sampled when the slave receives a Data_Exchange, then the outputs are driven.
#[derive(Clone, Debug, Default)]
pub struct IoModule {
    inputs: Nibble,
    outputs: Nibble,
    fault: bool,
}

impl IoModule {
    /// A module with all pins low.
    pub fn new() -> IoModule {
        IoModule::default()
    }
    /// The input pins D3..D0.
    pub fn set_inputs(&mut self, v: Nibble) {
        self.inputs = v;
    }
    /// The input pins.
    pub fn inputs(&self) -> Nibble {
        self.inputs
    }
    /// The output pins as last driven (0000 after reset).
    pub fn outputs(&self) -> Nibble {
        self.outputs
    }
    /// Peripheral fault (status S1), a fault hook.
    pub fn set_periphery_fault(&mut self, on: bool) {
        self.fault = on;
    }
}

impl Peripheral for IoModule {
    fn exchange(&mut self, _now: SimTime, outputs: Nibble) -> Nibble {
        self.outputs = outputs;
        self.inputs
    }
    fn reset(&mut self) {
        self.outputs = Nibble::ZERO;
    }
    fn periphery_fault(&self) -> bool {
        self.fault
    }
    any_impls!();
}

/// The converter's I/O module at address 7 (AC2258, four relay outputs; docs/lab-bus.md §3.6):
/// out D0 = run, D1 = direction (1 up, 0 down); in D0 = converter ready, D1 = converter fault.
///
/// asi-lift carries the lab's output bits in positive logic (1 = relay closed, docs/lab-bus.md
/// §3.1), but the master's default outputs 1111 (activation, Data_Exchange_Active = 0, Offline)
/// are the wire value of the real bus, which a slave IC takes as its passive state: the ZMD
/// "ASI for you" (ASI4U) datasheet, §3.7.1, has its data outputs as open-drain drivers whose
/// register an IC reset sets to 0xF with the drivers off, so 1111 leaves the outputs as they
/// are at power-on (docs/lab-bus.md §3.6). The module therefore opens every relay on 1111. For
/// the lab this is exact: D2 and D3 drive nothing, so the PLC never commands 1111 here.
#[derive(Clone, Debug, Default)]
pub struct Converter {
    io: IoModule,
}

impl Converter {
    /// The master's default outputs: the slave IC's passive state.
    pub const PASSIVE: Nibble = Nibble::ALL;

    /// Outputs off, converter not ready.
    pub fn new() -> Converter {
        Converter::default()
    }
    /// The relay outputs D3..D0 as the module drives them: the bits last received, or 0000
    /// (all open) after reset and while the master sends its default outputs.
    pub fn outputs(&self) -> Nibble {
        Converter::relays(self.io.outputs)
    }
    /// The relays D3..D0 a received output nibble closes: the nibble, or none for the
    /// master's default outputs [`Converter::PASSIVE`].
    pub fn relays(received: Nibble) -> Nibble {
        if received == Converter::PASSIVE {
            Nibble::ZERO
        } else {
            received
        }
    }
    /// The output bits as last received (0000 after reset).
    pub fn received(&self) -> Nibble {
        self.io.outputs
    }
    /// Output D0: run the converter.
    pub fn run(&self) -> bool {
        self.outputs().bit(0)
    }
    /// Output D1: direction, `true` = up.
    pub fn direction_up(&self) -> bool {
        self.outputs().bit(1)
    }
    /// Input D0: the converter is ready.
    pub fn set_ready(&mut self, on: bool) {
        self.io.inputs = self.io.inputs.with_bit(0, on);
    }
    /// Input D1: the converter reports a fault.
    pub fn set_fault(&mut self, on: bool) {
        self.io.inputs = self.io.inputs.with_bit(1, on);
    }
}

impl Peripheral for Converter {
    fn exchange(&mut self, now: SimTime, outputs: Nibble) -> Nibble {
        self.io.exchange(now, outputs)
    }
    fn reset(&mut self) {
        self.io.reset();
    }
    any_impls!();
}

/// The IFM IG5886 load sensor at address 8 (S-1.1; docs/lab-bus.md decision): inputs D1..D0 = load
/// level 0 empty, 1 loaded, 2 full, 3 overloaded; D2 = operation ready (S-1.1, always 1 while
/// powered); D3 is an output (IO code 1) and reads back as sent.
#[derive(Clone, Debug, Default)]
pub struct LoadSensor {
    level: u8,
}

impl LoadSensor {
    /// An empty cabin.
    pub fn new() -> LoadSensor {
        LoadSensor::default()
    }
    /// The load level 0..=3 (higher values are taken as 3, overloaded).
    pub fn set_level(&mut self, level: u8) {
        self.level = level.min(3);
    }
    /// The load level.
    pub fn level(&self) -> u8 {
        self.level
    }
}

impl Peripheral for LoadSensor {
    fn exchange(&mut self, _now: SimTime, outputs: Nibble) -> Nibble {
        Nibble::from_low_bits(self.level | 0b0100 | (outputs.get() & 0b1000))
    }
    any_impls!();
}

#[cfg(test)]
mod tests {
    use super::*;

    fn n(bits: u8) -> Nibble {
        Nibble::from_low_bits(bits)
    }

    /// The activation's Data_Exchange carries the default outputs 1111, the value an IC
    /// reset leaves in the ASI4U's data output register with its drivers off (ASI4U
    /// datasheet §3.7.1): the converter sees neither run nor up, before or after it.
    #[test]
    fn the_default_outputs_1111_leave_the_converter_relays_open() {
        let mut c = Converter::new();
        c.reset();
        let t = SimTime::ZERO;
        c.exchange(t, n(0b1111));
        assert_eq!(c.received(), n(0b1111));
        assert_eq!(c.outputs(), Nibble::ZERO);
        assert!(!c.run() && !c.direction_up());
        // The PLC's first command: run up.
        c.exchange(t, n(0b0011));
        assert!(c.run() && c.direction_up());
        // Data_Exchange_Active = 0 or Offline: the default outputs again, every relay opens.
        c.exchange(t, n(0b1111));
        assert!(!c.run() && !c.direction_up());
        c.exchange(t, n(0b0001));
        assert!(c.run() && !c.direction_up());
        c.reset();
        assert_eq!(c.received(), Nibble::ZERO);
        assert!(!c.run());
    }
}
