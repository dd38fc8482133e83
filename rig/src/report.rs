//! The report of a run: what happened, in the form `asi-lift run --format json` writes and the
//! end-to-end tests assert.

mod log;
mod slaves;
pub mod traffic;
mod violation;

pub(crate) use log::monitor_drop;
pub use log::{Actor, ClientLog, LogEvent, LogLine, PlantLog, Rescue, RigNote};
use serde::Serialize;
pub use slaves::{
    slave_reports, slave_summary, slave_table_text, CheckCounts, Configuration, SlaveReport,
};
use std::fmt::Write as _;
pub use violation::{Violation, ViolationKind};

/// Everything a run produced.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Report {
    /// The scenario's name.
    pub scenario: String,
    /// Its seed.
    pub seed: u64,
    /// The controller's program, where it is not the built-in one (a Structured Text
    /// program's file, as given); absent for the built-in program and an outside controller.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub controller: Option<String>,
    /// Simulated time, seconds.
    pub simulated_s: f64,
    /// When the controller finished its initialisation (the first time), or null.
    pub initialised_at_s: Option<f64>,
    /// Every stop level at a floor, in order.
    pub arrivals: Vec<Arrival>,
    /// Every call served.
    pub served: Vec<Served>,
    /// Every button press of the scenario's passengers, and when the cabin answered it: the
    /// measure for comparing control algorithms (a press on a call already pending waits
    /// with it).
    pub passengers: Vec<Passenger>,
    /// The passengers of the scenario's traffic templates, measured as lift planners do
    /// (absent in a scenario without `[[traffic]]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub traffic: Option<traffic::TrafficReport>,
    /// The state at the end.
    #[serde(rename = "final")]
    pub final_state: FinalState,
    /// Bus statistics.
    pub bus: BusReport,
    /// Safety trips.
    pub safety: SafetyReport,
    /// Safety invariants the rig found broken; empty in a correct run.
    pub violations: Vec<Violation>,
    /// How long the controller held the cabin for bus faults (absent when it never did);
    /// `bus.dropouts` and `safety.monitor` say what the bus and the safety monitor did.
    #[serde(skip_serializing_if = "Availability::is_clear")]
    pub availability: Availability,
    /// A live run's figures (`asi-lift serve`; absent in a batch run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub live: Option<LiveReport>,
    /// The readable log of the run, one line per event.
    #[serde(skip)]
    pub log: Vec<LogLine>,
    /// The first error writing the bus trace or the waveforms (VCD, CSV), if any: the command
    /// then keeps those files out of place and says so.
    #[serde(skip)]
    pub output_error: Option<String>,
}

/// What a live run (`asi-lift serve`) adds to the report: who controlled the lift and how the
/// gateway and the wall clock fared.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LiveReport {
    /// `builtin`, `program` (a Structured Text program, named by the report's `controller`)
    /// or `external`.
    pub controller: String,
    /// Simulated seconds per wall second asked for, or `max`: at the end of the run (the
    /// live view's page may change it; the log says when).
    pub speed: String,
    /// Modbus and TTK4145 requests served.
    pub requests: u64,
    /// Requests answered with an exception.
    pub exceptions: u64,
    /// Client connections accepted since the servers started (they outlive a restart from
    /// the live view's page).
    pub connections: u64,
    /// Times the gateway's watchdog zeroed the output image.
    pub watchdog_trips: u64,
    /// The most the simulation fell behind the wall clock, ms (0 at `max`).
    pub max_lag_ms: f64,
    /// The lamps a TTK4145 client set that the lab lift lacks, as it left them (absent
    /// without one).
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub lamps: std::collections::BTreeMap<String, u8>,
}

/// The cabin came to rest level at a floor.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Arrival {
    /// The floor.
    pub floor: u8,
    /// When, seconds.
    pub at_s: f64,
    /// The cabin height above the floor-1 level, mm.
    pub position_mm: f64,
}

