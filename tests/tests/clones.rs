//! A copy of the rig (a snapshot: `Rig` is `Clone`) taken at any moment goes on exactly as the
//! original: the same report, and from that moment the same transactions, the same trace
//! lines and the same waveforms (the copy's VCD is the original's from that moment on, after
//! the header and the values as they stood).
//!
//! Here, to keep `cargo test` short: the first 10 s of every scenario file, copied at three
//! moments each; the first 3 s of the demo and of the noisy line with their VCDs; the first
//! 20 s of two random runs of the campaign generator (faults and all). Every scenario file whole and 40 whole random runs are the ignored test
//! `every_scenario_and_random_run_whole_forks_exactly`, which `.ci/run` runs on the release
//! build (`cargo test --release -p asi-lift-tests --test all clones -- --ignored`).

use crate::fast_path::SCENARIOS;
use asi_lift_tests::*;
use asi_master::record::TransactionRecord;
use asi_phy::{SimDuration, SimTime};
use asi_trace::trace::TraceFormat;
use rig::campaign::generate::generate;
use rig::campaign::profile::Profile;
use rig::rig::Rig;
use rig::scenario::Scenario;
use rig::waves::WaveOutputs;
use std::cell::RefCell;
use std::rc::Rc;

/// What a rig shows from the moment it is given its outputs on: its trace lines, every
/// transaction, and its VCD when asked for.
struct Outputs {
    trace: Shared,
    records: Rc<RefCell<Vec<TransactionRecord>>>,
    vcd: Option<Shared>,
}

impl Outputs {
    fn attach(rig: &mut Rig, vcd: bool) -> Outputs {
        let trace = Shared::default();
        rig.trace_to(Box::new(trace.clone()), TraceFormat::Jsonl);
        let records = Rc::new(RefCell::new(Vec::new()));
        let sink = records.clone();
        rig.on_transaction(Box::new(move |r| sink.borrow_mut().push(*r)));
        let vcd = vcd.then(|| {
            let out = Shared::default();
            rig.waves_to(WaveOutputs {
                vcd: Some(Box::new(out.clone())),
                csv: None,
                window: (SimTime::ZERO, SimTime::from_millis(2)),
                pulse_window: None,
            });
            out
        });
        Outputs {
            trace,
            records,
            vcd,
        }
    }
}

/// A copy of the original taken at `at`, and how much of the original's outputs was written
/// by then.
struct Fork {
    at: SimTime,
    rig: Rig,
    trace_len: usize,
    records_len: usize,
    vcd_len: usize,
}

/// Runs `sc` to `until` with every output, copying it at each of `cuts` (stepped to); then runs
/// each copy, given outputs of its own, to `until` too, and compares. `what` names the run.
fn forks_agree(what: &str, sc: &Scenario, until: SimDuration, cuts: &[SimTime], vcd: bool) {
    let mut rig = Rig::new(sc.clone()).unwrap_or_else(|e| panic!("{what}: {e}"));
    let original = Outputs::attach(&mut rig, vcd);
    let mut forks = Vec::new();
    for &at in cuts {
        while rig.step_until(at).is_some() {}
        forks.push(Fork {
            at: rig.now(),
            rig: rig.clone(),
            trace_len: original.trace.bytes().len(),
            records_len: original.records.borrow().len(),
            vcd_len: original.vcd.as_ref().map_or(0, |v| v.bytes().len()),
        });
    }
    let report = serde_json::to_string(&rig.run(Some(until))).expect("a report serialises");
    let trace = original.trace.bytes();
    let records = original.records.borrow().clone();
    let vcd_bytes = original.vcd.as_ref().map(Shared::bytes);
    assert!(!records.is_empty(), "{what}: the run made no transaction");
    for mut fork in forks {
        let at = fork.at;
        let own = Outputs::attach(&mut fork.rig, vcd);
        let copied = serde_json::to_string(&fork.rig.run(Some(until))).expect("serialises");
        assert!(
            copied == report,
            "{what}, copied at {at}: the reports differ\noriginal: {report}\ncopy:     {copied}"
        );
        let tail = &records[fork.records_len..];
        let own_records = own.records.borrow();
        if let Some(i) =
            (0..tail.len().max(own_records.len())).find(|&i| tail.get(i) != own_records.get(i))
        {
            panic!(
                "{what}, copied at {at}: transaction {i} after the copy differs: original {:?}, \
                 copy {:?}",
                tail.get(i),
                own_records.get(i)
            );
        }
        assert!(
            own.trace.bytes() == trace[fork.trace_len..],
            "{what}, copied at {at}: the trace lines after the copy differ"
        );
        if let (Some(original), Some(own)) = (&vcd_bytes, &own.vcd) {
            same_waves(what, at, original, fork.vcd_len, &own.bytes());
        }
    }
}

/// The value records of VCD text, `(code, value)`, in order (times, commands and `$end`s
/// left out).
fn records(text: &str) -> Vec<(String, String)> {
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#') && !l.starts_with('$'))
        .map(|l| match l.rsplit_once(' ') {
            Some((value, code)) => (code.to_owned(), value.to_owned()),
            None => {
                let (value, code) = l.split_at(1);
                (code.to_owned(), value.to_owned())
            }
        })
        .collect()
}

