//! The AS-i receiver: pulses in, telegrams out, each with the seven receiver checks (SPEC §1
//! "The seven receiver checks"; reference/asi.md §3.1; seed 003 §2.2.2).
//!
//! A telegram is the run of pulses between two pauses. The receiver anchors the half-bit grid at
//! the first pulse of the run, places every later pulse on the nearest grid point, and decodes
//! bit `i` from the pulse at the middle of its cell (grid point `2i + 1`: negative = 1,
//! positive = 0). It then applies the checks of SPEC §1, with these precisions (**Decision**,
//! recorded in the README):
//!
//! | check | fails when |
//! |---|---|
//! | start bit | the first pulse is positive, or the first bit decodes as 1 |
//! | alternation | two consecutive pulses have the same polarity |
//! | pause | inside the telegram two pulses are more than a bit time apart, or closer than the grid allows, or a pulse is off the grid by more than the tolerance; or, after an erroneous telegram, the telegram came after less than the asynchronous pause (the A²SI receiver needs 18 µs of silence to resynchronise) |
//! | information | a bit cell has no pulse at its middle |
//! | parity | the bits between start and end bit hold an odd number of ones |
//! | end bit | the last bit is not 1, or the line does not return to idle (a positive pulse at the end of the end bit) |
//! | length | the number of bits is not 14 (request) or 7 (response) |
//!
//! The receiver is a state machine fed one pulse at a time ([`Receiver::push`]); a telegram is
//! complete when the next pulse comes after a pause, or when [`Receiver::poll`] is called at or
//! after [`Receiver::poll_at`]. Nothing allocates; no input can make it panic.

use crate::manchester::{compact, manchester_levels, reverse_low};
use crate::pulse::{grid_masks, Polarity, Pulse, PulseTrain};
use crate::telegram::{Request, Response};
use crate::time::{SimDuration, SimTime};
use crate::timing::BusTiming;
use core::fmt;

/// One of the seven receiver checks, in the fixed order that picks the primary class.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[repr(u8)]
pub enum Check {
    /// The telegram does not begin with a negative pulse and a 0 bit.
    StartBit = 0,
    /// Two consecutive pulses with the same polarity.
    Alternation = 1,
    /// A pulse off the half-bit grid, a gap longer than a bit time, or too short a pause.
    Pause = 2,
    /// A bit cell without its mid-bit pulse (Manchester violation).
    Information = 3,
    /// Odd parity.
    Parity = 4,
    /// The end bit is not 1 or the line does not return to idle.
    EndBit = 5,
    /// Not 14 (request) or 7 (response) bits.
    Length = 6,
}

impl Check {
    /// All seven, in order.
    pub const ALL: [Check; 7] = [
        Check::StartBit,
        Check::Alternation,
        Check::Pause,
        Check::Information,
        Check::Parity,
        Check::EndBit,
        Check::Length,
    ];

    /// The check's name as SPEC §1 spells it.
    pub const fn name(self) -> &'static str {
        match self {
            Check::StartBit => "start bit",
            Check::Alternation => "alternation",
            Check::Pause => "pause",
            Check::Information => "information",
            Check::Parity => "parity",
            Check::EndBit => "end bit",
            Check::Length => "length",
        }
    }
}

impl fmt::Display for Check {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A set of failed checks.
#[derive(Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Checks(u8);

impl Checks {
    /// No check failed.
    pub const NONE: Checks = Checks(0);

    /// The set holding `check` only.
    pub const fn only(check: Check) -> Checks {
        Checks(1 << check as u8)
    }

    /// `true` if no check failed.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// `true` if `check` failed.
    pub const fn contains(self, check: Check) -> bool {
        self.0 & (1 << check as u8) != 0
    }

    /// The set with `check` added.
    pub const fn with(self, check: Check) -> Checks {
        Checks(self.0 | (1 << check as u8))
    }

