//! The `asi-lift` command as a user runs it: the built binary, real files and a real pipe
//! (the book, "The bus, traces and waveforms"); then its parts in this process, through the
//! library (modules `command`, `output`, `plot`, `run`). These are all of the command's tests:
//! the library and the binary have no unit-test builds of their own (Cargo.toml).

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn asi_lift() -> Command {
    Command::new(env!("CARGO_BIN_EXE_asi-lift"))
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn temp() -> tempfile::TempDir {
    tempfile::tempdir().expect("a temporary directory")
}

/// Runs `cmd` with its standard output read as `| head -1` does: the first line, then the
/// reader goes. Returns that line and how the command ended.
fn head_1(cmd: &mut Command) -> (String, std::process::Output) {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("asi-lift starts");
    let stdout = child.stdout.take().expect("stdout");
    let mut first = String::new();
    BufReader::new(stdout)
        .read_line(&mut first)
        .expect("one line");
    let out = child.wait_with_output().expect("asi-lift ends");
    (first, out)
}

fn fails(cmd: &mut Command) -> String {
    let out = cmd.output().expect("asi-lift runs");
    assert!(!out.status.success(), "{cmd:?} was accepted");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!err.contains("panicked"), "{err}");
    err
}

#[test]
fn two_spellings_of_one_file_are_refused_and_leave_nothing_behind() {
    let d = temp();
    let dotted: PathBuf = d.path().join(".").join("a.out");
    let plain = d.path().join("a.out");
    let err = fails(
        asi_lift()
            .args(["run", "--until", "1s", "--report"])
            .arg(d.path().join("r.txt"))
            .arg("--vcd")
            .arg(&dotted)
            .arg("--csv")
            .arg(&plain),
    );
    assert!(err.contains("--vcd") && err.contains("--csv"), "{err}");
    assert!(files_in(d.path()).is_empty(), "{:?}", files_in(d.path()));
}

#[test]
fn the_scenario_file_is_no_output() {
    let d = temp();
    let sc = d.path().join("s.toml");
    std::fs::write(&sc, "duration = \"1s\"\n").expect("write");
    let link = d.path().join("link.toml");
    std::os::unix::fs::symlink(&sc, &link).expect("symlink");
    let err = fails(
        asi_lift()
            .arg("run")
            .arg(&sc)
            .arg("--report")
            .arg(&link)
            .arg("--force"),
    );
    assert!(err.contains("same file"), "{err}");
    assert_eq!(
        std::fs::read_to_string(&sc).expect("read"),
        "duration = \"1s\"\n"
    );
}

#[test]
fn an_unwritable_or_existing_report_is_refused_and_the_users_file_kept() {
    let d = temp();
    let missing = d.path().join("no-such-dir").join("r.json");
    let err = fails(asi_lift().args(["run", "--report"]).arg(&missing));
    assert!(err.contains("no-such-dir"), "{err}");
    let mine = d.path().join("r.json");
    std::fs::write(&mine, "mine").expect("write");
    let err = fails(asi_lift().args(["run", "--report"]).arg(&mine));
    assert!(err.contains("--force"), "{err}");
    assert_eq!(std::fs::read_to_string(&mine).expect("read"), "mine");
    assert_eq!(files_in(d.path()), ["r.json"]);
}

/// A trace that cannot be written whole (a full disk: /dev/full) keeps every trace and
/// waveform file out of place, so a file of that name keeps what it had, even with --force;
/// the report is written and the command says what was not.
#[test]
fn a_trace_that_cannot_be_written_leaves_the_users_files_alone() {
    let d = temp();
    let vcd = d.path().join("run.vcd");
    std::fs::write(&vcd, "mine").expect("write");
    let report = d.path().join("r.txt");
    let err = fails(
        asi_lift()
            .args([
                "run",
                "demo",
                "--until",
                "3s",
                "--force",
                "--trace",
                "/dev/full",
            ])
            .arg("--vcd")
            .arg(&vcd)
            .arg("--report")
            .arg(&report),
    );
    assert!(err.contains("--trace /dev/full"), "{err}");
    assert!(err.contains("--vcd"), "{err}");
    assert!(err.contains("No space left"), "{err}");
    assert_eq!(std::fs::read_to_string(&vcd).expect("read"), "mine");
    let text = std::fs::read_to_string(&report).expect("the report is written");
    assert!(
        text.contains("the bus trace could not be written"),
        "{text}"
    );
    assert_eq!(files_in(d.path()), ["r.txt", "run.vcd"]);
}

#[test]
fn a_reader_that_goes_ends_the_run_quietly() {
    let d = temp();
    let report = d.path().join("r.json");
    // The reader goes after the first trace line, as `| head -1` does.
    let (first, out) = head_1(
        asi_lift()
            .args(["run", "--trace", "-", "--report"])
            .arg(&report),
    );
    assert!(!first.is_empty());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{:?}: {err}", out.status);
    assert!(!err.contains("panicked"), "{err}");
    // The run was cut short: its report is not put in place as if it were whole.
    assert!(files_in(d.path()).is_empty(), "{:?}", files_in(d.path()));
}

#[test]
fn decode_prints_as_it_goes_and_a_reader_that_goes_ends_it_quietly() {
    let d = temp();
    let vcd = d.path().join("run.vcd");
    let run = asi_lift()
        .args(["run", "--until", "2s", "--report", "-", "--vcd"])
        .arg(&vcd)
        .output()
        .expect("asi-lift run");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for (json, signal) in [(false, true), (true, true), (false, false)] {
        let mut cmd = asi_lift();
        cmd.arg("decode").arg(&vcd);
        // asi-lift's own VCD is read from its pulse wire when no signal is named.
        if signal {
            cmd.args(["--signal", "manchester"]);
        }
        if json {
            cmd.arg("--json");
        }
        let (first, out) = head_1(&mut cmd);
        assert!(
            first.contains(if json { "\"t_ns\"" } else { "time_s" }),
            "{first}"
        );
        // The reader went, as `| head -1` does, with thousands of telegrams still to come.
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{:?}: {err}", out.status);
        assert!(err.is_empty(), "{err}");
    }
}

/// `decode` of a capture ends with the statistics per slave worked out from the decoded
/// transactions: for a slave unplugged and plugged back on a clean line, the same counts as
/// the run's report, which the bus counted.
#[test]
fn decode_prints_the_statistics_per_slave_of_a_capture() {
    let d = temp();
    let scenario = d.path().join("unplugged.toml");
    std::fs::write(
        &scenario,
        "name = \"slave 6 unplugged\"\nduration = \"3s\"\n\n\
         [[event]]\nat = \"1s\"\nfault = { kind = \"slave-offline\", slave = 6 }\n\n\
         [[event]]\nat = \"1.4s\"\nfault = { kind = \"slave-online\", slave = 6 }\n",
    )
    .expect("scenario");
    let (vcd, report) = (d.path().join("run.vcd"), d.path().join("r.json"));
    let run = asi_lift()
        .arg("run")
        .arg(&scenario)
        .args(["--format", "json", "--report"])
        .arg(&report)
        .arg("--vcd")
        .arg(&vcd)
        .output()
        .expect("asi-lift run");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let out = asi_lift().arg("decode").arg(&vcd).output().expect("decode");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let table = &text[text.find("per slave").expect("the per-slave table")..];
    insta::assert_snapshot!(table);
    // The rows against the report's `bus.slaves[]`: the capture holds the whole run but the
    // request in flight at its end.
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).expect("report")).expect("JSON");
    let six = r["bus"]["slaves"]
        .as_array()
        .expect("bus.slaves")
        .iter()
        .find(|s| s["address"] == 6)
        .expect("slave 6");
    let row: Vec<&str> = table
        .lines()
        .find(|l| l.split_whitespace().next() == Some("6"))
        .expect("row of slave 6")
        .split_whitespace()
        .collect();
    for (column, key) in [
        (3, "repeats"),
        (5, "failed_after_repeat"),
        (6, "single_errors"),
        (7, "consecutive_errors"),
    ] {
        assert_eq!(row[column], six[key].to_string(), "{key}");
    }
    assert_eq!(six["dropouts"], 1);
    assert_eq!(six["worst_light"], "red");
}

#[test]
fn built_in_scenarios_are_listed_shown_and_run_by_name() {
    let out = asi_lift().arg("scenarios").output().expect("runs");
    let list = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    for name in ["demo", "door", "overtravel", "noise-1e-2"] {
        assert!(
            list.lines().any(|l| l.starts_with(&format!("{name} "))),
            "{list}"
        );
    }
    let out = asi_lift()
        .args(["scenarios", "show", "door"])
        .output()
        .expect("runs");
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let file = std::fs::read_to_string(repo.join("scenarios/door.toml")).expect("door.toml");
    assert_eq!(String::from_utf8_lossy(&out.stdout), file);
    // By name, with the algorithm from the command line.
    let out = asi_lift()
        .args(["run", "door", "--until", "1s", "--algorithm", "collective"])
        .output()
        .expect("runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("scenario \"door open\""), "{text}");
    assert!(text.contains("collective control"), "{text}");
    let err = fails(asi_lift().args(["run", "dooor"]));
    assert!(
        err.contains("no built-in scenario") && err.contains("door"),
        "{err}"
    );
}

#[test]
fn events_after_the_end_are_warned_of() {
    let d = temp();
    let sc = d.path().join("late.toml");
    std::fs::write(
        &sc,
        "duration = \"1s\"\n\n[[event]]\nat = \"5s\"\npress = \"cabin:2\"\n",
    )
    .expect("write");
    let out = asi_lift().arg("run").arg(&sc).output().expect("runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("late.toml:3: the event at 5 s comes at or after the scenario's end (1 s)"),
        "{err}"
    );
    // A run extended past the event (`--until`) has it happen: no warning.
    let out = asi_lift()
        .arg("run")
        .arg(&sc)
        .args(["--until", "6s"])
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("never happens"), "{err}");
}

#[test]
fn a_file_that_is_not_utf8_is_refused_at_its_place() {
    let d = temp();
    let sc = d.path().join("bad.toml");
    std::fs::write(&sc, b"name = \"ok\"\nseed = 1 # caf\xe9\n").expect("write");
    let err = fails(asi_lift().arg("run").arg(&sc));
    assert!(
        err.contains("bad.toml:2:15: not UTF-8 text (byte 0xE9)"),
        "{err}"
    );
}

