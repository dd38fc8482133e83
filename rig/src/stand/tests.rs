//! The SafeMOTION thesis' test guides (appendix A) on the stand with the demo parameters: the HMI
//! states and their times as each guide describes them; the stand's decisions; the scenario
//! reader's errors; determinism.

use super::builtin::{find, stand_scenario, STAND_BUILTINS};
use super::*;

fn builtin(name: &str) -> StandReport {
    let b = find(name).unwrap_or_else(|| panic!("built-in {name}"));
    run(&stand_scenario(b).unwrap_or_else(|e| panic!("{e}")))
}

fn from(text: &str) -> StandReport {
    run(&StandScenario::from_toml("test.toml", text).unwrap_or_else(|e| panic!("{e}")))
}

/// The page's states in order, with their times in ms.
fn states(r: &StandReport) -> Vec<(u64, HmiState)> {
    r.hmi.iter().map(|h| (h.at_ms, h.state)).collect()
}

/// The time (ms) of the first `who` line whose text contains `what`.
fn logged(r: &StandReport, who: &str, what: &str) -> Option<u64> {
    r.log
        .iter()
        .find(|l| l.who == who && l.text.contains(what))
        .map(|l| l.at_ms)
}

use HmiState::*;

/// A.2: STO de-energises in the scan of the request; Aktivní (red) until the Reset.
#[test]
fn guide_sto_active_at_once_until_reset() {
    let r = builtin("sto");
    assert_eq!(
        states(&r),
        [(0, Ready), (4_000, Active), (10_000, Ready)],
        "{}",
        r.to_text()
    );
    assert_eq!(logged(&r, "safety", "torque off"), Some(4_000));
    assert!(r.trips.is_empty() && r.stopwatch_ms.is_empty());
    // The axis coasts from 5 rev/s at 2 rev/s²: standstill 2.5 s later.
    assert_eq!(logged(&r, "axis", "standstill"), Some(6_500));
    assert_eq!(r.final_speed, 0.0);
}

/// A.3 steps 4–6: OK at 1 rev/s, NOK in the scan the speed passes 2 rev/s.
#[test]
fn guide_sos_ok_below_2_rev_s_nok_above() {
    let r = builtin("sos");
    let s = states(&r);
    assert_eq!(s[..2], [(0, Ready), (3_000, Ok)], "{}", r.to_text());
    // 1 → 3 rev/s at 10 rev/s² from 8 s: above 2 rev/s after 0.1 s.
    assert!(
        matches!(s[2], (t, Nok) if (8_100..=8_110).contains(&t)),
        "{s:?}"
    );
    assert_eq!(s[3], (13_000, Ready));
    assert_eq!(r.trips.len(), 1);
    assert!(
        r.trips[0].1.contains("faster than the allowed 2"),
        "{:?}",
        r.trips
    );
}

/// A.3 step 6, alternative: more than 100 rev in one direction since the request.
#[test]
fn guide_sos_nok_after_100_rev() {
    let r = from(
        r#"function = "sos"
duration = "80s"
speed = 1.5
[[event]]
at = "1s"
drive = "on"
[[event]]
at = "2s"
curtain = "break"
"#,
    );
    let s = states(&r);
    assert_eq!(s[1], (2_000, Ok));
    // 100 rev at 1.5 rev/s: 66.67 s after the request.
    assert!(
        matches!(s[2], (t, Nok) if (68_660..=68_680).contains(&t)),
        "{s:?}"
    );
    assert!(r.trips[0].1.contains("more than the allowed 100 rev"));
}

/// A.4: the axis keeps running: Del+Decel from the request, de-energised (NOK) 15 s after
/// it, the stopwatch at 15000 ms; no violation; the axis coasts to a stop.
#[test]
fn guide_ss1_running_axis_de_energised_at_15_s() {
    let r = builtin("ss1");
    assert_eq!(
        states(&r),
        [
            (0, Ready),
            (2_000, DelDecel),
            (17_000, Nok),
            (22_000, Ready)
        ],
        "{}",
        r.to_text()
    );
    assert_eq!(r.stopwatch_ms, [15_000]);
    assert!(r.trips.is_empty(), "SS1's stop is no violation");
    assert_eq!(logged(&r, "safety", "torque off"), Some(17_000));
    assert_eq!(logged(&r, "axis", "standstill"), Some(19_500));
}

/// A.4: under 2 rev/s for the early-limit time after the enable delay: de-energised 10 s
/// after the request.
#[test]
fn guide_ss1_early_limit_under_2_rev_s_for_5_s() {
    let r = from(
        r#"function = "ss1"
duration = "20s"
speed = 1.5
[[event]]
at = "1s"
drive = "on"
[[event]]
at = "2s"
curtain = "break"
"#,
    );
    assert_eq!(
        states(&r),
        [(0, Ready), (2_000, DelDecel), (12_000, Nok)],
        "{}",
        r.to_text()
    );
    assert_eq!(r.stopwatch_ms, [10_000]);
}

