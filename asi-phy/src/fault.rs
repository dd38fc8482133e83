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
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

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
#[error(
    "{}: a pulse error rate is a probability, 0..=1",
    crate::short_number(*.0)
)]
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
///
/// **The model**: every pulse is lost with probability `drop`; a pulse that is not lost has
/// the wrong sign with probability `flip` and is moved one grid step with probability
/// `shift`; after every pulse a spurious one appears with probability `insert`; all of these
/// independent, for every pulse alike.
///
/// **Decision: the faults are drawn by their gaps.** The injector does not draw four numbers
/// for every pulse. It draws how many pulses pass untouched before the next one that some
/// fault touches (a geometric number, one logarithm of a uniform draw), lets that many pass
/// without a draw, and for the touched pulse draws which faults hit it, each under the
/// condition that at least one does. That is the same model, pulse for pulse (the probability
/// of every combination of faults on every pulse, and the independence of the pulses), drawn
/// far less often: at 10⁻³ the line draws about once in a thousand pulses instead of four
/// times a pulse, so a noisy line costs little more than a quiet one (docs/timing.md, *Error
/// model*). Jitter (when set) is still a draw per pulse.
#[derive(Clone, Debug)]
pub struct FaultInjector {
    rng: ChaCha8Rng,
    rates: FaultRates,
    odds: Odds,
    half_bit: SimDuration,
    injected: u64,
    /// Pulses still to pass untouched before the next one a fault touches (`u64::MAX` with
    /// no fault rate: never).
    gap: u64,
}

/// The model's rates as the gap draw needs them, worked out once per set of rates.
#[derive(Clone, Copy, Debug)]
struct Odds {
    /// ln(1 − q), q the probability that a fault touches a pulse: the gaps' geometric
    /// distribution. 0 when no fault can happen (no gap ends), −∞ when every pulse is
    /// touched.
    ln_untouched: f64,
    /// A touched pulse is lost: drop / q.
    drop: Bernoulli,
    /// A touched pulse that is not lost has the wrong sign: flip / (1 − (1 − flip)(1 − shift)
    /// (1 − insert)), the probability of at least one of the three that are left.
    flip: Bernoulli,
    /// A touched pulse, neither lost nor flipped, is moved: shift / (1 − (1 − shift)(1 − insert)).
    /// Neither lost, flipped nor moved, it must be followed by a spurious pulse.
    shift: Bernoulli,
    /// The plain rates, for the faults that come on top of the one that touched the pulse.
    plain_shift: Bernoulli,
    plain_insert: Bernoulli,
    /// Either sign, either way.
    half: Bernoulli,
}

impl Odds {
    fn of(r: &FaultRates) -> Odds {
        let (d, f, s, i) = (
            clamp_probability(r.drop),
            clamp_probability(r.flip),
            clamp_probability(r.shift),
            clamp_probability(r.insert),
        );
        // ln(1 − p) summed: exact for the smallest rates, where 1 − (1 − p) is not.
        let ln_none = |ps: &[f64]| ps.iter().map(|p| (-p).ln_1p()).sum::<f64>();
        let plain = |p: f64| Bernoulli::new(p).expect("a clamped probability is in 0..=1");
        // `p` under the condition that it or one of `rest` happens, p / (1 − (1 − p)·Π(1 − r)):
        // certain if none of `rest` can (so that rounding never sends a draw down a branch of
        // probability 0).
        let given = |p: f64, rest: &[f64]| {
            if ln_none(rest) == 0.0 {
                return plain(1.0);
            }
            let ln_neither = rest.iter().fold((-p).ln_1p(), |a, r| a + (-r).ln_1p());
            plain((p / -ln_neither.exp_m1()).clamp(0.0, 1.0))
        };
        Odds {
            ln_untouched: ln_none(&[d, f, s, i]),
            drop: given(d, &[f, s, i]),
            flip: given(f, &[s, i]),
            shift: given(s, &[i]),
            plain_shift: plain(s),
            plain_insert: plain(i),
            half: plain(0.5),
        }
    }
}

/// What the faults do to one touched pulse.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
struct Touch {
    drop: bool,
    flip: bool,
    shift: bool,
    insert: bool,
}

