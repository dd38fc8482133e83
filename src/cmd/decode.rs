//! `asi-lift decode`: a capture of the line decoded into telegrams.

use super::{open_input, print_out};
use asi_phy::{Expect, SimDuration};
use asi_trace::analyser::TrafficAnalyser;
use asi_trace::capture::render::{json_line, stream_summary, text_header, text_line};
use asi_trace::capture::{decode_stream, CaptureFormat, DecodeOptions};
use clap::ValueEnum;
use std::io::Write as _;
use std::ops::ControlFlow;
use std::path::PathBuf;

/// The arguments of `asi-lift decode`.
#[derive(clap::Args)]
pub struct DecodeArgs {
    /// The capture file (`-` for standard input).
    pub file: PathBuf,
    /// The file format [default: VCD if the file starts with `$` or is named *.vcd, else
    /// CSV].
    #[arg(long, value_enum)]
    pub format: Option<InputFormat>,
    /// The VCD signal: its name (`line_voltage`) or dotted path (`rig.bus.line_voltage`);
    /// needed when the file has more than one, except in asi-lift's own VCD, whose pulse wire
    /// `rig.bus.manchester` (the whole run) is read by default.
    #[arg(long, value_name = "NAME")]
    pub signal: Option<String>,
    /// Write one JSON object per telegram and line (t_ns, type, bits, call, address, info,
    /// data, errors) and nothing else; the summary goes to standard error.
    #[arg(long)]
    pub json: bool,
    /// Nominal pulse amplitude in volts [default: estimated from the first 2^20 samples].
    #[arg(long, value_name = "V", value_parser = parse_volts)]
    pub nominal: Option<f32>,
    /// What the receiver listens for.
    #[arg(long, value_enum, default_value_t = Listen::Both)]
    pub expect: Listen,
    /// Sampling period for a VCD real signal, e.g. 40ns [default: the smallest spacing of
    /// its changes, at most 100 ns].
    #[arg(long, value_name = "DURATION")]
    pub sample_period: Option<String>,
}

/// The capture formats of `--format`.
#[derive(Clone, Copy, ValueEnum)]
pub enum InputFormat {
    /// `time,voltage` lines.
    Csv,
    /// A Value Change Dump.
    Vcd,
}

/// What the receiver listens for (`--expect`).
#[derive(Clone, Copy, ValueEnum)]
pub enum Listen {
    /// Master requests only.
    Requests,
    /// Slave responses only.
    Responses,
    /// A live bus: requests and the responses that follow them.
    Both,
}

/// Decodes the capture and prints its telegrams.
pub fn run(args: DecodeArgs) -> Result<u8, String> {
    let DecodeArgs {
        file,
        format,
        signal,
        json,
        nominal,
        expect,
        sample_period,
    } = args;
    let sample_period = match sample_period {
        None => None,
        Some(p) => match p.parse::<SimDuration>() {
            Ok(d) if !d.is_zero() => Some(d),
            Ok(_) => return Err("--sample-period must be longer than zero".into()),
            Err(e) => return Err(format!("--sample-period: {e}")),
        },
    };
    let opts = {
        let mut cfg = DecodeOptions::default();
        cfg.format = match format {
            Some(InputFormat::Csv) => Some(CaptureFormat::Csv),
            Some(InputFormat::Vcd) => Some(CaptureFormat::Vcd),
            None => CaptureFormat::of_path(&file),
        };
        cfg.signal = signal;
        cfg.nominal = nominal;
        cfg.expect = match expect {
            Listen::Requests => Expect::Requests,
            Listen::Responses => Expect::Responses,
            Listen::Both => Expect::Both,
        };
        cfg.sample_period = sample_period;
        cfg
    };
    let (name, input) = open_input(&file)?;
    // Each telegram is printed as it is found; a reader that has gone ends the decode.
    let mut out = std::io::stdout().lock();
    let mut failed = None;
    let mut gone = false;
    let mut header = !json;
    let mut analyser = TrafficAnalyser::default();
    let result = decode_stream(input, &opts, |t| {
        analyser.push(&t);
        let line = if json {
            match json_line(&t) {
                Ok(l) => l,
                Err(e) => {
                    failed = Some(format!("{name}: the telegrams as JSON: {e}"));
                    return ControlFlow::Break(());
                }
            }
        } else if std::mem::take(&mut header) {
            text_header() + &text_line(&t)
        } else {
            text_line(&t)
        };
        match out.write_all(line.as_bytes()) {
            Ok(()) => ControlFlow::Continue(()),
            Err(e) => {
                if e.kind() == std::io::ErrorKind::BrokenPipe {
                    gone = true;
                } else {
                    failed = Some(format!("standard output: {e}"));
                }
                ControlFlow::Break(())
            }
        }
    });
    if let Some(e) = failed {
        return Err(e);
    }
    match out.flush() {
        _ if gone => return Ok(0),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => return Ok(0),
        Err(e) => return Err(format!("standard output: {e}")),
        Ok(()) => {}
    }
    drop(out);
    let summary = result.map_err(|e| format!("{name}: {e}"))?;
    if json {
        eprintln!("{}", stream_summary(&summary));
    } else {
        let mut text = format!("{}\n", stream_summary(&summary));
        text.push_str(&slave_table(analyser));
        print_out(&text)?;
    }
    Ok(0)
}

/// The statistics per slave of the decoded transactions, as an analyser shows them: a
/// heading and a row per slave that answered (docs/master.md, "Statistics per slave"); empty
/// without transactions.
fn slave_table(analyser: TrafficAnalyser) -> String {
    let transactions = analyser.transactions();
    let table = analyser.finish();
    let rule = table.rule();
    let rows = rig::report::slave_reports(&table, None);
    if transactions == 0 || rows.is_empty() {
        return String::new();
    }
    format!(
        "\nper slave, from {transactions} transactions (lights by repeat rate over {} s windows, held {} s):\n{}",
        rule.window.as_secs_f64(),
        rule.hold.as_secs_f64(),
        rig::report::slave_table_text(&rows, false)
    )
}

/// `--nominal`: a positive, finite amplitude in volts that a capture's samples (32-bit floats)
/// can hold.
fn parse_volts(s: &str) -> Result<f32, String> {
    let range = format!("expected a positive number of volts up to {:e}", f32::MAX);
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v <= f64::from(f32::MAX) => Ok(v as f32),
        Ok(v) => Err(format!(
            "{} is out of range: {range}",
            asi_phy::short_number(v)
        )),
        Err(_) => Err(format!("not a number: {range}")),
    }
}
