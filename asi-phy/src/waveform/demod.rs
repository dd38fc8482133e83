//! The comparator that turns sampled line voltage back into pulses.

use super::render::{Waveform, WaveformError};
use crate::pulse::{Polarity, Pulse};
use crate::time::{SimDuration, SimTime};

/// Comparator settings (docs/physical-layer.md; docs/asi.md §1.1).
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct DemodConfig {
    /// Nominal pulse amplitude in volts (the 30 % ignore level is taken from it).
    pub nominal_amplitude: f32,
    /// Comparator threshold as a fraction of the first pulse's amplitude, 0.45..=0.55.
    pub threshold: f32,
    /// Fraction of the nominal amplitude below which nothing is a pulse (0.3).
    pub ignore_below: f32,
    /// Silence after which the comparators re-arm for a new telegram (9 µs, the receiver's
    /// pause).
    pub pause: SimDuration,
    /// Shortest excursion that counts as a pulse (spike filter, 0.5 µs).
    pub min_width: SimDuration,
    /// Time constant of the DC baseline tracker; zero for a fixed baseline of 0 V.
    pub baseline_tau: SimDuration,
}

impl Default for DemodConfig {
    fn default() -> Self {
        DemodConfig {
            nominal_amplitude: 2.5,
            threshold: 0.5,
            ignore_below: 0.3,
            pause: SimDuration::from_micros(9),
            min_width: SimDuration::from_nanos(500),
            baseline_tau: SimDuration::from_micros(200),
        }
    }
}

impl DemodConfig {
    fn check(&self) -> Result<(), WaveformError> {
        let err = |field, value: f32, rule| {
            Err(WaveformError {
                field,
                // The f32's shortest decimal (0.6, not 0.6000000238418579).
                value: value.to_string().parse().unwrap_or(f64::from(value)),
                rule,
            })
        };
        if !(self.nominal_amplitude.is_finite() && self.nominal_amplitude > 0.0) {
            return err(
                "nominal_amplitude",
                self.nominal_amplitude,
                "must be a positive number of volts",
            );
        }
        if !(0.45..=0.55).contains(&self.threshold) {
            return err(
                "threshold",
                self.threshold,
                "must lie within 0.45..=0.55 of the first pulse",
            );
        }
        if !(self.ignore_below > 0.0 && self.ignore_below < 1.0) {
            return err(
                "ignore_below",
                self.ignore_below,
                "must lie strictly between 0 and 1",
            );
        }
        Ok(())
    }
}

/// State of the excursion in progress.
#[derive(Clone, Copy, Debug)]
struct Lobe {
    negative: bool,
    /// Interpolated sample positions of the first and last crossing of the ignore level.
    in_ignore: f64,
    out_ignore: f64,
    /// Same for the locked threshold (NaN until crossed).
    in_thr: f64,
    out_thr: f64,
    peak: f32,
}

impl Lobe {
    /// An excursion that begins with value `x` at sample position `at`.
    fn new(x: f32, at: f64) -> Lobe {
        Lobe {
            negative: x < 0.0,
            in_ignore: at,
            out_ignore: f64::NAN,
            in_thr: f64::NAN,
            out_thr: f64::NAN,
            peak: x.abs(),
        }
    }
}

/// The comparator demodulator: samples in, pulses out. Feed it any number of buffers with
/// [`Demodulator::push`]; nothing allocates.
#[derive(Clone, Debug)]
pub struct Demodulator {
    cfg: DemodConfig,
    start: SimTime,
    period_ns: f64,
    ignore: f32,
    exit: f32,
    alpha: f32,
    pause_samples: f64,
    min_width_samples: f64,
    threshold: f32,
    baseline: Option<f32>,
    /// Index of the next sample.
    index: u64,
    prev: f32,
    lobe: Option<Lobe>,
    /// Sample position of the centre of the last accepted pulse.
    last_centre: Option<f64>,
    /// Samples to average for the initial baseline.
    baseline_window: usize,
}

impl Demodulator {
    /// A demodulator for samples taken every `period_ns`, the first at `start`.
    pub fn new(
        cfg: DemodConfig,
        start: SimTime,
        period_ns: f64,
    ) -> Result<Demodulator, WaveformError> {
        cfg.check()?;
        if !(period_ns.is_finite() && period_ns > 0.0) {
            return Err(WaveformError {
                field: "sample period",
                value: period_ns,
                rule: "must be a positive number of nanoseconds",
            });
        }
        let ignore = cfg.ignore_below * cfg.nominal_amplitude;
        let tau = cfg.baseline_tau.as_nanos() as f64;
        Ok(Demodulator {
            cfg,
            start,
            period_ns,
            ignore,
            exit: ignore * 0.5,
            alpha: if tau > 0.0 {
                (period_ns / tau).min(1.0) as f32
            } else {
                0.0
            },
            pause_samples: cfg.pause.as_nanos() as f64 / period_ns,
            min_width_samples: cfg.min_width.as_nanos() as f64 / period_ns,
            threshold: ignore,
            baseline: if tau > 0.0 { None } else { Some(0.0) },
            index: 0,
            prev: 0.0,
            lobe: None,
            last_centre: None,
            baseline_window: (tau / period_ns).clamp(1.0, 1e7) as usize,
        })
    }

