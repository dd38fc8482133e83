//! The program's phases (waiting, initialisation, service, bus fault), the steps of initialisation
//! (table 6.3 of the lift thesis) and of the automat (tables 6.4/6.5), and the [`State`] they show
//! as.

use super::events::HaltReason;
use crate::dispatch::Dir;
use asi_phy::SimTime;
use core::fmt;

/// Initialisation steps (table 6.3 of the lift thesis, extended for a start at floor 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum InitStep {
    /// Jede: down at the initialisation speed.
    Run,
    /// Brzdí: creeping with the 2 s timer after the left sensor rose.
    Brake { until: SimTime },
    /// Inside floor 1's long track: creep down until the right sensor rises (level) or the
    /// left one falls (we were below level).
    Floor1Down,
    /// Level at an unknown floor: creep down; which sensor falls first tells the floor.
    Probe,
    /// Below floor 1's level: creep up until both sensors are on.
    Floor1Up,
}

/// Automat steps (tables 6.4/6.5 of the lift thesis).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Step {
    /// Aktuální patro: standing at a floor.
    AtFloor,
    /// Porucha přetížení.
    Overload,
    /// Jede dolů / Jede nahoru.
    Travel,
    /// Dobrždění.
    Braking,
    /// Porucha Stop: stopped after STOP, waiting for a cabin request.
    StopFault,
    /// Held between floors; `braking` says which step to go back to.
    Halted { reason: HaltReason, braking: bool },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Phase {
    /// Until the first cabin word arrives, nothing is known.
    WaitInputs,
    Init(InitStep),
    Service(Step),
    /// The bus is not healthy: the cabin is held. `resume` is the step to go back to if the
    /// program never lost sight of the cabin (`blind` = the cabin word went stale or the power
    /// failed, after which the program initialises again).
    BusFault {
        resume: Option<Step>,
        blind: bool,
    },
}

/// The program's state as the report shows it: the phase, and in service the automat's step
/// (tables 6.3–6.5 of the lift thesis). [`State::name`] gives the words the report and the rig use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum State {
    /// No cabin word yet: nothing is known.
    WaitingForInputs,
    /// Initialisation (table 6.3 of the lift thesis), held or not.
    Initialising,
    /// The bus is not healthy: the cabin is held.
    BusFault,
    /// Aktuální patro: standing at a floor.
    AtFloor,
    /// Porucha přetížení.
    OverloadFault,
    /// Jede nahoru.
    MovingUp,
    /// Jede dolů.
    MovingDown,
    /// Dobrždění.
    Braking,
    /// Porucha Stop: stopped after STOP, waiting for a cabin request.
    StopFault,
    /// Held between floors.
    Halted,
}

impl State {
    /// Every state.
    pub const ALL: [State; 10] = [
        State::WaitingForInputs,
        State::Initialising,
        State::BusFault,
        State::AtFloor,
        State::OverloadFault,
        State::MovingUp,
        State::MovingDown,
        State::Braking,
        State::StopFault,
        State::Halted,
    ];

    /// Whether the program is in service: initialised, its automat running (not waiting for
    /// its inputs, initialising or in a bus fault).
    pub fn in_service(self) -> bool {
        !matches!(
            self,
            State::WaitingForInputs | State::Initialising | State::BusFault
        )
    }

    /// The state of a name ([`State::name`]).
    pub fn from_name(name: &str) -> Option<State> {
        State::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The state in words, as the report shows it.
    pub fn name(self) -> &'static str {
        match self {
            State::WaitingForInputs => "waiting for inputs",
            State::Initialising => "initialising",
            State::BusFault => "bus fault",
            State::AtFloor => "at floor",
            State::OverloadFault => "overload fault",
            State::MovingUp => "moving up",
            State::MovingDown => "moving down",
            State::Braking => "braking",
            State::StopFault => "STOP fault",
            State::Halted => "halted",
        }
    }
}

impl fmt::Display for State {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.name())
    }
}

/// In files (reports, campaign lines) a state is its name.
impl serde::Serialize for State {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for State {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<State, D::Error> {
        let name = <std::borrow::Cow<'de, str>>::deserialize(d)?;
        State::from_name(&name)
            .ok_or_else(|| serde::de::Error::custom(format!("unknown controller state `{name}`")))
    }
}

impl Phase {
    /// The state shown for this phase; `dir` is the direction of the present trip.
    pub(super) fn state(self, dir: Option<Dir>) -> State {
        match self {
            Phase::WaitInputs => State::WaitingForInputs,
            Phase::Init(_) => State::Initialising,
            Phase::BusFault { .. } => State::BusFault,
            Phase::Service(step) => match step {
                Step::AtFloor => State::AtFloor,
                Step::Overload => State::OverloadFault,
                Step::Travel if dir == Some(Dir::Up) => State::MovingUp,
                Step::Travel => State::MovingDown,
                Step::Braking => State::Braking,
                Step::StopFault => State::StopFault,
                Step::Halted { .. } => State::Halted,
            },
        }
    }
}
