//! `asi-lift run`: a scenario on the whole rig, its report, trace and waveforms.

use super::output::Outputs;
use super::scenarios::find;
use super::{picture, plot, print_out, read_input, EXIT_VIOLATIONS};
use asi_phy::{SimDuration, SimTime};
use asi_trace::trace::TraceFormat;
use clap::ValueEnum;
use rig::waves::WaveOutputs;
use rig::{Rig, Scenario};
use std::io::IsTerminal;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

/// The arguments of `asi-lift run`.
#[derive(clap::Args)]
pub struct RunArgs {
    /// The scenario: a file (TOML, `-` for standard input) or the name of a built-in one
    /// (`asi-lift scenarios` lists them). Without it, the built-in demo runs.
    pub scenario: Option<PathBuf>,
    /// The control algorithm, overriding the scenario's.
    #[arg(long, value_enum)]
    pub algorithm: Option<AlgorithmArg>,
    /// Use this seed instead of the scenario's.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Run this IEC 61131-3 Structured Text program as the PLC instead of the built-in one
    /// (the asi-lift guide, "Your PLC program in Structured Text"). A program that does not
    /// compile is refused before the run with every error, each at its line and column.
    #[arg(long, value_name = "FILE.st")]
    pub controller: Option<PathBuf>,
    /// Compile the program of `--controller` together with this library of function blocks,
    /// types and globals (e.g. the lab's handshakes, `controllers/lab.st`). Repeatable.
    #[arg(long, value_name = "FILE.st")]
    pub library: Vec<PathBuf>,
    /// End the simulation at this time (e.g. 30s, 2min): earlier than the scenario's
    /// duration, it stops the run there; later, it extends the run to it.
    #[arg(long, value_name = "DURATION")]
    pub until: Option<String>,
    /// Where the report goes: a file, or `-` for standard output [default: standard output;
    /// when the trace or the plot goes there, only the summary, to standard error].
    #[arg(long, value_name = "FILE|-")]
    pub report: Option<PathBuf>,
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
    /// Write a Value Change Dump (GTKWave, Surfer) of the whole run: the line's pulses
    /// (for the pulse window), the telegram fields, the plant, the controller and the safety
    /// logic; the line voltage for the waveform window.
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
    /// The window of the VCD's pulse wire (rig.bus.manchester), START..END in simulated
    /// time [default: the whole run]. The pulse wire is most of a long run's VCD (about 4 MB
    /// per simulated second); the other signals always cover the whole run.
    #[arg(long, value_name = "START..END")]
    pub pulse_window: Option<String>,
    /// Draw the run: cabin position and velocity over time with the floors, vanes and
    /// overtravel trip points, the calls pressed and served, K1, the safety trips and the
    /// bus's repeats per transaction; with traffic templates, the distribution of the
    /// passengers' waiting and journey times. SVG for a `.svg` file, PNG (1400 × 1000 pixels) for a
    /// `.png` one; another extension is refused, and a name without one (`/dev/null`, `-`)
    /// gets SVG.
    #[arg(long, value_name = "FILE.svg|FILE.png")]
    pub plot: Option<PathBuf>,
    /// Overwrite the report, trace, VCD, CSV and plot files if they exist.
    #[arg(long)]
    pub force: bool,
    /// Run the bus pulse-exact: every telegram through the pulse decoder, without the
    /// simulator's fast paths. Every output is the same; it is slower, and the reference the
    /// fast paths are checked and measured against.
    #[arg(long)]
    pub pulse_exact: bool,
}

/// The control algorithms of `--algorithm`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum AlgorithmArg {
    /// Cabin calls first, in the order pressed, then hall calls (the thesis's program).
    Fifo,
    /// Collective control: every call on the way, in the direction of travel.
    Collective,
}

/// The forms of the report (`--format`).
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// The readable log of the run and a summary.
    Text,
    /// The report as JSON.
    Json,
}

