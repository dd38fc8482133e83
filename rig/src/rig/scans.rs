//! The rig's scans: the safety logic's (with the bus watch and the safe drive's) every 1 ms, and
//! the PLC's, each with what it hands to the report and the log.

use super::*;
use asi_bus::{Look, LookWatch, Stop};

/// What [`Rig::quiet_scans`] did.
pub(super) enum Stretch {
    /// Nothing: the next moment is not the start of a stretch of quiet scans.
    None,
    /// It took a stretch of quiet scans, and a new output the bus stopped at, if any: the
    /// rig goes on from its next moment.
    Went,
    /// It took the quiet scans before this scan time, where the bus stopped: the rig steps
    /// here (the bus is there already).
    StepAt(SimTime),
}

/// What the safety scan reads of the bus ([`Look`]): the master's LAS (A slots) in normal
/// operation, the addresses the safety monitor releases (the scan reads the overtravel
/// sensors'), whether it has dropped a release since the last look, and the drive count.
trait Reads {
    /// `true` if the master is in normal operation with the LAS the watch saw last (`seen`,
    /// [`LasWatch::seen`]): the watch then has nothing to note.
    fn las_seen(&self, seen: Option<u32>) -> bool;
    /// `true` if the monitor releases the safety sensor at `address`.
    fn releases(&self, address: u8) -> bool;
}

impl Reads for Look {
    #[inline]
    fn las_seen(&self, seen: Option<u32>) -> bool {
        self.las.is_some() && self.las == seen
    }

    #[inline]
    fn releases(&self, address: u8) -> bool {
        self.released >> address & 1 == 1
    }
}

impl Rig {
    /// The master's LAS and the safety monitor's drops since the last look (`reads`, the bus
    /// as the scan at `t` finds it), to the report and the log (every safety scan, 1 ms). In
    /// almost every scan the master is in normal operation with the LAS the watch saw last,
    /// and the monitor has dropped nothing: the watch is then left as it is (as
    /// [`LasWatch::update`] leaves it then).
    #[inline]
    fn watch_bus_reads(&mut self, t: SimTime, reads: Look) {
        if !reads.las_seen(self.judge.las_watch.seen()) {
            self.las_moved(t, reads.las);
        }
        if reads.drops {
            let monitor = self.lab.monitor_id();
            let drops = self.lab.bus_mut().take_monitor_drops(monitor);
            self.log_drops(drops);
        }
    }

    /// [`Rig::watch_bus_reads`] of the bus as it is, at `t` (the end of a run).
    pub(super) fn watch_bus(&mut self, t: SimTime) {
        let reads = self.lab.bus().look(self.lab.monitor_id());
        self.watch_bus_reads(t, reads);
    }

    /// The LAS at `t` (`None` outside normal operation) to the watch, and who left and came
    /// back to the log.
    #[inline(never)]
    fn las_moved(&mut self, t: SimTime, las: Option<u32>) {
        let (left, back) = self.judge.las_watch.update(t, las);
        if left | back != 0 {
            self.log_las(t, left, back);
        }
    }

    /// The addresses that `left` LAS and came `back` at `t`, to the log.
    #[inline(never)]
    fn log_las(&mut self, t: SimTime, left: u32, back: u32) {
        for i in 1..32u8 {
            if left & (1 << i) != 0 {
                let e = LogEvent::Las {
                    address: i,
                    left: true,
                };
                self.log_at(t, Actor::Bus, e);
            }
            if back & (1 << i) != 0 {
                let e = LogEvent::Las {
                    address: i,
                    left: false,
                };
                self.log_at(t, Actor::Bus, e);
            }
        }
    }

