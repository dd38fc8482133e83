//! The line voltage: APM pulses rendered as sampled sin² pulses, and the comparator that turns
//! sampled voltage back into pulses (SPEC §1 "Waveform"; reference/asi.md §1.1; seed 003 §2.2.1).
//!
//! The demodulator follows the receiver rule of the slave ICs: after a pause the comparators
//! re-arm; the first pulse of a telegram (normally the negative start pulse) sets the threshold
//! to a fraction (45..55 %, default 50 %) of its amplitude; disturbances below 30 % of the
//! nominal amplitude are never pulses. It tracks a slow DC baseline, so it works on captures
//! that did not come from this crate: an oscilloscope trace on top of the 30 V supply, with
//! uneven amplitudes, noise and an arbitrary start.

use crate::pulse::{Polarity, Pulse};
use crate::time::{SimDuration, SimTime};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// How pulses are rendered as voltage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WaveformConfig {
    /// Peak voltage of one pulse (default 2.5 V, i.e. 5 Vpp, inside the 3..8 Vpp the
    /// receivers accept).
    pub amplitude: f32,
    /// Time between samples (default 100 ns, 10 MS/s).
    pub sample_period: SimDuration,
    /// Base width of one sin² pulse (default 3 µs, one half-bit).
    pub pulse_width: SimDuration,
    /// RMS of white Gaussian noise added to every sample (default 0).
    pub noise_rms: f32,
    /// Constant offset added to every sample (default 0).
    pub dc_offset: f32,
    /// Seed of the noise.
    pub seed: u64,
}

impl Default for WaveformConfig {
    fn default() -> Self {
        WaveformConfig {
            amplitude: 2.5,
            sample_period: SimDuration::from_nanos(100),
            pulse_width: SimDuration::from_micros(3),
            noise_rms: 0.0,
            dc_offset: 0.0,
            seed: 0,
        }
    }
}

/// A bad waveform or demodulator setting: the field and why.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("{field} = {value}: {rule}")]
pub struct WaveformError {
    /// The field at fault.
    pub field: &'static str,
    /// Its value.
    pub value: f64,
    /// The rule it breaks.
    pub rule: &'static str,
}

/// Sampled line voltage: `samples[i]` is the voltage at `start + i · period_ns`.
#[derive(Clone, Debug, PartialEq)]
pub struct Waveform {
    /// Time of the first sample.
    pub start: SimTime,
    /// Time between samples in nanoseconds (fractional for oscilloscope captures).
    pub period_ns: f64,
    /// Volts.
    pub samples: Vec<f32>,
}

/// A burst of noise on the line: Gaussian noise of `rms` volts from `start` for `duration`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseBurst {
    /// Start of the burst.
    pub start: SimTime,
    /// Its length.
    pub duration: SimDuration,
    /// Its RMS voltage.
    pub rms: f32,
}

impl WaveformConfig {
    fn check(&self) -> Result<(), WaveformError> {
        let err = |field, value: f64, rule| Err(WaveformError { field, value, rule });
        if !(self.amplitude.is_finite() && self.amplitude > 0.0) {
            return err(
                "amplitude",
                self.amplitude as f64,
                "must be a positive number of volts",
            );
        }
        if self.sample_period.is_zero() {
            return err("sample_period", 0.0, "must be positive");
        }
        if self.pulse_width < self.sample_period.saturating_mul(2) {
            return err(
                "pulse_width",
                self.pulse_width.as_nanos() as f64,
                "must span at least two samples",
            );
        }
        if !(self.noise_rms.is_finite() && self.noise_rms >= 0.0) {
            return err(
                "noise_rms",
                self.noise_rms as f64,
                "must be zero or positive",
            );
        }
        if !self.dc_offset.is_finite() {
            return err("dc_offset", self.dc_offset as f64, "must be a number");
        }
        Ok(())
    }
}

/// Renders `pulses` as line voltage from `from` until `until` (exclusive).
pub fn render<I: IntoIterator<Item = Pulse>>(
    pulses: I,
    from: SimTime,
    until: SimTime,
    cfg: &WaveformConfig,
) -> Result<Waveform, WaveformError> {
    cfg.check()?;
    let period = cfg.sample_period.as_nanos();
    let n = until
        .saturating_duration_since(from)
        .as_nanos()
        .div_ceil(period);
    if n > 1 << 32 {
        return Err(WaveformError {
            field: "until",
            value: n as f64,
            rule: "more than 2^32 samples in one waveform",
        });
    }
    let mut samples = vec![cfg.dc_offset; n as usize];
    let width = cfg.pulse_width.as_nanos() as f64;
    let half = cfg.pulse_width.as_nanos() / 2;
    for p in pulses {
        let sign = match p.polarity {
            Polarity::Negative => -cfg.amplitude,
            Polarity::Positive => cfg.amplitude,
        };
        let lo = p.at.as_nanos().saturating_sub(half);
        let hi = p.at.as_nanos().saturating_add(half);
        // Samples with lo < t < hi.
        let first = lo.saturating_sub(from.as_nanos()).div_ceil(period);
        let last = hi.saturating_sub(from.as_nanos()).div_ceil(period).min(n);
        for i in first..last {
            let t = from.as_nanos() + i * period;
            if t <= lo || t >= hi {
                continue;
            }
            let phase = (t - lo) as f64 / width * core::f64::consts::PI;
            let s = phase.sin();
            samples[i as usize] += sign * (s * s) as f32;
        }
    }
    let mut wf = Waveform {
        start: from,
        period_ns: period as f64,
        samples,
    };
    if cfg.noise_rms > 0.0 {
        let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
        for s in &mut wf.samples {
            *s += cfg.noise_rms * gaussian(&mut rng);
        }
    }
    Ok(wf)
}

