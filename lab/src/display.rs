//! The display word shown on the floor displays and in the cabin (tables 4.2
//! and 4.4 of the lift thesis; docs/lab-bus.md).
//!
//! Layout, bit 0 = D1:
//!
//! ```text
//!  D10 D9 D8 D7 D6 | D5 | D4   | D3     | D2    | D1
//!  floor 1..24     | up | down | moving | fault | parity
//! ```
//!
//! **Parity (asi-lift's decision; the thesis names the bit but not the rule):** even, like
//! every AS-i parity: D1 is chosen so that D10..D1 together have an even number of ones.

use core::fmt;

use serde::{Deserialize, Serialize};

/// The bits of "floor 1, standing, no fault" (D6 and the parity bit D1): what the PLC side
/// sends before the program has decided anything.
pub const FLOOR_1_AT_REST: u16 = (1 << 5) | 1;

/// Whether the bits D10..D1 of a received word pass the even parity (the decision above).
pub const fn parity_ok(bits: u16) -> bool {
    bits.count_ones() % 2 == 0
}

/// The highest floor number the word carries (five bits, D10..D6, numbers 1..24 in table 4.2).
pub const MAX_FLOOR: u8 = 24;

const FLOOR_SHIFT: u16 = 5;
const UP: u16 = 1 << 4;
const DOWN: u16 = 1 << 3;
const MOVING: u16 = 1 << 2;
const FAULT: u16 = 1 << 1;
const PARITY: u16 = 1;
const WIDTH_MASK: u16 = (1 << 10) - 1;

/// What a display shows: floor number, arrows, moving and fault lamps (table 4.2 of the lift
/// thesis). The PLC program decides it, [`DisplayWord::encode`] gives the 10 bits D10..D1 the
/// handshakes carry, and a display reads them back with [`DisplayWord::decode`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct DisplayWord {
    /// Floor number 1..=24 (D10..D6, `Cislo_Patra`).
    pub floor: u8,
    /// Up arrow (D5, `Smer_Nahoru`).
    pub up: bool,
    /// Down arrow (D4, `Smer_Dolu`).
    pub down: bool,
    /// The cabin is moving (D3, "jede / stojí").
    pub moving: bool,
    /// Fault lamp (D2, `Porucha`).
    pub fault: bool,
}

/// Why a 10-bit display word cannot be shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
pub enum DisplayWordError {
    /// Bits above D10 are set: not a display word.
    #[error("display word {raw:#06x} has bits above D10 set")]
    TooWide {
        /// The word as received.
        raw: u16,
    },
    /// D10..D1 have an odd number of ones.
    #[error("display word {raw:#05x} fails the even parity over D10..D1")]
    Parity {
        /// The word as received.
        raw: u16,
    },
    /// The floor number is 0 or above 24.
    #[error("display word carries floor {floor}: floor numbers are 1..24")]
    Floor {
        /// The floor number in D10..D6.
        floor: u8,
    },
}

impl DisplayWord {
    /// The 10-bit word D10..D1 with its even parity bit; fails for a floor outside 1..=24.
    pub fn encode(&self) -> Result<u16, DisplayWordError> {
        if !(1..=MAX_FLOOR).contains(&self.floor) {
            return Err(DisplayWordError::Floor { floor: self.floor });
        }
        let flag = |on: bool, bit: u16| if on { bit } else { 0 };
        let data = u16::from(self.floor) << FLOOR_SHIFT
            | flag(self.up, UP)
            | flag(self.down, DOWN)
            | flag(self.moving, MOVING)
            | flag(self.fault, FAULT);
        Ok(data | flag(data.count_ones() % 2 == 1, PARITY))
    }

    /// Reads a received word, checking width, parity and floor number in that order, so a
    /// corrupted word is reported rather than shown as garbage.
    pub fn decode(raw: u16) -> Result<DisplayWord, DisplayWordError> {
        if raw & !WIDTH_MASK != 0 {
            return Err(DisplayWordError::TooWide { raw });
        }
        if !parity_ok(raw) {
            return Err(DisplayWordError::Parity { raw });
        }
        // Five bits: always fits in a u8.
        let floor = (raw >> FLOOR_SHIFT) as u8;
        if !(1..=MAX_FLOOR).contains(&floor) {
            return Err(DisplayWordError::Floor { floor });
        }
        Ok(DisplayWord {
            floor,
            up: raw & UP != 0,
            down: raw & DOWN != 0,
            moving: raw & MOVING != 0,
            fault: raw & FAULT != 0,
        })
    }
}

impl fmt::Display for DisplayWord {
    /// What a passenger sees, e.g. `3 ▲ moving` or `1 fault`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.floor)?;
        for (on, text) in [
            (self.up, " ▲"),
            (self.down, " ▼"),
            (self.moving, " moving"),
            (self.fault, " fault"),
        ] {
            if on {
                f.write_str(text)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
// Binary literals grouped by field (floor | up | down | moving | fault | parity).
#[allow(clippy::unusual_byte_groupings)]
mod tests {
    use super::*;

    #[test]
    fn the_word_before_the_program_decides_is_floor_1_at_rest() {
        let word = DisplayWord {
            floor: 1,
            ..DisplayWord::default()
        };
        assert_eq!(word.encode(), Ok(FLOOR_1_AT_REST));
    }

    #[test]
    fn floor_3_up_moving_has_the_documented_bits() {
        let word = DisplayWord {
            floor: 3,
            up: true,
            down: false,
            moving: true,
            fault: false,
        };
        // D10..D6 = 00011, D5 up, D3 moving: four ones, so D1 = 0.
        assert_eq!(word.encode(), Ok(0b00011_1_0_1_0_0));
        // Floor 1 alone has one 1: D1 = 1 makes it even.
        let floor1 = DisplayWord {
            floor: 1,
            up: false,
            down: false,
            moving: false,
            fault: false,
        };
        assert_eq!(floor1.encode(), Ok(0b00001_0_0_0_0_1));
    }

    #[test]
    fn every_valid_word_round_trips_and_every_single_bit_flip_is_caught() {
        for floor in 1..=24u8 {
            for flags in 0..16u8 {
                let word = DisplayWord {
                    floor,
                    up: flags & 8 != 0,
                    down: flags & 4 != 0,
                    moving: flags & 2 != 0,
                    fault: flags & 1 != 0,
                };
                let raw = word.encode().unwrap_or(u16::MAX);
                assert_eq!(DisplayWord::decode(raw), Ok(word));
                for bit in 0..10 {
                    assert_eq!(
                        DisplayWord::decode(raw ^ (1 << bit)),
                        Err(DisplayWordError::Parity {
                            raw: raw ^ (1 << bit)
                        })
                    );
                }
            }
        }
    }

    #[test]
    fn bad_words_are_named_not_shown() {
        assert_eq!(
            DisplayWord::decode(0x400),
            Err(DisplayWordError::TooWide { raw: 0x400 })
        );
        // Floor 0 with even parity.
        assert_eq!(
            DisplayWord::decode(0b00000_1_1_0_0_0),
            Err(DisplayWordError::Floor { floor: 0 })
        );
        // Floor 25 = 11001 (three ones) with D1 = 1.
        assert_eq!(
            DisplayWord::decode(0b11001_0_0_0_0_1),
            Err(DisplayWordError::Floor { floor: 25 })
        );
        let err = DisplayWord {
            floor: 0,
            up: false,
            down: false,
            moving: false,
            fault: false,
        }
        .encode();
        assert_eq!(err, Err(DisplayWordError::Floor { floor: 0 }));
    }
}
