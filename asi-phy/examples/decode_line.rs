//! Decodes the phy bench's line (every request followed by a response, one 154 µs slot each)
//! with `Receiver::push_slice` a given number of times: a deterministic driver for counting
//! instructions per telegram of arbitrary-pulse decoding.
//!
//! `cargo build --release -p asi-lift-phy --example decode_line`, then
//! `valgrind --tool=callgrind target/release/examples/decode_line 100` and the same with `0`:
//! the difference over 100 × 4096 telegrams is the cost of one telegram. With a second
//! argument `trains` the line goes as encoded trains (`LineDecoder::push_train`), as the bus
//! decodes it.

use asi_phy::{
    BusTiming, Expect, LineDecoder, Listener, Nibble, Pulse, PulseTrain, Receiver, ReceiverConfig,
    Request, Response, SimTime,
};
use std::hint::black_box;

fn main() {
    let rounds: u32 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(100);
    let timing = BusTiming::default();
    let h = timing.half_bit();
    let trains_mode = std::env::args().nth(2).as_deref() == Some("trains");
    let mut pulses: Vec<Pulse> = Vec::new();
    let mut trains: Vec<PulseTrain> = Vec::new();
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
        trains.push(req);
        trains.push(resp);
        telegrams += 2;
        t += timing.transaction();
    }
    let cfg = timing.receiver(Expect::Both);
    let valid = if trains_mode {
        decode_trains(&trains, &cfg, rounds)
    } else {
        decode_pulses(&pulses, &cfg, rounds)
    };
    println!(
        "{} pulses, {telegrams} telegrams a round, {rounds} rounds, {valid} valid",
        pulses.len()
    );
}

// Each way in a function of its own, so that the compiler's choices for one (what it inlines,
// which register holds the count) do not change the count of the other.

/// Decodes the line's pulses `rounds` times; the number of valid telegrams.
#[inline(never)]
fn decode_pulses(pulses: &[Pulse], cfg: &ReceiverConfig, rounds: u32) -> u64 {
    let mut valid = 0u64;
    for _ in 0..rounds {
        let mut rx = Receiver::new(*cfg);
        rx.push_slice(black_box(pulses), |r| valid += r.is_valid() as u64);
        valid += rx.flush().map_or(0, |r| r.is_valid() as u64);
    }
    valid
}

/// Decodes the line's encoded trains `rounds` times; the number of valid telegrams.
#[inline(never)]
fn decode_trains(trains: &[PulseTrain], cfg: &ReceiverConfig, rounds: u32) -> u64 {
    let mut valid = 0u64;
    for _ in 0..rounds {
        let (mut line, mut listener) = (LineDecoder::new(cfg), Listener::new(cfg));
        for t in black_box(trains) {
            if let Some(f) = line.push_train(t) {
                valid += listener.accept(&f).is_valid() as u64;
            }
        }
        valid += line
            .flush()
            .map_or(0, |f| listener.accept(&f).is_valid() as u64);
    }
    valid
}
