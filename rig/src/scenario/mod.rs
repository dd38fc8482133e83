//! Scenario files: what happens to the lift, and when (TOML; documented in README.md).
//!
//! The scenario itself and its limits are here; `read` reads a file (a malformed one gets an
//! error that names the file, the line and the field at fault; unknown keys are errors, not
//! silently ignored), `write` writes one back.

pub mod builtin;
pub mod program;
pub(crate) mod read;
#[cfg(test)]
mod tests;
pub mod traffic;
mod write;

use asi_phy::{SimDuration, SimTime};
use controller::Algorithm;
use lift_model::{Button, End, LiftConfig, LoadLevel, SensorFault, VaneSensor};
use std::fmt;
use std::ops::RangeInclusive;

/// A scenario, checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    /// Its name, for the report.
    pub name: String,
    /// The seed of every random choice (line noise; the traffic templates without a seed of
    /// their own).
    pub seed: u64,
    /// How long to simulate.
    pub duration: SimDuration,
    /// The controller's algorithm.
    pub algorithm: Algorithm,
    /// Floors, 2..=24.
    pub floors: u8,
    /// Cabin height at power-on above the floor-1 level, mm.
    pub start_mm: f64,
    /// Load at power-on.
    pub load: LoadLevel,
    /// Door closed at power-on.
    pub door_closed: bool,
    /// Probability that a pulse on the line is corrupted.
    pub pulse_error_rate: f64,
    /// Plain I/O modules added to the lab bus at its free addresses (0..=20): the lift on a
    /// fuller bus.
    pub extra_slaves: u8,
    /// The AS-i master's mode from power-on (docs/master.md §2.3): protected (the lab's) or
    /// configuration, where every detected slave is activated and the prj LED is yellow.
    pub master_mode: asi_master::Mode,
    /// The PLC scan period.
    pub plc_scan: SimDuration,
    /// The lift's PLC program, if not the built-in one: a Structured Text program
    /// (`[controller] program`, or `--controller` on the command line).
    pub program: Option<program::ProgramFile>,
    /// Whether the operator presses the safety reset once after power-on, as at the lab
    /// (the overtravel monitor needs a manual reset before K1 can close).
    pub power_on_reset: bool,
    /// The lab drive has a safe encoder and a drive safety monitor (`[drive] safe = true`;
    /// docs/drive-safety.md §6): SS1 on STOP, SOS with the door open, SLS, SDI and SLP, STO
    /// through K1. Off by default.
    pub safe_drive: bool,
    /// The events, in time order.
    pub events: Vec<ScenarioEvent>,
    /// The traffic templates (`[[traffic]]`): passengers generated from a seed, each a hall
    /// call at their origin and, once aboard, a cabin call to their destination.
    pub traffic: Vec<traffic::Traffic>,
}

/// One scheduled action.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioEvent {
    /// When.
    pub at: SimTime,
    /// What.
    pub action: Action,
    /// The line of the `[[event]]` in the file (0 for built-in scenarios).
    pub line: usize,
}

/// What a scenario event does.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// A button is pressed and held.
    Press {
        /// Which.
        button: Button,
        /// For how long.
        hold: SimDuration,
    },
    /// The load changes.
    Load(LoadLevel),
    /// The door is moved by hand.
    Door {
        /// `true` = closed.
        closed: bool,
    },
    /// The hand crank on the motor moves the cabin (only without power).
    Crank {
        /// Millimetres, positive up.
        mm: f64,
    },
    /// The operator's safety reset button (overtravel recovery).
    Reset,
    /// The operator's overtravel rescue (the book, "Start heights"): if the cabin stands where
    /// initialisation cannot find floor 1 by itself ([`needs_rescue`]: on or beyond an
    /// overtravel sensor, or below floor 1's vane) and K1 is open, the operator cranks it to
    /// the level of the nearer end floor; otherwise nothing.
    Rescue,
    /// The operator's acknowledge of a safety group error (ERR_ACK).
    Ack,
    /// From now on a lift attendant answers every safety stop that an operator can answer
    /// (the book, "The attendant"): once K1 has been open for such a cause for a while, a round
    /// of the overtravel rescue, the acknowledge and the safety reset, repeated while K1 stays
    /// open. The safety logic alone decides whether a reset is taken.
    Attend,
    /// A fault is injected.
    Fault(Fault),
}

