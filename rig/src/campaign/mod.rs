//! Campaigns (`asi-lift campaign`): many random valid scenarios run on the whole rig, each
//! judged (violations, panics, in service at the end), every failure shrunk to a minimal
//! scenario file that reproduces it with `asi-lift run`. Documented in README.md
//! ("Campaigns").
//!
//! - [`profile`]: the generator's weights, built-in or from a file;
//! - [`generate`]: (campaign seed, run index, profile) → scenario, a pure function;
//! - [`run`]: the worker pool (crossbeam channels) and the in-order output;
//! - [`shrink`]: failing scenarios made minimal;
//! - [`summary`]: result files merged into one table.
//!
//! The simulation never reads the wall clock nor an unseeded random source, so a campaign's
//! lines depend only on its seed, its run count, its shard and its profile, never on the
//! number of worker threads.

pub mod generate;
pub mod profile;
pub mod run;
pub mod shrink;
pub mod summary;

use crate::referee::Referee;
use crate::report::{round3, Report, ViolationKind};
use crate::rig::Rig;
use crate::scenario::Scenario;
use controller::State;
use generate::Probe;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RunOutcome {
    /// No violation, and in service at the end (or not judged).
    Ok,
    /// No violation and in service at the end, but only after the attendant's rounds
    /// (rescue, acknowledge, reset): the lift needed a person to come back. Not a failure;
    /// counted apart so that a campaign tells such runs from those that came back by
    /// themselves.
    Attended,
    /// The second referee ([`crate::referee`], campaign option `--referee`) found a hazard
    /// the invariant watch did not name: a blind spot of one of them.
    Disagreement,
    /// The rig found a safety invariant broken.
    Violation,
    /// No violation, but the probe was not served or the controller did not end in a normal
    /// service state.
    OutOfService,
    /// The simulation panicked.
    Panic,
    /// The rig could not be built for the scenario.
    Error,
}

impl RunOutcome {
    /// Every outcome, in the order of the summary.
    pub const ALL: [RunOutcome; 7] = [
        RunOutcome::Ok,
        RunOutcome::Attended,
        RunOutcome::Disagreement,
        RunOutcome::Violation,
        RunOutcome::OutOfService,
        RunOutcome::Panic,
        RunOutcome::Error,
    ];

    /// The name in the JSON lines.
    pub fn name(self) -> &'static str {
        match self {
            RunOutcome::Ok => "ok",
            RunOutcome::Attended => "attended",
            RunOutcome::Disagreement => "disagreement",
            RunOutcome::Violation => "violation",
            RunOutcome::OutOfService => "out-of-service",
            RunOutcome::Panic => "panic",
            RunOutcome::Error => "error",
        }
    }
}

impl RunOutcome {
    /// Whether the run fails the campaign (and is shrunk to a reproducer): all but `ok` and
    /// `attended`.
    pub fn is_failure(self) -> bool {
        !matches!(self, RunOutcome::Ok | RunOutcome::Attended)
    }
}

impl fmt::Display for RunOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The controller states of normal service (`final.state` of the report): the lift at the
/// end of a run is in service only in one of these.
pub const SERVICE_STATES: [State; 4] = [
    State::AtFloor,
    State::MovingUp,
    State::MovingDown,
    State::Braking,
];

/// What running a scenario gave.
#[derive(Clone, Debug)]
pub enum Execution {
    /// The run's report.
    Report(Box<Report>),
    /// The simulation panicked, with this message.
    Panic(String),
    /// The rig refused the scenario.
    Error(String),
}

/// Runs `sc` on the whole rig to its end; a panic is caught and becomes
/// [`Execution::Panic`].
pub fn execute(sc: &Scenario) -> Execution {
    execute_with(sc, |rig| rig.run(None))
}

/// As [`execute`], with the second referee beside the rig ([`Referee::run`]); also its
/// disagreements with the invariant watch (none after a panic or an error).
pub fn execute_refereed(sc: &Scenario) -> (Execution, Vec<String>) {
    let mut found = Vec::new();
    let exec = execute_with(sc, |rig| {
        let (report, referee) = Referee::run(rig, None);
        found = referee.disagreements(&report);
        report
    });
    if !matches!(exec, Execution::Report(_)) {
        found.clear();
    }
    (exec, found)
}

fn execute_with(sc: &Scenario, run: impl FnOnce(Rig) -> Report) -> Execution {
    let sc = sc.clone();
    let result = catch_unwind(AssertUnwindSafe(move || Rig::new(sc).map(run)));
    match result {
        Ok(Ok(report)) => Execution::Report(Box::new(report)),
        Ok(Err(e)) => Execution::Error(e.to_string()),
        Err(payload) => Execution::Panic(
            payload
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic without a message".into()),
        ),
    }
}

