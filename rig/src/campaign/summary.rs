//! `asi-lift campaign summarize`: the lines of one campaign, from any number of files (the
//! shards), merged into one table.

use super::{p95, RunLine, RunOutcome};
use crate::report::count;
use crate::report::ViolationKind;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// A campaign's results, merged.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// The campaign's seed.
    pub campaign_seed: u64,
    /// Its profile.
    pub profile: String,
    /// Runs of the whole campaign.
    pub campaign_runs: u64,
    /// Runs found in the files.
    pub runs: u64,
    /// Runs of the campaign missing from the files (shards not given).
    pub missing: u64,
    /// Runs per outcome (every outcome listed).
    pub outcomes: BTreeMap<String, u64>,
    /// Violations by kind: how many, and in how many runs.
    pub violations: BTreeMap<ViolationKind, KindCount>,
    /// Runs not in service at the end (`in_service: false`), those with violations included;
    /// the outcome `out-of-service` counts the others.
    pub out_of_service: u64,
    /// Runs in service at the end.
    pub in_service: u64,
    /// Runs not judged (`in_service: null`).
    pub not_judged: u64,
    /// Presses of call buttons.
    pub presses: u64,
    /// Presses answered.
    pub served: u64,
    /// Waits over every answered press of every run, seconds.
    pub waits: MergedWaits,
    /// Safety trips.
    pub safety_trips: u64,
    /// Of those, the safe drive's trips, and the runs with one (absent when there are none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drive_trips: Option<TripCount>,
    /// The attendant's rounds after the repairs.
    pub attendant_rounds: u64,
    /// Runs in which the attendant made a round.
    pub attended_runs: u64,
    /// Bus transactions.
    pub transactions: u64,
    /// Immediate repeats.
    pub repeats: u64,
    /// Repeats per transaction.
    pub repeats_per_transaction: f64,
    /// Simulated seconds.
    pub simulated_s: f64,
    /// The failing runs' indices and reproducers, by index.
    pub failures: Vec<Failure>,
}

/// Violations of one kind.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct KindCount {
    /// Violations.
    pub violations: u64,
    /// Runs with at least one.
    pub runs: u64,
}

/// Trips of one kind.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TripCount {
    /// Trips.
    pub trips: u64,
    /// Runs with at least one.
    pub runs: u64,
}

/// Waits of all runs together.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MergedWaits {
    /// How many.
    pub count: u64,
    /// Mean, s.
    pub mean_s: Option<f64>,
    /// 95th percentile (nearest rank), s.
    pub p95_s: Option<f64>,
    /// Longest, s.
    pub max_s: Option<f64>,
}

/// A failing run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Failure {
    /// Its index.
    pub index: u64,
    /// Its outcome.
    pub outcome: RunOutcome,
    /// Its first violation's kind, if any.
    pub first_violation: Option<ViolationKind>,
    /// Its reproducer's file name, if written.
    pub reproducer: Option<String>,
}

/// Merges the campaign lines of `files` (name, text). Errors name the file and the line:
/// a malformed line, a run index seen twice (overlapping shards), lines of different
/// campaigns; and no lines at all.
pub fn summarize(files: &[(String, String)]) -> Result<Summary, String> {
    let mut seen: BTreeMap<u64, (String, usize)> = BTreeMap::new();
    let mut lines: Vec<RunLine> = Vec::new();
    let mut first: Option<(RunLine, String, usize)> = None;
    for (name, text) in files {
        for (n, raw) in text.lines().enumerate() {
            let n = n + 1;
            if raw.trim().is_empty() {
                continue;
            }
            let l: RunLine = serde_json::from_str(raw)
                .map_err(|e| format!("{name}:{n}: not a campaign line: {e}"))?;
            if let Some((f, fname, fline)) = &first {
                if (f.campaign_seed, f.runs, &f.profile) != (l.campaign_seed, l.runs, &l.profile) {
                    return Err(format!(
                        "{name}:{n}: run {} belongs to campaign seed {} with {} runs, profile {}, \
                         but {fname}:{fline} to campaign seed {} with {} runs, profile {}: \
                         summarize one campaign at a time",
                        l.index,
                        l.campaign_seed,
                        l.runs,
                        l.profile,
                        f.campaign_seed,
                        f.runs,
                        f.profile
                    ));
                }
            } else {
                first = Some((l.clone(), name.clone(), n));
            }
            if l.index >= l.runs {
                return Err(format!(
                    "{name}:{n}: run index {} lies outside the campaign's {} runs",
                    l.index, l.runs
                ));
            }
            if let Some((f, fl)) = seen.get(&l.index) {
                return Err(format!(
                    "{name}:{n}: run {} is also at {f}:{fl} (overlapping shards?)",
                    l.index
                ));
            }
            seen.insert(l.index, (name.clone(), n));
            lines.push(l);
        }
    }
    let Some((f, _, _)) = first else {
        return Err("no campaign lines in the given files".into());
    };
    lines.sort_by_key(|l| l.index);
    let mut s = Summary {
        campaign_seed: f.campaign_seed,
        profile: f.profile.clone(),
        campaign_runs: f.runs,
        runs: lines.len() as u64,
        missing: f.runs - lines.len() as u64,
        outcomes: RunOutcome::ALL
            .iter()
            .map(|o| (o.name().to_owned(), 0))
            .collect(),
        violations: BTreeMap::new(),
        out_of_service: 0,
        in_service: 0,
        not_judged: 0,
        presses: 0,
        served: 0,
        waits: MergedWaits {
            count: 0,
            mean_s: None,
            p95_s: None,
            max_s: None,
        },
        safety_trips: 0,
        drive_trips: None,
        attendant_rounds: 0,
        attended_runs: 0,
        transactions: 0,
        repeats: 0,
        repeats_per_transaction: 0.0,
        simulated_s: 0.0,
        failures: Vec::new(),
    };
    let mut waits: Vec<f64> = Vec::new();
    for l in &lines {
        *s.outcomes.entry(l.outcome.name().to_owned()).or_default() += 1;
        let mut kinds: Vec<ViolationKind> = Vec::new();
        for v in &l.violations {
            let k = s.violations.entry(v.kind).or_default();
            k.violations += 1;
            if !kinds.contains(&v.kind) {
                kinds.push(v.kind);
                k.runs += 1;
            }
        }
        match l.in_service {
            Some(true) => s.in_service += 1,
            Some(false) => s.out_of_service += 1,
            None => s.not_judged += 1,
        }
        s.presses += l.presses as u64;
        s.served += l.served as u64;
        waits.extend(&l.waits_s);
        s.safety_trips += l.safety_trips as u64;
        if l.drive_trips > 0 {
            let d = s.drive_trips.get_or_insert_with(TripCount::default);
            d.trips += l.drive_trips as u64;
            d.runs += 1;
        }
        s.attendant_rounds += u64::from(l.attendant_rounds);
        s.attended_runs += u64::from(l.attendant_rounds > 0);
        s.transactions += l.bus.transactions;
        s.repeats += l.bus.repeats;
        s.simulated_s += l.simulated_s;
        if l.outcome.is_failure() {
            s.failures.push(Failure {
                index: l.index,
                outcome: l.outcome,
                first_violation: l.violations.first().map(|v| v.kind),
                reproducer: l.reproducer.clone(),
            });
        }
    }
    waits.sort_by(f64::total_cmp);
    s.waits = MergedWaits {
        count: waits.len() as u64,
        mean_s: (!waits.is_empty())
            .then(|| (waits.iter().sum::<f64>() / waits.len() as f64 * 1000.0).round() / 1000.0),
        p95_s: p95(&waits),
        max_s: waits.last().copied(),
    };
    if s.transactions > 0 {
        s.repeats_per_transaction = s.repeats as f64 / s.transactions as f64;
    }
    s.simulated_s = (s.simulated_s * 1000.0).round() / 1000.0;
    Ok(s)
}

