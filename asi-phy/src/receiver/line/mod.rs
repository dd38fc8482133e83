//! The line half of a receiver: pulse runs assembled on the half-bit grid into [`Frame`]s, with
//! the checks that depend on the line alone.
//!
//! - this file: the [`LineDecoder`], the grid and its placement, runs pulse by pulse and their
//!   frames;
//! - `whole`: the hot path, a run decided at once (`Run::whole`) and its frame.

use super::checks::{Check, Checks};
use super::config::ReceiverConfig;
use crate::manchester::{compact, compact32, manchester_levels, reverse_low, reverse_low16};
use crate::pulse::{grid_masks, Polarity, Pulse, PulseTrain};
use crate::time::{SimDuration, SimTime};

/// A pulse run between two pauses as every receiver on the line sees it: its timing, its bits,
/// and the checks that depend on the line alone. [`Listener::accept`](super::Listener::accept)
/// turns it into one receiver's [`Received`](super::Received) telegram.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Frame {
    /// Time of the first pulse.
    pub start: SimTime,
    /// Time of the last pulse.
    pub end: SimTime,
    /// Number of pulses.
    pub pulses: u32,
    /// Number of bits decoded.
    pub bit_count: u32,
    /// The first (up to 32) bits, first bit in the most significant used position.
    pub raw: u32,
    /// The failed checks that depend on the line alone: all but length (which depends on what
    /// the listener expects) and the pause before the telegram (which depends on its state).
    pub line_failed: Checks,
}

/// The telegram in progress.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Run {
    /// Time of the first pulse, ns.
    pub(super) t0: u64,
    /// Time of the last pulse, ns.
    pub(super) last_t: u64,
    /// Grid point of the last pulse.
    pub(super) last_g: u64,
    pub(super) last_positive: bool,
    /// The last pulse lies within the tolerance of its grid point `last_g` (counted modulo
    /// 2⁶⁴ ns, as the decoder's grid arithmetic is): on a grid where [`Grid::recip`] is set,
    /// a pulse on one of the next two grid points then cannot come after a pause.
    pub(super) on_grid: bool,
    pub(super) count: u32,
    pub(super) occupied: u64,
    pub(super) positive: u64,
    pub(super) failed: Checks,
    /// For a run known to be clean Manchester: its bits in transmission order.
    pub(super) clean: Option<u32>,
}

/// The grid of a decoder and the constant of its fast scan ([`Run::scan`]).
#[derive(Clone, Copy, Debug)]
struct Grid {
    /// Half-bit, ns.
    h: u64,
    /// Jitter tolerance, ns.
    tol: u64,
    /// Twice the tolerance (saturating).
    two_tol: u64,
    /// The silence that ends a run, ns.
    pause: u64,
    /// ⌈2⁶⁴ / h⌉ where the fast scan applies, else 0: where the grid is 2 to 2²⁴ ns, the
    /// tolerance under half of it (so a pulse is within the tolerance of at most one grid
    /// point) and two half-bits and twice the tolerance shorter than the pause (so two pulses
    /// each within the tolerance of grid points one or two apart are never a pause).
    recip: u64,
    /// ⌈(2·tol + 1) · 2⁶⁴ / h⌉ − 1 where the fast scan applies: the largest low half of
    /// `y · recip` of a pulse within the tolerance of its grid point ([`Grid::place`]).
    within: u64,
}

impl Grid {
    fn new(cfg: &ReceiverConfig) -> Grid {
        let (h, tol, pause) = (cfg.half_bit, cfg.tolerance, cfg.pause);
        let fast = (2..=1 << 24).contains(&h) && tol < h.div_ceil(2) && 2 * h + 2 * tol < pause;
        let two_tol = tol.saturating_mul(2);
        let (recip, within) = if fast {
            // 2·tol + 1 ≤ h, so both fit in 64 bits (the second is 2⁶⁴ − 1 when 2·tol + 1 = h:
            // the one is taken off before the narrowing).
            let h = u128::from(h);
            (
                (1u128 << 64).div_ceil(h) as u64,
                (((u128::from(two_tol) + 1) << 64).div_ceil(h) - 1) as u64,
            )
        } else {
            (0, 0)
        };
        Grid {
            h,
            tol,
            two_tol,
            pause,
            recip,
            within,
        }
    }

