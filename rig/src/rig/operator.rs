//! The operator's and the scenario's actions in the words of the run's log, and the
//! operator's overtravel rescue.

use crate::scenario::{needs_rescue, Action, Fault};
use lift_model::{Lift, SensorFault};

/// How long an operator holds the reset or acknowledge button.
pub(super) const OPERATOR_PULSE: asi_phy::SimDuration = asi_phy::SimDuration::from_millis(100);

/// A scenario action as the log tells it.
pub(super) fn describe(a: &Action) -> String {
    match a {
        Action::Press { button, hold } => format!("{button} pressed for {hold}"),
        Action::Load(l) => format!("load becomes {}", l.name()),
        Action::Door { closed } => format!("door {}", if *closed { "closed" } else { "opened" }),
        Action::Crank { mm } => format!("hand crank {mm:+.1} mm"),
        Action::Reset => "operator presses the safety reset".into(),
        Action::Rescue => "operator's overtravel rescue".into(),
        Action::Ack => "operator acknowledges the safety group error".into(),
        Action::Fault(f) => match f {
            Fault::SlaveOffline { slave } => format!("fault: slave {slave} taken off the bus"),
            Fault::SlaveOnline { slave } => format!("fault cleared: slave {slave} back on the bus"),
            Fault::PowerFail { duration } => format!("fault: AS-i power fails for {duration}"),
            Fault::SafeLinkDrop { duration } => {
                format!("fault: the cabin STOP safe link is silent for {duration}")
            }
            Fault::Vane { sensor, fault } => match fault {
                SensorFault::None => format!("fault cleared: the {sensor} vane sensor works again"),
                SensorFault::StuckOn => format!("fault: the {sensor} vane sensor is stuck on"),
                SensorFault::StuckOff => format!("fault: the {sensor} vane sensor is stuck off"),
            },
        },
    }
}

/// What the operator's overtravel rescue does to the cabin as it stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Rescue {
    /// The cabin stands where initialisation finds floor 1 by itself.
    NotNeeded,
    /// K1 is closed: nobody cranks a drive that has power.
    K1Closed,
    /// Crank this far (mm, + up) to the nearer end floor's level.
    Crank(f64),
}

/// The operator's overtravel rescue for a cabin that stands where initialisation cannot find
/// floor 1 by itself (on or beyond an overtravel sensor, below floor 1's vane): a crank to the
/// nearer end floor's level, only with K1 open.
pub(super) fn rescue(lift: &Lift, floors: u8) -> Rescue {
    let x = lift.position_mm();
    if !needs_rescue(floors, x) {
        return Rescue::NotNeeded;
    }
    let end_floor = if x < 0.0 { 1 } else { floors };
    let Some(to) = lift.config().floor_level_mm(end_floor) else {
        return Rescue::NotNeeded;
    };
    if lift.k1_closed() {
        return Rescue::K1Closed;
    }
    Rescue::Crank(to - x)
}
