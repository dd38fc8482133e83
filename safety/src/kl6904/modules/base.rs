//! What the stateful modules share: their states, errors and events, the pair monitor and the
//! common state machine ([`Core`]).

use asi_phy::{SimDuration, SimTime};
use core::fmt;

use crate::primitives::PulseDetector;

/// The state of a stateful function module (docs/safety-logic.md §6.1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FbState {
    /// The group does not run: all outputs 0.
    #[default]
    Stop,
    /// Safe state demanded or restart pending: outputs 0.
    Safe,
    /// Normal operation: outputs 1.
    Run,
    /// A demand arrived: the immediate output is 0, the delayed one still 1.
    DelayOut,
    /// An error was detected: outputs 0 and Error = 1 until the group's ERR_ACK.
    Error,
}

impl FbState {
    /// Upper-case name as on the Beckhoff status page.
    pub const fn name(self) -> &'static str {
        match self {
            FbState::Stop => "STOP",
            FbState::Safe => "SAFE",
            FbState::Run => "RUN",
            FbState::DelayOut => "DELAYOUT",
            FbState::Error => "ERROR",
        }
    }
}

impl fmt::Display for FbState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An error a module detected (reported to its group as FB_ERR).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FbError {
    /// The two inputs of pair `pair` (1-based: 1 = inputs 1/2) differed longer than the
    /// discrepancy time.
    Discrepancy {
        /// Pair number, 1-based.
        pair: u8,
    },
    /// MON: Secure1 and Secure2 differed longer than their discrepancy time.
    SecureDiscrepancy,
    /// EDM input `channel` (1 or 2) was not 1 when the safe state was to be left.
    Edm {
        /// 1 for EDM1, 2 for EDM2.
        channel: u8,
    },
    /// OPMODE: no input or more than one input set for longer than the discrepancy time.
    ModeSelection,
}

impl fmt::Display for FbError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FbError::Discrepancy { pair } => write!(
                f,
                "discrepancy time exceeded on input pair {pair} (inputs {}/{})",
                2 * pair - 1,
                2 * pair
            ),
            FbError::SecureDiscrepancy => {
                f.write_str("discrepancy time exceeded on Secure1/Secure2")
            }
            FbError::Edm { channel } => write!(
                f,
                "EDM{channel} not 1 at restart (contactor not released, welded?)"
            ),
            FbError::ModeSelection => f.write_str(
                "mode selection invalid (none or several inputs) longer than the discrepancy time",
            ),
        }
    }
}

/// Diag bit of an EDM1 error (ESTOP and MON, §3.3 of the KL6904 manual).
pub(crate) const EDM1_BIT: u8 = 4;
/// Diag bit of an EDM2 error.
pub(crate) const EDM2_BIT: u8 = 5;

/// Something a module did in a scan, for the event log.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FbEvent {
    /// The module left RUN because of a demand; `inputs` has bit `n-1` set for each input `n`
    /// that demanded the safe state (for OPMODE: the selection changed).
    SafeStateDemanded {
        /// Bit `n-1` set for each demanding input `n`.
        inputs: u8,
    },
    /// The delayed output went to 0 at the end of the delay time.
    DelayedOutputOff,
    /// The module entered RUN (restart accepted, or automatic restart).
    Restarted,
    /// The module detected an error and entered ERROR.
    Error(FbError),
    /// The group acknowledged the module's error.
    Acknowledged,
    /// The module was stopped because its group stopped running.
    Stopped,
}

/// Discrepancy monitoring of two inputs that form a pair (§4.4.1 of the KL6904 manual): they may
/// differ only for the discrepancy time.
///
/// **Decision**: an error is raised when the difference has lasted *longer than* the time
/// (the KL6904 manual: "if the discrepancy time is exceeded"), checked in the same scan; PLCopen's
/// SF_Equivalent instead uses TON.Q (≥) read one call later, and keeps that behaviour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct PairMonitor {
    since: Option<SimTime>,
}

impl PairMonitor {
    /// `true` when `a` and `b` have differed for longer than `time`.
    pub(crate) fn exceeded(&mut self, now: SimTime, a: bool, b: bool, time: SimDuration) -> bool {
        if a == b {
            self.since = None;
            return false;
        }
        let since = *self.since.get_or_insert(now);
        now.saturating_duration_since(since) > time
    }

    pub(crate) fn reset(&mut self) {
        self.since = None;
    }

    /// `true` while the two inputs differ: the time is running, so a later scan with the same
    /// inputs may raise the error.
    pub(crate) fn running(&self) -> bool {
        self.since.is_some()
    }
}

/// The state machine ESTOP and MON share: two outputs, one immediate and one delayed, a
/// restart interlock, an error state and its diagnostic bits.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Core {
    pub(crate) state: FbState,
    delay_since: Option<SimTime>,
    pub(crate) restart: PulseDetector,
    pub(crate) diag: u8,
    pub(crate) events: Vec<FbEvent>,
    /// Whether the cause of the latched error was still present in the last scan.
    pub(crate) cause_active: bool,
    acknowledged: bool,
}

