//! rig: the asi-lift lab rig as a library. It wires the simulated AS-i bus, the lab lift, its
//! PLC program and its safety logic together on one simulated clock ([`rig`]), driven by a
//! scenario ([`scenario`]), judged by the invariant watch and summed up in a [`report`]; around
//! it the waveform outputs of a run ([`waves`]), the timing analysis ([`timing`]) and the fault
//! campaigns ([`campaign`]); beside it the teaching stand of the SafeMOTION thesis ([`stand`]). The
//! `asi-lift` command, the tests and other front-ends use it.
//!
//! # Time
//!
//! A rig lives on simulated time only: it never reads the wall clock, and its one random
//! source, the line noise, is seeded by the scenario. The same scenario with the same seed
//! gives the same report, trace and waveforms, byte for byte, however it is stepped.
//! [`Rig::run`] goes to the end in one call. [`Rig::step_until`] handles the next moment
//! (a bus event that reaches the plant, a plant edge, a PLC or safety scan, a scenario event)
//! if it comes before the run's end and no later than the time given, and returns it: between
//! moments the caller may look at the rig, [`Rig::schedule`] or do actions
//! ([`Rig::act_now`]), and then step on. [`Rig::run`] goes on from the moment reached to the
//! end (the moment at the end included); [`Rig::finish`] ends the run where it stands.
//!
//! ```
//! use asi_phy::{SimDuration, SimTime, SlaveAddr};
//! use rig::scenario::builtin::Builtin;
//! use rig::Rig;
//!
//! // The built-in demo, as `asi-lift run` runs it, shortened to 20 simulated seconds.
//! let mut sc = Builtin::find("demo").expect("built in").scenario()?;
//! sc.duration = SimDuration::from_secs(20);
//! let report = Rig::new(sc.clone())?.run(None);
//! assert!(report.violations.is_empty());
//! assert_eq!(report.arrivals[0].floor, 1); // initialised at floor 1
//!
//! // The same run stepped: stop at 5 s and read the master's image. The converter's slave
//! // (address 7) drives the cabin down to find floor 1: its output D0 (run) is on.
//! let mut rig = Rig::new(sc)?;
//! while rig.step_until(SimTime::from_millis(5_000)).is_some() {}
//! let converter = SlaveAddr::a(lab::address::CONVERTER).expect("an address");
//! assert!(rig.lab().bus().image().output.nibble(converter).bit(0));
//! assert!(rig.lift().velocity_mm_s() < 0.0);
//! // Stepped or not, the run is the same: `run` goes on from the moment reached.
//! assert_eq!(rig.run(None), report);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod campaign;
pub mod explore;
pub mod referee;
pub mod report;
pub mod rig;
pub mod scenario;
pub mod stand;
pub mod timing;
pub mod waves;

pub use crate::rig::{Rig, RigError};
pub use report::{Actor, Report};
pub use scenario::Scenario;
