//! The `asi-lift` command.

use asi_lift::campaign::profile::Profile;
use asi_lift::campaign::run::{run_campaign, Finished, Plan, Shard};
use asi_lift::campaign::summary::summarize;
use asi_lift::capture::{
    decode_capture, summary, to_json_lines, to_text, CaptureFormat, DecodeOptions,
};
use asi_lift::phy_tools::{describe, parse_call, waveform_csv};
use asi_lift::rig::Rig;
use asi_lift::scenario::Scenario;
use asi_lift::timing::{analyse, BusChoice, TimingOptions, MAX_DURATION, MAX_SAMPLES};
use asi_lift::trace::TraceFormat;
use asi_lift::waves::WaveOutputs;
use asi_phy::waveform::WaveformConfig;
use asi_phy::SimTime;
use asi_phy::{Expect, SimDuration};
use clap::{Parser, Subcommand, ValueEnum};
use std::io::{BufRead, IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// asi-lift: the AS-Interface laboratory lift, simulated to the bit and to the millisecond.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the lab lift: the AS-i bus, the lift, the PLC program and the safety logic on one
    /// simulated clock, driven by a scenario file (the built-in demo without one).
    Run {
        /// The scenario file (TOML). Without it, the built-in demo runs.
        scenario: Option<PathBuf>,
        /// Use this seed instead of the scenario's.
        #[arg(long)]
        seed: Option<u64>,
        /// Stop the simulation at this time (e.g. 30s, 2min) if earlier than the scenario's
        /// duration.
        #[arg(long, value_name = "DURATION")]
        until: Option<String>,
        /// Where the report goes: a file, or `-` for standard output.
        #[arg(long, value_name = "FILE|-", default_value = "-")]
        report: PathBuf,
        /// The report's format.
        #[arg(long, value_enum, default_value_t = Format::Text)]
        format: Format,
        /// Write every bus transaction, one line each, to this file (`-` for standard
        /// output): JSON lines for a `.jsonl` or `.json` file, readable text otherwise.
        #[arg(long, value_name = "FILE|-")]
        trace: Option<PathBuf>,
        /// The trace's form, overriding the file name's.
        #[arg(long, value_enum)]
        trace_format: Option<TraceForm>,
        /// Write a Value Change Dump (GTKWave, Surfer) of the whole run: the line's pulses,
        /// the telegram fields, the plant, the controller and the safety logic; the line
        /// voltage for the waveform window.
        #[arg(long, value_name = "FILE")]
        vcd: Option<PathBuf>,
        /// Write the line voltage of the waveform window as `time_s,voltage_v` CSV, as an
        /// oscilloscope exports it.
        #[arg(long, value_name = "FILE")]
        csv: Option<PathBuf>,
        /// The window of line voltage in the VCD and the CSV, START..END in simulated time
        /// (e.g. 5s..5.01s).
        #[arg(long, value_name = "START..END", default_value = "0ms..10ms")]
        waveform_window: String,
        /// Overwrite the report, trace, VCD and CSV files if they exist.
        #[arg(long)]
        force: bool,
    },
    /// Show how a master call or slave response travels on the line: bits, Manchester levels,
    /// APM pulses; optionally write its line voltage as CSV.
    ///
    /// Calls by their ZMD mnemonic: dexg ADDR VALUE, wpar ADDR VALUE, adra NEW, wid1 VALUE,
    /// dela|res|rdio|rdid|rid1|rid2|rdst ADDR, br01, resp VALUE. ADDR is 0..31 with an optional
    /// A/B suffix (7B); VALUE is four binary digits (1010), 0b1010 or 0..15.
    Encode {
        /// The call and its arguments, e.g. `dexg 5 1010`.
        #[arg(required = true, num_args = 1..)]
        call: Vec<String>,
        /// Write the line voltage as `time,voltage` CSV to this file (`-` for standard output).
        #[arg(long, value_name = "FILE")]
        csv: Option<PathBuf>,
        /// Overwrite the CSV file if it exists.
        #[arg(long)]
        force: bool,
        /// Pulse amplitude in volts.
        #[arg(long, default_value_t = 2.5)]
        amplitude: f32,
        /// RMS of added white noise in volts.
        #[arg(long, default_value_t = 0.0)]
        noise_rms: f32,
        /// Seed of the noise.
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// Decode a capture of the line into telegrams, through the comparator and the seven
    /// receiver checks.
    ///
    /// A capture is an oscilloscope's CSV (`time,voltage` in seconds and volts; a header line
    /// and `#` comments allowed) or a VCD with the line voltage (a real signal) or the
    /// demodulated line (a 1-bit wire, idle high: every record is one pulse, 0 negative, 1
    /// positive). Prints one line per telegram: time in seconds in the capture's own time
    /// base, type (request, response, unknown), bits ST..EB, call, address, info or data, and
    /// the failed checks; then a summary. A capture without telegrams says "no telegrams
    /// found" and exits with 0.
    Decode {
        /// The capture file (`-` for standard input).
        file: PathBuf,
        /// The file format [default: VCD if the file starts with `$` or is named *.vcd, else
        /// CSV].
        #[arg(long, value_enum)]
        format: Option<InputFormat>,
        /// The VCD signal: its name (`line_voltage`) or dotted path (`rig.bus.line_voltage`);
        /// needed when the file has more than one.
        #[arg(long, value_name = "NAME")]
        signal: Option<String>,
        /// Write one JSON object per telegram and line (t_ns, type, bits, call, address, info,
        /// data, errors) and nothing else; the summary goes to standard error.
        #[arg(long)]
        json: bool,
        /// Nominal pulse amplitude in volts (estimated from the capture if not given).
        #[arg(long, value_name = "V")]
        nominal: Option<f32>,
        /// What the receiver listens for.
        #[arg(long, value_enum, default_value_t = Listen::Both)]
        expect: Listen,
        /// Sampling period for a VCD real signal, e.g. 40ns [default: the smallest spacing of
        /// its changes, at most 100 ns].
        #[arg(long, value_name = "DURATION")]
        sample_period: Option<String>,
    },
    /// Timing analysis (SPEC §7): transaction and cycle time, per-slave update period,
    /// repeats, handshake word times and end-to-end latencies, analytic and simulated side by
    /// side, compared with the seed's T = (n + 2) · 154 µs.
    Timing {
        /// The bus: `lab` (the lab lift, whole rig), a number 1..31 of standard slaves, or
        /// `62ab` (62 A/B slaves).
        #[arg(long, default_value = "lab", value_parser = parse_bus)]
        bus: BusChoice,
        /// Plain I/O modules added to the lab bus at its free addresses (0..20).
        #[arg(long, value_name = "N", allow_negative_numbers = true)]
        extra_slaves: Option<u8>,
        /// Probability that a pulse on the line is corrupted (0 <= P < 1).
        #[arg(
            long,
            value_name = "P",
            default_value_t = 0.0,
            allow_negative_numbers = true
        )]
        error_rate: f64,
        /// Seed of the line noise and of the press moments.
        #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
        seed: u64,
        /// Simulated measurement window of the bus statistics (e.g. 60s, 2min).
        #[arg(
            long,
            value_name = "DURATION",
            default_value = "60s",
            allow_hyphen_values = true
        )]
        duration: String,
        /// Latency samples of each chain (lab bus).
        #[arg(
            long,
            value_name = "K",
            default_value_t = 100,
            allow_negative_numbers = true
        )]
        samples: u32,
        /// Write the report as JSON instead of the table.
        #[arg(long)]
        json: bool,
        /// Also write an SVG with histograms of the cycle time and of the latencies.
        #[arg(long, value_name = "FILE")]
        svg: Option<PathBuf>,
        /// Overwrite the SVG file if it exists.
        #[arg(long)]
        force: bool,
    },
    /// Run many random valid scenarios on the whole rig (README.md, "Campaigns"): one JSON
    /// line per run, every failure shrunk to a scenario file that reproduces it; or merge
    /// result files with `campaign summarize`.
    #[command(args_conflicts_with_subcommands = true)]
    Campaign {
        #[command(subcommand)]
        action: Option<CampaignAction>,
        #[command(flatten)]
        args: CampaignArgs,
    },
}

