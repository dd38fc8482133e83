//! The statistics per slave in the report's words: `bus.slaves[]` of the JSON, the summary's
//! `slaves` lines, the table of `asi-lift timing` and `asi-lift decode` (docs/master.md,
//! "Statistics per slave"; the AS-Interface Analyser's "Advanced Statistics", "Consecutive
//! Errors" and "Configuration").

use super::{round3, ErrorCounts};
use asi_master::slave_stats::{SlaveStats, SlaveTable, NO_SLAVE};
use asi_master::ProjectedConfig;
use asi_phy::{Check, SlaveAddr, SlaveCodes};
use serde::Serialize;
use std::fmt::Write as _;

/// Errors per receiver check, without the missing responses.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[non_exhaustive]
pub struct CheckCounts {
    /// Start bit.
    pub start_bit: u64,
    /// Alternation.
    pub alternation: u64,
    /// Pause.
    pub pause: u64,
    /// Information.
    pub information: u64,
    /// Parity.
    pub parity: u64,
    /// End bit.
    pub end_bit: u64,
    /// Length.
    pub length: u64,
}

impl CheckCounts {
    /// Counts by check, index = [`Check`] as u8.
    pub fn of(counts: &[u64; 7]) -> CheckCounts {
        CheckCounts::from_fn(|k| counts[k as usize])
    }

    /// Each check's count as `c` gives it.
    pub fn from_fn(c: impl Fn(Check) -> u64) -> CheckCounts {
        CheckCounts {
            start_bit: c(Check::StartBit),
            alternation: c(Check::Alternation),
            pause: c(Check::Pause),
            information: c(Check::Information),
            parity: c(Check::Parity),
            end_bit: c(Check::EndBit),
            length: c(Check::Length),
        }
    }

    /// `true` if every count is 0.
    pub fn is_zero(&self) -> bool {
        *self == CheckCounts::default()
    }
}

impl ErrorCounts {
    /// Every count together: telegrams that failed a check and missing responses.
    pub fn total(&self) -> u64 {
        let c = &self.checks;
        c.start_bit
            + c.alternation
            + c.pause
            + c.information
            + c.parity
            + c.end_bit
            + c.length
            + self.no_response
    }
}

/// Where a slave stands against the projected configuration, from the traffic (the
/// analyser's "Configuration").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Configuration {
    /// Projected, and it answers with the projected codes.
    AsProjected,
    /// Projected, and it answers with other codes.
    DifferentProfile,
    /// Projected, and it never answered.
    Missing,
    /// It answers, and is not projected.
    NotProjected,
}

impl Configuration {
    /// `as projected`, `different profile`, `missing`, `not projected`.
    pub const fn words(self) -> &'static str {
        match self {
            Configuration::AsProjected => "as projected",
            Configuration::DifferentProfile => "different profile",
            Configuration::Missing => "missing",
            Configuration::NotProjected => "not projected",
        }
    }
}

/// One slave's statistics (`bus.slaves[]`): an object per address that took part in the
/// traffic or is projected.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct SlaveReport {
    /// The address 0..31.
    pub address: u8,
    /// `A` or `B` for a slave of extended addressing (ID code A); absent for a standard slave.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ab: Option<&'static str>,
    /// Transactions addressed to it, repeats included.
    pub calls: u64,
    /// Calls that were no repeat and no fault.
    pub first_try_ok: u64,
    /// Immediate repeats of a failed call.
    pub repeats: u64,
    /// Repeats over calls, per cent (to 3 decimals).
    pub repeat_percent: f64,
    /// Calls that still failed after their repeat.
    pub failed_after_repeat: u64,
    /// Errors between two calls that were no fault (the repeat put it right).
    pub single_errors: u64,
    /// Errors that followed an error on the same slave.
    pub consecutive_errors: u64,
    /// The most errors in a row.
    pub longest_error_run: u32,
    /// Erroneous telegrams by primary check class, requests and responses together, and
    /// missing responses (as `bus.errors`, whose counts are the sums of these).
    pub errors: ErrorCounts,
    /// The part of `errors` in requests the slaves received corrupted (absent when none).
    #[serde(skip_serializing_if = "CheckCounts::is_zero")]
    pub request_errors: CheckCounts,
    /// Times it left LAS while the master stayed in normal operation.
    pub dropouts: u32,
    /// Time out of LAS after those drop-outs, seconds (to the millisecond).
    pub out_of_las_s: f64,
    /// The traffic light at the end, with its hold time: `green`, `yellow`, `red` (null
    /// before it was first evaluated).
    pub light: Option<&'static str>,
    /// The worst light since the start.
    pub worst_light: Option<&'static str>,
    /// The projected profile `S-IO.ID.ID2 (ID1 x)` (absent when not projected).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub projected: Option<String>,
    /// The profile its answers showed (`?` for a code never read; absent when none was).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seen: Option<String>,
    /// Where it stands against the projected configuration (absent without one: a capture).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub configuration: Option<Configuration>,
}

