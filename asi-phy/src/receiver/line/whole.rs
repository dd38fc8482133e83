//! The decoder's hot path: a run of pulses decided at once ([`Run::whole`]), from its scan to
//! the frame handed on.

use super::{bit_checks, bit_checks_odd, level_raw, Check, Checks, Frame, Grid, Run};
use crate::pulse::{Polarity, Pulse};
use crate::time::SimTime;

/// Grid points 1, 3, .., 63: the middles of the bit cells.
const MIDS: u64 = 0xAAAA_AAAA_AAAA_AAAA;

/// Eight bits in the order [`fold16`] leaves them (bit `2k` holds bit `k`, bit `2k + 1` holds
/// bit `k + 4`, for `k` < 4) in reverse order (bit `k` to bit `7 − k`) and shifted left by
/// `shift`, with their parity in bit 16, the first of them (bit 0) left out if `rest`.
const fn folded_rev8(shift: u32, rest: bool) -> [u32; 256] {
    let mut t = [0u32; 256];
    let mut b = 0;
    while b < 256 {
        let mut r = 0u32;
        let mut k = 0;
        while k < 8 {
            let from = if k < 4 { 2 * k } else { 2 * (k - 4) + 1 };
            r |= ((b as u32 >> from) & 1) << (7 - k);
            k += 1;
        }
        let counted = if rest { r & 0x7F } else { r };
        t[b] = r << shift | (counted.count_ones() & 1) << 16;
        b += 1;
    }
    t
}

/// [`folded_rev8`] for the first eight cells (their bits in bits 8..=15, the parity of all but
/// the first) and for the next eight (in bits 0..=7): the two entries of a run's bits differ in
/// their bits, so that they add up by exclusive or, bits and parity at once.
const FOLDED_REV8: [[u32; 256]; 2] = [folded_rev8(8, true), folded_rev8(0, false)];

/// Bits 0, 2, .., 30 of `x` (the odd bits must be 0) folded into two bytes: bits 0..=14 into
/// bits 0..=7 and bits 16..=30 into bits 16..=23, in the order [`folded_rev8`] reads.
#[inline(always)]
const fn fold16(x: u32) -> u32 {
    x | (x >> 7)
}

/// The first `cells` (≤ 16) bits of a clean run in transmission order (first bit highest, as
/// [`Frame::raw`]) from `ones`, bit `2i` set where the middle of cell `i` (point `2i + 1`)
/// holds a negative pulse (the odd bits 0), and the parity of all but the first (1 for an odd
/// number of ones):
/// one fold and two table lookups where compaction, reversal and the parity took about three
/// times as many instructions.
#[inline(always)]
fn raw16(ones: u32, cells: u32) -> (u32, u32) {
    let folded = fold16(ones);
    let w =
        FOLDED_REV8[0][(folded & 0xFF) as usize] ^ FOLDED_REV8[1][((folded >> 16) & 0xFF) as usize];
    ((w & 0xFFFF) >> (16 - cells), w >> 16)
}

impl Run {
    /// The run that begins with `first` and goes on in `tail`, if it is decided at once: its
    /// first pulse is negative, its pulses after the first all lie within the tolerance of the
    /// grid, one or two points apart (as in the fast scan, [`Run::scan`]), with alternating
    /// signs, and the pulse after them comes after a pause. Calls `out` with its frame and
    /// returns the pulses after it (which begin with the pulse after the pause); `None` leaves
    /// the run to [`Run::begin`] and [`Run::extend`], which give the same result for any run.
    ///
    /// Every telegram a sound transmitter sends is such a run, so this is the decoder's hot
    /// path: it looks at the 31 pulses a run can hold within the masks and the one after them
    /// as an array, so a pulse costs little more than its placement. A run it cannot decide
    /// (one beginning with a positive pulse, or one less than 32 pulses before the end of the
    /// slice) goes the longer way, which is exact for any run.
    ///
    /// The 31 steps of the scan are written out, each with its own constant index, so the sign
    /// it expects and its own way out, which checks the signs of the pulses taken. The frame
    /// is made ([`whole_frame`]) and handed to `out` in line, in the loop of
    /// [`LineDecoder::push_slice`](super::LineDecoder::push_slice): the scan's registers are
    /// free by then and nothing goes through memory on the way (made out of line, its result
    /// was stored and loaded again, and the call saved and restored registers). The run's last
    /// grid point is found again from the masks: kept from the scan past the check of the step
    /// that reads it, it cost a register copy a pulse.
    // (The last step's grid point goes unread: no pulse follows it in the array.)
    #[allow(unused_assignments)]
    #[inline(always)]
    pub(super) fn whole<'p>(
        first: &Pulse,
        tail: &'p [Pulse],
        grid: &Grid,
        out: &mut impl FnMut(Frame),
    ) -> Option<&'p [Pulse]> {
        if grid.recip == 0 || first.polarity == Polarity::Positive {
            return None;
        }
        let ahead: &[Pulse; 32] = tail.first_chunk()?;
        let t0 = first.at.as_nanos();
        let base = t0.wrapping_sub(grid.tol);
        // The grid points of the 1st, 3rd, .. pulse of the run (all negative) and of the 2nd,
        // 4th, .. (all positive), and the grid point of the last pulse taken.
        let (mut negative, mut positive, mut last_g) = (1u64, 0u64, 0u64);
        // The number of positive pulses among the even ones of `ahead` less that among the
        // odd ones: the number of the even ones exactly where all of them are positive and
        // none of the odd ones.
        let mut signs = 0u8;
        // How many pulses of `ahead` the run takes.
        let n: usize = 'scan: {
            macro_rules! take_while_placed {
                ($($i:literal)*) => {
                    $(
                        let p = &ahead[$i];
                        let at = p.at.as_nanos().wrapping_sub(base);
                        let Some(q) = grid.place(at, last_g) else {
                            // The first i take ⌈i/2⌉ of the even ones.
                            if usize::from(signs) != usize::div_ceil($i, 2) {
                                return None;
                            }
                            break 'scan $i;
                        };
                        // q ≤ 2·(i + 1) ≤ 62; the first pulse after the run's first takes
                        // point 1 or 2, whose bit is 2·q (an addition, not a shift by a
                        // register).
                        let bit = if $i == 0 { q << 1 } else { 1u64.wrapping_shl(q as u32) };
                        if $i % 2 == 0 {
                            positive |= bit;
                            signs = signs.wrapping_add(p.polarity as u8);
                        } else {
                            negative |= bit;
                            signs = signs.wrapping_sub(p.polarity as u8);
                        }
                        last_g = q;
                    )*
                };
            }
            take_while_placed!(
                0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29
                30
            );
            if usize::from(signs) != usize::div_ceil(31, 2) {
                return None;
            }
            31
        };
        // The pulse after the run (n ≤ 31) and the run's last.
        let at = ahead.get(n)?.at.as_nanos();
        let last_t = match n.checked_sub(1) {
            Some(last) => ahead[last].at.as_nanos(),
            None => t0,
        };
        if !(at.wrapping_sub(last_t) >= grid.pause && at >= last_t) {
            return None;
        }
        // (Point 0 holds the first pulse: the compiler need not mind an empty mask.)
        let g = u64::from(63 - (negative | positive | 1).leading_zeros());
        out(whole_frame(t0, last_t, n, negative, positive, g));
        Some(&tail[n..])
    }
}

