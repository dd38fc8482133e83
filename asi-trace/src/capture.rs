//! Captures of the line decoded into telegrams (`asi-lift decode`; SPEC §1).
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
//! VCD of a run decodes to the times of the simulator's clock. [`to_text`] and
//! [`to_json_lines`] render them.

use crate::telegrams::TelegramRecord;
use crate::vcd::read::{Change, Timescale, Value, Var, VcdReader};
use asi_phy::waveform::{
    read_capture, CaptureError, DemodConfig, Demodulator, Waveform, WaveformError,
};
use asi_phy::{BusTiming, Expect, Polarity, Pulse, Received, Receiver, SimDuration, SimTime};
use core::fmt;
use std::fmt::Write as _;
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
pub enum Source {
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
    pub source: Source,
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
        source: Source::Wire {
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
        source: Source::Voltage {
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

/// `t_ns` as seconds with nine decimals: `0.000112000`, `-0.000001500`.
pub fn seconds(t_ns: i64) -> String {
    let sign = if t_ns < 0 { "-" } else { "" };
    let a = t_ns.unsigned_abs();
    format!("{sign}{}.{:09}", a / 1_000_000_000, a % 1_000_000_000)
}

impl fmt::Display for Source {
    /// `1201 samples every 100 ns, nominal amplitude 2.500 V` or `wire rig.bus.line`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Source::Voltage {
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
            Source::Wire { signal } => write!(f, "wire {signal}"),
        }
    }
}

/// The closing line: `2 telegrams, 2 valid; 32 pulses from wire rig.bus.line`, or
/// `no telegrams found; …`.
pub fn summary(d: &Decoded) -> String {
    let head = match d.telegrams.len() {
        0 => "no telegrams found".to_owned(),
        1 => format!("1 telegram, {} valid", d.valid()),
        n => format!("{n} telegrams, {} valid", d.valid()),
    };
    format!("{head}; {} pulses from {}", d.pulses, d.source)
}

/// One line per telegram under a header row, and the [`summary`] as the last line.
///
/// ```text
///         time_s  type      bits            call                   address  info   data  errors
///    0.000010000  request   00001010101001  Data_Exchange          5        01010  -     ok
/// ```
pub fn to_text(d: &Decoded) -> String {
    let mut s = String::new();
    let dash = |o: Option<&str>| o.unwrap_or("-").to_owned();
    if !d.telegrams.is_empty() {
        let _ = writeln!(
            s,
            "{:>14}  {:<8}  {:<14}  {:<21}  {:<7}  {:<5}  {:<4}  errors",
            "time_s", "type", "bits", "call", "address", "info", "data"
        );
    }
    for t in &d.telegrams {
        let errors = if t.errors.is_empty() {
            "ok".to_owned()
        } else {
            t.errors.join(",")
        };
        let _ = writeln!(
            s,
            "{:>14}  {:<8}  {:<14}  {:<21}  {:<7}  {:<5}  {:<4}  {errors}",
            seconds(t.t_ns),
            t.kind.name(),
            t.bits,
            dash(t.call),
            t.address.map_or("-".into(), |a| a.to_string()),
            dash(t.info.as_deref()),
            dash(t.data.as_deref()),
        );
    }
    s.push_str(&summary(d));
    s.push('\n');
    s
}

/// One JSON object per telegram and line, the fields of [`TelegramRecord`].
pub fn to_json_lines(d: &Decoded) -> Result<String, serde_json::Error> {
    let mut s = String::new();
    for t in &d.telegrams {
        s.push_str(&serde_json::to_string(t)?);
        s.push('\n');
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::telegrams::TelegramType;
    use asi_phy::waveform::{render, WaveformConfig};
    use asi_phy::{Address, Nibble, PulseTrain, Request, Response};
    use proptest::prelude::*;

    /// SPEC §1 worked vectors: Data_Exchange 5 out=1010 from 10 µs, then the response 0110
    /// 18 µs after the request's last pulse (94 µs).
    fn spec_records() -> Vec<TelegramRecord> {
        vec![
            TelegramRecord {
                t_ns: 10_000,
                kind: TelegramType::Request,
                bits: "00001010101001".into(),
                call: Some("Data_Exchange"),
                address: Some(5),
                info: Some("01010".into()),
                data: None,
                errors: vec![],
            },
            TelegramRecord {
                t_ns: 112_000,
                kind: TelegramType::Response,
                bits: "0011001".into(),
                call: None,
                address: None,
                info: None,
                data: Some("0110".into()),
                errors: vec![],
            },
        ]
    }

    /// Pulses in SPEC §1 notation (`0- 1+ ..`, grid points of 3 µs) from `start_us`.
    fn spec_pulses(spec: &str, start_us: u64) -> Vec<Pulse> {
        spec.split_whitespace()
            .map(|tok| {
                let (k, sign) = tok.split_at(tok.len() - 1);
                let k: u64 = k.parse().expect("grid point");
                let polarity = if sign == "+" {
                    Polarity::Positive
                } else {
                    Polarity::Negative
                };
                Pulse::new(SimTime::from_micros(start_us + 3 * k), polarity)
            })
            .collect()
    }

    fn spec_line() -> Vec<Pulse> {
        let mut p = spec_pulses(
            "0- 1+ 2- 3+ 4- 5+ 6- 7+ 9- 11+ 13- 15+ 17- 19+ 21- 23+ 24- 25+ 27- 28+",
            10,
        );
        p.extend(spec_pulses(
            "0- 1+ 2- 3+ 5- 6+ 7- 9+ 10- 11+ 13- 14+",
            94 + 18,
        ));
        p
    }

    /// A wire VCD as asi-lift writes one: the idle level in `$dumpvars`, then one record per
    /// pulse, `ticks_per_ns` units per nanosecond (a fraction for coarse timescales).
    fn wire_vcd(pulses: &[Pulse], timescale: &str, ticks_per_ns: f64) -> String {
        let mut s = format!(
            "$timescale {timescale} $end\n$scope module rig $end\n$scope module bus $end\n\
             $var wire 1 ! line $end\n$upscope $end\n$upscope $end\n$enddefinitions $end\n\
             #0\n$dumpvars\n1!\n$end\n"
        );
        for p in pulses {
            let t = (p.at.as_nanos() as f64 * ticks_per_ns).round() as u64;
            let v = u8::from(p.polarity == Polarity::Positive);
            let _ = writeln!(s, "#{t}\n{v}!");
        }
        s
    }

    fn decode(text: &str, opts: &DecodeOptions) -> Result<Decoded, DecodeError> {
        decode_capture(text.as_bytes(), opts)
    }

    fn telegrams(text: &str) -> Vec<TelegramRecord> {
        decode(text, &DecodeOptions::default())
            .expect("decodes")
            .telegrams
    }

    /// The worked vectors by hand: a logic analyser's view of the comparator output in µs.
    const SPEC_WIRE_VCD: &str = "\
$date asi-lift test $end
$version hand-written $end
$comment SPEC 1 worked vectors: Data_Exchange 5 out=1010, response 0110 $end
$timescale 1 us $end
$scope module rig $end
$scope module bus $end
$var wire 1 ! line $end
$upscope $end
$upscope $end
$enddefinitions $end
$dumpvars
1!
$end
#10 0!
#13 1!
#16 0!
#19 1!
#22 0!
#25 1!
#28 0!
#31 1!
#37 0!
#43 1!
#49 0!
#55 1!
#61 0!
#67 1!
#73 0!
#79 1!
#82 0!
#85 1!
#91 0!
#94 1!
$comment response 18 us after the last pulse $end
#112 0!
#115 1!
#118 0!
#121 1!
#127 0!
#130 1!
#133 0!
#139 1!
#142 0!
#145 1!
#151 0!
#154 1!
";

    #[test]
    fn a_wire_vcd_of_the_spec_vectors_decodes_to_them() {
        let d = decode(SPEC_WIRE_VCD, &DecodeOptions::default()).expect("decodes");
        assert_eq!(d.telegrams, spec_records());
        assert_eq!(d.pulses, 32);
        assert_eq!(
            d.source,
            Source::Wire {
                signal: "rig.bus.line".into()
            }
        );
        // The hand-written file holds the encoder's pulses.
        assert_eq!(
            telegrams(&wire_vcd(&spec_line(), "1 us", 1e-3)),
            spec_records()
        );
    }

    #[test]
    fn the_timescale_gives_the_time_base() {
        for (ts, ticks_per_ns) in [
            ("1 us", 1e-3),
            ("10 ns", 0.1),
            ("1 ns", 1.0),
            ("100 ps", 10.0),
        ] {
            let got = telegrams(&wire_vcd(&spec_line(), ts, ticks_per_ns));
            assert_eq!(got, spec_records(), "{ts}");
        }
        // The same file read as 1 ms per unit: the telegrams are slow, not there.
        let slow = SPEC_WIRE_VCD.replace("1 us", "1 ms");
        assert!(telegrams(&slow).iter().all(|t| !t.is_valid()));
    }

    #[test]
    fn a_real_vcd_rendered_from_the_pulses_decodes_the_same() {
        let wf = render(
            spec_line(),
            SimTime::ZERO,
            SimTime::from_micros(170),
            &WaveformConfig::default(),
        )
        .expect("render");
        // The voltage is written on change only; the wire rides along in the same file.
        let mut s = String::from(
            "$timescale 1 ns $end\n$scope module rig $end\n$scope module bus $end\n\
             $var real 64 % line_voltage $end\n$var wire 1 ! line $end\n\
             $upscope $end\n$upscope $end\n$enddefinitions $end\n#0\n$dumpvars r0 % 1! $end\n",
        );
        let mut last = 0.0;
        for (i, v) in wf.samples.iter().enumerate() {
            if *v != last {
                let _ = writeln!(s, "#{}\nr{v} %", 100 * i);
                last = *v;
            }
        }
        let _ = writeln!(s, "#170000\nr0 %");
        for signal in ["line_voltage", "bus.line_voltage", "rig.bus.line_voltage"] {
            let opts = DecodeOptions {
                signal: Some(signal.into()),
                ..DecodeOptions::default()
            };
            let d = decode(&s, &opts).expect("decodes");
            assert_eq!(d.telegrams, spec_records(), "{signal}");
            let Source::Voltage {
                samples, period_ns, ..
            } = d.source
            else {
                panic!("{:?}", d.source)
            };
            assert_eq!((samples, period_ns), (1701, 100.0));
        }
        // A grid finer than the changes holds each value over two samples: the line arrives
        // half a change spacing late, well inside the receiver's tolerance.
        let opts = DecodeOptions {
            signal: Some("line_voltage".into()),
            sample_period: Some(SimDuration::from_nanos(50)),
            ..DecodeOptions::default()
        };
        let late: Vec<TelegramRecord> = spec_records()
            .into_iter()
            .map(|t| TelegramRecord {
                t_ns: t.t_ns + 25,
                ..t
            })
            .collect();
        assert_eq!(decode(&s, &opts).expect("50 ns").telegrams, late);
    }

    #[test]
    fn a_csv_with_a_header_and_comments_keeps_its_own_time() {
        // A scope on the 30 V supply whose record starts at 1 ms.
        let cfg = WaveformConfig {
            dc_offset: 30.0,
            ..WaveformConfig::default()
        };
        let wf =
            render(spec_line(), SimTime::ZERO, SimTime::from_micros(170), &cfg).expect("render");
        let mut s = String::from("# exported by a scope\ntime_s,voltage_v\n");
        for (i, v) in wf.samples.iter().enumerate() {
            if i == 500 {
                s.push_str("# a comment among the samples\n");
            }
            let _ = writeln!(s, "{:.9},{v:.5}", 1e-3 + i as f64 * 1e-7);
        }
        let got = telegrams(&s);
        let want: Vec<TelegramRecord> = spec_records()
            .into_iter()
            .map(|t| TelegramRecord {
                t_ns: t.t_ns + 1_000_000,
                ..t
            })
            .collect();
        assert_eq!(got, want);
    }

    #[test]
    fn a_repeated_level_is_a_pulse_so_a_line_fault_stays_visible() {
        // Pulse 6- of the request sent positive: three positive pulses in a row.
        let mut line = spec_line();
        line[6].polarity = Polarity::Positive;
        let got = telegrams(&wire_vcd(&line, "1 ns", 1.0));
        assert_eq!(
            got[0],
            TelegramRecord {
                t_ns: 10_000,
                kind: TelegramType::Request,
                bits: "00001010101001".into(),
                call: None,
                address: None,
                info: None,
                data: None,
                errors: vec!["alternation"],
            }
        );
    }

    #[test]
    fn the_first_high_record_is_the_idle_line() {
        // A logic analyser writes the level at the start of its record, without `$dumpvars`.
        let analyser = SPEC_WIRE_VCD.replace("$dumpvars\n1!\n$end\n", "#0 1!\n");
        assert_eq!(telegrams(&analyser), spec_records());
    }

    #[test]
    fn a_run_of_neither_length_is_unknown() {
        // A response with no request before it: a live-bus receiver waits for a request.
        let lone = spec_pulses("0- 1+ 2- 3+ 5- 6+ 7- 9+ 10- 11+ 13- 14+", 5);
        let got = telegrams(&wire_vcd(&lone, "1 ns", 1.0));
        assert_eq!(got.len(), 1);
        assert_eq!(
            (got[0].kind, got[0].bits.as_str(), got[0].errors.as_slice()),
            (TelegramType::Unknown, "0011001", &["length"][..])
        );
        let d = Decoded {
            telegrams: got,
            pulses: 12,
            source: Source::Wire { signal: "l".into() },
        };
        assert!(to_text(&d).contains("unknown   0011001"), "{}", to_text(&d));
    }

    #[test]
    fn json_lines_carry_the_trace_fields() {
        let d = decode(SPEC_WIRE_VCD, &DecodeOptions::default()).expect("decodes");
        let json = to_json_lines(&d).expect("serialises");
        let lines: Vec<serde_json::Value> = json
            .lines()
            .map(|l| serde_json::from_str(l).expect("JSON"))
            .collect();
        assert_eq!(
            lines,
            [
                serde_json::json!({"t_ns": 10000, "type": "request", "bits": "00001010101001",
                    "call": "Data_Exchange", "address": 5, "info": "01010", "data": null,
                    "errors": []}),
                serde_json::json!({"t_ns": 112000, "type": "response", "bits": "0011001",
                    "call": null, "address": null, "info": null, "data": "0110", "errors": []}),
            ]
        );
        let bad = TelegramRecord::received(
            -1500,
            &Receiver::new(BusTiming::default().receiver(Expect::Requests))
                .decode(spec_pulses("0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 10- 11+", 0))
                .next()
                .expect("a run"),
        );
        let v = serde_json::to_value(&bad).expect("JSON");
        assert_eq!(v["t_ns"], -1500);
        assert_eq!(v["type"], "unknown");
        assert_eq!(v["call"], serde_json::Value::Null);
        assert_eq!(v["errors"], serde_json::json!(["end_bit", "length"]));
    }

    #[test]
    fn text_lines_and_the_summary() {
        let d = decode(SPEC_WIRE_VCD, &DecodeOptions::default()).expect("decodes");
        assert_eq!(
            to_text(&d),
            "        time_s  type      bits            call                   address  info   data  errors\n\
             \x20  0.000010000  request   00001010101001  Data_Exchange          5        01010  -     ok\n\
             \x20  0.000112000  response  0011001         -                      -        -      0110  ok\n\
             2 telegrams, 2 valid; 32 pulses from wire rig.bus.line\n"
        );
        assert_eq!(seconds(-1_500), "-0.000001500");
        assert_eq!(seconds(754_000_000_123), "754.000000123");
        let idle = "$var wire 1 ! line $end $enddefinitions $end\n#0 1!\n#100000\n";
        let d = decode(idle, &DecodeOptions::default()).expect("idle");
        assert_eq!(to_text(&d), "no telegrams found; 0 pulses from wire line\n");
    }

    /// Each bad input: its error and line.
    #[test]
    fn every_bad_capture_names_the_line() {
        let head = "$timescale 1 ns $end\n$var wire 1 ! line $end\n";
        let cases: Vec<(String, usize, &str)> = vec![
            (String::new(), 1, "the file is empty"),
            (
                "time_s,voltage\n".into(),
                1,
                "is a header and no `time,voltage` sample follows",
            ),
            (
                "0,1\n1e-7,1\n2e-7,1\nabc,1\n".into(),
                4,
                "`abc,1` is not two numbers",
            ),
            (
                "0,1\n1e-7,1\n2e-7".into(),
                3,
                "expected `time,voltage`, found `2e-7`",
            ),
            ("0,1\n2e-7,1\n1e-7,1\n".into(), 3, "does not increase"),
            (head.into(), 2, "no `$enddefinitions`"),
            (
                format!("{head}$enddefinitions $end\n#10 0!\n#5 1!\n"),
                5,
                "goes back",
            ),
            (
                format!("{head}$enddefinitions $end\n#10 0!\n#12 1\"\n"),
                5,
                "unknown identifier code `\"`",
            ),
            (
                format!("{head}$enddefinitions $end\n#10 0!\n#12 x!\n"),
                5,
                "line is `x` at #12",
            ),
            (
                format!("{head}$enddefinitions $end\n#10 0!\n#12 r1.5 !\n"),
                5,
                "holds a real",
            ),
        ];
        for (text, line, cause) in cases {
            match decode(&text, &DecodeOptions::default()) {
                Err(DecodeError::File(e)) => {
                    assert_eq!(e.line, line, "{text:?}: {e}");
                    assert!(e.cause.contains(cause), "{text:?}: {e}");
                }
                other => panic!("{text:?}: {other:?}"),
            }
        }
        let not_text = b"0,1\n1e-7,1\n\xff\xfe,1\n";
        let e = decode_capture(&not_text[..], &DecodeOptions::default()).expect_err("binary");
        assert_eq!(e.to_string(), "line 3: not text (invalid UTF-8)");
    }

    #[test]
    fn the_signal_is_named_and_must_carry_the_line() {
        let text = "$timescale 1 ns $end\n$scope module rig $end\n$scope module bus $end\n\
            $var wire 1 ! line $end\n$var real 64 \" line_voltage $end\n$upscope $end\n\
            $scope module plc $end\n$var wire 1 # line $end\n$var wire 4 $ word [3:0] $end\n\
            $var string 1 % state $end\n$upscope $end\n$upscope $end\n$enddefinitions $end\n";
        let named = |s: Option<&str>| {
            decode(
                text,
                &DecodeOptions {
                    signal: s.map(String::from),
                    ..DecodeOptions::default()
                },
            )
        };
        let all = "rig.bus.line (wire), rig.bus.line_voltage (real), rig.plc.line (wire), \
                   rig.plc.word (wire, 4 bits), rig.plc.state (string)";
        assert_eq!(
            named(None).expect_err("several").to_string(),
            format!("several signals: choose one with --signal NAME; the file has: {all}")
        );
        assert_eq!(
            named(Some("volts")).expect_err("none").to_string(),
            format!("no signal `volts`; the file has: {all}")
        );
        assert_eq!(
            named(Some("line")).expect_err("two").to_string(),
            "`line` names several signals: rig.bus.line (wire), rig.plc.line (wire); give the \
             full path"
        );
        assert!(named(Some("bus.line")).is_ok());
        // One identifier code declared in two scopes is one signal.
        let aliased = text.replace("$var wire 1 # line", "$var wire 1 ! line");
        let alias = decode(
            &aliased,
            &DecodeOptions {
                signal: Some("line".into()),
                ..DecodeOptions::default()
            },
        );
        assert!(alias.is_ok(), "{alias:?}");
        assert!(named(Some("rig.plc.line")).is_ok());
        for (s, shown) in [
            ("word", "rig.plc.word (wire, 4 bits)"),
            ("state", "rig.plc.state (string)"),
        ] {
            assert_eq!(
                named(Some(s)).expect_err(s),
                DecodeError::Undecodable {
                    signal: shown.into()
                }
            );
        }
    }

    #[test]
    fn the_format_comes_from_the_content_or_the_name() {
        assert_eq!(
            CaptureFormat::sniff(b"\n  $date x $end"),
            CaptureFormat::Vcd
        );
        assert_eq!(CaptureFormat::sniff(b"$comment\n"), CaptureFormat::Vcd);
        assert_eq!(CaptureFormat::sniff(b"# scope\n0,1\n"), CaptureFormat::Csv);
        assert_eq!(CaptureFormat::sniff(b""), CaptureFormat::Csv);
        assert_eq!(
            CaptureFormat::of_path(Path::new("run.VCD")),
            Some(CaptureFormat::Vcd)
        );
        assert_eq!(CaptureFormat::of_path(Path::new("scope.csv")), None);
        // A .vcd that holds CSV is read as a VCD and says what it found.
        let opts = DecodeOptions {
            format: Some(CaptureFormat::Vcd),
            ..DecodeOptions::default()
        };
        assert_eq!(
            decode("0,1\n", &opts).expect_err("not a VCD").to_string(),
            "line 1: `0,1` is no VCD command (they start with `$`)"
        );
    }

    #[test]
    fn a_written_waveform_decodes_back() {
        let t = crate::encode::parse_call(&["rid1".into(), "7".into()]).expect("call");
        let csv = crate::encode::waveform_csv(t, &WaveformConfig::default()).expect("render");
        let d = decode(&csv, &DecodeOptions::default()).expect("decode");
        assert_eq!(d.telegrams.len(), 1);
        assert_eq!(d.telegrams[0].call, Some("Read_ID1"));
        assert!(to_text(&d).contains("1 telegram, 1 valid; 22 pulses from 1040 samples"));
    }

    proptest! {
        /// Valid requests, some answered, written as a wire VCD: decoded back to themselves at
        /// the simulator's nanosecond times.
        #[test]
        fn requests_in_a_wire_vcd_decode_back(
            calls in proptest::collection::vec(
                (any::<bool>(), 0u8..32, 0u8..32, proptest::option::of(0u8..16)),
                1..8,
            ),
            start in 0u64..1_000_000,
        ) {
            let h = BusTiming::default().half_bit();
            let mut pulses = Vec::new();
            let mut want = Vec::new();
            for (i, (cb, a, info, answer)) in calls.into_iter().enumerate() {
                let address = Address::new(a).expect("0..32");
                let q = Request::from_fields(cb, address, info).expect("5-bit info");
                let t = SimTime::from_nanos(start + 154_000 * i as u64);
                pulses.extend(PulseTrain::request(q, t, h));
                want.push(TelegramRecord::request(t.as_nanos() as i64, q));
                if let Some(d) = answer {
                    let r = Response::new(Nibble::from_low_bits(d));
                    let t = t + SimDuration::from_micros(84 + 18);
                    pulses.extend(PulseTrain::response(r, t, h));
                    want.push(TelegramRecord::response(t.as_nanos() as i64, r));
                }
            }
            prop_assert_eq!(telegrams(&wire_vcd(&pulses, "1 ns", 1.0)), want);
        }
    }
}
