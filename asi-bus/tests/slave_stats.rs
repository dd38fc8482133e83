//! The statistics per slave as the bus counts them (docs/master.md, "Statistics per slave"):
//! on a noisy line they add up to the bus totals and agree with what a passive analyser works
//! out from the trace; a slave taken off the bus turns red and back to green after the hold
//! time; the codes seen in the traffic are the projected ones.

use crate::common::*;
use asi_bus::lab::LabLift;
use asi_master::slave_stats::{judged_error, RecordTally, NO_SLAVE};
use asi_master::{BusStats, Light, LightRule, TransactionRecord};
use asi_phy::{Check, FaultRates, SimDuration, SimTime};
use std::sync::{Arc, Mutex};

/// The lab bus running at 40 ms with every trace record collected by a callback.
fn collected_lab() -> (LabLift, Arc<Mutex<Vec<TransactionRecord>>>) {
    let mut lab = LabLift::new().expect("lab");
    let all = Arc::new(Mutex::new(Vec::new()));
    let sink = Arc::clone(&all);
    lab.bus_mut()
        .set_trace_callback(Some(Box::new(move |r: &TransactionRecord| {
            sink.lock().expect("trace").push(*r);
        })));
    lab.bus_mut().advance_to(ms(40));
    assert!(lab.bus().is_running());
    (lab, all)
}

#[test]
fn on_a_noisy_line_the_slaves_add_up_to_the_bus_totals() {
    let (mut lab, all) = collected_lab();
    lab.bus_mut().set_line_faults(
        7,
        FaultRates::uniform(asi_phy::PulseErrorRate::new(0.002).expect("a probability")),
    );
    lab.bus_mut().advance_to(ms(3_040));
    let bus = lab.bus().stats();
    let table = lab.bus().slave_stats();
    let trace = all.lock().expect("trace").clone();
    assert!(bus.repeats > 100, "{bus}");
    let classes = Check::ALL.iter().filter(|&&c| bus.errors(c) > 0).count();
    assert!(classes >= 4, "{bus}");

    // Sums over the slaves, field by field.
    let sum =
        |f: &dyn Fn(&asi_master::SlaveStats) -> u64| table.iter().map(|(_, s)| f(s)).sum::<u64>();
    assert_eq!(sum(&|s| s.calls), bus.transactions);
    assert_eq!(sum(&|s| s.repeats), bus.repeats);
    assert_eq!(sum(&|s| s.failed_after_repeat), bus.failed_after_repeat);
    assert_eq!(sum(&|s| s.no_response), bus.no_response);
    for c in Check::ALL {
        assert_eq!(sum(&|s| s.errors(c)), bus.errors(c), "{c:?}");
        assert_eq!(
            sum(&|s| s.request_errors[c as usize]),
            bus.request_errors[c as usize]
        );
    }
    // Every transaction of the trace is one call, and the bus counted them all.
    assert_eq!(trace.len() as u64, bus.transactions);
    // The same counts, worked out from the records as a listener would: the verdicts from
    // the responses and the repeats that follow.
    let mut from_records = BusStats::default();
    for (i, r) in trace.iter().enumerate() {
        let error = judged_error(r);
        let repeated = trace.get(i + 1).is_some_and(|n| n.repeat);
        from_records.record(r, error, error && repeated);
    }
    let counted = BusStats {
        dropouts: 0,
        cycles: 0,
        cycle_min: SimDuration::ZERO,
        cycle_max: SimDuration::ZERO,
        cycle_total: SimDuration::ZERO,
        ..bus
    };
    assert_eq!(from_records, counted);
    let mut listener = RecordTally::new(LightRule::default());
    for r in &trace {
        listener.push(*r);
    }
    let heard = listener.finish(lab.bus().now());
    for ((i, s), (_, h)) in table.iter().zip(heard.iter()) {
        assert_eq!(
            (s.calls, s.repeats, s.first_try_ok(), s.single_errors()),
            (h.calls, h.repeats, h.first_try_ok(), h.single_errors()),
            "place {i}"
        );
        assert_eq!(
            (s.consecutive_errors, s.request_errors, s.response_errors),
            (h.consecutive_errors, h.request_errors, h.response_errors),
            "place {i}"
        );
    }
    // Each of the eleven slaves had its share of the noise, and the noise was no worse than
    // the repeats put right: no slave dropped out.
    for n in [1u8, 2, 3, 4, 5, 6, 7, 8, 10, 11, 12] {
        let s = table.get(n).expect("slave");
        assert!(s.repeats > 0, "slave {n}: {s:?}");
        assert!(s.single_errors() > 0, "slave {n}: {s:?}");
        assert_eq!(s.dropouts, 0);
        assert!(s.light.is_some(), "slave {n}");
    }
    assert_eq!(table.get(NO_SLAVE).map(|s| s.calls), Some(0));
}

