//! Both sides of the nibble handshakes and of S-7.3 stepped against each other, without a bus:
//! the PLC side of asi-master and the device side of asi-slaves, on the engines and words of
//! asi-phy.

use crate::common::display_bits;
use asi_master::integrated_analog::*;
use asi_master::plc_handshake::*;
use asi_phy::handshake::*;
use asi_phy::handshake_words::*;
use asi_phy::Nibble;
use asi_slaves::analog_firmware::*;
use asi_slaves::device_handshake::*;

/// Runs a PLC-side and a device-side step function against each other: the device steps
/// `dev_per_plc` times per PLC step (cycles per scan).
fn run<F, G>(mut plc: F, mut dev: G, scans: usize, dev_per_plc: usize)
where
    F: FnMut(Nibble) -> Nibble,
    G: FnMut(Nibble) -> Nibble,
{
    let mut input = Nibble::ZERO; // slave -> master
    let mut output; // master -> slave
    for _ in 0..scans {
        output = plc(input);
        for _ in 0..dev_per_plc {
            input = dev(output);
        }
    }
}

#[test]
#[allow(clippy::unusual_byte_groupings)] // grouped by the fields of table 4.2
fn display_word_layout_of_table_4_2() {
    let w = display_bits(3, true, false, true, false);
    // D10..D6 = 00011, D5 up = 1, D4 = 0, D3 moving = 1, D2 = 0, D1 parity.
    assert_eq!(w >> 1, 0b00011_1_0_1_0);
    assert!(lab::display::parity_ok(w));
    assert_eq!(w & 1, 0, "four ones already: parity 0");
    assert_eq!(
        display_bits(1, false, true, false, false),
        0b00001_0_1_0_0_0
    );
    let w = display_bits(2, false, false, false, false);
    assert_eq!(w, 0b00010_0_0_0_0_1, "one 1: parity 1");
    let shown = lab::DisplayWord::decode(w).expect("valid");
    assert_eq!((shown.floor, shown.up, shown.down), (2, false, false));
    let floor_25 = lab::DisplayWord {
        floor: 25,
        ..lab::DisplayWord::default()
    };
    assert_eq!(
        floor_25.encode(),
        Err(lab::DisplayWordError::Floor { floor: 25 })
    );
    assert!(!lab::display::parity_ok(0b1));
}

#[test]
fn floor_word_and_buttons_pass_in_both_directions() {
    let mut m = FloorStationMaster::new();
    let mut s = FloorStationSlave::new();
    let w = display_bits(4, false, true, true, false);
    m.set_word(w);
    s.set_buttons(true, false);
    s.set_buttons(false, false); // a short press, latched
    let mut calls = FloorCalls::default();
    let mut dev = |o| s.step(o);
    run(
        |i| {
            let o = m.step(i);
            let c = m.take_calls();
            calls.up |= c.up;
            calls.down |= c.down;
            o
        },
        &mut dev,
        20,
        3,
    );
    assert_eq!(s.display(), Some(w));
    assert!(calls.up && !calls.down);
    assert!(m.words_sent() >= 2);
}

#[test]
fn a_floor_step_needs_the_k_toggle() {
    let mut s = FloorStationSlave::new();
    assert_eq!(s.step(Nibble::ZERO).get(), SYNC_CODE);
    // Same K: still syncing.
    assert_eq!(s.step(Nibble::from_low_bits(0b0111)).get(), SYNC_CODE);
    // K toggled: sync acknowledged, first step 111.
    assert_eq!(s.step(Nibble::from_low_bits(0b1000)).get(), 0b111);
    // K toggled with D10..D8 = 000: next code 010.
    assert_eq!(s.step(Nibble::from_low_bits(0b0000)).get(), 0b010);
    assert_eq!(s.step(Nibble::from_low_bits(0b0000)).get(), 0b010);
}

#[test]
fn cabin_display_word_passes_in_seven_steps() {
    let mut m = CabinDisplayMaster::new();
    let mut s = CabinDisplaySlave::new();
    let w = display_bits(17, true, false, true, true);
    m.set_word(w);
    let mut dev = |o| s.step(o);
    run(|i| m.step(i), &mut dev, 40, 2);
    assert_eq!(s.display(), Some(w));
    assert_eq!(s.words().bad(), 0);
}

#[test]
fn cabin_panel_word_passes_in_two_halves() {
    let mut m = CabinPanelMaster::new();
    let mut s = CabinPanelSlave::new();
    let want = CabinPanelState {
        floor_buttons: (1 << 2) | (1 << 20),
        bell: true,
        stop: false,
        door_closed: true,
        vane_left: true,
        vane_right: false,
    };
    *s.signals_mut() = want;
    let mut dev = |o| s.step(o);
    run(|i| m.step(i), &mut dev, 60, 2);
    assert_eq!(m.state(), Some(want));
    assert!(m.state().expect("state").floor_button(3));
    assert!(m.state().expect("state").floor_button(21));
    assert_eq!(m.words().bad(), 0);
}

