//! A safety invariant broken ([`Violation`]) and the invariants the rig watches
//! ([`ViolationKind`]).

use serde::Serialize;

/// A safety invariant broken.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Violation {
    /// When it was found, seconds.
    pub at_s: f64,
    /// Which invariant.
    pub kind: ViolationKind,
    /// What was seen.
    pub detail: String,
}

/// The invariants the rig watches (the book, "Violations"); in files by their names. Declared
/// in the order of their names, which is their order in summaries.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, serde::Deserialize,
)]
pub enum ViolationKind {
    /// The cabin moves with the door open beyond the reaction budget.
    #[serde(rename = "door-open-moving")]
    DoorOpenMoving,
    /// K1 stays closed with an overtravel sensor tripped.
    #[serde(rename = "k1-in-overtravel")]
    K1InOvertravel,
    /// The cabin hits a mechanical end of the shaft.
    #[serde(rename = "mechanical-end")]
    MechanicalEnd,
    /// Unintended movement: the car that stood at rest with the door open moved further than
    /// a few mm (watched with the safe drive only; the book, "Violations").
    #[serde(rename = "unintended-movement")]
    UnintendedMovement,
    /// The cabin moves overloaded beyond the reaction budget.
    #[serde(rename = "overloaded-moving")]
    OverloadedMoving,
    /// K1 still closed after STOP's delay and a margin.
    #[serde(rename = "stop-ignored")]
    StopIgnored,
    /// After STOP the cabin went on past the next floor in its direction of travel, reversed,
    /// or started a new run, before the circuit was restarted (docs/safety.md).
    #[serde(rename = "stop-overrun")]
    StopOverrun,
}

impl ViolationKind {
    /// Every kind.
    pub const ALL: [ViolationKind; 7] = [
        ViolationKind::DoorOpenMoving,
        ViolationKind::K1InOvertravel,
        ViolationKind::MechanicalEnd,
        ViolationKind::UnintendedMovement,
        ViolationKind::OverloadedMoving,
        ViolationKind::StopIgnored,
        ViolationKind::StopOverrun,
    ];

    /// The kind's name in reports and files.
    pub const fn name(self) -> &'static str {
        match self {
            ViolationKind::DoorOpenMoving => "door-open-moving",
            ViolationKind::OverloadedMoving => "overloaded-moving",
            ViolationKind::K1InOvertravel => "k1-in-overtravel",
            ViolationKind::MechanicalEnd => "mechanical-end",
            ViolationKind::UnintendedMovement => "unintended-movement",
            ViolationKind::StopIgnored => "stop-ignored",
            ViolationKind::StopOverrun => "stop-overrun",
        }
    }
}

impl std::fmt::Display for ViolationKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.name())
    }
}
