//! The lab experiment: the whole rig runs for the window (handshake words and S-7.3 values
//! timed from the devices' counters), then the lift shuttles between floors 1 and 2 and every
//! trip gives a hall call sample and a STOP sample at seeded random moments.

use super::bus::READY_WITHIN;
use super::collector::{lock, take, BusWindow, Collector};
use super::options::{TimingError, TimingOptions};
use super::report::{HallSample, LabTiming, Latencies, StopSample};
use super::stats::{figure_of, Summary, Ticker};
use crate::rig::Rig;
use crate::scenario::{Action, Scenario};
use asi_master::lab::CONVERTER;
use asi_phy::{SimDuration, SimTime};
use lift_model::{Button, LoadLevel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::sync::{Arc, Mutex};

/// The lift stands at `floor`, ready to depart: program at the floor without a fault, drive
/// powered and not moving, no STOP demand.
fn ready_at(rig: &Rig, floor: u8) -> bool {
    let p = rig.plc().program();
    let d = p.outputs().display;
    p.is_initialised()
        && !d.moving
        && !d.fault
        && p.current_floor() == floor
        && p.target() == floor
        && !p.outputs().run
        && rig.lift().velocity_mm_s() == 0.0
        && rig.lift().k1_closed()
        && rig.lift().converter_ready()
        && rig.estop_out()
}

/// Steps `rig` until `cond` holds (checked now and after every moment), at most `limit`.
fn wait_until(
    rig: &mut Rig,
    limit: SimDuration,
    mut cond: impl FnMut(&Rig) -> bool,
) -> Option<SimTime> {
    if cond(rig) {
        return Some(rig.now());
    }
    let deadline = rig.now() + limit;
    while let Some(t) = rig.step_until(deadline) {
        if cond(rig) {
            return Some(t);
        }
    }
    None
}

/// How long the operator takes to press the reset after an unexpected trip.
const OPERATOR_REACTION: SimDuration = SimDuration::from_millis(100);

/// [`wait_until`], with the operator resetting a trip that opens K1 without a STOP demand
/// (the Safety-at-Work monitor under line noise); counts the resets in `resets`. Before the
/// program is initialised, only a trip after K1 had closed in this wait counts (at power-on K1
/// is open until the operator's first reset).
fn wait_resetting(
    rig: &mut Rig,
    limit: SimDuration,
    resets: &mut u32,
    mut cond: impl FnMut(&Rig) -> bool,
) -> Option<SimTime> {
    let deadline = rig.now() + limit;
    let mut reset_at: Option<SimTime> = None;
    let mut powered = false;
    loop {
        if cond(rig) {
            return Some(rig.now());
        }
        powered |= rig.lift().k1_closed();
        let tripped = (rig.plc().program().is_initialised() || powered)
            && rig.estop_out()
            && !rig.lift().k1_closed();
        if tripped && reset_at.is_none_or(|t| rig.now() >= t + SimDuration::from_secs(1)) {
            let at = rig.now() + OPERATOR_REACTION;
            rig.schedule(at, Action::Reset);
            reset_at = Some(at);
            *resets += 1;
        }
        rig.step_until(deadline)?;
    }
}

/// Mixed into the options' seed for the press moments ("timing" in ASCII): the line noise is a
/// ChaCha8 stream seeded with the seed itself (asi-phy's `FaultInjector`), and the press moments must
/// not repeat its draws.
const PRESS_STREAM: u64 = 0x7469_6D69_6E67;

/// The seeded source of press moments.
fn press_rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed ^ PRESS_STREAM)
}

/// A uniform duration in [0, span).
fn below(rng: &mut ChaCha8Rng, span: SimDuration) -> SimDuration {
    match span.as_nanos() {
        0 => SimDuration::ZERO,
        n => SimDuration::from_nanos(rng.random_range(0..n)),
    }
}

fn ms(d: SimDuration) -> f64 {
    d.as_nanos() as f64 / 1e6
}

