//! The wire: pulses in, frames out, with the fast path for clean telegrams.

use super::base::Line;
use crate::{BusTiming, Expect, Frame, LineDecoder, Pulse, SimDuration, SimTime, Transmission};

/// The bare line with its decoder: no faults, nothing recorded.
#[derive(Clone, Debug)]
pub struct Wire {
    decoder: LineDecoder,
    pause: SimDuration,
    /// A clean telegram on a quiet line, and its frame: handed on whole at its end plus the
    /// pause, or to the decoder if something comes on the line before.
    pending: Option<(Transmission, Frame)>,
    exact: bool,
}

impl Wire {
    /// A quiet wire with the receiver grid of `timing`.
    pub fn new(timing: &BusTiming) -> Wire {
        Wire {
            decoder: LineDecoder::new(&timing.receiver(Expect::Both)),
            pause: timing.min_pause(),
            pending: None,
            exact: false,
        }
    }

    /// Pulse-exact (`true`): every train goes through the pulse decoder, the fast path for
    /// clean telegrams is off. The frames are the same either way (tested for every request
    /// and response in `tests/line.rs`, and for whole runs of the rig); the exact mode is
    /// the reference the fast path is measured and checked against.
    pub fn set_pulse_exact(&mut self, on: bool) {
        self.exact = on;
    }

    /// `true` while the fast path is on and the line is idle: no telegram pending, none in
    /// the decoder. A clean telegram transmitted now becomes the pending frame, which
    /// [`Line::poll`] hands on at its end plus the pause, leaving the wire idle again.
    pub fn is_idle_fast(&self) -> bool {
        !self.exact && self.is_idle()
    }

    /// `true` while the line is idle: no telegram pending, none in the decoder.
    #[inline]
    pub fn is_idle(&self) -> bool {
        self.pending.is_none() && self.decoder.poll_at().is_none()
    }

    /// `true` while pulse-exact ([`Wire::set_pulse_exact`]).
    pub fn is_pulse_exact(&self) -> bool {
        self.exact
    }

    /// Hands a pending clean train to the decoder (something else comes on the line).
    /// The train through the decoder, after the clean frame kept for the fast path: kept out
    /// of line, so that the fast path of [`Line::transmit`] inlines into its callers.
    #[inline(never)]
    fn transmit_decoded(&mut self, tg: &Transmission, done: &mut impl FnMut(Frame)) {
        self.flush_pending(done);
        if let Some(f) = self.decoder.push_train(&tg.train()) {
            done(f);
        }
    }

    fn flush_pending(&mut self, done: &mut impl FnMut(Frame)) {
        if let Some((t, _)) = self.pending.take() {
            if let Some(f) = self.decoder.push_train(&t.train()) {
                done(f);
            }
        }
    }
}

impl Line for Wire {
    #[inline]
    fn transmit(&mut self, tg: &Transmission, done: &mut impl FnMut(Frame)) {
        if !self.exact && self.decoder.poll_at().is_none() {
            let quiet = match &self.pending {
                None => true,
                Some((_, p)) => tg.start() >= p.end && tg.start() - p.end >= self.pause,
            };
            if quiet {
                if let Some((_, f)) = self.pending.take() {
                    done(f);
                }
                self.pending = Some((*tg, tg.frame()));
                return;
            }
        }
        self.transmit_decoded(tg, done);
    }

    fn transmit_pulses(&mut self, pulses: &mut Vec<Pulse>, done: &mut impl FnMut(Frame)) {
        self.flush_pending(done);
        for p in pulses.iter() {
            if let Some(f) = self.decoder.push(*p) {
                done(f);
            }
        }
    }

    #[inline]
    fn poll_at(&self) -> Option<SimTime> {
        match &self.pending {
            Some((_, f)) => Some(f.end + self.pause),
            None => self.decoder.poll_at(),
        }
    }

    #[inline]
    fn poll(&mut self, now: SimTime) -> Option<Frame> {
        match &self.pending {
            Some((_, f)) if now >= f.end + self.pause => self.pending.take().map(|(_, f)| f),
            Some(_) => None,
            None => self.decoder.poll(now),
        }
    }

    fn reset(&mut self) {
        self.decoder.reset();
        self.pending = None;
    }
}
