//! The master's LEDs (seed 003 table 3.2; docs/master.md §2.8) on the lab bus: each LED
//! changes in a scenario of its own, and the protected and configuration modes treat a slave
//! that is not projected as the thesis describes.

use crate::common::*;
use asi_bus::lab::LabLift;
use asi_bus::Bus;
use asi_master::mailbox::{completed, post, Command, JobResult};
use asi_master::{Led, MasterLeds, Mode, PlcLink};
use asi_phy::SimDuration;
use asi_slaves::devices::{IoModule, AC2726};
use asi_slaves::Slave;

/// Index of each LED in [`MasterLeds::each`].
const PWR: usize = 0;
const OK: usize = 1;
const SYS: usize = 2;
const ASI: usize = 3;
const ASI_ACTIVE: usize = 4;
const PRG: usize = 5;
const PRJ: usize = 6;

fn leds(bus: &Bus) -> MasterLeds {
    bus.master().leds()
}

/// Advances the bus until `until` holds, at most `limit` ms of simulated time.
fn run_until(bus: &mut Bus, limit: u64, until: impl Fn(&Bus) -> bool) {
    let end = bus.now() + SimDuration::from_millis(limit);
    while !until(bus) {
        let t = bus.poll_at();
        assert!(t < end, "not reached within {limit} ms: {}", leds(bus));
        bus.advance_to(t);
    }
}

/// Runs a mailbox job to its end.
fn job(bus: &mut Bus, cmd: Command, args: &[u8]) -> JobResult {
    post(&mut bus.image_mut().output, cmd, args);
    let limit = bus.now() + SimDuration::from_millis(100);
    loop {
        if let Some((_, r, _)) = completed(&bus.image().input, &bus.image().output) {
            return r;
        }
        let t = bus.poll_at();
        assert!(t < limit, "job {cmd:?} not done");
        bus.advance_to(t);
    }
}

/// The lab bus with its PLC connected and running from the start.
fn lab() -> LabLift {
    let mut lab = LabLift::new().expect("lab");
    lab.bus_mut().set_plc_link(PlcLink::RUN);
    lab
}

#[test]
fn start_up_turns_as_i_active_green_after_offline() {
    let mut lab = lab();
    let l = leds(lab.bus());
    assert_eq!(
        (l.asi_active, l.asi, l.pwr),
        (Led::Off, Led::Red, Led::Green)
    );
    assert_eq!((l.sys, l.ok), (Led::Green, Led::Green));
    run_until(lab.bus_mut(), 100, |b| leds(b) == MasterLeds::NORMAL);
    let w = lab.bus().master().led_watch();
    // The PLC link set at the start is the starting state, no change.
    assert_eq!(w.changes(), [0, 0, 0, 1, 1, 0, 0]);
    let away = w.away(lab.bus().now());
    assert!(away[ASI_ACTIVE] > SimDuration::from_millis(5), "{away:?}");
    assert_eq!(away[PWR], SimDuration::ZERO);
}

#[test]
fn a_power_fail_turns_pwr_off_and_back() {
    let mut lab = lab();
    lab.bus_mut().advance_to(ms(100));
    assert_eq!(leds(lab.bus()), MasterLeds::NORMAL);
    lab.bus_mut().set_supply_voltage(0.0);
    let l = leds(lab.bus());
    assert_eq!((l.pwr, l.asi_active, l.asi), (Led::Off, Led::Off, Led::Red));
    lab.bus_mut().advance_to(ms(300));
    lab.bus_mut().set_supply_voltage(30.0);
    assert_eq!(leds(lab.bus()).pwr, Led::Green);
    run_until(lab.bus_mut(), 300, |b| leds(b) == MasterLeds::NORMAL);
    let w = lab.bus().master().led_watch();
    assert_eq!(w.changes()[PWR], 2);
    assert_eq!(w.away(lab.bus().now())[PWR], SimDuration::from_millis(200));
}

