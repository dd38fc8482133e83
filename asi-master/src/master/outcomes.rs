//! Outcomes: what each response (or its absence) changes in the lists, the image and the
//! phase.

use super::*;

impl Master {
    // ----- outcomes -------------------------------------------------------------------

    pub(super) fn apply(&mut self, tx: Tx, resp: Option<Nibble>) {
        match tx {
            Tx::Detect(a, r) => self.detect_result(a, r, resp),
            Tx::ActivateParam(a) => match resp {
                Some(p) => {
                    self.pi[a.index() as usize] = p;
                    self.act_param_done = true;
                }
                None => self.act_todo.set(a, false),
            },
            Tx::ActivateDexg(a) => {
                self.act_todo.set(a, false);
                self.act_param_done = false;
                if let Some(d) = resp {
                    self.activate(a, d);
                }
            }
            Tx::Exchange(a) => self.exchange_result(a, resp),
            Tx::Status(a) => {
                // Nearly every status repeats the last one: LPF, and so the flags, change
                // only when the peripheral-fault bit does.
                if let Some(s) = resp {
                    if self.lpf.contains(a) != s.bit(1) {
                        self.lpf.set(a, s.bit(1));
                        self.touch_inputs();
                    }
                }
            }
            Tx::Include(a, step) => self.include_result(a, step, resp),
            Tx::Job(step) => self.job_result(step, resp),
            Tx::OfflineDefault(_) => {}
        }
    }

    #[inline(never)]
    pub(super) fn detect_result(&mut self, a: SlaveAddr, r: Read, resp: Option<Nibble>) {
        let Some(mut p) = self.det_probe.filter(|p| p.a == a) else {
            return;
        };
        let Some(v) = resp else {
            self.det_probe = None;
            return;
        };
        match r {
            Read::Io => {
                p.codes.io = v;
                p.step = Read::Id;
            }
            Read::Id => {
                p.codes.id = v;
                p.step = Read::Id1;
            }
            Read::Id1 => {
                p.codes.id1 = v;
                p.step = Read::Id2;
            }
            Read::Id2 => {
                p.codes.id2 = v;
                self.lds.set(a, true);
                self.touch_inputs();
                self.set_detected(a.index() as usize, p.codes);
                self.det_probe = None;
                return;
            }
        }
        self.det_probe = Some(p);
    }

    #[inline(never)]
    pub(super) fn activate(&mut self, a: SlaveAddr, inputs: Nibble) {
        let i = a.index() as usize;
        self.las.set(a, true);
        self.touch_inputs();
        self.fails[i] = 0;
        self.image.input.set_nibble(a, inputs);
        let codes = self.detected[i];
        let engine = codes.is_analog_7_3().then(|| {
            if codes.analog_is_input() {
                AnalogEngine::Input(S73InputMaster::new())
            } else {
                AnalogEngine::Output(S73OutputMaster::new(codes.analog_channels()))
            }
        });
        self.set_analog(i, engine);
        self.analog_out[i] = Nibble::ZERO;
        if self.has_analog(i) {
            self.step_analog(a, inputs);
        }
    }

    pub(super) fn deactivate(&mut self, a: SlaveAddr) {
        let i = a.index() as usize;
        self.las.set(a, false);
        self.lpf.set(a, false);
        self.touch_inputs();
        self.image.input.set_nibble(a, Nibble::ZERO);
        self.set_analog(i, None);
        self.fails[i] = 0;
    }

    pub(super) fn step_analog(&mut self, a: SlaveAddr, input: Nibble) {
        let i = a.index() as usize;
        let n = a.number();
        match &mut self.analog[i] {
            Some(AnalogEngine::Output(e)) => {
                e.set_values(self.image.output.analog_channels(n));
                self.analog_out[i] = e.step(input);
            }
            Some(AnalogEngine::Input(e)) => {
                let (out, done) = e.step(input);
                self.analog_out[i] = out;
                if let Some((ch, v)) = done {
                    if v.valid {
                        let word = if v.overflow { OVERFLOW_VALUE } else { v.value };
                        self.image.input.set_analog(n, ch, word);
                    }
                }
            }
            None => {}
        }
    }

