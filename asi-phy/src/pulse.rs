//! Alternating Pulse Modulation: Manchester edges as line pulses on the half-bit grid (docs/physical-layer.md
//! "Pulse model"; docs/asi.md §1.2; §2.2.1, figure 2.1 of the lift thesis).
//!
//! Every Manchester edge becomes one sin²-shaped voltage pulse: a falling edge (transmit current
//! switched on) a negative pulse, a rising edge a positive one. The line idles high, so the
//! first pulse of a telegram is negative, pulses alternate, and the return to idle after the end
//! bit is a positive pulse. A request's pulses lie on grid points 0..=28 (0..84 µs), a response's
//! on 0..=14 (0..42 µs).

use crate::manchester::HalfBits;
use crate::telegram::{Request, Response};
use crate::time::{SimDuration, SimTime};
use core::fmt;

/// The sign of a line pulse.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Polarity {
    /// A falling Manchester edge.
    Negative,
    /// A rising Manchester edge.
    Positive,
}

impl Polarity {
    /// The other polarity.
    pub const fn flipped(self) -> Polarity {
        match self {
            Polarity::Negative => Polarity::Positive,
            Polarity::Positive => Polarity::Negative,
        }
    }

    /// `-` or `+`.
    pub const fn sign(self) -> char {
        match self {
            Polarity::Negative => '-',
            Polarity::Positive => '+',
        }
    }
}

/// One pulse on the line: the time of its centre and its polarity.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Pulse {
    /// Centre of the pulse.
    pub at: SimTime,
    /// Its sign.
    pub polarity: Polarity,
}

impl Pulse {
    /// A pulse at `at` with `polarity`.
    pub const fn new(at: SimTime, polarity: Polarity) -> Pulse {
        Pulse { at, polarity }
    }
}

/// The pulse masks of Manchester levels (`levels` bit `k` = cell `k`, 1 = high, `len` ≤ 32
/// cells) with the line idle high before and after: a pulse at each level change, positive
/// where the line rises. Returns (occupied, positive), bit `k` = grid point `k`.
pub(crate) const fn grid_masks(levels: u32, len: u32) -> (u64, u64) {
    // Levels of cells 0..len, then idle high at cell `len`.
    let lv = (levels as u64) | (1 << len);
    // The level before each cell: idle high before cell 0.
    let prev = (lv << 1) | 1;
    let span = (1u64 << (len + 1)) - 1;
    let occupied = (lv ^ prev) & span;
    (occupied, occupied & lv)
}

/// The pulses of one telegram on the half-bit grid, starting at a given time.
///
/// Held as two masks over grid points (bit `k` = point `k`): which points carry a pulse, and
/// which of those are positive. Building one is a few shifts, so the bus can encode every
/// transaction without allocating; [`PulseTrain::iter`] yields the timed pulses.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct PulseTrain {
    start: SimTime,
    half_bit: SimDuration,
    occupied: u64,
    positive: u64,
    points: u8,
}

impl PulseTrain {
    /// The pulses of Manchester `levels` with the line idle high before and after, the first
    /// grid point at `start`.
    pub const fn from_half_bits(
        levels: HalfBits,
        start: SimTime,
        half_bit: SimDuration,
    ) -> PulseTrain {
        let len = levels.len();
        let (occupied, positive) = grid_masks(levels.mask(), len);
        PulseTrain {
            start,
            half_bit,
            occupied,
            positive,
            points: (len + 1) as u8,
        }
    }

    /// A request's pulse train starting at `start` on the `half_bit` grid.
    pub const fn request(r: Request, start: SimTime, half_bit: SimDuration) -> PulseTrain {
        PulseTrain::from_half_bits(
            HalfBits::encode(r.bits() as u32, Request::BITS),
            start,
            half_bit,
        )
    }

    /// A response's pulse train starting at `start` on the `half_bit` grid.
    pub const fn response(r: Response, start: SimTime, half_bit: SimDuration) -> PulseTrain {
        PulseTrain::from_half_bits(
            HalfBits::encode(r.bits() as u32, Response::BITS),
            start,
            half_bit,
        )
    }

    /// The same pulses moved to start at `start`.
    pub const fn at(mut self, start: SimTime) -> PulseTrain {
        self.start = start;
        self
    }

    /// Time of grid point 0 (the first pulse).
    pub const fn start(&self) -> SimTime {
        self.start
    }

    /// Time of the last pulse.
    pub fn end(&self) -> SimTime {
        if self.occupied == 0 {
            return self.start;
        }
        let last = 63 - self.occupied.leading_zeros() as u64;
        self.start + self.half_bit.saturating_mul(last)
    }

    /// The grid spacing.
    pub const fn half_bit(&self) -> SimDuration {
        self.half_bit
    }

    /// Number of pulses.
    pub const fn len(&self) -> u32 {
        self.occupied.count_ones()
    }

    /// `true` if there are no pulses.
    pub const fn is_empty(&self) -> bool {
        self.occupied == 0
    }

    /// Number of grid points the telegram spans (29 for a request, 15 for a response).
    pub const fn grid_points(&self) -> u32 {
        self.points as u32
    }

