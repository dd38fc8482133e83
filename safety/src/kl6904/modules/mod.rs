//! The function modules of the KL6904 (§4 of the KL6904 manual): AND, OR, OPMODE, ESTOP, MON,
//! DECOUPLE.
//!
//! Each stateful module is a plain state machine called once per safety scan with the time,
//! whether its group runs, and its input values; it returns every output on every call
//! (docs/safety-logic.md §5.1 "every output must be assigned in every cycle"). The states follow
//! the newer Beckhoff FB state names (docs/safety-logic.md §6.1): STOP, SAFE, RUN, DELAYOUT,
//! ERROR; the group's RESET state lives in [`crate::kl6904::group`].

/// The diagnostic accessors every stateful module (ESTOP, MON, OPMODE) has, over its [`Core`].
macro_rules! core_accessors {
    ($module:ty) => {
        impl $module {
            /// The state after the last scan.
            pub fn state(&self) -> FbState {
                self.core.state
            }

            /// Diagnostic bits (§3.3 of the KL6904 manual): ESTOP 0–3 discrepancy of pair 1–4; MON
            /// 0–1 MonIn pairs, 2 Secure pair; ESTOP and MON 4 EDM1, 5 EDM2; OPMODE 0 discrepancy.
            pub fn diag(&self) -> u8 {
                self.core.diag
            }

            /// What the module did in the last scan.
            pub fn events(&self) -> &[FbEvent] {
                &self.core.events
            }

            /// `true` while the cause of the latched error was still present in the last scan
            /// (the group then refuses ERR_ACK).
            pub fn error_cause_active(&self) -> bool {
                self.core.error_cause_active()
            }

            /// The group's ERR_ACK: ERROR → SAFE (the module's restart rule then applies).
            pub fn acknowledge(&mut self) {
                self.core.acknowledge();
            }

            /// The shared state machine, for the logic.
            pub(crate) fn core(&self) -> &Core {
                &self.core
            }

            /// The shared state machine, for the logic's acknowledgement.
            pub(crate) fn core_mut(&mut self) -> &mut Core {
                &mut self.core
            }
        }
    };
}

mod base;
mod estop;
mod gates;
mod mon;
mod opmode;

pub(crate) use base::Core;
pub use base::{FbError, FbEvent, FbState};
pub use estop::{Estop, EstopConfig, EstopInputs, EstopOutputs};
pub use gates::{and, decouple, or};
pub(crate) use gates::{and_bits, or_bits};
pub use mon::{Mon, MonConfig, MonInputs, MonOutputs};
pub use opmode::{OpMode, OpModeConfig, OpModeInputs, OpModeOutputs};
