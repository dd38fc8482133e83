//! Regressions of unsafe or unrecoverable runs that the fault campaign found.
//! Each test is the reproducer as a scenario file body, run on the whole rig, and asserts what
//! a safety engineer expects of it: no invariant broken, the fault ends in a safe reported
//! state, and service resumes once the fault is repaired.

use asi_lift_tests::*;
use controller::ProgramEventKind;
use controller::{HaltReason, LostReason, ProgramEventKind as Ctl};
use rig::report::{LogEvent, Report, Rescue, TripCause};
use rig::scenario::Action;
use safety::lift::K1Cause;
use safety::LiftSafetyCause as Cause;

/// The times the safety logic closed K1.
fn k1_closed_at(r: &Report) -> Vec<f64> {
    r.log
        .iter()
        .filter(|l| l.event == LogEvent::Safety(Cause::K1Closed))
        .map(|l| l.at_s)
        .collect()
}

/// Arrivals where the controller's floor and the floor the cabin stands level at agree.
fn assert_arrivals_agree(r: &Report) {
    for a in &r.arrivals {
        let level = (f64::from(a.floor) - 1.0) * 400.0;
        assert!((a.position_mm - level).abs() <= 10.0, "{a:?}");
    }
    for (line, floor) in r.log.iter().filter_map(|l| match l.event {
        LogEvent::Controller(ProgramEventKind::Arrived { floor }) => Some((l, floor)),
        _ => None,
    }) {
        let rest = r
            .arrivals
            .iter()
            .find(|a| a.at_s >= line.at_s)
            .unwrap_or_else(|| panic!("no stop after {line:?}"));
        assert_eq!(
            rest.floor, floor,
            "controller said {line:?}, cabin at {rest:?}"
        );
    }
}

#[test]
fn door_open_at_power_on_holds_the_initialisation() {
    let r = run_toml(
        "door open at power-on",
        r#"
duration = "50s"
[lift]
door = "open"
[[event]]
at = "20s"
door = "closed"
"#,
    );
    assert_no_violations(&r);
    assert!(has_event(&r, program(Ctl::InitHeld(HaltReason::DoorOpen))));
    assert!(
        r.initialised_at_s.is_some_and(|t| t > 20.0),
        "{:?}",
        r.initialised_at_s
    );
    assert_eq!(stops(&r), [1]);
}

#[test]
fn door_open_during_a_new_initialisation_after_a_power_fail_holds_it() {
    let r = run_toml(
        "door open in re-initialisation",
        r#"
duration = "60s"
[lift]
start_mm = 0.0
[[event]]
at = "5s"
fault = { kind = "power-fail", duration = "1s" }
[[event]]
at = "6s"
door = "open"
[[event]]
at = "10s"
reset = true
[[event]]
at = "30s"
door = "closed"
[[event]]
at = "35s"
press = "cabin:2"
"#,
    );
    assert_no_violations(&r);
    assert_eq!(served(&r), [(2, "cabin".into())]);
}

#[test]
fn the_hand_crank_with_the_door_open_is_not_the_drive_moving() {
    // STOP at floor 2 opens K1 after the STOP delay; then the door is opened and the operator
    // turns the motor by hand. That is no drive motion with the door open.
    let r = run_toml(
        "crank with the door open",
        r#"
duration = "60s"
[lift]
start_mm = 0.0
[[event]]
at = "5s"
press = "cabin:2"
[[event]]
at = "15s"
press = "stop"
[[event]]
at = "26s"
door = "open"
[[event]]
at = "27s"
crank_mm = 10.0
"#,
    );
    assert_no_violations(&r);
    assert!(has_event(&r, |e| *e == LogEvent::Action(Action::Crank { mm: 10.0 })));
    assert!(
        !has_event(&r, |e| matches!(e, LogEvent::Refused(_))),
        "{}",
        r.to_text()
    );
    let at_floor_2 = r.arrivals.get(1).expect("arrival at floor 2");
    assert_eq!(at_floor_2.floor, 2);
    let moved = r.final_state.position_mm - at_floor_2.position_mm;
    assert!((moved - 10.0).abs() < 1e-6, "{moved}");
}

