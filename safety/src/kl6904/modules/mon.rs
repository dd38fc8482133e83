//! The MON function module (§4.5 of the KL6904 manual; docs/safety-logic.md §1.6).

use asi_phy::{SimDuration, SimTime};

use super::base::{Core, FbError, FbEvent, FbState, PairMonitor};
use crate::kl6904::signal::Contact;

/// Parameters of a MON module (§4.5.3 of the KL6904 manual).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct MonConfig {
    /// MonIn1..4 (four inputs, docs/source-errors.md): `None` = not activated, else the contact
    /// type.
    pub inputs: [Option<Contact>; 4],
    /// Discrepancy time of pairs MonIn1/2 and MonIn3/4; non-zero makes a pair.
    pub discrepancy: [SimDuration; 2],
    /// Secure1 and Secure2 (muting): `None` = not used, else their contact type. Both inputs
    /// of the pair share it.
    pub secure: Option<Contact>,
    /// Discrepancy time of the Secure pair; non-zero activates the check.
    pub secure_discrepancy: SimDuration,
    /// "Manual": leaving the safe state needs a 0→1→0 pulse on Restart; otherwise it is left
    /// automatically when no input demands it.
    pub manual_restart: bool,
    /// "Manual Function Test": after the module starts, every active MonIn must demand the safe
    /// state once before the safe state can be left.
    pub function_test: bool,
    /// EDM1 (feedback of MonOut) activated.
    pub edm1: bool,
    /// EDM2 (feedback of MonDelOut) activated.
    pub edm2: bool,
    /// Delay Time of MonDelOut.
    pub delay: SimDuration,
}

/// Input values of a MON module for one scan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MonInputs {
    /// MonIn1..4, raw.
    pub mon_in: [bool; 4],
    /// Secure1, Secure2, raw.
    pub secure: [bool; 2],
    /// Restart (used only with manual restart).
    pub restart: bool,
    /// EDM1 (1 = contactor released).
    pub edm1: bool,
    /// EDM2.
    pub edm2: bool,
}

/// Outputs of a MON module (table 4-14 of the KL6904 manual).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MonOutputs {
    /// First output: 0 at once on a demand.
    pub mon_out: bool,
    /// Second output: 0 after the Delay Time.
    pub mon_del_out: bool,
    /// An error is latched until the group's ERR_ACK.
    pub error: bool,
}

/// Diagnostic bit of a Secure-pair discrepancy (§3.3 of the KL6904 manual; 0–1 are the MonIn pairs,
/// 4–5 EDM1/EDM2).
const SECURE_BIT: u8 = 2;

/// The KL6904 monitoring module (safety door, or the lift's overtravel sensors).
///
/// - An active MonIn demanding the safe state drops MonOut at once and MonDelOut after the
///   Delay Time, unless muted: with Secure inputs as break contacts the MonIn inputs are
///   ignored while Secure1 = Secure2 = 1, as make contacts while both are 0.
/// - Manual restart: the safe state is left by a 0→1→0 Restart pulse; an activated EDM input
///   that is not 1 at that moment is an error (diag bit 4/5).
/// - Automatic restart: the safe state is left as soon as nothing demands it; an EDM input that is
///   not 1 then keeps the module in SAFE *without* an error (§4.5.1 of the KL6904 manual: "an EDM
///   error is only detected with manual restart"; docs/safety-logic.md §10 point 5 — kept as the
///   KL6904 manual says, and shown as a SAFE module whose EDM input is 0).
/// - MonIn pairs and the Secure pair are discrepancy-monitored; manual function test as in
///   [`MonConfig::function_test`].
///
/// **Decisions**: as for ESTOP, a restart is accepted only in SAFE (after the delay); the
/// function test counts the raw demands (muted or not) since the module last started (group
/// start or restart after an error) and applies before the first release after that start.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Mon {
    config: MonConfig,
    /// Bit `n` set for each activated MonIn*n+1*, and for each of them with a make contact
    /// (both from `config`, for the scan's bit masks).
    active: u8,
    make: u8,
    core: Core,
    pairs: [PairMonitor; 2],
    secure_pair: PairMonitor,
    /// Bit `n` set once MonIn*n+1* has demanded the safe state since the module started.
    tested: u8,
}

/// Positions of the inputs after MonIn1..4 in an input mask ([`Mon::scan_bits`]).
const SECURE1: u16 = 1 << 4;
const SECURE2: u16 = 1 << 5;
const RESTART: u16 = 1 << 6;
const EDM1: u16 = 1 << 7;
const EDM2: u16 = 1 << 8;

impl MonInputs {
    /// The inputs as a mask in the order of the module's inputs: bit `n` MonIn*n+1*, bits 4
    /// and 5 Secure1 and Secure2, 6 Restart, 7 EDM1, 8 EDM2.
    fn bits(&self) -> u16 {
        let ins = self.mon_in.iter().enumerate();
        let flag = |on: bool, bit: u16| if on { bit } else { 0 };
        ins.fold(0, |m, (n, &v)| m | u16::from(v) << n)
            | flag(self.secure[0], SECURE1)
            | flag(self.secure[1], SECURE2)
            | flag(self.restart, RESTART)
            | flag(self.edm1, EDM1)
            | flag(self.edm2, EDM2)
    }
}

