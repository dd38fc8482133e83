//! What every line and line wrapper is: the [`Line`] trait, and how simultaneous trains
//! superimpose on the line.

use crate::{Frame, Polarity, Pulse, PulseTrain, SimTime, Transmission};

/// A line that carries pulse trains to one decoder: the [`Wire`](super::Wire), or a wrapper around a line.
pub trait Line {
    /// Puts the telegram `tg` on the line, as its transmitter sent it. `done` gets every frame
    /// the line completes on the way.
    fn transmit(&mut self, tg: &Transmission, done: &mut impl FnMut(Frame));

    /// Puts `pulses` (in time order) on the line: pulses that are not one clean telegram
    /// (superimposed answers, or pulses a wrapper changed). A wrapper may change them in place.
    fn transmit_pulses(&mut self, pulses: &mut Vec<Pulse>, done: &mut impl FnMut(Frame));

    /// Puts several simultaneous trains on the line, superimposed.
    fn transmit_merged(&mut self, trains: &[PulseTrain], done: &mut impl FnMut(Frame)) {
        let mut merged = superimpose(trains);
        self.transmit_pulses(&mut merged, done);
    }

    /// When the frame on the line completes if nothing more comes.
    fn poll_at(&self) -> Option<SimTime>;

    /// The frame on the line, if it has completed by `now`.
    fn poll(&mut self, now: SimTime) -> Option<Frame>;

    /// Drops whatever is on the line (power fail).
    fn reset(&mut self);
}

/// Simultaneous trains as they are on the line: at each grid point the sum of their pulses'
/// signs, one pulse of the sum's sign or none where they cancel.
pub fn superimpose(trains: &[PulseTrain]) -> Vec<Pulse> {
    let mut all: Vec<Pulse> = trains.iter().flat_map(|t| t.iter()).collect();
    all.sort_by_key(|p| p.at);
    let mut merged = Vec::with_capacity(all.len());
    let mut i = 0;
    while i < all.len() {
        let at = all[i].at;
        let mut sum = 0i32;
        while i < all.len() && all[i].at == at {
            sum += match all[i].polarity {
                Polarity::Positive => 1,
                Polarity::Negative => -1,
            };
            i += 1;
        }
        if sum != 0 {
            let polarity = if sum > 0 {
                Polarity::Positive
            } else {
                Polarity::Negative
            };
            merged.push(Pulse::new(at, polarity));
        }
    }
    merged
}
