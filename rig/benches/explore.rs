//! Explorer throughput: forks per wall second of the demo's single-fault sweep over a window
//! (the whole catalogue, every 100 ms over 10..20 s, horizon 60 s by default) with 1 and with
//! 2 worker threads, and the check that both give the same lines. Not a timed test: it prints
//! the figures the book ("The fault explorer") and docs/dev/explorer.md quote.
//!
//! `cargo bench -p asi-lift-rig --bench explore` (arguments after `--`: the window's first and
//! last second and the grid's step in ms, default `10 20 100`).

use asi_phy::{SimDuration, SimTime};
use rig::campaign::run::Shard;
use rig::explore::catalogue::{FaultKind, Params};
use rig::explore::{explore, Plan, Verdict};
use rig::{Rig, Scenario};
use std::collections::BTreeMap;
use std::time::Instant;

fn main() {
    let nums: Vec<u64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let (from, to, every) = match nums[..] {
        [a, b, e, ..] => (a, b, e),
        _ => (10, 20, 100),
    };
    let sc = match Scenario::demo() {
        Ok(sc) => sc,
        Err(e) => {
            eprintln!("the demo: {e}");
            std::process::exit(1);
        }
    };
    let plan = Plan {
        kinds: FaultKind::all_for(&sc),
        params: Params::default(),
        every: SimDuration::from_millis(every),
        window: (
            SimTime::from_millis(from * 1000),
            SimTime::from_millis(to * 1000),
        ),
        horizon: SimDuration::from_secs(60),
        shard: Shard::ALL,
    };
    let make = || Rig::new(sc.clone()).map_err(|e| e.to_string());
    let mut first: Option<Vec<String>> = None;
    let mut rates = Vec::new();
    for jobs in [1usize, 2] {
        let mut lines = Vec::new();
        let mut verdicts: BTreeMap<Verdict, u64> = BTreeMap::new();
        let mut ran = 0.0;
        let wall = Instant::now();
        let mut sink = |l: rig::explore::ForkLine| {
            *verdicts.entry(l.verdict).or_default() += 1;
            ran += l.ran_s;
            lines.push(l.to_json_line().map_err(|e| e.to_string())?);
            Ok(())
        };
        if let Err(e) = explore(&make, &plan, jobs, &mut sink, &mut |_| {}) {
            eprintln!("explore: {}", e.0);
            std::process::exit(1);
        }
        let secs = wall.elapsed().as_secs_f64();
        let rate = lines.len() as f64 / secs;
        rates.push(rate);
        let by: Vec<String> = verdicts.iter().map(|(v, n)| format!("{n} {v}")).collect();
        println!(
            "{jobs} job{}: {} forks ({}) in {secs:.1} s wall = {rate:.0} forks per s; {:.1} simulated s per fork",
            if jobs == 1 { "" } else { "s" },
            lines.len(),
            by.join(", "),
            ran / lines.len().max(1) as f64
        );
        match &first {
            None => first = Some(lines),
            Some(f) if *f != lines => {
                eprintln!("the lines differ between 1 and {jobs} jobs");
                std::process::exit(1);
            }
            Some(_) => {}
        }
    }
    println!("speed-up with 2 jobs: {:.2}x", rates[1] / rates[0]);
}