/// A.4 with a motion control that brakes to the safe drive's speed limit: standstill long
/// before the enable delay ends, de-energised by the early limit at 10 s.
#[test]
fn ss1_with_the_motion_control_braking_is_off_at_10_s() {
    let r = from(
        r#"function = "ss1"
duration = "20s"
speed = 5.0
[stand]
follows_limit = true
[[event]]
at = "1s"
drive = "on"
[[event]]
at = "2s"
curtain = "break"
"#,
    );
    assert_eq!(states(&r)[2], (12_000, Nok), "{}", r.to_text());
    assert_eq!(logged(&r, "axis", "standstill"), Some(2_500));
}

/// A.5: braked within the window: OK by the early limit 10 s after the request, then NOK
/// above 2 rev/s.
#[test]
fn guide_ss2_ok_by_the_early_limit_then_nok_above_2_rev_s() {
    let r = builtin("ss2");
    let s = states(&r);
    assert_eq!(
        s[..3],
        [(0, Ready), (2_000, DelDecel), (12_000, Ok)],
        "{}",
        r.to_text()
    );
    assert!(
        matches!(s[3], (t, Nok) if (18_200..=18_210).contains(&t)),
        "{s:?}"
    );
    assert_eq!(s[4], (23_000, Ready));
    assert_eq!(r.stopwatch_ms, [10_000]);
}

/// A.5: not slowed within the window: NOK 15 s after the request.
#[test]
fn guide_ss2_not_slowed_in_time_nok_at_15_s() {
    let r = from(
        r#"function = "ss2"
duration = "20s"
speed = -7.0
[[event]]
at = "1s"
drive = "on"
[[event]]
at = "2s"
curtain = "break"
"#,
    );
    assert_eq!(states(&r), [(0, Ready), (2_000, DelDecel), (17_000, Nok)]);
    assert_eq!(r.stopwatch_ms, [15_000]);
    assert!(r.trips[0].1.contains("ramp time ran out"));
}

/// A.6, SLS1: slowed under 8 rev/s: OK at 10 s by the early limit; NOK above 8 rev/s.
#[test]
fn guide_sls1_ok_under_8_rev_s_then_nok_above() {
    let r = builtin("sls1");
    let s = states(&r);
    assert_eq!(
        s[..3],
        [(0, Ready), (2_000, DelDecel), (12_000, Ok)],
        "{}",
        r.to_text()
    );
    // 6 → 9 rev/s from 18 s: above 8 rev/s after 0.2 s.
    assert!(
        matches!(s[3], (t, Nok) if (18_200..=18_210).contains(&t)),
        "{s:?}"
    );
    assert_eq!(r.stopwatch_ms, [10_000]);
}

/// A.6, SLS2: still above 5 rev/s when the window ends: NOK 15 s after the request.
#[test]
fn guide_sls2_not_slowed_in_time_nok_at_15_s() {
    let r = builtin("sls2");
    assert_eq!(
        states(&r),
        [
            (0, Ready),
            (2_000, DelDecel),
            (17_000, Nok),
            (22_000, Ready)
        ],
        "{}",
        r.to_text()
    );
    assert_eq!(r.stopwatch_ms, [15_000]);
}

/// A.7: requested at standstill (OK), NOK after 50 rev.
#[test]
fn guide_sli_nok_after_50_rev() {
    let r = builtin("sli");
    let s = states(&r);
    assert_eq!(s[..2], [(0, Ready), (2_000, Ok)], "{}", r.to_text());
    // 0.5 s ramp (1.25 rev) from 4 s, then 48.75 rev at 5 rev/s: 14.25 s.
    assert!(
        matches!(s[2], (t, Nok) if (14_250..=14_260).contains(&t)),
        "{s:?}"
    );
    assert!(r.trips[0].1.contains("more than the allowed 50 rev"));
    assert!(r.stopwatch_ms.is_empty(), "SLI's page has no stopwatch");
}

/// A.8, SDI-P: forwards OK; backwards NOK after 100 rev from the furthest point (25 rev).
#[test]
fn guide_sdi_p_nok_after_100_rev_backwards() {
    let r = builtin("sdi-p");
    let s = states(&r);
    assert_eq!(s[..2], [(0, Ready), (2_000, Ok)], "{}", r.to_text());
    assert!(
        matches!(s[2], (t, Nok) if (28_750..=28_760).contains(&t)),
        "{s:?}"
    );
    assert!(r.trips[0].1.contains("forbidden direction"));
}

/// A.8, SDI-N: the mirror image.
#[test]
fn guide_sdi_n_nok_after_100_rev_forwards() {
    let r = builtin("sdi-n");
    let s = states(&r);
    assert_eq!(s[..2], [(0, Ready), (2_000, Ok)], "{}", r.to_text());
    assert!(
        matches!(s[2], (t, Nok) if (28_750..=28_760).contains(&t)),
        "{s:?}"
    );
}