#[derive(Subcommand)]
enum CampaignAction {
    /// Merge the JSON lines of one campaign (its shards, in any order) into one table: runs,
    /// outcomes, violations by kind, out-of-service runs, waits, repeats per transaction.
    Summarize {
        /// The result files (`-` for standard input).
        #[arg(required = true, value_name = "FILE")]
        files: Vec<PathBuf>,
        /// Write the summary as JSON.
        #[arg(long)]
        json: bool,
    },
}

#[derive(clap::Args)]
struct CampaignArgs {
    /// Runs of the whole campaign (all shards together).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 100,
        allow_negative_numbers = true
    )]
    runs: u64,
    /// The campaign seed: the same seed gives the same runs and the same lines.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 1,
        allow_negative_numbers = true
    )]
    seed: u64,
    /// Worker threads [default: all cores].
    #[arg(long, value_name = "J", allow_negative_numbers = true)]
    jobs: Option<usize>,
    /// Run only the K-th of N disjoint parts (1-based): the runs whose index i has
    /// i mod N = K - 1.
    #[arg(long, value_name = "K/N", value_parser = parse_shard)]
    shard: Option<Shard>,
    /// Write the JSON lines to this file instead of standard output.
    #[arg(long, value_name = "FILE.jsonl")]
    out: Option<PathBuf>,
    /// The generator's profile: a built-in (default, quiet, noisy, smoke) or a profile file.
    #[arg(long, value_name = "NAME|FILE", default_value = "default")]
    profile: String,
    /// Where the shrunk reproducers of failing runs go (created when needed).
    #[arg(long, value_name = "DIR", default_value = "campaign-failures")]
    failures: PathBuf,
    /// Runs a failure may spend on shrinking (0: write the failing scenario as generated).
    #[arg(
        long,
        value_name = "RUNS",
        default_value_t = 64,
        allow_negative_numbers = true
    )]
    shrink_budget: u32,
    /// Overwrite the --out file if it exists.
    #[arg(long)]
    force: bool,
}

