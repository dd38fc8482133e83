//! Scheduling: which call comes next in each phase, and the transitions between phases.

use super::*;

impl Master {
    // ----- scheduling -----------------------------------------------------------------

    pub(super) fn next_tx(&mut self, now: SimTime) -> Option<Tx> {
        for _ in 0..4 {
            match self.phase {
                Phase::Offline => {
                    if !self.power_ok || self.host.offline || now < self.wake_at {
                        return None;
                    }
                    self.start_detection();
                }
                Phase::Detection => {
                    if self.host.offline {
                        self.go_offline();
                        return None;
                    }
                    if let Some(tx) = self.detect_next() {
                        return Some(tx);
                    }
                }
                Phase::Activation => {
                    if self.host.offline {
                        self.go_offline();
                        return None;
                    }
                    if let Some(tx) = self.activation_next() {
                        return Some(tx);
                    }
                }
                Phase::NormalOperation => {
                    if self.host.offline {
                        return self.offline_next();
                    }
                    return self.normal_next(now);
                }
            }
        }
        None
    }

    #[inline(never)]
    pub(super) fn start_detection(&mut self) {
        self.phase = Phase::Detection;
        self.det_cursor = 0;
        self.det_probe = None;
        self.lds = SlaveList::EMPTY;
        self.las = SlaveList::EMPTY;
        self.lpf = SlaveList::EMPTY;
        self.touch_inputs();
        self.update_flags();
    }

    pub(super) fn occupies_whole(&self, n: u8) -> bool {
        match SlaveAddr::a(n) {
            Some(a) => self.lds.contains(a) && !self.detected[a.index() as usize].is_ab(),
            None => false,
        }
    }

    #[inline(never)]
    pub(super) fn detect_next(&mut self) -> Option<Tx> {
        for _ in 0..=65 {
            if let Some(p) = self.det_probe {
                return Some(Tx::Detect(p.a, p.step));
            }
            if self.det_cursor >= 64 {
                if self.lds.is_empty() {
                    self.det_cursor = 0;
                    continue;
                }
                self.act_todo = self.lds.iter().filter(|&a| self.eligible(a)).collect();
                self.act_param_done = false;
                self.phase = Phase::Activation;
                self.touch_inputs();
                return None;
            }
            let i = self.det_cursor;
            self.det_cursor += 1;
            let Some(a) = SlaveAddr::from_index(i) else {
                continue;
            };
            if a.select == Select::B && self.occupies_whole(a.number()) {
                continue;
            }
            self.det_probe = Some(Probe {
                a,
                step: Read::Io,
                codes: UNKNOWN_CODES,
            });
        }
        None
    }

    #[inline(never)]
    pub(super) fn activation_next(&mut self) -> Option<Tx> {
        let Some(a) = self.act_todo.iter().next() else {
            self.phase = Phase::NormalOperation;
            self.touch_inputs();
            self.stage = Stage::Data;
            self.cursor = 1;
            self.cycle_open = false;
            self.cycle_start = None;
            return None;
        };
        Some(if self.act_param_done {
            Tx::ActivateDexg(a)
        } else {
            Tx::ActivateParam(a)
        })
    }

    pub(super) fn slot(&self, n: u8) -> Option<SlaveAddr> {
        let a = SlaveAddr::a(n)?;
        let b = SlaveAddr::b(n);
        let has_b = b.is_some_and(|b| self.las.contains(b));
        match (self.las.contains(a), has_b) {
            (true, true) if self.odd_cycle => b,
            (true, _) => Some(a),
            (false, true) => b,
            (false, false) => None,
        }
    }

    pub(super) fn normal_next(&mut self, now: SimTime) -> Option<Tx> {
        for _ in 0..4 {
            match self.stage {
                Stage::Data => {
                    if !self.cycle_open {
                        self.open_cycle(now);
                    }
                    // The next slot at or after the cursor that holds an A or a B slave of
                    // LAS, found in the list bits rather than by asking each address.
                    let las = self.las.bits();
                    let occupied = (las as u32 | (las >> 32) as u32) as u64;
                    let ahead = occupied & (u64::MAX << self.cursor.min(32));
                    if ahead != 0 {
                        let n = ahead.trailing_zeros() as u8;
                        self.cursor = n + 1;
                        if let Some(a) = self.slot(n) {
                            return Some(Tx::Exchange(a));
                        }
                    }
                    self.cursor = 32;
                    self.stage = Stage::Management;
                }
                Stage::Management => {
                    self.stage = Stage::Inclusion;
                    if let Some(tx) = self.management_next() {
                        return Some(tx);
                    }
                }
                Stage::Inclusion => {
                    self.stage = Stage::Data;
                    self.cursor = 1;
                    self.cycle_open = false;
                    self.odd_cycle = !self.odd_cycle;
                    if let Some(tx) = self.inclusion_next() {
                        return Some(tx);
                    }
                }
            }
        }
        None
    }