/// A call served.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Served {
    /// The floor.
    pub floor: u8,
    /// A cabin or a hall call.
    pub source: CallSource,
    /// For a hall call, the direction.
    pub direction: Option<HallDirection>,
    /// When the passenger pressed the button (or, if no press matches, when the controller
    /// stored the call), seconds.
    pub requested_at_s: f64,
    /// When the cabin stopped there, seconds.
    pub served_at_s: f64,
}

/// One passenger's press and its answer.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Passenger {
    /// The button, as in the scenario: `cabin:3`, `hall-up:2`.
    pub button: String,
    /// When it was pressed, seconds.
    pub pressed_at_s: f64,
    /// When the cabin stopped to serve it, or null if it never did (or the call was dropped
    /// by STOP).
    pub served_at_s: Option<f64>,
}

/// Mean waiting times over the passengers who were served (`None` without any).
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
#[non_exhaustive]
pub struct Waits {
    /// Hall calls: press to the cabin's arrival (the lift engineer's waiting time).
    pub hall_mean_s: Option<f64>,
    /// Cabin calls: press to arrival at the destination.
    pub cabin_mean_s: Option<f64>,
    /// All served presses.
    pub all_mean_s: Option<f64>,
    /// Presses never answered.
    pub unserved: usize,
}

/// The state at the end of the run.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct FinalState {
    /// The controller's current floor (Aktualni_Patro); absent under an outside controller.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub floor: Option<u8>,
    /// The cabin height, mm.
    pub position_mm: f64,
    /// Where the cabin stands, from its height.
    pub cabin_at: CabinAt,
    /// The built-in controller's state; absent under an outside controller.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub state: Option<controller::State>,
    /// The cabin moves.
    pub moving: bool,
    /// K1's main contacts are closed.
    pub contactor_closed: bool,
    /// Why the safety logic keeps K1 open (absent while it is closed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k1_open_cause: Option<String>,
    /// FIFO_Kabina (collective: pending cabin calls ascending); absent under an outside
    /// controller.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fifo_cabin: Option<Vec<u8>>,
    /// FIFO_Patra (collective: pending hall calls ascending); absent under an outside
    /// controller.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fifo_hall: Option<Vec<u8>>,
}

/// Bus figures.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct BusReport {
    /// Transactions, repeats included.
    pub transactions: u64,
    /// Immediate repeats.
    pub repeats: u64,
    /// Erroneous telegrams by primary check class, requests and responses together.
    pub errors: ErrorCounts,
    /// Cycle time of normal operation, µs.
    pub cycle_us: CycleTimes,
    /// Slaves that left LAS in normal operation (absent when none did), by address.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub dropouts: Vec<SlaveDropouts>,
    /// Statistics per slave, as an AS-i analyser shows them: every address that took part in
    /// the traffic or is projected (absent when none did).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub slaves: Vec<SlaveReport>,
    /// The AS-i master's LEDs (seed 003 table 3.2; docs/master.md §2.8): each at the end of
    /// the run, how often it changed and how long it was away from undisturbed operation.
    pub master_leds: MasterLedsReport,
}

/// The master's LEDs over a run, one object per LED of seed 003 table 3.2.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[non_exhaustive]
pub struct MasterLedsReport {
    /// PWR: the master's power (AS-i power fail turns it off).
    pub pwr: LedReport,
    /// OK: the PLC in run mode.
    pub ok: LedReport,
    /// SYS: the connection to the PLC.
    pub sys: LedReport,
    /// AS-i: green AS-i OK, red configuration error, red flashing peripheral fault.
    pub asi: LedReport,
    /// AS-i: normal operation active.
    pub asi_active: LedReport,
    /// prg: automatic addressing enabled (flashing: a missing slave can be readdressed).
    pub prg: LedReport,
    /// prj mode: configuration mode (yellow).
    pub prj: LedReport,
}

/// One LED over a run.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[non_exhaustive]
pub struct LedReport {
    /// Its light at the end: `off`, `green`, `green_flashing`, `red`, `red_flashing`,
    /// `yellow`.
    pub end: &'static str,
    /// How often its light changed (not counting the start).
    pub changes: u32,
    /// Seconds it showed something else than in undisturbed operation in protected mode
    /// (every LED green but prj, which is off), to the millisecond.
    pub abnormal_s: f64,
}

