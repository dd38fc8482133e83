//! What the live view's page shows (the book, "Live view in the browser"): one snapshot of the
//! rig as JSON, built on the rig thread every 40 ms of wall time and shared by every
//! browser watching; and the rolling list of the last bus transactions that goes into it.

use asi_master::record::TransactionRecord;
use asi_master::Phase;
use asi_phy::{Check, SimDuration, SlaveAddr};
use asi_trace::telegrams::check_key;
use controller::structured::StProgram;
use controller::{Algorithm, Outside};
use lab::address;
use lift_model::{Button, DisplayId, DisplayState, End, VaneSensor};
use rig::Rig;
use safety::kl6904::modules::FbState;
use serde::Serialize;
use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;

/// How many of the last bus transactions a snapshot lists.
pub const TELEGRAMS: usize = 16;
/// How many of the run's last log lines a snapshot lists.
pub const LOG_LINES: usize = 12;
/// How many of a Structured Text program's variables a snapshot lists (a program may declare
/// thousands; the page shows a PLC's watch list, not a memory dump).
pub const WATCH: usize = 256;

/// The last bus transactions, kept by the rig's transaction observer on the rig thread.
pub type Telegrams = Rc<RefCell<VecDeque<TransactionRecord>>>;

/// Attaches an observer that keeps the last [`TELEGRAMS`] transactions and returns the list it
/// fills.
pub fn observe(rig: &mut Rig) -> Telegrams {
    let list: Telegrams = Rc::new(RefCell::new(VecDeque::with_capacity(TELEGRAMS + 1)));
    let keep = Rc::clone(&list);
    rig.on_transaction(Box::new(move |r| {
        let mut l = keep.borrow_mut();
        if l.len() == TELEGRAMS {
            l.pop_front();
        }
        l.push_back(*r);
    }));
    list
}

/// The live run around the rig: what the rig itself does not know.
#[derive(Clone, Debug, Serialize)]
pub struct Run {
    /// The speed (`1`, `10`, `max`).
    pub speed: String,
    /// How far the simulation is behind the wall clock, ms.
    pub lag_ms: f64,
    /// Who runs the lift: `builtin` (the built-in program), `program` (a Structured Text
    /// program) or `external` (a client).
    pub controller: &'static str,
    /// Requests served over Modbus TCP and TTK4145.
    pub requests: u64,
    /// The page has paused the run: simulated time stands still.
    pub paused: bool,
    /// The run has ended.
    pub ended: bool,
}

/// One snapshot of the rig.
#[derive(Debug, Serialize)]
pub struct View {
    /// Always `"view"`: the page tells snapshots from replies by it.
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// Simulated time, s.
    pub t_s: f64,
    /// The run around the rig.
    pub run: Run,
    /// The shaft's geometry, mm above the floor-1 level.
    pub shaft: Shaft,
    /// The plant.
    pub lift: LiftView,
    /// The floor displays (floor 1 first) and the cabin display, as the slaves show them.
    pub displays: Vec<DisplayView>,
    /// The bus.
    pub bus: BusView,
    /// The safety logic.
    pub safety: SafetyView,
    /// The PLC program.
    pub controller: ControllerView,
    /// Violations of the safety invariants so far, and the last of them.
    pub violations: usize,
    /// The last violation, if any.
    pub last_violation: Option<String>,
    /// The run's last log lines, oldest first: `12.345 s  who: text`.
    pub log: Vec<String>,
}

/// The shaft to scale.
#[derive(Debug, Serialize)]
pub struct Shaft {
    /// Floors.
    pub floors: u8,
    /// Each floor's level.
    pub levels_mm: Vec<f64>,
    /// Per floor, where the left (Snimac_1) and the right (Snimac_2) sensor sees its vane.
    pub vanes: Vec<VaneView>,
    /// Where the overtravel sensors trip: bottom, top.
    pub trip_mm: [f64; 2],
    /// The mechanical ends: bottom, top.
    pub end_mm: [f64; 2],
}

