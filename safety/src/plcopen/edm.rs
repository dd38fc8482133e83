//! SF_EDM, PLCopen v2.01 (docs/safety-logic.md §5.2; FBS_EDM).

use asi_phy::{SimDuration, SimTime};

use super::diag::DiagCode;
use crate::primitives::{RTrig, Ton};

/// Inputs of [`SfEdm`]. All default to FALSE / zero.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SfEdmInputs {
    /// FALSE sets all outputs to their initial values.
    pub activate: bool,
    /// Control signal from the preceding safety block: TRUE enables the actuator.
    pub s_out_control: bool,
    /// Feedback of actuator 1: **TRUE = initial (released) state**, FALSE = switched.
    pub s_edm1: bool,
    /// Feedback of actuator 2; bridge it to `s_edm1` for a single feedback.
    pub s_edm2: bool,
    /// The actuator's longest response time.
    pub monitoring_time: SimDuration,
    /// TRUE: no reset needed after activation.
    pub s_start_reset: bool,
    /// Acknowledge on the rising edge.
    pub reset: bool,
}

/// Outputs of [`SfEdm`], all assigned on every call.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SfEdmOutputs {
    /// The block is active.
    pub ready: bool,
    /// Drives the actuator.
    pub s_edm_out: bool,
    /// An error is latched.
    pub error: bool,
    /// The state.
    pub diag_code: DiagCode,
}

/// The states of SF_EDM (FBS_EDM).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum EdmState {
    /// `0000` not active.
    #[default]
    Idle,
    /// `8401` start-up inhibit: reset required.
    Init,
    /// `8810` output disabled; the switch-off timer starts on entry.
    OutDisable,
    /// `8000` output enabled; the switch-on timer starts on entry.
    OutEnable,
    /// `C001` static Reset in 8401.
    ResetError,
    /// `C100` rising edges of S_OutControl and Reset in the same call (a programming error).
    InitError,
    /// `C010`/`C020`/`C030`: EDM1 / EDM2 / both FALSE when S_OutControl enables (in 8810).
    NotReleasedAtEnable(EdmChannels),
    /// `C040`/`C050`/`C060`: EDM1 / EDM2 / both still FALSE after MonitoringTime in 8810.
    NotReleasedInTime(EdmChannels),
    /// `C070`/`C080`/`C090`: EDM1 / EDM2 / both still TRUE after MonitoringTime in 8000.
    /// **INFER**: the source table is truncated here (docs/safety-logic.md §5.2, §10 point 7);
    /// the codes continue the pattern and are unverified.
    NotSwitchedInTime(EdmChannels),
}

/// Which feedback channels an SF_EDM error concerns.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EdmChannels {
    /// S_EDM1 only.
    Edm1,
    /// S_EDM2 only.
    Edm2,
    /// Both.
    Both,
}

impl EdmChannels {
    /// The channels for which `bad` holds, if any.
    fn of(bad1: bool, bad2: bool) -> Option<Self> {
        match (bad1, bad2) {
            (true, true) => Some(EdmChannels::Both),
            (true, false) => Some(EdmChannels::Edm1),
            (false, true) => Some(EdmChannels::Edm2),
            (false, false) => None,
        }
    }

    const fn offset(self) -> u16 {
        match self {
            EdmChannels::Edm1 => 0x00,
            EdmChannels::Edm2 => 0x10,
            EdmChannels::Both => 0x20,
        }
    }
}

impl EdmState {
    /// The DiagCode of the state.
    pub const fn code(self) -> DiagCode {
        DiagCode(match self {
            EdmState::Idle => 0x0000,
            EdmState::Init => 0x8401,
            EdmState::OutDisable => 0x8810,
            EdmState::OutEnable => 0x8000,
            EdmState::ResetError => 0xC001,
            EdmState::InitError => 0xC100,
            EdmState::NotReleasedAtEnable(c) => 0xC010 + c.offset(),
            EdmState::NotReleasedInTime(c) => 0xC040 + c.offset(),
            EdmState::NotSwitchedInTime(c) => 0xC070 + c.offset(),
        })
    }

    fn is_error(self) -> bool {
        self.code().is_error()
    }
}

/// PLCopen SF_EDM: drives an actuator (contactor) and monitors its feedback contacts.
///
/// It checks the released state before enabling and that the feedback switches within
/// MonitoringTime after every enable and disable (docs/safety-logic.md §5.2). Transitions
/// (**Decision** where the published table is silent; one per call, first match wins):
///
/// | from | condition | to |
/// |---|---|---|
/// | 0000 | Activate ∧ S_StartReset / Activate | 8810 / 8401 |
/// | 8401 | R_TRIG(Reset) ∧ R_TRIG(S_OutControl) / R_TRIG(Reset) / Reset (static) | C100 / 8810 / C001 |
/// | 8810 | S_OutControl ∧ ¬(EDM1 ∧ EDM2) / timer.Q ∧ ¬(EDM1 ∧ EDM2) / S_OutControl | C010–C030 / C040–C060 / 8000 |
/// | 8000 | ¬S_OutControl / timer.Q ∧ (EDM1 ∨ EDM2) | 8810 / C070–C090 |
/// | C001, C100 | ¬Reset | 8401 |
/// | C010–C090 | R_TRIG(Reset) | 8810 (monitoring starts again) |
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SfEdm {
    state: EdmState,
    reset_trig: RTrig,
    control_trig: RTrig,
    timer: Ton,
}

impl SfEdm {
    /// A block in Idle.
    pub fn new() -> Self {
        Self::default()
    }

    /// The current state.
    pub fn state(&self) -> EdmState {
        self.state
    }

    /// One call at `now`.
    pub fn call(&mut self, now: SimTime, i: SfEdmInputs) -> SfEdmOutputs {
        use EdmState::*;
        let reset_edge = self.reset_trig.call(i.reset);
        let control_edge = self.control_trig.call(i.s_out_control);
        let expired = self.timer.q();
        let released = EdmChannels::of(!i.s_edm1, !i.s_edm2);
        let still_released = EdmChannels::of(i.s_edm1, i.s_edm2);
        let before = self.state;
        self.state = if !i.activate {
            Idle
        } else {
            match self.state {
                Idle if i.s_start_reset => OutDisable,
                Idle => Init,
                Init if reset_edge && control_edge => InitError,
                Init if reset_edge => OutDisable,
                Init if i.reset => ResetError,
                OutDisable => match released {
                    Some(c) if i.s_out_control => NotReleasedAtEnable(c),
                    Some(c) if expired => NotReleasedInTime(c),
                    None if i.s_out_control => OutEnable,
                    _ => OutDisable,
                },
                OutEnable if !i.s_out_control => OutDisable,
                OutEnable => match still_released {
                    Some(c) if expired => NotSwitchedInTime(c),
                    _ => OutEnable,
                },
                ResetError | InitError if !i.reset => Init,
                NotReleasedAtEnable(_) | NotReleasedInTime(_) | NotSwitchedInTime(_)
                    if reset_edge =>
                {
                    OutDisable
                }
                unchanged => unchanged,
            }
        };
        let s = self.state;
        if s != before {
            self.timer.reset();
        }
        self.timer
            .call(now, matches!(s, OutDisable | OutEnable), i.monitoring_time);
        SfEdmOutputs {
            ready: s != Idle,
            s_edm_out: s == OutEnable,
            error: s.is_error(),
            diag_code: s.code(),
        }
    }
}
