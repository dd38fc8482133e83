//! Fault injection on the line: exact faults for exhaustive tests, and a seeded injector that
//! corrupts traffic at a given rate so that higher layers can be tested against a noisy bus
//! reproducibly (in the manner of smoltcp's `FaultInjector::new(inner, seed)`).
//!
//! The pulse faults are the four ways a disturbance changes what a receiver's comparators see:
//! a pulse lost (drop), a spurious pulse (insert), a pulse of the wrong sign (flip), and a pulse
//! seen at the wrong time (shift). Noise bursts on a sampled waveform live in
//! [`crate::waveform`].

use crate::pulse::{Polarity, Pulse, PulseTrain};
use crate::time::{SimDuration, SimTime};
use crate::waveform::{NoiseBurst, Waveform};
use rand::distr::Bernoulli;
use rand::Rng;
// The tests draw the reference stream from `ChaCha8Rng` itself.
#[cfg(test)]
use rand::{RngCore, SeedableRng};
#[cfg(test)]
use rand_chacha::ChaCha8Rng;
use stream::FaultStream;

mod stream;

/// One exact fault on a pulse sequence. Indices refer to the sequence before any fault.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PulseFault {
    /// The pulse at `index` is lost.
    Drop {
        /// Index into the original sequence.
        index: usize,
    },
    /// A spurious pulse appears.
    Insert {
        /// Its time.
        at: SimTime,
        /// Its sign.
        polarity: Polarity,
    },
    /// The pulse at `index` has the wrong sign.
    Flip {
        /// Index into the original sequence.
        index: usize,
    },
    /// The pulse at `index` is seen `by_ns` nanoseconds late (negative: early).
    Shift {
        /// Index into the original sequence.
        index: usize,
        /// Signed shift in nanoseconds.
        by_ns: i64,
    },
}

/// Every single fault of the four kinds on an encoded `train`, relative to its own grid: drop,
/// flip, and shift by one grid step either way of each pulse, and a pulse of either sign at each
/// free grid point of the telegram's span. The fault set of the exhaustive single-fault test and
/// of the residual-error measurement.
pub fn single_faults(train: &PulseTrain) -> Vec<PulseFault> {
    let h = train.half_bit().as_nanos();
    let mut faults = Vec::new();
    for index in 0..train.len() as usize {
        faults.push(PulseFault::Drop { index });
        faults.push(PulseFault::Flip { index });
        faults.push(PulseFault::Shift {
            index,
            by_ns: h as i64,
        });
        faults.push(PulseFault::Shift {
            index,
            by_ns: -(h as i64),
        });
    }
    for k in 0..train.grid_points() {
        if train.pulse_at(k).is_none() {
            let at = train.start() + SimDuration::from_nanos(k as u64 * h);
            for polarity in [Polarity::Negative, Polarity::Positive] {
                faults.push(PulseFault::Insert { at, polarity });
            }
        }
    }
    faults
}

/// Applies `faults` to `pulses`, writing the result in time order to `out` (cleared first).
/// Faults naming an index past the end are ignored; so is a second fault on a dropped pulse.
pub fn apply_faults(pulses: &[Pulse], faults: &[PulseFault], out: &mut Vec<Pulse>) {
    out.clear();
    out.extend_from_slice(pulses);
    let mut dropped = 0u128;
    let mut dropped_far = Vec::new();
    for f in faults {
        match *f {
            PulseFault::Drop { index } if index < out.len() => {
                if index < 128 {
                    dropped |= 1 << index;
                } else {
                    dropped_far.push(index);
                }
            }
            PulseFault::Flip { index } if index < pulses.len() => {
                out[index].polarity = out[index].polarity.flipped();
            }
            PulseFault::Shift { index, by_ns } if index < pulses.len() => {
                let p = &mut out[index];
                p.at = shift(p.at, by_ns);
            }
            _ => {}
        }
    }
    let mut i = 0usize;
    out.retain(|_| {
        let keep = if i < 128 {
            dropped & (1 << i) == 0
        } else {
            !dropped_far.contains(&i)
        };
        i += 1;
        keep
    });
    for f in faults {
        if let PulseFault::Insert { at, polarity } = *f {
            out.push(Pulse::new(at, polarity));
        }
    }
    out.sort_by_key(|p| p.at);
}

