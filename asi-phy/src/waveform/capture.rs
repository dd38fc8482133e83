//! Captures read from text files of `time,voltage` lines (an oscilloscope's export).

use super::render::Waveform;
use crate::time::SimTime;

/// A capture read from a text file of `time,voltage` lines.
#[derive(Clone, Debug, PartialEq)]
pub struct Capture {
    /// Time of the first sample in the file's own time base, seconds.
    pub first_time_s: f64,
    /// The samples, the first at [`SimTime::ZERO`].
    pub waveform: Waveform,
}

/// Why a capture file could not be read: the line and the cause.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("line {line}: {cause}")]
pub struct CaptureError {
    /// 1-based line number.
    pub line: usize,
    /// What is wrong there.
    pub cause: String,
}

/// Reads an oscilloscope export: one sample per line, `time,voltage` (seconds, volts),
/// separated by a comma, semicolon, tab or spaces. Blank lines and lines starting with `#` are
/// skipped, and so are non-numeric lines before the first sample (headers). Sample spacing must
/// be even (within 1 % of the mean), as an oscilloscope's is.
pub fn read_capture(text: &str) -> Result<Capture, CaptureError> {
    let mut times: Vec<(usize, f64)> = Vec::new();
    let mut samples = Vec::new();
    // The header lines before the first sample: the first one and how many.
    let mut header: Option<(usize, &str)> = None;
    let mut header_lines = 0;
    for (n, line) in text.lines().enumerate() {
        let line_no = n + 1;
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let mut fields = l.split([',', ';', '\t', ' ']).filter(|f| !f.is_empty());
        let (Some(t), Some(v)) = (fields.next(), fields.next()) else {
            if samples.is_empty() {
                header.get_or_insert((line_no, l));
                header_lines += 1;
                continue;
            }
            return Err(CaptureError {
                line: line_no,
                cause: format!("expected `time,voltage`, found `{l}`"),
            });
        };
        let (t, v) = match (t.parse::<f64>(), v.parse::<f32>()) {
            (Ok(t), Ok(v)) if t.is_finite() && v.is_finite() => (t, v),
            _ if samples.is_empty() => {
                header.get_or_insert((line_no, l));
                header_lines += 1;
                continue;
            }
            _ => {
                return Err(CaptureError {
                    line: line_no,
                    cause: format!("`{l}` is not two numbers (seconds, volts)"),
                })
            }
        };
        if let Some(&(_, last)) = times.last() {
            if t <= last {
                return Err(CaptureError {
                    line: line_no,
                    cause: format!("time {t} s does not increase (previous sample {last} s)"),
                });
            }
        }
        times.push((line_no, t));
        samples.push(v);
    }
    if samples.len() < 2 {
        let last = text.lines().count().max(1);
        let (line, cause) = match (times.first(), header) {
            (Some(&(line, _)), _) => (line, "only one sample: a capture needs two or more".into()),
            (None, Some((line, l))) if header_lines == 1 => (
                line,
                format!("`{l}` is a header and no `time,voltage` sample follows"),
            ),
            (None, Some((line, l))) => (
                line,
                format!(
                    "no samples: `{l}` and the {} lines after it are not `time,voltage` \
                     (seconds, volts)",
                    header_lines - 1
                ),
            ),
            (None, None) if text.trim().is_empty() => (last, "the file is empty".into()),
            (None, None) => (last, "no samples: the file holds only comments".into()),
        };
        return Err(CaptureError { line, cause });
    }
    let (first, last) = (times[0].1, times[times.len() - 1].1);
    let period_s = (last - first) / (times.len() - 1) as f64;
    // Judge each step against the median step, so one bad step is named where it is.
    let mut steps: Vec<f64> = times.windows(2).map(|w| w[1].1 - w[0].1).collect();
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2];
    for w in times.windows(2) {
        let dt = w[1].1 - w[0].1;
        if (dt - median).abs() > 0.01 * median {
            return Err(CaptureError {
                line: w[1].0,
                cause: format!(
                    "uneven sample spacing: {:.3} ns here, {:.3} ns elsewhere",
                    dt * 1e9,
                    median * 1e9
                ),
            });
        }
    }
    Ok(Capture {
        first_time_s: first,
        waveform: Waveform {
            start: SimTime::ZERO,
            period_ns: period_s * 1e9,
            samples,
        },
    })
}
