//! What the application watches of the slaves' outputs: the addresses whose new output
//! nibbles end [`Bus::advance_before`] early ([`Watch::outputs`]), and the new nibbles
//! that change nothing a slave drives, which may pass ([`Bus::drive_count`],
//! [`Watch::drives_only_through`]).

use super::*;

/// No output nibble taken yet (or lost with a reset).
pub(super) const NO_OUTPUT: u8 = 0xFF;

/// What a request taken by a slave does to what the watched slaves drive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum OutputNote {
    /// Nothing new.
    Same,
    /// A Data_Exchange hands the watched slave at this address a new output nibble.
    New(usize, u8),
    /// A call that writes to the watched slave at this address: its next nibble is new.
    Forget(usize),
    /// The broadcast reset: every next nibble is new.
    ForgetAll,
}

impl Bus {
    /// A count that moves whenever what a counting slave device drives
    /// ([`Peripheral::drive_changes`]) may have
    /// changed: at each call into the slaves in which one's count moved, and at each of the
    /// application's accesses that may change anything ([`Bus::slave_mut`], the fault hooks
    /// that reset slaves). `None` when no device counts.
    #[inline]
    pub fn drive_count(&self) -> Option<u64> {
        self.drive_counted.then_some(self.drive_total)
    }

    /// What the application is about to do may change what a slave drives.
    pub(super) fn drives_may_move(&mut self) {
        self.drive_total += 1;
    }

    /// Whether a new output nibble taken at the bus's time passes without ending
    /// [`Bus::advance_before`] ([`Watch::drives_only_through`]): within the time given, and
    /// the drive count has not moved since the bus last looked (which it now has).
    #[inline(never)]
    fn output_passes_quietly(&mut self) -> bool {
        let Some(c) = self.drive_count() else {
            return false;
        };
        let moved = c != self.drive_seen;
        self.drive_seen = c;
        !moved
            && self
                .watch
                .drives_only_through
                .is_some_and(|u| self.now <= u)
    }

    /// What request `req`, taken by a slave, does to what the watched slaves drive: a
    /// Data_Exchange with a new output nibble, or any call that writes (parameter, address,
    /// reset), after which the next Data_Exchange counts as new too. A Data_Exchange is told
    /// from its bits, without decoding the call (`told`, [`Told::of`] `req`).
    pub(super) fn output_note(&self, req: Request, told: Told) -> OutputNote {
        let exchange_note = |a: usize, data: u8| {
            if self.watch.outputs >> a & 1 == 1 && self.last_out[a] != data {
                OutputNote::New(a, data)
            } else {
                OutputNote::Same
            }
        };
        let call = match told {
            Told::Exchange(address, data) => {
                return exchange_note(address.get() as usize, data.get())
            }
            Told::Call(call) => call,
        };
        let a = req.address().get() as usize;
        match call {
            Call::DataExchange { data, .. } => exchange_note(a, data.get()),
            Call::ReadIoConfiguration { .. }
            | Call::ReadIdCode { .. }
            | Call::ReadId1 { .. }
            | Call::ReadId2 { .. }
            | Call::ReadStatus { .. } => OutputNote::Same,
            Call::BroadcastReset => OutputNote::ForgetAll,
            _ if self.watch.outputs >> a & 1 == 1 => OutputNote::Forget(a),
            _ => OutputNote::Same,
        }
    }

    /// Notes what request `req`, taken by a slave, does to what the watched slaves drive
    /// ([`Bus::output_note`] of `told`, [`Told::of`] `req`): a change ends
    /// [`Bus::advance_before`] at this event.
    #[inline(always)]
    pub(super) fn note_output(&mut self, req: Request, told: Told) {
        match self.output_note(req, told) {
            OutputNote::Same => {}
            OutputNote::New(a, data) => {
                self.last_out[a] = data;
                self.output_taken |= !self.output_passes_quietly();
            }
            OutputNote::Forget(a) => {
                self.last_out[a] = NO_OUTPUT;
                self.output_taken |= !self.output_passes_quietly();
            }
            OutputNote::ForgetAll => {
                self.last_out = [NO_OUTPUT; 32];
                self.output_taken |= self.watch.outputs != 0;
            }
        }
    }
}
