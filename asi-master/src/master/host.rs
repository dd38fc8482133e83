//! The host interface: the host flags and the command mailbox's jobs, checked, started and
//! finished.

use super::*;

impl Master {
    // ----- host interface -------------------------------------------------------------

    /// Reads the host flags and takes a posted mailbox job, before every call but a repeat.
    /// Both checks are inlined into the caller; what follows a change is not.
    ///
    /// Both read only the output image, the host flags in force, the running job and the
    /// mailbox's T, so they are skipped unless the output image was written since the last
    /// look: the PLC writes it once a scan, the bus asks at every call. A job that ends
    /// counts the output image as written, so that a job posted meanwhile is taken. Debug
    /// builds (and so the tests) check at every skip that the checks would have found nothing.
    #[inline]
    pub(super) fn service_host(&mut self, now: SimTime) {
        if !self.image.output.take_written() {
            debug_assert!(
                self.image.output.word(0) & HOST_FLAG_BITS == self.host_bits
                    && (self.job.is_some() || !self.mailbox.posted(&self.image.output)),
                "an output write or the end of a job missed the image's note"
            );
            return;
        }
        // The host flags change only when their three bits of output word 0 do.
        let bits = self.image.output.word(0) & HOST_FLAG_BITS;
        if bits != self.host_bits {
            self.host_flags_changed(now, bits);
        }
        if self.job.is_none() {
            if let Some(req) = self.mailbox.take(&self.image.output) {
                self.take_job(req);
            }
        }
    }

    /// The host flags' bits of output word 0 are now `bits`.
    #[inline(never)]
    fn host_flags_changed(&mut self, now: SimTime, bits: u16) {
        self.host_bits = bits;
        let host = HostFlags::from_output_word0(bits);
        if self.host.offline && !host.offline && self.phase == Phase::Offline {
            self.wake_at = self.wake_at.max(now);
        }
        self.host = host;
        self.touch_inputs();
    }

    /// Starts the job the PLC posted.
    #[inline(never)]
    fn take_job(&mut self, req: MailboxRequest) {
        self.start_job(req);
        self.update_flags();
    }

    fn finish_job(&mut self, req: &MailboxRequest, result: JobResult, response: &[u8]) {
        self.mailbox
            .finish(&mut self.image.input, req, result, response);
        self.job = None;
        // A job the PLC posted while this one ran is taken at the next call.
        self.image.output.mark_written();
    }

    /// Starts the host job `req`: each command checks its arguments, then answers at once or
    /// leaves the job for the cycle to send.
    fn start_job(&mut self, req: MailboxRequest) {
        let Some(cmd) = Command::from_code(req.command) else {
            return self.finish_job(&req, JobResult::UnknownCommand, &[]);
        };
        match cmd {
            Command::WriteParameter | Command::ReadStatus => self.job_parameter_or_status(req, cmd),
            Command::ChangeAddress => self.job_change_address(req),
            Command::ReadProjected => self.job_read_projected(req),
            Command::ReadActual => self.job_read_actual(req),
            Command::WriteProjected => self.job_write_projected(req),
            Command::StoreActual => self.job_store_actual(req),
            Command::SetMode => self.job_set_mode(req),
            Command::ReadList => self.job_read_list(req),
            Command::ReadFlags => self.job_read_flags(req),
        }
    }

    /// Write_Parameter or Read_Status to a detected slave: checked here, sent by the cycle.
    fn job_parameter_or_status(&mut self, req: MailboxRequest, cmd: Command) {
        use JobResult as R;
        let b = req.bytes;
        let addr = address_from_byte(b[0]);
        let bus_phase = self.phase == Phase::NormalOperation;
        let Some(a) = addr.filter(|a| a.number() != 0) else {
            return self.finish_job(&req, R::InvalidArgument, &[]);
        };
        if !bus_phase {
            return self.finish_job(&req, R::NotAllowed, &[]);
        }
        if !self.lds.contains(a) {
            return self.finish_job(&req, R::SlaveNotFound, &[]);
        }
        let step = if cmd == Command::WriteParameter {
            let max = if self.detected[a.index() as usize].is_ab() {
                7
            } else {
                15
            };
            if b[1] > max {
                return self.finish_job(&req, R::InvalidArgument, &[]);
            }
            JobStep::Param(a, Nibble::from_low_bits(b[1]))
        } else {
            JobStep::Status(a)
        };
        self.job = Some((req, step));
    }