    /// The grid masks: which points carry a pulse, and which of those are positive.
    pub(crate) const fn masks(&self) -> (u64, u64) {
        (self.occupied, self.positive)
    }

    /// The pulse at grid point `k`, if any.
    pub fn pulse_at(&self, k: u32) -> Option<Pulse> {
        if k >= 64 || self.occupied & (1 << k) == 0 {
            return None;
        }
        let polarity = if self.positive & (1 << k) != 0 {
            Polarity::Positive
        } else {
            Polarity::Negative
        };
        Some(Pulse::new(
            self.start + self.half_bit.saturating_mul(k as u64),
            polarity,
        ))
    }

    /// The pulses in time order.
    pub fn iter(&self) -> PulseIter {
        PulseIter {
            train: *self,
            rest: self.occupied,
        }
    }
}

impl IntoIterator for PulseTrain {
    type Item = Pulse;
    type IntoIter = PulseIter;
    fn into_iter(self) -> PulseIter {
        self.iter()
    }
}

/// The pulses of a [`PulseTrain`] in time order.
#[derive(Clone, Debug)]
pub struct PulseIter {
    train: PulseTrain,
    rest: u64,
}

impl Iterator for PulseIter {
    type Item = Pulse;

    fn next(&mut self) -> Option<Pulse> {
        if self.rest == 0 {
            return None;
        }
        let k = self.rest.trailing_zeros();
        self.rest &= self.rest - 1;
        self.train.pulse_at(k)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.rest.count_ones() as usize;
        (n, Some(n))
    }
}

impl ExactSizeIterator for PulseIter {}

impl fmt::Debug for PulseTrain {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "PulseTrain(at {}: {self})", self.start)
    }
}

impl fmt::Display for PulseTrain {
    /// Grid points with signs, as in docs/physical-layer.md's table: `0- 1+ 2- 3+ ...`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut rest = self.occupied;
        let mut first = true;
        while rest != 0 {
            let k = rest.trailing_zeros();
            rest &= rest - 1;
            let s = if self.positive & (1 << k) != 0 {
                '+'
            } else {
                '-'
            };
            if !first {
                f.write_str(" ")?;
            }
            first = false;
            write!(f, "{k}{s}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::telegram::{Address, Nibble};

    const H: SimDuration = SimDuration::from_micros(3);

    /// The four worked vectors of docs/physical-layer.md.
    #[test]
    fn spec_vector_data_exchange_address_5_outputs_1010() {
        let r = Request::data_exchange(
            Address::new(5).expect("addr"),
            Nibble::from_low_bits(0b1010),
        )
        .expect("valid");
        let t = PulseTrain::request(r, SimTime::ZERO, H);
        assert_eq!(
            t.to_string(),
            "0- 1+ 2- 3+ 4- 5+ 6- 7+ 9- 11+ 13- 15+ 17- 19+ 21- 23+ 24- 25+ 27- 28+"
        );
    }

    #[test]
    fn spec_vector_broadcast_reset() {
        let t = PulseTrain::request(Request::broadcast_reset(), SimTime::ZERO, H);
        assert_eq!(
            t.to_string(),
            "0- 1+ 3- 4+ 5- 6+ 7- 8+ 9- 10+ 11- 12+ 13- 14+ 15- 17+ 19- 21+ 23- 24+ 25- 26+ 27- 28+"
        );
    }

    #[test]
    fn spec_vector_response_0110() {
        let t = PulseTrain::response(
            Response::new(Nibble::from_low_bits(0b0110)),
            SimTime::ZERO,
            H,
        );
        assert_eq!(t.to_string(), "0- 1+ 2- 3+ 5- 6+ 7- 9+ 10- 11+ 13- 14+");
    }

    #[test]
    fn spec_vector_response_0000() {
        let t = PulseTrain::response(Response::new(Nibble::ZERO), SimTime::ZERO, H);
        assert_eq!(
            t.to_string(),
            "0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 10- 11+ 13- 14+"
        );
    }

    #[test]
    fn pulses_are_timed_from_the_start_on_the_grid() {
        let start = SimTime::from_micros(1000);
        let t = PulseTrain::response(Response::new(Nibble::ZERO), start, H);
        let pulses: Vec<Pulse> = t.iter().collect();
        assert_eq!(pulses.len(), 14);
        assert_eq!(pulses[0], Pulse::new(start, Polarity::Negative));
        assert_eq!(
            pulses[13],
            Pulse::new(SimTime::from_micros(1042), Polarity::Positive)
        );
        assert_eq!(t.end(), SimTime::from_micros(1042));
        assert_eq!(t.grid_points(), 15);
    }

    #[test]
    fn every_request_starts_negative_alternates_and_ends_positive_at_84_us() {
        for body in 0u16..1 << 11 {
            let bits = (body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1;
            let r = Request::from_bits(bits).expect("valid");
            let t = PulseTrain::request(r, SimTime::ZERO, H);
            let p: Vec<Pulse> = t.iter().collect();
            assert_eq!(p[0].polarity, Polarity::Negative);
            assert!(p.windows(2).all(|w| w[0].polarity != w[1].polarity));
            assert_eq!(
                p.last().map(|p| (p.at, p.polarity)),
                Some((SimTime::from_micros(84), Polarity::Positive))
            );
        }
    }
}
