//! Cost of one safety scan of the lift's project, in the steady state (K1 closed) and while
//! the STOP delay runs. At the 1 ms scan period, an hour of simulated time is 3.6 million scans.

use asi_phy::SimTime;
use criterion::{criterion_main, Criterion};
use safety::{LiftSafety, LiftSafetyConfig, LiftSafetyInputs};

fn started() -> (LiftSafety, u64) {
    let mut s = LiftSafety::new(LiftSafetyConfig::default()).expect("lift project");
    let mut i = LiftSafetyInputs::healthy();
    let mut t = 0;
    for (restart, reset) in [(false, false), (true, true), (false, false)] {
        i.controller_restart = restart;
        i.operator_reset = reset;
        for _ in 0..20 {
            s.scan(SimTime::from_millis(t), &i);
            t += 1;
        }
    }
    (s, t)
}

fn bench(c: &mut Criterion) {
    let (mut s, mut t) = started();
    let i = LiftSafetyInputs {
        k1_aux: false,
        ..LiftSafetyInputs::healthy()
    };
    c.bench_function("lift scan, running", |b| {
        b.iter(|| {
            t += 1;
            s.scan(SimTime::from_millis(t), &i).k1
        })
    });
    let (mut s, mut t) = started();
    let stop = LiftSafetyInputs {
        stop_ch1: false,
        stop_ch2: false,
        k1_aux: false,
        ..LiftSafetyInputs::healthy()
    };
    c.bench_function("lift scan, STOP delay running", |b| {
        b.iter(|| {
            // stays within the 9.1 s delay for the first 9100 iterations; later ones measure
            // the safe state, which costs the same work
            t += 1;
            s.scan(SimTime::from_millis(t), &stop).k1
        })
    });
}

/// `criterion_group!` defines a public function it cannot document.
#[allow(missing_docs)]
mod group {
    criterion::criterion_group!(benches, super::bench);
}

criterion_main!(group::benches);