    /// The grid point of a pulse `y` ns after the start of the tolerance window of point 0
    /// (counted modulo 2⁶⁴), if it lies within the tolerance of one of the two points after
    /// `prev` (< 2¹⁶); for a grid with a fast scan ([`Grid::recip`]).
    ///
    /// One widening multiplication by the reciprocal places it and measures it: with
    /// `recip = 2⁶⁴/h + ε` (0 ≤ ε < 1) and `y = q·h + r` (0 ≤ r < h), `y · recip` is
    /// `q·2⁶⁴ + r·2⁶⁴/h + y·ε`. Its high half is at most 2¹⁶ only for `y < 2¹⁶·h + h`, and
    /// then `y·ε < 2⁴⁰ ≤ 2⁶⁴/h`, so the high half is `q` and the low half lies in
    /// `[r·2⁶⁴/h, (r + 1)·2⁶⁴/h)`: it is at most [`Grid::within`] exactly where
    /// `r ≤ 2·tol`. So this is exactly the check by division (`place_by_division` in the
    /// tests keeps it as the reference), in one multiplication and two comparisons.
    #[inline(always)]
    fn place(&self, y: u64, prev: u64) -> Option<u64> {
        let m = u128::from(y) * u128::from(self.recip);
        let q = (m >> 64) as u64;
        let within = m as u64 <= self.within;
        let step = q.wrapping_sub(prev).wrapping_sub(1) <= 1;
        (within && step).then_some(q)
    }
}

/// The line half of a receiver: assembles pulses into [`Frame`]s on the half-bit grid.
///
/// All receivers on one segment hear the same pulses, so a bus can decode each pulse run once
/// with one `LineDecoder` and hand the frame to every slave's [`Listener`](super::Listener); the
/// result is the same as running a full [`Receiver`](super::Receiver) per slave.
#[derive(Clone, Debug)]
pub struct LineDecoder {
    grid: Grid,
    active: bool,
    run: Run,
}

impl LineDecoder {
    /// A decoder with the grid, tolerance and pause of `cfg`.
    pub fn new(cfg: &ReceiverConfig) -> LineDecoder {
        LineDecoder {
            grid: Grid::new(cfg),
            active: false,
            run: Run::default(),
        }
    }

    /// Takes the next pulse; returns the previous frame if this pulse comes after a pause.
    /// A pulse that goes back in time is a pause (timing) error of the frame in progress.
    pub fn push(&mut self, pulse: Pulse) -> Option<Frame> {
        let mut done = None;
        self.push_slice(&[pulse], |f| done = Some(f));
        done
    }

    /// Takes a slice of pulses, calling `out` with every frame they complete; the same as
    /// calling [`LineDecoder::push`] for each.
    ///
    /// A run that lies on the grid with alternating signs and ends at a pause within the slice
    /// is decoded at once (`Run::whole`, in this loop, which makes its frame from the scan's
    /// masks and hands it to `out`); any other goes through `Run::extend`, pulse by pulse where
    /// it leaves the grid. This function only cuts the slice at the pauses.
    pub fn push_slice(&mut self, pulses: &[Pulse], mut out: impl FnMut(Frame)) {
        let grid = self.grid;
        let mut rest = pulses;
        if self.active {
            if rest.is_empty() {
                return;
            }
            let taken = self.run.extend(rest, &grid);
            // The pulse after the run, if any, comes after a pause and begins the next one.
            match rest.get(taken..) {
                Some(r) if !r.is_empty() => rest = r,
                _ => return,
            }
            self.active = false;
            out(self.run.finish());
        }
        while let Some((first, tail)) = rest.split_first() {
            // A clean run at once.
            if let Some(after) = Run::whole(first, tail, &grid, &mut out) {
                rest = after;
                continue;
            }
            // Any other pulse by pulse.
            match self.by_pulse(first, tail, &mut out) {
                Some(r) => rest = r,
                None => return,
            }
        }
    }

