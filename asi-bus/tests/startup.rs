//! Power-on start-up of the lab lift's bus: detection, activation, first cycles (docs/master.md;
//! docs/asi.md §5.1).

use crate::common::*;
use asi_bus::lab::LabLift;
use asi_master::{Phase, TxKind};

#[test]
fn power_on_start_up_of_the_lab_bus() {
    let mut lab = LabLift::new().expect("lab");
    lab.bus_mut().enable_trace(10_000);
    // Offline until the start-up delay is over.
    assert_eq!(lab.bus().master().phase(), Phase::Offline);
    assert!(lab.bus().master().flags().offline_ready());
    lab.bus_mut().advance_to(ms(4));
    assert!(
        lab.bus_mut().drain_trace().is_empty(),
        "no traffic while offline"
    );
    let mut trace = Vec::new();
    // Until the end of the second normal cycle.
    while lab.bus().stats().cycles < 2 {
        let t = lab.bus().poll_at();
        lab.bus_mut().advance_to(t);
        trace.extend(lab.bus_mut().drain_trace());
    }
    let m = lab.bus().master();
    assert_eq!(m.phase(), Phase::NormalOperation);
    assert_eq!(m.lds().to_string(), "1A 2A 3A 4A 5A 6A 7A 8A 10A 11A 12A");
    assert_eq!(m.las(), m.lds());
    assert_eq!(m.las(), m.lps());
    assert!(m.flags().config_ok());
    assert!(m.flags().normal_operation_active());
    // F3 = 1: protected mode (configuration not active); F0..F2 = 0.
    assert_eq!(lab.bus().image().input.word(0) >> 12, 0b1000);
    // Every detected address was read IO, ID, ID1, ID2 in that order.
    let detect: Vec<_> = trace
        .iter()
        .filter(|r| r.kind == TxKind::Detection)
        .collect();
    assert_eq!(detect.len(), 11 * 4 + (32 - 11) + (31 - 11));
    let cycle = (11 + 2) * 154;
    assert_eq!(lab.bus().stats().cycle_min, us(cycle));
    insta::assert_snapshot!(lines(&trace));
}

/// Activation sends the converter's I/O slave (7) Write_Parameter and a Data_Exchange with the
/// default outputs 1111, the passive state of the slave IC's outputs (ZMD ASI4U datasheet
/// §3.7.1: an IC reset leaves 0xF in the data output register, drivers off): the telegram
/// goes out, and the converter never sees run or up until the PLC commands them.
#[test]
fn activation_default_outputs_command_nothing_at_the_converter() {
    let mut lab = LabLift::new().expect("lab");
    lab.bus_mut().enable_trace(10_000);
    let mut trace = Vec::new();
    while lab.bus().stats().cycles < 3 {
        let t = lab.bus().poll_at();
        lab.bus_mut().advance_to(t);
        trace.extend(lab.bus_mut().drain_trace());
        let c = lab.converter().expect("converter");
        assert!(!c.run() && !c.direction_up(), "at {t}: {:?}", c.outputs());
    }
    let activation: Vec<_> = trace
        .iter()
        .filter(|r| r.kind == TxKind::Activation && r.request.address().get() == 7)
        .map(|r| r.request.info())
        .collect();
    assert_eq!(
        activation,
        [0b11111, 0b01111],
        "Write_Parameter, Data_Exchange 1111"
    );
    lab.bus_mut()
        .image_mut()
        .output
        .set_nibble(a(7), asi_phy::Nibble::from_low_bits(0b0011));
    let t = lab.bus().now() + us(5_000);
    lab.bus_mut().advance_to(t);
    let c = lab.converter().expect("converter");
    assert!(c.run() && c.direction_up());
}
