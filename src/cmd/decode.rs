//! `asi-lift decode`: a capture of the line decoded into telegrams.

use super::{open_input, print_out};
use asi_phy::{Expect, SimDuration};
use asi_trace::capture::render::{summary, to_json_lines, to_text};
use asi_trace::capture::{decode_capture, CaptureFormat, DecodeOptions};
use clap::ValueEnum;
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
    /// needed when the file has more than one.
    #[arg(long, value_name = "NAME")]
    pub signal: Option<String>,
    /// Write one JSON object per telegram and line (t_ns, type, bits, call, address, info,
    /// data, errors) and nothing else; the summary goes to standard error.
    #[arg(long)]
    pub json: bool,
    /// Nominal pulse amplitude in volts (estimated from the capture if not given).
    #[arg(long, value_name = "V")]
    pub nominal: Option<f32>,
    /// What the receiver listens for.
    #[arg(long, value_enum, default_value_t = Listen::Both)]
    pub expect: Listen,
    /// Sampling period for a VCD real signal, e.g. 40ns [default: the smallest spacing of
    /// its changes, at most 100 ns].
    #[arg(long, value_name = "DURATION")]
    pub sample_period: Option<String>,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum InputFormat {
    /// `time,voltage` lines.
    Csv,
    /// A Value Change Dump.
    Vcd,
}

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
    let opts = DecodeOptions {
        format: match format {
            Some(InputFormat::Csv) => Some(CaptureFormat::Csv),
            Some(InputFormat::Vcd) => Some(CaptureFormat::Vcd),
            None => CaptureFormat::of_path(&file),
        },
        signal,
        nominal,
        expect: match expect {
            Listen::Requests => Expect::Requests,
            Listen::Responses => Expect::Responses,
            Listen::Both => Expect::Both,
        },
        sample_period,
    };
    let (name, input) = open_input(&file)?;
    let decoded = decode_capture(input, &opts).map_err(|e| format!("{name}: {e}"))?;
    if json {
        print_out(
            &to_json_lines(&decoded).map_err(|e| format!("{name}: the telegrams as JSON: {e}"))?,
        )?;
        eprintln!("{}", summary(&decoded));
    } else {
        print_out(&to_text(&decoded))?;
    }
    Ok(0)
}
