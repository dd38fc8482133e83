//! Prints the transaction trace of the lab lift's bus from power-on, with statistics.
//!
//! `cargo run -p asi-lift-bus --example trace -- 30` (milliseconds of simulated time).

use asi_bus::lab::LabLift;
use asi_phy::SimTime;

fn main() {
    let ms: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(30);
    let mut lab = match LabLift::new() {
        Ok(l) => l,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    lab.bus_mut().enable_trace(1 << 20);
    lab.bus_mut().advance_to(SimTime::from_millis(ms));
    for r in lab.bus_mut().drain_trace() {
        println!("{r}");
    }
    let m = lab.bus().master();
    println!("{}", lab.bus().stats());
    println!("phase {:?}, flags {}", m.phase(), m.flags());
    println!("LDS {}  LAS {}  LPS {}", m.lds(), m.las(), m.lps());
}
