//! The lift with the safe drive (`[drive] safe = true`, docs/drive-safety.md §6): STOP with
//! SS1, the runaway at a floor with the door open ending in SOS → STO, the same runaway
//! without the safe drive, the option off leaving a run as it was, and a small campaign with
//! the option on.

use asi_lift_tests::{has_event, run, run_toml, safety_event, scenario, stops};
use asi_phy::SimDuration;
use lift_model::End;
use rig::campaign::generate::{generate, Generated};
use rig::campaign::profile::Profile;
use rig::campaign::summary::summarize;
use rig::campaign::{execute, judge, line, Execution, LineContext};
use rig::report::{LogEvent, PlantLog, Report, TripCause, ViolationKind};
use rig::scenario::{Action, Fault, Scenario};
use safety::drive::{DriveEventKind, Function};
use safety::LiftSafetyCause as Cause;

/// The STOP circuit's fixed delay before K1 drops (docs/safety.md §6.2).
const STOP_DELAY_S: f64 = 9.1;

fn drive(r: &Report) -> &rig::report::DriveReport {
    r.safety
        .drive
        .as_ref()
        .unwrap_or_else(|| panic!("no safe-drive section\n{}", r.to_text()))
}

#[test]
fn stop_is_ss1_the_torque_goes_off_once_the_car_stands_well_before_9_1_s() {
    let r = run(scenario("safe-drive"));
    assert!(r.violations.is_empty(), "{}", r.to_text());
    let d = drive(&r);
    assert!(d.trips.is_empty(), "{:?}", d.trips);
    // The STOP at 21 s; the car stands level at floor 2 at 22.513 s; SS1 takes the torque
    // off by the early limit at 23.004 s: 2.004 s after the STOP.
    let stop = d
        .ss1_stops
        .iter()
        .find(|s| s.requested_at_s == 21.0)
        .unwrap_or_else(|| panic!("no SS1 at the STOP: {:?}", d.ss1_stops));
    let took = stop.took_s.expect("the torque went off");
    assert!(took < STOP_DELAY_S, "{took}");
    assert!((took - 2.004).abs() < 1e-9, "{took}");
    let rest = r
        .arrivals
        .iter()
        .find(|a| a.floor == 2)
        .expect("stopped at floor 2");
    // The early limit's 0.5 s begin once the motor turns slower than 0.2 rev/s (2 mm/s),
    // 9 ms before the converter's ramp (223.4 mm/s²) brings the car to rest.
    let off = stop.torque_off_at_s.expect("off");
    let after_rest = off - rest.at_s;
    assert!((0.489..=0.5).contains(&after_rest), "{after_rest}");
    assert!(has_event(&r, |e| *e == LogEvent::Drive(DriveEventKind::TorqueOff)));
    // The cabin request at 40 s restarts the STOP circuit: SS1 ends, service goes on; the
    // door opened at floor 3 is SOS, which holds without a trip.
    assert_eq!(stops(&r), vec![1, 2, 3, 1]);
    assert!(has_event(&r, |e| {
        *e == LogEvent::Drive(DriveEventKind::SafeStateReached(Function::Sos))
    }));
    assert!(r.final_state.contactor_closed);
}

#[test]
fn without_the_safe_drive_the_same_stop_waits_9_1_s_for_k1() {
    let mut sc = scenario("safe-drive");
    sc.safe_drive = false;
    let r = run(sc);
    assert!(r.safety.drive.is_none());
    assert!(has_event(
        &r,
        safety_event(
            |c| matches!(c, Cause::StopDelayElapsed { delay } if *delay == SimDuration::from_millis(9_100))
        )
    ));
    // K1 opens only at 30.1 s: the first K1 opening after the STOP.
    let k1 = r
        .safety
        .trips
        .iter()
        .find(|t| t.at_s > 21.0 && t.cause.is_k1_opened())
        .expect("K1 opened");
    assert!((k1.at_s - 30.1).abs() < 1e-6, "{}", k1.at_s);
}

