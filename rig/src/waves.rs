//! Waveform outputs of a run: the VCD of `asi-lift run --vcd` and the line-voltage CSV of
//! `--csv` (docs/physical-layer.md "Waveform", §7).
//!
//! The VCD holds, for the whole run, the AS-i line as the Manchester level (one record per
//! pulse, so a pulse that repeats the level — a line fault — is still a record), the decoded
//! telegram fields of every transaction, and the rig's state: the plant, the controller, the
//! safety logic. The line voltage itself (`line_voltage`, the sampled sin² pulses as they are
//! on the line, faults included) is written only for a window, default the first 10 ms, so a
//! long run stays small; the CSV holds the same window as `time_s,voltage_v`. The pulse wire
//! is the bulk of a long run's VCD (about [`VCD_PULSE_BYTES_PER_S`] per simulated second), so
//! it too can be bounded by a window ([`WaveOutputs::pulse_window`]); [`estimate_vcd_bytes`]
//! tells before the run how large the VCD will be.

use crate::report::round3;
use asi_master::record::{describe_request, TransactionRecord};
use asi_phy::waveform::{render, WaveformConfig};
use asi_phy::{BusTiming, Polarity, Pulse, SimDuration, SimTime};
use asi_trace::vcd;
use asi_trace::vcd::write::{Sample, VarId, VarKind, VcdWriter};
use std::fmt::Write as _;
use std::io::{self, Write};

/// Where the waveform outputs go and which window of line voltage they hold.
pub struct WaveOutputs {
    /// The VCD, if wanted.
    pub vcd: Option<Box<dyn Write>>,
    /// The line-voltage CSV, if wanted.
    pub csv: Option<Box<dyn Write>>,
    /// The window of line voltage, `[start, end)`.
    pub window: (SimTime, SimTime),
    /// The window of the VCD's pulse wire (`rig.bus.manchester`), `[start, end)`; `None`
    /// for the whole run. The rest of the VCD (telegram fields, plant, controller, safety)
    /// always covers the whole run.
    pub pulse_window: Option<(SimTime, SimTime)>,
}

/// The default window of line voltage: the first 10 ms.
pub const DEFAULT_WINDOW: (SimTime, SimTime) = (SimTime::ZERO, SimTime::from_millis(10));

/// Bytes of VCD per simulated second of pulse wire: 3.3 MB measured on the demo's bus (a 4 s
/// run, 16.3 MB with the whole pulse wire, 3.2 MB with 1 ms of it), rounded up for the
/// longer time stamps of a long run.
pub const VCD_PULSE_BYTES_PER_S: u64 = 3_400_000;
/// Bytes of VCD per simulated second of line voltage while the bus is busy (10 MS/s, written
/// on change): 142 MB measured (a 2 s run with 100 ms of voltage against one with 10 ms).
pub const VCD_VOLTAGE_BYTES_PER_S: u64 = 145_000_000;
/// Bytes of VCD per simulated second of the rest: telegram fields, plant, controller, safety
/// (0.64 MB measured: a 4 s run against a 2 s one, both with 1 ms of pulse wire).
pub const VCD_REST_BYTES_PER_S: u64 = 650_000;

/// The CSV's size, roughly, for line voltage over `voltage` (the part of the waveform window
/// inside the run) ending at `end`: one line per sample of the default grid (10 MS/s), each
/// the time with 9 decimals, a comma, the voltage with 5 decimals (at most 8 characters) and
/// a newline. Measured: 100 ms of the demo's window at 0.5 s, 20.3 MB; estimated 21.0 MB.
pub fn estimate_csv_bytes(voltage: SimDuration, end: SimTime) -> u64 {
    let period = WaveformConfig::default().sample_period.as_nanos().max(1);
    let samples = voltage.as_nanos() / period;
    let whole_seconds = end.as_nanos() / 1_000_000_000;
    let digits = whole_seconds.checked_ilog10().map_or(1, |d| d as u64 + 1);
    let line = digits + 1 + 9 + 1 + 8 + 1;
    samples.saturating_mul(line)
}

