//! The rig's scans: the safety logic's (with the bus watch and the safe drive's) every 1 ms, and
//! the PLC's, each with what it hands to the report and the log.

use super::*;

impl Rig {
    /// The master's LAS and the safety monitor's drops since the last look, to the report
    /// and the log (every safety scan, 1 ms). In almost every scan the master is in normal
    /// operation with the LAS the watch saw last, and the monitor has dropped nothing: that
    /// is told by two looks, and the watch is left as it is (as [`LasWatch::update`] leaves
    /// it then).
    #[inline]
    pub(super) fn watch_bus(&mut self, t: SimTime) {
        let m = self.lab.bus.master();
        let las = (m.phase() == asi_master::Phase::NormalOperation).then(|| m.las().bits() as u32);
        if las.is_none() || las != self.las_watch.seen() {
            self.las_moved(t, las);
        }
        if self.lab.monitor().is_some_and(|m| m.has_drops()) {
            let drops = self.lab.bus.take_monitor_drops(self.lab.monitor);
            self.log_drops(drops);
        }
    }

    /// The LAS at `t` (`None` outside normal operation) to the watch, and who left and came
    /// back to the log.
    #[inline(never)]
    fn las_moved(&mut self, t: SimTime, las: Option<u32>) {
        let (left, back) = self.las_watch.update(t, las);
        if left | back != 0 {
            self.log_las(t, left, back);
        }
    }

    /// The addresses that `left` LAS and came `back` at `t`, to the log.
    #[inline(never)]
    fn log_las(&mut self, t: SimTime, left: u32, back: u32) {
        for i in 1..32u8 {
            if left & (1 << i) != 0 {
                self.log_at(t, "bus", format!("slave {i} dropped out of LAS"));
            }
            if back & (1 << i) != 0 {
                self.log_at(t, "bus", format!("slave {i} back in LAS"));
            }
        }
    }

    /// The safety monitor's drops, to the log and the report.
    #[inline(never)]
    fn log_drops(&mut self, drops: Vec<asi_slaves::monitor::MonitorDrop>) {
        for d in drops {
            let (cause, text) = words::monitor_drop(d.why);
            let address = d.address.get();
            self.log_at(
                d.at,
                "monitor",
                format!("safety sensor {address} not released: {text}"),
            );
            self.report.safety.monitor.push(MonitorTrip {
                at_s: d.at.as_secs_f64(),
                address,
                cause: cause.into(),
            });
        }
    }

    /// The safety logic's scan at `t`, with the bus watch before it and the safe drive's scan
    /// and the attendant's watch after it.
    ///
    /// Almost every scan is a quiet one (`LiftSafety::scan_if_quiet`), whose outputs are the
    /// last scan's with no events: the rig already holds what they give it (EStopOut, the
    /// diagnosis, K1), so nothing is handed on, where nothing else looks at them at this
    /// scan: the safe drive's scan (it runs every scan) and the attendant's watch while it
    /// counts (after a scan that found K1 open for a cause a round answers, see
    /// [`Rig::attendant_idle`]).
    pub(super) fn safety_scan(&mut self, t: SimTime) {
        self.watch_bus(t);
        let [ch1, ch2] = self.lift.stop_channels();
        let inputs = LiftSafetyInputs {
            stop_ch1: ch1,
            stop_ch2: ch2,
            overtravel_bottom_released: self.lab.released(SAFETY_BOTTOM),
            overtravel_top_released: self.lab.released(SAFETY_TOP),
            overloaded: self.to_safety.overloaded,
            k1_aux: self.lift.k1_aux_closed(),
            operator_reset: self.operator_reset,
            err_ack: self.err_ack,
            controller_restart: self.to_safety.restart,
        };
        if self.attendant_idle && self.drive.is_none() && self.safety.scan_if_quiet(t, &inputs) {
            #[cfg(test)]
            self.assert_quiet_scan_kept(t);
            return;
        }
        let out = self.safety.scan(t, &inputs);
        #[cfg(test)]
        {
            self.scanned = Some((out.k1, out.estop_out, out.diag));
        }
        for e in &out.events {
            let kind = match e.kind {
                LiftEventKind::Trip => Some(TripKind::Trip),
                LiftEventKind::Error => Some(TripKind::Error),
                LiftEventKind::PowerOff => Some(TripKind::PowerOff),
                LiftEventKind::Release | LiftEventKind::Acknowledge | LiftEventKind::Info => None,
            };
            if let Some(kind) = kind {
                self.report.safety.trips.push(Trip {
                    at_s: e.at_s(),
                    kind,
                    cause: e.cause.clone(),
                });
            }
            self.report.log.push(LogLine {
                at_s: e.at_s(),
                who: "safety",
                text: e.cause.clone(),
            });
        }
        self.from_safety = FromSafety {
            estop_out: out.estop_out,
        };
        let k1 = self.drive_scan(t, out.estop_out, out.k1);
        let drive_tripped = self.drive.as_ref().is_some_and(|d| d.error().is_some());
        let answered = out
            .diag
            .k1_open_cause
            .as_ref()
            .is_some_and(operator::answers);
        let watched = answered || (drive_tripped && !k1);
        self.attendant_idle = !watched;
        if self.attendant.watch(t, watched) {
            let cause = out
                .diag
                .k1_open_cause
                .map(|c| c.to_string())
                .or_else(|| self.drive.as_ref().and_then(|d| d.torque_off_cause()));
            self.log(
                "attendant",
                format!(
                    "K1 open for {ATTENDANT_NOTICE} ({}): rescue, acknowledge and reset",
                    cause.unwrap_or_default()
                ),
            );
            self.report.safety.attendant_rounds += 1;
            self.act(t, "attendant", &Action::Rescue);
            let ack = t + ATTENDANT_ACK_AFTER;
            self.timers.push((ack, Timer::Attendant(Round::Ack)));
            let reset = ack + ATTENDANT_RESET_AFTER;
            self.timers.push((reset, Timer::Attendant(Round::Reset)));
        }
        self.safety_out = Some(out.diag);
        if k1 != self.k1 {
            self.k1 = k1;
            if let Err(e) = self.lift.set_contactor(t, k1) {
                self.log("plant", format!("error: {e}"));
            }
            self.plant_dirty = true;
        }
    }

