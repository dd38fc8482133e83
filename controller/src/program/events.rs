//! What the program reports: its events, why it halts, why it stops trusting its floor count,
//! and how initialisation starts; with the words the log and the report show for them.

use crate::dispatch::{ServedCall, Source};
use asi_phy::{SimDuration, SimTime};
use core::fmt;

/// Why the program holds the cabin where it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HaltReason {
    /// The door opened during travel.
    DoorOpen,
    /// The cabin became overloaded during travel.
    Overload,
    /// The converter reported a fault.
    ConverterFault,
    /// The converter lost its power (K1 open).
    NoPower,
    /// STOP is demanded (initialisation only; in service STOP has its own states).
    Stop,
    /// The vane sensors showed no edge where one was due (initialisation only): held until a
    /// sensor changes, or for [`NO_VANE_RETRY`] at most.
    NoVane,
}

/// How long initialisation waits after its watchdog before it tries again without a vane
/// sensor edge.
pub const NO_VANE_RETRY: SimDuration = SimDuration::from_secs(10);

impl fmt::Display for HaltReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            HaltReason::DoorOpen => "door open",
            HaltReason::Overload => "overloaded",
            HaltReason::ConverterFault => "converter fault",
            HaltReason::NoPower => "no drive power (K1 open)",
            HaltReason::Stop => "STOP circuit open",
            HaltReason::NoVane => "no vane edge where one was due (a vane sensor fault?)",
        })
    }
}

/// Something the program did, for the log and the report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProgramEventKind {
    /// Initialisation began, from the sensor state seen.
    InitStarted {
        /// What the vane sensors showed.
        start: InitStart,
    },
    /// The cabin stands at floor 1 and the automat takes over.
    Initialised,
    /// A call was stored.
    CallStored {
        /// The floor.
        floor: u8,
        /// Cabin or hall.
        source: Source,
    },
    /// A call was lost because its memory was full.
    CallLost {
        /// The floor.
        floor: u8,
        /// Cabin or hall.
        source: Source,
    },
    /// The cabin leaves for a target.
    Departed {
        /// The floor it leaves.
        from: u8,
        /// Where it goes.
        to: u8,
    },
    /// The cabin passed a floor's first vane edge.
    Passed {
        /// The floor.
        floor: u8,
    },
    /// The cabin creeps into its stop floor.
    Braking {
        /// The floor.
        floor: u8,
    },
    /// The Structured Text program faulted at `line`:`column` of its source and the PLC went
    /// to STOP (its outputs zeroed).
    PlcStopped {
        /// The source line.
        line: u32,
        /// The column.
        column: u32,
        /// What happened.
        cause: st::run::FaultCause,
    },
    /// The cabin stopped level at a floor.
    Arrived {
        /// The floor.
        floor: u8,
    },
    /// A call was served by a stop.
    Served(ServedCall),
    /// STOP in the cabin: the target becomes the next floor in the direction of travel.
    StopDemanded {
        /// The target given up (FIFO: the request is dropped, as in the lift thesis).
        dropped: Option<u8>,
        /// The floor the cabin will stop at.
        stop_at: u8,
    },
    /// The cabin stands in the STOP fault.
    StopFault,
    /// A cabin request after STOP resumes service.
    Resumed,
    /// Overload at a floor: no departure.
    OverloadFault,
    /// The load is back to normal.
    OverloadCleared,
    /// The cabin is held between floors.
    Halted(HaltReason),
    /// The hold is over; travel continues.
    Continued,
    /// The cabin slave or the bus is lost: the cabin stops.
    BusFault,
    /// The bus is back; the program initialises again.
    BusRestored,
    /// Initialisation is held (the cabin does not move) until the reason is gone; then it
    /// starts again from what the vane sensors show.
    InitHeld(HaltReason),
    /// The vane sensors contradict the counted floor, or changed while the program did not
    /// move the cabin (a hand crank): the position is not trusted and is found again by
    /// initialisation before the next journey.
    PositionLost {
        /// What gave it away.
        why: LostReason,
    },
}