/// The VCD's size, roughly, for a run of `run` whose pulse wire covers `pulses` and line
/// voltage `voltage` (each the part of its window inside the run).
pub fn estimate_vcd_bytes(run: SimDuration, pulses: SimDuration, voltage: SimDuration) -> u64 {
    let bytes = |d: SimDuration, per_s: u64| {
        u64::try_from(d.as_nanos() as u128 * per_s as u128 / 1_000_000_000).unwrap_or(u64::MAX)
    };
    bytes(run, VCD_REST_BYTES_PER_S)
        .saturating_add(bytes(pulses, VCD_PULSE_BYTES_PER_S))
        .saturating_add(bytes(voltage, VCD_VOLTAGE_BYTES_PER_S))
}

/// How far behind the bus the VCD is written: a transaction is recorded when it ends, up to
/// a few hundred µs after its request started.
const LAG: SimDuration = SimDuration::from_millis(2);
/// Cabin position and velocity are sampled at most this often while they change.
const REAL_PERIOD: SimDuration = SimDuration::from_millis(1);

/// The rig's state at one moment, as the VCD shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct RigSample {
    /// Cabin height above the floor-1 level, mm.
    pub position_mm: f64,
    /// Cabin velocity, mm/s (positive up).
    pub velocity_mm_s: f64,
    /// Left vane sensor.
    pub vane_left: bool,
    /// Right vane sensor.
    pub vane_right: bool,
    /// Bottom overtravel sensor free.
    pub overtravel_bottom_free: bool,
    /// Top overtravel sensor free.
    pub overtravel_top_free: bool,
    /// Contactor K1 closed.
    pub k1: bool,
    /// Door closed.
    pub door_closed: bool,
    /// Converter run command.
    pub converter_run: bool,
    /// Converter direction: up.
    pub converter_up: bool,
    /// Speed set-point on the current loop, µA.
    pub setpoint_ua: u16,
    /// The controller's state.
    pub controller_state: &'static str,
    /// The floor the controller believes the cabin at.
    pub floor: u8,
    /// The controller's target floor (0 = none).
    pub target_floor: u8,
    /// Calls in the cabin FIFO.
    pub fifo_cabin: u8,
    /// Calls in the hall FIFO.
    pub fifo_hall: u8,
    /// ESTOP's output to the controller (`false` = STOP demanded).
    pub estop_out: bool,
    /// The safety group's state (RUN, STOP, ERROR, RESET).
    pub group_state: &'static str,
    /// FB_ERR.
    pub fb_err: bool,
    /// COM_ERR.
    pub com_err: bool,
    /// OUT_ERR.
    pub out_err: bool,
    /// The AS-i supply, V.
    pub supply_v: f64,
    /// The safe drive's bits (with `[drive] safe = true`).
    pub drive: Option<DriveSample>,
    /// The AS-i master's LEDs (seed 003 table 3.2).
    pub master_leds: asi_master::MasterLeds,
}

/// The safe drive's bits at one moment (scope `rig.drive_safety`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriveSample {
    /// The control bits the safety logic sets (active-low: FALSE = requested) and Reset.
    pub control: safety::drive::ControlBits,
    /// The status bits, SDC and NotErrFunc.
    pub status: safety::drive::StatusBits,
    /// The torque enabled (FALSE = STO, K1 open, brake applied).
    pub torque: bool,
}

/// The VCD's variables of the safe drive: per function its control and status bit.
#[derive(Clone)]
struct DriveIds {
    control: Vec<VarId>,
    status: Vec<VarId>,
    sdc: VarId,
    not_err_func: VarId,
    torque: VarId,
    reset: VarId,
}

