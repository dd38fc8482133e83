//! Runs a built-in scenario on the whole rig and reads its report: where the cabin came to
//! rest, the calls it served and how long each passenger waited, the safety trips, and what
//! the invariant watch found.
//!
//! ```text
//! cargo run --example run_scenario            # the demo
//! cargo run --example run_scenario -- stop    # another built-in scenario
//! ```
//!
//! `asi-lift scenarios` lists the built-in scenarios; [`rig::Scenario::from_toml`] reads one
//! of your own.

use rig::report::Report;
use rig::scenario::builtin::Builtin;
use rig::Rig;
use std::error::Error;

/// Runs the built-in scenario `name` to its end.
fn run(name: &str) -> Result<Report, Box<dyn Error>> {
    let builtin = Builtin::find(name).ok_or_else(|| format!("no built-in scenario {name:?}"))?;
    Ok(Rig::new(builtin.scenario()?)?.run(None))
}

fn main() -> Result<(), Box<dyn Error>> {
    let name = std::env::args().nth(1).unwrap_or_else(|| "demo".into());
    let report = run(&name)?;
    println!("{name}: {:.0} s simulated", report.simulated_s);
    for a in &report.arrivals {
        println!("{:8.3} s  at rest level at floor {}", a.at_s, a.floor);
    }
    for s in &report.served {
        println!(
            "{:8.3} s  {} call to floor {} served after {:.1} s",
            s.served_at_s,
            s.source,
            s.floor,
            s.served_at_s - s.requested_at_s
        );
    }
    for t in &report.safety.trips {
        println!("{:8.3} s  safety: {}", t.at_s, t.cause);
    }
    match report.violations.as_slice() {
        [] => println!("violations: none"),
        found => {
            for v in found {
                println!("{:8.3} s  VIOLATION {}: {}", v.at_s, v.kind, v.detail);
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rig::report::CallSource;

    /// The demo as its file describes it: initialised at floor 1, the cabin call to floor 3,
    /// the hall call at floor 4 stored meanwhile, the call home; no trip, no violation.
    #[test]
    fn the_demo_serves_its_three_calls_and_breaks_no_rule() {
        let report = run("demo").expect("the demo runs");
        let served: Vec<(u8, CallSource)> =
            report.served.iter().map(|s| (s.floor, s.source)).collect();
        assert_eq!(
            served,
            [
                (3, CallSource::Cabin),
                (4, CallSource::Hall),
                (1, CallSource::Cabin)
            ]
        );
        assert_eq!(report.arrivals[0].floor, 1, "initialised at floor 1");
        assert!(report.safety.trips.is_empty(), "{:?}", report.safety.trips);
        assert!(report.violations.is_empty(), "{:?}", report.violations);
    }

    #[test]
    fn an_unknown_name_is_an_error() {
        let e = run("no-such").expect_err("no such scenario");
        assert_eq!(e.to_string(), "no built-in scenario \"no-such\"");
    }
}
