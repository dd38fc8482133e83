//! Cost of running the plant (docs/lift-plant.md "events exact in time"): advancing from one edge to the
//! next, and advancing by a PLC scan, on a 24-floor lift shuttling between its overtravel
//! sensors at Rychlost 11000 (reversing on each trip, so every kind of motion segment occurs).
//!
//! Run: `cargo bench -p asi-lift-benches --bench events -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use asi_phy::{SimDuration, SimTime};
use criterion::{criterion_main, Criterion, Throughput};
use lift_model::{Lift, LiftConfig, PlantEventKind};

/// A 24-floor lift running up from floor 1 at 68.8 mm/s.
fn shuttle() -> Lift {
    let config = {
        let mut cfg = LiftConfig::default();
        cfg.floors = 24;
        cfg
    };
    let Ok(mut lift) = Lift::new(config) else {
        unreachable!("the default geometry with 24 floors is valid")
    };
    let _ = lift.set_contactor(SimTime::ZERO, true);
    let _ = lift.set_converter(SimTime::ZERO, true, true, 11_000);
    lift
}

/// Advances to `t`; on an overtravel trip, reverses the drive. Returns the number of edges.
fn advance(lift: &mut Lift, t: SimTime, up: &mut bool) -> usize {
    let mut edges = 0;
    let mut tripped = false;
    if let Ok(events) = lift.advance_to(t) {
        for e in events {
            edges += 1;
            tripped |= matches!(e.kind, PlantEventKind::Overtravel { tripped: true, .. });
        }
    }
    if tripped {
        *up = !*up;
        let _ = lift.set_run_direction(t, true, *up);
    }
    edges
}

fn plant(c: &mut Criterion) {
    let mut group = c.benchmark_group("plant");
    group.throughput(Throughput::Elements(1));

    group.bench_function("advance_to_next_event", |b| {
        let mut lift = shuttle();
        let mut up = true;
        b.iter(|| {
            let t = lift.next_event().unwrap_or(lift.now());
            black_box(advance(&mut lift, t, &mut up))
        });
    });

    group.bench_function("advance_by_10ms_scan", |b| {
        let mut lift = shuttle();
        let mut up = true;
        b.iter(|| {
            let t = lift.now() + SimDuration::from_millis(10);
            black_box(advance(&mut lift, t, &mut up))
        });
    });
    group.finish();
}

/// The benchmark group (what `criterion_group!` would generate, but documented).
fn benches() {
    let mut c = Criterion::default().configure_from_args();
    plant(&mut c);
}

criterion_main!(benches);