impl Summary {
    /// The summary as pretty JSON.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }

    /// The summary as a table.
    pub fn to_text(&self) -> String {
        let mut t = String::new();
        let _ = writeln!(
            t,
            "campaign seed {}, profile {}: {} of {}{}, {:.0} simulated s",
            self.campaign_seed,
            self.profile,
            self.runs,
            count(self.campaign_runs, "run", "runs"),
            if self.missing > 0 {
                format!(" ({} missing: not every shard given)", self.missing)
            } else {
                String::new()
            },
            self.simulated_s
        );
        let pct = |n: u64, of: u64| {
            if of == 0 {
                0.0
            } else {
                n as f64 * 100.0 / of as f64
            }
        };
        let _ = writeln!(t, "\n{:<28}{:>8}{:>9}", "outcome", "runs", "%");
        for o in RunOutcome::ALL {
            let n = self.outcomes.get(o.name()).copied().unwrap_or(0);
            let _ = writeln!(t, "{:<28}{n:>8}{:>8.1}%", o.name(), pct(n, self.runs));
        }
        let _ = writeln!(
            t,
            "\n{:<28}{:>8}{:>9}",
            "violations by kind", "count", "runs"
        );
        if self.violations.is_empty() {
            let _ = writeln!(t, "{:<28}{:>8}{:>9}", "none", 0, 0);
        }
        for (k, c) in &self.violations {
            let _ = writeln!(t, "{k:<28}{:>8}{:>9}", c.violations, c.runs);
        }
        let _ = writeln!(t);
        let row = |t: &mut String, name: &str, value: String| {
            let _ = writeln!(t, "{name:<28}{value}");
        };
        row(
            &mut t,
            "in service at the end",
            format!(
                "{} yes, {} no (runs with violations included), {} not judged",
                self.in_service, self.out_of_service, self.not_judged
            ),
        );
        row(
            &mut t,
            "presses answered",
            format!(
                "{} of {} ({:.1}%)",
                self.served,
                self.presses,
                pct(self.served, self.presses)
            ),
        );
        let s = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.1} s"));
        row(
            &mut t,
            "waits",
            format!(
                "mean {}, p95 {}, max {} ({} waits)",
                s(self.waits.mean_s),
                s(self.waits.p95_s),
                s(self.waits.max_s),
                self.waits.count
            ),
        );
        row(&mut t, "safety trips", self.safety_trips.to_string());
        if let Some(d) = &self.drive_trips {
            row(
                &mut t,
                "  of them the safe drive's",
                format!("{} in {}", d.trips, count(d.runs, "run", "runs")),
            );
        }
        row(
            &mut t,
            "attendant rounds",
            format!(
                "{} in {}",
                self.attendant_rounds,
                count(self.attended_runs, "run", "runs")
            ),
        );
        row(
            &mut t,
            "bus repeats",
            format!(
                "{} in {} transactions = {:.5} per transaction",
                self.repeats, self.transactions, self.repeats_per_transaction
            ),
        );
        if !self.failures.is_empty() {
            let _ = writeln!(t, "\nfailing runs");
            for f in &self.failures {
                let _ = writeln!(
                    t,
                    "  {:>6}  {:<15} {:<20} {}",
                    f.index,
                    f.outcome.name(),
                    f.first_violation.map_or("", ViolationKind::name),
                    f.reproducer.as_deref().unwrap_or("")
                );
            }
        }
        t
    }
}
