//! `asi-lift serve`: the rig on the wall clock with a virtual AS-i/Modbus TCP gateway, for
//! an outside controller or a client that watches the built-in one (the asi-lift guide, chapter "Live mode and your own controller").

use super::output::Outputs;
use super::run::{load_scenario, report_body, set_program, trace_form, Format, TraceForm};
use super::{print_out, EXIT_VIOLATIONS};
use asi_phy::SimDuration;
use gateway::live::LiveConfig;
use gateway::{Owner, Speed};
use rig::Rig;
use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
use std::fs::File;
use std::io::{BufWriter, IsTerminal, Seek, SeekFrom, Write};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

/// The arguments of `asi-lift serve`.
#[derive(clap::Args)]
pub struct ServeArgs {
    /// The scenario: a file (TOML, `-` for standard input) or the name of a built-in one. Its
    /// events (presses, faults) happen at their times as in `asi-lift run`. Without it, the
    /// built-in demo.
    pub scenario: Option<PathBuf>,
    /// Where the Modbus TCP server listens. Only loopback unless an address is given here.
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:5020")]
    pub listen: String,
    /// Simulated seconds per wall second (e.g. 1, 0.5, 10), or `max`: as fast as the machine
    /// can with the built-in controller; with an outside controller, paced by its requests
    /// (each advances the simulation by `--step`). The live view's page can change it while
    /// the run goes on.
    #[arg(long, value_name = "X|max", default_value = "1")]
    pub speed: String,
    /// Who runs the lift: `builtin`, the built-in PLC program (clients may watch); a
    /// Structured Text program `FILE.st` as the PLC (clients may watch; the live view shows
    /// its variables); or `external`, the Modbus client (the built-in program is off; the
    /// client writes the output image) [default: builtin, or the scenario's
    /// `[controller] program`; external with `--ttk4145`].
    #[arg(long, value_name = "builtin|external|FILE.st", value_parser = parse_controller)]
    pub controller: Option<ControllerArg>,
    /// Compile the program of `--controller FILE.st` together with this library (e.g.
    /// `controllers/lab.st`). Repeatable.
    #[arg(long, value_name = "FILE.st")]
    pub library: Vec<PathBuf>,
    /// Also serve the TTK4145 lab elevator protocol (4-byte messages) on this address, for
    /// the course's elevator controllers (the asi-lift guide, chapter "The TTK4145 front
    /// end"); the built-in
    /// program is off then.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:15657")]
    pub ttk4145: Option<String>,
    /// Also serve the live view, a page that shows the rig as it runs and lets a browser press
    /// its buttons, inject faults, pause the run, change its speed and restart it (the
    /// asi-lift guide, chapter "Live view in the browser"), on this address
    /// [default: off; 127.0.0.1:8080 when given without an address]. Only loopback unless an
    /// address is given here.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8080")]
    pub http: Option<String>,
    /// A host name the live view answers to besides its own address and loopback (a name of
    /// this machine, a proxy's): `NAME` with the live view's port, or `NAME:PORT`. Repeatable.
    /// Other names get 403 (Forbidden), against DNS rebinding.
    #[arg(long = "allow-host", value_name = "NAME")]
    pub allow_hosts: Vec<String>,
    /// With an outside controller: the output image goes to zero when no client has written
    /// it for this long (simulated time; 0 = off).
    #[arg(long, value_name = "DURATION", default_value = "1s")]
    pub watchdog: String,
    /// At `--speed max` with an outside controller: how far each request advances the
    /// simulation.
    #[arg(long, value_name = "DURATION", default_value = "1ms")]
    pub step: String,
    /// Show only the status line while the run goes on, not its log as it happens (the
    /// report at the end has the whole log either way).
    #[arg(long, short = 'q')]
    pub quiet: bool,
    /// End the run at this simulated time (e.g. 60s, 10min) [default: Ctrl-C ends it].
    #[arg(long, value_name = "DURATION")]
    pub until: Option<String>,
    /// Use this seed instead of the scenario's.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Where the report goes at the end: a file, or `-` for standard output.
    #[arg(long, value_name = "FILE|-", default_value = "-")]
    pub report: PathBuf,
    /// The report's format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,
    /// Write every bus transaction, one line each, to this file: JSON lines for a `.jsonl`
    /// or `.json` file, readable text otherwise. A restart from the live view's page starts
    /// it again: it holds the last run, as the report does.
    #[arg(long, value_name = "FILE")]
    pub trace: Option<PathBuf>,
    /// The trace's form, overriding the file name's.
    #[arg(long, value_enum)]
    pub trace_format: Option<TraceForm>,
    /// Overwrite the report and trace files if they exist.
    #[arg(long)]
    pub force: bool,
}