fn declare_drive(w: &mut VcdWriter<Box<dyn Write>>) -> DriveIds {
    const DRIVE: &[&str] = &["rig", "drive_safety"];
    // In the order of `Function::ALL`.
    const CONTROL: [&str; 15] = [
        "control_sto",
        "control_sbc",
        "control_ss1",
        "control_ss2",
        "control_sos",
        "control_sls1",
        "control_sls2",
        "control_sls3",
        "control_sls4",
        "control_slp",
        "control_sdi_p",
        "control_sdi_n",
        "control_sli",
        "control_sla",
        "control_slt",
    ];
    const STATUS: [&str; 15] = [
        "status_sto",
        "status_sbc",
        "status_ss1",
        "status_ss2",
        "status_sos",
        "status_sls1",
        "status_sls2",
        "status_sls3",
        "status_sls4",
        "status_slp",
        "status_sdi_p",
        "status_sdi_n",
        "status_sli",
        "status_sla",
        "status_slt",
    ];
    DriveIds {
        control: CONTROL
            .iter()
            .map(|n| w.var(DRIVE, n, VarKind::Wire(1)))
            .collect(),
        status: STATUS
            .iter()
            .map(|n| w.var(DRIVE, n, VarKind::Wire(1)))
            .collect(),
        sdc: w.var(DRIVE, "status_sdc", VarKind::Wire(1)),
        not_err_func: w.var(DRIVE, "status_not_err_func", VarKind::Wire(1)),
        torque: w.var(DRIVE, "torque_enabled", VarKind::Wire(1)),
        reset: w.var(DRIVE, "control_reset", VarKind::Wire(1)),
    }
}

#[derive(Clone)]
struct Ids {
    manchester: VarId,
    line_voltage: VarId,
    request: VarId,
    call: VarId,
    address: VarId,
    info: VarId,
    response: VarId,
    data: VarId,
    errors: VarId,
    repeat: VarId,
    supply: VarId,
    position: VarId,
    velocity: VarId,
    vane_left: VarId,
    vane_right: VarId,
    ot_bottom: VarId,
    ot_top: VarId,
    k1: VarId,
    door: VarId,
    run: VarId,
    up: VarId,
    setpoint: VarId,
    state: VarId,
    floor: VarId,
    target: VarId,
    fifo_cabin: VarId,
    fifo_hall: VarId,
    estop_out: VarId,
    group: VarId,
    fb_err: VarId,
    com_err: VarId,
    out_err: VarId,
    /// The master's LEDs, in the order of `MasterLeds::NAMES`.
    leds: [VarId; asi_master::leds::LED_COUNT],
}

fn declare(w: &mut VcdWriter<Box<dyn Write>>) -> Ids {
    const BUS: &[&str] = vcd::BUS_SCOPE;
    const PLANT: &[&str] = &["rig", "plant"];
    const CTL: &[&str] = &["rig", "controller"];
    const SAFETY: &[&str] = &["rig", "safety"];
    const LEDS: &[&str] = &["rig", "master_leds"];
    Ids {
        manchester: w.var_every_record(BUS, vcd::PULSE_WIRE, VarKind::Wire(1)),
        line_voltage: w.var(BUS, vcd::LINE_VOLTAGE, VarKind::Real),
        request: w.var(BUS, "request", VarKind::Wire(14)),
        call: w.var(BUS, "call", VarKind::Text),
        address: w.var(BUS, "address", VarKind::Wire(5)),
        info: w.var(BUS, "info", VarKind::Wire(5)),
        response: w.var(BUS, "response", VarKind::Wire(7)),
        data: w.var(BUS, "data", VarKind::Wire(4)),
        errors: w.var(BUS, "errors", VarKind::Text),
        repeat: w.var(BUS, "repeat", VarKind::Wire(1)),
        supply: w.var(BUS, "supply_voltage", VarKind::Real),
        position: w.var(PLANT, "cabin_position_mm", VarKind::Real),
        velocity: w.var(PLANT, "cabin_velocity_mm_s", VarKind::Real),
        vane_left: w.var(PLANT, "vane_left", VarKind::Wire(1)),
        vane_right: w.var(PLANT, "vane_right", VarKind::Wire(1)),
        ot_bottom: w.var(PLANT, "overtravel_bottom_free", VarKind::Wire(1)),
        ot_top: w.var(PLANT, "overtravel_top_free", VarKind::Wire(1)),
        k1: w.var(PLANT, "k1", VarKind::Wire(1)),
        door: w.var(PLANT, "door_closed", VarKind::Wire(1)),
        run: w.var(PLANT, "converter_run", VarKind::Wire(1)),
        up: w.var(PLANT, "converter_up", VarKind::Wire(1)),
        setpoint: w.var(PLANT, "converter_setpoint_ua", VarKind::Wire(16)),
        state: w.var(CTL, "state", VarKind::Text),
        floor: w.var(CTL, "floor", VarKind::Wire(5)),
        target: w.var(CTL, "target_floor", VarKind::Wire(5)),
        fifo_cabin: w.var(CTL, "fifo_cabin_fill", VarKind::Wire(5)),
        fifo_hall: w.var(CTL, "fifo_hall_fill", VarKind::Wire(5)),
        estop_out: w.var(SAFETY, "estop_out", VarKind::Wire(1)),
        group: w.var(SAFETY, "group_state", VarKind::Text),
        fb_err: w.var(SAFETY, "fb_err", VarKind::Wire(1)),
        com_err: w.var(SAFETY, "com_err", VarKind::Wire(1)),
        out_err: w.var(SAFETY, "out_err", VarKind::Wire(1)),
        leds: asi_master::MasterLeds::NAMES.map(|n| w.var(LEDS, n, VarKind::Text)),
    }
}

