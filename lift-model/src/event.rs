//! What the plant reports as it runs: every edge it makes on its own, with its exact time
//! (docs/lift-plant.md "events exact in time").

use core::fmt;

use asi_phy::SimTime;

use crate::controls::Button;
use crate::sensor::{End, VaneSensor};

/// One edge, at the first nanosecond at which the new state holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantEvent {
    /// When: the getters report the new state from this instant on, and the old one until the
    /// nanosecond before.
    pub at: SimTime,
    /// What changed.
    pub kind: PlantEventKind,
}

/// The edges the plant makes by itself. Changes that an input causes at once (contactor
/// contacts, converter ready, a button pressed, the door) are not reported: the caller made
/// them and can read them from the getters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PlantEventKind {
    /// A vane sensor on the cabin changed (§6.4 of the lift thesis; `Snimac_1`, `Snimac_2`).
    Vane {
        /// Which sensor.
        sensor: VaneSensor,
        /// Its new level: on over a vane track.
        on: bool,
    },
    /// An overtravel safety sensor changed (GG505S, §6.3 of the lift thesis).
    Overtravel {
        /// Which end.
        end: End,
        /// `true`: now tripped (its safety slave sends 0000); `false`: free again.
        tripped: bool,
    },
    /// The converter reached its set frequency: the cabin runs at constant speed from now.
    RampEnd {
        /// The signed cabin velocity reached, mm/s (positive up).
        velocity_mm_s: f64,
    },
    /// The cabin came to rest: end of a ramp to zero, of braking, or of a crank, or the
    /// momentary standstill of a reversal.
    Stopped {
        /// Where, mm above floor 1.
        position_mm: f64,
    },
    /// The cabin hit a mechanical end and stopped there. Also recorded in
    /// [`crate::Lift::crashes`].
    Crash {
        /// Which end.
        end: End,
        /// The speed at impact, mm/s.
        impact_mm_s: f64,
    },
    /// The converter's fault output changed on its own: it trips (stall, overcurrent) when
    /// the cabin hits a mechanical end while the drive has power.
    ConverterFault {
        /// The new level of the fault output.
        fault: bool,
    },
    /// A button's press ran out and the button is up again.
    Released {
        /// Which button.
        button: Button,
    },
}

/// A recorded impact on a mechanical end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crash {
    /// When.
    pub at: SimTime,
    /// Which end.
    pub end: End,
    /// The speed at impact, mm/s.
    pub impact_mm_s: f64,
    /// Whether the drive had power (the converter trips) or not (brake or hand crank).
    pub powered: bool,
}

impl fmt::Display for PlantEventKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let on_off = |on: bool| if on { "on" } else { "off" };
        match *self {
            PlantEventKind::Vane { sensor, on } => write!(f, "{sensor} {}", on_off(on)),
            PlantEventKind::Overtravel { end, tripped } => {
                let state = if tripped { "tripped" } else { "free" };
                write!(f, "{end} overtravel {state}")
            }
            PlantEventKind::RampEnd { velocity_mm_s } => {
                write!(f, "ramp end at {velocity_mm_s:.3} mm/s")
            }
            PlantEventKind::Stopped { position_mm } => write!(f, "stopped at {position_mm:.3} mm"),
            PlantEventKind::Crash { end, impact_mm_s } => {
                write!(f, "CRASH into the {end} end at {impact_mm_s:.3} mm/s")
            }
            PlantEventKind::ConverterFault { fault } => {
                write!(f, "converter fault {}", on_off(fault))
            }
            PlantEventKind::Released { button } => write!(f, "{button} released"),
        }
    }
}

impl fmt::Display for PlantEvent {
    /// One line of a trace, e.g. `1.234567890 s  Snimac_2 (right) on`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}  {}", self.at, self.kind)
    }
}
