//! Captures read from text files of `time,voltage` lines (an oscilloscope's export), whole
//! ([`read_capture`]) or as a stream ([`CaptureReader`]), which holds only a bounded prefix.

use super::render::Waveform;
use crate::message::short_number;
use crate::time::SimTime;
use std::borrow::Cow;
use std::io::{BufRead, Read};

/// The longest line a capture may hold, in bytes. A `time,voltage` line is some tens of bytes
/// and a VCD line rarely more than a few kB: a longer one is no capture (a binary file,
/// `/dev/zero`), and is refused before it fills memory.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// `text` as quoted in a message: whole when short, else its first 60 characters and `…`, so
/// that a huge token does not fill the message.
pub fn excerpt(text: &str) -> Cow<'_, str> {
    match text.char_indices().nth(60) {
        None => Cow::Borrowed(text),
        Some((cut, _)) => Cow::Owned(format!("{}…", &text[..cut])),
    }
}

/// Reads a line into `buf` as [`BufRead::read_until`] does, but at most [`MAX_LINE_BYTES`] of
/// it: a longer line is an error naming line `line_no`, whatever the input's length.
pub fn read_line_bounded(
    input: &mut impl BufRead,
    buf: &mut Vec<u8>,
    line_no: usize,
) -> Result<usize, CaptureError> {
    let n = input
        .take(MAX_LINE_BYTES as u64 + 1)
        .read_until(b'\n', buf)
        .map_err(|e| CaptureError {
            line: line_no,
            cause: e.to_string(),
        })?;
    if buf.len() > MAX_LINE_BYTES {
        return Err(CaptureError {
            line: line_no,
            cause: format!(
                "the line is longer than {} MiB: not a text capture",
                MAX_LINE_BYTES >> 20
            ),
        });
    }
    Ok(n)
}

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
/// be even (within 1 % of the median), as an oscilloscope's is.
pub fn read_capture(text: &str) -> Result<Capture, CaptureError> {
    let (_, cap) = CaptureReader::open(text.as_bytes(), usize::MAX)?;
    Ok(cap)
}

/// A capture read as it goes: [`CaptureReader::open`] reads a prefix of the file (the
/// samples that fix the period and the spacing rule), [`CaptureReader::read`] the rest a
/// buffer at a time. Memory is bounded by the prefix, whatever the file's length.
///
/// The rules are [`read_capture`]'s, judged on the prefix: the period is the prefix's mean
/// spacing, and every later step must lie within 1 % of the prefix's median step. A file that
/// fits in the prefix reads exactly as [`read_capture`] reads it.
#[derive(Debug)]
pub struct CaptureReader<R> {
    input: R,
    line: Vec<u8>,
    line_no: usize,
    /// Time and line of the last sample.
    last: (f64, usize),
    /// The prefix's median step, seconds.
    median: f64,
}

/// One parsed line of a capture.
enum Parsed {
    /// Blank or a comment.
    Skip,
    /// Not a sample: a header before the first sample, an error after it.
    NotSample { two_fields: bool },
    /// A sample.
    Sample(f64, f32),
    /// Two numbers, one of them infinite, NaN or beyond a voltage's range.
    OutOfRange { t: f64, v: f64 },
}

fn parse(l: &str) -> Parsed {
    if l.is_empty() || l.starts_with('#') {
        return Parsed::Skip;
    }
    let mut fields = l.split([',', ';', '\t', ' ']).filter(|f| !f.is_empty());
    let (Some(t), Some(v)) = (fields.next(), fields.next()) else {
        return Parsed::NotSample { two_fields: false };
    };
    match (t.parse::<f64>(), v.parse::<f64>()) {
        (Ok(t), Ok(v)) if t.is_finite() && v.is_finite() && (v as f32).is_finite() => {
            Parsed::Sample(t, v as f32)
        }
        (Ok(t), Ok(v)) => Parsed::OutOfRange { t, v },
        _ => Parsed::NotSample { two_fields: true },
    }
}

