//! The bus line: one medium that every receiver hears (SPEC §1; reference/asi.md §1.2), in
//! smoltcp's manner: a [`Wire`] that carries pulses and decodes frames, and wrappers around any
//! [`Line`] that add something on the way: [`Faulty`] corrupts the pulses (a seeded
//! [`FaultInjector`](crate::FaultInjector) and one-shot exact [`PulseFault`](crate::PulseFault)s
//! of asi-phy `fault`), [`Tap`] records every pulse as it is on the line. The bus uses
//! [`Medium`]: the tap inside the fault wrapper, so that it records the pulses after faults.
//!
//! Two slaves answering at once superimpose their pulses ([`superimpose`]): at each grid point
//! pulses of the same sign add up to one pulse of that sign and pulses of opposite signs cancel
//! (the transmit currents add), so identical answers arrive intact and different answers are
//! corrupted. One [`LineDecoder`](crate::LineDecoder) assembles the line's pulses into frames
//! once for all receivers; each receiver's own [`Listener`](crate::Listener) then judges the
//! frame.
//!
//! **Fast path.** A telegram a correct transmitter encoded, alone on a quiet line without
//! faults, decodes to its own bits with no line check failed; asi-phy's
//! `LineDecoder::push_train` recognises such a train by re-encoding it. The wire knows the
//! telegram it just encoded, so it keeps the train as the pending frame directly (the frame
//! asi-phy would produce: same start, end, pulse count, bits). Any fault, overlap or second
//! transmitter sends the pending train and the new pulses through the decoder instead. The
//! equivalence is tested for every request and response (`tests/line.rs`).

mod faulty;
mod tap;
mod wire;

pub use faulty::Faulty;
pub use tap::Tap;
pub use wire::Wire;

use crate::{BusTiming, Frame, Polarity, Pulse, PulseTrain, SimTime};

/// The line as the bus sees it: the wire with its tap, inside the fault wrapper.
pub type Medium = Faulty<Tap<Wire>>;

impl Medium {
    /// A quiet line with the receiver grid of `timing`, no faults, nothing recorded.
    pub fn quiet(timing: &BusTiming) -> Medium {
        Faulty::new(Tap::new(Wire::new(timing)))
    }
}

/// A line that carries pulse trains to one decoder: the [`Wire`], or a wrapper around a line.
pub trait Line {
    /// Puts the encoded telegram `train` on the line; `raw` holds its `bits` bits (first bit
    /// highest) as the transmitter sent them. `done` gets every frame the line completes on the
    /// way.
    fn transmit(&mut self, train: &PulseTrain, raw: u32, bits: u32, done: &mut impl FnMut(Frame));

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
