//! Steps the rig to a moment, reads the AS-i master's process image there, and forks the run:
//! a copy of the rig (a snapshot) goes on exactly as the original would, so each copy can try
//! something else from that moment. Here the original runs the demo as it is, and a copy has
//! a passenger press STOP in the moving cabin.
//!
//! ```text
//! cargo run --example fork_a_run
//! ```

use asi_phy::{SimDuration, SimTime, SlaveAddr};
use lift_model::Button;
use rig::report::Report;
use rig::scenario::builtin::Builtin;
use rig::scenario::Action;
use rig::Rig;
use std::error::Error;

/// When the fork is taken: the cabin travels from floor 1 to floor 3.
const FORK_AT: SimTime = SimTime::from_millis(18_000);

/// The demo, the image read at [`FORK_AT`], and the runs from there: the original, an
/// untouched copy, and a copy in which STOP is pressed at once.
struct Forked {
    /// The converter slave's output nibble at the fork (D0 run, D1 up).
    converter_outputs: u8,
    original: Report,
    copy: Report,
    stopped: Report,
}

fn fork() -> Result<Forked, Box<dyn Error>> {
    let sc = Builtin::find("demo").ok_or("no demo")?.scenario()?;
    let mut rig = Rig::new(sc)?;
    // Step moment by moment to the fork: between moments the rig can be read and acted on.
    while rig.step_until(FORK_AT).is_some() {}
    let converter = SlaveAddr::a(lab::address::CONVERTER).ok_or("no address")?;
    let converter_outputs = rig.lab().bus().image().output.nibble(converter).get();

    let copy = rig.clone();
    let mut stopped = rig.clone();
    stopped.act_now(
        rig::Actor::Scenario,
        &Action::Press {
            button: Button::Stop,
            hold: SimDuration::from_secs(2),
        },
    );
    Ok(Forked {
        converter_outputs,
        original: rig.run(None),
        copy: copy.run(None),
        stopped: stopped.run(None),
    })
}

fn floors(r: &Report) -> Vec<u8> {
    r.arrivals.iter().map(|a| a.floor).collect()
}

fn main() -> Result<(), Box<dyn Error>> {
    let f = fork()?;
    println!(
        "at {:.3} s: the converter's outputs are {:04b} (run {}, up {})",
        FORK_AT.as_secs_f64(),
        f.converter_outputs,
        f.converter_outputs & 1,
        f.converter_outputs >> 1 & 1
    );
    println!("original: at rest at floors {:?}", floors(&f.original));
    println!(
        "copy:     at rest at floors {:?} (the same run: {})",
        floors(&f.copy),
        f.copy == f.original
    );
    println!("STOP:     at rest at floors {:?}", floors(&f.stopped));
    for t in &f.stopped.safety.trips {
        println!("{:8.3} s  safety: {}", t.at_s, t.cause);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rig::report::TripCause;
    use safety::LiftSafetyCause;

    /// The cabin is travelling up at the fork; an untouched copy gives the original's report;
    /// STOP in the copy trips the STOP circuit at once, and nothing is violated.
    #[test]
    fn a_copy_goes_on_as_the_original_and_another_tries_stop() {
        let f = fork().expect("the demo forks");
        assert_eq!(f.converter_outputs & 0b11, 0b11, "running up at the fork");
        assert!(f.copy == f.original);
        let stop = f.stopped.safety.trips.first().expect("a trip");
        assert!(matches!(
            stop.cause,
            TripCause::Logic(LiftSafetyCause::StopDemanded { .. })
        ));
        // At the safety logic's next scan (every 1 ms) after the press.
        let after = stop.at_s - FORK_AT.as_secs_f64();
        assert!(after > 0.0 && after <= 0.001 + 1e-9, "{after}");
        assert!(f.original.safety.trips.is_empty());
        assert!(
            f.stopped.violations.is_empty(),
            "{:?}",
            f.stopped.violations
        );
        assert_ne!(floors(&f.stopped), floors(&f.original));
    }
}
