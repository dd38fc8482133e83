//! The line decoder as it was before the per-pulse loop was rewritten for speed (the
//! `fastdecode` change), kept verbatim but for its names: the reference the equivalence
//! property test (`tests::the_line_decoder_equals_its_reference`) holds the fast one to.
#![allow(dead_code)]

use super::line::Frame;

use super::checks::{Check, Checks};
use super::config::ReceiverConfig;
use crate::manchester::{compact, manchester_levels, reverse_low};
use crate::pulse::{grid_masks, Polarity, Pulse, PulseTrain};
use crate::time::{SimDuration, SimTime};

/// The telegram in progress.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct ReferenceRun {
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
pub(super) struct ReferenceLineDecoder {
    half_bit: u64,
    tolerance: u64,
    pause: u64,
    active: bool,
    run: ReferenceRun,
}

impl ReferenceLineDecoder {
    /// A decoder with the grid, tolerance and pause of `cfg`.
    pub fn new(cfg: &ReceiverConfig) -> ReferenceLineDecoder {
        ReferenceLineDecoder {
            half_bit: cfg.half_bit,
            tolerance: cfg.tolerance,
            pause: cfg.pause,
            active: false,
            run: ReferenceRun::default(),
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
    /// calling `push` for each.
    ///
    /// This is the receiver's one per-pulse loop. The state of the run lives in locals so that
    /// it stays in registers; the common pulse (within the tolerance of one of the next two
    /// grid points) costs no branch beyond the loop's own.
    pub fn push_slice(&mut self, pulses: &[Pulse], mut out: impl FnMut(Frame)) {
        let (h, tol, pause) = (self.half_bit, self.tolerance, self.pause);
        let half = (h / 2) as i64;
        let mut rest = pulses;
        if !self.active {
            let Some((first, tail)) = rest.split_first() else {
                return;
            };
            self.run = ReferenceRun::begin(*first, h);
            self.active = true;
            rest = tail;
        }
        if rest.is_empty() {
            return;
        }
        // The run in locals, so that nothing in the loop takes its address.
        let ReferenceRun {
            mut t0,
            mut last_t,
            mut next_at,
            mut last_g,
            mut last_positive,
            mut count,
            mut occupied,
            mut positive,
            mut failed,
            ..
        } = self.run;
        let mut same = false;
        let mut off = false;
        // The locals back in a run, with the checks the loop collected. Any pulse added makes a
        // clean run's stored bits stale.
        macro_rules! packed {
            () => {
                ReferenceRun {
                    t0,
                    last_t,
                    next_at,
                    last_g,
                    last_positive,
                    count,
                    occupied,
                    positive,
                    failed: failed
                        .with_if(Check::Alternation, same)
                        .with_if(Check::Pause, off),
                    clean: None,
                }
            };
        }
        for p in rest {
            let at = p.at.as_nanos();
            let pos = p.polarity == Polarity::Positive;
            // A pulse that goes back in time wraps to a huge gap: it is no pause.
            if at.wrapping_sub(last_t) >= pause && at >= last_t {
                out(packed!().finish());
                ReferenceRun {
                    t0,
                    last_t,
                    next_at,
                    last_g,
                    last_positive,
                    count,
                    occupied,
                    positive,
                    failed,
                    ..
                } = ReferenceRun::begin(*p, h);
                same = false;
                off = false;
                continue;
            }
            let dev1 = at.wrapping_sub(t0).wrapping_sub(next_at) as i64;
            let two = dev1 > half;
            let dev = dev1.wrapping_sub(if two { h as i64 } else { 0 });
            let g = if dev.unsigned_abs() <= tol {
                last_g + 1 + two as u64
            } else {
                off = true;
                off_grid(h, at, t0, last_t, last_g)
            };
            same |= pos == last_positive;
            if g < 64 {
                occupied |= 1 << g;
                positive |= (pos as u64) << g;
            }
            last_g = g;
            // Wraps only past 584 years of grid points, where every pulse is a pause error.
            next_at = g.wrapping_add(1).wrapping_mul(h);
            last_t = at;
            last_positive = pos;
            count = count.saturating_add(1);
        }
        self.run = packed!();
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
    fn clean_run(&self, train: &PulseTrain) -> Option<ReferenceRun> {
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
        Some(ReferenceRun {
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

impl ReferenceRun {
    fn begin(p: Pulse, h: u64) -> ReferenceRun {
        let positive = p.polarity == Polarity::Positive;
        ReferenceRun {
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

    fn finish(self) -> Frame {
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
