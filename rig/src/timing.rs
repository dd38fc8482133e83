//! `asi-lift timing`: the timing analysis of SPEC §7 for the lab bus, a bus of N standard
//! slaves or 62 A/B slaves, analytic and simulated side by side.
//!
//! **Analytic.** One transaction is request + master pause + response + slave pause (154 µs
//! with the default [`BusTiming`], SPEC §1). The seed's cycle is T = (n + 2) · 154 µs for n
//! slaves (seed 003 §2.1). The model's own cycle (SPEC §2) is one transaction per LAS slot, one
//! management call, and one inclusion call while an address is left to include:
//! (slots + 2) · 154 µs, or (slots + 1) · 154 µs with every address used; an address holding an
//! A and a B slave is one slot serving them in alternate cycles, so each of them sees twice the
//! cycle.
//!
//! **Error model.** The line noise is asi-phy's seeded [`FaultRates::uniform`]`(p)`: each pulse
//! is dropped, flipped, shifted or followed by a spurious pulse with probability p/4 each, drawn
//! independently, so a pulse comes through untouched with probability c = (1 − p/4)⁴. Every
//! single pulse fault fails one of the seven receiver checks (asi-phy's exhaustive test), and a
//! corrupt request gets no answer, so a transaction of m request and s response pulses fails
//! with q = 1 − c^(m+s). A failure is repeated once at once (SPEC §2), so the expected number
//! of repeats per cycle is Σ q over the cycle's transactions that expect an answer, each repeat
//! costing one transaction time; a corrupt response also delays the next request by the
//! asynchronous pause minus the slave pause (18 − 10 = 8 µs, asi-master `bus`). The pulse
//! counts depend on the bits, so the expectation is summed over the telegrams actually sent
//! (the first tries; [`PulseTrain`] counts their pulses), which also gives its variance: the
//! simulated repeat count and mean cycle are compared with it in standard errors.
//!
//! **Simulated.** The bus runs (for the lab bus: the whole rig, lift standing at floor 1 after
//! its initialisation) for the measurement window; every transaction record feeds the
//! statistics: cycle times from one first Data_Exchange of a cycle to the next, per-slave update
//! periods between successful Data_Exchanges, repeats. On the lab bus the handshake word times
//! and the S-7.3 value period come from the devices' and the PLC's word counters, stepped
//! moment by moment.
//!
//! **Latencies** (lab bus). After the window the lift shuttles between floors 1 and 2: at a
//! seeded random moment (0..500 ms after it is ready, so uniform against the 10 ms PLC scan, the
//! bus cycle and the handshake words) a hall button at the other floor is pressed; the call is
//! registered when the PLC program holds it (as target or in FIFO_Patra); the converter's run
//! bit is first seen on the bus in the first intact Data_Exchange to address 7 that carries it.
//! 0.3..1 s after the run bit, STOP is pressed at a random moment: the safety logic's EStopOut
//! drops, and K1 opens after the STOP delay (SPEC §6); the cabin stops at the floor it was
//! heading for, and a cabin request there restarts the STOP circuit for the next sample. So one
//! trip gives one sample of each chain.

use crate::rig::{Rig, RigError};
use crate::scenario::{Action, Scenario};
use asi_bus::lab::{io_bus, CONVERTER};
use asi_bus::Bus;
use asi_master::{
    ConfigError, MasterConfig, ProjectedConfig, ProjectedSlave, TransactionRecord, TxKind,
};
use asi_phy::{
    BusTiming, Call, FaultRates, Nibble, PulseTrain, Request, Response, Select, SimDuration,
    SimTime, SlaveAddr, SlaveCodes,
};
use asi_slaves::devices::{IoModule, AB_MODULE, AC2726};
use asi_slaves::Slave;
use lift_model::{Button, LoadLevel};
use serde::Serialize;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::sync::{Arc, Mutex, MutexGuard};

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
    /// The number of slaves n of the seed's formula.
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
}

impl Default for TimingOptions {
    fn default() -> Self {
        TimingOptions {
            bus: BusChoice::Lab { extra: 0 },
            pulse_error_rate: 0.0,
            seed: 1,
            duration: SimDuration::from_secs(60),
            samples: 100,
        }
    }
}

/// The longest measurement window accepted.
pub const MAX_DURATION: SimDuration = SimDuration::from_secs(3600);
/// The most latency samples accepted.
pub const MAX_SAMPLES: u32 = 10_000;

/// Why the analysis cannot run.
#[derive(Debug, thiserror::Error)]
pub enum TimingError {
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

impl TimingOptions {
    /// Checks the options.
    pub fn check(&self) -> Result<(), TimingError> {
        let err = |option, value: String, rule| {
            Err(TimingError::Option {
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
        let p = self.pulse_error_rate;
        if !(p.is_finite() && (0.0..1.0).contains(&p)) {
            return err(
                "pulse error rate",
                p.to_string(),
                "must be a probability 0 <= p < 1",
            );
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

// ----- the report ---------------------------------------------------------------------------

/// One quantity: analytic value or bound, and the simulated min/mean/max over `samples`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Figure {
    /// The analytic value (a mean where the error model makes it one).
    pub analytic: Option<f64>,
    /// An analytic upper bound (latencies).
    pub bound: Option<f64>,
    /// Simulated minimum.
    pub min: Option<f64>,
    /// Simulated mean.
    pub mean: Option<f64>,
    /// Simulated maximum.
    pub max: Option<f64>,
    /// Number of simulated values.
    pub samples: u64,
}

impl Figure {
    fn analytic(mut self, v: f64) -> Figure {
        self.analytic = Some(v);
        self
    }
    fn bound(mut self, v: f64) -> Figure {
        self.bound = Some(v);
        self
    }
}

/// A histogram: `counts[i]` values in `[lo + i·width, lo + (i + 1)·width)`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Histogram {
    /// Lower edge of the first bin.
    pub lo: f64,
    /// Bin width.
    pub width: f64,
    /// Values per bin.
    pub counts: Vec<u64>,
}

/// Repeats: counted in simulation and expected from the error model.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Repeats {
    /// Immediate repeats in the measured cycles.
    pub count: u64,
    /// Expected from the error model, given the telegrams sent.
    pub expected: f64,
    /// Standard deviation of the count under the error model.
    pub standard_error: f64,
    /// Repeats per cycle.
    pub per_cycle: Figure,
    /// Repeats as a fraction of all transactions.
    pub fraction: Figure,
    /// Transactions that still failed after their repeat.
    pub failed_after_repeat: u64,
    /// Slaves dropped from LAS (failed in consecutive cycles).
    pub dropouts: u64,
}

/// How the error model was evaluated.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ErrorModel {
    /// Probability that a pulse comes through untouched: (1 − p/4)⁴.
    pub pulse_clean: f64,
    /// Mean pulses (request + response) of the transactions that expect an answer.
    pub mean_pulses: f64,
    /// Mean probability that such a transaction fails.
    pub mean_fail_probability: f64,
    /// Standard error of the simulated mean cycle under the model, µs.
    pub cycle_mean_standard_error_us: f64,
}

/// One hall call: press → registered in the PLC → run bit on the bus.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HallSample {
    /// When the button was pressed, s.
    pub pressed_s: f64,
    /// Press → call registered, ms.
    pub registered_ms: f64,
    /// Call registered → run bit first seen on the bus, ms.
    pub run_bit_ms: f64,
}

/// One STOP: press → EStopOut drops → K1 opens.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StopSample {
    /// When STOP was pressed, s.
    pub pressed_s: f64,
    /// Press → EStopOut off, ms.
    pub estop_out_ms: f64,
    /// EStopOut off → K1 open, ms.
    pub k1_open_ms: f64,
}

/// End-to-end latencies on the lab bus, ms.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Latencies {
    /// Hall button press → call registered in the PLC.
    pub press_to_registered_ms: Figure,
    /// Call registered → converter run bit first seen on the bus.
    pub registered_to_run_bit_ms: Figure,
    /// Hall button press → run bit on the bus.
    pub press_to_run_bit_ms: Figure,
    /// STOP pressed → the safety logic's EStopOut off.
    pub stop_to_estop_out_ms: Figure,
    /// EStopOut off → K1 open.
    pub estop_out_to_k1_open_ms: Figure,
    /// STOP pressed → K1 open.
    pub stop_to_k1_open_ms: Figure,
    /// The hall call samples.
    pub hall: Vec<HallSample>,
    /// The STOP samples.
    pub stop: Vec<StopSample>,
    /// Trips the samples did not cause (the Safety-at-Work monitor under line noise), each
    /// reset by the operator; a STOP sample with such a trip is not counted.
    pub operator_resets: u32,
    /// Why sampling ended early, if it did.
    pub incomplete: Option<String>,
}