/// Who runs the lift in a live run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ControllerArg {
    /// The built-in PLC program; the gateway's outputs are read-only.
    Builtin,
    /// A Structured Text program in the PLC; the gateway's outputs are read-only.
    Program(PathBuf),
    /// The Modbus client is the PLC.
    External,
}

/// `--controller`: `builtin`, `external`, or a program's file.
fn parse_controller(s: &str) -> Result<ControllerArg, String> {
    Ok(match s {
        "builtin" => ControllerArg::Builtin,
        "external" => ControllerArg::External,
        "" => return Err("give builtin, external or a Structured Text file".into()),
        file => ControllerArg::Program(PathBuf::from(file)),
    })
}

/// How long a live run lasts without `--until`: until Ctrl-C, in practice.
const OPEN_END: SimDuration = SimDuration::from_secs(365 * 24 * 3600);

/// The address given to `flag`. `--ttk4145` and `--http` take an optional value, so a
/// scenario written after them is read as their address: the error says so.
fn address(flag: &str, value: &str, example: &str) -> Result<SocketAddr, String> {
    value.parse().map_err(|e| {
        let scenario = Path::new(value).exists() || super::scenarios::find(value).is_ok();
        let hint = if scenario {
            format!(
                "; `{value}` is a scenario: put it before {flag}, or give the address as {flag}={example}"
            )
        } else {
            String::new()
        };
        format!("{flag} {value}: {e} (expected an address such as {example}){hint}")
    })
}