impl SlaveReport {
    /// The report of list place `place` (0..63) with statistics `s`; `projected` is the
    /// projected configuration if there is one.
    pub fn of(place: u8, s: &SlaveStats, projected: Option<&ProjectedConfig>) -> SlaveReport {
        let a = SlaveAddr::from_index(place);
        let is_projected = |p: &ProjectedConfig| a.is_some_and(|a| p.lps().contains(a));
        let codes = projected
            .filter(|p| is_projected(p))
            .zip(a)
            .map(|(p, a)| p.codes(a));
        let b = place >= 32;
        let ab = b || s.seen.is_ab() || codes.is_some_and(|c| c.is_ab());
        let configuration = projected.map(|_| match codes {
            None => Configuration::NotProjected,
            Some(_) if s.answers() == 0 => Configuration::Missing,
            Some(c) if agrees(s, &c) => Configuration::AsProjected,
            Some(_) => Configuration::DifferentProfile,
        });
        SlaveReport {
            address: place & 31,
            ab: ab.then_some(if b { "B" } else { "A" }),
            calls: s.calls,
            first_try_ok: s.first_try_ok(),
            repeats: s.repeats,
            repeat_percent: round3(s.repeat_percent()),
            failed_after_repeat: s.failed_after_repeat,
            single_errors: s.single_errors(),
            consecutive_errors: s.consecutive_errors,
            longest_error_run: s.longest_error_run,
            errors: ErrorCounts {
                checks: CheckCounts::from_fn(|k| s.errors(k)),
                no_response: s.no_response,
            },
            request_errors: CheckCounts::of(&s.request_errors),
            dropouts: s.dropouts,
            out_of_las_s: round3(s.out_of_las.as_secs_f64()),
            light: s.light.map(|l| l.name()),
            worst_light: s.worst_light.map(|l| l.name()),
            projected: codes.map(|c| c.to_string()),
            seen: (!s.seen.is_empty()).then(|| s.seen.to_string()),
            configuration,
        }
    }

    /// The address as the master writes it: `6`, `5A`, `5B`.
    pub fn label(&self) -> String {
        match self.ab {
            Some(h) => format!("{}{h}", self.address),
            None => self.address.to_string(),
        }
    }
}

/// The codes seen agree with the projected ones, as a master in protected mode compares them
/// (a code never seen does not disagree).
fn agrees(s: &SlaveStats, c: &SlaveCodes) -> bool {
    match s.seen.codes() {
        Some(seen) => c.matches(&seen),
        None => {
            let same = |seen: Option<asi_phy::Nibble>, want: asi_phy::Nibble| {
                seen.is_none_or(|n| n == want)
            };
            same(s.seen.io, c.io) && same(s.seen.id, c.id) && same(s.seen.id2, c.id2)
        }
    }
}

/// The slaves of `table` that took part in the traffic or are projected, in list order (A
/// addresses ascending, then B).
pub fn slave_reports(table: &SlaveTable, projected: Option<&ProjectedConfig>) -> Vec<SlaveReport> {
    let lps = projected.map_or(0, |p| p.lps().bits());
    table
        .iter()
        .filter(|&(i, s)| i != NO_SLAVE && (s.takes_part() || lps >> i & 1 != 0))
        .map(|(i, s)| SlaveReport::of(i, s, projected))
        .collect()
}

