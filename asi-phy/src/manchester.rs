//! Manchester II coding of telegram bits (docs/physical-layer.md "Pulse model"; §2.2.1 of the lift
//! thesis).
//!
//! The line idles high. A bit 0 is sent as low-then-high, a bit 1 as high-then-low, so every bit
//! cell has a transition at its middle. [`HalfBits`] holds the level of each half-bit cell.

use crate::telegram::{Request, Response, TelegramError};
use core::fmt;

/// A line level of one half-bit cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Level {
    /// No transmit current: the idle level.
    High,
    /// Transmit current on.
    Low,
}

/// The half-bit levels of a telegram of up to 16 bits, in transmission order.
///
/// Internally bit `k` (least significant first) is the level of half-bit cell `k`, 1 = high.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct HalfBits {
    levels: u32,
    len: u8,
}

/// A bit cell whose two halves have the same level: no mid-bit transition.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("Manchester violation in bit cell {cell}: both halves {level:?}")]
pub struct ManchesterError {
    /// The bit index in transmission order (0 = start bit).
    pub cell: u32,
    /// The level of both halves.
    pub level: Level,
}

/// Bit-reversed bytes: baseline x86-64 has no bit-reverse instruction, and `u32::reverse_bits`
/// then costs some twenty operations on every telegram.
const REV8: [u8; 256] = {
    let mut t = [0u8; 256];
    let mut i = 0;
    while i < 256 {
        t[i] = (i as u8).reverse_bits();
        i += 1;
    }
    t
};

/// The low `n` (≤ 32) bits of `x` in reverse order: bit `i` moves to bit `n − 1 − i`; bits
/// above `n` are dropped.
pub(crate) const fn reverse_low(x: u32, n: u32) -> u32 {
    if n == 0 {
        return 0;
    }
    let r = (REV8[(x & 0xFF) as usize] as u32) << 24
        | (REV8[((x >> 8) & 0xFF) as usize] as u32) << 16
        | (REV8[((x >> 16) & 0xFF) as usize] as u32) << 8
        | REV8[(x >> 24) as usize] as u32;
    r >> (32 - n)
}

/// The low `n` (≤ 16) bits of `x` in reverse order, as [`reverse_low`] with two table lookups.
pub(crate) const fn reverse_low16(x: u32, n: u32) -> u32 {
    let r = (REV8[(x & 0xFF) as usize] as u32) << 8 | REV8[((x >> 8) & 0xFF) as usize] as u32;
    r >> (16 - n)
}

/// Moves bit `2i` of `x` to bit `i` (i < 16), as [`compact`] on 32 bits; odd bits are dropped.
pub(crate) const fn compact32(x: u32) -> u32 {
    let mut x = x & 0x5555_5555;
    x = (x | (x >> 1)) & 0x3333_3333;
    x = (x | (x >> 2)) & 0x0F0F_0F0F;
    x = (x | (x >> 4)) & 0x00FF_00FF;
    (x | (x >> 8)) & 0xFFFF
}

/// Moves bit `i` of `x` (i < 16) to bit `2i`.
pub(crate) const fn spread(x: u32) -> u32 {
    let mut x = x & 0xFFFF;
    x = (x | (x << 8)) & 0x00FF_00FF;
    x = (x | (x << 4)) & 0x0F0F_0F0F;
    x = (x | (x << 2)) & 0x3333_3333;
    (x | (x << 1)) & 0x5555_5555
}

/// Moves bit `2i` of `x` to bit `i` (the inverse of [`spread`]); odd bits are dropped.
pub(crate) const fn compact(x: u64) -> u32 {
    let mut x = x & 0x5555_5555_5555_5555;
    x = (x | (x >> 1)) & 0x3333_3333_3333_3333;
    x = (x | (x >> 2)) & 0x0F0F_0F0F_0F0F_0F0F;
    x = (x | (x >> 4)) & 0x00FF_00FF_00FF_00FF;
    x = (x | (x >> 8)) & 0x0000_FFFF_0000_FFFF;
    ((x | (x >> 16)) & 0xFFFF_FFFF) as u32
}

