//! Tests of reading and writing scenario files.

use super::*;

fn err(text: &str) -> String {
    Scenario::from_toml("t.toml", text)
        .expect_err("must fail")
        .to_string()
}

/// `[controller] program`: the file relative to the scenario's directory, read and compiled
/// with the scenario; written back as an absolute path, which reads back to the same program;
/// a missing file or a wrong program refused at the key.
#[test]
fn a_program_is_read_relative_to_the_scenario_and_written_back_absolute() {
    let dir = std::env::temp_dir().join(format!("asi-lift-program-key-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a directory");
    std::fs::write(
        dir.join("idle.st"),
        "PROGRAM Lift\nVAR Restart : BOOL; END_VAR\n  Restart := FALSE;\nEND_PROGRAM\n",
    )
    .expect("write");
    std::fs::write(dir.join("bad.st"), "PROGRAM Lift\n  x := 1;\nEND_PROGRAM\n").expect("write");
    let file = dir.join("sc.toml");
    let name = file.display().to_string();
    let sc = Scenario::from_toml(&name, "[controller]\nprogram = \"idle.st\"\n").expect("read");
    // A program on a library: both relative to the scenario, both written back absolute.
    std::fs::write(
        dir.join("lib.st"),
        "FUNCTION Off : BOOL\nVAR_INPUT x : BOOL; END_VAR\n  Off := FALSE;\nEND_FUNCTION\n",
    )
    .expect("write");
    std::fs::write(
        dir.join("uses.st"),
        "PROGRAM Lift\nVAR Restart : BOOL; END_VAR\n  Restart := Off(x := TRUE);\nEND_PROGRAM\n",
    )
    .expect("write");
    let with_lib = Scenario::from_toml(
        &name,
        "[controller]\nprogram = \"uses.st\"\nlibrary = [\"lib.st\"]\n",
    )
    .expect("read with a library");
    let lib_text = with_lib.to_toml();
    let lib_abs = std::path::absolute(dir.join("lib.st")).expect("absolute");
    assert!(
        lib_text.contains(&format!("library = [\"{}\"]", lib_abs.display())),
        "{lib_text}"
    );
    let lib_again = Scenario::from_toml("elsewhere/y.toml", &lib_text).expect("read back");
    let libs: Vec<&std::path::Path> = lib_again
        .program
        .as_ref()
        .expect("a program")
        .libraries()
        .collect();
    assert_eq!(libs, [lib_abs.as_path()]);
    assert!(
        Scenario::from_toml(&name, "[controller]\nprogram = \"uses.st\"\n")
            .expect_err("Off is the library's")
            .to_string()
            .contains("uses.st:3:14")
    );
    let p = sc.program.as_ref().expect("a program");
    assert_eq!(p.path(), dir.join("idle.st"));
    let text = sc.to_toml();
    let absolute = std::path::absolute(dir.join("idle.st")).expect("absolute");
    assert!(
        text.contains(&format!("program = \"{}\"", absolute.display())),
        "{text}"
    );
    // Read back from anywhere: the same program.
    let again = Scenario::from_toml("elsewhere/x.toml", &text).expect("read back");
    assert_eq!(
        again.program.as_ref().map(|p| p.path()),
        Some(absolute.as_path())
    );
    assert_eq!(
        Scenario {
            program: None,
            name: sc.name.clone(),
            ..again
        },
        Scenario {
            program: None,
            ..sc
        }
    );

    let missing = Scenario::from_toml(&name, "[controller]\nprogram = \"gone.st\"\n")
        .expect_err("no such file")
        .to_string();
    assert!(
        missing.starts_with(&format!(
            "{name}:2:11: controller.program: {}",
            dir.join("gone.st").display()
        )),
        "{missing}"
    );
    let wrong = Scenario::from_toml(&name, "[controller]\nprogram = \"bad.st\"\n")
        .expect_err("a wrong program")
        .to_string();
    assert!(
        wrong.contains("the program is refused (1 error)"),
        "{wrong}"
    );
    assert!(
        wrong.contains("bad.st:2:3: error: no variable is named `x`"),
        "{wrong}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn reads_the_example_of_the_issue() {
    let s = Scenario::from_toml(
        "cabin.toml",
        r#"
name = "cabin call"
seed = 1
duration = "90s"
algorithm = "fifo"
[lift]
floors = 4
start_mm = 650.0
load = "empty"
door = "closed"
[bus]
pulse_error_rate = 0.0
[[event]]
at = "20s"
press = "cabin:3"
[[event]]
at = "1.5min"
press = "stop"
hold = "2s"
[[event]]
at = "25s"
fault = { kind = "safe-link-drop", duration = "300ms" }
"#,
    )
    .expect("valid");
    assert_eq!(s.name, "cabin call");
    assert_eq!(s.duration, SimDuration::from_secs(90));
    assert_eq!(
        s.events.iter().map(|e| (e.at, e.line)).collect::<Vec<_>>(),
        [
            (SimTime::from_millis(20_000), 13),
            (SimTime::from_millis(25_000), 20),
            (SimTime::from_millis(90_000), 16)
        ]
    );
    assert_eq!(
        s.events[0].action,
        Action::Press {
            button: Button::Cabin(3),
            hold: DEFAULT_HOLD
        }
    );
}

#[test]
fn errors_name_the_file_the_line_and_the_field() {
    assert_eq!(
        err("name = \"x\"\n[lift]\nfloors = 4\nstart_mm = 9000.0\n"),
        "t.toml:4:12: lift.start_mm: 9000 mm lies outside the shaft between the mechanical ends (-140..1340 mm)"
    );
    assert_eq!(
        err("[[event]]\nat = \"5s\"\npress = \"cabin:7\"\n"),
        "t.toml:3:9: event[1].press: floor `7` does not exist: the lift has floors 1..4"
    );
    assert_eq!(
        err("[[event]]\nat = \"5 parsecs\"\nreset = true\n"),
        "t.toml:2:6: event[1].at: unknown unit `parsecs` in `5 parsecs`: use ns, us, ms, s, min or h"
    );
    assert!(err("[[event]]\nat = \"5s\"\n").starts_with("t.toml:1:1: event[1]: no action"));
    assert!(
        err("[[event]]\nat = \"5s\"\nreset = true\nack = true\n").contains("more than one action")
    );
    assert!(err("[[event]]\nat = \"5s\"\npress = \"hall-down:1\"\n")
        .contains("floor 1 has no down button"));
    assert!(
        err("[[event]]\nat = \"5s\"\nfault = { kind = \"slave-offline\" }\n")
            .contains("needs `slave = N`")
    );
    assert_eq!(
        err("[bus]\nextra_slaves = 21\n"),
        "t.toml:2:16: bus.extra_slaves: 21: the lab bus has room for 0..=20 more slaves"
    );
    assert!(
        err("algorithm = \"scan\"\n").contains("t.toml:1:13: algorithm: unknown algorithm `scan`")
    );
}

#[test]
fn more_floors_than_the_lab_bus_has_stations_for_are_refused_at_their_line() {
    let e = err("seed = 1\n[lift]\nfloors = 5\n");
    assert!(
        e.starts_with("t.toml:3:10: lift.floors: 5: the lab bus has floor stations for 2..4"),
        "{e}"
    );
    assert!(Scenario::from_toml("t.toml", "[lift]\nfloors = 4\n").is_ok());
}

#[test]
fn errors_of_the_toml_reader_name_the_table_and_quote_little() {
    // A value the TOML reader refuses is named with its table, not only its key.
    let e = err("[bus]\nextra_slaves = 1\n[lift]\nfloors = 99999999999999999999\n");
    assert!(e.starts_with("t.toml:4:10: lift.floors: "), "{e}");
    let e = err("[lift]\nstart_mm = \"high\"\n");
    assert!(e.starts_with("t.toml:2:12: lift.start_mm: "), "{e}");
    let e =
        err("[[event]]\nat = \"1s\"\npress = \"cabin:1\"\n\n[[event]]\nat = \"2s\"\npress = 5\n");
    assert!(e.starts_with("t.toml:7:9: event[2].press: "), "{e}");
    // Deep nesting is refused at its place.
    let e = err(&format!("x = {}{}\n", "[".repeat(5000), "]".repeat(5000)));
    assert!(e.starts_with("t.toml:1:"), "{e}");
    // A long bad value is quoted in part.
    let e = err(&format!("duration = \"{}\"\n", "y".repeat(3000)));
    assert!(e.len() < 300 && e.contains("(3000 characters)"), "{e}");
}

#[test]
fn events_after_the_end_are_found_for_a_warning() {
    let sc = Scenario::from_toml(
        "t.toml",
        "duration = \"10s\"\n[[event]]\nat = \"5s\"\nreset = true\n[[event]]\nat = \"10s\"\nack = true\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let late: Vec<usize> = sc.late_events().map(|e| e.line).collect();
    assert_eq!(late, [5]);
}

#[test]
fn reads_traffic_templates() {
    let sc = Scenario::from_toml(
        "t.toml",
        "seed = 9\nduration = \"1h\"\n[[traffic]]\npattern = \"up-peak\"\nper_minute = 2.5\n\n\
         [[traffic]]\npattern = \"interfloor\"\nper_minute = 1.0\nseed = 4\nstart = \"10min\"\n\
         duration = \"20min\"\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    use traffic::{Pattern, Traffic};
    assert_eq!(
        sc.traffic,
        [
            Traffic {
                pattern: Pattern::UpPeak,
                per_minute: 2.5,
                // The scenario's (moved by the template's place) unless it has its own.
                seed: None,
                start: SimDuration::ZERO,
                duration: None,
                line: 3,
            },
            Traffic {
                pattern: Pattern::Interfloor,
                per_minute: 1.0,
                seed: Some(4),
                start: SimDuration::from_secs(600),
                duration: Some(SimDuration::from_secs(1200)),
                line: 7,
            },
        ]
    );
}

#[test]
fn traffic_errors_name_the_template_and_the_key() {
    let t = |body: &str| {
        err(&format!("duration = \"1h\"\n[[traffic]]\npattern = \"up-peak\"\nper_minute = 1.0\n[[traffic]]\n{body}"))
    };
    assert_eq!(
        t("pattern = \"lunch\"\nper_minute = 1.0\n"),
        "t.toml:6:11: traffic[2].pattern: unknown pattern `lunch`: use up-peak, down-peak or interfloor"
    );
    assert_eq!(
        t("pattern = \"interfloor\"\nper_minute = 0.0\n"),
        "t.toml:7:14: traffic[2].per_minute: 0: the mean arrivals per minute lie above 0 and up to 60"
    );
    assert!(
        t("pattern = \"interfloor\"\nper_minute = -3.0\n").contains("traffic[2].per_minute: -3:")
    );
    assert_eq!(
        t("per_minute = 2.0\n"),
        "t.toml:5:1: traffic[2].pattern: a traffic template needs `pattern = \"up-peak\"`, `\"down-peak\"` or `\"interfloor\"`"
    );
    assert!(t("pattern = \"interfloor\"\n").starts_with(
        "t.toml:5:1: traffic[2].per_minute: a traffic template needs `per_minute = …`"
    ));
    assert_eq!(
        t("pattern = \"interfloor\"\nper_minute = 1.0\nstart = \"2h\"\n"),
        "t.toml:8:9: traffic[2].start: 7200 s: the traffic starts at or after the scenario's end (3600 s)"
    );
    assert!(
        t("pattern = \"interfloor\"\nper_minute = 1.0\nduration = \"0s\"\n")
            .starts_with("t.toml:8:12: traffic[2].duration: must be longer than zero")
    );
    assert!(
        t("pattern = \"interfloor\"\nper_minute = 1.0\nduration = \"soon\"\n")
            .starts_with("t.toml:8:12: traffic[2].duration: ")
    );
    // The TOML reader's errors are named with the template too.
    let e = t("pattern = \"interfloor\"\nper_minute = \"many\"\n");
    assert!(e.starts_with("t.toml:7:14: traffic[2].per_minute: "), "{e}");
    let e = t("pattern = \"interfloor\"\nper_minute = 1.0\nseed = -1\n");
    assert!(e.starts_with("t.toml:8:8: traffic[2].seed: "), "{e}");
    let e = t("pattern = \"interfloor\"\nrate = 1.0\n");
    assert!(
        e.starts_with("t.toml:7:1: traffic[2].rate: unknown field `rate`"),
        "{e}"
    );
}

#[test]
fn unknown_keys_are_errors() {
    let e = err("name = \"x\"\n[lift]\nfloor = 4\n");
    assert!(
        e.starts_with("t.toml:3:1: lift.floor: unknown field `floor`"),
        "{e}"
    );
    let e = err("speed = 3\n");
    assert!(
        e.starts_with("t.toml:1:1: speed: unknown field `speed`"),
        "{e}"
    );
    let e = err("[[event]]\nat = \"1s\"\npress = \"stop\"\nduration = \"2s\"\n");
    assert!(e.contains("unknown field `duration`"), "{e}");
}

mod round_trip {
    use super::*;
    use crate::scenario::traffic::{Pattern, Traffic, MAX_PER_MINUTE};
    use proptest::prelude::*;

    fn duration_ns(max: u64) -> impl Strategy<Value = SimDuration> {
        // Whole seconds, milliseconds and microseconds as well as odd nanoseconds.
        prop_oneof![
            (1..=max / 1_000_000_000).prop_map(SimDuration::from_secs),
            (1..=max / 1_000_000).prop_map(SimDuration::from_millis),
            (1..=max / 1_000).prop_map(SimDuration::from_micros),
            (1..=max).prop_map(SimDuration::from_nanos),
        ]
    }

    fn button(floors: u8) -> impl Strategy<Value = Button> {
        prop_oneof![
            (1..=floors).prop_map(Button::Cabin),
            (1..floors).prop_map(Button::HallUp),
            (2..=floors).prop_map(Button::HallDown),
            Just(Button::Stop),
            Just(Button::Bell),
        ]
    }

    fn load() -> impl Strategy<Value = LoadLevel> {
        prop_oneof![
            Just(LoadLevel::Empty),
            Just(LoadLevel::Loaded),
            Just(LoadLevel::Full),
            Just(LoadLevel::Overloaded),
        ]
    }

    fn action(floors: u8) -> impl Strategy<Value = Action> {
        let sensor = prop_oneof![Just(VaneSensor::Left), Just(VaneSensor::Right)];
        let sensor_fault = prop_oneof![
            Just(SensorFault::None),
            Just(SensorFault::StuckOn),
            Just(SensorFault::StuckOff)
        ];
        prop_oneof![
            (button(floors), duration_ns(10_000_000_000))
                .prop_map(|(button, hold)| Action::Press { button, hold }),
            load().prop_map(Action::Load),
            any::<bool>().prop_map(|closed| Action::Door { closed }),
            (-10_000.0..=10_000.0f64)
                .prop_filter("non-zero", |mm| *mm != 0.0)
                .prop_map(|mm| Action::Crank { mm }),
            Just(Action::Reset),
            Just(Action::Rescue),
            Just(Action::Ack),
            Just(Action::Attend),
            (1..=31u8).prop_map(|slave| Action::Fault(Fault::SlaveOffline { slave })),
            (1..=31u8).prop_map(|slave| Action::Fault(Fault::SlaveOnline { slave })),
            duration_ns(60_000_000_000)
                .prop_map(|duration| Action::Fault(Fault::PowerFail { duration })),
            duration_ns(60_000_000_000)
                .prop_map(|duration| Action::Fault(Fault::SafeLinkDrop { duration })),
            (sensor, sensor_fault)
                .prop_map(|(sensor, fault)| Action::Fault(Fault::Vane { sensor, fault })),
            any::<bool>().prop_map(|up| Action::Fault(Fault::ConverterRunaway { up })),
            Just(Action::Fault(Fault::ConverterRepaired)),
            Just(Action::Fault(Fault::EncoderFailed)),
            Just(Action::Fault(Fault::EncoderRepaired)),
        ]
    }

    prop_compose! {
        fn event(floors: u8)(at in 0..=3_600_000_000_000u64, action in action(floors))
            -> ScenarioEvent {
            ScenarioEvent { at: SimTime::from_nanos(at), action, line: 0 }
        }
    }

    prop_compose! {
        // The rig's lab bus has floor stations for up to four floors.
        fn lift()(floors in 2..=lab::address::FLOOR_STATIONS)(
            floors in Just(floors),
            start in start_range_mm(floors),
            events in proptest::collection::vec(event(floors), 0..12),
        ) -> (u8, f64, Vec<ScenarioEvent>) {
            (floors, start, events)
        }
    }

    prop_compose! {
        fn scenario()(
            name in any::<String>(),
            seed in any::<u64>(),
            duration in duration_ns(36_000_000_000_000),
            collective in any::<bool>(),
            (floors, start_mm, events) in lift(),
            load in load(),
            door_closed in any::<bool>(),
            pulse_error_rate in prop_oneof![Just(0.0), Just(1.0), 0.0..=1.0f64],
            extra_slaves in 0..=20u8,
            scan in PLC_SCAN_RANGE.start().as_nanos()..=PLC_SCAN_RANGE.end().as_nanos(),
            power_on_reset in any::<bool>(),
            safe_drive in any::<bool>(),
            configuration_mode in any::<bool>(),
            traffic in proptest::collection::vec(
                (
                    0..3usize,
                    prop_oneof![Just(MAX_PER_MINUTE), 1e-9..=MAX_PER_MINUTE],
                    proptest::option::of(any::<u64>()),
                    any::<u64>(),
                    proptest::option::of(duration_ns(36_000_000_000_000)),
                ),
                0..3,
            ),
        ) -> Scenario {
            Scenario {
                name,
                seed,
                duration,
                algorithm: if collective { Algorithm::Collective } else { Algorithm::Fifo },
                floors,
                start_mm,
                load,
                door_closed,
                pulse_error_rate,
                extra_slaves,
                master_mode: if configuration_mode {
                    asi_master::Mode::Configuration
                } else {
                    asi_master::Mode::Protected
                },
                plc_scan: SimDuration::from_nanos(scan),
                program: None,
                power_on_reset,
                safe_drive,
                // Only the safe drive has an encoder to fail.
                events: events
                    .into_iter()
                    .filter(|e| {
                        safe_drive
                            || !matches!(
                                e.action,
                                Action::Fault(Fault::EncoderFailed | Fault::EncoderRepaired)
                            )
                    })
                    .collect(),
                traffic: traffic
                    .into_iter()
                    .map(|(p, per_minute, seed, start, length)| Traffic {
                        pattern: [Pattern::UpPeak, Pattern::DownPeak, Pattern::Interfloor][p],
                        per_minute,
                        seed,
                        // Within the scenario, as the reader wants.
                        start: SimDuration::from_nanos(start % duration.as_nanos()),
                        duration: length,
                        line: 0,
                    })
                    .collect(),
            }
        }
    }

    proptest! {
        #[test]
        fn to_toml_reads_back_to_an_equal_scenario(sc in scenario()) {
            let text = sc.to_toml();
            let mut back = match Scenario::from_toml("written.toml", &text) {
                Ok(b) => b,
                Err(e) => return Err(TestCaseError::fail(format!("{e}\n{text}"))),
            };
            back.events.iter_mut().for_each(|e| e.line = 0);
            back.traffic.iter_mut().for_each(|t| t.line = 0);
            let mut expected = sc;
            expected.events.sort_by_key(|e| e.at);
            prop_assert_eq!(back, expected, "{}", text);
        }
    }

    #[test]
    fn the_written_scenario_files_are_readable() {
        let sc = Scenario::from_toml("demo.toml", include_str!("../../scenarios/demo.toml"))
            .expect("demo");
        let text = sc.to_toml();
        assert!(
            text.contains("[[event]]\nat = \"15s\"\npress = \"cabin:3\"\n"),
            "{text}"
        );
        assert!(text.starts_with("name = \"demo\"\nseed = 1\n"), "{text}");
        let back = Scenario::from_toml("w.toml", &text).expect("back");
        assert_eq!(back.events.len(), sc.events.len());
    }
}

#[test]
fn the_start_range_is_the_shaft_between_the_mechanical_ends() {
    // Sensors 60 mm beyond the end floors, the ends 80 mm further (docs/lift-plant.md).
    assert_eq!(start_range_mm(4), -140.0..=1340.0);
    assert_eq!(start_range_mm(2), -140.0..=540.0);
    let at = |mm: f64| format!("[lift]\nfloors = 2\nstart_mm = {mm:?}\n");
    assert!(Scenario::from_toml("t.toml", &at(540.0)).is_ok());
    assert!(Scenario::from_toml("t.toml", &at(-140.0)).is_ok());
    assert!(
        Scenario::from_toml("t.toml", &at(-70.0)).is_ok(),
        "beyond the sensor"
    );
    assert!(err(&at(540.5)).contains("(-140..540 mm)"));
    assert!(err(&at(-140.5)).contains("lift.start_mm"));
}

#[test]
fn the_demo_is_valid() {
    let text = include_str!("../../scenarios/demo.toml");
    let s = Scenario::from_toml("demo.toml", text).expect("demo");
    assert!(!s.events.is_empty());
    assert_eq!(Scenario::demo(), Ok(s));
}

#[test]
fn the_encoder_faults_are_read_only_with_the_safe_drive() {
    let sc = Scenario::from_toml(
        "t.toml",
        "[drive]\nsafe = true\n\n[[event]]\nat = \"5s\"\nfault = { kind = \"encoder-failed\" }\n\n[[event]]\nat = \"6s\"\nfault = { kind = \"encoder-repaired\" }\n",
    )
    .expect("reads");
    assert_eq!(sc.events[0].action, Action::Fault(Fault::EncoderFailed));
    assert_eq!(sc.events[1].action, Action::Fault(Fault::EncoderRepaired));
    let ev = |fault: &str| format!("[[event]]\nat = \"5s\"\nfault = {fault}\n");
    assert_eq!(
        err(&ev("{ kind = \"encoder-failed\" }")),
        "t.toml:3:18: event[1].fault.kind: `encoder-failed` needs `[drive] safe = true`: the lab lift's only encoder is the safe drive's"
    );
    assert_eq!(
        err(&format!(
            "[drive]\nsafe = true\n{}",
            ev("{ kind = \"encoder-repaired\", slave = 3 }")
        )),
        "t.toml:5:9: event[1].fault.slave: `encoder-repaired` takes no `slave`"
    );
}

#[test]
fn the_safe_drive_and_the_converter_runaway_are_read_and_checked() {
    let sc = Scenario::from_toml(
        "t.toml",
        "[drive]\nsafe = true\n\n[[event]]\nat = \"5s\"\nfault = { kind = \"converter-runaway\", direction = \"down\" }\n\n[[event]]\nat = \"6s\"\nfault = { kind = \"converter-repaired\" }\n",
    )
    .expect("reads");
    assert!(sc.safe_drive);
    assert_eq!(
        sc.events[0].action,
        Action::Fault(Fault::ConverterRunaway { up: false })
    );
    assert_eq!(sc.events[1].action, Action::Fault(Fault::ConverterRepaired));
    assert!(!Scenario::defaults().safe_drive, "off by default");
    let ev = |fault: &str| format!("[[event]]\nat = \"5s\"\nfault = {fault}\n");
    assert_eq!(
        err(&ev("{ kind = \"converter-runaway\" }")),
        "t.toml:3:9: event[1].fault.direction: `converter-runaway` needs `direction = \"up\"` or `\"down\"`"
    );
    assert_eq!(
        err(&ev(
            "{ kind = \"converter-runaway\", direction = \"sideways\" }"
        )),
        "t.toml:3:51: event[1].fault.direction: unknown direction `sideways`: use up or down"
    );
    assert_eq!(
        err(&ev("{ kind = \"converter-repaired\", direction = \"up\" }")),
        "t.toml:3:9: event[1].fault.direction: `converter-repaired` takes no `direction`"
    );
    assert_eq!(
        err(&ev(
            "{ kind = \"power-fail\", duration = \"1s\", direction = \"up\" }"
        )),
        "t.toml:3:9: event[1].fault.direction: `power-fail` takes no `direction`"
    );
    assert_eq!(
        err(&ev(
            "{ kind = \"converter-runaway\", direction = \"up\", slave = 7 }"
        )),
        "t.toml:3:9: event[1].fault.slave: `converter-runaway` takes no `slave`"
    );
    let e = err("[drive]\nsafe = \"yes\"\n");
    assert!(e.starts_with("t.toml:2:8: drive.safe: "), "{e}");
    let e = err("[drive]\nsafe = true\nsafety = true\n");
    assert!(e.contains("unknown field `safety`"), "{e}");
    assert!(err(&ev("{ kind = \"runaway\" }")).contains(
        "converter-runaway, converter-repaired, encoder-failed, encoder-repaired or line-noise"
    ));
}

/// Random and mutated bytes into the scenario reader: never a panic; an error names its file
/// and says what is wrong in a line or two, whatever the input.
mod fuzz {
    use super::*;
    use proptest::prelude::*;

    /// The scenario files of the repository, read once.
    fn files() -> &'static [String] {
        static FILES: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
        FILES.get_or_init(|| {
            let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
            let mut names: Vec<_> = std::fs::read_dir(&dir)
                .expect("scenarios/")
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "toml"))
                .collect();
            names.sort();
            names
                .iter()
                .map(|p| std::fs::read_to_string(p).expect("a scenario"))
                .collect()
        })
    }

    use asi_phy::testing::mutate;

    fn check(bytes: &[u8]) -> Result<(), TestCaseError> {
        let text = String::from_utf8_lossy(bytes);
        if let Err(e) = Scenario::from_toml("f.toml", &text) {
            let m = e.to_string();
            prop_assert!(m.starts_with("f.toml"), "{}", m);
            prop_assert!(m.len() < 600, "{} bytes: {}", m.len(), m);
        }
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(asi_phy::testing::fuzz_cases(1000)))]

        #[test]
        fn mutated_scenario_files_are_read_or_refused_clearly(
            which in any::<prop::sample::Index>(),
            edits in prop::collection::vec((any::<u8>(), any::<usize>(), any::<u8>()), 1..6),
        ) {
            let text = which.get(files());
            check(&mutate(text.as_bytes(), &edits))?;
        }

        #[test]
        fn random_bytes_are_refused_clearly(
            bytes in prop::collection::vec(any::<u8>(), 0..300),
        ) {
            check(&bytes)?;
        }

        #[test]
        fn random_toml_like_text_is_read_or_refused_clearly(
            text in "(\\[[a-z_.\\[\\]]{0,12}\\]\n|[a-z_]{1,12} = [-+0-9a-z.e\"{}\\[\\], =:]{0,30}\n){0,12}",
        ) {
            check(text.as_bytes())?;
        }
    }
}

