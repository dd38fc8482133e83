//! Statistics of simulated values: the report's [`Figure`] (analytic value or bound beside the
//! simulated min/mean/max), [`Histogram`]s, the running [`Summary`] behind them, and the
//! [`Ticker`] that times a counter's increments.

use asi_phy::{SimDuration, SimTime};
use serde::Serialize;

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
    pub(super) fn analytic(mut self, v: f64) -> Figure {
        self.analytic = Some(v);
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

#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Summary {
    pub(super) n: u64,
    min: f64,
    max: f64,
    pub(super) sum: f64,
}

impl Summary {
    pub(super) fn add(&mut self, x: f64) {
        if self.n == 0 || x < self.min {
            self.min = x;
        }
        if self.n == 0 || x > self.max {
            self.max = x;
        }
        self.sum += x;
        self.n += 1;
    }

    pub(super) fn merge(&mut self, o: &Summary) {
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

    pub(super) fn figure(&self, scale: f64) -> Figure {
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

pub(super) fn figure_of(values: &[f64]) -> Figure {
    let mut s = Summary::default();
    for v in values {
        s.add(*v);
    }
    s.figure(1.0)
}

pub(super) fn histogram(values: &[f64], min_width: f64, bins: usize) -> Histogram {
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

/// Counts words (or values) as a counter increments; keeps the intervals between increments
/// `stride` apart.
#[derive(Clone, Debug, Default)]
pub(super) struct Ticker {
    count: Option<u64>,
    times: Vec<SimTime>,
    stride: usize,
    pub(super) intervals: Summary,
}

impl Ticker {
    pub(super) fn new(stride: usize) -> Ticker {
        Ticker {
            stride: stride.max(1),
            ..Ticker::default()
        }
    }

    pub(super) fn poll(&mut self, count: u64, now: SimTime) {
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

/// A duration in milliseconds.
pub(super) fn ms(d: SimDuration) -> f64 {
    d.as_nanos() as f64 / 1e6
}
