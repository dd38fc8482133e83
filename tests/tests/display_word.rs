//! The display word of tables 4.2/4.4 of the lift thesis from the PLC program to the plant's
//! displays: the program decides a `lab::DisplayWord`, the PLC side of the floor station handshake
//! (table 4.3) and of the cabin display handshake (table 4.5) carry its bits to the devices, and
//! the plant's displays show what the program decided; a word that arrives with a flipped bit is
//! refused by the display, not shown.

use asi_master::plc_handshake::{CabinDisplayMaster, FloorStationMaster};
use asi_phy::Nibble;
use asi_slaves::device_handshake::{CabinDisplaySlave, FloorStationSlave};
use lab::DisplayWord;
use lift_model::DisplayState;

/// Steps a PLC side and a device side against each other until `done` or 400 scans, two device
/// steps (AS-i cycles) per PLC scan.
fn exchange(
    mut plc: impl FnMut(Nibble) -> Nibble,
    mut dev: impl FnMut(Nibble) -> Nibble,
    mut done: impl FnMut() -> bool,
) -> bool {
    let mut input = Nibble::ZERO;
    for _ in 0..400 {
        let output = plc(input);
        for _ in 0..2 {
            input = dev(output);
        }
        if done() {
            return true;
        }
    }
    false
}

fn every_word() -> impl Iterator<Item = DisplayWord> {
    (1..=24u8).flat_map(|floor| {
        (0..16u8).map(move |flags| DisplayWord {
            floor,
            up: flags & 8 != 0,
            down: flags & 4 != 0,
            moving: flags & 2 != 0,
            fault: flags & 1 != 0,
        })
    })
}

#[test]
fn every_word_the_program_decides_is_shown_as_decided_through_the_floor_handshake() {
    let mut n = 0;
    for word in every_word() {
        let bits = word.encode().expect("floors 1..24 encode");
        let mut plc = FloorStationMaster::new();
        let slave = std::cell::RefCell::new(FloorStationSlave::new());
        plc.set_word(bits);
        let arrived = exchange(
            |i| plc.step(i),
            |o| slave.borrow_mut().step(o),
            || slave.borrow().display() == Some(bits),
        );
        assert!(arrived, "{word:?} never arrived");
        assert_eq!(DisplayState::from_raw(bits), DisplayState::Showing(word));
        // One flipped bit anywhere in D10..D1 is refused by the display.
        for bit in 0..10 {
            assert!(
                matches!(
                    DisplayState::from_raw(bits ^ (1 << bit)),
                    DisplayState::BadWord { .. }
                ),
                "{word:?} bit {bit}"
            );
        }
        n += 1;
    }
    assert_eq!(n, 24 * 16);
}

#[test]
fn the_cabin_display_shows_the_words_the_program_decides() {
    for word in every_word().step_by(7) {
        let bits = word.encode().expect("floors 1..24 encode");
        let mut plc = CabinDisplayMaster::new();
        let slave = std::cell::RefCell::new(CabinDisplaySlave::new());
        plc.set_word(bits);
        let arrived = exchange(
            |i| plc.step(i),
            |o| slave.borrow_mut().step(o),
            || slave.borrow().display() == Some(bits),
        );
        assert!(arrived, "{word:?} never arrived");
        assert_eq!(DisplayState::from_raw(bits), DisplayState::Showing(word));
    }
}