/// A floor's vane as the two sensors see it.
#[derive(Debug, Serialize)]
pub struct VaneView {
    /// The floor.
    pub floor: u8,
    /// The left sensor's track (from, to).
    pub left: (f64, f64),
    /// The right sensor's track (from, to).
    pub right: (f64, f64),
}

/// The plant now.
#[derive(Debug, Serialize)]
pub struct LiftView {
    /// The cabin's height.
    pub position_mm: f64,
    /// Its speed, + up.
    pub velocity_mm_s: f64,
    /// The floor it stands level at, if any.
    pub level_floor: Option<u8>,
    /// The left vane sensor (Snimac_1) is on.
    pub vane_left: bool,
    /// The right vane sensor (Snimac_2) is on.
    pub vane_right: bool,
    /// The bottom overtravel sensor is free.
    pub overtravel_bottom_free: bool,
    /// The top overtravel sensor is free.
    pub overtravel_top_free: bool,
    /// The door is closed.
    pub door_closed: bool,
    /// The load: empty, loaded, full, overloaded.
    pub load: &'static str,
    /// K1 (drive power) is closed.
    pub k1: bool,
    /// K1's auxiliary contact is closed.
    pub k1_aux: bool,
    /// The converter runs.
    pub converter_run: bool,
    /// Its direction is up.
    pub converter_up: bool,
    /// The converter's output frequency, Hz.
    pub converter_hz: f64,
    /// The speed set-point on the S-7.3 output, µA.
    pub setpoint_ua: u16,
    /// Someone turns the hand crank.
    pub hand_cranking: bool,
    /// The buttons pressed now (`cabin:3`, `hall-up:1`, `stop`, `bell`).
    pub pressed: Vec<String>,
}

/// A display as its slave shows it.
#[derive(Debug, Serialize)]
pub struct DisplayView {
    /// `floor 1` .. or `cabin`.
    pub id: String,
    /// `blank`, `showing` or `error`.
    pub state: &'static str,
    /// The floor number shown.
    pub floor: Option<u8>,
    /// Up arrow.
    pub up: bool,
    /// Down arrow.
    pub down: bool,
    /// Moving lamp.
    pub moving: bool,
    /// Fault lamp.
    pub fault: bool,
    /// Why the last word could not be shown.
    pub error: Option<String>,
}