fn shift(t: SimTime, by_ns: i64) -> SimTime {
    if by_ns >= 0 {
        t + SimDuration::from_nanos(by_ns as u64)
    } else {
        t - SimDuration::from_nanos(by_ns.unsigned_abs())
    }
}

/// How often the seeded injector corrupts pulses. Each rate is a probability per pulse.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FaultRates {
    /// A pulse is lost.
    pub drop: f64,
    /// A spurious pulse of random sign appears on the next grid point after a pulse.
    pub insert: f64,
    /// A pulse has the wrong sign.
    pub flip: f64,
    /// A pulse is seen one grid step early or late.
    pub shift: f64,
    /// Every pulse is moved by a uniform random time in ±`jitter` (not counted as a fault).
    pub jitter: SimDuration,
}

/// The total probability of a fault per pulse on the line, checked: a finite probability,
/// 0 ≤ p ≤ 1. The one check of a pulse error rate wherever one comes from (a scenario file,
/// `asi-lift timing --error-rate`, a campaign profile).
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
pub struct PulseErrorRate(f64);

/// A pulse error rate that is no probability.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("{0}: a pulse error rate is a probability, 0..=1")]
pub struct PulseErrorRateError(pub f64);

impl PulseErrorRate {
    /// A quiet line.
    pub const ZERO: PulseErrorRate = PulseErrorRate(0.0);

    /// The rate `p`, if it is a probability.
    pub fn new(p: f64) -> Result<PulseErrorRate, PulseErrorRateError> {
        if p.is_finite() && (0.0..=1.0).contains(&p) {
            Ok(PulseErrorRate(p))
        } else {
            Err(PulseErrorRateError(p))
        }
    }

    /// The probability.
    pub const fn get(self) -> f64 {
        self.0
    }
}

impl FaultRates {
    /// No corruption at all.
    pub const NONE: FaultRates = FaultRates {
        drop: 0.0,
        insert: 0.0,
        flip: 0.0,
        shift: 0.0,
        jitter: SimDuration::ZERO,
    };

    /// A total fault probability `rate` per pulse, shared equally by the four kinds.
    pub fn uniform(rate: PulseErrorRate) -> FaultRates {
        let r = rate.get() / 4.0;
        FaultRates {
            drop: r,
            insert: r,
            flip: r,
            shift: r,
            jitter: SimDuration::ZERO,
        }
    }

    /// `true` if this corrupts nothing and adds no jitter.
    pub fn is_clean(&self) -> bool {
        self.drop <= 0.0
            && self.insert <= 0.0
            && self.flip <= 0.0
            && self.shift <= 0.0
            && self.jitter.is_zero()
    }
}

fn clamp_probability(p: f64) -> f64 {
    if p.is_nan() {
        0.0
    } else {
        p.clamp(0.0, 1.0)
    }
}

/// A seeded source of pulse faults: the same seed and traffic give the same corruption.
#[derive(Clone, Debug)]
pub struct FaultInjector {
    /// `ChaCha8Rng::seed_from_u64(seed)`'s numbers (see [`stream`]).
    rng: FaultStream,
    rates: FaultRates,
    odds: Odds,
    half_bit: SimDuration,
    injected: u64,
}

/// The rates as Bernoulli distributions, made once instead of at every draw: a draw from one
/// takes the same random number and gives the same answer as `random_bool` with its
/// probability (rand's `random_bool` makes the same distribution and samples it), so the
/// random stream and the corruption stay what they were.
#[derive(Clone, Copy, Debug)]
struct Odds {
    drop: Bernoulli,
    flip: Bernoulli,
    shift: Bernoulli,
    insert: Bernoulli,
    half: Bernoulli,
    /// The thresholds of the drop, flip, shift and insert draws, in the order `corrupt` draws
    /// them for a pulse: a draw below its threshold is a fault. `None` where
    /// [`FaultInjector::pass_untouched`] cannot tell an untouched telegram by its draws alone:
    /// with jitter (a range draw of its own comes first for every pulse) or with a rate of 1
    /// (that fault happens without a draw).
    untouched: Option<[u64; 4]>,
}

impl Odds {
    fn of(r: &FaultRates) -> Odds {
        let b = |p: f64| {
            Bernoulli::new(clamp_probability(p)).expect("a clamped probability is in 0..=1")
        };
        let t = |p: f64| hit_threshold(clamp_probability(p));
        let untouched = match (t(r.drop), t(r.flip), t(r.shift), t(r.insert)) {
            (Some(d), Some(f), Some(s), Some(i)) if r.jitter.is_zero() => Some([d, f, s, i]),
            _ => None,
        };
        Odds {
            drop: b(r.drop),
            flip: b(r.flip),
            shift: b(r.shift),
            insert: b(r.insert),
            half: b(0.5),
            untouched,
        }
    }
}

