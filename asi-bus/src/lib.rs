//! asi-bus: the AS-Interface segment of asi-lift, master and slaves on one pulse-level line
//! (docs/architecture.md–3; §3 of the lift thesis).
//!
//! Sans-IO and deterministic: the [`Bus`] ties asi-master's [`Master`](asi_master::Master),
//! asi-phy's [`Medium`](asi_phy::line::Medium) and asi-slaves' [`Slave`](asi_slaves::Slave)s and
//! Safety at Work monitors together, driven by simulated time passed in; nothing reads a clock.
//! Every transaction travels as APM pulses through asi-phy's line decoder and the seven
//! receiver checks.
//!
//! ```
//! use asi_bus::lab::LabLift;
//! use asi_phy::SimTime;
//!
//! let mut lab = LabLift::new().expect("lab bus");
//! lab.bus_mut().advance_to(SimTime::from_millis(60));
//! assert!(lab.bus().is_running());
//! assert!(lab.bus().master().flags().config_ok());
//! ```
//!
//! Modules: [`bus`] (the segment), [`lab`] (the lab lift bus).

pub mod bus;
pub mod lab;

pub use bus::{Bus, Look, LookWatch, MonitorId, SlaveId, Stop, Watch};