    /// Change address: checked here; the cycle deletes the old address, then assigns the new one.
    fn job_change_address(&mut self, req: MailboxRequest) {
        use JobResult as R;
        let b = req.bytes;
        let addr = address_from_byte(b[0]);
        let bus_phase = self.phase == Phase::NormalOperation;
        let (Some(from), Some(to)) = (addr, address_from_byte(b[1])) else {
            return self.finish_job(&req, R::InvalidArgument, &[]);
        };
        if from.number() == 0 || from == to || (to.number() != 0 && to.select != from.select) {
            return self.finish_job(&req, R::InvalidArgument, &[]);
        }
        if !bus_phase {
            return self.finish_job(&req, R::NotAllowed, &[]);
        }
        if !self.lds.contains(from) {
            return self.finish_job(&req, R::SlaveNotFound, &[]);
        }
        if self.lds.contains(ZERO_A) {
            return self.finish_job(&req, R::NotAllowed, &[]);
        }
        if to.number() != 0 && (self.lds.contains(to) || self.occupies_whole(to.number())) {
            return self.finish_job(&req, R::AddressOccupied, &[]);
        }
        self.job = Some((req, JobStep::Delete(from, to)));
    }

    /// Reads the projected codes and parameter of one address.
    fn job_read_projected(&mut self, req: MailboxRequest) {
        use JobResult as R;
        let addr = address_from_byte(req.bytes[0]);
        let Some(a) = addr else {
            return self.finish_job(&req, R::InvalidArgument, &[]);
        };
        let c = codes_bytes(self.projected.codes(a));
        let r = [
            self.projected.lps().contains(a) as u8,
            c[0],
            c[1],
            self.projected.parameter(a).get(),
        ];
        self.finish_job(&req, R::Ok, &r);
    }

    /// Reads the detected codes and parameter image of one address.
    fn job_read_actual(&mut self, req: MailboxRequest) {
        use JobResult as R;
        let addr = address_from_byte(req.bytes[0]);
        let Some(a) = addr else {
            return self.finish_job(&req, R::InvalidArgument, &[]);
        };
        let c = codes_bytes(self.detected[a.index() as usize]);
        let r = [
            self.lds.contains(a) as u8,
            c[0],
            c[1],
            self.pi[a.index() as usize].get(),
        ];
        self.finish_job(&req, R::Ok, &r);
    }

    /// Writes (or removes) one projected slave, in configuration mode.
    fn job_write_projected(&mut self, req: MailboxRequest) {
        use JobResult as R;
        let b = req.bytes;
        let addr = address_from_byte(b[0]);
        if self.mode != Mode::Configuration {
            return self.finish_job(&req, R::NotAllowed, &[]);
        }
        let Some(a) = addr.filter(|a| a.number() != 0) else {
            return self.finish_job(&req, R::InvalidArgument, &[]);
        };
        let mut p = self.projected.clone();
        p.remove(a);
        if b[1] != 0 {
            let s = crate::config::ProjectedSlave {
                addr: a,
                codes: SlaveCodes::new(b[2] >> 4, b[2], b[3] >> 4, b[3]),
                parameter: Nibble::from_low_bits(b[4]),
            };
            if p.insert(s).is_err() {
                return self.finish_job(&req, R::InvalidArgument, &[]);
            }
        }
        self.projected = p;
        self.touch_inputs();
        self.finish_job(&req, R::Ok, &[]);
    }