    /// Every check failed in `self` or in `other`.
    pub const fn union(self, other: Checks) -> Checks {
        Checks(self.0 | other.0)
    }

    /// The set whose bit `k` stands for the check `Check::ALL[k]`; bits 7 and up are ignored.
    pub const fn from_bits(bits: u8) -> Checks {
        Checks(bits & 0x7F)
    }

    /// The set as bits, bit `k` for `Check::ALL[k]`.
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// The set with `check` added if `failed`.
    pub const fn with_if(self, check: Check, failed: bool) -> Checks {
        Checks(self.0 | ((failed as u8) << check as u8))
    }

    /// The first failed check in the fixed order of SPEC §1, the telegram's primary class.
    pub const fn primary(self) -> Option<Check> {
        if self.0 == 0 {
            return None;
        }
        Some(Check::ALL[self.0.trailing_zeros() as usize])
    }

    /// The failed checks in order.
    pub fn iter(self) -> impl Iterator<Item = Check> {
        Check::ALL.into_iter().filter(move |c| self.contains(*c))
    }

    /// Number of failed checks.
    pub const fn len(self) -> u32 {
        self.0.count_ones()
    }
}

impl core::ops::BitOr for Checks {
    type Output = Checks;
    fn bitor(self, rhs: Checks) -> Checks {
        self.union(rhs)
    }
}

impl core::ops::BitOrAssign for Checks {
    fn bitor_assign(&mut self, rhs: Checks) {
        *self = self.union(rhs);
    }
}

impl fmt::Debug for Checks {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_set().entries(self.iter()).finish()
    }
}

impl fmt::Display for Checks {
    /// `ok`, or the failed checks joined by `+`: `alternation+information`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_empty() {
            return f.write_str("ok");
        }
        for (i, c) in self.iter().enumerate() {
            if i > 0 {
                f.write_str("+")?;
            }
            f.write_str(c.name())?;
        }
        Ok(())
    }
}

/// Which telegrams a receiver listens for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Expect {
    /// Every telegram is a 14-bit request (a slave that hears only the master).
    Requests,
    /// Every telegram is a 7-bit response (the master during its response window).
    Responses,
    /// A live bus: a telegram that starts within the response timeout after a valid request is
    /// that request's response, anything else a request. Responses never change the receiver's
    /// synchronisation: a slave that is not addressed waits out the reply of another slave
    /// (A²SI §7.1.2.1). This is the setting for slaves and for bus monitors.
    Both,
}

/// What a received telegram was taken for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TelegramKind {
    /// A master request, 14 bits expected.
    Request,
    /// A slave response, 7 bits expected.
    Response,
}

impl TelegramKind {
    /// The length this kind of telegram has.
    pub const fn bits(self) -> u32 {
        match self {
            TelegramKind::Request => Request::BITS,
            TelegramKind::Response => Response::BITS,
        }
    }
}

/// Receiver settings, derived from a [`BusTiming`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReceiverConfig {
    half_bit: u64,
    tolerance: u64,
    pause: u64,
    async_pause: u64,
    response_window: u64,
    expect: Expect,
}

impl ReceiverConfig {
    /// The settings for `timing`, listening for `expect`.
    pub fn new(timing: &BusTiming, expect: Expect) -> ReceiverConfig {
        ReceiverConfig {
            half_bit: timing.half_bit().as_nanos().max(1),
            tolerance: timing.tolerance().as_nanos(),
            pause: timing.min_pause().as_nanos().max(1),
            async_pause: timing.async_pause().as_nanos(),
            response_window: timing.response_timeout().as_nanos(),
            expect,
        }
    }

    /// What this receiver listens for.
    pub const fn expect(&self) -> Expect {
        self.expect
    }

    /// The silence that ends a telegram.
    pub const fn pause(&self) -> SimDuration {
        SimDuration::from_nanos(self.pause)
    }
}

