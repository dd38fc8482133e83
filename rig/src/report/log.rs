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
    /// The scenario, the operator or the attendant does this (its actor tells who).
    Action(crate::scenario::Action),
    /// The plant refused the action just logged.
    Refused(lift_model::PlantError),
    /// What the operator's overtravel rescue found to do.
    Rescue(Rescue),
    /// The plant refused an input of the rig's own ([`Actor::Plant`]).
    PlantError(lift_model::PlantError),
    /// The invariant watch found a violation ([`Actor::Judge`]).
    Violation {
        /// What kind.
        kind: super::violation::ViolationKind,
        /// Its details, in words.
        detail: String,
    },
    /// The attendant begins a round: K1 has been open for the attendant's notice time, for
    /// `cause` ([`Actor::Attendant`]).
    AttendantRound {
        /// How long K1 had been open.
        after: asi_phy::SimDuration,
        /// Why K1 is open, in the safety logic's or the safe drive's words.
        cause: String,
    },
    /// A note of the rig's own.
    Note(RigNote),
    /// What the gateway of `serve` or one of its clients did ([`Actor::Gateway`],
    /// [`Actor::Web`], [`Actor::Ttk4145`], [`Actor::Live`], the listeners).
    Client(ClientLog),
    /// Anything else, in words.
    Text(String),
}

/// What the gateway of `serve` or one of its clients did, as the run's log tells it.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum ClientLog {
    /// The page set the line noise's pulse error rate.
    LineNoise(f64),
    /// The gateway's watchdog: no output write for this long, so the output image is zero.
    WatchdogExpired {
        /// The watchdog's time, ms.
        after_ms: u64,
    },
    /// Outputs are written again after the watchdog.
    WatchdogClear,
    /// The operator stopped the live run (Ctrl-C or a termination signal).
    StoppedBySignal,
    /// The machine cannot keep up at this speed: the run is this far behind the wall clock.
    Behind {
        /// The speed, as the page writes it.
        speed: String,
        /// How far behind, ms.
        lag_ms: f64,
    },
    /// The page paused (`true`) or resumed the run.
    Paused(bool),
    /// The page set the speed.
    Speed {
        /// The new speed, as the page writes it.
        speed: String,
        /// The speed before.
        was: String,
    },
    /// The page restarted the run; the earlier run had reached this time.
    Restarted {
        /// Seconds.
        reached_s: f64,
    },
    /// A TTK4145 client's motor command: up (1), down (−1) or stop (0).
    Motor(i8),
    /// A lamp the lab lift lacks changed (a TTK4145 client).
    Lamp {
        /// Its name.
        name: String,
        /// Its value.
        value: u8,
    },
    /// A listener accepts connections again after this many failed tries.
    AcceptingAgain(u64),
    /// A listener cannot accept a connection, for this reason; it tries again, at most
    /// `retry_ms` apart.
    CannotAccept {
        /// Why.
        error: String,
        /// The longest wait between tries, ms.
        retry_ms: u128,
    },
}

impl std::fmt::Display for ClientLog {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ClientLog::LineNoise(rate) => write!(f, "line noise: pulse error rate {rate}"),
            ClientLog::WatchdogExpired { after_ms } => write!(
                f,
                "watchdog: no output write for {after_ms} ms: the output image is zero"
            ),
            ClientLog::WatchdogClear => {
                f.write_str("outputs written again: the watchdog is clear")
            }
            ClientLog::StoppedBySignal => {
                f.write_str("stopped by the operator (Ctrl-C or a termination signal)")
            }
            ClientLog::Behind { speed, lag_ms } => write!(
                f,
                "the machine cannot keep up at speed {speed}: {lag_ms:.0} ms behind the wall clock"
            ),
            ClientLog::Paused(true) => f.write_str("run paused by the page"),
            ClientLog::Paused(false) => f.write_str("run resumed by the page"),
            ClientLog::Speed { speed, was } => {
                write!(f, "speed {speed} (was {was}), set by the page")
            }
            ClientLog::Restarted { reached_s } => write!(
                f,
                "restarted by the page: the earlier run had reached {reached_s:.3} s; this report is of the run since the restart"
            ),
            ClientLog::Motor(1) => f.write_str("motor up"),
            ClientLog::Motor(-1) => f.write_str("motor down"),
            ClientLog::Motor(_) => f.write_str("motor stop"),
            ClientLog::Lamp { name, value } => write!(f, "{name}: {value}"),
            ClientLog::AcceptingAgain(failed) => {
                write!(f, "accepting connections again after {failed} failed tries")
            }
            ClientLog::CannotAccept { error, retry_ms } => write!(
                f,
                "cannot accept a connection: {error}; trying again, at most {retry_ms} ms apart"
            ),
        }
    }
}

