//! Fault scenarios: corrupted telegrams and repeats, a slave lost and re-admitted, line noise,
//! AS-i power fail, a wrong slave in protected mode, a replaced slave auto-addressed, two
//! slaves answering at once, safety slaves that freeze, trip or go missing (docs/master.md, §3;
//! docs/asi.md §2.5, §5, §7).

use crate::common::*;
use asi_bus::Bus;
use asi_master::{MasterConfig, Phase, ProjectedConfig, TransactionRecord};
use asi_phy::{Check, FaultRates, Nibble, PulseFault};
use asi_slaves::devices::{FloorStation, IoModule, AC2726, IG5886};
use asi_slaves::monitor::NotReleased;
use asi_slaves::Slave;

/// Steps the bus to just after a transaction's responses went on the line, so that the next
/// telegram on the line is the next request.
fn to_next_request(bus: &mut Bus) {
    let n = bus.stats().transactions;
    while bus.stats().transactions == n {
        let t = bus.poll_at();
        bus.advance_to(t);
    }
    let t = bus.poll_at();
    bus.advance_to(t);
}

fn repeats_follow_their_failure(trace: &[TransactionRecord]) {
    for w in trace.windows(2) {
        if w[1].repeat {
            assert_eq!(w[1].request, w[0].request);
            assert!(!w[0].ok(), "{}", w[0]);
            // At once: one transaction time later, more if noise kept the line busy.
            assert!(w[1].start - w[0].start >= us(154));
            assert!(w[1].start - w[0].start < us(170));
        }
    }
}

#[test]
fn a_corrupted_request_and_its_repeat() {
    let mut lab = running_lab(40);
    to_next_request(lab.bus_mut());
    // Pulse 6 of the next request arrives with the wrong sign.
    lab.bus_mut()
        .corrupt_next_telegram(vec![PulseFault::Flip { index: 6 }]);
    let t = lab.bus().now();
    lab.bus_mut().advance_to(t + us(6 * 154));
    let trace = lab.bus_mut().drain_trace();
    let s = lab.bus().stats();
    assert_eq!(s.repeats, 1);
    assert_eq!(s.request_errors[Check::Alternation as usize], 1);
    assert_eq!(s.failed_after_repeat, 0);
    repeats_follow_their_failure(&trace);
    let i = trace.iter().position(|r| r.repeat).expect("repeat");
    assert!(
        trace[i - 1].no_response,
        "the slave ignored the corrupt request"
    );
    assert!(trace[i].ok());
    insta::assert_snapshot!(lines(&trace[trace.len() - 6..]));
}

#[test]
fn a_corrupted_response_is_repeated_too() {
    let mut lab = running_lab(40);
    to_next_request(lab.bus_mut());
    // The next request goes out clean; corrupt the response that follows it.
    let t = lab.bus().poll_at();
    lab.bus_mut().advance_to(t);
    lab.bus_mut()
        .corrupt_next_telegram(vec![PulseFault::Drop { index: 4 }]);
    let t = lab.bus().now();
    lab.bus_mut().advance_to(t + us(4 * 154));
    let trace = lab.bus_mut().drain_trace();
    let s = lab.bus().stats();
    assert_eq!(s.repeats, 1);
    let i = trace.iter().position(|r| r.repeat).expect("repeat");
    assert!(!trace[i - 1].response_failed.is_empty(), "{}", trace[i - 1]);
    assert!(trace[i - 1].request_failed.is_empty());
    assert!(trace[i].ok());
}

