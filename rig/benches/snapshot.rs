//! What a snapshot of the rig costs: the wall time of `Rig::clone`, the rig's size in place
//! and the heap bytes a clone allocates, for built-in scenarios at moments through their
//! first minute, against the wall time the rig takes to run one simulated second from there
//! (what a fault explorer that forks at a moment and runs on weighs it against).
//!
//! The bytes are what dhat's heap profiler counts while one clone runs (its blocks as asked
//! for, the allocator's own overhead left out). Wall times are the median of `runs=N` clones
//! (default 201) at each moment, without the profiler.
//!
//! `cargo bench -p asi-lift-rig --bench snapshot --features heap-count` (the feature brings
//! in dhat for this bench alone; arguments after `--`: scenario names, default `demo noise
//! safe-drive`; `runs=N`).

use asi_phy::{SimDuration, SimTime};
use rig::scenario::builtin::Builtin;
use rig::Rig;
use std::time::Instant;

// dhat's allocator passes every call to the system's, and counts while a profiler runs (only
// around the counted clone, not the timed ones).
#[global_allocator]
static ALLOCATOR: dhat::Alloc = dhat::Alloc;

/// The heap blocks and bytes `rig.clone()` allocates.
fn clone_cost(rig: &Rig) -> (u64, u64) {
    let profiler = dhat::Profiler::builder().testing().build();
    let copy = rig.clone();
    let stats = dhat::HeapStats::get();
    drop(copy);
    drop(profiler);
    (stats.total_blocks, stats.total_bytes)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut names = Vec::new();
    let mut runs = 201;
    for a in std::env::args().skip(1).filter(|a| a != "--bench") {
        match a.strip_prefix("runs=") {
            Some(n) => runs = n.parse().expect("runs=N"),
            None => names.push(a),
        }
    }
    if names.is_empty() {
        names = vec!["demo".into(), "noise".into(), "safe-drive".into()];
    }
    println!(
        "A rig is {} bytes in place, and a clone allocates on the heap:",
        std::mem::size_of::<Rig>()
    );
    println!(
        "{:<12} {:>8} {:>12} {:>8} {:>12} {:>14}",
        "scenario", "at", "clone", "blocks", "bytes", "1 s run on"
    );
    for name in names {
        let sc = Builtin::find(&name)
            .unwrap_or_else(|| panic!("no built-in scenario {name}"))
            .scenario()
            .expect("a built-in scenario loads");
        let mut rig = Rig::new(sc).expect("a rig");
        for at_s in [1, 10, 30, 60] {
            let at = SimTime::ZERO + SimDuration::from_secs(at_s);
            while rig.step_until(at).is_some() {}
            let mut times = Vec::with_capacity(runs);
            for _ in 0..runs {
                let start = Instant::now();
                let copy = std::hint::black_box(rig.clone());
                times.push(start.elapsed().as_secs_f64());
                drop(copy);
            }
            let (blocks, bytes) = clone_cost(&rig);
            // What the copy is weighed against: one simulated second run on from there.
            let mut copy = rig.clone();
            let start = Instant::now();
            while copy.step_until(at + SimDuration::from_secs(1)).is_some() {}
            let second = start.elapsed().as_secs_f64();
            println!(
                "{:<12} {:>6} s {:>9.1} µs {:>8} {:>12} {:>11.1} µs",
                name,
                at_s,
                median(times) * 1e6,
                blocks,
                bytes,
                second * 1e6
            );
        }
    }
}
