//! The AS-i master's LEDs of seed 003 table 3.2 in the report of whole runs (`bus.master_leds`,
//! docs/master.md §2.8): start-up, a power fail, a slave off the bus, configuration mode.

use asi_lift_tests::{run_file, run_toml};

#[test]
fn a_quiet_run_ends_with_every_led_normal_after_start_up() {
    let r = run_toml(
        "quiet",
        "name = \"quiet\"\nduration = \"5s\"\n[lift]\nstart_mm = 0.0\n",
    );
    let l = &r.bus.master_leds;
    for (name, led) in [
        ("pwr", &l.pwr),
        ("ok", &l.ok),
        ("sys", &l.sys),
        ("asi", &l.asi),
        ("asi_active", &l.asi_active),
        ("prg", &l.prg),
    ] {
        assert_eq!(led.end, "green", "{name}");
    }
    assert_eq!(l.prj.end, "off");
    // Start-up: configuration error until the slaves are active, then normal operation.
    assert_eq!((l.asi.changes, l.asi_active.changes), (1, 1));
    assert!(l.asi_active.abnormal_s > 0.0 && l.asi_active.abnormal_s < 0.2);
    // The built-in PLC runs from the start.
    assert_eq!((l.sys.changes, l.ok.changes, l.pwr.changes), (0, 0, 0));
    assert_eq!(l.ok.abnormal_s, 0.0);
}

#[test]
fn a_power_fail_turns_pwr_off_for_its_duration() {
    let l = run_file("power-fail").bus.master_leds;
    assert_eq!((l.pwr.end, l.pwr.changes), ("green", 2));
    assert!(
        (l.pwr.abnormal_s - 2.0).abs() < 0.01,
        "{}",
        l.pwr.abnormal_s
    );
    assert_eq!(
        l.asi_active.changes, 3,
        "start-up, off at the power fail, on again"
    );
}

#[test]
fn a_slave_off_the_bus_shows_the_configuration_error() {
    let l = run_file("lost-cabin-slave").bus.master_leds;
    // Red at start-up, green, red while slave 6 is away, green again.
    assert_eq!((l.asi.end, l.asi.changes), ("green", 3));
    assert!(l.asi.abnormal_s > 19.0, "{}", l.asi.abnormal_s);
    // One projected slave missing: automatic addressing available, prg flashes.
    assert_eq!(l.prg.changes, 2);
    assert_eq!(
        l.asi_active.changes, 1,
        "the others stay in normal operation"
    );
}

#[test]
fn configuration_mode_lights_prj_for_the_whole_run() {
    let r = run_toml(
        "configuration mode",
        "name = \"configuration mode\"\nduration = \"5s\"\n[lift]\nstart_mm = 0.0\n\
         [bus]\nmaster_mode = \"configuration\"\n",
    );
    let l = &r.bus.master_leds;
    assert_eq!((l.prj.end, l.prj.changes), ("yellow", 0));
    assert!((l.prj.abnormal_s - 5.0).abs() < 1e-9);
    assert_eq!(l.asi.end, "green", "every lab slave is projected");
    // Automatic addressing needs protected mode.
    assert_eq!(l.prg.end, "off");
    assert!(
        r.initialised_at_s.is_some(),
        "the lift runs as in protected mode"
    );
}