/// Why the program stopped trusting its floor count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LostReason {
    /// A vane edge while the program did not move the cabin (moved by hand).
    MovedByHand,
    /// Floor 1's turned vane (the left sensor first) where the count expected another floor,
    /// or another floor's vane where it expected floor 1.
    WrongVane,
    /// A vane beyond the last floor in the direction of travel.
    BeyondEndFloor,
    /// The cabin left its stop floor's vane without ever standing level in it, or did not
    /// reach its level in time.
    MissedLevel,
    /// No vane within the travel watchdog.
    NoVane,
    /// A vane sensor stayed on for longer than a vane takes to pass.
    StuckSensor,
}

impl fmt::Display for LostReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LostReason::MovedByHand => "the cabin moved while the drive was off",
            LostReason::WrongVane => "the vane seen is not the floor counted",
            LostReason::BeyondEndFloor => "a vane beyond the end floor",
            LostReason::MissedLevel => "the stop floor's level was passed",
            LostReason::NoVane => "no vane where one was due",
            LostReason::StuckSensor => "a vane sensor stays on",
        })
    }
}

/// An event with the scan time it happened in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Event {
    /// The scan's time.
    pub at: SimTime,
    /// What happened.
    pub kind: ProgramEventKind,
}

/// The vane sensors at the start of initialisation, which decide how it proceeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InitStart {
    /// No vane, or only the right sensor: the lift thesis' routine (down at 11000 µA).
    ThesisRoutine,
    /// Only the left sensor: inside floor 1's long track, above or below level.
    Floor1Track,
    /// Both sensors: level at some floor; a slow probe tells floor 1 from the others.
    Level,
    /// No vane, but the cabin was last seen creeping down inside floor 1's vane (before a hold
    /// or a bus fault): it is just below floor 1 and creeps up to its level.
    BelowFloor1,
}

impl fmt::Display for ProgramEventKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let src = |s: &Source| match s {
            Source::Cabin => "cabin",
            Source::Hall => "hall",
        };
        match self {
            ProgramEventKind::InitStarted { start } => write!(
                f,
                "initialisation: {}",
                match start {
                    InitStart::ThesisRoutine => "running down to find floor 1",
                    InitStart::Floor1Track => "inside floor 1's vane, creeping to level",
                    InitStart::Level => "level at a floor, probing which one",
                    InitStart::BelowFloor1 => "just below floor 1's vane, creeping up",
                }
            ),
            ProgramEventKind::Initialised => f.write_str("initialised at floor 1"),
            ProgramEventKind::PlcStopped {
                line,
                column,
                cause,
            } => write!(
                f,
                "PLC in STOP: {cause} at line {line}, column {column}; outputs zeroed"
            ),
            ProgramEventKind::CallStored { floor, source } => {
                write!(f, "{} call to floor {floor} stored", src(source))
            }
            ProgramEventKind::CallLost { floor, source } => {
                write!(f, "{} call to floor {floor} lost: memory full", src(source))
            }
            ProgramEventKind::Departed { from, to } => {
                write!(f, "departs floor {from} for floor {to}")
            }
            ProgramEventKind::Passed { floor } => write!(f, "passes floor {floor}"),
            ProgramEventKind::Braking { floor } => write!(f, "brakes for floor {floor}"),
            ProgramEventKind::Arrived { floor } => write!(f, "arrives at floor {floor}"),
            ProgramEventKind::Served(s) => {
                write!(f, "{} call to floor {} served", src(&s.source), s.floor)
            }
            ProgramEventKind::StopDemanded { dropped, stop_at } => match dropped {
                Some(d) => write!(f, "STOP: stops at floor {stop_at}, target {d} dropped"),
                None => write!(f, "STOP: stops at floor {stop_at}"),
            },
            ProgramEventKind::StopFault => f.write_str("STOP fault: waiting for a cabin request"),
            ProgramEventKind::Resumed => f.write_str("cabin request after STOP: service resumes"),
            ProgramEventKind::OverloadFault => f.write_str("overloaded: no departure"),
            ProgramEventKind::OverloadCleared => f.write_str("load back to normal"),
            ProgramEventKind::Halted(r) => write!(f, "halted between floors: {r}"),
            ProgramEventKind::Continued => f.write_str("continues travel"),
            ProgramEventKind::BusFault => f.write_str("cabin slave or bus lost: cabin stopped"),
            ProgramEventKind::BusRestored => f.write_str("bus restored: initialising again"),
            ProgramEventKind::InitHeld(r) => write!(f, "initialisation held: {r}"),
            ProgramEventKind::PositionLost { why } => {
                write!(f, "floor count not trusted ({why}): initialising again")
            }
        }
    }
}
