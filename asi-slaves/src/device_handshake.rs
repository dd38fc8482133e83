//! The device side of the lab lift's nibble handshakes (tables 4.2–4.7 of the lift thesis): the
//! `*Slave` types inside the slave devices of [`crate::devices`], built on the engines of
//! [`asi_phy::handshake`] and the words of [`asi_phy::handshake_words`]. The master (PLC) side is
//! `asi_master::plc_handshake`.

use asi_phy::handshake::{
    EchoAnswerer, EchoEvent, Requester, RequesterEvent, CODE_BOTH, CODE_DOWN, CODE_UP, FOUR_STEPS,
    SEVEN_STEPS,
};
use asi_phy::handshake_words::{
    seven_step_word, split_seven_step_word, CabinPanelState, WordLog, CABIN_DISPLAY_CHANNEL,
    DISPLAY_BITS, OV_VALID,
};
use asi_phy::Nibble;

/// The device side of a floor station, table 4.3 of the lift thesis: requests the display word in
/// four steps and reports the buttons between words.
///
/// A button press is latched until it has been reported, so a press shorter than a word is
/// not lost; a held button is reported after every word.
#[derive(Clone, Debug)]
pub struct FloorStationSlave {
    requester: Requester,
    up_pressed: bool,
    down_pressed: bool,
    up_latched: bool,
    down_latched: bool,
    words: WordLog<u16>,
}

impl Default for FloorStationSlave {
    fn default() -> Self {
        Self::new()
    }
}

impl FloorStationSlave {
    /// A device that has just powered up: no word shown yet.
    pub fn new() -> FloorStationSlave {
        FloorStationSlave {
            requester: Requester::new(&FOUR_STEPS),
            up_pressed: false,
            down_pressed: false,
            up_latched: false,
            down_latched: false,
            words: WordLog::default(),
        }
    }

    /// Sets the button levels (pressed = `true`); a press is latched.
    pub fn set_buttons(&mut self, up: bool, down: bool) {
        self.up_pressed = up;
        self.down_pressed = down;
        self.up_latched |= up;
        self.down_latched |= down;
    }

    /// One step with the output nibble the master sent; returns the input nibble to present.
    ///
    /// A latched press is queued as the extra code unless one is pending already. The latches
    /// are looked at first: without a press (almost every step) there is nothing to queue,
    /// and the requester is not asked whether an extra is pending.
    #[inline]
    pub fn step(&mut self, outputs: Nibble) -> Nibble {
        let code = match (self.up_latched, self.down_latched) {
            (true, true) => Some(CODE_BOTH),
            (true, false) => Some(CODE_UP),
            (false, true) => Some(CODE_DOWN),
            (false, false) => None,
        };
        if let Some(c) = code.filter(|_| !self.requester.extra_pending()) {
            self.requester.queue_extra(c);
        }
        let (out, ev) = self.requester.step(outputs);
        match ev {
            Some(RequesterEvent::Word(bits)) => {
                let w = (bits >> 2) as u16 & DISPLAY_BITS;
                let ok = bits & 0b11 == OV_VALID && lab::display::parity_ok(w);
                self.words.record(ok.then_some(w));
            }
            Some(RequesterEvent::Extra(c)) => {
                if c == CODE_UP || c == CODE_BOTH {
                    self.up_latched = self.up_pressed;
                }
                if c == CODE_DOWN || c == CODE_BOTH {
                    self.down_latched = self.down_pressed;
                }
            }
            _ => {}
        }
        out
    }

    /// The last good display word received.
    pub fn display(&self) -> Option<u16> {
        self.words.last()
    }

    /// Words received and dropped.
    pub fn words(&self) -> &WordLog<u16> {
        &self.words
    }

    /// Power-up reset: the display goes blank, latches are cleared.
    pub fn reset(&mut self) {
        *self = FloorStationSlave::new();
    }
}

/// The device side of the cabin display (table 4.5 of the lift thesis): requests the word in
/// 7 steps.
#[derive(Clone, Debug)]
pub struct CabinDisplaySlave {
    requester: Requester,
    words: WordLog<u16>,
}

impl Default for CabinDisplaySlave {
    fn default() -> Self {
        Self::new()
    }
}

impl CabinDisplaySlave {
    /// A device that has just powered up.
    pub fn new() -> CabinDisplaySlave {
        CabinDisplaySlave {
            requester: Requester::new(&SEVEN_STEPS),
            words: WordLog::default(),
        }
    }

    /// One step with the master's output nibble; returns the input nibble to present.
    #[inline]
    pub fn step(&mut self, outputs: Nibble) -> Nibble {
        let (out, ev) = self.requester.step(outputs);
        if let Some(RequesterEvent::Word(bits)) = ev {
            let (e, d, o, v) = split_seven_step_word(bits);
            let w = d & DISPLAY_BITS;
            let ok =
                e == CABIN_DISPLAY_CHANNEL && v && !o && d >> 10 == 0 && lab::display::parity_ok(w);
            self.words.record(ok.then_some(w));
        }
        out
    }

