//! The simulator's fast paths change nothing anyone can observe: every scenario of
//! `scenarios/` and random scenarios with faults give the same report, the same bus trace and
//! the same VCD whether the bus runs with its fast paths (the default) or pulse-exact
//! (`asi-lift run --pulse-exact`: every telegram through the pulse decoder).
//!
//! Here: the first minute of every scenario file, the VCD of the demo and of the noisy line,
//! and the first 90 s of 4 random runs of the campaign generator, to keep `cargo test` short.
//! Every scenario file whole and 200 whole random runs are the ignored tests
//! `every_scenario_file_whole_agrees` and `every_fast_path_agrees_on_200_random_runs`, which
//! `.ci/run` runs on the release build (`cargo test --release -p asi-lift-tests --test all
//! fast_path -- --ignored`).

use asi_lift_tests::*;
use asi_master::record::TransactionRecord;
use asi_phy::{SimDuration, SimTime};
use rig::campaign::generate::generate;
use rig::campaign::profile::Profile;
use rig::rig::Rig;
use rig::scenario::Scenario;
use rig::waves::WaveOutputs;
use std::io::Write;
use std::sync::{Arc, Mutex};

/// A `Write` whose bytes the test keeps.
#[derive(Clone, Default)]
struct Shared(Arc<Mutex<Vec<u8>>>);

impl Write for Shared {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.lock().expect("not poisoned").extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// What a run shows: its report as JSON, every transaction, and the VCD when asked for.
#[derive(PartialEq)]
struct Seen {
    report: String,
    transactions: Vec<TransactionRecord>,
    vcd: Vec<u8>,
}

fn seen(sc: &Scenario, pulse_exact: bool, until: Option<SimDuration>, vcd: bool) -> Seen {
    let mut rig = Rig::new(sc.clone()).unwrap_or_else(|e| panic!("{}: {e}", sc.name));
    rig.set_pulse_exact(pulse_exact);
    let records = Arc::new(Mutex::new(Vec::new()));
    let sink = records.clone();
    rig.on_transaction(Box::new(move |r| {
        sink.lock().expect("not poisoned").push(*r);
    }));
    let out = Shared::default();
    if vcd {
        rig.waves_to(WaveOutputs {
            vcd: Some(Box::new(out.clone())),
            csv: None,
            window: (SimTime::ZERO, SimTime::from_millis(2)),
            pulse_window: None,
        });
    }
    let report = rig.run(until);
    let transactions = std::mem::take(&mut *records.lock().expect("not poisoned"));
    let vcd = std::mem::take(&mut *out.0.lock().expect("not poisoned"));
    Seen {
        report: serde_json::to_string(&report).expect("a report serialises"),
        transactions,
        vcd,
    }
}

/// Both paths, compared; `what` names the run in a failure.
fn agree(what: &str, sc: &Scenario, until: Option<SimDuration>, vcd: bool) {
    let fast = seen(sc, false, until, vcd);
    let exact = seen(sc, true, until, vcd);
    assert!(
        !fast.transactions.is_empty(),
        "{what}: the run made no transaction"
    );
    if let Some(i) = (0..fast.transactions.len().max(exact.transactions.len()))
        .find(|&i| fast.transactions.get(i) != exact.transactions.get(i))
    {
        panic!(
            "{what}: transaction {i} differs: fast {:?}, pulse-exact {:?}",
            fast.transactions.get(i),
            exact.transactions.get(i)
        );
    }
    assert!(
        fast.report == exact.report,
        "{what}: the reports differ\nfast:  {}\nexact: {}",
        fast.report,
        exact.report
    );
    assert!(fast.vcd == exact.vcd, "{what}: the VCDs differ");
    if vcd {
        assert!(fast.vcd.len() > 1000, "{what}: a VCD was written");
    }
}

pub(crate) const SCENARIOS: [&str; 17] = [
    "busy",
    "demo",
    "door",
    "fifo",
    "lost-cabin-slave",
    "noise",
    "noise-1e-2",
    "noise-5e-3",
    "overload",
    "overtravel",
    "power-fail",
    "safe-drive",
    "safe-drive-encoder",
    "safe-drive-runaway",
    "safe-link-drop",
    "stop",
    "vane-sensor-broken",
];

#[test]
fn the_list_names_every_scenario_file() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .expect("scenarios/")
        .filter_map(|e| {
            let name = e.ok()?.file_name().into_string().ok()?;
            name.strip_suffix(".toml").map(str::to_owned)
        })
        .collect();
    files.sort();
    assert_eq!(files, SCENARIOS);
}

#[test]
fn the_first_minute_of_every_scenario_file_is_the_same_on_both_paths() {
    for name in SCENARIOS {
        agree(
            name,
            &scenario(name),
            Some(SimDuration::from_secs(60)),
            false,
        );
    }
}

#[test]
#[ignore = "35 simulated minutes twice: .ci/run runs it on the release build"]
fn every_scenario_file_whole_agrees() {
    for name in SCENARIOS {
        agree(name, &scenario(name), None, false);
    }
}

#[test]
fn traffic_templates_give_the_same_outputs_on_both_paths() {
    // The passengers' presses come at the rig's own moments, and a cabin press at a moment
    // its hall call's stop set: both paths must take them alike.
    let sc = Scenario::from_toml(
        "traffic.toml",
        "duration = \"150s\"\n[[traffic]]\npattern = \"interfloor\"\nper_minute = 6.0\nseed = 2\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    agree("interfloor traffic", &sc, None, false);
}

#[test]
fn the_demo_gives_the_same_vcd_on_both_paths() {
    agree(
        "demo with VCD",
        &scenario("demo"),
        Some(SimDuration::from_secs(3)),
        true,
    );
    agree(
        "noise with VCD",
        &scenario("noise"),
        Some(SimDuration::from_secs(3)),
        true,
    );
}

/// Runs `0..runs` of the campaign `profile` with the CI campaign's seed, shared out over the
/// machine's cores.
fn random_runs(profile: &str, runs: u64, until: Option<SimDuration>) {
    let profile = Profile::built_in(profile).expect("a built-in profile");
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get() as u64);
    std::thread::scope(|s| {
        for k in 0..threads {
            let profile = &profile;
            s.spawn(move || {
                for index in (k..runs).step_by(threads as usize) {
                    let g = generate(2026, index, profile);
                    let what = format!("random run {index} ({})", profile.name);
                    agree(&what, &g.scenario, until, false);
                }
            });
        }
    });
}

#[test]
fn random_runs_with_faults_give_the_same_outputs_on_both_paths() {
    random_runs("default", 4, Some(SimDuration::from_secs(90)));
}

#[test]
#[ignore = "240 runs of minutes: .ci/run runs it on the release build"]
fn every_fast_path_agrees_on_200_random_runs() {
    random_runs("default", 200, None);
    // And the lift with the safe drive.
    random_runs("safe-drive", 40, None);
}
