//! The normal cycle's common calls on short paths: the data stage's Data_Exchange
//! ([`Master::next_exchange`], its telegram looked up in [`DEXG`]), the cycle's Read_Status
//! and inclusion probe ([`Master::next_cycle_call`]) and their usual outcomes
//! ([`Master::judge_cycle_call`]). Each is what the general path does in that case; the
//! tests compare them with it transaction by transaction.

use super::*;

impl Master {
    /// The Data_Exchange the data stage of a normal cycle sends next, or `None` when the next
    /// call is anything else (the stage ends, another phase, host Offline): then
    /// [`Master::next_transmit`] decides, from the same state (at most the cycle is opened,
    /// as the general path would do first).
    ///
    /// This is [`Master::normal_next`]'s data stage, [`Master::slot`] and
    /// [`Master::request_for`] of `Tx::Exchange` in one, without the general dispatch; the
    /// telegram comes from [`DEXG`] instead of being assembled. The tests compare it with
    /// the general path transaction by transaction.
    #[inline]
    pub(super) fn next_exchange(&mut self, now: SimTime) -> Option<Transmit> {
        if self.phase != Phase::NormalOperation || self.host.offline || self.stage != Stage::Data {
            return None;
        }
        if !self.cycle_open {
            self.open_cycle(now);
        }
        let las = self.las.bits();
        let occupied = (las as u32 | (las >> 32) as u32) as u64;
        // `occupied` has 32 bits: a shift by 32..=63 clears them all as one by 32 does (the
        // general path's `min(32)`); the cursor is never above 33.
        let ahead = occupied & (u64::MAX << (self.cursor & 63));
        let n = ahead.trailing_zeros() as u8;
        // Nothing ahead (n = 64) ends the stage; address 0 has no Data_Exchange (the
        // general path fails the call). Both are left to the general path.
        if !(1..=31).contains(&n) {
            return None;
        }
        // `slot(n)`: the A slave, or the B slave if it is alone or it is an odd cycle.
        let has_a = las >> n & 1 != 0;
        let has_b = las >> (n + 32) & 1 != 0;
        let index = if has_b && (!has_a || self.odd_cycle) {
            n + 32
        } else {
            n
        };
        let a = SlaveAddr::from_index(index)?;
        self.cursor = n + 1;
        let i = index as usize;
        let out = if !self.host.data_exchange_active {
            Nibble::ALL
        } else if self.has_analog(i) {
            self.analog_out[i]
        } else {
            self.image.output.nibble_of_bit(i)
        };
        let ab = self.detected[i].is_ab();
        let request = if ab {
            DEXG.ab[i][(out.get() & 7) as usize]
        } else {
            // An address is 1..=31 here and a nibble holds 4 bits; the masks only let the
            // compiler see it.
            DEXG.standard[(n & 31) as usize][(out.get() & 0xF) as usize]
        };
        self.in_flight = Some(InFlight {
            tx: Tx::Exchange(a),
            request,
            repeated: false,
        });
        Some(Transmit {
            request,
            kind: TxKind::DataExchange,
            repeat: false,
            ab,
            slave: index,
        })
    }

    /// The call after [`Master::next_exchange`] found none: the cycle's other two calls,
    /// Read_Status of the next LAS slave when the data stage has ended and the inclusion
    /// probe of the next free address, or anything else through [`Master::next_transmit`].
    ///
    /// The two calls are [`Master::normal_next`]'s management and inclusion stages,
    /// [`Master::request_for`] and the start of the call in one, without the general
    /// dispatch. Each is taken only where it is sure to be the general path's call (worked
    /// out before anything is changed); the rest (a host job, no LAS slave, a running
    /// inclusion, nothing to include) is left to the general path, from the same state. The
    /// tests compare them with the general path transaction by transaction.
    #[inline(never)]
    pub(super) fn next_cycle_call(&mut self, now: SimTime) -> Option<Transmit> {
        if self.phase == Phase::NormalOperation && !self.host.offline && self.job.is_none() {
            let t = match self.stage {
                Stage::Data => self.next_status(),
                Stage::Inclusion => self.next_probe(),
                Stage::Management => None,
            };
            if t.is_some() {
                return t;
            }
        }
        self.next_transmit(now)
    }

    /// The management call at the end of the data stage: Read_Status of the first LAS slave
    /// at or after the status cursor (as [`Master::management_next`]), when no LAS slot is
    /// left ahead of the cursor and no host job waits; `None`, with nothing changed,
    /// otherwise.
    #[inline]
    fn next_status(&mut self) -> Option<Transmit> {
        let las = self.las.bits();
        let occupied = (las as u32 | (las >> 32) as u32) as u64;
        if las == 0 || occupied & (u64::MAX << self.cursor.min(32)) != 0 {
            return None;
        }
        // Bit 32 (0B) is never in a list.
        let c = u32::from(self.status_cursor);
        let i = ((c + las.rotate_right(c).trailing_zeros()) % 64) as u8;
        let a = SlaveAddr::from_index(i)?;
        let request = requests::READS.status[i as usize]?;
        self.cursor = 32;
        self.stage = Stage::Inclusion;
        self.status_cursor = (i + 1) % 64;
        self.in_flight = Some(InFlight {
            tx: Tx::Status(a),
            request,
            repeated: false,
        });
        Some(Transmit {
            request,
            kind: TxKind::Management,
            repeat: false,
            ab: false,
            slave: i,
        })
    }

