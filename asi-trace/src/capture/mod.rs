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
//! Decoding is pure and streams: [`decode_stream`] hands over [`TelegramRecord`]s, the shape
//! of the run's trace, as it finds them, timed in the capture's own time base (a CSV's seconds,
//! a VCD's timescale), so that a VCD of a run decodes to the times of the simulator's clock.
//! It reads the input a line at a time and holds only a prefix ([`PREFIX_SAMPLES`]), the
//! telegram in progress and counters, so memory is bounded whatever the capture's size.
//! [`decode_capture`] collects them all; [`render`] renders them.

pub mod render;

use crate::telegrams::TelegramRecord;
use crate::vcd::read::{Change, Timescale, Value, Var, VcdReader};
use asi_phy::waveform::{
    CaptureError, CaptureReader, DemodConfig, Demodulator, Waveform, WaveformError,
};
use asi_phy::{BusTiming, Expect, Polarity, Pulse, Received, Receiver, SimDuration, SimTime};
use core::ops::ControlFlow;
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
#[non_exhaustive]
pub struct DecodeOptions {
    /// The file format; `None` looks at the content ([`CaptureFormat::sniff`]).
    pub format: Option<CaptureFormat>,
    /// The VCD signal to decode: its reference name, full dotted path or trailing scopes.
    /// `None` takes the only variable of the file.
    pub signal: Option<String>,
    /// Nominal pulse amplitude in volts; `None` estimates it from the capture's first
    /// [`PREFIX_SAMPLES`] samples.
    pub nominal: Option<f32>,
    /// What the receiver listens for.
    pub expect: Expect,
    /// The sampling grid for a VCD real signal; `None` takes the smallest spacing between
    /// its first [`PREFIX_SAMPLES`] changes, at most 100 ns.
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

/// The most samples a real VCD signal's grid may hold: a guard against a grid that would
/// take hours to run through (a tiny `--sample-period` or a wrong timescale), not a memory
/// limit, since the samples are never held (2^36: almost two hours at 10 MS/s).
pub const MAX_SAMPLES: u64 = 1 << 36;

/// The longest sampling period chosen for a real VCD signal (the rendering's 10 MS/s).
const MAX_PERIOD_NS: f64 = 100.0;

/// How much of a voltage capture is looked at before decoding starts: the first 2^20 samples
/// (0.1 s at 10 MS/s, 4 MB), or for a real VCD signal its first 2^20 changes. What needs a
/// look at the capture is judged on this prefix, so memory stays bounded whatever the
/// capture's length: a CSV's period and spacing rule, a real signal's sampling grid (the
/// smallest spacing of its changes), the estimated nominal amplitude and the comparator's
/// first baseline. A capture no longer than the prefix decodes as if read whole.
pub const PREFIX_SAMPLES: usize = 1 << 20;

/// Samples handed to the comparator at a time.
const CHUNK: usize = 1 << 16;

/// What a decode found besides the telegrams: the numbers of the closing summary
/// ([`render::summary`]).
#[derive(Clone, Debug, PartialEq)]
pub struct DecodeSummary {
    /// Telegrams found.
    pub telegrams: usize,
    /// Those that passed every check.
    pub valid: usize,
    /// Pulses found on the line.
    pub pulses: usize,
    /// What they were read from.
    pub source: CaptureSource,
}

impl Decoded {
    /// The numbers of the closing summary.
    pub fn summary(&self) -> DecodeSummary {
        DecodeSummary {
            telegrams: self.telegrams.len(),
            valid: self.valid(),
            pulses: self.pulses,
            source: self.source.clone(),
        }
    }
}

/// Decodes the capture read from `input` into telegrams, all of them in memory; see
/// [`decode_stream`] for a capture of any size.
pub fn decode_capture(input: impl BufRead, opts: &DecodeOptions) -> Result<Decoded, DecodeError> {
    let mut telegrams = Vec::new();
    let s = decode_stream(input, opts, |t| {
        telegrams.push(t);
        ControlFlow::Continue(())
    })?;
    Ok(Decoded {
        telegrams,
        pulses: s.pulses,
        source: s.source,
    })
}

/// Decodes the capture read from `input`, calling `sink` with every telegram as it is found,
/// in time order, and returns the summary. Memory is bounded whatever the capture's length:
/// the input is read a line at a time, and only a prefix ([`PREFIX_SAMPLES`]), the telegram
/// being received and counters are held. `sink` returning [`ControlFlow::Break`] ends the
/// decode early (the reader has gone); the summary then counts what was found so far.
///
/// A malformed line after some telegrams were handed over is still an error: the telegrams
/// before it stand.
pub fn decode_stream(
    mut input: impl BufRead,
    opts: &DecodeOptions,
    mut sink: impl FnMut(TelegramRecord) -> ControlFlow<()>,
) -> Result<DecodeSummary, DecodeError> {
    let format = match opts.format {
        Some(f) => f,
        None => CaptureFormat::sniff(input.fill_buf().map_err(|e| CaptureError {
            line: 1,
            cause: e.to_string(),
        })?),
    };
    let mut out = Telegrams {
        rx: Receiver::new(BusTiming::default().receiver(opts.expect)),
        origin_ns: 0,
        sink: &mut sink,
        telegrams: 0,
        valid: 0,
        pulses: 0,
        stopped: false,
    };
    let source = match format {
        CaptureFormat::Csv => stream_csv(input, opts, &mut out)?,
        CaptureFormat::Vcd => stream_vcd(input, opts, &mut out)?,
    };
    Ok(DecodeSummary {
        telegrams: out.telegrams,
        valid: out.valid,
        pulses: out.pulses,
        source,
    })
}

/// Decodes a CSV capture of line voltage; times are the file's seconds.
pub fn decode_csv(text: &str, opts: &DecodeOptions) -> Result<Decoded, DecodeError> {
    let opts = DecodeOptions {
        format: Some(CaptureFormat::Csv),
        ..opts.clone()
    };
    decode_capture(text.as_bytes(), &opts)
}

/// Decodes a VCD capture; times are the file's times in its timescale, in nanoseconds.
pub fn decode_vcd(input: impl BufRead, opts: &DecodeOptions) -> Result<Decoded, DecodeError> {
    let opts = DecodeOptions {
        format: Some(CaptureFormat::Vcd),
        ..opts.clone()
    };
    decode_capture(input, &opts)
}

/// The receiver and what has left it: every telegram goes to the sink as it completes.
struct Telegrams<'s> {
    rx: Receiver,
    /// Added to every telegram's time (a CSV's first time).
    origin_ns: i64,
    sink: &'s mut dyn FnMut(TelegramRecord) -> ControlFlow<()>,
    telegrams: usize,
    valid: usize,
    pulses: usize,
    /// The sink asked to stop.
    stopped: bool,
}