/// The slaves as a table, a row per slave under a header row, each line with its newline;
/// `las` says whether the drop-outs and the time out of LAS are known (a capture's listener
/// does not see the master's LAS: `-`).
pub fn slave_table_text(rows: &[SlaveReport], las: bool) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:>5} {:>9} {:>9} {:>7} {:>8} {:>6} {:>6} {:>6} {:>7} {:>6} {:>5} {:>8}  {:<6} {:<6} profile",
        "slave",
        "calls",
        "1st ok",
        "repeats",
        "repeat %",
        "failed",
        "single",
        "consec",
        "no resp",
        "errors",
        "drops",
        "out s",
        "light",
        "worst"
    );
    for r in rows {
        let profile = match (&r.seen, &r.projected, r.configuration) {
            (_, _, Some(Configuration::Missing)) => {
                format!(
                    "missing, projected {}",
                    r.projected.as_deref().unwrap_or("?")
                )
            }
            (Some(seen), _, Some(Configuration::DifferentProfile)) => format!(
                "{seen}, projected {}",
                r.projected.as_deref().unwrap_or("?")
            ),
            (Some(seen), _, Some(Configuration::NotProjected)) => {
                format!("{seen}, not projected")
            }
            (Some(seen), _, _) => seen.clone(),
            (None, Some(p), _) => format!("not read, projected {p}"),
            (None, None, _) => "not read".to_owned(),
        };
        let (drops, out) = if las {
            (r.dropouts.to_string(), format!("{:.3}", r.out_of_las_s))
        } else {
            ("-".to_owned(), "-".to_owned())
        };
        let _ = writeln!(
            s,
            "{:>5} {:>9} {:>9} {:>7} {:>8.3} {:>6} {:>6} {:>6} {:>7} {:>6} {:>5} {:>8}  {:<6} {:<6} {profile}",
            r.label(),
            r.calls,
            r.first_try_ok,
            r.repeats,
            r.repeat_percent,
            r.failed_after_repeat,
            r.single_errors,
            r.consecutive_errors,
            r.errors.no_response,
            r.errors.total(),
            drops,
            out,
            r.light.unwrap_or("-"),
            r.worst_light.unwrap_or("-"),
        );
    }
    s
}

/// A light's rank for sorting: none, green, yellow, red.
fn rank(light: Option<&str>) -> u8 {
    match light {
        Some("red") => 3,
        Some("yellow") => 2,
        Some("green") => 1,
        _ => 0,
    }
}

/// The summary's lines on the slaves: the configuration from the traffic and the lights, then
/// the worst slaves (at most three, by worst light, repeat rate and errors), each line with
/// its newline; the second line only when a slave had a repeat or an error.
pub fn slave_summary(rows: &[SlaveReport]) -> String {
    let mut s = String::new();
    let mut parts = Vec::new();
    for c in [
        Configuration::AsProjected,
        Configuration::DifferentProfile,
        Configuration::Missing,
        Configuration::NotProjected,
    ] {
        let these: Vec<String> = rows
            .iter()
            .filter(|r| r.configuration == Some(c))
            .map(SlaveReport::label)
            .collect();
        match these.len() {
            0 => {}
            n if c == Configuration::AsProjected => parts.push(format!("{n} {}", c.words())),
            n => parts.push(format!("{n} {} ({})", c.words(), these.join(", "))),
        }
    }
    let mut lights = Vec::new();
    for l in ["green", "yellow", "red"] {
        let n = rows.iter().filter(|r| r.light == Some(l)).count();
        if n > 0 {
            lights.push(format!("{n} {l}"));
        }
    }
    let lights = if lights.is_empty() {
        "no lights yet".to_owned()
    } else {
        format!("lights {}", lights.join(", "))
    };
    let _ = writeln!(
        s,
        "  slaves             {}; {lights}",
        if parts.is_empty() {
            "none".to_owned()
        } else {
            parts.join(", ")
        }
    );
    let mut worst: Vec<&SlaveReport> = rows
        .iter()
        .filter(|r| r.repeats > 0 || r.errors.total() > 0 || rank(r.worst_light) > 1)
        .collect();
    worst.sort_by(|a, b| {
        rank(b.worst_light)
            .cmp(&rank(a.worst_light))
            .then(b.repeat_percent.total_cmp(&a.repeat_percent))
            .then(b.errors.total().cmp(&a.errors.total()))
            .then(a.address.cmp(&b.address))
    });
    if !worst.is_empty() {
        let shown: Vec<String> = worst
            .iter()
            .take(3)
            .map(|r| {
                let mut w = format!(
                    "{} {} (now {}): {:.2} % repeats, {} errors",
                    r.label(),
                    r.worst_light.unwrap_or("no light"),
                    r.light.unwrap_or("no light"),
                    r.repeat_percent,
                    r.errors.total()
                );
                if r.dropouts > 0 {
                    let times = if r.dropouts == 1 { "time" } else { "times" };
                    let _ = write!(w, ", left LAS {} {times}", r.dropouts);
                }
                w
            })
            .collect();
        let _ = writeln!(s, "  worst slaves       {}", shown.join("; "));
    }
    s
}