    /// A cycle starts at `now`: the previous one's time goes to the statistics.
    #[inline(never)]
    pub(super) fn open_cycle(&mut self, now: SimTime) {
        self.cycle_open = true;
        if let Some(s) = self.cycle_start {
            self.stats.record_cycle(now.saturating_duration_since(s));
        }
        self.cycle_start = Some(now);
    }

    #[inline(never)]
    pub(super) fn management_next(&mut self) -> Option<Tx> {
        if let Some((_, step)) = self.job {
            return Some(Tx::Job(step));
        }
        if self.las.is_empty() {
            return None;
        }
        // The first LAS bit at or after the cursor, going round after bit 63 (bit 32, 0B, is
        // no address).
        let bits = self.las.bits() & !(1 << 32);
        if bits == 0 {
            return None;
        }
        let c = u32::from(self.status_cursor);
        let i = (c + bits.rotate_right(c).trailing_zeros()) % 64;
        self.status_cursor = ((i + 1) % 64) as u8;
        SlaveAddr::from_index(i as u8).map(Tx::Status)
    }

    #[inline(never)]
    pub(super) fn inclusion_next(&mut self) -> Option<Tx> {
        if let (Some(p), Some(step)) = (self.incl, self.incl_step) {
            return Some(Tx::Include(p.a, step));
        }
        if let Some(a) = self.incl_priority.take() {
            return Some(self.begin_inclusion(a));
        }
        let i = self.inclusion_scan()?;
        self.incl_cursor = (i + 1) % 64;
        SlaveAddr::from_index(i).map(|a| self.begin_inclusion(a))
    }

    /// The first inclusion candidate's list bit at or after the inclusion cursor (0..=63),
    /// going round after bit 63, or `None` when there is none (the cursor, moved on by one
    /// for each bit asked, would then be back where it was).
    ///
    /// Every bit's candidacy at once, from the lists: an A address 1..=31 not in LAS; a B address not in LAS whose A address no standard slave
    /// holds whole; 0A, not in LAS, while some address 1..=31 is neither held whole nor
    /// active. The tests compare it with asking each address in turn.
    pub(super) fn inclusion_scan(&self) -> Option<u8> {
        debug_assert_eq!(
            self.ab_mask,
            (0..64).fold(0u64, |m, i| m | (self.detected[i].is_ab() as u64) << i),
            "ab_mask out of step with detected"
        );
        let las = self.las.bits();
        // Bit n (1..=31): `occupies_whole(n)`.
        let whole = (self.lds.bits() & !self.ab_mask) as u32 & !1;
        let free_a = !(las as u32) & !1;
        // Bit 0 of the B half, 0B, is no address.
        let free_b = !((las >> 32) as u32) & !whole & !1;
        let zero = las & 1 == 0 && free_a & !whole != 0;
        let candidates = u64::from(free_a) | u64::from(zero) | u64::from(free_b) << 32;
        if candidates == 0 {
            return None;
        }
        let c = u32::from(self.incl_cursor) % 64;
        Some(((c + candidates.rotate_right(c).trailing_zeros()) % 64) as u8)
    }

    pub(super) fn begin_inclusion(&mut self, a: SlaveAddr) -> Tx {
        self.incl = Some(Probe {
            a,
            step: Read::Io,
            codes: UNKNOWN_CODES,
        });
        self.incl_step = Some(InclStep::Read(Read::Io));
        Tx::Include(a, InclStep::Read(Read::Io))
    }

    #[inline(never)]
    pub(super) fn offline_next(&mut self) -> Option<Tx> {
        while self.offline_cursor < 64 {
            let i = self.offline_cursor;
            self.offline_cursor += 1;
            if let Some(a) = SlaveAddr::from_index(i) {
                if self.las.contains(a) {
                    return Some(Tx::OfflineDefault(a));
                }
            }
        }
        self.go_offline();
        None
    }

    #[inline(never)]
    pub(super) fn go_offline(&mut self) {
        self.phase = Phase::Offline;
        self.in_flight = None;
        self.repeat_pending = false;
        self.lds = SlaveList::EMPTY;
        self.las = SlaveList::EMPTY;
        self.lpf = SlaveList::EMPTY;
        self.touch_inputs();
        for w in 0..16 {
            let keep = if w == 0 { 0xF000 } else { 0 };
            let v = self.image.input.word(w) & keep;
            self.image.input.set_word(w, v);
        }
        for e in self.analog.iter_mut() {
            *e = None;
        }
        self.analog_mask = 0;
        self.det_probe = None;
        self.incl = None;
        self.incl_step = None;
        self.incl_priority = None;
        self.stage = Stage::Data;
        self.cursor = 1;
        self.cycle_open = false;
        self.cycle_start = None;
        self.offline_cursor = 0;
        if let Some((req, _)) = self.job.take() {
            self.mailbox.abort(&mut self.image.input, &req);
            // A job the PLC posted meanwhile is taken at the next call.
            self.image.output.mark_written();
        }
        self.update_flags();
    }
}