    /// The safety monitor's drops, to the log and the report.
    #[inline(never)]
    fn log_drops(&mut self, drops: Vec<asi_slaves::monitor::MonitorDrop>) {
        for d in drops {
            let (cause, _) = crate::report::monitor_drop(d.why);
            let address = d.address.get();
            let e = LogEvent::MonitorDrop {
                address,
                why: d.why,
            };
            self.log_at(d.at, Actor::Monitor, e);
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
    /// Almost every scan is a quiet one (before the logic's deadline, `LiftSafety::poll_at`),
    /// whose outputs are the last scan's with no events: the rig already holds what they
    /// give it (EStopOut, the diagnosis, K1), so it leaves the scan out
    /// (`LiftSafety::skip_through`) where nothing else looks at them at this scan: the safe
    /// drive's scan (it runs every scan) and the attendant's watch while it counts (after a
    /// scan that found K1 open for a cause a round answers, see [`People::attendant_idle`]).
    pub(super) fn safety_scan(&mut self, t: SimTime) {
        let reads = self.lab.bus().look(self.lab.monitor_id());
        self.watch_bus_reads(t, reads);
        let inputs = self.safety_inputs(reads);
        if self.people.attendant_idle
            && self.safety.drive.is_none()
            && t < self.safety.logic.poll_at(&inputs)
            && self.safety.logic.skip_through(t)
        {
            #[cfg(test)]
            self.assert_quiet_scan_kept(t);
            return;
        }
        let out = self.safety.logic.scan(t, &inputs);
        #[cfg(test)]
        {
            self.probes.scanned = Some((out.k1, out.estop_out, out.diag));
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
                    cause: TripCause::Logic(e.cause.clone()),
                });
            }
            self.report.log.push(LogLine::new(
                e.at_s(),
                Actor::Safety,
                LogEvent::Safety(e.cause.clone()),
            ));
        }
        self.safety.from = FromSafety {
            estop_out: out.estop_out,
        };
        let k1 = self.drive_scan(t, out.estop_out, out.k1);
        let drive_tripped = self
            .safety
            .drive
            .as_ref()
            .is_some_and(|d| d.error().is_some());
        let answered = out
            .diag
            .k1_open_cause
            .as_ref()
            .is_some_and(operator::answers);
        let watched = answered || (drive_tripped && !k1);
        self.people.attendant_idle = !watched;
        if self.people.attendant.watch(t, watched) {
            let cause = out.diag.k1_open_cause.map(|c| c.to_string()).or_else(|| {
                self.safety
                    .drive
                    .as_ref()
                    .and_then(|d| d.torque_off_cause())
            });
            let round = LogEvent::AttendantRound {
                after: ATTENDANT_NOTICE,
                cause: cause.unwrap_or_default(),
            };
            self.log(Actor::Attendant, round);
            self.report.safety.attendant_rounds += 1;
            self.act(t, Actor::Attendant, &Action::Rescue);
            let ack = t + ATTENDANT_ACK_AFTER;
            self.agenda.timers.push((ack, Timer::Attendant(Round::Ack)));
            let reset = ack + ATTENDANT_RESET_AFTER;
            self.agenda
                .timers
                .push((reset, Timer::Attendant(Round::Reset)));
        }
        self.safety.out = Some(out.diag);
        if k1 != self.safety.k1 {
            self.safety.k1 = k1;
            if let Err(e) = self.lift.set_contactor(t, k1) {
                self.log(Actor::Plant, LogEvent::PlantError(e));
            }
            self.wiring.plant_dirty = true;
        }
    }

    /// Leaves out the safety scans from the rig's next moment `t` on, where each would be a
    /// quiet one that hands nothing on ([`Rig::safety_scan`]), and nothing else comes before
    /// the stretch's end: the bus runs through the stretch's scan times in one call, watching
    /// what the scan reads at each ([`asi_bus::Watch::look`]) and stopping where it brings
    /// the scan anything new, and the logic is told of the scans left out
    /// (`LiftSafety::skip_through`).
    ///
    /// The stretch begins at a safety scan with the inputs of the last one, before the
    /// logic's deadline (`LiftSafety::poll_at`), the LAS the watch saw and no monitor drop,
    /// the attendant idle and no safe drive. It ends before the next moment of anything else
    /// that a step handles (PLC scan, scenario event, timer, plant edge, the end), before the
    /// logic's deadline, and not after the time through which new outputs pass the rig by
    /// (`quiet`, [`Rig::outputs_pass_until`]: no dirty plant, no waves, not pulse-exact,
    /// and the invariant watch's quiet holds). Within it the rest of each step does nothing:
    /// the plant has no edge, the invariant watch's check is skipped, the slaves' new outputs
    /// pass (the bus stops at one that does not, and at a scan time by which the drive count
    /// has moved), and the scan's inputs from the plant, the PLC and the operator stay as they
    /// are. The fast-path tests compare runs with the pulse-exact path, which takes every
    /// step; the rig's tests compare runs with one call per moment ([`Rig::advance`], which
    /// takes no stretch).
    pub(super) fn quiet_scans(
        &mut self,
        t: SimTime,
        quiet: Option<SimTime>,
        limit: SimTime,
    ) -> Stretch {
        let Some(through) = quiet else {
            return Stretch::None;
        };
        if t != self.agenda.next_safety
            || !self.people.attendant_idle
            || self.safety.drive.is_some()
        {
            return Stretch::None;
        }
        let monitor = self.lab.monitor_id();
        let reads = self.lab.bus().look(monitor);
        if !reads.las_seen(self.judge.las_watch.seen()) || reads.drops {
            return Stretch::None;
        }
        // What the slaves drive is read at a step when the drive count has moved: the bus
        // stops where it has.
        if reads.drives.is_none() || self.wiring.drives_seen != reads.drives {
            return Stretch::None;
        }
        let inputs = self.safety_inputs(reads);
        let after = |at: SimTime| {
            at.checked_add(SimDuration::from_nanos(1))
                .unwrap_or(SimTime::MAX)
        };
        let mut until = self
            .own_next_but_safety()
            .min(self.agenda.end)
            .min(self.safety.logic.poll_at(&inputs))
            .min(after(through))
            .min(after(limit));
        if let Some(e) = self.lift.next_event() {
            until = until.min(e);
        }
        if t >= until {
            return Stretch::None;
        }
        // The bus runs to the last scan time before `until`, and no further.
        let periods = (until - t)
            .as_nanos()
            .div_ceil(SAFETY_SCAN_PERIOD.as_nanos());
        let last = t + SimDuration::from_nanos((periods - 1) * SAFETY_SCAN_PERIOD.as_nanos());
        let bus = self.lab.bus_mut();
        let mut watch = bus.watching();
        watch.look = Some(LookWatch {
            monitor,
            first: t,
            period: SAFETY_SCAN_PERIOD,
            seen: reads,
        });
        bus.watch(watch);
        let stop = bus.advance_before(after(last));
        watch.look = None;
        bus.watch(watch);
        // The first scan time the bus did not pass.
        let next = match stop {
            None => last + SAFETY_SCAN_PERIOD,
            Some(Stop::Look(at)) => at,
            Some(Stop::Output(at)) if at < t => t,
            Some(Stop::Output(at)) => {
                let passed = (at - t).as_nanos() / SAFETY_SCAN_PERIOD.as_nanos() + 1;
                t + SimDuration::from_nanos(passed * SAFETY_SCAN_PERIOD.as_nanos())
            }
        };
        if next > t {
            // Each scan time's step: the plant brought to it (it has no edge before
            // `until`), the invariant watch (whose quiet holds), and the quiet scans.
            let passed = next - SAFETY_SCAN_PERIOD;
            self.agenda.now = passed;
            self.advance_plant(passed);
            self.check_invariants(passed);
            let kept = self.safety.logic.skip_through(passed);
            debug_assert!(kept, "the safety scans from {t} are not quiet ones");
            #[cfg(test)]
            {
                let n = (next - t).as_nanos() / SAFETY_SCAN_PERIOD.as_nanos();
                self.probes.stretch_scans += n;
            }
            self.agenda.next_safety = next;
            self.own_moments_changed();
        }
        match stop {
            None => Stretch::Went,
            Some(Stop::Output(at)) => {
                self.output_taken(at);
                Stretch::Went
            }
            Some(Stop::Look(at)) => Stretch::StepAt(at),
        }
    }

    /// The safety logic's inputs, with what it reads of the bus (`reads`).
    #[inline]
    fn safety_inputs(&self, reads: Look) -> LiftSafetyInputs {
        let [ch1, ch2] = self.lift.stop_channels();
        LiftSafetyInputs {
            stop_ch1: ch1,
            stop_ch2: ch2,
            overtravel_bottom_released: reads.releases(SAFETY_BOTTOM),
            overtravel_top_released: reads.releases(SAFETY_TOP),
            overloaded: self.safety.to.overloaded,
            k1_aux: self.lift.k1_aux_closed(),
            operator_reset: self.safety.operator_reset,
            err_ack: self.safety.err_ack,
            controller_restart: self.safety.to.restart,
        }
    }

    /// A quiet scan at `t` gives the rig nothing new: its outputs, which are the last scan's
    /// (`LiftSafety::scan`), are the ones the rig holds.
    #[cfg(test)]
    fn assert_quiet_scan_kept(&self, t: SimTime) {
        assert_eq!(
            self.probes
                .scanned
                .map(|(k1, estop_out, diag)| (k1, estop_out, Some(diag))),
            Some((self.safety.k1, self.safety.from.estop_out, self.safety.out)),
            "a quiet scan at {t} gives the rig something new"
        );
    }

    /// The safe drive's scan at `t` (docs/drive-safety.md §6), after the safety logic's (its
    /// EStopOut `estop_out`, its K1 output `k1`); returns K1's coil: the safety logic's output
    /// and the drive's torque enable in series. Without the safe drive, `k1` as it is.
    pub(super) fn drive_scan(&mut self, t: SimTime, estop_out: bool, k1: bool) -> bool {
        let Some(guard) = self.safety.drive.as_mut() else {
            return k1;
        };
        let signals = drive::Signals {
            estop_out,
            initialising: self.controller.status().initialising(),
            run: self.wiring.applied.run,
            up: self.wiring.applied.up,
            setpoint_ua: self.wiring.applied.setpoint_ua,
            reset: self.safety.operator_reset,
            door_closed: self.lift.door_closed(),
            position_mm: self.lift.position_mm(),
            velocity_mm_s: self.lift.velocity_mm_s(),
        };
        let (torque, lines) = guard.scan(t, &signals, &mut self.report.safety.trips);
        for (at, e) in lines {
            self.log_at(at, Actor::Drive, LogEvent::Drive(e));
        }
        k1 && torque
    }

    pub(super) fn plc_scan(&mut self, t: SimTime) {
        self.safety.to = self
            .controller
            .scan(t, self.lab.bus_mut().image_mut(), self.safety.from);
        let link = self.controller.plc_link();
        if link != self.lab.bus().master().plc_link() {
            self.lab.bus_mut().set_plc_link(link);
        }
        let held = self.controller.status().bus_fault();
        match (self.judge.bus_fault_since, held) {
            (None, true) => {
                self.judge.bus_fault_since = Some(t);
                self.report.availability.bus_fault_holds += 1;
            }
            (Some(s), false) => {
                self.report.availability.bus_fault_s += (t - s).as_secs_f64();
                self.judge.bus_fault_since = None;
            }
            _ => {}
        }
        for e in self.controller.drain_events() {
            match e.kind {
                Ctl::Initialised if self.report.initialised_at_s.is_none() => {
                    self.report.initialised_at_s = Some(e.at.as_secs_f64());
                }
                Ctl::StopDemanded {
                    dropped: Some(f), ..
                } => self.people.passengers.target_dropped(f, e.at),
                Ctl::Served(s) => {
                    let served = self.people.passengers.served(&s, e.at);
                    self.report.served.push(served);
                    self.riders_answered();
                }
                _ => {}
            }
            self.log_at(e.at, Actor::Controller, LogEvent::Controller(e.kind));
        }
    }
}