/// The frame of a run decided at once: first pulse at `t0`, last at `last_t` on grid point `g`,
/// `n` pulses after the first, the grid points of its negative pulses (among them point 0) and
/// of its positive ones; the same as [`Run::finish`] of that run.
///
/// The run's points rise by one or two, so a point under `g` without a pulse has one on the
/// point above it: the missing middles of cells are the odd points without a pulse below one
/// with a pulse, and where none is missing the bits are the negative pulses on odd points.
#[inline(always)]
fn whole_frame(t0: u64, last_t: u64, n: usize, negative: u64, positive: u64, g: u64) -> Frame {
    let occupied = negative | positive;
    // g ≤ 62.
    let cells = (g as u32 + 1) >> 1;
    let (raw, failed) = if cells <= 16 {
        // The middles are points 1, 3, .., 31 at most, in 32 bits.
        let missing = !(occupied as u32) & (occupied >> 1) as u32 & MIDS as u32;
        if missing == 0 {
            let (raw, odd) = raw16((negative >> 1) as u32 & !MIDS as u32, cells);
            // The first bit is 1 where the middle of the first cell holds a negative pulse.
            let first = (negative >> 1) as u32 & 1;
            (raw, bit_checks_odd(raw, odd, first, cells, g))
        } else {
            information(occupied, positive, cells, g)
        }
    } else if !occupied & (occupied >> 1) & MIDS == 0 {
        // As in `Run::finish`: reversed, point 2i + 1 is point 62 − 2i, which compacts to
        // bit 31 − i.
        let top = crate::manchester::compact((negative & MIDS).reverse_bits());
        let raw = (u64::from(top) >> (32 - cells)) as u32;
        (raw, bit_checks(raw, cells, g))
    } else {
        information(occupied, positive, cells, g)
    };
    Frame {
        start: SimTime::from_nanos(t0),
        end: SimTime::from_nanos(last_t),
        pulses: n as u32 + 1,
        bit_count: cells,
        raw,
        line_failed: failed,
    }
}

/// The bits and the checks of a run decided at once with a missing middle of a cell.
#[cold]
fn information(occupied: u64, positive: u64, cells: u32, g: u64) -> (u32, Checks) {
    let raw = level_raw(occupied, positive, cells);
    (
        raw,
        Checks::only(Check::Information).union(bit_checks(raw, cells, g)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::manchester::{compact32, reverse_low16};

    /// The fold and the tables give the bits compaction and reversal give, and the parity of
    /// all but the first, for every cell count and every pattern of 16 bits.
    #[test]
    fn the_folded_table_reads_the_bits_as_compaction_and_reversal() {
        for cells in 0..=16u32 {
            let below = if cells == 0 {
                0
            } else {
                u64::MAX >> (64 - 2 * cells)
            };
            for bits in 0..=0xFFFFu64 {
                let spread = u64::from(crate::manchester::spread(bits as u32)) << 1;
                let ones = spread & below;
                let raw = reverse_low16(compact32((ones >> 1) as u32), cells);
                let want = (raw, (ones & !2).count_ones() & 1);
                assert_eq!(raw16((ones >> 1) as u32, cells), want, "{bits:#x} {cells}");
            }
        }
    }
}
