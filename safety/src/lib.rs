//! safety: the TwinSAFE logic and PLCopen safety blocks that guard the asi-lift lift (docs/safety.md).
//!
//! - [`primitives`]: IEC `R_TRIG`, `F_TRIG`, `TON` and the TwinSAFE 0→1→0 pulse detector;
//! - [`kl6904`]: the Beckhoff KL6904 logic terminal (the KL6904 manual);
//! - [`plcopen`]: SF_EmergencyStop (the SF_EmergencyStop help), SF_Equivalent and SF_EDM;
//! - [`drive`]: a drive's integrated safety functions STO, SBC, SS1, SS2, SOS, SLS, SLP, SDI,
//!   SLI, SLA (the SafeMOTION thesis and the drive manual, docs/drive-safety.md);
//! - [`lift`]: the lift's safety project (docs/safety.md), the API the rig wires;
//! - [`lift_drive`]: the lift's safe drive, a [`drive`] monitor on the lift's motor with the
//!   safety logic's requests (docs/drive-safety.md §6), the option `[drive] safe = true`.
//!
//! All time is [`asi_phy::SimTime`], passed in by the caller; nothing reads the wall clock and
//! nothing is random, so a run is reproducible scan by scan.

pub mod drive;
pub mod kl6904;
pub mod lift;
pub mod lift_drive;
pub mod plcopen;
pub mod primitives;

pub use lift::{
    LiftSafety, LiftSafetyCause, LiftSafetyConfig, LiftSafetyEvent, LiftSafetyInputs,
    LiftSafetyOutputs, SafeLink, SAFETY_SCAN_PERIOD,
};