#[test]
fn a_slave_lost_and_readmitted() {
    let mut lab = running_lab(40);
    let floor2 = lab.slave_id(2).expect("floor 2");
    let t0 = lab.bus().now();
    lab.bus_mut().detach(floor2);
    lab.bus_mut().advance_to(t0 + us(8 * 13 * 154));
    let m = lab.bus().master();
    assert!(!m.las().contains(a(2)));
    assert!(!m.lds().contains(a(2)));
    assert!(m.lcs().contains(a(2)));
    assert!(!m.flags().config_ok());
    assert_eq!(
        lab.bus().image().input.word(0) >> 12 & 1,
        1,
        "F0 ConfigError"
    );
    assert_eq!(lab.bus().image().input.nibble(a(2)), Nibble::ZERO);
    assert_eq!(lab.bus().stats().dropouts, 1);
    lab.bus_mut().attach(floor2);
    let back = lab.bus().now();
    while !lab.bus().master().las().contains(a(2)) {
        let t = lab.bus().poll_at();
        assert!(t < back + asi_phy::SimDuration::from_millis(200));
        lab.bus_mut().advance_to(t);
    }
    let now = lab.bus().now();
    lab.bus_mut().advance_to(now + us(154));
    assert!(lab.bus().master().flags().config_ok());
    assert_eq!(lab.bus().image().input.word(0) >> 12 & 1, 0);
    let trace = lab.bus_mut().drain_trace();
    repeats_follow_their_failure(&trace);
    let to2: Vec<_> = trace.iter().filter(|r| target(r) == 2).copied().collect();
    // Three cycles of a failed exchange and its repeat, then only inclusion probes.
    assert_eq!(to2.iter().filter(|r| r.repeat).count(), 3);
    insta::assert_snapshot!(folded(&to2));
}

#[test]
fn line_noise_is_absorbed_by_repeats() {
    let mut lab = running_lab(40);
    lab.bus_mut().set_line_faults(
        42,
        FaultRates::uniform(asi_phy::PulseErrorRate::new(0.002).expect("a probability")),
    );
    lab.bus_mut().advance_to(ms(2_040));
    let s = lab.bus().stats();
    let trace = lab.bus_mut().drain_trace();
    repeats_follow_their_failure(&trace);
    assert!(s.repeats > 100, "{s}");
    assert!(s.transactions > 12_000);
    let classes = Check::ALL.iter().filter(|&&c| s.errors(c) > 0).count();
    assert!(classes >= 4, "{s}");
    assert_eq!(s.dropouts, 0, "{s}");
    assert!(lab.bus().faults_injected() > 0);
    let m = lab.bus().master();
    assert_eq!(m.las(), m.lps());
    assert!(m.flags().config_ok());
    // Safety codes survive: the repeat sees the code the slave held (SAP5 rule).
    assert!(lab.released(11) && lab.released(12));
}

#[test]
fn power_fail_sets_apf_goes_offline_and_restarts() {
    let mut lab = running_lab(40);
    lab.bus_mut().image_mut().output.set_analog(10, 1, 11_000);
    lab.bus_mut().advance_to(ms(100));
    assert_eq!(lab.analog_output().expect("out").current_ua(1), 11_000);
    let before = lab.bus().stats().transactions;
    lab.bus_mut().set_supply_voltage(0.0);
    let m = lab.bus().master();
    assert!(m.flags().apf());
    assert!(m.flags().offline_ready());
    assert_eq!(m.phase(), Phase::Offline);
    assert!(m.lcs().contains(a(0)), "LCS bit 0: power fail");
    assert_eq!(lab.bus().image().input.word(0) >> 13 & 1, 1, "F1 APF");
    assert_eq!(lab.bus().poll_at(), asi_phy::SimTime::MAX);
    lab.bus_mut().advance_to(ms(200));
    assert_eq!(
        lab.bus().stats().transactions,
        before,
        "no traffic; the transaction cut by the power fail is not counted"
    );
    lab.bus_mut().set_supply_voltage(30.0);
    assert!(!lab.bus().master().flags().apf());
    lab.bus_mut().advance_to(ms(204));
    assert_eq!(lab.bus().master().phase(), Phase::Offline, "start-up delay");
    assert_eq!(
        lab.analog_output().expect("out").current_ua(1),
        0,
        "the slaves lost power and reset"
    );
    assert_eq!(lab.floor(1).and_then(|f| f.display()), None);
    lab.bus_mut().advance_to(ms(260));
    let m = lab.bus().master();
    assert_eq!(m.phase(), Phase::NormalOperation);
    assert!(m.flags().config_ok());
    assert_eq!(lab.bus().image().input.word(0) >> 12, 0b1000);
    lab.bus_mut().advance_to(ms(320));
    assert_eq!(lab.analog_output().expect("out").current_ua(1), 11_000);
}