#[test]
fn a_burst_of_line_noise_is_read_written_and_checked() {
    let text = "[[event]]\nat = \"5s\"\nfault = { kind = \"line-noise\", rate = 0.01, duration = \"500ms\" }\n";
    let sc = Scenario::from_toml("t.toml", text).expect("reads");
    let burst = Fault::LineNoise {
        rate: 0.01,
        duration: SimDuration::from_millis(500),
    };
    assert_eq!(sc.events[0].action, Action::Fault(burst));
    // Written and read back, the same burst.
    let mut back = Scenario::from_toml("t.toml", &sc.to_toml()).expect("reads back");
    back.events
        .iter_mut()
        .for_each(|e| e.line = sc.events[0].line);
    assert_eq!(back, sc);
    let ev = |fault: &str| format!("[[event]]\nat = \"5s\"\nfault = {fault}\n");
    assert_eq!(
        err(&ev("{ kind = \"line-noise\", duration = \"1s\" }")),
        "t.toml:3:9: event[1].fault.rate: `line-noise` needs `rate = P`, the probability that a pulse is corrupted"
    );
    assert_eq!(
        err(&ev("{ kind = \"line-noise\", rate = 0.01 }")),
        "t.toml:3:9: event[1].fault.duration: `line-noise` needs `duration = \"…\"`"
    );
    assert_eq!(
        err(&ev("{ kind = \"line-noise\", rate = 1.5, duration = \"1s\" }")),
        "t.toml:3:39: event[1].fault.rate: 1.5: a burst's rate is a probability above 0 and at most 1"
    );
    assert_eq!(
        err(&ev(
            "{ kind = \"power-fail\", rate = 0.1, duration = \"1s\" }"
        )),
        "t.toml:3:9: event[1].fault.rate: `power-fail` takes no `rate`"
    );
}
