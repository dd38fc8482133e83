//! Running a campaign: J worker threads take run indices from a crossbeam channel, generate,
//! run, judge and shrink, and send their results back on another; the caller gets them in
//! index order (a reorder buffer), so the output is the same for any number of workers.

use super::generate::{generate, Generated};
use super::profile::Profile;
use super::shrink::{shrink, Case, Shrunk};
use super::{digest, execute, execute_refereed, judge, line, LineContext, RunLine, RunOutcome};
use crate::scenario::Scenario;
use crossbeam_channel::unbounded;
use std::collections::BTreeMap;
use std::fmt;
use std::fmt::Write as _;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

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
    /// Run the second referee beside every run ([`crate::referee`]): a hazard it finds that
    /// the invariant watch did not name fails the run as a `disagreement`.
    pub referee: bool,
    /// The directory the reproducers go to, as the user named it: each one's header prints
    /// the command that runs it from where the campaign was started.
    pub failures: std::path::PathBuf,
    /// The PLC program every run gets (`campaign --controller FILE.st`), if not the built-in
    /// one; the reproducers name its file.
    pub program: Option<crate::scenario::program::ProgramFile>,
}

impl Plan {
    /// How many runs this plan's shard holds: the indices below `runs` that are K − 1 more
    /// than a multiple of N.
    pub fn count(&self) -> u64 {
        let first = self.shard.k - 1;
        if self.runs <= first {
            0
        } else {
            (self.runs - 1 - first) / self.shard.n + 1
        }
    }

    /// The index of the shard's `nth` run (0-based, below [`Plan::count`]): computed, not
    /// searched, so a shard of a huge campaign starts at once.
    pub fn index(&self, nth: u64) -> u64 {
        self.shard.k - 1 + nth * self.shard.n
    }

    /// The indices this plan runs, ascending.
    pub fn indices(&self) -> impl DoubleEndedIterator<Item = u64> + '_ {
        (0..self.count()).map(|nth| self.index(nth))
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
    let scenario = Scenario {
        program: plan.program.clone(),
        ..scenario
    };
    let text = scenario.to_toml();
    let dig = digest(&text);
    let (exec, disagreements) = if plan.referee {
        execute_refereed(&scenario)
    } else {
        (execute(&scenario), Vec::new())
    };
    let mut verdict = judge(&exec, probe.as_ref());
    if !disagreements.is_empty() {
        verdict.outcome = RunOutcome::Disagreement;
    }
    let ctx = LineContext {
        index,
        runs: plan.runs,
        campaign_seed: plan.seed,
        profile: &plan.profile.name,
        seed: scenario.seed,
        digest: dig.clone(),
    };
    let mut line = line(ctx, &exec, &verdict);
    if !verdict.outcome.is_failure() {
        return Finished {
            line,
            reproducer: None,
        };
    }
    // A disagreement is kept as generated: the shrinker judges runs without the referee.
    let budget = if disagreements.is_empty() {
        plan.shrink_budget
    } else {
        0
    };
    line.disagreements = disagreements;
    let events_before = scenario.events.len();
    let duration_before = scenario.duration;
    let case = Case {
        scenario,
        tail,
        probe,
    };
    let shrunk = shrink(case, exec, verdict, budget);
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
            Some(v) => format!("violation {} at {:.3} s: {}", v.kind, v.at_s, v.detail),
            None => match &shrunk.case.probe {
                Some(p) => format!(
                    "out of service: the probe, cabin:{} pressed at {} s, {}; {}",
                    p.floor,
                    p.at.as_secs_f64(),
                    if super::probe_served(r, p) {
                        "is served"
                    } else {
                        "is never served"
                    },
                    r.final_state.state.map_or_else(
                        || "the controller does not tell its state".to_string(),
                        |s| format!("the controller ends in state `{s}`")
                    )
                ),
                None => "out of service".into(),
            },
        },
        super::Execution::Panic(m) => format!("panic: {m}"),
        super::Execution::Error(m) => format!("the rig refuses the scenario: {m}"),
    };
    let what = match line.disagreements.first() {
        Some(d) => format!("the referee disagrees: {d} (watch: {what})"),
        None => what,
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
    let _ = writeln!(
        h,
        "# reproduce: asi-lift run {}",
        shell_word(&plan.failures.join(file_name).to_string_lossy())
    );
    h.push('\n');
    h + &sc.to_toml()
}

