//! One simulated hour of the whole rig serving traffic, timed in the process's CPU time, with
//! the simulator's fast paths and pulse-exact (every telegram through the pulse decoder), for
//! six rigs: the lab lift (11 slaves) under random presses (`lab`), the same on a full 31-slave
//! bus (20 extra I/O modules, `full`) and on a noisy line (one pulse in a thousand corrupted,
//! `noise`); and the same three under the busy traffic of a traffic template (`busy`,
//! `busy-full`, `busy-noise`): Poisson arrivals with a mean gap of 30 s, origin and destination
//! uniform over the floors (interfloor), each passenger a hall call and then a cabin call (the
//! book, "Traffic as planners measure it"). Release build, traces off, one thread. Both paths
//! run in the same process one after the other, so their ratio holds on a machine that is busy
//! with something else. The targets: ≥ 3600× real time for `lab`, `full`, `busy` and
//! `busy-full`, ≥ 1000× for `noise` and ≥ 1500× for `busy-noise`; 10,000× for `lab` is the
//! moonshot.
//!
//! Each path runs three times (`runs=N` for another count) and the median CPU time is the
//! figure, with the range beside it: a single run on a shared machine can be a fifth off. CPU
//! time is the thread's time on a core (Linux's `/proc/thread-self/schedstat`), which another
//! job on the machine does not stretch as it does the wall clock; where that file cannot be
//! read the bench says so and times the wall clock.
//!
//! `cargo bench -p asi-lift-rig --bench rig` (arguments after `--`: simulated seconds, default 3600;
//! a rig's name to run only that rig; `fast` to skip the pulse-exact runs; `runs=N`). The
//! instructions per AS-i transaction: the bench binary under callgrind
//! (`valgrind --tool=callgrind --callgrind-out-file=/dev/null target/release/deps/rig-… 600 busy
//! fast runs=1`), its count of instructions over the transactions the bench prints.

use asi_phy::{SimDuration, SimTime};
use lift_model::Button;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rig::rig::Rig;
use rig::scenario::traffic::{Pattern, Traffic};
use rig::scenario::{Action, Scenario, ScenarioEvent};
use std::time::Instant;

/// Passengers at random: a press every 15..45 s, a cabin call or a hall call at a random floor.
fn traffic(seconds: u64, extra_slaves: u8, pulse_error_rate: f64) -> Scenario {
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
        pulse_error_rate,
        events,
        ..Scenario::defaults()
    }
}

/// A busy hour of passengers from a traffic template: Poisson arrivals, a mean gap of 30 s,
/// interfloor (random origin and destination), a hall call and then a cabin call each.
fn busy(seconds: u64) -> Scenario {
    Scenario {
        name: "busy traffic".into(),
        duration: SimDuration::from_secs(seconds),
        traffic: vec![Traffic {
            pattern: Pattern::Interfloor,
            per_minute: 2.0,
            seed: Some(2026),
            // After the controller's initialisation.
            start: SimDuration::from_secs(15),
            duration: None,
            line: 0,
        }],
        ..Scenario::defaults()
    }
}

/// The names of the rigs, in the order they run.
const RIGS: [&str; 6] = ["lab", "full", "noise", "busy", "busy-full", "busy-noise"];

/// The scenario of rig `name` ([`RIGS`]) for `seconds`.
fn rig_scenario(name: &str, seconds: u64) -> Scenario {
    let (busy_traffic, extra, noise) = match name {
        "lab" => (false, 0, 0.0),
        "full" => (false, 20, 0.0),
        "noise" => (false, 0, 1e-3),
        "busy" => (true, 0, 0.0),
        "busy-full" => (true, 20, 0.0),
        _ => (true, 0, 1e-3),
    };
    if busy_traffic {
        Scenario {
            extra_slaves: extra,
            pulse_error_rate: noise,
            ..busy(seconds)
        }
    } else {
        traffic(seconds, extra, noise)
    }
}

/// The CPU time this thread has run, in seconds (Linux's `/proc/thread-self/schedstat`: its
/// first field is the time on a core in ns); `None` where that cannot be read.
fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: u64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns as f64 * 1e-9)
}

