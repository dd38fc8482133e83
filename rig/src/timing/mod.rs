//! `asi-lift timing`: the timing analysis of docs/timing.md for the lab bus, a bus of N standard
//! slaves or 62 A/B slaves, analytic and simulated side by side.
//!
//! **Analytic.** One transaction is request + master pause + response + slave pause (154 µs with
//! the default [`BusTiming`], docs/physical-layer.md). The lift thesis' cycle is
//! T = (n + 2) · 154 µs for n slaves (§2.1). The model's own cycle (docs/master.md) is one
//! transaction per LAS slot, one management call, and one inclusion call while an address is left
//! to include: (slots + 2) · 154 µs, or (slots + 1) · 154 µs with every address used; an address
//! holding an A and a B slave is one slot serving them in alternate cycles, so each of them sees
//! twice the cycle. The report's model row is this formula (module `formula`, from asi-phy's
//! [`BusTiming`] parts and the bus's slots), never a simulated count: it agrees with the simulation
//! only because the simulated master keeps the slot rule. Where the LAS changes in the window (a
//! slave drops out) the formula does not apply and the report says so instead of giving a value.
//!
//! **Error model.** The line noise is asi-phy's seeded [`asi_phy::FaultRates::uniform`]`(p)`: each pulse
//! is dropped, flipped, shifted or followed by a spurious pulse with probability p/4 each, drawn
//! independently, so a pulse comes through untouched with probability c = (1 − p/4)⁴. Every
//! single pulse fault fails one of the seven receiver checks (asi-phy's exhaustive test), and a
//! corrupt request gets no answer, so a transaction of m request and s response pulses fails
//! with q = 1 − c^(m+s). A failure is repeated once at once (docs/master.md), so the expected number
//! of repeats per cycle is Σ q over the cycle's transactions that expect an answer, each repeat
//! costing one transaction time; a corrupt response also delays the next request by the
//! asynchronous pause minus the slave pause (18 − 10 = 8 µs, asi-master `bus`). The pulse
//! counts depend on the bits, so the expectation is summed over the telegrams actually sent
//! (the first tries; [`asi_phy::PulseTrain`] counts their pulses), which also gives its variance: the
//! simulated repeat count and mean cycle are compared with it in standard errors. The expected
//! cycle is the clean formula plus (slots + 1) times the mean expected extra time of an answered
//! transaction.
//!
//! **Simulated.** The bus runs (for the lab bus: the whole rig, lift standing at floor 1 after
//! its initialisation) for the measurement window; every transaction record feeds the
//! statistics: cycle times from one first Data_Exchange of a cycle to the next, per-slave update
//! periods between successful Data_Exchanges, repeats. On the lab bus the handshake word times
//! and the S-7.3 value period come from the devices' and the PLC's word counters, stepped
//! moment by moment.
//!
//! **Latencies** (lab bus). After the window the lift shuttles between floors 1 and 2: at a
//! seeded random moment (0..500 ms after it is ready, so uniform against the 10 ms PLC scan, the
//! bus cycle and the handshake words) a hall button at the other floor is pressed; the call is
//! registered when the PLC program holds it (as target or in FIFO_Patra); the converter's run
//! bit is first seen on the bus in the first intact Data_Exchange to address 7 that carries it.
//! 0.3..1 s after the run bit, STOP is pressed at a random moment: the safety logic's EStopOut
//! drops, and K1 opens after the STOP delay (docs/safety.md); the cabin stops at the floor it was
//! heading for, and a cabin request there restarts the STOP circuit for the next sample. So one
//! trip gives one sample of each chain.

mod bus;
mod collector;
mod error_model;
mod formula;
mod lab;
mod latency;
mod options;
mod render;
mod report;
mod stats;
#[cfg(test)]
mod tests;

pub use error_model::ErrorModel;
pub use options::{
    analysable_error_rate, AnalysisError, BusChoice, TimingOptions, MAX_DURATION, MAX_SAMPLES,
};
pub use report::{HallSample, LabTiming, Latencies, Repeats, StopSample, TimingReport};
pub use stats::{Figure, Histogram};