impl MasterLedsReport {
    /// The report of the master's LED watch up to `now`.
    pub fn of(watch: &asi_master::LedWatch, now: asi_phy::SimTime) -> MasterLedsReport {
        let end = watch.shown().each();
        let changes = watch.changes();
        let away = watch.away(now);
        let led = |i: usize| LedReport {
            end: end[i].name(),
            changes: changes[i],
            abnormal_s: round3(away[i].as_secs_f64()),
        };
        MasterLedsReport {
            pwr: led(0),
            ok: led(1),
            sys: led(2),
            asi: led(3),
            asi_active: led(4),
            prg: led(5),
            prj: led(6),
        }
    }
}

/// A slave's absences from LAS in normal operation.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct SlaveDropouts {
    /// The slave's address.
    pub address: u8,
    /// How often the master dropped it from LAS.
    pub count: u32,
    /// Time out of LAS in all, seconds (to the millisecond; up to the end of the run).
    pub out_of_las_s: f64,
}

/// Why the lift could not serve.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Availability {
    /// Times the controller held the cabin for a bus fault (an essential slave out of LAS, a
    /// stale cabin word, AS-i power fail).
    pub bus_fault_holds: u32,
    /// Time held for bus faults, seconds (up to the end of the run).
    pub bus_fault_s: f64,
}

impl Availability {
    /// Nothing held the lift.
    pub fn is_clear(&self) -> bool {
        *self == Availability::default()
    }
}

/// Errors per receiver check, and missing responses.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[non_exhaustive]
pub struct ErrorCounts {
    /// Telegrams that failed each of the seven checks (in the JSON, each check's count
    /// stands beside `no_response`).
    #[serde(flatten)]
    pub checks: CheckCounts,
    /// A response was due and none came.
    pub no_response: u64,
}

/// Minimum, mean and maximum.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct CycleTimes {
    /// Shortest.
    pub min: f64,
    /// Mean.
    pub mean: f64,
    /// Longest.
    pub max: f64,
}

/// The safety logic's trips.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct SafetyReport {
    /// Every trip and error, in order.
    pub trips: Vec<Trip>,
    /// Every time the Safety-at-Work monitor dropped the release of a safety sensor, in order
    /// (absent when it never did).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub monitor: Vec<MonitorTrip>,
    /// Every time the cabin reached an overtravel sensor under power (K1 closed), in order
    /// (absent when it never did): contained by the safety logic, so no violation, but a
    /// failure of the controller (docs/safety.md).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub overtravel_reached: Vec<OvertravelReached>,
    /// How many rounds (rescue, acknowledge, reset) the attendant made (absent when none).
    #[serde(skip_serializing_if = "is_zero")]
    pub attendant_rounds: u32,
    /// The safe drive's record (absent without `[drive] safe = true`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drive: Option<DriveReport>,
}

/// `n` and the noun `one` in the number `n` takes: "1 press", "3 presses", "0 presses" (the
/// plural `many` given, as English spells it).
pub fn count(n: impl Into<u64>, one: &str, many: &str) -> String {
    let n = n.into();
    format!("{n} {}", if n == 1 { one } else { many })
}

impl SafetyReport {
    /// The trips as the operator sees them: what tripped. The records of their consequences
    /// (K1 opening, the STOP delay running out: [`TripKind::PowerOff`]) are left out, so a
    /// trip counts once wherever it is counted (the summary, the plot).
    pub fn causes(&self) -> impl Iterator<Item = &Trip> {
        self.trips.iter().filter(|t| t.kind != TripKind::PowerOff)
    }
}

/// The cabin reached an overtravel sensor under power.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct OvertravelReached {
    /// When, seconds.
    pub at_s: f64,
    /// `top` or `bottom`.
    pub end: String,
    /// The cabin's height then, mm.
    pub position_mm: f64,
}

