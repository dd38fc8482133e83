//! The plant: its state and how it is built (docs/lift-plant.md). The event loop and the cabin's motion
//! are in `time`, the inputs in `inputs`, the outputs in `outputs`.

mod inputs;
mod outputs;
mod time;

use std::collections::VecDeque;

use asi_phy::SimTime;

use crate::config::{LiftConfig, LiftConfigError};
use crate::controls::{Button, Buttons, ContactFault, LoadLevel, SensorFault};
use crate::display::DisplayState;
use crate::event::{Crash, PlantEvent};
use crate::motion::Segment;
use crate::sensor::End;
use crate::shaft::{Levels, Shaft};

/// Why an input was refused. The plant is unchanged by a refused input, except that time has
/// moved on to `now` if it was later than the plant's time.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlantError {
    /// An input or `advance_to` earlier than the plant's own time.
    #[error("input at {now} is earlier than the plant's time {plant_time}: simulated time only moves forward")]
    TimeReversed {
        /// The time given.
        now: SimTime,
        /// The plant's time.
        plant_time: SimTime,
    },
    /// A button the lift does not have.
    #[error("the {floors}-floor lift has no {button} (there is no hall up at the top floor and no hall down at floor 1)")]
    NoSuchButton {
        /// The button asked for.
        button: Button,
        /// The lift's floors.
        floors: u8,
    },
    /// A press of zero duration, which no one could observe.
    #[error("a press of the {button} must last at least 1 ns")]
    EmptyPress {
        /// The button asked for.
        button: Button,
    },
    /// A display the lift does not have.
    #[error("the {floors}-floor lift has no display at floor {floor}")]
    NoSuchDisplay {
        /// The floor asked for.
        floor: u8,
        /// The lift's floors.
        floors: u8,
    },
    /// A crank distance that is NaN or infinite.
    #[error("crank distance {distance_mm:?} mm is not a finite number")]
    CrankDistance {
        /// The distance given.
        distance_mm: f64,
    },
    /// The crank needs the drive without power (§6.3 of the lift thesis).
    #[error("the hand crank is refused while contactor K1 is closed: the drive has power")]
    CrankWhilePowered,
    /// The crank needs the cabin at rest.
    #[error("the hand crank is refused while the cabin moves ({velocity_mm_s:.3} mm/s)")]
    CrankWhileMoving {
        /// The cabin's velocity.
        velocity_mm_s: f64,
    },
    /// The cabin already touches the mechanical end in the direction asked.
    #[error(
        "the cabin stands against the {end} mechanical end: it cannot be cranked further that way"
    )]
    CrankBlocked {
        /// Which end.
        end: End,
    },
}

/// What moves the cabin now; a change of goal re-plans the motion.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Goal {
    /// The converter has power and no fault: it ramps to this velocity (0 when not running).
    Drive { v_target: f64 },
    /// No drive power, or the converter is faulted: the brake holds or stops the cabin.
    Brake,
    /// A person turns the motor by hand to this position.
    Crank { target_mm: f64 },
}

/// Contactor K1 between the mains and the converter (docs/lift-plant.md, §6).
#[derive(Clone, Copy, Debug)]
struct Contactor {
    coil: bool,
    main_closed: bool,
    weld_fault: bool,
}

/// The converter's inputs and internal faults.
#[derive(Clone, Copy, Debug)]
struct Converter {
    run: bool,
    up: bool,
    setpoint_ua: u16,
    injected_fault: bool,
    stalled: bool,
    /// A runaway fault: the converter drives the motor this way (`true` up) at its highest
    /// frequency, whatever run, direction and set-point say.
    runaway: Option<bool>,
}

/// The events queued since the caller last drained them, in time order.
///
/// At almost every moment of a run none is queued: then no drain of the queue is made, and
/// [`ExactSizeIterator::len`] says 0 at once.
pub struct Events<'a>(Option<std::collections::vec_deque::Drain<'a, PlantEvent>>);

impl Iterator for Events<'_> {
    type Item = PlantEvent;
    fn next(&mut self) -> Option<PlantEvent> {
        self.0.as_mut()?.next()
    }
    fn size_hint(&self) -> (usize, Option<usize>) {
        self.0.as_ref().map_or((0, Some(0)), |d| d.size_hint())
    }
}

