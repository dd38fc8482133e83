//! Campaign throughput: simulated seconds per wall second of a fixed campaign (the default
//! profile, seed 1, 24 runs, shrinking off) with 1 and with 2 worker threads. Not a timed
//! test: it prints the figures that README.md ("Campaigns") quotes.
//!
//! `cargo bench -p asi-lift-rig --bench campaign` (arguments after `--`: the number of runs, default 24).

use rig::campaign::profile::Profile;
use rig::campaign::run::{run_campaign, Plan, Shard};
use std::time::Instant;

fn main() {
    let runs: u64 = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(24);
    let Some(profile) = Profile::built_in("default") else {
        eprintln!("no default profile");
        std::process::exit(1);
    };
    let plan = Plan {
        seed: 1,
        runs,
        shard: Shard::ALL,
        profile,
        shrink_budget: 0,
        referee: false,
        failures: "failures".into(),
        program: None,
    };
    let mut first: Option<Vec<String>> = None;
    let mut rates = Vec::new();
    for jobs in [1usize, 2] {
        let mut simulated = 0.0;
        let mut lines = Vec::new();
        let wall = Instant::now();
        let mut sink = |f: rig::campaign::run::Finished| {
            simulated += f.line.simulated_s;
            lines.push(f.line.to_json_line().expect("serialises"));
            Ok(())
        };
        if let Err(e) = run_campaign(&plan, jobs, &mut sink, &mut |_| {}) {
            eprintln!("campaign: {}", e.0);
            std::process::exit(1);
        }
        let secs = wall.elapsed().as_secs_f64();
        let rate = simulated / secs;
        rates.push(rate);
        println!(
            "{jobs} job{}: {runs} runs, {simulated:.0} simulated s in {secs:.1} s wall = {rate:.0} simulated s per wall s",
            if jobs == 1 { "" } else { "s" }
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