    /// The run that begins with `first` and goes on in `tail`, pulse by pulse where it leaves
    /// the grid (`Run::extend`): calls `out` with its frame and returns the pulses after it if
    /// it ends within the slice, else keeps it as the frame in progress.
    ///
    /// Out of line, so that the compiler gives the registers of `push_slice`'s loop to the runs
    /// decided at once, the common case (7.6 instructions a telegram fewer on the phy bench's
    /// line since the run decided at once makes its frame in that loop; 4 before).
    #[inline(never)]
    fn by_pulse<'p>(
        &mut self,
        first: &Pulse,
        tail: &'p [Pulse],
        out: &mut impl FnMut(Frame),
    ) -> Option<&'p [Pulse]> {
        let grid = self.grid;
        let mut run = Run::begin(*first);
        let taken = run.extend(tail, &grid);
        match tail.get(taken..) {
            Some(r) if !r.is_empty() => {
                out(run.finish());
                Some(r)
            }
            _ => {
                self.run = run;
                self.active = true;
                None
            }
        }
    }

    /// Takes a whole encoded pulse train; the same result as pushing its pulses one by one,
    /// in constant time when the train is clean Manchester on this decoder's grid (the case of
    /// every telegram a correct transmitter sends).
    pub fn push_train(&mut self, train: &PulseTrain) -> Option<Frame> {
        let start = train.start().as_nanos();
        let after_pause = !self.active
            || (start >= self.run.last_t && start - self.run.last_t >= self.grid.pause);
        let clean = if after_pause {
            self.clean_run(train)
        } else {
            None
        };
        let Some(clean) = clean else {
            // Not clean, or overlapping the frame in progress: go pulse by pulse.
            let mut done = None;
            for p in train.iter() {
                if let Some(f) = self.push(p) {
                    done = Some(f);
                }
            }
            return done;
        };
        let done = self.flush();
        self.run = clean;
        self.active = true;
        done
    }

    /// The run of a train that re-encodes to itself, i.e. passes every line check but those
    /// computed from its bits.
    fn clean_run(&self, train: &PulseTrain) -> Option<Run> {
        let (occupied, positive) = train.masks();
        // The receiver anchors its grid at the first pulse: a clean train has it at point 0.
        if occupied & 1 == 0 || train.half_bit().as_nanos() != self.grid.h {
            return None;
        }
        let g = 63 - occupied.leading_zeros() as u64;
        let n = g.div_ceil(2) as u32;
        if n > 16 {
            return None;
        }
        let mids = mid_mask(n);
        if occupied & mids != mids {
            return None;
        }
        // Bit i (first sent in bit 0) is 1 where the mid pulse of cell i is negative.
        let t = compact((!positive & mids) >> 1);
        if grid_masks(manchester_levels(t, n), 2 * n) != (occupied, positive) {
            return None;
        }
        Some(Run {
            t0: train.start().as_nanos(),
            last_t: train.start().as_nanos() + g * self.grid.h,
            last_g: g,
            last_positive: positive & (1 << g) != 0,
            on_grid: true,
            count: occupied.count_ones(),
            occupied,
            positive,
            failed: Checks::NONE,
            clean: Some(if n == 0 { 0 } else { reverse_low(t, n) }),
        })
    }

    /// The silence that ends a frame.
    pub fn pause(&self) -> SimDuration {
        SimDuration::from_nanos(self.grid.pause)
    }

    /// When the frame in progress will be complete if no further pulse comes.
    pub fn poll_at(&self) -> Option<SimTime> {
        self.active
            .then(|| SimTime::from_nanos(self.run.last_t.saturating_add(self.grid.pause)))
    }

    /// Completes the frame in progress if the line has been silent for a pause by `now`.
    pub fn poll(&mut self, now: SimTime) -> Option<Frame> {
        match self.poll_at() {
            Some(t) if now >= t => self.flush(),
            _ => None,
        }
    }

    /// Completes the frame in progress now, whatever the time (end of a capture).
    pub fn flush(&mut self) -> Option<Frame> {
        if !self.active {
            return None;
        }
        self.active = false;
        Some(self.run.finish())
    }

    /// Drops any frame in progress.
    pub fn reset(&mut self) {
        self.active = false;
    }
}

/// The pulses the fast scan placed on the grid ([`Placed::scan`]).
#[derive(Clone, Copy, Debug)]
struct Placed {
    /// How many it took.
    n: usize,
    /// The grid point of the last one taken (the one before them if none).
    last_g: u64,
    /// Their grid points.
    occupied: u64,
    /// Their signs in order, the latest in bit 0 (1 = positive).
    signs: u64,
}