/// The lab bus's own figures, ms.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LabTiming {
    /// The PLC scan, ms.
    pub plc_scan_ms: f64,
    /// The safety logic's scan, ms.
    pub safety_scan_ms: f64,
    /// The STOP delay of EStopDelOut, ms.
    pub stop_delay_ms: f64,
    /// S-7.3 value period of the current-loop output (7 cycles per value, any channel).
    pub analog_value_ms: Figure,
    /// Refresh of one channel of the two-channel AC2618 (the speed set-point): 14 cycles.
    pub setpoint_refresh_ms: Figure,
    /// Floor station display word (4 handshake steps), per station.
    pub floor_word_ms: Figure,
    /// Cabin display word (7 steps).
    pub cabin_display_word_ms: Figure,
    /// Cabin panel 32-bit word (two halves of 7 steps).
    pub cabin_panel_word_ms: Figure,
    /// End-to-end latencies.
    pub latencies: Latencies,
}

/// The timing analysis of one bus configuration (SPEC §7).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TimingReport {
    /// The bus, in words.
    pub bus: String,
    /// Slaves n (of the seed's formula).
    pub slaves: u32,
    /// LAS slots (addresses in use).
    pub slots: u32,
    /// Whether an inclusion call is part of every cycle (an address is free).
    pub inclusion_call: bool,
    /// Pulse error rate.
    pub pulse_error_rate: f64,
    /// Seed.
    pub seed: u64,
    /// The measurement window, s.
    pub window_s: f64,
    /// Complete cycles measured.
    pub cycles: u64,
    /// Transactions in them.
    pub transactions: u64,
    /// Transaction time (start to start), µs.
    pub transaction_us: Figure,
    /// The seed's cycle T = (n + 2) · 154 µs.
    pub seed_cycle_us: f64,
    /// Cycle time: analytic = the model's formula (plus the expected repeats with errors).
    pub cycle_us: Figure,
    /// Cycle times, µs.
    pub cycle_histogram: Histogram,
    /// Time between successive successful Data_Exchanges with one slave, µs.
    pub slave_update_us: Figure,
    /// Repeats and drop-outs.
    pub repeats: Repeats,
    /// The error model's numbers (with a pulse error rate).
    pub error_model: Option<ErrorModel>,
    /// The lab bus's handshakes and latencies.
    pub lab: Option<LabTiming>,
}

// ----- statistics from the trace ------------------------------------------------------------

#[derive(Clone, Copy, Debug, Default)]
struct Summary {
    n: u64,
    min: f64,
    max: f64,
    sum: f64,
}

impl Summary {
    fn add(&mut self, x: f64) {
        if self.n == 0 || x < self.min {
            self.min = x;
        }
        if self.n == 0 || x > self.max {
            self.max = x;
        }
        self.sum += x;
        self.n += 1;
    }

    fn merge(&mut self, o: &Summary) {
        if o.n == 0 {
            return;
        }
        if self.n == 0 {
            *self = *o;
            return;
        }
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
        self.sum += o.sum;
        self.n += o.n;
    }

    fn figure(&self, scale: f64) -> Figure {
        if self.n == 0 {
            return Figure::default();
        }
        Figure {
            min: Some(self.min * scale),
            mean: Some(self.sum / self.n as f64 * scale),
            max: Some(self.max * scale),
            samples: self.n,
            ..Figure::default()
        }
    }
}

/// Expectations of the error model, summed over first tries.
#[derive(Clone, Copy, Debug, Default)]
struct Expect {
    repeats: f64,
    repeats_var: f64,
    /// Expected extra time over the clean transaction time, ns.
    extra_ns: f64,
    extra_var: f64,
    /// Σ q² over Data_Exchanges (both tries failing), and their count.
    dx_q2: f64,
    dx: u64,
    /// Σ (m + s) and Σ q over transactions that expect an answer, and their count.
    pulses: f64,
    q: f64,
    answered: u64,
}

impl Expect {
    fn add(&mut self, o: &Expect) {
        self.repeats += o.repeats;
        self.repeats_var += o.repeats_var;
        self.extra_ns += o.extra_ns;
        self.extra_var += o.extra_var;
        self.dx_q2 += o.dx_q2;
        self.dx += o.dx;
        self.pulses += o.pulses;
        self.q += o.q;
        self.answered += o.answered;
    }
}

/// The statistics fed by every transaction record.
#[derive(Debug)]
struct Collector {
    half_bit: SimDuration,
    tx_ns: f64,
    delay_ns: f64,
    clean: f64,
    converter: Option<u8>,
    active: bool,
    last_kind: Option<TxKind>,
    prev_start: Option<SimTime>,
    cycle_start: Option<SimTime>,
    pending: Option<(TransactionRecord, bool)>,
    responses: HashMap<u16, u32>,
    response_pulses: Summary,
    // The open cycle.
    cur: Expect,
    cur_first: u64,
    cur_repeats: u64,
    // Committed complete cycles.
    cycles: Vec<u64>,
    expect: Expect,
    first_tries: u64,
    repeats: u64,
    spacing: Summary,
    last_ok: HashMap<(u8, bool), SimTime>,
    update: Summary,
    // The converter's run bit as the slave last took it, and its rising edges on the bus.
    run: bool,
    run_rises: Vec<SimTime>,
}

impl Collector {
    fn new(timing: &BusTiming, pulse_error_rate: f64, converter: Option<u8>) -> Collector {
        let r = pulse_error_rate / 4.0;
        Collector {
            half_bit: timing.half_bit(),
            tx_ns: timing.transaction().as_nanos() as f64,
            delay_ns: timing
                .async_pause()
                .saturating_sub(timing.slave_pause())
                .as_nanos() as f64,
            clean: (1.0 - r).powi(4),
            converter,
            active: false,
            last_kind: None,
            prev_start: None,
            cycle_start: None,
            pending: None,
            responses: HashMap::new(),
            response_pulses: Summary::default(),
            cur: Expect::default(),
            cur_first: 0,
            cur_repeats: 0,
            cycles: Vec::new(),
            expect: Expect::default(),
            first_tries: 0,
            repeats: 0,
            spacing: Summary::default(),
            last_ok: HashMap::new(),
            update: Summary::default(),
            run: false,
            run_rises: Vec::new(),
        }
    }

    fn start_window(&mut self) {
        self.active = true;
        self.prev_start = None;
        self.cycle_start = None;
        self.pending = None;
        self.last_ok.clear();
    }

    fn end_window(&mut self) {
        self.active = false;
        self.pending = None;
    }

    fn record(&mut self, r: &TransactionRecord) {
        self.watch_converter(r);
        if let Some((p, in_cycle)) = self.pending.take() {
            self.resolve(&p, r.repeat.then_some(r), in_cycle);
        }
        let boundary = r.kind == TxKind::DataExchange
            && !r.repeat
            && self.last_kind.is_some_and(|k| k != TxKind::DataExchange);
        self.last_kind = Some(r.kind);
        if !self.active {
            return;
        }
        if boundary {
            if let Some(s) = self.cycle_start {
                self.cycles.push((r.start - s).as_nanos());
                self.expect.add(&self.cur);
                self.first_tries += self.cur_first;
                self.repeats += self.cur_repeats;
            }
            self.cycle_start = Some(r.start);
            self.cur = Expect::default();
            self.cur_first = 0;
            self.cur_repeats = 0;
        }
        if let Some(p) = self.prev_start {
            self.spacing.add((r.start - p).as_nanos() as f64);
        }
        self.prev_start = Some(r.start);
        if r.repeat {
            self.cur_repeats += 1;
        } else {
            self.cur_first += 1;
            self.pending = Some((*r, self.cycle_start.is_some()));
        }
        let exchange = r.kind == TxKind::DataExchange && r.response.is_some();
        if let (Call::DataExchange { address, .. }, true) = (r.request.call(), exchange) {
            let b = r.ab && r.request.ab_payload().is_some_and(|(s, _)| s == Select::B);
            if let Some(last) = self.last_ok.insert((address.get(), b), r.start) {
                self.update.add((r.start - last).as_nanos() as f64);
            }
        }
    }

