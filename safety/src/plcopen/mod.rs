//! PLCopen Safety function blocks (PLCopen TC5 Part 1, v2.x DiagCodes).
//!
//! - [`SfEmergencyStop`]: exactly as the SF_EmergencyStop help (CODESYS help, tables 22–25)
//!   specifies, with the transitions of docs/safety-logic.md §5.3;
//! - [`SfEquivalent`]: the two-channel check the cabin STOP pair needs (docs/safety-logic.md §5.2,
//!   v2.01 codes of the FBS_EQUI enumeration);
//! - [`SfEdm`]: external device monitoring for the contactor (docs/safety-logic.md §5.2, FBS_EDM).
//!
//! Structure common to all three, as in the reference transcriptions (docs/safety-logic.md §5.2):
//! edge detectors first, then at most one state transition per call evaluated from the
//! previous state (Activate = FALSE → Idle with the highest priority, in the same call), then
//! every output assigned from the new state. Timers are read in the transition section and
//! updated in the output section, so an expired timer is acted on in the call *after* it
//! expires (docs/safety-logic.md §8.1, §10 point 4).

mod diag;
mod edm;
mod emergency_stop;
mod equivalent;

pub use diag::DiagCode;
pub use edm::{SfEdm, SfEdmInputs, SfEdmOutputs};
pub use emergency_stop::{SfEmergencyStop, SfEmergencyStopInputs, SfEmergencyStopOutputs};
pub use equivalent::{SfEquivalent, SfEquivalentInputs, SfEquivalentOutputs};
