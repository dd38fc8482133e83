//! The FMEA sheet of an exploration: its lines, from any number of files (the shards),
//! merged into one table of fault kind × lift phase with the count of each verdict
//! (`asi-lift explore summarize`, and the end of `asi-lift explore`).

use super::{ForkLine, Phase, Verdict};
use crate::report::ViolationKind;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// One row of the sheet: a fault kind in a phase, and how its forks ended.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    /// The fault kind.
    pub fault: String,
    /// The lift's phase at injection.
    pub phase: Phase,
    /// Forks.
    pub forks: u64,
    /// Forks per verdict (every verdict listed).
    pub verdicts: BTreeMap<Verdict, u64>,
    /// The person's actions of the stops that need one, and how often.
    pub actions: BTreeMap<String, u64>,
    /// The violations by kind, and the first instant of each, seconds.
    pub violations: BTreeMap<ViolationKind, (u64, f64)>,
}

/// An exploration's lines, merged.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Sheet {
    /// The scenario's name.
    pub scenario: String,
    /// Forks of the whole exploration.
    pub exploration_forks: u64,
    /// Forks found in the files.
    pub forks: u64,
    /// Forks of the exploration missing from the files (shards not given).
    pub missing: u64,
    /// Forks per verdict, all kinds and phases together.
    pub verdicts: BTreeMap<Verdict, u64>,
    /// The rows, by fault kind in the order of first appearance, then by phase.
    pub rows: Vec<Row>,
}

/// Merges the lines of `files` (name, text). Errors name the file and the line: a malformed
/// line, a fork seen twice (overlapping shards), lines of different explorations; and no
/// lines at all.
pub fn summarize(files: &[(String, String)]) -> Result<Sheet, String> {
    let mut seen: BTreeMap<u64, (String, usize)> = BTreeMap::new();
    let mut lines: Vec<ForkLine> = Vec::new();
    let mut first: Option<(String, u64, String, usize)> = None;
    for (name, text) in files {
        for (n, raw) in text.lines().enumerate() {
            let n = n + 1;
            if raw.trim().is_empty() {
                continue;
            }
            let l: ForkLine = serde_json::from_str(raw)
                .map_err(|e| format!("{name}:{n}: not a line of `asi-lift explore`: {e}"))?;
            match &first {
                Some((sc, forks, fname, fline)) if (sc, *forks) != (&l.scenario, l.forks) => {
                    return Err(format!(
                        "{name}:{n}: fork {} belongs to an exploration of `{}` with {} forks, \
                         but {fname}:{fline} to one of `{sc}` with {forks}: summarize one \
                         exploration at a time",
                        l.index, l.scenario, l.forks
                    ));
                }
                Some(_) => {}
                None => first = Some((l.scenario.clone(), l.forks, name.clone(), n)),
            }
            if l.index >= l.forks {
                return Err(format!(
                    "{name}:{n}: fork {} lies outside the exploration's {} forks",
                    l.index, l.forks
                ));
            }
            if let Some((f, fl)) = seen.get(&l.index) {
                return Err(format!(
                    "{name}:{n}: fork {} is also at {f}:{fl} (overlapping shards?)",
                    l.index
                ));
            }
            seen.insert(l.index, (name.clone(), n));
            lines.push(l);
        }
    }
    let Some((scenario, total, _, _)) = first else {
        return Err("no lines of `asi-lift explore` in the given files".into());
    };
    lines.sort_by_key(|l| l.index);
    Ok(sheet(&scenario, total, &lines))
}