    /// A demodulator for `wf`'s timing.
    pub fn for_waveform(cfg: DemodConfig, wf: &Waveform) -> Result<Demodulator, WaveformError> {
        Demodulator::new(cfg, wf.start, wf.period_ns)
    }

    /// Runs `samples` (the continuation of all samples pushed before) through the comparator,
    /// calling `out` with each pulse found, in time order.
    pub fn push(&mut self, samples: &[f32], mut out: impl FnMut(Pulse)) {
        let mut base = match self.baseline {
            Some(b) => b,
            // The first baseline is the mean of the first time constant's samples: APM pulses
            // alternate, so a telegram carries no DC.
            None => {
                let head = &samples[..samples.len().min(self.baseline_window)];
                let (sum, n) = head
                    .iter()
                    .filter(|v| v.is_finite())
                    .fold((0.0f64, 0usize), |(s, n), &v| (s + v as f64, n + 1));
                if n == 0 {
                    0.0
                } else {
                    (sum / n as f64) as f32
                }
            }
        };
        let alpha = self.alpha;
        let ignore = self.ignore;
        let mut prev = self.prev;
        let first = self.index;
        let mut k = 0usize;
        while k < samples.len() {
            if self.lobe.is_none() {
                // The quiet line: the tight loop most samples go through.
                while k < samples.len() {
                    let x = samples[k] - base;
                    // Also leaves on NaN, which the slow path below handles.
                    if x.abs().partial_cmp(&ignore) != Some(core::cmp::Ordering::Less) {
                        break;
                    }
                    base += alpha * x;
                    prev = x;
                    k += 1;
                }
                let Some(&v) = samples.get(k) else { break };
                let i = first + k as u64;
                // Non-finite samples (a capture's overflow marks) count as the baseline.
                let x = if v.is_finite() { v - base } else { 0.0 };
                if x.abs() >= ignore {
                    self.lobe = Some(Lobe::new(x, crossing(i, prev.abs(), x.abs(), ignore)));
                    self.track(i, prev, x);
                }
                prev = x;
                k += 1;
                continue;
            }
            let v = samples[k];
            let i = first + k as u64;
            let x = if v.is_finite() { v - base } else { 0.0 };
            let mag = x.abs();
            let negative = self.lobe.as_ref().is_some_and(|l| l.negative);
            if (x < 0.0) == negative && mag >= self.exit {
                self.track(i, prev, x);
            } else {
                self.close(i, prev, x, &mut out);
                if mag >= ignore {
                    // A sign change without a pass through the quiet band.
                    self.lobe = Some(Lobe::new(x, i as f64));
                    self.track(i, prev, x);
                } else {
                    base += alpha * x;
                }
            }
            prev = x;
            k += 1;
        }
        let i = first + samples.len() as u64;
        self.prev = prev;
        self.index = i;
        if alpha > 0.0 {
            self.baseline = Some(base);
        }
    }

    /// Runs `n` samples of the one value `v` through the comparator, as [`Demodulator::push`]
    /// of them would, in time bounded by the comparator's settling rather than by `n`: once a
    /// block of them leaves the comparator's state as it was, every further one would too
    /// (the baseline has settled and a lobe neither opens nor closes on a constant line), and
    /// only the sample clock moves on. For a capture's long flat spans.
    pub fn push_constant(&mut self, v: f32, n: u64, mut out: impl FnMut(Pulse)) {
        const BLOCK: usize = 4096;
        let block = [v; BLOCK];
        let mut left = n;
        while left > 0 {
            let k = left.min(BLOCK as u64) as usize;
            let before = self.state_bits();
            self.push(&block[..k], &mut out);
            left -= k as u64;
            if k == BLOCK && self.state_bits() == before {
                self.index += left;
                return;
            }
        }
    }