/// How long a wait in the latency sampling may take before sampling gives up.
const STEP_LIMIT: SimDuration = SimDuration::from_secs(60);
const HOLD: SimDuration = SimDuration::from_millis(300);

/// The lab rig: window statistics, then latency samples.
pub(super) fn run_lab(
    opts: &TimingOptions,
    extra: u8,
) -> Result<(Collector, BusWindow, LabTiming), TimingError> {
    let mut sc = Scenario::defaults();
    sc.name = "timing".into();
    sc.seed = opts.seed;
    sc.duration = SimDuration::from_secs(10_000_000);
    sc.start_mm = 0.0;
    sc.load = LoadLevel::Empty;
    sc.door_closed = true;
    sc.pulse_error_rate = opts.pulse_error_rate;
    sc.extra_slaves = extra;
    let plc_scan = sc.plc_scan;
    let mut rig = Rig::new(sc)?;
    let timing = *rig.lab().bus.timing();
    let shared = Arc::new(Mutex::new(Collector::new(
        &timing,
        opts.pulse_error_rate,
        Some(CONVERTER),
    )));
    let sink = Arc::clone(&shared);
    rig.lab_mut()
        .bus
        .set_trace_callback(Some(Box::new(move |r| lock(&sink).record(r))));

    // The Safety-at-Work monitor may trip under line noise during initialisation too: the
    // operator resets it, as during the latency samples.
    let mut init_resets = 0;
    if wait_resetting(&mut rig, READY_WITHIN, &mut init_resets, |r| ready_at(r, 1)).is_none() {
        return Err(TimingError::NotReady {
            what: "the lift did not initialise at floor 1",
            within: READY_WITHIN,
        });
    }

    // The measurement window: the lift stands; the handshakes and the bus run on.
    let start = rig.now();
    lock(&shared).start_window();
    let before = rig.lab().bus.stats();
    let las_at_start = rig.lab().bus.master().las().len();
    let mut floors: Vec<Ticker> = (0..4).map(|_| Ticker::new(1)).collect();
    let mut display = Ticker::new(1);
    let mut panel = Ticker::new(1);
    let mut analog = Ticker::new(1);
    let mut setpoint = Ticker::new(2);
    let poll = |rig: &Rig,
                floors: &mut [Ticker],
                display: &mut Ticker,
                panel: &mut Ticker,
                analog: &mut Ticker,
                setpoint: &mut Ticker| {
        let now = rig.now();
        let lab = rig.lab();
        for (i, t) in floors.iter_mut().enumerate() {
            if let Some(s) = lab.floor(i as u8 + 1) {
                let w = s.engine().words();
                t.poll(w.good() as u64 + w.bad() as u64, now);
            }
        }
        if let Some(d) = lab.cabin_display() {
            let w = d.engine().words();
            display.poll(w.good() as u64 + w.bad() as u64, now);
        }
        let w = rig.plc().cabin_panel().words();
        panel.poll(w.good() as u64 + w.bad() as u64, now);
        if let Some(a) = lab.analog_output() {
            analog.poll(a.values_received() as u64, now);
            setpoint.poll(a.values_received() as u64, now);
        }
    };
    poll(
        &rig,
        &mut floors,
        &mut display,
        &mut panel,
        &mut analog,
        &mut setpoint,
    );
    while rig.step_until(start + opts.duration).is_some() {
        poll(
            &rig,
            &mut floors,
            &mut display,
            &mut panel,
            &mut analog,
            &mut setpoint,
        );
    }
    lock(&shared).end_window();
    let after = rig.lab().bus.stats();

    let mut floor_words = Summary::default();
    for t in &floors {
        floor_words.merge(&t.intervals);
    }
    let safety_cfg = safety::LiftSafetyConfig::default();
    let mut latencies = sample_latencies(&mut rig, &shared, opts);
    latencies.operator_resets += init_resets;
    rig.lab_mut().bus.set_trace_callback(None);
    drop(rig);
    let collector = take(&shared);
    let lab = LabTiming {
        plc_scan_ms: ms(plc_scan),
        safety_scan_ms: ms(safety::SAFETY_SCAN_PERIOD),
        stop_delay_ms: ms(safety_cfg.estop_delay),
        analog_value_ms: analog.intervals.figure(1e-6),
        setpoint_refresh_ms: setpoint.intervals.figure(1e-6),
        floor_word_ms: floor_words.figure(1e-6),
        cabin_display_word_ms: display.intervals.figure(1e-6),
        cabin_panel_word_ms: panel.intervals.figure(1e-6),
        latencies,
    };
    Ok((
        collector,
        BusWindow {
            failed_after_repeat: after.failed_after_repeat - before.failed_after_repeat,
            dropouts: after.dropouts - before.dropouts,
            las_at_start,
        },
        lab,
    ))
}

