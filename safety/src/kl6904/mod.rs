//! The Beckhoff TwinSAFE KL6904 logic terminal (seed 004; reference/safety.md §1, §6, §8.3).
//!
//! - [`signal`]: contact types, signal kinds and references;
//! - [`modules`]: the function modules AND, OR, OPMODE, ESTOP, MON, DECOUPLE.

pub mod modules;
pub mod signal;
