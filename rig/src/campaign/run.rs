//! Running a campaign: J worker threads take run indices from a crossbeam channel, generate,
//! run, judge and shrink, and send their results back on another; the caller gets them in
//! index order (a reorder buffer), so the output is the same for any number of workers.

use super::generate::{generate, Generated};
use super::profile::Profile;
use super::shrink::{shrink, Case, Shrunk};
use super::{digest, execute, judge, line, LineContext, RunLine, RunOutcome};
use crossbeam_channel::{unbounded, Receiver, Sender};
use std::collections::BTreeMap;
use std::fmt;
use std::fmt::Write as _;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};

/// The K-th of N disjoint parts of a campaign (1-based K): the runs whose index i has
/// i mod N = K − 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which part, 1..=n.
    pub k: u64,
    /// Of how many.
    pub n: u64,
}

impl Shard {
    /// The whole campaign.
    pub const ALL: Shard = Shard { k: 1, n: 1 };

    /// `true` if run `index` belongs to this part.
    pub fn contains(&self, index: u64) -> bool {
        index % self.n == self.k - 1
    }
}

impl std::str::FromStr for Shard {
    type Err = String;

    /// Reads `K/N` with 1 ≤ K ≤ N.
    fn from_str(s: &str) -> Result<Shard, String> {
        let (k, n) = s
            .split_once('/')
            .ok_or_else(|| format!("`{s}`: expected K/N, e.g. 2/8 (1-based K)"))?;
        let k: u64 = k
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: K is not a whole number"))?;
        let n: u64 = n
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: N is not a whole number"))?;
        if n == 0 {
            return Err(format!("`{s}`: N must be at least 1"));
        }
        if k == 0 || k > n {
            return Err(format!(
                "`{s}`: K must lie within 1..={n} (shards are numbered from 1)"
            ));
        }
        Ok(Shard { k, n })
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.k, self.n)
    }
}

/// What a campaign is: everything its lines depend on.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The campaign seed.
    pub seed: u64,
    /// Runs of the whole campaign.
    pub runs: u64,
    /// The part of it to run.
    pub shard: Shard,
    /// The generator's profile.
    pub profile: Profile,
    /// Runs a failure may spend on shrinking (0: write the failing scenario as generated).
    pub shrink_budget: u32,
}

impl Plan {
    /// The indices this plan runs, ascending.
    pub fn indices(&self) -> impl Iterator<Item = u64> + '_ {
        (0..self.runs).filter(|i| self.shard.contains(*i))
    }
}

/// A failing run's reproducer: a scenario file.
#[derive(Clone, Debug, PartialEq)]
pub struct Reproducer {
    /// Its file name: `run-<index>-<digest>.toml` (index zero-padded to 6 digits).
    pub file_name: String,
    /// The file: a comment header (what failed, how to reproduce) and the shrunk scenario.
    pub text: String,
}

/// A finished run: its line and, for a failure, its reproducer.
#[derive(Clone, Debug)]
pub struct Finished {
    /// The line (its `reproducer` is for the caller to fill in when it writes the file).
    pub line: RunLine,
    /// The reproducer of a failure.
    pub reproducer: Option<Reproducer>,
}

/// Runs index `index` of `plan`: generate, run, judge, shrink if it failed.
pub fn run_one(plan: &Plan, index: u64) -> Finished {
    let Generated {
        scenario,
        tail,
        probe,
    } = generate(plan.seed, index, &plan.profile);
    let text = scenario.to_toml();
    let dig = digest(&text);
    let exec = execute(&scenario);
    let verdict = judge(&exec, probe.as_ref());
    let ctx = LineContext {
        index,
        runs: plan.runs,
        campaign_seed: plan.seed,
        profile: &plan.profile.name,
        seed: scenario.seed,
        digest: dig.clone(),
    };
    let line = line(ctx, &exec, &verdict);
    if verdict.outcome == RunOutcome::Ok {
        return Finished {
            line,
            reproducer: None,
        };
    }
    let events_before = scenario.events.len();
    let duration_before = scenario.duration;
    let case = Case {
        scenario,
        tail,
        probe,
    };
    let shrunk = shrink(case, exec, verdict, plan.shrink_budget);
    let file_name = format!("run-{index:06}-{dig}.toml");
    let text = reproducer_text(
        plan,
        &line,
        &shrunk,
        &file_name,
        events_before,
        duration_before,
    );
    Finished {
        line,
        reproducer: Some(Reproducer { file_name, text }),
    }
}

