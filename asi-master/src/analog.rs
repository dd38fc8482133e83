//! S-7.3 analog transfer (seed 003 §2.3, table 2.2; reference/asi.md §6.3; SPEC §3).
//!
//! A 16-bit value travels with its channel E3..E1, overflow O and valid V in 7 steps of 3 data
//! bits plus the control bit K: E3E2E1 | D16..D14 | D13..D11 | D10..D8 | D7..D5 | D4..D2 |
//! D1 O V. The step handshake is the one of [`crate::handshake`] (requester code on D2..D0,
//! answerer K on D3 and data on D2..D0) with the seven codes of table 4.5.
//!
//! Direction (**Decision**, following seed tables 4.5 and 4.7 which use this layout): for an
//! output slave (master → slave) the slave requests and the master answers; for an input slave
//! the master requests and the slave answers. The master runs its side itself (integrated
//! analog, master profile M3/M4 with CTT1) and steps it on every Data_Exchange with the slave;
//! the slave's firmware reacts within the same telegram, so one value takes 7 cycles.
//!
//! Channels (**Decision**): E3..E1 is the channel number 1..4 in binary (seed: "binary number
//! of the channel 1 to 4"); the master sends the channels of an output slave in turn, an input
//! slave sends its channels in turn. Values with O = 1 are written to the image as 0x7FFF
//! (overflow), values with V = 0 leave the image word unchanged.

use crate::handshake::{
    seven_step_word, split_seven_step_word, Answerer, AnswererEvent, Requester, RequesterEvent,
    SEVEN_STEPS,
};
use asi_phy::Nibble;

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

/// The master's side of an S-7.3 output slave: answers the slave's step requests with the
/// channel values taken from the output image.
#[derive(Clone, Debug)]
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

/// The slave's side of an S-7.3 output: requests values, keeps the last valid one per channel.
#[derive(Clone, Debug)]
pub struct S73OutputSlave {
    requester: Requester,
    channels: u8,
    values: [Option<u16>; 4],
    received: u32,
}

impl S73OutputSlave {
    /// A slave with `channels` (1..=4) channels that has just powered up.
    pub fn new(channels: u8) -> S73OutputSlave {
        S73OutputSlave {
            requester: Requester::new(&SEVEN_STEPS),
            channels: channels.clamp(1, 4),
            values: [None; 4],
            received: 0,
        }
    }

    /// One step with the master's output nibble; returns the input nibble.
    pub fn step(&mut self, outputs: Nibble) -> Nibble {
        let (out, ev) = self.requester.step(outputs);
        if let Some(RequesterEvent::Word(bits)) = ev {
            let (e, d, o, v) = split_seven_step_word(bits);
            if v && !o && (1..=self.channels).contains(&e) {
                self.values[(e - 1) as usize] = Some(d);
                self.received = self.received.wrapping_add(1);
            }
        }
        out
    }

    /// The last valid value of `channel` (1..=4), `None` before the first.
    pub fn value(&self, channel: u8) -> Option<u16> {
        self.values
            .get(channel.wrapping_sub(1) as usize)
            .copied()
            .flatten()
    }

    /// Values received.
    pub fn received(&self) -> u32 {
        self.received
    }

    /// Power-up reset: no values.
    pub fn reset(&mut self) {
        *self = S73OutputSlave::new(self.channels);
    }
}

/// The master's side of an S-7.3 input slave: requests values step by step.
#[derive(Clone, Debug)]
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

/// The slave's side of an S-7.3 input: answers the master's steps with its channels in turn.
#[derive(Clone, Debug)]
pub struct S73InputSlave {
    answerer: Answerer,
    channels: u8,
    next: u8,
    values: [AnalogValue; 4],
}

impl S73InputSlave {
    /// A slave with `channels` (1..=4) channels, all values invalid.
    pub fn new(channels: u8) -> S73InputSlave {
        S73InputSlave {
            answerer: Answerer::new(&SEVEN_STEPS),
            channels: channels.clamp(1, 4),
            next: 1,
            values: [AnalogValue::default(); 4],
        }
    }

    /// Sets the value of `channel` (1..=4).
    pub fn set_value(&mut self, channel: u8, v: AnalogValue) {
        if let Some(x) = self.values.get_mut(channel.wrapping_sub(1) as usize) {
            *x = v;
        }
    }

    /// One step with the master's output nibble; returns the input nibble.
    pub fn step(&mut self, outputs: Nibble) -> Nibble {
        let ch = self.next;
        let v = self.values[(ch - 1) as usize];
        let (out, ev) = self.answerer.step_with(outputs, || {
            seven_step_word(ch, v.value, v.overflow, v.valid)
        });
        if ev == Some(AnswererEvent::WordStarted) {
            self.next = if ch >= self.channels { 1 } else { ch + 1 };
        }
        out
    }

    /// Power-up reset (keeps the measured values, which are the plant's).
    pub fn reset(&mut self) {
        let values = self.values;
        *self = S73InputSlave::new(self.channels);
        self.values = values;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
