//! What a receiver listens for and its settings, derived from the bus timing.

use crate::telegram::{Request, Response};
use crate::time::SimDuration;
use crate::timing::BusTiming;

/// Which telegrams a receiver listens for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Expect {
    /// Every telegram is a 14-bit request (a slave that hears only the master).
    Requests,
    /// Every telegram is a 7-bit response (the master during its response window).
    Responses,
    /// A live bus: a telegram that starts within the response timeout after a valid request is
    /// that request's response, anything else a request. Responses never change the receiver's
    /// synchronisation: a slave that is not addressed waits out the reply of another slave
    /// (A²SI §7.1.2.1). This is the setting for slaves and for bus monitors.
    Both,
}

/// What a received telegram was taken for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TelegramKind {
    /// A master request, 14 bits expected.
    Request,
    /// A slave response, 7 bits expected.
    Response,
}

impl TelegramKind {
    /// The length this kind of telegram has.
    pub const fn bits(self) -> u32 {
        match self {
            TelegramKind::Request => Request::BITS,
            TelegramKind::Response => Response::BITS,
        }
    }
}

/// Receiver settings, derived from a [`BusTiming`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReceiverConfig {
    pub(super) half_bit: u64,
    pub(super) tolerance: u64,
    pub(super) pause: u64,
    pub(super) async_pause: u64,
    pub(super) response_window: u64,
    pub(super) expect: Expect,
}

impl ReceiverConfig {
    /// The settings for `timing`, listening for `expect`.
    pub fn new(timing: &BusTiming, expect: Expect) -> ReceiverConfig {
        ReceiverConfig {
            half_bit: timing.half_bit().as_nanos().max(1),
            tolerance: timing.tolerance().as_nanos(),
            pause: timing.min_pause().as_nanos().max(1),
            async_pause: timing.async_pause().as_nanos(),
            response_window: timing.response_timeout().as_nanos(),
            expect,
        }
    }

    /// What this receiver listens for.
    pub const fn expect(&self) -> Expect {
        self.expect
    }

    /// The silence that ends a telegram.
    pub const fn pause(&self) -> SimDuration {
        SimDuration::from_nanos(self.pause)
    }
}

impl BusTiming {
    /// The receiver settings that follow from this timing.
    pub fn receiver(&self, expect: Expect) -> ReceiverConfig {
        ReceiverConfig::new(self, expect)
    }
}
