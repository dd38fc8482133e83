//! The analytic model: the AS-i cycle of a bus from its slots, the master's slot rule and
//! asi-phy's [`BusTiming`], never from a simulated count; with line noise plus the error
//! model's expected repeats; and the lab's handshake periods and latency bounds that follow.
//!
//! **The cycle** (asi-master's slot rule, `master.rs`): one Data_Exchange per LAS slot, one
//! management call (a mailbox job, else Read_Status of a LAS slave: answered), and one inclusion
//! call to an address that is still free (a probe answered by silence), skipped when every address
//! is used. An answered transaction is request + master pause + response + slave pause (84 + 18 +
//! 42 + 10 = 154 µs), an unanswered one request + response timeout + slave pause (84 + 60 +
//! 10 = 154 µs). So the clean cycle is (slots + 2) · 154 µs, the thesis' T = (n + 2) · 154 µs (§2.1
//! of the lift thesis) for n standard slaves while an address is free, (slots + 1) · 154 µs with
//! all 31 used. An address holding an A and a B slave is one slot serving A and B in alternate
//! cycles, so each of them is updated every second cycle.
//!
//! **With line noise** every answered transaction of the cycle adds the error model's expected
//! extra time ([`super::error_model::LineNoise::first_try`]): the cycle's expectation is the
//! clean cycle plus (slots + 1) times the mean extra time of an answered transaction.

use super::options::BusChoice;
use asi_phy::BusTiming;

/// The cycle of one bus configuration under the master's slot rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct CycleModel {
    /// Slaves n (of the thesis' formula).
    pub(super) slaves: u32,
    /// LAS slots: occupied addresses (an A/B pair shares one).
    pub(super) slots: u32,
    /// Whether an address is left to include, so every cycle has an inclusion call.
    pub(super) inclusion_call: bool,
    /// An answered transaction, µs.
    pub(super) transaction_us: f64,
    /// A transaction that gets no answer (the inclusion probe of a free address), µs.
    pub(super) unanswered_us: f64,
    /// Cycles between two updates of one slave: 2 for the halves of an A/B pair.
    pub(super) update_cycles: u32,
}

impl CycleModel {
    /// The model of `bus` with `timing`.
    pub(super) fn new(bus: BusChoice, timing: &BusTiming) -> CycleModel {
        let answered = timing.request_span()
            + timing.master_pause()
            + timing.response_span()
            + timing.slave_pause();
        let unanswered = timing.request_span() + timing.response_timeout() + timing.slave_pause();
        let (slots, inclusion_call, update_cycles) = match bus {
            // 31 addresses, each with an A and a B slave: nothing left to include.
            BusChoice::AbPairs => (31, false, 2),
            BusChoice::Standard { n } => (n as u32, n < 31, 1),
            BusChoice::Lab { extra } => {
                let slots = bus.slots();
                debug_assert_eq!(slots, 11 + extra as u32);
                (slots, slots < 31, 1)
            }
        };
        CycleModel {
            slaves: bus.slaves(),
            slots,
            inclusion_call,
            transaction_us: answered.as_micros_f64(),
            unanswered_us: unanswered.as_micros_f64(),
            update_cycles,
        }
    }

    /// Transactions per cycle that expect an answer: one per slot and the management call.
    pub(super) fn answered(&self) -> u32 {
        self.slots + 1
    }

    /// First tries per cycle: the answered ones and the inclusion call.
    pub(super) fn first_tries(&self) -> u32 {
        self.answered() + self.inclusion_call as u32
    }

    /// The thesis' cycle T = (n + 2) · 154 µs (§2.1 of the lift thesis), µs.
    pub(super) fn thesis_cycle_us(&self) -> f64 {
        (self.slaves + 2) as f64 * self.transaction_us
    }

    /// The cycle without line errors, µs.
    pub(super) fn clean_cycle_us(&self) -> f64 {
        let inclusion = if self.inclusion_call {
            self.unanswered_us
        } else {
            0.0
        };
        self.answered() as f64 * self.transaction_us + inclusion
    }

    /// The expected cycle when every answered transaction adds `extra_us` on average, µs.
    pub(super) fn cycle_us(&self, extra_us: f64) -> f64 {
        self.clean_cycle_us() + self.answered() as f64 * extra_us
    }