    fn watch_converter(&mut self, r: &TransactionRecord) {
        let Some(conv) = self.converter else {
            return;
        };
        if let Call::DataExchange { address, data } = r.request.call() {
            if address.get() == conv && r.request_failed.is_empty() {
                let run = data.bit(0);
                if run && !self.run {
                    self.run_rises.push(r.start);
                }
                self.run = run;
            }
        }
    }

    fn request_pulses(&self, q: Request) -> u32 {
        PulseTrain::request(q, SimTime::ZERO, self.half_bit).len()
    }

    fn response_pulses_of(&self, r: Response) -> u32 {
        PulseTrain::response(r, SimTime::ZERO, self.half_bit).len()
    }

    /// Adds the error model's expectation for first try `p`; `repeat` is the record after it
    /// if that is its repeat.
    fn resolve(
        &mut self,
        p: &TransactionRecord,
        repeat: Option<&TransactionRecord>,
        in_cycle: bool,
    ) {
        let bits = p.request.bits();
        let known = p
            .response
            .or_else(|| repeat.and_then(|r| r.response))
            .map(|r| self.response_pulses_of(r));
        if let Some(s) = known {
            self.responses.insert(bits, s);
            self.response_pulses.add(s as f64);
        }
        // A first try that failed without a repeat was a probe answered by silence, which is
        // never repeated: it adds nothing.
        let s = match (known, p.response.is_some() || repeat.is_some()) {
            (Some(s), _) => s,
            (None, true) => self.responses.get(&bits).copied().unwrap_or_else(|| {
                if self.response_pulses.n > 0 {
                    (self.response_pulses.sum / self.response_pulses.n as f64).round() as u32
                } else {
                    12
                }
            }),
            (None, false) => return,
        };
        if !in_cycle {
            return;
        }
        let m = self.request_pulses(p.request);
        let a = 1.0 - self.clean.powi(m as i32);
        let rb = (1.0 - a) * (1.0 - self.clean.powi(s as i32));
        let q = a + rb;
        let (t, d) = (self.tx_ns, self.delay_ns);
        // Extra time X = t·F + d·(D1 + F·D2): F the first try fails (q), D1 its response was
        // corrupt (rb, implies F), D2 the repeat's response was corrupt (rb).
        let mean = t * q + d * rb * (1.0 + q);
        let sq = a * ((1.0 - rb) * t * t + rb * (t + d) * (t + d))
            + rb * ((1.0 - rb) * (t + d) * (t + d) + rb * (t + 2.0 * d) * (t + 2.0 * d));
        let e = &mut self.cur;
        e.repeats += q;
        e.repeats_var += q * (1.0 - q);
        e.extra_ns += mean;
        e.extra_var += (sq - mean * mean).max(0.0);
        e.pulses += (m + s) as f64;
        e.q += q;
        e.answered += 1;
        if matches!(p.request.call(), Call::DataExchange { .. }) {
            e.dx_q2 += q * q;
            e.dx += 1;
        }
    }
}

fn lock(c: &Mutex<Collector>) -> MutexGuard<'_, Collector> {
    c.lock().unwrap_or_else(|e| e.into_inner())
}

fn histogram(values: &[f64], min_width: f64, bins: usize) -> Histogram {
    let Some(lo) = values.iter().copied().reduce(f64::min) else {
        return Histogram::default();
    };
    let hi = values.iter().copied().fold(lo, f64::max);
    if hi == lo {
        // A single value (a bus without errors) in the middle of a few empty bins.
        let mut counts = vec![0u64; 11];
        counts[5] = values.len() as u64;
        return Histogram {
            lo: lo - 5.5 * min_width,
            width: min_width,
            counts,
        };
    }
    let width = ((hi - lo) / bins.max(1) as f64).max(min_width);
    let n = ((hi - lo) / width).floor() as usize + 1;
    let mut counts = vec![0u64; n];
    for v in values {
        let i = (((v - lo) / width).floor() as usize).min(n - 1);
        counts[i] += 1;
    }
    Histogram { lo, width, counts }
}

// ----- buses --------------------------------------------------------------------------------

/// 62 A/B I/O modules, all projected (as in asi-bus's cycle-time test).
fn ab_bus() -> Result<Bus, ConfigError> {
    let b_codes = SlaveCodes {
        id1: Nibble::from_low_bits(0xF),
        ..AB_MODULE
    };
    let mut projected = Vec::new();
    let mut slaves = Vec::new();
    for n in 1..=31u8 {
        let address = asi_phy::Address::new(n).ok_or_else(|| ConfigError::Slave {
            name: format!("address {n}"),
            why: "out of range".into(),
        })?;
        for (sel, codes) in [(SlaveAddr::a(n), AB_MODULE), (SlaveAddr::b(n), b_codes)] {
            let Some(sel) = sel else { continue };
            projected.push(ProjectedSlave {
                addr: sel,
                codes,
                parameter: Nibble::from_low_bits(7),
            });
            slaves.push(Slave::new(
                format!("{sel}"),
                address,
                codes,
                Box::new(IoModule::new()),
            ));
        }
    }
    Bus::new(
        MasterConfig::default(),
        ProjectedConfig::new(projected)?,
        slaves,
    )
}

/// How long a bus or the rig may take to get ready.
const READY_WITHIN: SimDuration = SimDuration::from_secs(60);

fn run_plain(opts: &TimingOptions) -> Result<(Collector, BusWindow), TimingError> {
    let mut bus = match opts.bus {
        BusChoice::Standard { n } => io_bus(n, AC2726)?,
        _ => ab_bus()?,
    };
    if opts.pulse_error_rate > 0.0 {
        bus.set_line_faults(opts.seed, FaultRates::uniform(opts.pulse_error_rate));
    }
    let shared = Arc::new(Mutex::new(Collector::new(
        bus.timing(),
        opts.pulse_error_rate,
        None,
    )));
    let sink = Arc::clone(&shared);
    bus.set_trace_callback(Some(Box::new(move |r| lock(&sink).record(r))));
    let want = opts.bus.slaves();
    let deadline = SimTime::ZERO + READY_WITHIN;
    let mut t = SimTime::ZERO;
    while !(bus.is_running() && bus.master().las().len() == want) {
        if t >= deadline {
            return Err(TimingError::NotReady {
                what: "the master did not activate every slave",
                within: READY_WITHIN,
            });
        }
        t += SimDuration::from_millis(10);
        bus.advance_to(t);
    }
    // A few cycles of normal operation before measuring.
    let start = t + SimDuration::from_millis(50);
    bus.advance_to(start);
    lock(&shared).start_window();
    let before = bus.stats();
    bus.advance_to(start + opts.duration);
    lock(&shared).end_window();
    let after = bus.stats();
    bus.set_trace_callback(None);
    drop(bus);
    let collector = take(&shared);
    Ok((
        collector,
        BusWindow {
            failed_after_repeat: after.failed_after_repeat - before.failed_after_repeat,
            dropouts: after.dropouts - before.dropouts,
        },
    ))
}

/// The statistics out of their shared place (the bus holds a clone of it until its trace
/// callback is removed).
fn take(shared: &Mutex<Collector>) -> Collector {
    std::mem::replace(
        &mut *lock(shared),
        Collector::new(&BusTiming::default(), 0.0, None),
    )
}

/// What the bus statistics say about the window.
#[derive(Clone, Copy, Debug, Default)]
struct BusWindow {
    failed_after_repeat: u64,
    dropouts: u64,
}

// ----- the lab rig --------------------------------------------------------------------------

/// Counts words (or values) as a counter increments; keeps the intervals between increments
/// `stride` apart.
#[derive(Clone, Debug, Default)]
struct Ticker {
    count: Option<u64>,
    times: Vec<SimTime>,
    stride: usize,
    intervals: Summary,
}

impl Ticker {
    fn new(stride: usize) -> Ticker {
        Ticker {
            stride: stride.max(1),
            ..Ticker::default()
        }
    }

    fn poll(&mut self, count: u64, now: SimTime) {
        match self.count {
            None => self.count = Some(count),
            Some(c) if c != count => {
                // Only single steps are timed: a reset or a jump restarts the timing.
                if count == c + 1 {
                    self.times.push(now);
                    let n = self.times.len();
                    if n > self.stride {
                        let d = now - self.times[n - 1 - self.stride];
                        self.intervals.add(d.as_nanos() as f64);
                    }
                } else {
                    self.times.clear();
                }
                self.count = Some(count);
            }
            _ => {}
        }
    }
}

