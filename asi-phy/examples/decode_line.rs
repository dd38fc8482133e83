//! Decodes the phy bench's line (every request followed by a response, one 154 µs slot each)
//! with `Receiver::push_slice` a given number of times: a deterministic driver for counting
//! instructions per telegram of arbitrary-pulse decoding.
//!
//! `cargo build --release -p asi-phy --example decode_line`, then
//! `valgrind --tool=callgrind target/release/examples/decode_line 100` and the same with `0`:
//! the difference over 100 × 4096 telegrams is the cost of one telegram.

use asi_phy::{BusTiming, Expect, Nibble, Pulse, PulseTrain, Receiver, Request, Response, SimTime};
use std::hint::black_box;

fn main() {
    let rounds: u32 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(100);
    let timing = BusTiming::default();
    let h = timing.half_bit();
    let mut pulses: Vec<Pulse> = Vec::new();
    let mut t = SimTime::from_micros(10);
    let mut telegrams = 0u64;
    for body in 0u16..1 << 11 {
        let bits = (body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1;
        let req = PulseTrain::request(Request::from_bits(bits).expect("valid"), t, h);
        let resp = PulseTrain::response(
            Response::new(Nibble::from_low_bits(body as u8)),
            req.end() + timing.master_pause(),
            h,
        );
        pulses.extend(req);
        pulses.extend(resp);
        telegrams += 2;
        t += timing.transaction();
    }
    let mut valid = 0u64;
    for _ in 0..rounds {
        let mut rx = Receiver::new(timing.receiver(Expect::Both));
        rx.push_slice(black_box(&pulses), |r| valid += r.is_valid() as u64);
        valid += rx.flush().map_or(0, |r| r.is_valid() as u64);
    }
    println!(
        "{} pulses, {telegrams} telegrams a round, {rounds} rounds, {valid} valid",
        pulses.len()
    );
}
