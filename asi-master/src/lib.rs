//! asi-master: the AS-Interface master of asi-lift, its process image, and the lab lift's
//! slaves on a pulse-level simulated bus (SPEC §2, §3, §7; seed 003 §2.2.3, §2.3, §3, §4).
//!
//! Sans-IO and deterministic, in the manner of smoltcp and quinn-proto: the [`Master`], the
//! [`Slave`]s, the [`Medium`](medium::Medium) and the [`Bus`] that ties them together are state
//! machines driven by simulated time passed in; nothing reads a clock, spawns a thread or uses
//! an unseeded random number. Every transaction travels as APM pulses through asi-phy's line
//! decoder and the seven receiver checks.
//!
//! ```
//! use asi_master::lab::LabLift;
//! use asi_phy::SimTime;
//!
//! let mut lab = LabLift::new().expect("lab bus");
//! lab.bus.advance_to(SimTime::from_millis(60));
//! assert!(lab.bus.is_running());
//! assert!(lab.bus.master().flags().config_ok());
//! ```
//!
//! Modules, one per concept: [`image`] (seed 003 table 4.1 word layout), [`lists`] (LDS, LAS,
//! LPS, LCS, LPF, flags), [`master`] (phases and cycle), [`mailbox`] (host jobs), [`trace`]
//! (transaction records and statistics), [`slave`] (slave IC), [`devices`] (the lab lift's
//! slaves), [`handshake`] (tables 4.2–4.7 engines), [`analog`] (S-7.3), [`safety`] (Safety at
//! Work monitor), [`medium`] (the line), [`bus`] (the segment), [`lab`] (the lab lift bus).

pub mod analog;
pub mod bus;
pub mod config;
pub mod devices;
pub mod handshake;
pub mod image;
pub mod lab;
pub mod lists;
pub mod mailbox;
pub mod master;
pub mod medium;
pub mod safety;
pub mod slave;
pub mod trace;

pub use bus::{Bus, MonitorId, SlaveId};
pub use config::{ConfigError, MasterConfig, Mode, ProjectedConfig, ProjectedSlave, SlaveCodes};
pub use image::{Image, ProcessImage};
pub use lists::{EcFlags, HostFlags, SlaveAddr, SlaveList};
pub use master::{Master, Outcome, Phase};
pub use slave::{Peripheral, Slave};
pub use trace::{BusStats, TraceRing, TransactionRecord, TxKind};
