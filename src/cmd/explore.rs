//! `asi-lift explore`: every fault of the catalogue at every instant of a grid over a
//! scenario, each fork run to its verdict; one JSON line per fork and the FMEA sheet;
//! `explore summarize` merges result files (the asi-lift guide, "The fault explorer").

use super::run::{load_program, load_scenario};
use super::{open_output, print_out, read_input, EXIT_VIOLATIONS};
use asi_phy::{SimDuration, SimTime};
use clap::Subcommand;
use rig::campaign::run::Shard;
use rig::explore::catalogue::{parse_kinds, FaultKind, Params};
use rig::explore::summary::{sheet, summarize};
use rig::explore::{explore, ForkLine, Plan, Verdict};
use rig::Rig;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

/// What `asi-lift explore` does besides exploring.
#[derive(Subcommand)]
pub enum ExploreAction {
    /// Merge the JSON lines of one exploration (its shards, in any order) into its FMEA
    /// sheet: fault kind × lift phase, the count of each verdict.
    Summarize {
        /// The result files (`-` for standard input).
        #[arg(required = true, value_name = "FILE")]
        files: Vec<PathBuf>,
        /// Write the sheet as JSON.
        #[arg(long)]
        json: bool,
        /// Draw the picture of the outcomes (fault kind × instant, above the cabin's
        /// position) into this SVG file.
        #[arg(long, value_name = "FILE.svg")]
        svg: Option<PathBuf>,
        /// Overwrite the --svg file if it exists.
        #[arg(long)]
        force: bool,
    },
}

/// The arguments of `asi-lift explore`.
#[derive(clap::Args)]
pub struct ExploreArgs {
    /// The scenario: a file (TOML) or the name of a built-in one.
    #[arg(value_name = "SCENARIO")]
    pub scenario: Option<PathBuf>,
    /// Which faults: `single`, one fault per fork (pairs are not there yet).
    #[arg(long, value_name = "single", default_value = "single")]
    pub faults: String,
    /// The grid's step: a fork at every multiple of it within the window.
    #[arg(long, value_name = "DURATION", default_value = "100ms")]
    pub every: String,
    /// The first and the last instant of the grid, START..END (e.g. 10s..20s) [default: the
    /// whole scenario, but its last horizon-free instant].
    #[arg(long, value_name = "START..END")]
    pub window: Option<String>,
    /// The fault kinds, comma-separated (e.g. slave-off:7,stop,vane) [default: the whole
    /// catalogue].
    #[arg(long, value_name = "KIND,…")]
    pub kinds: Option<String>,
    /// How long a fork runs on after its fault at most.
    #[arg(long, value_name = "DURATION", default_value = "60s")]
    pub horizon: String,
    /// How long a slave stays off the bus before it is put back.
    #[arg(long, value_name = "DURATION", default_value = "2s")]
    pub off_for: String,
    /// Worker threads [default: all cores].
    #[arg(long, value_name = "J", allow_negative_numbers = true)]
    pub jobs: Option<usize>,
    /// Run only the K-th of N disjoint parts (1-based): the forks whose index i has
    /// i mod N = K - 1.
    #[arg(long, value_name = "K/N", value_parser = parse_shard)]
    pub shard: Option<Shard>,
    /// Write the JSON lines to this file instead of standard output.
    #[arg(long, value_name = "FILE.jsonl")]
    pub out: Option<PathBuf>,
    /// Run this IEC 61131-3 Structured Text program as the PLC instead of the built-in one
    /// (or the scenario's `[controller] program`); the reproducers name it.
    #[arg(long, value_name = "FILE.st")]
    pub controller: Option<PathBuf>,
    /// Compile the program of `--controller` together with this library (e.g.
    /// `controllers/lab.st`). Repeatable.
    #[arg(long, value_name = "FILE.st")]
    pub library: Vec<PathBuf>,
    /// Draw the picture of the outcomes (fault kind × instant, above the cabin's position)
    /// into this SVG file.
    #[arg(long, value_name = "FILE.svg")]
    pub svg: Option<PathBuf>,
    /// Where the scenario files that reproduce violations and panics go (created when
    /// needed): the scenario with the fault written in, to the fork's horizon.
    #[arg(long, value_name = "DIR", default_value = "explore-failures")]
    pub failures: PathBuf,
    /// Overwrite the --out and --svg files if they exist.
    #[arg(long)]
    pub force: bool,
}

fn duration(flag: &str, text: &str) -> Result<SimDuration, String> {
    text.trim()
        .parse::<SimDuration>()
        .map_err(|e| format!("{flag} {text}: {e}"))
}