/// The lift stands at `floor`, ready to depart: program at the floor without a fault, drive
/// powered and not moving, no STOP demand.
fn ready_at(rig: &Rig, floor: u8) -> bool {
    let p = rig.plc().program();
    let d = p.outputs().display;
    p.is_initialised()
        && !d.moving
        && !d.fault
        && p.current_floor() == floor
        && p.target() == floor
        && !p.outputs().run
        && rig.lift().velocity_mm_s() == 0.0
        && rig.lift().k1_closed()
        && rig.lift().converter_ready()
        && rig.estop_out()
}

/// Steps `rig` until `cond` holds (checked now and after every moment), at most `limit`.
fn wait_until(
    rig: &mut Rig,
    limit: SimDuration,
    mut cond: impl FnMut(&Rig) -> bool,
) -> Option<SimTime> {
    if cond(rig) {
        return Some(rig.now());
    }
    let deadline = rig.now() + limit;
    while let Some(t) = rig.step_until(deadline) {
        if cond(rig) {
            return Some(t);
        }
    }
    None
}

/// How long the operator takes to press the reset after an unexpected trip.
const OPERATOR_REACTION: SimDuration = SimDuration::from_millis(100);

/// [`wait_until`], with the operator resetting a trip that opens K1 without a STOP demand
/// (the Safety-at-Work monitor under line noise); counts the resets in `resets`. Before the
/// program is initialised, only a trip after K1 had closed in this wait counts (at power-on K1
/// is open until the operator's first reset).
fn wait_resetting(
    rig: &mut Rig,
    limit: SimDuration,
    resets: &mut u32,
    mut cond: impl FnMut(&Rig) -> bool,
) -> Option<SimTime> {
    let deadline = rig.now() + limit;
    let mut reset_at: Option<SimTime> = None;
    let mut powered = false;
    loop {
        if cond(rig) {
            return Some(rig.now());
        }
        powered |= rig.lift().k1_closed();
        let tripped = (rig.plc().program().is_initialised() || powered)
            && rig.estop_out()
            && !rig.lift().k1_closed();
        if tripped && reset_at.is_none_or(|t| rig.now() >= t + SimDuration::from_secs(1)) {
            let at = rig.now() + OPERATOR_REACTION;
            rig.schedule(at, Action::Reset);
            reset_at = Some(at);
            *resets += 1;
        }
        rig.step_until(deadline)?;
    }
}

/// SplitMix64: the seeded source of press moments.
#[derive(Clone, Debug)]
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A uniform duration in [0, span).
    fn below(&mut self, span: SimDuration) -> SimDuration {
        match span.as_nanos() {
            0 => SimDuration::ZERO,
            n => SimDuration::from_nanos(self.next() % n),
        }
    }
}

fn ms(d: SimDuration) -> f64 {
    d.as_nanos() as f64 / 1e6
}

/// How long a wait in the latency sampling may take before sampling gives up.
const STEP_LIMIT: SimDuration = SimDuration::from_secs(60);
const HOLD: SimDuration = SimDuration::from_millis(300);

/// The lab rig: window statistics, then latency samples.
fn run_lab(
    opts: &TimingOptions,
    extra: u8,
) -> Result<(Collector, BusWindow, LabTiming), TimingError> {
    let mut sc = Scenario::defaults();
    sc.name = "timing".into();
    sc.seed = opts.seed;
    sc.duration = SimDuration::from_secs(10_000_000);
    sc.start_mm = 0.0;
    sc.load = LoadLevel::Empty;
    sc.door_closed = true;
    sc.pulse_error_rate = opts.pulse_error_rate;
    sc.extra_slaves = extra;
    let plc_scan = sc.plc_scan;
    let mut rig = Rig::new(sc)?;
    let timing = *rig.lab().bus.timing();
    let shared = Arc::new(Mutex::new(Collector::new(
        &timing,
        opts.pulse_error_rate,
        Some(CONVERTER),
    )));
    let sink = Arc::clone(&shared);
    rig.lab_mut()
        .bus
        .set_trace_callback(Some(Box::new(move |r| lock(&sink).record(r))));

    // The Safety-at-Work monitor may trip under line noise during initialisation too: the
    // operator resets it, as during the latency samples.
    let mut init_resets = 0;
    if wait_resetting(&mut rig, READY_WITHIN, &mut init_resets, |r| ready_at(r, 1)).is_none() {
        return Err(TimingError::NotReady {
            what: "the lift did not initialise at floor 1",
            within: READY_WITHIN,
        });
    }

    // The measurement window: the lift stands; the handshakes and the bus run on.
    let start = rig.now();
    lock(&shared).start_window();
    let before = rig.lab().bus.stats();
    let mut floors: Vec<Ticker> = (0..4).map(|_| Ticker::new(1)).collect();
    let mut display = Ticker::new(1);
    let mut panel = Ticker::new(1);
    let mut analog = Ticker::new(1);
    let mut setpoint = Ticker::new(2);
    let poll = |rig: &Rig,
                floors: &mut [Ticker],
                display: &mut Ticker,
                panel: &mut Ticker,
                analog: &mut Ticker,
                setpoint: &mut Ticker| {
        let now = rig.now();
        let lab = rig.lab();
        for (i, t) in floors.iter_mut().enumerate() {
            if let Some(s) = lab.floor(i as u8 + 1) {
                let w = s.engine().words();
                t.poll(w.good() as u64 + w.bad() as u64, now);
            }
        }
        if let Some(d) = lab.cabin_display() {
            let w = d.engine().words();
            display.poll(w.good() as u64 + w.bad() as u64, now);
        }
        let w = rig.plc().cabin_panel().words();
        panel.poll(w.good() as u64 + w.bad() as u64, now);
        if let Some(a) = lab.analog_output() {
            analog.poll(a.values_received() as u64, now);
            setpoint.poll(a.values_received() as u64, now);
        }
    };
    poll(
        &rig,
        &mut floors,
        &mut display,
        &mut panel,
        &mut analog,
        &mut setpoint,
    );
    while rig.step_until(start + opts.duration).is_some() {
        poll(
            &rig,
            &mut floors,
            &mut display,
            &mut panel,
            &mut analog,
            &mut setpoint,
        );
    }
    lock(&shared).end_window();
    let after = rig.lab().bus.stats();

    let mut floor_words = Summary::default();
    for t in &floors {
        floor_words.merge(&t.intervals);
    }
    let safety_cfg = safety::LiftSafetyConfig::default();
    let mut latencies = sample_latencies(&mut rig, &shared, opts);
    latencies.operator_resets += init_resets;
    rig.lab_mut().bus.set_trace_callback(None);
    drop(rig);
    let collector = take(&shared);
    let lab = LabTiming {
        plc_scan_ms: ms(plc_scan),
        safety_scan_ms: ms(safety::SAFETY_SCAN_PERIOD),
        stop_delay_ms: ms(safety_cfg.estop_delay),
        analog_value_ms: analog.intervals.figure(1e-6),
        setpoint_refresh_ms: setpoint.intervals.figure(1e-6),
        floor_word_ms: floor_words.figure(1e-6),
        cabin_display_word_ms: display.intervals.figure(1e-6),
        cabin_panel_word_ms: panel.intervals.figure(1e-6),
        latencies,
    };
    Ok((
        collector,
        BusWindow {
            failed_after_repeat: after.failed_after_repeat - before.failed_after_repeat,
            dropouts: after.dropouts - before.dropouts,
        },
        lab,
    ))
}

/// The program has arrived at `floor` (it stands there, possibly in the STOP fault).
fn arrived(rig: &Rig, floor: u8) -> bool {
    let p = rig.plc().program();
    p.current_floor() == floor && matches!(p.state_name(), "at floor" | "STOP fault")
}

/// Notes the first moment the program is seen arrived at `floor`.
fn track(rig: &Rig, floor: u8, arrival: &mut Option<SimTime>) {
    if arrival.is_none() && arrived(rig, floor) {
        *arrival = Some(rig.now());
    }
}

