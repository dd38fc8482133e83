//! What people operate and see (docs/lab-bus.md, §4): presses with a duration and their release
//! edges, STOP's three contacts, door, load, displays; and inputs that make no sense are
//! refused with an error, never a panic.

use crate::common::*;
use asi_phy::{SimDuration, SimTime};
use lab::{DisplayWord, DisplayWordError};
use lift_model::{
    Button, ContactFault, DisplayId, DisplayState, Lift, LiftConfig, LoadLevel, PlantError,
    PlantEventKind, StopChannel,
};
use proptest::prelude::*;

#[test]
fn a_press_holds_from_its_start_until_the_nanosecond_before_its_end() {
    let mut lift = lift_at(0.0);
    ok(lift.press(secs(1.0), Button::Cabin(3), SimDuration::from_millis(200)));
    assert!(lift.is_pressed(Button::Cabin(3)));
    assert!(!lift.is_pressed(Button::Cabin(2)));
    assert_eq!(lift.next_event(), Some(secs(1.2)));
    assert!(advance(&mut lift, secs(1.2) - SimDuration::from_nanos(1)).is_empty());
    assert!(lift.is_pressed(Button::Cabin(3)));
    let released = advance(&mut lift, secs(5.0));
    assert_eq!(released.len(), 1);
    assert_eq!(released[0].at, secs(1.2));
    assert_eq!(
        released[0].kind,
        PlantEventKind::Released {
            button: Button::Cabin(3)
        }
    );
    assert!(!lift.is_pressed(Button::Cabin(3)));
}

#[test]
fn a_second_press_extends_a_held_button_and_a_held_one_stays_until_released() {
    let mut lift = lift_at(0.0);
    ok(lift.press(secs(0.0), Button::HallUp(1), SimDuration::from_secs(1)));
    ok(lift.press(secs(0.5), Button::HallUp(1), SimDuration::from_secs(1)));
    // A shorter press inside a longer one does not shorten it.
    ok(lift.press(secs(0.6), Button::HallUp(1), SimDuration::from_millis(1)));
    let events = advance(&mut lift, secs(3.0));
    assert_eq!(events.len(), 1);
    assert_eq!(events[0].at, secs(1.5));

    ok(lift.press(secs(3.0), Button::Bell, SimDuration::MAX));
    assert_eq!(lift.next_event(), None);
    advance(&mut lift, secs(3600.0));
    assert!(lift.is_pressed(Button::Bell));
    ok(lift.release(secs(3600.0), Button::Bell));
    assert!(!lift.is_pressed(Button::Bell));
}

#[test]
fn presses_ending_together_are_reported_in_one_instant_in_button_order() {
    let mut lift = lift_at(0.0);
    let d = SimDuration::from_millis(100);
    ok(lift.press(SimTime::ZERO, Button::Stop, d));
    ok(lift.press(SimTime::ZERO, Button::HallDown(4), d));
    ok(lift.press(SimTime::ZERO, Button::Cabin(1), d));
    let kinds: Vec<PlantEventKind> = advance(&mut lift, secs(1.0))
        .iter()
        .map(|e| e.kind)
        .collect();
    assert_eq!(
        kinds,
        [Button::Cabin(1), Button::HallDown(4), Button::Stop]
            .map(|button| PlantEventKind::Released { button })
    );
}

#[test]
fn stop_opens_both_nc_channels_and_closes_the_standard_contact() {
    let mut lift = lift_at(0.0);
    assert_eq!(lift.stop_channels(), [true, true]);
    assert!(!lift.stop_pressed());
    ok(lift.press(secs(1.0), Button::Stop, SimDuration::from_secs(2)));
    assert_eq!(lift.stop_channels(), [false, false]);
    assert!(lift.stop_pressed());
    // A welded channel stays closed: the discrepancy the safety logic must catch.
    ok(lift.set_stop_channel_fault(secs(1.5), StopChannel::Two, ContactFault::StuckClosed));
    assert_eq!(lift.stop_channels(), [false, true]);
    advance(&mut lift, secs(3.0));
    assert_eq!(lift.stop_channels(), [true, true]);
    ok(lift.set_stop_channel_fault(secs(3.0), StopChannel::One, ContactFault::StuckOpen));
    assert_eq!(lift.stop_channels(), [false, true]);
}