#[test]
fn cabin_panel_parity_rejects_a_flipped_bit() {
    let s = CabinPanelState {
        floor_buttons: 0b101,
        ..Default::default()
    };
    let (h0, h1) = s.halves();
    assert_eq!(CabinPanelState::from_halves(h0, h1), Some(s));
    assert_eq!(CabinPanelState::from_halves(h0 ^ 1, h1), None);
}

/// A panel state whose two halves are easy to read off table 4.6: floors 1, 3, 16 and 24,
/// STOP and door closed (parity D14 = 0: six ones).
fn table_4_6_example() -> CabinPanelState {
    CabinPanelState {
        floor_buttons: (1 << 23) | (1 << 15) | 0b101,
        stop: true,
        door_closed: true,
        ..Default::default()
    }
}

/// Table 4.7 of the lift thesis, worked vector: the master's requests `K111`, `K101`, `K100`,
/// `K011`, `K010`, `K001`, `K000` with K toggling at every step, and the slave's answers: the K it
/// answers to on D3, then E3E2E1, D16..D14, ..., D1 O V of table 4.6.
#[test]
fn table_4_7_request_and_answer_nibbles() {
    let want = table_4_6_example();
    assert_eq!(want.halves(), (0x8005, 0x1480));
    let mut m = CabinPanelMaster::new();
    let mut s = CabinPanelSlave::new();
    *s.signals_mut() = want;
    // Before its first step the master looks at the slave's D3 (0 after power-up) and
    // starts with the other K.
    let mut out = m.step(Nibble::ZERO);
    let mut pairs = Vec::new();
    for _ in 0..14 {
        let answer = s.step(out);
        pairs.push((out.get(), answer.get()));
        out = m.step(answer);
    }
    #[rustfmt::skip]
    let expected: [(u8, u8); 14] = [
        // Half 0 (E = 000): D16..D1 = floors 16..1 = 1000 0000 0000 0101, O = 0, V = 1.
        (0b1_111, 0b1_000), // K 111 -> E3 E2 E1     = 000
        (0b0_101, 0b0_100), // K 101 -> D16 D15 D14  = 100
        (0b1_100, 0b1_000), // K 100 -> D13 D12 D11  = 000
        (0b0_011, 0b0_000), // K 011 -> D10 D9 D8    = 000
        (0b1_010, 0b1_000), // K 010 -> D7 D6 D5     = 000
        (0b0_001, 0b0_010), // K 001 -> D4 D3 D2     = 010
        (0b1_000, 0b1_101), // K 000 -> D1 O V       = 101
        // Half 1 (E = 001): parity 0, door closed, bell 0, STOP, vanes 00, floors 24..17.
        (0b0_111, 0b0_001), // K 111 -> E3 E2 E1     = 001
        (0b1_101, 0b1_000), // K 101 -> D16 D15 D14  = 000 (D14 parity)
        (0b0_100, 0b0_101), // K 100 -> D13 D12 D11  = SnZavD Zvonek Stop = 101
        (0b1_011, 0b1_001), // K 011 -> D10 D9 D8    = Snim2 Snim1 floor 24 = 001
        (0b0_010, 0b0_000), // K 010 -> D7 D6 D5     = floors 23..21
        (0b1_001, 0b1_000), // K 001 -> D4 D3 D2     = floors 20..18
        (0b0_000, 0b0_001), // K 000 -> D1 O V       = floor 17, O = 0, V = 1
    ];
    assert_eq!(pairs, expected);
    assert_eq!(m.state(), Some(want));
    assert_eq!((m.words().good(), m.words().bad()), (1, 0));
    // The next word starts with the other K again.
    assert_eq!(out.get(), 0b1_111);
}

/// The master completes a step only on its own K echoed: a stale answer (the other K) or
/// the same request stepped again does not advance it.
#[test]
fn a_cabin_panel_step_needs_the_echo() {
    let mut m = CabinPanelMaster::new();
    assert_eq!(
        m.step(Nibble::from_low_bits(0b1_010)).get(),
        0b0_111,
        "K = !D3"
    );
    assert_eq!(
        m.step(Nibble::from_low_bits(0b1_000)).get(),
        0b0_111,
        "no echo"
    );
    assert_eq!(
        m.step(Nibble::from_low_bits(0b0_000)).get(),
        0b1_101,
        "echo: next step"
    );
    assert_eq!(
        m.step(Nibble::from_low_bits(0b0_000)).get(),
        0b1_101,
        "stale: wait"
    );
    let mut s = CabinPanelSlave::new();
    let a = s.step(Nibble::from_low_bits(0b0_111));
    assert_eq!(a.get(), 0b0_000);
    assert_eq!(s.step(Nibble::from_low_bits(0b0_111)), a, "idempotent");
    // Out of sequence (K not toggled): refused with the other K.
    assert_eq!(s.step(Nibble::from_low_bits(0b0_101)).get(), 0b1_000);
    assert_eq!(s.refused(), 1);
    // ... until a new word starts.
    // (half 0 again: the abandoned word is sent again from its start).
    assert_eq!(s.step(Nibble::from_low_bits(0b1_111)).get(), 0b1_000);
}