/// An injected fault.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// A slave is taken off the bus.
    SlaveOffline {
        /// Its address.
        slave: u8,
    },
    /// A slave is put back.
    SlaveOnline {
        /// Its address.
        slave: u8,
    },
    /// The AS-i supply fails for a while.
    PowerFail {
        /// How long.
        duration: SimDuration,
    },
    /// The safe connection of the cabin STOP terminal delivers nothing for a while.
    SafeLinkDrop {
        /// How long.
        duration: SimDuration,
    },
    /// A vane sensor's output fails (stuck on or off) or is repaired.
    Vane {
        /// Which sensor.
        sensor: VaneSensor,
        /// Its fault from now on (`SensorFault::None` = repaired).
        fault: SensorFault,
    },
    /// The converter runs away: it drives the motor this way at its highest frequency,
    /// against its commands, while it has power (docs/lift-plant.md §4.7).
    ConverterRunaway {
        /// `true` up.
        up: bool,
    },
    /// The converter's runaway is repaired: it follows its commands again.
    ConverterRepaired,
    /// The safe drive's encoder cannot be read (a broken cable, a dead sensor): the drive
    /// monitor trips to STO (docs/drive-safety.md §6.4). Only with `[drive] safe = true`.
    EncoderFailed,
    /// The encoder is repaired: it reads again (a trip stays until the operator's reset).
    EncoderRepaired,
    /// A burst of line noise: for a while every pulse on the line is corrupted with this
    /// probability (on top of nothing: the burst's draws take the place of the line's own noise,
    /// which goes on afterwards from its own seed again).
    LineNoise {
        /// The probability that a pulse is corrupted, 0 < rate ≤ 1.
        rate: f64,
        /// How long.
        duration: SimDuration,
    },
}

/// The PLC scan periods the program works with. The cabin's 32-bit word takes 14 handshake steps of
/// one scan each (tables 4.6/4.7 of the lift thesis), so its inputs are up to about 15 scans old:
/// at 20 ms a 300 ms press is always seen and initialisation sees floor 1's vane in time; at 25 ms
/// some press phases are lost, at 30 ms initialisation can miss floor 1's level (measured; the
/// book, "Scenario files").
pub const PLC_SCAN_RANGE: std::ops::RangeInclusive<SimDuration> =
    SimDuration::from_millis(1)..=SimDuration::from_millis(20);

/// What the default press lasts: a person's push.
pub const DEFAULT_HOLD: SimDuration = SimDuration::from_millis(300);

/// Why a scenario cannot be used: where and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScenarioError {
    /// The file (or `<built-in>`).
    pub file: String,
    /// 1-based line, 0 if unknown.
    pub line: usize,
    /// 1-based column, 0 if unknown.
    pub column: usize,
    /// The field at fault, e.g. `event[3].press` or `lift.start_mm`.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.line, self.field.is_empty()) {
            (0, true) => write!(f, "{}: {}", self.file, self.message),
            (0, false) => write!(f, "{}: {}: {}", self.file, self.field, self.message),
            (l, true) => write!(f, "{}:{l}:{}: {}", self.file, self.column, self.message),
            (l, false) => write!(
                f,
                "{}:{l}:{}: {}: {}",
                self.file, self.column, self.field, self.message
            ),
        }
    }
}

impl std::error::Error for ScenarioError {}

/// The legal cabin heights at power-on (`lift.start_mm`) for a lift of `floors` floors, mm
/// above the floor-1 level: the whole shaft between the mechanical ends (docs/lift-plant.md: the
/// overtravel sensors trip 60 mm beyond the end floors, the ends are 80 mm further), because
/// a power-on after an overrun finds the cabin on or beyond a sensor; it is recovered by hand
/// (the book, "Scenario files"). The one place that says so: the scenario reader checks
/// `start_mm` against it and the campaign generator draws start positions from it.
pub fn start_range_mm(floors: u8) -> RangeInclusive<f64> {
    let shaft = {
        let mut cfg = LiftConfig::default();
        cfg.floors = floors;
        cfg
    };
    shaft.end_position_mm(End::Bottom)..=shaft.end_position_mm(End::Top)
}

/// Whether a cabin standing at `position_mm` needs the operator's rescue before initialisation
/// can find floor 1 by itself (the book, "Start heights"). It does not from the bottom of floor
/// 1's vane up to the top overtravel sensor; below that (beyond the bottom sensor, or between
/// it and the vane, where the run down ends on the sensor) and beyond the top sensor it does.
pub fn needs_rescue(floors: u8, position_mm: f64) -> bool {
    let shaft = {
        let mut cfg = LiftConfig::default();
        cfg.floors = floors;
        cfg
    };
    let vane_bottom = shaft
        .vane_track_mm(VaneSensor::Left, 1)
        .map_or(shaft.trip_position_mm(End::Bottom), |(lo, _)| lo);
    position_mm < vane_bottom || position_mm >= shaft.trip_position_mm(End::Top)
}

impl Scenario {
    /// A scenario with nothing in it: the defaults every file starts from.
    pub fn defaults() -> Scenario {
        Scenario {
            name: "unnamed".into(),
            seed: 1,
            duration: SimDuration::from_secs(60),
            algorithm: Algorithm::Fifo,
            floors: 4,
            start_mm: 650.0,
            load: LoadLevel::Empty,
            door_closed: true,
            pulse_error_rate: 0.0,
            extra_slaves: 0,
            master_mode: asi_master::Mode::Protected,
            plc_scan: SimDuration::from_millis(10),
            program: None,
            power_on_reset: true,
            safe_drive: false,
            events: Vec::new(),
            traffic: Vec::new(),
        }
    }

    /// The events at or after the scenario's end: they never happen (a file's reader warns).
    pub fn late_events(&self) -> impl Iterator<Item = &ScenarioEvent> {
        let end = SimTime::ZERO + self.duration;
        self.events.iter().filter(move |e| e.at >= end)
    }
}