#[test]
fn a_slave_taken_off_the_bus_turns_red_and_back_to_green_after_the_hold_time() {
    let hold = SimDuration::from_secs(3);
    let mut lab = LabLift::new().expect("lab");
    lab.bus_mut().set_light_rule(LightRule {
        hold,
        ..LightRule::default()
    });
    let light = |lab: &LabLift, n: u8| lab.bus().slave_stats().get(n).and_then(|s| s.light);
    lab.bus_mut().advance_to(ms(2_000));
    assert_eq!(light(&lab, 2), Some(Light::Green));
    let floor2 = lab.slave_id(2).expect("floor 2");
    lab.bus_mut().detach(floor2);
    // The window that ends at 3 s sees it out of LAS.
    lab.bus_mut().advance_to(ms(3_000));
    assert!(!lab.bus().master().las().contains(a(2)));
    assert_eq!(light(&lab, 2), Some(Light::Red));
    assert_eq!(light(&lab, 3), Some(Light::Green), "the others stay green");
    lab.bus_mut().advance_to(ms(5_500));
    lab.bus_mut().attach(floor2);
    // Back in LAS within a few cycles; still red: the hold time runs from the last window
    // that saw it out of LAS, the one that ended at 5 s.
    let mut back = None;
    while back.is_none() {
        let t = lab.bus().poll_at();
        lab.bus_mut().advance_to(t);
        if lab.bus().master().las().contains(a(2)) {
            back = Some(t);
        }
    }
    let back = back.expect("back");
    assert!(back < ms(5_700), "{back}");
    lab.bus_mut().advance_to(ms(6_000));
    assert_eq!(light(&lab, 2), Some(Light::Red));
    lab.bus_mut().advance_to(ms(7_999));
    assert_eq!(light(&lab, 2), Some(Light::Red));
    lab.bus_mut().advance_to(ms(8_000));
    assert_eq!(light(&lab, 2), Some(Light::Green));
    let s = lab.bus().slave_stats().get(2).copied().expect("slave 2");
    assert_eq!(s.worst_light, Some(Light::Red));
    assert_eq!(s.dropouts, 1);
    assert_eq!(lab.bus().stats().dropouts, 1);
    // Out of LAS from the drop-out (a few cycles after 2 s) to its return.
    let out = s.out_of_las.as_secs_f64();
    assert!(out > 3.4 && out < 3.6, "{out}");
    // The failed calls before it dropped: three cycles of a call and its repeat, the
    // repeats failing too (docs/master.md: three failed cycles drop a slave).
    assert_eq!(s.failed_after_repeat, 3);
    assert_eq!(s.single_errors(), 0);
    assert_eq!(s.consecutive_errors, 5);
    assert_eq!(s.longest_error_run, 6);
}

#[test]
fn the_codes_seen_in_the_traffic_are_the_projected_ones() {
    let mut lab = LabLift::new().expect("lab");
    lab.bus_mut().advance_to(ms(200));
    let table = lab.bus().slave_stats();
    let projected = lab.bus().master().projected().clone();
    for a in lab.bus().master().lps().iter() {
        let seen = table.get(a.index()).expect("slave").seen;
        assert_eq!(seen.codes(), Some(projected.codes(a)), "slave {a}");
    }
    // Empty addresses answer nothing and take no part, however often they are probed.
    let nine = table.get(9).expect("address 9");
    assert!(nine.calls > 0);
    assert!(!nine.takes_part());
    assert!(nine.seen.is_empty());
    assert!(nine.light.is_none());
}

#[test]
fn a_power_fail_turns_every_slave_red() {
    let mut lab = LabLift::new().expect("lab");
    lab.bus_mut().advance_to(ms(1_500));
    lab.bus_mut().set_supply_voltage(0.0);
    lab.bus_mut().advance_to(ms(2_500));
    let table = lab.bus().slave_stats();
    for a in lab.bus().master().lps().iter() {
        let s = table.get(a.index()).expect("slave");
        assert_eq!(s.light, Some(Light::Red), "slave {a}");
        // Leaving normal operation is no drop-out.
        assert_eq!(s.dropouts, 0);
    }
    assert_eq!(lab.bus().now(), SimTime::from_millis(2_500));
}
