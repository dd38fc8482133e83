//! The ESTOP function module (§4.4 of the KL6904 manual; docs/safety-logic.md §1.6).

use asi_phy::{SimDuration, SimTime};

use super::base::{Core, FbError, FbEvent, FbState, PairMonitor};
use crate::kl6904::signal::Contact;

/// Parameters of an ESTOP module (the "Activated", contact, Delay-Time and discrepancy settings
/// of §4.4.3 of the KL6904 manual).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct EstopConfig {
    /// EStopIn1..8: `None` = input not activated, else its contact type.
    pub inputs: [Option<Contact>; 8],
    /// Discrepancy time of pairs 1/2, 3/4, 5/6, 7/8. A non-zero time makes the two inputs a pair
    /// (table 4-10 of the KL6904 manual: "if the discrepancy time is not 0"); zero leaves them
    /// single channels.
    pub discrepancy: [SimDuration; 4],
    /// EDM1 (feedback of EStopOut) activated.
    pub edm1: bool,
    /// EDM2 (feedback of EStopDelOut) activated.
    pub edm2: bool,
    /// Delay Time of EStopDelOut.
    pub delay: SimDuration,
}

/// Input values of an ESTOP module for one scan (inactive inputs are ignored).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EstopInputs {
    /// EStopIn1..8, raw (before the contact type).
    pub estop_in: [bool; 8],
    /// Restart: a 0→1→0 pulse leaves the safe state.
    pub restart: bool,
    /// EDM1: external feedback of EStopOut (1 = contactor released).
    pub edm1: bool,
    /// EDM2: external feedback of EStopDelOut.
    pub edm2: bool,
}

/// Outputs of an ESTOP module (table 4-11 of the KL6904 manual).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EstopOutputs {
    /// First output: 0 at once on a demand.
    pub estop_out: bool,
    /// Second output: 0 after the Delay Time.
    pub estop_del_out: bool,
    /// An error (discrepancy or EDM) is latched until the group's ERR_ACK.
    pub error: bool,
}

/// The KL6904 emergency-stop module.
///
/// - As soon as an active input demands the safe state, EStopOut goes to 0 at once and
///   EStopDelOut after the Delay Time (§4.4.1 of the KL6904 manual).
/// - The safe state — at start (group activated) and after every demand — is left only by a
///   0→1→0 sequence on Restart, acting on its falling edge.
/// - When a restart is accepted, every activated EDM input must read 1, else the module enters
///   ERROR with diag bit 4/5 (a welded contactor, §5.1 of the KL6904 manual).
/// - Inputs paired by a non-zero discrepancy time may differ only for that time, else ERROR
///   with diag bit 0–3. In ERROR all outputs are 0; only the group's ERR_ACK leaves it.
///
/// **Decisions** where the KL6904 manual is silent:
/// - a restart is accepted only in SAFE, i.e. once the delayed output too has gone to 0 and no
///   input demands the safe state; a pulse during the delay is ignored (the EDM check is then
///   meaningful: a contactor driven by EStopDelOut must have released);
/// - an error is *resolved* (ERR_ACK may clear it) when the offending pair agrees again, or the
///   offending EDM input reads 1 again; the group refuses the acknowledgement before that.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Estop {
    config: EstopConfig,
    /// Bit `n` set for each activated EStopIn*n+1*, and for each of them with a make contact
    /// (both from `config`, for the scan's bit masks).
    active: u8,
    make: u8,
    core: Core,
    pairs: [PairMonitor; 4],
}

/// Positions of the inputs after EStopIn1..8 in an input mask ([`Estop::scan_bits`]).
const RESTART: u16 = 1 << 8;
const EDM1: u16 = 1 << 9;
const EDM2: u16 = 1 << 10;

