//! End-to-end runs of the whole rig: AS-i bus at pulse level with the lab lift's slaves, the
//! lift plant, the PLC program and the safety logic on one simulated clock. Each test runs a
//! scenario (most of them the files in `scenarios/`, which users can run themselves) and
//! asserts its report.

use asi_lift_tests::*;
use asi_phy::{SimDuration, SimTime};
use controller::{HaltReason, LostReason, ProgramEventKind as Ctl};
use lift_model::Button;
use lift_model::End;
use rig::report::{LogEvent, PlantLog, TripCause};
use rig::scenario::{Action, Scenario, ScenarioEvent};
use safety::kl6904::connection::{ConnDiag, ConnEvent};
use safety::kl6904::logic::LogicEventKind;
use safety::lift::K1Cause;
use safety::LiftSafetyCause as Cause;

fn at(s: f64) -> SimTime {
    SimTime::ZERO + SimDuration::from_secs_f64(s).expect("time")
}

fn press(s: f64, button: Button) -> ScenarioEvent {
    ScenarioEvent {
        at: at(s),
        action: Action::Press {
            button,
            hold: SimDuration::from_millis(300),
        },
        line: 0,
    }
}

#[test]
fn initialises_from_several_heights_including_floor_1() {
    // Level at floor 1 (which the lift thesis' routine cannot handle), inside floor 1's vane above
    // and below level, between floors, level at floors 2 and 4, inside floor 3's vane.
    for start in [0.0, 30.0, -30.0, 650.0, 400.0, 1200.0, 1000.0, 830.0] {
        let sc = Scenario {
            name: format!("init from {start} mm"),
            start_mm: start,
            duration: SimDuration::from_secs(40),
            ..Scenario::defaults()
        };
        let r = run(sc);
        assert_no_violations(&r);
        let init = r
            .initialised_at_s
            .unwrap_or_else(|| panic!("from {start} mm: not initialised\n{}", r.to_text()));
        // Down at 68.8 mm/s at most 1.2 m, plus the slow phases: well under 30 s.
        assert!(init < 30.0, "from {start} mm: initialised only at {init} s");
        let first = &r.arrivals[0];
        assert_eq!(first.floor, 1, "from {start} mm");
        assert!(
            first.position_mm.abs() <= 10.0,
            "from {start} mm: {} mm off level",
            first.position_mm
        );
        assert_eq!(r.final_state.state, Some(controller::State::AtFloor));
        assert!(
            r.safety.trips.is_empty(),
            "from {start} mm: {:?}",
            r.safety.trips
        );
    }
}

#[test]
fn the_demo_serves_a_cabin_call_and_a_hall_call_stored_meanwhile() {
    let r = run(Scenario::demo().expect("the demo"));
    assert_no_violations(&r);
    assert_eq!(stops(&r), [1, 3, 4, 1]);
    assert_eq!(
        served(&r),
        [(3, "cabin".into()), (4, "hall".into()), (1, "cabin".into())]
    );
    for a in &r.arrivals {
        let level = (a.floor as f64 - 1.0) * 400.0;
        assert!((a.position_mm - level).abs() <= 10.0, "{a:?}");
    }
    // The hall call (pressed at 20 s) waits for the cabin call (pressed at 15 s).
    let hall = &r.served[1];
    assert_eq!(hall.requested_at_s, 20.0);
    assert!(hall.served_at_s > r.served[0].served_at_s);
    assert!(r.bus.transactions > 500_000);
    assert_eq!(r.bus.repeats, 0);
    // 11 slaves in the lab bus: (n + 2) · 154 µs.
    assert_eq!(r.bus.cycle_us.mean, 13.0 * 154.0);
}

#[test]
fn cabin_calls_are_served_in_fifo_order_then_the_hall_call() {
    let r = run_file("fifo");
    assert_no_violations(&r);
    // Pressed 3, 2, 4 (2 would be nearer after 3, but FIFO keeps the order); then the hall call
    // at floor 1, stored while the cabin calls were served.
    assert_eq!(stops(&r), [1, 3, 2, 4, 1]);
    assert_eq!(
        served(&r),
        [
            (3, "cabin".into()),
            (2, "cabin".into()),
            (4, "cabin".into()),
            (1, "hall".into())
        ]
    );
    assert!(
        r.served[3].requested_at_s < r.served[0].served_at_s,
        "the hall call was pressed early"
    );
}

