//! Snapshots of the bus trace (its text form, as `asi-lift run --trace` writes it) at the
//! moments users study: a floor call from the press to the cabin's arrival, a STOP, a
//! corrupted transaction and its repeat, a slave dropping out and returning. Runs of seconds
//! give thousands of transactions, so each snapshot keeps the telegrams of the slaves involved
//! and, of their data exchanges, only those whose outputs or inputs changed.
//! (`INSTA_UPDATE=always cargo test -p asi-lift-tests --test traces`, then read the .snap.)

use asi_lift_tests::*;
use asi_master::record::TransactionRecord;
use asi_phy::{Call, SimDuration, SimTime};
use lift_model::Button;
use rig::report::Report;
use rig::rig::Rig;
use rig::scenario::{Action, Scenario, ScenarioEvent};
use std::cell::RefCell;
use std::rc::Rc;

/// Runs `sc` and returns its report and every bus transaction.
fn traced(sc: Scenario) -> (Report, Vec<TransactionRecord>) {
    let records = Rc::new(RefCell::new(Vec::new()));
    let sink = records.clone();
    let mut rig = Rig::new(sc).expect("rig");
    rig.on_transaction(Box::new(move |r| sink.borrow_mut().push(*r)));
    let report = rig.run(None);
    let records = records.take();
    (report, records)
}

/// Two observers of one run (the live view's and an application's) each get every
/// transaction, in order: adding the second does not take the first one's place.
#[test]
fn every_observer_gets_every_transaction() {
    let sc = Scenario {
        duration: SimDuration::from_secs(2),
        ..Scenario::defaults()
    };
    let (_, alone) = traced(sc.clone());
    let first = Rc::new(RefCell::new(Vec::new()));
    let second = Rc::new(RefCell::new(Vec::new()));
    let mut rig = Rig::new(sc).expect("rig");
    for list in [&first, &second] {
        let sink = Rc::clone(list);
        rig.on_transaction(Box::new(move |r| sink.borrow_mut().push(*r)));
    }
    rig.run(None);
    assert!(alone.len() > 10_000, "{} transactions", alone.len());
    assert_eq!(*first.borrow(), alone);
    assert_eq!(*second.borrow(), alone);
}

fn at(s: f64) -> SimTime {
    SimTime::ZERO + SimDuration::from_secs_f64(s).expect("time")
}

/// The data exchanges within `from..to` with one of `addresses` whose outputs or inputs differ
/// from the slave's last ones (for plain I/O slaves, whose nibbles change only with what they
/// carry), and every failed or repeated one.
fn changes(records: &[TransactionRecord], addresses: &[u8], from: SimTime, to: SimTime) -> String {
    let mut last: [Option<(u8, Option<u8>)>; 32] = [None; 32];
    let mut out = String::new();
    for r in records {
        let a = r.request.address().get();
        let Call::DataExchange { data, .. } = r.request.call() else {
            continue;
        };
        if !addresses.contains(&a) {
            continue;
        }
        let now = (data.get(), r.response.map(|d| d.data().get()));
        let changed = last[a as usize] != Some(now);
        last[a as usize] = Some(now);
        if (changed || !r.ok() || r.repeat) && r.start >= from && r.start < to {
            out.push_str(&format!("{r}\n"));
        }
    }
    out
}

/// Every transaction within `from..to` with one of `addresses` (the handshake slaves change
/// their nibbles at every step of a word, so they are shown whole for a short window).
fn window(records: &[TransactionRecord], addresses: &[u8], from: SimTime, to: SimTime) -> String {
    records
        .iter()
        .filter(|r| r.start >= from && r.start < to)
        .filter(|r| addresses.contains(&r.request.address().get()))
        .filter(|r| !matches!(r.request.call(), Call::ReadStatus { .. }))
        .map(|r| format!("{r}\n"))
        .collect()
}

fn press(s: f64, button: Button) -> ScenarioEvent {
    ScenarioEvent {
        at: at(s),
        action: Action::Press {
            button,
            hold: SimDuration::from_millis(300),
        },
        line: 0,
    }
}