/// The waveform outputs of one run.
pub struct Waves {
    vcd: Option<(VcdWriter<Box<dyn Write>>, Ids)>,
    drive: Option<DriveIds>,
    csv: Option<Box<dyn Write>>,
    window: (SimTime, SimTime),
    pulse_window: (SimTime, SimTime),
    window_pulses: Vec<Pulse>,
    /// The line voltage is written up to here.
    rendered_to: SimTime,
    csv_header: bool,
    wave: WaveformConfig,
    response_after: SimDuration,
    last_real: Option<(SimTime, f64, f64)>,
    /// The master's LEDs last written.
    last_leds: Option<asi_master::MasterLeds>,
    error: Option<String>,
}

impl Waves {
    /// Waveform outputs for a bus of `timing`.
    pub fn new(out: WaveOutputs, timing: &BusTiming) -> Waves {
        let vcd = out.vcd.map(|o| {
            let mut w = VcdWriter::new(o);
            let ids = declare(&mut w);
            (w, ids)
        });
        Waves {
            vcd,
            drive: None,
            csv: out.csv,
            window: out.window,
            pulse_window: out
                .pulse_window
                .unwrap_or((SimTime::ZERO, SimTime::from_nanos(u64::MAX))),
            window_pulses: Vec::new(),
            rendered_to: out.window.0,
            csv_header: false,
            wave: WaveformConfig::default(),
            response_after: timing.request_span() + timing.master_pause(),
            last_real: None,
            last_leds: None,
            error: None,
        }
    }

    /// Waveforms that go on from where these stand into the writers of `out` (for a copy of a
    /// rig; the windows stay these ones'): the same variables, the changes not yet written,
    /// the line voltage not yet drawn. The VCD begins with its header and every variable's
    /// value at the last time written ([`VcdWriter::continue_into`]), the CSV with its header;
    /// every record after that is one these waveforms write.
    pub fn continue_into(&self, out: WaveOutputs) -> Waves {
        let vcd = match (&self.vcd, out.vcd) {
            (Some((w, ids)), Some(o)) => Some((w.continue_into(o), ids.clone())),
            _ => None,
        };
        Waves {
            vcd,
            drive: self.drive.clone(),
            csv: self.csv.as_ref().and(out.csv),
            window: self.window,
            pulse_window: self.pulse_window,
            window_pulses: self.window_pulses.clone(),
            rendered_to: self.rendered_to,
            csv_header: false,
            wave: self.wave,
            response_after: self.response_after,
            last_real: self.last_real,
            last_leds: self.last_leds,
            error: None,
        }
    }

