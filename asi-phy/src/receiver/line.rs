//! The line half of a receiver: pulse runs assembled on the half-bit grid into [`Frame`]s, with
//! the checks that depend on the line alone.

use super::checks::{Check, Checks};
use super::config::ReceiverConfig;
use crate::manchester::{compact, manchester_levels, reverse_low};
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
    /// Time of grid point `last_g + 1` after `t0`, ns.
    pub(super) next_at: u64,
    /// Grid point of the last pulse.
    pub(super) last_g: u64,
    pub(super) last_positive: bool,
    pub(super) count: u32,
    pub(super) occupied: u64,
    pub(super) positive: u64,
    pub(super) failed: Checks,
    /// For a run known to be clean Manchester: its bits in transmission order.
    pub(super) clean: Option<u32>,
}

/// The line half of a receiver: assembles pulses into [`Frame`]s on the half-bit grid.
///
/// All receivers on one segment hear the same pulses, so a bus can decode each pulse run once
/// with one `LineDecoder` and hand the frame to every slave's [`Listener`](super::Listener); the
/// result is the same as running a full [`Receiver`](super::Receiver) per slave.
#[derive(Clone, Debug)]
pub struct LineDecoder {
    half_bit: u64,
    tolerance: u64,
    pause: u64,
    active: bool,
    run: Run,
}

