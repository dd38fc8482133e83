//! The fields a telegram carries: the 4-bit [`Nibble`], the slave [`Address`] and the A/B
//! [`Select`].

use core::fmt;

/// A 4-bit value: slave data D3..D0, a parameter P3..P0, a code or status S3..S0.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Nibble(pub(super) u8);

impl Nibble {
    /// 0000.
    pub const ZERO: Nibble = Nibble(0);
    /// 1111 (the default output value of a master, docs/asi.md §5.1).
    pub const ALL: Nibble = Nibble(0xF);

    /// `v` as a nibble, or `None` if `v > 15`.
    pub const fn new(v: u8) -> Option<Nibble> {
        if v <= 0xF {
            Some(Nibble(v))
        } else {
            None
        }
    }

    /// The low four bits of `v` (the rest is discarded on purpose).
    pub const fn from_low_bits(v: u8) -> Nibble {
        Nibble(v & 0xF)
    }

    /// The value 0..=15.
    pub const fn get(self) -> u8 {
        self.0
    }

    /// Bit `i` (0 = D0 .. 3 = D3); `false` for `i > 3`.
    pub const fn bit(self, i: u8) -> bool {
        i < 4 && self.0 & (1 << i) != 0
    }

    /// This nibble with bit `i` (0..=3) set to `value`; unchanged for `i > 3`.
    pub const fn with_bit(self, i: u8, value: bool) -> Nibble {
        if i > 3 {
            return self;
        }
        if value {
            Nibble(self.0 | (1 << i))
        } else {
            Nibble(self.0 & !(1 << i))
        }
    }
}

impl fmt::Display for Nibble {
    /// Four binary digits, D3 first: `1010`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04b}", self.0)
    }
}

/// A 5-bit slave address A4..A0, 0..=31. Address 0 is the delivery address of new slaves;
/// 31 with the broadcast code is the broadcast call.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Address(pub(super) u8);

impl Address {
    /// Address 0, where new slaves are delivered.
    pub const ZERO: Address = Address(0);

    /// `v` as an address, or `None` if `v > 31`.
    pub const fn new(v: u8) -> Option<Address> {
        if v <= 31 {
            Some(Address(v))
        } else {
            None
        }
    }

    /// The address 0..=31.
    pub const fn get(self) -> u8 {
        self.0
    }

    /// Every address 1..=31 in ascending order (the order of the data exchange phase).
    pub fn slaves() -> impl Iterator<Item = Address> {
        (1..=31).map(Address)
    }
}

impl fmt::Display for Address {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// The A/B select of extended addressing (docs/master.md; docs/asi.md §4.2). A standard slave
/// answers the `A` encodings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Select {
    /// The A slave, or a standard (non A/B) slave.
    #[default]
    A,
    /// The B slave of an address.
    B,
}

impl fmt::Display for Select {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Select::A => "A",
            Select::B => "B",
        })
    }
}
