//! The analysis end to end: clean buses against the formula, noisy ones against the error
//! model, the lab bus, the options and the outputs.

use super::*;
use asi_phy::SimDuration;

fn opts(bus: BusChoice, p: f64, secs: u64, samples: u32) -> TimingOptions {
    TimingOptions {
        bus,
        pulse_error_rate: p,
        seed: 7,
        duration: SimDuration::from_secs(secs),
        samples,
        program: None,
    }
}

fn exact(f: &Figure, v: f64) {
    assert!(f.samples > 0, "{f:?}");
    for x in [f.analytic, f.min, f.mean, f.max] {
        let x = x.unwrap_or(f64::NAN);
        assert!((x - v).abs() < 1e-6, "{f:?} != {v}");
    }
}

/// Without errors every cycle is the model's formula (docs/master.md), which is the lift thesis'
/// (n + 2) · 154 µs wherever an inclusion address is left; 31 slaves leave none.
#[test]
fn clean_buses_run_the_model_formula_exactly() {
    for (bus, model, seed) in [
        (BusChoice::Standard { n: 1 }, 3.0 * 154.0, 3.0 * 154.0),
        (BusChoice::Standard { n: 17 }, 19.0 * 154.0, 19.0 * 154.0),
        (BusChoice::Standard { n: 30 }, 32.0 * 154.0, 32.0 * 154.0),
        (BusChoice::Standard { n: 31 }, 32.0 * 154.0, 33.0 * 154.0),
        (BusChoice::AbPairs, 32.0 * 154.0, 64.0 * 154.0),
    ] {
        let r = analyse(&opts(bus, 0.0, 1, 0)).expect("analysis");
        exact(&r.transaction_us, 154.0);
        exact(&r.cycle_us, model);
        assert_eq!(r.thesis_cycle_us, seed);
        assert!(r.cycles > 150, "{bus:?}: {}", r.cycles);
        assert_eq!(r.repeats.count, 0);
        assert_eq!(r.repeats.expected, 0.0);
        assert_eq!(r.cycle_histogram.counts.iter().sum::<u64>(), r.cycles);
        // Each slave is served every cycle, an A/B slave every second one: 64 · 154 µs,
        // the lift thesis' formula for 62 slaves (≤ 10 ms).
        let per_slave = if bus == BusChoice::AbPairs { 2.0 } else { 1.0 };
        exact(&r.slave_update_us, per_slave * model);
    }
}

/// The lab bus in the whole rig: 13 · 154 = 2002 µs; one S-7.3 value every 7 cycles; the
/// handshake words take one PLC scan per step; the latencies keep their bounds.
#[test]
fn the_lab_bus_without_errors() {
    let r = analyse(&opts(BusChoice::Lab { extra: 0 }, 0.0, 2, 3)).expect("analysis");
    exact(&r.cycle_us, 2002.0);
    assert_eq!(r.thesis_cycle_us, 2002.0);
    exact(&r.slave_update_us, 2002.0);
    let lab = r.lab.expect("lab figures");
    exact(&lab.analog_value_ms, 7.0 * 2.002);
    exact(&lab.setpoint_refresh_ms, 14.0 * 2.002);
    for (f, steps) in [
        (&lab.floor_word_ms, 4.0),
        (&lab.cabin_display_word_ms, 7.0),
        (&lab.cabin_panel_word_ms, 14.0),
    ] {
        let mean = f.mean.expect("words");
        assert!((mean - steps * 10.0).abs() < 0.1, "{f:?}");
        // A word ends at a Data_Exchange: up to a cycle either side of the scan grid.
        assert!(f.min.unwrap_or(0.0) >= steps * 10.0 - 2.002 - 1e-6, "{f:?}");
        assert!(
            f.max.unwrap_or(f64::MAX) <= steps * 10.0 + 2.002 + 1e-6,
            "{f:?}"
        );
    }
    let lat = &lab.latencies;
    assert_eq!(
        (lat.hall.len(), lat.stop.len()),
        (3, 3),
        "{:?}",
        lat.incomplete
    );
    assert_eq!(lat.operator_resets, 0);
    within_bounds(lat);
    // STOP reaches EStopOut at the next safety scan; K1 opens exactly the STOP delay later.
    exact(&lat.estop_out_to_k1_open_ms, 9100.0);
}

fn within_bounds(lat: &Latencies) {
    for f in [
        &lat.press_to_registered_ms,
        &lat.registered_to_run_bit_ms,
        &lat.press_to_run_bit_ms,
        &lat.stop_to_estop_out_ms,
        &lat.stop_to_k1_open_ms,
    ] {
        let bound = f.bound.expect("a bound");
        assert!(f.samples > 0);
        assert!(f.min.unwrap_or(-1.0) >= 0.0, "{f:?}");
        assert!(f.max.unwrap_or(f64::MAX) <= bound + 1e-9, "{f:?}");
    }
    // Registering takes at least the extra code's trip through the image.
    assert!(lat.press_to_registered_ms.min.unwrap_or(0.0) > 0.154);
}

/// The lab lift on a full bus (20 extra modules, 31 slaves): 32 · 154 µs, an S-7.3 value
/// every 7 · 4.928 ms; the same seed gives the same samples.
#[test]
fn the_lab_lift_on_a_full_bus_is_deterministic() {
    let o = opts(BusChoice::Lab { extra: 20 }, 0.0, 1, 2);
    let r = analyse(&o).expect("analysis");
    exact(&r.cycle_us, 32.0 * 154.0);
    let lab = r.lab.clone().expect("lab figures");
    exact(&lab.analog_value_ms, 7.0 * 4.928);
    within_bounds(&lab.latencies);
    let again = analyse(&o).expect("analysis");
    assert_eq!(r, again);
    let other = analyse(&TimingOptions { seed: 8, ..o }).expect("analysis");
    assert_ne!(
        lab.latencies.hall,
        other.lab.expect("lab figures").latencies.hall
    );
}

