//! The run's log: who did or saw what ([`Actor`]), and what each line says ([`LogEvent`]),
//! typed where its source is; the words are rendering only.

/// Who did or saw what a line of the run's log tells.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum Actor {
    /// The rig itself: power-on, its operator's actions, its notes on the run.
    Rig,
    /// An event of the scenario file.
    Scenario,
    /// The lift plant: the cabin at rest, sensors, K1.
    Plant,
    /// The AS-i bus: slaves leaving and rejoining LAS.
    Bus,
    /// The Safety-at-Work monitor.
    Monitor,
    /// The safety logic (the KL6904 project).
    Safety,
    /// The safe drive.
    Drive,
    /// The lift's controller.
    Controller,
    /// The lift attendant of a scenario's `attend`.
    Attendant,
    /// The invariant watch's judge (a violation).
    Judge,
    /// The gateway of `serve` (its watchdog).
    Gateway,
    /// The gateway's Modbus TCP server (its listener).
    ModbusServer,
    /// The live view's HTTP server (its listener).
    HttpServer,
    /// A Modbus TCP client of the gateway.
    Client,
    /// A TTK4145 client.
    Ttk4145,
    /// The live view's page.
    Web,
    /// The live run (pacing, the end of the run).
    Live,
}

impl Actor {
    /// The name the readable log shows.
    pub fn name(self) -> &'static str {
        match self {
            Actor::Rig | Actor::Judge => "rig",
            Actor::Scenario => "scenario",
            Actor::Plant => "plant",
            Actor::Bus => "bus",
            Actor::Monitor => "monitor",
            Actor::Safety => "safety",
            Actor::Drive => "drive",
            Actor::Controller => "controller",
            Actor::Attendant => "attendant",
            Actor::Gateway => "gateway",
            Actor::ModbusServer => "modbus",
            Actor::HttpServer => "http",
            Actor::Client => "client",
            Actor::Ttk4145 => "ttk4145",
            Actor::Web => "web",
            Actor::Live => "live",
        }
    }
}

impl std::fmt::Display for Actor {
    /// The name, padded as the formatter asks (`{:<10}`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.name())
    }
}

/// One line of the run's log.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct LogLine {
    /// Seconds.
    pub at_s: f64,
    /// Who.
    pub who: Actor,
    /// What ([`LogEvent`]; [`LogLine::text`] in words).
    pub event: LogEvent,
}

impl LogLine {
    /// A line of `who` at `at_s` saying `event`.
    pub fn new(at_s: f64, who: Actor, event: LogEvent) -> LogLine {
        LogLine { at_s, who, event }
    }

    /// What the line says, in words.
    pub fn text(&self) -> String {
        self.event.to_string()
    }
}

impl std::fmt::Display for LogLine {
    /// The line as the readable log prints it: time, who, what.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:>10.3} s  {:<10}  {}", self.at_s, self.who, self.event)
    }
}

/// What a [`LogLine`] says: the events of the safety logic, the controller, the plant, the
/// bus, the safety monitor and the safe drive as they are; the rest (the scenario's and the
/// operator's actions, the gateway's clients, the rig's notes) in words. `Display` gives the
/// log's words.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum LogEvent {
    /// The lift's safety logic reported this ([`Actor::Safety`]).
    Safety(safety::LiftSafetyCause),
    /// The built-in program reported this ([`Actor::Controller`]).
    Controller(controller::ProgramEventKind),
    /// The plant ([`Actor::Plant`]).
    Plant(PlantLog),
    /// A slave left the master's list of active slaves (`left`), or came back
    /// ([`Actor::Bus`]).
    Las {
        /// The slave's address.
        address: u8,
        /// `true`: it left; `false`: it came back.
        left: bool,
    },
    /// The Safety-at-Work monitor does not release the safety sensor at `address`, for
    /// `why` ([`Actor::Monitor`]).
    MonitorDrop {
        /// The sensor's address.
        address: u8,
        /// Why.
        why: asi_slaves::monitor::NotReleased,
    },
    /// The safe drive ([`Actor::Drive`]).
    Drive(safety::drive::DriveEventKind),
    /// Anything else, in words.
    Text(String),
}