/// The number below which a draw from rand's `Bernoulli::new(p)` is a hit, for a clamped `p`:
/// `Bernoulli` keeps it private, so it is worked out here as rand 0.9 does (`p` times 2^64,
/// truncated) and a test pins the two together. `None` for `p = 1`, which `Bernoulli` answers
/// with `true` without drawing a number at all.
fn hit_threshold(p: f64) -> Option<u64> {
    // 2^64; `p * SCALE` for the largest `p` below 1 is 2^64 - 2048, so the cast never saturates.
    const SCALE: f64 = 2.0 * (1u64 << 63) as f64;
    if p < 1.0 {
        Some((p * SCALE) as u64)
    } else {
        None
    }
}

impl FaultInjector {
    /// An injector with `rates` on the `half_bit` grid, seeded with `seed`.
    pub fn new(seed: u64, rates: FaultRates, half_bit: SimDuration) -> FaultInjector {
        FaultInjector {
            rng: FaultStream::seed_from_u64(seed),
            rates,
            odds: Odds::of(&rates),
            half_bit,
            injected: 0,
        }
    }

    /// Its rates.
    pub fn rates(&self) -> FaultRates {
        self.rates
    }

    /// Changes the rates; the random stream continues.
    pub fn set_rates(&mut self, rates: FaultRates) {
        self.rates = rates;
        self.odds = Odds::of(&rates);
    }

    /// Faults injected so far.
    pub fn injected(&self) -> u64 {
        self.injected
    }

    /// Takes the draws of a telegram of `pulses` pulses if the injector leaves it untouched,
    /// without looking at its pulses: returns `true` then, with the random stream and
    /// [`injected`](Self::injected) where [`corrupt`](Self::corrupt) would have left them (its
    /// output would have been the pulses as they are). Returns `false`, with nothing drawn, if a
    /// draw is a fault or the rates have jitter or a rate of 1; `corrupt` then does as ever.
    ///
    /// This is the noisy line's fast path: at realistic error rates most telegrams pass
    /// untouched, and this takes their random numbers without walking their pulses, building
    /// an output or sampling through `Bernoulli`.
    pub fn pass_untouched(&mut self, pulses: u32) -> bool {
        if self.rates.is_clean() {
            // `corrupt` draws nothing and copies.
            return true;
        }
        let Some(t) = self.odds.untouched else {
            return false;
        };
        // Why this is exact: without jitter, `corrupt` draws for every pulse from the four
        // Bernoulli odds (drop, then flip and shift, then insert), each sample one `next_u64`
        // compared with its threshold (none is 1, so none answers without drawing). A pulse
        // none of them hits takes exactly these four draws, all misses, and nothing else (the
        // `half` draws follow hits only). So an untouched telegram is exactly the next
        // 4 * `pulses` numbers of the stream all missing their thresholds in turn, which is
        // what `all_miss` draws and compares (all four of a pulse, as `corrupt` does for a
        // pulse without a fault). If one is a hit, the stream goes back to where it was, and
        // `corrupt` draws the same numbers again.
        self.rng.all_miss(&t, pulses)
    }

    /// Corrupts one telegram's `pulses` into `out` (cleared first); returns the number of
    /// faults injected. With clean rates `out` is a copy and no random number is drawn.
    pub fn corrupt<I: IntoIterator<Item = Pulse>>(
        &mut self,
        pulses: I,
        out: &mut Vec<Pulse>,
    ) -> u32 {
        out.clear();
        if self.rates.is_clean() {
            out.extend(pulses);
            return 0;
        }
        let r = self.odds;
        let h = self.half_bit.as_nanos() as i64;
        let j = self.rates.jitter.as_nanos() as i64;
        let mut faults = 0u32;
        let mut sorted = true;
        for p in pulses {
            let mut p = p;
            if j > 0 {
                p.at = shift(p.at, self.rng.random_range(-j..=j));
            }
            if self.rng.sample(r.drop) {
                faults += 1;
            } else {
                if self.rng.sample(r.flip) {
                    p.polarity = p.polarity.flipped();
                    faults += 1;
                }
                if self.rng.sample(r.shift) {
                    let by = if self.rng.sample(r.half) { h } else { -h };
                    p.at = shift(p.at, by);
                    faults += 1;
                    sorted = false;
                }
                out.push(p);
            }
            if self.rng.sample(r.insert) {
                let polarity = if self.rng.sample(r.half) {
                    Polarity::Positive
                } else {
                    Polarity::Negative
                };
                out.push(Pulse::new(
                    p.at + SimDuration::from_nanos(h as u64),
                    polarity,
                ));
                faults += 1;
                sorted = false;
            }
        }
        if !sorted {
            out.sort_by_key(|p| p.at);
        }
        self.injected += faults as u64;
        faults
    }
}