#[test]
fn a_runaway_at_a_floor_with_the_door_open_ends_in_sos_then_sto_within_the_tolerance() {
    let r = run(scenario("safe-drive-runaway"));
    assert!(r.violations.is_empty(), "{}", r.to_text());
    let d = drive(&r);
    assert_eq!(d.trips.len(), 1, "{:?}", d.trips);
    let trip = &d.trips[0];
    assert_eq!(trip.function, "SOS");
    assert!(
        trip.cause.contains("faster than the allowed 0.2 rev/s"),
        "{}",
        trip.cause
    );
    // The runaway begins at 30 s; at 223.4 mm/s² the motor passes 0.2 rev/s in the 9th ms.
    assert!((trip.at_s - 30.009).abs() < 1e-9, "{}", trip.at_s);
    // The car stood level at floor 2; it moved a few hundredths of a mm, far inside SOS's
    // 0.5 rev (5 mm) and the watch's 10 mm.
    let at_floor = r
        .arrivals
        .iter()
        .find(|a| a.floor == 2)
        .expect("at floor 2")
        .position_mm;
    let moved = r.final_state.position_mm - at_floor;
    assert!(moved > 0.0 && moved < 0.1, "{moved} mm");
    // STO is K1 opening: the report's safety trips name the drive, and the operator's reset
    // (after the repair) brings the torque back.
    assert!(r
        .safety
        .trips
        .iter()
        .any(|t| matches!(t.cause, TripCause::Drive(v) if v.function() == Some(Function::Sos))));
    assert!(has_event(&r, |e| *e == LogEvent::Drive(DriveEventKind::Reset)));
    assert!(r.final_state.contactor_closed, "{}", r.to_text());
    assert!(r.to_text().contains("SOS tripped"));
}

/// The encoder fails 2.76 s into a journey up: the monitor trips in the same scan (it counts a
/// reading it cannot get as unsafe), K1 opens and the car stops between floors 1 and 2; it stays
/// there while the encoder is broken, and after the repair and the operator's reset the lift
/// finishes the journey and serves the next call, with no violation.
#[test]
fn a_failed_encoder_stops_the_car_between_floors_until_repaired_and_reset() {
    let mut sc = scenario("safe-drive-encoder");
    sc.duration = SimDuration::from_secs(29);
    let broken = run(sc);
    assert!(broken.violations.is_empty(), "{}", broken.to_text());
    let d = drive(&broken);
    assert_eq!(d.trips.len(), 1, "{:?}", d.trips);
    assert_eq!(d.trips[0].function, "encoder");
    assert_eq!(d.trips[0].at_s, 13.0);
    assert!(d.trips[0].cause.contains("no valid position or speed"));
    assert!(!broken.final_state.contactor_closed, "{}", broken.to_text());
    assert!(!broken.final_state.moving, "{}", broken.to_text());
    let x = broken.final_state.position_mm;
    assert!(
        x > 10.0 && x < 400.0,
        "stopped at {x} mm, between floors 1 and 2"
    );

    let r = run(scenario("safe-drive-encoder"));
    assert!(r.violations.is_empty(), "{}", r.to_text());
    assert_eq!(drive(&r).trips.len(), 1, "{:?}", drive(&r).trips);
    assert!(has_event(&r, |e| *e == LogEvent::Drive(DriveEventKind::Reset)));
    let floors: Vec<u8> = r.arrivals.iter().map(|a| a.floor).collect();
    assert_eq!(floors, [1, 4, 2], "{}", r.to_text());
    assert!(r.final_state.contactor_closed);
}

#[test]
fn the_same_runaway_without_the_safe_drive_runs_the_car_off_with_the_door_open() {
    let mut sc = scenario("safe-drive-runaway");
    sc.safe_drive = false;
    sc.duration = SimDuration::from_secs(40);
    let r = run(sc);
    // Nothing stops the car until the top overtravel sensor opens K1.
    let kinds: Vec<ViolationKind> = r.violations.iter().map(|v| v.kind).collect();
    assert_eq!(
        kinds,
        vec![ViolationKind::DoorOpenMoving],
        "{}",
        r.to_text()
    );
    assert!(
        r.final_state.position_mm > 1_260.0,
        "{}",
        r.final_state.position_mm
    );
    assert!(r.final_state.k1_open_cause.is_some());
}

