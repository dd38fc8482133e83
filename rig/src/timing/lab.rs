//! The lab experiment: the whole rig runs for the window (handshake words and S-7.3 values
//! timed from the devices' counters), then the latency samples ([`super::latency`]).

use super::bus::READY_WITHIN;
use super::collector::{lock, take, BusWindow, Collector};
use super::latency::{ready_at, sample_latencies, wait_resetting, InService};
use super::options::{AnalysisError, TimingOptions};
use super::report::LabTiming;
use super::stats::{ms, Summary, Ticker};
use crate::rig::Rig;
use crate::scenario::Scenario;
use asi_phy::SimDuration;
use lab::address::CONVERTER;
use lift_model::LoadLevel;
use std::sync::{Arc, Mutex};

/// The lab rig: window statistics, then latency samples.
pub(super) fn run_lab(
    opts: &TimingOptions,
    extra: u8,
) -> Result<(Collector, BusWindow, LabTiming), AnalysisError> {
    let sc = lab_scenario(opts, extra);
    let plc_scan = sc.plc_scan;
    let mut rig = Rig::new(sc)?;
    let timing = *rig.lab().bus().timing();
    let shared = Arc::new(Mutex::new(Collector::new(
        &timing,
        opts.pulse_error_rate,
        Some(CONVERTER),
    )));
    let sink = Arc::clone(&shared);
    rig.lab_mut()
        .bus_mut()
        .set_trace_callback(Some(Box::new(move |r| lock(&sink).record(r))));
    let mut service = InService::default();
    let init_resets = initialise(&mut rig, &mut service)?;
    let (words, window) = measure_window(&mut rig, &shared, opts.duration, &mut service);
    let mut latencies = sample_latencies(&mut rig, &shared, opts, service.0);
    latencies.operator_resets += init_resets;
    rig.lab_mut().bus_mut().set_trace_callback(None);
    drop(rig);
    let collector = take(&shared);
    let lab = LabTiming {
        plc_scan_ms: ms(plc_scan),
        safety_scan_ms: ms(safety::SAFETY_SCAN_PERIOD),
        stop_delay_ms: ms(safety::LiftSafetyConfig::default().estop_delay),
        latencies,
        ..words.figures()
    };
    Ok((collector, window, lab))
}

/// The rig for the timing: the lift empty at floor 1 with its door closed, `extra` I/O modules
/// on the bus, the line noise and seed of `opts`, and no end of its own.
fn lab_scenario(opts: &TimingOptions, extra: u8) -> Scenario {
    let mut sc = Scenario::defaults();
    sc.name = "timing".into();
    sc.seed = opts.seed;
    sc.duration = SimDuration::from_secs(10_000_000);
    sc.start_mm = 0.0;
    sc.load = LoadLevel::Empty;
    sc.door_closed = true;
    sc.pulse_error_rate = opts.pulse_error_rate;
    sc.extra_slaves = extra;
    sc.program = opts.program.clone();
    sc
}

/// Brings the lift to ready at floor 1; the operator's resets on the way. The Safety-at-Work
/// monitor may trip under line noise during initialisation too: the operator resets it, as
/// during the latency samples.
fn initialise(rig: &mut Rig, service: &mut InService) -> Result<u32, AnalysisError> {
    let mut resets = 0;
    let ready = wait_resetting(rig, READY_WITHIN, &mut resets, |r| {
        service.note(r);
        ready_at(r, 1)
    });
    match ready {
        Some(_) => Ok(resets),
        None if rig.controller_status().state.is_none() => Err(AnalysisError::NotReady {
            what: "the controller does not tell its state, floor and target (a Structured \
                   Text program tells them through the agreed variables `State`, `Floor` and \
                   `Target`), so the lift is never seen ready at floor 1",
            within: READY_WITHIN,
        }),
        None => Err(AnalysisError::NotReady {
            what: "the lift did not initialise at floor 1",
            within: READY_WITHIN,
        }),
    }
}

/// The measurement window: the lift stands; the handshakes and the bus run on, the word and
/// value counters polled moment by moment.
fn measure_window(
    rig: &mut Rig,
    shared: &Mutex<Collector>,
    duration: SimDuration,
    service: &mut InService,
) -> (WordTimers, BusWindow) {
    let start = rig.now();
    lock(shared).start_window();
    let before = rig.lab().bus().stats();
    let slaves_before = rig.lab().bus().slave_stats();
    let las_at_start = rig.lab().bus().master().las().len();
    let mut words = WordTimers::new();
    words.poll(rig);
    while rig.step_until(start + duration).is_some() {
        service.note(rig);
        words.poll(rig);
    }
    lock(shared).end_window();
    let after = rig.lab().bus().stats();
    let bus = rig.lab().bus();
    let window = BusWindow {
        failed_after_repeat: after.failed_after_repeat - before.failed_after_repeat,
        dropouts: after.dropouts - before.dropouts,
        slaves: crate::report::slave_reports(
            &bus.slave_stats().since(&slaves_before),
            Some(bus.master().projected()),
        ),
        las_at_start,
    };
    (words, window)
}

/// The handshake words and S-7.3 values, timed from the devices' and the PLC's counters.
struct WordTimers {
    floors: Vec<Ticker>,
    display: Ticker,
    panel: Ticker,
    analog: Ticker,
    setpoint: Ticker,
}

impl WordTimers {
    fn new() -> WordTimers {
        WordTimers {
            floors: (0..4).map(|_| Ticker::new(1)).collect(),
            display: Ticker::new(1),
            panel: Ticker::new(1),
            analog: Ticker::new(1),
            // The AC2618's two channels are served in turn: one channel every second value.
            setpoint: Ticker::new(2),
        }
    }

    fn poll(&mut self, rig: &Rig) {
        let now = rig.now();
        let lab = rig.lab();
        for (i, t) in self.floors.iter_mut().enumerate() {
            if let Some(s) = lab.floor(i as u8 + 1) {
                let w = s.engine().words();
                t.poll(w.good() as u64 + w.bad() as u64, now);
            }
        }
        if let Some(d) = lab.cabin_display() {
            let w = d.engine().words();
            self.display.poll(w.good() as u64 + w.bad() as u64, now);
        }
        // The cabin word as the PLC receives it: only the built-in program counts it.
        if let Some(plc) = rig.plc() {
            let w = plc.cabin_panel().words();
            self.panel.poll(w.good() as u64 + w.bad() as u64, now);
        }
        if let Some(a) = lab.analog_output() {
            self.analog.poll(a.values_received() as u64, now);
            self.setpoint.poll(a.values_received() as u64, now);
        }
    }

    /// The simulated periods, ms (the analytic values are the formula's, set later).
    fn figures(&self) -> LabTiming {
        let mut floor_words = Summary::default();
        for t in &self.floors {
            floor_words.merge(&t.intervals);
        }
        LabTiming {
            analog_value_ms: self.analog.intervals.figure(1e-6),
            setpoint_refresh_ms: self.setpoint.intervals.figure(1e-6),
            floor_word_ms: floor_words.figure(1e-6),
            cabin_display_word_ms: self.display.intervals.figure(1e-6),
            cabin_panel_word_ms: self.panel.intervals.figure(1e-6),
            ..LabTiming::default()
        }
    }
}
