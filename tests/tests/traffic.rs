//! Traffic templates on the whole rig: the passengers' calls, the report's `traffic` and its
//! figures checked by hand.

use asi_lift_tests::{run, run_file};
use rig::report::traffic::TripReport;
use rig::scenario::Scenario;

fn up_peak(algorithm: &str) -> Scenario {
    Scenario::from_toml(
        "up-peak.toml",
        &format!(
            "name = \"up-peak\"\nduration = \"10min\"\nalgorithm = \"{algorithm}\"\n\
             [[traffic]]\npattern = \"up-peak\"\nper_minute = 2.0\nseed = 3\nstart = \"15s\"\n"
        ),
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// The ⌈p/100 × n⌉-th smallest of `v`, in whole numbers so that no rounding enters.
fn by_hand(v: &[f64], p: usize) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    let rank = (v.len() * p).div_ceil(100);
    v[rank - 1]
}

#[test]
fn each_passenger_calls_the_cabin_boards_and_is_brought_up() {
    let r = run(up_peak("collective"));
    assert!(r.violations.is_empty(), "{:?}", r.violations);
    let t = r
        .traffic
        .as_ref()
        .expect("a scenario with traffic reports it");
    assert!(
        t.passengers >= 10,
        "{} passengers in 10 min at 2/min",
        t.passengers
    );
    assert_eq!(t.passengers, t.trips.len());
    for p in &t.trips {
        assert_eq!(p.origin, 1, "up-peak enters at floor 1");
        assert!(p.destination > 1);
        // The hall press is the passenger's own, at the origin, in the report's presses.
        assert!(r
            .passengers
            .iter()
            .any(|q| q.button == "hall-up:1" && (q.pressed_at_s - p.hall_pressed_s).abs() < 1e-3));
        let Some(answered) = p.hall_answered_s else {
            continue;
        };
        // A stop at the origin answered the hall call; the cabin press follows 1 s later.
        assert!(r
            .served
            .iter()
            .any(|s| s.floor == 1 && (s.served_at_s - answered).abs() < 1e-3));
        let cabin = p.cabin_pressed_s.expect("aboard, the passenger presses");
        assert!((cabin - answered - 1.0).abs() < 2e-3, "{p:?}");
        if let Some(d) = p.delivered_s {
            assert!(d > cabin);
            assert!(r
                .arrivals
                .iter()
                .any(|a| a.floor == p.destination && (a.at_s - d).abs() < 1.0));
        }
    }
    assert!(t.delivered > 0 && t.delivered <= t.boarded && t.boarded <= t.passengers);
}

#[test]
fn the_percentiles_are_the_nearest_rank_by_hand() {
    let r = run(up_peak("fifo"));
    let t = r.traffic.expect("traffic");
    let times = |f: &dyn Fn(&TripReport) -> Option<f64>| -> Vec<f64> {
        t.trips.iter().filter_map(f).collect()
    };
    let hall = times(&|p| Some(p.hall_answered_s? - p.hall_pressed_s));
    let cabin = times(&|p| Some(p.delivered_s? - p.cabin_pressed_s?));
    let journey = times(&|p| Some(p.delivered_s? - p.hall_pressed_s));
    for (name, v, got) in [
        ("hall", &hall, &t.waiting.hall),
        ("cabin", &cabin, &t.waiting.cabin),
        ("journey", &journey, &t.journey),
    ] {
        assert!(v.len() >= 5, "{name}: {} answered", v.len());
        assert_eq!(got.count, v.len(), "{name}");
        let close = |a: Option<f64>, b: f64| (a.expect("some") - b).abs() < 2e-3;
        assert!(close(got.p95_s, by_hand(v, 95)), "{name}: {got:?}");
        assert!(close(got.max_s, by_hand(v, 100)), "{name}: {got:?}");
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        assert!(close(got.mean_s, mean), "{name}: {got:?} against {mean}");
    }
    // The handling capacity's mean: delivered per 300 s over the traffic's span (15 s to the
    // end).
    let span = 600.0 - 15.0;
    let per5 = t.delivered as f64 * 300.0 / span;
    assert!((t.handling_capacity.mean_per_5min - per5).abs() < 1e-3);
    assert_eq!(t.handling_capacity.span_s, span);
}

#[test]
fn the_same_scenario_gives_the_same_passengers_and_report() {
    let a = run(up_peak("fifo"));
    let b = run(up_peak("fifo"));
    assert_eq!(a, b);
    // Another seed of the scenario moves passengers drawn from it, not those of a template
    // with its own seed.
    let mut other = up_peak("fifo");
    other.seed += 1;
    assert_eq!(
        run(other).traffic.map(|t| t.trips.len()),
        a.traffic.map(|t| t.trips.len())
    );
}

#[test]
fn the_json_has_traffic_only_with_templates() {
    let json = run(up_peak("collective")).to_json().expect("json");
    let v: serde_json::Value = serde_json::from_str(&json).expect("parses");
    let t = &v["traffic"];
    for key in ["passengers", "boarded", "delivered", "trips"] {
        assert!(!t[key].is_null(), "traffic.{key}");
    }
    for kind in ["hall", "cabin"] {
        for key in ["count", "unanswered", "mean_s", "p95_s", "max_s"] {
            assert!(
                t["waiting"][kind].get(key).is_some(),
                "traffic.waiting.{kind}.{key}"
            );
        }
    }
    assert!(t["journey"]["p95_s"].is_number());
    for key in ["mean_per_5min", "peak_per_5min", "span_s"] {
        assert!(t["handling_capacity"][key].is_number(), "{key}");
    }
    let trip = &t["trips"][0];
    for key in [
        "origin",
        "destination",
        "hall_pressed_s",
        "hall_answered_s",
        "cabin_pressed_s",
        "delivered_s",
    ] {
        assert!(trip.get(key).is_some(), "traffic.trips[0].{key}");
    }
    let demo = run_file("demo").to_json().expect("json");
    assert!(!demo.contains("\"traffic\""), "no templates, no traffic");
}