use asi_phy::BusTiming;
use bus::run_plain;
use collector::{BusWindow, Collector};
use error_model::Expect;
use formula::CycleModel;
use lab::run_lab;
use stats::{histogram, Summary};

/// Runs the analysis for `opts`: the bus runs, then the model's figures are set beside the
/// measured ones.
pub fn analyse(opts: &TimingOptions) -> Result<TimingReport, AnalysisError> {
    opts.check()?;
    let model = CycleModel::new(opts.bus, &BusTiming::default());
    let (c, window, lab) = run(opts)?;
    let expected = Expected::new(&model, &c.expect, &window);
    let cycle_values: Vec<f64> = c.cycles.iter().map(|&ns| ns as f64 / 1e3).collect();
    let mut cycle_sum = Summary::default();
    for v in &cycle_values {
        cycle_sum.add(*v);
    }
    let cycles = c.cycles.len() as u64;
    let transactions = c.first_tries + c.repeats;
    let mut slave_update_us = c.update.figure(1e-3);
    slave_update_us.analytic = expected
        .cycle_us
        .map(|t| model.update_us(t, expected.both_fail));
    let mut cycle_us = cycle_sum.figure(1.0);
    cycle_us.analytic = expected.cycle_us;
    Ok(TimingReport {
        bus: opts.bus.describe(),
        slaves: model.slaves,
        slots: model.slots,
        inclusion_call: model.inclusion_call,
        pulse_error_rate: opts.pulse_error_rate,
        seed: opts.seed,
        window_s: opts.duration.as_secs_f64(),
        cycles,
        transactions,
        transaction_us: c.spacing.figure(1e-3).analytic(model.transaction_us),
        thesis_cycle_us: model.thesis_cycle_us(),
        cycle_us,
        cycle_histogram: histogram(&cycle_values, 1.0, 40),
        slave_update_us,
        repeats: repeats(&c, &window, &model, &expected),
        error_model: (opts.pulse_error_rate > 0.0).then(|| error_model(&c)),
        lab: lab.map(|l| lab_analytic(l, &model, &expected)),
        model_note: expected.note,
        per_slave: window.slaves,
    })
}

/// Runs the bus of `opts`: the collector's statistics, the window's drop-outs, and on the lab
/// bus its handshakes and latencies.
fn run(opts: &TimingOptions) -> Result<(Collector, BusWindow, Option<LabTiming>), AnalysisError> {
    Ok(match opts.bus {
        BusChoice::Lab { extra } => {
            let (c, w, lab) = run_lab(opts, extra)?;
            (c, w, Some(lab))
        }
        _ => {
            let (c, w) = run_plain(opts)?;
            (c, w, None)
        }
    })
}

/// The model's figures for a run: the cycle formula and, with line noise, the error model's
/// expectation per answered transaction (from the telegrams sent: their pulse counts are the
/// error model's input). The cycle counts and transaction counts of the run are not used.
struct Expected {
    /// The expected mean cycle, µs; none where the formula does not apply.
    cycle_us: Option<f64>,
    /// The probability that a Data_Exchange fails both tries (no update).
    both_fail: f64,
    /// The mean probability that an answered transaction fails.
    fail_probability: f64,
    /// Why the cycle formula does not apply to this run.
    note: Option<String>,
}

impl Expected {
    fn new(model: &CycleModel, e: &Expect, window: &BusWindow) -> Expected {
        let per_answered = |x: f64| {
            if e.answered > 0 {
                x / e.answered as f64
            } else {
                0.0
            }
        };
        let extra_us = per_answered(e.extra_ns) / 1e3;
        let note = match (window.dropouts, window.las_at_start) {
            (0, las) if las >= model.slaves => None,
            (0, las) => Some(format!(
                "the LAS held {las} of {} slaves when the window began",
                model.slaves
            )),
            (d, _) => Some(format!("{d} slave drop-out(s) in the window")),
        }
        .map(|why| {
            format!(
                "{why}: the cycle formula holds for a constant LAS only, so the cycle, the \
                 update period, the repeats per cycle and the lab's S-7.3 and handshake periods \
                 have no analytic value"
            )
        });
        Expected {
            cycle_us: note.is_none().then(|| model.cycle_us(extra_us)),
            both_fail: if e.dx > 0 { e.dx_q2 / e.dx as f64 } else { 0.0 },
            fail_probability: per_answered(e.q),
            note,
        }
    }
}