/// What the safe drive did (docs/drive-safety.md §6).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[non_exhaustive]
pub struct DriveReport {
    /// Every trip: which function, and why (each also a `safety.trips` record).
    pub trips: Vec<DriveTrip>,
    /// Every SS1 stop: from the STOP circuit's demand to the torque off.
    pub ss1_stops: Vec<Ss1Stop>,
}

/// A safe-drive function tripped: STO and the brake.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct DriveTrip {
    /// When, seconds.
    pub at_s: f64,
    /// The function (`SOS`, `SLS2`, `SLP`, …), or `encoder` when the reading was lost.
    pub function: String,
    /// Why, in words, with the measured value and the limit.
    pub cause: String,
    /// The car's height then, mm.
    pub position_mm: f64,
}

/// One SS1 stop.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Ss1Stop {
    /// When SS1 was requested (the STOP circuit's demand), seconds.
    pub requested_at_s: f64,
    /// When SS1 took the torque off (null if the demand ended first, or the run did).
    pub torque_off_at_s: Option<f64>,
    /// The time the stop took, seconds (null as above).
    pub took_s: Option<f64>,
    /// When the demand ended (the STOP circuit restarted; at power-on its first start),
    /// seconds; null if it lasted to the end of the run.
    pub released_at_s: Option<f64>,
}

fn is_zero(n: &u32) -> bool {
    *n == 0
}

/// The Safety-at-Work monitor dropped a sensor's release.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct MonitorTrip {
    /// When, seconds.
    pub at_s: f64,
    /// The safety sensor's address (11 bottom, 12 top).
    pub address: u8,
    /// `0000` (the sensor is tripped), `wrong-code`, `frozen-code`, or `silence` (no valid
    /// code within the monitor's tolerance time).
    pub cause: String,
}

/// One safety trip, error, or output the safety logic switched off.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Trip {
    /// When, seconds.
    pub at_s: f64,
    /// What it is.
    pub kind: TripKind,
    /// Why (in the JSON report, in words).
    pub cause: TripCause,
}

/// Why a [`Trip`] happened: what the safety logic or the safe drive reported. `Display` (and
/// the JSON report) gives it in words.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum TripCause {
    /// The lift's safety logic: a safety function, the group, a connection, K1.
    Logic(safety::LiftSafetyCause),
    /// The safe drive: a function tripped.
    Drive(safety::drive::Violation),
}

impl TripCause {
    /// `true` if K1 opened ([`safety::LiftSafetyCause::K1Opened`]).
    pub fn is_k1_opened(&self) -> bool {
        matches!(self, TripCause::Logic(safety::LiftSafetyCause::K1Opened(_)))
    }
}

impl std::fmt::Display for TripCause {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TripCause::Logic(c) => c.fmt(f),
            TripCause::Drive(v) => write!(f, "safe drive: {v}"),
        }
    }
}

impl Serialize for TripCause {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// What a [`Trip`] record is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TripKind {
    /// A safety function or the group tripped: the cause of a safety stop.
    Trip,
    /// An error was detected (FB_ERR, COM_ERR, OUT_ERR, a logic fault): also a cause.
    Error,
    /// An output went off because of a trip or an error: K1 opened, the STOP delay elapsed.
    PowerOff,
}

/// Where the cabin stands, as an operator says it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CabinAt {
    /// Level with a floor (within the level window).
    Floor(u8),
    /// Between two floors.
    Between(u8, u8),
    /// Below floor 1's level window.
    BelowFloor1,
    /// Above the top floor's level window.
    AboveTop,
}

impl CabinAt {
    /// Where a cabin at `position_mm` stands in the lift `config`.
    pub fn of(config: &lift_model::LiftConfig, position_mm: f64) -> CabinAt {
        if let Some(f) = config.level_floor(position_mm) {
            return CabinAt::Floor(f);
        }
        let below = (position_mm / config.floor_pitch_mm).floor() as i64 + 1;
        if below < 1 {
            CabinAt::BelowFloor1
        } else if below >= i64::from(config.floors) {
            CabinAt::AboveTop
        } else {
            CabinAt::Between(below as u8, below as u8 + 1)
        }
    }
}

