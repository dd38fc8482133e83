//! Captures of the line decoded into telegrams (`asi-lift decode`; docs/physical-layer.md).
//!
//! A capture is an oscilloscope's `time,voltage` CSV, or a VCD with one of two signals:
//!
//! - the line voltage, a real variable: held between its changes onto an even sampling grid
//!   and read like a CSV, by the comparator demodulator and the receiver;
//! - the demodulated Manchester line, a 1-bit wire (idle high, as a logic analyser on a
//!   receiver's comparator output shows it): every record is one pulse, `0` negative and `1`
//!   positive, even one that repeats the current value (asi-lift writes a record per pulse,
//!   so two pulses of one polarity, a line fault, stay visible). The pulses go straight to the
//!   receiver.
//!
//! Decoding is pure: [`decode_capture`] returns [`TelegramRecord`]s, the shape of the run's
//! trace, timed in the capture's own time base (a CSV's seconds, a VCD's timescale), so that a
//! VCD of a run decodes to the times of the simulator's clock. [`render::to_text`] and
//! [`render::to_json_lines`] render them.

pub mod render;

use crate::telegrams::TelegramRecord;
use crate::vcd::read::{Change, Timescale, Value, Var, VcdReader};
use asi_phy::waveform::{
    read_capture, CaptureError, DemodConfig, Demodulator, Waveform, WaveformError,
};
use asi_phy::{BusTiming, Expect, Polarity, Pulse, Received, Receiver, SimDuration, SimTime};
use std::io::BufRead;
use std::path::Path;

/// The file format of a capture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CaptureFormat {
    /// `time,voltage` lines, as oscilloscopes export them.
    Csv,
    /// A Value Change Dump.
    Vcd,
}

impl CaptureFormat {
    /// The format a file name says: `.vcd` is a VCD; other names say nothing.
    pub fn of_path(path: &Path) -> Option<CaptureFormat> {
        path.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("vcd"))
            .then_some(CaptureFormat::Vcd)
    }

    /// The format of a file that begins with `head`: a VCD begins with a `$` command
    /// (`$date`, `$timescale`, `$comment`, …) after optional whitespace; anything else is
    /// taken for a CSV.
    pub fn sniff(head: &[u8]) -> CaptureFormat {
        match head.iter().find(|b| !b.is_ascii_whitespace()) {
            Some(b'$') => CaptureFormat::Vcd,
            _ => CaptureFormat::Csv,
        }
    }
}

/// How to decode a capture.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodeOptions {
    /// The file format; `None` looks at the content ([`CaptureFormat::sniff`]).
    pub format: Option<CaptureFormat>,
    /// The VCD signal to decode: its reference name, full dotted path or trailing scopes.
    /// `None` takes the only variable of the file.
    pub signal: Option<String>,
    /// Nominal pulse amplitude in volts; `None` estimates it from the capture.
    pub nominal: Option<f32>,
    /// What the receiver listens for.
    pub expect: Expect,
    /// The sampling grid for a VCD real signal; `None` takes the smallest spacing between
    /// its changes, at most 100 ns.
    pub sample_period: Option<SimDuration>,
}

impl Default for DecodeOptions {
    /// Detect the format, one signal, estimate the amplitude, a live bus.
    fn default() -> Self {
        DecodeOptions {
            format: None,
            signal: None,
            nominal: None,
            expect: Expect::Both,
            sample_period: None,
        }
    }
}

/// What the telegrams were read from.
#[derive(Clone, Debug, PartialEq)]
pub enum CaptureSource {
    /// Sampled line voltage: a CSV, or a VCD real variable held onto a grid.
    Voltage {
        /// The VCD variable (`None` for a CSV).
        signal: Option<String>,
        /// Number of samples.
        samples: usize,
        /// Time between samples, ns.
        period_ns: f64,
        /// The nominal amplitude the comparator used; `None` for a flat line.
        nominal: Option<f32>,
    },
    /// A VCD wire with the demodulated line, one record per pulse.
    Wire {
        /// The VCD variable.
        signal: String,
    },
}

/// A decoded capture.
#[derive(Clone, Debug, PartialEq)]
pub struct Decoded {
    /// The telegrams in time order.
    pub telegrams: Vec<TelegramRecord>,
    /// Number of pulses found on the line.
    pub pulses: usize,
    /// What they were read from.
    pub source: CaptureSource,
}