impl Placed {
    /// Takes the leading pulses of `pulses` that each lie within the tolerance of one of the
    /// two grid points after the previous one's (the one before them on point `last_g`),
    /// the grid's point 0 lying at `base` + the tolerance. The grid must have a fast scan
    /// ([`Grid::recip`]) and `pulses` must hold at most `(63 - last_g) / 2` pulses, so that
    /// every grid point stays under 64.
    ///
    /// Every pulse is placed by itself, from its distance to point 0 ([`Grid::place`]): its
    /// distance to its grid point is at most the tolerance, and the point is one or two after
    /// the last. Two pulses go at a time, which leaves one loop step and one register copy of
    /// the last point per pair.
    #[inline(always)]
    fn scan(pulses: &[Pulse], base: u64, last_g: u64, grid: &Grid) -> Placed {
        // The grid point of a pulse if it takes one of the next two after `prev`.
        let place = |p: &Pulse, prev: u64| grid.place(p.at.as_nanos().wrapping_sub(base), prev);
        let mut placed = Placed {
            n: 0,
            last_g,
            occupied: 0,
            signs: 0,
        };
        let take = |placed: &mut Placed, p: &Pulse, q: u64| {
            placed.occupied |= 1u64.wrapping_shl(q as u32);
            placed.signs = (placed.signs << 1) | p.polarity as u64;
            placed.last_g = q;
        };
        let mut pairs = pulses.chunks_exact(2);
        for pair in pairs.by_ref() {
            let Some(q0) = place(&pair[0], placed.last_g) else {
                return placed;
            };
            take(&mut placed, &pair[0], q0);
            let Some(q1) = place(&pair[1], q0) else {
                placed.n += 1;
                return placed;
            };
            take(&mut placed, &pair[1], q1);
            placed.n += 2;
        }
        if let [p] = pairs.remainder() {
            if let Some(q) = place(p, placed.last_g) {
                take(&mut placed, p, q);
                placed.n += 1;
            }
        }
        placed
    }
}

impl Run {
    fn begin(p: Pulse) -> Run {
        let positive = p.polarity == Polarity::Positive;
        Run {
            t0: p.at.as_nanos(),
            last_t: p.at.as_nanos(),
            last_g: 0,
            last_positive: positive,
            on_grid: true,
            count: 1,
            occupied: 1,
            positive: positive as u64,
            failed: if positive {
                Checks::only(Check::StartBit)
            } else {
                Checks::NONE
            },
            clean: None,
        }
    }

    /// Adds the leading pulses of `pulses` that belong to this run (all up to the first that
    /// comes after a pause) and returns how many it took.
    ///
    /// While the last pulse lies on its grid point, the pulses go through the fast scan
    /// ([`Run::scan`]); the first it does not take (the pulse after a pause, one off the grid,
    /// one past the masks) goes through [`Run::step`], which is the reference rule for any
    /// pulse, and the scan resumes once a pulse lies on the grid again.
    #[inline]
    fn extend(&mut self, pulses: &[Pulse], grid: &Grid) -> usize {
        let mut same = false;
        let mut off = false;
        let mut taken = 0;
        loop {
            if grid.recip != 0 && self.on_grid && self.last_g < 62 {
                // At most this many pulses keep the grid point within the masks (each takes
                // one or two points).
                let room = ((63 - self.last_g) / 2) as usize;
                let end = pulses.len().min(taken + room);
                let (n, s) = self.scan(&pulses[taken..end], grid);
                same |= s;
                taken += n;
            }
            let Some(&p) = pulses.get(taken) else {
                break;
            };
            let at = p.at.as_nanos();
            // A pulse that goes back in time wraps to a huge gap: it is no pause.
            if at.wrapping_sub(self.last_t) >= grid.pause && at >= self.last_t {
                break;
            }
            let s;
            let o;
            (*self, s, o) = self.step(p, grid);
            same |= s;
            off |= o;
            taken += 1;
        }
        if taken > 0 {
            self.count = self
                .count
                .saturating_add(u32::try_from(taken).unwrap_or(u32::MAX));
            self.failed = self
                .failed
                .with_if(Check::Alternation, same)
                .with_if(Check::Pause, off);
        }
        // Any pulse added makes a clean run's stored bits stale (and a clean run finished here
        // decodes to the same bits from its masks).
        self.clean = None;
        taken
    }