#[test]
fn a_slave_off_the_bus_is_a_configuration_error_and_opens_auto_addressing() {
    let mut lab = lab();
    lab.bus_mut().advance_to(ms(100));
    let id = lab.slave_id(3).expect("floor 3");
    lab.bus_mut().detach(id);
    run_until(lab.bus_mut(), 100, |b| !b.master().las().contains(a(3)));
    let l = leds(lab.bus());
    assert_eq!(l.asi, Led::Red, "one projected slave missing");
    assert_eq!(l.asi_active, Led::Green, "the others are served");
    assert_eq!(
        l.prg,
        Led::GreenFlashing,
        "one projected slave missing: a new slave at 0 would take its address"
    );
    lab.bus_mut().attach(id);
    run_until(lab.bus_mut(), 200, |b| leds(b) == MasterLeds::NORMAL);
    let w = lab.bus().master().led_watch();
    assert_eq!(w.changes()[ASI], 3, "red at start-up, green, red, green");
    assert_eq!(w.changes()[PRG], 2);
}

#[test]
fn auto_addressing_disabled_turns_prg_off() {
    let mut lab = lab();
    lab.bus_mut().advance_to(ms(100));
    let w0 = lab.bus().image().output.word(0);
    lab.bus_mut()
        .image_mut()
        .output
        .set_word(0, w0 | asi_master::HostFlags::WORD0_NO_AUTO_ADDRESS);
    lab.bus_mut().advance_to(ms(110));
    assert_eq!(leds(lab.bus()).prg, Led::Off);
    assert_eq!(lab.bus().master().led_watch().changes()[PRG], 1);
}

#[test]
fn the_plc_link_drives_sys_and_ok() {
    let mut lab = lab();
    lab.bus_mut().advance_to(ms(100));
    lab.bus_mut().set_plc_link(PlcLink {
        connected: true,
        run: false,
    });
    let l = leds(lab.bus());
    assert_eq!((l.sys, l.ok), (Led::Green, Led::Off), "PLC in stop");
    lab.bus_mut().advance_to(ms(150));
    lab.bus_mut().set_plc_link(PlcLink::NONE);
    let l = leds(lab.bus());
    assert_eq!((l.sys, l.ok), (Led::Off, Led::Off), "no PLC");
    lab.bus_mut().advance_to(ms(200));
    lab.bus_mut().set_plc_link(PlcLink::RUN);
    assert_eq!(leds(lab.bus()), MasterLeds::NORMAL);
    let w = lab.bus().master().led_watch();
    assert_eq!((w.changes()[OK], w.changes()[SYS]), (2, 2));
    let away = w.away(ms(300));
    assert_eq!(away[OK], SimDuration::from_millis(100));
    assert_eq!(away[SYS], SimDuration::from_millis(50));
}

/// The thesis's two modes with a slave that is not projected: protected mode leaves it out
/// of LAS and shows the configuration error; configuration mode activates every detected
/// slave and lights prj; back in protected mode it is deactivated again.
#[test]
fn protected_mode_keeps_an_unprojected_slave_out_and_configuration_mode_takes_it_in() {
    let mut lab = lab();
    lab.bus_mut().advance_to(ms(100));
    lab.bus_mut()
        .add_slave(Slave::new(
            "unprojected",
            addr(20),
            AC2726,
            Box::new(IoModule::new()),
        ))
        .expect("slave");
    run_until(lab.bus_mut(), 200, |b| b.master().lds().contains(a(20)));
    let later = lab.bus().now() + SimDuration::from_millis(50);
    lab.bus_mut().advance_to(later);
    let m = lab.bus().master();
    assert_eq!(m.mode(), Mode::Protected);
    assert!(!m.las().contains(a(20)), "protected mode: not activated");
    let l = leds(lab.bus());
    assert_eq!((l.asi, l.prj), (Led::Red, Led::Off));
    assert_eq!(
        l.prg,
        Led::Off,
        "a slave not projected blocks auto addressing"
    );

    assert_eq!(job(lab.bus_mut(), Command::SetMode, &[1]), JobResult::Ok);
    run_until(lab.bus_mut(), 200, |b| b.master().las().contains(a(20)));
    let l = leds(lab.bus());
    assert_eq!(l.prj, Led::Yellow, "configuration mode");
    assert_eq!(l.asi, Led::Red, "still not projected");
    assert_eq!(l.asi_active, Led::Green);

    assert_eq!(job(lab.bus_mut(), Command::SetMode, &[0]), JobResult::Ok);
    assert!(!lab.bus().master().las().contains(a(20)), "deactivated");
    assert_eq!(leds(lab.bus()).prj, Led::Off);
    let w = lab.bus().master().led_watch();
    assert_eq!(w.changes()[PRJ], 2);
}