#[test]
fn door_and_load_read_back_as_set() {
    let mut lift = lift_at(0.0);
    assert!(lift.door_closed());
    assert_eq!(lift.load(), LoadLevel::Empty);
    ok(lift.set_door(secs(1.0), false));
    ok(lift.set_load(secs(1.0), LoadLevel::Overloaded));
    assert!(!lift.door_closed());
    assert_eq!(lift.load().code(), 3);
    assert_eq!(
        [LoadLevel::Empty, LoadLevel::Loaded, LoadLevel::Full].map(LoadLevel::code),
        [0, 1, 2]
    );
}

#[test]
fn the_displays_show_the_last_complete_word_or_say_it_is_bad() {
    let mut lift = lift_at(0.0);
    assert_eq!(lift.display(DisplayId::Cabin), Some(DisplayState::Blank));
    let word = DisplayWord {
        floor: 2,
        up: true,
        down: false,
        moving: true,
        fault: false,
    };
    let raw = word.encode().unwrap_or(0);
    ok(lift.set_display(secs(1.0), DisplayId::Floor(4), raw));
    ok(lift.set_display(secs(1.0), DisplayId::Cabin, raw));
    assert_eq!(
        lift.display(DisplayId::Floor(4)),
        Some(DisplayState::Showing(word))
    );
    assert_eq!(lift.display(DisplayId::Floor(3)), Some(DisplayState::Blank));
    assert_eq!(word.to_string(), "2 ▲ moving");
    // One bit flipped on the way: the display says so instead of showing another floor.
    ok(lift.set_display(secs(2.0), DisplayId::Cabin, raw ^ 0b10_0000));
    assert_eq!(
        lift.display(DisplayId::Cabin),
        Some(DisplayState::BadWord {
            raw: raw ^ 0b10_0000,
            error: DisplayWordError::Parity {
                raw: raw ^ 0b10_0000
            }
        })
    );
    assert_eq!(lift.display(DisplayId::Floor(5)), None);
    assert_eq!(
        lift.set_display(secs(2.0), DisplayId::Floor(0), raw),
        Err(PlantError::NoSuchDisplay {
            floor: 0,
            floors: 4
        })
    );
}

#[test]
fn buttons_the_lift_does_not_have_are_refused_by_name() {
    let mut lift = lift_at(0.0);
    let d = SimDuration::from_millis(100);
    for button in [
        Button::HallUp(4),
        Button::HallDown(1),
        Button::Cabin(0),
        Button::Cabin(5),
    ] {
        assert_eq!(
            lift.press(SimTime::ZERO, button, d),
            Err(PlantError::NoSuchButton { button, floors: 4 })
        );
        assert!(!lift.is_pressed(button));
    }
    let message = lift
        .press(SimTime::ZERO, Button::HallUp(4), d)
        .err()
        .map(|e| e.to_string());
    assert_eq!(
        message.as_deref(),
        Some("the 4-floor lift has no hall up button at floor 4 (there is no hall up at the top floor and no hall down at floor 1)")
    );
    assert_eq!(
        lift.press(SimTime::ZERO, Button::Bell, SimDuration::ZERO),
        Err(PlantError::EmptyPress {
            button: Button::Bell
        })
    );
}

#[test]
fn time_never_runs_backwards() {
    let mut lift = lift_at(0.0);
    advance(&mut lift, secs(2.0));
    let err = PlantError::TimeReversed {
        now: secs(1.0),
        plant_time: secs(2.0),
    };
    assert_eq!(lift.set_door(secs(1.0), false).err(), Some(err.clone()));
    assert_eq!(lift.advance_to(secs(1.0)).err(), Some(err.clone()));
    assert!(lift.door_closed());
    assert_eq!(
        err.to_string(),
        "input at 1.000000000 s is earlier than the plant's time 2.000000000 s: simulated time only moves forward"
    );
}