/// An overloaded cabin at 650 mm and `fault` at 5 s: K1 never closes, the cabin never moves.
fn overloaded_cabin_stays_still_through(fault: &str) {
    let r = run_toml(
        "overloaded through a fault",
        &format!(
            r#"
duration = "40s"
[lift]
start_mm = 650.0
load = "overloaded"
[[event]]
at = "5s"
fault = {fault}
"#
        ),
    );
    assert_no_violations(&r);
    assert!(k1_closed_at(&r).is_empty(), "{}", r.to_text());
    assert_eq!(r.final_state.position_mm, 650.0);
}

#[test]
fn the_load_sensor_leaving_the_bus_keeps_the_overloaded_cabin_still() {
    overloaded_cabin_stays_still_through(r#"{ kind = "slave-offline", slave = 8 }"#);
}

#[test]
fn an_as_i_power_fail_keeps_the_overloaded_cabin_still() {
    overloaded_cabin_stays_still_through(r#"{ kind = "power-fail", duration = "2s" }"#);
}

#[test]
fn a_lost_load_sensor_is_no_obstacle_once_it_is_back() {
    let r = run_toml(
        "load sensor away and back",
        r#"
duration = "60s"
[lift]
start_mm = 0.0
[[event]]
at = "5s"
fault = { kind = "slave-offline", slave = 8 }
[[event]]
at = "10s"
press = "cabin:2"
[[event]]
at = "20s"
fault = { kind = "slave-online", slave = 8 }
"#,
    );
    assert_no_violations(&r);
    // No journey while the load is unknown; served after the sensor is back.
    assert_eq!(served(&r), [(2, "cabin".into())]);
    assert!(r.served[0].served_at_s > 20.0);
}

#[test]
fn the_floor_count_survives_a_halt_between_floors() {
    let r = run_toml(
        "halt at a vane",
        r#"
duration = "80s"
[lift]
start_mm = 0.0
[[event]]
at = "5s"
press = "cabin:3"
[[event]]
at = "11.3s"
door = "open"
[[event]]
at = "15s"
door = "closed"
[[event]]
at = "40s"
press = "cabin:4"
"#,
    );
    assert_no_violations(&r);
    assert!(r.safety.trips.is_empty(), "{:?}", r.safety.trips);
    assert_arrivals_agree(&r);
    assert_eq!(served(&r), [(3, "cabin".into()), (4, "cabin".into())]);
}

#[test]
fn the_door_opened_at_every_moment_of_a_journey_never_loses_the_floor() {
    // A halt near any vane edge: the count must hold wherever the cabin comes to rest.
    for tenth in 0..30 {
        let open_at = 9.0 + f64::from(tenth) * 0.1;
        let r = run_toml(
            "halt sweep",
            &format!(
                r#"
duration = "70s"
[lift]
start_mm = 0.0
[[event]]
at = "5s"
press = "cabin:3"
[[event]]
at = "{open_at}s"
door = "open"
[[event]]
at = "{close}s"
door = "closed"
[[event]]
at = "45s"
press = "cabin:4"
"#,
                close = open_at + 3.0
            ),
        );
        assert_no_violations(&r);
        assert!(
            r.safety.trips.is_empty(),
            "door at {open_at}: {:?}",
            r.safety.trips
        );
        assert_arrivals_agree(&r);
        assert_eq!(
            served(&r),
            [(3, "cabin".into()), (4, "cabin".into())],
            "door at {open_at}"
        );
    }
}

#[test]
fn stop_during_initialisation_then_a_cabin_call_initialises_and_serves() {
    let r = run_toml(
        "STOP while initialising",
        r#"
duration = "80s"
[lift]
start_mm = 400.0
[[event]]
at = "6.5s"
press = "stop"
[[event]]
at = "40s"
press = "cabin:3"
"#,
    );
    assert_no_violations(&r);
    assert!(r.safety.trips.iter().all(|t| !matches!(
        t.cause,
        TripCause::Logic(
            Cause::OvertravelTripped { .. }
                | Cause::OvertravelContactOpen
                | Cause::K1Opened(K1Cause::Overtravel { .. } | K1Cause::OvertravelResetPending)
        )
    )));
    assert!(r.initialised_at_s.is_some_and(|t| t > 40.0));
    assert_arrivals_agree(&r);
    assert_eq!(served(&r), [(3, "cabin".into())]);
}

#[test]
fn starts_beyond_what_initialisation_can_find_recover_by_the_documented_procedure() {
    // Below floor 1's vane the run down meets the bottom overtravel sensor (nothing tells
    // -50 mm from 1250 mm, where the same run is right); beyond a sensor K1 never closes. Both
    // recover as at the lab: crank back, safety reset, and the controller initialises.
    for (start, crank) in [(-45.0, 40.0), (-70.0, 60.0), (1290.0, -60.0)] {
        let r = run_toml(
            "start beyond",
            &format!(
                r#"
duration = "70s"
[lift]
start_mm = {start}
[[event]]
at = "4s"
crank_mm = {crank}
[[event]]
at = "8s"
reset = true
[[event]]
at = "9s"
ack = true
[[event]]
at = "40s"
press = "cabin:3"
"#
            ),
        );
        assert_no_violations(&r);
        assert!(
            !has_event(&r, |e| matches!(e, LogEvent::Refused(_))),
            "start {start}: {}",
            r.to_text()
        );
        assert!(
            r.initialised_at_s.is_some(),
            "start {start}: {}",
            r.to_text()
        );
        assert_arrivals_agree(&r);
        assert_eq!(served(&r), [(3, "cabin".into())], "start {start}");
    }
}

#[test]
fn the_scan_range_initialises_everywhere_and_sees_every_short_press() {
    // The limits of the documented PLC scan range (1..20 ms): initialisation from heights
    // around every vane and a 300 ms press at any phase of the 14-scan cabin word.
    for scan in ["1ms", "20ms"] {
        for (start, press_at) in [
            (-35.0, 5.000),
            (20.0, 5.047),
            (380.0, 5.113),
            (650.0, 5.181),
            (1000.0, 5.257),
            (1250.0, 5.311),
            (0.0, 5.383),
            (1200.0, 5.419),
        ] {
            let r = run_toml(
                "scan range",
                &format!(
                    r#"
duration = "75s"
[lift]
start_mm = {start}
[controller]
scan = "{scan}"
[[event]]
at = "30s"
press = "cabin:3"
[[event]]
at = "{press}s"
press = "hall-up:2"
"#,
                    press = press_at + 35.0
                ),
            );
            assert_no_violations(&r);
            assert!(
                r.safety.trips.is_empty(),
                "{scan} from {start}: {:?}",
                r.safety.trips
            );
            let floors: Vec<u8> = r.served.iter().map(|s| s.floor).collect();
            assert_eq!(floors, [3, 2], "{scan} from {start}:\n{}", r.to_text());
        }
    }
}

#[test]
fn a_scan_beyond_20_ms_is_refused_with_the_reason() {
    let e = rig::scenario::Scenario::from_toml("s.toml", "[controller]\nscan = \"30ms\"\n")
        .expect_err("30 ms");
    let text = e.to_string();
    assert!(
        text.contains("controller.scan") && text.contains("1..20 ms"),
        "{text}"
    );
}

#[test]
fn a_new_initialisation_after_a_bus_fault_never_moves_with_the_door_open() {
    // Door open from power-on, the converter I/O module away and back: the initialisation that
    // follows the bus fault must hold for the door from its first scan.
    let r = run_toml(
        "door open through a bus fault",
        r#"
duration = "70s"
[lift]
start_mm = 800.0
door = "open"
[controller]
scan = "20ms"
[[event]]
at = "51993ms"
fault = { kind = "slave-offline", slave = 7 }
[[event]]
at = "63629ms"
fault = { kind = "slave-online", slave = 7 }
"#,
    );
    assert_no_violations(&r);
    assert_eq!(r.final_state.position_mm, 800.0);
    assert!(event_after(&r, program(Ctl::InitHeld(HaltReason::DoorOpen)), 63.0).is_some());
}

#[test]
fn a_run_onto_the_bottom_sensor_after_the_repairs_is_rescued_by_a_second_round() {
    // Campaign 12, run 3764: the cabin held overloaded at floor 1's level while its left vane
    // sensor was stuck off. The repair and the load falling come at the same moment; the hold
    // ends and initialisation restarts from the PLC's reading of a few ms before, the left
    // sensor off, and runs down onto the bottom sensor (safely: K1 opens). The operator's first
    // rescue comes while K1 is still closed and is refused; the second one, after the trip,
    // cranks the cabin back, and the reset brings service back.
    let r = run_toml(
        "run onto the bottom sensor after the repairs",
        r#"
duration = "70s"
[lift]
start_mm = 0.0
load = "overloaded"
[[event]]
at = "5s"
fault = { kind = "vane-stuck-off", sensor = "left" }
[[event]]
at = "11s"
fault = { kind = "vane-repaired", sensor = "left" }
[[event]]
at = "11s"
load = "loaded"
[[event]]
at = "13s"
rescue = true
[[event]]
at = "19s"
ack = true
[[event]]
at = "20s"
reset = true
[[event]]
at = "23s"
rescue = true
[[event]]
at = "31s"
ack = true
[[event]]
at = "32s"
reset = true
[[event]]
at = "33s"
press = "cabin:4"
"#,
    );
    assert_no_violations(&r);
    let refused = event_at(&r, |e| *e == LogEvent::Rescue(Rescue::K1Closed)).expect("refused");
    let tripped = event_at(
        &r,
        safety_event(|c| matches!(c, Cause::K1Opened(K1Cause::Overtravel { bottom: true, .. }))),
    )
    .expect("trip");
    let cranked = event_at(
        &r,
        |e| matches!(e, LogEvent::Rescue(Rescue::Crank(mm)) if *mm > 0.0),
    )
    .expect("second rescue");
    assert!(refused < tripped && tripped < cranked, "{}", r.to_text());
    assert!(r.initialised_at_s.is_some_and(|t| t > 32.0));
    assert_arrivals_agree(&r);
    assert_eq!(served(&r), [(4, "cabin".into())]);
}

#[test]
fn a_monitor_trip_from_line_noise_halts_safely_until_the_operator_resets() {
    // Campaign 12, run 6768 (its noise now 2e-3 with seed 145, see the data file): with the
    // line noise still present after every repair, the top overtravel sensor's codes miss the
    // monitor's tolerance time once. The safety logic
    // counts the unread sensor as tripped and opens K1; the cabin halts between floors and
    // waits for the operator, whose acknowledge and reset bring it back into service.
    let r = run_toml(
        "noise trip after the recovery",
        include_str!("data/noise-trip-after-recovery.toml"),
    );
    assert_no_violations(&r);
    let (dropped, opened) = sensor_12_dropped_and_k1_opened(&r);
    assert!(opened - dropped < 0.01, "{}", r.to_text());
    assert!(
        event_after(
            &r,
            |e: &LogEvent| matches!(e, LogEvent::Controller(Ctl::Halted(_))),
            opened
        )
        .is_some(),
        "{}",
        r.to_text()
    );
    let reset = event_after(&r, safety_event(|c| *c == Cause::OvertravelReset), opened)
        .expect("the operator's reset");
    assert!(reset >= 151.0);
    assert!(event_after(&r, safety_event(|c| *c == Cause::K1Closed), reset - 0.001).is_some());
    let last = r.served.last().expect("a call served");
    assert!(last.served_at_s > reset, "{last:?}");
    assert_eq!(r.final_state.state, Some(controller::State::AtFloor));
}

/// When the monitor first dropped sensor 12, and when K1 opened after it.
fn sensor_12_dropped_and_k1_opened(r: &Report) -> (f64, f64) {
    let dropped = event_at(r, |e| {
        matches!(e, LogEvent::MonitorDrop { address: 12, .. })
    })
    .expect("sensor 12 dropped");
    let opened = event_after(
        r,
        safety_event(|c| matches!(c, Cause::K1Opened(_))),
        dropped,
    )
    .expect("K1 opens");
    (dropped, opened)
}

#[test]
fn an_attendant_answers_a_monitor_trip_from_line_noise_after_the_repairs() {
    // The same run as the campaign generates it now: with the repairs at 93 s an attendant
    // takes over (`attend`) in place of the operator's fixed rounds and late reset. The monitor
    // trip after the probe is answered 2 s later: a round of rescue (none needed), acknowledge
    // 6 s and reset 7 s after it; the lift is back in service and serves the last hall call.
    let mut sc = rig::scenario::Scenario::from_toml(
        "noise trip, attended",
        include_str!("data/noise-trip-after-recovery.toml"),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let repairs = asi_phy::SimTime::from_millis(93_000);
    sc.events.retain(|e| {
        e.at < repairs || !matches!(e.action, Action::Rescue | Action::Ack | Action::Reset)
    });
    sc.events.push(rig::scenario::ScenarioEvent {
        at: repairs,
        action: Action::Attend,
        line: 0,
    });
    sc.events.sort_by_key(|e| e.at);
    let r = run(sc);
    assert_no_violations(&r);
    let (_, opened) = sensor_12_dropped_and_k1_opened(&r);
    let round = event_after(&r, |e| matches!(e, LogEvent::AttendantRound { .. }), opened)
        .expect("the attendant's round");
    assert!((round - opened - 2.0).abs() < 0.02, "{}", r.to_text());
    let reset = event_after(&r, safety_event(|c| *c == Cause::OvertravelReset), round)
        .expect("the attendant's reset");
    // The reset is pressed 7 s after the round begins and taken on its release, 100 ms on.
    assert!((reset - round - 7.1).abs() < 0.02, "{}", r.to_text());
    assert!(event_after(&r, safety_event(|c| *c == Cause::K1Closed), reset - 0.001).is_some());
    // The first round answered the group error of the safe-link drop at 84 s.
    assert_eq!(r.safety.attendant_rounds, 2);
    assert_eq!(r.final_state.state, Some(controller::State::AtFloor));
    assert!(
        r.passengers.iter().all(|p| p.served_at_s.is_some()),
        "{}",
        r.to_text()
    );
}

/// The judge adds up the time the cabin moves with the door open over any 10 s (docs/safety.md).
/// The door opened twice in one journey, 6 s apart (campaign seed 2026, run 30): each opening
/// costs the built-in program about 0.55 s of motion (the cabin word, a scan, the converter's
/// ramp), 1.07 s together. After a door opening halts the cabin, it now waits 11 s before the
/// next run, so the second opening finds it at rest.
#[test]
fn a_door_opened_twice_in_one_journey_is_not_a_second_of_motion() {
    let r = run_toml(
        "door twice during travel",
        r#"
duration = "40s"
[lift]
start_mm = 400.0
load = "full"
[bus]
pulse_error_rate = 0.001
[[event]]
at = "12612ms"
press = "hall-up:2"
[[event]]
at = "12990ms"
door = "open"
[[event]]
at = "16748ms"
door = "closed"
[[event]]
at = "18918ms"
door = "open"
[[event]]
at = "20s"
door = "closed"
"#,
    );
    assert_no_violations(&r);
    let halted = event_at(&r, program(Ctl::Halted(HaltReason::DoorOpen))).expect("halt");
    let continued = event_after(&r, program(Ctl::Continued), halted).expect("on");
    assert!(continued >= halted + 11.0, "{}", r.to_text());
    assert_eq!(served(&r), [(2, "hall".into())]);
}

/// STOP pressed while a bus fault held the cabin between floors (campaign seed 2026, run 134):
/// when the bus came back the program resumed the journey to the next floor, a run started
/// under STOP. Now it waits for the circuit's restart.
#[test]
fn a_cabin_held_by_a_bus_fault_starts_no_run_under_stop() {
    let r = run_toml(
        "STOP in a bus fault",
        r#"
duration = "49s"
[lift]
floors = 2
start_mm = 52.1
load = "loaded"
[[event]]
at = "38582ms"
press = "cabin:2"
[[event]]
at = "41705ms"
fault = { kind = "slave-offline", slave = 10 }
[[event]]
at = "41932ms"
press = "stop"
hold = "1466ms"
[[event]]
at = "47421ms"
fault = { kind = "slave-online", slave = 10 }
"#,
    );
    assert_no_violations(&r);
    assert!(has_event(&r, program(Ctl::InitHeld(HaltReason::Stop))));
    assert!(!r.final_state.moving, "{}", r.to_text());
}

/// The level sensor stuck off while the cabin brakes for the floor STOP chose (campaign seed
/// 2026, run 45): the program ran on to the vane's far end and stopped 42 mm past the level.
/// Its level watchdog now stops the cabin inside the vane.
#[test]
fn a_level_sensor_lost_while_braking_for_stop_stops_the_cabin_inside_the_vane() {
    let r = run_toml(
        "level sensor lost under STOP",
        r#"
duration = "107s"
algorithm = "collective"
[lift]
start_mm = 400.0
[controller]
scan = "2ms"
[[event]]
at = "44366ms"
press = "stop"
hold = "310ms"
[[event]]
at = "51610ms"
press = "hall-down:4"
[[event]]
at = "58407ms"
press = "cabin:2"
[[event]]
at = "95454ms"
press = "hall-up:1"
hold = "539ms"
[[event]]
at = "97389ms"
press = "stop"
hold = "1887ms"
[[event]]
at = "102657ms"
fault = { kind = "vane-stuck-off", sensor = "left" }
"#,
    );
    assert_no_violations(&r);
    assert!(
        has_event(
            &r,
            program(Ctl::PositionLost {
                why: LostReason::MissedLevel
            })
        ),
        "the missed level is reported: {}",
        r.to_text()
    );
    assert!(
        r.final_state.position_mm > 765.0 && r.final_state.position_mm < 800.0,
        "{}",
        r.to_text()
    );
}

/// The operator's reset closes K1 during a crank turn under STOP (campaign seed 13, run 801):
/// the converter takes the moving cabin over and brings it to rest. No run was started; the
/// judge counts the motion as powered and under way (docs/safety.md).
#[test]
fn power_taking_over_a_crank_turn_under_stop_is_no_new_run() {
    let r = run_toml(
        "crank and reset under STOP",
        r#"
duration = "40s"
[lift]
start_mm = 0.0
load = "overloaded"
[[event]]
at = "17063ms"
load = "full"
[[event]]
at = "32780ms"
press = "stop"
hold = "1743ms"
[[event]]
at = "33424ms"
crank_mm = 18.2
[[event]]
at = "34104ms"
reset = true
"#,
    );
    assert_no_violations(&r);
    assert!(has_event(&r, safety_event(|c| *c == Cause::K1Closed)));
}