/// The judgement of one run.
#[derive(Clone, Debug, PartialEq)]
pub struct RunVerdict {
    /// How it ended.
    pub outcome: RunOutcome,
    /// In service at the end: `None` without a judged probe (or without a report).
    pub in_service: Option<bool>,
    /// The first violation's kind, if any.
    pub first_violation: Option<ViolationKind>,
}

impl RunVerdict {
    /// What "fails the same way" compares while shrinking: the outcome and the first
    /// violation's kind.
    pub fn signature(&self) -> (RunOutcome, Option<ViolationKind>) {
        (self.outcome, self.first_violation)
    }
}

/// `true` if the report shows the probe served.
pub fn probe_served(report: &Report, probe: &Probe) -> bool {
    let button = format!("cabin:{}", probe.floor);
    let at = probe.at.as_secs_f64();
    report
        .passengers
        .iter()
        .any(|p| p.button == button && p.pressed_at_s == at && p.served_at_s.is_some())
}

/// Judges a run of a scenario with `probe` (see [`RunOutcome`]).
pub fn judge(exec: &Execution, probe: Option<&Probe>) -> RunVerdict {
    match exec {
        Execution::Panic(_) => RunVerdict {
            outcome: RunOutcome::Panic,
            in_service: None,
            first_violation: None,
        },
        Execution::Error(_) => RunVerdict {
            outcome: RunOutcome::Error,
            in_service: None,
            first_violation: None,
        },
        Execution::Report(r) => {
            // In service: the program ends in a normal service state (if it tells its state:
            // a controller that does not is judged by the lift alone), and the probe was
            // served or the lift is still working through the calls queued before it (it
            // served one after the probe was pressed, or the automat is moving the cabin).
            let in_service = probe.filter(|p| p.judged).map(|p| {
                let state = r.final_state.state;
                let working = r.served.iter().any(|s| s.served_at_s >= p.at.as_secs_f64())
                    || (r.final_state.moving && state != Some(State::AtFloor));
                (probe_served(r, p) || working) && state.is_none_or(|s| SERVICE_STATES.contains(&s))
            });
            let first_violation = r.violations.first().map(|v| v.kind);
            let outcome = if first_violation.is_some() {
                RunOutcome::Violation
            } else if in_service == Some(false) {
                RunOutcome::OutOfService
            } else if r.safety.attendant_rounds > 0 {
                RunOutcome::Attended
            } else {
                RunOutcome::Ok
            };
            RunVerdict {
                outcome,
                in_service,
                first_violation,
            }
        }
    }
}

/// The 64-bit FNV-1a hash of `text`, as 16 hex digits: the scenario digest of a run.
pub fn digest(text: &str) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.as_bytes() {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// One line of a campaign's output (JSON): what a run did. The fields are documented in
/// README.md ("Campaigns").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunLine {
    /// The run's index in the campaign, 0-based.
    pub index: u64,
    /// How many runs the campaign has (all shards together).
    pub runs: u64,
    /// The campaign's seed.
    pub campaign_seed: u64,
    /// The profile's name.
    pub profile: String,
    /// The run's own seed (generator and line noise).
    pub seed: u64,
    /// FNV-1a of the generated scenario's TOML text, 16 hex digits.
    pub digest: String,
    /// How it ended.
    pub outcome: RunOutcome,
    /// The violations, in order.
    pub violations: Vec<LineViolation>,
    /// Presses of call buttons (cabin and hall).
    pub presses: usize,
    /// Of those, the presses the cabin answered.
    pub served: usize,
    /// Waiting times of the answered presses, press to the cabin's arrival.
    pub waits: WaitStats,
    /// The waits themselves, seconds (ms resolution), in press order.
    pub waits_s: Vec<f64>,
    /// Safety trips and errors.
    pub safety_trips: usize,
    /// Of those, the safe drive's trips (absent in runs without a trip of the safe drive).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub drive_trips: usize,
    /// Rounds of the attendant (rescue, acknowledge, reset) after the repairs (0 in the
    /// lines of campaigns before the attendant).
    #[serde(default)]
    pub attendant_rounds: u32,
    /// Bus figures.
    pub bus: LineBus,
    /// In service at the end: the probe was served and the controller ended in a service
    /// state; null when not judged (no probe, a vane sensor left broken on purpose, no report).
    pub in_service: Option<bool>,
    /// Simulated seconds.
    pub simulated_s: f64,
    /// The controller's final state.
    pub final_state: Option<State>,
    /// The panic's or the rig's error message.
    pub error: Option<String>,
    /// The file name of the shrunk reproducer in the failures directory, for a failure.
    pub reproducer: Option<String>,
    /// With `--referee`: the hazards the second referee found that the invariant watch did
    /// not name (absent when the two agree).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub disagreements: Vec<String>,
}

impl RunLine {
    /// The line as written to the output: one JSON object, no line break.
    pub fn to_json_line(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string(self)
    }
}

/// A violation in a run line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LineViolation {
    /// Its kind (the book, "Violations").
    pub kind: ViolationKind,
    /// When, seconds.
    pub at_s: f64,
}