/// The bus now.
#[derive(Debug, Serialize)]
pub struct BusView {
    /// The master's phase.
    pub phase: &'static str,
    /// The master's LEDs (seed 003 table 3.2): name and light (`off`, `green`,
    /// `green_flashing`, `red`, `red_flashing`, `yellow`), PWR first.
    pub master_leds: Vec<(&'static str, &'static str)>,
    /// The slaves in any list, by address.
    pub slaves: Vec<SlaveView>,
    /// The lab's slave addresses (for the page's offline/online choice).
    pub lab_addresses: Vec<u8>,
    /// AS-i cycle time, µs: mean, minimum, maximum.
    pub cycle_us: [f64; 3],
    /// Transactions so far, repeats among them.
    pub transactions: u64,
    /// Immediate repeats so far.
    pub repeats: u64,
    /// Receiver errors per check (requests and responses), in the order of the seven checks,
    /// then the missing responses.
    pub errors: Vec<(&'static str, u64)>,
    /// Line noise: the probability that a pulse is corrupted.
    pub line_noise: f64,
    /// The AS-i supply, V.
    pub supply_v: f64,
    /// The last transactions in the trace's text form, oldest first.
    pub telegrams: Vec<String>,
}

/// One slave address.
#[derive(Debug, Serialize)]
pub struct SlaveView {
    /// `7A`, `5B` …
    pub addr: String,
    /// Its number.
    pub number: u8,
    /// What it is on the lab bus.
    pub name: &'static str,
    /// Detected.
    pub lds: bool,
    /// Activated.
    pub las: bool,
    /// Projected.
    pub lps: bool,
    /// Periphery fault.
    pub lpf: bool,
    /// The last input nibble (D3..D0).
    pub input: String,
    /// The last output nibble (D3..D0).
    pub output: String,
    /// Its traffic light as an analyser shows it (`green`, `yellow`, `red`; absent before
    /// the master's first normal operation or for a slave without traffic).
    pub light: Option<&'static str>,
    /// Calls to it so far, repeats included.
    pub calls: u64,
    /// Repeats of its calls so far.
    pub repeats: u64,
}

/// The safety logic now.
#[derive(Debug, Serialize)]
pub struct SafetyView {
    /// The group `drive`: RUN, STOP, ERROR …
    pub group: &'static str,
    /// FB_ERR, COM_ERR, OUT_ERR.
    pub fb_err: bool,
    /// COM_ERR.
    pub com_err: bool,
    /// OUT_ERR.
    pub out_err: bool,
    /// The ESTOP module's state.
    pub estop: &'static str,
    /// The MON (overtravel) module's state.
    pub mon: &'static str,
    /// EStopOut (to the controller; on = no STOP demand).
    pub estop_out: bool,
    /// EStopDelOut (to K1; off once the STOP delay has elapsed).
    pub estop_del_out: bool,
    /// Why K1 is open, if it is.
    pub k1_open_cause: Option<String>,
    /// The cabin STOP terminal's safe link diag byte, in words.
    pub stop_link: Vec<&'static str>,
    /// The logic stopped on an internal fault.
    pub logic_fault: bool,
}

/// The PLC program now.
#[derive(Debug, Serialize)]
pub struct ControllerView {
    /// An outside controller is the PLC (the fields below are then absent).
    pub external: bool,
    /// FIFO or collective.
    pub algorithm: Option<&'static str>,
    /// Initialised.
    pub initialised: Option<bool>,
    /// The automat's state.
    pub state: Option<&'static str>,
    /// The floor it counts the cabin at.
    pub floor: Option<u8>,
    /// Its target.
    pub target: Option<u8>,
    /// The cabin request memory, oldest first.
    pub fifo_cabin: Option<Vec<u8>>,
    /// The hall request memory, oldest first.
    pub fifo_hall: Option<Vec<u8>>,
    /// The Structured Text program the PLC runs, if not the built-in one (its file).
    pub program: Option<String>,
    /// Why that PLC is in STOP (`file:line:column: cause`), if it is.
    pub stopped: Option<String>,
    /// That program's variables of elementary type, each with its value as a literal of its
    /// type, as a PLC's online mode shows them: the first [`WATCH`] in declaration order.
    pub watch: Option<Vec<(String, String)>>,
    /// How many more variables the program has than the watch list shows.
    pub watch_left_out: usize,
}

/// The lab's name for a slave address.
fn slave_name(n: u8) -> &'static str {
    match n {
        1..=4 => "floor station",
        address::CABIN_DISPLAY => "cabin display",
        address::CABIN_PANEL => "cabin panel",
        address::CONVERTER => "converter",
        address::LOAD_SENSOR => "load sensor",
        address::SPEED_SETPOINT => "speed set-point",
        address::SAFETY_BOTTOM => "overtravel bottom",
        address::SAFETY_TOP => "overtravel top",
        _ => "I/O module",
    }
}

fn nibble(v: u8) -> String {
    format!("{:04b}", v & 0xF)
}

fn us(d: SimDuration) -> f64 {
    (d.as_nanos() as f64 / 1e3 * 10.0).round() / 10.0
}