/// What the plant did that the log tells.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum PlantLog {
    /// The cabin came to rest level at `floor`, `offset_mm` from its level.
    AtRest {
        /// The floor.
        floor: u8,
        /// Above (+) or below (−) the floor's level, mm.
        offset_mm: f64,
    },
    /// The cabin hit a mechanical end.
    Crash {
        /// Which end.
        end: lift_model::End,
        /// At this speed, mm/s.
        impact_mm_s: f64,
    },
    /// An overtravel sensor tripped with the cabin at `position_mm`.
    OvertravelTripped {
        /// Which end's sensor.
        end: lift_model::End,
        /// The cabin's position, mm.
        position_mm: f64,
    },
    /// An overtravel sensor is free again.
    OvertravelFree {
        /// Which end's sensor.
        end: lift_model::End,
    },
    /// The converter's fault output changed.
    ConverterFault {
        /// Its new level.
        fault: bool,
    },
}

impl std::fmt::Display for PlantLog {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PlantLog::AtRest { floor, offset_mm } => {
                write!(
                    f,
                    "cabin at rest level at floor {floor} ({offset_mm:+.1} mm)"
                )
            }
            PlantLog::Crash { end, impact_mm_s } => write!(
                f,
                "crash into the mechanical end ({end:?}) at {impact_mm_s:.1} mm/s"
            ),
            PlantLog::OvertravelTripped { end, position_mm } => {
                write!(
                    f,
                    "overtravel sensor ({end:?}) tripped at {position_mm:.1} mm"
                )
            }
            PlantLog::OvertravelFree { end } => write!(f, "overtravel sensor ({end:?}) free again"),
            PlantLog::ConverterFault { fault } => write!(f, "converter fault: {fault:?}"),
        }
    }
}

impl std::fmt::Display for LogEvent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use safety::drive::DriveEventKind;
        match self {
            LogEvent::Safety(c) => c.fmt(f),
            LogEvent::Controller(e) => e.fmt(f),
            LogEvent::Plant(p) => p.fmt(f),
            LogEvent::Las {
                address,
                left: true,
            } => {
                write!(f, "slave {address} dropped out of LAS")
            }
            LogEvent::Las { address, .. } => write!(f, "slave {address} back in LAS"),
            LogEvent::MonitorDrop { address, why } => write!(
                f,
                "safety sensor {address} not released: {}",
                monitor_drop(*why).1
            ),
            // K1 is in series with the drive's torque enable (the safe drive's wiring).
            LogEvent::Drive(DriveEventKind::TorqueOff) => {
                f.write_str("torque off (STO): K1 opens, the brake falls")
            }
            LogEvent::Drive(DriveEventKind::TorqueOn) => f.write_str("torque on: K1 may close"),
            LogEvent::Drive(e) => e.fmt(f),
            LogEvent::Text(t) => f.write_str(t),
        }
    }
}

impl From<String> for LogEvent {
    fn from(text: String) -> LogEvent {
        LogEvent::Text(text)
    }
}

/// A drop of the Safety-at-Work monitor: its cause's key in the report and its words.
pub(crate) fn monitor_drop(why: asi_slaves::monitor::NotReleased) -> (&'static str, String) {
    match why {
        asi_slaves::monitor::NotReleased::Tripped => ("0000", "the sensor sends 0000".to_string()),
        asi_slaves::monitor::NotReleased::WrongCode { expected, got } => (
            "wrong-code",
            format!("wrong code {got:04b} (expected {expected:04b})"),
        ),
        asi_slaves::monitor::NotReleased::Frozen { code } => {
            ("frozen-code", format!("frozen code {code:04b}"))
        }
        _ => (
            "silence",
            "no valid code within the tolerance time".to_string(),
        ),
    }
}
