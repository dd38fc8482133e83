//! The `asi-lift` command as a user runs it: the built binary, real files and a real pipe
//! (README.md, "Outputs").

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
    for json in [false, true] {
        let mut cmd = asi_lift();
        cmd.args(["decode", "--signal", "manchester"]).arg(&vcd);
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