impl FaultInjector {
    /// An injector with `rates` on the `half_bit` grid, seeded with `seed`.
    pub fn new(seed: u64, rates: FaultRates, half_bit: SimDuration) -> FaultInjector {
        let mut inj = FaultInjector {
            rng: ChaCha8Rng::seed_from_u64(seed),
            rates,
            odds: Odds::of(&rates),
            half_bit,
            injected: 0,
            gap: u64::MAX,
        };
        inj.gap = inj.draw_gap();
        inj
    }

    /// Its rates.
    pub fn rates(&self) -> FaultRates {
        self.rates
    }

    /// Changes the rates; the random stream continues, and the gap to the next touched pulse
    /// is drawn again for the new rates (the pulses to come do not remember the old ones).
    pub fn set_rates(&mut self, rates: FaultRates) {
        self.rates = rates;
        self.odds = Odds::of(&rates);
        self.gap = self.draw_gap();
    }

    /// Faults injected so far.
    pub fn injected(&self) -> u64 {
        self.injected
    }

    /// The number of pulses that pass untouched before the next touched one: geometric,
    /// P(gap ≥ k) = (1 − q)^k, one uniform draw; `u64::MAX` (never) without a fault rate.
    fn draw_gap(&mut self) -> u64 {
        let ln_untouched = self.odds.ln_untouched;
        if ln_untouched == 0.0 {
            return u64::MAX;
        }
        // u in (0, 1]: ln u ≤ 0, and ln u / ln(1 − q) ≥ k exactly when u ≤ (1 − q)^k. Every
        // pulse touched (q = 1, ln(1 − q) = −∞) gives 0; the cast saturates far out.
        let u = 1.0 - self.rng.random::<f64>();
        let gap = (u.ln() / ln_untouched).floor();
        if gap.is_nan() {
            0
        } else {
            gap as u64
        }
    }

    /// What the faults do to the next pulse: `None` if it passes untouched.
    #[inline]
    fn touch_next(&mut self) -> Option<Touch> {
        if self.gap > 0 {
            self.gap -= 1;
            None
        } else {
            Some(self.draw_touch())
        }
    }

    /// The faults on a pulse that at least one touches, each drawn under that condition
    /// (see [`Odds`]); then the next gap.
    fn draw_touch(&mut self) -> Touch {
        let o = self.odds;
        let mut t = Touch::default();
        if self.rng.sample(o.drop) {
            t.drop = true;
            t.insert = self.rng.sample(o.plain_insert);
        } else if self.rng.sample(o.flip) {
            t.flip = true;
            t.shift = self.rng.sample(o.plain_shift);
            t.insert = self.rng.sample(o.plain_insert);
        } else if self.rng.sample(o.shift) {
            t.shift = true;
            t.insert = self.rng.sample(o.plain_insert);
        } else {
            t.insert = true;
        }
        self.gap = self.draw_gap();
        t
    }