impl Decoded {
    /// Number of telegrams that passed every check.
    pub fn valid(&self) -> usize {
        self.telegrams.iter().filter(|t| t.is_valid()).count()
    }
}

/// Why a capture could not be decoded.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DecodeError {
    /// The file is malformed at a line.
    #[error(transparent)]
    File(#[from] CaptureError),
    /// The VCD signal asked for does not exist, or none was asked for among several.
    #[error("{}; the file has: {}", match .wanted {
        Some(w) => format!("no signal `{w}`"),
        None => "several signals: choose one with --signal NAME".into(),
    }, .available.join(", "))]
    NoSignal {
        /// The name asked for.
        wanted: Option<String>,
        /// The file's signals, as `path (type)`.
        available: Vec<String>,
    },
    /// The name fits several signals.
    #[error("`{wanted}` names several signals: {}; give the full path", .matches.join(", "))]
    Ambiguous {
        /// The name asked for.
        wanted: String,
        /// The signals it fits.
        matches: Vec<String>,
    },
    /// The signal cannot carry the line.
    #[error(
        "signal {signal} cannot be decoded: the line is a real variable (its voltage) or a 1-bit \
         wire (the demodulated line)"
    )]
    Undecodable {
        /// The signal, as `path (type, width)`.
        signal: String,
    },
    /// A real signal's grid would hold too many samples.
    #[error(
        "{samples} samples every {period_ns} ns are too many (at most {MAX_SAMPLES}): give a \
         longer --sample-period"
    )]
    TooManySamples {
        /// Samples the grid would hold.
        samples: u64,
        /// The grid's period, ns.
        period_ns: f64,
    },
    /// A demodulator setting is out of range (the nominal amplitude).
    #[error(transparent)]
    Settings(#[from] WaveformError),
}

/// The most samples a real VCD signal is held onto (512 MB of `f32`).
pub const MAX_SAMPLES: u64 = 1 << 27;

/// The longest sampling period chosen for a real VCD signal (the rendering's 10 MS/s).
const MAX_PERIOD_NS: f64 = 100.0;

/// Decodes the capture read from `input` into telegrams.
pub fn decode_capture(
    mut input: impl BufRead,
    opts: &DecodeOptions,
) -> Result<Decoded, DecodeError> {
    let format = match opts.format {
        Some(f) => f,
        None => CaptureFormat::sniff(input.fill_buf().map_err(|e| CaptureError {
            line: 1,
            cause: e.to_string(),
        })?),
    };
    match format {
        CaptureFormat::Csv => decode_csv(&read_text(input)?, opts),
        CaptureFormat::Vcd => decode_vcd(input, opts),
    }
}

/// Decodes a CSV capture of line voltage; times are the file's seconds.
pub fn decode_csv(text: &str, opts: &DecodeOptions) -> Result<Decoded, DecodeError> {
    let cap = read_capture(text)?;
    // The waveform starts at zero: the file's first time is added back to every telegram.
    let origin_ns = (cap.first_time_s * 1e9).round() as i64;
    decode_voltage(&cap.waveform, origin_ns, None, opts)
}

/// Decodes a VCD capture; times are the file's times in its timescale, in nanoseconds.
pub fn decode_vcd(input: impl BufRead, opts: &DecodeOptions) -> Result<Decoded, DecodeError> {
    let reader = VcdReader::new(input)?;
    let var = choose_signal(reader.vars(), opts.signal.as_deref())?.clone();
    if var.is_real() {
        decode_vcd_voltage(reader, &var, opts)
    } else if var.width == 1 && !var.is_string() {
        decode_vcd_wire(reader, &var, opts)
    } else {
        Err(DecodeError::Undecodable {
            signal: var.to_string(),
        })
    }
}