#[test]
fn the_option_off_changes_nothing_in_a_run() {
    // The same scenario file with `[drive] safe = false` written out and with no `[drive]`
    // at all gives the same report, and the report has no safe-drive section.
    let body = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/stop.toml"),
    )
    .expect("stop.toml");
    let plain = run_toml("stop", &body);
    let off = run_toml("stop", &format!("{body}\n[drive]\nsafe = false\n"));
    assert_eq!(plain, off);
    assert!(plain.safety.drive.is_none());
    let json = plain.to_json().expect("json");
    assert!(!json.contains("\"drive\""));
    assert!(!json.contains("unintended-movement"));
}

#[test]
fn a_scenario_with_the_safe_drive_and_a_runaway_reads_back_from_its_file() {
    let sc = scenario("safe-drive-runaway");
    assert!(sc.safe_drive);
    let text = sc.to_toml();
    assert!(text.contains("[drive]\nsafe = true"), "{text}");
    assert!(text.contains("kind = \"converter-runaway\", direction = \"up\""));
    let back = Scenario::from_toml("back", &text).expect("reads back");
    let strip = |s: &Scenario| {
        let mut s = s.clone();
        for e in &mut s.events {
            e.line = 0;
        }
        s
    };
    assert_eq!(strip(&back), strip(&sc));
    // Off: no [drive] section written, as before the option existed.
    let mut off = sc.clone();
    off.safe_drive = false;
    assert!(!off.to_toml().contains("[drive]"));
}

#[test]
fn a_campaign_with_the_safe_drive_has_no_violations() {
    // A short version of the campaign the book reports ("The safe drive on the lift") (200 runs): 6 runs of the
    // safe-drive profile, each on the whole rig with the safe drive.
    let profile = Profile::built_in("safe-drive").expect("built in");
    for index in 0..6 {
        let g = generate(17, index, &profile);
        assert!(g.scenario.safe_drive);
        let Execution::Report(r) = execute(&g.scenario) else {
            panic!("run {index} did not run");
        };
        assert!(
            r.violations.is_empty(),
            "run {index}:\n{}\n{}",
            g.scenario.to_toml(),
            r.to_text()
        );
        assert!(r.safety.drive.is_some());
    }
    // The default profile leaves it off.
    let g = generate(17, 0, &Profile::built_in("default").expect("default"));
    assert!(!g.scenario.safe_drive);
}

/// The runs of the safe-drive campaign (seed 17, 200 runs) in which `fault` happens, each one
/// followed by a `repair` (the recovery's at the latest); more than 20 of them. The default
/// profile draws the fault in none of its 200.
fn safe_drive_runs_with(
    what: &str,
    fault: impl Fn(&Action) -> bool,
    repair: impl Fn(&Action) -> bool,
) -> Vec<(u64, Generated)> {
    let profile = Profile::built_in("safe-drive").expect("built in");
    let mut with = Vec::new();
    for index in 0..200 {
        let g = generate(17, index, &profile);
        let events = &g.scenario.events;
        if let Some(last) = events.iter().rposition(|e| fault(&e.action)) {
            assert!(
                events[last..].iter().any(|e| repair(&e.action)),
                "run {index}: {what} never repaired"
            );
            with.push((index, g));
        }
    }
    assert!(with.len() > 20, "{} runs of 200 with {what}", with.len());
    let default = Profile::built_in("default").expect("default");
    for index in 0..200 {
        let g = generate(17, index, &default);
        assert!(!g.scenario.events.iter().any(|e| fault(&e.action)));
    }
    with
}