    /// A quiet scan at `t` gives the rig nothing new: its outputs, which are the last scan's
    /// (`LiftSafety::scan`), are the ones the rig holds.
    #[cfg(test)]
    fn assert_quiet_scan_kept(&self, t: SimTime) {
        assert_eq!(
            self.scanned
                .map(|(k1, estop_out, diag)| (k1, estop_out, Some(diag))),
            Some((self.k1, self.from_safety.estop_out, self.safety_out)),
            "a quiet scan at {t} gives the rig something new"
        );
    }

    /// The safe drive's scan at `t` (docs/drive-safety.md §6), after the safety logic's (its
    /// EStopOut `estop_out`, its K1 output `k1`); returns K1's coil: the safety logic's output
    /// and the drive's torque enable in series. Without the safe drive, `k1` as it is.
    pub(super) fn drive_scan(&mut self, t: SimTime, estop_out: bool, k1: bool) -> bool {
        let Some(guard) = self.drive.as_mut() else {
            return k1;
        };
        let signals = drive::Signals {
            estop_out,
            initialising: self.external.is_none()
                && self.plc.program().state() == controller::State::Initialising,
            run: self.applied.run,
            up: self.applied.up,
            setpoint_ua: self.applied.setpoint_ua,
            reset: self.operator_reset,
            door_closed: self.lift.door_closed(),
            position_mm: self.lift.position_mm(),
            velocity_mm_s: self.lift.velocity_mm_s(),
        };
        let (torque, lines) = guard.scan(t, &signals, &mut self.report.safety.trips);
        for (at, text) in lines {
            self.log_at(at, "drive", text);
        }
        k1 && torque
    }

    pub(super) fn plc_scan(&mut self, t: SimTime) {
        if let Some(signals) = self.external {
            // The outside controller writes the output image itself, between moments.
            self.to_safety = signals;
            return;
        }
        self.to_safety = self.plc.scan(t, self.lab.bus.image_mut(), self.from_safety);
        let held = self.plc.program().state() == controller::State::BusFault;
        match (self.bus_fault_since, held) {
            (None, true) => {
                self.bus_fault_since = Some(t);
                self.report.availability.bus_fault_holds += 1;
            }
            (Some(s), false) => {
                self.report.availability.bus_fault_s += (t - s).as_secs_f64();
                self.bus_fault_since = None;
            }
            _ => {}
        }
        let events: Vec<_> = self.plc.program_mut().drain_events().collect();
        for e in events {
            match e.kind {
                Ctl::Initialised if self.report.initialised_at_s.is_none() => {
                    self.report.initialised_at_s = Some(e.at.as_secs_f64());
                }
                Ctl::StopDemanded {
                    dropped: Some(f), ..
                } => self.passengers.target_dropped(f, e.at),
                Ctl::Served(s) => {
                    let served = self.passengers.served(&s, e.at);
                    self.report.served.push(served);
                }
                _ => {}
            }
            self.log_at(e.at, "controller", e.kind.to_string());
        }
    }
}