/// A clock for one run: the thread's CPU time, else the wall clock.
struct Clock {
    wall: Instant,
    cpu: Option<f64>,
}

impl Clock {
    fn start() -> Clock {
        Clock {
            wall: Instant::now(),
            cpu: cpu_seconds(),
        }
    }

    /// Seconds since the start, of CPU time where it can be read.
    fn elapsed(&self) -> f64 {
        match (self.cpu, cpu_seconds()) {
            (Some(a), Some(b)) => b - a,
            _ => self.wall.elapsed().as_secs_f64(),
        }
    }
}

/// Runs `sc` on one path; the CPU time and the report.
fn timed(sc: &Scenario, pulse_exact: bool) -> (f64, rig::report::Report) {
    let mut rig = match Rig::new(sc.clone()) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("{}: {e}", sc.name);
            std::process::exit(1);
        }
    };
    rig.set_pulse_exact(pulse_exact);
    let clock = Clock::start();
    let report = rig.run(None);
    (clock.elapsed(), report)
}

/// Runs `sc` `runs` times on one path; the median CPU time, the fastest and the slowest, and
/// the report (every run's must be the same).
fn timed_runs(
    sc: &Scenario,
    pulse_exact: bool,
    runs: usize,
) -> ((f64, f64, f64), rig::report::Report) {
    let (first, report) = timed(sc, pulse_exact);
    let mut secs = vec![first];
    for _ in 1..runs {
        let (s, r) = timed(sc, pulse_exact);
        if r != report {
            eprintln!("{}: two runs of the same scenario differ", sc.name);
            std::process::exit(1);
        }
        secs.push(s);
    }
    secs.sort_by(f64::total_cmp);
    (
        (secs[secs.len() / 2], secs[0], secs[secs.len() - 1]),
        report,
    )
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let seconds: u64 = args.iter().find_map(|a| a.parse().ok()).unwrap_or(3600);
    let only = args.iter().find(|a| RIGS.contains(&a.as_str()));
    let fast_only = args.iter().any(|a| a == "fast");
    let runs: usize = match args.iter().find_map(|a| a.strip_prefix("runs=")) {
        None => 3,
        Some(n) => match n.parse() {
            Ok(n) if n > 0 => n,
            _ => {
                eprintln!("runs={n}: must be a whole number of runs, at least 1");
                std::process::exit(2);
            }
        },
    };
    let clock = if cpu_seconds().is_some() {
        "CPU"
    } else {
        eprintln!("the thread's CPU time cannot be read here: timing the wall clock");
        "wall"
    };
    for name in RIGS {
        if only.is_some_and(|o| o != name) {
            continue;
        }
        let sc = rig_scenario(name, seconds);
        let (extra, noise) = (sc.extra_slaves, sc.pulse_error_rate);
        let ((secs, fastest, slowest), report) = timed_runs(&sc, false, runs);
        // The traffic template's passengers press twice each, the hand-written ones once.
        let presses = report.passengers.len();
        println!(
            "{name:>10}: {seconds} s simulated ({} slaves, line noise {noise}, {presses} presses, {} served, {} transactions) in {secs:.2} s {clock} (median of {runs}: {fastest:.2}–{slowest:.2} s) = {:.0}x real time ({:.0}–{:.0}x), {:.1} ns per transaction",
            11 + extra as usize,
            report.served.len(),
            report.bus.transactions,
            seconds as f64 / secs,
            seconds as f64 / slowest,
            seconds as f64 / fastest,
            secs * 1e9 / report.bus.transactions as f64
        );
        if !report.violations.is_empty() {
            eprintln!("{name}: violations {:?}", report.violations);
            std::process::exit(1);
        }
        if fast_only {
            continue;
        }
        let ((exact_secs, _, _), exact) = timed_runs(&sc, true, runs);
        if exact != report {
            eprintln!("{name}: the pulse-exact run's report differs from the fast one");
            std::process::exit(1);
        }
        println!(
            "{:>10}  pulse-exact: {exact_secs:.2} s {clock} (median of {runs}) = {:.0}x real time; the fast path is {:.2}x as fast",
            "",
            seconds as f64 / exact_secs,
            exact_secs / secs
        );
    }
}
