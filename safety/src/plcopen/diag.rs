//! The DiagCode every PLCopen function block reports.

use core::fmt;

/// A PLCopen DiagCode (WORD): `0000` idle, `8xxx` active without error, `Cxxx` error.
///
/// In v2.x codes the bit `0x0800` marks SafetyDemand and `0x0400` marks ResetRequest
/// (docs/safety-logic.md §5.1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct DiagCode(pub u16);

impl DiagCode {
    /// `0000`: the block is not active.
    pub const IDLE: DiagCode = DiagCode(0x0000);

    /// `true` for the error codes `Cxxx`.
    pub const fn is_error(self) -> bool {
        self.0 & 0xF000 == 0xC000
    }
}

impl fmt::Display for DiagCode {
    /// Four hex digits as in the tables, e.g. `8802`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04X}", self.0)
    }
}
