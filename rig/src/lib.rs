//! rig: the asi-lift lab rig as a library. It wires the simulated AS-i bus, the lab lift, its
//! PLC program and its safety logic together on one simulated clock ([`rig`]), driven by a
//! scenario ([`scenario`]), judged by the invariant watch and summed up in a [`report`]; around
//! it the waveform outputs of a run ([`waves`]), the timing analysis ([`timing`]) and the fault
//! campaigns ([`campaign`]); beside it the teaching stand of the SafeMOTION thesis ([`stand`]). The
//! `asi-lift` command, the tests and other front-ends use it.

pub mod campaign;
pub mod referee;
pub mod report;
pub mod rig;
pub mod scenario;
pub mod stand;
pub mod timing;
pub mod waves;

pub use crate::rig::{Rig, RigError};
pub use report::{Actor, Report};
pub use scenario::Scenario;
