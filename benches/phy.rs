//! Throughput of the asi-phy hot paths (issue targets, one core, release):
//! encode request → pulse train ≥ 100 M/s; pulse-level decode with all seven checks
//! ≥ 50 M telegrams/s; waveform demodulation ≥ 250 M samples/s.
//!
//! `cargo bench -p asi-lift-benches --bench phy`

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use asi_phy::waveform::{render, DemodConfig, Demodulator, WaveformConfig};
use asi_phy::{
    BusTiming, Expect, LineDecoder, Listener, Nibble, Pulse, PulseTrain, Receiver, Request,
    Response, SimDuration, SimTime,
};
use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use std::hint::black_box;

fn requests() -> Vec<Request> {
    (0u16..1 << 11)
        .map(|body| {
            Request::from_bits((body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1)
                .expect("valid")
        })
        .collect()
}

/// A bus-like line: each request followed by its response, one 154 µs slot each.
fn line(timing: &BusTiming) -> (Vec<Pulse>, Vec<PulseTrain>, u64) {
    let h = timing.half_bit();
    let mut pulses = Vec::new();
    let mut trains = Vec::new();
    let mut t = SimTime::from_micros(10);
    let mut telegrams = 0;
    for (i, r) in requests().into_iter().enumerate() {
        let req = PulseTrain::request(r, t, h);
        let resp = PulseTrain::response(
            Response::new(Nibble::from_low_bits(i as u8)),
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
    (pulses, trains, telegrams)
}

fn encode(c: &mut Criterion) {
    let reqs = requests();
    let h = BusTiming::default().half_bit();
    let mut g = c.benchmark_group("encode");
    g.throughput(Throughput::Elements(reqs.len() as u64));
    g.bench_function("request_to_pulse_train", |b| {
        b.iter(|| {
            let mut acc = 0u32;
            let mut t = SimTime::ZERO;
            for r in &reqs {
                let train = PulseTrain::request(black_box(*r), t, h);
                acc = acc.wrapping_add(train.len());
                t += SimDuration::from_micros(154);
            }
            acc
        })
    });
    g.finish();
}

fn decode(c: &mut Criterion) {
    let timing = BusTiming::default();
    let (pulses, trains, telegrams) = line(&timing);
    let mut g = c.benchmark_group("decode");
    g.throughput(Throughput::Elements(telegrams));
    g.bench_function("pulses_seven_checks", |b| {
        b.iter_batched_ref(
            || Receiver::new(timing.receiver(Expect::Both)),
            |rx| {
                let mut valid = 0u32;
                rx.push_slice(&pulses, |r| valid += r.is_valid() as u32);
                valid + rx.flush().map_or(0, |r| r.is_valid() as u32)
            },
            BatchSize::SmallInput,
        )
    });
    g.bench_function("train_seven_checks", |b| {
        let cfg = timing.receiver(Expect::Both);
        b.iter_batched_ref(
            || (LineDecoder::new(&cfg), Listener::new(&cfg)),
            |(line, listener)| {
                let mut valid = 0u32;
                for t in &trains {
                    if let Some(f) = line.push_train(t) {
                        valid += listener.accept(&f).is_valid() as u32;
                    }
                }
                valid
            },
            BatchSize::SmallInput,
        )
    });
    g.finish();
}

fn demodulate(c: &mut Criterion) {
    let timing = BusTiming::default();
    let (pulses, _, _) = line(&timing);
    let end = pulses.last().map_or(SimTime::ZERO, |p| p.at) + SimDuration::from_micros(20);
    let wf = render(pulses, SimTime::ZERO, end, &WaveformConfig::default()).expect("render");
    let mut g = c.benchmark_group("waveform");
    g.throughput(Throughput::Elements(wf.samples.len() as u64));
    g.bench_function("demodulate", |b| {
        b.iter_batched_ref(
            || Demodulator::for_waveform(DemodConfig::default(), &wf).expect("demod"),
            |d| {
                let mut n = 0u32;
                d.push(&wf.samples, |_| n += 1);
                n
            },
            BatchSize::SmallInput,
        )
    });
    g.finish();
}

criterion_group!(benches, encode, decode, demodulate);
criterion_main!(benches);
