//! The process image against table 4.1 of the lift thesis on the running lab bus: where each
//! slave's nibble and each flag sits, host flags in output word 0, analog words (docs/master.md).

use crate::common::*;
use asi_bus::lab::LabLift;
use asi_bus::Bus;
use asi_master::{HostFlags, MasterConfig, Phase, ProjectedConfig, ProjectedSlave, TxKind};
use asi_phy::handshake_words::AnalogValue;
use asi_phy::{Call, Nibble};
use asi_slaves::devices::{AnalogInput, IoModule, AC2726, ANALOG_INPUT_2CH};
use asi_slaves::Slave;

#[test]
fn input_nibbles_land_where_table_4_1_puts_them() {
    let mut lab = running_lab(40);
    // Slave 7 (word 1 bits 3..0): converter ready D0 and fault D1.
    lab.converter_mut().expect("converter").set_ready(true);
    lab.converter_mut().expect("converter").set_fault(true);
    // Slave 8 (word 2 bits 15..12): load level 2, D2 = operation ready.
    lab.load_sensor_mut().expect("load").set_level(2);
    lab.bus_mut().advance_to(ms(45));
    let w = |i| lab.bus().image().input.word(i);
    assert_eq!(w(1) & 0x000F, 0b0011, "slave 7 in word 1 bits 3..0");
    assert_eq!(w(2) >> 12, 0b0110, "slave 8 in word 2 bits 15..12");
    assert_eq!(lab.bus().image().input.nibble(a(8)).get(), 0b0110);
    // Slaves 11 and 12 (word 2 bits 3..0, word 3 bits 15..12) show their safety codes.
    let s11 = (w(2) & 0xF) as u8;
    let s12 = (w(3) >> 12) as u8;
    assert!(lab
        .safety_sensor(11)
        .expect("11")
        .table()
        .codes()
        .contains(&s11));
    assert!(lab
        .safety_sensor(12)
        .expect("12")
        .table()
        .codes()
        .contains(&s12));
    // Nothing at 9 or 13..31: zero nibbles.
    assert_eq!(w(2) >> 8 & 0xF, 0, "slave 9");
    assert_eq!(w(3) & 0x0FFF, 0, "slaves 13..15");
    for i in 4..32 {
        assert_eq!(w(i), 0, "word {i}");
    }
}

#[test]
fn output_nibbles_reach_the_slaves_from_table_4_1_positions() {
    let mut lab = running_lab(40);
    // Slave 7 is word 1 bits 3..0: run (D0) and up (D1).
    let w1 = lab.bus().image().output.word(1);
    lab.bus_mut()
        .image_mut()
        .output
        .set_word(1, (w1 & !0xF) | 0b0011);
    lab.bus_mut().advance_to(ms(45));
    let c = lab.converter().expect("converter");
    assert!(c.run() && c.direction_up());
    lab.bus_mut()
        .image_mut()
        .output
        .set_nibble(a(7), Nibble::from_low_bits(0b0001));
    lab.bus_mut().advance_to(ms(50));
    let c = lab.converter().expect("converter");
    assert!(c.run() && !c.direction_up());
}

#[test]
fn flags_f0_to_f3_in_word_0() {
    let mut lab = running_lab(40);
    let f = |lab: &LabLift| lab.bus().image().input.word(0) >> 12;
    // Protected mode, configuration OK, power OK, periphery OK: only F3 (not active) = 1.
    assert_eq!(f(&lab), 0b1000);
    // F0: a projected slave missing.
    let conv = lab.slave_id(7).expect("7");
    lab.bus_mut().detach(conv);
    lab.bus_mut().advance_to(ms(60));
    assert_eq!(f(&lab), 0b1001);
    lab.bus_mut().attach(conv);
    lab.bus_mut().advance_to(ms(250));
    assert_eq!(f(&lab), 0b1000);
    // F1: AS-i power fail.
    lab.bus_mut().set_supply_voltage(20.0);
    assert_eq!(f(&lab) & 0b0010, 0b0010);
    lab.bus_mut().set_supply_voltage(30.0);
    lab.bus_mut().advance_to(ms(300));
    assert_eq!(f(&lab), 0b1000);
}

#[test]
fn f2_periphery_fault_comes_from_the_status_read() {
    let mut bus = io_bus(3);
    bus.advance_to(ms(30));
    let id = bus.find(2).expect("slave 2");
    bus.device_mut::<IoModule>(id)
        .expect("io")
        .set_periphery_fault(true);
    bus.advance_to(ms(50));
    assert!(bus.master().lpf().contains(a(2)));
    assert!(!bus.master().flags().periphery_ok());
    assert_eq!(bus.image().input.word(0) >> 14 & 1, 1, "F2");
    bus.device_mut::<IoModule>(id)
        .expect("io")
        .set_periphery_fault(false);
    bus.advance_to(ms(70));
    assert_eq!(bus.image().input.word(0) >> 14 & 1, 0);
}

