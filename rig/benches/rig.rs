//! One simulated hour of the whole rig serving traffic, timed on the wall clock: the lab lift
//! (11 slaves) and the lab lift on a full 31-slave bus (20 extra I/O modules). The issue's
//! target is ≤ 1 s of wall time per simulated hour (≥ 3600× real time), release build, traces
//! off.
//!
//! `cargo bench -p rig --bench rig` (arguments after `--`: simulated seconds, default 3600; `lab` or
//! `full` to run only one of the two).

use asi_phy::{SimDuration, SimTime};
use lift_model::Button;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rig::rig::Rig;
use rig::scenario::{Action, Scenario, ScenarioEvent};
use std::time::Instant;

/// Passengers at random: a press every 15..45 s, a cabin call or a hall call at a random floor.
fn traffic(seconds: u64, extra_slaves: u8) -> Scenario {
    let mut rng = ChaCha8Rng::seed_from_u64(2026);
    let mut events = Vec::new();
    let mut t = 15.0;
    while t < seconds as f64 {
        let floor = rng.random_range(1..=4u8);
        let button = match rng.random_range(0..3) {
            0 => Button::Cabin(floor),
            1 if floor < 4 => Button::HallUp(floor),
            _ if floor > 1 => Button::HallDown(floor),
            _ => Button::HallUp(floor),
        };
        events.push(ScenarioEvent {
            at: SimTime::ZERO + SimDuration::from_millis((t * 1000.0) as u64),
            action: Action::Press {
                button,
                hold: SimDuration::from_millis(300),
            },
            line: 0,
        });
        t += rng.random_range(15.0..45.0);
    }
    Scenario {
        name: format!("traffic, {extra_slaves} extra slaves"),
        duration: SimDuration::from_secs(seconds),
        extra_slaves,
        events,
        ..Scenario::defaults()
    }
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let seconds: u64 = args.iter().find_map(|a| a.parse().ok()).unwrap_or(3600);
    let only = args.iter().find(|a| *a == "lab" || *a == "full");
    for (name, extra) in [("lab", 0u8), ("full", 20)] {
        if only.is_some_and(|o| o != name) {
            continue;
        }
        let sc = traffic(seconds, extra);
        let presses = sc.events.len();
        let rig = match Rig::new(sc) {
            Ok(r) => r,
            Err(e) => {
                eprintln!("{name}: {e}");
                std::process::exit(1);
            }
        };
        let wall = Instant::now();
        let report = rig.run(None);
        let secs = wall.elapsed().as_secs_f64();
        println!(
            "{name:>4}: {seconds} s simulated ({} slaves, {presses} presses, {} served, {} transactions) in {secs:.2} s wall = {:.0}x real time, {:.1} ns per transaction",
            11 + extra as usize,
            report.served.len(),
            report.bus.transactions,
            seconds as f64 / secs,
            secs * 1e9 / report.bus.transactions as f64
        );
        if !report.violations.is_empty() {
            eprintln!("{name}: violations {:?}", report.violations);
            std::process::exit(1);
        }
    }
}