/// The plan the arguments give for the scenario `sc`.
fn plan(args: &ExploreArgs, sc: &rig::Scenario) -> Result<Plan, String> {
    if args.faults != "single" {
        return Err(format!(
            "--faults {}: only `single` is there yet (one fault per fork)",
            args.faults
        ));
    }
    let every = duration("--every", &args.every)?;
    if every < SimDuration::from_millis(1) {
        return Err(format!(
            "--every {}: the grid's step is at least 1 ms",
            args.every
        ));
    }
    let horizon = duration("--horizon", &args.horizon)?;
    if horizon.is_zero() || horizon > MAX_HORIZON {
        return Err(format!(
            "--horizon {}: must be longer than zero and at most {MAX_HORIZON}",
            args.horizon
        ));
    }
    let off_for = duration("--off-for", &args.off_for)?;
    if off_for.is_zero() {
        return Err(format!(
            "--off-for {}: must be longer than zero",
            args.off_for
        ));
    }
    let end = SimTime::ZERO + sc.duration;
    let window = match &args.window {
        None => (SimTime::ZERO + every, end - SimDuration::from_nanos(1)),
        Some(w) => {
            let err = |why: String| format!("--window {w}: {why}");
            let (a, b) = w
                .split_once("..")
                .ok_or_else(|| err("expected START..END, e.g. 10s..20s".into()))?;
            let a: SimDuration = a.trim().parse().map_err(|e| err(format!("{e}")))?;
            let b: SimDuration = b.trim().parse().map_err(|e| err(format!("{e}")))?;
            if b < a {
                return Err(err("END must not come before START".into()));
            }
            if SimTime::ZERO + b >= end {
                return Err(err(format!(
                    "END must come before the scenario's end ({})",
                    sc.duration
                )));
            }
            (SimTime::ZERO + a, SimTime::ZERO + b)
        }
    };
    let kinds = match &args.kinds {
        None => FaultKind::all_for(sc),
        Some(k) => parse_kinds(k, sc).map_err(|e| format!("--kinds: {e}"))?,
    };
    let plan = Plan {
        kinds,
        params: Params {
            off_for,
            ..Params::default()
        },
        every,
        window,
        horizon,
        shard: args.shard.unwrap_or(Shard::ALL),
    };
    if plan.instants() == 0 {
        return Err(format!(
            "--every {}: no instant of the grid falls within the window and before the scenario's end ({})",
            args.every, sc.duration
        ));
    }
    Ok(plan)
}

/// The longest horizon: a day of lift after the fault is more than any stop takes to show.
const MAX_HORIZON: SimDuration = SimDuration::from_secs(24 * 3600);

/// `asi-lift explore`: runs the plan, writes the lines, prints the sheet to standard error.
pub fn run(args: ExploreArgs) -> Result<u8, String> {
    let jobs = match args.jobs {
        Some(0) => return Err("--jobs: 0: give at least one worker thread".into()),
        Some(j) => j,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let (mut sc, file) = load_scenario(args.scenario.as_deref(), None)?;
    let plan = plan(&args, &sc)?;
    match &args.controller {
        Some(path) => sc.program = Some(load_program(path, &args.library)?),
        None if !args.library.is_empty() => {
            return Err(
                "--library: a library goes with a program: give --controller FILE.st too".into(),
            )
        }
        None => {}
    }
    let out_path = args.out.clone().unwrap_or_else(|| PathBuf::from("-"));
    let mut inputs: Vec<(&str, &Path)> = Vec::new();
    if let Some(f) = file {
        inputs.push(("the scenario", f));
    }
    if let Some(p) = &sc.program {
        inputs.push(("the program", p.path()));
        inputs.extend(p.libraries().map(|l| ("the library", l)));
    }
    super::output::refuse_inputs("--out", &out_path, &inputs)?;
    if let Some(svg) = &args.svg {
        super::output::refuse_inputs("--svg", svg, &inputs)?;
        if svg.exists() && !args.force {
            return Err(format!(
                "{} exists; pass --force to overwrite it",
                svg.display()
            ));
        }
    }
    let mut out = open_output(&out_path, args.force)?;
    let out_name = if out_path == Path::new("-") {
        "standard output".to_string()
    } else {
        out_path.display().to_string()
    };
    // The scenario's program, if it has one, is in every rig it makes.
    let make = || -> Result<Rig, String> { Rig::new(sc.clone()).map_err(|e| e.to_string()) };
    // A panic in a fork is its verdict, reported in its line: keep the workers' panic
    // messages off the terminal.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let worker = std::thread::current()
            .name()
            .is_some_and(|n| n.starts_with("explore-worker-"));
        if !worker {
            default_hook(info);
        }
    }));
    let count = plan.count();
    let bar = if std::io::stderr().is_terminal() {
        let bar = indicatif::ProgressBar::new(count);
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{elapsed_precise} [{bar:30}] {pos}/{len} forks, {per_sec}, eta {eta}",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar
    } else {
        indicatif::ProgressBar::hidden()
    };
    let mut lines: Vec<ForkLine> = Vec::new();
    let reader_gone = std::cell::Cell::new(false);
    if args.failures.exists() && !args.failures.is_dir() {
        return Err(format!(
            "--failures {}: exists and is not a directory",
            args.failures.display()
        ));
    }
    let mut written = 0u64;
    let mut sink = |mut l: ForkLine| -> Result<(), String> {
        if matches!(l.verdict, Verdict::Violation | Verdict::Panic) {
            let (name, text) = reproducer(&sc, &plan, &l, &args.failures);
            let path = super::campaign::write_reproducer(&args.failures, &name, &text)?;
            l.reproducer = path.file_name().map(|n| n.to_string_lossy().into_owned());
            written += 1;
        }
        let text = l
            .to_json_line()
            .map_err(|e| format!("fork {}: its line as JSON: {e}", l.index))?;
        lines.push(l);
        writeln!(out, "{text}").map_err(|e| {
            if e.kind() == std::io::ErrorKind::BrokenPipe {
                reader_gone.set(true);
            }
            format!("{out_name}: {e}")
        })
    };
    let mut progress = |done: &[ForkLine]| bar.inc(done.len() as u64);
    let result = explore(&make, &plan, jobs, &mut sink, &mut progress);
    bar.finish_and_clear();
    let _ = std::panic::take_hook();
    if reader_gone.get() {
        return Ok(0);
    }
    result.map_err(|e| e.0)?;
    out.flush().map_err(|e| format!("{out_name}: {e}"))?;
    drop(out);
    if let Some(svg) = &args.svg {
        write_svg(svg, &lines, args.force)?;
    }
    let s = sheet(&sc.name, plan.forks(), &lines);
    eprint!("{}", s.to_text());
    if written > 0 {
        eprintln!(
            "{} written to {}",
            rig::report::count(written, "reproducer", "reproducers"),
            args.failures.display()
        );
    }
    let bad = lines
        .iter()
        .any(|l| matches!(l.verdict, Verdict::Violation | Verdict::Panic));
    Ok(if bad { EXIT_VIOLATIONS } else { 0 })
}