fn parse_shard(s: &str) -> Result<Shard, String> {
    s.parse()
}

fn parse_bus(s: &str) -> Result<BusChoice, String> {
    s.parse()
}

#[derive(Clone, Copy, ValueEnum)]
enum InputFormat {
    /// `time,voltage` lines.
    Csv,
    /// A Value Change Dump.
    Vcd,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Format {
    /// The readable log of the run and a summary.
    Text,
    /// The report as JSON.
    Json,
}

#[derive(Clone, Copy, ValueEnum)]
enum TraceForm {
    /// One readable line per transaction.
    Text,
    /// One JSON object per transaction.
    Jsonl,
}

#[derive(Clone, Copy, ValueEnum)]
enum Listen {
    /// Master requests only.
    Requests,
    /// Slave responses only.
    Responses,
    /// A live bus: requests and the responses that follow them.
    Both,
}

/// Exit code of a run that found safety violations.
const EXIT_VIOLATIONS: u8 = 3;

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(code) => ExitCode::from(code),
        Err(msg) => {
            eprintln!("asi-lift: {msg}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<u8, String> {
    match cli.command {
        Command::Run {
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
            force,
        } => {
            let mut sc = match &scenario {
                None => Scenario::demo(),
                Some(path) => {
                    let text = read_input(path)?;
                    Scenario::from_toml(&path.display().to_string(), &text)
                        .map_err(|e| e.to_string())?
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
            let rep = rig.run_observed(until, &mut progress);
            if shown {
                eprint!("\r{:60}\r", "");
            }
            let body = match format {
                Format::Text => rep.to_text(),
                Format::Json => rep.to_json() + "\n",
            };
            write_output(&report, &body, force)?;
            if report != Path::new("-") {
                let text = rep.to_text();
                let summary = text.split("\nsummary").nth(1).unwrap_or("");
                print!("summary{summary}");
                println!("report written to {}", report.display());
            }
            Ok(if rep.violations.is_empty() {
                0
            } else {
                EXIT_VIOLATIONS
            })
        }
        Command::Encode {
            call,
            csv,
            force,
            amplitude,
            noise_rms,
            seed,
        } => {
            let t = parse_call(&call).map_err(|e| e.to_string())?;
            match csv {
                None => print!("{}", describe(t)),
                Some(path) => {
                    let cfg = WaveformConfig {
                        amplitude,
                        noise_rms,
                        seed,
                        ..WaveformConfig::default()
                    };
                    let text = waveform_csv(t, &cfg).map_err(|e| e.to_string())?;
                    write_output(&path, &text, force)?;
                    if path != Path::new("-") {
                        print!("{}", describe(t));
                        println!("wrote       {}", path.display());
                    }
                }
            }
            Ok(0)
        }
        Command::Decode {
            file,
            format,
            signal,
            json,
            nominal,
            expect,
            sample_period,
        } => {
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
                print_out(&to_json_lines(&decoded))?;
                eprintln!("{}", summary(&decoded));
            } else {
                print_out(&to_text(&decoded))?;
            }
            Ok(0)
        }
        Command::Campaign { action, args } => match action {
            None => campaign(args),
            Some(CampaignAction::Summarize { files, json }) => campaign_summary(&files, json),
        },
        Command::Timing {
            bus,
            extra_slaves,
            error_rate,
            seed,
            duration,
            samples,
            json,
            svg,
            force,
        } => {
            let opts = timing_options(bus, extra_slaves, error_rate, seed, &duration, samples)?;
            // Refuse an existing SVG before spending the simulation on it.
            let mut svg_out = match &svg {
                Some(path) => Some((path, open_output(path, force)?)),
                None => None,
            };
            let rep = analyse(&opts).map_err(|e| e.to_string())?;
            if json {
                println!("{}", rep.to_json());
            } else {
                print!("{}", rep.to_text());
            }
            if let Some((path, out)) = &mut svg_out {
                out.write_all(rep.to_svg().as_bytes())
                    .and_then(|()| out.flush())
                    .map_err(|e| format!("{}: {e}", path.display()))?;
                if !json {
                    println!("SVG written to {}", path.display());
                }
            }
            Ok(0)
        }
    }
}

/// `asi-lift campaign`: runs the plan, writes the lines and the reproducers.
fn campaign(args: CampaignArgs) -> Result<u8, String> {
    if args.runs == 0 {
        return Err("--runs: 0: a campaign has at least one run".into());
    }
    let jobs = match args.jobs {
        Some(0) => return Err("--jobs: 0: give at least one worker thread".into()),
        Some(j) => j,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let profile = Profile::resolve(&args.profile).map_err(|e| e.to_string())?;
    let plan = Plan {
        seed: args.seed,
        runs: args.runs,
        shard: args.shard.unwrap_or(Shard::ALL),
        profile,
        shrink_budget: args.shrink_budget,
    };
    let count = plan.indices().count() as u64;
    if count == 0 {
        // More shards than runs (an array larger than the campaign): nothing to do here.
        eprintln!(
            "asi-lift: --shard {}: the campaign's {} runs leave this shard empty",
            plan.shard, plan.runs
        );
    }
    if args.failures.exists() && !args.failures.is_dir() {
        return Err(format!(
            "--failures {}: exists and is not a directory",
            args.failures.display()
        ));
    }
    let out_path = args.out.clone().unwrap_or_else(|| PathBuf::from("-"));
    let mut out = open_output(&out_path, args.force)?;
    let out_name = if out_path == Path::new("-") {
        "standard output".to_string()
    } else {
        out_path.display().to_string()
    };
    // A panic in a run is an outcome of the campaign, reported in its line: keep the
    // workers' panic messages off the terminal.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let worker = std::thread::current()
            .name()
            .is_some_and(|n| n.starts_with("campaign-worker-"));
        if !worker {
            default_hook(info);
        }
    }));
    let bar = if std::io::stderr().is_terminal() {
        let bar = indicatif::ProgressBar::new(count);
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{elapsed_precise} [{bar:30}] {pos}/{len} runs, {msg}, eta {eta}",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar
    } else {
        indicatif::ProgressBar::hidden()
    };
    let mut outcomes = std::collections::BTreeMap::<String, u64>::new();
    let mut failures_seen = 0u64;
    let mut written: Vec<PathBuf> = Vec::new();
    let failures_dir = args.failures.clone();
    let mut sink = |mut f: Finished| -> Result<(), String> {
        if let Some(r) = &f.reproducer {
            let path = write_reproducer(&failures_dir, &r.file_name, &r.text)?;
            f.line.reproducer = path.file_name().map(|n| n.to_string_lossy().into_owned());
            written.push(path);
        }
        *outcomes
            .entry(f.line.outcome.name().to_owned())
            .or_default() += 1;
        writeln!(out, "{}", f.line.to_json_line())
            .and_then(|()| out.flush())
            .map_err(|e| format!("{out_name}: {e}"))
    };
    let mut progress = |f: &Finished| {
        if f.reproducer.is_some() {
            failures_seen += 1;
        }
        bar.set_message(format!("{failures_seen} failing"));
        bar.inc(1);
    };
    let result = run_campaign(&plan, jobs, &mut sink, &mut progress);
    bar.finish_and_clear();
    let _ = std::panic::take_hook();
    result.map_err(|e| e.0)?;
    let failing = count - outcomes.get("ok").copied().unwrap_or(0);
    let by: Vec<String> = outcomes.iter().map(|(k, v)| format!("{v} {k}")).collect();
    eprintln!(
        "campaign seed {}, profile {}, shard {}: {count} runs: {}",
        plan.seed,
        plan.profile.name,
        plan.shard,
        by.join(", ")
    );
    if failing > 0 {
        eprintln!(
            "{} reproducers written to {}",
            written.len(),
            args.failures.display()
        );
        return Ok(EXIT_VIOLATIONS);
    }
    Ok(0)
}

/// Writes a reproducer into `dir` as `name`, never over another file: an existing file
/// with the same text is kept as it is, one with other text gets the next free name
/// (`run-000042-…-2.toml`).
fn write_reproducer(dir: &Path, name: &str, text: &str) -> Result<PathBuf, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("--failures {}: {e}", dir.display()))?;
    let stem = name.trim_end_matches(".toml");
    for n in 1..1000 {
        let path = if n == 1 {
            dir.join(name)
        } else {
            dir.join(format!("{stem}-{n}.toml"))
        };
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)
        {
            Ok(mut f) => {
                f.write_all(text.as_bytes())
                    .map_err(|e| format!("{}: {e}", path.display()))?;
                return Ok(path);
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                if std::fs::read_to_string(&path).is_ok_and(|t| t == text) {
                    return Ok(path);
                }
            }
            Err(e) => return Err(format!("{}: {e}", path.display())),
        }
    }
    Err(format!(
        "--failures {}: no free name for {name}",
        dir.display()
    ))
}