/// What the operator's overtravel rescue does to the cabin as it stands.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Rescue {
    /// The cabin stands where initialisation finds floor 1 by itself.
    NotNeeded,
    /// K1 is closed: nobody cranks a drive that has power.
    K1Closed,
    /// Crank this far (mm, + up) to the nearer end floor's level.
    Crank(f64),
}

impl std::fmt::Display for Rescue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Rescue::NotNeeded => f.write_str("the cabin needs no rescue"),
            Rescue::K1Closed => f.write_str("K1 is closed: no rescue by hand"),
            Rescue::Crank(mm) => write!(f, "hand crank {mm:+.1} mm"),
        }
    }
}

/// The rig's own notes on a run.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum RigNote {
    /// The caller stopped the run before its end.
    StoppedEarly,
    /// The bus trace could not be written, for this reason.
    TraceNotWritten(String),
    /// AS-i power is back after a power fail.
    PowerBack,
    /// A burst of line noise is over: the line has its own noise again.
    NoiseOver,
    /// A burst of line noise with a rate that is no probability: nothing happens.
    NoNoise(String),
    /// The operator presses the safety reset after power-on.
    ResetAfterPowerOn,
    /// A scenario's fault names a slave address the lab bus does not have.
    NoSlave(u8),
    /// A scenario's encoder fault without the safe drive.
    NoEncoder,
    /// The cabin reached an overtravel sensor under power (`top` or the bottom one).
    OvertravelReached {
        /// The top sensor (`false`: the bottom one).
        top: bool,
        /// The cabin's position, mm.
        position_mm: f64,
    },
    /// A source's lines left out of a long log: `left_out` of its `seen` lines, where the
    /// log keeps its `first` and its `last` ones.
    LeftOut {
        /// Whose lines.
        who: Actor,
        /// How many were left out.
        left_out: u64,
        /// How many it logged.
        seen: u64,
        /// How many of its first lines are kept.
        first: usize,
        /// How many of its last lines are kept.
        last: usize,
    },
}

impl std::fmt::Display for RigNote {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RigNote::StoppedEarly => f.write_str("the run was stopped early by its caller"),
            RigNote::TraceNotWritten(e) => write!(f, "the bus trace could not be written: {e}"),
            RigNote::PowerBack => f.write_str("AS-i power back"),
            RigNote::NoiseOver => f.write_str("the burst of line noise is over"),
            RigNote::NoNoise(e) => write!(f, "no burst of line noise: {e}"),
            RigNote::ResetAfterPowerOn => {
                f.write_str("operator presses the safety reset after power-on")
            }
            RigNote::NoSlave(a) => write!(f, "no slave at address {a} on the lab bus"),
            RigNote::NoEncoder => {
                f.write_str("no safe drive, so no encoder: the fault changes nothing")
            }
            RigNote::OvertravelReached { top, position_mm } => write!(
                f,
                "the cabin reached the {} overtravel sensor under power at {position_mm:.1} mm",
                if *top { "top" } else { "bottom" }
            ),
            RigNote::LeftOut {
                who,
                left_out,
                seen,
                first,
                last,
            } => write!(
                f,
                "… {left_out} lines left out (of {seen} `{who}` lines the first {first} and the last {last} are kept)"
            ),
        }
    }
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
            LogEvent::Action(a) => a.fmt(f),
            LogEvent::Refused(e) => write!(f, "refused by the plant: {e}"),
            LogEvent::Rescue(r) => r.fmt(f),
            LogEvent::PlantError(e) => write!(f, "error: {e}"),
            LogEvent::Violation { kind, detail } => write!(f, "VIOLATION {kind}: {detail}"),
            LogEvent::AttendantRound { after, cause } => write!(
                f,
                "K1 open for {after} ({cause}): rescue, acknowledge and reset"
            ),
            LogEvent::Note(n) => n.fmt(f),
            LogEvent::Client(c) => c.fmt(f),
            LogEvent::Text(t) => f.write_str(t),
        }
    }
}

impl From<ClientLog> for LogEvent {
    fn from(c: ClientLog) -> LogEvent {
        LogEvent::Client(c)
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