/// Shuttles the lift between floors 1 and 2 and times a hall call and a STOP on every trip.
fn sample_latencies(rig: &mut Rig, shared: &Mutex<Collector>, opts: &TimingOptions) -> Latencies {
    let mut rng = Rng(opts.seed ^ 0x7469_6D69_6E67);
    let dwell = rig.plc().program().config().dwell;
    let stop_delay = safety::LiftSafetyConfig::default().estop_delay;
    let mut out = Latencies::default();
    let mut here = 1u8;
    // When the program last arrived at a floor: it departs no earlier than a dwell later.
    let mut arrival = rig.plc().program().initialised_at();
    let fail = |out: &mut Latencies, k: usize, what: &str| {
        out.incomplete = Some(format!(
            "sampling stopped after {k} samples: {what} not seen within {STEP_LIMIT}"
        ));
    };
    for k in 0..opts.samples as usize {
        let there = if here == 1 { 2 } else { 1 };
        let mut resets = 0;
        let ready = wait_resetting(rig, STEP_LIMIT, &mut resets, |r| {
            track(r, here, &mut arrival);
            ready_at(r, here)
        });
        out.operator_resets += resets;
        let Some(ready) = ready else {
            fail(&mut out, k, "the lift ready at its floor");
            break;
        };
        let earliest = ready.max(arrival.unwrap_or(ready) + dwell) + SimDuration::from_millis(100);
        let press = earliest + rng.below(SimDuration::from_millis(500));
        let button = if there == 1 {
            Button::HallUp(1)
        } else {
            Button::HallDown(there)
        };
        rig.schedule(press, Action::Press { button, hold: HOLD });
        // Registered: the program holds the call (as its target or in FIFO_Patra).
        let mut resets = 0;
        let registered = wait_resetting(rig, STEP_LIMIT, &mut resets, |r| {
            let p = r.plc().program();
            r.now() >= press && (p.target() == there || p.fifo_hall().contains(&there))
        });
        let rise = registered.and_then(|registered| {
            wait_resetting(rig, STEP_LIMIT, &mut resets, |_| {
                lock(shared).run_rises.iter().any(|&t| t >= registered)
            })?;
            lock(shared)
                .run_rises
                .iter()
                .copied()
                .find(|&t| t >= registered)
        });
        out.operator_resets += resets;
        let (Some(registered), Some(rise)) = (registered, rise) else {
            fail(
                &mut out,
                k,
                "the hall call registered and the run bit on the bus",
            );
            break;
        };
        // A trip reset on the way held the departure: that sample is not counted.
        if resets == 0 {
            out.hall.push(HallSample {
                pressed_s: press.as_secs_f64(),
                registered_ms: ms(registered - press),
                run_bit_ms: ms(rise - registered),
            });
        }
        arrival = None;

        // STOP during the trip.
        let stop = rise.max(rig.now())
            + SimDuration::from_millis(300)
            + rng.below(SimDuration::from_millis(700));
        rig.schedule(
            stop,
            Action::Press {
                button: Button::Stop,
                hold: HOLD,
            },
        );
        let estop = wait_until(rig, STEP_LIMIT, |r| {
            track(r, there, &mut arrival);
            r.now() >= stop && !r.estop_out()
        });
        let Some(estop) = estop else {
            fail(&mut out, k, "EStopOut off after STOP");
            break;
        };
        // K1 opens when the STOP delay has run out. Opening earlier is a trip the sample did
        // not cause (the Safety-at-Work monitor under line noise): the operator resets it, K1
        // closes again until the delay runs out, and the sample is not counted.
        let mut spoiled = false;
        let k1 = loop {
            let Some(k1) = wait_until(rig, STEP_LIMIT, |r| {
                track(r, there, &mut arrival);
                !r.lift().k1_closed()
            }) else {
                break None;
            };
            if k1 - estop + safety::SAFETY_SCAN_PERIOD >= stop_delay {
                break Some(k1);
            }
            spoiled = true;
            out.operator_resets += 1;
            rig.schedule(k1 + OPERATOR_REACTION, Action::Reset);
            // The STOP delay may run out before the reset takes effect: then K1 stays open.
            let delay_over = estop + stop_delay + safety::SAFETY_SCAN_PERIOD;
            let closed = wait_until(rig, STEP_LIMIT, |r| {
                track(r, there, &mut arrival);
                r.lift().k1_closed() || r.now() >= delay_over
            });
            match closed {
                None => break None,
                Some(t) if !rig.lift().k1_closed() => break Some(t),
                Some(_) => {}
            }
        };
        let Some(k1) = k1 else {
            fail(&mut out, k, "K1 open after STOP");
            break;
        };
        if !spoiled {
            out.stop.push(StopSample {
                pressed_s: stop.as_secs_f64(),
                estop_out_ms: ms(estop - stop),
                k1_open_ms: ms(k1 - estop),
            });
        }
        // The cabin stands at the floor it was heading for (or, after a trip, held short of
        // it): a cabin request for that floor restarts the STOP circuit and service resumes.
        let rest = wait_until(rig, STEP_LIMIT, |r| {
            track(r, there, &mut arrival);
            r.lift().velocity_mm_s() == 0.0
        });
        if rest.is_none() {
            fail(&mut out, k, "the cabin at rest after STOP");
            break;
        }
        rig.schedule(
            rig.now() + OPERATOR_REACTION,
            Action::Press {
                button: Button::Cabin(there),
                hold: HOLD,
            },
        );
        here = there;
    }
    let hall_reg: Vec<f64> = out.hall.iter().map(|s| s.registered_ms).collect();
    let hall_run: Vec<f64> = out.hall.iter().map(|s| s.run_bit_ms).collect();
    let hall_all: Vec<f64> = out
        .hall
        .iter()
        .map(|s| s.registered_ms + s.run_bit_ms)
        .collect();
    let stop_e: Vec<f64> = out.stop.iter().map(|s| s.estop_out_ms).collect();
    let stop_k: Vec<f64> = out.stop.iter().map(|s| s.k1_open_ms).collect();
    let stop_all: Vec<f64> = out
        .stop
        .iter()
        .map(|s| s.estop_out_ms + s.k1_open_ms)
        .collect();
    out.press_to_registered_ms = figure_of(&hall_reg);
    out.registered_to_run_bit_ms = figure_of(&hall_run);
    out.press_to_run_bit_ms = figure_of(&hall_all);
    out.stop_to_estop_out_ms = figure_of(&stop_e);
    out.estop_out_to_k1_open_ms = figure_of(&stop_k);
    out.stop_to_k1_open_ms = figure_of(&stop_all);
    out
}

fn figure_of(values: &[f64]) -> Figure {
    let mut s = Summary::default();
    for v in values {
        s.add(*v);
    }
    s.figure(1.0)
}

// ----- the analysis -------------------------------------------------------------------------