/// Runs the campaign run `index` and asserts it ends without a violation.
fn execute_safely(index: u64, g: &Generated) -> Execution {
    let exec = execute(&g.scenario);
    let Execution::Report(r) = &exec else {
        panic!("run {index} did not run");
    };
    assert!(
        r.violations.is_empty(),
        "run {index}:\n{}\n{}",
        g.scenario.to_toml(),
        r.to_text()
    );
    exec
}

/// The safe-drive profile lets the converter run away (the `runaway` activity), each time
/// repaired by the recovery at the latest; the first two runs with one end without a
/// violation, a drive trip among their safety trips. The default profile never draws one.
#[test]
fn the_safe_drive_campaign_lets_the_converter_run_away_and_stays_safe() {
    let with = safe_drive_runs_with(
        "a runaway",
        |a| matches!(a, Action::Fault(Fault::ConverterRunaway { .. })),
        |a| matches!(a, Action::Fault(Fault::ConverterRepaired)),
    );
    for (index, g) in with.iter().take(2) {
        execute_safely(*index, g);
    }
}

/// The safe-drive profile also fails the encoder (the `encoder` activity), each time repaired
/// by the recovery at the latest; the first two runs with one end without a violation, the
/// encoder's trip among their safety trips, and their campaign lines and summary count the
/// safe drive's trips apart. The default profile never draws one.
#[test]
fn the_safe_drive_campaign_fails_the_encoder_and_stays_safe() {
    let with = safe_drive_runs_with(
        "an encoder fault",
        |a| matches!(a, Action::Fault(Fault::EncoderFailed)),
        |a| matches!(a, Action::Fault(Fault::EncoderRepaired)),
    );
    let mut lines = String::new();
    let mut drive_trips = 0;
    for (index, g) in with.iter().take(2) {
        let exec = execute_safely(*index, g);
        let Execution::Report(r) = &exec else {
            unreachable!("execute_safely returns a report");
        };
        assert!(
            drive(r).trips.iter().any(|t| t.function == "encoder"),
            "run {index}: {:?}",
            drive(r).trips
        );
        drive_trips += drive(r).trips.len() as u64;
        let ctx = LineContext {
            index: *index,
            runs: 200,
            campaign_seed: 17,
            profile: "safe-drive",
            seed: g.scenario.seed,
            digest: String::new(),
        };
        let l = line(ctx, &exec, &judge(&exec, g.probe.as_ref()));
        assert_eq!(l.drive_trips, drive(r).trips.len());
        assert!(l.safety_trips >= l.drive_trips);
        lines += &(l.to_json_line().expect("a line") + "\n");
    }
    let s = summarize(&[("lines".into(), lines)]).expect("a summary");
    let d = s.drive_trips.as_ref().expect("the safe drive's trips");
    assert_eq!((d.trips, d.runs), (drive_trips, 2));
    let text = s.to_text();
    assert!(
        text.lines()
            .any(|l| l.starts_with("  of them the safe drive's")
                && l.ends_with(&format!(" {drive_trips} in 2 runs"))),
        "{text}"
    );
}

/// The times (ns) and values of the 1-bit VCD variable `name` of scope `rig.drive_safety`.
fn vcd_bit(vcd: &str, name: &str) -> Vec<(u64, bool)> {
    let id = vcd
        .lines()
        .skip_while(|l| !l.contains("$scope module drive_safety"))
        .find_map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            (w.len() >= 5 && w[0] == "$var" && w[4] == name).then(|| w[3].to_owned())
        })
        .unwrap_or_else(|| panic!("no variable {name} in rig.drive_safety"));
    let body = &vcd[vcd.find("$enddefinitions").expect("header")..];
    let mut t = 0;
    let mut out = Vec::new();
    for tok in body.lines().map(str::trim) {
        if let Some(n) = tok.strip_prefix('#').and_then(|n| n.parse().ok()) {
            t = n;
        } else if tok.len() == id.len() + 1 && tok.ends_with(id.as_str()) {
            match &tok[..1] {
                "0" => out.push((t, false)),
                "1" => out.push((t, true)),
                _ => {}
            }
        }
    }
    out
}

