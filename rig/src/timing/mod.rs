//! `asi-lift timing`: the timing analysis of SPEC §7 for the lab bus, a bus of N standard
//! slaves or 62 A/B slaves, analytic and simulated side by side.
//!
//! **Analytic.** One transaction is request + master pause + response + slave pause (154 µs
//! with the default [`BusTiming`], SPEC §1). The seed's cycle is T = (n + 2) · 154 µs for n
//! slaves (seed 003 §2.1). The model's own cycle (SPEC §2) is one transaction per LAS slot, one
//! management call, and one inclusion call while an address is left to include:
//! (slots + 2) · 154 µs, or (slots + 1) · 154 µs with every address used; an address holding an
//! A and a B slave is one slot serving them in alternate cycles, so each of them sees twice the
//! cycle.
//!
//! **Error model.** The line noise is asi-phy's seeded [`FaultRates::uniform`]`(p)`: each pulse
//! is dropped, flipped, shifted or followed by a spurious pulse with probability p/4 each, drawn
//! independently, so a pulse comes through untouched with probability c = (1 − p/4)⁴. Every
//! single pulse fault fails one of the seven receiver checks (asi-phy's exhaustive test), and a
//! corrupt request gets no answer, so a transaction of m request and s response pulses fails
//! with q = 1 − c^(m+s). A failure is repeated once at once (SPEC §2), so the expected number
//! of repeats per cycle is Σ q over the cycle's transactions that expect an answer, each repeat
//! costing one transaction time; a corrupt response also delays the next request by the
//! asynchronous pause minus the slave pause (18 − 10 = 8 µs, asi-master `bus`). The pulse
//! counts depend on the bits, so the expectation is summed over the telegrams actually sent
//! (the first tries; [`PulseTrain`] counts their pulses), which also gives its variance: the
//! simulated repeat count and mean cycle are compared with it in standard errors.
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
//! drops, and K1 opens after the STOP delay (SPEC §6); the cabin stops at the floor it was
//! heading for, and a cabin request there restarts the STOP circuit for the next sample. So one
//! trip gives one sample of each chain.

mod bus;
mod collector;
mod error_model;
mod lab;
mod options;
mod render;
mod report;
mod stats;
#[cfg(test)]
mod tests;

pub use error_model::ErrorModel;
pub use options::{BusChoice, TimingError, TimingOptions, MAX_DURATION, MAX_SAMPLES};
pub use report::{HallSample, LabTiming, Latencies, Repeats, StopSample, TimingReport};
pub use stats::{Figure, Histogram};

use asi_phy::BusTiming;
use bus::run_plain;
use lab::run_lab;
use stats::{histogram, Summary};

// ----- the analysis -------------------------------------------------------------------------

