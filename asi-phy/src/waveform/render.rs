//! Pulses rendered as sampled sin² voltage, and noise bursts added to it.

use crate::pulse::{Polarity, Pulse};
use crate::time::{SimDuration, SimTime};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// How pulses are rendered as voltage.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
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
#[error("{field} = {}: {rule}", crate::short_number(*.value))]
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