/// The reproducer of the fork of `line` in the exploration `plan` of `sc`: its file name and
/// text, a comment header (what failed, how to run it) and the scenario with the fault
/// written in, lasting to the fork's horizon (with the scenario's program, if it has one).
pub fn reproducer(
    sc: &rig::Scenario,
    plan: &Plan,
    line: &ForkLine,
    failures: &Path,
) -> (String, String) {
    let kinds = plan.kinds.len() as u64;
    let kind = plan.kinds[(line.index % kinds) as usize];
    let at = plan.instant(line.index / kinds);
    let repro = rig::explore::written_in(sc.clone(), kind, &plan.params, at, plan.horizon);
    let name = format!(
        "fork-{:07}-{}.toml",
        line.index,
        kind.name().replace(':', "-")
    );
    let one_line = |t: &str| t.replace(['\n', '\r'], " ");
    let header = format!(
        "# asi-lift explore reproducer: fault {kind} at {} in scenario `{}` ({} phase), fork {} of {}\n\
         # fails: {}{}: {}\n\
         # reproduce: asi-lift run {}\n\n",
        at - SimTime::ZERO,
        one_line(&sc.name),
        line.phase,
        line.index,
        line.forks,
        line.verdict,
        line.violation.map_or(String::new(), |v| format!(" {v}")),
        one_line(&line.detail),
        failures.join(&name).display(),
    );
    (name, header + &repro.to_toml())
}

/// Writes the picture of `lines` to `path`, never over a file unless `force`.
fn write_svg(path: &Path, lines: &[ForkLine], force: bool) -> Result<(), String> {
    let mut f = open_output(path, force).map_err(|e| format!("--svg: {e}"))?;
    f.write_all(super::explore_svg::svg(lines).as_bytes())
        .and_then(|()| f.flush())
        .map_err(|e| format!("--svg {}: {e}", path.display()))
}

/// `asi-lift explore summarize`.
pub fn summarize_files(
    files: &[PathBuf],
    json: bool,
    svg: Option<&Path>,
    force: bool,
) -> Result<u8, String> {
    if let Some(svg) = svg {
        let inputs: Vec<(&str, &Path)> = files
            .iter()
            .map(|f| ("a result file", f.as_path()))
            .collect();
        super::output::refuse_inputs("--svg", svg, &inputs)?;
    }
    let mut texts = Vec::new();
    for f in files {
        let name = if f == Path::new("-") {
            "standard input".to_string()
        } else {
            f.display().to_string()
        };
        texts.push((name, read_input(f, super::MAX_RESULTS_BYTES)?));
    }
    let s = summarize(&texts)?;
    if let Some(path) = svg {
        let mut lines: Vec<ForkLine> = Vec::new();
        for (_, text) in &texts {
            for raw in text.lines().filter(|l| !l.trim().is_empty()) {
                // Read once already by `summarize`, which refused anything malformed.
                lines.push(serde_json::from_str(raw).map_err(|e| e.to_string())?);
            }
        }
        lines.sort_by_key(|l| l.index);
        write_svg(path, &lines, force)?;
    }
    print_out(&if json {
        s.to_json().map_err(|e| format!("the sheet as JSON: {e}"))? + "\n"
    } else {
        s.to_text()
    })?;
    Ok(0)
}

fn parse_shard(s: &str) -> Result<Shard, String> {
    s.parse()
}