/// The forms of the transaction trace (`--trace-format`).
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
        algorithm,
        seed,
        until,
        report,
        format,
        trace,
        trace_format,
        vcd,
        csv,
        waveform_window,
        pulse_window,
        plot,
        force,
        pulse_exact,
        controller,
        library,
    } = args;
    let until = match until {
        None => None,
        Some(u) => Some(
            u.parse::<SimDuration>()
                .map_err(|e| format!("--until: {e}"))?,
        ),
    };
    let (mut sc, file) = load_scenario(scenario.as_deref(), until)?;
    if let Some(s) = seed {
        sc.seed = s;
    }
    if let Some(a) = algorithm {
        sc.algorithm = match a {
            AlgorithmArg::Fifo => controller::Algorithm::Fifo,
            AlgorithmArg::Collective => controller::Algorithm::Collective,
        };
    }
    let window = parse_window("--waveform-window", &waveform_window)?;
    let pulse_window = pulse_window
        .map(|w| parse_window("--pulse-window", &w))
        .transpose()?;
    // Every output is checked, and its temporary file made, before the simulation; an
    // interrupted run removes them.
    super::output::clean_up_on_signals()?;
    let mut outs = Outputs::new(force);
    if let Some(path) = file {
        outs.input("the scenario", path)?;
    }
    set_program(&mut sc, controller.as_deref(), &library, &mut outs)?;
    // Standard output is a stream: when the trace or the plot takes it and no --report is
    // given, the report is only its summary, on standard error.
    let stdout = Some(Path::new("-"));
    let stream_on_stdout = trace.as_deref() == stdout || plot.as_deref() == stdout;
    let report = match report {
        Some(r) => Some(r),
        None if stream_on_stdout => {
            if format == Format::Json {
                return Err(
                    "--format json: the trace or the plot takes standard output; give the report a file with --report FILE".into(),
                );
            }
            None
        }
        None => Some(PathBuf::from("-")),
    };
    let report_sink = report
        .as_deref()
        .map(|p| outs.add("--report", p))
        .transpose()?;
    let trace_sink = trace
        .as_deref()
        .map(|p| outs.add("--trace", p))
        .transpose()?;
    let vcd_sink = vcd.as_deref().map(|p| outs.add("--vcd", p)).transpose()?;
    let csv_sink = csv.as_deref().map(|p| outs.add("--csv", p)).transpose()?;
    let plot_format = plot.as_deref().map(picture::format_of).transpose()?;
    let plot_sink = plot.as_deref().map(|p| outs.add("--plot", p)).transpose()?;
    let end = SimTime::ZERO + until.map_or(sc.duration, |u| u.min(sc.duration));
    if vcd.is_some() {
        if let Some(w) = vcd_size_warning(end, pulse_window, window) {
            eprintln!("asi-lift: warning: {w}");
        }
    }
    if csv.is_some() {
        if let Some(w) = csv_size_warning(end, window) {
            eprintln!("asi-lift: warning: {w}");
        }
    }
    let mut rig = Rig::new(sc).map_err(|e| e.to_string())?;
    rig.set_pulse_exact(pulse_exact);
    if let (Some(path), Some(sink)) = (&trace, &trace_sink) {
        rig.trace_to(outs.writer(sink)?, trace_form(trace_format, path));
    }
    if vcd_sink.is_some() || csv_sink.is_some() {
        let writer = |s: &_| outs.writer(s).map(|w| w as Box<dyn std::io::Write>);
        let vcd = vcd_sink.as_ref().map(writer).transpose()?;
        let csv = csv_sink.as_ref().map(writer).transpose()?;
        rig.waves_to(WaveOutputs {
            vcd,
            csv,
            window,
            pulse_window,
        });
    }
    let bar = progress_bar();
    let wall = std::time::Instant::now();
    let terminal = std::io::stderr().is_terminal();
    let mut progress = |t: SimTime, end: SimTime| {
        show_after(&bar, wall, terminal);
        bar.set_length(end.as_nanos() / 1_000_000);
        bar.set_position(t.as_nanos() / 1_000_000);
        if outs.stdout_gone() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    };
    let samples = plot_sink
        .is_some()
        .then(|| plot::record(&mut rig, end, &mut progress));
    let rep = rig.run_observed(until, &mut progress);
    bar.finish_and_clear();
    if outs.stdout_gone() {
        // The reader of standard output has gone (`| head`): the run ends quietly, and its
        // other outputs, cut short, are not put in place.
        return Ok(0);
    }
    if let Some(sink) = &report_sink {
        outs.write_all(sink, &report_body(&rep, format)?)?;
    }
    if let (Some(sink), Some(format), Some(mut samples)) = (&plot_sink, plot_format, samples) {
        samples.finish(&rep);
        let picture = plot::draw(&samples, &rep, format).map_err(|e| {
            format!(
                "--plot {}: {e}",
                plot.as_deref().unwrap_or(Path::new("")).display()
            )
        })?;
        outs.write_all(sink, &picture)?;
    }
    // A trace or waveform file that could not be written whole is not put in place (a file
    // of that name keeps what it had); the report and the plot are.
    let lost = outs.keep_out_unwritten(
        rep.output_error.as_deref(),
        &[
            ("--trace", trace_sink.as_ref()),
            ("--vcd", vcd_sink.as_ref()),
            ("--csv", csv_sink.as_ref()),
        ],
    );
    outs.commit()?;
    if let Some(lost) = lost {
        return Err(lost);
    }
    let summary = match report.as_deref() {
        None => Some(rep.summary_text()),
        Some(r) if r != Path::new("-") => Some(format!(
            "{}report written to {}\n",
            rep.summary_text(),
            r.display()
        )),
        Some(_) => None,
    };
    if let Some(summary) = summary {
        // Human text goes to standard error when a data stream (the trace, the plot) is on
        // standard output; a reader that has gone (`| head`) is no error.
        if stream_on_stdout {
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

/// The report as `format` asks.
pub fn report_body(rep: &rig::Report, format: Format) -> Result<String, String> {
    Ok(match format {
        Format::Text => rep.to_text(),
        Format::Json => {
            rep.to_json()
                .map_err(|e| format!("the report as JSON: {e}"))?
                + "\n"
        }
    })
}

/// The trace's form: `--trace-format` if given, else the file name's.
pub fn trace_form(form: Option<TraceForm>, path: &Path) -> TraceFormat {
    match form {
        Some(TraceForm::Text) => TraceFormat::Text,
        Some(TraceForm::Jsonl) => TraceFormat::Jsonl,
        None => TraceFormat::for_path(path),
    }
}

/// The Structured Text program of `--controller FILE.st` with the libraries of `--library`,
/// read and compiled; every error at once if it is refused.
pub fn load_program(
    path: &Path,
    libraries: &[PathBuf],
) -> Result<rig::scenario::program::ProgramFile, String> {
    rig::scenario::program::ProgramFile::read(path, libraries).map_err(|e| {
        // A program written on a library (the lab's handshakes) and given without it.
        let unknown = [
            "no type is named `",
            "no function or block instance is named `",
        ];
        let hint = if libraries.is_empty() && unknown.iter().any(|u| e.contains(u)) {
            "\n(if the program uses a library's blocks or types, compile it with --library \
             FILE.st, e.g. --library controllers/lab.st)"
        } else {
            ""
        };
        format!("--controller {e}{hint}")
    })
}

/// `--controller FILE.st` (with `--library`) in the place of the scenario's program, if
/// given; the program's and its libraries' files are inputs the outputs must not overwrite.
pub fn set_program(
    sc: &mut Scenario,
    controller: Option<&Path>,
    libraries: &[PathBuf],
    outs: &mut Outputs,
) -> Result<(), String> {
    match controller {
        Some(path) => sc.program = Some(load_program(path, libraries)?),
        None if !libraries.is_empty() => {
            return Err(
                "--library: a library goes with a program: give --controller FILE.st too".into(),
            )
        }
        None => {}
    }
    if let Some(p) = &sc.program {
        outs.input("the program", p.path())?;
        for l in p.libraries() {
            outs.input("the library", l)?;
        }
    }
    Ok(())
}

/// The scenario named on the command line: a file if there is one by that name (`-` for
/// standard input), else a built-in scenario, else the demo; with the file's path. An
/// `extend_to` later than its duration (`run --until`) extends it, as `serve --until` does.
/// Warns of events at or after the end, so only of those that really never happen.
pub fn load_scenario(
    scenario: Option<&Path>,
    extend_to: Option<SimDuration>,
) -> Result<(Scenario, Option<&Path>), String> {
    // A file if there is one by that name, else a built-in scenario.
    let is_file = |p: &Path| p == Path::new("-") || p.exists() || p.components().count() > 1;
    let file = scenario.filter(|p| is_file(p));
    let mut sc = match (scenario, file) {
        (None, _) => Scenario::demo().map_err(|e| e.to_string())?,
        (Some(_), Some(path)) => {
            let text = read_input(path, super::MAX_TOML_BYTES)?;
            Scenario::from_toml(&path.display().to_string(), &text).map_err(|e| e.to_string())?
        }
        (Some(name), None) => find(&name.to_string_lossy())
            .map_err(|e| format!("{e} (and no file {} here)", name.display()))?
            .scenario()
            .map_err(|e| e.to_string())?,
    };
    if let Some(u) = extend_to {
        sc.duration = sc.duration.max(u);
    }
    for e in sc.late_events() {
        let place = file.map_or_else(
            || sc.name.clone(),
            |p| format!("{}:{}", p.display(), e.line),
        );
        eprintln!(
            "asi-lift: warning: {place}: the event at {} comes at or after the scenario's end ({}) and never happens",
            e.at.saturating_duration_since(SimTime::ZERO),
            sc.duration
        );
    }
    Ok((sc, file))
}

/// The progress of a run on a terminal (standard error): simulated seconds, the rate in
/// simulated seconds per second, the time left. Positions are simulated milliseconds;
/// indicatif limits the redraws. It starts hidden; the caller shows it ([`show_after`]).
fn progress_bar() -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::hidden();
    let secs = |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
        let _ = write!(w, "{:.1}", state.pos() as f64 / 1000.0);
    };
    let len = |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
        let _ = write!(w, "{:.1}", state.len().unwrap_or(0) as f64 / 1000.0);
    };
    let rate = |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
        let _ = write!(w, "{:.1}", state.per_sec() / 1000.0);
    };
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "[{bar:30}] simulated {sim} s of {end} s, {rate} s per s, {eta} left",
    ) {
        bar.set_style(
            style
                .with_key("sim", secs)
                .with_key("end", len)
                .with_key("rate", rate)
                .progress_chars("=> "),
        );
    }
    bar
}