    pub(super) fn exchange_result(&mut self, a: SlaveAddr, resp: Option<Nibble>) {
        if !self.las.contains(a) {
            return;
        }
        let i = a.index() as usize;
        match resp {
            Some(d) => self.exchange_answered(a, d),
            None => {
                self.fails[i] = self.fails[i].saturating_add(1);
                if self.fails[i] >= self.cfg.max_failed_cycles {
                    self.deactivate(a);
                    self.lds.set(a, false);
                    self.touch_inputs();
                    self.lcs.set(a, true);
                    self.stats.dropouts += 1;
                }
            }
        }
    }

    /// Slave `a` answered its Data_Exchange with inputs `d`: its count of failures restarts
    /// and `d` goes to the input image (through the analog engine's handshake if it has one).
    /// Nothing for a slave no longer in LAS.
    #[inline]
    pub(super) fn exchange_answered(&mut self, a: SlaveAddr, d: Nibble) {
        if !self.las.contains(a) {
            return;
        }
        // A list bit is 0..=63; the mask only lets the compiler see it.
        let i = (a.index() & 63) as usize;
        self.fails[i] = 0;
        self.image.input.set_nibble(a, d);
        if self.has_analog(i) {
            self.step_analog(a, d);
        }
    }

    pub(super) fn auto_address_target(
        &self,
        codes: SlaveCodes,
    ) -> Option<(SlaveAddr, Option<Nibble>)> {
        if !self.compute_flags().auto_address_available() {
            return None;
        }
        let missing = SlaveList::from_bits(self.projected.lps().bits() & !self.lds.bits());
        let target = missing.iter().next()?;
        let want = self.projected.codes(target);
        if !codes.matches(&want) {
            return None;
        }
        let id1 = if want.is_ab() {
            let sel = if target.select == Select::B { 8 } else { 0 };
            Nibble::from_low_bits((codes.id1.get() & 7) | sel)
        } else {
            want.id1
        };
        Some((target, (id1 != codes.id1).then_some(id1)))
    }

    #[inline(never)]
    pub(super) fn include_result(&mut self, a: SlaveAddr, step: InclStep, resp: Option<Nibble>) {
        let Some(mut p) = self.incl.filter(|p| p.a == a) else {
            return;
        };
        let end = |m: &mut Master| {
            m.incl = None;
            m.incl_step = None;
        };
        let Some(v) = resp else {
            if matches!(step, InclStep::Read(_)) && self.lds.contains(a) && !self.las.contains(a) {
                self.lds.set(a, false);
                self.touch_inputs();
                self.lcs.set(a, true);
            }
            return end(self);
        };
        let next = match step {
            InclStep::Read(Read::Io) => {
                p.codes.io = v;
                InclStep::Read(Read::Id)
            }
            InclStep::Read(Read::Id) => {
                p.codes.id = v;
                InclStep::Read(Read::Id1)
            }
            InclStep::Read(Read::Id1) => {
                p.codes.id1 = v;
                InclStep::Read(Read::Id2)
            }
            InclStep::Read(Read::Id2) => {
                p.codes.id2 = v;
                self.lds.set(a, true);
                self.touch_inputs();
                self.set_detected(a.index() as usize, p.codes);
                if a.number() == 0 {
                    match self.auto_address_target(p.codes) {
                        Some((t, Some(id1))) => InclStep::AutoId1(t, id1),
                        Some((t, None)) => InclStep::AutoAssign(t),
                        None => return end(self),
                    }
                } else if self.eligible(a) {
                    InclStep::Param
                } else {
                    return end(self);
                }
            }
            InclStep::Param => {
                self.pi[a.index() as usize] = v;
                InclStep::Dexg
            }
            InclStep::Dexg => {
                self.activate(a, v);
                return end(self);
            }
            InclStep::AutoId1(t, _) => InclStep::AutoAssign(t),
            InclStep::AutoAssign(t) => {
                if v == ACK_0110 {
                    self.lds.set(ZERO_A, false);
                    self.touch_inputs();
                    self.incl_priority = Some(t);
                }
                return end(self);
            }
        };
        self.incl = Some(p);
        self.incl_step = Some(next);
    }
}