/// A telegram as the receiver saw it: its bits, its timing, and the checks that failed.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Received {
    /// What the receiver took it for (which length it expected).
    pub kind: TelegramKind,
    /// Time of the first pulse.
    pub start: SimTime,
    /// Time of the last pulse.
    pub end: SimTime,
    /// Number of pulses.
    pub pulses: u32,
    /// Number of bits decoded (a cell is counted once its middle is reached).
    pub bit_count: u32,
    /// The first (up to 32) bits, first bit in the most significant used position.
    pub raw: u32,
    /// The checks that failed.
    pub failed: Checks,
}

impl Received {
    /// `true` if every check passed.
    pub const fn is_valid(&self) -> bool {
        self.failed.is_empty()
    }

    /// The primary error class, `None` for a valid telegram.
    pub const fn primary(&self) -> Option<Check> {
        self.failed.primary()
    }

    /// The request, if this is a valid one.
    pub fn request(&self) -> Option<Request> {
        if self.is_valid() && self.kind == TelegramKind::Request {
            Request::from_bits(self.raw as u16).ok()
        } else {
            None
        }
    }

    /// The response, if this is a valid one.
    pub fn response(&self) -> Option<Response> {
        if self.is_valid() && self.kind == TelegramKind::Response {
            Response::from_bits(self.raw as u8).ok()
        } else {
            None
        }
    }

    /// The decoded bits as `0`/`1` digits (at most 32), for traces of broken telegrams.
    pub fn bit_string(&self) -> String {
        let n = self.bit_count.min(32);
        (0..n)
            .map(|i| {
                if self.raw >> (n - 1 - i) & 1 == 1 {
                    '1'
                } else {
                    '0'
                }
            })
            .collect()
    }
}

impl fmt::Debug for Received {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Received({:?} at {} bits={} [{}] {})",
            self.kind,
            self.start,
            self.bit_count,
            self.bit_string(),
            self.failed
        )
    }
}

/// A pulse run between two pauses as every receiver on the line sees it: its timing, its bits,
/// and the checks that depend on the line alone. [`Listener::accept`] turns it into one
/// receiver's [`Received`] telegram.
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
struct Run {
    /// Time of the first pulse, ns.
    t0: u64,
    /// Time of the last pulse, ns.
    last_t: u64,
    /// Time of grid point `last_g + 1` after `t0`, ns.
    next_at: u64,
    /// Grid point of the last pulse.
    last_g: u64,
    last_positive: bool,
    count: u32,
    occupied: u64,
    positive: u64,
    failed: Checks,
    /// For a run known to be clean Manchester: its bits in transmission order.
    clean: Option<u32>,
}