/// Runs the analysis for `opts`.
pub fn analyse(opts: &TimingOptions) -> Result<TimingReport, TimingError> {
    opts.check()?;
    let timing = BusTiming::default();
    let (c, window, lab) = match opts.bus {
        BusChoice::Lab { extra } => {
            let (c, w, lab) = run_lab(opts, extra)?;
            (c, w, Some(lab))
        }
        _ => {
            let (c, w) = run_plain(opts)?;
            (c, w, None)
        }
    };
    let tx_us = timing.transaction().as_micros_f64();
    let n = opts.bus.slaves();
    let slots = opts.bus.slots();
    let inclusion = slots < 31;
    let model_us = (slots + 1 + inclusion as u32) as f64 * tx_us;
    let per_slave = if opts.bus == BusChoice::AbPairs {
        2.0
    } else {
        1.0
    };
    let cycles = c.cycles.len() as u64;
    let cycle_values: Vec<f64> = c.cycles.iter().map(|&ns| ns as f64 / 1e3).collect();
    let mut cycle_sum = Summary::default();
    for v in &cycle_values {
        cycle_sum.add(*v);
    }
    let e = c.expect;
    let noisy = opts.pulse_error_rate > 0.0;
    // The clean cycles' transactions (the model's formula, unless slaves dropped out) plus
    // the error model's expected extra time.
    let expected_cycle = if cycles > 0 {
        (c.first_tries as f64 * tx_us * 1e3 + e.extra_ns) / cycles as f64 / 1e3
    } else {
        model_us
    };
    // Both tries failing leaves a Data_Exchange without update.
    let both_fail = if e.dx > 0 { e.dx_q2 / e.dx as f64 } else { 0.0 };
    let transactions = c.first_tries + c.repeats;
    let repeats = Repeats {
        count: c.repeats,
        expected: e.repeats,
        standard_error: e.repeats_var.sqrt(),
        per_cycle: Figure {
            mean: (cycles > 0).then(|| c.repeats as f64 / cycles as f64),
            samples: cycles,
            ..Figure::default()
        }
        .analytic(if cycles > 0 {
            e.repeats / cycles as f64
        } else {
            0.0
        }),
        fraction: Figure {
            mean: (transactions > 0).then(|| c.repeats as f64 / transactions as f64),
            samples: transactions,
            ..Figure::default()
        }
        .analytic(if c.first_tries > 0 {
            e.repeats / (c.first_tries as f64 + e.repeats)
        } else {
            0.0
        }),
        failed_after_repeat: window.failed_after_repeat,
        dropouts: window.dropouts,
    };
    let error_model = noisy.then(|| ErrorModel {
        pulse_clean: c.noise.clean,
        mean_pulses: if e.answered > 0 {
            e.pulses / e.answered as f64
        } else {
            0.0
        },
        mean_fail_probability: if e.answered > 0 {
            e.q / e.answered as f64
        } else {
            0.0
        },
        cycle_mean_standard_error_us: if cycles > 0 {
            e.extra_var.sqrt() / cycles as f64 / 1e3
        } else {
            0.0
        },
    });
    let lab = lab.map(|mut l| {
        let t_ms = expected_cycle / 1e3;
        let tx_ms = tx_us / 1e3;
        let scan = l.plc_scan_ms;
        // A handshake step: the PLC's answer leaves in the next Data_Exchange with the slave
        // (within one cycle), the slave's next code comes back in the one after and reaches
        // the image at its end; the PLC sees it in the next scan. While 2T + 154 µs ≤ scan
        // every step takes one scan; beyond, a fraction (2T + 154 µs − scan)/T of them two.
        let late = ((2.0 * t_ms + tx_ms - scan) / t_ms).clamp(0.0, 1.0);
        let step = scan * (1.0 + late);
        l.analog_value_ms = l.analog_value_ms.analytic(7.0 * t_ms / (1.0 - both_fail));
        l.setpoint_refresh_ms = l
            .setpoint_refresh_ms
            .analytic(14.0 * t_ms / (1.0 - both_fail));
        l.floor_word_ms = l.floor_word_ms.analytic(4.0 * step);
        l.cabin_display_word_ms = l.cabin_display_word_ms.analytic(7.0 * step);
        l.cabin_panel_word_ms = l.cabin_panel_word_ms.analytic(14.0 * step);
        // The bounds hold without line errors (a repeat or a lost exchange adds to them).
        let cycle_ms = model_us / 1e3;
        let step_max = scan * ((2.0 * cycle_ms + tx_ms) / scan).ceil();
        let lat = &mut l.latencies;
        // Pressed just after the floor slave finished a word, the call waits for the next
        // word (4 steps) and is reported as one extra step: its first code reaches the image
        // one cycle later and the PLC's next scan answers it, then one step per scan.
        let reg = cycle_ms + tx_ms + scan + 4.0 * step_max;
        lat.press_to_registered_ms = lat.press_to_registered_ms.clone().bound(reg);
        // The run bit leaves in the next Data_Exchange with the converter: within one cycle.
        lat.registered_to_run_bit_ms = lat.registered_to_run_bit_ms.clone().bound(cycle_ms);
        lat.press_to_run_bit_ms = lat.press_to_run_bit_ms.clone().bound(reg + cycle_ms);
        // STOP is read by the next safety scan; EStopDelOut follows after the STOP delay.
        let safety_scan = l.safety_scan_ms;
        lat.stop_to_estop_out_ms = lat.stop_to_estop_out_ms.clone().bound(safety_scan);
        lat.estop_out_to_k1_open_ms = lat
            .estop_out_to_k1_open_ms
            .clone()
            .analytic(l.stop_delay_ms);
        lat.stop_to_k1_open_ms = lat
            .stop_to_k1_open_ms
            .clone()
            .bound(l.stop_delay_ms + safety_scan);
        l
    });
    Ok(TimingReport {
        bus: opts.bus.describe(),
        slaves: n,
        slots,
        inclusion_call: inclusion,
        pulse_error_rate: opts.pulse_error_rate,
        seed: opts.seed,
        window_s: opts.duration.as_secs_f64(),
        cycles,
        transactions,
        transaction_us: c.spacing.figure(1e-3).analytic(tx_us),
        seed_cycle_us: (n + 2) as f64 * tx_us,
        cycle_us: cycle_sum.figure(1.0).analytic(expected_cycle),
        cycle_histogram: histogram(&cycle_values, 1.0, 40),
        slave_update_us: c
            .update
            .figure(1e-3)
            .analytic(per_slave * expected_cycle / (1.0 - both_fail)),
        repeats,
        error_model,
        lab,
    })
}
