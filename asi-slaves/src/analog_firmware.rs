//! The slave firmware's side of the S-7.3 analog transfer (§2.3, table 2.2 of the lift thesis;
//! docs/asi.md §6.3; docs/lab-bus.md).
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
//! This module is the slave's side ([`S73OutputSlave`], [`S73InputSlave`]); the master's side
//! is `asi_master::integrated_analog`.

use asi_phy::handshake::{Answerer, AnswererEvent, Requester, RequesterEvent, SEVEN_STEPS};
use asi_phy::handshake_words::{seven_step_word, split_seven_step_word, AnalogValue};
use asi_phy::Nibble;

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