    /// The last good display word.
    pub fn display(&self) -> Option<u16> {
        self.words.last()
    }

    /// Words received and dropped.
    pub fn words(&self) -> &WordLog<u16> {
        &self.words
    }

    /// Power-up reset.
    pub fn reset(&mut self) {
        *self = CabinDisplaySlave::new();
    }
}

/// The device side of the cabin panel (tables 4.6/4.7 of the lift thesis): answers the master's
/// step requests ([`EchoAnswerer`]); the two halves of one 32-bit word are sampled together when
/// half 0 starts, and the halves alternate with every half answered to its last step.
#[derive(Clone, Debug)]
pub struct CabinPanelSlave {
    answerer: EchoAnswerer,
    signals: CabinPanelState,
    snapshot: (u16, u16),
    next_half: u8,
    refused: u32,
}

impl Default for CabinPanelSlave {
    fn default() -> Self {
        Self::new()
    }
}

impl CabinPanelSlave {
    /// A device that has just powered up.
    pub fn new() -> CabinPanelSlave {
        CabinPanelSlave {
            answerer: EchoAnswerer::new(&SEVEN_STEPS),
            signals: CabinPanelState::default(),
            snapshot: (0, 0),
            next_half: 0,
            refused: 0,
        }
    }

    /// The current signal levels (read by the next word).
    pub fn signals_mut(&mut self) -> &mut CabinPanelState {
        &mut self.signals
    }

    /// The current signal levels.
    pub fn signals(&self) -> &CabinPanelState {
        &self.signals
    }

    /// Requests refused as out of sequence since power-up.
    pub fn refused(&self) -> u32 {
        self.refused
    }

    /// One step with the master's output nibble; returns the input nibble to present.
    #[inline]
    pub fn step(&mut self, outputs: Nibble) -> Nibble {
        let signals = self.signals;
        let half = self.next_half;
        let snapshot = &mut self.snapshot;
        let (out, ev) = self.answerer.step_with(outputs, || {
            if half == 0 {
                *snapshot = signals.halves();
                seven_step_word(0, snapshot.0, false, true)
            } else {
                seven_step_word(1, snapshot.1, false, true)
            }
        });
        match ev {
            // The next half only after this one was answered to its end: a word the master
            // abandoned (or the activation's default 1111, which looks like a first step) is
            // sent again from its start.
            Some(EchoEvent::WordDone) => self.next_half ^= 1,
            Some(EchoEvent::Refused { .. }) => self.refused = self.refused.wrapping_add(1),
            _ => {}
        }
        out
    }

    /// Power-up reset (keeps the signal levels, which are the plant's).
    pub fn reset(&mut self) {
        let s = self.signals;
        *self = CabinPanelSlave::new();
        self.signals = s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The floor station's step as it was: asks the requester first whether an extra code is
    /// pending, then looks at the latches (the reference for [`FloorStationSlave::step`]).
    fn reference_step(s: &mut FloorStationSlave, outputs: Nibble) -> Nibble {
        if !s.requester.extra_pending() {
            let code = match (s.up_latched, s.down_latched) {
                (true, true) => Some(CODE_BOTH),
                (true, false) => Some(CODE_UP),
                (false, true) => Some(CODE_DOWN),
                (false, false) => None,
            };
            if let Some(c) = code {
                s.requester.queue_extra(c);
            }
        }
        let (out, ev) = s.requester.step(outputs);
        match ev {
            Some(RequesterEvent::Word(bits)) => {
                let w = (bits >> 2) as u16 & DISPLAY_BITS;
                let ok = bits & 0b11 == OV_VALID && lab::display::parity_ok(w);
                s.words.record(ok.then_some(w));
            }
            Some(RequesterEvent::Extra(c)) => {
                if c == CODE_UP || c == CODE_BOTH {
                    s.up_latched = s.up_pressed;
                }
                if c == CODE_DOWN || c == CODE_BOTH {
                    s.down_latched = s.down_pressed;
                }
            }
            _ => {}
        }
        out
    }

    proptest! {
        /// Any run of output nibbles and button changes: the same inputs and the same state
        /// after every step as the reference.
        #[test]
        fn the_floor_station_steps_as_the_reference(
            run in proptest::collection::vec((0u8..16, 0u8..8), 1..400),
        ) {
            let mut fast = FloorStationSlave::new();
            let mut slow = FloorStationSlave::new();
            for (outputs, buttons) in run {
                // One step in two changes nothing but the outputs; otherwise the buttons.
                if buttons < 4 {
                    let (up, down) = (buttons & 1 != 0, buttons & 2 != 0);
                    fast.set_buttons(up, down);
                    slow.set_buttons(up, down);
                }
                let outputs = Nibble::from_low_bits(outputs);
                prop_assert_eq!(fast.step(outputs), reference_step(&mut slow, outputs));
                prop_assert_eq!(format!("{fast:?}"), format!("{slow:?}"));
            }
        }
    }
}