/// The Manchester levels of `n` (≤ 16) bits given first-sent-first (bit `i` of `t` is the
/// `i`-th bit sent): bit `2i` of the result is the first half of cell `i`, 1 = high.
pub(crate) const fn manchester_levels(t: u32, n: u32) -> u32 {
    let mask = if n >= 16 { 0xFFFF } else { (1u32 << n) - 1 };
    let t = t & mask;
    spread(t) | (spread(!t & mask) << 1)
}

impl HalfBits {
    /// The Manchester levels of the `n` (≤ 16) bits in `bits`, the first bit sent in bit
    /// `n - 1`. Bits above `n` are ignored.
    pub const fn encode(bits: u32, n: u32) -> HalfBits {
        let n = if n > 16 { 16 } else { n };
        if n == 0 {
            return HalfBits { levels: 0, len: 0 };
        }
        // Transmission order, first bit in bit 0.
        let t = reverse_low(bits, n);
        HalfBits {
            levels: manchester_levels(t, n),
            len: (2 * n) as u8,
        }
    }

    /// Number of half-bit cells (twice the number of bits).
    pub const fn len(&self) -> u32 {
        self.len as u32
    }

    /// `true` if there are no cells.
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The level of half-bit cell `k`, or `None` past the end.
    pub const fn level(&self, k: u32) -> Option<Level> {
        if k >= self.len as u32 {
            None
        } else if self.levels & (1 << k) != 0 {
            Some(Level::High)
        } else {
            Some(Level::Low)
        }
    }

    /// The levels in transmission order.
    pub fn levels(&self) -> impl Iterator<Item = Level> + '_ {
        (0..self.len()).filter_map(|k| self.level(k))
    }

    /// The levels as a mask, bit `k` = cell `k`, 1 = high (for the pulse encoder).
    pub(crate) const fn mask(&self) -> u32 {
        self.levels
    }

    /// Builds cells from levels in transmission order (up to 32 cells; more are an error).
    pub fn from_levels(levels: &[Level]) -> Option<HalfBits> {
        if levels.len() > 32 || levels.len() % 2 != 0 {
            return None;
        }
        let mut mask = 0u32;
        for (k, l) in levels.iter().enumerate() {
            if *l == Level::High {
                mask |= 1 << k;
            }
        }
        Some(HalfBits {
            levels: mask,
            len: levels.len() as u8,
        })
    }

    /// The bits back, first sent in the most significant position, and their count; or the
    /// first cell without a mid-bit transition.
    pub const fn decode(&self) -> Result<(u32, u32), ManchesterError> {
        let n = self.len as u32 / 2;
        let first = self.levels as u64;
        let second = (self.levels >> 1) as u64;
        let same = !(first ^ second) & 0x5555_5555 & ((1u64 << (2 * n)) - 1);
        if same != 0 {
            let k = same.trailing_zeros();
            let level = if self.levels & (1 << k) != 0 {
                Level::High
            } else {
                Level::Low
            };
            return Err(ManchesterError { cell: k / 2, level });
        }
        // A bit is 1 when its first half is high.
        let t = compact(first);
        if n == 0 {
            return Ok((0, 0));
        }
        Ok((reverse_low(t, n), n))
    }

    /// The request these levels carry, if they are a valid one.
    pub fn to_request(&self) -> Result<Request, HalfBitsError> {
        let (bits, n) = self.decode()?;
        if n != Request::BITS {
            return Err(HalfBitsError::Length {
                expected: Request::BITS,
                found: n,
            });
        }
        Ok(Request::from_bits(bits as u16)?)
    }

    /// The response these levels carry, if they are a valid one.
    pub fn to_response(&self) -> Result<Response, HalfBitsError> {
        let (bits, n) = self.decode()?;
        if n != Response::BITS {
            return Err(HalfBitsError::Length {
                expected: Response::BITS,
                found: n,
            });
        }
        Ok(Response::from_bits(bits as u8)?)
    }
}