/// The sheet of `lines` (in index order) of an exploration of `scenario` with `total` forks.
pub fn sheet(scenario: &str, total: u64, lines: &[ForkLine]) -> Sheet {
    let zero = || {
        Verdict::ALL
            .iter()
            .map(|v| (*v, 0))
            .collect::<BTreeMap<_, _>>()
    };
    let mut order: Vec<String> = Vec::new();
    let mut rows: BTreeMap<(usize, Phase), Row> = BTreeMap::new();
    let mut verdicts = zero();
    for l in lines {
        let k = match order.iter().position(|f| *f == l.fault) {
            Some(k) => k,
            None => {
                order.push(l.fault.clone());
                order.len() - 1
            }
        };
        let row = rows.entry((k, l.phase)).or_insert_with(|| Row {
            fault: l.fault.clone(),
            phase: l.phase,
            forks: 0,
            verdicts: zero(),
            actions: BTreeMap::new(),
            violations: BTreeMap::new(),
        });
        row.forks += 1;
        *row.verdicts.entry(l.verdict).or_default() += 1;
        *verdicts.entry(l.verdict).or_default() += 1;
        if let Some(a) = &l.action {
            *row.actions.entry(a.clone()).or_default() += 1;
        }
        if let Some(v) = l.violation {
            let e = row.violations.entry(v).or_insert((0, l.at_s));
            e.0 += 1;
        }
    }
    Sheet {
        scenario: scenario.to_owned(),
        exploration_forks: total,
        forks: lines.len() as u64,
        missing: total - lines.len() as u64,
        verdicts,
        rows: rows.into_values().collect(),
    }
}

impl Sheet {
    /// The sheet as pretty JSON.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }

    /// The sheet as a table: a row per fault kind and phase, a column per verdict; then the
    /// actions the stops need and the violations found.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "exploration of `{}`: {} of {} forks{}",
            self.scenario,
            self.forks,
            self.exploration_forks,
            if self.missing > 0 {
                format!(" ({} missing: shards not given?)", self.missing)
            } else {
                String::new()
            }
        );
        let fault_w = self
            .rows
            .iter()
            .map(|r| r.fault.len())
            .chain([5])
            .max()
            .unwrap_or(5);
        let _ = write!(s, "{:<fault_w$}  {:<12}  {:>6}", "fault", "phase", "forks");
        for v in Verdict::ALL {
            let _ = write!(s, "  {:>w$}", v.name(), w = v.name().len());
        }
        s.push('\n');
        let mut last = "";
        for r in &self.rows {
            let fault = if r.fault == last {
                ""
            } else {
                r.fault.as_str()
            };
            last = &r.fault;
            let _ = write!(
                s,
                "{fault:<fault_w$}  {:<12}  {:>6}",
                r.phase.name(),
                r.forks
            );
            for v in Verdict::ALL {
                let n = r.verdicts.get(&v).copied().unwrap_or(0);
                let _ = write!(s, "  {:>w$}", n, w = v.name().len());
            }
            s.push('\n');
        }
        let _ = write!(s, "{:<fault_w$}  {:<12}  {:>6}", "all", "", self.forks);
        for v in Verdict::ALL {
            let n = self.verdicts.get(&v).copied().unwrap_or(0);
            let _ = write!(s, "  {:>w$}", n, w = v.name().len());
        }
        s.push('\n');
        let mut actions: BTreeMap<&str, u64> = BTreeMap::new();
        for r in &self.rows {
            for (a, n) in &r.actions {
                *actions.entry(a).or_default() += n;
            }
        }
        if !actions.is_empty() {
            s.push_str("\nwhat the stops need a person for:\n");
            for (a, n) in actions {
                let _ = writeln!(s, "  {n:>6}  {a}");
            }
        }
        let violating: Vec<&Row> = self
            .rows
            .iter()
            .filter(|r| !r.violations.is_empty())
            .collect();
        if !violating.is_empty() {
            s.push_str("\nviolations:\n");
            for r in violating {
                for (k, (n, at)) in &r.violations {
                    let _ = writeln!(
                        s,
                        "  {} {}: {n} × {k}, first injected at {at} s",
                        r.fault,
                        r.phase.name()
                    );
                }
            }
        }
        s
    }
}
