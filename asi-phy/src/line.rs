//! The bus line: one medium that every receiver hears, with its fault injector and tap (SPEC §1; reference/asi.md §1.2).
//!
//! Transmitters put pulse trains on the line, optionally through a seeded fault injector or a
//! one-shot exact fault list (asi-phy `fault`). Two slaves answering at once superimpose their
//! pulses: at each grid point pulses of the same sign add up to one pulse of that sign and
//! pulses of opposite signs cancel (the transmit currents add), so identical answers arrive
//! intact and different answers are corrupted. One [`LineDecoder`] assembles the line's pulses
//! into frames once for all receivers; each receiver's own [`Listener`](crate::Listener) then
//! judges the frame.
//!
//! **Fast path.** A telegram a correct transmitter encoded, alone on a quiet line without
//! faults, decodes to its own bits with no line check failed; asi-phy's
//! `LineDecoder::push_train` recognises such a train by re-encoding it. The medium knows the
//! telegram it just encoded, so it keeps the train as the pending frame directly (the frame
//! asi-phy would produce: same start, end, pulse count, bits). Any fault, overlap or second
//! transmitter sends the pending train and the new pulses through the decoder instead. The
//! equivalence is tested for every request and response (`tests/medium.rs`).

use crate::fault::apply_faults;
use crate::{
    BusTiming, Expect, FaultInjector, FaultRates, Frame, LineDecoder, Polarity, Pulse, PulseFault,
    PulseTrain,
};

/// The line with its decoder and fault sources.
#[derive(Debug)]
pub struct Medium {
    decoder: LineDecoder,
    injector: Option<FaultInjector>,
    one_shot: Vec<PulseFault>,
    pulses: Vec<Pulse>,
    scratch: Vec<Pulse>,
    faults_injected: u64,
    pause: crate::SimDuration,
    pending: Option<(PulseTrain, Frame)>,
    /// Every pulse put on the line (after faults), when someone records the line.
    tap: Option<Vec<Pulse>>,
}

impl Medium {
    /// A quiet line with the receiver grid of `timing`.
    pub fn new(timing: &BusTiming) -> Medium {
        Medium {
            decoder: LineDecoder::new(&timing.receiver(Expect::Both)),
            injector: None,
            one_shot: Vec::new(),
            pulses: Vec::with_capacity(64),
            scratch: Vec::with_capacity(64),
            faults_injected: 0,
            pause: timing.min_pause(),
            pending: None,
            tap: None,
        }
    }

    /// Seeded random line faults from now on (`FaultRates::NONE` or `None` switches them off).
    pub fn set_faults(&mut self, injector: Option<FaultInjector>) {
        self.injector = injector.filter(|i| !i.rates().is_clean());
    }

    /// The rates in force.
    pub fn fault_rates(&self) -> FaultRates {
        self.injector
            .as_ref()
            .map_or(FaultRates::NONE, |i| i.rates())
    }

    /// Exact faults for the next telegram put on the line (indices into its pulses).
    pub fn corrupt_next(&mut self, faults: Vec<PulseFault>) {
        self.one_shot = faults;
    }

    /// Pulse faults injected so far (random and exact).
    pub fn faults_injected(&self) -> u64 {
        self.faults_injected + self.injector.as_ref().map_or(0, |i| i.injected())
    }

    /// Starts (`true`) or stops recording every pulse that goes on the line, as it is there:
    /// after faults, with colliding answers superimposed.
    pub fn record_pulses(&mut self, on: bool) {
        self.tap = on.then(|| self.tap.take().unwrap_or_default());
    }

    /// Takes the pulses recorded since the last call (in the order they went on the line).
    pub fn take_pulses(&mut self) -> Vec<Pulse> {
        self.tap.as_mut().map(core::mem::take).unwrap_or_default()
    }

    /// Puts the encoded telegram `train` on the line; `raw` holds its `bits` bits (first bit
    /// highest) as the transmitter sent them. `done` gets every frame the line completes on the
    /// way.
    pub fn transmit(
        &mut self,
        train: &PulseTrain,
        raw: u32,
        bits: u32,
        done: &mut impl FnMut(Frame),
    ) {
        let clean = self.injector.is_none() && self.one_shot.is_empty();
        if let (Some(tap), true) = (self.tap.as_mut(), clean) {
            tap.extend(train.iter());
        }
        if clean && self.decoder.poll_at().is_none() {
            let quiet = match &self.pending {
                None => true,
                Some((p, _)) => train.start() >= p.end() && train.start() - p.end() >= self.pause,
            };
            if quiet {
                if let Some((_, f)) = self.pending.take() {
                    done(f);
                }
                self.pending = Some((
                    *train,
                    Frame {
                        start: train.start(),
                        end: train.end(),
                        pulses: train.len(),
                        bit_count: bits,
                        raw,
                        line_failed: crate::Checks::NONE,
                    },
                ));
                return;
            }
        }
        self.flush_pending(done);
        if clean {
            if let Some(f) = self.decoder.push_train(train) {
                done(f);
            }
            return;
        }
        let mut pulses = core::mem::take(&mut self.pulses);
        pulses.clear();
        pulses.extend(train.iter());
        self.push_pulses(&mut pulses, done);
        self.pulses = pulses;
    }

    /// Hands a pending clean train to the decoder (something else comes on the line).
    fn flush_pending(&mut self, done: &mut impl FnMut(Frame)) {
        if let Some((t, _)) = self.pending.take() {
            if let Some(f) = self.decoder.push_train(&t) {
                done(f);
            }
        }
    }

    /// Puts several simultaneous trains on the line, superimposed.
    pub fn transmit_merged(&mut self, trains: &[PulseTrain], done: &mut impl FnMut(Frame)) {
        self.flush_pending(done);
        let mut all: Vec<Pulse> = trains.iter().flat_map(|t| t.iter()).collect();
        all.sort_by_key(|p| p.at);
        let mut merged = core::mem::take(&mut self.pulses);
        merged.clear();
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
        self.push_pulses(&mut merged, done);
        self.pulses = merged;
    }

    fn push_pulses(&mut self, pulses: &mut Vec<Pulse>, done: &mut impl FnMut(Frame)) {
        if !self.one_shot.is_empty() {
            let faults = core::mem::take(&mut self.one_shot);
            apply_faults(pulses, &faults, &mut self.scratch);
            self.faults_injected += faults.len() as u64;
            core::mem::swap(pulses, &mut self.scratch);
        }
        if let Some(inj) = &mut self.injector {
            inj.corrupt(pulses.iter().copied(), &mut self.scratch);
            core::mem::swap(pulses, &mut self.scratch);
        }
        if let Some(tap) = self.tap.as_mut() {
            tap.extend_from_slice(pulses);
        }
        for p in pulses.iter() {
            if let Some(f) = self.decoder.push(*p) {
                done(f);
            }
        }
    }

    /// When the frame on the line completes if nothing more comes.
    pub fn poll_at(&self) -> Option<crate::SimTime> {
        match &self.pending {
            Some((_, f)) => Some(f.end + self.pause),
            None => self.decoder.poll_at(),
        }
    }

    /// The frame on the line, if it has completed by `now`.
    pub fn poll(&mut self, now: crate::SimTime) -> Option<Frame> {
        match &self.pending {
            Some((_, f)) if now >= f.end + self.pause => self.pending.take().map(|(_, f)| f),
            Some(_) => None,
            None => self.decoder.poll(now),
        }
    }

    /// Drops whatever is on the line (power fail).
    pub fn reset(&mut self) {
        self.decoder.reset();
        self.pending = None;
    }
}
