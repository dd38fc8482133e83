//! The seven receiver checks and the set of those a telegram failed.

use core::fmt;

/// One of the seven receiver checks, in the fixed order that picks the primary class.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[repr(u8)]
pub enum Check {
    /// The telegram does not begin with a negative pulse and a 0 bit.
    StartBit = 0,
    /// Two consecutive pulses with the same polarity.
    Alternation = 1,
    /// A pulse off the half-bit grid, a gap longer than a bit time, or too short a pause.
    Pause = 2,
    /// A bit cell without its mid-bit pulse (Manchester violation).
    Information = 3,
    /// Odd parity.
    Parity = 4,
    /// The end bit is not 1 or the line does not return to idle.
    EndBit = 5,
    /// Not 14 (request) or 7 (response) bits.
    Length = 6,
}

impl Check {
    /// All seven, in order.
    pub const ALL: [Check; 7] = [
        Check::StartBit,
        Check::Alternation,
        Check::Pause,
        Check::Information,
        Check::Parity,
        Check::EndBit,
        Check::Length,
    ];

    /// The check's name as docs/physical-layer.md spells it.
    pub const fn name(self) -> &'static str {
        match self {
            Check::StartBit => "start bit",
            Check::Alternation => "alternation",
            Check::Pause => "pause",
            Check::Information => "information",
            Check::Parity => "parity",
            Check::EndBit => "end bit",
            Check::Length => "length",
        }
    }
}

impl fmt::Display for Check {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A set of failed checks.
#[derive(Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Checks(u8);

impl Checks {
    /// No check failed.
    pub const NONE: Checks = Checks(0);

    /// The set holding `check` only.
    pub const fn only(check: Check) -> Checks {
        Checks(1 << check as u8)
    }

    /// `true` if no check failed.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// `true` if `check` failed.
    pub const fn contains(self, check: Check) -> bool {
        self.0 & (1 << check as u8) != 0
    }

    /// The set with `check` added.
    pub const fn with(self, check: Check) -> Checks {
        Checks(self.0 | (1 << check as u8))
    }

    /// Every check failed in `self` or in `other`.
    pub const fn union(self, other: Checks) -> Checks {
        Checks(self.0 | other.0)
    }

    /// The set whose bit `k` stands for the check `Check::ALL[k]`; bits 7 and up are ignored.
    pub const fn from_bits(bits: u8) -> Checks {
        Checks(bits & 0x7F)
    }

    /// The set as bits, bit `k` for `Check::ALL[k]`.
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// The set with `check` added if `failed`.
    pub const fn with_if(self, check: Check, failed: bool) -> Checks {
        Checks(self.0 | ((failed as u8) << check as u8))
    }

    /// The first failed check in the fixed order of docs/physical-layer.md, the telegram's primary class.
    pub const fn primary(self) -> Option<Check> {
        if self.0 == 0 {
            return None;
        }
        Some(Check::ALL[self.0.trailing_zeros() as usize])
    }

    /// The failed checks in order.
    pub fn iter(self) -> impl Iterator<Item = Check> {
        Check::ALL.into_iter().filter(move |c| self.contains(*c))
    }

    /// Number of failed checks.
    pub const fn len(self) -> u32 {
        self.0.count_ones()
    }
}

impl core::ops::BitOr for Checks {
    type Output = Checks;
    fn bitor(self, rhs: Checks) -> Checks {
        self.union(rhs)
    }
}

impl core::ops::BitOrAssign for Checks {
    fn bitor_assign(&mut self, rhs: Checks) {
        *self = self.union(rhs);
    }
}

impl fmt::Debug for Checks {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_set().entries(self.iter()).finish()
    }
}

impl fmt::Display for Checks {
    /// `ok`, or the failed checks joined by `+`: `alternation+information`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_empty() {
            return f.write_str("ok");
        }
        for (i, c) in self.iter().enumerate() {
            if i > 0 {
                f.write_str("+")?;
            }
            f.write_str(c.name())?;
        }
        Ok(())
    }
}