    /// Waveforms begun at `now` of a run under way (a copy of a rig given outputs of its own):
    /// the line voltage is drawn from `now` on, as nothing before it was seen.
    pub fn starting_at(mut self, now: SimTime) -> Waves {
        self.rendered_to = self.rendered_to.max(now);
        self
    }

    /// Adds the scope `rig.drive_safety` (the safe drive's bits) to the VCD; before the first
    /// sample.
    pub fn with_drive_safety(mut self) -> Waves {
        if let Some((w, _)) = &mut self.vcd {
            self.drive = Some(declare_drive(w));
        }
        self
    }

    /// The first error writing an output, if any.
    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// Pulses that went on the line.
    pub fn pulses(&mut self, pulses: &[Pulse]) {
        let (from, until) = self.window;
        let margin = self.wave.pulse_width;
        for p in pulses {
            if p.at + margin > from.max(self.rendered_to) && p.at < until + margin {
                self.window_pulses.push(*p);
            }
            let (pulses_from, pulses_until) = self.pulse_window;
            if let (Some((w, ids)), true) =
                (&mut self.vcd, pulses_from <= p.at && p.at < pulses_until)
            {
                let level = matches!(p.polarity, Polarity::Positive);
                w.change(p.at.as_nanos(), ids.manchester, level.into());
            }
        }
    }

    /// A finished transaction: its telegram fields at the times they were on the line.
    pub fn transaction(&mut self, r: &TransactionRecord) {
        let Some((w, ids)) = &mut self.vcd else {
            return;
        };
        let t = r.start.as_nanos();
        w.change(t, ids.request, Sample::Bits(r.request.bits() as u64));
        w.change(t, ids.call, Sample::Text(describe_request(r.request, r.ab)));
        w.change(
            t,
            ids.address,
            Sample::Bits(r.request.address().get() as u64),
        );
        w.change(t, ids.info, Sample::Bits(r.request.info() as u64));
        w.change(t, ids.repeat, r.repeat.into());
        let failed = r.request_failed.union(r.response_failed);
        let mut errors = String::new();
        for c in failed.iter() {
            let _ = write!(
                errors,
                "{}{}",
                if errors.is_empty() { "" } else { "+" },
                asi_trace::telegrams::check_key(c)
            );
        }
        if errors.is_empty() {
            errors.push_str(if r.no_response { "no_response" } else { "ok" });
        }
        w.change(t, ids.errors, Sample::Text(errors));
        let tr = (r.start + self.response_after).as_nanos();
        match r.response {
            Some(resp) => {
                w.change(tr, ids.response, Sample::Bits(resp.bits() as u64));
                w.change(tr, ids.data, Sample::Bits(resp.data().get() as u64));
            }
            None => {
                w.change(tr, ids.response, Sample::Unknown);
                w.change(tr, ids.data, Sample::Unknown);
            }
        }
    }

