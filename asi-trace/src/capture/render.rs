//! A decoded capture for people and machines: one line per telegram and a summary, or JSON
//! lines.

use super::{CaptureSource, DecodeSummary, Decoded};
use crate::telegrams::TelegramRecord;
use core::fmt;

/// `t_ns` as seconds with nine decimals: `0.000112000`, `-0.000001500`.
pub fn seconds(t_ns: i64) -> String {
    let sign = if t_ns < 0 { "-" } else { "" };
    let a = t_ns.unsigned_abs();
    format!("{sign}{}.{:09}", a / 1_000_000_000, a % 1_000_000_000)
}

impl fmt::Display for CaptureSource {
    /// `1201 samples every 100 ns, nominal amplitude 2.500 V` or `wire rig.bus.line`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CaptureSource::Voltage {
                signal,
                samples,
                period_ns,
                nominal,
            } => {
                let s = if *samples == 1 { "" } else { "s" };
                write!(f, "{samples} sample{s} every {period_ns:.3} ns")?;
                if let Some(s) = signal {
                    write!(f, " of {s}")?;
                }
                match nominal {
                    Some(a) => write!(f, ", nominal amplitude {a:.3} V"),
                    None => f.write_str(", a flat line"),
                }
            }
            CaptureSource::Wire { signal } => write!(f, "wire {signal}"),
        }
    }
}

/// The closing line: `2 telegrams, 2 valid; 32 pulses from wire rig.bus.line`, or
/// `no telegrams found; …`.
pub fn summary(d: &Decoded) -> String {
    stream_summary(&d.summary())
}

/// The closing line of a decode that streamed its telegrams ([`summary`]).
pub fn stream_summary(d: &DecodeSummary) -> String {
    let head = match d.telegrams {
        0 => "no telegrams found".to_owned(),
        1 => format!("1 telegram, {} valid", d.valid),
        n => format!("{n} telegrams, {} valid", d.valid),
    };
    format!("{head}; {} pulses from {}", d.pulses, d.source)
}

/// The header row of the text rendering, with its newline.
pub fn text_header() -> String {
    format!(
        "{:>14}  {:<8}  {:<14}  {:<21}  {:<7}  {:<5}  {:<4}  errors\n",
        "time_s", "type", "bits", "call", "address", "info", "data"
    )
}

/// One telegram's line of the text rendering, with its newline.
pub fn text_line(t: &TelegramRecord) -> String {
    let dash = |o: Option<&str>| o.unwrap_or("-").to_owned();
    let errors = if t.errors.is_empty() {
        "ok".to_owned()
    } else {
        t.errors.join(",")
    };
    format!(
        "{:>14}  {:<8}  {:<14}  {:<21}  {:<7}  {:<5}  {:<4}  {errors}\n",
        seconds(t.t_ns),
        t.kind.name(),
        t.bits,
        dash(t.call),
        t.address.map_or("-".into(), |a| a.to_string()),
        dash(t.info.as_deref()),
        dash(t.data.as_deref()),
    )
}

/// One line per telegram under a header row ([`text_header`], [`text_line`]), and the
/// [`summary`] as the last line.
///
/// ```text
///         time_s  type      bits            call                   address  info   data  errors
///    0.000010000  request   00001010101001  Data_Exchange          5        01010  -     ok
/// ```
pub fn to_text(d: &Decoded) -> String {
    let mut s = String::new();
    if !d.telegrams.is_empty() {
        s.push_str(&text_header());
    }
    for t in &d.telegrams {
        s.push_str(&text_line(t));
    }
    s.push_str(&summary(d));
    s.push('\n');
    s
}

/// One telegram as a JSON object on a line, with its newline.
pub fn json_line(t: &TelegramRecord) -> Result<String, serde_json::Error> {
    let mut s = serde_json::to_string(t)?;
    s.push('\n');
    Ok(s)
}

/// One JSON object per telegram and line, the fields of [`TelegramRecord`].
pub fn to_json_lines(d: &Decoded) -> Result<String, serde_json::Error> {
    let mut s = String::new();
    for t in &d.telegrams {
        s.push_str(&json_line(t)?);
    }
    Ok(s)
}
