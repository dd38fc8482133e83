//! Throughput of a 31-slave bus in normal operation at pulse level (target: ≥ 5 M
//! transactions per second on one core).
//!
//! Run: `cargo bench -p asi-lift-benches --bench bus -- --warm-up-time 1 --measurement-time 5`.

// criterion_group! and criterion_main! generate undocumented items.
#![allow(missing_docs)]
use asi_bus::lab::io_bus;
use asi_phy::{SimDuration, SimTime};
use asi_slaves::devices::AC2726;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;

fn normal_operation(c: &mut Criterion) {
    let mut bus = io_bus(31, AC2726).expect("bus");
    bus.advance_to(SimTime::from_millis(100));
    assert!(bus.is_running());
    // 1000 transactions of 154 µs per iteration.
    let step = SimDuration::from_micros(154_000);
    let mut g = c.benchmark_group("bus");
    g.throughput(Throughput::Elements(1000));
    g.bench_function("31_slaves_1000_transactions", |b| {
        b.iter(|| {
            let t = bus.now() + step;
            bus.advance_to(black_box(t));
        })
    });
    g.finish();
    let s = bus.stats();
    assert_eq!(s.repeats, 0);
    assert_eq!(s.cycle_max, SimDuration::from_micros(32 * 154));
}

criterion_group!(benches, normal_operation);
criterion_main!(benches);