/// With line noise the repeat count and the mean cycle lie within 5 standard errors of the
/// error model's expectation (docs/timing.md: "within statistical bounds").
#[test]
fn noisy_buses_agree_with_the_error_model() {
    for (bus, p, secs) in [
        (BusChoice::Standard { n: 31 }, 0.002, 10),
        (BusChoice::Standard { n: 3 }, 0.001, 10),
        (BusChoice::AbPairs, 0.002, 10),
        (BusChoice::Lab { extra: 0 }, 0.002, 4),
    ] {
        let r = analyse(&opts(bus, p, secs, 0)).expect("analysis");
        let rep = &r.repeats;
        assert!(rep.count > 500, "{bus:?}: {rep:?}");
        let z = (rep.count as f64 - rep.expected) / rep.standard_error;
        assert!(z.abs() < 5.0, "{bus:?}: repeats z = {z}: {rep:?}");
        let m = r.error_model.as_ref().expect("error model");
        let z = (r.cycle_us.mean.unwrap_or(0.0) - r.cycle_us.analytic.unwrap_or(0.0))
            / m.cycle_mean_standard_error_us;
        assert!(z.abs() < 5.0, "{bus:?}: cycle z = {z}: {:?}", r.cycle_us);
        // The fraction of repeats follows from the same expectation.
        let f = &rep.fraction;
        let (a, s) = (f.analytic.unwrap_or(0.0), f.mean.unwrap_or(1.0));
        assert!(
            (a - s).abs() < 5.0 * rep.standard_error / r.transactions as f64,
            "{f:?}"
        );
        // Most cycles are still the clean one; a repeat adds a transaction or more.
        let clean = (r.slots + 1 + r.inclusion_call as u32) as f64 * 154.0;
        assert_eq!(r.cycle_us.min, Some(clean), "{bus:?}");
        assert!(r.cycle_us.max.unwrap_or(0.0) >= clean + 154.0, "{bus:?}");
    }
}

#[test]
fn options_are_checked() {
    assert_eq!("lab".parse(), Ok(BusChoice::Lab { extra: 0 }));
    assert_eq!("62ab".parse(), Ok(BusChoice::AbPairs));
    assert_eq!("31".parse(), Ok(BusChoice::Standard { n: 31 }));
    for bad in ["0", "32", "62", "x", "-1", ""] {
        assert!(bad.parse::<BusChoice>().is_err(), "{bad}");
    }
    let ok = TimingOptions::default();
    assert!(ok.check().is_ok());
    for bad in [
        TimingOptions {
            pulse_error_rate: 1.0,
            ..ok.clone()
        },
        TimingOptions {
            pulse_error_rate: -0.1,
            ..ok.clone()
        },
        TimingOptions {
            pulse_error_rate: f64::NAN,
            ..ok.clone()
        },
        TimingOptions {
            bus: BusChoice::Lab { extra: 21 },
            ..ok.clone()
        },
        TimingOptions {
            bus: BusChoice::Standard { n: 0 },
            ..ok.clone()
        },
        TimingOptions {
            duration: SimDuration::ZERO,
            ..ok.clone()
        },
    ] {
        assert!(
            matches!(analyse(&bad), Err(AnalysisError::Option { .. })),
            "{bad:?}"
        );
    }
}

#[test]
fn the_outputs_show_every_figure() {
    let r = analyse(&opts(BusChoice::Standard { n: 4 }, 0.001, 1, 0)).expect("analysis");
    let text = r.to_text();
    for want in [
        "transaction",
        "thesis: T = (n + 2)",
        "per-slave",
        "error model",
    ] {
        assert!(text.contains(want), "{text}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&r.to_json().expect("serialises")).expect("json");
    assert_eq!(json["cycle_us"]["analytic"].as_f64(), r.cycle_us.analytic);
    // The formula applies: no note, and the JSON has no such field.
    assert_eq!(r.model_note, None);
    assert!(json.get("model_note").is_none());
    let svg = r.to_svg();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
}

/// Slaves that drop out change the LAS, so the cycle formula does not apply: the report says so
/// instead of giving a model value for the cycle and what follows from it.
#[test]
fn drop_outs_leave_the_cycle_without_a_model_value() {
    let r = analyse(&opts(BusChoice::Standard { n: 3 }, 0.01, 2, 0)).expect("analysis");
    assert!(r.repeats.dropouts > 0, "{:?}", r.repeats);
    assert_eq!(r.cycle_us.analytic, None);
    assert_eq!(r.slave_update_us.analytic, None);
    assert_eq!(r.repeats.per_cycle.analytic, None);
    assert!(r.cycle_us.mean.is_some());
    let note = r.model_note.clone().expect("a note");
    assert!(note.contains("drop-out"), "{note}");
    assert!(r.to_text().contains(&format!("model: {note}")));
    let json: serde_json::Value =
        serde_json::from_str(&r.to_json().expect("serialises")).expect("json");
    assert_eq!(json["model_note"].as_str(), Some(note.as_str()));
    assert!(json["cycle_us"]["analytic"].is_null());
}