    /// The rig's state at `t`.
    pub fn sample(&mut self, t: SimTime, s: &RigSample) {
        let Some((w, ids)) = &mut self.vcd else {
            return;
        };
        let n = t.as_nanos();
        let real_due = match self.last_real {
            None => true,
            Some((at, p, v)) => {
                v != s.velocity_mm_s || (p != s.position_mm && t - at >= REAL_PERIOD)
            }
        };
        if real_due {
            w.change(n, ids.position, Sample::Real(round3(s.position_mm)));
            w.change(n, ids.velocity, Sample::Real(round3(s.velocity_mm_s)));
            self.last_real = Some((t, s.position_mm, s.velocity_mm_s));
        }
        let bits = [
            (ids.vane_left, s.vane_left),
            (ids.vane_right, s.vane_right),
            (ids.ot_bottom, s.overtravel_bottom_free),
            (ids.ot_top, s.overtravel_top_free),
            (ids.k1, s.k1),
            (ids.door, s.door_closed),
            (ids.run, s.converter_run),
            (ids.up, s.converter_up),
            (ids.estop_out, s.estop_out),
            (ids.fb_err, s.fb_err),
            (ids.com_err, s.com_err),
            (ids.out_err, s.out_err),
        ];
        for (id, b) in bits {
            w.change(n, id, b.into());
        }
        let words = [
            (ids.setpoint, s.setpoint_ua as u64),
            (ids.floor, s.floor as u64),
            (ids.target, s.target_floor as u64),
            (ids.fifo_cabin, s.fifo_cabin as u64),
            (ids.fifo_hall, s.fifo_hall as u64),
        ];
        for (id, v) in words {
            w.change(n, id, Sample::Bits(v));
        }
        w.change(n, ids.state, Sample::Text(s.controller_state.into()));
        w.change(n, ids.group, Sample::Text(s.group_state.into()));
        w.change(n, ids.supply, Sample::Real(s.supply_v));
        // They change seldom: only a change is handed to the writer.
        if self.last_leds != Some(s.master_leds) {
            for (id, led) in ids.leds.iter().zip(s.master_leds.each()) {
                w.change(n, *id, Sample::Text(led.name().into()));
            }
            self.last_leds = Some(s.master_leds);
        }
        if let (Some(d), Some(ds)) = (&self.drive, &s.drive) {
            for (i, f) in safety::drive::Function::ALL.iter().enumerate() {
                w.change(n, d.control[i], (!ds.control.requested(*f)).into());
                w.change(n, d.status[i], ds.status.of(*f).into());
            }
            let bits = [
                (d.sdc, ds.status.sdc),
                (d.not_err_func, ds.status.not_err_func),
                (d.torque, ds.torque),
                (d.reset, ds.control.reset),
            ];
            for (id, b) in bits {
                w.change(n, id, b.into());
            }
        }
    }

    /// Writes what is complete up to `now` (the bus's time).
    pub fn flush(&mut self, now: SimTime) {
        let upto = now.as_nanos().saturating_sub(LAG.as_nanos());
        self.write_window(SimTime::from_nanos(upto));
        if let Some((w, _)) = &mut self.vcd {
            if let Err(e) = w.flush_until(upto) {
                self.fail(e);
            }
        }
    }

    /// Writes everything; `end` is the end of the run.
    pub fn finish(&mut self, end: SimTime) {
        self.write_window(end);
        if let Some((w, _)) = self.vcd.take() {
            if let Err(e) = w.finish(end.as_nanos()) {
                self.fail(e);
            }
        }
        if let Some(mut c) = self.csv.take() {
            if let Err(e) = c.flush() {
                self.fail(e);
            }
        }
    }

    /// Renders the window's line voltage up to `upto` into the VCD and the CSV, a piece at a
    /// time on the sample grid of the window (every pulse that reaches into a piece is kept
    /// until the piece is written, so the pieces join seamlessly).
    fn write_window(&mut self, upto: SimTime) {
        let (from, until) = self.window;
        let period = self.wave.sample_period.as_nanos();
        let end = upto.min(until);
        if end <= self.rendered_to {
            return;
        }
        // The next piece ends on the sample grid of the window.
        let whole = (end.as_nanos() - from.as_nanos()) / period * period;
        let end = if end == until {
            end
        } else {
            SimTime::from_nanos(from.as_nanos() + whole)
        };
        if end <= self.rendered_to {
            return;
        }
        let start = self.rendered_to;
        let wf = match render(self.window_pulses.iter().copied(), start, end, &self.wave) {
            Ok(wf) => wf,
            Err(e) => {
                self.error.get_or_insert_with(|| e.to_string());
                self.rendered_to = until;
                return;
            }
        };
        self.rendered_to = start + SimDuration::from_nanos(wf.samples.len() as u64 * period);
        let half = self.wave.pulse_width.as_nanos() / 2;
        let done = self.rendered_to.as_nanos();
        self.window_pulses.retain(|p| p.at.as_nanos() + half > done);
        if let Some((w, ids)) = &mut self.vcd {
            for (i, v) in wf.samples.iter().enumerate() {
                let t = wf.time_of(i as f64).as_nanos();
                w.change(t, ids.line_voltage, Sample::Real(round5(*v)));
            }
        }
        if let Some(c) = &mut self.csv {
            let mut result = Ok(());
            if !self.csv_header {
                self.csv_header = true;
                result = writeln!(c, "time_s,voltage_v");
            }
            for (i, v) in wf.samples.iter().enumerate() {
                if result.is_err() {
                    break;
                }
                result = writeln!(c, "{:.9},{v:.5}", wf.time_of(i as f64).as_secs_f64());
            }
            if let Err(e) = result {
                self.fail(e);
            }
        }
    }

