//! A slave's address and identification codes, as the telegrams carry them (docs/asi.md §5.2, §6.1;
//! §2.2.3 of the lift thesis): what a master projects and lists, and what a slave holds.

use crate::{Address, Nibble, Select};
use core::fmt;

/// Acknowledge of Address_Assignment and Reset_Slave (docs/asi.md §4).
pub const ACK_0110: Nibble = Nibble::from_low_bits(0b0110);

/// A slave address with its A/B select: 1..31 (A or B), 0 (A only). A standard (non A/B) slave
/// is addressed as `A`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SlaveAddr {
    /// Address 0..=31.
    pub address: Address,
    /// A or B.
    pub select: Select,
}

impl SlaveAddr {
    /// `n` (0..=31) as an A (or standard) address; `None` above 31.
    pub const fn a(n: u8) -> Option<SlaveAddr> {
        match Address::new(n) {
            Some(address) => Some(SlaveAddr {
                address,
                select: Select::A,
            }),
            None => None,
        }
    }

    /// `n` (1..=31) as a B address; `None` for 0 (0B does not exist) and above 31.
    pub const fn b(n: u8) -> Option<SlaveAddr> {
        if n == 0 {
            return None;
        }
        match Address::new(n) {
            Some(address) => Some(SlaveAddr {
                address,
                select: Select::B,
            }),
            None => None,
        }
    }

    /// The list bit of this address: 0..31 for A, 32..63 for B.
    pub const fn index(self) -> u8 {
        match self.select {
            Select::A => self.address.get(),
            Select::B => 32 + self.address.get(),
        }
    }

    /// The address of list bit `i` (0..=63); `None` for 32 (0B) and above 63.
    pub const fn from_index(i: u8) -> Option<SlaveAddr> {
        if i < 32 {
            SlaveAddr::a(i)
        } else if i < 64 {
            SlaveAddr::b(i - 32)
        } else {
            None
        }
    }

    /// The address number 0..=31.
    pub const fn number(self) -> u8 {
        self.address.get()
    }
}

impl fmt::Display for SlaveAddr {
    /// `5` for a standard/A slave is written `5A`; B slaves `5B`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}{}", self.address.get(), self.select)
    }
}

/// The four identification codes of a slave: IO configuration, ID code, extended ID1 and ID2
/// (§2.2.3 of the lift thesis; docs/asi.md §6.1). The profile is written `S-IO.ID.ID2`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SlaveCodes {
    /// IO configuration (direction of D0..D3).
    pub io: Nibble,
    /// ID code: A = extended addressing (A/B slave), B = Safety at Work, 3 = S-7.3 analog.
    pub id: Nibble,
    /// Extended ID code 1 (user-writable; bit 3 is the A/B select of an A/B slave).
    pub id1: Nibble,
    /// Extended ID code 2 (sub-profile).
    pub id2: Nibble,
}

impl SlaveCodes {
    /// ID code of an A/B (extended addressing) slave.
    pub const ID_AB: u8 = 0xA;
    /// ID code of a Safety at Work slave.
    pub const ID_SAFETY: u8 = 0xB;
    /// ID code of an S-7.3 analog slave.
    pub const ID_ANALOG_7_3: u8 = 0x3;

    /// Codes from the four nibble values (each taken modulo 16).
    pub const fn new(io: u8, id: u8, id1: u8, id2: u8) -> SlaveCodes {
        SlaveCodes {
            io: Nibble::from_low_bits(io),
            id: Nibble::from_low_bits(id),
            id1: Nibble::from_low_bits(id1),
            id2: Nibble::from_low_bits(id2),
        }
    }

    /// `true` for an A/B slave (ID code A).
    pub const fn is_ab(&self) -> bool {
        self.id.get() == Self::ID_AB
    }

    /// `true` for an S-7.3 analog slave handled by the master (ID code 3, ID2 bit 2 = analog).
    pub const fn is_analog_7_3(&self) -> bool {
        self.id.get() == Self::ID_ANALOG_7_3 && self.id2.get() & 0b0100 != 0
    }

    /// For an S-7.3 slave: `true` if it is an input slave (ID2 bit 3 = 1).
    pub const fn analog_is_input(&self) -> bool {
        self.id2.get() & 0b1000 != 0
    }

    /// For an S-7.3 slave: its number of channels (ID2 bits 1..0: 00 = 1, 01 = 2, else 4).
    pub const fn analog_channels(&self) -> u8 {
        match self.id2.get() & 0b11 {
            0 => 1,
            1 => 2,
            _ => 4,
        }
    }

    /// The codes a master compares in protected mode: IO, ID and ID2, and ID1 except the A/B
    /// select bit of an A/B slave (docs/asi.md §5.5).
    pub fn matches(&self, other: &SlaveCodes) -> bool {
        let id1_mask = if self.is_ab() { 0b0111 } else { 0b1111 };
        self.io == other.io
            && self.id == other.id
            && self.id2 == other.id2
            && (self.id1.get() & id1_mask) == (other.id1.get() & id1_mask)
    }
}

impl fmt::Display for SlaveCodes {
    /// The profile `S-IO.ID.ID2` with ID1: `S-7.0.F (ID1 F)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "S-{:X}.{:X}.{:X} (ID1 {:X})",
            self.io.get(),
            self.id.get(),
            self.id2.get(),
            self.id1.get()
        )
    }
}