    /// The fast scan: takes the leading pulses of `pulses` that each lie within the tolerance
    /// of one of the two grid points after the previous one's, and returns how many it took and
    /// whether two consecutive ones (counting the run's last pulse before them) have the same
    /// sign. The caller ensures that the grid has a fast scan ([`Grid::recip`]), that the
    /// run's last pulse lies on its grid point ([`Run::on_grid`]), and that `pulses` holds at
    /// most `(63 - last_g) / 2` pulses, so that every grid point stays under 64.
    ///
    /// Every pulse is placed on the grid by itself, from its distance to the run's first pulse
    /// (a multiplication by the reciprocal of the grid), and then checked exactly: its distance
    /// to that grid point is at most the tolerance, and the point is one or two after the last.
    /// That is exactly where the reference rule puts it (with a tolerance under half the grid,
    /// the next two grid points' tolerance windows are apart), and such a pulse is never a pause
    /// (see [`Grid::recip`]); so the pulses hold no chain from one to the next but the check
    /// of the step. The signs are only collected in order; where they alternate (as on any
    /// sound line) the positive pulses are every other one of the masks'.
    #[inline]
    fn scan(&mut self, pulses: &[Pulse], grid: &Grid) -> (usize, bool) {
        let placed = Placed::scan(pulses, self.t0.wrapping_sub(grid.tol), self.last_g, grid);
        let (n, q_prev, occupied, signs) = (placed.n, placed.last_g, placed.occupied, placed.signs);
        if n == 0 {
            return (0, false);
        }
        // The run's last sign above the scanned ones (n ≤ 31): they alternate where every
        // sign differs from the one before it.
        let chain = signs | (self.last_positive as u64) << n;
        let all = (1u64 << n) - 1;
        let alternate = (chain ^ (chain >> 1)) & all == all;
        let positive = if alternate {
            // The prefix parity is 1 on the 1st, 3rd, .. scanned pulse; the 1st has the sign
            // opposite to the run's last pulse.
            let odd = prefix_parity(occupied);
            occupied & if self.last_positive { !odd } else { odd }
        } else {
            scatter(signs, occupied)
        };
        self.occupied |= occupied;
        self.positive |= positive;
        self.last_g = q_prev;
        self.last_t = pulses[n - 1].at.as_nanos();
        self.last_positive = signs & 1 == 1;
        (n, !alternate)
    }

    /// One pulse that does not come after a pause, by the reference rule: on the nearer of the
    /// next two grid points if within the tolerance of it, else off the grid (a pause error).
    /// Returns the run with it, whether it has the last pulse's sign and whether it is off the
    /// grid. (By value, so that the caller's run need not live in memory.)
    #[inline(never)]
    fn step(mut self, p: Pulse, grid: &Grid) -> (Run, bool, bool) {
        let h = grid.h;
        let at = p.at.as_nanos();
        let pos = p.polarity == Polarity::Positive;
        // Wraps only past 584 years of grid points, where every pulse is a pause error.
        let next_at = self.last_g.wrapping_add(1).wrapping_mul(h);
        let dev1 = at.wrapping_sub(self.t0).wrapping_sub(next_at) as i64;
        let two = dev1 > (h / 2) as i64;
        let dev = dev1.wrapping_sub(if two { h as i64 } else { 0 });
        let off = dev.unsigned_abs() > grid.tol;
        let g = if off {
            off_grid(h, at, self.t0, self.last_t, self.last_g)
        } else {
            self.last_g.wrapping_add(1 + two as u64)
        };
        let same = pos == self.last_positive;
        if g < 64 {
            self.occupied |= 1 << g;
            self.positive |= (pos as u64) << g;
        }
        self.last_g = g;
        self.last_t = at;
        self.last_positive = pos;
        self.on_grid = at
            .wrapping_sub(self.t0)
            .wrapping_sub(g.wrapping_mul(h))
            .wrapping_add(grid.tol)
            <= grid.two_tol;
        (self, same, off)
    }

    #[inline(always)]
    fn finish(&self) -> Frame {
        let g = self.last_g;
        let n = g.div_ceil(2);
        let mut failed = self.failed;
        let cells = n.min(32) as u32;
        let mids = mid_mask(cells);
        let raw = match self.clean {
            Some(raw) => raw,
            None if self.occupied & mids == mids => {
                // Bit i is 1 where the mid pulse of cell i (point 2i + 1) is negative.
                let ones = !self.positive & mids;
                if cells <= 16 {
                    // Every telegram of the bus: 32 bits to compact and 16 to reverse.
                    reverse_low16(compact32((ones >> 1) as u32), cells)
                } else {
                    // Reversed, point 2i + 1 is point 62 − 2i, which compacts to bit 31 − i:
                    // the bits in transmission order, first bit highest, in the top `cells`.
                    let top = compact(ones.reverse_bits());
                    (u64::from(top) >> (32 - cells)) as u32
                }
            }
            None => {
                failed = failed.with(Check::Information);
                level_raw(self.occupied, self.positive, cells)
            }
        };
        failed = failed.union(bit_checks(raw, cells, g));
        Frame {
            start: SimTime::from_nanos(self.t0),
            end: SimTime::from_nanos(self.last_t),
            pulses: self.count,
            bit_count: n.min(u32::MAX as u64) as u32,
            raw,
            line_failed: failed,
        }
    }
}