impl From<Request> for HalfBits {
    fn from(r: Request) -> HalfBits {
        HalfBits::encode(r.bits() as u32, Request::BITS)
    }
}

impl From<Response> for HalfBits {
    fn from(r: Response) -> HalfBits {
        HalfBits::encode(r.bits() as u32, Response::BITS)
    }
}

/// Why half-bit levels are not a telegram.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum HalfBitsError {
    /// A cell without a mid-bit transition.
    #[error(transparent)]
    Manchester(#[from] ManchesterError),
    /// The wrong number of bits.
    #[error("{found} bits, a telegram of this kind has {expected}")]
    Length {
        /// Bits a telegram of the kind has.
        expected: u32,
        /// Bits found.
        found: u32,
    },
    /// The bits break a telegram rule.
    #[error(transparent)]
    Telegram(#[from] TelegramError),
}

impl fmt::Debug for HalfBits {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "HalfBits({self})")
    }
}

impl fmt::Display for HalfBits {
    /// `H`/`L` per cell, a space between bit cells: `LH LH HL`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (k, l) in self.levels().enumerate() {
            if k > 0 && k % 2 == 0 {
                f.write_str(" ")?;
            }
            f.write_str(if l == Level::High { "H" } else { "L" })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::telegram::Nibble;

    #[test]
    fn bit_zero_is_low_then_high_and_one_is_high_then_low() {
        let r = Response::new(Nibble::from_low_bits(0b0110));
        // 0 0110 0 1
        assert_eq!(HalfBits::from(r).to_string(), "LH LH HL HL LH LH HL");
    }

    #[test]
    fn reverse_low_matches_the_library() {
        for n in 1..=32u32 {
            for x in [0u32, 1, 0x8000_0001, 0xDEAD_BEEF, 0x1234_5678, u32::MAX] {
                let want = (x & (u32::MAX >> (32 - n))).reverse_bits() >> (32 - n);
                assert_eq!(reverse_low(x, n), want, "{x:#x} {n}");
            }
        }
    }

    #[test]
    fn spread_and_compact_are_inverse() {
        for x in 0..=0xFFFFu32 {
            assert_eq!(compact(spread(x) as u64), x);
            assert_eq!(compact32(spread(x)), x);
            assert_eq!(compact32(spread(x) | spread(x) << 1), x);
        }
    }

    #[test]
    fn reverse_low16_is_reverse_low() {
        for n in 0..=16u32 {
            for x in (0..=0xFFFFu32).step_by(7).chain([0xFFFF, 0x8001]) {
                let low = x & ((1u32 << n) - 1);
                let want = if n == 0 { 0 } else { reverse_low(low, n) };
                assert_eq!(reverse_low16(low, n), want, "{x:#x} {n}");
            }
        }
    }

    #[test]
    fn decode_reports_the_first_violated_cell() {
        let mut levels: Vec<Level> = HalfBits::from(Response::new(Nibble::ZERO))
            .levels()
            .collect();
        levels[6] = Level::High; // cell 3 becomes H H
        let hb = HalfBits::from_levels(&levels).expect("14 cells");
        assert_eq!(
            hb.decode(),
            Err(ManchesterError {
                cell: 3,
                level: Level::High
            })
        );
    }

    #[test]
    fn every_request_and_response_round_trips_through_levels() {
        for body in 0u16..1 << 11 {
            let r = Request::from_bits((body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1)
                .expect("valid");
            assert_eq!(HalfBits::from(r).to_request(), Ok(r));
        }
        for v in 0..16 {
            let r = Response::new(Nibble::from_low_bits(v));
            assert_eq!(HalfBits::from(r).to_response(), Ok(r));
            assert_eq!(
                HalfBits::from(r).to_request(),
                Err(HalfBitsError::Length {
                    expected: 14,
                    found: 7
                })
            );
        }
    }
}
