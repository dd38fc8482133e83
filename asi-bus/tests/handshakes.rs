//! The lab lift's handshakes over the simulated bus, with the PLC side stepped from the
//! process image every 10 ms scan (docs/lab-bus.md, §5; tables 4.2–4.7, 2.2 of the lift thesis).

use crate::common::*;
use asi_bus::lab::LabLift;
use asi_bus::Bus;
use asi_master::plc_handshake::{
    CabinDisplayMaster, CabinPanelMaster, FloorCalls, FloorStationMaster,
};
use asi_master::TransactionRecord;
use asi_phy::handshake_words::CabinPanelState;
use asi_phy::{Call, Nibble, SimDuration, SimTime};

const SCAN: SimDuration = SimDuration::from_millis(10);

/// Runs the bus with a PLC scan every 10 ms (at 30 ms, 40 ms, ...) until `done` or `limit`.
fn run_plc(
    lab: &mut LabLift,
    limit: SimTime,
    mut scan: impl FnMut(&mut Bus),
    mut done: impl FnMut(&LabLift) -> bool,
) -> SimTime {
    let mut next_scan = ms(30);
    loop {
        let t = lab.bus().poll_at().min(next_scan);
        assert!(t <= limit, "not done by {limit}");
        lab.bus_mut().advance_to(t);
        if t == next_scan {
            scan(lab.bus_mut());
            next_scan += SCAN;
        }
        if done(lab) {
            // Let the transaction in progress finish, so the trace shows it.
            lab.bus_mut().advance_to(t + us(154));
            return t;
        }
    }
}

fn plc_step(bus: &mut Bus, n: u8, step: impl FnOnce(Nibble) -> Nibble) {
    let input = bus.image().input.nibble(a(n));
    let out = step(input);
    bus.image_mut().output.set_nibble(a(n), out);
}

fn exchanges_with(trace: &[TransactionRecord], n: u8) -> Vec<TransactionRecord> {
    trace
        .iter()
        .filter(|r| matches!(r.request.call(), Call::DataExchange { address, .. } if address.get() == n))
        .copied()
        .collect()
}

/// Table 4.3 of the lift thesis: the floor slave requests 111, 010, 001, 000; the PLC answers
/// D10..D8, D7..D5, D4..D2, D1 O V toggling K; between words the slave reports its buttons
/// (101 = up).
#[test]
fn floor_display_word_and_up_button() {
    let mut lab = running_lab(29);
    let word = display_bits(3, true, false, true, false);
    let mut plc = FloorStationMaster::new();
    plc.set_word(word);
    let calls = std::cell::Cell::new(FloorCalls::default());
    if let Some(f) = lab.floor_mut(1) {
        // A short press, latched by the floor electronics.
        f.set_buttons(true, false);
        f.set_buttons(false, false);
    }
    run_plc(
        &mut lab,
        ms(400),
        |bus| {
            plc_step(bus, 1, |i| plc.step(i));
            let c = plc.take_calls();
            let old = calls.get();
            calls.set(FloorCalls {
                up: old.up | c.up,
                down: old.down | c.down,
            });
        },
        |lab| {
            // Done once the button report was acknowledged and the next word requested.
            lab.floor(1).and_then(|f| f.display()) == Some(word)
                && calls.get().up
                && lab.bus().image().input.nibble(a(1)).get() == 0b0111
        },
    );
    assert!(!calls.get().down);
    assert_eq!(
        lab.floor(2).and_then(|f| f.display()),
        None,
        "floor 2 got nothing"
    );
    let trace = lab.bus_mut().drain_trace();
    insta::assert_snapshot!(folded(&exchanges_with(&trace, 1)));
}