impl EstopInputs {
    /// The inputs as a mask in the order of the module's inputs: bit `n` EStopIn*n+1*, bit 8
    /// Restart, 9 EDM1, 10 EDM2.
    fn bits(&self) -> u16 {
        let ins = self.estop_in.iter().enumerate();
        ins.fold(0, |m, (n, &v)| m | u16::from(v) << n)
            | if self.restart { RESTART } else { 0 }
            | if self.edm1 { EDM1 } else { 0 }
            | if self.edm2 { EDM2 } else { 0 }
    }
}

impl Estop {
    /// A module in STOP.
    pub fn new(config: EstopConfig) -> Self {
        let mask = |f: fn(Contact) -> bool| {
            (0..8).fold(0, |m, n| match config.inputs[n] {
                Some(c) if f(c) => m | 1 << n,
                _ => m,
            })
        };
        Estop {
            active: mask(|_| true),
            make: mask(|c| c == Contact::Make),
            config,
            ..Default::default()
        }
    }

    /// The parameters.
    pub fn config(&self) -> &EstopConfig {
        &self.config
    }

    /// One scan at `now`; `run` is whether the module's group is in RUN.
    pub fn scan(&mut self, now: SimTime, run: bool, i: &EstopInputs) -> EstopOutputs {
        self.scan_bits(now, run, i.bits())
    }

    /// [`Estop::scan`] with the inputs as a mask (bit `n` EStopIn*n+1*, bit 8 Restart, 9 EDM1,
    /// 10 EDM2: the order of the module's inputs), as the logic reads them.
    pub(crate) fn scan_bits(&mut self, now: SimTime, run: bool, inputs: u16) -> EstopOutputs {
        let cfg = &self.config;
        // Bit n: EStopIn n+1 is activated and demands the safe state (a break contact at 0,
        // a make contact at 1).
        let demands = self.active & !(inputs as u8 ^ self.make);
        let demanding = |n: usize| demands & 1 << n != 0;
        let edm_bad = [
            cfg.edm1 && inputs & EDM1 == 0,
            cfg.edm2 && inputs & EDM2 == 0,
        ];

        let running = self.core.begin(run);
        if !running || self.core.state == FbState::Error {
            self.pairs.iter_mut().for_each(PairMonitor::reset);
        } else {
            for k in 0..4 {
                let t = cfg.discrepancy[k];
                if !t.is_zero()
                    && self.pairs[k].exceeded(now, demanding(2 * k), demanding(2 * k + 1), t)
                {
                    self.core
                        .fail(k as u8, FbError::Discrepancy { pair: k as u8 + 1 });
                }
            }
        }
        let demand = demands;
        let accept = running && self.core.state == FbState::Safe && demand == 0;
        let restart = self.core.restart.call(inputs & RESTART != 0, accept);
        if running {
            match self.core.state {
                FbState::Run | FbState::DelayOut => self.core.supervise(now, demand, cfg.delay),
                FbState::Safe if restart => self.core.restart_checking_edm(edm_bad),
                _ => {}
            }
        }
        let diag = self.core.diag;
        self.core.cause_active = (0..4)
            .any(|k| diag & 1 << k != 0 && demanding(2 * k) != demanding(2 * k + 1))
            || self.core.edm_cause_active(edm_bad);
        let (estop_out, estop_del_out, error) = self.core.outputs();
        EstopOutputs {
            estop_out,
            estop_del_out,
            error,
        }
    }
}

impl Estop {
    /// `true` if the last scan, which started in state `before`, left nothing for another
    /// scan with the same inputs and group state to do before [`Estop::delay_ends`]: no event, no
    /// change of state, no discrepancy time running (the logic's quiet scan relies on it).
    pub(crate) fn quiet(&self, before: FbState) -> bool {
        self.core.quiet(before) && !(self.pairs.iter().any(PairMonitor::running))
    }

    /// In DELAYOUT, when the delayed output goes off (the first scan at or after it is not a
    /// quiet one).
    pub(crate) fn delay_ends(&self) -> Option<SimTime> {
        self.core.delay_ends(self.config.delay)
    }
}

core_accessors!(Estop);
