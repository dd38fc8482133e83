//! asi-master: the AS-Interface master of asi-lift, its process image and host interface
//! (docs/master.md, §3, §7; §2.2.3, §2.3, §3, §4 of the lift thesis).
//!
//! Sans-IO and deterministic, in the manner of smoltcp and quinn-proto: the [`Master`] is a
//! state machine driven by simulated time passed in; nothing reads a clock, spawns a thread or
//! uses an unseeded random number. It knows the slaves only through the telegrams: the bus that
//! carries them (the `asi-bus` crate) puts its requests on asi-phy's line and hands it the
//! responses.
//!
//! Modules, one per concept: [`image`] (the word layout of table 4.1 of the lift thesis), [`lists`]
//! (LDS, LAS, LPS, LCS, LPF, flags), [`config`] (projected configuration, settings), [`master`]
//! (phases and cycle), [`mailbox`] (host jobs), [`record`] (transaction records and statistics),
//! [`slave_stats`] (the statistics per slave an analyser shows),
//! [`leds`] (the indicators of seed 003 table 3.2), [`integrated_analog`] (the master's side of S-7.3), [`plc_handshake`] (the PLC side of
//! tables 4.2–4.7).

pub mod config;
pub mod image;
pub mod integrated_analog;
pub mod leds;
pub mod lists;
pub mod mailbox;
pub mod master;
pub mod plc_handshake;
pub mod record;
pub mod slave_stats;

pub use config::{ConfigError, MasterConfig, Mode, ProjectedConfig, ProjectedSlave};
pub use image::{Image, ProcessImage};
pub use leds::{Led, LedWatch, MasterLeds, PlcLink};
pub use lists::{EcFlags, HostFlags, SlaveList};
pub use master::{Master, Outcome, Phase};
pub use record::{BusStats, TraceRing, TransactionRecord, TxKind};
pub use slave_stats::{Light, LightRule, SlaveStats, SlaveTable};