/// The slave is reset (power cycle, re-admission) in the middle of a word: it refuses the
/// master's request out of sequence, the master gets no echo, starts a new word after its
/// stall limit, and the next word arrives whole; no word is taken from the torn one.
#[test]
fn cabin_panel_slave_reset_mid_word_resynchronises() {
    let want = table_4_6_example();
    let mut m = CabinPanelMaster::new().with_stall_limit(5);
    let mut s = CabinPanelSlave::new();
    *s.signals_mut() = want;
    let mut input = Nibble::ZERO;
    let mut updates = Vec::new();
    for i in 0..60 {
        let out = m.step(input);
        if i == 4 {
            s.reset();
        }
        input = s.step(out);
        updates.extend(m.take_update());
    }
    assert_eq!(s.refused(), 1);
    assert_eq!(m.restarts(), 1);
    assert_eq!(m.words().bad(), 0);
    assert!(!updates.is_empty() && updates.iter().all(|&u| u == want));
}

/// The PLC restarts in the middle of a word: the master starts a new word with the K that
/// differs from the D3 it sees, the slave takes it as a new word at once (no stall).
#[test]
fn cabin_panel_master_restart_mid_word_needs_no_stall() {
    let want = table_4_6_example();
    let mut m = CabinPanelMaster::new().with_stall_limit(5);
    let mut s = CabinPanelSlave::new();
    *s.signals_mut() = want;
    let mut input = Nibble::ZERO;
    let mut updates = Vec::new();
    for i in 0..60 {
        if i == 4 {
            // In the middle of half 0.
            m.reset();
        }
        let out = m.step(input);
        input = s.step(out);
        updates.extend(m.take_update());
    }
    assert_eq!((m.restarts(), s.refused()), (0, 0));
    // The slave sends the abandoned half 0 again from its start: nothing is dropped.
    assert_eq!(m.words().bad(), 0);
    assert!(updates.len() >= 2 && updates.iter().all(|&u| u == want));
}

#[test]
fn a_requester_reset_mid_word_recovers() {
    let mut m = CabinDisplayMaster::new();
    let mut s = CabinDisplaySlave::new();
    let w = display_bits(2, false, false, false, false);
    m.set_word(w);
    let mut input = Nibble::ZERO;
    for i in 0..400 {
        let out = m.step(input);
        if i == 9 {
            s.reset();
        }
        input = s.step(out);
    }
    assert_eq!(s.display(), Some(w));
}

#[test]
fn an_answerer_is_idempotent() {
    let mut a = Answerer::new(&FOUR_STEPS);
    let (o1, e1) = a.step_with(Nibble::from_low_bits(0b111), || 0b101_000_000_000);
    assert_eq!(e1, Some(AnswererEvent::WordStarted));
    assert_eq!(o1.get(), 0b1101);
    let (o2, e2) = a.step_with(Nibble::from_low_bits(0b111), || 0);
    assert_eq!((o2, e2), (o1, None));
}

/// Integrated analog: both sides step on the same Data_Exchange (the slave answers within
/// the telegram), so after the sync a value takes exactly 7 exchanges.
#[test]
fn an_output_value_takes_seven_exchanges() {
    let mut m = S73OutputMaster::new(1);
    let mut s = S73OutputSlave::new(1);
    m.set_value(1, 11000);
    let mut input = Nibble::ZERO;
    let mut got_at = Vec::new();
    for cycle in 0..40 {
        let out = m.step(input);
        input = s.step(out);
        if s.received() as usize > got_at.len() {
            got_at.push(cycle);
        }
    }
    assert_eq!(s.value(1), Some(11000));
    assert!(got_at.len() >= 4);
    assert!(got_at.windows(2).all(|w| w[1] - w[0] == 7), "{got_at:?}");
}

#[test]
fn input_values_alternate_channels() {
    let mut m = S73InputMaster::new();
    let mut s = S73InputSlave::new(2);
    s.set_value(
        1,
        AnalogValue {
            value: 1234,
            overflow: false,
            valid: true,
        },
    );
    s.set_value(
        2,
        AnalogValue {
            value: 0xFFFF,
            overflow: true,
            valid: true,
        },
    );
    let mut input = Nibble::ZERO;
    let mut got = Vec::new();
    for _ in 0..40 {
        let (out, done) = m.step(input);
        got.extend(done);
        input = s.step(out);
    }
    assert!(got.len() >= 4);
    assert!(got.contains(&(
        1,
        AnalogValue {
            value: 1234,
            overflow: false,
            valid: true
        }
    )));
    assert!(got.iter().any(|(ch, v)| *ch == 2 && v.overflow));
}
