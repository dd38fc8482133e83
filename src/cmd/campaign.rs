//! `asi-lift campaign`: many random valid scenarios on the whole rig, their lines, the
//! reproducers of failing runs; `campaign summarize` merges result files.

use super::{open_output, print_out, read_input, EXIT_VIOLATIONS};
use clap::Subcommand;
use rig::campaign::profile::Profile;
use rig::campaign::run::{run_campaign, Finished, Plan, Shard};
use rig::campaign::summary::summarize;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

/// What `asi-lift campaign` does besides running a campaign.
#[derive(Subcommand)]
pub enum CampaignAction {
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

/// The arguments of `asi-lift campaign`.
#[derive(clap::Args)]
pub struct CampaignArgs {
    /// Runs of the whole campaign (all shards together).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 100,
        allow_negative_numbers = true
    )]
    pub runs: u64,
    /// The campaign seed: the same seed gives the same runs and the same lines.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 1,
        allow_negative_numbers = true
    )]
    pub seed: u64,
    /// Worker threads [default: all cores].
    #[arg(long, value_name = "J", allow_negative_numbers = true)]
    pub jobs: Option<usize>,
    /// Run only the K-th of N disjoint parts (1-based): the runs whose index i has
    /// i mod N = K - 1.
    #[arg(long, value_name = "K/N", value_parser = parse_shard)]
    pub shard: Option<Shard>,
    /// Write the JSON lines to this file instead of standard output.
    #[arg(long, value_name = "FILE.jsonl")]
    pub out: Option<PathBuf>,
    /// The generator's profile: a built-in (default, quiet, noisy, smoke, safe-drive) or a
    /// profile file.
    #[arg(long, value_name = "NAME|FILE", default_value = "default")]
    pub profile: String,
    /// Where the shrunk reproducers of failing runs go (created when needed).
    #[arg(long, value_name = "DIR", default_value = "campaign-failures")]
    pub failures: PathBuf,
    /// Runs a failure may spend on shrinking (0: write the failing scenario as generated).
    #[arg(
        long,
        value_name = "RUNS",
        default_value_t = 64,
        allow_negative_numbers = true
    )]
    pub shrink_budget: u32,
    /// Run the second referee beside every run: a hazard it finds in the plant that the
    /// invariant watch did not name fails the run as a `disagreement` (a little slower).
    #[arg(long)]
    pub referee: bool,
    /// Run every scenario with this IEC 61131-3 Structured Text program as the PLC instead of
    /// the built-in one; the reproducers name it. A program that does not compile is refused
    /// before the first run.
    #[arg(long, value_name = "FILE.st")]
    pub controller: Option<PathBuf>,
    /// Compile the program of `--controller` together with this library (e.g.
    /// `controllers/lab.st`). Repeatable.
    #[arg(long, value_name = "FILE.st")]
    pub library: Vec<PathBuf>,
    /// Overwrite the --out file if it exists.
    #[arg(long)]
    pub force: bool,
}