/// `asi-lift campaign summarize`.
fn campaign_summary(files: &[PathBuf], json: bool) -> Result<u8, String> {
    let mut texts = Vec::new();
    for f in files {
        let name = if f == Path::new("-") {
            "standard input".to_string()
        } else {
            f.display().to_string()
        };
        texts.push((name, read_input(f)?));
    }
    let s = summarize(&texts)?;
    print_out(&if json {
        s.to_json() + "\n"
    } else {
        s.to_text()
    })?;
    Ok(0)
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

/// Writes `text` to standard output; a reader that has gone (`| head`) is no error.
fn print_out(text: &str) -> Result<(), String> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(format!("standard output: {e}"))
        }
        _ => Ok(()),
    }
}

/// A file (`-` = standard input) to read line by line, and its name for messages.
fn open_input(path: &Path) -> Result<(String, Box<dyn BufRead>), String> {
    if path == Path::new("-") {
        return Ok(("standard input".into(), Box::new(std::io::stdin().lock())));
    }
    let name = path.display().to_string();
    let f = std::fs::File::open(path).map_err(|e| format!("{name}: {e}"))?;
    Ok((name, Box::new(std::io::BufReader::new(f))))
}

/// The timing options from the command line, each bad value named by its argument.
fn timing_options(
    bus: BusChoice,
    extra_slaves: Option<u8>,
    error_rate: f64,
    seed: u64,
    duration: &str,
    samples: u32,
) -> Result<TimingOptions, String> {
    let bus = match (bus, extra_slaves) {
        (BusChoice::Lab { .. }, Some(extra)) if extra > 20 => {
            return Err(format!(
                "--extra-slaves: {extra}: the lab bus has 20 free addresses (0..20)"
            ))
        }
        (BusChoice::Lab { .. }, Some(extra)) => BusChoice::Lab { extra },
        (_, Some(_)) => {
            return Err("--extra-slaves applies to --bus lab only".into());
        }
        (b, None) => b,
    };
    if !(error_rate.is_finite() && (0.0..1.0).contains(&error_rate)) {
        return Err(format!(
            "--error-rate: {error_rate}: a pulse error probability is 0 <= P < 1"
        ));
    }
    let duration: SimDuration = duration.parse().map_err(|e| format!("--duration: {e}"))?;
    if duration.is_zero() || duration > MAX_DURATION {
        return Err(format!(
            "--duration: {duration}: must be more than 0 and at most 1 h"
        ));
    }
    if samples > MAX_SAMPLES {
        return Err(format!("--samples: {samples}: at most {MAX_SAMPLES}"));
    }
    Ok(TimingOptions {
        bus,
        pulse_error_rate: error_rate,
        seed,
        duration,
        samples,
    })
}

