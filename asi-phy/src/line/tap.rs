//! The tap: records every pulse that goes on the line, as it is there.

use super::base::Line;
use crate::{Frame, Pulse, SimTime, Transmission};

/// A line whose pulses are recorded while recording is on (a wrapper, like smoltcp's packet
/// capture): inside [`Faulty`](super::Faulty) it records the pulses after faults, with
/// colliding answers superimposed.
#[derive(Clone, Debug)]
pub struct Tap<L> {
    inner: L,
    recorded: Option<Vec<Pulse>>,
}

impl<L> Tap<L> {
    /// `inner` with the tap off.
    pub fn new(inner: L) -> Tap<L> {
        Tap {
            inner,
            recorded: None,
        }
    }

    /// Starts (`true`) or stops recording every pulse that goes on the line.
    pub fn record_pulses(&mut self, on: bool) {
        self.recorded = on.then(|| self.recorded.take().unwrap_or_default());
    }

    /// `true` while the tap records.
    pub fn is_recording(&self) -> bool {
        self.recorded.is_some()
    }

    /// The line inside.
    pub fn inner(&self) -> &L {
        &self.inner
    }

    /// The line inside.
    pub fn inner_mut(&mut self) -> &mut L {
        &mut self.inner
    }

    /// Takes the pulses recorded since the last call (in the order they went on the line).
    pub fn take_pulses(&mut self) -> Vec<Pulse> {
        self.recorded
            .as_mut()
            .map(core::mem::take)
            .unwrap_or_default()
    }
}

impl<L: Line> Line for Tap<L> {
    // A pass-through on every telegram: inlined, it costs nothing while nothing records.
    #[inline]
    fn transmit(&mut self, tg: &Transmission, done: &mut impl FnMut(Frame)) {
        if let Some(rec) = self.recorded.as_mut() {
            rec.extend(tg.train().iter());
        }
        self.inner.transmit(tg, done);
    }

    fn transmit_pulses(&mut self, pulses: &mut Vec<Pulse>, done: &mut impl FnMut(Frame)) {
        if let Some(rec) = self.recorded.as_mut() {
            rec.extend_from_slice(pulses);
        }
        self.inner.transmit_pulses(pulses, done);
    }

    fn poll_at(&self) -> Option<SimTime> {
        self.inner.poll_at()
    }

    fn poll(&mut self, now: SimTime) -> Option<Frame> {
        self.inner.poll(now)
    }

    fn reset(&mut self) {
        self.inner.reset();
    }
}