impl ExactSizeIterator for Events<'_> {}

/// The laboratory lift of the lift thesis as a plant: shaft, cabin, converter, motor, brake, K1,
/// sensors, buttons, door, load and displays (docs/lift-plant.md). Sans-IO: time is passed in.
///
/// # Time and events
///
/// The plant has its own time [`Lift::now`]. [`Lift::next_event`] says when the next edge
/// happens under the present inputs; [`Lift::advance_to`] moves to a later time and returns
/// every edge up to and including it, in time order, each at the first nanosecond at which
/// its new state holds (see the crate documentation for the rounding rule). Edges at one
/// nanosecond come in this order: button releases, sensor edges in the order the cabin meets
/// them, then the end of the motion segment. The result does not depend on how the caller
/// steps: one call to `t`, a million small ones, or jumps from event to event give the same
/// events at the same times and the same state.
///
/// Every input method takes `now ≥` [`Lift::now`], first brings the plant to `now` (queuing the
/// edges on the way, returned by the next `advance_to`), then applies the input at `now`.
#[derive(Clone, Debug)]
pub struct Lift {
    config: LiftConfig,
    shaft: Shaft,
    ramp_mm_s2: f64,
    now: SimTime,
    motion: Segment,
    /// Boundaries `shaft.boundaries[..split]` are below the cabin.
    split: usize,
    /// The next crossing is searched from here (the last change of motion or crossing).
    search_from: SimTime,
    next_crossing: Option<SimTime>,
    levels: Levels,
    goal: Goal,
    k1: Contactor,
    converter: Converter,
    crank_target_mm: Option<f64>,
    buttons: Buttons,
    stop_faults: [ContactFault; 2],
    /// Faults of the left and right vane sensors' outputs.
    vane_faults: [SensorFault; 2],
    door_closed: bool,
    load: LoadLevel,
    /// Floors 1..N, then the cabin.
    displays: Vec<DisplayState>,
    crashes: Vec<Crash>,
    events: VecDeque<PlantEvent>,
    /// Counts the inputs and the handled edges ([`Lift::changes`]).
    changes: u64,
    /// The next edge ([`Lift::next_event`]), kept up to date by
    /// [`Lift::next_event_changed`].
    next: Option<SimTime>,
}

impl Lift {
    /// Builds the plant at time zero, the cabin at rest at `config.initial_position_mm`,
    /// K1 open, converter stopped at 4000 µA, door closed, cabin empty, displays blank.
    pub fn new(config: LiftConfig) -> Result<Lift, LiftConfigError> {
        config.validate()?;
        let shaft = Shaft::new(&config);
        let x = config.initial_position_mm;
        let split = shaft.split_at(x);
        let levels = shaft.levels_below(split);
        let floors = config.floors;
        Ok(Lift {
            ramp_mm_s2: config.drive.ramp_mm_s2(),
            shaft,
            now: SimTime::ZERO,
            motion: Segment::rest(SimTime::ZERO, x),
            split,
            search_from: SimTime::ZERO,
            next_crossing: None,
            levels,
            goal: Goal::Brake,
            k1: Contactor {
                coil: false,
                main_closed: false,
                weld_fault: false,
            },
            converter: Converter {
                run: false,
                up: false,
                setpoint_ua: lab::setpoint::STANDSTILL_UA,
                injected_fault: false,
                stalled: false,
                runaway: None,
            },
            crank_target_mm: None,
            buttons: Buttons::new(floors),
            stop_faults: [ContactFault::None; 2],
            vane_faults: [SensorFault::None; 2],
            door_closed: true,
            load: LoadLevel::Empty,
            displays: vec![DisplayState::Blank; usize::from(floors) + 1],
            crashes: Vec::new(),
            events: VecDeque::with_capacity(64),
            changes: 0,
            next: None,
            config,
        })
    }

    /// The configuration the plant was built from.
    pub fn config(&self) -> &LiftConfig {
        &self.config
    }

    /// The plant's time: the last `advance_to` or input.
    pub fn now(&self) -> SimTime {
        self.now
    }
}
