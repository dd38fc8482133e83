//! The master's LAS watched in normal operation: drop-outs and the time each address spends
//! out of it, for the report's `bus.dropouts`.

use asi_phy::{SimDuration, SimTime};

/// Watches the master's LAS in normal operation: drop-outs and time out of LAS per address.
#[derive(Clone, Debug, Default)]
pub(super) struct LasWatch {
    /// The LAS (A slots) last seen in normal operation, `None` outside it.
    las: Option<u32>,
    /// Since when each address is out of LAS.
    out_since: [Option<SimTime>; 32],
    /// Drop-outs per address.
    count: [u32; 32],
    /// Time out of LAS per address, closed intervals.
    out: [SimDuration; 32],
}

impl LasWatch {
    /// The LAS last seen in normal operation, `None` outside it: while the master's is this
    /// one, [`LasWatch::update`] finds nothing and changes nothing.
    pub(super) fn seen(&self) -> Option<u32> {
        self.las
    }

    /// The LAS at `t` (`None` when the master is not in normal operation); returns the
    /// addresses that left and that came back.
    pub(super) fn update(&mut self, t: SimTime, las: Option<u32>) -> (u32, u32) {
        let Some(now) = las else {
            // Offline (power fail, start-up): no drop-outs, close the open absences.
            self.close(t);
            self.las = None;
            return (0, 0);
        };
        // The same LAS in almost every scan: nothing to count.
        if self.las == Some(now) {
            return (0, 0);
        }
        let Some(before) = self.las.replace(now) else {
            return (0, 0);
        };
        let left = before & !now;
        let mut back = now & !before;
        // Only the addresses that changed (none in almost every scan), lowest first.
        let mut changed = left | back;
        while changed != 0 {
            let i = changed.trailing_zeros() as usize;
            changed &= changed - 1;
            if left & (1 << i) != 0 {
                self.count[i] += 1;
                self.out_since[i] = Some(t);
            }
            if back & (1 << i) != 0 {
                match self.out_since[i].take() {
                    Some(s) => self.out[i] += t - s,
                    // Joined for the first time (start-up): not a return.
                    None => back &= !(1 << i),
                }
            }
        }
        (left, back)
    }

    /// Ends the open absences at `t`.
    pub(super) fn close(&mut self, t: SimTime) {
        for i in 0..32 {
            if let Some(s) = self.out_since[i].take() {
                self.out[i] += t - s;
            }
        }
    }

    /// The addresses that dropped out, with their count and time out of LAS (closed
    /// intervals).
    pub(super) fn dropouts(&self) -> impl Iterator<Item = (u8, u32, SimDuration)> + '_ {
        (1..32u8)
            .filter(|&i| self.count[i as usize] > 0)
            .map(|i| (i, self.count[i as usize], self.out[i as usize]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The watch as it was written first: every address looked at in every update. The
    /// watch must do exactly what this does.
    fn update_every_address(w: &mut LasWatch, t: SimTime, las: Option<u32>) -> (u32, u32) {
        let Some(now) = las else {
            w.close(t);
            w.las = None;
            return (0, 0);
        };
        let Some(before) = w.las.replace(now) else {
            return (0, 0);
        };
        let left = before & !now;
        let mut back = now & !before;
        for i in 0..32 {
            if left & (1 << i) != 0 {
                w.count[i] += 1;
                w.out_since[i] = Some(t);
            }
            if back & (1 << i) != 0 {
                match w.out_since[i].take() {
                    Some(s) => w.out[i] += t - s,
                    None => back &= !(1 << i),
                }
            }
        }
        (left, back)
    }

    /// A LAS that mostly stays, sometimes loses or regains a few slaves, sometimes is gone.
    fn las_steps() -> impl Strategy<Value = Vec<(u64, Option<u32>)>> {
        prop::collection::vec(
            (
                1..5_000_000u64,
                prop_oneof![
                    1 => Just(None),
                    8 => any::<u32>().prop_map(Some),
                    8 => Just(Some(0x1DFE)),
                    4 => (0..32u32).prop_map(|b| Some(0x1DFE & !(1 << b))),
                ],
            ),
            0..200,
        )
    }

    proptest! {
        #[test]
        fn only_the_changed_addresses_give_what_every_address_gives(steps in las_steps()) {
            let (mut fast, mut full) = (LasWatch::default(), LasWatch::default());
            let mut t = SimTime::ZERO;
            for (dt, las) in steps {
                t += SimDuration::from_nanos(dt);
                prop_assert_eq!(fast.update(t, las), update_every_address(&mut full, t, las));
                prop_assert_eq!(format!("{fast:?}"), format!("{full:?}"));
            }
            fast.close(t);
            full.close(t);
            prop_assert_eq!(
                fast.dropouts().collect::<Vec<_>>(),
                full.dropouts().collect::<Vec<_>>()
            );
        }
    }

    #[test]
    fn a_slave_that_leaves_and_comes_back_is_counted_with_its_time_out() {
        let mut w = LasWatch::default();
        let ms = SimTime::from_millis;
        assert_eq!(w.update(ms(0), Some(0b110)), (0, 0));
        assert_eq!(w.update(ms(1), Some(0b010)), (0b100, 0));
        assert_eq!(
            w.update(ms(5), Some(0b1110)),
            (0, 0b100),
            "8 joined: not a return"
        );
        assert_eq!(
            w.dropouts().collect::<Vec<_>>(),
            [(2, 1, SimDuration::from_millis(4))]
        );
    }
}
