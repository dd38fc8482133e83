//! The lab lift's slave devices (docs/lab-bus.md table; table 3.1 of the lift thesis) and generic
//! ones, each a [`Peripheral`](crate::slave::Peripheral) with its peripheral side as plain signals
//! the rig connects to the lift plant.
//!
//! | address | device | profile | module |
//! |---|---|---|---|
//! | 1..4 | IFM AC2726 at floors 1..4 | S-7.0.F | [`FloorStation`] (table 4.3 handshake) |
//! | 5 | AC2726 in the cabin | S-7.0.F | [`CabinDisplay`] (table 4.5 handshake) |
//! | 6 | AC2726 in the cabin | S-7.0.F | [`CabinPanel`] (tables 4.6/4.7 handshake) |
//! | 7 | IFM AC2258 I/O module | S-7.0.E | [`Converter`] |
//! | 8 | IFM IG5886 load sensor | S-1.1 | [`LoadSensor`] |
//! | 10 | IFM AC2618 current-loop output | S-7.3.5 | [`AnalogOutput`] |
//! | 11, 12 | IFM GG505S safety sensors | S-0.B.F | [`SafetySensor`] |

mod analog_io;
mod io;
mod lift;
mod safety_sensor;

pub use analog_io::{AnalogInput, AnalogOutput};
pub use io::{Converter, IoModule, LoadSensor};
pub use lift::{CabinDisplay, CabinPanel, FloorStation, HandshakeEngine, HandshakeModule};
pub use safety_sensor::{SafetySensor, CODE_HOLD};

use asi_phy::SlaveCodes;

/// IFM AC2726, 4DI/4DO module: S-7.0.F (table 3.1 of the lift thesis).
pub const AC2726: SlaveCodes = SlaveCodes::new(0x7, 0x0, 0xF, 0xF);
/// IFM AC2258, I/O module: S-7.0.E (table 3.1 of the lift thesis).
pub const AC2258: SlaveCodes = SlaveCodes::new(0x7, 0x0, 0xF, 0xE);
/// IFM IG5886, load sensor: S-1.1 (table 3.1 of the lift thesis; a 2.0 profile, ID2 read as F).
pub const IG5886: SlaveCodes = SlaveCodes::new(0x1, 0x1, 0xF, 0xF);
/// IFM AC2618, two-channel current-loop output: S-7.3.5 (table 3.1 of the lift thesis).
pub const AC2618: SlaveCodes = SlaveCodes::new(0x7, 0x3, 0xF, 0x5);
/// IFM GG505S, safety sensor: S-0.B.F (§6.3 of the lift thesis; docs/lab-bus.md).
pub const GG505S: SlaveCodes = SlaveCodes::new(0x0, 0xB, 0xF, 0xF);
/// A generic two-channel S-7.3 analog input: S-7.3.D (ID2 = 1101: input, analog, 2 channels).
pub const ANALOG_INPUT_2CH: SlaveCodes = SlaveCodes::new(0x7, 0x3, 0xF, 0xD);
/// A generic A/B 4I/3O module: S-7.A.7 (ID1 7 = A; set ID1 bit 3 for B).
pub const AB_MODULE: SlaveCodes = SlaveCodes::new(0x7, 0xA, 0x7, 0x7);

/// Implements the `as_any` boilerplate of [`Peripheral`](crate::slave::Peripheral).
macro_rules! any_impls {
    () => {
        fn as_any(&self) -> &dyn core::any::Any {
            self
        }
        fn as_any_mut(&mut self) -> &mut dyn core::any::Any {
            self
        }
    };
}
pub(crate) use any_impls;
