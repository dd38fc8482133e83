//! The OPMODE function module (§4.3 of the KL6904 manual; docs/source-errors.md;
//! docs/safety-logic.md §1.6).

use asi_phy::{SimDuration, SimTime};

use super::base::{Core, FbError, FbEvent, FbState, PairMonitor};

/// Parameters of an OPMODE module (§4.3.3 of the KL6904 manual).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct OpModeConfig {
    /// OpIn1..8 activated.
    pub inputs: [bool; 8],
    /// Restart activated: the safe state is left at start and after every mode change only by a
    /// 0→1→0 Restart pulse. Without it the selected output follows the selector.
    pub restart: bool,
    /// Discrepancy time for the change-over between modes; zero = not monitored.
    pub discrepancy: SimDuration,
}

/// Input values of an OPMODE module for one scan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OpModeInputs {
    /// OpIn1..8.
    pub op_in: [bool; 8],
    /// Restart.
    pub restart: bool,
}

/// Outputs of an OPMODE module (table 4-8 of the KL6904 manual).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OpModeOutputs {
    /// OpOut1..8: at most one is 1.
    pub op_out: [bool; 8],
    /// A discrepancy (input check) error is latched until the group's ERR_ACK.
    pub error: bool,
}

/// The KL6904 operating-mode selector.
///
/// Only when exactly one active input is 1 is its output set; with no input or more than one
/// input set all outputs are 0 (docs/source-errors.md corrects the KL6904 manual's "one or more").
///
/// **Decisions** (docs/safety-logic.md §10 point 6, not specified in detail):
/// - the discrepancy time bounds how long the selection may be invalid (none or several inputs
///   set) — the moment a selector switch spends between two positions; longer is an ERROR with
///   diag bit 0, resolved once exactly one input is set again; without a discrepancy time an
///   invalid selection only makes the outputs safe;
/// - with Restart, any departure from the running mode (to another mode or to an invalid
///   selection) makes all outputs safe until a Restart pulse while a valid mode is selected;
///   without Restart a change from one valid mode to another switches the output in the same
///   scan (the latched mode is what is output, never the raw inputs: docs/safety-logic.md §5.2,
///   the SF_ModeSelector lesson).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct OpMode {
    config: OpModeConfig,
    /// Bit `n` set for each activated OpIn*n+1* (from `config`, for the scan's bit masks).
    active: u8,
    core: Core,
    mode: usize,
    /// Times how long the selection has been invalid (a "pair" of invalid vs. FALSE).
    invalid: PairMonitor,
}

/// The position of Restart after OpIn1..8 in an input mask ([`OpMode::scan_bits`]).
const RESTART: u16 = 1 << 8;

impl OpModeInputs {
    /// The inputs as a mask in the order of the module's inputs: bit `n` OpIn*n+1*, bit 8
    /// Restart.
    fn bits(&self) -> u16 {
        let ins = self.op_in.iter().enumerate();
        ins.fold(0, |m, (n, &v)| m | u16::from(v) << n) | if self.restart { RESTART } else { 0 }
    }
}

impl OpMode {
    /// A module in STOP.
    pub fn new(config: OpModeConfig) -> Self {
        OpMode {
            active: (0..8).fold(0, |m, n| if config.inputs[n] { m | 1 << n } else { m }),
            config,
            ..Default::default()
        }
    }

    /// The parameters.
    pub fn config(&self) -> &OpModeConfig {
        &self.config
    }

    /// One scan at `now`; `run` is whether the module's group is in RUN.
    pub fn scan(&mut self, now: SimTime, run: bool, i: &OpModeInputs) -> OpModeOutputs {
        self.scan_bits(now, run, i.bits())
    }

    /// [`OpMode::scan`] with the inputs as a mask (bit `n` OpIn*n+1*, bit 8 Restart: the order
    /// of the module's inputs), as the logic reads them.
    pub(crate) fn scan_bits(&mut self, now: SimTime, run: bool, inputs: u16) -> OpModeOutputs {
        // Bit n: OpIn n+1 is activated and set.
        let set = self.active & inputs as u8;
        let selected = (set.count_ones() == 1).then(|| set.trailing_zeros() as usize);
        let running = self.core.begin(run);
        let t = self.config.discrepancy;
        if !running {
            self.invalid.reset();
        } else if self.core.state != FbState::Error
            && !t.is_zero()
            && self.invalid.exceeded(now, selected.is_none(), false, t)
        {
            self.core.fail(0, FbError::ModeSelection);
        }
        let accept = running && self.core.state == FbState::Safe && selected.is_some();
        let restart = self
            .core
            .restart
            .call(inputs & RESTART != 0, accept && self.config.restart);
        if running {
            match (self.core.state, selected) {
                (FbState::Run, Some(m)) if m == self.mode => {}
                (FbState::Run, Some(m)) if !self.config.restart => self.mode = m,
                (FbState::Run, _) => {
                    self.core.state = FbState::Safe;
                    self.core
                        .events
                        .push(FbEvent::SafeStateDemanded { inputs: set });
                }
                (FbState::Safe, Some(m)) if restart || !self.config.restart => {
                    self.mode = m;
                    self.core.release();
                }
                _ => {}
            }
        }
        self.core.cause_active = selected.is_none();
        let mut op_out = [false; 8];
        if self.core.state == FbState::Run {
            op_out[self.mode] = true;
        }
        OpModeOutputs {
            op_out,
            error: self.core.state == FbState::Error,
        }
    }

    /// The selected mode (0-based) while in RUN.
    pub fn mode(&self) -> Option<usize> {
        (self.core.state == FbState::Run).then_some(self.mode)
    }
}

impl OpMode {
    /// `true` if the last scan, which started in state `before`, left nothing for another
    /// scan with the same inputs and group state to do, at any later time: no event, no
    /// change of state, no discrepancy time running (the logic's quiet scan relies on it).
    /// OPMODE has no delay.
    pub(crate) fn quiet(&self, before: FbState) -> bool {
        self.core.quiet(before) && !(self.invalid.running())
    }
}

core_accessors!(OpMode);