impl<R: BufRead> CaptureReader<R> {
    /// Reads the header and the first `prefix` samples (all of them if the file is shorter):
    /// they are returned as a [`Capture`], and the reader continues after them.
    pub fn open(input: R, prefix: usize) -> Result<(CaptureReader<R>, Capture), CaptureError> {
        let mut r = CaptureReader {
            input,
            line: Vec::new(),
            line_no: 0,
            last: (0.0, 0),
            median: 0.0,
        };
        let prefix = prefix.max(2);
        let mut times: Vec<(usize, f64)> = Vec::new();
        let mut samples = Vec::new();
        // The header lines before the first sample: the first one and how many.
        let mut header: Option<(usize, String)> = None;
        let mut header_lines = 0;
        // Whether the input holds nothing but whitespace so far.
        let mut blank = true;
        while samples.len() < prefix {
            let Some((line_no, l)) = r.next_line()? else {
                break;
            };
            blank &= l.is_empty();
            let (t, v) = match parse(l) {
                Parsed::Skip => continue,
                Parsed::Sample(t, v) => (t, v),
                Parsed::NotSample { .. } if samples.is_empty() => {
                    header.get_or_insert_with(|| (line_no, l.to_owned()));
                    header_lines += 1;
                    continue;
                }
                Parsed::NotSample { two_fields } => return Err(not_sample(line_no, l, two_fields)),
                Parsed::OutOfRange { t, v } => return Err(out_of_range(line_no, t, v)),
            };
            if let Some(&(_, last)) = times.last() {
                if t <= last {
                    return Err(not_increasing(line_no, t, last));
                }
            }
            times.push((line_no, t));
            samples.push(v);
        }
        if samples.len() < 2 {
            let last = r.line_no.max(1);
            let (line, cause) = match (times.first(), header) {
                (Some(&(line, _)), _) => {
                    (line, "only one sample: a capture needs two or more".into())
                }
                (None, Some((line, l))) if header_lines == 1 => (
                    line,
                    format!(
                        "`{}` is a header and no `time,voltage` sample follows",
                        excerpt(&l)
                    ),
                ),
                (None, Some((line, l))) => (
                    line,
                    format!(
                        "no samples: `{}` and the {} lines after it are not `time,voltage` \
                         (seconds, volts)",
                        excerpt(&l),
                        header_lines - 1
                    ),
                ),
                (None, None) if blank => (last, "the file is empty".into()),
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
        drop(steps);
        for w in times.windows(2) {
            check_step(w[1].0, w[1].1 - w[0].1, median)?;
        }
        r.median = median;
        r.last = (last, times[times.len() - 1].0);
        Ok((
            r,
            Capture {
                first_time_s: first,
                waveform: Waveform {
                    start: SimTime::ZERO,
                    period_ns: period_s * 1e9,
                    samples,
                },
            },
        ))
    }

    /// Reads the samples that follow, at most `max` of them (at least one), into `out` (which
    /// is cleared first). An empty `out` is the end of the file.
    pub fn read(&mut self, out: &mut Vec<f32>, max: usize) -> Result<(), CaptureError> {
        out.clear();
        while out.len() < max.max(1) {
            let Some((line_no, l)) = self.next_line()? else {
                break;
            };
            let (t, v) = match parse(l) {
                Parsed::Skip => continue,
                Parsed::Sample(t, v) => (t, v),
                Parsed::NotSample { two_fields } => return Err(not_sample(line_no, l, two_fields)),
                Parsed::OutOfRange { t, v } => return Err(out_of_range(line_no, t, v)),
            };
            let last = self.last.0;
            if t <= last {
                return Err(not_increasing(line_no, t, last));
            }
            check_step(line_no, t - last, self.median)?;
            self.last = (t, line_no);
            out.push(v);
        }
        Ok(())
    }

    /// The next line, trimmed, and its number; `None` at the end of the input.
    fn next_line(&mut self) -> Result<Option<(usize, &str)>, CaptureError> {
        self.line.clear();
        let n = self.line_no + 1;
        let got = read_line_bounded(&mut self.input, &mut self.line, n)?;
        if got == 0 {
            return Ok(None);
        }
        self.line_no = n;
        let l = core::str::from_utf8(&self.line).map_err(|_| CaptureError {
            line: n,
            cause: "not text (invalid UTF-8)".into(),
        })?;
        Ok(Some((n, l.trim())))
    }
}

fn not_sample(line: usize, l: &str, two_fields: bool) -> CaptureError {
    CaptureError {
        line,
        cause: if two_fields {
            format!("`{}` is not two numbers (seconds, volts)", excerpt(l))
        } else {
            format!("expected `time,voltage`, found `{}`", excerpt(l))
        },
    }
}

fn out_of_range(line: usize, t: f64, v: f64) -> CaptureError {
    CaptureError {
        line,
        cause: if t.is_finite() {
            format!(
                "voltage {} V is out of range: expected a finite voltage within ±{:e} V",
                short_number(v),
                f32::MAX
            )
        } else {
            format!(
                "time {} s is out of range: expected a finite time in seconds",
                short_number(t)
            )
        },
    }
}

fn not_increasing(line: usize, t: f64, last: f64) -> CaptureError {
    CaptureError {
        line,
        cause: format!(
            "time {} s does not increase (previous sample {} s)",
            short_number(t),
            short_number(last)
        ),
    }
}

fn check_step(line: usize, dt: f64, median: f64) -> Result<(), CaptureError> {
    if (dt - median).abs() > 0.01 * median {
        return Err(CaptureError {
            line,
            cause: format!(
                "uneven sample spacing: {:.3} ns here, {:.3} ns elsewhere",
                dt * 1e9,
                median * 1e9
            ),
        });
    }
    Ok(())
}
