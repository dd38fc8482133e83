use asi_master::lab::LabLift;
use asi_phy::SimTime;
fn main() {
    let mut lab = LabLift::new().expect("lab");
    lab.bus.enable_trace(100_000);
    let ms: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20);
    lab.bus.advance_to(SimTime::from_millis(ms));
    for r in lab.bus.drain_trace() {
        println!("{r}");
    }
    println!("{}", lab.bus.stats());
    println!("flags {}", lab.bus.master().flags());
    println!(
        "LDS {} LAS {}",
        lab.bus.master().lds(),
        lab.bus.master().las()
    );
    println!("word0 {:04X}", lab.bus.image().input.word(0));
}