/// The line half of a receiver: assembles pulses into [`Frame`]s on the half-bit grid.
///
/// All receivers on one segment hear the same pulses, so a bus can decode each pulse run once
/// with one `LineDecoder` and hand the frame to every slave's [`Listener`]; the result is the
/// same as running a full [`Receiver`] per slave.
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
            self.run = Run::begin(*first, h);
            self.active = true;
            rest = tail;
        }
        if rest.is_empty() {
            return;
        }
        // The run in locals, so that nothing in the loop takes its address.
        let Run {
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
                Run {
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
                Run {
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
                } = Run::begin(*p, h);
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

/// The listener half of a receiver: what it expects, and its synchronisation.
///
/// After a telegram that failed any check the listener is asynchronous and accepts the next
/// one only after [`BusTiming::async_pause`] of silence (A²SI §7.1.2.1); a fresh listener has
/// heard nothing, so its first telegram needs no pause.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Listener {
    expect: Expect,
    async_pause: u64,
    response_window: u64,
    synced: bool,
    prev_end: Option<SimTime>,
    window_from: Option<SimTime>,
}

impl Listener {
    /// A listener that has just powered up, with the expectations of `cfg`.
    pub fn new(cfg: &ReceiverConfig) -> Listener {
        Listener {
            expect: cfg.expect,
            async_pause: cfg.async_pause,
            response_window: cfg.response_window,
            synced: false,
            prev_end: None,
            window_from: None,
        }
    }

    /// `true` after a valid telegram.
    pub fn is_synchronised(&self) -> bool {
        self.synced
    }

    /// Back to the power-up state.
    pub fn reset(&mut self) {
        self.synced = false;
        self.prev_end = None;
        self.window_from = None;
    }

    /// The telegram this listener makes of `frame`, with all seven checks.
    pub fn accept(&mut self, frame: &Frame) -> Received {
        let mut kind = match self.expect {
            Expect::Requests | Expect::Both => TelegramKind::Request,
            Expect::Responses => TelegramKind::Response,
        };
        if let Some(from) = self.window_from.take() {
            if frame.start >= from
                && frame.start.as_nanos() - from.as_nanos() <= self.response_window
            {
                kind = TelegramKind::Response;
            }
        }
        let mut failed = frame.line_failed;
        if let Some(prev) = self.prev_end {
            let silence = frame.start.as_nanos().saturating_sub(prev.as_nanos());
            if !self.synced && silence < self.async_pause {
                failed = failed.with(Check::Pause);
            }
        }
        if frame.bit_count != kind.bits() {
            failed = failed.with(Check::Length);
        }
        self.prev_end = Some(frame.end);
        let is_request = kind == TelegramKind::Request;
        if is_request || self.expect != Expect::Both {
            self.synced = failed.is_empty();
        }
        if self.expect == Expect::Both && is_request && failed.is_empty() {
            self.window_from = Some(frame.end);
        }
        Received {
            kind,
            start: frame.start,
            end: frame.end,
            pulses: frame.pulses,
            bit_count: frame.bit_count,
            raw: frame.raw,
            failed,
        }
    }
}

/// A streaming AS-i receiver: a [`LineDecoder`] and a [`Listener`] in one.
#[derive(Clone, Debug)]
pub struct Receiver {
    cfg: ReceiverConfig,
    line: LineDecoder,
    listener: Listener,
}

impl Receiver {
    /// A receiver that has just powered up (asynchronous, idle).
    pub fn new(cfg: ReceiverConfig) -> Receiver {
        Receiver {
            line: LineDecoder::new(&cfg),
            listener: Listener::new(&cfg),
            cfg,
        }
    }

    /// Its settings.
    pub fn config(&self) -> &ReceiverConfig {
        &self.cfg
    }

    /// `true` after a valid telegram: the next one is accepted after the normal pause.
    pub fn is_synchronised(&self) -> bool {
        self.listener.is_synchronised()
    }

    /// Back to the power-up state, dropping any telegram in progress.
    pub fn reset(&mut self) {
        self.line.reset();
        self.listener.reset();
    }

    /// Takes the next pulse. Returns the previous telegram if this pulse comes after a pause
    /// and so completes it. Pulses are expected in time order; one that goes back in time is a
    /// pause (timing) error of the telegram in progress.
    pub fn push(&mut self, pulse: Pulse) -> Option<Received> {
        let frame = self.line.push(pulse)?;
        Some(self.listener.accept(&frame))
    }

    /// Takes a slice of pulses, calling `out` with every telegram they complete (see
    /// [`LineDecoder::push_slice`]); the fastest way to decode a capture.
    pub fn push_slice(&mut self, pulses: &[Pulse], mut out: impl FnMut(Received)) {
        let listener = &mut self.listener;
        self.line.push_slice(pulses, |f| out(listener.accept(&f)));
    }

    /// Takes a whole encoded pulse train (see [`LineDecoder::push_train`]).
    pub fn push_train(&mut self, train: &PulseTrain) -> Option<Received> {
        let frame = self.line.push_train(train)?;
        Some(self.listener.accept(&frame))
    }

    /// When the telegram in progress will be complete if no further pulse comes.
    pub fn poll_at(&self) -> Option<SimTime> {
        self.line.poll_at()
    }

    /// Completes the telegram in progress if the line has been silent for a pause by `now`.
    pub fn poll(&mut self, now: SimTime) -> Option<Received> {
        let frame = self.line.poll(now)?;
        Some(self.listener.accept(&frame))
    }

    /// Completes the telegram in progress now, whatever the time (end of a capture).
    pub fn flush(&mut self) -> Option<Received> {
        let frame = self.line.flush()?;
        Some(self.listener.accept(&frame))
    }

    /// Decodes a whole pulse sequence, yielding every telegram (the last one flushed).
    pub fn decode<I: IntoIterator<Item = Pulse>>(&mut self, pulses: I) -> Decode<'_, I::IntoIter> {
        Decode {
            rx: self,
            pulses: pulses.into_iter(),
            done: false,
        }
    }
}

