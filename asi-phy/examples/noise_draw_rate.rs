//! How fast ChaCha8 makes random bytes on this machine, and what that means for a noisy line:
//! the fault injector draws four 64-bit numbers per pulse (one per fault kind), from
//! `ChaCha8Rng`, whether or not a fault happens. `cargo run --release -p asi-phy --example
//! noise_draw_rate` prints the generator's rate and the wall time one simulated hour of the lab
//! lift's line (13 transactions per 2,002 µs cycle, each a request and a response of the mean
//! pulse count over all requests and all responses) spends on these draws alone, with every
//! other cost taken away: a bound on the noisy rig's speed that no faster bus can lift.

use asi_phy::{Nibble, Request, Response, SimDuration, SimTime, Transmission};
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::time::Instant;

fn main() {
    let mut rng = ChaCha8Rng::seed_from_u64(2026);
    let mut buf = vec![0u8; 1 << 20];
    let rounds = 2048u32;
    let wall = Instant::now();
    for _ in 0..rounds {
        rng.fill_bytes(&mut buf);
        black_box(&buf);
    }
    let rate = f64::from(rounds) * buf.len() as f64 / wall.elapsed().as_secs_f64();
    let h = SimDuration::from_micros(3);
    let requests: Vec<u32> = (0u16..1 << 11)
        .filter_map(|body| {
            let bits = (body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1;
            Request::from_bits(bits).ok()
        })
        .map(|r| Transmission::request(r, SimTime::ZERO, h).pulses())
        .collect();
    let responses: Vec<u32> = (0u8..16)
        .map(|d| Transmission::response(Response::new(Nibble::from_low_bits(d)), SimTime::ZERO, h))
        .map(|t| t.pulses())
        .collect();
    let mean = |v: &[u32]| v.iter().map(|&p| f64::from(p)).sum::<f64>() / v.len() as f64;
    let pulses_per_transaction = mean(&requests) + mean(&responses);
    let transactions_per_s = 13.0 / 2_002e-6;
    let bytes_per_hour = transactions_per_s * pulses_per_transaction * 4.0 * 8.0 * 3600.0;
    println!(
        "{pulses_per_transaction:.2} pulses per transaction, {transactions_per_s:.0} transactions/s"
    );
    println!(
        "ChaCha8Rng: {:.2} GB/s; a simulated hour of the noisy lab line draws {:.1} GB: {:.2} s \
         of wall time for the draws alone ({:.0}x real time at best)",
        rate / 1e9,
        bytes_per_hour / 1e9,
        bytes_per_hour / rate,
        3600.0 / (bytes_per_hour / rate)
    );
}