impl Telegrams<'_> {
    fn pulse(&mut self, p: Pulse) {
        self.pulses += 1;
        if let Some(r) = self.rx.push(p) {
            self.emit(&r);
        }
    }

    /// The end of the capture: the telegram in progress is complete.
    fn finish(&mut self) {
        if let Some(r) = self.rx.flush() {
            self.emit(&r);
        }
    }

    fn emit(&mut self, r: &Received) {
        if self.stopped {
            return;
        }
        let t = self
            .origin_ns
            .saturating_add(r.start.as_nanos().min(i64::MAX as u64) as i64);
        let record = TelegramRecord::received(t, r);
        self.telegrams += 1;
        self.valid += usize::from(record.is_valid());
        if (self.sink)(record).is_break() {
            self.stopped = true;
        }
    }

    /// The error that ends a VCD reader's loop when the sink has stopped; never shown.
    fn stop_reading() -> CaptureError {
        CaptureError {
            line: 0,
            cause: String::new(),
        }
    }
}

/// A CSV capture read a buffer at a time.
fn stream_csv(
    input: impl BufRead,
    opts: &DecodeOptions,
    out: &mut Telegrams<'_>,
) -> Result<CaptureSource, DecodeError> {
    let (mut reader, head) = CaptureReader::open(input, PREFIX_SAMPLES)?;
    // The waveform starts at zero: the file's first time is added back to every telegram.
    out.origin_ns = (head.first_time_s * 1e9).round() as i64;
    let wf = head.waveform;
    let mut comp = Comparator::new(wf.start, wf.period_ns, opts.nominal);
    comp.push(&wf.samples, out)?;
    drop(wf);
    let mut buf = Vec::with_capacity(CHUNK);
    while !out.stopped {
        reader.read(&mut buf, CHUNK)?;
        if buf.is_empty() {
            break;
        }
        comp.push(&buf, out)?;
    }
    comp.finish(None, out)
}