#[test]
fn f3_is_0_in_configuration_mode() {
    let cfg = {
        let mut cfg = MasterConfig::default();
        cfg.mode = asi_master::Mode::Configuration;
        cfg
    };
    let slaves = vec![Slave::new("io", addr(4), AC2726, Box::new(IoModule::new()))];
    let mut bus = Bus::new(cfg, ProjectedConfig::default(), slaves).expect("bus");
    bus.advance_to(ms(30));
    assert!(
        bus.master().las().contains(a(4)),
        "activated although not projected"
    );
    // Configuration active: F3 = 0; not projected: F0 = 1.
    assert_eq!(bus.image().input.word(0) >> 12, 0b0001);
}

#[test]
fn analog_input_words_of_slaves_10_to_31() {
    let mut projected = Vec::new();
    let mut slaves = Vec::new();
    for n in [10u8, 17, 31] {
        projected.push(ProjectedSlave {
            addr: a(n),
            codes: ANALOG_INPUT_2CH,
            parameter: Nibble::ALL,
        });
        let mut dev = AnalogInput::new(2);
        for ch in 1..=2u8 {
            dev.set_value(
                ch,
                AnalogValue {
                    value: 1000 * n as u16 + ch as u16,
                    overflow: false,
                    valid: true,
                },
            );
        }
        slaves.push(Slave::new(
            format!("ai {n}"),
            addr(n),
            ANALOG_INPUT_2CH,
            Box::new(dev),
        ));
    }
    let p = ProjectedConfig::new(projected).expect("projection");
    let mut bus = Bus::new(MasterConfig::default(), p, slaves).expect("bus");
    bus.advance_to(ms(120));
    let w = |i| bus.image().input.word(i);
    assert_eq!(w(68), 10_001, "slave 10 channel 1 at word 68");
    assert_eq!(w(69), 10_002, "slave 10 channel 2 at word 69");
    assert_eq!(w(68 + 4 * 7), 17_001, "slave 17 channel 1 at word 96");
    assert_eq!(w(68 + 4 * 7 + 1), 17_002);
    assert_eq!(w(152), 31_001, "slave 31 channel 1 at word 152");
    assert_eq!(w(153), 31_002, "slave 31 channel 2 at word 153");
    assert_eq!(w(154), 0, "no channel 3");
    // Overflow reads as 0x7FFF.
    let id = bus.find(31).expect("31");
    bus.device_mut::<AnalogInput>(id).expect("ai").set_value(
        2,
        AnalogValue {
            value: 40_000,
            overflow: true,
            valid: true,
        },
    );
    bus.advance_to(ms(200));
    assert_eq!(bus.image().input.word(153), 0x7FFF);
}

#[test]
fn host_flag_offline_sends_default_outputs_then_stops() {
    let mut lab = running_lab(40);
    lab.bus_mut().enable_trace(100_000);
    lab.bus_mut()
        .image_mut()
        .output
        .set_nibble(a(7), Nibble::from_low_bits(1));
    lab.bus_mut().advance_to(ms(45));
    assert!(lab.converter().expect("c").run());
    let w0 = lab.bus().image().output.word(0);
    lab.bus_mut()
        .image_mut()
        .output
        .set_word(0, w0 | HostFlags::WORD0_OFFLINE);
    lab.bus_mut().advance_to(ms(60));
    let m = lab.bus().master();
    assert_eq!(m.phase(), Phase::Offline);
    assert!(m.flags().offline_ready());
    assert!(m.host_flags().offline);
    assert_eq!(
        lab.bus().image().input.nibble(a(8)),
        Nibble::ZERO,
        "inputs zeroed"
    );
    // The converter got the default outputs 1111 on the way out.
    let trace = lab.bus_mut().drain_trace();
    let offline: Vec<_> = trace.iter().filter(|r| r.kind == TxKind::Offline).collect();
    assert_eq!(offline.len(), 11);
    assert!(offline.iter().all(|r| r.request.info() == 0b01111));
    let c = lab.converter().expect("c");
    assert_eq!(c.received().get(), 0b1111);
    // 1111 is the slave IC's passive state: the converter's relays open (ZMD ASI4U §3.7.1).
    assert!(!c.run() && !c.direction_up());
    assert_eq!(
        lab.bus().poll_at(),
        asi_phy::SimTime::MAX,
        "quiet until the PLC acts"
    );
    // Back on line.
    lab.bus_mut().image_mut().output.set_word(0, w0);
    lab.bus_mut().advance_to(ms(100));
    assert!(lab.bus().is_running());
}

#[test]
fn host_flag_lock_data_exchange_sends_1111() {
    let mut lab = running_lab(40);
    lab.bus_mut().enable_trace(100_000);
    lab.bus_mut()
        .image_mut()
        .output
        .set_word(0, HostFlags::WORD0_LOCK_DATA_EXCHANGE);
    lab.bus_mut().advance_to(ms(50));
    assert!(!lab.bus().master().host_flags().data_exchange_active);
    let trace = lab.bus_mut().drain_trace();
    let late: Vec<_> = trace
        .iter()
        .filter(|r| r.start > ms(43) && matches!(r.request.call(), Call::DataExchange { .. }))
        .collect();
    assert!(!late.is_empty());
    assert!(late.iter().all(|r| r.request.info() & 0xF == 0xF));
}
