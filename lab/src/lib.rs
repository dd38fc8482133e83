//! lab: the facts of the lab lift that more than one part of asi-lift relies on, with one
//! home each (docs/lab-bus.md):
//!
//! - [`address`]: which slave sits at which AS-i address (§2.2.3 of the lift thesis): the bus
//!   builder puts the devices there, the PLC program addresses them, the rig wires them to the
//!   plant, the campaign takes them offline;
//! - [`display`]: the display word of the floor and cabin displays (tables 4.2 and 4.4 of the lift
//!   thesis): the PLC program writes it, the handshakes carry it, the plant's displays show it;
//! - [`setpoint`]: the speed set-point that means standstill (§6.4 of the lift thesis).
//!
//! The crate depends on nothing of asi-lift, so that the bus, the plant and the controller can
//! all use it.

pub mod address;
pub mod display;
pub mod setpoint;

pub use display::{DisplayWord, DisplayWordError};
