//! Loading a big scenario file: 100,000 events of every kind, read by `Scenario::from_toml`,
//! timed on the wall clock in a release build. The target is well under a second (the reader
//! is linear in the file: places are found by a binary search over the line starts).
//!
//! `cargo bench -p asi-lift-rig --bench scenario_load` (an argument after `--`: the number of events,
//! default 100000).

use rig::scenario::{Scenario, DEFAULT_HOLD};
use std::fmt::Write as _;
use std::time::Instant;

/// A scenario file of `n` events, a press, a load change, a door, a fault and an operator's
/// action in turn, one every 10 ms.
fn file(n: usize) -> String {
    let mut s = String::from("name = \"big\"\nduration = \"2h\"\n");
    for i in 0..n {
        let at = 1_000 + 10 * i;
        let _ = write!(s, "\n[[event]]\nat = \"{at}ms\"\n");
        let _ = match i % 5 {
            0 => writeln!(
                s,
                "press = \"cabin:{}\"\nhold = \"{}\"",
                i % 4 + 1,
                DEFAULT_HOLD
            ),
            1 => writeln!(s, "load = \"{}\"", ["empty", "loaded", "full"][i % 3]),
            2 => writeln!(s, "door = \"{}\"", ["open", "closed"][i % 2]),
            3 => writeln!(
                s,
                "fault = {{ kind = \"slave-offline\", slave = {} }}",
                i % 12 + 1
            ),
            _ => writeln!(s, "reset = true"),
        };
    }
    s
}

fn main() {
    let n: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(100_000);
    let text = file(n);
    let wall = Instant::now();
    let sc = match Scenario::from_toml("big.toml", &text) {
        Ok(sc) => sc,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    let secs = wall.elapsed().as_secs_f64();
    assert_eq!(sc.events.len(), n);
    println!(
        "{n} events ({:.1} MB of TOML) loaded in {secs:.3} s",
        text.len() as f64 / 1e6
    );
}