impl Mon {
    /// A module in STOP.
    pub fn new(config: MonConfig) -> Self {
        let mask = |f: fn(Contact) -> bool| {
            (0..4).fold(0, |m, n| match config.inputs[n] {
                Some(c) if f(c) => m | 1 << n,
                _ => m,
            })
        };
        Mon {
            active: mask(|_| true),
            make: mask(|c| c == Contact::Make),
            config,
            ..Default::default()
        }
    }

    /// The parameters.
    pub fn config(&self) -> &MonConfig {
        &self.config
    }

    /// One scan at `now`; `run` is whether the module's group is in RUN.
    pub fn scan(&mut self, now: SimTime, run: bool, i: &MonInputs) -> MonOutputs {
        self.scan_bits(now, run, i.bits())
    }

    /// [`Mon::scan`] with the inputs as a mask (bit `n` MonIn*n+1*, bits 4 and 5 Secure1 and
    /// Secure2, 6 Restart, 7 EDM1, 8 EDM2: the order of the module's inputs), as the logic
    /// reads them.
    pub(crate) fn scan_bits(&mut self, now: SimTime, run: bool, inputs: u16) -> MonOutputs {
        let cfg = &self.config;
        // Bit n: MonIn n+1 is activated and demands the safe state (a break contact at 0, a
        // make contact at 1), muted or not.
        let raw = self.active & !(inputs as u8 ^ self.make);
        let raw_at = |n: usize| raw & 1 << n != 0;
        let secure_on = cfg.secure.map(|c| {
            [
                c.normalise(inputs & SECURE1 != 0),
                c.normalise(inputs & SECURE2 != 0),
            ]
        });
        let muted = secure_on.is_some_and(|[a, b]| a && b);
        let demands = if muted { 0 } else { raw };
        let edm_bad = [
            cfg.edm1 && inputs & EDM1 == 0,
            cfg.edm2 && inputs & EDM2 == 0,
        ];

        let was_stopped = self.core.state == FbState::Stop;
        let running = self.core.begin(run);
        if running && was_stopped {
            self.tested = 0;
        }
        self.tested |= raw;
        if !running || self.core.state == FbState::Error {
            self.pairs.iter_mut().for_each(PairMonitor::reset);
            self.secure_pair.reset();
        } else {
            for k in 0..2 {
                let t = cfg.discrepancy[k];
                if !t.is_zero() && self.pairs[k].exceeded(now, raw_at(2 * k), raw_at(2 * k + 1), t)
                {
                    self.core
                        .fail(k as u8, FbError::Discrepancy { pair: k as u8 + 1 });
                }
            }
            if let Some([a, b]) = secure_on {
                let t = cfg.secure_discrepancy;
                if !t.is_zero() && self.secure_pair.exceeded(now, a, b, t) {
                    self.core.fail(SECURE_BIT, FbError::SecureDiscrepancy);
                }
            }
        }

        let demand = demands;
        // Every activated input has demanded the safe state once.
        let tested = !cfg.function_test || self.active & !self.tested == 0;
        let may_leave = running && self.core.state == FbState::Safe && demand == 0 && tested;
        let restart = self
            .core
            .restart
            .call(inputs & RESTART != 0, may_leave && cfg.manual_restart);
        if running {
            match self.core.state {
                FbState::Run | FbState::DelayOut => self.core.supervise(now, demand, cfg.delay),
                FbState::Safe if cfg.manual_restart && restart => {
                    self.core.restart_checking_edm(edm_bad);
                }
                FbState::Safe if !cfg.manual_restart && may_leave && !edm_bad.contains(&true) => {
                    self.core.release();
                }
                _ => {}
            }
        }

        let diag = self.core.diag;
        self.core.cause_active = (0..2)
            .any(|k| diag & 1 << k != 0 && raw_at(2 * k) != raw_at(2 * k + 1))
            || (diag & 1 << SECURE_BIT != 0 && secure_on.is_some_and(|[a, b]| a != b))
            || self.core.edm_cause_active(edm_bad);
        let (mon_out, mon_del_out, error) = self.core.outputs();
        MonOutputs {
            mon_out,
            mon_del_out,
            error,
        }
    }
}

impl Mon {
    /// `true` if the last scan, which started in state `before`, left nothing for another
    /// scan with the same inputs and group state to do before [`Mon::delay_ends`]: no event, no
    /// change of state, no discrepancy time running (the logic's quiet scan relies on it).
    pub(crate) fn quiet(&self, before: FbState) -> bool {
        self.core.quiet(before)
            && !(self.pairs.iter().any(PairMonitor::running) || self.secure_pair.running())
    }

    /// In DELAYOUT, when the delayed output goes off (the first scan at or after it is not a
    /// quiet one).
    pub(crate) fn delay_ends(&self) -> Option<SimTime> {
        self.core.delay_ends(self.config.delay)
    }
}

core_accessors!(Mon);