/// Figure 4.4's order, and the guides' names for STO and SS1.
#[test]
fn hmi_state_follows_figure_4_4() {
    let f = Function::Ss2;
    assert_eq!(hmi_state(f, false, true, false, true, true), Error);
    assert_eq!(hmi_state(f, true, false, false, true, true), NotSelected);
    assert_eq!(hmi_state(f, true, true, true, false, true), Ready);
    assert_eq!(hmi_state(f, true, true, false, false, true), DelDecel);
    assert_eq!(hmi_state(f, true, true, false, true, true), Ok);
    assert_eq!(hmi_state(f, true, true, false, false, false), Nok);
    assert_eq!(
        hmi_state(Function::Sto, true, true, false, true, true),
        Active
    );
    assert_eq!(hmi_state(Function::Ss1, true, true, false, true, true), Nok);
    assert_eq!(NotSelected.colour(), "grey");
    assert_eq!(DelDecel.to_string(), "Del+Decel (orange)");
}

/// The curtain's restart interlock: a Reset while the hand is still in the field does
/// nothing; the drive starts again only after Reset and a new Zap.
#[test]
fn the_curtain_needs_a_reset_with_the_field_clear() {
    let r = from(
        r#"function = "sto"
duration = "12s"
speed = 2.0
[[event]]
at = "1s"
drive = "on"
[[event]]
at = "2s"
curtain = "break"
hold = "3s"
[[event]]
at = "3s"
reset = true
[[event]]
at = "6s"
drive = "on"
[[event]]
at = "7s"
reset = true
[[event]]
at = "8s"
drive = "on"
"#,
    );
    assert_eq!(
        states(&r),
        [(0, Ready), (2_000, Active), (7_000, Ready)],
        "{}",
        r.to_text()
    );
    assert!(logged(&r, "student", "does not start").is_some_and(|t| t == 6_000));
    assert_eq!(logged(&r, "drive", "Zap - P"), Some(1_000));
    assert!(r.log.iter().filter(|l| l.text.contains("Zap - P")).count() == 2);
    assert_eq!(r.final_speed, 2.0);
}

/// With a holding brake the axis stops at 50 rev/s² instead of coasting at 2 rev/s².
#[test]
fn a_brake_stops_the_axis_quickly() {
    let r = from(
        r#"function = "sto"
duration = "6s"
speed = 5.0
[stand]
brake = true
[[event]]
at = "1s"
drive = "on"
[[event]]
at = "2s"
curtain = "break"
"#,
    );
    assert_eq!(logged(&r, "axis", "standstill"), Some(2_100));
    assert!(r.log.iter().any(|l| l.text.contains("brake applied")));
}

/// Every built-in reads, runs twice to the same report, and every file in scenarios/stand/ is
/// built in.
#[test]
fn every_stand_scenario_is_built_in_and_deterministic() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/stand");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .expect("scenarios/stand/")
        .filter_map(|e| {
            let name = e.ok()?.file_name().to_string_lossy().into_owned();
            name.strip_suffix(".toml").map(str::to_owned)
        })
        .collect();
    files.sort();
    let mut names: Vec<String> = STAND_BUILTINS.iter().map(|b| b.name.to_owned()).collect();
    names.sort();
    assert_eq!(names, files);
    for b in STAND_BUILTINS {
        let sc = stand_scenario(b).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scenario::function_name(sc.function), b.name);
        assert!(sc.events.iter().all(|e| e.at < SimTime::ZERO + sc.duration));
        let (a, c) = (run(&sc), run(&sc));
        assert_eq!(a, c, "{}", b.name);
        assert_eq!(a.to_text(), c.to_text());
        let s = b.summary();
        assert!(s.ends_with('.') && s.len() < 250, "{}: {s}", b.name);
    }
}

/// A malformed file names the file, the line and the field.
#[test]
fn errors_name_file_line_and_field() {
    let err = |text: &str| {
        StandScenario::from_toml("g.toml", text)
            .expect_err("refused")
            .to_string()
    };
    let e = err("function = \"sls3\"\nduration = \"1s\"\n");
    assert!(
        e.starts_with("g.toml:1:12: function: unknown function `sls3`"),
        "{e}"
    );
    let e = err("function = \"sos\"\nduration = \"1s\"\n[[event]]\nat = \"1s\"\nspeed = 80.0\n");
    assert!(e.starts_with("g.toml:5:9: event[1].speed: 80 rev/s"), "{e}");
    let e = err("function = \"sos\"\nduration = \"1s\"\n[[event]]\nat = \"1s\"\ndrive = \"go\"\n");
    assert!(
        e.starts_with("g.toml:5:9: event[1].drive: unknown drive command"),
        "{e}"
    );
    let e = err("function = \"sos\"\nduration = \"1s\"\n[[event]]\nat = \"1s\"\nreset = true\nspeed = 1.0\n");
    assert!(
        e.starts_with("g.toml:3:1: event[1]: more than one action"),
        "{e}"
    );
    let e = err("function = \"sos\"\nduration = \"1s\"\n[stand]\nbrakes = true\n");
    assert!(
        e.starts_with("g.toml:4:1: stand.brakes: unknown field"),
        "{e}"
    );
    let e = err("function = \"sos\"\nduration = \"0s\"\n");
    assert!(
        e.starts_with("g.toml:2:12: duration: must be longer"),
        "{e}"
    );
    let e = err("function = \"sos\"\n");
    assert!(e.contains("duration"), "{e}");
}