/// Shows `bar` on a terminal once the run has taken a second of wall time (a short run shows
/// none); on standard error, never in a data stream.
fn show_after(bar: &indicatif::ProgressBar, wall: std::time::Instant, terminal: bool) {
    if terminal && bar.is_hidden() && wall.elapsed() > std::time::Duration::from_secs(1) {
        bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
    }
}

/// The VCD or CSV size above which `run` warns before the run.
const VCD_WARN_BYTES: u64 = 1_000_000_000;

/// A warning if the VCD of a run ending at `end` will be larger than [`VCD_WARN_BYTES`]: its
/// estimated size and the option that bounds it.
pub fn vcd_size_warning(
    end: SimTime,
    pulse_window: Option<(SimTime, SimTime)>,
    voltage_window: (SimTime, SimTime),
) -> Option<String> {
    // The part of a window inside the run.
    let inside = |(a, b): (SimTime, SimTime)| b.min(end).saturating_duration_since(a.min(end));
    let run = end.saturating_duration_since(SimTime::ZERO);
    let pulses = inside(pulse_window.unwrap_or((SimTime::ZERO, end)));
    let voltage = inside(voltage_window);
    let bytes = rig::waves::estimate_vcd_bytes(run, pulses, voltage);
    if bytes <= VCD_WARN_BYTES {
        return None;
    }
    let pulse_bytes = rig::waves::estimate_vcd_bytes(SimDuration::ZERO, pulses, SimDuration::ZERO);
    let (what, option) = if pulse_bytes * 2 >= bytes {
        (format!("{pulses} of pulse wire"), "--pulse-window")
    } else {
        (format!("{voltage} of line voltage"), "--waveform-window")
    };
    Some(format!(
        "the VCD will be about {:.1} GB, mostly {what}: bound it with {option} START..END",
        bytes as f64 / 1e9
    ))
}

/// A warning if the CSV of a run ending at `end` will be larger than [`VCD_WARN_BYTES`]: its
/// estimated size and the option that bounds it.
pub fn csv_size_warning(end: SimTime, voltage_window: (SimTime, SimTime)) -> Option<String> {
    let (a, b) = voltage_window;
    let last = b.min(end);
    let voltage = last.saturating_duration_since(a.min(end));
    let bytes = rig::waves::estimate_csv_bytes(voltage, last);
    (bytes > VCD_WARN_BYTES).then(|| {
        format!(
            "the CSV will be about {:.1} GB, {voltage} of line voltage: bound it with --waveform-window START..END",
            bytes as f64 / 1e9
        )
    })
}

/// Parses `START..END` in simulated time.
fn parse_window(option: &str, s: &str) -> Result<(SimTime, SimTime), String> {
    let err = |why: String| format!("{option} {s}: {why}");
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
