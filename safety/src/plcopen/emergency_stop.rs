//! SF_EmergencyStop, PLCopen v2.x (the SF_EmergencyStop help, tables 22–25; docs/safety-logic.md
//! §2, §5.3).

use super::diag::DiagCode;
use crate::primitives::RTrig;

/// Inputs of [`SfEmergencyStop`] (table 22 of the SF_EmergencyStop help). All default to FALSE, the
/// initial values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SfEmergencyStopInputs {
    /// FALSE sets all outputs to their initial values (Idle, highest priority).
    pub activate: bool,
    /// FALSE: safety demand (button pressed); TRUE: no demand.
    pub s_estop_in: bool,
    /// TRUE: acknowledge automatically the first time the safety controller starts.
    pub s_start_reset: bool,
    /// TRUE: acknowledge automatically after a demand has cleared.
    pub s_auto_reset: bool,
    /// Acknowledge on its rising edge; a static TRUE is detected as an error.
    pub reset: bool,
}

/// Outputs of [`SfEmergencyStop`] (table 23 of the SF_EmergencyStop help), all assigned on every
/// call.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SfEmergencyStopOutputs {
    /// The block is active and its outputs are valid.
    pub ready: bool,
    /// TRUE: enable; FALSE: demand, reset needed or error.
    pub s_estop_out: bool,
    /// The safety function is demanded (v2.x).
    pub safety_demand: bool,
    /// The operator should press Reset (v2.x).
    pub reset_request: bool,
    /// A static Reset was detected.
    pub error: bool,
    /// The state, tables 24/25 of the SF_EmergencyStop help.
    pub diag_code: DiagCode,
}

/// The states of SF_EmergencyStop, named as in the FBS_ESTOP enumeration (the SF_EmergencyStop help
/// tables 24/25; their DiagCode is [`EStopState::code`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum EStopState {
    /// `0000` Idle: not active.
    #[default]
    Idle,
    /// `8001` Init: activated, checks S_StartReset.
    Init,
    /// `8802` Wait for S_EStopIn 1: checks Reset = FALSE, waits for S_EStopIn = TRUE.
    WaitForIn1,
    /// `8402` Wait for Reset 1: waits for a rising edge of Reset.
    WaitForReset1,
    /// `8804` Wait for S_EStopIn 2: a demand was detected; checks Reset = FALSE.
    WaitForIn2,
    /// `8404` Wait for Reset 2: checks S_AutoReset or waits for a rising edge of Reset.
    WaitForReset2,
    /// `8000` Safety output enabled.
    OutEnabled,
    /// `C001` Reset error 1: Reset TRUE while waiting for S_EStopIn (start path).
    ResetError1,
    /// `C011` Reset error 2: Reset TRUE while waiting for S_EStopIn (after a demand).
    ResetError2,
}

impl EStopState {
    /// The DiagCode of the state.
    pub const fn code(self) -> DiagCode {
        DiagCode(match self {
            EStopState::Idle => 0x0000,
            EStopState::Init => 0x8001,
            EStopState::WaitForIn1 => 0x8802,
            EStopState::WaitForReset1 => 0x8402,
            EStopState::WaitForIn2 => 0x8804,
            EStopState::WaitForReset2 => 0x8404,
            EStopState::OutEnabled => 0x8000,
            EStopState::ResetError1 => 0xC001,
            EStopState::ResetError2 => 0xC011,
        })
    }
}

/// PLCopen SF_EmergencyStop: monitors an emergency-stop button (the SF_EmergencyStop help).
///
/// Transitions (docs/safety-logic.md §5.3, v2.01 codes; one per call, first match wins):
///
/// | from | condition | to |
/// |---|---|---|
/// | any | ¬Activate | 0000 |
/// | 0000 | Activate | 8001 |
/// | 8001 | ¬S_StartReset / S_StartReset ∧ ¬In / S_StartReset ∧ In | 8802 / 8804 / 8000 |
/// | 8802 | Reset / In | C001 / 8402 |
/// | 8402 | ¬In / R_TRIG(Reset) | 8802 / 8000 |
/// | 8804 | Reset / In ∧ ¬AutoReset / In ∧ AutoReset | C011 / 8404 / 8000 |
/// | 8404 | ¬In / R_TRIG(Reset) ∨ AutoReset | 8804 / 8000 |
/// | 8000 | ¬In | 8804 |
/// | C001, C011 | ¬Reset | 8802, 8804 |
///
/// **Decision** (docs/safety-logic.md §2 AMBIG, §10 point 1): C001 and C011 share one text in the
/// SF_EmergencyStop help; C001 is the static Reset on the start path (from 8802), C011 after a
/// demand (from 8804). The static Reset is flagged in the *wait-for-input* states, as the v2 texts
/// say ("checks Reset = FALSE and waits for S_EStopIn = TRUE"), so a held button can never
/// acknowledge the moment the demand clears.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SfEmergencyStop {
    state: EStopState,
    reset_trig: RTrig,
}

impl SfEmergencyStop {
    /// A block in Idle.
    pub fn new() -> Self {
        Self::default()
    }

    /// The current state.
    pub fn state(&self) -> EStopState {
        self.state
    }

    /// One call of the block: at most one transition, then every output.
    pub fn call(&mut self, i: SfEmergencyStopInputs) -> SfEmergencyStopOutputs {
        use EStopState::*;
        let reset_edge = self.reset_trig.call(i.reset);
        self.state = if !i.activate {
            Idle
        } else {
            match self.state {
                Idle => Init,
                Init if !i.s_start_reset => WaitForIn1,
                Init if !i.s_estop_in => WaitForIn2,
                Init => OutEnabled,
                WaitForIn1 if i.reset => ResetError1,
                WaitForIn1 if i.s_estop_in => WaitForReset1,
                WaitForReset1 if !i.s_estop_in => WaitForIn1,
                WaitForReset1 if reset_edge => OutEnabled,
                WaitForIn2 if i.reset => ResetError2,
                WaitForIn2 if i.s_estop_in && !i.s_auto_reset => WaitForReset2,
                WaitForIn2 if i.s_estop_in => OutEnabled,
                WaitForReset2 if !i.s_estop_in => WaitForIn2,
                WaitForReset2 if reset_edge || i.s_auto_reset => OutEnabled,
                OutEnabled if !i.s_estop_in => WaitForIn2,
                ResetError1 if !i.reset => WaitForIn1,
                ResetError2 if !i.reset => WaitForIn2,
                unchanged => unchanged,
            }
        };
        let s = self.state;
        SfEmergencyStopOutputs {
            ready: s != Idle,
            s_estop_out: s == OutEnabled,
            safety_demand: matches!(s, WaitForIn1 | WaitForIn2),
            reset_request: matches!(s, WaitForReset1 | WaitForReset2),
            error: matches!(s, ResetError1 | ResetError2),
            diag_code: s.code(),
        }
    }
}