impl std::fmt::Display for CabinAt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CabinAt::Floor(n) => write!(f, "at floor {n}"),
            CabinAt::Between(a, b) => write!(f, "between floors {a} and {b}"),
            CabinAt::BelowFloor1 => f.write_str("below floor 1"),
            CabinAt::AboveTop => f.write_str("above the top floor"),
        }
    }
}

/// Where a served call came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CallSource {
    /// A cabin button.
    Cabin,
    /// A hall (floor station) button.
    Hall,
}

impl std::fmt::Display for CallSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(match self {
            CallSource::Cabin => "cabin",
            CallSource::Hall => "hall",
        })
    }
}

/// The direction a hall call asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum HallDirection {
    /// Up.
    Up,
    /// Down.
    Down,
}

impl Report {
    /// The report of a run at power-on, before anything happened: the scenario's name and
    /// seed, the cabin at `start_mm`.
    pub fn at_power_on(scenario: &str, seed: u64, start_mm: f64) -> Report {
        Report {
            scenario: scenario.to_owned(),
            seed,
            simulated_s: 0.0,
            initialised_at_s: None,
            arrivals: Vec::new(),
            served: Vec::new(),
            passengers: Vec::new(),
            traffic: None,
            final_state: FinalState {
                floor: Some(1),
                position_mm: start_mm,
                // Replaced by the run's end state, as every field here.
                cabin_at: CabinAt::Floor(1),
                state: Some(controller::State::WaitingForInputs),
                moving: false,
                contactor_closed: false,
                k1_open_cause: None,
                fifo_cabin: Some(Vec::new()),
                fifo_hall: Some(Vec::new()),
            },
            bus: BusReport {
                transactions: 0,
                repeats: 0,
                errors: ErrorCounts::default(),
                cycle_us: CycleTimes {
                    min: 0.0,
                    mean: 0.0,
                    max: 0.0,
                },
                dropouts: Vec::new(),
                slaves: Vec::new(),
                master_leds: MasterLedsReport::default(),
            },
            safety: SafetyReport {
                trips: Vec::new(),
                monitor: Vec::new(),
                overtravel_reached: Vec::new(),
                attendant_rounds: 0,
                drive: None,
            },
            violations: Vec::new(),
            controller: None,
            availability: Availability::default(),
            live: None,
            log: Vec::new(),
            output_error: None,
        }
    }

    /// Mean waiting times per passenger press.
    pub fn waits(&self) -> Waits {
        let mean = |f: &dyn Fn(&Passenger) -> bool| {
            let w: Vec<f64> = self
                .passengers
                .iter()
                .filter(|p| f(p))
                .filter_map(|p| p.served_at_s.map(|s| s - p.pressed_at_s))
                .collect();
            (!w.is_empty()).then(|| w.iter().sum::<f64>() / w.len() as f64)
        };
        Waits {
            hall_mean_s: mean(&|p| p.button.starts_with("hall")),
            cabin_mean_s: mean(&|p| p.button.starts_with("cabin")),
            all_mean_s: mean(&|_| true),
            unserved: self
                .passengers
                .iter()
                .filter(|p| p.served_at_s.is_none())
                .count(),
        }
    }

    /// The report as pretty JSON.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }

