//! asi-slaves: the AS-Interface slaves of asi-lift (docs/master.md, §3; §2.3, §3, §4 of the lift
//! thesis): the slave IC, the lab lift's slave devices, the device side of the nibble handshakes
//! and of S-7.3, and the passive Safety at Work monitor.
//!
//! Sans-IO and deterministic: every type is a state machine driven by the telegrams and the
//! simulated time it is handed; nothing reads a clock. A slave knows nothing of the master: this
//! crate sits on asi-phy only, and the bus (the `asi-bus` crate) hands each slave the requests
//! its receiver accepted.
//!
//! Modules, one per concept: [`slave`] (slave IC), [`devices`] (the lab lift's slaves),
//! [`device_handshake`] (the device side of tables 4.2–4.7), [`analog_firmware`] (the slave's
//! side of S-7.3), [`monitor`] (Safety at Work code tables and monitor).

pub mod analog_firmware;
pub mod device_handshake;
pub mod devices;
pub mod monitor;
pub mod slave;

pub use monitor::{CodeTable, Heard, SafetyMonitor};
pub use slave::{Peripheral, Slave};