impl Waveform {
    /// Time of sample `i` (rounded to the nanosecond).
    pub fn time_of(&self, i: f64) -> SimTime {
        let ns = (i * self.period_ns).max(0.0).round();
        self.start + SimDuration::from_nanos(ns.min(u64::MAX as f64) as u64)
    }

    /// Adds a noise burst, seeded with `seed`.
    pub fn add_burst(&mut self, burst: &NoiseBurst, seed: u64) {
        if self.period_ns <= 0.0 || !burst.rms.is_finite() {
            return;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let from =
            burst.start.saturating_duration_since(self.start).as_nanos() as f64 / self.period_ns;
        let to = from + burst.duration.as_nanos() as f64 / self.period_ns;
        let len = self.samples.len() as f64;
        let (a, b) = (
            from.ceil().clamp(0.0, len) as usize,
            to.ceil().clamp(0.0, len) as usize,
        );
        for s in &mut self.samples[a..b] {
            *s += burst.rms * gaussian(&mut rng);
        }
    }
}

/// A standard normal sample (Box–Muller).
fn gaussian(rng: &mut ChaCha8Rng) -> f32 {
    let u1: f64 = rng.random::<f64>().max(f64::MIN_POSITIVE);
    let u2: f64 = rng.random();
    ((-2.0 * u1.ln()).sqrt() * (2.0 * core::f64::consts::PI * u2).cos()) as f32
}

/// Comparator settings (SPEC §1; reference/asi.md §1.1).
#[derive(Clone, Copy, Debug, PartialEq)]
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
                value: value as f64,
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

/// A capture read from a text file of `time,voltage` lines.
#[derive(Clone, Debug, PartialEq)]
pub struct Capture {
    /// Time of the first sample in the file's own time base, seconds.
    pub first_time_s: f64,
    /// The samples, the first at [`SimTime::ZERO`].
    pub waveform: Waveform,
}

/// Why a capture file could not be read: the line and the cause.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("line {line}: {cause}")]
pub struct CaptureError {
    /// 1-based line number.
    pub line: usize,
    /// What is wrong there.
    pub cause: String,
}

/// Reads an oscilloscope export: one sample per line, `time,voltage` (seconds, volts),
/// separated by a comma, semicolon, tab or spaces. Blank lines and lines starting with `#` are
/// skipped, and so are non-numeric lines before the first sample (headers). Sample spacing must
/// be even (within 1 % of the mean), as an oscilloscope's is.
pub fn read_capture(text: &str) -> Result<Capture, CaptureError> {
    let mut times: Vec<(usize, f64)> = Vec::new();
    let mut samples = Vec::new();
    // The header lines before the first sample: the first one and how many.
    let mut header: Option<(usize, &str)> = None;
    let mut header_lines = 0;
    for (n, line) in text.lines().enumerate() {
        let line_no = n + 1;
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let mut fields = l.split([',', ';', '\t', ' ']).filter(|f| !f.is_empty());
        let (Some(t), Some(v)) = (fields.next(), fields.next()) else {
            if samples.is_empty() {
                header.get_or_insert((line_no, l));
                header_lines += 1;
                continue;
            }
            return Err(CaptureError {
                line: line_no,
                cause: format!("expected `time,voltage`, found `{l}`"),
            });
        };
        let (t, v) = match (t.parse::<f64>(), v.parse::<f32>()) {
            (Ok(t), Ok(v)) if t.is_finite() && v.is_finite() => (t, v),
            _ if samples.is_empty() => {
                header.get_or_insert((line_no, l));
                header_lines += 1;
                continue;
            }
            _ => {
                return Err(CaptureError {
                    line: line_no,
                    cause: format!("`{l}` is not two numbers (seconds, volts)"),
                })
            }
        };
        if let Some(&(_, last)) = times.last() {
            if t <= last {
                return Err(CaptureError {
                    line: line_no,
                    cause: format!("time {t} s does not increase (previous sample {last} s)"),
                });
            }
        }
        times.push((line_no, t));
        samples.push(v);
    }
    if samples.len() < 2 {
        let last = text.lines().count().max(1);
        let (line, cause) = match (times.first(), header) {
            (Some(&(line, _)), _) => (line, "only one sample: a capture needs two or more".into()),
            (None, Some((line, l))) if header_lines == 1 => (
                line,
                format!("`{l}` is a header and no `time,voltage` sample follows"),
            ),
            (None, Some((line, l))) => (
                line,
                format!(
                    "no samples: `{l}` and the {} lines after it are not `time,voltage` \
                     (seconds, volts)",
                    header_lines - 1
                ),
            ),
            (None, None) if text.trim().is_empty() => (last, "the file is empty".into()),
            (None, None) => (last, "no samples: the file holds only comments".into()),
        };
        return Err(CaptureError { line, cause });
    }
    let (first, last) = (times[0].1, times[times.len() - 1].1);
    let period_s = (last - first) / (times.len() - 1) as f64;
    // Judge each step against the median step, so one bad step is named where it is.
    let mut steps: Vec<f64> = times.windows(2).map(|w| w[1].1 - w[0].1).collect();
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2];
    for w in times.windows(2) {
        let dt = w[1].1 - w[0].1;
        if (dt - median).abs() > 0.01 * median {
            return Err(CaptureError {
                line: w[1].0,
                cause: format!(
                    "uneven sample spacing: {:.3} ns here, {:.3} ns elsewhere",
                    dt * 1e9,
                    median * 1e9
                ),
            });
        }
    }
    Ok(Capture {
        first_time_s: first,
        waveform: Waveform {
            start: SimTime::ZERO,
            period_ns: period_s * 1e9,
            samples,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pulse::PulseTrain;
    use crate::receiver::{Expect, Receiver};
    use crate::telegram::{Address, Nibble, Request};
    use crate::timing::BusTiming;

    fn dexg() -> Request {
        Request::data_exchange(Address::new(5).expect("a"), Nibble::from_low_bits(0b1010))
            .expect("valid")
    }

    fn train(at_us: u64) -> PulseTrain {
        PulseTrain::request(
            dexg(),
            SimTime::from_micros(at_us),
            BusTiming::default().half_bit(),
        )
    }

    fn decode(pulses: Vec<Pulse>) -> Vec<crate::receiver::Received> {
        Receiver::new(BusTiming::default().receiver(Expect::Requests))
            .decode(pulses)
            .collect()
    }

    #[test]
    fn a_rendered_pulse_is_sin_squared_of_the_configured_amplitude() {
        let p = Pulse::new(SimTime::from_micros(10), Polarity::Negative);
        let wf = render(
            [p],
            SimTime::ZERO,
            SimTime::from_micros(20),
            &WaveformConfig::default(),
        )
        .expect("ok");
        assert_eq!(wf.samples.len(), 200);
        assert!(
            (wf.samples[100] + 2.5).abs() < 1e-6,
            "peak {}",
            wf.samples[100]
        );
        assert!((wf.samples[100 - 7] + 2.5 * 0.5).abs() < 0.2);
        assert_eq!(wf.samples[85], 0.0);
        assert_eq!(wf.samples[115], 0.0);
    }

    #[test]
    fn demodulation_recovers_the_exact_pulse_times() {
        let t = train(20);
        let wf = render(
            t,
            SimTime::ZERO,
            SimTime::from_micros(120),
            &WaveformConfig::default(),
        )
        .expect("ok");
        let got = Demodulator::demodulate(DemodConfig::default(), &wf).expect("ok");
        let want: Vec<Pulse> = t.iter().collect();
        assert_eq!(got, want);
    }

    #[test]
    fn works_on_a_capture_on_the_supply_with_noise_uneven_amplitude_and_odd_start() {
        // 30 V supply, 6 Vpp, 0.1 V RMS noise, 25 MS/s, a capture starting in mid telegram.
        let cfg = WaveformConfig {
            amplitude: 3.0,
            sample_period: SimDuration::from_nanos(40),
            noise_rms: 0.1,
            dc_offset: 30.0,
            seed: 3,
            ..WaveformConfig::default()
        };
        let mut pulses: Vec<Pulse> = train(0).iter().collect();
        pulses.extend(train(154));
        pulses.extend(train(308));
        let mut wf = render(
            pulses,
            SimTime::from_micros(40),
            SimTime::from_micros(420),
            &cfg,
        )
        .expect("ok");
        // The second telegram's pulses at 65 % (master must see 60 %): scale by hand.
        for (i, s) in wf.samples.iter_mut().enumerate() {
            let t = 40_000 + 40 * i as u64;
            if (154_000..240_000).contains(&t) {
                *s = 30.0 + (*s - 30.0) * 0.65;
            }
        }
        let demod = DemodConfig {
            nominal_amplitude: 3.0,
            ..DemodConfig::default()
        };
        let got = decode(Demodulator::demodulate(demod, &wf).expect("ok"));
        let valid: Vec<Option<Request>> = got.iter().map(|r| r.request()).collect();
        // The cut first telegram is broken; the next two are read.
        assert_eq!(valid.len(), 3, "{got:?}");
        assert_eq!(valid[0], None);
        assert_eq!(&valid[1..], &[Some(dexg()), Some(dexg())]);
    }

    #[test]
    fn disturbances_below_30_percent_are_ignored() {
        let mut wf = render(
            train(20),
            SimTime::ZERO,
            SimTime::from_micros(200),
            &WaveformConfig::default(),
        )
        .expect("ok");
        // A 0.7 V (28 %) blip in the pause after the telegram.
        let blip = render(
            [Pulse::new(SimTime::from_micros(150), Polarity::Negative)],
            SimTime::ZERO,
            SimTime::from_micros(200),
            &WaveformConfig {
                amplitude: 0.7,
                ..WaveformConfig::default()
            },
        )
        .expect("ok");
        for (s, b) in wf.samples.iter_mut().zip(&blip.samples) {
            *s += b;
        }
        let got = decode(Demodulator::demodulate(DemodConfig::default(), &wf).expect("ok"));
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].request(), Some(dexg()));
    }

    #[test]
    fn a_noise_burst_corrupts_a_telegram_and_the_receiver_says_so() {
        let mut wf = render(
            train(20),
            SimTime::ZERO,
            SimTime::from_micros(120),
            &WaveformConfig::default(),
        )
        .expect("ok");
        wf.add_burst(
            &NoiseBurst {
                start: SimTime::from_micros(50),
                duration: SimDuration::from_micros(10),
                rms: 3.0,
            },
            9,
        );
        let got = decode(Demodulator::demodulate(DemodConfig::default(), &wf).expect("ok"));
        assert!(got.iter().all(|r| !r.is_valid()), "{got:?}");
    }

    #[test]
    fn bad_settings_are_rejected_with_the_field() {
        let e = render(
            [],
            SimTime::ZERO,
            SimTime::ZERO,
            &WaveformConfig {
                amplitude: -1.0,
                ..WaveformConfig::default()
            },
        )
        .expect_err("negative amplitude");
        assert_eq!(e.field, "amplitude");
        let e = Demodulator::new(
            DemodConfig {
                threshold: 0.6,
                ..DemodConfig::default()
            },
            SimTime::ZERO,
            100.0,
        )
        .expect_err("threshold");
        assert_eq!(
            e.to_string(),
            "threshold = 0.6000000238418579: must lie within 0.45..=0.55 of the first pulse"
        );
        assert!(Demodulator::new(DemodConfig::default(), SimTime::ZERO, f64::NAN).is_err());
    }

    #[test]
    fn reads_a_capture_and_names_the_bad_line() {
        let cap =
            read_capture("Time,Ch1\n# scope export\n-1e-6,30.1\n-0.9e-6,30.2\n-0.8e-6,29.9\n")
                .expect("ok");
        assert_eq!(cap.waveform.samples, [30.1, 30.2, 29.9]);
        assert!((cap.waveform.period_ns - 100.0).abs() < 1e-6);
        assert_eq!(cap.first_time_s, -1e-6);
        let e = read_capture("0,1\n1e-7,1\nabc,2\n").expect_err("bad line");
        assert_eq!(
            (e.line, e.cause.as_str()),
            (3, "`abc,2` is not two numbers (seconds, volts)")
        );
        let e = read_capture("0,1\n1e-7,1\n3e-7,1\n4e-7,1\n").expect_err("uneven");
        assert_eq!(e.line, 3);
        let e = read_capture("0,1\n0,1\n").expect_err("not increasing");
        assert_eq!(e.line, 2);
    }

    #[test]
    fn a_capture_without_samples_says_why() {
        let cases = [
            ("", 1, "the file is empty"),
            ("\n  \n", 2, "the file is empty"),
            ("# scope\n#\n", 2, "no samples: the file holds only comments"),
            (
                "# export\ntime_s,voltage\n",
                2,
                "`time_s,voltage` is a header and no `time,voltage` sample follows",
            ),
            (
                "hello\nworld\nagain\n",
                1,
                "no samples: `hello` and the 2 lines after it are not `time,voltage` (seconds, volts)",
            ),
            (
                "t,v\n0,1\n",
                2,
                "only one sample: a capture needs two or more",
            ),
        ];
        for (text, line, cause) in cases {
            let e = read_capture(text).expect_err(text);
            assert_eq!((e.line, e.cause.as_str()), (line, cause), "{text:?}");
        }
    }
}