/// The telegrams of a pulse sequence; see [`Receiver::decode`].
#[derive(Debug)]
pub struct Decode<'a, I> {
    rx: &'a mut Receiver,
    pulses: I,
    done: bool,
}

impl<I: Iterator<Item = Pulse>> Iterator for Decode<'_, I> {
    type Item = Received;

    fn next(&mut self) -> Option<Received> {
        if self.done {
            return None;
        }
        for p in self.pulses.by_ref() {
            if let Some(r) = self.rx.push(p) {
                return Some(r);
            }
        }
        self.done = true;
        self.rx.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::manchester::HalfBits;
    use crate::pulse::PulseTrain;
    use crate::telegram::{Address, Nibble};

    fn timing() -> BusTiming {
        BusTiming::default()
    }

    fn rx(expect: Expect) -> Receiver {
        Receiver::new(timing().receiver(expect))
    }

    fn train(req: Request, at_us: u64) -> PulseTrain {
        PulseTrain::request(req, SimTime::from_micros(at_us), timing().half_bit())
    }

    fn dexg(a: u8, d: u8) -> Request {
        Request::data_exchange(Address::new(a).expect("addr"), Nibble::from_low_bits(d))
            .expect("valid")
    }

    fn pulses(spec: &str, start_us: u64) -> Vec<Pulse> {
        spec.split_whitespace()
            .map(|tok| {
                let (k, s) = tok.split_at(tok.len() - 1);
                let k: f64 = k.parse().expect("grid point");
                let pol = if s == "+" {
                    Polarity::Positive
                } else {
                    Polarity::Negative
                };
                Pulse::new(
                    SimTime::from_nanos(start_us * 1000 + (3000.0 * k) as u64),
                    pol,
                )
            })
            .collect()
    }

    #[test]
    fn decodes_the_spec_vectors() {
        let mut r = rx(Expect::Requests);
        let got: Vec<Received> = r.decode(train(dexg(5, 0b1010), 0)).collect();
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].request(), Some(dexg(5, 0b1010)));
        let mut r = rx(Expect::Responses);
        let got: Vec<Received> = r
            .decode(pulses("0- 1+ 2- 3+ 5- 6+ 7- 9+ 10- 11+ 13- 14+", 0))
            .collect();
        assert_eq!(
            got[0].response().map(|r| r.data()),
            Some(Nibble::from_low_bits(0b0110))
        );
    }

    #[test]
    fn a_telegram_completes_after_the_pause() {
        let mut r = rx(Expect::Requests);
        for p in train(dexg(3, 1), 0) {
            assert_eq!(r.push(p), None);
        }
        assert_eq!(r.poll_at(), Some(SimTime::from_micros(84 + 9)));
        assert_eq!(r.poll(SimTime::from_micros(92)), None);
        let got = r.poll(SimTime::from_micros(93)).expect("complete");
        assert_eq!(got.request(), Some(dexg(3, 1)));
        assert_eq!(
            (got.start, got.end),
            (SimTime::ZERO, SimTime::from_micros(84))
        );
        assert!(r.is_synchronised());
    }

    /// One hand-made broken telegram per check, the class it must get.
    #[test]
    fn each_check_has_its_class() {
        let cases = [
            // Response 0000 with the start pulse positive.
            (
                "0+ 1- 2+ 3- 4+ 5- 6+ 7- 8+ 9- 10+ 11- 13+ 14-",
                Check::StartBit,
            ),
            // 0110 with pulse 6+ flipped.
            (
                "0- 1+ 2- 3+ 5- 6- 7- 9+ 10- 11+ 13- 14+",
                Check::Alternation,
            ),
            // 0000 with pulse 10- half a grid step late.
            (
                "0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 10.5- 11+ 13- 14+",
                Check::Pause,
            ),
            // 0000 with the mid pulse of cell 5 moved to the free boundary after it.
            (
                "0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 10- 12+ 13- 14+",
                Check::Information,
            ),
            // 0000 with PB = 1: 0 0000 1 1.
            (
                "0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 11- 12+ 13- 14+",
                Check::Parity,
            ),
            // 0 0000 0 0 then idle: no end bit 1.
            (
                "0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 10- 11+ 12- 13+",
                Check::EndBit,
            ),
            // Six bits: 0 0000 1 (a response without its last bit).
            ("0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 11- 12+", Check::Length),
        ];
        for (spec, check) in cases {
            let mut r = rx(Expect::Responses);
            let got: Vec<Received> = r.decode(pulses(spec, 0)).collect();
            assert_eq!(got.len(), 1, "{spec}");
            assert_eq!(got[0].primary(), Some(check), "{spec}: {:?}", got[0]);
        }
    }

    #[test]
    fn a_missing_return_to_idle_is_an_end_bit_error() {
        // Response 0000 without its final positive pulse: the line stays low.
        let mut r = rx(Expect::Responses);
        let got: Vec<Received> = r
            .decode(pulses("0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 10- 11+ 13-", 0))
            .collect();
        assert_eq!(got[0].failed, Checks::only(Check::EndBit));
    }

    #[test]
    fn jitter_within_tolerance_is_accepted_and_beyond_is_a_pause_error() {
        let mut p: Vec<Pulse> = train(dexg(9, 6), 0).iter().collect();
        for (i, x) in p.iter_mut().enumerate() {
            x.at = if i % 2 == 0 {
                x.at + SimDuration::from_nanos(500)
            } else {
                x.at - SimDuration::from_nanos(0)
            };
        }
        p[0].at = SimTime::ZERO;
        let got: Vec<Received> = rx(Expect::Requests).decode(p.clone()).collect();
        assert_eq!(got[0].request(), Some(dexg(9, 6)));
        p[5].at += SimDuration::from_nanos(501);
        let got: Vec<Received> = rx(Expect::Requests).decode(p).collect();
        assert_eq!(got[0].failed, Checks::only(Check::Pause));
    }

    #[test]
    fn after_an_error_the_next_request_needs_the_asynchronous_pause() {
        let mut r = rx(Expect::Requests);
        let mut bad: Vec<Pulse> = train(dexg(4, 0), 0).iter().collect();
        bad[4].polarity = bad[4].polarity.flipped();
        let good_soon = train(dexg(4, 0), 84 + 10);
        let good_later = train(dexg(4, 0), 84 + 10 + 84 + 18);
        let got: Vec<Received> = r
            .decode(bad.into_iter().chain(good_soon).chain(good_later))
            .collect();
        assert_eq!(got.len(), 3);
        assert!(got[0].failed.contains(Check::Alternation));
        assert_eq!(
            got[1].failed,
            Checks::only(Check::Pause),
            "10 µs after an error is too soon"
        );
        assert_eq!(
            got[2].request(),
            Some(dexg(4, 0)),
            "18 µs after an error is enough"
        );
    }

    #[test]
    fn on_a_live_bus_the_reply_to_a_valid_request_is_a_response() {
        let t = timing();
        let req = train(dexg(4, 0), 0);
        let resp = PulseTrain::response(
            Response::new(Nibble::from_low_bits(5)),
            SimTime::from_micros(102),
            t.half_bit(),
        );
        let next = train(dexg(5, 0), 154);
        let mut r = rx(Expect::Both);
        let got: Vec<Received> = r.decode(req.into_iter().chain(resp).chain(next)).collect();
        let kinds: Vec<_> = got.iter().map(|g| (g.kind, g.is_valid())).collect();
        assert_eq!(
            kinds,
            [
                (TelegramKind::Request, true),
                (TelegramKind::Response, true),
                (TelegramKind::Request, true)
            ]
        );
        assert_eq!(got[1].response().map(|r| r.data().get()), Some(5));
    }

    /// The constant-time path for encoded trains gives exactly what pulse-by-pulse decoding
    /// gives, for every request and response, back to back and overlapping.
    #[test]
    fn push_train_equals_pushing_each_pulse() {
        let h = timing().half_bit();
        let mut trains = Vec::new();
        let mut t = 0u64;
        for body in 0u16..1 << 11 {
            let bits = (body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1;
            let req = Request::from_bits(bits).expect("valid");
            trains.push(PulseTrain::request(req, SimTime::from_micros(t), h));
            let resp = Response::new(Nibble::from_low_bits(body as u8));
            trains.push(PulseTrain::response(resp, SimTime::from_micros(t + 102), h));
            // Every 7th gap is too short, every 11th train overlaps its predecessor.
            t += match body % 77 {
                0 => 150,
                b if b % 11 == 0 => 60,
                b if b % 7 == 0 => 146,
                _ => 154,
            };
        }
        for expect in [Expect::Requests, Expect::Responses, Expect::Both] {
            let mut fast = rx(expect);
            let mut slow = rx(expect);
            let mut a = Vec::new();
            let mut b = Vec::new();
            for tr in &trains {
                a.extend(fast.push_train(tr));
                for p in tr.iter() {
                    b.extend(slow.push(p));
                }
            }
            a.extend(fast.flush());
            b.extend(slow.flush());
            assert_eq!(a, b, "{expect:?}");
        }
    }

    #[test]
    fn a_train_whose_first_pulse_is_not_at_its_start_is_decoded_from_its_first_pulse() {
        // 1 0 0 ... : the line is high in the first half-cell, so the first pulse is at point 1.
        let levels = HalfBits::encode(0b10_0000_0000_0001, 14);
        let train =
            PulseTrain::from_half_bits(levels, SimTime::from_micros(30), timing().half_bit());
        assert!(train.pulse_at(0).is_none());
        let mut fast = rx(Expect::Requests);
        let a: Vec<Received> = fast
            .push_train(&train)
            .into_iter()
            .chain(fast.flush())
            .collect();
        let b: Vec<Received> = rx(Expect::Requests).decode(train).collect();
        assert_eq!(a, b);
        assert!(!b[0].is_valid());
    }

    #[test]
    fn odd_inputs_never_panic() {
        let mut r = rx(Expect::Both);
        let wild = [
            Pulse::new(SimTime::MAX, Polarity::Positive),
            Pulse::new(SimTime::ZERO, Polarity::Positive),
            Pulse::new(SimTime::ZERO, Polarity::Positive),
            Pulse::new(SimTime::from_nanos(1), Polarity::Negative),
            Pulse::new(SimTime::MAX, Polarity::Negative),
        ];
        let got: Vec<Received> = r.decode(wild).collect();
        assert!(got.iter().all(|g| !g.is_valid()));
        // A run far longer than any telegram.
        let long = (0..10_000u64).map(|k| {
            Pulse::new(
                SimTime::from_micros(3 * k),
                if k % 2 == 0 {
                    Polarity::Negative
                } else {
                    Polarity::Positive
                },
            )
        });
        let got: Vec<Received> = rx(Expect::Requests).decode(long).collect();
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].bit_count, 5000);
        assert!(got[0].failed.contains(Check::Length));
    }
}