/// Serves the rig until `--until` or Ctrl-C and writes the report.
pub fn run(args: ServeArgs) -> Result<u8, String> {
    let ServeArgs {
        scenario,
        listen,
        speed,
        controller,
        library,
        ttk4145,
        http,
        allow_hosts,
        watchdog,
        step,
        quiet,
        until,
        seed,
        report,
        format,
        trace,
        trace_format,
        force,
    } = args;
    let listen = address("--listen", &listen, "127.0.0.1:5020")?;
    let ttk = ttk4145
        .map(|a| address("--ttk4145", &a, "127.0.0.1:15657"))
        .transpose()?;
    let http = http
        .map(|a| address("--http", &a, "127.0.0.1:8080"))
        .transpose()?;
    // Without --controller: the scenario's program, else the built-in one (`None` here).
    let controller = match (controller, ttk) {
        (Some(c @ (ControllerArg::Builtin | ControllerArg::Program(_))), Some(_)) => {
            let which = match c {
                ControllerArg::Program(p) => p.display().to_string(),
                _ => "builtin".into(),
            };
            return Err(format!("--ttk4145: a TTK4145 client is the controller; it cannot run beside --controller {which}"));
        }
        (Some(c), _) => Some(c),
        (None, Some(_)) => Some(ControllerArg::External),
        (None, None) => None,
    };
    if !allow_hosts.is_empty() && http.is_none() {
        return Err("--allow-host: names the live view's hosts; give --http too".into());
    }
    if let Some(bad) = allow_hosts
        .iter()
        .find(|h| !gateway::web::Hosts::valid_name(h))
    {
        return Err(format!(
            "--allow-host {bad}: expected a host name or IP address, optionally with :PORT"
        ));
    }
    let speed = parse_speed(&speed)?;
    let duration =
        |flag: &str, s: &str| s.parse::<SimDuration>().map_err(|e| format!("{flag}: {e}"));
    let watchdog = duration("--watchdog", &watchdog)?;
    let step = duration("--step", &step)?;
    if step.is_zero() {
        return Err(
            "--step: must be longer than 0 (each request advances the simulation by it)".into(),
        );
    }
    let until = until.map(|u| duration("--until", &u)).transpose()?;
    let (mut sc, file) = load_scenario(scenario.as_deref(), None)?;
    if let Some(s) = seed {
        sc.seed = s;
    }
    sc.duration = until.unwrap_or(OPEN_END);
    let owner = match controller {
        Some(ControllerArg::External) => Owner::External,
        _ => Owner::Builtin,
    };
    let program = match controller {
        Some(ControllerArg::Program(p)) => Some(p),
        Some(ControllerArg::Builtin | ControllerArg::External) => {
            sc.program = None;
            None
        }
        None => None,
    };
    if owner == Owner::External {
        if let Some(w) = speed.outside_controller_warning() {
            eprintln!("asi-lift: warning: --{w}");
        }
    }

    // SIGTERM (docker stop, Kubernetes) and SIGHUP end the run as Ctrl-C does, with its
    // report; so does any of them (Ctrl-C too) before the servers are up.
    let stop = Arc::new(AtomicBool::new(false));
    for signal in [SIGINT, SIGTERM, SIGHUP] {
        signal_hook::flag::register(signal, Arc::clone(&stop))
            .map_err(|e| format!("cannot handle signals: {e}"))?;
    }
    let mut outs = Outputs::new(force);
    if let Some(path) = file {
        outs.input("the scenario", path)?;
    }
    set_program(&mut sc, program.as_deref(), &library, &mut outs)?;
    let report_sink = outs.add("--report", &report)?;
    if trace.as_deref() == Some(Path::new("-")) {
        return Err("--trace: a live run's trace goes to a file, not to standard output".into());
    }
    let trace_sink = trace
        .as_deref()
        .map(|p| outs.add("--trace", p))
        .transpose()?;
    let trace_out = match (&trace, &trace_sink) {
        (Some(path), Some(sink)) => Some((
            RunTrace::new(outs.file(sink)?, path),
            trace_form(trace_format, path),
        )),
        _ => None,
    };

    let who = match (owner, &sc.program) {
        (Owner::External, _) => "external controller".to_owned(),
        (Owner::Builtin, Some(p)) => format!("controller {}", p.path().display()),
        (Owner::Builtin, None) => "built-in controller".to_owned(),
    };
    // Called again for each restart from the live view's page: the same scenario and seed,
    // the same controller, and the trace started again.
    let make_rig = move || {
        let mut rig = Rig::new(sc.clone())?;
        if owner == Owner::External {
            rig = rig.with_external_controller();
        }
        if let Some((trace, form)) = &trace_out {
            rig.trace_to(trace.next_run()?, *form);
        }
        Ok(rig)
    };
    let cfg = {
        let mut cfg = LiveConfig::default();
        cfg.speed = speed;
        cfg.owner = owner;
        cfg.watchdog = watchdog;
        cfg.step = step;
        cfg
    };
    let servers = gateway::Listen {
        modbus: listen,
        ttk,
        http,
    };
    let options = {
        let mut cfg = gateway::Options::default();
        cfg.allow_hosts = allow_hosts;
        cfg
    };
    let running =
        gateway::start_with(make_rig, cfg, servers, options).map_err(|e| e.to_string())?;
    running.stop_on_ctrl_c();
    let addr = running.local_addr();
    for a in std::iter::once(addr)
        .chain(running.ttk_addr())
        .chain(running.http_addr())
    {
        if !a.ip().is_loopback() {
            eprintln!(
                "asi-lift: warning: listening on {a}, not loopback: anyone who reaches this machine can drive the lift"
            );
        }
    }
    if let Some(a) = running.ttk_addr() {
        eprintln!("asi-lift: TTK4145 elevator server on {a}");
    }
    if let Some(a) = running.http_addr() {
        eprintln!("asi-lift: live view on http://{a}/");
    }
    eprintln!(
        "asi-lift: Modbus TCP gateway on {addr}, {}, speed {speed}{}; Ctrl-C ends the run",
        who,
        until.map_or(String::new(), |u| format!(", until {u}"))
    );
    let terminal = std::io::stderr().is_terminal();
    for s in running.status().iter() {
        if stop.swap(false, Ordering::Relaxed) {
            running.stop();
        }
        if !quiet {
            // The log as it happens, above the status line on a terminal.
            let clear = if terminal { "\r\x1b[K" } else { "" };
            let mut err = std::io::stderr().lock();
            for line in &s.log {
                let _ = writeln!(err, "{clear}{line}");
            }
            if s.log_left_out > 0 {
                let _ = writeln!(
                    err,
                    "{clear}      … {} more log lines in this second, in the report",
                    s.log_left_out
                );
            }
        }
        if terminal {
            eprint!(
                "\r  simulated {:.1} s, {} requests, lag {:.1} ms, {} violations{}{}   ",
                s.simulated_s,
                s.requests,
                s.lag_ms,
                s.violations,
                if s.watchdog_tripped {
                    ", WATCHDOG: outputs zero"
                } else {
                    ""
                },
                if s.paused { ", paused by the page" } else { "" }
            );
            let _ = std::io::stderr().flush();
        }
        if s.ended {
            break;
        }
    }
    if terminal {
        eprintln!();
    }
    let rep = running.wait();
    outs.write_all(&report_sink, &report_body(&rep, format)?)?;
    let lost = outs.keep_out_unwritten(
        rep.output_error.as_deref(),
        &[("--trace", trace_sink.as_ref())],
    );
    outs.commit()?;
    if let Some(lost) = lost {
        return Err(lost);
    }
    if report != Path::new("-") {
        print_out(&format!(
            "{}report written to {}\n",
            rep.summary_text(),
            report.display()
        ))?;
    }
    Ok(if rep.violations.is_empty() {
        0
    } else {
        EXIT_VIOLATIONS
    })
}

