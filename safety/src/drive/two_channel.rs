//! The drive manual's activation of a function by two digital inputs (docs/drive-safety.md §3.5).
//!
//! The drive manual's drive (a TGZ) activates one safety function per axis by two digital inputs,
//! active-low: both must change within 10 ms of each other, else the function stays active
//! until the drive restarts. [`TwoChannelActivation`] turns the two inputs into the function's
//! control bit of [`super::ControlBits`].
//!
//! **Decisions** where the drive manual is silent: one input FALSE is enough to request the
//! function (the safe side: the request does not wait for the second channel); the request ends
//! only when both are TRUE again; the second edge may come up to 10 ms after the first (the scan
//! that sees the inputs agree at 10 ms counts), a scan that still sees them differ 10 ms after the
//! first scan that saw them differ latches the request; a latched request is left only by
//! [`TwoChannelActivation::restart`] (the drive's restart), not by the inputs agreeing again nor by
//! S_Control_Reset.

use asi_phy::{SimDuration, SimTime};

/// The drive manual's rule: both inputs must change within 10 ms.
pub const TWO_CHANNEL_DISCREPANCY: SimDuration = SimDuration::from_millis(10);

/// The two-channel activation of one function.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TwoChannelActivation {
    discrepancy: SimDuration,
    /// Since when the two inputs differ.
    differ_since: Option<SimTime>,
    /// The discrepancy lasted too long: requested until the restart.
    latched: bool,
}

impl Default for TwoChannelActivation {
    fn default() -> Self {
        Self::new(TWO_CHANNEL_DISCREPANCY)
    }
}

impl TwoChannelActivation {
    /// An activation whose inputs may differ for at most `discrepancy`.
    pub fn new(discrepancy: SimDuration) -> Self {
        Self {
            discrepancy,
            differ_since: None,
            latched: false,
        }
    }

    /// One scan at `now` with the two inputs (active-low: FALSE = requested); returns the
    /// function's control bit (FALSE = requested).
    pub fn scan(&mut self, now: SimTime, a: bool, b: bool) -> bool {
        if a == b {
            self.differ_since = None;
        } else {
            let since = *self.differ_since.get_or_insert(now);
            if now - since >= self.discrepancy {
                self.latched = true;
            }
        }
        !self.latched && a && b
    }

    /// `true` while a discrepancy has latched the request.
    pub fn latched(&self) -> bool {
        self.latched
    }

    /// The drive's restart: the latch is cleared.
    pub fn restart(&mut self) {
        self.latched = false;
        self.differ_since = None;
    }
}