    /// Lets a telegram of `pulses` pulses pass if the injector leaves it untouched, without
    /// looking at its pulses: returns `true` then, with the injector where
    /// [`corrupt`](Self::corrupt) would have left it (its output would have been the pulses as
    /// they are). Returns `false`, with nothing changed, if a fault touches one of them or the
    /// rates have jitter (a draw for every pulse); `corrupt` then does as ever.
    ///
    /// This is the noisy line's fast path: at realistic error rates most telegrams fall
    /// within a gap between touched pulses.
    #[inline]
    pub fn pass_untouched(&mut self, pulses: u32) -> bool {
        if self.rates.is_clean() {
            // `corrupt` draws nothing and copies.
            return true;
        }
        if !self.rates.jitter.is_zero() || self.gap < u64::from(pulses) {
            return false;
        }
        self.gap -= u64::from(pulses);
        true
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
        let h = self.half_bit.as_nanos() as i64;
        let j = self.rates.jitter.as_nanos() as i64;
        let mut faults = 0u32;
        let mut sorted = true;
        for p in pulses {
            let mut p = p;
            if j > 0 {
                p.at = shift(p.at, self.rng.random_range(-j..=j));
            }
            let Some(t) = self.touch_next() else {
                out.push(p);
                continue;
            };
            if t.drop {
                faults += 1;
            } else {
                if t.flip {
                    p.polarity = p.polarity.flipped();
                    faults += 1;
                }
                if t.shift {
                    let by = if self.rng.sample(self.odds.half) {
                        h
                    } else {
                        -h
                    };
                    p.at = shift(p.at, by);
                    faults += 1;
                    sorted = false;
                }
                out.push(p);
            }
            if t.insert {
                let polarity = if self.rng.sample(self.odds.half) {
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
    use rand::RngCore;

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
        /// A telegram let through by `pass_untouched` is what `corrupt` would have made of it,
        /// and leaves the injector where `corrupt` would have: two injectors of one seed, one
        /// trying the quick path first, the other always `corrupt`, stay the same throughout.
        #[test]
        fn the_quick_path_corrupts_as_corrupt_does(
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
            let mut reference = FaultInjector::new(seed, first, h);
            let (mut out, mut want) = (Vec::new(), Vec::new());
            for (k, &(bits, n, odd)) in telegrams.iter().enumerate() {
                if k == switch_at {
                    inj.set_rates(second);
                    reference.set_rates(second);
                }
                // Something else (noise bursts) may have drawn from the stream.
                if odd {
                    inj.rng.next_u32();
                    reference.rng.next_u32();
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
                let want_faults = reference.corrupt(train.iter(), &mut want);
                proptest::prop_assert_eq!(&got, &want);
                proptest::prop_assert_eq!(got_faults, want_faults);
                proptest::prop_assert_eq!(inj.injected(), reference.injected());
                proptest::prop_assert_eq!(inj.gap, reference.gap);
                proptest::prop_assert_eq!(inj.rng.get_word_pos(), reference.rng.get_word_pos());
            }
        }
    }

    /// The combinations of faults on one pulse, each with its probability under the model
    /// (the four independent per-pulse rates; flip and shift only on a pulse not lost).
    fn model_odds(r: &FaultRates) -> Vec<(Option<Touch>, f64)> {
        let mut odds = vec![(
            None,
            (1.0 - r.drop) * (1.0 - r.flip) * (1.0 - r.shift) * (1.0 - r.insert),
        )];
        let p = |on: bool, x: f64| if on { x } else { 1.0 - x };
        for insert in [false, true] {
            let t = Touch {
                drop: true,
                insert,
                ..Touch::default()
            };
            odds.push((Some(t), r.drop * p(insert, r.insert)));
            for flip in [false, true] {
                for shift in [false, true] {
                    if flip || shift || insert {
                        let t = Touch {
                            drop: false,
                            flip,
                            shift,
                            insert,
                        };
                        let q = (1.0 - r.drop)
                            * p(flip, r.flip)
                            * p(shift, r.shift)
                            * p(insert, r.insert);
                        odds.push((Some(t), q));
                    }
                }
            }
        }
        odds
    }

    /// Pearson's χ² of the counts `seen` against the probabilities `odds` over `n` trials.
    fn chi_square<K: Eq + std::hash::Hash>(
        odds: &[(K, f64)],
        seen: &std::collections::HashMap<K, u64>,
        n: u64,
    ) -> f64 {
        assert_eq!(seen.values().sum::<u64>(), n);
        assert!(
            seen.keys().all(|k| odds.iter().any(|(o, _)| o == k)),
            "a combination the model does not have"
        );
        odds.iter()
            .map(|(k, p)| {
                let e = p * n as f64;
                let o = seen.get(k).copied().unwrap_or(0) as f64;
                (o - e) * (o - e) / e
            })
            .sum()
    }

    /// The gap draw makes the per-pulse model: over 200,000 pulses, the ten combinations of
    /// faults on a pulse come as often as the four independent rates say (χ², 9 degrees of
    /// freedom, below 40: p < 10⁻⁵ for a sound injector), and whether a pulse is touched is
    /// independent of whether the one before was (χ² of the 2 × 2 table of neighbours against
    /// the model's four cells, 3 degrees of freedom, below 25). A gap one too long, or a
    /// drop drawn without its condition, is far outside (both tried).
    #[test]
    fn the_gaps_make_the_per_pulse_model() {
        let h = SimDuration::from_micros(3);
        for (seed, drop, insert, flip, shift) in [
            (1u64, 0.05, 0.04, 0.03, 0.02),
            (2, 0.02, 0.02, 0.02, 0.02),
            (3, 0.3, 0.0, 0.2, 0.1),
            (4, 0.0, 0.1, 0.0, 0.05),
            (5, 0.6, 0.5, 0.7, 0.4),
        ] {
            let r = FaultRates {
                drop,
                insert,
                flip,
                shift,
                jitter: SimDuration::ZERO,
            };
            let odds: Vec<_> = model_odds(&r)
                .into_iter()
                .filter(|(_, p)| *p > 0.0)
                .collect();
            let mut inj = FaultInjector::new(seed, r, h);
            let n = 200_000u64;
            let mut seen = std::collections::HashMap::new();
            let mut pairs = std::collections::HashMap::new();
            let mut before = None;
            for _ in 0..n {
                let t = inj.touch_next();
                *seen.entry(t).or_insert(0u64) += 1;
                if let Some(b) = before {
                    *pairs.entry((b, t.is_some())).or_insert(0u64) += 1;
                }
                before = Some(t.is_some());
            }
            let x = chi_square(&odds, &seen, n);
            assert!(
                x < 40.0,
                "rates {r:?}: χ² {x} over {} combinations, {seen:?}",
                odds.len()
            );
            let q = 1.0 - odds[0].1;
            let pair_odds = [
                ((false, false), (1.0 - q) * (1.0 - q)),
                ((false, true), (1.0 - q) * q),
                ((true, false), q * (1.0 - q)),
                ((true, true), q * q),
            ];
            let y = chi_square(&pair_odds, &pairs, n - 1);
            assert!(y < 25.0, "rates {r:?}: neighbours' χ² {y}, {pairs:?}");
        }
    }

    /// Rates of 0 and 1: a rate of 1 touches every pulse with that fault, a rate of 0 never
    /// draws it, and a line with only jitter injects no fault.
    #[test]
    fn certain_and_impossible_faults() {
        let h = SimDuration::from_micros(3);
        let train: Vec<Pulse> = (0..200).map(|k| p(20 * k, k % 2 == 0)).collect();
        let mut out = Vec::new();
        let flips = FaultRates {
            flip: 1.0,
            ..FaultRates::NONE
        };
        let mut inj = FaultInjector::new(9, flips, h);
        assert_eq!(inj.corrupt(train.iter().copied(), &mut out), 200);
        let flipped: Vec<Pulse> = train
            .iter()
            .map(|q| Pulse::new(q.at, q.polarity.flipped()))
            .collect();
        assert_eq!(out, flipped);
        let drops = FaultRates {
            drop: 1.0,
            ..FaultRates::NONE
        };
        let mut inj = FaultInjector::new(9, drops, h);
        assert_eq!(inj.corrupt(train.iter().copied(), &mut out), 200);
        assert!(out.is_empty());
        let jitter = FaultRates {
            jitter: SimDuration::from_nanos(100),
            ..FaultRates::NONE
        };
        let mut inj = FaultInjector::new(9, jitter, h);
        assert_eq!(inj.corrupt(train.iter().copied(), &mut out), 0);
        assert_eq!(out.len(), 200);
        assert!(out
            .iter()
            .zip(&train)
            .all(|(a, b)| a.at.as_nanos().abs_diff(b.at.as_nanos()) <= 100));
        assert!(!inj.pass_untouched(1), "jitter is a draw for every pulse");
        // The smallest rate: the gap is finite but long, and the injector still works.
        let tiny = FaultRates {
            shift: f64::MIN_POSITIVE,
            ..FaultRates::NONE
        };
        let mut inj = FaultInjector::new(9, tiny, h);
        assert!(inj.gap > 1 << 60, "{}", inj.gap);
        assert!(inj.pass_untouched(200));
        assert_eq!(inj.corrupt(train.iter().copied(), &mut out), 0);
    }

    /// At a real line's rate most telegrams take the quick path, which draws nothing, and
    /// one that is hit leaves the injector as it was: the quick path is used, not merely
    /// harmless.
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
            let (gap, pos) = (inj.gap, inj.rng.get_word_pos());
            if inj.pass_untouched(train.len()) {
                passed += 1;
                assert_eq!(inj.gap, gap - u64::from(train.len()));
                assert_eq!(inj.rng.get_word_pos(), pos);
            } else {
                hit += 1;
                assert_eq!((inj.gap, inj.rng.get_word_pos()), (gap, pos));
                let mut out = Vec::new();
                assert!(inj.corrupt(train.iter(), &mut out) > 0);
            }
        }
        assert!(passed > 1900 && hit > 0, "{passed} passed, {hit} hit");
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