    /// The inclusion stage at the start of a call: the cycle closes and the next inclusion
    /// candidate gets its first probe, Read_IO_Configuration (as [`Master::normal_next`] and
    /// [`Master::inclusion_next`]), when no inclusion is running or asked for by a job and
    /// there is a candidate; `None`, with nothing changed, otherwise.
    #[inline]
    fn next_probe(&mut self) -> Option<Transmit> {
        if (self.incl.is_some() && self.incl_step.is_some()) || self.incl_priority.is_some() {
            return None;
        }
        let i = self.inclusion_scan()?;
        let a = SlaveAddr::from_index(i)?;
        let request = requests::READS.io[i as usize]?;
        self.stage = Stage::Data;
        self.cursor = 1;
        self.cycle_open = false;
        self.odd_cycle = !self.odd_cycle;
        self.incl_cursor = (i + 1) % 64;
        let tx = self.begin_inclusion(a);
        self.in_flight = Some(InFlight {
            tx,
            request,
            repeated: false,
        });
        Some(Transmit {
            request,
            kind: TxKind::Inclusion,
            repeat: false,
            ab: false,
            slave: i,
        })
    }

    /// [`Master::handle_outcome`] for every outcome but an answered Data_Exchange: the
    /// cycle's other two calls as they nearly always end (Read_Status answered, the
    /// inclusion probe of a free address unanswered) take a short path; every other outcome
    /// goes through [`Master::judge_outcome`].
    ///
    /// Each short path is what `judge_outcome` and [`Master::apply`] do with that outcome:
    /// neither is a failure, so neither is repeated. The tests compare them with the general
    /// path.
    #[inline(never)]
    pub(super) fn judge_cycle_call(&mut self, now: SimTime, outcome: Outcome) -> Verdict {
        let quiet = Verdict {
            repeat: false,
            error: false,
        };
        match (self.in_flight, outcome) {
            (
                Some(InFlight {
                    tx: Tx::Status(a), ..
                }),
                Outcome::Response(r),
            ) => {
                self.in_flight = None;
                self.inputs_before();
                // As `apply`: LPF, and so the flags, change only when the peripheral-fault
                // bit does.
                let fault = r.data().bit(1);
                if self.lpf.contains(a) != fault {
                    self.lpf.set(a, fault);
                    self.touch_inputs();
                }
                self.inputs_after(now);
                quiet
            }
            (
                Some(InFlight {
                    tx: Tx::Include(a, InclStep::Read(Read::Io)),
                    ..
                }),
                Outcome::NoResponse,
            ) => {
                self.in_flight = None;
                self.inputs_before();
                // `include_result` of a probe without an answer: the inclusion in progress
                // at `a` ends, and a detected slave that is not active leaves LDS.
                if self.incl.is_some_and(|p| p.a == a) {
                    if self.lds.contains(a) && !self.las.contains(a) {
                        self.lds.set(a, false);
                        self.touch_inputs();
                        self.lcs.set(a, true);
                    }
                    self.incl = None;
                    self.incl_step = None;
                }
                self.inputs_after(now);
                quiet
            }
            _ => self.judge_outcome(now, outcome),
        }
    }
}

/// Every Data_Exchange request, built at compile time, so the cycle's most frequent call is
/// a look-up instead of assembling the telegram and its parity bit.
pub(super) struct DexgTable {
    /// `[n][d]`: standard slave `n` (any select), outputs `d`, as `Request::data_exchange`.
    pub(super) standard: [[Request; 16]; 32],
    /// `[i][d]`: the A/B slave of list bit `i`, outputs D2..D0 = `d`, as
    /// `Request::data_exchange_ab`.
    pub(super) ab: [[Request; 8]; 64],
}

/// The Data_Exchange requests (address 0 and bit 32, 0B, have none: they hold a placeholder
/// that is never read).
pub(super) static DEXG: DexgTable = DexgTable::build();

impl DexgTable {
    const fn build() -> DexgTable {
        const fn ok(r: Result<Request, asi_phy::TelegramError>) -> Request {
            match r {
                Ok(r) => r,
                Err(_) => panic!("a Data_Exchange request in range"),
            }
        }
        let none = ok(Request::from_fields(false, asi_phy::Address::ZERO, 0));
        let mut t = DexgTable {
            standard: [[none; 16]; 32],
            ab: [[none; 8]; 64],
        };
        let mut n = 1;
        while n < 32 {
            let Some(address) = asi_phy::Address::new(n) else {
                panic!("address in range")
            };
            let mut d = 0;
            while d < 16 {
                let out = Nibble::from_low_bits(d);
                t.standard[n as usize][d as usize] = ok(Request::data_exchange(address, out));
                if d < 8 {
                    t.ab[n as usize][d as usize] =
                        ok(Request::data_exchange_ab(address, Select::A, out));
                    t.ab[32 + n as usize][d as usize] =
                        ok(Request::data_exchange_ab(address, Select::B, out));
                }
                d += 1;
            }
            n += 1;
        }
        t
    }
}
