//! The fault wrapper: seeded random pulse faults and one-shot exact ones.

use super::base::Line;
use super::tap::Tap;
use crate::fault::apply_faults;
use crate::{FaultInjector, FaultRates, Frame, Pulse, PulseFault, SimTime, Transmission};

/// A line whose pulses pass a seeded [`FaultInjector`] and a one-shot list of exact
/// [`PulseFault`]s on their way (a wrapper, like smoltcp's fault injector). Without faults a
/// clean telegram goes on to the inner line as it is (and may take the wire's fast path).
#[derive(Clone, Debug)]
pub struct Faulty<L> {
    inner: L,
    injector: Option<FaultInjector>,
    one_shot: Vec<PulseFault>,
    pulses: Vec<Pulse>,
    scratch: Vec<Pulse>,
    faults_injected: u64,
    exact: bool,
}

impl<L> Faulty<L> {
    /// `inner` without faults.
    pub fn new(inner: L) -> Faulty<L> {
        Faulty {
            inner,
            injector: None,
            one_shot: Vec::new(),
            pulses: Vec::with_capacity(64),
            scratch: Vec::with_capacity(64),
            faults_injected: 0,
            exact: false,
        }
    }

    /// Pulse-exact (`true`): with random faults armed, every train goes on as pulses, also
    /// those the injector left untouched (the default, `false`, hands those on as clean
    /// trains; see [`Wire::set_pulse_exact`](super::Wire::set_pulse_exact)).
    pub fn set_faults_pulse_exact(&mut self, on: bool) {
        self.exact = on;
    }

    /// The line inside.
    pub fn inner_mut(&mut self) -> &mut L {
        &mut self.inner
    }

    /// Seeded random line faults from now on (`FaultRates::NONE` or `None` switches them off).
    /// The faults the injector it replaces has injected stay counted.
    pub fn set_faults(&mut self, injector: Option<FaultInjector>) {
        if let Some(old) = self.injector.take() {
            self.faults_injected += old.injected();
        }
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

    /// The line inside.
    pub fn inner(&self) -> &L {
        &self.inner
    }

    /// `true` if telegram `tg` put on the line now would go on to the inner line as it is,
    /// taking the injector's draws for it then (as [`Line::transmit`] would); `false`, with
    /// nothing drawn, if a one-shot fault is armed, the line is pulse-exact or the injector
    /// would touch it.
    #[inline]
    pub fn pass_untouched(&mut self, tg: &Transmission) -> bool {
        if !self.one_shot.is_empty() {
            return false;
        }
        match &mut self.injector {
            None => true,
            Some(inj) => !self.exact && inj.pass_untouched(tg.pulses()),
        }
    }

    /// `true` while a one-shot fault is armed for the next telegram.
    pub fn has_one_shot(&self) -> bool {
        !self.one_shot.is_empty()
    }

    /// `true` while no fault is armed: telegrams pass unchanged.
    pub fn is_clean(&self) -> bool {
        self.injector.is_none() && self.one_shot.is_empty()
    }

    /// Applies the armed faults to `pulses`: the one-shot list first, then the injector.
    fn corrupt(&mut self, pulses: &mut Vec<Pulse>) {
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
    }
}

impl<L: Line> Faulty<L> {
    /// [`Line::transmit`] with faults armed.
    #[inline(never)]
    fn transmit_faulty(&mut self, tg: &Transmission, done: &mut impl FnMut(Frame)) {
        // Random faults only: the injector draws for every pulse as ever, and a train it left
        // untouched (no fault, no jitter) is a clean train that may take the wire's fast path;
        // the rest go on as pulses. Same draws, same frames (tests/line.rs). Most trains are
        // untouched, and the injector can tell so from its draws and the number of pulses
        // alone; only if it cannot does the train go through `corrupt` pulse by pulse.
        if self.one_shot.is_empty() && !self.exact {
            if let Some(inj) = &mut self.injector {
                if inj.pass_untouched(tg.pulses()) {
                    self.inner.transmit(tg, done);
                    return;
                }
                let mut pulses = core::mem::take(&mut self.pulses);
                let faults = inj.corrupt(tg.train().iter(), &mut pulses);
                if faults == 0 && inj.rates().jitter.is_zero() {
                    self.inner.transmit(tg, done);
                } else {
                    self.inner.transmit_pulses(&mut pulses, done);
                }
                self.pulses = pulses;
                return;
            }
        }
        let mut pulses = core::mem::take(&mut self.pulses);
        pulses.clear();
        pulses.extend(tg.train().iter());
        self.transmit_pulses(&mut pulses, done);
        self.pulses = pulses;
    }
}

impl<L> Faulty<Tap<L>> {
    /// Starts (`true`) or stops recording every pulse that goes on the line, as it is there:
    /// after faults, with colliding answers superimposed.
    pub fn record_pulses(&mut self, on: bool) {
        self.inner.record_pulses(on);
    }

    /// Takes the pulses recorded since the last call (in the order they went on the line).
    pub fn take_pulses(&mut self) -> Vec<Pulse> {
        self.inner.take_pulses()
    }
}

impl<L: Line> Line for Faulty<L> {
    // The clean line's pass-through inlines into the caller; the faulty path stays apart.
    #[inline]
    fn transmit(&mut self, tg: &Transmission, done: &mut impl FnMut(Frame)) {
        if self.is_clean() {
            self.inner.transmit(tg, done);
        } else {
            self.transmit_faulty(tg, done);
        }
    }

    fn transmit_pulses(&mut self, pulses: &mut Vec<Pulse>, done: &mut impl FnMut(Frame)) {
        self.corrupt(pulses);
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