fn read_input(path: &Path) -> Result<String, String> {
    if path == Path::new("-") {
        let mut s = String::new();
        std::io::stdin()
            .read_to_string(&mut s)
            .map_err(|e| format!("standard input: {e}"))?;
        return Ok(s);
    }
    std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// Writes `text` to `path`, never replacing a file the user has unless `force` is given.
fn write_output(path: &Path, text: &str, force: bool) -> Result<(), String> {
    let mut out = open_output(path, force)?;
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// Opens `path` for writing (`-` = standard output), never replacing a file the user has
/// unless `force` is given.
fn open_output(path: &Path, force: bool) -> Result<Box<dyn Write>, String> {
    if path == Path::new("-") {
        return Ok(Box::new(std::io::BufWriter::new(std::io::stdout())));
    }
    let mut options = std::fs::OpenOptions::new();
    options.write(true);
    if force {
        options.create(true).truncate(true);
    } else {
        options.create_new(true);
    }
    let f = options.open(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::AlreadyExists => {
            format!("{} exists; pass --force to overwrite it", path.display())
        }
        _ => format!("{}: {e}", path.display()),
    })?;
    Ok(Box::new(std::io::BufWriter::new(f)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timing(args: &[&str]) -> Result<u8, String> {
        let cli = Cli::try_parse_from(["asi-lift", "timing"].iter().chain(args))
            .map_err(|e| e.to_string())?;
        run(cli)
    }

    fn fails_naming(args: &[&str], what: &str) {
        match timing(args) {
            Ok(_) => panic!("{args:?} was accepted"),
            Err(e) => assert!(e.contains(what), "{args:?}: {e}"),
        }
    }

    #[test]
    fn bad_timing_arguments_are_named() {
        fails_naming(&["--bus", "lift"], "--bus");
        fails_naming(&["--bus", "lift"], "expected lab");
        fails_naming(&["--bus", "0"], "1..31");
        fails_naming(&["--bus", "32"], "1..31");
        fails_naming(&["--bus", "62"], "62ab");
        fails_naming(&["--error-rate", "1.5"], "--error-rate");
        fails_naming(&["--error-rate", "1"], "--error-rate");
        fails_naming(&["--error-rate", "-0.1"], "--error-rate");
        fails_naming(&["--error-rate", "NaN"], "--error-rate");
        fails_naming(&["--error-rate", "often"], "--error-rate");
        fails_naming(&["--extra-slaves", "21"], "--extra-slaves");
        fails_naming(&["--bus", "31", "--extra-slaves", "1"], "--extra-slaves");
        fails_naming(&["--duration", "0s"], "--duration");
        fails_naming(&["--duration", "soon"], "--duration");
        fails_naming(&["--duration", "2h"], "--duration");
        fails_naming(&["--samples", "20000"], "--samples");
        fails_naming(&["--seed", "-1"], "--seed");
        fails_naming(&["--samples", "-3"], "--samples");
        fails_naming(&["--extra-slaves", "-3"], "--extra-slaves");
        fails_naming(&["--duration", "-3s"], "--duration");
    }

    fn campaign_cli(args: &[&str]) -> Result<u8, String> {
        let cli = Cli::try_parse_from(["asi-lift", "campaign"].iter().chain(args))
            .map_err(|e| e.to_string())?;
        run(cli)
    }

    fn campaign_fails_naming(args: &[&str], what: &str) {
        match campaign_cli(args) {
            Ok(_) => panic!("{args:?} was accepted"),
            Err(e) => assert!(e.contains(what), "{args:?}: {e}"),
        }
    }

    fn temp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("asi-lift-cli-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir
    }

    #[test]
    fn bad_campaign_arguments_are_named() {
        campaign_fails_naming(&["--shard", "0/3"], "--shard");
        campaign_fails_naming(&["--shard", "0/3"], "numbered from 1");
        campaign_fails_naming(&["--shard", "4/3"], "1..=3");
        campaign_fails_naming(&["--shard", "3"], "K/N");
        campaign_fails_naming(&["--runs", "abc"], "--runs");
        campaign_fails_naming(&["--runs", "0"], "--runs");
        campaign_fails_naming(&["--runs", "-5"], "--runs");
        campaign_fails_naming(&["--jobs", "0"], "--jobs");
        campaign_fails_naming(&["--jobs", "-2"], "--jobs");
        campaign_fails_naming(&["--shrink-budget", "-1"], "--shrink-budget");
        campaign_fails_naming(&["--seed", "x"], "--seed");
        // An empty shard (more shards than runs) is no error: it has nothing to do.
        let dir = temp("empty-shard");
        let out = dir.join("empty.jsonl").to_string_lossy().to_string();
        assert_eq!(
            campaign_cli(&["--runs", "2", "--shard", "3/3", "--out", &out]),
            Ok(0)
        );
        assert_eq!(std::fs::read_to_string(&out).ok().as_deref(), Some(""));
        let _ = std::fs::remove_dir_all(&dir);
        campaign_fails_naming(&["--profile", "loud"], "--profile loud: no such built-in");
        let dir = temp("bad-profile");
        let bad = dir.join("bad.toml");
        std::fs::write(&bad, "[event]\nmeteor = 3\n").expect("write");
        let bad = bad.to_string_lossy().to_string();
        campaign_fails_naming(&["--profile", &bad], "unknown event kind");
        campaign_fails_naming(&["--profile", &dir.to_string_lossy()], "--profile");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_campaign_refuses_to_overwrite_and_its_shards_summarize_to_the_whole() {
        let dir = temp("shards");
        let profile = dir.join("short.toml");
        std::fs::write(
            &profile,
            "base = \"smoke\"\nduration = [\"70s\", \"75s\"]\nprobe_lead = \"10s\"\nevents = [1, 4]\n",
        )
        .expect("profile");
        let p = profile.to_string_lossy().to_string();
        let path = |n: &str| dir.join(n).to_string_lossy().to_string();
        let failures = path("failures");
        let common = ["--runs", "6", "--seed", "3", "--profile", &p, "--jobs", "2"];
        let go = |extra: &[&str]| {
            let mut a: Vec<&str> = common.to_vec();
            a.extend_from_slice(extra);
            a.extend_from_slice(&["--failures", &failures, "--shrink-budget", "2"]);
            campaign_cli(&a)
        };
        let whole = path("whole.jsonl");
        let code = go(&["--out", &whole]).expect("campaign");
        assert!(code == 0 || code == EXIT_VIOLATIONS);
        // Not again without --force, and the file stays as it was.
        let before = std::fs::read_to_string(&whole).expect("lines");
        let again = go(&["--out", &whole]).expect_err("refused");
        assert!(again.contains("--force"), "{again}");
        assert_eq!(std::fs::read_to_string(&whole).ok(), Some(before.clone()));
        assert_eq!(go(&["--out", &whole, "--force"]), Ok(code));
        assert_eq!(std::fs::read_to_string(&whole).ok(), Some(before.clone()));
        let (a, b) = (path("a.jsonl"), path("b.jsonl"));
        go(&["--out", &a, "--shard", "1/2"]).expect("shard 1");
        go(&["--out", &b, "--shard", "2/2"]).expect("shard 2");
        let read = |f: &str| std::fs::read_to_string(f).expect("read");
        let mut union: Vec<String> = [read(&a), read(&b)]
            .iter()
            .flat_map(|t| t.lines().map(String::from).collect::<Vec<_>>())
            .collect();
        let index = |l: &String| -> u64 {
            let v: serde_json::Value = serde_json::from_str(l).expect("json");
            v["index"].as_u64().expect("index")
        };
        union.sort_by_key(index);
        let whole_lines: Vec<String> = before.lines().map(String::from).collect();
        assert_eq!(union, whole_lines);
        // Every failing run has its reproducer, which `asi-lift run` reads.
        for l in &whole_lines {
            let v: serde_json::Value = serde_json::from_str(l).expect("json");
            match v["reproducer"].as_str() {
                Some(name) => {
                    assert_ne!(v["outcome"], "ok");
                    let file = dir.join("failures").join(name);
                    let text = std::fs::read_to_string(&file).expect("reproducer");
                    assert!(text.contains("# reproduce: asi-lift run"), "{text}");
                    Scenario::from_toml(name, &text).expect("a valid scenario");
                }
                None => assert_eq!(v["outcome"], "ok"),
            }
        }
        // The summary of the shards is the summary of the whole.
        let files = |f: &[&str]| f.iter().map(PathBuf::from).collect::<Vec<_>>();
        let merged = summarize(&[("a".into(), read(&a)), ("b".into(), read(&b))]).expect("merge");
        let single = summarize(&[("w".into(), read(&whole))]).expect("whole");
        assert_eq!(merged, single);
        assert_eq!(merged.runs, 6);
        assert_eq!(merged.missing, 0);
        assert_eq!(campaign_summary(&files(&[&a, &b]), false), Ok(0));
        // Overlapping shards and malformed lines are named by file and line.
        let e = campaign_summary(&files(&[&a, &whole]), true).expect_err("duplicate");
        assert!(
            e.contains(&format!("{whole}:1: run 0 is also at {a}:1")),
            "{e}"
        );
        let junk = path("junk.jsonl");
        std::fs::write(
            &junk,
            format!(
                "{}\n{{\"index\": 1}}\n",
                read(&b).lines().next().unwrap_or("")
            ),
        )
        .expect("junk");
        let e = campaign_summary(&files(&[&junk]), false).expect_err("malformed");
        assert!(
            e.starts_with(&format!("{junk}:2: not a campaign line")),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_reproducer_never_replaces_another_file() {
        let dir = temp("repro");
        let first = write_reproducer(&dir, "run-000001-ab.toml", "one").expect("write");
        assert_eq!(
            write_reproducer(&dir, "run-000001-ab.toml", "one"),
            Ok(first.clone())
        );
        let second = write_reproducer(&dir, "run-000001-ab.toml", "two").expect("write");
        assert_eq!(second, dir.join("run-000001-ab-2.toml"));
        assert_eq!(std::fs::read_to_string(&first).ok().as_deref(), Some("one"));
        assert_eq!(
            std::fs::read_to_string(&second).ok().as_deref(),
            Some("two")
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_timing_svg_is_not_overwritten_without_force() {
        let path = std::env::temp_dir().join(format!("asi-lift-timing-{}.svg", std::process::id()));
        let p = path.to_string_lossy().to_string();
        std::fs::write(&path, "keep").expect("temp file");
        let args = ["--bus", "2", "--duration", "50ms", "--svg", p.as_str()];
        fails_naming(&args, "--force");
        assert_eq!(std::fs::read_to_string(&path).ok().as_deref(), Some("keep"));
        let forced = [&args[..], &["--force", "--json"]].concat();
        assert_eq!(timing(&forced), Ok(0));
        let svg = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(svg.starts_with("<svg"), "{svg}");
        let _ = std::fs::remove_file(&path);
    }
}