impl Core {
    /// Start of a scan: clears the events; handles a stopped group. Returns `false` when the
    /// group does not run (the caller then only writes its outputs).
    pub(crate) fn begin(&mut self, run: bool) -> bool {
        self.events.clear();
        if core::mem::take(&mut self.acknowledged) {
            self.events.push(FbEvent::Acknowledged);
        }
        if !run {
            if !matches!(self.state, FbState::Stop | FbState::Error) {
                self.state = FbState::Stop;
                self.delay_since = None;
                self.events.push(FbEvent::Stopped);
            }
            return false;
        }
        if self.state == FbState::Stop {
            // Started (group activated): the safe state is left only by a restart.
            self.state = FbState::Safe;
        }
        true
    }

    /// Enter ERROR with diagnostic bit `bit` set (unless already there).
    pub(crate) fn fail(&mut self, bit: u8, error: FbError) {
        self.diag |= 1 << bit;
        if self.state != FbState::Error {
            self.state = FbState::Error;
            self.delay_since = None;
        }
        self.events.push(FbEvent::Error(error));
    }

    /// RUN and DELAYOUT: react to a demand and run the delay.
    pub(crate) fn supervise(&mut self, now: SimTime, demand: u8, delay: SimDuration) {
        if self.state == FbState::Run && demand != 0 {
            self.events
                .push(FbEvent::SafeStateDemanded { inputs: demand });
            self.state = FbState::DelayOut;
            self.delay_since = Some(now);
        }
        if self.state == FbState::DelayOut {
            let since = *self.delay_since.get_or_insert(now);
            if now.saturating_duration_since(since) >= delay {
                self.state = FbState::Safe;
                self.delay_since = None;
                self.events.push(FbEvent::DelayedOutputOff);
            }
        }
    }

    /// Leave the safe state.
    pub(crate) fn release(&mut self) {
        self.state = FbState::Run;
        self.events.push(FbEvent::Restarted);
    }

    /// A restart was accepted: check the activated EDM inputs (`edm_bad[k]` = EDM*k+1* activated
    /// and not 1) and leave the safe state, or enter ERROR with diag bit 4/5 (§4.4.1 of the KL6904
    /// manual).
    pub(crate) fn restart_checking_edm(&mut self, edm_bad: [bool; 2]) {
        for (k, bit) in [EDM1_BIT, EDM2_BIT].into_iter().enumerate() {
            if edm_bad[k] {
                self.fail(
                    bit,
                    FbError::Edm {
                        channel: k as u8 + 1,
                    },
                );
            }
        }
        if self.state == FbState::Safe {
            self.release();
        }
    }

    /// `true` while a latched EDM error's input still is not 1.
    pub(crate) fn edm_cause_active(&self, edm_bad: [bool; 2]) -> bool {
        (self.diag & 1 << EDM1_BIT != 0 && edm_bad[0])
            || (self.diag & 1 << EDM2_BIT != 0 && edm_bad[1])
    }

    /// The group's ERR_ACK: leave ERROR for SAFE and clear the diagnostic bits.
    pub(crate) fn acknowledge(&mut self) {
        if self.state == FbState::Error {
            self.state = FbState::Safe;
            self.diag = 0;
            // Reported with the next scan's events (the group acknowledges between scans).
            self.acknowledged = true;
        }
    }

    /// `true` while in ERROR and its cause was still present in the last scan.
    pub(crate) fn error_cause_active(&self) -> bool {
        self.state == FbState::Error && self.cause_active
    }

    /// `true` if the last scan left nothing for another scan with the same inputs to do before
    /// [`Core::delay_ends`]: it reported nothing and did not change the state (`before`, the
    /// state it started from), and a delay that runs has its start. The module's own timers
    /// (its pair monitors) are the caller's to check.
    pub(crate) fn quiet(&self, before: FbState) -> bool {
        let delay_known = self.state != FbState::DelayOut || self.delay_since.is_some();
        self.events.is_empty() && self.state == before && delay_known
    }

    /// In DELAYOUT, when the delayed output goes off with the Delay Time `delay`: the first
    /// scan at or after it ends the delay ([`Core::supervise`]); `None` in any other state
    /// (or past the end of time).
    pub(crate) fn delay_ends(&self, delay: SimDuration) -> Option<SimTime> {
        match (self.state, self.delay_since) {
            (FbState::DelayOut, Some(since)) => since.checked_add(delay),
            _ => None,
        }
    }

    /// (immediate output, delayed output, Error).
    pub(crate) fn outputs(&self) -> (bool, bool, bool) {
        (
            self.state == FbState::Run,
            matches!(self.state, FbState::Run | FbState::DelayOut),
            self.state == FbState::Error,
        )
    }
}
