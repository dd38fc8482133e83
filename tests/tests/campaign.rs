//! Campaigns end to end: the same lines whatever the number of worker threads, shards that
//! cover the campaign exactly once, the deployment files, and the CI campaign of 300 runs
//! without a failure (ignored here: `.ci/run` runs the same campaign on the release build,
//! where it takes a minute instead of two and keeps `cargo test --workspace` short).

use asi_phy::SimDuration;
use rig::campaign::profile::Profile;
use rig::campaign::run::{run_campaign, Finished, Plan, Shard};
use rig::campaign::RunOutcome;
use std::path::PathBuf;

/// Short runs (70..75 s, probe 10 s before the end, 1..5 events) for fast tests.
fn short_profile() -> Profile {
    let mut p = Profile::built_in("smoke").expect("smoke");
    p.name = "test".into();
    p.duration = (SimDuration::from_secs(70), SimDuration::from_secs(75));
    p.probe_lead = SimDuration::from_secs(10);
    p.events = (1, 5);
    p.check().expect("a valid profile");
    p
}

/// The campaign's lines as the CLI writes them, and its finished runs.
fn lines(plan: &Plan, jobs: usize) -> (Vec<String>, Vec<Finished>) {
    let mut out = Vec::new();
    let mut finished = Vec::new();
    let mut sink = |f: Finished| {
        out.push(f.line.to_json_line().expect("serialises"));
        finished.push(f);
        Ok(())
    };
    run_campaign(plan, jobs, &mut sink, &mut |_| {}).expect("campaign");
    (out, finished)
}

fn plan(runs: u64, shard: Shard) -> Plan {
    Plan {
        seed: 7,
        runs,
        shard,
        profile: short_profile(),
        shrink_budget: 3,
        referee: false,
        failures: "failures".into(),
        program: None,
    }
}

#[test]
fn the_same_seed_gives_the_same_lines_whatever_the_jobs() {
    let p = plan(6, Shard::ALL);
    let (one, f1) = lines(&p, 1);
    let (two, f2) = lines(&p, 2);
    assert_eq!(one.len(), 6);
    assert_eq!(one, two);
    // The reproducers too.
    let repro = |f: &[Finished]| -> Vec<Option<String>> {
        f.iter()
            .map(|f| f.reproducer.as_ref().map(|r| r.text.clone()))
            .collect()
    };
    assert_eq!(repro(&f1), repro(&f2));
    // Every line names its index, in order, and a different seed changes the runs.
    for (i, l) in one.iter().enumerate() {
        assert!(
            l.starts_with(&format!("{{\"index\":{i},\"runs\":6,")),
            "{l}"
        );
    }
    let other = Plan { seed: 8, ..p };
    assert_ne!(lines(&other, 2).0, one);
}

#[test]
fn the_union_of_the_shards_is_the_campaign_line_for_line() {
    let whole = lines(&plan(7, Shard::ALL), 2).0;
    let mut union: Vec<(u64, String)> = Vec::new();
    for k in 1..=3 {
        let part = lines(&plan(7, Shard { k, n: 3 }), 2).0;
        // Shard k has the indices i with i mod 3 = k - 1.
        assert_eq!(part.len(), (7 + 3 - k as usize) / 3);
        for l in part {
            let v: serde_json::Value = serde_json::from_str(&l).expect("json");
            let i = v["index"].as_u64().expect("index");
            assert_eq!(i % 3, k - 1);
            union.push((i, l));
        }
    }
    union.sort();
    let union: Vec<String> = union.into_iter().map(|(_, l)| l).collect();
    assert_eq!(union, whole);
}

fn repo_file(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(path)
}

#[test]
fn the_slurm_script_is_valid_bash() {
    let script = repo_file("deploy/slurm.sh");
    let text = std::fs::read_to_string(&script).expect("deploy/slurm.sh");
    assert!(text.contains("SLURM_ARRAY_TASK_ID"));
    assert!(text.contains("--shard"));
    match std::process::Command::new("bash")
        .arg("-n")
        .arg(&script)
        .output()
    {
        Ok(out) => assert!(
            out.status.success(),
            "bash -n deploy/slurm.sh: {}",
            String::from_utf8_lossy(&out.stderr)
        ),
        Err(e) => eprintln!("no bash here ({e}): only the contents were checked"),
    }
}

#[test]
fn the_kubernetes_job_shards_by_completion_index() {
    let text = std::fs::read_to_string(repo_file("deploy/k8s-job.yaml")).expect("k8s-job.yaml");
    for needed in [
        "kind: Job",
        "completionMode: Indexed",
        "JOB_COMPLETION_INDEX",
        "--shard",
        "campaign",
    ] {
        assert!(text.contains(needed), "deploy/k8s-job.yaml lacks {needed}");
    }
    // Plain YAML: no tabs, and `completions` equals the shard count the command uses.
    assert!(!text.contains('\t'));
    let value = |key: &str| -> Option<String> {
        text.lines().map(str::trim).find_map(|l| {
            l.strip_prefix(key)
                .map(|v| v.trim().trim_matches('"').to_owned())
        })
    };
    assert_eq!(
        value("completions:"),
        value("- name: SHARDS").and(value("value:"))
    );
    let containerfile =
        std::fs::read_to_string(repo_file("deploy/Containerfile")).expect("Containerfile");
    assert!(containerfile.contains("cargo build --release"));
}

/// The CI campaign: a few hundred runs of the default profile without a violation, a
/// panic or a lift out of service. 300 runs take about 124 s in the test profile on two cores
/// (the book, "Campaigns").
#[test]
#[ignore = "run by .ci/run on the release build (asi-lift campaign --runs 300 --seed 2026)"]
fn a_ci_campaign_of_300_runs_has_no_failure() {
    let plan = Plan {
        seed: 2026,
        runs: 300,
        shard: Shard::ALL,
        profile: Profile::built_in("default").expect("default"),
        shrink_budget: 0,
        referee: false,
        failures: "failures".into(),
        program: None,
    };
    let jobs = std::thread::available_parallelism().map_or(1, |n| n.get());
    let wall = std::time::Instant::now();
    let (_, finished) = lines(&plan, jobs);
    eprintln!(
        "300 runs in {:.1} s on {jobs} threads",
        wall.elapsed().as_secs_f64()
    );
    let failing: Vec<String> = finished
        .iter()
        .filter(|f| f.line.outcome != RunOutcome::Ok)
        .map(|f| {
            format!(
                "run {}: {} {:?}\n{}",
                f.line.index,
                f.line.outcome,
                f.line.violations.first().map(|v| &v.kind),
                f.reproducer.as_ref().map_or("", |r| r.text.as_str())
            )
        })
        .collect();
    assert!(
        failing.is_empty(),
        "{} of 300 runs fail; the first:\n{}",
        failing.len(),
        failing.first().map_or("", String::as_str)
    );
}
