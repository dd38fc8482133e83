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
            // The index is always below 8 (it moves on modulo 8): `% 8` tells the compiler,
            // which then leaves out the bounds check.
            Nibble::from_low_bits(self.table.codes()[self.index % 8])
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A free sensor sends its table in order, round and round; a repeat within the hold
    /// gets the same code; tripped it sends 0000.
    #[test]
    fn the_codes_go_round_the_table_and_a_repeat_gets_the_same_code() {
        let table = CodeTable::from_serial(7);
        let mut s = SafetySensor::new(table);
        let mut now = SimTime::ZERO;
        for i in 0..20 {
            let code = s.exchange(now, Nibble::ZERO);
            assert_eq!(code.get(), table.codes()[i % 8], "exchange {i}");
            let repeat = now + SimDuration::from_micros(100);
            assert_eq!(s.exchange(repeat, Nibble::ZERO), code, "repeat {i}");
            now += SimDuration::from_millis(2);
        }
        s.set_free(false);
        assert_eq!(s.exchange(now, Nibble::ZERO), Nibble::ZERO);
    }
}
