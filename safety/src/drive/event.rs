//! What the safe drive reports: violations with their evidence and the event log.

use std::fmt;

use asi_phy::SimTime;

use super::function::Function;

/// Why a function tripped. Each carries the measured value and the limit it broke.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Violation {
    /// The speed is above a limit that is being monitored (SOS, SS2, SLS after its ramp).
    SpeedAbove {
        /// The function.
        function: Function,
        /// Measured speed, rev/s.
        speed: f64,
        /// The limit (magnitude), rev/s.
        limit: f64,
    },
    /// The ramp window ended and the speed was still above the target (SS2, SLS).
    NotSlowedInTime {
        /// The function.
        function: Function,
        /// Measured speed at the window's end, rev/s.
        speed: f64,
        /// The target (magnitude), rev/s.
        target: f64,
    },
    /// Ramp monitoring: the speed is above the deceleration envelope.
    AboveEnvelope {
        /// The function.
        function: Function,
        /// Measured speed, rev/s.
        speed: f64,
        /// The envelope at this time, rev/s.
        envelope: f64,
    },
    /// The axis moved too far from the reference position (SOS, SS2, SLI).
    MovedTooFar {
        /// The function.
        function: Function,
        /// Travel from the reference, rev (signed).
        travel: f64,
        /// The allowed travel either way, rev.
        limit: f64,
    },
    /// SDI: the axis moved against the permitted direction by more than the tolerance.
    WrongDirection {
        /// SDI-P or SDI-N.
        function: Function,
        /// Travel against the direction, rev.
        travel: f64,
        /// The position tolerance, rev.
        tolerance: f64,
    },
    /// SLP: the position left [lower, upper].
    OutsidePositionLimits {
        /// Measured position, rev.
        position: f64,
        /// The lower limit, rev.
        lower: f64,
        /// The upper limit, rev.
        upper: f64,
    },
    /// SLI requested while the axis was not at standstill.
    NotAtStandstill {
        /// The function.
        function: Function,
        /// Measured speed, rev/s.
        speed: f64,
        /// The standstill speed tolerance, rev/s.
        tolerance: f64,
    },
    /// SLA: the acceleration or deceleration is above its limit.
    AccelerationAbove {
        /// Measured acceleration (signed), rev/s².
        acceleration: f64,
        /// The limit that applied, rev/s².
        limit: f64,
    },
    /// SLT: the drive's torque is above its limit.
    TorqueAbove {
        /// The drive's torque (signed), mNm.
        torque: f64,
        /// The limit, mNm.
        limit: f64,
    },
    /// SLT is active but the scan brought no valid torque: it counts as above the limit.
    TorqueLost,
    /// A function that needs a safe encoder was requested on an axis without one.
    NeedsEncoder {
        /// The function.
        function: Function,
    },
    /// SLP was requested on an axis whose encoder is not absolute multi-turn.
    NeedsAbsoluteEncoder,
    /// The axis has a safe encoder but the scan brought no valid position or speed.
    FeedbackLost,
}

