//! The cabin's two vane sensors and the shaft's two ends, by name: the plant's configuration,
//! its events and the shaft all speak of them.

use core::fmt;

use serde::{Deserialize, Serialize};

/// One of the two vane (lamel) sensors on the cabin (tables 6.1, 6.2 of the lift thesis).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum VaneSensor {
    /// `Snimac_1`, the left sensor: long track at floor 1, short at floors 2..N.
    Left,
    /// `Snimac_2`, the right sensor: short track at floor 1, long at floors 2..N.
    Right,
}

impl VaneSensor {
    /// The lift thesis' variable name: `Snimac_1` (left) or `Snimac_2` (right).
    pub fn thesis_name(self) -> &'static str {
        match self {
            VaneSensor::Left => "Snimac_1",
            VaneSensor::Right => "Snimac_2",
        }
    }
}

impl fmt::Display for VaneSensor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let side = match self {
            VaneSensor::Left => "left",
            VaneSensor::Right => "right",
        };
        write!(f, "{} ({side})", self.thesis_name())
    }
}

/// An end of the shaft: where an overtravel sensor and a mechanical end are (docs/lift-plant.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum End {
    /// Below floor 1 (safety slave 11, docs/lab-bus.md).
    Bottom,
    /// Above the top floor (safety slave 12, docs/lab-bus.md).
    Top,
}

impl fmt::Display for End {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            End::Bottom => "bottom",
            End::Top => "top",
        })
    }
}