    /// Projects the detected slaves as they are, in configuration mode.
    fn job_store_actual(&mut self, req: MailboxRequest) {
        use JobResult as R;
        if self.mode != Mode::Configuration {
            return self.finish_job(&req, R::NotAllowed, &[]);
        }
        let mut p = ProjectedConfig::default();
        for a in self.lds.without_zero().iter() {
            let s = crate::config::ProjectedSlave {
                addr: a,
                codes: self.detected[a.index() as usize],
                parameter: self.pi[a.index() as usize],
            };
            if p.insert(s).is_err() {
                return self.finish_job(&req, R::InvalidArgument, &[]);
            }
        }
        self.projected = p;
        self.touch_inputs();
        self.finish_job(&req, R::Ok, &[]);
    }

    /// Sets protected or configuration mode; protected mode deactivates what it does not allow.
    fn job_set_mode(&mut self, req: MailboxRequest) {
        use JobResult as R;
        let b = req.bytes;
        let mode = match b[0] {
            0 => Mode::Protected,
            1 => Mode::Configuration,
            _ => return self.finish_job(&req, R::InvalidArgument, &[]),
        };
        self.mode = mode;
        self.touch_inputs();
        if mode == Mode::Protected {
            // Slaves that are active but not projected (or wrong) leave LAS.
            for a in self.las.iter() {
                if !self.eligible(a) {
                    self.deactivate(a);
                }
            }
        }
        self.finish_job(&req, R::Ok, &[]);
    }

    /// Reads LDS, LAS, LPS, LCS (and clears it) or LPF.
    fn job_read_list(&mut self, req: MailboxRequest) {
        use JobResult as R;
        let b = req.bytes;
        let list = match b[0] {
            0 => self.lds,
            1 => self.las,
            2 => self.projected.lps(),
            3 => self.take_lcs(),
            4 => self.lpf,
            _ => return self.finish_job(&req, R::InvalidArgument, &[]),
        };
        self.finish_job(&req, R::Ok, &list.to_bytes());
    }

    /// Reads the EC flags.
    fn job_read_flags(&mut self, req: MailboxRequest) {
        use JobResult as R;
        let f = self.compute_flags().bits();
        self.finish_job(&req, R::Ok, &f.to_be_bytes());
    }

    #[inline(never)]
    pub(super) fn job_result(&mut self, step: JobStep, resp: Option<Nibble>) {
        let Some((req, _)) = self.job else {
            return;
        };
        let Some(v) = resp else {
            return self.finish_job(&req, JobResult::NoResponse, &[]);
        };
        match step {
            JobStep::Param(a, _) => {
                self.pi[a.index() as usize] = v;
                self.finish_job(&req, JobResult::Ok, &[v.get()]);
            }
            JobStep::Status(a) => {
                if self.las.contains(a) {
                    self.lpf.set(a, v.bit(1));
                    self.touch_inputs();
                }
                self.finish_job(&req, JobResult::Ok, &[v.get()]);
            }
            JobStep::Delete(from, to) => {
                self.deactivate(from);
                self.lds.set(from, false);
                self.touch_inputs();
                if to.number() == 0 {
                    self.finish_job(&req, JobResult::Ok, &[]);
                } else {
                    self.job = Some((req, JobStep::Assign(to)));
                }
            }
            JobStep::Assign(to) => {
                if v == ACK_0110 {
                    self.incl_priority = Some(to);
                    self.finish_job(&req, JobResult::Ok, &[]);
                } else {
                    self.finish_job(&req, JobResult::NoResponse, &[]);
                }
            }
        }
    }
}

/// The codes as the mailbox reads them: IO and ID in one byte, ID1 and ID2 in the next.
fn codes_bytes(c: SlaveCodes) -> [u8; 2] {
    [
        (c.io.get() << 4) | c.id.get(),
        (c.id1.get() << 4) | c.id2.get(),
    ]
}