/// A hall call at floor 3 with the cabin idle at floor 1: floor station 3's handshake in the 40 ms
/// after the press (the up-button code between its words, table 4.3 of the lift thesis), then the
/// converter I/O (address 7) from the press to the arrival: ready, run and direction bits set, the
/// run bit dropped at floor 3.
#[test]
fn a_floor_call_from_the_press_to_the_arrival() {
    let sc = Scenario {
        name: "floor call".into(),
        start_mm: 0.0,
        duration: SimDuration::from_secs(30),
        events: vec![press(15.0, Button::HallUp(3))],
        ..Scenario::defaults()
    };
    let (report, records) = traced(sc);
    let arrival = report
        .arrivals
        .iter()
        .find(|a| a.floor == 3)
        .expect("the cabin reaches floor 3");
    let until = at(arrival.at_s) + SimDuration::from_millis(100);
    let station = window(&records, &[3], at(15.0), at(15.04));
    let converter = changes(&records, &[7], at(15.0), until);
    assert!(converter.contains("out=0011"), "{converter}");
    insta::assert_snapshot!(format!(
        "--- floor station 3 after the press at 15 s\n{station}--- converter I/O until the arrival\n{converter}"
    ));
}

/// STOP in the cabin while travelling (scenarios/stop.toml): the cabin panel's handshake in the
/// 40 ms after STOP is pressed (the STOP bit travels in its 32-bit word), then the converter
/// I/O until the cabin stands at the next floor: the run bit dropped.
#[test]
fn a_stop_while_travelling() {
    let (report, records) = traced(Scenario {
        duration: SimDuration::from_secs(30),
        ..scenario("stop")
    });
    let stopped = report
        .arrivals
        .iter()
        .find(|a| a.at_s > 18.0)
        .expect("the cabin stops after STOP");
    let until = at(stopped.at_s) + SimDuration::from_millis(100);
    let panel = window(&records, &[6], at(18.0), at(18.04));
    let converter = changes(&records, &[7], at(18.0), until);
    insta::assert_snapshot!(format!(
        "--- cabin panel after STOP at 18 s\n{panel}--- converter I/O until the stop\n{converter}"
    ));
}

/// On the noisy line of scenarios/noise.toml: the first corrupted transaction, its immediate
/// repeat, and the transactions around them, unfiltered.
#[test]
fn a_corrupted_transaction_and_its_repeat() {
    let (_, records) = traced(Scenario {
        duration: SimDuration::from_secs(14),
        ..scenario("noise")
    });
    // The first repeat after start-up (normal operation with all slaves).
    let i = records
        .iter()
        .position(|r| r.repeat && r.start > at(13.0))
        .expect("a repeat on the noisy line");
    assert!(!records[i - 1].ok(), "the try before the repeat failed");
    assert_eq!(records[i].request, records[i - 1].request);
    let text: String = records[i - 3..i + 3]
        .iter()
        .map(|r| format!("{r}\n"))
        .collect();
    insta::assert_snapshot!(text);
}

/// The cabin slave taken off the bus during travel and put back (scenarios/lost-cabin-slave
/// .toml): its data exchanges go unanswered, are repeated, it leaves LAS; when it is back the
/// inclusion phase finds it, reads its codes and activates it again.
#[test]
fn a_slave_dropping_out_and_returning() {
    let (_, records) = traced(Scenario {
        duration: SimDuration::from_secs(41),
        ..scenario("lost-cabin-slave")
    });
    let lost = window(&records, &[6], at(20.0), at(20.03));
    let back = window(&records, &[6], at(40.0), at(40.2));
    assert!(lost.contains("no response"), "{lost}");
    assert!(back.contains("Read_IO_Configuration 6A"), "{back}");
    insta::assert_snapshot!(format!(
        "--- slave 6 taken off the bus at 20 s\n{lost}--- slave 6 back at 40 s\n{back}"
    ));
}
