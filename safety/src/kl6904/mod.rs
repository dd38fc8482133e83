//! The Beckhoff TwinSAFE KL6904 logic terminal (the KL6904 manual; docs/safety-logic.md §1, §6,
//! §8.3).
//!
//! - [`signal`]: contact types, signal kinds and references;
//! - [`modules`]: the function modules AND, OR, OPMODE, ESTOP, MON, DECOUPLE;
//! - [`group`]: TwinSAFE groups with RUN, ERR_ACK, FB_ERR, COM_ERR, OUT_ERR;
//! - [`connection`]: TwinSAFE connections, the safe telegram and the black channel;
//! - [`project`]: a project as data (TOML file or builder);
//! - [`verify`]: the verifier's rules;
//! - [`logic`]: the runtime that scans a verified project.

pub mod connection;
pub mod group;
pub mod logic;
pub mod modules;
pub mod project;
pub mod signal;
pub mod verify;

pub use logic::TwinSafeLogic;
pub use project::Project;