/// A VCD capture, its chosen signal.
fn stream_vcd(
    input: impl BufRead,
    opts: &DecodeOptions,
    out: &mut Telegrams<'_>,
) -> Result<CaptureSource, DecodeError> {
    let reader = VcdReader::new(input)?;
    let var = choose_signal(reader.vars(), opts.signal.as_deref())?.clone();
    if var.is_real() {
        stream_vcd_voltage(reader, &var, opts, out)
    } else if var.width == 1 && !var.is_string() {
        stream_vcd_wire(reader, &var, out)
    } else {
        Err(DecodeError::Undecodable {
            signal: var.to_string(),
        })
    }
}

/// The variable `wanted` names; if no name is given, the only one, or in a file of asi-lift's
/// own the pulse wire ([`crate::vcd::PULSE_WIRE`]), which holds the whole run where the line
/// voltage holds only the waveform window.
fn choose_signal<'v>(vars: &'v [Var], wanted: Option<&str>) -> Result<&'v Var, DecodeError> {
    let listed = |vs: &[&Var]| vs.iter().map(|v| v.to_string()).collect::<Vec<_>>();
    let all: Vec<&Var> = vars.iter().collect();
    let Some(wanted) = wanted else {
        let pulse_wire = crate::vcd::BUS_SCOPE.join(".") + "." + crate::vcd::PULSE_WIRE;
        let own = vars
            .iter()
            .find(|v| v.path == pulse_wire && v.width == 1 && !v.is_real() && !v.is_string());
        return match (all.as_slice(), own) {
            ([one], _) => Ok(one),
            (_, Some(own)) => Ok(own),
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
fn stream_vcd_wire<R: BufRead>(
    reader: VcdReader<R>,
    var: &Var,
    out: &mut Telegrams<'_>,
) -> Result<CaptureSource, DecodeError> {
    let ts = reader.timescale();
    // Whether the line's level is known; until it is, a 1 is the idle line, not a pulse.
    let mut known = false;
    let read = reader.for_each_change(&var.id, |c| {
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
        out.pulse(Pulse::new(at, polarity));
        if out.stopped {
            return Err(Telegrams::stop_reading());
        }
        Ok(())
    });
    match read {
        Err(_) if out.stopped => {}
        r => r?,
    }
    out.finish();
    Ok(CaptureSource::Wire {
        signal: var.path.clone(),
    })
}

/// The line voltage: held between its changes onto an even grid, then demodulated like a CSV.
fn stream_vcd_voltage<R: BufRead>(
    reader: VcdReader<R>,
    var: &Var,
    opts: &DecodeOptions,
    out: &mut Telegrams<'_>,
) -> Result<CaptureSource, DecodeError> {
    let ts = reader.timescale();
    let mut grid = Grid {
        ts,
        sample_period: opts.sample_period.map(|p| p.as_nanos() as f64),
        nominal: opts.nominal,
        start_ns: 0,
        held: Vec::new(),
        last: None,
        running: None,
    };
    // An error of the grid or the comparator, which the reader's loop cannot carry.
    let mut failed = None;
    let read = reader.for_each_change(&var.id, |c| {
        let v = match c.value {
            Value::Real(v) if v.is_finite() && (v as f32).is_finite() => v as f32,
            Value::Real(v) => {
                return Err(CaptureError {
                    line: c.line,
                    cause: format!(
                        "{var}: {} is out of range: expected a finite voltage within ±{:e} V",
                        asi_phy::short_number(v),
                        f32::MAX
                    ),
                })
            }
            _ => {
                return Err(CaptureError {
                    line: c.line,
                    cause: format!("{var} needs a finite real value (r1.25)"),
                })
            }
        };
        match grid.last {
            // The last record at a time wins.
            Some((t, ref mut last)) if t == c.time => *last = v,
            prev => {
                if prev.is_none() {
                    grid.start_ns = vcd_nanos(ts, &c)?;
                }
                if let Err(e) = grid.commit(prev, out) {
                    failed = Some(e);
                    return Err(Telegrams::stop_reading());
                }
                grid.last = Some((c.time, v));
            }
        }
        if out.stopped {
            return Err(Telegrams::stop_reading());
        }
        Ok(())
    });
    if let Some(e) = failed {
        return Err(e);
    }
    match read {
        Err(_) if out.stopped => {}
        r => r?,
    }
    let last = grid.last.take();
    grid.commit(last, out)?;
    if grid.running.is_none() {
        grid.start(out)?;
    }
    let Some(mut g) = grid.running.take() else {
        unreachable!("the grid has started")
    };
    // The grid ends at the last change.
    if let Some(cur) = g.cur {
        let span = ts.to_nanos_f64(cur.0 - g.first);
        let n = (span / g.period_ns).floor() as u64 + 1;
        g.emit_n(cur.1, n.saturating_sub(g.next), out)?;
    }
    g.comp.push(&g.chunk, out)?;
    g.comp.finish(Some(var.path.clone()), out)
}

/// A real VCD signal's changes onto an even grid: the first [`PREFIX_SAMPLES`] changes are
/// held to choose the grid's period, then every change is run through as it comes.
struct Grid {
    ts: Timescale,
    /// The period asked for, ns.
    sample_period: Option<f64>,
    /// The nominal amplitude asked for.
    nominal: Option<f32>,
    /// The first change's time, ns.
    start_ns: u64,
    /// The changes held before the grid starts: (time in units, volts), one per time.
    held: Vec<(u64, f32)>,
    /// The latest change, which a record at the same time may still replace.
    last: Option<(u64, f32)>,
    running: Option<Running>,
}

/// The grid under way.
struct Running {
    ts: Timescale,
    /// The first change's time, units.
    first: u64,
    period_ns: f64,
    /// Index of the next grid point.
    next: u64,
    /// The change in force.
    cur: Option<(u64, f32)>,
    /// Samples not yet handed to the comparator.
    chunk: Vec<f32>,
    comp: Comparator,
}

impl Grid {
    /// Takes a change whose value is final.
    fn commit(
        &mut self,
        change: Option<(u64, f32)>,
        out: &mut Telegrams<'_>,
    ) -> Result<(), DecodeError> {
        let Some(change) = change else { return Ok(()) };
        match &mut self.running {
            Some(g) => g.advance(change, out),
            None => {
                self.held.push(change);
                if self.held.len() >= PREFIX_SAMPLES {
                    self.start(out)?;
                }
                Ok(())
            }
        }
    }

    /// Chooses the period from the held changes and runs them through.
    fn start(&mut self, out: &mut Telegrams<'_>) -> Result<(), DecodeError> {
        let ts = self.ts;
        let held = core::mem::take(&mut self.held);
        let period_ns = match self.sample_period {
            Some(p) => p,
            None => held
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
        let g = self.running.insert(Running {
            ts,
            first: held.first().map_or(0, |c| c.0),
            period_ns,
            next: 0,
            cur: None,
            chunk: Vec::with_capacity(CHUNK),
            comp: Comparator::new(SimTime::from_nanos(self.start_ns), period_ns, self.nominal),
        });
        for c in held {
            g.advance(c, out)?;
        }
        Ok(())
    }
}

impl Running {
    /// Grid point i at first + i · period holds the last change at or before it; a change a
    /// hair after a grid point (float rounding) counts as on it. A new change fills the grid
    /// points before it with the change in force.
    fn advance(&mut self, change: (u64, f32), out: &mut Telegrams<'_>) -> Result<(), DecodeError> {
        let Some(cur) = self.cur else {
            self.cur = Some(change);
            return Ok(());
        };
        let at = self.ts.to_nanos_f64(change.0 - self.first);
        let needed = (at / self.period_ns).floor() as u64 + 1;
        if needed > MAX_SAMPLES {
            return Err(DecodeError::TooManySamples {
                samples: needed,
                period_ns: self.period_ns,
            });
        }
        let eps = self.period_ns * 1e-6;
        // The points surely before the change at once (a long flat span is run through in
        // bounded time), the last one or two by the exact rule.
        let surely = (((at - eps) / self.period_ns).floor() as u64).saturating_sub(1);
        self.emit_n(cur.1, surely.saturating_sub(self.next), out)?;
        while self.next as f64 * self.period_ns + eps < at && !out.stopped {
            self.emit(cur.1, out)?;
        }
        self.cur = Some(change);
        Ok(())
    }

    /// `n` grid points of the value `v`. The comparator always gets whole chunks, as from
    /// [`Running::emit`] one at a time; the whole chunks of a long span go in as one constant
    /// run, in time bounded by the comparator's settling, not by `n`.
    fn emit_n(&mut self, v: f32, mut n: u64, out: &mut Telegrams<'_>) -> Result<(), DecodeError> {
        while n > 0 && !self.chunk.is_empty() && !out.stopped {
            self.emit(v, out)?;
            n -= 1;
        }
        let bulk = n / CHUNK as u64 * CHUNK as u64;
        if bulk > 0 && !out.stopped {
            self.comp.push_constant(v, bulk, out)?;
            self.next += bulk;
            n -= bulk;
        }
        while n > 0 && !out.stopped {
            self.emit(v, out)?;
            n -= 1;
        }
        Ok(())
    }

    fn emit(&mut self, v: f32, out: &mut Telegrams<'_>) -> Result<(), DecodeError> {
        self.chunk.push(v);
        self.next += 1;
        if self.chunk.len() == CHUNK {
            self.comp.push(&self.chunk, out)?;
            self.chunk.clear();
        }
        Ok(())
    }
}

/// Sampled voltage through the comparator into the receiver. The first [`PREFIX_SAMPLES`]
/// samples are held to estimate the nominal amplitude (unless it is given) and to start the
/// comparator's baseline; the rest go straight through. A flat block (no amplitude to
/// estimate: a line not yet powered, a bus not yet started) is kept as runs of equal samples,
/// which a flat line makes few, and the estimate is tried on the next block; the first block
/// that is not flat sets the amplitude, and the runs go through the comparator before it.
struct Comparator {
    start: SimTime,
    period_ns: f64,
    /// The amplitude given, then the one used (`None`: a flat line).
    nominal: Option<f32>,
    held: Vec<f32>,
    /// The flat blocks before `held`: (value, count) runs.
    quiet: Vec<(f32, u64)>,
    state: CompState,
    samples: u64,
}

enum CompState {
    Holding,
    Running(Demodulator),
    /// A flat line to its end: no pulses.
    Flat,
}

impl Comparator {
    fn new(start: SimTime, period_ns: f64, nominal: Option<f32>) -> Comparator {
        Comparator {
            start,
            period_ns,
            nominal,
            held: Vec::new(),
            quiet: Vec::new(),
            state: CompState::Holding,
            samples: 0,
        }
    }

    fn push(&mut self, samples: &[f32], out: &mut Telegrams<'_>) -> Result<(), DecodeError> {
        self.samples += samples.len() as u64;
        match &mut self.state {
            CompState::Running(d) => d.push(samples, |p| out.pulse(p)),
            CompState::Flat => {}
            CompState::Holding => {
                self.held.extend_from_slice(samples);
                if self.held.len() >= PREFIX_SAMPLES {
                    self.judge(false, out)?;
                }
            }
        }
        Ok(())
    }

    /// `n` samples of the one value `v`, as [`Comparator::push`] of them all would; `n` and
    /// the samples pushed before are whole chunks, so that the held blocks are judged where
    /// they would be. Time is bounded by the comparator's settling, not by `n`.
    fn push_constant(
        &mut self,
        v: f32,
        n: u64,
        out: &mut Telegrams<'_>,
    ) -> Result<(), DecodeError> {
        self.samples += n;
        let mut n = n;
        if matches!(self.state, CompState::Holding) {
            let k = n.min((PREFIX_SAMPLES - self.held.len()) as u64);
            self.held.extend(std::iter::repeat_n(v, k as usize));
            n -= k;
            if self.held.len() >= PREFIX_SAMPLES {
                self.judge(false, out)?;
            }
        }
        match &mut self.state {
            CompState::Running(d) => d.push_constant(v, n, |p| out.pulse(p)),
            CompState::Flat => {}
            CompState::Holding => {
                // Whole blocks of one value are flat: quiet line, as judging each would find.
                let whole = n / PREFIX_SAMPLES as u64 * PREFIX_SAMPLES as u64;
                if whole > 0 {
                    match self.quiet.last_mut() {
                        Some((w, m)) if w.to_bits() == v.to_bits() => *m += whole,
                        _ => self.quiet.push((v, whole)),
                    }
                }
                self.held
                    .extend(std::iter::repeat_n(v, (n - whole) as usize));
            }
        }
        Ok(())
    }

    /// Estimates the amplitude on the held block and starts the comparator, or keeps the
    /// block as quiet line; at the `end`, a line quiet throughout is flat.
    fn judge(&mut self, end: bool, out: &mut Telegrams<'_>) -> Result<(), DecodeError> {
        let held = core::mem::take(&mut self.held);
        let Some(nominal_amplitude) = self.nominal.or_else(|| amplitude_of(&held)) else {
            for &v in &held {
                match self.quiet.last_mut() {
                    Some((w, n)) if w.to_bits() == v.to_bits() => *n += 1,
                    _ => self.quiet.push((v, 1)),
                }
            }
            if end {
                self.state = CompState::Flat;
            }
            return Ok(());
        };
        self.nominal = Some(nominal_amplitude);
        let cfg = {
            let mut cfg = DemodConfig::default();
            cfg.nominal_amplitude = nominal_amplitude;
            cfg
        };
        let mut d = Demodulator::new(cfg, self.start, self.period_ns)?;
        let mut buf = Vec::new();
        // Whether the comparator has had its first samples (which set its first baseline).
        let mut started = false;
        for (v, mut n) in core::mem::take(&mut self.quiet) {
            while n > 0 {
                if started && buf.is_empty() && n >= CHUNK as u64 {
                    // The rest of a long run at once: the chunks' bounds no longer matter.
                    d.push_constant(v, n, |p| out.pulse(p));
                    break;
                }
                buf.push(v);
                n -= 1;
                if buf.len() == CHUNK {
                    d.push(&buf, |p| out.pulse(p));
                    buf.clear();
                    started = true;
                }
            }
        }
        // An empty push would fix the baseline at 0 V before the first samples are seen.
        if !buf.is_empty() {
            d.push(&buf, |p| out.pulse(p));
        }
        d.push(&held, |p| out.pulse(p));
        self.state = CompState::Running(d);
        Ok(())
    }

    /// The end of the samples.
    fn finish(
        mut self,
        signal: Option<String>,
        out: &mut Telegrams<'_>,
    ) -> Result<CaptureSource, DecodeError> {
        if matches!(self.state, CompState::Holding) {
            self.judge(true, out)?;
        }
        if let CompState::Running(d) = &mut self.state {
            d.finish(|p| out.pulse(p));
        }
        out.finish();
        Ok(CaptureSource::Voltage {
            signal,
            samples: self.samples as usize,
            period_ns: self.period_ns,
            nominal: self.nominal,
        })
    }
}

/// A robust estimate of the pulse amplitude: the 99.5th percentile of the distance from the
/// median sample (the median is the idle line). `None` for a flat line. Decoding estimates it
/// on the capture's first [`PREFIX_SAMPLES`] samples.
pub fn estimate_amplitude(wf: &Waveform) -> Option<f32> {
    amplitude_of(&wf.samples)
}

fn amplitude_of(samples: &[f32]) -> Option<f32> {
    let mut v: Vec<f32> = samples.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    let mid = v.len() / 2;
    let median = *v.select_nth_unstable_by(mid, f32::total_cmp).1;
    for x in &mut v {
        *x = (*x - median).abs();
    }
    let k = ((v.len() - 1) as f64 * 0.995) as usize;
    let a = *v.select_nth_unstable_by(k, f32::total_cmp).1;
    (a > 0.0).then_some(a)
}

#[cfg(test)]
mod tests;