#[test]
fn stop_while_moving_stops_at_the_next_floor_and_resumes_only_on_a_cabin_request() {
    let r = run_file("stop");
    assert_no_violations(&r);
    // Heading up from 1 to 4, STOP at 18 s between floors 1 and 2: the cabin stops at 2.
    assert_eq!(stops_between(&r, 0.0, 50.0), [1, 2]);
    assert!(r.arrivals[1].at_s < 25.0);
    assert!(has_event(
        &r,
        program(Ctl::StopDemanded {
            dropped: Some(4),
            stop_at: 2
        })
    ));
    // The safety logic demanded the stop at once and took drive power after its delay.
    assert!(
        r.safety
            .trips
            .iter()
            .any(|t| t.at_s == 18.0
                && matches!(t.cause, TripCause::Logic(Cause::StopDemanded { .. })))
    );
    let k1_off =
        event_at(&r, safety_event(|c| matches!(c, Cause::K1Opened(_)))).expect("K1 opened");
    assert!((27.0..27.2).contains(&k1_off), "{k1_off}");
    // The hall call at 40 s does not resume service; the cabin request at 50 s does.
    assert!(event_at(&r, program(Ctl::Resumed)).is_some_and(|t| t > 50.0));
    assert_eq!(stops_between(&r, 50.0, 90.0), [4, 3]);
    assert_eq!(served(&r), [(4, "cabin".into()), (3, "hall".into())]);
    assert_eq!(
        r.served[0].requested_at_s, 50.0,
        "the dropped press at 12 s is not the request"
    );
}

#[test]
fn stop_during_initialisation_holds_it_until_a_cabin_request() {
    let mut sc = Scenario {
        name: "stop during initialisation".into(),
        start_mm: 650.0,
        duration: SimDuration::from_secs(70),
        ..Scenario::defaults()
    };
    sc.events = vec![
        ScenarioEvent {
            at: at(3.0),
            action: Action::Press {
                button: Button::Stop,
                hold: SimDuration::from_secs(1),
            },
            line: 0,
        },
        press(25.0, Button::Cabin(3)),
    ];
    let r = run(sc);
    assert_no_violations(&r);
    // K1 opens after the STOP delay and stays open: no restart without a cabin request.
    let off = event_at(&r, safety_event(|c| matches!(c, Cause::K1Opened(_)))).expect("K1 opened");
    assert!((12.0..12.2).contains(&off), "{off}");
    let on_again =
        event_after(&r, safety_event(|c| *c == Cause::K1Closed), off).expect("K1 closed again");
    assert!(on_again > 25.0, "restarted without a request at {on_again}");
    assert!(r.initialised_at_s.is_some_and(|t| t > 25.0));
    assert_eq!(stops(&r), [1, 3]);
}

#[test]
fn overload_blocks_departure_until_the_load_drops() {
    let r = run_file("overload");
    assert_no_violations(&r);
    assert_eq!(stops_between(&r, 0.0, 30.0), [1]);
    assert!(has_event(&r, program(Ctl::OverloadFault)));
    assert!(r
        .safety
        .trips
        .iter()
        .any(|t| t.cause == TripCause::Logic(Cause::K1Opened(K1Cause::Overloaded))));
    let departs = event_at(&r, program(Ctl::Departed { from: 1, to: 3 })).expect("departs");
    assert!((30.0..31.0).contains(&departs), "{departs}");
    assert_eq!(stops(&r), [1, 3]);
}

#[test]
fn an_open_door_blocks_departure() {
    let r = run_file("door");
    assert_no_violations(&r);
    let departs = event_at(&r, program(Ctl::Departed { from: 1, to: 2 })).expect("departs");
    assert!(
        (25.0..26.0).contains(&departs),
        "left at {departs} s with the door open until 25 s"
    );
    assert_eq!(stops(&r), [1, 2]);
}

