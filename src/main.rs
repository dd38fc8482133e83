//! The `asi-lift` command: argument parsing and one module per subcommand ([`cmd`]). The
//! simulation lives in the `rig` library, the files in `asi-trace`.

mod cmd;

use clap::{Parser, Subcommand};
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
    Run(cmd::run::RunArgs),
    /// List the built-in scenarios (one line each), or print one as TOML to copy and edit.
    Scenarios {
        #[command(subcommand)]
        action: Option<cmd::scenarios::ScenariosAction>,
    },
    /// Show how a master call or slave response travels on the line: bits, Manchester levels,
    /// APM pulses; optionally write its line voltage as CSV.
    ///
    /// Calls by their ZMD mnemonic: dexg ADDR VALUE, wpar ADDR VALUE, adra NEW, wid1 VALUE,
    /// dela|res|rdio|rdid|rid1|rid2|rdst ADDR, br01, resp VALUE. ADDR is 0..31 with an optional
    /// A/B suffix (7B); VALUE is four binary digits (1010), 0b1010 or 0..15.
    Encode(cmd::encode::EncodeArgs),
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
    Decode(cmd::decode::DecodeArgs),
    /// Run the lab lift live, on the wall clock, behind a virtual AS-i gateway that speaks
    /// Modbus TCP (README.md, "Live mode"): a client watches the built-in controller, or with
    /// `--controller external` is the PLC itself. Ctrl-C or `--until` ends the run and writes
    /// the report.
    Serve(cmd::serve::ServeArgs),
    /// Timing analysis (docs/timing.md): transaction and cycle time, per-slave update period,
    /// repeats, handshake word times and end-to-end latencies, analytic and simulated side by
    /// side, compared with the textbook cycle time T = (n + 2) · 154 µs.
    Timing(cmd::timing::TimingArgs),
    /// Run many random valid scenarios on the whole rig (README.md, "Campaigns"): one JSON
    /// line per run, every failure shrunk to a scenario file that reproduces it; or merge
    /// result files with `campaign summarize`.
    #[command(args_conflicts_with_subcommands = true)]
    Campaign {
        #[command(subcommand)]
        action: Option<cmd::campaign::CampaignAction>,
        #[command(flatten)]
        args: cmd::campaign::CampaignArgs,
    },
}

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
        Command::Run(args) => cmd::run::run(args),
        Command::Scenarios { action } => cmd::scenarios::run(action),
        Command::Encode(args) => cmd::encode::run(args),
        Command::Decode(args) => cmd::decode::run(args),
        Command::Timing(args) => cmd::timing::run(args),
        Command::Serve(args) => cmd::serve::run(args),
        Command::Campaign { action, args } => match action {
            None => cmd::campaign::run(args),
            Some(cmd::campaign::CampaignAction::Summarize { files, json }) => {
                cmd::campaign::summarize_files(&files, json)
            }
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cmd::campaign::{summarize_files as campaign_summary, write_reproducer};
    use cmd::EXIT_VIOLATIONS;
    use rig::campaign::summary::summarize;
    use rig::Scenario;
    use std::path::PathBuf;

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

    fn run_cli(args: &[&str]) -> Result<u8, String> {
        let cli = Cli::try_parse_from(["asi-lift", "run"].iter().chain(args))
            .map_err(|e| e.to_string())?;
        run(cli)
    }

    #[test]
    fn the_plot_of_a_run_is_deterministic_and_leaves_the_run_alone() {
        let dir = temp("plot");
        let path = |n: &str| dir.join(n).to_string_lossy().to_string();
        let (a, b) = (path("a.svg"), path("b.svg"));
        let (ra, rb, plain) = (path("a.json"), path("b.json"), path("plain.json"));
        let common = ["--until", "20s", "--format", "json"];
        for (svg, report) in [(&a, &ra), (&b, &rb)] {
            let args = [&common[..], &["--plot", svg, "--report", report]].concat();
            assert_eq!(run_cli(&args), Ok(0));
        }
        assert_eq!(
            run_cli(&[&common[..], &["--report", &plain]].concat()),
            Ok(0)
        );
        let read = |f: &str| std::fs::read_to_string(f).expect("output");
        let svg = read(&a);
        assert!(svg.starts_with("<svg"), "{}", &svg[..svg.len().min(200)]);
        assert!(svg.trim_end().ends_with("</svg>"));
        for label in ["floor 1", "floor 2", "floor 3", "floor 4", "time (s)"] {
            assert!(svg.contains(label), "no {label:?} in the plot");
        }
        assert_eq!(svg, read(&b), "two runs of one scenario, two plots");
        // Sampling for the plot only pauses the simulation between moments.
        assert_eq!(read(&ra), read(&plain));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_plot_never_replaces_a_file_and_a_bad_path_is_named_before_the_run() {
        let dir = temp("plot-refused");
        let plot = dir.join("plot.svg");
        std::fs::write(&plot, "keep").expect("temp file");
        let p = plot.to_string_lossy().to_string();
        let report = dir.join("report.txt");
        let r = report.to_string_lossy().to_string();
        let e = run_cli(&["--until", "1s", "--plot", &p, "--report", &r]).expect_err("refused");
        assert!(e.contains(&p) && e.contains("--force"), "{e}");
        assert_eq!(std::fs::read_to_string(&plot).ok().as_deref(), Some("keep"));
        // Refused before the run: the report, written after it, is not there.
        assert!(!report.exists());
        let bad = dir.join("no-such-dir").join("plot.svg");
        let b = bad.to_string_lossy().to_string();
        let e = run_cli(&["--until", "1s", "--plot", &b, "--report", &r]).expect_err("bad path");
        assert!(e.contains(&b), "{e}");
        assert!(!report.exists());
        let e = run_cli(&["--until", "1s", "--plot", "-"]).expect_err("two on stdout");
        assert!(e.contains("--plot"), "{e}");
        assert_eq!(
            run_cli(&["--until", "1s", "--plot", &p, "--report", &r, "--force"]),
            Ok(0)
        );
        let svg = std::fs::read_to_string(&plot).unwrap_or_default();
        assert!(svg.starts_with("<svg"), "{svg}");
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