/// The program has arrived at `floor` (it stands there, possibly in the STOP fault).
fn arrived(rig: &Rig, floor: u8) -> bool {
    let p = rig.plc().program();
    p.current_floor() == floor && matches!(p.state_name(), "at floor" | "STOP fault")
}

/// Notes the first moment the program is seen arrived at `floor`.
fn track(rig: &Rig, floor: u8, arrival: &mut Option<SimTime>) {
    if arrival.is_none() && arrived(rig, floor) {
        *arrival = Some(rig.now());
    }
}

/// Shuttles the lift between floors 1 and 2 and times a hall call and a STOP on every trip.
fn sample_latencies(rig: &mut Rig, shared: &Mutex<Collector>, opts: &TimingOptions) -> Latencies {
    let mut rng = press_rng(opts.seed);
    let dwell = rig.plc().program().config().dwell;
    let stop_delay = safety::LiftSafetyConfig::default().estop_delay;
    let mut out = Latencies::default();
    let mut here = 1u8;
    // When the program last arrived at a floor: it departs no earlier than a dwell later.
    let mut arrival = rig.plc().program().initialised_at();
    let fail = |out: &mut Latencies, k: usize, what: &str| {
        out.incomplete = Some(format!(
            "sampling stopped after {k} samples: {what} not seen within {STEP_LIMIT}"
        ));
    };
    for k in 0..opts.samples as usize {
        let there = if here == 1 { 2 } else { 1 };
        let mut resets = 0;
        let ready = wait_resetting(rig, STEP_LIMIT, &mut resets, |r| {
            track(r, here, &mut arrival);
            ready_at(r, here)
        });
        out.operator_resets += resets;
        let Some(ready) = ready else {
            fail(&mut out, k, "the lift ready at its floor");
            break;
        };
        let earliest = ready.max(arrival.unwrap_or(ready) + dwell) + SimDuration::from_millis(100);
        let press = earliest + below(&mut rng, SimDuration::from_millis(500));
        let button = if there == 1 {
            Button::HallUp(1)
        } else {
            Button::HallDown(there)
        };
        rig.schedule(press, Action::Press { button, hold: HOLD });
        // Registered: the program holds the call (as its target or in FIFO_Patra).
        let mut resets = 0;
        let registered = wait_resetting(rig, STEP_LIMIT, &mut resets, |r| {
            let p = r.plc().program();
            r.now() >= press && (p.target() == there || p.fifo_hall().contains(&there))
        });
        let rise = registered.and_then(|registered| {
            wait_resetting(rig, STEP_LIMIT, &mut resets, |_| {
                lock(shared).run_rises.iter().any(|&t| t >= registered)
            })?;
            lock(shared)
                .run_rises
                .iter()
                .copied()
                .find(|&t| t >= registered)
        });
        out.operator_resets += resets;
        let (Some(registered), Some(rise)) = (registered, rise) else {
            fail(
                &mut out,
                k,
                "the hall call registered and the run bit on the bus",
            );
            break;
        };
        // A trip reset on the way held the departure: that sample is not counted.
        if resets == 0 {
            out.hall.push(HallSample {
                pressed_s: press.as_secs_f64(),
                registered_ms: ms(registered - press),
                run_bit_ms: ms(rise - registered),
            });
        }
        arrival = None;

        // STOP during the trip.
        let stop = rise.max(rig.now())
            + SimDuration::from_millis(300)
            + below(&mut rng, SimDuration::from_millis(700));
        rig.schedule(
            stop,
            Action::Press {
                button: Button::Stop,
                hold: HOLD,
            },
        );
        let estop = wait_until(rig, STEP_LIMIT, |r| {
            track(r, there, &mut arrival);
            r.now() >= stop && !r.estop_out()
        });
        let Some(estop) = estop else {
            fail(&mut out, k, "EStopOut off after STOP");
            break;
        };
        // K1 opens when the STOP delay has run out. Opening earlier is a trip the sample did
        // not cause (the Safety-at-Work monitor under line noise): the operator resets it, K1
        // closes again until the delay runs out, and the sample is not counted.
        let mut spoiled = false;
        let k1 = loop {
            let Some(k1) = wait_until(rig, STEP_LIMIT, |r| {
                track(r, there, &mut arrival);
                !r.lift().k1_closed()
            }) else {
                break None;
            };
            if k1 - estop + safety::SAFETY_SCAN_PERIOD >= stop_delay {
                break Some(k1);
            }
            spoiled = true;
            out.operator_resets += 1;
            rig.schedule(k1 + OPERATOR_REACTION, Action::Reset);
            // The STOP delay may run out before the reset takes effect: then K1 stays open.
            let delay_over = estop + stop_delay + safety::SAFETY_SCAN_PERIOD;
            let closed = wait_until(rig, STEP_LIMIT, |r| {
                track(r, there, &mut arrival);
                r.lift().k1_closed() || r.now() >= delay_over
            });
            match closed {
                None => break None,
                Some(t) if !rig.lift().k1_closed() => break Some(t),
                Some(_) => {}
            }
        };
        let Some(k1) = k1 else {
            fail(&mut out, k, "K1 open after STOP");
            break;
        };
        if !spoiled {
            out.stop.push(StopSample {
                pressed_s: stop.as_secs_f64(),
                estop_out_ms: ms(estop - stop),
                k1_open_ms: ms(k1 - estop),
            });
        }
        // The cabin stands at the floor it was heading for (or, after a trip, held short of
        // it): a cabin request for that floor restarts the STOP circuit and service resumes.
        let rest = wait_until(rig, STEP_LIMIT, |r| {
            track(r, there, &mut arrival);
            r.lift().velocity_mm_s() == 0.0
        });
        if rest.is_none() {
            fail(&mut out, k, "the cabin at rest after STOP");
            break;
        }
        rig.schedule(
            rig.now() + OPERATOR_REACTION,
            Action::Press {
                button: Button::Cabin(there),
                hold: HOLD,
            },
        );
        here = there;
    }
    let hall_reg: Vec<f64> = out.hall.iter().map(|s| s.registered_ms).collect();
    let hall_run: Vec<f64> = out.hall.iter().map(|s| s.run_bit_ms).collect();
    let hall_all: Vec<f64> = out
        .hall
        .iter()
        .map(|s| s.registered_ms + s.run_bit_ms)
        .collect();
    let stop_e: Vec<f64> = out.stop.iter().map(|s| s.estop_out_ms).collect();
    let stop_k: Vec<f64> = out.stop.iter().map(|s| s.k1_open_ms).collect();
    let stop_all: Vec<f64> = out
        .stop
        .iter()
        .map(|s| s.estop_out_ms + s.k1_open_ms)
        .collect();
    out.press_to_registered_ms = figure_of(&hall_reg);
    out.registered_to_run_bit_ms = figure_of(&hall_run);
    out.press_to_run_bit_ms = figure_of(&hall_all);
    out.stop_to_estop_out_ms = figure_of(&stop_e);
    out.estop_out_to_k1_open_ms = figure_of(&stop_k);
    out.stop_to_k1_open_ms = figure_of(&stop_all);
    out
}