#[test]
fn the_door_opened_during_travel_halts_the_cabin_between_floors() {
    let mut sc = Scenario {
        name: "door during travel".into(),
        start_mm: 0.0,
        duration: SimDuration::from_secs(60),
        ..Scenario::defaults()
    };
    sc.events = vec![
        press(5.0, Button::Cabin(3)),
        ScenarioEvent {
            at: at(13.0),
            action: Action::Door { closed: false },
            line: 0,
        },
        ScenarioEvent {
            at: at(20.0),
            action: Action::Door { closed: true },
            line: 0,
        },
    ];
    let r = run(sc);
    assert_no_violations(&r);
    let halted = event_at(&r, program(Ctl::Halted(HaltReason::DoorOpen))).expect("halted");
    assert!((13.0..13.5).contains(&halted), "{halted}");
    assert!(event_at(&r, program(Ctl::Continued)).is_some_and(|t| t >= 20.0));
    assert_eq!(stops(&r), [1, 3]);
}

#[test]
fn an_overtravel_trip_takes_power_until_cranked_back_reset_and_restarted() {
    let r = run_file("overtravel");
    assert_no_violations(&r);
    let trip = r
        .safety
        .trips
        .iter()
        .find(|t| {
            matches!(
                t.cause,
                TripCause::Logic(Cause::OvertravelTripped { bottom: true, .. })
            )
        })
        .expect("overtravel trip");
    // Cranked at 10 mm/s from where the cabin stood level: the sensor at -60 mm trips
    // (x + 60) / 10 s after 25 s.
    let x = r
        .arrivals
        .iter()
        .rfind(|a| a.at_s < 25.0)
        .expect("level at floor 1")
        .position_mm;
    let expected = 25.0 + (x + 60.0) / 10.0;
    assert!(
        (trip.at_s - expected).abs() < 0.01,
        "{} vs {expected}",
        trip.at_s
    );
    assert!(has_event(&r, |e| *e
        == LogEvent::Plant(PlantLog::OvertravelFree {
            end: End::Bottom
        })));
    assert!(
        event_after(&r, safety_event(|c| *c == Cause::OvertravelReset), 30.0)
            .is_some_and(|t| t > 55.0)
    );
    let k1_on = r
        .log
        .iter()
        .filter(|l| l.event == LogEvent::Safety(Cause::K1Closed))
        .map(|l| l.at_s)
        .next_back()
        .expect("K1 closed again");
    assert!(
        k1_on > 60.0,
        "power came back before the cabin request: {k1_on}"
    );
    // The crank moved the cabin out of floor 1's vane while the drive was off: the program no
    // longer trusts its count and finds floor 1 again before the journey.
    assert!(event_after(
        &r,
        program(Ctl::PositionLost {
            why: LostReason::MovedByHand
        }),
        25.0
    )
    .is_some_and(|t| t < 40.0));
    assert_eq!(stops_between(&r, 60.0, 120.0), [1, 3]);
}

#[test]
fn a_broken_vane_sensor_never_takes_the_cabin_to_an_overtravel_sensor() {
    let r = run_file("vane-sensor-broken");
    assert_no_violations(&r);
    // With the right sensor stuck off, floor 2's vane shows its short (left) sensor alone,
    // which no working pair shows at floors 2..4: the controller stops at once and
    // initialises again.
    let caught = event_at(
        &r,
        program(Ctl::PositionLost {
            why: LostReason::WrongVane,
        }),
    )
    .expect("caught");
    assert!((10.0..16.0).contains(&caught), "{caught}");
    // It hunts for floor 1 without ever reaching an overtravel sensor; K1 never drops.
    assert!(r.safety.trips.is_empty(), "{:?}", r.safety.trips);
    assert!(!has_event(&r, |e| {
        matches!(
            e,
            LogEvent::Plant(PlantLog::OvertravelTripped { .. } | PlantLog::OvertravelFree { .. })
        )
    }));
    // After the repair at 50 s: floor 1 found (a wrong guess is caught as the cabin leaves
    // the vane), then the interrupted journey to floor 4, then the call pressed meanwhile.
    let again = event_after(&r, program(Ctl::Initialised), 50.0).expect("again");
    assert!(again < 80.0, "{again}");
    assert_eq!(served(&r), [(4, "cabin".into()), (1, "cabin".into())]);
    let last_two: Vec<u8> = stops(&r).into_iter().rev().take(2).collect();
    assert_eq!(last_two, [1, 4]);
}

