//! One simulated hour of a 31-slave bus in normal operation at pulse level, timed on the wall
//! clock (the target: under 5 s, i.e. at least 5 M transactions per second).
//!
//! `cargo run --release -p asi-master --example hour` (an optional argument gives the
//! simulated seconds, default 3600).

use asi_master::devices::{IoModule, AC2726};
use asi_master::{Bus, MasterConfig, ProjectedConfig, ProjectedSlave, Slave, SlaveAddr};
use asi_phy::{Address, Nibble, SimDuration, SimTime};
use std::time::Instant;

fn main() {
    let mut projected = Vec::new();
    let mut slaves = Vec::new();
    for n in 1..=31u8 {
        let (Some(a), Some(sa)) = (Address::new(n), SlaveAddr::a(n)) else {
            return;
        };
        projected.push(ProjectedSlave {
            addr: sa,
            codes: AC2726,
            parameter: Nibble::ALL,
        });
        slaves.push(Slave::new(
            format!("io {n}"),
            a,
            AC2726,
            Box::new(IoModule::new()),
        ));
    }
    let bus =
        ProjectedConfig::new(projected).and_then(|p| Bus::new(MasterConfig::default(), p, slaves));
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