/// `word` as one word of a POSIX shell command: as it is if it holds only characters no shell
/// reads specially, else in single quotes (a quote within as `'\''`).
fn shell_word(word: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "_-./+,:@%=".contains(c);
    if !word.is_empty() && word.chars().all(plain) {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', "'\\''"))
    }
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
    // The workers take the shard's runs by their place in it, from a shared counter: no list
    // of the indices is made, so a shard of a huge campaign starts at once.
    let count = plan.count();
    let jobs = jobs.clamp(1, usize::try_from(count).unwrap_or(usize::MAX).max(1));
    let taken = AtomicU64::new(0);
    let (done_tx, done_rx) = unbounded::<(u64, Finished)>();
    let cancel = AtomicBool::new(false);
    std::thread::scope(|scope| {
        for w in 0..jobs {
            let (done_tx, cancel, taken) = (done_tx.clone(), &cancel, &taken);
            let spawned = std::thread::Builder::new()
                .name(format!("campaign-worker-{w}"))
                .spawn_scoped(scope, move || loop {
                    let nth = taken.fetch_add(1, Ordering::Relaxed);
                    if nth >= count || cancel.load(Ordering::Relaxed) {
                        break;
                    }
                    let i = plan.index(nth);
                    let f = catch_unwind(AssertUnwindSafe(|| run_one(plan, i)))
                        .unwrap_or_else(|p| crashed(plan, i, &p));
                    if done_tx.send((nth, f)).is_err() {
                        break;
                    }
                });
            if let Err(e) = spawned {
                cancel.store(true, Ordering::Relaxed);
                return Err(Stopped(format!("cannot start a worker thread: {e}")));
            }
        }
        drop(done_tx);
        // Finished runs by their place in the shard, until their turn comes.
        let mut pending: BTreeMap<u64, Finished> = BTreeMap::new();
        let mut next = 0u64;
        for (nth, f) in done_rx.iter() {
            progress(&f);
            pending.insert(nth, f);
            while let Some(f) = pending.remove(&next) {
                next += 1;
                if let Err(e) = sink(f) {
                    cancel.store(true, Ordering::Relaxed);
                    return Err(Stopped(e));
                }
            }
        }
        if next < count {
            return Err(Stopped(format!(
                "only {next} of {count} runs finished (a worker thread died)"
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

    #[test]
    fn a_reproducers_path_is_one_shell_word() {
        assert_eq!(
            shell_word("out/run-000001-ab.toml"),
            "out/run-000001-ab.toml"
        );
        assert_eq!(shell_word("my runs/r.toml"), "'my runs/r.toml'");
        assert_eq!(shell_word("it's/r.toml"), "'it'\\''s/r.toml'");
    }

    #[test]
    fn a_shards_runs_are_computed_not_searched() {
        let plan = |runs, k, n| Plan {
            seed: 1,
            runs,
            shard: Shard { k, n },
            profile: Profile::built_in("smoke").expect("smoke"),
            shrink_budget: 0,
            referee: false,
            failures: "failures".into(),
            program: None,
        };
        // The last of 10^12 shards of a campaign of 10^12 runs: found by walking the indices,
        // its one run would take hours to reach.
        let big = 1_000_000_000_000;
        let last = plan(big, big, big);
        assert_eq!(last.indices().next(), Some(big - 1));
        assert_eq!(last.indices().next_back(), Some(big - 1));
        let first = plan(big, 1, big);
        assert_eq!(first.indices().next_back(), Some(0));
        // The same runs as the filter over all indices, for small plans.
        for runs in 0..12 {
            for n in 1..6 {
                for k in 1..=n {
                    let p = plan(runs, k, n);
                    let want: Vec<u64> = (0..runs).filter(|i| p.shard.contains(*i)).collect();
                    assert_eq!(p.indices().collect::<Vec<_>>(), want, "{runs} {k}/{n}");
                }
            }
        }
    }
}