/// The checks a frame's bits decide: start bit, parity and end bit, for `raw` holding its
/// first `cells` bits (the first highest, nothing above them; 0 without a cell) and its last
/// pulse on grid point `g`.
///
/// Without a branch or a mask for each: the first bit is what shifts out below the cells, the
/// parity of the bits between the first and the last is that of all of them less those two
/// (with one cell the identity does not hold, but there is no parity to check), and the three
/// failures are put together as bits of the set (the compiler made a longer sequence of
/// tests of the flags one by one).
#[inline(always)]
fn bit_checks(raw: u32, cells: u32, g: u64) -> Checks {
    let first = (u64::from(raw) << 1 >> cells) as u32 & 1;
    bit_checks_odd(raw, odd_parity(raw) as u32 ^ first, first, cells, g)
}

/// [`bit_checks`] with the first bit of `raw` known (`first`: 0 without a cell) and the parity
/// of its other bits (`rest_odd`: 1 for an odd number of ones).
#[inline(always)]
fn bit_checks_odd(raw: u32, rest_odd: u32, first: u32, cells: u32, g: u64) -> Checks {
    let last = raw & 1;
    let between_odd = rest_odd ^ last;
    let parity = between_odd & u32::from(cells >= 3);
    // The last pulse not at the end of a cell, or a last bit 0.
    let end = (g as u32 & 1) | (last ^ 1);
    Checks::from_bits(
        (first << Check::StartBit as u32
            | parity << Check::Parity as u32
            | end << Check::EndBit as u32) as u8,
    )
}

/// Bit j is the parity of the bits of `x` at j and below.
const fn prefix_parity(x: u64) -> u64 {
    let mut x = x;
    x ^= x << 1;
    x ^= x << 2;
    x ^= x << 4;
    x ^= x << 8;
    x ^= x << 16;
    x ^= x << 32;
    x
}

/// The signs of a scan that do not alternate on the grid points in `occupied`: the latest
/// sign (bit 0 of `signs`) on the highest point, and so on down.
#[cold]
fn scatter(signs: u64, occupied: u64) -> u64 {
    let mut positive = 0;
    let mut rest = occupied;
    let mut signs = signs;
    while rest != 0 {
        let top = 63 - rest.leading_zeros();
        positive |= (signs & 1) << top;
        signs >>= 1;
        rest &= !(1 << top);
    }
    positive
}

/// `true` if `x` has an odd number of ones (without relying on a popcount instruction): the
/// parity of each nibble in its low bit, then their sum in the top nibble by one multiplication.
const fn odd_parity(x: u32) -> bool {
    let mut x = x ^ (x >> 1);
    x ^= x >> 2;
    (x & 0x1111_1111).wrapping_mul(0x1111_1111) >> 28 & 1 == 1
}

/// The grid point of a pulse at `at` off the next two grid points of its run: the nearest one,
/// but never behind the last pulse's point `last_g`. The run has a pause error.
#[cold]
fn off_grid(h: u64, at: u64, t0: u64, last_t: u64, last_g: u64) -> u64 {
    if at < last_t {
        return last_g.saturating_add(1);
    }
    let q = at.saturating_sub(t0).saturating_add(h / 2) / h;
    q.max(last_g.saturating_add(1))
}

/// Grid points 1, 3, .., 2·cells − 1: the middles of the first `cells` (≤ 32) bit cells.
const fn mid_mask(cells: u32) -> u64 {
    if cells == 0 {
        0
    } else {
        0xAAAA_AAAA_AAAA_AAAA & (u64::MAX >> (64 - 2 * cells))
    }
}

/// [`level_bits`] in transmission order, first bit highest.
#[cold]
fn level_raw(occupied: u64, positive: u64, cells: u32) -> u32 {
    if cells == 0 {
        0
    } else {
        reverse_low(level_bits(occupied, positive, cells), cells)
    }
}

/// Bits read from line levels when some mid pulses are missing: a cell reads 1 where the line
/// is low during its second half (the level left by the last pulse at or before its middle).
fn level_bits(occupied: u64, positive: u64, cells: u32) -> u32 {
    let mut bits = 0u32;
    for i in 0..cells {
        let upto = occupied & (u64::MAX >> (62 - 2 * i));
        if upto != 0 {
            let last = 63 - upto.leading_zeros();
            if positive & (1 << last) == 0 {
                bits |= 1 << i;
            }
        }
    }
    bits
}

#[cfg(test)]
mod tests;
mod whole;