#[test]
fn a_lost_cabin_slave_stops_the_cabin_and_service_resumes_after_it_returns() {
    let r = run_file("lost-cabin-slave");
    assert_no_violations(&r);
    let lost = event_at(&r, program(Ctl::BusFault)).expect("reported");
    assert!((20.0..20.1).contains(&lost), "{lost}");
    // No stop while it is away, and no stop anywhere but at floors.
    assert_eq!(stops_between(&r, 20.0, 40.0), Vec::<u8>::new());
    assert!(r.bus.errors.no_response > 0);
    // Back at 40 s: the program initialises again and serves the interrupted call.
    assert!(event_after(
        &r,
        |e: &LogEvent| matches!(
            e,
            LogEvent::Controller(Ctl::InitStarted { .. } | Ctl::InitHeld(_))
        ),
        20.0
    )
    .is_some_and(|t| t > 40.0));
    assert_eq!(stops_between(&r, 40.0, 90.0), [1, 4]);
    assert_eq!(served(&r), [(4, "cabin".into())]);
}

#[test]
fn traffic_on_a_noisy_line_is_served_correctly_with_repeats() {
    let r = run_file("noise");
    assert_no_violations(&r);
    assert!(r.bus.repeats > 10_000, "{:?}", r.bus);
    let e = &r.bus.errors;
    assert!(
        e.checks.alternation > 0
            && e.checks.start_bit > 0
            && e.checks.pause > 0
            && e.checks.information > 0
            && e.checks.parity > 0
    );
    assert_eq!(
        served(&r),
        [
            (3, "cabin".into()),
            (2, "hall".into()),
            (4, "cabin".into()),
            (3, "hall".into()),
            (1, "cabin".into())
        ]
    );
    for a in &r.arrivals {
        assert!((a.position_mm - (a.floor as f64 - 1.0) * 400.0).abs() <= 10.0);
    }
    // Repeats stretch the cycle.
    assert!(r.bus.cycle_us.max > r.bus.cycle_us.mean);
}

#[test]
fn a_silent_safe_link_trips_com_err_and_needs_acknowledge_reset_and_a_request() {
    let r = run_file("safe-link-drop");
    assert_no_violations(&r);
    assert!(r.safety.trips.iter().any(|t| match &t.cause {
        TripCause::Logic(Cause::Logic(LogicEventKind::Connection {
            event: ConnEvent::Error { bit, .. },
            ..
        })) => *bit == ConnDiag::WATCHDOG,
        _ => false,
    }));
    let k1_off = event_at(
        &r,
        safety_event(|c| matches!(c, Cause::K1Opened(K1Cause::GroupError(e)) if e.com_err)),
    )
    .expect("K1 off");
    assert!((18.0..18.2).contains(&k1_off), "{k1_off}");
    assert!(has_event(&r, program(Ctl::Halted(HaltReason::NoPower))));
    assert!(event_at(
        &r,
        safety_event(|c| matches!(c, Cause::Logic(LogicEventKind::GroupAcknowledged { .. })))
    )
    .is_some_and(|t| t >= 30.0));
    // The cabin request at 35 s restarts the STOP circuit; the cabin completes its stop at
    // floor 2 and then serves the request.
    assert!(
        event_after(&r, safety_event(|c| *c == Cause::StopRestarted), 18.0)
            .is_some_and(|t| t > 35.0)
    );
    assert_eq!(stops_between(&r, 18.0, 90.0), [2, 4]);
}

#[test]
fn an_asi_power_fail_takes_the_lift_out_until_power_reset_and_request() {
    let r = run_file("power-fail");
    assert_no_violations(&r);
    assert!(event_at(&r, program(Ctl::BusFault)).is_some_and(|t| (15.0..15.1).contains(&t)));
    // The safety monitor loses the overtravel sensors' codes: the overtravel function trips.
    assert!(r
        .safety
        .trips
        .iter()
        .any(|t| (15.0..15.2).contains(&t.at_s)));
    assert!(event_after(&r, program(Ctl::Initialised), 15.0).is_some_and(|t| t > 25.0));
    assert_eq!(stops_between(&r, 30.0, 90.0), [2]);
}

