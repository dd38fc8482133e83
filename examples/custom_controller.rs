//! A lift controller of your own on the simulated lab bus: it shuttles the cabin between the
//! floor below where it starts and the floor above that, and stands 3 s at each.
//!
//! ```text
//! cargo run --example custom_controller
//! ```
//!
//! The controller implements [`controller::Controller`]: one PLC scan over the AS-i master's
//! process image. The lab bus's I/O comes from the library ([`PlcIo`]: the handshakes of the
//! floor stations and the cabin panel, the load sensor, the converter, the S-7.3 speed
//! set-point), so the controller's own part is a function from [`Inputs`] to [`Outputs`], as
//! the built-in program's is. The rig judges it as it judges any controller: the run's report
//! lists every safety violation.

use asi_phy::{SimDuration, SimTime};
use controller::plc::{FromSafety, PlcIo, ToSafety};
use controller::{Controller, Inputs, Outputs, ProcessImage};
use rig::scenario::builtin::Builtin;
use rig::Rig;
use std::any::Any;

/// The converter's speed set-points, µA of the current loop (the lift thesis, tables 6.4 and
/// 6.5): travel 59.4 mm/s, creep 20.6 mm/s, standstill.
const TRAVEL_UA: u16 = 10_000;
const CREEP_UA: u16 = 6_000;
const STANDSTILL_UA: u16 = 4_000;
/// How long the cabin stands at a floor.
const DWELL: SimDuration = SimDuration::from_secs(3);
/// How often the STOP circuit's restart is pulsed while the safety logic holds it open.
const RESTART_EVERY: SimDuration = SimDuration::from_millis(500);

/// Where the shuttle is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    /// Running `up` (or down) to the next floor's level; `left` once the cabin is out of the
    /// vane it started in.
    Running { up: bool, left: bool },
    /// Standing level at a floor until the time given; then it goes the other way.
    Standing { until: SimTime, next_up: bool },
}

/// The shuttle: a controller of its own on the library's I/O.
#[derive(Clone)]
struct Shuttle {
    io: PlcIo,
    phase: Phase,
    /// The vane sensors (left, right) of the last cabin word: both on = level at a floor.
    vanes: (bool, bool),
    last_restart: Option<SimTime>,
    /// Floors reached, for the caller.
    stops: u32,
}

impl Shuttle {
    fn new() -> Shuttle {
        Shuttle {
            io: PlcIo::new(4).expect("the lab bus has 4 floor stations"),
            phase: Phase::Running {
                up: false,
                left: true,
            },
            vanes: (false, false),
            last_restart: None,
            stops: 0,
        }
    }

    /// The shuttle's program: the inputs of a scan to its outputs.
    fn program(&mut self, now: SimTime, i: &Inputs) -> Outputs {
        if let Some(cabin) = i.cabin {
            self.vanes = (cabin.vane_left, cabin.vane_right);
        }
        let mut out = Outputs {
            setpoint_ua: STANDSTILL_UA,
            // A load that cannot be read counts as overloaded, its unsafe value.
            overloaded: i.load >= 3 || i.load_lost,
            ..Outputs::default()
        };
        // The safety logic opens the STOP circuit at power-on and after a STOP: pulse its
        // restart until EStopOut is back.
        if !i.estop_ok && self.last_restart.is_none_or(|t| now >= t + RESTART_EVERY) {
            out.restart = true;
            self.last_restart = Some(now);
        }
        let powered = i.estop_ok && i.converter_ready && !i.converter_fault && i.bus_ok;
        let level = self.vanes.0 && self.vanes.1;
        let in_vane = self.vanes.0 || self.vanes.1;
        match self.phase {
            Phase::Standing { until, next_up } => {
                if now >= until {
                    self.phase = Phase::Running {
                        up: next_up,
                        left: false,
                    };
                }
            }
            Phase::Running { up, left } => {
                let left = left || !in_vane;
                if left && level {
                    self.stops += 1;
                    self.phase = Phase::Standing {
                        until: now + DWELL,
                        next_up: !up,
                    };
                } else if powered && !out.overloaded {
                    out.run = true;
                    out.up = up;
                    // Creep once the next floor's vane has begun.
                    out.setpoint_ua = if left && in_vane { CREEP_UA } else { TRAVEL_UA };
                    self.phase = Phase::Running { up, left };
                }
            }
        }
        out
    }
}

impl Controller for Shuttle {
    fn scan_period(&self) -> SimDuration {
        SimDuration::from_millis(10)
    }

    fn scan(&mut self, now: SimTime, image: &mut ProcessImage, safety: FromSafety) -> ToSafety {
        let inputs = self.io.read(image, safety);
        let outputs = self.program(now, &inputs);
        self.io.write(&outputs, image)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// The built-in demo's rig (the cabin powered on between floors 2 and 3) for `seconds`, with
/// the shuttle in the built-in program's place.
fn shuttle_rig(seconds: u64) -> Rig {
    let mut sc = Builtin::find("demo")
        .expect("the demo is built in")
        .scenario()
        .expect("the demo reads");
    sc.duration = SimDuration::from_secs(seconds);
    // The shuttle answers no calls: the demo's presses are left out.
    sc.events.clear();
    Rig::new(sc)
        .expect("the demo builds")
        .with_controller(Shuttle::new())
}

fn main() {
    let report = shuttle_rig(120).run(None);
    for a in &report.arrivals {
        println!(
            "{:8.3} s  level at floor {} ({:.1} mm)",
            a.at_s, a.floor, a.position_mm
        );
    }
    println!(
        "violations: {}",
        if report.violations.is_empty() {
            "none".to_string()
        } else {
            format!("{:?}", report.violations)
        }
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shuttle serves floors 2 and 3 in turn, and the judge finds nothing wrong.
    #[test]
    fn the_shuttle_goes_between_two_floors_and_breaks_no_rule() {
        let mut rig = shuttle_rig(120);
        while rig.step_until(rig.end()).is_some() {}
        let stops = rig.controller::<Shuttle>().expect("the shuttle").stops;
        let report = rig.finish();
        assert!(report.violations.is_empty(), "{:?}", report.violations);
        let floors: Vec<u8> = report.arrivals.iter().map(|a| a.floor).collect();
        assert!(floors.len() >= 4, "{floors:?}");
        assert_eq!(stops as usize, floors.len(), "{floors:?}");
        for pair in floors.windows(2) {
            assert_ne!(pair[0], pair[1], "{floors:?}");
            assert!(pair.iter().all(|f| [2, 3].contains(f)), "{floors:?}");
        }
    }
}