/// `asi-lift campaign`: runs the plan, writes the lines and the reproducers.
pub fn run(args: CampaignArgs) -> Result<u8, String> {
    if args.runs == 0 {
        return Err("--runs: 0: a campaign has at least one run".into());
    }
    let jobs = match args.jobs {
        Some(0) => return Err("--jobs: 0: give at least one worker thread".into()),
        Some(j) => j,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let profile = Profile::resolve(&args.profile).map_err(|e| e.to_string())?;
    if args.controller.is_none() && !args.library.is_empty() {
        return Err(
            "--library: a library goes with a program: give --controller FILE.st too".into(),
        );
    }
    let program = args
        .controller
        .as_deref()
        .map(|p| super::run::load_program(p, &args.library))
        .transpose()?;
    let plan = Plan {
        seed: args.seed,
        runs: args.runs,
        shard: args.shard.unwrap_or(Shard::ALL),
        profile,
        shrink_budget: args.shrink_budget,
        referee: args.referee,
        failures: args.failures.clone(),
        program,
    };
    let count = plan.count();
    if count == 0 {
        // More shards than runs (an array larger than the campaign): nothing to do here.
        eprintln!(
            "asi-lift: --shard {}: the campaign's {} leave this shard empty",
            plan.shard,
            rig::report::count(plan.runs, "run", "runs")
        );
    }
    if args.failures.exists() && !args.failures.is_dir() {
        return Err(format!(
            "--failures {}: exists and is not a directory",
            args.failures.display()
        ));
    }
    let out_path = args.out.clone().unwrap_or_else(|| PathBuf::from("-"));
    // The profile file is an input: no --force may truncate it.
    let profile_file = Path::new(&args.profile);
    if Profile::built_in(&args.profile).is_none() && profile_file.exists() {
        super::output::refuse_inputs("--out", &out_path, &[("--profile", profile_file)])?;
    }
    // So is the program.
    if let Some(p) = &args.controller {
        super::output::refuse_inputs("--out", &out_path, &[("--controller", p)])?;
    }
    for l in &args.library {
        super::output::refuse_inputs("--out", &out_path, &[("--library", l)])?;
    }
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
    // Set when standard output's reader has gone (`| head`): the campaign stops quietly.
    let reader_gone = std::cell::Cell::new(false);
    let mut sink = |mut f: Finished| -> Result<(), String> {
        if let Some(r) = &f.reproducer {
            let path = write_reproducer(&failures_dir, &r.file_name, &r.text)?;
            f.line.reproducer = path.file_name().map(|n| n.to_string_lossy().into_owned());
            written.push(path);
        }
        *outcomes
            .entry(f.line.outcome.name().to_owned())
            .or_default() += 1;
        let line = f
            .line
            .to_json_line()
            .map_err(|e| format!("run {}: its line as JSON: {e}", f.line.index))?;
        writeln!(out, "{line}")
            .and_then(|()| out.flush())
            .map_err(|e| {
                if e.kind() == std::io::ErrorKind::BrokenPipe {
                    reader_gone.set(true);
                }
                format!("{out_name}: {e}")
            })
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
    if reader_gone.get() {
        return Ok(0);
    }
    result.map_err(|e| e.0)?;
    let failing = count
        - outcomes.get("ok").copied().unwrap_or(0)
        - outcomes.get("attended").copied().unwrap_or(0);
    let by: Vec<String> = outcomes.iter().map(|(k, v)| format!("{v} {k}")).collect();
    eprintln!(
        "campaign seed {}, profile {}, shard {}: {}: {}",
        plan.seed,
        plan.profile.name,
        plan.shard,
        rig::report::count(count, "run", "runs"),
        by.join(", ")
    );
    if failing > 0 {
        eprintln!(
            "{} written to {}",
            rig::report::count(written.len() as u64, "reproducer", "reproducers"),
            args.failures.display()
        );
        return Ok(EXIT_VIOLATIONS);
    }
    Ok(0)
}

/// Writes a reproducer into `dir` as `name`, never over another file: an existing file
/// with the same text is kept as it is, one with other text gets the next free name
/// (`run-000042-…-2.toml`).
pub fn write_reproducer(dir: &Path, name: &str, text: &str) -> Result<PathBuf, String> {
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
                if same_text(&path, text) {
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

/// Whether the file at `path` holds `text`, reading no more than one byte past its length (the
/// file may be anything: a device, a huge file of that name).
fn same_text(path: &Path, text: &str) -> bool {
    use std::io::Read;
    let mut got = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(text.len() as u64 + 1).read_to_end(&mut got))
        .is_ok_and(|_| got == text.as_bytes())
}

/// `asi-lift campaign summarize`.
pub fn summarize_files(files: &[PathBuf], json: bool) -> Result<u8, String> {
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
    print_out(&if json {
        s.to_json()
            .map_err(|e| format!("the summary as JSON: {e}"))?
            + "\n"
    } else {
        s.to_text()
    })?;
    Ok(0)
}

fn parse_shard(s: &str) -> Result<Shard, String> {
    s.parse()
}