impl FaultInjector {
    /// Adds noise bursts to `wf` at random times: on average `per_ms` bursts a millisecond,
    /// each `duration` long with Gaussian noise of `rms` volts. Returns the bursts added, in time
    /// order, so a test can say which telegrams they hit.
    pub fn noise_bursts(
        &mut self,
        wf: &mut Waveform,
        per_ms: f64,
        duration: SimDuration,
        rms: f32,
    ) -> Vec<NoiseBurst> {
        let span_ns = wf.samples.len() as f64 * wf.period_ns;
        let rate_per_ns = clamp_rate(per_ms) / 1e6;
        let mut bursts = Vec::new();
        if rate_per_ns <= 0.0 || !span_ns.is_finite() {
            return bursts;
        }
        // Exponential gaps between bursts: a Poisson process.
        let mut t = 0.0f64;
        loop {
            let u: f64 = self.rng.random::<f64>().max(f64::MIN_POSITIVE);
            t += -u.ln() / rate_per_ns;
            if t >= span_ns {
                break;
            }
            let burst = NoiseBurst {
                start: wf.start + SimDuration::from_nanos(t as u64),
                duration,
                rms,
            };
            wf.add_burst(&burst, self.rng.random());
            bursts.push(burst);
            self.injected += 1;
        }
        bursts
    }
}

