//! The words the lab lift's nibble handshakes carry (tables 4.2–4.7 of the lift thesis; S-7.3),
//! shared by the master (PLC) side and the device side: the display word's bits, the cabin panel's
//! 32-bit word, the S-7.3 analog value and seven-step layout, and the log of words a receiver took.

/// The 10 bits D10..D1 of a display word (tables 4.2, 4.4 of the lift thesis; its fields are the
/// lab crate's `DisplayWord`) as the handshakes carry it: bits above D10 are not part of it.
pub const DISPLAY_BITS: u16 = (1 << 10) - 1;

/// **Decision** on O and V closing a word (tables 4.3, 4.5 of the lift thesis; S-7.3 meaning of
/// table 2.2): O = 0 (value in range), V = 1 (valid data). A receiver ignores a word with V = 0,
/// O = 1 or a parity error and keeps showing the last good one.
pub const OV_VALID: u32 = 0b01;

/// The 12 bits of a floor word transfer: D10..D1 O V.
/// The floor station's word as it travels (table 4.3): the display word's bits, then O and V.
pub const fn floor_transport(bits: u16) -> u32 {
    (((bits & DISPLAY_BITS) as u32) << 2) | OV_VALID
}

/// The 21 bits of a 7-step transfer (S-7.3 layout, table 2.2 of the lift thesis): E3..E1, D16..D1,
/// O, V.
pub const fn seven_step_word(e: u8, d16: u16, overflow: bool, valid: bool) -> u32 {
    (((e & 7) as u32) << 18) | ((d16 as u32) << 2) | ((overflow as u32) << 1) | valid as u32
}

/// The fields of a 21-bit 7-step word: (E, D16..D1, O, V).
pub const fn split_seven_step_word(w: u32) -> (u8, u16, bool, bool) {
    (
        ((w >> 18) & 7) as u8,
        (w >> 2) as u16,
        w & 0b10 != 0,
        w & 1 != 0,
    )
}

/// The words a receiving side took and dropped, and the last good one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct WordLog<T> {
    last: Option<T>,
    good: u32,
    bad: u32,
}

impl<T> Default for WordLog<T> {
    fn default() -> Self {
        WordLog {
            last: None,
            good: 0,
            bad: 0,
        }
    }
}

impl<T: Copy> WordLog<T> {
    /// Records a received word: `Some` if it passed its checks, `None` if it was dropped.
    pub fn record(&mut self, w: Option<T>) {
        match w {
            Some(w) => {
                self.last = Some(w);
                self.good = self.good.wrapping_add(1);
            }
            None => self.bad = self.bad.wrapping_add(1),
        }
    }
    /// The last good word.
    pub fn last(&self) -> Option<T> {
        self.last
    }
    /// Good words received.
    pub fn good(&self) -> u32 {
        self.good
    }
    /// Words dropped (parity, O, V, channel, order).
    pub fn bad(&self) -> u32 {
        self.bad
    }
}

/// **Decision**: the cabin display word travels as S-7.3 channel E = 001 (table 4.5 gives the
/// layout E3E2E1 D16..D1 O V; the display word occupies D10..D1, D16..D11 = 0).
pub const CABIN_DISPLAY_CHANNEL: u8 = 1;

/// The cabin display's word as it travels (table 4.5): S-7.3 channel [`CABIN_DISPLAY_CHANNEL`].
pub fn cabin_transport(bits: u16) -> u32 {
    seven_step_word(CABIN_DISPLAY_CHANNEL, bits & DISPLAY_BITS, false, true)
}

/// The cabin's buttons and sensors as one 32-bit word travels them (table 4.6 of the lift thesis).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct CabinPanelState {
    /// Floor buttons 1..24: bit n − 1 = floor n.
    pub floor_buttons: u32,
    /// Bell (Zvonek).
    pub bell: bool,
    /// STOP.
    pub stop: bool,
    /// Door closed (SnZavD).
    pub door_closed: bool,
    /// Left vane sensor, Snimac_1 (table 4.6 "Sním 1", D9 of the second half).
    pub vane_left: bool,
    /// Right vane sensor, Snimac_2 (table 4.6 "Sním 2", D10 of the second half).
    pub vane_right: bool,
}

impl CabinPanelState {
    /// `true` if the button of `floor` (1..=24) is pressed.
    pub fn floor_button(&self, floor: u8) -> bool {
        (1..=24).contains(&floor) && self.floor_buttons & (1 << (floor - 1)) != 0
    }

    /// The two halves D16..D1 (table 4.6): half 0 (E = 000) = floors 16..1; half 1 (E = 001)
    /// = D14 parity, D13 door closed, D12 bell, D11 STOP, D10 right vane, D9 left vane, D8..D1
    /// floors 24..17. **Decision** (parity): D14 makes the 32 data bits of both halves hold an
    /// even number of ones.
    pub fn halves(&self) -> (u16, u16) {
        let h0 = (self.floor_buttons & 0xFFFF) as u16;
        let mut h1 = ((self.floor_buttons >> 16) & 0xFF) as u16
            | (self.vane_left as u16) << 8
            | (self.vane_right as u16) << 9
            | (self.stop as u16) << 10
            | (self.bell as u16) << 11
            | (self.door_closed as u16) << 12;
        if (h0.count_ones() + h1.count_ones()) % 2 == 1 {
            h1 |= 1 << 13;
        }
        (h0, h1)
    }

    /// The state from two halves, or `None` if the parity fails or D16, D15 of half 1 are set.
    pub fn from_halves(h0: u16, h1: u16) -> Option<CabinPanelState> {
        if (h0.count_ones() + h1.count_ones()) % 2 == 1 || h1 >> 14 != 0 {
            return None;
        }
        Some(CabinPanelState {
            floor_buttons: h0 as u32 | ((h1 as u32 & 0xFF) << 16),
            vane_left: h1 & (1 << 8) != 0,
            vane_right: h1 & (1 << 9) != 0,
            stop: h1 & (1 << 10) != 0,
            bell: h1 & (1 << 11) != 0,
            door_closed: h1 & (1 << 12) != 0,
        })
    }
}

/// The image value written for an overflowing analog input (S-7.3 convention).
pub const OVERFLOW_VALUE: u16 = 0x7FFF;

/// One analog value with its flags.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct AnalogValue {
    /// D16..D1.
    pub value: u16,
    /// O: out of range.
    pub overflow: bool,
    /// V: valid.
    pub valid: bool,
}