impl Violation {
    /// The function that tripped, if one did.
    pub fn function(&self) -> Option<Function> {
        match *self {
            Violation::SpeedAbove { function, .. }
            | Violation::NotSlowedInTime { function, .. }
            | Violation::AboveEnvelope { function, .. }
            | Violation::MovedTooFar { function, .. }
            | Violation::WrongDirection { function, .. }
            | Violation::NotAtStandstill { function, .. }
            | Violation::NeedsEncoder { function } => Some(function),
            Violation::OutsidePositionLimits { .. } | Violation::NeedsAbsoluteEncoder => {
                Some(Function::Slp)
            }
            Violation::AccelerationAbove { .. } => Some(Function::Sla),
            Violation::TorqueAbove { .. } | Violation::TorqueLost => Some(Function::Slt),
            Violation::FeedbackLost => None,
        }
    }
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Violation::SpeedAbove {
                function,
                speed,
                limit,
            } => write!(
                f,
                "{function}: the axis turns at {speed:.3} rev/s, faster than the allowed {limit} rev/s"
            ),
            Violation::NotSlowedInTime {
                function,
                speed,
                target,
            } => write!(
                f,
                "{function}: the ramp time ran out and the axis still turns at {speed:.3} rev/s, above {target} rev/s"
            ),
            Violation::AboveEnvelope {
                function,
                speed,
                envelope,
            } => write!(
                f,
                "{function}: the axis brakes too slowly: {speed:.3} rev/s is above the braking ramp's {envelope:.3} rev/s"
            ),
            Violation::MovedTooFar {
                function,
                travel,
                limit,
            } => write!(
                f,
                "{function}: the axis moved {travel:.3} rev from where it was held, more than the allowed {limit} rev"
            ),
            Violation::WrongDirection {
                function,
                travel,
                tolerance,
            } => write!(
                f,
                "{function}: the axis moved {travel:.3} rev in the forbidden direction, more than the allowed {tolerance} rev"
            ),
            Violation::OutsidePositionLimits {
                position,
                lower,
                upper,
            } => write!(
                f,
                "SLP: the axis is at {position:.3} rev, outside the allowed range {lower:.3} to {upper:.3} rev"
            ),
            Violation::NotAtStandstill {
                function,
                speed,
                tolerance,
            } => write!(
                f,
                "{function}: requested while the axis turned at {speed:.3} rev/s; it must be requested at standstill (at most {tolerance} rev/s)"
            ),
            Violation::AccelerationAbove {
                acceleration,
                limit,
            } => write!(
                f,
                "SLA: the axis changes speed at {acceleration:.3} rev/s², more than the allowed {limit} rev/s²"
            ),
            Violation::TorqueAbove { torque, limit } => write!(
                f,
                "SLT: the drive produces {torque:.1} mNm, more than the allowed {limit} mNm"
            ),
            Violation::TorqueLost => f.write_str(
                "SLT: the drive gave no valid torque in this scan (counted as above the limit)",
            ),
            Violation::NeedsEncoder { function } => write!(
                f,
                "{function} requested, but the axis has no safe encoder: without one only STO, SBC and SS1 work"
            ),
            Violation::NeedsAbsoluteEncoder => f.write_str(
                "SLP requested, but the axis's encoder is not absolute multi-turn: SLP needs one",
            ),
            Violation::FeedbackLost => {
                f.write_str("the safe encoder gave no valid position or speed in this scan")
            }
        }
    }
}

/// The kind of a [`DriveEvent`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DriveEventKind {
    /// A function's control bit fell: the function is requested.
    Requested(Function),
    /// A function's safe state is reached (its status bit rises).
    SafeStateReached(Function),
    /// A function's request ended (for SLI: once the disable delay has run out).
    Released(Function),
    /// A violation: the error is latched and the torque goes off.
    Tripped(Violation),
    /// The torque went off (STO, SBC, the end of SS1, an error, Activate FALSE).
    TorqueOff,
    /// The torque is enabled again.
    TorqueOn,
    /// S_Control_Reset acknowledged the error.
    Reset,
}

/// One line of the drive's safety log.
#[derive(Clone, Debug, PartialEq)]
pub struct DriveEvent {
    /// The scan's time.
    pub at: SimTime,
    /// What happened.
    pub kind: DriveEventKind,
}

impl DriveEvent {
    /// `true` for a violation.
    pub fn is_trip(&self) -> bool {
        matches!(self.kind, DriveEventKind::Tripped(_))
    }
}

impl fmt::Display for DriveEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.at, self.kind)
    }
}

impl fmt::Display for DriveEventKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DriveEventKind::Requested(fun) => write!(f, "{fun} requested (control bit FALSE)"),
            DriveEventKind::SafeStateReached(fun) => {
                write!(f, "{fun} reached its safe state (status TRUE)")
            }
            DriveEventKind::Released(fun) => write!(f, "{fun} no longer requested"),
            DriveEventKind::Tripped(v) => write!(f, "tripped, torque off: {v}"),
            DriveEventKind::TorqueOff => f.write_str("torque off"),
            DriveEventKind::TorqueOn => f.write_str("torque on"),
            DriveEventKind::Reset => f.write_str("error acknowledged by S_Control_Reset"),
        }
    }
}