fn reproducer_text(
    plan: &Plan,
    line: &RunLine,
    shrunk: &Shrunk,
    file_name: &str,
    events_before: usize,
    duration_before: asi_phy::SimDuration,
) -> String {
    let mut h = String::new();
    let _ = writeln!(
        h,
        "# asi-lift campaign reproducer: run {} of campaign seed {} ({} runs, profile {}), run seed {}, scenario digest {}",
        line.index, plan.seed, plan.runs, plan.profile.name, line.seed, line.digest
    );
    let what = match &shrunk.execution {
        super::Execution::Report(r) => match r.violations.first() {
            Some(v) => format!(
                "violation {} at {:.3} s: {}",
                v.kind, v.at_s, v.detail
            ),
            None => match &shrunk.case.probe {
                Some(p) => format!(
                    "out of service: the probe, cabin:{} pressed at {} s, {}; the controller ends in state `{}`",
                    p.floor,
                    p.at.as_secs_f64(),
                    if super::probe_served(r, p) {
                        "is served"
                    } else {
                        "is never served"
                    },
                    r.final_state
                        .state
                        .map_or_else(|| "external".to_string(), |s| s.to_string())
                ),
                None => "out of service".into(),
            },
        },
        super::Execution::Panic(m) => format!("panic: {m}"),
        super::Execution::Error(m) => format!("the rig refuses the scenario: {m}"),
    };
    let _ = writeln!(h, "# fails: {what}");
    let sc = &shrunk.case.scenario;
    let _ = writeln!(
        h,
        "# shrunk from {events_before} events and {} to {} events and {} ({} runs spent shrinking)",
        duration_before,
        sc.events.len(),
        sc.duration,
        shrunk.attempts
    );
    if shrunk.verdict.outcome == RunOutcome::OutOfService {
        let _ = writeln!(
            h,
            "# in service means: the last cabin call (the probe) is served and the controller ends in one of: {}",
            super::SERVICE_STATES.map(|s| s.name()).join(", ")
        );
    }
    let _ = writeln!(h, "# reproduce: asi-lift run {file_name}");
    h.push('\n');
    h + &sc.to_toml()
}

/// The line of a run whose generator or shrinker panicked (the simulation's own panics are
/// caught by [`super::execute`]).
fn crashed(plan: &Plan, index: u64, payload: &Box<dyn std::any::Any + Send>) -> Finished {
    let msg = payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".into());
    let exec = super::Execution::Panic(format!("campaign: {msg}"));
    let verdict = judge(&exec, None);
    let ctx = LineContext {
        index,
        runs: plan.runs,
        campaign_seed: plan.seed,
        profile: &plan.profile.name,
        seed: super::generate::run_seed(plan.seed, index),
        digest: String::new(),
    };
    Finished {
        line: line(ctx, &exec, &verdict),
        reproducer: None,
    }
}

/// Why a campaign stopped early.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Stopped(pub String);

/// Runs `plan` on `jobs` worker threads and hands every finished run to `sink` in index
/// order; `progress` hears of each run as it finishes (in any order). A sink error stops the
/// campaign: the workers finish their current runs and start no more.
pub fn run_campaign(
    plan: &Plan,
    jobs: usize,
    sink: &mut dyn FnMut(Finished) -> Result<(), String>,
    progress: &mut dyn FnMut(&Finished),
) -> Result<(), Stopped> {
    let indices: Vec<u64> = plan.indices().collect();
    let jobs = jobs.clamp(1, indices.len().max(1));
    let (work_tx, work_rx): (Sender<u64>, Receiver<u64>) = unbounded();
    let (done_tx, done_rx) = unbounded::<(u64, Finished)>();
    for i in &indices {
        // The receiver lives until the end of this function: sending cannot fail.
        let _ = work_tx.send(*i);
    }
    drop(work_tx);
    let cancel = AtomicBool::new(false);
    std::thread::scope(|scope| {
        for w in 0..jobs {
            let (work_rx, done_tx, cancel) = (work_rx.clone(), done_tx.clone(), &cancel);
            let spawned = std::thread::Builder::new()
                .name(format!("campaign-worker-{w}"))
                .spawn_scoped(scope, move || {
                    for i in work_rx.iter() {
                        if cancel.load(Ordering::Relaxed) {
                            break;
                        }
                        let f = catch_unwind(AssertUnwindSafe(|| run_one(plan, i)))
                            .unwrap_or_else(|p| crashed(plan, i, &p));
                        if done_tx.send((i, f)).is_err() {
                            break;
                        }
                    }
                });
            if let Err(e) = spawned {
                cancel.store(true, Ordering::Relaxed);
                return Err(Stopped(format!("cannot start a worker thread: {e}")));
            }
        }
        drop(done_tx);
        let mut pending: BTreeMap<u64, Finished> = BTreeMap::new();
        let mut next = 0usize;
        for (i, f) in done_rx.iter() {
            progress(&f);
            pending.insert(i, f);
            while let Some(f) = indices.get(next).and_then(|i| pending.remove(i)) {
                next += 1;
                if let Err(e) = sink(f) {
                    cancel.store(true, Ordering::Relaxed);
                    return Err(Stopped(e));
                }
            }
        }
        if next < indices.len() {
            return Err(Stopped(format!(
                "only {next} of {} runs finished (a worker thread died)",
                indices.len()
            )));
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_partition() {
        assert_eq!("2/3".parse::<Shard>(), Ok(Shard { k: 2, n: 3 }));
        for bad in ["0/3", "4/3", "1/0", "a/3", "3", "1/x", "-1/3"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        assert!("0/3"
            .parse::<Shard>()
            .expect_err("0")
            .contains("numbered from 1"));
        let shards: Vec<Shard> = (1..=3).map(|k| Shard { k, n: 3 }).collect();
        for i in 0..30 {
            assert_eq!(shards.iter().filter(|s| s.contains(i)).count(), 1);
        }
    }
}