/// A live run's trace file, which holds one run from its power-on, as the report does: the
/// last one, when the live view's page restarts the run. Each run writes through a writer of
/// its own; the next run's truncates the file, and from then on the earlier run's writer
/// (dropped, and flushed, only after the fresh rig has replaced it) writes nothing. A pipe or
/// a device cannot be truncated: there the runs follow one another.
struct RunTrace {
    shared: Arc<Mutex<TraceShared>>,
    shown: PathBuf,
}

struct TraceShared {
    file: File,
    /// The run whose writer writes; the others' bytes are dropped.
    run: u64,
}

/// One run's writer of a [`RunTrace`].
struct RunTraceWriter {
    shared: Arc<Mutex<TraceShared>>,
    run: u64,
}

impl RunTrace {
    fn new(file: File, path: &Path) -> RunTrace {
        RunTrace {
            shared: Arc::new(Mutex::new(TraceShared { file, run: 0 })),
            shown: path.to_path_buf(),
        }
    }

    /// The writer of the next run, the file emptied for it (after the first).
    fn next_run(&self) -> Result<Box<dyn Write>, String> {
        let mut s = self.shared.lock().unwrap_or_else(PoisonError::into_inner);
        if s.run > 0 && s.file.metadata().is_ok_and(|m| m.is_file()) {
            s.file
                .set_len(0)
                .and_then(|()| s.file.seek(SeekFrom::Start(0)).map(|_| ()))
                .map_err(|e| {
                    format!(
                        "--trace {}: cannot start it again: {e}",
                        self.shown.display()
                    )
                })?;
        }
        s.run += 1;
        Ok(Box::new(BufWriter::new(RunTraceWriter {
            shared: Arc::clone(&self.shared),
            run: s.run,
        })))
    }
}

impl Write for RunTraceWriter {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let mut s = self.shared.lock().unwrap_or_else(PoisonError::into_inner);
        if s.run != self.run {
            return Ok(buf.len());
        }
        s.file.write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        let mut s = self.shared.lock().unwrap_or_else(PoisonError::into_inner);
        if s.run != self.run {
            return Ok(());
        }
        s.file.flush()
    }
}

/// `--speed`: a factor within the live mode's bounds, or `max`.
fn parse_speed(s: &str) -> Result<Speed, String> {
    if s == "max" {
        return Ok(Speed::Max);
    }
    let expected = || {
        format!(
            "--speed {s}: expected a factor from {} to {} (simulated seconds per wall second) or `max`",
            gateway::live::MIN_SPEED,
            gateway::live::MAX_SPEED
        )
    };
    let x = s.parse::<f64>().map_err(|_| expected())?;
    Speed::factor(x).map_err(|_| expected())
}
