//! The bus line: one medium that every receiver hears (docs/physical-layer.md; docs/asi.md §1.2), in
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

mod base;
mod faulty;
mod tap;
mod transmission;
mod wire;

pub use base::{superimpose, Line};
pub use faulty::Faulty;
pub use tap::Tap;
pub use transmission::Transmission;
pub use wire::Wire;

use crate::{BusTiming, Frame};

/// The line as the bus sees it: the wire with its tap, inside the fault wrapper.
pub type Medium = Faulty<Tap<Wire>>;

impl Medium {
    /// A quiet line with the receiver grid of `timing`, no faults, nothing recorded.
    pub fn quiet(timing: &BusTiming) -> Medium {
        Faulty::new(Tap::new(Wire::new(timing)))
    }

    /// Pulse-exact (`true`) or with the fast paths for clean telegrams (the default): the
    /// wire's ([`Wire::set_pulse_exact`]) and, on a noisy line, the fault wrapper's for the
    /// trains the injector left untouched ([`Faulty::set_faults_pulse_exact`]).
    pub fn set_pulse_exact(&mut self, on: bool) {
        self.set_faults_pulse_exact(on);
        self.inner_mut().inner_mut().set_pulse_exact(on);
    }

    /// `true` if telegram `tg`, put on the line now, would be handed on as its own frame
    /// ([`Transmission::frame`]) at its end plus the pause, with nothing else on the line:
    /// nothing recorded, not pulse-exact, no telegram pending or in the decoder, no one-shot
    /// fault armed, and the fault injector (if any) leaves it untouched. The injector's draws
    /// for it are taken then, as [`Line::transmit`] would take them ([`FaultInjector::
    /// pass_untouched`](crate::FaultInjector::pass_untouched)); with `false` nothing is drawn.
    /// A telegram that passes so leaves the line as it found it, so a caller that knows its
    /// telegram is alone on the line may take the frame directly instead, and put the
    /// telegram on the line later with [`Medium::transmit_taken`] if it must.
    #[inline]
    pub fn takes_clean(&mut self, tg: &Transmission) -> bool {
        !self.inner().is_recording()
            && self.inner().inner().is_idle_fast()
            && self.pass_untouched(tg)
    }

    /// `true` if the line is plain: no fault armed (no injector, no one-shot fault), nothing
    /// recorded, not pulse-exact. Every telegram then passes the faults untouched without a
    /// draw ([`Faulty::pass_untouched`] is `true`), and [`Medium::takes_clean`] is
    /// [`Medium::is_idle`] (tested below). Only arming faults, recording and the pulse-exact
    /// mode make a plain line not plain; a one-shot fault used up may make it plain again.
    pub fn is_plain(&self) -> bool {
        self.is_clean() && !self.inner().is_recording() && !self.inner().inner().is_pulse_exact()
    }

    /// `true` if no telegram is pending on the line and none is in its decoder
    /// ([`Wire::is_idle`]).
    #[inline]
    pub fn is_idle(&self) -> bool {
        self.inner().inner().is_idle()
    }

    /// Puts telegram `tg`, which [`Medium::takes_clean`] passed, on the line past the faults
    /// whose draws that took: where [`Line::transmit`] would have put it then.
    pub fn transmit_taken(&mut self, tg: &Transmission, done: &mut impl FnMut(Frame)) {
        self.inner_mut().transmit(tg, done);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{FaultInjector, FaultRates, PulseFault, SimDuration, SimTime};
    use proptest::prelude::*;

    proptest! {
        /// On a plain line every telegram passes the faults untouched and the line takes it
        /// clean exactly when it is idle; a line that is not plain is one with a fault armed,
        /// recording or pulse-exact. Random telegrams, after random ones on the line, with
        /// each of the things that make a line not plain switched on and off.
        #[test]
        fn a_plain_line_takes_a_telegram_clean_when_it_is_idle(
            steps in proptest::collection::vec(
                (any::<u16>(), 0u64..400_000, 0u8..8, any::<bool>()),
                1..40,
            ),
        ) {
            let timing = BusTiming::default();
            let mut m = Medium::quiet(&timing);
            let mut t = SimTime::ZERO;
            for (raw, gap, change, send) in steps {
                match change {
                    0 => m.set_faults(Some(FaultInjector::new(
                        u64::from(raw),
                        FaultRates::uniform(crate::PulseErrorRate::new(1e-3).expect("a rate")),
                        timing.half_bit(),
                    ))),
                    1 => m.set_faults(None),
                    2 => m.corrupt_next(vec![PulseFault::Drop {
                        index: usize::from(raw % 4),
                    }]),
                    3 => m.record_pulses(raw % 2 == 0),
                    4 => m.set_pulse_exact(raw % 2 == 0),
                    _ => {}
                }
                prop_assert_eq!(
                    m.is_plain(),
                    m.fault_rates().is_clean()
                        && !m.has_one_shot()
                        && !m.inner().is_recording()
                        && !m.inner().inner().is_pulse_exact()
                );
                t += SimDuration::from_nanos(gap);
                while let Some(at) = m.poll_at().filter(|&at| at <= t) {
                    m.poll(at);
                }
                let tg = Transmission::new(u32::from(raw), 14, t, timing.half_bit());
                if m.is_plain() {
                    let idle = m.is_idle();
                    prop_assert!(m.pass_untouched(&tg));
                    prop_assert_eq!(m.takes_clean(&tg), idle);
                }
                if send {
                    m.transmit(&tg, &mut |_| {});
                }
            }
        }
    }
}