    /// Expected repeats per cycle when an answered transaction fails with mean probability `q`.
    pub(super) fn repeats_per_cycle(&self, q: f64) -> f64 {
        self.answered() as f64 * q
    }

    /// Expected repeats as a fraction of all transactions, with `q` as above.
    pub(super) fn repeat_fraction(&self, q: f64) -> f64 {
        let r = self.repeats_per_cycle(q);
        r / (self.first_tries() as f64 + r)
    }

    /// The mean period between two successful Data_Exchanges with one slave for a mean cycle of
    /// `cycle_us`, when a Data_Exchange fails both tries with probability `both_fail`, µs.
    pub(super) fn update_us(&self, cycle_us: f64, both_fail: f64) -> f64 {
        self.update_cycles as f64 * cycle_us / (1.0 - both_fail)
    }
}

/// The mean PLC handshake step, ms, for a mean cycle `t_ms`: the PLC's answer leaves in the next
/// Data_Exchange with the slave (within one cycle), the slave's next code comes back in the one
/// after and reaches the image at its end; the PLC sees it in the next scan. While
/// 2T + 154 µs ≤ scan every step takes one scan; beyond, a fraction (2T + 154 µs − scan)/T of
/// them two.
pub(super) fn handshake_step_ms(t_ms: f64, tx_ms: f64, scan_ms: f64) -> f64 {
    let late = ((2.0 * t_ms + tx_ms - scan_ms) / t_ms).clamp(0.0, 1.0);
    scan_ms * (1.0 + late)
}

/// The longest PLC handshake step without line errors, ms: whole scans covering 2T + 154 µs.
pub(super) fn handshake_step_max_ms(cycle_ms: f64, tx_ms: f64, scan_ms: f64) -> f64 {
    scan_ms * ((2.0 * cycle_ms + tx_ms) / scan_ms).ceil()
}

/// The bound of hall press → call registered without line errors, ms: pressed just after the
/// floor slave finished a word, the call waits for the next word (4 steps) and is reported as
/// one extra step: its first code reaches the image one cycle later and the PLC's next scan
/// answers it, then one step per scan.
pub(super) fn registration_bound_ms(cycle_ms: f64, tx_ms: f64, scan_ms: f64) -> f64 {
    cycle_ms + tx_ms + scan_ms + 4.0 * handshake_step_max_ms(cycle_ms, tx_ms, scan_ms)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The formula from asi-phy's timing alone: 154 µs per transaction, the thesis' (n + 2) for
    /// a bus with a free address, one less with all 31 used, two cycles per A/B update.
    #[test]
    fn the_cycle_follows_the_slot_rule() {
        let t = BusTiming::default();
        assert_eq!(
            CycleModel::new(BusChoice::Standard { n: 1 }, &t).transaction_us,
            t.transaction().as_micros_f64()
        );
        for (bus, clean, thesis, update) in [
            (BusChoice::Standard { n: 1 }, 3.0, 3.0, 3.0),
            (BusChoice::Standard { n: 30 }, 32.0, 32.0, 32.0),
            (BusChoice::Standard { n: 31 }, 32.0, 33.0, 32.0),
            (BusChoice::Lab { extra: 0 }, 13.0, 13.0, 13.0),
            (BusChoice::Lab { extra: 20 }, 32.0, 33.0, 32.0),
            (BusChoice::AbPairs, 32.0, 64.0, 64.0),
        ] {
            let m = CycleModel::new(bus, &t);
            assert_eq!(m.clean_cycle_us(), clean * 154.0, "{bus:?}");
            assert_eq!(m.thesis_cycle_us(), thesis * 154.0, "{bus:?}");
            assert_eq!(
                m.update_us(m.clean_cycle_us(), 0.0),
                update * 154.0,
                "{bus:?}"
            );
            assert_eq!(m.repeat_fraction(0.0), 0.0);
        }
        // A slower response timeout lengthens only the inclusion call.
        let slow = BusTiming::builder()
            .response_timeout(asi_phy::SimDuration::from_micros(70))
            .build()
            .expect("timing");
        let m = CycleModel::new(BusChoice::Standard { n: 5 }, &slow);
        assert_eq!(m.clean_cycle_us(), 6.0 * 154.0 + 164.0);
    }
}