/// Runs the analysis for `opts`.
pub fn analyse(opts: &TimingOptions) -> Result<TimingReport, TimingError> {
    opts.check()?;
    let timing = BusTiming::default();
    let (c, window, lab) = match opts.bus {
        BusChoice::Lab { extra } => {
            let (c, w, lab) = run_lab(opts, extra)?;
            (c, w, Some(lab))
        }
        _ => {
            let (c, w) = run_plain(opts)?;
            (c, w, None)
        }
    };
    let tx_us = timing.transaction().as_micros_f64();
    let n = opts.bus.slaves();
    let slots = opts.bus.slots();
    let inclusion = slots < 31;
    let model_us = (slots + 1 + inclusion as u32) as f64 * tx_us;
    let per_slave = if opts.bus == BusChoice::AbPairs {
        2.0
    } else {
        1.0
    };
    let cycles = c.cycles.len() as u64;
    let cycle_values: Vec<f64> = c.cycles.iter().map(|&ns| ns as f64 / 1e3).collect();
    let mut cycle_sum = Summary::default();
    for v in &cycle_values {
        cycle_sum.add(*v);
    }
    let e = c.expect;
    let noisy = opts.pulse_error_rate > 0.0;
    // The clean cycles' transactions (the model's formula, unless slaves dropped out) plus
    // the error model's expected extra time.
    let expected_cycle = if cycles > 0 {
        (c.first_tries as f64 * tx_us * 1e3 + e.extra_ns) / cycles as f64 / 1e3
    } else {
        model_us
    };
    // Both tries failing leaves a Data_Exchange without update.
    let both_fail = if e.dx > 0 { e.dx_q2 / e.dx as f64 } else { 0.0 };
    let transactions = c.first_tries + c.repeats;
    let repeats = Repeats {
        count: c.repeats,
        expected: e.repeats,
        standard_error: e.repeats_var.sqrt(),
        per_cycle: Figure {
            mean: (cycles > 0).then(|| c.repeats as f64 / cycles as f64),
            samples: cycles,
            ..Figure::default()
        }
        .analytic(if cycles > 0 {
            e.repeats / cycles as f64
        } else {
            0.0
        }),
        fraction: Figure {
            mean: (transactions > 0).then(|| c.repeats as f64 / transactions as f64),
            samples: transactions,
            ..Figure::default()
        }
        .analytic(if c.first_tries > 0 {
            e.repeats / (c.first_tries as f64 + e.repeats)
        } else {
            0.0
        }),
        failed_after_repeat: window.failed_after_repeat,
        dropouts: window.dropouts,
    };
    let error_model = noisy.then(|| ErrorModel {
        pulse_clean: c.clean,
        mean_pulses: if e.answered > 0 {
            e.pulses / e.answered as f64
        } else {
            0.0
        },
        mean_fail_probability: if e.answered > 0 {
            e.q / e.answered as f64
        } else {
            0.0
        },
        cycle_mean_standard_error_us: if cycles > 0 {
            e.extra_var.sqrt() / cycles as f64 / 1e3
        } else {
            0.0
        },
    });
    let lab = lab.map(|mut l| {
        let t_ms = expected_cycle / 1e3;
        let tx_ms = tx_us / 1e3;
        let scan = l.plc_scan_ms;
        // A handshake step: the PLC's answer leaves in the next Data_Exchange with the slave
        // (within one cycle), the slave's next code comes back in the one after and reaches
        // the image at its end; the PLC sees it in the next scan. While 2T + 154 µs ≤ scan
        // every step takes one scan; beyond, a fraction (2T + 154 µs − scan)/T of them two.
        let late = ((2.0 * t_ms + tx_ms - scan) / t_ms).clamp(0.0, 1.0);
        let step = scan * (1.0 + late);
        l.analog_value_ms = l.analog_value_ms.analytic(7.0 * t_ms / (1.0 - both_fail));
        l.setpoint_refresh_ms = l
            .setpoint_refresh_ms
            .analytic(14.0 * t_ms / (1.0 - both_fail));
        l.floor_word_ms = l.floor_word_ms.analytic(4.0 * step);
        l.cabin_display_word_ms = l.cabin_display_word_ms.analytic(7.0 * step);
        l.cabin_panel_word_ms = l.cabin_panel_word_ms.analytic(14.0 * step);
        // The bounds hold without line errors (a repeat or a lost exchange adds to them).
        let cycle_ms = model_us / 1e3;
        let step_max = scan * ((2.0 * cycle_ms + tx_ms) / scan).ceil();
        let lat = &mut l.latencies;
        // Pressed just after the floor slave finished a word, the call waits for the next
        // word (4 steps) and is reported as one extra step: its first code reaches the image
        // one cycle later and the PLC's next scan answers it, then one step per scan.
        let reg = cycle_ms + tx_ms + scan + 4.0 * step_max;
        lat.press_to_registered_ms = lat.press_to_registered_ms.clone().bound(reg);
        // The run bit leaves in the next Data_Exchange with the converter: within one cycle.
        lat.registered_to_run_bit_ms = lat.registered_to_run_bit_ms.clone().bound(cycle_ms);
        lat.press_to_run_bit_ms = lat.press_to_run_bit_ms.clone().bound(reg + cycle_ms);
        // STOP is read by the next safety scan; EStopDelOut follows after the STOP delay.
        let safety_scan = l.safety_scan_ms;
        lat.stop_to_estop_out_ms = lat.stop_to_estop_out_ms.clone().bound(safety_scan);
        lat.estop_out_to_k1_open_ms = lat
            .estop_out_to_k1_open_ms
            .clone()
            .analytic(l.stop_delay_ms);
        lat.stop_to_k1_open_ms = lat
            .stop_to_k1_open_ms
            .clone()
            .bound(l.stop_delay_ms + safety_scan);
        l
    });
    Ok(TimingReport {
        bus: opts.bus.describe(),
        slaves: n,
        slots,
        inclusion_call: inclusion,
        pulse_error_rate: opts.pulse_error_rate,
        seed: opts.seed,
        window_s: opts.duration.as_secs_f64(),
        cycles,
        transactions,
        transaction_us: c.spacing.figure(1e-3).analytic(tx_us),
        seed_cycle_us: (n + 2) as f64 * tx_us,
        cycle_us: cycle_sum.figure(1.0).analytic(expected_cycle),
        cycle_histogram: histogram(&cycle_values, 1.0, 40),
        slave_update_us: c
            .update
            .figure(1e-3)
            .analytic(per_slave * expected_cycle / (1.0 - both_fail)),
        repeats,
        error_model,
        lab,
    })
}

// ----- output -------------------------------------------------------------------------------

fn num(v: Option<f64>, decimals: usize) -> String {
    match v {
        Some(x) => format!("{x:.decimals$}"),
        None => "-".into(),
    }
}

impl TimingReport {
    /// The report as an aligned text table.
    pub fn to_text(&self) -> String {
        let mut rows: Vec<[String; 6]> = Vec::new();
        let mut row = |q: &str, f: &Figure, unit: &str, d: usize| {
            let analytic = match (f.analytic, f.bound) {
                (Some(a), _) => num(Some(a), d),
                (None, Some(b)) => format!("≤ {}", num(Some(b), d)),
                _ => "-".into(),
            };
            rows.push([
                q.into(),
                analytic,
                num(f.min, d),
                num(f.mean, d),
                num(f.max, d),
                unit.into(),
            ]);
        };
        row("transaction", &self.transaction_us, "µs", 1);
        row(
            &format!("cycle, seed: T = (n + 2) · 154 µs, n = {}", self.slaves),
            &Figure::default().analytic(self.seed_cycle_us),
            "µs",
            1,
        );
        let formula = if self.inclusion_call { 2 } else { 1 };
        row(
            &format!(
                "cycle, model: ({} slots + {formula}) · 154 µs{}",
                self.slots,
                if self.pulse_error_rate > 0.0 {
                    " + repeats"
                } else {
                    ""
                }
            ),
            &self.cycle_us,
            "µs",
            1,
        );
        row("per-slave update period", &self.slave_update_us, "µs", 1);
        row("repeats per cycle", &self.repeats.per_cycle, "", 4);
        row("repeats / transactions", &self.repeats.fraction, "", 5);
        row(
            "repeats (count)",
            &Figure {
                analytic: Some(self.repeats.expected),
                mean: Some(self.repeats.count as f64),
                ..Figure::default()
            },
            "",
            1,
        );
        row(
            "failed after repeat / slave drop-outs",
            &Figure {
                min: Some(self.repeats.failed_after_repeat as f64),
                max: Some(self.repeats.dropouts as f64),
                ..Figure::default()
            },
            "",
            0,
        );
        if let Some(l) = &self.lab {
            row("S-7.3 value period (7 cycles)", &l.analog_value_ms, "ms", 2);
            row(
                "speed set-point refresh (channel 1 of 2)",
                &l.setpoint_refresh_ms,
                "ms",
                2,
            );
            row("floor display word (4 steps)", &l.floor_word_ms, "ms", 2);
            row(
                "cabin display word (7 steps)",
                &l.cabin_display_word_ms,
                "ms",
                2,
            );
            row(
                "cabin panel word (2 × 7 steps)",
                &l.cabin_panel_word_ms,
                "ms",
                2,
            );
            let lat = &l.latencies;
            row(
                "hall press → call registered",
                &lat.press_to_registered_ms,
                "ms",
                2,
            );
            row(
                "call registered → run bit on the bus",
                &lat.registered_to_run_bit_ms,
                "ms",
                2,
            );
            row(
                "hall press → run bit on the bus",
                &lat.press_to_run_bit_ms,
                "ms",
                2,
            );
            row("STOP → EStopOut off", &lat.stop_to_estop_out_ms, "ms", 2);
            row(
                "EStopOut off → K1 open",
                &lat.estop_out_to_k1_open_ms,
                "ms",
                2,
            );
            row("STOP → K1 open", &lat.stop_to_k1_open_ms, "ms", 2);
        }
        let header = ["quantity", "analytic", "min", "mean", "max", "unit"];
        let width = |i: usize| {
            rows.iter()
                .map(|r| r[i].chars().count())
                .chain([header[i].chars().count()])
                .max()
                .unwrap_or(0)
        };
        let w: Vec<usize> = (0..6).map(width).collect();
        let mut out = String::new();
        let _ = writeln!(
            out,
            "asi-lift timing: {}, pulse error rate {}, seed {}, {} s measured: {} cycles, {} transactions",
            self.bus, self.pulse_error_rate, self.seed, self.window_s, self.cycles, self.transactions
        );
        if let Some(l) = &self.lab {
            let _ = writeln!(
                out,
                "latencies: {} hall calls and {} STOPs at random moments; PLC scan {} ms, safety scan {} ms, STOP delay {} ms{}{}",
                l.latencies.hall.len(),
                l.latencies.stop.len(),
                l.plc_scan_ms,
                l.safety_scan_ms,
                l.stop_delay_ms,
                match l.latencies.operator_resets {
                    0 => String::new(),
                    n => format!(
                        "\n{n} trip(s) not caused by a sample (Safety-at-Work monitor under line noise) reset by the operator"
                    ),
                },
                l.latencies
                    .incomplete
                    .as_ref()
                    .map(|s| format!("\nwarning: {s}"))
                    .unwrap_or_default()
            );
        }
        out.push('\n');
        let mut line = |cells: [&str; 6]| {
            let mut s = String::new();
            for (i, c) in cells.iter().enumerate() {
                let pad = w[i].saturating_sub(c.chars().count());
                if i == 0 || i == 5 {
                    s.push_str(c);
                    if i == 0 {
                        s.push_str(&" ".repeat(pad));
                    }
                } else {
                    s.push_str(&" ".repeat(pad));
                    s.push_str(c);
                }
                if i < 5 {
                    s.push_str("  ");
                }
            }
            out.push_str(s.trim_end());
            out.push('\n');
        };
        line(header);
        for r in &rows {
            line([&r[0], &r[1], &r[2], &r[3], &r[4], &r[5]]);
        }
        if let Some(m) = &self.error_model {
            let _ = writeln!(
                out,
                "\nerror model: a pulse comes through with c = (1 − p/4)^4 = {:.6}; a transaction of \
                 m + s pulses fails with q = 1 − c^(m+s) (here {:.1} pulses, q = {:.4} on average) \
                 and is repeated once.\nrepeats: {} counted, {:.1} ± {:.1} expected; mean cycle \
                 {:.2} µs simulated, {:.2} ± {:.2} µs expected.",
                m.pulse_clean,
                m.mean_pulses,
                m.mean_fail_probability,
                self.repeats.count,
                self.repeats.expected,
                self.repeats.standard_error,
                self.cycle_us.mean.unwrap_or(0.0),
                self.cycle_us.analytic.unwrap_or(0.0),
                m.cycle_mean_standard_error_us
            );
        }
        out
    }