    /// The readable log and a summary.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "scenario \"{}\", seed {}", self.scenario, self.seed);
        for l in &self.log {
            let _ = writeln!(s, "{l}");
        }
        s.push('\n');
        s + &self.summary_text()
    }

    /// The summary of the run, from its `summary after … s` line on.
    pub fn summary_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "summary after {:.3} s", self.simulated_s);
        match self.initialised_at_s {
            Some(t) => {
                let _ = writeln!(s, "  initialised at     {t:.3} s");
            }
            // Only the built-in program tells when it is initialised.
            None if self.final_state.state.is_none() => {
                let why = match &self.controller {
                    Some(name) => format!("the program {name} does not tell"),
                    None => "an outside controller".to_owned(),
                };
                let _ = writeln!(s, "  initialised at     not known ({why})");
            }
            None => {
                let _ = writeln!(s, "  initialised at     never");
            }
        }
        // The floors the cabin came to rest at, a floor it rested at again (a re-initialisation,
        // a halt after STOP) once.
        let mut stops: Vec<String> = Vec::new();
        for a in &self.arrivals {
            let f = a.floor.to_string();
            if stops.last() != Some(&f) {
                stops.push(f);
            }
        }
        let _ = writeln!(
            s,
            "  came to rest at    {}",
            if stops.is_empty() {
                "no floor".into()
            } else {
                format!("floor {}", stops.join(", then "))
            }
        );
        // Two counts that differ: the stops that served a stored call, and the passengers'
        // presses (a press on a call already pending waits with it, and is answered by the
        // same stop). Each line says which it counts.
        let presses = self.passengers.len() as u64;
        let w = self.waits();
        let _ = writeln!(
            s,
            "  calls served       {} (answering {} of {} of call buttons)",
            self.served.len(),
            presses - w.unserved as u64,
            count(presses, "press", "presses"),
        );
        if !self.passengers.is_empty() {
            let show = |m: Option<f64>| m.map_or("none".to_string(), |v| format!("{v:.1} s"));
            let _ = writeln!(
                s,
                "  passenger waits    hall calls {}, cabin calls {}, all {} (mean over {} answered, {} unanswered)",
                show(w.hall_mean_s),
                show(w.cabin_mean_s),
                show(w.all_mean_s),
                count(presses - w.unserved as u64, "press", "presses"),
                w.unserved
            );
        }
        if let Some(t) = &self.traffic {
            s.push_str(&t.summary());
        }
        let f = &self.final_state;
        let controller = match (f.state, f.floor) {
            (Some(state), Some(floor)) => format!("controller: {state}, floor count {floor}"),
            _ => match &self.controller {
                Some(name) => format!("controller: {name}"),
                None => "controller: external".to_string(),
            },
        };
        let _ = writeln!(
            s,
            "  at the end         cabin {} ({:.1} mm), {}, K1 {}; {controller}",
            f.cabin_at,
            f.position_mm,
            if f.moving { "moving" } else { "at rest" },
            if f.contactor_closed { "closed" } else { "open" },
        );
        if let Some(c) = &f.k1_open_cause {
            let _ = writeln!(s, "  K1 open because    {c}");
        }
        if let (Some(cabin), Some(hall)) = (&f.fifo_cabin, &f.fifo_hall) {
            let _ = writeln!(s, "  pending calls      cabin {cabin:?}, hall {hall:?}");
        }
        if let Some(l) = &self.live {
            let _ = writeln!(
                s,
                "  live               {} controller at speed {}; {} requests from {} connections, {} exceptions, {} watchdog trips; lag max {:.1} ms",
                l.controller, l.speed, l.requests, l.connections, l.exceptions, l.watchdog_trips, l.max_lag_ms
            );
        }
        let b = &self.bus;
        let e = &b.errors;
        let _ = writeln!(
            s,
            "  bus                {} transactions, {} repeats; errors: start {} alt {} pause {} info {} parity {} end {} length {}, no response {}",
            b.transactions, b.repeats, e.checks.start_bit, e.checks.alternation, e.checks.pause, e.checks.information, e.checks.parity, e.checks.end_bit, e.checks.length, e.no_response
        );
        let _ = writeln!(
            s,
            "  AS-i cycle         min {:.0} µs, mean {:.1} µs, max {:.0} µs",
            b.cycle_us.min, b.cycle_us.mean, b.cycle_us.max
        );
        if !b.slaves.is_empty() {
            s.push_str(&slave_summary(&b.slaves));
        }
        for d in &b.dropouts {
            let _ = writeln!(
                s,
                "  slave {:<2} left LAS  {}, out {:.3} s",
                d.address,
                count(d.count, "time", "times"),
                d.out_of_las_s
            );
        }
        // A safety stop as the operator sees it: what tripped; K1 opening and the STOP delay
        // running out are its consequences, counted apart.
        let causes: Vec<&Trip> = self.safety.causes().collect();
        let power_off = self
            .safety
            .trips
            .iter()
            .filter(|t| t.kind == TripKind::PowerOff && t.cause.is_k1_opened())
            .count();
        // With the safe drive its torque-off opens K1 too: the count is the safety logic's,
        // and says so; the drive's own are listed below.
        let by = if self.safety.drive.is_some() {
            " by the safety logic"
        } else {
            ""
        };
        let _ = writeln!(
            s,
            "  safety trips       {} (K1 opened{by} {})",
            causes.len(),
            count(power_off as u64, "time", "times")
        );
        const SHOWN: usize = 5;
        for t in causes.iter().take(SHOWN) {
            let _ = writeln!(s, "    {:>10.3} s  {}", t.at_s, t.cause);
        }
        if causes.len() > SHOWN {
            let _ = writeln!(s, "    … and {} more", causes.len() - SHOWN);
        }
        if let Some(d) = &self.safety.drive {
            let _ = writeln!(
                s,
                "  safe drive         {}",
                count(d.trips.len() as u64, "trip", "trips")
            );
            for t in d.trips.iter().take(SHOWN) {
                let _ = writeln!(
                    s,
                    "    {:>10.3} s  {} tripped: {}",
                    t.at_s, t.function, t.cause
                );
            }
            for st in &d.ss1_stops {
                match st.took_s {
                    Some(took) => {
                        let _ = writeln!(
                            s,
                            "    {:>10.3} s  STOP: SS1 took the torque off after {took:.3} s",
                            st.requested_at_s
                        );
                    }
                    None => {
                        let _ = writeln!(
                            s,
                            "    {:>10.3} s  STOP circuit demand: SS1 requested, {}",
                            st.requested_at_s,
                            match st.released_at_s {
                                Some(r) => format!("released at {r:.3} s with the torque on"),
                                None => "the torque still on".into(),
                            }
                        );
                    }
                }
            }
        }
        let reached = &self.safety.overtravel_reached;
        if !reached.is_empty() {
            let list: Vec<String> = reached
                .iter()
                .take(SHOWN)
                .map(|r| format!("{} at {:.3} s", r.end, r.at_s))
                .collect();
            let more = reached.len().saturating_sub(SHOWN);
            let more = if more > 0 {
                format!(", … and {more} more")
            } else {
                String::new()
            };
            let _ = writeln!(
                s,
                "  overtravel reached {} under power, contained by the safety logic ({}{more})",
                reached.len(),
                list.join(", ")
            );
        }
        if self.safety.attendant_rounds > 0 {
            let _ = writeln!(s, "  attendant rounds   {}", self.safety.attendant_rounds);
        }
        if !self.safety.monitor.is_empty() {
            let mut causes: Vec<(String, usize)> = Vec::new();
            for m in &self.safety.monitor {
                let key = format!("{} at {}", m.cause, m.address);
                match causes.iter_mut().find(|(k, _)| *k == key) {
                    Some((_, n)) => *n += 1,
                    None => causes.push((key, 1)),
                }
            }
            let list: Vec<String> = causes.iter().map(|(k, n)| format!("{n} × {k}")).collect();
            let _ = writeln!(s, "  monitor drops      {}", list.join(", "));
        }
        let a = &self.availability;
        if a.bus_fault_holds > 0 {
            let _ = writeln!(
                s,
                "  bus-fault holds    {}, {:.3} s in all",
                a.bus_fault_holds, a.bus_fault_s
            );
        }
        if self.violations.is_empty() {
            let _ = writeln!(s, "  violations         none");
        } else {
            let _ = writeln!(s, "  violations         {}", self.violations.len());
            for v in &self.violations {
                let _ = writeln!(s, "    {:>10.3} s  {}: {}", v.at_s, v.kind, v.detail);
            }
        }
        s
    }
}

/// `x` rounded to three decimals: the precision of the report's and the waveforms' figures
/// (µm, ms, µs).
pub fn round3(x: f64) -> f64 {
    (x * 1000.0).round() / 1000.0
}
