//! One simulated hour of a 31-slave bus in normal operation at pulse level, timed on the wall
//! clock (the target: under 5 s, i.e. at least 5 M transactions per second).
//!
//! `cargo run --release -p asi-lift-bus --example hour` (an optional argument gives the
//! simulated seconds, default 3600; a second argument `lab` runs the lab lift's bus instead,
//! with its handshake devices and the safety monitor).

use asi_bus::lab::{io_bus, LabLift};
use asi_phy::{SimDuration, SimTime};
use asi_slaves::devices::AC2726;
use std::time::Instant;

fn main() {
    let lab = std::env::args().nth(2).as_deref() == Some("lab");
    let bus = if lab {
        LabLift::new().map(LabLift::into_bus)
    } else {
        io_bus(31, AC2726)
    };
    let mut bus = match bus {
        Ok(b) => b,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    bus.advance_to(SimTime::from_millis(100));
    let start_tx = bus.stats().transactions;
    let wall = Instant::now();
    let secs_sim: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(3600);
    bus.advance_to(SimTime::from_millis(100) + SimDuration::from_secs(secs_sim));
    let secs = wall.elapsed().as_secs_f64();
    let s = bus.stats();
    let n = s.transactions - start_tx;
    println!(
        "{secs_sim} s simulated: {n} transactions in {secs:.2} s wall = {:.2} M transactions/s",
        n as f64 / secs / 1e6
    );
    println!("{s}");
}
