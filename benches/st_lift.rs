//! The lab hour with the reference program in Structured Text (`controllers/lift.st` on
//! `controllers/lab.st`) beside the built-in program, in one process one after the other:
//! one simulated hour of random traffic on the lab lift (11 slaves), release build, traces
//! off, timed on the wall clock, each three times (`runs=N` for another count), the median
//! the figure. The target: ≥ 1,000× real time with the reference program.
//!
//! `cargo bench -p asi-lift-benches --bench st_lift` (arguments after `--`: simulated
//! seconds, default 3600; `runs=N`).

use asi_phy::{SimDuration, SimTime};
use controller::structured::StProgram;
use lift_model::Button;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rig::rig::Rig;
use rig::scenario::{Action, Scenario, ScenarioEvent};
use std::time::Instant;

const LAB: &str = include_str!("../controllers/lab.st");
const LIFT: &str = include_str!("../controllers/lift.st");

/// Passengers at random, as the rig bench's lab hour: a press every 15..45 s, a cabin call
/// or a hall call at a random floor.
fn traffic(seconds: u64) -> Scenario {
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
        name: "lab hour".into(),
        duration: SimDuration::from_secs(seconds),
        events,
        ..Scenario::defaults()
    }
}

/// One run: wall seconds and the calls served.
fn run(sc: &Scenario, st: bool) -> (f64, usize) {
    let mut rig = Rig::new(sc.clone()).expect("the rig");
    if st {
        let p = StProgram::compile_with(&[("lab.st", LAB)], "lift.st", LIFT)
            .unwrap_or_else(|e| panic!("{e}"));
        rig = rig.with_controller(p);
    }
    let t0 = Instant::now();
    let report = rig.run(None);
    (t0.elapsed().as_secs_f64(), report.served.len())
}

fn main() {
    let mut seconds = 3600u64;
    let mut runs = 3usize;
    for a in std::env::args().skip(1) {
        if let Some(n) = a.strip_prefix("runs=") {
            runs = n.parse().expect("runs=N");
        } else if let Ok(s) = a.parse() {
            seconds = s;
        }
    }
    let sc = traffic(seconds);
    for (name, st) in [("built-in program", false), ("lift.st", true)] {
        let mut times = Vec::new();
        let mut served = 0;
        for _ in 0..runs.max(1) {
            let (t, s) = run(&sc, st);
            times.push(t);
            served = s;
        }
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        println!(
            "{name:17} {seconds} s simulated in {median:.2} s (median of {}; {:.2}–{:.2} s): {:.0}× real time, {served} calls served",
            times.len(),
            times[0],
            times[times.len() - 1],
            seconds as f64 / median
        );
    }
}
