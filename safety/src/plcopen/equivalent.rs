//! SF_Equivalent, PLCopen v2.01 codes (docs/safety-logic.md §5.2, §9.2; FBS_EQUI).

use asi_phy::{SimDuration, SimTime};

use super::diag::DiagCode;
use crate::primitives::Ton;

/// Inputs of [`SfEquivalent`]. All default to FALSE / zero.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SfEquivalentInputs {
    /// FALSE sets all outputs to their initial values.
    pub activate: bool,
    /// Channel A (TRUE = contact closed, no demand).
    pub s_channel_a: bool,
    /// Channel B.
    pub s_channel_b: bool,
    /// The longest time the two channels may differ. PLCopen meaning: `0` is *zero tolerance*,
    /// not "unpaired" as in the Beckhoff blocks (docs/safety-logic.md §10 point 3).
    pub discrepancy_time: SimDuration,
}

/// Outputs of [`SfEquivalent`], all assigned on every call.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SfEquivalentOutputs {
    /// The block is active.
    pub ready: bool,
    /// TRUE only while both channels are TRUE and they switched within the discrepancy time.
    pub s_equivalent_out: bool,
    /// A safety demand is present (v2.x: the `0x0800` bit of the DiagCode).
    pub safety_demand: bool,
    /// A discrepancy error is latched.
    pub error: bool,
    /// The state.
    pub diag_code: DiagCode,
}

/// The states of SF_Equivalent (FBS_EQUI; the v1 code of docs/safety-logic.md §5.2 in brackets).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum EquivalentState {
    /// `0000` not active.
    #[default]
    Idle,
    /// `8801` [8001] activated; both channels FALSE or waiting for a first channel.
    Init,
    /// `8802` [8004] channel A TRUE, waiting for B; discrepancy timer running.
    WaitForB,
    /// `8804` [8014] channel B TRUE, waiting for A; discrepancy timer running.
    WaitForA,
    /// `8000` both channels TRUE: output enabled.
    OutEnabled,
    /// `8806` [8005] one channel dropped; waiting for the other; timer running.
    FromActiveWait,
    /// `C010` [C001] discrepancy time elapsed in WaitForB.
    Error1,
    /// `C020` [C002] discrepancy time elapsed in WaitForA.
    Error2,
    /// `C030` [C003] discrepancy time elapsed in FromActiveWait.
    Error3,
}

impl EquivalentState {
    /// The v2.01 DiagCode of the state.
    pub const fn code(self) -> DiagCode {
        DiagCode(match self {
            EquivalentState::Idle => 0x0000,
            EquivalentState::Init => 0x8801,
            EquivalentState::WaitForB => 0x8802,
            EquivalentState::WaitForA => 0x8804,
            EquivalentState::OutEnabled => 0x8000,
            EquivalentState::FromActiveWait => 0x8806,
            EquivalentState::Error1 => 0xC010,
            EquivalentState::Error2 => 0xC020,
            EquivalentState::Error3 => 0xC030,
        })
    }

    fn timing(self) -> bool {
        matches!(
            self,
            EquivalentState::WaitForB | EquivalentState::WaitForA | EquivalentState::FromActiveWait
        )
    }
}

/// PLCopen SF_Equivalent: two equivalent (both NC) channels to one output with discrepancy-time
/// monitoring. It has no restart interlock; put SF_EmergencyStop or similar behind it.
///
/// Transitions (docs/safety-logic.md §5.2, one per call, first match wins):
///
/// | from | condition | to |
/// |---|---|---|
/// | 0000 | Activate | 8801 |
/// | 8801 | A ∧ ¬B / B ∧ ¬A / A ∧ B | 8802 / 8804 / 8000 |
/// | 8802 | timer.Q / ¬A / B | C010 / 8801 / 8000 |
/// | 8804 | timer.Q / ¬B / A | C020 / 8801 / 8000 |
/// | 8000 | A xor B / ¬A ∧ ¬B | 8806 / 8801 |
/// | 8806 | timer.Q / ¬A ∧ ¬B | C030 / 8801 |
/// | Cxxx | ¬A ∧ ¬B | 8801 |
///
/// The discrepancy timer runs while in 8802/8804/8806 and is read at the start of the next
/// call, so Error appears one call after the timer expires (docs/safety-logic.md §9.1: the
/// property "timer.Q ∧ Ready ⇒ Error" is known to fail by that one call). An error clears
/// without Reset once both channels are FALSE.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SfEquivalent {
    state: EquivalentState,
    timer: Ton,
}

impl SfEquivalent {
    /// A block in Idle.
    pub fn new() -> Self {
        Self::default()
    }

    /// The current state.
    pub fn state(&self) -> EquivalentState {
        self.state
    }

    /// Q of the discrepancy timer after the last call.
    pub fn timer_q(&self) -> bool {
        self.timer.q()
    }

    /// One call at `now`.
    pub fn call(&mut self, now: SimTime, i: SfEquivalentInputs) -> SfEquivalentOutputs {
        use EquivalentState::*;
        let (a, b) = (i.s_channel_a, i.s_channel_b);
        let expired = self.timer.q();
        let before = self.state;
        self.state = if !i.activate {
            Idle
        } else {
            match self.state {
                Idle => Init,
                Init if a && !b => WaitForB,
                Init if b && !a => WaitForA,
                Init if a && b => OutEnabled,
                WaitForB if expired => Error1,
                WaitForB if !a => Init,
                WaitForB if b => OutEnabled,
                WaitForA if expired => Error2,
                WaitForA if !b => Init,
                WaitForA if a => OutEnabled,
                OutEnabled if a != b => FromActiveWait,
                OutEnabled if !a && !b => Init,
                FromActiveWait if expired => Error3,
                FromActiveWait if !a && !b => Init,
                Error1 | Error2 | Error3 if !a && !b => Init,
                unchanged => unchanged,
            }
        };
        let s = self.state;
        // A timed state entered from another timed state starts a fresh timer.
        if s != before {
            self.timer.reset();
        }
        self.timer.call(now, s.timing(), i.discrepancy_time);
        SfEquivalentOutputs {
            ready: s != Idle,
            s_equivalent_out: s == OutEnabled,
            safety_demand: s.code().0 & 0xF800 == 0x8800,
            error: matches!(s, Error1 | Error2 | Error3),
            diag_code: s.code(),
        }
    }
}
