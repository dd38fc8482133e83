//! What to analyse and how long: the bus, the line noise, the seed, the window, the samples;
//! their limits and their validation.

use crate::rig::RigError;
use asi_master::ConfigError;
use asi_phy::PulseErrorRate;
use asi_phy::SimDuration;

/// The bus to analyse.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BusChoice {
    /// The lab lift's 11 slaves plus `extra` (0..=20) plain I/O modules at its free addresses,
    /// with the whole rig running.
    Lab {
        /// Extra I/O modules.
        extra: u8,
    },
    /// `n` (1..=31) plain standard I/O modules at addresses 1..=n.
    Standard {
        /// Number of slaves.
        n: u8,
    },
    /// 62 A/B I/O modules, 1A..31A and 1B..31B.
    AbPairs,
}

impl BusChoice {
    /// The number of slaves n of the lift thesis' formula.
    pub fn slaves(self) -> u32 {
        match self {
            BusChoice::Lab { extra } => 11 + extra as u32,
            BusChoice::Standard { n } => n as u32,
            BusChoice::AbPairs => 62,
        }
    }

    /// Occupied addresses (LAS slots: an A/B pair shares one).
    pub fn slots(self) -> u32 {
        match self {
            BusChoice::AbPairs => 31,
            other => other.slaves(),
        }
    }

    /// A readable name.
    pub fn describe(self) -> String {
        match self {
            BusChoice::Lab { extra: 0 } => "lab bus (11 slaves)".into(),
            BusChoice::Lab { extra } => format!(
                "lab bus with {extra} extra I/O modules ({} slaves)",
                11 + extra as u32
            ),
            BusChoice::Standard { n } => format!("{n} standard slaves"),
            BusChoice::AbPairs => "62 A/B slaves (31 addresses × A and B)".into(),
        }
    }
}

impl core::str::FromStr for BusChoice {
    type Err = String;

    /// `lab`, `1`..`31` or `62ab`.
    fn from_str(s: &str) -> Result<BusChoice, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "lab" => Ok(BusChoice::Lab { extra: 0 }),
            "62ab" => Ok(BusChoice::AbPairs),
            t => match t.parse::<u32>() {
                Ok(n @ 1..=31) => Ok(BusChoice::Standard { n: n as u8 }),
                Ok(n) => Err(format!(
                    "{n} standard slaves: a bus has 1..31 (62 A/B slaves: 62ab)"
                )),
                Err(_) => Err(format!(
                    "`{s}`: expected lab, a number of standard slaves 1..31, or 62ab"
                )),
            },
        }
    }
}

/// What to analyse and how long.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct TimingOptions {
    /// The bus.
    pub bus: BusChoice,
    /// Probability that a pulse on the line is corrupted (0 ≤ p < 1).
    pub pulse_error_rate: f64,
    /// Seed of the line noise and of the press moments.
    pub seed: u64,
    /// Simulated measurement window of the bus statistics.
    pub duration: SimDuration,
    /// Latency samples of each chain (lab bus only).
    pub samples: u32,
    /// The PLC program timed on the lab bus, if not the built-in one: a Structured Text
    /// program that tells its state, floor, target and calls through the agreed variables.
    pub program: Option<crate::scenario::program::ProgramFile>,
}

impl Default for TimingOptions {
    fn default() -> Self {
        TimingOptions {
            bus: BusChoice::Lab { extra: 0 },
            pulse_error_rate: 0.0,
            seed: 1,
            duration: SimDuration::from_secs(60),
            samples: 100,
            program: None,
        }
    }
}

/// The longest measurement window accepted.
pub const MAX_DURATION: SimDuration = SimDuration::from_secs(3600);
/// The most latency samples accepted.
pub const MAX_SAMPLES: u32 = 10_000;

/// Why the analysis cannot run.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    /// An option out of range.
    #[error("{option} = {value}: {rule}")]
    Option {
        /// The option.
        option: &'static str,
        /// Its value.
        value: String,
        /// What it must be.
        rule: &'static str,
    },
    /// The bus cannot be built.
    #[error("bus: {0}")]
    Bus(#[from] ConfigError),
    /// The rig cannot be built.
    #[error("{0}")]
    Rig(#[from] RigError),
    /// The bus or the lift never got ready (e.g. the error rate is too high).
    #[error("{what} within {within} of simulated time (pulse error rate too high?)")]
    NotReady {
        /// What did not happen.
        what: &'static str,
        /// How long it was given.
        within: SimDuration,
    },
}

/// The pulse error rates the analysis takes: a probability (asi-phy's [`PulseErrorRate`]) below
/// 1, because at 1 no transaction gets through and there is nothing to measure.
pub fn analysable_error_rate(p: f64) -> Result<PulseErrorRate, &'static str> {
    match PulseErrorRate::new(p) {
        Ok(rate) if rate.get() < 1.0 => Ok(rate),
        Ok(_) => Err("must be below 1: at 1 no transaction gets through"),
        Err(_) => Err("must be a probability 0 <= p < 1"),
    }
}

impl TimingOptions {
    /// Checks the options.
    pub fn check(&self) -> Result<(), AnalysisError> {
        let err = |option, value: String, rule| {
            Err(AnalysisError::Option {
                option,
                value,
                rule,
            })
        };
        match self.bus {
            BusChoice::Lab { extra } if extra > 20 => {
                return err(
                    "extra slaves",
                    extra.to_string(),
                    "must be 0..=20 (the addresses the lab leaves free)",
                )
            }
            BusChoice::Standard { n } if !(1..=31).contains(&n) => {
                return err("standard slaves", n.to_string(), "must be 1..=31")
            }
            _ => {}
        }
        if let Err(rule) = analysable_error_rate(self.pulse_error_rate) {
            return err("pulse error rate", self.pulse_error_rate.to_string(), rule);
        }
        if self.duration.is_zero() || self.duration > MAX_DURATION {
            return err(
                "duration",
                self.duration.to_string(),
                "must be more than 0 and at most 1 h",
            );
        }
        if self.samples > MAX_SAMPLES {
            return err("samples", self.samples.to_string(), "must be at most 10000");
        }
        Ok(())
    }
}