    fn fail(&mut self, e: io::Error) {
        self.error.get_or_insert_with(|| e.to_string());
        self.vcd = None;
        self.csv = None;
    }
}

fn round5(x: f32) -> f64 {
    (x as f64 * 1e5).round() / 1e5
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::RefCell;
    use std::rc::Rc;

    #[derive(Clone, Default)]
    struct Shared(Rc<RefCell<Vec<u8>>>);

    impl Write for Shared {
        fn write(&mut self, b: &[u8]) -> io::Result<usize> {
            self.0.borrow_mut().extend_from_slice(b);
            Ok(b.len())
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    /// The times of the pulse wire's records in a VCD written with `pulse_window`.
    fn pulse_records(pulse_window: Option<(SimTime, SimTime)>) -> Vec<u64> {
        let vcd = Shared::default();
        let mut w = Waves::new(
            WaveOutputs {
                vcd: Some(Box::new(vcd.clone())),
                csv: None,
                window: (SimTime::ZERO, SimTime::from_micros(1)),
                pulse_window,
            },
            &BusTiming::default(),
        );
        let pulses: Vec<Pulse> = [1, 5, 9]
            .iter()
            .map(|&ms| Pulse::new(SimTime::from_millis(ms), Polarity::Negative))
            .collect();
        w.pulses(&pulses);
        w.finish(SimTime::from_millis(10));
        assert_eq!(w.error(), None);
        let text = String::from_utf8(vcd.0.borrow().clone()).expect("text");
        let body = &text[text.find("$enddefinitions").expect("header")..];
        let mut t = 0;
        let mut got = Vec::new();
        for tok in body.split_whitespace() {
            if let Some(n) = tok.strip_prefix('#') {
                t = n.parse().expect("time");
            } else if tok == "0!" {
                got.push(t);
            }
        }
        got
    }

    #[test]
    fn the_pulse_wire_keeps_to_its_window() {
        assert_eq!(pulse_records(None), [1_000_000, 5_000_000, 9_000_000]);
        let window = (SimTime::from_millis(2), SimTime::from_millis(9));
        assert_eq!(pulse_records(Some(window)), [5_000_000]);
    }

    #[test]
    fn the_vcd_size_is_estimated_from_its_windows() {
        let s = |ms: u64| SimDuration::from_millis(ms);
        assert_eq!(estimate_vcd_bytes(s(0), s(0), s(0)), 0);
        assert_eq!(
            estimate_vcd_bytes(s(1000), s(1000), s(10)),
            VCD_REST_BYTES_PER_S + VCD_PULSE_BYTES_PER_S + VCD_VOLTAGE_BYTES_PER_S / 100
        );
        // The CSV: 1,000,000 samples of 21-character lines for 100 ms ending before 10 s
        // (the demo's 0.5..0.6 s window wrote 20,338,505 bytes), longer lines later.
        assert_eq!(
            estimate_csv_bytes(s(100), SimTime::from_millis(600)),
            21_000_000
        );
        assert_eq!(
            estimate_csv_bytes(s(100), SimTime::from_millis(720_000)),
            23_000_000
        );
        assert_eq!(estimate_csv_bytes(s(0), SimTime::from_millis(600)), 0);
        // 12 minutes of everything but the voltage: about 3 GB.
        let twelve = estimate_vcd_bytes(s(720_000), s(720_000), s(0));
        assert!((2_500_000_000..3_500_000_000).contains(&twelve), "{twelve}");
    }
}
