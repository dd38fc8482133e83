//! `asi-lift run`: a scenario on the whole rig, its report, trace and waveforms.

use super::{open_output, plot, print_out, read_input, write_output, EXIT_VIOLATIONS};
use asi_phy::{SimDuration, SimTime};
use asi_trace::trace::TraceFormat;
use clap::ValueEnum;
use rig::waves::WaveOutputs;
use rig::{Rig, Scenario};
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

/// The arguments of `asi-lift run`.
#[derive(clap::Args)]
pub struct RunArgs {
    /// The scenario file (TOML). Without it, the built-in demo runs.
    pub scenario: Option<PathBuf>,
    /// Use this seed instead of the scenario's.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Stop the simulation at this time (e.g. 30s, 2min) if earlier than the scenario's
    /// duration.
    #[arg(long, value_name = "DURATION")]
    pub until: Option<String>,
    /// Where the report goes: a file, or `-` for standard output.
    #[arg(long, value_name = "FILE|-", default_value = "-")]
    pub report: PathBuf,
    /// The report's format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,
    /// Write every bus transaction, one line each, to this file (`-` for standard
    /// output): JSON lines for a `.jsonl` or `.json` file, readable text otherwise.
    #[arg(long, value_name = "FILE|-")]
    pub trace: Option<PathBuf>,
    /// The trace's form, overriding the file name's.
    #[arg(long, value_enum)]
    pub trace_format: Option<TraceForm>,
    /// Write a Value Change Dump (GTKWave, Surfer) of the whole run: the line's pulses,
    /// the telegram fields, the plant, the controller and the safety logic; the line
    /// voltage for the waveform window.
    #[arg(long, value_name = "FILE")]
    pub vcd: Option<PathBuf>,
    /// Write the line voltage of the waveform window as `time_s,voltage_v` CSV, as an
    /// oscilloscope exports it.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// The window of line voltage in the VCD and the CSV, START..END in simulated time
    /// (e.g. 5s..5.01s).
    #[arg(long, value_name = "START..END", default_value = "0ms..10ms")]
    pub waveform_window: String,
    /// Draw the run as SVG: cabin position and velocity over time with the floors, vanes and
    /// overtravel trip points, the calls pressed and served, K1, the safety trips and the
    /// bus's repeats per transaction.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Overwrite the report, trace, VCD, CSV and plot files if they exist.
    #[arg(long)]
    pub force: bool,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// The readable log of the run and a summary.
    Text,
    /// The report as JSON.
    Json,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum TraceForm {
    /// One readable line per transaction.
    Text,
    /// One JSON object per transaction.
    Jsonl,
}

/// Runs the scenario and writes its outputs; the exit code says whether it broke an invariant.
pub fn run(args: RunArgs) -> Result<u8, String> {
    let RunArgs {
        scenario,
        seed,
        until,
        report,
        format,
        trace,
        trace_format,
        vcd,
        csv,
        waveform_window,
        plot,
        force,
    } = args;
    let mut sc = match &scenario {
        None => Scenario::demo().map_err(|e| e.to_string())?,
        Some(path) => {
            let text = read_input(path)?;
            Scenario::from_toml(&path.display().to_string(), &text).map_err(|e| e.to_string())?
        }
    };
    if let Some(s) = seed {
        sc.seed = s;
    }
    let until = match until {
        None => None,
        Some(u) => Some(
            u.parse::<SimDuration>()
                .map_err(|e| format!("--until: {e}"))?,
        ),
    };
    let window = parse_window(&waveform_window)?;
    let outputs: Vec<(&str, &PathBuf)> = [
        ("--report", Some(&report)),
        ("--trace", trace.as_ref()),
        ("--vcd", vcd.as_ref()),
        ("--csv", csv.as_ref()),
        ("--plot", plot.as_ref()),
    ]
    .into_iter()
    .filter_map(|(k, p)| p.map(|p| (k, p)))
    .collect();
    for (i, (a, pa)) in outputs.iter().enumerate() {
        for (b, pb) in &outputs[i + 1..] {
            if pa == pb {
                return Err(if *pa == Path::new("-") {
                    format!("{a} and {b} both want standard output: give one a file")
                } else {
                    format!("{a} and {b} both name {}", pa.display())
                });
            }
        }
    }
    let end = SimTime::ZERO + until.map_or(sc.duration, |u| u.min(sc.duration));
    let mut rig = Rig::new(sc).map_err(|e| e.to_string())?;
    if let Some(path) = &trace {
        let form = match trace_format {
            Some(TraceForm::Text) => TraceFormat::Text,
            Some(TraceForm::Jsonl) => TraceFormat::Jsonl,
            None => TraceFormat::for_path(path),
        };
        rig.trace_to(open_output(path, force)?, form);
    }
    if vcd.is_some() || csv.is_some() {
        let vcd = vcd.as_deref().map(|p| open_output(p, force)).transpose()?;
        let csv = csv.as_deref().map(|p| open_output(p, force)).transpose()?;
        rig.waves_to(WaveOutputs { vcd, csv, window });
    }
    // Opened before the run, like the others, so that a bad path costs no simulation.
    let plot_out = plot
        .as_deref()
        .map(|p| open_output(p, force).map(|out| (p, out)))
        .transpose()?;
    let wall = std::time::Instant::now();
    let show = std::io::stderr().is_terminal();
    let mut shown = false;
    let mut progress = |t: SimTime, end: SimTime| {
        if show && wall.elapsed().as_secs_f64() > 1.0 {
            shown = true;
            let pct = t.as_secs_f64() / end.as_secs_f64().max(1e-9) * 100.0;
            eprint!(
                "\r  simulated {:.1} s of {:.1} s ({pct:.0} %)",
                t.as_secs_f64(),
                end.as_secs_f64()
            );
        }
    };
    let samples = plot_out
        .is_some()
        .then(|| plot::record(&mut rig, end, &mut progress));
    let rep = rig.run_observed(until, &mut progress);
    if shown {
        eprint!("\r{:60}\r", "");
    }
    let body = match format {
        Format::Text => rep.to_text(),
        Format::Json => {
            rep.to_json()
                .map_err(|e| format!("the report as JSON: {e}"))?
                + "\n"
        }
    };
    write_output(&report, &body, force)?;
    if let (Some((path, mut out)), Some(mut samples)) = (plot_out, samples) {
        samples.finish(&rep);
        let svg = plot::draw(&samples, &rep).map_err(|e| format!("{}: {e}", path.display()))?;
        out.write_all(svg.as_bytes())
            .and_then(|()| out.flush())
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    if report != Path::new("-") {
        let summary = format!(
            "{}report written to {}\n",
            rep.summary_text(),
            report.display()
        );
        // Human text goes to standard error when a data stream (the trace, the plot) is on
        // standard output; a reader that has gone (`| head`) is no error.
        let stdout = Some(Path::new("-"));
        if trace.as_deref() == stdout || plot.as_deref() == stdout {
            eprint!("{summary}");
        } else {
            print_out(&summary)?;
        }
    }
    Ok(if rep.violations.is_empty() {
        0
    } else {
        EXIT_VIOLATIONS
    })
}

/// Parses `START..END` in simulated time.
fn parse_window(s: &str) -> Result<(SimTime, SimTime), String> {
    let err = |why: String| format!("--waveform-window {s}: {why}");
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| err("expected START..END, e.g. 0ms..10ms".into()))?;
    let a: SimDuration = a.trim().parse().map_err(|e| err(format!("{e}")))?;
    let b: SimDuration = b.trim().parse().map_err(|e| err(format!("{e}")))?;
    if b <= a {
        return Err(err("END must be after START".into()));
    }
    Ok((SimTime::ZERO + a, SimTime::ZERO + b))
}
