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
    /// The LAS at `t` (`None` when the master is not in normal operation); returns the
    /// addresses that left and that came back.
    pub(super) fn update(&mut self, t: SimTime, las: Option<u32>) -> (u32, u32) {
        let Some(now) = las else {
            // Offline (power fail, start-up): no drop-outs, close the open absences.
            self.close(t);
            self.las = None;
            return (0, 0);
        };
        let Some(before) = self.las.replace(now) else {
            return (0, 0);
        };
        let left = before & !now;
        let mut back = now & !before;
        for i in 0..32 {
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