    /// Everything of the state but the sample clock, bit for bit.
    fn state_bits(&self) -> [u64; 10] {
        let f = |x: f32| u64::from(x.to_bits());
        let lobe = self.lobe.map_or([u64::MAX; 5], |l| {
            [
                u64::from(l.negative) << 32 | f(l.peak),
                l.in_ignore.to_bits(),
                l.out_ignore.to_bits(),
                l.in_thr.to_bits(),
                l.out_thr.to_bits(),
            ]
        });
        [
            self.baseline.map_or(u64::MAX, f),
            f(self.prev),
            f(self.threshold),
            self.last_centre.map_or(u64::MAX, f64::to_bits),
            lobe[0],
            lobe[1],
            lobe[2],
            lobe[3],
            lobe[4],
            u64::from(self.lobe.is_some()),
        ]
    }

    /// Ends the input: a pulse still in progress is closed and reported.
    pub fn finish(&mut self, mut out: impl FnMut(Pulse)) {
        if self.lobe.is_some() {
            self.close(self.index, self.prev, 0.0, &mut out);
        }
    }

    /// Demodulates a whole waveform into pulses.
    pub fn demodulate(cfg: DemodConfig, wf: &Waveform) -> Result<Vec<Pulse>, WaveformError> {
        let mut d = Demodulator::for_waveform(cfg, wf)?;
        let mut pulses = Vec::new();
        d.push(&wf.samples, |p| pulses.push(p));
        d.finish(|p| pulses.push(p));
        Ok(pulses)
    }

    /// Updates the lobe in progress with sample `i` of value `x` (after the baseline).
    fn track(&mut self, i: u64, prev: f32, x: f32) {
        let threshold = self.threshold;
        let ignore = self.ignore;
        let Some(lobe) = &mut self.lobe else { return };
        let mag = x.abs();
        let pmag = if (prev < 0.0) == lobe.negative {
            prev.abs()
        } else {
            0.0
        };
        lobe.peak = lobe.peak.max(mag);
        if mag >= threshold {
            if lobe.in_thr.is_nan() {
                lobe.in_thr = crossing(i, pmag, mag, threshold);
            }
            lobe.out_thr = f64::NAN;
        } else if pmag >= threshold && lobe.out_thr.is_nan() {
            lobe.out_thr = crossing(i, pmag, mag, threshold);
        }
        if mag >= ignore {
            lobe.out_ignore = f64::NAN;
        } else if pmag >= ignore && lobe.out_ignore.is_nan() {
            lobe.out_ignore = crossing(i, pmag, mag, ignore);
        }
    }

    /// Closes the lobe at sample `i` (the first sample outside it, of value `x`) and reports it
    /// if it is a pulse.
    fn close(&mut self, i: u64, prev: f32, x: f32, out: &mut impl FnMut(Pulse)) {
        let Some(mut lobe) = self.lobe.take() else {
            return;
        };
        let same = |v: f32| {
            if (v < 0.0) == lobe.negative {
                v.abs()
            } else {
                0.0
            }
        };
        let (pmag, mag) = (same(prev), same(x));
        if lobe.out_ignore.is_nan() {
            lobe.out_ignore = crossing(i, pmag, mag, self.ignore);
        }
        if !lobe.in_thr.is_nan() && lobe.out_thr.is_nan() {
            lobe.out_thr = crossing(i, pmag, mag, self.threshold);
        }
        let centre_ignore = (lobe.in_ignore + lobe.out_ignore) / 2.0;
        let rearmed = match self.last_centre {
            None => true,
            Some(c) => centre_ignore - c >= self.pause_samples,
        };
        if lobe.out_ignore - lobe.in_ignore < self.min_width_samples {
            return;
        }
        let centre = if rearmed {
            centre_ignore
        } else if lobe.peak >= self.threshold && !lobe.in_thr.is_nan() {
            (lobe.in_thr + lobe.out_thr) / 2.0
        } else {
            return;
        };
        if rearmed {
            self.threshold = (self.cfg.threshold * lobe.peak).max(self.ignore);
        }
        self.last_centre = Some(centre);
        let ns = (centre * self.period_ns)
            .max(0.0)
            .round()
            .min(u64::MAX as f64) as u64;
        let polarity = if lobe.negative {
            Polarity::Negative
        } else {
            Polarity::Positive
        };
        out(Pulse::new(
            self.start + SimDuration::from_nanos(ns),
            polarity,
        ));
    }
}

/// The fractional sample position where |x| crosses `level` between sample `i − 1` (magnitude
/// `a`) and sample `i` (magnitude `b`).
fn crossing(i: u64, a: f32, b: f32, level: f32) -> f64 {
    let i = i as f64;
    let d = b - a;
    if d.abs() < f32::EPSILON {
        return i;
    }
    let f = ((level - a) / d).clamp(0.0, 1.0) as f64;
    i - 1.0 + f
}