#[test]
fn cranking_into_the_mechanical_end_is_a_violation() {
    // With power off after STOP, a technician cranks far below floor 1: the report must say so.
    let mut sc = Scenario {
        name: "crank into the end".into(),
        start_mm: 0.0,
        duration: SimDuration::from_secs(60),
        ..Scenario::defaults()
    };
    sc.events = vec![
        ScenarioEvent {
            at: at(5.0),
            action: Action::Press {
                button: Button::Stop,
                hold: SimDuration::from_secs(1),
            },
            line: 0,
        },
        ScenarioEvent {
            at: at(20.0),
            action: Action::Crank { mm: -200.0 },
            line: 0,
        },
    ];
    let r = run(sc);
    let kinds: Vec<&str> = r.violations.iter().map(|v| v.kind.name()).collect();
    assert_eq!(kinds, ["mechanical-end"], "{}", r.to_text());
    // -3.4 mm to the end at -140 mm at 10 mm/s: about 13.7 s after 20 s.
    assert!(
        (33.0..34.5).contains(&r.violations[0].at_s),
        "{}",
        r.violations[0].at_s
    );
}

#[test]
fn a_run_is_deterministic_and_the_seed_matters() {
    let a = run_file("noise").to_json().expect("serialises");
    let b = run_file("noise").to_json().expect("serialises");
    assert_eq!(a, b);
    let mut sc = scenario("noise");
    sc.seed = 8;
    let c = run(sc);
    assert_ne!(c.to_json().expect("serialises"), a);
    assert_no_violations(&c);
}

#[test]
fn the_collective_control_beats_fifo_on_the_busy_scenario() {
    let fifo = run_file("busy");
    let mut sc = scenario("busy");
    sc.algorithm = controller::Algorithm::Collective;
    let coll = run(sc);
    assert_no_violations(&fifo);
    assert_no_violations(&coll);
    let (f, c) = (fifo.waits(), coll.waits());
    assert_eq!((f.unserved, c.unserved), (0, 0));
    assert_eq!(fifo.passengers.len(), 64);
    assert!(
        c.all_mean_s < f.all_mean_s,
        "collective {c:?} vs fifo {f:?}"
    );
    assert!(
        c.hall_mean_s < f.hall_mean_s,
        "collective {c:?} vs fifo {f:?}"
    );
    println!("busy scenario, mean passenger wait: fifo {f:?}, collective {c:?}");
}

#[test]
fn a_held_hall_button_at_the_cabins_floor_is_served_once() {
    // The floor station reports a held button after every word (about every 50 ms); the PLC
    // takes it as one press, so the call is served once, not once per report.
    let sc = Scenario {
        name: "held hall button".into(),
        start_mm: 0.0,
        duration: SimDuration::from_secs(20),
        events: vec![ScenarioEvent {
            at: at(15.0),
            action: Action::Press {
                button: Button::HallUp(1),
                hold: SimDuration::from_secs(2),
            },
            line: 0,
        }],
        ..Scenario::defaults()
    };
    let r = run(sc);
    assert_no_violations(&r);
    assert_eq!(served(&r), [(1, "hall".to_string())], "{}", r.to_text());
}

#[test]
fn the_readme_example_scenario_runs_clean_and_ends_in_service() {
    // The scenario file of the book's "Scenario files" (book/src/scenarios.md, once README.md's),
    // with every key the format has: it must show what it says, so no violation, no event after
    // its end, and the lift serving again once everything is repaired.
    let readme = include_str!("../../book/src/scenarios.md");
    let start = readme.find("## Scenario files").expect("the section");
    let body = &readme[start..];
    let open = body.find("```toml\n").expect("the example") + "```toml\n".len();
    let close = body[open..].find("```").expect("its end") + open;
    let sc = rig::Scenario::from_toml("book example", &body[open..close])
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(sc.late_events().count(), 0);
    let r = run(sc);
    assert_no_violations(&r);
    let last = r.served.last().expect("a call served");
    assert_eq!(last.floor, 1);
    assert!(last.served_at_s > 120.0, "{}", r.to_text());
    assert_eq!(r.final_state.state, Some(controller::State::AtFloor));
    assert!(r.final_state.contactor_closed);
}