#[test]
fn the_vcd_shows_the_functions_bits_under_rig_drive_safety() {
    use asi_lift_tests::Shared;
    use asi_phy::SimTime;
    use rig::rig::Rig;
    use rig::waves::WaveOutputs;
    let vcd_of = |sc: Scenario| {
        let vcd = Shared::default();
        let mut rig = Rig::new(sc).expect("rig");
        rig.waves_to(WaveOutputs {
            vcd: Some(Box::new(vcd.clone())),
            csv: None,
            window: (SimTime::ZERO, SimTime::from_micros(10)),
            pulse_window: Some((SimTime::ZERO, SimTime::from_micros(10))),
        });
        rig.run(Some(SimDuration::from_millis(30_100)));
        String::from_utf8(vcd.bytes()).expect("utf-8")
    };
    let vcd = vcd_of(scenario("safe-drive-runaway"));
    // SOS: its control bit falls when the door opens (25 s; active-low), its status rises in
    // that scan and falls at the trip (30.009 s) with NotErrFunc and the torque.
    let s = |ms: u64| ms * 1_000_000;
    let last_before =
        |bits: &[(u64, bool)], t: u64| bits.iter().rev().find(|(at, _)| *at <= t).map(|(_, b)| *b);
    let control = vcd_bit(&vcd, "control_sos");
    assert_eq!(last_before(&control, s(24_999)), Some(true));
    assert_eq!(last_before(&control, s(25_000)), Some(false));
    let status = vcd_bit(&vcd, "status_sos");
    assert_eq!(last_before(&status, s(25_000)), Some(true));
    assert_eq!(last_before(&status, s(30_008)), Some(true));
    assert_eq!(last_before(&status, s(30_009)), Some(false));
    for name in ["status_not_err_func", "torque_enabled"] {
        let bits = vcd_bit(&vcd, name);
        assert_eq!(last_before(&bits, s(30_008)), Some(true), "{name}");
        assert_eq!(last_before(&bits, s(30_009)), Some(false), "{name}");
    }
    // SLP is requested throughout (its control bit FALSE) and its status TRUE until the trip.
    assert!(vcd_bit(&vcd, "control_slp").iter().all(|(_, b)| !b));
    // Without the safe drive the VCD has no such scope.
    let mut off = scenario("safe-drive-runaway");
    off.safe_drive = false;
    off.duration = SimDuration::from_millis(300);
    assert!(!vcd_of(off).contains("drive_safety"));
}

#[test]
fn slp_stops_a_runaway_on_the_journey_up_and_the_overtravel_sensor_backs_it() {
    // the book, "The safe drive on the lift": a runaway up during the journey to floor 4.
    let r = run_toml(
        "slp",
        "duration = \"40s\"\n[lift]\nstart_mm = 650.0\n[drive]\nsafe = true\n\
         [[event]]\nat = \"15s\"\npress = \"cabin:4\"\n\
         [[event]]\nat = \"17s\"\nfault = { kind = \"converter-runaway\", direction = \"up\" }\n",
    );
    assert!(r.violations.is_empty(), "{}", r.to_text());
    let d = drive(&r);
    assert_eq!(d.trips.len(), 1, "{:?}", d.trips);
    assert_eq!(d.trips[0].function, "SLP");
    assert!(
        (d.trips[0].at_s - 24.601).abs() < 1e-9,
        "{}",
        d.trips[0].at_s
    );
    // 1250 mm is SLP's limit; at 153.2 mm/s the brake needs 23.5 mm more.
    assert!(
        (d.trips[0].position_mm - 1250.0).abs() < 0.2,
        "{}",
        d.trips[0].position_mm
    );
    assert!((r.final_state.position_mm - 1273.5).abs() < 0.1);
    assert!(has_event(&r, |e| {
        matches!(
            e,
            LogEvent::Plant(PlantLog::OvertravelTripped { end: End::Top, .. })
        )
    }));
    assert!(!has_event(&r, |e| matches!(
        e,
        LogEvent::Plant(PlantLog::Crash { .. })
    )));
}