/// The copy's VCD, begun when the copy was given its outputs: the original's header; then,
/// at the last time the original had written, every variable's value as the original had
/// last written it (`$dumpvars`); then byte for byte what the original wrote after the copy
/// was taken (`written` bytes in).
fn same_waves(what: &str, at: SimTime, original: &[u8], written: usize, copy: &[u8]) {
    let original = std::str::from_utf8(original).expect("a VCD is text");
    let copy = std::str::from_utf8(copy).expect("a VCD is text");
    let (header, _) = original
        .split_once("$enddefinitions $end\n")
        .expect("a header");
    let rest = copy
        .strip_prefix(header)
        .and_then(|r| r.strip_prefix("$enddefinitions $end\n"))
        .unwrap_or_else(|| panic!("{what}, copied at {at}: the copy's VCD has another header"));
    let (dump, body) = rest
        .split_once("$end\n")
        .unwrap_or_else(|| panic!("{what}, copied at {at}: no $dumpvars in the copy's VCD"));
    let before = &original[..written];
    let last_time = before
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix('#'))
        .expect("the original had written a time");
    assert_eq!(
        dump.lines().next(),
        Some(format!("#{last_time}").as_str()),
        "{what}, copied at {at}: the copy's values stand at another time"
    );
    let earlier = records(before);
    let stated = records(dump);
    assert!(
        !stated.is_empty(),
        "{what}, copied at {at}: no value stated"
    );
    for (code, value) in &stated {
        let last = earlier
            .iter()
            .rev()
            .find(|(c, _)| c == code)
            .map(|(_, v)| v);
        assert_eq!(
            last,
            Some(value),
            "{what}, copied at {at}: the copy states variable {code} otherwise"
        );
    }
    let after = &original[written..];
    assert!(
        !after.is_empty(),
        "{what}, copied at {at}: nothing written after the copy"
    );
    if body != after {
        let i = body
            .lines()
            .zip(after.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(body.lines().count().min(after.lines().count()));
        panic!(
            "{what}, copied at {at}: VCD line {i} after the copy differs: copy {:?}, original \
             {:?}",
            body.lines().nth(i),
            after.lines().nth(i)
        );
    }
}

/// Three moments within `until`, none on a round time: early, in the middle, late.
fn cuts(until: SimDuration, salt: u64) -> Vec<SimTime> {
    let span = until.as_nanos();
    [7, 45, 83]
        .iter()
        .map(|pct| SimTime::from_nanos(span / 100 * pct + 1_234_567 * (salt + 1) % 999_983))
        .collect()
}

/// The first 10 s of the scenario files `names` (the `first`th of the list on), each copied
/// at three moments.
fn scenario_files_fork_exactly(first: usize, names: &[&str]) {
    let until = SimDuration::from_secs(10);
    for (k, name) in names.iter().enumerate() {
        let salt = (first + k) as u64;
        forks_agree(name, &scenario(name), until, &cuts(until, salt), false);
    }
}

// The scenario files in two halves, so that the test binary's threads share them out.
#[test]
fn a_copy_of_the_first_scenario_files_goes_on_as_the_original() {
    scenario_files_fork_exactly(0, &SCENARIOS[..9]);
}

#[test]
fn a_copy_of_the_other_scenario_files_goes_on_as_the_original() {
    scenario_files_fork_exactly(9, &SCENARIOS[9..]);
}

#[test]
fn a_copy_writes_the_waveforms_the_original_writes() {
    let until = SimDuration::from_secs(3);
    for name in ["demo", "noise"] {
        forks_agree(name, &scenario(name), until, &cuts(until, 5), true);
    }
}

/// Runs `0..runs` of the campaign `profile` with the CI campaign's seed, each to `until` (its
/// end if `None`), copied at three moments.
fn random_runs(profile: &str, runs: u64, until: Option<SimDuration>) {
    let profile = Profile::built_in(profile).expect("a built-in profile");
    for index in 0..runs {
        let g = generate(2026, index, &profile);
        let until = until.unwrap_or(g.scenario.duration);
        let what = format!("random run {index} ({})", profile.name);
        forks_agree(&what, &g.scenario, until, &cuts(until, index), false);
    }
}

#[test]
fn a_copy_of_a_random_run_with_faults_goes_on_as_the_original() {
    random_runs("default", 2, Some(SimDuration::from_secs(20)));
}

#[test]
#[ignore = "every scenario and 40 random runs whole: .ci/run runs it on the release build"]
fn every_scenario_and_random_run_whole_forks_exactly() {
    std::thread::scope(|s| {
        s.spawn(|| {
            for (k, name) in SCENARIOS.iter().enumerate() {
                let sc = scenario(name);
                let until = sc.duration;
                forks_agree(name, &sc, until, &cuts(until, k as u64), false);
            }
        });
        s.spawn(|| random_runs("default", 32, None));
        s.spawn(|| random_runs("safe-drive", 8, None));
    });
}