#[test]
fn slaves_without_power_drop_their_outputs_at_once() {
    // The converter's run bit and the speed loop must not stay frozen at their last value
    // while the AS-i supply is down or the module is unplugged: the drive would run on.
    let mut lab = running_lab(40);
    lab.bus_mut().image_mut().output.set_analog(10, 1, 11_000);
    lab.bus_mut().image_mut().output.set_nibble(
        asi_phy::SlaveAddr::a(7).expect("7"),
        Nibble::from_low_bits(0b0011),
    );
    lab.bus_mut().advance_to(ms(100));
    assert!(lab.converter().expect("converter").run());
    assert_eq!(lab.analog_output().expect("out").current_ua(1), 11_000);
    lab.bus_mut().set_supply_voltage(0.0);
    assert!(
        !lab.converter().expect("converter").run(),
        "power fail: run off"
    );
    assert_eq!(lab.analog_output().expect("out").current_ua(1), 0);

    let mut lab = running_lab(40);
    lab.bus_mut().image_mut().output.set_nibble(
        asi_phy::SlaveAddr::a(7).expect("7"),
        Nibble::from_low_bits(0b0011),
    );
    lab.bus_mut().advance_to(ms(100));
    assert!(lab.converter().expect("converter").run());
    let id = lab.slave_id(7).expect("converter I/O");
    lab.bus_mut().detach(id);
    assert!(
        !lab.converter().expect("converter").run(),
        "unplugged: run off"
    );
}

#[test]
fn a_brown_out_above_the_slaves_minimum_stops_only_the_master() {
    let mut lab = running_lab(40);
    lab.bus_mut().set_supply_voltage(19.0);
    assert!(lab.bus().master().flags().apf());
    lab.bus_mut().advance_to(ms(100));
    lab.bus_mut().set_supply_voltage(30.0);
    lab.bus_mut().advance_to(ms(160));
    assert!(lab.bus().is_running());
    assert!(lab.bus().master().flags().config_ok());
}

#[test]
fn a_wrong_slave_in_protected_mode_is_a_configuration_error() {
    let mut lab = running_lab(40);
    let load = lab.slave_id(8).expect("load sensor");
    lab.bus_mut().detach(load);
    // An AC2726 where the IG5886 (S-1.1) belongs.
    lab.bus_mut()
        .add_slave(Slave::new(
            "wrong module",
            addr(8),
            AC2726,
            Box::new(IoModule::new()),
        ))
        .expect("slave");
    lab.bus_mut().advance_to(ms(400));
    let m = lab.bus().master();
    assert!(m.lds().contains(a(8)));
    assert!(!m.las().contains(a(8)));
    assert_eq!(m.detected_codes(a(8)), Some(AC2726));
    assert!(!m.flags().config_ok());
    assert!(
        !m.flags().auto_address_assign(),
        "a wrong slave blocks auto addressing"
    );
    assert_eq!(lab.bus().image().input.word(0) >> 12 & 1, 1);
    assert_eq!(lab.bus().image().input.nibble(a(8)), Nibble::ZERO);
    assert_ne!(IG5886, AC2726);
}

#[test]
fn a_replaced_slave_at_address_0_is_auto_addressed() {
    let mut lab = running_lab(40);
    let old = lab.slave_id(3).expect("floor 3");
    lab.bus_mut().detach(old);
    let new = lab
        .bus_mut()
        .add_slave(Slave::new(
            "new floor 3",
            addr(0),
            AC2726,
            Box::new(FloorStation::new()),
        ))
        .expect("slave");
    let t0 = lab.bus().now();
    while lab.bus().master().las().contains(a(3)) {
        let t = lab.bus().poll_at();
        lab.bus_mut().advance_to(t);
    }
    while !lab.bus().master().las().contains(a(3)) {
        let t = lab.bus().poll_at();
        assert!(
            t < t0 + asi_phy::SimDuration::from_millis(400),
            "not readdressed"
        );
        lab.bus_mut().advance_to(t);
    }
    let now = lab.bus().now();
    lab.bus_mut().advance_to(now + us(154));
    let s = lab.bus().slave(new).expect("new slave");
    assert_eq!((s.addr(), s.nv_address()), (a(3), addr(3)));
    let m = lab.bus().master();
    assert!(m.flags().config_ok());
    assert!(!m.flags().lds0());
    let trace = lab.bus_mut().drain_trace();
    let seq: Vec<_> = trace
        .iter()
        .filter(|r| (target(r) == 0 || target(r) == 3) && r.ok())
        .copied()
        .collect();
    insta::assert_snapshot!(folded(&seq));
}

