//! The IFM GG505S safety sensor (S-0.B.F, Safety at Work; docs/asi.md §7; docs/lab-bus.md).

use super::any_impls;
use crate::monitor::CodeTable;
use crate::slave::Peripheral;
use asi_phy::{Nibble, SimDuration, SimTime};

/// How long a safe slave keeps the same code after a Data_Exchange, so that an immediate master
/// repeat gets the same code (SAP5 datasheet p.50: 224 µs + 16 µs; docs/asi.md §7).
pub const CODE_HOLD: SimDuration = SimDuration::from_micros(240);

/// A safe input slave: while free it answers each Data_Exchange with the next value of its own
/// 8-value code table; tripped it answers 0000.
///
/// A Data_Exchange that comes within [`CODE_HOLD`] of the previous one (a master repeat) gets
/// the same code. Fault hook: [`SafetySensor::set_frozen`] makes it keep sending one code.
#[derive(Clone, Debug)]
pub struct SafetySensor {
    table: CodeTable,
    index: usize,
    free: bool,
    frozen: bool,
    last: Option<SimTime>,
}

impl SafetySensor {
    /// A free sensor with `table`.
    pub fn new(table: CodeTable) -> SafetySensor {
        SafetySensor {
            table,
            index: 0,
            free: true,
            frozen: false,
            last: None,
        }
    }
    /// Its code table.
    pub fn table(&self) -> CodeTable {
        self.table
    }
    /// Free (`true`, the cabin is within its travel) or tripped.
    pub fn set_free(&mut self, free: bool) {
        self.free = free;
    }
    /// `true` while free.
    pub fn is_free(&self) -> bool {
        self.free
    }
    /// Fault hook: the code sequence stops advancing (a frozen code).
    pub fn set_frozen(&mut self, frozen: bool) {
        self.frozen = frozen;
    }
}

impl Peripheral for SafetySensor {
    fn exchange(&mut self, now: SimTime, _outputs: Nibble) -> Nibble {
        let advance = match self.last {
            Some(t) => now.saturating_duration_since(t) > CODE_HOLD,
            None => false,
        };
        if advance && !self.frozen {
            self.index = (self.index + 1) % 8;
        }
        self.last = Some(now);
        if self.free {
            Nibble::from_low_bits(self.table.codes()[self.index])
        } else {
            Nibble::ZERO
        }
    }
    fn reset(&mut self) {
        self.index = 0;
        self.last = None;
    }
    any_impls!();
}