/// Waiting-time statistics of one run, seconds (null without any wait).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WaitStats {
    /// Mean.
    pub mean_s: Option<f64>,
    /// 95th percentile (nearest rank).
    pub p95_s: Option<f64>,
    /// Longest.
    pub max_s: Option<f64>,
}

/// Bus figures of a run line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LineBus {
    /// Transactions, repeats included.
    pub transactions: u64,
    /// Immediate repeats.
    pub repeats: u64,
}

/// The 95th percentile of `sorted` by nearest rank (`None` if empty).
pub fn p95(sorted: &[f64]) -> Option<f64> {
    if sorted.is_empty() {
        return None;
    }
    let rank = (0.95 * sorted.len() as f64).ceil() as usize;
    sorted.get(rank.clamp(1, sorted.len()) - 1).copied()
}

/// Who a line belongs to: the campaign and the run.
#[derive(Clone, Debug)]
pub struct LineContext<'a> {
    /// Run index.
    pub index: u64,
    /// Runs of the campaign.
    pub runs: u64,
    /// Campaign seed.
    pub campaign_seed: u64,
    /// Profile name.
    pub profile: &'a str,
    /// The run's seed.
    pub seed: u64,
    /// The scenario digest.
    pub digest: String,
}

/// The line of a run.
pub fn line(ctx: LineContext<'_>, exec: &Execution, verdict: &RunVerdict) -> RunLine {
    let mut l = RunLine {
        index: ctx.index,
        runs: ctx.runs,
        campaign_seed: ctx.campaign_seed,
        profile: ctx.profile.to_owned(),
        seed: ctx.seed,
        digest: ctx.digest,
        outcome: verdict.outcome,
        violations: Vec::new(),
        presses: 0,
        served: 0,
        waits: WaitStats {
            mean_s: None,
            p95_s: None,
            max_s: None,
        },
        waits_s: Vec::new(),
        safety_trips: 0,
        drive_trips: 0,
        attendant_rounds: 0,
        bus: LineBus {
            transactions: 0,
            repeats: 0,
        },
        in_service: verdict.in_service,
        simulated_s: 0.0,
        final_state: None,
        error: None,
        reproducer: None,
        disagreements: Vec::new(),
    };
    match exec {
        Execution::Panic(m) | Execution::Error(m) => l.error = Some(m.clone()),
        Execution::Report(r) => {
            l.violations = r
                .violations
                .iter()
                .map(|v| LineViolation {
                    kind: v.kind,
                    at_s: round3(v.at_s),
                })
                .collect();
            l.presses = r.passengers.len();
            l.waits_s = r
                .passengers
                .iter()
                .filter_map(|p| p.served_at_s.map(|s| round3(s - p.pressed_at_s)))
                .collect();
            l.served = l.waits_s.len();
            let mut sorted = l.waits_s.clone();
            sorted.sort_by(f64::total_cmp);
            if !sorted.is_empty() {
                l.waits = WaitStats {
                    mean_s: Some(round3(sorted.iter().sum::<f64>() / sorted.len() as f64)),
                    p95_s: p95(&sorted),
                    max_s: sorted.last().copied(),
                };
            }
            l.safety_trips = r.safety.trips.len();
            l.drive_trips = r.safety.drive.as_ref().map_or(0, |d| d.trips.len());
            l.attendant_rounds = r.safety.attendant_rounds;
            l.bus = LineBus {
                transactions: r.bus.transactions,
                repeats: r.bus.repeats,
            };
            l.simulated_s = r.simulated_s;
            l.final_state = r.final_state.state;
        }
    }
    l
}

/// For serde: a count of zero is left out of a line.
fn is_zero(n: &usize) -> bool {
    *n == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_of_known_texts() {
        assert_eq!(digest(""), "cbf29ce484222325");
        assert_eq!(digest("a"), "af63dc4c8601ec8c");
        assert_eq!(digest("foobar"), "85944171f73967e8");
    }

    #[test]
    fn p95_is_the_nearest_rank() {
        assert_eq!(p95(&[]), None);
        assert_eq!(p95(&[3.0]), Some(3.0));
        let v: Vec<f64> = (1..=20).map(f64::from).collect();
        assert_eq!(p95(&v), Some(19.0));
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(p95(&v), Some(95.0));
    }

    #[test]
    fn a_panic_is_an_outcome_with_its_message() {
        let mut sc = Scenario::defaults();
        // A scenario the rig refuses is an error, not a panic.
        sc.floors = 30;
        let exec = execute(&sc);
        assert!(matches!(exec, Execution::Error(_)), "{exec:?}");
        assert_eq!(judge(&exec, None).outcome, RunOutcome::Error);
        let exec = Execution::Panic("boom".into());
        assert_eq!(judge(&exec, None).outcome, RunOutcome::Panic);
    }
}