fn clamp_rate(r: f64) -> f64 {
    if r.is_finite() {
        r.max(0.0)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::waveform::{render, WaveformConfig};

    fn p(us: u64, pos: bool) -> Pulse {
        Pulse::new(
            SimTime::from_micros(us),
            if pos {
                Polarity::Positive
            } else {
                Polarity::Negative
            },
        )
    }

    use proptest::prelude::Just;

    proptest::proptest! {
        #[test]
        fn the_injectors_odds_draw_as_random_bool_does(
            seed in proptest::prelude::any::<u64>(),
            rates in proptest::collection::vec(
                proptest::prop_oneof![
                    Just(0.0), Just(1.0), 0.0..1.0f64, Just(f64::NAN)
                ], 4),
            jitter in proptest::prop_oneof![Just(0u64), 1..500u64],
            telegrams in 1..40usize,
        ) {
            let r = FaultRates {
                drop: rates[0],
                insert: rates[1],
                flip: rates[2],
                shift: rates[3],
                jitter: SimDuration::from_nanos(jitter),
            };
            let h = SimDuration::from_nanos(3_000);
            let mut inj = FaultInjector::new(seed, r, h);
            let mut reference = ChaCha8Rng::seed_from_u64(seed);
            let mut out = Vec::new();
            for k in 0..telegrams as u64 {
                let Ok(q) = crate::Request::from_bits((k * 977 % 16384) as u16) else {
                    continue;
                };
                let train = PulseTrain::request(q, SimTime::from_micros(200 * k), h);
                let pulses: Vec<Pulse> = train.iter().collect();
                let faults = inj.corrupt(pulses.iter().copied(), &mut out);
                let (want, want_faults) = corrupt_pulse_by_pulse(&mut reference, r, 3_000, pulses.iter().copied());
                proptest::prop_assert_eq!(faults, want_faults);
                // Pulses at the same time may come in either order; the line sorts them so.
                let mut got = out.clone();
                got.sort_by_key(|p| (p.at, p.polarity == Polarity::Positive));
                let mut want = want;
                want.sort_by_key(|p| (p.at, p.polarity == Polarity::Positive));
                proptest::prop_assert_eq!(got, want);
            }
        }
    }

    /// `corrupt` pulse by pulse, as it was written first and before
    /// [`FaultInjector::pass_untouched`], with `random_bool` at every draw instead of the
    /// injector's odds: the reference both the odds (made once) and the quick path must match,
    /// down to the order of the output.
    fn corrupt_pulse_by_pulse(
        rng: &mut ChaCha8Rng,
        r: FaultRates,
        h: i64,
        pulses: impl IntoIterator<Item = Pulse>,
    ) -> (Vec<Pulse>, u32) {
        let mut out = Vec::new();
        if r.is_clean() {
            out.extend(pulses);
            return (out, 0);
        }
        let j = r.jitter.as_nanos() as i64;
        let mut faults = 0u32;
        let mut sorted = true;
        for p in pulses {
            let mut p = p;
            if j > 0 {
                p.at = shift(p.at, rng.random_range(-j..=j));
            }
            if rng.random_bool(clamp_probability(r.drop)) {
                faults += 1;
            } else {
                if rng.random_bool(clamp_probability(r.flip)) {
                    p.polarity = p.polarity.flipped();
                    faults += 1;
                }
                if rng.random_bool(clamp_probability(r.shift)) {
                    let by = if rng.random_bool(0.5) { h } else { -h };
                    p.at = shift(p.at, by);
                    faults += 1;
                    sorted = false;
                }
                out.push(p);
            }
            if rng.random_bool(clamp_probability(r.insert)) {
                let polarity = if rng.random_bool(0.5) {
                    Polarity::Positive
                } else {
                    Polarity::Negative
                };
                out.push(Pulse::new(
                    p.at + SimDuration::from_nanos(h as u64),
                    polarity,
                ));
                faults += 1;
                sorted = false;
            }
        }
        if !sorted {
            out.sort_by_key(|p| p.at);
        }
        (out, faults)
    }

    /// A rate for the quick-path test: the edges (0, 1, NaN, the smallest and the largest
    /// below 1), rates as low as a real line's, at which most telegrams pass untouched, and
    /// any probability, at which most are hit.
    fn any_rate() -> impl proptest::strategy::Strategy<Value = f64> {
        proptest::prop_oneof![
            Just(0.0),
            Just(1.0),
            Just(f64::NAN),
            Just(f64::MIN_POSITIVE),
            Just(1.0 - f64::EPSILON),
            0.0..1e-12f64,
            0.0..1e-2f64,
            0.0..1.0f64,
        ]
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(512))]
        #[test]
        fn the_quick_path_corrupts_as_pulse_by_pulse_does(
            seed in proptest::prelude::any::<u64>(),
            rates in proptest::collection::vec(any_rate(), 8),
            jitter in proptest::prop_oneof![3 => Just(0u64), 1 => 1..500u64],
            switch_at in 0..60usize,
            telegrams in proptest::collection::vec(
                (proptest::prelude::any::<u32>(), 0..=16u32, proptest::prelude::any::<bool>()),
                1..60,
            ),
        ) {
            let rates_of = |r: &[f64], jitter| FaultRates {
                drop: r[0],
                insert: r[1],
                flip: r[2],
                shift: r[3],
                jitter: SimDuration::from_nanos(jitter),
            };
            // The rates change once, the second ones without jitter.
            let (first, second) = (rates_of(&rates[..4], jitter), rates_of(&rates[4..], 0));
            let h = SimDuration::from_nanos(3_000);
            let mut inj = FaultInjector::new(seed, first, h);
            let mut reference = ChaCha8Rng::seed_from_u64(seed);
            let mut reference_injected = 0u64;
            let mut out = Vec::new();
            for (k, &(bits, n, odd)) in telegrams.iter().enumerate() {
                if k == switch_at {
                    inj.set_rates(second);
                }
                let r = if k < switch_at { first } else { second };
                // Something else (noise bursts) may have left the stream at an odd word.
                if odd {
                    inj.rng.next_u32();
                    reference.next_u32();
                }
                let train = PulseTrain::from_half_bits(
                    crate::HalfBits::encode(bits, n),
                    SimTime::from_micros(200 * k as u64),
                    h,
                );
                let (got, got_faults) = if inj.pass_untouched(train.len()) {
                    (train.iter().collect(), 0)
                } else {
                    let faults = inj.corrupt(train.iter(), &mut out);
                    (out.clone(), faults)
                };
                let (want, want_faults) = corrupt_pulse_by_pulse(&mut reference, r, 3_000, train.iter());
                reference_injected += want_faults as u64;
                proptest::prop_assert_eq!(got, want);
                proptest::prop_assert_eq!(got_faults, want_faults);
                proptest::prop_assert_eq!(inj.injected(), reference_injected);
                // The same stream from here on: same seed, stream and word position.
                proptest::prop_assert_eq!(&inj.rng, &reference);
            }
            for _ in 0..8 {
                proptest::prop_assert_eq!(inj.rng.next_u64(), reference.next_u64());
            }
        }
    }

    /// A source of random numbers that answers every draw with `value` and counts the draws.
    struct Fixed {
        value: u64,
        draws: u32,
    }

    impl RngCore for Fixed {
        fn next_u32(&mut self) -> u32 {
            self.draws += 1;
            self.value as u32
        }
        fn next_u64(&mut self) -> u64 {
            self.draws += 1;
            self.value
        }
        fn fill_bytes(&mut self, dst: &mut [u8]) {
            for chunk in dst.chunks_mut(8) {
                let v = self.next_u64().to_le_bytes();
                chunk.copy_from_slice(&v[..chunk.len()]);
            }
        }
    }

    /// `hit_threshold` is exactly where rand's `Bernoulli` turns from a hit to a miss: a draw
    /// one below it hits, a draw of it misses, and every sample takes one draw; for p = 1
    /// there is no threshold and `Bernoulli` answers without a draw.
    #[test]
    fn the_hit_threshold_is_where_bernoulli_turns() {
        let two_64 = 2f64.powi(64);
        let mut ps = vec![
            0.0,
            -0.0,
            f64::NAN,
            -1.0,
            2.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            5e-324,
            f64::MIN_POSITIVE,
            1e-300,
            1e-20,
            1.0 / two_64,
            0.5 / two_64,
            1.5 / two_64,
            3.0 / two_64,
            1e-3 / 4.0,
            2.5e-4,
            0.1,
            1.0 / 3.0,
            0.5,
            0.5 + f64::EPSILON,
            0.999,
            1.0 - f64::EPSILON,
            1.0 - f64::EPSILON / 2.0,
            1.0,
        ];
        let mut rng = ChaCha8Rng::seed_from_u64(64);
        for _ in 0..20_000 {
            let u: f64 = rng.random();
            // Uniform ones, and tiny ones spread over many magnitudes.
            ps.push(u);
            ps.push(u.powi(rng.random_range(2..200)));
            ps.push((rng.random_range(0..1u64 << 20) as f64) / two_64);
        }
        let sample = |b: &Bernoulli, value: u64| {
            let mut f = Fixed { value, draws: 0 };
            let hit = f.sample(b);
            (hit, f.draws)
        };
        for p in ps {
            let p = clamp_probability(p);
            let b = Bernoulli::new(p).expect("a clamped probability");
            match hit_threshold(p) {
                None => {
                    assert_eq!(p, 1.0);
                    assert_eq!(sample(&b, 0), (true, 0), "p = 1 draws nothing");
                    assert_eq!(sample(&b, u64::MAX), (true, 0));
                }
                Some(t) => {
                    assert_eq!(sample(&b, t), (false, 1), "p = {p:e}, threshold {t}");
                    if t > 0 {
                        assert_eq!(sample(&b, t - 1), (true, 1), "p = {p:e}, threshold {t}");
                    }
                    assert_eq!(sample(&b, u64::MAX), (false, 1), "p = {p:e}");
                    assert_eq!(sample(&b, 0), (t > 0, 1), "p = {p:e}");
                }
            }
        }
    }

    /// At a real line's rate most telegrams take the quick path, and one that is hit leaves
    /// the stream where it was: the quick path is used, not merely harmless.
    #[test]
    fn most_telegrams_pass_untouched_at_a_low_rate() {
        let h = SimDuration::from_micros(3);
        let rates = FaultRates::uniform(PulseErrorRate::new(1e-3).expect("a probability"));
        let mut inj = FaultInjector::new(3, rates, h);
        let mut passed = 0;
        let mut hit = 0;
        for k in 0..2000u64 {
            // A valid request: start bit 0, even parity, end bit 1.
            let body = (k * 977 % 2048) as u16;
            let bits = (body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1;
            let q = crate::Request::from_bits(bits).expect("a valid request");
            let train = PulseTrain::request(q, SimTime::from_micros(200 * k), h);
            let before = inj.rng.clone();
            if inj.pass_untouched(train.len()) {
                passed += 1;
                assert_ne!(inj.rng, before);
            } else {
                hit += 1;
                assert_eq!(inj.rng, before);
                let mut out = Vec::new();
                assert!(inj.corrupt(train.iter(), &mut out) > 0);
            }
        }
        assert!(passed > 1800 && hit > 0, "{passed} passed, {hit} hit");
        // With jitter or a certain fault the quick path stands aside.
        for rates in [
            FaultRates {
                jitter: SimDuration::from_nanos(10),
                ..rates
            },
            FaultRates { flip: 1.0, ..rates },
        ] {
            let mut inj = FaultInjector::new(3, rates, h);
            let before = inj.rng.clone();
            assert!(!inj.pass_untouched(14));
            assert_eq!(inj.rng, before);
        }
    }

    #[test]
    fn exact_faults_do_what_they_say() {
        let base = [p(0, false), p(3, true), p(6, false), p(9, true)];
        let mut out = Vec::new();
        apply_faults(
            &base,
            &[
                PulseFault::Drop { index: 1 },
                PulseFault::Flip { index: 2 },
                PulseFault::Shift {
                    index: 3,
                    by_ns: -4000,
                },
                PulseFault::Insert {
                    at: SimTime::from_micros(12),
                    polarity: Polarity::Negative,
                },
                PulseFault::Drop { index: 99 },
            ],
            &mut out,
        );
        assert_eq!(out, [p(0, false), p(5, true), p(6, true), p(12, false)]);
    }

    #[test]
    fn the_injector_is_deterministic_per_seed_and_counts_its_faults() {
        let base: Vec<Pulse> = (0..1000).map(|k| p(3 * k, k % 2 == 1)).collect();
        let h = SimDuration::from_micros(3);
        let run = |seed| {
            let mut inj = FaultInjector::new(
                seed,
                FaultRates::uniform(PulseErrorRate::new(0.1).expect("a probability")),
                h,
            );
            let mut out = Vec::new();
            let n = inj.corrupt(base.iter().copied(), &mut out);
            (n, out)
        };
        let (n1, a) = run(7);
        let (n2, b) = run(7);
        let (_, c) = run(8);
        assert_eq!((n1, &a), (n2, &b));
        assert_ne!(a, c);
        // 1000 pulses at 10 %: the count is near 100.
        assert!((60..=140).contains(&n1), "{n1}");
        assert!(a.windows(2).all(|w| w[0].at <= w[1].at));
    }

    #[test]
    fn noise_bursts_are_seeded_and_land_inside_the_waveform() {
        let quiet = render(
            [],
            SimTime::ZERO,
            SimTime::from_millis(10),
            &WaveformConfig::default(),
        )
        .expect("render");
        let run = |seed| {
            let mut wf = quiet.clone();
            let mut inj = FaultInjector::new(seed, FaultRates::NONE, SimDuration::from_micros(3));
            let bursts = inj.noise_bursts(&mut wf, 2.0, SimDuration::from_micros(5), 1.0);
            (bursts, wf)
        };
        let (a, wa) = run(5);
        let (b, wb) = run(5);
        assert_eq!((&a, &wa), (&b, &wb));
        // 2 per ms over 10 ms: about 20.
        assert!((8..=35).contains(&a.len()), "{}", a.len());
        assert!(a.windows(2).all(|w| w[0].start <= w[1].start));
        assert!(a.iter().all(|b| b.start < SimTime::from_millis(10)));
        // Noise only where a burst is.
        let noisy = wa.samples.iter().filter(|v| **v != 0.0).count();
        assert!(noisy > 0 && noisy <= a.len() * 50, "{noisy}");
        let mut none = quiet.clone();
        let mut inj = FaultInjector::new(5, FaultRates::NONE, SimDuration::from_micros(3));
        assert!(inj
            .noise_bursts(&mut none, f64::NAN, SimDuration::from_micros(5), 1.0)
            .is_empty());
    }

    #[test]
    fn clean_rates_copy_the_pulses() {
        let base = [p(0, false), p(3, true)];
        let mut inj = FaultInjector::new(1, FaultRates::NONE, SimDuration::from_micros(3));
        let mut out = Vec::new();
        assert_eq!(inj.corrupt(base, &mut out), 0);
        assert_eq!(out, base);
        for bad in [f64::NAN, -0.1, 1.5, f64::INFINITY] {
            assert!(PulseErrorRate::new(bad).is_err(), "{bad}");
        }
        assert_eq!(FaultRates::uniform(PulseErrorRate::ZERO), FaultRates::NONE);
    }
}
