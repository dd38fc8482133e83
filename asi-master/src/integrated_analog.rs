//! The master's integrated S-7.3 analog transfer (§2.3, table 2.2 of the lift thesis; docs/asi.md
//! §6.3; docs/lab-bus.md).
//!
//! A 16-bit value travels with its channel E3..E1, overflow O and valid V in 7 steps of 3 data
//! bits plus the control bit K: E3E2E1 | D16..D14 | D13..D11 | D10..D8 | D7..D5 | D4..D2 |
//! D1 O V. The step handshake is the one of [`asi_phy::handshake`] (requester code on D2..D0,
//! answerer K on D3 and data on D2..D0) with the seven codes of table 4.5.
//!
//! Direction (**Decision**, following tables 4.5 and 4.7 of the lift thesis which use this layout):
//! for an output slave (master → slave) the slave requests and the master answers; for an input
//! slave the master requests and the slave answers. The master runs its side itself (integrated
//! analog, master profile M3/M4 with CTT1) and steps it on every Data_Exchange with the slave; the
//! slave's firmware reacts within the same telegram, so one value takes 7 cycles.
//!
//! Channels (**Decision**): E3..E1 is the channel number 1..4 in binary (the lift thesis: "binary
//! number of the channel 1 to 4"); the master sends the channels of an output slave in turn, an
//! input slave sends its channels in turn. Values with O = 1 are written to the image as 0x7FFF
//! (overflow), values with V = 0 leave the image word unchanged.
//!
//! This module is the master's side ([`S73OutputMaster`], [`S73InputMaster`]); the slave's
//! firmware side is `asi_slaves::analog_firmware`.

use asi_phy::handshake::{Answerer, AnswererEvent, Requester, RequesterEvent, SEVEN_STEPS};
use asi_phy::handshake_words::{seven_step_word, split_seven_step_word, AnalogValue};
use asi_phy::Nibble;

/// The image value written for an overflowing analog input (S-7.3 convention).
pub const OVERFLOW_VALUE: u16 = 0x7FFF;

/// The master's side of an S-7.3 output slave: answers the slave's step requests with the
/// channel values taken from the output image.
#[derive(Clone, Debug, PartialEq)]
pub struct S73OutputMaster {
    answerer: Answerer,
    channels: u8,
    next: u8,
    values: [u16; 4],
    transfers: u32,
}

impl S73OutputMaster {
    /// An engine for a slave with `channels` (1..=4) channels. K starts at 1: the slave was
    /// activated with the default outputs 1111, so it has seen K = 1.
    pub fn new(channels: u8) -> S73OutputMaster {
        S73OutputMaster {
            answerer: Answerer::with_k(&SEVEN_STEPS, true),
            channels: channels.clamp(1, 4),
            next: 1,
            values: [0; 4],
            transfers: 0,
        }
    }

    /// The value to send on `channel` (1..=4) from the next transfer on.
    pub fn set_value(&mut self, channel: u8, value: u16) {
        if let Some(v) = self.values.get_mut(channel.wrapping_sub(1) as usize) {
            *v = value;
        }
    }

    /// The values to send on channels 1..=4 from the next transfer on: `set_value` of each.
    pub fn set_values(&mut self, values: [u16; 4]) {
        self.values = values;
    }

    /// One step: the slave's last input nibble in, the output nibble for the next
    /// Data_Exchange out.
    pub fn step(&mut self, input: Nibble) -> Nibble {
        let ch = self.next;
        let value = self.values[(ch - 1) as usize];
        let (out, ev) = self
            .answerer
            .step_with(input, || seven_step_word(ch, value, false, true));
        match ev {
            Some(AnswererEvent::WordStarted) => {
                self.next = if ch >= self.channels { 1 } else { ch + 1 };
            }
            Some(AnswererEvent::WordDone) => self.transfers = self.transfers.wrapping_add(1),
            _ => {}
        }
        out
    }

    /// Values transferred so far.
    pub fn transfers(&self) -> u32 {
        self.transfers
    }

    /// Back to the start (after the slave was lost or reset).
    pub fn reset(&mut self) {
        self.answerer = Answerer::with_k(&SEVEN_STEPS, true);
        self.next = 1;
    }
}

/// The master's side of an S-7.3 input slave: requests values step by step.
#[derive(Clone, Debug, PartialEq)]
pub struct S73InputMaster {
    requester: Requester,
    transfers: u32,
}

impl Default for S73InputMaster {
    fn default() -> Self {
        Self::new()
    }
}

impl S73InputMaster {
    /// A fresh engine.
    pub fn new() -> S73InputMaster {
        S73InputMaster {
            requester: Requester::new(&SEVEN_STEPS),
            transfers: 0,
        }
    }

    /// One step with the slave's last input nibble: the output nibble for the next
    /// Data_Exchange, and a completed value with its channel (1..=4).
    pub fn step(&mut self, input: Nibble) -> (Nibble, Option<(u8, AnalogValue)>) {
        let (out, ev) = self.requester.step(input);
        let done = match ev {
            Some(RequesterEvent::Word(bits)) => {
                let (e, value, overflow, valid) = split_seven_step_word(bits);
                self.transfers = self.transfers.wrapping_add(1);
                Some((
                    e,
                    AnalogValue {
                        value,
                        overflow,
                        valid,
                    },
                ))
            }
            _ => None,
        };
        (out, done)
    }

    /// Values received so far.
    pub fn transfers(&self) -> u32 {
        self.transfers
    }

    /// Back to the start.
    pub fn reset(&mut self) {
        self.requester.reset();
    }
}