/// Repeats counted against the error model: the count against Σ q over the first tries sent,
/// per cycle and as a fraction from the formula.
fn repeats(c: &Collector, window: &BusWindow, model: &CycleModel, x: &Expected) -> Repeats {
    let e = &c.expect;
    let cycles = c.cycles.len() as u64;
    let transactions = c.first_tries + c.repeats;
    // Per cycle only where the cycle formula applies.
    let applies = x.cycle_us.is_some();
    Repeats {
        count: c.repeats,
        expected: e.repeats,
        standard_error: e.repeats_var.sqrt(),
        per_cycle: Figure {
            analytic: applies.then(|| model.repeats_per_cycle(x.fail_probability)),
            mean: (cycles > 0).then(|| c.repeats as f64 / cycles as f64),
            samples: cycles,
            ..Figure::default()
        },
        fraction: Figure {
            analytic: applies.then(|| model.repeat_fraction(x.fail_probability)),
            mean: (transactions > 0).then(|| c.repeats as f64 / transactions as f64),
            samples: transactions,
            ..Figure::default()
        },
        failed_after_repeat: window.failed_after_repeat,
        dropouts: window.dropouts,
    }
}

/// How the error model was evaluated over the telegrams sent.
fn error_model(c: &Collector) -> ErrorModel {
    let e = &c.expect;
    let cycles = c.cycles.len() as u64;
    let per_answered = |x: f64| {
        if e.answered > 0 {
            x / e.answered as f64
        } else {
            0.0
        }
    };
    ErrorModel {
        pulse_clean: c.noise.clean,
        mean_pulses: per_answered(e.pulses),
        mean_fail_probability: per_answered(e.q),
        cycle_mean_standard_error_us: if cycles > 0 {
            e.extra_var.sqrt() / cycles as f64 / 1e3
        } else {
            0.0
        },
    }
}

/// The lab's analytic figures: S-7.3 and handshake periods from the expected cycle, the
/// latencies' bounds from the clean cycle (they hold without line errors: a repeat or a lost
/// exchange adds to them).
fn lab_analytic(mut l: LabTiming, model: &CycleModel, x: &Expected) -> LabTiming {
    let tx_ms = model.transaction_us / 1e3;
    let scan = l.plc_scan_ms;
    if let Some(t_ms) = x.cycle_us.map(|t| t / 1e3) {
        let step = formula::handshake_step_ms(t_ms, tx_ms, scan);
        // One S-7.3 value takes 7 cycles; the AC2618's two channels are served in turn.
        l.analog_value_ms.analytic = Some(7.0 * t_ms / (1.0 - x.both_fail));
        l.setpoint_refresh_ms.analytic = Some(14.0 * t_ms / (1.0 - x.both_fail));
        l.floor_word_ms.analytic = Some(4.0 * step);
        l.cabin_display_word_ms.analytic = Some(7.0 * step);
        l.cabin_panel_word_ms.analytic = Some(14.0 * step);
    }
    let cycle_ms = model.clean_cycle_us() / 1e3;
    let reg = formula::registration_bound_ms(cycle_ms, tx_ms, scan);
    let safety_scan = l.safety_scan_ms;
    let stop_delay = l.stop_delay_ms;
    let lat = &mut l.latencies;
    lat.press_to_registered_ms.bound = Some(reg);
    // The run bit leaves in the next Data_Exchange with the converter: within one cycle.
    lat.registered_to_run_bit_ms.bound = Some(cycle_ms);
    lat.press_to_run_bit_ms.bound = Some(reg + cycle_ms);
    // STOP is read by the next safety scan; EStopDelOut follows after the STOP delay.
    lat.stop_to_estop_out_ms.bound = Some(safety_scan);
    lat.estop_out_to_k1_open_ms.analytic = Some(stop_delay);
    lat.stop_to_k1_open_ms.bound = Some(stop_delay + safety_scan);
    l
}
