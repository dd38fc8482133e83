//! Throughput of a 31-slave bus in normal operation at pulse level (issue 3: ≥ 5 M
//! transactions per second on one core).
//!
//! Run: `cargo bench -p asi-master -- --warm-up-time 1 --measurement-time 5`.

// criterion_group! and criterion_main! generate undocumented items.
#![allow(missing_docs)]
use asi_master::devices::{IoModule, AC2726};
use asi_master::{Bus, MasterConfig, ProjectedConfig, ProjectedSlave, Slave, SlaveAddr};
use asi_phy::{Address, Nibble, SimDuration, SimTime};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;

fn bus_31() -> Bus {
    let mut projected = Vec::new();
    let mut slaves = Vec::new();
    for n in 1..=31u8 {
        let a = Address::new(n).expect("address");
        projected.push(ProjectedSlave {
            addr: SlaveAddr::a(n).expect("address"),
            codes: AC2726,
            parameter: Nibble::ALL,
        });
        slaves.push(Slave::new(
            format!("io {n}"),
            a,
            AC2726,
            Box::new(IoModule::new()),
        ));
    }
    let p = ProjectedConfig::new(projected).expect("projection");
    let mut bus = Bus::new(MasterConfig::default(), p, slaves).expect("bus");
    bus.advance_to(SimTime::from_millis(100));
    assert!(bus.is_running());
    bus
}

fn normal_operation(c: &mut Criterion) {
    let mut bus = bus_31();
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
