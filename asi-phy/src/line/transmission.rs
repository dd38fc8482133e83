//! What a transmitter puts on the line: a telegram's bits, its start and the grid.

use crate::manchester::HalfBits;
use crate::{Checks, Frame, PulseTrain, Request, Response, SimDuration, SimTime};

/// A telegram as its transmitter puts it on the line: its bits, its start and the half-bit
/// grid. A [`Line`](super::Line) takes this rather than the [`PulseTrain`]: the pulses
/// are worked out only where something needs them (a recording tap, a fault injector, the
/// pulse decoder), while the fast path for a clean telegram needs only its [`frame`], which
/// takes a few operations on the bits (held equal to the train's for every request, every
/// response and random words of up to 16 bits by the tests below).
///
/// [`frame`]: Transmission::frame
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Transmission {
    raw: u32,
    bits: u32,
    start: SimTime,
    half_bit: SimDuration,
}

impl Transmission {
    /// The `bits` (≤ 16 are encoded) low bits of `raw`, first bit highest, starting at
    /// `start` on the `half_bit` grid.
    pub const fn new(raw: u32, bits: u32, start: SimTime, half_bit: SimDuration) -> Transmission {
        Transmission {
            raw,
            bits,
            start,
            half_bit,
        }
    }

    /// A request starting at `start`.
    pub const fn request(r: Request, start: SimTime, half_bit: SimDuration) -> Transmission {
        Transmission::new(r.bits() as u32, Request::BITS, start, half_bit)
    }

    /// A response starting at `start`.
    pub const fn response(r: Response, start: SimTime, half_bit: SimDuration) -> Transmission {
        Transmission::new(r.bits() as u32, Response::BITS, start, half_bit)
    }

    /// The bits as sent, first bit highest.
    pub const fn raw(&self) -> u32 {
        self.raw
    }

    /// The number of bits.
    pub const fn bits(&self) -> u32 {
        self.bits
    }

    /// Time of the first grid point.
    pub const fn start(&self) -> SimTime {
        self.start
    }

    /// The pulses on the line.
    pub const fn train(&self) -> PulseTrain {
        PulseTrain::from_half_bits(
            HalfBits::encode(self.raw, self.bits),
            self.start,
            self.half_bit,
        )
    }

    /// The number of pulses and the grid point of the last, from the bits alone. Every bit
    /// has its mid-bit edge; the line idles high, so a first bit 0 adds an edge before it and
    /// a last bit 1 one after it (at point `2n`, else the last is the mid-bit edge at
    /// `2n - 1`); and between two bits the level changes where they are equal.
    #[inline]
    const fn shape(&self) -> (u32, u32) {
        let n = if self.bits > 16 { 16 } else { self.bits };
        if n == 0 {
            return (0, 0);
        }
        let w = self.raw & ((1 << n) - 1);
        let first = (w >> (n - 1)) & 1;
        let last = w & 1;
        let changes = ((w ^ (w >> 1)) & ((1 << (n - 1)) - 1)).count_ones();
        let equal_neighbours = n - 1 - changes;
        (n + (1 - first) + equal_neighbours + last, 2 * n - 1 + last)
    }

    /// The number of pulses ([`PulseTrain::len`] of the train).
    pub const fn pulses(&self) -> u32 {
        self.shape().0
    }

    /// Time of the last pulse ([`PulseTrain::end`] of the train).
    pub fn end(&self) -> SimTime {
        self.start + self.half_bit.saturating_mul(self.shape().1 as u64)
    }

    /// The frame a receiver's line decoder makes of the telegram alone on a quiet line.
    /// Inlined, so that the shape of a request's or a response's known length folds.
    #[inline]
    pub fn frame(&self) -> Frame {
        let (pulses, last) = self.shape();
        Frame {
            start: self.start,
            end: self.start + self.half_bit.saturating_mul(last as u64),
            pulses,
            bit_count: self.bits,
            raw: self.raw,
            line_failed: Checks::NONE,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Nibble;

    const H: SimDuration = SimDuration::from_micros(3);

    /// The transmission's frame, pulse count and end are its train's, for every request and
    /// response on the bus and for random words of every length up to 16 bits (and beyond,
    /// where the encoder stops at 16).
    #[test]
    fn a_transmission_has_the_pulses_and_end_of_its_train() {
        let start = SimTime::from_micros(1234);
        let check = |tg: Transmission| {
            let train = tg.train();
            assert_eq!(tg.pulses(), train.len(), "{tg:?}");
            assert_eq!(tg.end(), train.end(), "{tg:?}");
            let f = tg.frame();
            assert_eq!(
                (f.start, f.end, f.pulses, f.bit_count, f.raw),
                (train.start(), train.end(), train.len(), tg.bits(), tg.raw()),
                "{tg:?}"
            );
            assert!(f.line_failed.is_empty());
        };
        for raw in 0u32..1 << 14 {
            check(Transmission::new(raw, 14, start, H));
        }
        for raw in 0u32..1 << 7 {
            check(Transmission::new(raw, 7, start, H));
        }
        let mut x = 0x9E37_79B9_u32;
        for i in 0..20_000u32 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            check(Transmission::new(x, i % 19, start, H));
        }
        let r = Request::broadcast_reset();
        assert_eq!(
            Transmission::request(r, start, H).train(),
            PulseTrain::request(r, start, H)
        );
        let a = Response::new(Nibble::from_low_bits(0b0110));
        assert_eq!(
            Transmission::response(a, start, H).train(),
            PulseTrain::response(a, start, H)
        );
    }
}