/// The variable `wanted` names, or the only one if no name is given.
fn choose_signal<'v>(vars: &'v [Var], wanted: Option<&str>) -> Result<&'v Var, DecodeError> {
    let listed = |vs: &[&Var]| vs.iter().map(|v| v.to_string()).collect::<Vec<_>>();
    let all: Vec<&Var> = vars.iter().collect();
    let Some(wanted) = wanted else {
        return match all.as_slice() {
            [one] => Ok(one),
            _ => Err(DecodeError::NoSignal {
                wanted: None,
                available: listed(&all),
            }),
        };
    };
    // A full path wins over a shorter name that also fits it.
    let exact: Vec<&Var> = vars.iter().filter(|v| v.path == wanted).collect();
    let mut fits = if exact.is_empty() {
        vars.iter().filter(|v| v.is_named(wanted)).collect()
    } else {
        exact
    };
    // Aliases (one identifier code declared in several scopes) are one signal.
    let mut seen = std::collections::HashSet::new();
    fits.retain(|v| seen.insert(v.id.as_str()));
    match fits.as_slice() {
        [one] => Ok(one),
        [] => Err(DecodeError::NoSignal {
            wanted: Some(wanted.to_owned()),
            available: listed(&all),
        }),
        _ => Err(DecodeError::Ambiguous {
            wanted: wanted.to_owned(),
            matches: listed(&fits),
        }),
    }
}

/// A VCD time in nanoseconds for a telegram's time stamp.
fn vcd_nanos(ts: Timescale, c: &Change<'_>) -> Result<u64, CaptureError> {
    ts.to_nanos(c.time)
        .filter(|&ns| ns <= i64::MAX as u64)
        .ok_or_else(|| CaptureError {
            line: c.line,
            cause: format!("time #{} ({ts} units) is beyond 292 years", c.time),
        })
}

/// The demodulated line: every record a pulse, straight into the receiver.
fn decode_vcd_wire<R: BufRead>(
    reader: VcdReader<R>,
    var: &Var,
    opts: &DecodeOptions,
) -> Result<Decoded, DecodeError> {
    let ts = reader.timescale();
    let mut rx = Receiver::new(BusTiming::default().receiver(opts.expect));
    let mut found = Vec::new();
    let mut pulses = 0;
    // Whether the line's level is known; until it is, a 1 is the idle line, not a pulse.
    let mut known = false;
    reader.for_each_change(&var.id, |c| {
        let level = match c.value {
            Value::Bit(b) => b,
            // `b1 !` is a 1-bit vector's way of writing `1!`.
            Value::Vector(v) => v.chars().last().map_or('x', |b| b.to_ascii_lowercase()),
            Value::Real(_) | Value::Text => {
                return Err(CaptureError {
                    line: c.line,
                    cause: format!("{var} holds a real or string value"),
                })
            }
        };
        if c.dump {
            // `$dumpvars` and its kin state the current level: no pulse.
            known = matches!(level, '0' | '1');
            return Ok(());
        }
        let polarity = match level {
            '0' => Polarity::Negative,
            '1' if !known => {
                known = true;
                return Ok(());
            }
            '1' => Polarity::Positive,
            other => {
                return Err(CaptureError {
                    line: c.line,
                    cause: format!(
                        "{} is `{other}` at #{}: the demodulated line is 0 or 1",
                        var.path, c.time
                    ),
                })
            }
        };
        known = true;
        let at = SimTime::from_nanos(vcd_nanos(ts, &c)?);
        pulses += 1;
        found.extend(rx.push(Pulse::new(at, polarity)));
        Ok(())
    })?;
    found.extend(rx.flush());
    Ok(Decoded {
        telegrams: records(&found, 0),
        pulses,
        source: CaptureSource::Wire {
            signal: var.path.clone(),
        },
    })
}

