//! The error model: line noise (a pulse error probability) → the probability that a
//! transaction fails → the expected repeats and the extra time they cost, with their variance.

use asi_phy::BusTiming;
use serde::Serialize;

/// How the error model was evaluated.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[non_exhaustive]
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

/// Expectations of the error model, summed over first tries.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Expect {
    pub(super) repeats: f64,
    pub(super) repeats_var: f64,
    /// Expected extra time over the clean transaction time, ns.
    pub(super) extra_ns: f64,
    pub(super) extra_var: f64,
    /// Σ q² over Data_Exchanges (both tries failing), and their count.
    pub(super) dx_q2: f64,
    pub(super) dx: u64,
    /// Σ (m + s) and Σ q over transactions that expect an answer, and their count.
    pub(super) pulses: f64,
    pub(super) q: f64,
    pub(super) answered: u64,
}

impl Expect {
    pub(super) fn add(&mut self, o: &Expect) {
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

/// The line noise of asi-phy's `FaultRates::uniform(p)` and what a failure costs on the bus.
#[derive(Clone, Copy, Debug)]
pub(super) struct LineNoise {
    /// Probability that a pulse comes through untouched: (1 − p/4)⁴.
    pub(super) clean: f64,
    /// One transaction (the repeat), ns.
    tx_ns: f64,
    /// The delay after a corrupt response: asynchronous pause minus slave pause, ns.
    delay_ns: f64,
}

impl LineNoise {
    /// Each pulse is dropped, flipped, shifted or followed by a spurious one with p/4 each.
    pub(super) fn new(timing: &BusTiming, pulse_error_rate: f64) -> LineNoise {
        let r = pulse_error_rate / 4.0;
        LineNoise {
            clean: (1.0 - r).powi(4),
            tx_ns: timing.transaction().as_nanos() as f64,
            delay_ns: timing
                .async_pause()
                .saturating_sub(timing.slave_pause())
                .as_nanos() as f64,
        }
    }

    /// The expectation for one first try of `m` request and `s` response pulses that expects an
    /// answer: it fails with q = 1 − c^(m+s) and is then repeated once at once.
    pub(super) fn first_try(&self, m: u32, s: u32, data_exchange: bool) -> Expect {
        let a = 1.0 - self.clean.powi(m as i32);
        let rb = (1.0 - a) * (1.0 - self.clean.powi(s as i32));
        let q = a + rb;
        let (t, d) = (self.tx_ns, self.delay_ns);
        // Extra time X = t·F + d·(D1 + F·D2): F the first try fails (q), D1 its response was
        // corrupt (rb, implies F), D2 the repeat's response was corrupt (rb).
        let mean = t * q + d * rb * (1.0 + q);
        let sq = a * ((1.0 - rb) * t * t + rb * (t + d) * (t + d))
            + rb * ((1.0 - rb) * (t + d) * (t + d) + rb * (t + 2.0 * d) * (t + 2.0 * d));
        Expect {
            repeats: q,
            repeats_var: q * (1.0 - q),
            extra_ns: mean,
            extra_var: (sq - mean * mean).max(0.0),
            dx_q2: if data_exchange { q * q } else { 0.0 },
            dx: data_exchange as u64,
            pulses: (m + s) as f64,
            q,
            answered: 1,
        }
    }
}