#[test]
fn two_slaves_answering_at_once_corrupt_each_other() {
    let p = ProjectedConfig::default();
    let codes_a = AC2726;
    let codes_b = IG5886;
    let slaves = vec![
        Slave::new("one", addr(4), codes_a, Box::new(IoModule::new())),
        Slave::new("two", addr(4), codes_b, Box::new(IoModule::new())),
        Slave::new("three", addr(5), codes_a, Box::new(IoModule::new())),
    ];
    let cfg = {
        let mut cfg = MasterConfig::default();
        cfg.mode = asi_master::Mode::Configuration;
        cfg
    };
    let mut bus = Bus::new(cfg, p, slaves).expect("bus");
    bus.enable_trace(10_000);
    bus.advance_to(ms(30));
    let trace = bus.drain_trace();
    let io4: Vec<_> = trace.iter().filter(|r| target(r) == 4).take(2).collect();
    // IO codes 0111 and 0001 superimposed: pulses of opposite sign cancel.
    assert_eq!(io4.len(), 2);
    assert!(!io4[0].response_failed.is_empty(), "{}", io4[0]);
    assert!(io4[1].repeat && !io4[1].response_failed.is_empty());
    let m = bus.master();
    assert!(!m.lds().contains(a(4)));
    assert!(m.las().contains(a(5)));
}

#[test]
fn safety_monitor_learns_releases_and_catches_a_frozen_tripped_or_missing_code() {
    let mut lab = running_lab(40);
    lab.bus_mut().advance_to(ms(100));
    assert!(lab.released(11) && lab.released(12));
    let table = lab.safety_sensor(11).expect("sensor").table();
    assert_eq!(
        lab.monitor().and_then(|m| m.table(addr(11))),
        Some(table),
        "learned the slave's own table"
    );
    // Frozen code: the second repeat of a code drops the release within two cycles.
    lab.safety_sensor_mut(11).expect("sensor").set_frozen(true);
    let now = lab.bus().now();
    lab.bus_mut().advance_to(now + us(3 * 13 * 154));
    assert!(!lab.released(11));
    assert!(matches!(
        lab.monitor().and_then(|m| m.state(addr(11))),
        Some(Err(NotReleased::Frozen { .. }))
    ));
    assert!(lab.released(12), "the other slave is unaffected");
    lab.safety_sensor_mut(11).expect("sensor").set_frozen(false);
    let now = lab.bus().now();
    lab.bus_mut().advance_to(now + us(10 * 13 * 154));
    assert!(lab.released(11), "a full correct rotation releases again");
    // Tripped: 0000 drops the release at the next exchange.
    lab.safety_sensor_mut(12).expect("sensor").set_free(false);
    let now = lab.bus().now();
    lab.bus_mut().advance_to(now + us(13 * 154));
    assert_eq!(
        lab.monitor().and_then(|m| m.state(addr(12))),
        Some(Err(NotReleased::Tripped))
    );
    // Missing: the slave is unplugged; 40 ms without a code.
    let s11 = lab.slave_id(11).expect("11");
    lab.bus_mut().detach(s11);
    let now = lab.bus().now();
    lab.bus_mut()
        .advance_to(now + asi_phy::SimDuration::from_millis(30));
    assert!(lab.released(11));
    let now = lab.bus().now();
    lab.bus_mut()
        .advance_to(now + asi_phy::SimDuration::from_millis(15));
    assert_eq!(
        lab.monitor().and_then(|m| m.state(addr(11))),
        Some(Err(NotReleased::Missing))
    );
}

#[test]
fn a_wrong_code_table_is_not_released() {
    let mut lab = running_lab(40);
    lab.bus_mut().advance_to(ms(100));
    assert!(lab.released(11));
    // Swap the sensor at 11 for one with another table (a wrong slave).
    let s11 = lab.slave_id(11).expect("11");
    lab.bus_mut().detach(s11);
    let other =
        asi_slaves::devices::SafetySensor::new(asi_slaves::monitor::CodeTable::from_serial(999));
    lab.bus_mut()
        .add_slave(Slave::new(
            "other sensor",
            addr(11),
            asi_slaves::devices::GG505S,
            Box::new(other),
        ))
        .expect("slave");
    lab.bus_mut().advance_to(ms(400));
    assert!(lab.bus().master().las().contains(a(11)), "AS-i cannot tell");
    assert!(!lab.released(11), "the monitor can");
    assert!(matches!(
        lab.monitor().and_then(|m| m.state(addr(11))),
        Some(Err(NotReleased::WrongCode { .. }))
    ));
}
