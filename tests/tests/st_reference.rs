//! The reference program `controllers/lift.st` (the lift thesis's program in Structured
//! Text, on the handshake library `controllers/lab.st`) against the built-in program: the same
//! bus trace, transaction by transaction, and the same JSON report but for its top-level
//! `controller` field, on the built-in scenarios and on random campaign runs with faults.
//!
//! Here: the first 30 s of the demo and of a few scenarios, to keep `cargo test` short.
//! Every scenario whole and 200 random campaign runs are the ignored test
//! `every_scenario_and_200_random_runs_agree`, run on the release build
//! (`cargo test --release -p asi-lift-tests --test all st_reference -- --ignored`).

use asi_lift_tests::scenario;
use asi_master::record::TransactionRecord;
use asi_phy::SimDuration;
use controller::structured::StProgram;
use controller::Algorithm;
use rig::campaign::generate::generate;
use rig::campaign::profile::Profile;
use rig::rig::Rig;
use rig::scenario::Scenario;
use std::sync::{Arc, Mutex};

const LAB: &str = include_str!("../../controllers/lab.st");
const LIFT: &str = include_str!("../../controllers/lift.st");

/// The reference program, compiled with its library.
pub(crate) fn reference() -> StProgram {
    StProgram::compile_with(&[("lab.st", LAB)], "lift.st", LIFT).unwrap_or_else(|e| panic!("{e}"))
}

struct Seen {
    report: serde_json::Value,
    transactions: Vec<TransactionRecord>,
}

fn seen(sc: &Scenario, st: bool, until: Option<SimDuration>) -> Seen {
    let mut rig = Rig::new(sc.clone()).unwrap_or_else(|e| panic!("{}: {e}", sc.name));
    if st {
        rig = rig.with_controller(reference().with_scan(sc.plc_scan));
    }
    let records = Arc::new(Mutex::new(Vec::new()));
    let sink = records.clone();
    rig.on_transaction(Box::new(move |r| {
        sink.lock().expect("not poisoned").push(*r);
    }));
    let report = rig.run(until);
    let mut report = serde_json::to_value(&report).expect("a report serialises");
    if st {
        let controller = report.as_object_mut().and_then(|o| o.remove("controller"));
        assert_eq!(
            controller,
            Some(serde_json::Value::String("lift.st".into())),
            "the report names the program"
        );
    }
    let transactions = std::mem::take(&mut *records.lock().expect("not poisoned"));
    Seen {
        report,
        transactions,
    }
}

/// The built-in program and the reference program on `sc`, compared; the first difference
/// of the log, then of the report, then of the trace, in a failure.
pub(crate) fn agree(what: &str, sc: &Scenario, until: Option<SimDuration>) {
    let builtin = seen(sc, false, until);
    let st = seen(sc, true, until);
    let log = |s: &Seen| -> Vec<String> {
        s.report["log"]
            .as_array()
            .map(|l| l.iter().map(|e| e.to_string()).collect())
            .unwrap_or_default()
    };
    let (lb, ls) = (log(&builtin), log(&st));
    if let Some(i) = (0..lb.len().max(ls.len())).find(|&i| lb.get(i) != ls.get(i)) {
        panic!(
            "{what}: log line {i} differs\nbuilt-in: {:?}\nlift.st:  {:?}\nbefore: {:?}",
            lb.get(i),
            ls.get(i),
            &lb[i.saturating_sub(3)..i]
        );
    }
    if builtin.report != st.report {
        let (b, s) = (builtin.report.to_string(), st.report.to_string());
        let at = b
            .bytes()
            .zip(s.bytes())
            .position(|(x, y)| x != y)
            .unwrap_or(b.len().min(s.len()));
        panic!(
            "{what}: the reports differ at byte {at}\nbuilt-in: …{}\nlift.st:  …{}",
            &b[at.saturating_sub(200)..(at + 200).min(b.len())],
            &s[at.saturating_sub(200)..(at + 200).min(s.len())]
        );
    }
    if let Some(i) = (0..builtin.transactions.len().max(st.transactions.len()))
        .find(|&i| builtin.transactions.get(i) != st.transactions.get(i))
    {
        panic!(
            "{what}: transaction {i} differs: built-in {:?}, lift.st {:?}",
            builtin.transactions.get(i),
            st.transactions.get(i)
        );
    }
}

#[test]
fn the_reference_program_equals_the_built_in_one_on_the_demo() {
    agree("demo", &scenario("demo"), None);
}

#[test]
fn the_reference_program_equals_the_built_in_one_in_the_first_30_s_of_some_scenarios() {
    for name in ["stop", "door", "overload", "lost-cabin-slave"] {
        agree(name, &scenario(name), Some(SimDuration::from_secs(30)));
    }
}

/// The scenario's floors and algorithm reach the program (`Floors`, `Algorithm`): a busy
/// 100 s under the collective control, and the first 40 s of the first random campaign
/// runs with two floors (FIFO) and three floors (collective), whose floor stations beyond the
/// floors served must stay untouched.
#[test]
fn the_reference_program_follows_the_scenario_s_floors_and_algorithm() {
    let mut busy = scenario("busy");
    busy.algorithm = Algorithm::Collective;
    agree("busy, collective", &busy, Some(SimDuration::from_secs(100)));
    let profile = Profile::built_in("default").expect("a built-in profile");
    for (floors, algorithm) in [(2, Algorithm::Fifo), (3, Algorithm::Collective)] {
        let g = (0..1000)
            .map(|i| generate(2026, i, &profile))
            .find(|g| g.scenario.floors == floors && g.scenario.algorithm == algorithm)
            .expect("such a run among the first thousand");
        agree(
            &format!("{} ({floors} floors, {algorithm:?})", g.scenario.name),
            &g.scenario,
            Some(SimDuration::from_secs(40)),
        );
    }
}

#[test]
#[ignore = "every scenario whole and 200 campaign runs, twice: .ci/run runs it in release"]
fn every_scenario_and_200_random_runs_agree() {
    for name in crate::fast_path::SCENARIOS {
        agree(name, &scenario(name), None);
    }
    let profile = Profile::built_in("default").expect("a built-in profile");
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get() as u64);
    std::thread::scope(|s| {
        for k in 0..threads {
            let profile = &profile;
            s.spawn(move || {
                for index in (k..200).step_by(threads as usize) {
                    let g = generate(2026, index, profile);
                    agree(&format!("random run {index}"), &g.scenario, None);
                }
            });
        }
    });
}