/// The line voltage: held onto an even grid, then demodulated like a CSV.
fn decode_vcd_voltage<R: BufRead>(
    reader: VcdReader<R>,
    var: &Var,
    opts: &DecodeOptions,
) -> Result<Decoded, DecodeError> {
    let ts = reader.timescale();
    // (time in units, volts), one per time: the last record at a time wins.
    let mut changes: Vec<(u64, f32)> = Vec::new();
    let mut start_ns = 0;
    reader.for_each_change(&var.id, |c| {
        let v = match c.value {
            Value::Real(v) if v.is_finite() && (v as f32).is_finite() => v as f32,
            _ => {
                return Err(CaptureError {
                    line: c.line,
                    cause: format!("{var} needs a finite real value (r1.25)"),
                })
            }
        };
        match changes.last_mut() {
            Some(last) if last.0 == c.time => last.1 = v,
            _ => {
                if changes.is_empty() {
                    start_ns = vcd_nanos(ts, &c)?;
                }
                changes.push((c.time, v));
            }
        }
        Ok(())
    })?;
    let period_ns = match opts.sample_period {
        Some(p) => p.as_nanos() as f64,
        None => changes
            .windows(2)
            .map(|w| ts.to_nanos_f64(w[1].0 - w[0].0))
            .fold(MAX_PERIOD_NS, f64::min),
    };
    if period_ns <= 0.0 {
        return Err(DecodeError::Settings(WaveformError {
            field: "sample period",
            value: period_ns,
            rule: "must be positive",
        }));
    }
    let first = changes.first().map_or(0, |c| c.0);
    let span_ns = changes.last().map_or(0.0, |c| ts.to_nanos_f64(c.0 - first));
    let n = if changes.is_empty() {
        0
    } else {
        (span_ns / period_ns).floor() as u64 + 1
    };
    if n > MAX_SAMPLES {
        return Err(DecodeError::TooManySamples {
            samples: n,
            period_ns,
        });
    }
    // Sample i at first + i · period holds the last change at or before it; a change a hair
    // after a grid point (float rounding) counts as on it.
    let eps = period_ns * 1e-6;
    let mut samples = Vec::with_capacity(n as usize);
    let mut k = 0;
    for i in 0..n {
        let t = i as f64 * period_ns + eps;
        while k + 1 < changes.len() && ts.to_nanos_f64(changes[k + 1].0 - first) <= t {
            k += 1;
        }
        samples.push(changes[k].1);
    }
    let wf = Waveform {
        start: SimTime::from_nanos(start_ns),
        period_ns,
        samples,
    };
    decode_voltage(&wf, 0, Some(var.path.clone()), opts)
}

/// Sampled voltage through the comparator and the receiver; telegram times are `origin_ns`
/// plus the waveform's.
fn decode_voltage(
    wf: &Waveform,
    origin_ns: i64,
    signal: Option<String>,
    opts: &DecodeOptions,
) -> Result<Decoded, DecodeError> {
    let nominal = opts.nominal.or_else(|| estimate_amplitude(wf));
    let (found, pulses) = match nominal {
        // A flat line carries no pulses.
        None => (Vec::new(), 0),
        Some(nominal_amplitude) => {
            let demod = DemodConfig {
                nominal_amplitude,
                ..DemodConfig::default()
            };
            let pulses = Demodulator::demodulate(demod, wf)?;
            let mut rx = Receiver::new(BusTiming::default().receiver(opts.expect));
            let found: Vec<Received> = rx.decode(pulses.iter().copied()).collect();
            (found, pulses.len())
        }
    };
    Ok(Decoded {
        telegrams: records(&found, origin_ns),
        pulses,
        source: CaptureSource::Voltage {
            signal,
            samples: wf.samples.len(),
            period_ns: wf.period_ns,
            nominal,
        },
    })
}

fn records(found: &[Received], origin_ns: i64) -> Vec<TelegramRecord> {
    found
        .iter()
        .map(|r| {
            let t = origin_ns.saturating_add(r.start.as_nanos().min(i64::MAX as u64) as i64);
            TelegramRecord::received(t, r)
        })
        .collect()
}

/// A robust estimate of the pulse amplitude: the 99.5th percentile of the distance from the
/// median sample (the median is the idle line). `None` for a flat line.
pub fn estimate_amplitude(wf: &Waveform) -> Option<f32> {
    let mut v: Vec<f32> = wf
        .samples
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f32::total_cmp);
    let median = v[v.len() / 2];
    let mut d: Vec<f32> = v.iter().map(|x| (x - median).abs()).collect();
    d.sort_by(f32::total_cmp);
    let a = d[((d.len() - 1) as f64 * 0.995) as usize];
    (a > 0.0).then_some(a)
}

/// The whole input as text; a line that is not UTF-8 is an error naming it.
fn read_text(mut input: impl BufRead) -> Result<String, CaptureError> {
    let mut text = String::new();
    let mut line = Vec::new();
    for n in 1.. {
        line.clear();
        let got = input
            .read_until(b'\n', &mut line)
            .map_err(|e| CaptureError {
                line: n,
                cause: e.to_string(),
            })?;
        if got == 0 {
            break;
        }
        text.push_str(core::str::from_utf8(&line).map_err(|_| CaptureError {
            line: n,
            cause: "not text (invalid UTF-8)".into(),
        })?);
    }
    Ok(text)
}

#[cfg(test)]
mod tests;
