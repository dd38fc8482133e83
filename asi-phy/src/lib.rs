//! asi-phy: the AS-Interface physical and link layer of asi-lift (SPEC §1, seed 003 §2.2).
//!
//! Everything above this crate (master, slaves, traces, timing analysis) stands on it.

#![cfg_attr(not(test), warn(clippy::unwrap_used))]

pub mod time;

pub use time::{SimDuration, SimTime};