impl LineDecoder {
    /// A decoder with the grid, tolerance and pause of `cfg`.
    pub fn new(cfg: &ReceiverConfig) -> LineDecoder {
        LineDecoder {
            half_bit: cfg.half_bit,
            tolerance: cfg.tolerance,
            pause: cfg.pause,
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
    /// This is the receiver's one per-pulse loop, [`Run::extend`]; this function only cuts the
    /// slice at the pauses, so that the loop itself holds nothing but the run.
    pub fn push_slice(&mut self, pulses: &[Pulse], mut out: impl FnMut(Frame)) {
        let (h, tol, pause) = (self.half_bit, self.tolerance, self.pause);
        let mut rest = pulses;
        loop {
            if !self.active {
                let Some((first, tail)) = rest.split_first() else {
                    return;
                };
                self.run = Run::begin(*first, h);
                self.active = true;
                rest = tail;
            }
            if rest.is_empty() {
                return;
            }
            let taken = self.run.extend(rest, h, tol, pause);
            // The pulse after the run, if any, comes after a pause and begins the next one.
            rest = match rest.get(taken..) {
                Some(r) if !r.is_empty() => r,
                _ => return,
            };
            self.active = false;
            out(self.run.finish());
        }
    }

    /// Takes a whole encoded pulse train; the same result as pushing its pulses one by one,
    /// in constant time when the train is clean Manchester on this decoder's grid (the case of
    /// every telegram a correct transmitter sends).
    pub fn push_train(&mut self, train: &PulseTrain) -> Option<Frame> {
        let start = train.start().as_nanos();
        let after_pause =
            !self.active || (start >= self.run.last_t && start - self.run.last_t >= self.pause);
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
        if occupied & 1 == 0 || train.half_bit().as_nanos() != self.half_bit {
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
            last_t: train.start().as_nanos() + g * self.half_bit,
            next_at: (g + 1) * self.half_bit,
            last_g: g,
            last_positive: positive & (1 << g) != 0,
            count: occupied.count_ones(),
            occupied,
            positive,
            failed: Checks::NONE,
            clean: Some(if n == 0 { 0 } else { reverse_low(t, n) }),
        })
    }

    /// The silence that ends a frame.
    pub fn pause(&self) -> SimDuration {
        SimDuration::from_nanos(self.pause)
    }

    /// When the frame in progress will be complete if no further pulse comes.
    pub fn poll_at(&self) -> Option<SimTime> {
        self.active
            .then(|| SimTime::from_nanos(self.run.last_t.saturating_add(self.pause)))
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

impl Run {
    fn begin(p: Pulse, h: u64) -> Run {
        let positive = p.polarity == Polarity::Positive;
        Run {
            t0: p.at.as_nanos(),
            last_t: p.at.as_nanos(),
            next_at: h,
            last_g: 0,
            last_positive: positive,
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
    /// The state lives in locals so that it stays in registers, and the grid point after the
    /// last pulse is kept as an absolute time (`t0 + next_at`, wrapping as `next_at` does),
    /// advanced by one or two half bits: the chain from one pulse to the next is a subtraction,
    /// a comparison and an addition. The common pulse (within the tolerance of one of the next
    /// two grid points) costs no branch beyond the loop's own.
    fn extend(&mut self, pulses: &[Pulse], h: u64, tol: u64, pause: u64) -> usize {
        let half = (h / 2) as i64;
        let t0 = self.t0;
        let mut next = t0.wrapping_add(self.next_at);
        let mut last_t = self.last_t;
        let mut last_positive = self.last_positive;
        let mut occupied = self.occupied;
        let mut positive = self.positive;
        let mut same = false;
        let mut off = false;
        let mut taken = 0;
        loop {
            // The grid point of the last pulse as a bit (0 once past the masks' 64 points),
            // and how many points the pulses on the grid have advanced from it.
            let mut cursor = if self.last_g < 64 {
                1u64 << self.last_g
            } else {
                0
            };
            let mut steps = 0u64;
            let mut stop = None;
            while let Some(p) = pulses.get(taken) {
                let at = p.at.as_nanos();
                // A pulse that goes back in time wraps to a huge gap: it is no pause.
                if at.wrapping_sub(last_t) >= pause && at >= last_t {
                    stop = Some(false);
                    break;
                }
                let dev1 = at.wrapping_sub(next) as i64;
                let two = dev1 > half;
                // `h` if the pulse is nearer the second grid point, else 0: a mask, not a
                // branch (which way a pulse goes is the data's, and a branch on it mispredicts).
                let skip = (two as u64).wrapping_neg() & h;
                let dev = dev1.wrapping_sub(skip as i64);
                if dev.unsigned_abs() > tol {
                    stop = Some(true);
                    break;
                }
                let pos = p.polarity == Polarity::Positive;
                next = next.wrapping_add(h).wrapping_add(skip);
                cursor = (cursor << 1) << two as u32;
                steps += 1 + two as u64;
                occupied |= cursor;
                positive |= cursor & (pos as u64).wrapping_neg();
                same |= pos == last_positive;
                last_t = at;
                last_positive = pos;
                taken += 1;
            }
            self.last_g += steps;
            if stop != Some(true) {
                break;
            }
            // A pulse off the next two grid points: the run has a pause error.
            let p = pulses[taken];
            let at = p.at.as_nanos();
            let pos = p.polarity == Polarity::Positive;
            off = true;
            let g = off_grid(h, at, t0, last_t, self.last_g);
            // Wraps only past 584 years of grid points, where every pulse is a pause error.
            next = t0.wrapping_add(g.wrapping_add(1).wrapping_mul(h));
            same |= pos == last_positive;
            if g < 64 {
                occupied |= 1 << g;
                positive |= (pos as u64) << g;
            }
            self.last_g = g;
            last_t = at;
            last_positive = pos;
            taken += 1;
        }
        if taken > 0 {
            self.next_at = next.wrapping_sub(t0);
            self.last_t = last_t;
            self.last_positive = last_positive;
            self.occupied = occupied;
            self.positive = positive;
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

    fn finish(&self) -> Frame {
        let g = self.last_g;
        let n = g.div_ceil(2);
        let mut failed = self.failed;
        let cells = n.min(32) as u32;
        let raw = match self.clean {
            Some(raw) => raw,
            None => {
                let mids = mid_mask(cells);
                let raw = if self.occupied & mids == mids {
                    // Bit i is 1 where the mid pulse of cell i is negative.
                    compact((!self.positive & mids) >> 1)
                } else {
                    failed = failed.with(Check::Information);
                    level_bits(self.occupied, self.positive, cells)
                };
                // Bit i is in position i; turn it into transmission order, first bit highest.
                if cells == 0 {
                    0
                } else {
                    reverse_low(raw, cells)
                }
            }
        };
        if cells >= 1 && raw >> (cells - 1) & 1 == 1 {
            failed = failed.with(Check::StartBit);
        }
        if cells >= 3 {
            let between = (raw >> 1) & ((1 << (cells - 2)) - 1);
            if odd_parity(between) {
                failed = failed.with(Check::Parity);
            }
        }
        if g % 2 != 0 || n == 0 || raw & 1 == 0 {
            failed = failed.with(Check::EndBit);
        }
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

/// `true` if `x` has an odd number of ones (without relying on a popcount instruction).
const fn odd_parity(x: u32) -> bool {
    let mut x = x ^ (x >> 16);
    x ^= x >> 8;
    x ^= x >> 4;
    x ^= x >> 2;
    x ^= x >> 1;
    x & 1 == 1
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