    /// The report as JSON.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }

    /// An SVG with histograms of the cycle time and of each latency.
    pub fn to_svg(&self) -> String {
        let mut panels: Vec<(String, Histogram, &str)> = vec![(
            format!("cycle time, {}", self.bus),
            self.cycle_histogram.clone(),
            "µs",
        )];
        if let Some(l) = &self.lab {
            let lat = &l.latencies;
            let series: [(&str, Vec<f64>); 5] = [
                (
                    "hall press → call registered",
                    lat.hall.iter().map(|s| s.registered_ms).collect(),
                ),
                (
                    "call registered → run bit on the bus",
                    lat.hall.iter().map(|s| s.run_bit_ms).collect(),
                ),
                (
                    "hall press → run bit on the bus",
                    lat.hall
                        .iter()
                        .map(|s| s.registered_ms + s.run_bit_ms)
                        .collect(),
                ),
                (
                    "STOP → EStopOut off",
                    lat.stop.iter().map(|s| s.estop_out_ms).collect(),
                ),
                (
                    "STOP → K1 open",
                    lat.stop
                        .iter()
                        .map(|s| s.estop_out_ms + s.k1_open_ms)
                        .collect(),
                ),
            ];
            for (name, v) in series {
                if !v.is_empty() {
                    panels.push((
                        format!("{name} ({} samples)", v.len()),
                        histogram(&v, 0.001, 30),
                        "ms",
                    ));
                }
            }
        }
        svg(&panels)
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Hand-written SVG: one panel per histogram, stacked.
fn svg(panels: &[(String, Histogram, &str)]) -> String {
    const W: f64 = 760.0;
    const PH: f64 = 170.0;
    const LEFT: f64 = 60.0;
    const RIGHT: f64 = 20.0;
    let height = PH * panels.len() as f64 + 10.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{height}" viewBox="0 0 {W} {height}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(s, r#"<rect width="{W}" height="{height}" fill="white"/>"#);
    for (k, (title, h, unit)) in panels.iter().enumerate() {
        let top = PH * k as f64 + 10.0;
        let plot_top = top + 22.0;
        let plot_h = PH - 60.0;
        let base = plot_top + plot_h;
        let plot_w = W - LEFT - RIGHT;
        let _ = writeln!(
            s,
            r#"<text x="{LEFT}" y="{:.1}" font-size="13" font-weight="bold">{}</text>"#,
            top + 12.0,
            esc(title)
        );
        let peak = h.counts.iter().copied().max().unwrap_or(0).max(1);
        let n = h.counts.len().max(1);
        let bw = plot_w / n as f64;
        for (i, &c) in h.counts.iter().enumerate() {
            if c == 0 {
                continue;
            }
            let bh = plot_h * c as f64 / peak as f64;
            let _ = writeln!(
                s,
                r##"<rect x="{:.2}" y="{:.2}" width="{:.2}" height="{:.2}" fill="#4a7ab5"><title>{:.3}..{:.3} {unit}: {c}</title></rect>"##,
                LEFT + bw * i as f64 + 0.5,
                base - bh,
                (bw - 1.0).max(0.5),
                bh,
                h.lo + h.width * i as f64,
                h.lo + h.width * (i + 1) as f64,
            );
        }
        let _ = writeln!(
            s,
            r#"<line x1="{LEFT}" y1="{base:.1}" x2="{:.1}" y2="{base:.1}" stroke="black"/>"#,
            W - RIGHT
        );
        let _ = writeln!(
            s,
            r#"<line x1="{LEFT}" y1="{plot_top:.1}" x2="{LEFT}" y2="{base:.1}" stroke="black"/>"#
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="end">{peak}</text>"#,
            LEFT - 4.0,
            plot_top + 8.0
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{base:.1}" text-anchor="end">0</text>"#,
            LEFT - 4.0
        );
        let hi = h.lo + h.width * n as f64;
        let _ = writeln!(
            s,
            r#"<text x="{LEFT}" y="{:.1}">{:.3} {unit}</text>"#,
            base + 14.0,
            h.lo
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="end">{:.3} {unit}</text>"#,
            W - RIGHT,
            base + 14.0,
            hi
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">count per bin of {:.3} {unit}</text>"#,
            LEFT + plot_w / 2.0,
            base + 14.0,
            h.width
        );
    }
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts(bus: BusChoice, p: f64, secs: u64, samples: u32) -> TimingOptions {
        TimingOptions {
            bus,
            pulse_error_rate: p,
            seed: 7,
            duration: SimDuration::from_secs(secs),
            samples,
        }
    }

    fn exact(f: &Figure, v: f64) {
        assert!(f.samples > 0, "{f:?}");
        for x in [f.analytic, f.min, f.mean, f.max] {
            let x = x.unwrap_or(f64::NAN);
            assert!((x - v).abs() < 1e-6, "{f:?} != {v}");
        }
    }

    /// Without errors every cycle is the model's formula (SPEC §2), which is the seed's
    /// (n + 2) · 154 µs wherever an inclusion address is left; 31 slaves leave none.
    #[test]
    fn clean_buses_run_the_model_formula_exactly() {
        for (bus, model, seed) in [
            (BusChoice::Standard { n: 1 }, 3.0 * 154.0, 3.0 * 154.0),
            (BusChoice::Standard { n: 17 }, 19.0 * 154.0, 19.0 * 154.0),
            (BusChoice::Standard { n: 30 }, 32.0 * 154.0, 32.0 * 154.0),
            (BusChoice::Standard { n: 31 }, 32.0 * 154.0, 33.0 * 154.0),
            (BusChoice::AbPairs, 32.0 * 154.0, 64.0 * 154.0),
        ] {
            let r = analyse(&opts(bus, 0.0, 1, 0)).expect("analysis");
            exact(&r.transaction_us, 154.0);
            exact(&r.cycle_us, model);
            assert_eq!(r.seed_cycle_us, seed);
            assert!(r.cycles > 150, "{bus:?}: {}", r.cycles);
            assert_eq!(r.repeats.count, 0);
            assert_eq!(r.repeats.expected, 0.0);
            assert_eq!(r.cycle_histogram.counts.iter().sum::<u64>(), r.cycles);
            // Each slave is served every cycle, an A/B slave every second one: 64 · 154 µs,
            // the seed's formula for 62 slaves (≤ 10 ms).
            let per_slave = if bus == BusChoice::AbPairs { 2.0 } else { 1.0 };
            exact(&r.slave_update_us, per_slave * model);
        }
    }

    /// The lab bus in the whole rig: 13 · 154 = 2002 µs; one S-7.3 value every 7 cycles; the
    /// handshake words take one PLC scan per step; the latencies keep their bounds.
    #[test]
    fn the_lab_bus_without_errors() {
        let r = analyse(&opts(BusChoice::Lab { extra: 0 }, 0.0, 2, 3)).expect("analysis");
        exact(&r.cycle_us, 2002.0);
        assert_eq!(r.seed_cycle_us, 2002.0);
        exact(&r.slave_update_us, 2002.0);
        let lab = r.lab.expect("lab figures");
        exact(&lab.analog_value_ms, 7.0 * 2.002);
        exact(&lab.setpoint_refresh_ms, 14.0 * 2.002);
        for (f, steps) in [
            (&lab.floor_word_ms, 4.0),
            (&lab.cabin_display_word_ms, 7.0),
            (&lab.cabin_panel_word_ms, 14.0),
        ] {
            let mean = f.mean.expect("words");
            assert!((mean - steps * 10.0).abs() < 0.1, "{f:?}");
            // A word ends at a Data_Exchange: up to a cycle either side of the scan grid.
            assert!(f.min.unwrap_or(0.0) >= steps * 10.0 - 2.002 - 1e-6, "{f:?}");
            assert!(
                f.max.unwrap_or(f64::MAX) <= steps * 10.0 + 2.002 + 1e-6,
                "{f:?}"
            );
        }
        let lat = &lab.latencies;
        assert_eq!(
            (lat.hall.len(), lat.stop.len()),
            (3, 3),
            "{:?}",
            lat.incomplete
        );
        assert_eq!(lat.operator_resets, 0);
        within_bounds(lat);
        // STOP reaches EStopOut at the next safety scan; K1 opens exactly the STOP delay later.
        exact(&lat.estop_out_to_k1_open_ms, 9100.0);
    }

    fn within_bounds(lat: &Latencies) {
        for f in [
            &lat.press_to_registered_ms,
            &lat.registered_to_run_bit_ms,
            &lat.press_to_run_bit_ms,
            &lat.stop_to_estop_out_ms,
            &lat.stop_to_k1_open_ms,
        ] {
            let bound = f.bound.expect("a bound");
            assert!(f.samples > 0);
            assert!(f.min.unwrap_or(-1.0) >= 0.0, "{f:?}");
            assert!(f.max.unwrap_or(f64::MAX) <= bound + 1e-9, "{f:?}");
        }
        // Registering takes at least the extra code's trip through the image.
        assert!(lat.press_to_registered_ms.min.unwrap_or(0.0) > 0.154);
    }

    /// The lab lift on a full bus (20 extra modules, 31 slaves): 32 · 154 µs, an S-7.3 value
    /// every 7 · 4.928 ms; the same seed gives the same samples.
    #[test]
    fn the_lab_lift_on_a_full_bus_is_deterministic() {
        let o = opts(BusChoice::Lab { extra: 20 }, 0.0, 1, 2);
        let r = analyse(&o).expect("analysis");
        exact(&r.cycle_us, 32.0 * 154.0);
        let lab = r.lab.clone().expect("lab figures");
        exact(&lab.analog_value_ms, 7.0 * 4.928);
        within_bounds(&lab.latencies);
        let again = analyse(&o).expect("analysis");
        assert_eq!(r, again);
        let other = analyse(&TimingOptions { seed: 8, ..o }).expect("analysis");
        assert_ne!(
            lab.latencies.hall,
            other.lab.expect("lab figures").latencies.hall
        );
    }

    /// With line noise the repeat count and the mean cycle lie within 5 standard errors of the
    /// error model's expectation (SPEC §7: "within statistical bounds").
    #[test]
    fn noisy_buses_agree_with_the_error_model() {
        for (bus, p, secs) in [
            (BusChoice::Standard { n: 31 }, 0.002, 10),
            (BusChoice::Standard { n: 3 }, 0.001, 10),
            (BusChoice::AbPairs, 0.002, 10),
            (BusChoice::Lab { extra: 0 }, 0.002, 4),
        ] {
            let r = analyse(&opts(bus, p, secs, 0)).expect("analysis");
            let rep = &r.repeats;
            assert!(rep.count > 500, "{bus:?}: {rep:?}");
            let z = (rep.count as f64 - rep.expected) / rep.standard_error;
            assert!(z.abs() < 5.0, "{bus:?}: repeats z = {z}: {rep:?}");
            let m = r.error_model.as_ref().expect("error model");
            let z = (r.cycle_us.mean.unwrap_or(0.0) - r.cycle_us.analytic.unwrap_or(0.0))
                / m.cycle_mean_standard_error_us;
            assert!(z.abs() < 5.0, "{bus:?}: cycle z = {z}: {:?}", r.cycle_us);
            // The fraction of repeats follows from the same expectation.
            let f = &rep.fraction;
            let (a, s) = (f.analytic.unwrap_or(0.0), f.mean.unwrap_or(1.0));
            assert!(
                (a - s).abs() < 5.0 * rep.standard_error / r.transactions as f64,
                "{f:?}"
            );
            // Most cycles are still the clean one; a repeat adds a transaction or more.
            let clean = (r.slots + 1 + r.inclusion_call as u32) as f64 * 154.0;
            assert_eq!(r.cycle_us.min, Some(clean), "{bus:?}");
            assert!(r.cycle_us.max.unwrap_or(0.0) >= clean + 154.0, "{bus:?}");
        }
    }

    #[test]
    fn options_are_checked() {
        assert_eq!("lab".parse(), Ok(BusChoice::Lab { extra: 0 }));
        assert_eq!("62ab".parse(), Ok(BusChoice::AbPairs));
        assert_eq!("31".parse(), Ok(BusChoice::Standard { n: 31 }));
        for bad in ["0", "32", "62", "x", "-1", ""] {
            assert!(bad.parse::<BusChoice>().is_err(), "{bad}");
        }
        let ok = TimingOptions::default();
        assert!(ok.check().is_ok());
        for bad in [
            TimingOptions {
                pulse_error_rate: 1.0,
                ..ok.clone()
            },
            TimingOptions {
                pulse_error_rate: -0.1,
                ..ok.clone()
            },
            TimingOptions {
                pulse_error_rate: f64::NAN,
                ..ok.clone()
            },
            TimingOptions {
                bus: BusChoice::Lab { extra: 21 },
                ..ok.clone()
            },
            TimingOptions {
                bus: BusChoice::Standard { n: 0 },
                ..ok.clone()
            },
            TimingOptions {
                duration: SimDuration::ZERO,
                ..ok.clone()
            },
        ] {
            assert!(
                matches!(analyse(&bad), Err(TimingError::Option { .. })),
                "{bad:?}"
            );
        }
    }

    #[test]
    fn the_outputs_show_every_figure() {
        let r = analyse(&opts(BusChoice::Standard { n: 4 }, 0.001, 1, 0)).expect("analysis");
        let text = r.to_text();
        for want in [
            "transaction",
            "seed: T = (n + 2)",
            "per-slave",
            "error model",
        ] {
            assert!(text.contains(want), "{text}");
        }
        let json: serde_json::Value =
            serde_json::from_str(&r.to_json().expect("serialises")).expect("json");
        assert_eq!(json["cycle_us"]["analytic"].as_f64(), r.cycle_us.analytic);
        let svg = r.to_svg();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    }
}
