//! How many pulse faults does it take to fool the seven receiver checks?
//!
//! `cargo run --release -p asi-lift-phy --example residual_errors`
//!
//! 1. The exact minimum, over every pair of distinct valid telegrams of one kind, of the number
//!    of pulse faults (drop, insert, flip, shift by one grid step) that turns one telegram's
//!    pulse train into the other's (also shifted by up to two grid points): the smallest
//!    number of faults that yields a wrong telegram accepted as valid.
//! 2. Exhaustively, every pair of single faults on every valid telegram, through the real
//!    receiver: how many are detected, how many yield a wrong valid telegram.
//! 3. Random corruption at several per-pulse rates (seeded): the undetected-error rate.
//!
//! The published claim to compare with: an effective Hamming distance of 5
//! (feldbusse.de, docs/asi.md §3.2).

use asi_phy::fault::{apply_faults, single_faults, FaultInjector, FaultRates, PulseFault};
use asi_phy::{
    BusTiming, Expect, Nibble, Polarity, Pulse, PulseTrain, Receiver, Request, Response, SimTime,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Kind {
    Request,
    Response,
}

fn trains(kind: Kind, start: SimTime) -> Vec<(u16, PulseTrain)> {
    let h = BusTiming::default().half_bit();
    match kind {
        Kind::Request => (0u16..1 << 11)
            .map(|body| {
                let bits = (body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1;
                let r = Request::from_bits(bits).expect("valid");
                (bits, PulseTrain::request(r, start, h))
            })
            .collect(),
        Kind::Response => (0u8..16)
            .map(|v| {
                let r = Response::new(Nibble::from_low_bits(v));
                (r.bits() as u16, PulseTrain::response(r, start, h))
            })
            .collect(),
    }
}

/// Grid symbols of a train: 0 none, 1 negative, 2 positive, over points `-pad..len+pad`.
fn symbols(t: &PulseTrain, offset: i32, width: usize) -> Vec<u8> {
    let mut v = vec![0u8; width];
    for k in 0..t.grid_points() {
        if let Some(p) = t.pulse_at(k) {
            let i = k as i32 + offset;
            v[i as usize] = if p.polarity == Polarity::Negative {
                1
            } else {
                2
            };
        }
    }
    v
}

/// Fewest faults turning grid `a` into grid `b`: a mismatched point costs one (drop, insert
/// or flip); a pulse moved to a free neighbouring point costs one for both points.
fn fault_distance(a: &[u8], b: &[u8]) -> u32 {
    let n = a.len();
    let mut dp = vec![0u32; n + 1];
    for k in 0..n {
        let single = dp[k] + (a[k] != b[k]) as u32;
        let mut best = single;
        if k >= 1 {
            let (a0, b0, a1, b1) = (a[k - 1], b[k - 1], a[k], b[k]);
            let right = a0 != 0 && b0 == 0 && a1 == 0 && b1 == a0;
            let left = a0 == 0 && b0 != 0 && a1 == b0 && b1 == 0;
            if right || left {
                best = best.min(dp[k - 1] + 1);
            }
        }
        dp[k + 1] = best;
    }
    dp[n]
}

fn minimum_distance(kind: Kind) -> (u32, u64, String) {
    let all = trains(kind, SimTime::ZERO);
    let pad = 2i32;
    let width = all[0].1.grid_points() as usize + 2 * pad as usize;
    let grids: Vec<Vec<u8>> = all.iter().map(|(_, t)| symbols(t, pad, width)).collect();
    let shifted: Vec<Vec<Vec<u8>>> = all
        .iter()
        .map(|(_, t)| (-pad..=pad).map(|d| symbols(t, pad + d, width)).collect())
        .collect();
    let (mut best, mut count, mut example) = (u32::MAX, 0u64, String::new());
    for (i, a) in grids.iter().enumerate() {
        for (j, bs) in shifted.iter().enumerate() {
            if i == j {
                continue;
            }
            for (d, b) in bs.iter().enumerate() {
                let dist = fault_distance(a, b);
                if dist < best {
                    best = dist;
                    count = 0;
                    example = format!(
                        "{:0w$b} -> {:0w$b} (offset {} grid steps)\n      {}\n   -> {}",
                        all[i].0,
                        all[j].0,
                        d as i32 - pad,
                        all[i].1,
                        all[j].1,
                        w = if kind == Kind::Request { 14 } else { 7 }
                    );
                }
                if dist == best {
                    count += 1;
                }
            }
        }
    }
    (best, count, example)
}

/// Counts of outcomes.
#[derive(Default, Debug)]
struct Tally {
    trials: u64,
    /// Telegrams that received at least one fault.
    faulted: u64,
    /// Some telegram reported invalid (or nothing at all received).
    detected: u64,
    /// Everything valid, but not the telegram sent.
    undetected: u64,
    /// Everything valid and exactly the telegram sent.
    intact: u64,
}

/// Decodes a possibly corrupted telegram and counts the outcome.
fn classify(rx: &mut Receiver, pulses: &[Pulse], original: u16, tally: &mut Tally) {
    rx.reset();
    let mut all_valid = true;
    let mut wrong = false;
    let mut frames = 0;
    let mut see = |r: asi_phy::Received| {
        frames += 1;
        all_valid &= r.is_valid();
        wrong |= r.raw as u16 != original;
    };
    rx.push_slice(pulses, &mut see);
    if let Some(r) = rx.flush() {
        see(r);
    }
    tally.trials += 1;
    if frames == 0 || !all_valid {
        tally.detected += 1;
    } else if wrong || frames > 1 {
        tally.undetected += 1;
    } else {
        tally.intact += 1;
    }
}

fn receiver(kind: Kind) -> Receiver {
    let expect = if kind == Kind::Request {
        Expect::Requests
    } else {
        Expect::Responses
    };
    Receiver::new(BusTiming::default().receiver(expect))
}

/// The pulse a fault acts on, if any.
fn target(f: &PulseFault) -> Option<usize> {
    match *f {
        PulseFault::Drop { index }
        | PulseFault::Flip { index }
        | PulseFault::Shift { index, .. } => Some(index),
        PulseFault::Insert { .. } => None,
    }
}

/// `true` if the faults are distinct faults: no two on one pulse where one undoes or hides the
/// other (a drop hides anything else on its pulse, two shifts of one pulse add up to one or
/// none).
fn distinct(faults: &[PulseFault]) -> bool {
    for (i, a) in faults.iter().enumerate() {
        for b in &faults[i + 1..] {
            if let (Some(x), Some(y)) = (target(a), target(b)) {
                let shifts =
                    matches!(a, PulseFault::Shift { .. }) && matches!(b, PulseFault::Shift { .. });
                let drop =
                    matches!(a, PulseFault::Drop { .. }) || matches!(b, PulseFault::Drop { .. });
                if x == y && (shifts || drop) {
                    return false;
                }
            }
        }
    }
    true
}

fn exhaustive_pairs(kind: Kind) -> Tally {
    let mut rx = receiver(kind);
    let mut tally = Tally::default();
    let mut out = Vec::new();
    for (bits, train) in trains(kind, SimTime::from_micros(100)) {
        let pulses: Vec<Pulse> = train.iter().collect();
        let faults = single_faults(&train);
        for i in 0..faults.len() {
            for j in i + 1..faults.len() {
                let pair = [faults[i], faults[j]];
                if distinct(&pair) {
                    apply_faults(&pulses, &pair, &mut out);
                    classify(&mut rx, &out, bits, &mut tally);
                }
            }
        }
    }
    tally.faulted = tally.trials;
    tally
}

/// Every triple of distinct single faults on every telegram (`sample = None`), or `sample`
/// random triples.
fn triples(kind: Kind, sample: Option<u64>) -> Tally {
    let mut rx = receiver(kind);
    let mut tally = Tally::default();
    let mut out = Vec::new();
    let all: Vec<(u16, Vec<Pulse>, Vec<PulseFault>)> = trains(kind, SimTime::from_micros(100))
        .into_iter()
        .map(|(bits, t)| (bits, t.iter().collect(), single_faults(&t)))
        .collect();
    match sample {
        None => {
            for (bits, pulses, faults) in &all {
                let n = faults.len();
                for i in 0..n {
                    for j in i + 1..n {
                        for k in j + 1..n {
                            let set = [faults[i], faults[j], faults[k]];
                            if distinct(&set) {
                                apply_faults(pulses, &set, &mut out);
                                classify(&mut rx, &out, *bits, &mut tally);
                            }
                        }
                    }
                }
            }
        }
        Some(count) => {
            let mut rng = ChaCha8Rng::seed_from_u64(3);
            while tally.trials < count {
                let (bits, pulses, faults) = &all[rng.random_range(0..all.len())];
                let n = faults.len();
                let set = [
                    faults[rng.random_range(0..n)],
                    faults[rng.random_range(0..n)],
                    faults[rng.random_range(0..n)],
                ];
                if set[0] != set[1] && set[1] != set[2] && set[0] != set[2] && distinct(&set) {
                    apply_faults(pulses, &set, &mut out);
                    classify(&mut rx, &out, *bits, &mut tally);
                }
            }
        }
    }
    tally.faulted = tally.trials;
    tally
}

fn random_rate(kind: Kind, rate: f64, trials: u64, seed: u64) -> Tally {
    let mut rx = receiver(kind);
    let all = trains(kind, SimTime::from_micros(100));
    let mut inj = FaultInjector::new(
        seed,
        FaultRates::uniform(asi_phy::PulseErrorRate::new(rate).expect("a probability")),
        BusTiming::default().half_bit(),
    );
    let mut pick = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
    let mut tally = Tally::default();
    let mut out = Vec::new();
    for _ in 0..trials {
        let (bits, train) = &all[pick.random_range(0..all.len())];
        if inj.corrupt(train.iter(), &mut out) > 0 {
            tally.faulted += 1;
        }
        classify(&mut rx, &out, *bits, &mut tally);
    }
    tally
}

fn main() {
    println!("Pulse-fault model: drop, insert (free grid point, either sign), flip, shift by one grid step.\n");
    for kind in [Kind::Response, Kind::Request] {
        let (d, count, example) = minimum_distance(kind);
        println!("{kind:?}s: fewest pulse faults that turn one valid telegram into another: {d}");
        println!("   ({count} ordered telegram pairs/offsets reach it), e.g.\n   {example}");
    }
    println!();
    for kind in [Kind::Response, Kind::Request] {
        let t = exhaustive_pairs(kind);
        println!(
            "{kind:?}s, every pair of distinct single faults: {} pairs, {} detected, {} wrong telegram accepted, {} intact",
            t.trials, t.detected, t.undetected, t.intact
        );
    }
    let t = triples(Kind::Response, None);
    println!(
        "Responses, every triple of distinct single faults: {} triples, {} detected, {} wrong telegram accepted, {} intact",
        t.trials, t.detected, t.undetected, t.intact
    );
    let t = triples(Kind::Request, Some(20_000_000));
    println!(
        "Requests, 20,000,000 random triples of distinct single faults: {} detected, {} wrong telegram accepted, {} intact",
        t.detected, t.undetected, t.intact
    );
    println!();
    println!(
        "Random corruption (FaultRates::uniform(rate): each pulse faulted with that probability):"
    );
    println!("| kind | rate per pulse | telegrams | with ≥1 fault | detected | wrong telegram accepted | undetected per corrupted telegram |");
    println!("|---|---|---|---|---|---|---|");
    for kind in [Kind::Response, Kind::Request] {
        for (rate, trials) in [
            (0.001, 10_000_000u64),
            (0.01, 10_000_000),
            (0.05, 10_000_000),
            (0.1, 10_000_000),
            (0.3, 10_000_000),
        ] {
            let t = random_rate(kind, rate, trials, 2026);
            let per = if t.faulted == 0 {
                0.0
            } else {
                t.undetected as f64 / t.faulted as f64
            };
            println!(
                "| {kind:?} | {rate} | {} | {} | {} | {} | {per:.2e} |",
                t.trials, t.faulted, t.detected, t.undetected
            );
        }
    }
}