#[test]
fn endless_inputs_are_refused_with_a_clear_error_in_bounded_memory() {
    let d = temp();
    let cases: [(&[&str], &str); 6] = [
        (
            &["decode", "/dev/zero"],
            "/dev/zero: line 1: the line is longer than 1 MiB",
        ),
        (
            &["decode", "--format", "vcd", "/dev/zero"],
            "/dev/zero: line 1: the line is longer than 1 MiB",
        ),
        (&["run", "/dev/zero"], "/dev/zero: larger than 16 MiB"),
        (&["stand", "/dev/zero"], "/dev/zero: larger than 16 MiB"),
        (
            &["serve", "--listen", "127.0.0.1:0", "/dev/zero"],
            "/dev/zero: larger than 16 MiB",
        ),
        (
            &["campaign", "--runs", "1", "--profile", "/dev/zero"],
            "--profile /dev/zero: larger than 16 MiB",
        ),
    ];
    for (args, want) in cases {
        let out = asi_lift()
            .args(args)
            .current_dir(d.path())
            .output()
            .expect("asi-lift runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(err.len() < 400, "{args:?}: {err}");
    }
}

#[test]
fn outputs_follow_the_umask_and_a_replaced_file_keeps_its_mode() {
    use std::os::unix::fs::PermissionsExt;
    let d = temp();
    let report = d.path().join("r.txt");
    let mode = |p: &Path| std::fs::metadata(p).expect("exists").permissions().mode() & 0o7777;
    let run = |force: &str| {
        let out = Command::new("sh")
            .arg("-c")
            .arg(format!(
                "umask 027 && exec \"$0\" stand sto --report \"$1\" {force}"
            ))
            .arg(env!("CARGO_BIN_EXE_asi-lift"))
            .arg(&report)
            .output()
            .expect("sh runs");
        assert!(out.status.success(), "{out:?}");
    };
    run("");
    assert_eq!(mode(&report), 0o640);
    std::fs::set_permissions(&report, std::fs::Permissions::from_mode(0o664)).expect("chmod");
    run("--force");
    assert_eq!(mode(&report), 0o664);
}

/// `explore` names the flag and the cause of each bad argument, before it runs anything.
#[test]
fn explore_refuses_bad_flags_with_their_names_and_causes() {
    let cases: [(&[&str], &str); 12] = [
        (
            &["--every", "0ms"],
            "--every 0ms: the grid's step is at least 1 ms",
        ),
        (&["--every", "fast"], "--every fast: "),
        (
            &["--window", "10s"],
            "--window 10s: expected START..END, e.g. 10s..20s",
        ),
        (
            &["--window", "20s..10s"],
            "--window 20s..10s: END must not come before START",
        ),
        (
            &["--window", "10s..80s"],
            "--window 10s..80s: END must come before the scenario's end (80 s)",
        ),
        (
            &["--kinds", "door-close"],
            "--kinds: `door-close`: unknown fault kind (use slave-off:N,",
        ),
        (
            &["--kinds", "encoder-failed"],
            "--kinds: `encoder-failed`: needs `[drive] safe = true`",
        ),
        (
            &["--horizon", "0s"],
            "--horizon 0s: must be longer than zero and at most 86400 s",
        ),
        (
            &["--horizon", "1000000h"],
            "--horizon 1000000h: must be longer than zero and at most",
        ),
        (
            &["--every", "100s"],
            "--every 100s: no instant of the grid falls within the window",
        ),
        (
            &["--faults", "triples"],
            "--faults triples: only `single` is there yet",
        ),
        (
            &["--jobs", "0"],
            "--jobs: 0: give at least one worker thread",
        ),
    ];
    for (args, want) in cases {
        let err = fails(asi_lift().arg("explore").arg("demo").args(args));
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(err.len() < 400, "{args:?}: {err}");
    }
    let err = fails(asi_lift().args(["explore", "demo", "--shard", "3/2"]));
    assert!(err.contains("--shard"), "{err}");
    assert!(err.contains("numbered from 1"), "{err}");
}

/// `explore` writes its lines to `--out` and its sheet to standard error; `explore summarize`
/// merges the shards' files into the whole's sheet; an existing `--out` is kept.
#[test]
fn explore_shards_merge_into_the_whole_sheet() {
    let d = temp();
    let run = |out: &Path, shard: &str| {
        let status = asi_lift()
            .args([
                "explore",
                "demo",
                "--every",
                "500ms",
                "--window",
                "15s..15.5s",
            ])
            .args(["--kinds", "stop,crank", "--horizon", "3s", "--shard", shard])
            .arg("--out")
            .arg(out)
            .arg("--svg")
            .arg(out.with_extension("svg"))
            .output()
            .expect("asi-lift runs");
        assert!(status.status.success(), "{status:?}");
        String::from_utf8_lossy(&status.stderr).into_owned()
    };
    let whole = d.path().join("whole.jsonl");
    let sheet = run(&whole, "1/1");
    assert!(
        sheet.starts_with("exploration of `demo`: 4 of 4 forks\n"),
        "{sheet}"
    );
    let (a, b) = (d.path().join("a.jsonl"), d.path().join("b.jsonl"));
    run(&a, "1/2");
    run(&b, "2/2");
    let summary = |files: &[&Path]| {
        let out = asi_lift()
            .args(["explore", "summarize"])
            .args(files)
            .output()
            .expect("asi-lift runs");
        assert!(out.status.success(), "{out:?}");
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    assert_eq!(summary(&[&b, &a]), summary(&[&whole]));
    // The shards' picture is the whole's, byte for byte.
    let merged_svg = d.path().join("merged.svg");
    let out = asi_lift()
        .args(["explore", "summarize"])
        .args([&b, &a])
        .arg("--svg")
        .arg(&merged_svg)
        .output()
        .expect("asi-lift runs");
    assert!(out.status.success(), "{out:?}");
    let read = |p: &Path| std::fs::read_to_string(p).expect("an SVG");
    let svg = read(&merged_svg);
    assert_eq!(svg, read(&whole.with_extension("svg")));
    assert!(
        svg.starts_with("<svg ") && svg.contains("stop at 15 s: "),
        "{svg}"
    );
    assert_eq!(summary(&[&whole]), sheet);
    let err = fails(
        asi_lift()
            .args([
                "explore", "demo", "--every", "1s", "--window", "15s..15s", "--out",
            ])
            .arg(&whole),
    );
    assert!(
        err.contains("exists; pass --force to overwrite it"),
        "{err}"
    );
}

#[test]
fn numbers_out_of_range_are_named_compactly_with_the_range() {
    let d = temp();
    let file = |name: &str, text: &str| {
        let p = d.path().join(name);
        std::fs::write(&p, text).expect("write");
        p
    };
    let noise = file("noise.toml", "[bus]\npulse_error_rate = 1e308\n");
    let start = file("start.toml", "[lift]\nstart_mm = 1e308\n");
    let csv = file("v.csv", "0,1\n1e-7,1e308\n");
    let flat = file("flat.csv", "0,0\n1e-7,0\n");
    let cases: [(Vec<&std::ffi::OsStr>, &str); 4] = [
        (
            vec!["decode".as_ref(), "--nominal".as_ref(), "1e308".as_ref(), flat.as_ref()],
            "1e308 is out of range: expected a positive number of volts up to 3.4028235e38",
        ),
        (
            vec!["decode".as_ref(), csv.as_ref()],
            "line 2: voltage 1e308 V is out of range: expected a finite voltage within ±3.4028235e38 V",
        ),
        (
            vec!["run".as_ref(), noise.as_ref()],
            "bus.pulse_error_rate: 1e308: a pulse error rate is a probability, 0..=1",
        ),
        (
            vec!["run".as_ref(), start.as_ref()],
            "lift.start_mm: 1e308 mm lies outside the shaft",
        ),
    ];
    for (args, want) in cases {
        let err = fails(asi_lift().args(&args));
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(err.len() < 300, "{args:?}: {err}");
    }
}

#[test]
fn a_campaign_never_writes_over_its_profile() {
    let d = temp();
    let profile = d.path().join("p.toml");
    let text = "base = \"smoke\"\n";
    std::fs::write(&profile, text).expect("write");
    let link = d.path().join("hard.toml");
    std::fs::hard_link(&profile, &link).expect("hard link");
    let dotted = d.path().join(".").join("p.toml");
    for out in [&profile, &dotted, &link] {
        let err = fails(
            asi_lift()
                .args(["campaign", "--runs", "1", "--force", "--profile"])
                .arg(&profile)
                .arg("--out")
                .arg(out)
                .arg("--failures")
                .arg(d.path().join("f")),
        );
        assert!(err.contains("--profile") && err.contains("--out"), "{err}");
        assert_eq!(std::fs::read_to_string(&profile).expect("kept"), text);
    }
}

#[test]
fn a_campaign_whose_reader_goes_ends_quietly() {
    let d = temp();
    let (first, out) = head_1(
        asi_lift()
            .args([
                "campaign",
                "--runs",
                "3",
                "--jobs",
                "1",
                "--profile",
                "smoke",
            ])
            .arg("--failures")
            .arg(d.path().join("failures")),
    );
    assert!(first.starts_with("{\"index\":0"), "{first}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{:?}: {err}", out.status);
    assert!(
        !err.contains("Broken pipe") && !err.contains("panicked"),
        "{err}"
    );
}

#[test]
fn serve_names_its_bad_arguments_and_a_busy_port() {
    let err = fails(asi_lift().args(["serve", "--speed", "0"]));
    assert!(err.contains("--speed 0") && err.contains("max"), "{err}");
    // A factor whose wall times do not fit a `Duration` is refused, not a panic.
    let err = fails(asi_lift().args([
        "serve",
        "--speed",
        "1e-30",
        "--listen",
        "127.0.0.1:0",
        "--until",
        "1s",
    ]));
    assert!(
        err.contains("--speed 1e-30") && !err.contains("panicked"),
        "{err}"
    );
    let err = fails(asi_lift().args(["serve", "--listen", "localhost"]));
    assert!(err.contains("--listen localhost"), "{err}");
    let err = fails(asi_lift().args(["serve", "--ttk4145", "--controller", "builtin"]));
    assert!(err.contains("--ttk4145"), "{err}");
    let err = fails(asi_lift().args(["serve", "--step", "0ms", "--controller", "external"]));
    assert!(err.contains("--step"), "{err}");
    let err = fails(asi_lift().args(["serve", "--allow-host", "lab-pc"]));
    assert!(
        err.contains("--allow-host") && err.contains("--http"),
        "{err}"
    );
    let err = fails(asi_lift().args(["serve", "--http", "--allow-host", "a/b"]));
    assert!(err.contains("--allow-host a/b"), "{err}");
    let err = fails(asi_lift().args(["serve", "--trace", "-"]));
    assert!(err.contains("--trace"), "{err}");
    let err = fails(asi_lift().args(["serve", "--http", "localhost"]));
    assert!(
        err.contains("--http localhost") && err.contains("127.0.0.1:8080"),
        "{err}"
    );
    // A scenario after an optional-valued flag is read as its address: the error says so.
    let err = fails(asi_lift().args(["serve", "--http", "fifo"]));
    assert!(
        err.contains("--http fifo") && err.contains("`fifo` is a scenario: put it before --http"),
        "{err}"
    );
    let err = fails(asi_lift().args(["serve", "--ttk4145", "demo"]));
    assert!(err.contains("put it before --ttk4145"), "{err}");
    // A port already taken is named.
    let taken = std::net::TcpListener::bind("127.0.0.1:0").expect("a port");
    let addr = taken.local_addr().expect("its address").to_string();
    let err = fails(asi_lift().args(["serve", "--listen", &addr]));
    assert!(err.contains(&format!("cannot listen on {addr}")), "{err}");
    let err = fails(asi_lift().args(["serve", "--listen", "127.0.0.1:0", "--http", &addr]));
    assert!(err.contains(&format!("cannot listen on {addr}")), "{err}");
}

/// `asi-lift serve --speed max --until 3s` on the demo with `extra` arguments: its standard
/// error and its JSON report.
fn serve_3s(extra: &[&str]) -> (String, serde_json::Value) {
    let mut args = vec!["--speed", "max", "--until", "3s"];
    args.extend_from_slice(extra);
    serve_3s_at(&args)
}

/// A live run with `args` and no clients; its standard error and its JSON report.
fn serve_3s_at(args: &[&str]) -> (String, serde_json::Value) {
    let d = temp();
    let report = d.path().join("r.json");
    let out = asi_lift()
        .arg("serve")
        .args(["--listen", "127.0.0.1:0"])
        .args(args)
        .args(["--format", "json", "--report"])
        .arg(&report)
        .output()
        .expect("asi-lift runs");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{err}");
    let text = std::fs::read_to_string(&report).expect("the report");
    (err, serde_json::from_str(&text).expect("JSON"))
}

/// Without clients a live run at `max` is the batch run: `asi-lift run --until 3s` gives the
/// same report but `live`.
fn assert_the_batch_run(mut live: serde_json::Value) {
    let run = asi_lift()
        .args(["run", "--until", "3s", "--format", "json"])
        .output()
        .expect("asi-lift runs");
    let mut batch: serde_json::Value = serde_json::from_slice(&run.stdout).expect("JSON");
    live.as_object_mut().expect("an object").remove("live");
    batch.as_object_mut().expect("an object").remove("live");
    assert_eq!(live, batch);
}

/// `serve` shows the log as the run goes on (on standard error, with the status line), as
/// `run` prints it; `--quiet` keeps only the status.
#[test]
fn serve_shows_the_log_as_it_happens_unless_quiet() {
    let (err, _) = serve_3s(&[]);
    let line = "controller  initialisation: running down to find floor 1";
    assert!(err.contains(line), "{err}");
    assert!(err.contains("     0.160 s  controller"), "{err}");
    let (err, _) = serve_3s(&["--quiet"]);
    assert!(!err.contains(line), "{err}");
}

/// An outside controller at a speed factor above 1 is warned that its reactions come late.
#[test]
fn serve_warns_an_outside_controller_faster_than_real_time() {
    let (err, _) = serve_3s_at(&["--controller", "external", "--speed", "2", "--until", "1s"]);
    assert!(err.contains("warning: --speed 2"), "{err}");
    let (err, _) = serve_3s_at(&["--controller", "external", "--speed", "1", "--until", "1s"]);
    assert!(!err.contains("warning: --speed"), "{err}");
}

#[test]
fn serve_with_the_live_view_gives_the_same_run_as_without() {
    let (err, live) = serve_3s(&["--http", "127.0.0.1:0", "--allow-host", "lab-pc"]);
    assert!(err.contains("live view on http://127.0.0.1:"), "{err}");
    // Watching does not change the run.
    assert_the_batch_run(live);
}

/// A WebSocket text frame as a browser sends it (masked; `text` shorter than 126 bytes).
fn ws_text_frame(text: &str) -> Vec<u8> {
    let mask = [0x5a, 0x17, 0xc3, 0x2e];
    let mut f = vec![0x81, 0x80 | u8::try_from(text.len()).expect("a short text")];
    f.extend_from_slice(&mask);
    f.extend(text.bytes().enumerate().map(|(i, b)| b ^ mask[i % 4]));
    f
}

/// The live view's page restarts a run that writes a trace: the trace and the report are of
/// the run since the restart, the batch run's; the log (on standard error) says so.
#[test]
fn a_restart_from_the_page_leaves_the_trace_and_the_report_of_the_last_run() {
    use std::io::{Read, Write};
    let d = temp();
    let (trace, report) = (d.path().join("t.jsonl"), d.path().join("r.json"));
    let mut child = asi_lift()
        .args(["serve", "--listen", "127.0.0.1:0", "--http", "127.0.0.1:0"])
        .args(["--until", "3s", "--format", "json", "--report"])
        .arg(&report)
        .arg("--trace")
        .arg(&trace)
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .expect("asi-lift starts");
    let mut err = BufReader::new(child.stderr.take().expect("its standard error"));
    let mut seen = String::new();
    let addr = loop {
        let mut line = String::new();
        assert!(err.read_line(&mut line).expect("a line") > 0, "{seen}");
        seen.push_str(&line);
        if let Some(rest) = line.trim().strip_prefix("asi-lift: live view on http://") {
            break rest.trim_end_matches('/').to_owned();
        }
    };
    let rest = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = err.read_to_string(&mut text);
        text
    });
    let mut ws = std::net::TcpStream::connect(&addr).expect("the live view");
    let upgrade = format!(
        "GET /ws HTTP/1.1\r\nHost: {addr}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
    );
    ws.write_all(upgrade.as_bytes()).expect("the upgrade");
    let mut head = [0u8; 12];
    ws.read_exact(&mut head).expect("an answer");
    assert_eq!(&head, b"HTTP/1.1 101");
    // The snapshots are read and dropped, so that the server never waits to send one.
    let mut drain = ws.try_clone().expect("the socket");
    std::thread::spawn(move || std::io::copy(&mut drain, &mut std::io::sink()));
    // 0.7 s of the first run at speed 1, then the restart, then the rest at max.
    std::thread::sleep(std::time::Duration::from_millis(700));
    for command in [r#"{"restart":true}"#, r#"{"speed":"max"}"#] {
        let text = format!(r#"{{"id":1,"command":{command}}}"#);
        ws.write_all(&ws_text_frame(&text)).expect("a command");
    }
    let status = child.wait().expect("asi-lift ends");
    let err = rest.join().expect("its standard error");
    assert!(status.success(), "{err}");
    assert!(err.contains("restarted by the page"), "{err}");
    assert!(err.contains("speed max (was 1), set by the page"), "{err}");
    let batch_trace = d.path().join("batch.jsonl");
    let run = asi_lift()
        .args(["run", "--until", "3s", "--format", "json", "--trace"])
        .arg(&batch_trace)
        .output()
        .expect("asi-lift runs");
    assert!(run.status.success());
    let (t, b) = (
        std::fs::read(&trace).expect("the trace"),
        std::fs::read(&batch_trace).expect("the batch run's trace"),
    );
    assert!(
        t == b,
        "the traces differ: {} and {} bytes",
        t.len(),
        b.len()
    );
    let text = std::fs::read_to_string(&report).expect("the report");
    let mut live: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(live["live"]["speed"], "max");
    let mut batch: serde_json::Value = serde_json::from_slice(&run.stdout).expect("JSON");
    live.as_object_mut().expect("an object").remove("live");
    batch.as_object_mut().expect("an object").remove("live");
    assert_eq!(live, batch);
}

#[test]
fn serve_runs_free_to_its_end_and_writes_the_report_with_the_live_figures() {
    let (err, json) = serve_3s(&[]);
    assert!(err.contains("Modbus TCP gateway on 127.0.0.1:"), "{err}");
    assert_eq!(json["simulated_s"], 3.0);
    assert_eq!(json["live"]["controller"], "builtin");
    assert_eq!(json["live"]["speed"], "max");
    assert_the_batch_run(json);
}

#[test]
fn ctrl_c_ends_a_live_run_cleanly_with_its_report() {
    let d = temp();
    let report = d.path().join("r.txt");
    let mut child = asi_lift()
        .args(["serve", "--listen", "127.0.0.1:0", "--report"])
        .arg(&report)
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .expect("asi-lift starts");
    let mut err = BufReader::new(child.stderr.take().expect("its standard error"));
    let mut line = String::new();
    err.read_line(&mut line).expect("the first line");
    assert!(line.contains("Modbus TCP gateway on"), "{line}");
    // Let it run a moment, then Ctrl-C (SIGINT), as a user at the terminal does.
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(kill.success());
    let status = child.wait().expect("asi-lift ends");
    assert!(status.success(), "{status:?}");
    let text = std::fs::read_to_string(&report).expect("the report is written");
    assert!(
        text.contains("stopped by the operator (Ctrl-C or a termination signal)"),
        "{text}"
    );
    assert!(
        text.contains("live               builtin controller at speed 1"),
        "{text}"
    );
}

/// Sends `signal` (`INT`, `TERM`, `HUP`) to `child`, as a terminal, `kill` or docker does.
fn send(child: &std::process::Child, signal: &str) {
    let kill = Command::new("kill")
        .arg(format!("-{signal}"))
        .arg(child.id().to_string())
        .status()
        .expect("kill runs");
    assert!(kill.success());
}

#[test]
fn a_signal_ends_a_run_with_its_status_and_leaves_no_temporary_file() {
    let d = temp();
    let sc = d.path().join("long.toml");
    std::fs::write(&sc, "duration = \"1h\"\n").expect("write");
    // A file the run would replace: it keeps what it had.
    let kept = d.path().join("t.jsonl");
    std::fs::write(&kept, "mine\n").expect("write");
    for (signal, status) in [("INT", 130), ("TERM", 143), ("HUP", 129)] {
        let mut child = asi_lift()
            .arg("run")
            .arg(&sc)
            .arg("--force")
            .arg("--report")
            .arg(d.path().join("r.txt"))
            .arg("--trace")
            .arg(&kept)
            .arg("--vcd")
            .arg(d.path().join("w.vcd"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("asi-lift starts");
        // The temporary files are made before the simulation: wait for them, and a moment
        // of simulation with them growing.
        while !files_in(d.path()).iter().any(|f| f.ends_with(".part")) {
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        std::thread::sleep(std::time::Duration::from_millis(300));
        send(&child, signal);
        let got = child.wait().expect("asi-lift ends");
        assert_eq!(got.code(), Some(status), "{signal}: {got:?}");
        assert_eq!(files_in(d.path()), ["long.toml", "t.jsonl"], "{signal}");
        assert_eq!(std::fs::read_to_string(&kept).expect("kept"), "mine\n");
    }
}

#[test]
fn sigterm_and_sighup_end_a_live_run_with_its_report_as_ctrl_c_does() {
    for signal in ["TERM", "HUP"] {
        let d = temp();
        let report = d.path().join("r.txt");
        let mut child = asi_lift()
            .args(["serve", "--listen", "127.0.0.1:0", "--report"])
            .arg(&report)
            .stderr(Stdio::piped())
            .stdout(Stdio::null())
            .spawn()
            .expect("asi-lift starts");
        let mut err = BufReader::new(child.stderr.take().expect("its standard error"));
        let mut line = String::new();
        err.read_line(&mut line).expect("the first line");
        assert!(line.contains("Modbus TCP gateway on"), "{line}");
        std::thread::sleep(std::time::Duration::from_millis(500));
        send(&child, signal);
        let status = child.wait().expect("asi-lift ends");
        assert!(status.success(), "{signal}: {status:?}");
        let text = std::fs::read_to_string(&report).expect("the report is written");
        assert!(text.contains("stopped by the operator"), "{signal}: {text}");
        assert_eq!(files_in(d.path()), ["r.txt"], "{signal}");
    }
}

/// The command in this process: [`asi_lift::run`] on parsed arguments, and the campaign's
/// files.
mod command {
    use asi_lift::cmd::campaign::{summarize_files as campaign_summary, write_reproducer};
    use asi_lift::cmd::EXIT_VIOLATIONS;
    use asi_lift::{run, Cli};
    use clap::Parser;
    use rig::campaign::summary::summarize;
    use rig::Scenario;
    use std::path::PathBuf;

    /// Each command's help is its own: the first words of every subcommand's description,
    /// as `asi-lift --help` lists them.
    #[test]
    fn every_command_has_its_own_description() {
        use clap::CommandFactory;
        let cli = Cli::command();
        let about = |name: &str| {
            cli.find_subcommand(name)
                .and_then(|c| c.get_about())
                .map(|a| a.to_string())
                .unwrap_or_else(|| panic!("{name} has no description"))
        };
        for (name, start) in [
            ("run", "Run the lab lift"),
            ("stand", "The teaching stand of the SafeMOTION thesis"),
            ("campaign", "Run many random valid scenarios"),
            ("serve", ""),
            ("timing", "Timing analysis"),
        ] {
            let a = about(name);
            assert!(a.starts_with(start), "{name}: {a}");
        }
        assert!(!about("stand").contains("Campaigns"));
    }

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
                    // The command works from where the campaign was started.
                    let command = format!("# reproduce: asi-lift run {failures}/{name}\n");
                    assert!(text.contains(&command), "{text}");
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
        // A name taken by something endless is compared, not read whole.
        std::os::unix::fs::symlink("/dev/zero", dir.join("run-000002-cd.toml")).expect("link");
        assert_eq!(
            write_reproducer(&dir, "run-000002-cd.toml", "three"),
            Ok(dir.join("run-000002-cd-2.toml"))
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

    /// With the safe drive the plot gains a panel of its functions: a row for each the run
    /// requested (SOS at the open door here), its trip, and none without the safe drive.
    #[test]
    fn the_plot_of_a_run_with_the_safe_drive_shows_its_functions() {
        let dir = temp("plot-drive");
        let path = |n: &str| dir.join(n).to_string_lossy().to_string();
        let (svg, report) = (path("drive.svg"), path("drive.json"));
        let args = [
            "safe-drive-runaway",
            "--until",
            "35s",
            "--plot",
            &svg,
            "--report",
            &report,
        ];
        assert_eq!(run_cli(&args), Ok(0));
        let svg = std::fs::read_to_string(&svg).expect("output");
        for label in [
            "Safe drive: functions requested and safe states reached",
            "\nSOS\n",
            "\nSDI-N\n",
            "trip: torque off (1)",
        ] {
            assert!(svg.contains(label), "no {label:?} in the plot");
        }
        // SLT, never requested, has no row.
        assert!(!svg.contains("\nSLT\n"));
        let plain = path("plain.svg");
        let args = [
            "demo", "--until", "5s", "--plot", &plain, "--report", &report, "--force",
        ];
        assert_eq!(run_cli(&args), Ok(0));
        let plain = std::fs::read_to_string(&plain).expect("output");
        assert!(!plain.contains("Safe drive"));
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
        // Standard output takes one stream: a report asked there too is refused (without
        // --report, the summary goes to standard error).
        let e =
            run_cli(&["--until", "1s", "--plot", "-", "--report", "-"]).expect_err("two on stdout");
        assert!(e.contains("--plot") && e.contains("--report"), "{e}");
        assert_eq!(
            run_cli(&["--until", "1s", "--plot", &p, "--report", &r, "--force"]),
            Ok(0)
        );
        let svg = std::fs::read_to_string(&plot).unwrap_or_default();
        assert!(svg.starts_with("<svg"), "{svg}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// `--plot x.png` draws the same picture as PNG: a real PNG (it decodes) of the plot's
    /// size, its text drawn (the title's rows are not blank), and the same bytes for the same
    /// run, whatever fonts the machine has.
    #[test]
    fn a_png_plot_decodes_to_the_plots_size_and_is_the_same_for_the_same_run() {
        let dir = temp("plot-png");
        let path = |n: &str| dir.join(n).to_string_lossy().to_string();
        let (a, b) = (path("a.png"), path("b.PNG"));
        for png in [&a, &b] {
            let args = ["--until", "2s", "--plot", png, "--report", "/dev/null"];
            assert_eq!(run_cli(&args), Ok(0));
        }
        let bytes = std::fs::read(&a).expect("the PNG");
        assert!(
            bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
            "{:?}",
            &bytes[..bytes.len().min(16)]
        );
        assert!(
            bytes == std::fs::read(&b).expect("the PNG"),
            "two runs of one scenario, two PNGs"
        );
        let mut reader = png::Decoder::new(std::io::Cursor::new(&bytes))
            .read_info()
            .expect("the PNG's header");
        let mut rgb = vec![0; reader.output_buffer_size().expect("a size")];
        let frame = reader.next_frame(&mut rgb).expect("the PNG's pixels");
        assert_eq!((frame.width, frame.height), asi_lift::cmd::picture::SIZE);
        assert_eq!(
            (frame.color_type, frame.bit_depth),
            (png::ColorType::Rgb, png::BitDepth::Eight)
        );
        // The title, in black, is all that the top 30 rows hold.
        let title = &rgb[..frame.line_size * 30];
        assert!(title.iter().any(|&v| v < 64), "no title in the PNG");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// The SVG is the same, byte for byte, as before the plot could be a PNG: plotters lays
    /// it out by its own estimate of the text's size, not by the PNG's font (src/cmd/plot.rs).
    /// A deliberate change of the drawing changes the length and the digest here.
    #[test]
    fn the_svg_plot_is_laid_out_as_before_the_png() {
        let dir = temp("plot-svg-layout");
        let svg = dir.join("one.svg").to_string_lossy().to_string();
        let args = ["--until", "1s", "--plot", &svg, "--report", "/dev/null"];
        assert_eq!(run_cli(&args), Ok(0));
        let bytes = std::fs::read(&svg).expect("the SVG");
        // FNV-1a, 64 bits.
        let digest = bytes.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, &b| {
            (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        });
        assert_eq!((bytes.len(), digest), (79_792, 0x2e8d_7805_770c_09ce));
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

/// The outputs' checks ([`asi_lift::cmd::output`]), with files made between the steps.
mod output {
    use asi_lift::cmd::output::Outputs;
    use std::path::Path;

    fn dir() -> tempfile::TempDir {
        tempfile::tempdir().expect("a temporary directory")
    }

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .expect("list")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn one_file_through_two_spellings_is_refused() {
        let d = dir();
        let a = d.path().join("a.out");
        let dotted = d.path().join(".").join("a.out");
        let mut o = Outputs::new(false);
        o.add("--vcd", &a).expect("first");
        let e = o.add("--csv", &dotted).err().expect("the same file");
        assert!(e.contains("same file"), "{e}");
        // Nothing is written: the temporary file goes with the refused command.
        drop(o);
        assert!(names(d.path()).is_empty(), "{:?}", names(d.path()));
    }

    #[test]
    fn links_name_the_file_they_point_at() {
        let d = dir();
        let a = d.path().join("a.json");
        std::fs::write(&a, "mine").expect("write");
        let sym = d.path().join("sym.json");
        std::os::unix::fs::symlink(&a, &sym).expect("symlink");
        let hard = d.path().join("hard.json");
        std::fs::hard_link(&a, &hard).expect("hard link");
        let mut o = Outputs::new(true);
        o.add("--report", &a).expect("first");
        for other in [&sym, &hard] {
            let e = o.add("--trace", other).err().expect("the same file");
            assert!(e.contains("same file"), "{e}");
        }
        let mut o = Outputs::new(false);
        o.input("the scenario", &sym).expect("input");
        let e = o.add("--report", &hard).err().expect("the input");
        assert!(e.contains("same file"), "{e}");
    }

    #[test]
    fn an_existing_file_is_refused_without_force_before_anything_is_written() {
        let d = dir();
        let a = d.path().join("r.json");
        std::fs::write(&a, "mine").expect("write");
        let e = Outputs::new(false)
            .add("--report", &a)
            .err()
            .expect("exists");
        assert!(e.contains("--force"), "{e}");
        assert_eq!(std::fs::read_to_string(&a).expect("read"), "mine");
    }

    #[test]
    fn a_missing_directory_is_reported_when_the_output_is_added() {
        let d = dir();
        let e = Outputs::new(false)
            .add("--report", &d.path().join("no/such/r.json"))
            .err()
            .expect("no directory");
        assert!(e.contains("no/such"), "{e}");
    }

    #[test]
    fn files_appear_only_at_the_commit_and_replace_through_a_link_with_force() {
        let d = dir();
        let a = d.path().join("a.txt");
        let mut o = Outputs::new(false);
        let s = o.add("--report", &a).expect("add");
        o.write_all(&s, "first").expect("write");
        assert!(!a.exists(), "not before the commit");
        o.commit().expect("commit");
        assert_eq!(std::fs::read_to_string(&a).expect("read"), "first");
        // With --force through a symbolic link: the link stays, the file it names changes.
        let sym = d.path().join("sym.txt");
        std::os::unix::fs::symlink(&a, &sym).expect("symlink");
        let mut o = Outputs::new(true);
        let s = o.add("--report", &sym).expect("add");
        o.write_all(&s, "second").expect("write");
        o.commit().expect("commit");
        assert!(std::fs::symlink_metadata(&sym)
            .expect("meta")
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read_to_string(&a).expect("read"), "second");
        assert_eq!(names(d.path()), ["a.txt", "sym.txt"]);
    }

    #[test]
    fn a_device_is_written_directly_and_a_directory_refused() {
        let mut o = Outputs::new(false);
        let s = o.add("--trace", Path::new("/dev/null")).expect("/dev/null");
        o.write_all(&s, "gone").expect("write");
        o.commit().expect("commit");
        let d = dir();
        let e = Outputs::new(true)
            .add("--report", d.path())
            .err()
            .expect("dir");
        assert!(e.contains("directory"), "{e}");
    }

    #[test]
    fn a_file_made_meanwhile_is_kept_without_force() {
        let d = dir();
        let a = d.path().join("a.txt");
        let mut o = Outputs::new(false);
        let s = o.add("--report", &a).expect("add");
        o.write_all(&s, "ours").expect("write");
        std::fs::write(&a, "theirs").expect("write");
        let e = o.commit().expect_err("kept");
        assert!(e.contains("a.txt"), "{e}");
        assert_eq!(std::fs::read_to_string(&a).expect("read"), "theirs");
        assert_eq!(names(d.path()), ["a.txt"]);
    }
}

/// The plot's sampling ([`asi_lift::cmd::plot`]).
mod plot {
    use asi_lift::cmd::picture::{format_of, Format};
    use asi_lift::cmd::plot::{button_floor, sample_step, MIN_STEP};
    use asi_phy::SimDuration;

    #[test]
    fn the_sampling_step_keeps_long_runs_small() {
        assert_eq!(sample_step(SimDuration::from_secs(80)), MIN_STEP);
        assert_eq!(sample_step(SimDuration::from_secs(100)), MIN_STEP);
        assert_eq!(
            sample_step(SimDuration::from_secs(600)),
            SimDuration::from_millis(120)
        );
    }

    #[test]
    fn a_button_names_its_floor() {
        assert_eq!(button_floor("cabin:3"), Some(3));
        assert_eq!(button_floor("hall-down:4"), Some(4));
        assert_eq!(button_floor("cabin"), None);
    }

    /// The plot's format is its file's extension, in any case; no extension is SVG (`-`,
    /// `/dev/null`); another one, or a bare dot, is refused naming both formats.
    #[test]
    fn the_plots_format_is_its_files_extension() {
        let of = |p: &str| format_of(std::path::Path::new(p));
        for svg in ["run.svg", "RUN.SVG", "-", "/dev/null", "plots/run"] {
            assert_eq!(of(svg), Ok(Format::Svg), "{svg}");
        }
        for png in ["run.png", "run.Png", "docs/demo-plot.png"] {
            assert_eq!(of(png), Ok(Format::Png), "{png}");
        }
        for other in ["run.jpg", "run.", "run.png.gz", "run.svgz"] {
            let e = of(other).expect_err(other);
            assert!(
                e.contains("--plot")
                    && e.contains(other)
                    && e.contains(".svg")
                    && e.contains(".png"),
                "{e}"
            );
        }
    }
}

/// The warnings of `run` before a run ([`asi_lift::cmd::run`]).
mod run {
    use asi_lift::cmd::run::{csv_size_warning, vcd_size_warning};
    use asi_phy::SimTime;

    const MIN: u64 = 60;

    fn secs(s: u64) -> SimTime {
        SimTime::from_millis(s * 1000)
    }

    #[test]
    fn a_long_vcd_is_warned_of_naming_the_option_that_bounds_it() {
        let ten_ms = (SimTime::ZERO, SimTime::from_millis(10));
        // 12 minutes of pulse wire and the rest: about 2.9 GB.
        let w = vcd_size_warning(secs(12 * MIN), None, ten_ms).expect("12 minutes");
        assert!(w.contains("about 2.9 GB"), "{w}");
        assert!(w.contains("--pulse-window"), "{w}");
        // A minute, or 12 minutes with a bounded pulse wire, stays below 1 GB.
        assert_eq!(vcd_size_warning(secs(MIN), None, ten_ms), None);
        let bounded = Some((secs(60), secs(120)));
        assert_eq!(vcd_size_warning(secs(12 * MIN), bounded, ten_ms), None);
        // A pulse window past the end of the run counts for nothing.
        let late = Some((secs(13 * MIN), secs(20 * MIN)));
        assert_eq!(vcd_size_warning(secs(12 * MIN), late, ten_ms), None);
        // 10 s of line voltage is the bulk of a short run's VCD.
        let w = vcd_size_warning(secs(20), None, (SimTime::ZERO, secs(10))).expect("voltage");
        assert!(w.contains("--waveform-window"), "{w}");
    }

    #[test]
    fn a_large_csv_is_warned_of_naming_the_window() {
        // 10 s of voltage at 10 MS/s, 22-character lines: about 2.2 GB.
        let w = csv_size_warning(secs(20), (SimTime::ZERO, secs(10))).expect("10 s");
        assert!(w.contains("about 2.2 GB"), "{w}");
        assert!(w.contains("--waveform-window"), "{w}");
        // The default 10 ms, or a window mostly after the run's end, stays below 1 GB.
        let ten_ms = (SimTime::ZERO, SimTime::from_millis(10));
        assert_eq!(csv_size_warning(secs(12 * MIN), ten_ms), None);
        assert_eq!(csv_size_warning(secs(20), (secs(19), secs(100))), None);
    }
}

/// `asi-lift stand ss1` (the SafeMOTION thesis, guide A.4): the page's states with their times, the
/// stopwatch, the torque; twice the same output; exit code 0 (the stand only shows).
#[test]
fn stand_ss1_prints_what_the_student_sees() {
    let run = || asi_lift().args(["stand", "ss1"]).output().expect("runs");
    let out = run();
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8(out.stdout.clone()).expect("UTF-8");
    for line in [
        "    0.000 s  Neaktivní (green)",
        "    2.000 s  Del+Decel (orange)",
        "   17.000 s  NOK (red)",
        "   22.000 s  Neaktivní (green)",
        "stopwatch: 15000 ms",
    ] {
        assert!(
            text.lines().any(|l| l == line),
            "no line {line:?} in\n{text}"
        );
    }
    assert!(
        text.lines()
            .any(|l| l.starts_with("   17.000 s  safety")
                && l.ends_with("torque off, the axis coasts")),
        "{text}"
    );
    assert_eq!(run().stdout, out.stdout, "the same output twice");
}

/// `asi-lift stand` lists the nine guides; `--format json` is a report; a bad file is named
/// by file, line and field; an unknown name lists the built-in ones.
#[test]
fn stand_lists_reports_json_and_names_errors() {
    let out = asi_lift().arg("stand").output().expect("runs");
    let text = String::from_utf8_lossy(&out.stdout);
    let names: Vec<&str> = text
        .lines()
        .take_while(|l| !l.is_empty())
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert_eq!(
        names,
        ["sto", "sos", "ss1", "ss2", "sls1", "sls2", "sli", "sdi-p", "sdi-n"]
    );

    let out = asi_lift()
        .args(["stand", "sli", "--format", "json"])
        .output()
        .expect("runs");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["function"], "SLI");
    assert_eq!(v["hmi"][1]["text"], "OK");
    assert_eq!(v["hmi"][2]["text"], "NOK");
    assert_eq!(v["final_state"], "Ready");

    let d = temp();
    let f = d.path().join("bad.toml");
    std::fs::write(
        &f,
        "function = \"ss1\"\nduration = \"10s\"\n[[event]]\nat = \"1s\"\ncurtain = \"wave\"\n",
    )
    .expect("write");
    let err = fails(asi_lift().arg("stand").arg(&f));
    assert!(
        err.contains("bad.toml:5:11: event[1].curtain: unknown curtain action"),
        "{err}"
    );
    let err = fails(asi_lift().args(["stand", "nonesuch"]));
    assert!(err.contains("there are sto, sos, ss1"), "{err}");
    let err = fails(asi_lift().args(["stand", "show", "nonesuch"]));
    assert!(err.contains("there are sto, sos, ss1"), "{err}");
}

/// `asi-lift stand NAME --plot` draws the stand's run as SVG or PNG, the same bytes every
/// time, next to the report it prints; another extension is refused before the run.
#[test]
fn stand_plots_as_svg_or_png() {
    let d = temp();
    for (name, magic) in [
        ("ss1.svg", &b"<svg"[..]),
        ("ss1.png", &b"\x89PNG\r\n\x1a\n"[..]),
    ] {
        let file = d.path().join(name);
        let out = asi_lift()
            .args(["stand", "ss1", "--plot"])
            .arg(&file)
            .output()
            .expect("runs");
        assert!(out.status.success(), "{out:?}");
        assert!(String::from_utf8_lossy(&out.stdout).contains("stopwatch: 15000 ms"));
        let first = std::fs::read(&file).expect("the plot");
        assert!(first.starts_with(magic), "{name}");
        std::fs::remove_file(&file).expect("remove");
        let again = asi_lift()
            .args(["stand", "ss1", "--plot"])
            .arg(&file)
            .output()
            .expect("runs");
        assert!(again.status.success(), "{again:?}");
        assert_eq!(std::fs::read(&file).expect("the plot"), first, "{name}");
    }
    let svg = std::fs::read_to_string(d.path().join("ss1.svg")).expect("the SVG");
    assert!(
        svg.contains("SS1 page") && svg.contains("stopwatch: 15000 ms"),
        "{svg}"
    );
    let jpg = d.path().join("ss1.jpg");
    let err = fails(asi_lift().args(["stand", "ss1", "--plot"]).arg(&jpg));
    assert!(err.contains("--plot") && err.contains(".png"), "{err}");
    assert!(!jpg.exists());
}

/// `asi-lift stand show NAME` prints the built-in scenario as a file that runs as the
/// built-in one does, to copy and edit.
#[test]
fn stand_show_prints_a_file_that_runs_as_the_built_in_one() {
    let d = temp();
    let shown = asi_lift()
        .args(["stand", "show", "ss1"])
        .output()
        .expect("runs");
    assert!(shown.status.success(), "{shown:?}");
    let text = String::from_utf8(shown.stdout).expect("UTF-8");
    assert!(text.contains("function = \"ss1\""), "{text}");
    let file = d.path().join("my-guide.toml");
    std::fs::write(&file, &text).expect("write");
    let from_file = asi_lift().arg("stand").arg(&file).output().expect("runs");
    let built_in = asi_lift().args(["stand", "ss1"]).output().expect("runs");
    assert!(from_file.status.success(), "{from_file:?}");
    assert_eq!(from_file.stdout, built_in.stdout);
}

/// `asi-lift stand --report FILE` writes what it would print; a file that exists is kept
/// without `--force`, and the scenario file is never the report.
#[test]
fn stand_writes_its_report_to_a_file_and_keeps_what_exists() {
    let d = temp();
    let printed = asi_lift().args(["stand", "sos"]).output().expect("runs");
    let rep = d.path().join("sos.txt");
    let out = asi_lift()
        .args(["stand", "sos", "--report"])
        .arg(&rep)
        .output()
        .expect("runs");
    assert!(out.status.success(), "{out:?}");
    assert!(out.stdout.is_empty(), "{out:?}");
    assert_eq!(std::fs::read(&rep).expect("the report"), printed.stdout);

    std::fs::write(&rep, "mine").expect("write");
    let err = fails(asi_lift().args(["stand", "sos", "--report"]).arg(&rep));
    assert!(err.contains("--force"), "{err}");
    assert_eq!(std::fs::read_to_string(&rep).expect("kept"), "mine");
    let out = asi_lift()
        .args(["stand", "sos", "--force", "--report"])
        .arg(&rep)
        .output()
        .expect("runs");
    assert!(out.status.success(), "{out:?}");
    assert_eq!(std::fs::read(&rep).expect("the report"), printed.stdout);

    let sc = d.path().join("mine.toml");
    std::fs::write(&sc, "function = \"sos\"\nduration = \"10s\"\n").expect("write");
    let err = fails(
        asi_lift()
            .arg("stand")
            .arg(&sc)
            .arg("--force")
            .arg("--report")
            .arg(&sc),
    );
    assert!(err.contains("the scenario and --report"), "{err}");
    assert!(std::fs::read_to_string(&sc)
        .expect("kept")
        .starts_with("function"));
}

/// Every subcommand a user can type, as `asi-lift --help` lists them: named here, not read
/// from the definition, so that a subcommand lost from the command fails the tests below.
const SUBCOMMANDS: [&str; 10] = [
    "run",
    "scenarios",
    "encode",
    "decode",
    "serve",
    "timing",
    "stand",
    "campaign",
    "completions",
    "man",
];

/// The subcommands of the command's definition, for the generated files to be checked against
/// (a new one is covered without a change here).
fn defined_subcommands() -> Vec<String> {
    use clap::CommandFactory;
    let names: Vec<String> = asi_lift::Cli::command()
        .get_subcommands()
        .map(|c| c.get_name().to_owned())
        .collect();
    for name in SUBCOMMANDS {
        assert!(names.iter().any(|n| n == name), "{name} is gone");
    }
    names
}

fn stdout_of(args: &[&str]) -> String {
    let out = asi_lift().args(args).output().expect("asi-lift runs");
    assert!(out.status.success(), "{args:?}: {out:?}");
    String::from_utf8(out.stdout).expect("UTF-8")
}

/// What bash offers after `words` (the last one being completed) with `script` loaded, as
/// the shell does on Tab: the function `complete` registered for asi-lift, called with the
/// line's words.
fn bash_offers(script: &Path, words: &[&str]) -> Vec<String> {
    let driver = r#"
        source "$1" || exit 1
        shift
        f=$(complete -p asi-lift | sed -E 's/.*-F ([^ ]+).*/\1/')
        COMP_WORDS=("$@")
        COMP_CWORD=$(($# - 1))
        COMP_LINE="$*"
        COMP_POINT=${#COMP_LINE}
        "$f" asi-lift "${COMP_WORDS[COMP_CWORD]}" "${COMP_WORDS[COMP_CWORD-1]}"
        printf '%s\n' "${COMPREPLY[@]}"
    "#;
    let out = Command::new("bash")
        .args(["-c", driver, "bash"])
        .arg(script)
        .arg("asi-lift")
        .args(words)
        .output()
        .expect("bash runs");
    assert!(out.status.success(), "{words:?}: {out:?}");
    String::from_utf8(out.stdout)
        .expect("UTF-8")
        .lines()
        .map(String::from)
        .collect()
}

#[test]
fn the_bash_completion_offers_every_subcommand_and_is_valid_bash() {
    let d = temp();
    let file = d.path().join("asi-lift.bash");
    std::fs::write(&file, stdout_of(&["completions", "bash"])).expect("write");
    let check = Command::new("bash")
        .arg("-n")
        .arg(&file)
        .output()
        .expect("bash runs");
    assert!(check.status.success(), "{check:?}");

    let offered = bash_offers(&file, &[""]);
    for name in defined_subcommands() {
        assert!(offered.contains(&name), "{name} not offered: {offered:?}");
    }
    assert_eq!(bash_offers(&file, &["sc"]), ["scenarios"]);
    assert!(bash_offers(&file, &["scenarios", ""]).contains(&"show".to_owned()));
    assert!(bash_offers(&file, &["campaign", ""]).contains(&"summarize".to_owned()));
    assert!(bash_offers(&file, &["run", "--un"]).contains(&"--until".to_owned()));
    let shells = bash_offers(&file, &["completions", ""]);
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        assert!(shells.contains(&shell.to_owned()), "{shells:?}");
    }
}

#[test]
fn every_shell_has_a_completion_naming_the_command_and_an_unknown_one_is_refused() {
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let script = stdout_of(&["completions", shell]);
        assert!(script.contains("asi-lift"), "{shell}: {script}");
        assert!(script.contains("campaign"), "{shell}: no subcommands");
    }
    let err = fails(asi_lift().args(["completions", "tcsh"]));
    assert!(err.contains("invalid value 'tcsh'"), "{err}");
    assert!(
        err.contains("[possible values: bash, elvish, fish, powershell, zsh]"),
        "{err}"
    );
    let err = fails(asi_lift().arg("completions"));
    assert!(err.contains("<SHELL>"), "{err}");
}

/// The roff of a page without the quote-character definitions (`.ie`/`.el`) that
/// clap_mangen puts before the title, for every roff to read an apostrophe alike.
fn after_prelude(page: &str) -> &str {
    let start = page.find(".TH ").expect("a .TH line");
    assert!(
        page[..start]
            .lines()
            .all(|l| l.starts_with(".ie ") || l.starts_with(".el ")),
        "{}",
        &page[..start]
    );
    &page[start..]
}

#[test]
fn the_man_page_is_roff_and_names_every_subcommand() {
    let page = stdout_of(&["man"]);
    let page = after_prelude(&page);
    assert!(page.starts_with(".TH asi-lift 1 "), "{page}");
    assert!(page.contains("\n.SH NAME\n"), "{page}");
    assert!(page.contains("\n.SH SUBCOMMANDS\n"), "{page}");
    for name in defined_subcommands() {
        // roff escapes a hyphen as \-.
        let reference = format!("asi\\-lift\\-{}(1)", name.replace('-', "\\-"));
        assert!(page.contains(&reference), "no {reference} in\n{page}");
    }
}

#[test]
fn man_out_writes_a_page_per_subcommand_and_keeps_what_exists() {
    let d = temp();
    let dir = d.path().join("man1");
    let out = asi_lift()
        .args(["man", "--out"])
        .arg(&dir)
        .output()
        .expect("runs");
    assert!(out.status.success(), "{out:?}");
    assert!(out.stdout.is_empty(), "{out:?}");
    let mut expected: Vec<String> = defined_subcommands()
        .iter()
        .map(|n| format!("asi-lift-{n}.1"))
        .chain(
            [
                "asi-lift.1",
                "asi-lift-scenarios-show.1",
                "asi-lift-stand-show.1",
                "asi-lift-campaign-summarize.1",
                "asi-lift-explore-summarize.1",
            ]
            .map(String::from),
        )
        .collect();
    expected.sort();
    assert_eq!(files_in(&dir), expected);
    for f in &expected {
        let page = std::fs::read_to_string(dir.join(f)).expect("read");
        let title = f.trim_end_matches(".1");
        assert!(
            after_prelude(&page).starts_with(&format!(".TH {title} 1 ")),
            "{f}: {page}"
        );
    }
    let run_page = std::fs::read_to_string(dir.join("asi-lift-run.1")).expect("read");
    assert!(run_page.contains("\\-\\-until"), "{run_page}");

    // A page that exists is kept without --force, and no other page is written either.
    std::fs::write(dir.join("asi-lift-run.1"), "mine").expect("write");
    std::fs::remove_file(dir.join("asi-lift.1")).expect("remove");
    let err = fails(asi_lift().args(["man", "--out"]).arg(&dir));
    assert!(err.contains("asi-lift-run.1 exists; pass --force"), "{err}");
    assert_eq!(
        std::fs::read_to_string(dir.join("asi-lift-run.1")).expect("read"),
        "mine"
    );
    assert!(!dir.join("asi-lift.1").exists());
    let out = asi_lift()
        .args(["man", "--force", "--out"])
        .arg(&dir)
        .output()
        .expect("runs");
    assert!(out.status.success(), "{out:?}");
    assert_eq!(
        std::fs::read(dir.join("asi-lift-run.1")).expect("read"),
        run_page.as_bytes()
    );
    assert_eq!(files_in(&dir), expected);
}

/// `--trace -` without `--report`: the trace alone on standard output, the summary on standard
/// error (standard output is a stream, not refused as wanted twice).
#[test]
fn a_trace_on_standard_output_sends_the_summary_to_standard_error() {
    let out = asi_lift()
        .args(["run", "--until", "1s", "--trace", "-"])
        .output()
        .expect("asi-lift runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
    assert!(stderr.contains("summary after 1.000 s"), "{stderr}");
    assert!(!stdout.contains("summary"), "{stdout}");
    assert!(stdout.lines().count() > 100, "{stdout}");
    // JSON wants a file: the summary is text.
    let err = fails(asi_lift().args(["run", "--until", "1s", "--trace", "-", "--format", "json"]));
    assert!(err.contains("--report FILE"), "{err}");
}

/// A character device takes any number of writers: two outputs may both name /dev/null. A
/// FIFO would interleave them, and stays refused.
#[test]
fn two_outputs_may_share_a_device_but_not_a_fifo() {
    let out = asi_lift()
        .args([
            "run",
            "--until",
            "1s",
            "--report",
            "/dev/null",
            "--plot",
            "/dev/null",
        ])
        .output()
        .expect("asi-lift runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{:?}: {err}", out.status);
    let d = temp();
    let fifo = d.path().join("f");
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
    assert!(made.success());
    // A reader, so that opening the FIFO to write it does not wait for ever.
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read(fifo).expect("read the FIFO"))
    };
    let err = fails(
        asi_lift()
            .args(["run", "--until", "1s", "--report"])
            .arg(&fifo)
            .arg("--trace")
            .arg(&fifo),
    );
    assert!(err.contains("--report") && err.contains("--trace"), "{err}");
    assert!(reader.join().expect("the reader").is_empty());
}

/// `--plot run.jpg` is refused before the run, naming --plot, the file and the formats drawn,
/// rather than writing SVG or PNG under a name that promises another format; so is a name
/// ending in a bare dot. `.svg` (in any case) and a name without an extension are drawn as SVG.
#[test]
fn a_plot_with_another_extension_than_svg_or_png_is_refused() {
    let d = temp();
    for name in ["run.jpg", "run."] {
        let err = fails(
            asi_lift()
                .args(["run", "--until", "1s", "--plot"])
                .arg(d.path().join(name)),
        );
        assert!(
            err.contains("--plot")
                && err.contains(name)
                && err.contains(".svg")
                && err.contains(".png"),
            "{err}"
        );
    }
    assert!(files_in(d.path()).is_empty(), "{:?}", files_in(d.path()));
    let svg = d.path().join("run.SVG");
    let out = asi_lift()
        .args(["run", "--until", "1s", "--report", "/dev/null", "--plot"])
        .arg(&svg)
        .output()
        .expect("asi-lift runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).expect("the SVG");
    assert!(text.starts_with("<svg"), "{}", &text[..text.len().min(80)]);
}

/// The plot's legend counts the safety trips as the summary does: what tripped, not the
/// records of K1 opening (the overtravel scenario: 2 trips, K1 opened once).
#[test]
fn the_plot_counts_safety_trips_as_the_summary_does() {
    let d = temp();
    let svg = d.path().join("p.svg");
    let out = asi_lift()
        .args(["run", "overtravel", "--report", "/dev/null", "--plot"])
        .arg(&svg)
        .output()
        .expect("asi-lift runs");
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let line = summary
        .lines()
        .find(|l| l.trim_start().starts_with("safety trips"))
        .expect("the summary's trips");
    let n: usize = line
        .split_whitespace()
        .nth(2)
        .expect("a count")
        .parse()
        .expect("a number");
    assert!(n > 0, "{line}");
    let text = std::fs::read_to_string(&svg).expect("the SVG");
    assert!(text.contains(&format!("safety trip ({n})")), "{line}");
}

/// Counts of one take the singular, and the summary says what its two call counts count:
/// the stops that served a call, and the presses they answered (overtravel: one press, K1
/// opened once).
#[test]
fn the_summary_counts_in_words_that_fit_the_number() {
    let out = asi_lift()
        .args(["run", "overtravel"])
        .output()
        .expect("asi-lift runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for slip in ["1 presses", "1 times", "1 trips", "1 runs"] {
        assert!(!text.contains(slip), "{slip}: {text}");
    }
    assert!(
        text.contains("calls served       1 (answering 1 of 1 press of call buttons)"),
        "{text}"
    );
    assert!(text.contains("K1 opened 1 time)"), "{text}");
    assert!(
        text.contains("mean over 1 press answered, 0 unanswered"),
        "{text}"
    );
}

/// `run --until` later than the scenario's duration extends the run to it, as `serve --until`
/// does, rather than being ignored.
#[test]
fn run_until_beyond_the_scenarios_end_extends_the_run() {
    let d = temp();
    let sc = d.path().join("s.toml");
    std::fs::write(&sc, "duration = \"1s\"\n").expect("write");
    let summary = |until: &str| {
        let out = asi_lift()
            .arg("run")
            .arg(&sc)
            .args(["--until", until])
            .output()
            .expect("asi-lift runs");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let longer = summary("2s");
    assert!(longer.contains("summary after 2.000 s"), "{longer}");
    let shorter = summary("500ms");
    assert!(shorter.contains("summary after 0.500 s"), "{shorter}");
}

/// What names a file of the repository in a text the user reads.
const REPOSITORY_FILES: [&str; 3] = ["README", "docs/", ".md"];

/// The help texts stand on their own after `cargo install`, where no README or docs/ directory
/// comes along: they name the guide's chapters, not the repository's files.
#[test]
fn no_help_text_points_into_the_repository() {
    use clap::CommandFactory;
    fn walk(cmd: &mut clap::Command, path: &str) {
        let help = cmd.render_long_help().to_string();
        for file in REPOSITORY_FILES {
            assert!(!help.contains(file), "{path} --help names {file}:\n{help}");
        }
        for sub in cmd.get_subcommands_mut() {
            let name = format!("{path} {}", sub.get_name());
            walk(sub, &name);
        }
    }
    walk(&mut asi_lift::Cli::command(), "asi-lift");
}

/// Nor do the error messages that cite where a rule comes from: they name the guide's chapter
/// or the source document's section (the lift's configuration, the safety project's verifier).
#[test]
fn no_error_message_points_into_the_repository() {
    use lift_model::{LiftConfigError, VaneSensor};
    use safety::kl6904::connection::PartnerKind;
    use safety::kl6904::project::{ModuleDesc, ModuleKind};
    use safety::kl6904::signal::{GroupOutput, SignalRef};
    let mut messages: Vec<String> = [
        LiftConfigError::FloorCount { floors: 25 },
        LiftConfigError::TrackLengths {
            short_mm: 40.0,
            long_mm: 10.0,
        },
        LiftConfigError::VanesOverlap {
            sensor: VaneSensor::Right,
            lower_floor: 1,
            upper_floor: 2,
            lower_top_mm: 210.0,
            upper_bottom_mm: 190.0,
        },
    ]
    .iter()
    .map(ToString::to_string)
    .collect();
    // A safety project that breaks the rules whose messages cite the KL6904 manual: no ERR_ACK,
    // an ESTOP without Restart, an AND with one input, a Local-Out fed by a group output.
    let ms = asi_phy::SimDuration::from_millis;
    let mut project = safety::kl6904::Project::new("p", 1)
        .group("g", SignalRef::standard("ack"))
        .connection("t", "g", PartnerKind::Kl1904, 2, ms(100), &["a"])
        .module(
            ModuleDesc::new(ModuleKind::Estop, "estop", "g")
                .input("EStopIn1", SignalRef::twinsafe("t", "a")),
        )
        .module(
            ModuleDesc::new(ModuleKind::And, "and", "g")
                .input("AndIn1", SignalRef::fb("estop", "EStopOut")),
        )
        .local_output(1, "k1", "g", SignalRef::group("g", GroupOutput::FbErr));
    project.groups[0].err_ack = None;
    let errors = project.verify().expect_err("the project breaks four rules");
    messages.extend(errors.iter().map(|e| e.message.clone()));
    for cites in [
        "KL6904 manual, §3.1",
        "§4.1",
        "§4.4",
        "§2–§3",
        "asi-lift guide",
        "thesis",
    ] {
        assert!(
            messages.iter().any(|m| m.contains(cites)),
            "no message cites {cites}: {messages:#?}"
        );
    }
    for m in &messages {
        for file in REPOSITORY_FILES {
            assert!(!m.contains(file), "an error message names {file}: {m}");
        }
    }
}

/// `run --controller FILE.st`: a program that does not compile is refused before the run
/// with every error at its line and column, and nothing is written; one that compiles runs
/// as the PLC, and the JSON report names it.
#[test]
fn run_takes_a_structured_text_program_as_the_plc() {
    let d = temp();
    let bad = d.path().join("bad.st");
    std::fs::write(
        &bad,
        "PROGRAM Lift\nVAR run AT %QX7.0 : BOOL; n : INT; END_VAR\n  run := n + 1;\n  x := 3;\nEND_PROGRAM\n",
    )
    .expect("write");
    let report = d.path().join("report.json");
    let out = asi_lift()
        .args(["run", "--until", "1s", "--controller"])
        .arg(&bad)
        .arg("--report")
        .arg(&report)
        .output()
        .expect("asi-lift run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("the program is refused (2 errors)"), "{err}");
    assert!(
        err.contains("bad.st:3:10: error: a value of INT cannot be stored into BOOL"),
        "{err}"
    );
    assert!(
        err.contains("bad.st:4:3: error: no variable is named `x`"),
        "{err}"
    );
    assert!(!report.exists(), "a refused program writes nothing");

    let good = d.path().join("idle.st");
    std::fs::write(
        &good,
        "PROGRAM Lift\nVAR Restart : BOOL; t : TON; END_VAR\n  t(IN := NOT t.Q, PT := T#500ms);\n  Restart := t.Q;\nEND_PROGRAM\n",
    )
    .expect("write");
    let out = asi_lift()
        .args(["run", "--until", "2s", "--format", "json", "--controller"])
        .arg(&good)
        .output()
        .expect("asi-lift run");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(json["controller"], good.display().to_string());
    assert_eq!(json["violations"], serde_json::json!([]));
}

/// A scenario's `[controller] program` names a Structured Text file relative to the
/// scenario's own directory; `--controller` takes its place; a program that does not
/// compile is refused at the key's line; the program's file is an input no output may
/// overwrite.
#[test]
fn a_scenario_names_its_program_relative_to_itself() {
    let d = temp();
    let dir = d.path().join("lab");
    std::fs::create_dir(&dir).expect("mkdir");
    std::fs::write(
        dir.join("idle.st"),
        "PROGRAM Lift\nVAR Restart : BOOL; t : TON; END_VAR\n  t(IN := NOT t.Q, PT := T#500ms);\n  Restart := t.Q;\nEND_PROGRAM\n",
    )
    .expect("write");
    std::fs::write(dir.join("bad.st"), "PROGRAM Lift\n  x := 1;\nEND_PROGRAM\n").expect("write");
    let scenario = dir.join("sc.toml");
    std::fs::write(
        &scenario,
        "name = \"own program\"\nduration = \"2s\"\n\n[controller]\nprogram = \"idle.st\"\n",
    )
    .expect("write");
    // Run from elsewhere: the path is the scenario's, not the working directory's.
    let out = asi_lift()
        .current_dir(d.path())
        .args(["run", "--format", "json", "lab/sc.toml"])
        .output()
        .expect("asi-lift run");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(json["controller"], "lab/idle.st");

    // `--controller` takes the key's place.
    let out = asi_lift()
        .current_dir(d.path())
        .args([
            "run",
            "--format",
            "json",
            "lab/sc.toml",
            "--controller",
            "lab/bad.st",
        ])
        .output()
        .expect("asi-lift run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--controller lab/bad.st: the program is refused (1 error)"),
        "{err}"
    );

    // A wrong program named by the key: the key's place, then the program's errors.
    std::fs::write(
        &scenario,
        "name = \"own program\"\nduration = \"2s\"\n\n[controller]\nprogram = \"bad.st\"\n",
    )
    .expect("write");
    let err = fails(
        asi_lift()
            .current_dir(d.path())
            .args(["run", "lab/sc.toml"]),
    );
    assert!(
        err.contains(
            "lab/sc.toml:5:11: controller.program: lab/bad.st: the program is refused (1 error):"
        ),
        "{err}"
    );
    assert!(
        err.contains("lab/bad.st:2:3: error: no variable is named `x`"),
        "{err}"
    );

    // The program is an input: `--force` does not make it a report.
    let err = fails(asi_lift().current_dir(d.path()).args([
        "run",
        "--controller",
        "lab/idle.st",
        "--report",
        "lab/idle.st",
        "--force",
    ]));
    assert!(err.contains("the program"), "{err}");
    assert!(
        std::fs::read_to_string(dir.join("idle.st"))
            .expect("read")
            .starts_with("PROGRAM Lift"),
        "the program is kept"
    );
}

/// `campaign --controller FILE.st` runs every scenario with the program; a failing run's
/// reproducer names the program and, run again, fails the same way.
#[test]
fn a_campaign_runs_a_structured_text_program_and_its_reproducers_name_it() {
    let d = temp();
    // Keeps the safety logic's signals and moves nothing: every judged probe is unserved.
    let idle = d.path().join("idle.st");
    std::fs::write(
        &idle,
        "PROGRAM Lift\nVAR EStopOut : BOOL; Restart : BOOL; t : TON; END_VAR\n  t(IN := NOT t.Q, PT := T#1s);\n  Restart := t.Q AND NOT EStopOut;\nEND_PROGRAM\n",
    )
    .expect("write");
    let failures = d.path().join("failures");
    let out = asi_lift()
        .args([
            "campaign",
            "--runs",
            "2",
            "--profile",
            "smoke",
            "--shrink-budget",
            "0",
        ])
        .arg("--controller")
        .arg(&idle)
        .arg("--failures")
        .arg(&failures)
        .output()
        .expect("asi-lift campaign");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("out-of-service"), "{err}");
    let files = files_in(&failures);
    assert!(!files.is_empty(), "{err}");
    let reproducer = failures.join(&files[0]);
    let text = std::fs::read_to_string(&reproducer).expect("read");
    assert!(
        text.contains("the controller does not tell its state"),
        "{text}"
    );
    let absolute = std::path::absolute(&idle).expect("a path");
    assert!(
        text.contains(&format!("program = \"{}\"", absolute.display())),
        "{text}"
    );
    let out = asi_lift()
        .args(["run", "--format", "json"])
        .arg(&reproducer)
        .output()
        .expect("asi-lift run");
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(json["controller"], absolute.display().to_string());

    let err = fails(
        asi_lift()
            .args(["campaign", "--runs", "1", "--controller"])
            .arg(d.path().join("missing.st")),
    );
    assert!(
        err.contains("--controller") && err.contains("missing.st"),
        "{err}"
    );
}

/// `serve --controller FILE.st` runs the program as the PLC; a TTK4145 client cannot run
/// beside it.
#[test]
fn serve_takes_a_structured_text_program_as_the_plc() {
    let d = temp();
    let idle = d.path().join("idle.st");
    std::fs::write(
        &idle,
        "PROGRAM Lift\nVAR Restart : BOOL; t : TON; END_VAR\n  t(IN := NOT t.Q, PT := T#500ms);\n  Restart := t.Q;\nEND_PROGRAM\n",
    )
    .expect("write");
    let err = fails(
        asi_lift()
            .args(["serve", "--ttk4145", "--controller"])
            .arg(&idle),
    );
    assert!(err.contains("cannot run beside --controller"), "{err}");
    let out = asi_lift()
        .args([
            "serve",
            "--listen",
            "127.0.0.1:0",
            "--speed",
            "max",
            "--until",
            "2s",
        ])
        .args(["--format", "json", "-q", "--controller"])
        .arg(&idle)
        .output()
        .expect("asi-lift serve");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!("controller {}", idle.display())),
        "{err}"
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(json["controller"], idle.display().to_string());
    assert_eq!(json["live"]["controller"], "program");
}

/// The reference program with the lab's library (`--library`, or `library` beside `program`
/// in a scenario) gives the built-in program's report; without the library it is refused
/// with a hint; a library without a program is refused.
#[test]
fn the_reference_program_runs_with_its_library() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let lift = root.join("controllers/lift.st");
    let lab = root.join("controllers/lab.st");
    let json = |args: &[&std::ffi::OsStr]| -> serde_json::Value {
        let out = asi_lift()
            .args(["run", "demo", "--until", "15s", "--format", "json"])
            .args(args)
            .output()
            .expect("asi-lift run");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).expect("JSON")
    };
    let builtin = json(&[]);
    let mut st = json(&[
        "--controller".as_ref(),
        lift.as_os_str(),
        "--library".as_ref(),
        lab.as_os_str(),
    ]);
    assert_eq!(st["controller"], lift.display().to_string());
    st.as_object_mut().expect("an object").remove("controller");
    assert_eq!(st, builtin);

    let err = fails(
        asi_lift()
            .args(["run", "--until", "1s", "--controller"])
            .arg(&lift),
    );
    assert!(err.contains("compile it with --library FILE.st"), "{err}");
    let err = fails(
        asi_lift()
            .args(["run", "--until", "1s", "--library"])
            .arg(&lab),
    );
    assert!(
        err.contains("--library: a library goes with a program"),
        "{err}"
    );

    // The scenario's keys, relative to the scenario file.
    let d = temp();
    std::fs::copy(&lift, d.path().join("lift.st")).expect("copy");
    std::fs::copy(&lab, d.path().join("lab.st")).expect("copy");
    let sc = d.path().join("sc.toml");
    std::fs::write(
        &sc,
        "name = \"demo\"\nduration = \"15s\"\n[controller]\nprogram = \"lift.st\"\nlibrary = [\"lab.st\"]\n",
    )
    .expect("write");
    let out = asi_lift()
        .args(["run", "--format", "json"])
        .arg(&sc)
        .output()
        .expect("asi-lift run");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let from_file: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(from_file["violations"], serde_json::json!([]));
    assert_eq!(from_file["arrivals"], builtin["arrivals"]);
    std::fs::write(&sc, "[controller]\nlibrary = [\"lab.st\"]\n").expect("write");
    let err = fails(asi_lift().arg("run").arg(&sc));
    assert!(
        err.contains(":2:11: controller.library: a library goes with a program"),
        "{err}"
    );
}

/// The reproducer of a failing fork: a header that says what failed and how to run it, then
/// the scenario with the fault written in to the fork's horizon, which reads back as that
/// scenario.
#[test]
fn an_explorers_reproducer_is_the_scenario_with_the_fault_written_in() {
    use asi_phy::{SimDuration, SimTime};
    use rig::explore::catalogue::{FaultKind, Params};
    use rig::explore::{ForkLine, Phase, Plan, Verdict};
    let sc = rig::Scenario::demo().expect("the demo");
    let plan = Plan {
        kinds: vec![FaultKind::Stop, FaultKind::DoorOpen],
        params: Params::default(),
        every: SimDuration::from_millis(500),
        window: (SimTime::from_millis(20_000), SimTime::from_millis(21_000)),
        horizon: SimDuration::from_secs(30),
        shard: rig::campaign::run::Shard::ALL,
    };
    // Fork 3: the second instant (20.5 s), the second kind (door-open).
    let line = ForkLine {
        index: 3,
        forks: 6,
        scenario: "demo".into(),
        fault: "door-open".into(),
        at_s: 20.5,
        phase: Phase::Travelling,
        position_mm: 500.0,
        verdict: Verdict::Panic,
        violation: None,
        action: None,
        detail: "boom\nbang".into(),
        after_s: 0.0,
        ran_s: 0.0,
        reproducer: None,
    };
    let (name, text) = asi_lift::cmd::explore::reproducer(&sc, &plan, &line, Path::new("out"));
    assert_eq!(name, "fork-0000003-door-open.toml");
    let header: Vec<&str> = text.lines().take(3).collect();
    assert_eq!(
        header,
        [
            "# asi-lift explore reproducer: fault door-open at 20.5 s in scenario `demo` (travelling phase), fork 3 of 6",
            "# fails: panic: boom bang",
            "# reproduce: asi-lift run out/fork-0000003-door-open.toml",
        ]
    );
    let mut back = rig::Scenario::from_toml(&name, &text).expect("a scenario");
    back.events.iter_mut().for_each(|e| e.line = 0);
    let mut want = rig::explore::written_in(
        sc,
        FaultKind::DoorOpen,
        &plan.params,
        SimTime::from_millis(20_500),
        plan.horizon,
    );
    want.events.iter_mut().for_each(|e| e.line = 0);
    assert_eq!(back, want);
    assert_eq!(back.duration, SimDuration::from_millis(50_500));
}