/// Tables 4.6/4.7 of the lift thesis: the PLC requests the cabin word in two 7-step halves
/// (E = 000, E = 001) and checks its parity.
#[test]
fn cabin_32_bit_button_word() {
    let mut lab = running_lab(29);
    let want = CabinPanelState {
        floor_buttons: 1 << 1,
        bell: false,
        stop: false,
        door_closed: true,
        vane_left: true,
        vane_right: false,
    };
    if let Some(p) = lab.cabin_panel_mut() {
        p.set_floor_button(2, true);
        p.set_door_closed(true);
        p.set_vane_left(true);
    }
    let mut plc = CabinPanelMaster::new();
    let got = std::cell::Cell::new(None);
    run_plc(
        &mut lab,
        ms(800),
        |bus| {
            plc_step(bus, 6, |i| plc.step(i));
            got.set(got.get().or(plc.take_update()));
        },
        |_| got.get().is_some(),
    );
    assert_eq!(got.get(), Some(want));
    assert_eq!(plc.words().bad(), 0);
    let trace = lab.bus_mut().drain_trace();
    insta::assert_snapshot!(folded(&exchanges_with(&trace, 6)));
}

#[test]
fn cabin_display_word() {
    let mut lab = running_lab(29);
    let word = display_bits(4, false, true, true, true);
    let mut plc = CabinDisplayMaster::new();
    plc.set_word(word);
    run_plc(
        &mut lab,
        ms(800),
        |bus| plc_step(bus, 5, |i| plc.step(i)),
        |lab| lab.cabin_display().and_then(|d| d.display()) == Some(word),
    );
}

/// Table 2.2 of the lift thesis: the master itself moves the analog output word to the AC2618 in 7
/// cycles (integrated S-7.3, CTT1); channel 1 carries Rychlost = 11000 µA.
#[test]
fn one_s73_value_to_the_current_loop_output() {
    let mut lab = running_lab(29);
    lab.bus_mut().image_mut().output.set_analog(10, 1, 11_000);
    let mut at = Vec::new();
    let mut last = 0;
    run_plc(
        &mut lab,
        ms(200),
        |_| {},
        |lab| {
            let out = lab.analog_output().expect("AC2618");
            if out.values_received() != last {
                last = out.values_received();
                at.push((lab.bus().now(), out.current_ua(1)));
            }
            out.current_ua(1) == 11_000
        },
    );
    // Values arrive every 7 cycles of 13 transactions, channels 1 and 2 in turn.
    let cycle = us(13 * 154);
    for w in at.windows(2) {
        assert_eq!(
            w[1].0 - w[0].0,
            SimDuration::from_nanos(7 * cycle.as_nanos())
        );
    }
    let trace = lab.bus_mut().drain_trace();
    insta::assert_snapshot!(folded(&exchanges_with(&trace, 10)));
}

/// A held floor button is reported after every word (table 4.3) but is one press; released
/// for a word and pressed again, it is a second press.
#[test]
fn a_held_floor_button_is_one_press() {
    let mut lab = running_lab(30);
    let mut plc = FloorStationMaster::new();
    let (mut reports, mut presses) = (0, 0);
    let mut scans = 0;
    let mut at = ms(30);
    let mut scan_until =
        |lab: &mut LabLift, until: SimTime, reports: &mut u32, presses: &mut u32| {
            while at < until {
                lab.bus_mut().advance_to(at);
                plc_step(lab.bus_mut(), 1, |i| plc.step(i));
                *reports += plc.take_calls().up as u32;
                *presses += plc.take_presses().up as u32;
                at += SCAN;
                scans += 1;
            }
        };
    if let Some(f) = lab.floor_mut(1) {
        f.set_buttons(true, false);
    }
    scan_until(&mut lab, ms(600), &mut reports, &mut presses);
    assert!(
        reports >= 5,
        "a held button is reported after every word: {reports}"
    );
    assert_eq!(presses, 1);
    if let Some(f) = lab.floor_mut(1) {
        f.set_buttons(false, false);
    }
    scan_until(&mut lab, ms(800), &mut reports, &mut presses);
    if let Some(f) = lab.floor_mut(1) {
        f.set_buttons(true, false);
    }
    scan_until(&mut lab, ms(1000), &mut reports, &mut presses);
    assert_eq!(presses, 2);
    assert!(scans > 90);
}