#[test]
fn an_input_brings_the_plant_to_its_time_and_queues_the_edges_on_the_way() {
    let mut lift = driving(0.0, true, 10_000);
    // No advance_to: the bell press at 10 s carries the plant past floor 2's vane.
    ok(lift.press(secs(10.0), Button::Bell, SimDuration::from_secs(1)));
    assert_eq!(lift.now(), secs(10.0));
    let queued = advance(&mut lift, secs(10.0));
    assert_eq!(queued.len(), 7); // ramp end, 2 edges at floor 1, 4 at floor 2
    assert!(queued.windows(2).all(|w| w[0].at <= w[1].at));
}

/// One arbitrary thing a scenario might do.
#[derive(Clone, Debug)]
enum Action {
    Contactor(bool),
    Weld(bool),
    Converter(bool, bool, u16),
    ConverterFault(bool),
    Press(u8, u64),
    Release(u8),
    Crank(f64),
    Display(u8, u16),
    Door(bool),
}

fn action() -> impl Strategy<Value = Action> {
    prop_oneof![
        any::<bool>().prop_map(Action::Contactor),
        any::<bool>().prop_map(Action::Weld),
        (any::<bool>(), any::<bool>(), any::<u16>())
            .prop_map(|(r, u, s)| Action::Converter(r, u, s)),
        any::<bool>().prop_map(Action::ConverterFault),
        (any::<u8>(), any::<u64>()).prop_map(|(b, d)| Action::Press(b, d)),
        any::<u8>().prop_map(Action::Release),
        prop_oneof![
            any::<f64>(),
            -2000.0..2000.0f64,
            Just(f64::NAN),
            Just(f64::INFINITY),
            Just(-1e308)
        ]
        .prop_map(Action::Crank),
        (any::<u8>(), any::<u16>()).prop_map(|(d, w)| Action::Display(d, w)),
        any::<bool>().prop_map(Action::Door),
    ]
}

fn button(n: u8) -> Button {
    match n % 5 {
        0 => Button::Cabin(n / 5 % 8),
        1 => Button::HallUp(n / 5 % 8),
        2 => Button::HallDown(n / 5 % 8),
        3 => Button::Bell,
        _ => Button::Stop,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Whatever a scenario does, the plant answers with a result, never a panic, and the
    /// cabin stays between the mechanical ends with time moving forward.
    #[test]
    fn no_input_sequence_panics_or_leaves_the_shaft(
        floors in 2u8..=24,
        start in 0.0..1.0f64,
        script in prop::collection::vec((0u64..5_000_000_000, action()), 1..40),
    ) {
        let config = {
            let mut cfg = LiftConfig::default();
            cfg.floors = floors;
            cfg
        };
        let bottom = config.end_position_mm(lift_model::End::Bottom);
        let top = config.end_position_mm(lift_model::End::Top);
        let config = {
            let mut value = config;
            value.initial_position_mm = bottom + start * (top - bottom);
            value
        };
        let mut lift = Lift::new(config).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let mut now = SimTime::ZERO;
        let mut last_event = SimTime::ZERO;
        for (gap, action) in script {
            now += SimDuration::from_nanos(gap);
            let _ = match action {
                Action::Contactor(on) => lift.set_contactor(now, on),
                Action::Weld(on) => lift.set_contactor_welded(now, on),
                Action::Converter(r, u, s) => lift.set_converter(now, r, u, s),
                Action::ConverterFault(on) => lift.set_converter_fault(now, on),
                Action::Press(b, d) => lift.press(now, button(b), SimDuration::from_nanos(d)),
                Action::Release(b) => lift.release(now, button(b)),
                Action::Crank(mm) => lift.crank(now, mm),
                Action::Display(d, w) => lift.set_display(now, DisplayId::Floor(d % 26), w),
                Action::Door(closed) => lift.set_door(now, closed),
            };
            let events: Vec<_> = lift
                .advance_to(now)
                .map_err(|e| TestCaseError::fail(e.to_string()))?
                .collect();
            for e in events {
                prop_assert!(e.at >= last_event && e.at <= now);
                last_event = e.at;
            }
            let x = lift.position_mm();
            prop_assert!(x.is_finite() && x >= bottom && x <= top, "{}", x);
            prop_assert!(lift.next_event().is_none_or(|t| t >= now));
        }
    }
}