/// The snapshot of `rig` now.
pub fn build(rig: &Rig, run: Run, telegrams: Option<&Telegrams>) -> View {
    let lift = rig.lift();
    let cfg = lift.config();
    let floors = cfg.floors;
    let shaft = Shaft {
        floors,
        levels_mm: (1..=floors)
            .map(|f| cfg.floor_level_mm(f).unwrap_or_default())
            .collect(),
        vanes: (1..=floors)
            .map(|f| VaneView {
                floor: f,
                left: cfg.vane_track_mm(VaneSensor::Left, f).unwrap_or_default(),
                right: cfg.vane_track_mm(VaneSensor::Right, f).unwrap_or_default(),
            })
            .collect(),
        trip_mm: [
            cfg.trip_position_mm(End::Bottom),
            cfg.trip_position_mm(End::Top),
        ],
        end_mm: [
            cfg.end_position_mm(End::Bottom),
            cfg.end_position_mm(End::Top),
        ],
    };
    let mut buttons = vec![Button::Stop, Button::Bell];
    for f in 1..=floors {
        buttons.extend([Button::Cabin(f), Button::HallUp(f), Button::HallDown(f)]);
    }
    let diag = rig.safety_diag();
    let lab = rig.lab();
    let (converter_run, converter_up) = lab
        .converter()
        .map_or((false, false), |c| (c.run(), c.direction_up()));
    let lift_view = LiftView {
        position_mm: (lift.position_mm() * 10.0).round() / 10.0,
        velocity_mm_s: (lift.velocity_mm_s() * 10.0).round() / 10.0,
        level_floor: cfg.level_floor(lift.position_mm()),
        vane_left: lift.vane_left(),
        vane_right: lift.vane_right(),
        overtravel_bottom_free: lift.overtravel_bottom_free(),
        overtravel_top_free: lift.overtravel_top_free(),
        door_closed: lift.door_closed(),
        load: lift.load().name(),
        k1: lift.k1_closed(),
        k1_aux: lift.k1_aux_closed(),
        // What the converter's slave drives, as the plant gets it.
        converter_run,
        converter_up,
        converter_hz: (lift.converter_frequency_hz() * 100.0).round() / 100.0,
        setpoint_ua: lab.analog_output().map_or(0, |a| a.current_ua(1)),
        hand_cranking: lift.hand_cranking(),
        pressed: buttons
            .into_iter()
            .filter(|b| lift.is_pressed(*b))
            .map(Button::key)
            .collect(),
    };
    let displays = (1..=floors)
        .map(DisplayId::Floor)
        .chain([DisplayId::Cabin])
        .map(|id| display(id, lift.display(id)))
        .collect();

    let master = lab.bus().master();
    let (las, lds, lps, lpf) = (master.las(), master.lds(), master.lps(), master.lpf());
    let image = lab.bus().image();
    let table = lab.bus().slave_stats();
    let slaves = (1..64u8)
        .filter_map(SlaveAddr::from_index)
        .filter(|a| lds.contains(*a) || las.contains(*a) || lps.contains(*a) || lpf.contains(*a))
        .map(|a| SlaveView {
            addr: a.to_string(),
            number: a.number(),
            name: slave_name(a.number()),
            lds: lds.contains(a),
            las: las.contains(a),
            lps: lps.contains(a),
            lpf: lpf.contains(a),
            input: nibble(image.input.nibble(a).get()),
            output: nibble(image.output.nibble(a).get()),
            light: table.get(a.index()).and_then(|s| s.light).map(|l| l.name()),
            calls: table.get(a.index()).map_or(0, |s| s.calls),
            repeats: table.get(a.index()).map_or(0, |s| s.repeats),
        })
        .collect();
    let stats = lab.bus().stats();
    let mean = stats
        .cycle_total
        .as_nanos()
        .checked_div(stats.cycles)
        .map_or(SimDuration::ZERO, SimDuration::from_nanos);
    let mut errors: Vec<(&'static str, u64)> = Check::ALL
        .iter()
        .map(|&c| (check_key(c), stats.errors(c)))
        .collect();
    errors.push(("no_response", stats.no_response));
    let rates = lab.bus().line_fault_rates();
    let bus = BusView {
        phase: match master.phase() {
            Phase::Offline => "offline",
            Phase::Detection => "detection",
            Phase::Activation => "activation",
            Phase::NormalOperation => "normal operation",
        },
        master_leds: asi_master::MasterLeds::NAMES
            .into_iter()
            .zip(master.leds().each().map(|l| l.name()))
            .collect(),
        slaves,
        lab_addresses: lab_addresses(rig),
        cycle_us: [us(mean), us(stats.cycle_min), us(stats.cycle_max)],
        transactions: stats.transactions,
        repeats: stats.repeats,
        errors,
        line_noise: rates.drop + rates.insert + rates.flip + rates.shift,
        supply_v: lab.bus().supply_voltage(),
        telegrams: telegrams
            .map(|t| t.borrow().iter().map(|r| r.to_string()).collect())
            .unwrap_or_default(),
    };

    let module = |s: Option<FbState>| s.map_or("STOP", FbState::name);
    let estop = diag.map(|d| d.estop.state);
    let safety = SafetyView {
        group: diag.map_or("STOP", |d| d.group.state.name()),
        fb_err: diag.is_some_and(|d| d.group.errors.fb_err),
        com_err: diag.is_some_and(|d| d.group.errors.com_err),
        out_err: diag.is_some_and(|d| d.group.errors.out_err),
        estop: module(estop),
        mon: module(diag.map(|d| d.overtravel.state)),
        estop_out: rig.estop_out(),
        // EStopDelOut follows EStopOut into the STOP delay and drops at its end.
        estop_del_out: matches!(estop, Some(FbState::Run | FbState::DelayOut)),
        k1_open_cause: diag
            .and_then(|d| d.k1_open_cause)
            .filter(|_| !lift.k1_closed())
            .map(|c| c.to_string()),
        stop_link: diag
            .map(|d| d.stop_link.names().collect())
            .unwrap_or_default(),
        logic_fault: diag.is_some_and(|d| d.logic_fault),
    };

    let p = rig.plc().map(|plc| plc.program());
    let st = rig.controller::<StProgram>();
    let watch = st.map(StProgram::watch_text).unwrap_or_default();
    let controller = ControllerView {
        external: rig.controller::<Outside>().is_some(),
        algorithm: p.map(|p| match p.config().algorithm {
            Algorithm::Fifo => "FIFO",
            Algorithm::Collective => "collective",
        }),
        initialised: p.map(|p| p.is_initialised()),
        state: p.map(|p| p.state().name()),
        floor: p.map(|p| p.current_floor()),
        target: p.map(|p| p.target()),
        fifo_cabin: p.map(|p| p.fifo_cabin()),
        fifo_hall: p.map(|p| p.fifo_hall()),
        program: st.map(|p| p.name().to_owned()),
        stopped: st.and_then(StProgram::stopped),
        watch_left_out: watch.len().saturating_sub(WATCH),
        watch: st.map(|_| {
            watch
                .into_iter()
                .take(WATCH)
                .map(|(n, v)| (n.to_owned(), v))
                .collect()
        }),
    };

    let violations = rig.violations();
    let log = rig.recent_log(LOG_LINES);
    View {
        kind: "view",
        t_s: (rig.now().as_secs_f64() * 1e3).round() / 1e3,
        run,
        shaft,
        lift: lift_view,
        displays,
        bus,
        safety,
        controller,
        violations: violations.len(),
        last_violation: violations
            .last()
            .map(|v| format!("{:.3} s {}: {}", v.at_s, v.kind, v.detail)),
        log: log
            .iter()
            .map(|l| format!("{:9.3} s  {}: {}", l.at_s, l.who, l.event))
            .collect(),
    }
}

/// The lab bus's slave addresses: the lift's own and the extra modules of the scenario.
fn lab_addresses(rig: &Rig) -> Vec<u8> {
    (1..32u8)
        .filter(|&n| rig.lab().slave_id(n).is_some())
        .collect()
}

fn display(id: DisplayId, state: Option<DisplayState>) -> DisplayView {
    let name = match id {
        DisplayId::Floor(f) => format!("floor {f}"),
        DisplayId::Cabin => "cabin".into(),
    };
    let mut v = DisplayView {
        id: name,
        state: "blank",
        floor: None,
        up: false,
        down: false,
        moving: false,
        fault: false,
        error: None,
    };
    match state {
        None | Some(DisplayState::Blank) => {}
        Some(DisplayState::Showing(w)) => {
            v.state = "showing";
            v.floor = Some(w.floor);
            v.up = w.up;
            v.down = w.down;
            v.moving = w.moving;
            v.fault = w.fault;
        }
        Some(DisplayState::BadWord { error, .. }) => {
            v.state = "error";
            v.error = Some(error.to_string());
        }
    }
    v
}
