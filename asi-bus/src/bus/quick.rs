//! Quick transactions: a transaction's telegrams held off a line that takes them clean, their
//! frames handed to the receivers at their events (see the module documentation of the bus).

use super::*;

impl Bus {
    /// `true` if the transaction of request `req` may run quick: its telegrams held off the
    /// line and their frames taken directly ([`Bus::quick_request`], [`Bus::quick_finish`]),
    /// each as long as the line takes it clean ([`Medium::takes_clean`]: an idle line whose
    /// faults leave it untouched hands a telegram on as its own frame at its end plus the
    /// pause, and is idle again after it, so a telegram alone on it needs no line at all).
    /// What may not run quick: more than one receiver state among the slaves, a
    /// request two slaves may answer (their answers collide on the line), the broadcast reset
    /// (every slave takes it), a slave without power. A quick transaction goes on to its next
    /// event at once only within the horizon and while no new output waits to be taken by
    /// [`Bus::advance_before`], which must return at that event. Anything that changes the line, the slaves'
    /// receivers or their power puts a held telegram on the line first ([`Bus::release_held`]),
    /// and the transaction goes on as it would have. Held to the line's path by a lockstep
    /// test against the pulse-exact bus (`tests/quick.rs`) and by the rig's fast-path
    /// equivalence (tests/tests/fast_path.rs).
    ///
    /// Returns the slaves that take the request (at most one; none where no slave has its
    /// address), for [`Bus::quick_from`]; `None` where the transaction may not run quick.
    pub(super) fn may_run_quick(&self, req: Request) -> Option<u64> {
        if self.groups.len() != 1 || !self.slaves_powered || req.is_broadcast_reset() {
            return None;
        }
        let who = self.groups[0].members & self.addr_index[req.address().get() as usize];
        (who & who.wrapping_sub(1) == 0).then_some(who)
    }

    /// A quick transaction's request frame, at `t`: what `request_frame` and `hear` do with
    /// it, the slave's answer held off the line. When the transaction's end falls within the
    /// horizon it ends here too.
    pub(super) fn quick_request(&mut self, t: SimTime) {
        let (Some(cur), Some(f)) = (self.cur, self.held.take()) else {
            // Nothing held: the line's path.
            if let Some(c) = self.cur.as_mut() {
                c.quick = false;
            }
            self.request_frame(t);
            return;
        };
        debug_assert_eq!(
            f,
            request_frame(cur.tx.request, cur.start, self.request_last),
            "the held request frame is not the transaction's own"
        );
        self.cur = None;
        // What `may_run_quick` found at the start: anything that changes the slaves or their
        // addresses since releases the held request first.
        let who = self.groups[0].members & self.addr_index[cur.tx.request.address().get() as usize];
        self.quick_from(t, cur, who);
    }

    /// [`Bus::quick_request`] of transaction `cur`, its request held: in locals, and put in
    /// the bus only where the transaction has to wait for a later event (or leaves the quick
    /// path), so that a transaction run in one go from its start (`start_transaction`) never
    /// stores it. The held request's frame is [`request_frame`] of the transaction's request at
    /// its start (`cur.start` to `cur.req_end`), and the held answer's [`answer_frame`] of the
    /// answer at its start: each is built only where a receiver takes it or the transaction
    /// keeps it in the bus, not in a run of clean quick transactions, which takes the times
    /// alone. Inlined into the bus's one event loop (`Bus::events_through`), where most
    /// transactions run; as a call of its own it cost more (measured when the events still
    /// were a call each, and again after).
    ///
    /// `who`: the slave that takes the request ([`Bus::may_run_quick`]).
    #[inline(always)]
    pub(super) fn quick_from(&mut self, t: SimTime, mut cur: Current, who: u64) {
        cur.request_frames = 1;
        let request = if self.run_takes_request(t, cur.start, cur.req_end, cur.tx.request) {
            Some(cur.tx.request)
        } else {
            let f = request_frame(cur.tx.request, cur.start, self.request_last);
            let r = hear_in_step(
                &mut self.groups[0].listener,
                &mut self.monitors,
                &mut self.monitor_in_step,
                t,
                &f,
            );
            cur.request_failed = r.failed;
            // The held frame is the request's own (`start_transaction` made it of `cur.tx`).
            r.request_sent(cur.tx.request)
        };
        let base = cur.start + self.transaction;
        let mut answer = None;
        if let Some(q) = request {
            debug_assert_eq!(
                who,
                self.groups[0].members & self.addr_index[q.address().get() as usize],
                "not the slave of {q:?}"
            );
            if who != 0 {
                answer = self.ask_one(t, q, who);
            }
        }
        let timing = self.timing;
        // The held answer: its start and the answer.
        let mut held = None;
        if let Some(r) = answer {
            let start = cur.req_end + timing.master_pause();
            let tg = || Transmission::response(r, start, timing.half_bit());
            // The line is as the request found it (idle, nothing recorded: anything that
            // changes that releases the held request first), so only its faults are left to
            // ask, and on a plain line there are none.
            if self.line_plain || self.medium.pass_untouched(&tg()) {
                held = Some((start, r));
            } else {
                // The line touches the answer: the transaction goes on the line's path, from
                // the bus (`hear` finds it there).
                cur.quick = false;
                self.cur = Some(cur);
                self.transmit_answers(t, &[tg()]);
                let quiet = self
                    .medium
                    .poll_at()
                    .map(|p| p + (timing.slave_pause() - timing.min_pause()));
                self.state = State::AwaitResponse;
                self.next_event = quiet.map_or(base, |q| q.max(base)).max(t);
                return;
            }
        }
        // The line's path ends the transaction when the line is quiet, the slave pause after
        // the answer, but not before `base`; a held answer's quiet line is `base` itself
        // (`quiet_line_after_a_held_answer_is_the_transactions_end`), so the end is `base`
        // with or without an answer.
        let next = base.max(t);
        if next <= self.horizon && !self.output_taken {
            self.now = next;
            self.state = State::Idle;
            self.next_event = match self.quick_end(next, cur, held) {
                Some(resync) if resync > next => resync,
                _ => next,
            };
        } else {
            self.cur = Some(cur);
            self.held = held.map(|(start, r)| answer_frame(r, start, self.response_last));
            self.held_answer = held.map(|(_, r)| r);
            self.state = State::AwaitResponse;
            self.next_event = next;
        }
    }

    /// [`Bus::ask_slaves`] of request `req` at `now` for the one slave `who` (a quick
    /// transaction's: [`Bus::may_run_quick`]); its answer. A Data_Exchange, almost every
    /// call, is taken here, inlined into the quick transaction; every other call goes to
    /// `ask_slaves`. The same calls into the slave and the same notes as there.
    #[inline(always)]
    fn ask_one(&mut self, now: SimTime, req: Request, who: u64) -> Option<Response> {
        debug_assert_eq!(who & who.wrapping_sub(1), 0, "more than one slave");
        let told = Told::of(req);
        let i = who.trailing_zeros() as usize;
        let (Told::Exchange(..), Some(slot)) = (told, self.slaves.get_mut(i)) else {
            let mut answer = None;
            self.ask_slaves(now, req, who, |r| answer = Some(r));
            return answer;
        };
        let mut r = None;
        if slot.attached {
            r = slot.slave.handle(now, req);
            self.drive_total += u64::from(slot.slave.take_drive_moved());
        }
        self.note_output(req, told);
        r
    }

    /// A quick transaction's end, at `t`: the held answer's frame to the master's receiver,
    /// the slaves' and the monitors', then the master's verdict ([`Bus::close`]).
    pub(super) fn quick_finish(&mut self, t: SimTime) -> Option<SimTime> {
        let cur = self.cur.take()?;
        // A held answer's frame is always kept with its answer (`quick_from`), and both are
        // taken together (here and in `release_held`).
        let held = match (self.held.take(), self.held_answer.take()) {
            (Some(f), Some(a)) => {
                debug_assert_eq!(
                    f,
                    answer_frame(a, f.start, self.response_last),
                    "the held answer's frame is not its own"
                );
                Some((f.start, a))
            }
            (None, _) => None,
            (Some(f), None) => return self.quick_end_unknown(t, cur, f),
        };
        self.quick_end(t, cur, held)
    }

    /// [`Bus::quick_finish`] of transaction `cur` with its held answer (`held`: the answer's
    /// start and the answer) in locals.
    #[inline(always)]
    fn quick_end(
        &mut self,
        t: SimTime,
        mut cur: Current,
        held: Option<(SimTime, Response)>,
    ) -> Option<SimTime> {
        if let Some((start, a)) = held {
            let end = start + self.response_last;
            cur.line_end = cur.line_end.max(end);
            if self.run_takes_answer(t, &mut cur, start, end, a) {
                return self.close(t, &cur);
            }
            let f = answer_frame(a, start, self.response_last);
            cur.master_hears_as(&mut self.master_rx, &self.timing, &f, |r| {
                r.response_sent(a)
            });
            hear_in_step(
                &mut self.groups[0].listener,
                &mut self.monitors,
                &mut self.monitor_in_step,
                t,
                &f,
            );
        }
        self.close(t, &cur)
    }

    /// [`Bus::quick_end`] of a held frame `f` without the answer it was made of (which the bus
    /// never leaves: kept for completeness), heard as the line would hand it on.
    #[inline(never)]
    fn quick_end_unknown(&mut self, t: SimTime, mut cur: Current, f: Frame) -> Option<SimTime> {
        cur.line_end = cur.line_end.max(f.end);
        cur.master_hears(&mut self.master_rx, &self.timing, &f);
        hear_in_step(
            &mut self.groups[0].listener,
            &mut self.monitors,
            &mut self.monitor_in_step,
            t,
            &f,
        );
        self.close(t, &cur)
    }

    /// `true` if the clean request frame of request `q` from `start` to `end`, heard at `t`,
    /// is taken in a run of
    /// clean quick transactions ([`Unsettled`]): every receiver on the bus would take it as
    /// the valid request `q` (the slaves' receiver, in the state the run has left it,
    /// synchronised and not within a response window; the first monitor's, in step with it),
    /// the monitor judges it, and the run notes the state it leaves the receivers in
    /// instead of writing it into them. Starts a run where the receivers allow one; `false`,
    /// with the receivers settled, where the frame must go to them.
    #[inline(always)]
    fn run_takes_request(&mut self, t: SimTime, start: SimTime, end: SimTime, q: Request) -> bool {
        let slaves = &self.groups[0].listener;
        let window_from = match self.unsettled {
            Some(u) => u.window_open.then_some(u.slaves_end),
            None => {
                // A run starts from receivers that take a clean telegram without the
                // asynchronous pause, and only with at most one monitor, in step.
                let in_step = match self.monitors.as_slice() {
                    [] => true,
                    [first] => self.monitor_in_step || first.receiver() == slaves,
                    _ => false,
                };
                if !(in_step && slaves.is_synchronised() && self.master_rx.is_synchronised()) {
                    return false;
                }
                slaves.window_from()
            }
        };
        // Within the window it would be taken for a response (`Listener::accept`).
        if window_from.is_some_and(|from| {
            start >= from && start.as_nanos() - from.as_nanos() <= slaves.response_window()
        }) {
            self.settle();
            return false;
        }
        match &mut self.unsettled {
            Some(u) => {
                u.slaves_end = end;
                u.window_open = true;
            }
            None => {
                self.unsettled = Some(Unsettled {
                    slaves_end: end,
                    window_open: true,
                    master_end: None,
                });
            }
        }
        if let Some(first) = self.monitors.first_mut() {
            self.monitor_in_step = true;
            first.hear(t, Heard::Request(q));
        }
        true
    }

    /// `true` if the clean answer frame of answer `a` from `start` to `end`, heard at `t` in
    /// transaction `cur`, is taken in the run of clean quick transactions ([`Bus::run_takes_request`]): the
    /// slaves' receiver takes it as a valid response (it starts within the window the
    /// request opened), the master's (synchronised) as a valid response where it starts in
    /// the master's response window, and the monitor judges it. `false`, with the
    /// receivers settled, where the frame must go to them.
    #[inline(always)]
    fn run_takes_answer(
        &mut self,
        t: SimTime,
        cur: &mut Current,
        start: SimTime,
        end: SimTime,
        a: Response,
    ) -> bool {
        let Some(u) = self.unsettled.as_mut() else {
            return false;
        };
        let rw = self.groups[0].listener.response_window();
        let from = u.slaves_end;
        if !(u.window_open && start >= from && start.as_nanos() - from.as_nanos() <= rw) {
            self.settle();
            return false;
        }
        u.slaves_end = end;
        u.window_open = false;
        // What `Current::master_hears_as` does with a valid response.
        if start > cur.req_end && start <= cur.req_end + self.timing.response_timeout() {
            u.master_end = Some(end);
            cur.responses += 1;
            if cur.responses == 1 {
                cur.response = Some(a);
            } else {
                cur.response = None;
            }
        }
        if let Some(first) = self.monitors.first_mut() {
            first.hear(t, Heard::Response(a));
        }
        true
    }

    /// Writes the state a run of clean quick transactions has left the receivers in into
    /// them, and ends the run: called before anything else hears a frame, and at the end of
    /// every `advance_to` and `advance_before`, so that the bus is settled between calls.
    pub(super) fn settle(&mut self) {
        let Some(u) = self.unsettled.take() else {
            return;
        };
        let slaves = &mut self.groups[0].listener;
        slaves.took_valid(u.slaves_end, u.window_open);
        if let Some(first) = self.monitors.first_mut() {
            first.receiver_mut().clone_from(slaves);
        }
        if let Some(end) = u.master_end {
            self.master_rx.took_valid(end, false);
        }
    }

    /// Puts a quick transaction's held telegram on the line, where the line's path would
    /// have it by now, and lets the transaction go on that path: called before anything
    /// changes the line, the slaves' receivers or their power.
    pub(super) fn release_held(&mut self) {
        self.settle();
        // What comes may change the slaves' receivers: the first monitor's is compared with
        // theirs again before it takes their telegrams ([`hear_in_step`]).
        self.monitor_in_step = false;
        let Some(cur) = self.cur.as_mut().filter(|c| c.quick) else {
            return;
        };
        cur.quick = false;
        self.held_answer = None;
        if let Some(f) = self.held.take() {
            // The telegram the frame was made of; an idle, clean line keeps it pending, so no
            // frame comes out now.
            let tg = Transmission::new(f.raw, f.bit_count, f.start, self.timing.half_bit());
            self.medium.transmit_taken(&tg, &mut |_| {
                debug_assert!(false, "a held telegram went on a line that was not idle")
            });
        }
    }
}

/// The state a run of clean quick transactions has left the receivers in, not yet written
/// into them ([`Bus::settle`]). In such a run every frame is the clean frame of the telegram it
/// was made of, the slaves' receiver (one group) and the master's are synchronised, and the
/// first monitor's (the only one) is in step with the slaves': each frame is then taken as a
/// valid telegram of the kind its timing tells, and leaves each receiver in a state that
/// depends on that frame alone (`Listener::took_valid`). The run keeps that state here
/// instead of checking every frame three times. Held to the frame-by-frame path by the
/// lockstep test against the pulse-exact bus (`tests/quick.rs`), which compares the monitor
/// and, through everything the bus does afterwards, the other receivers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Unsettled {
    /// The end of the last frame the slaves' receiver took.
    slaves_end: SimTime,
    /// That frame was a request, whose response window is open.
    window_open: bool,
    /// The end of the last answer the master's receiver took in the run.
    master_end: Option<SimTime>,
}

/// The slaves' receiver `slaves` and the monitors take frame `f` at `t`; returns the slaves'
/// telegram. The first monitor's receiver hears what the slaves' does, so once the two are in
/// the same state (`in_step`, compared again only after something may have changed the
/// slaves' receivers: [`Bus::release_held`]) it takes the slaves' telegram and state
/// ([`SafetyMonitor::hear`], which debug builds check against its own receiver) instead of
/// checking every frame a second time. Inlined into the two events: a call of its
/// own cost as much as the second check it saves.
#[inline(always)]
fn hear_in_step(
    slaves: &mut Listener,
    monitors: &mut [SafetyMonitor],
    in_step: &mut bool,
    t: SimTime,
    f: &Frame,
) -> Received {
    let Some((first, rest)) = monitors.split_first_mut() else {
        return slaves.accept(f);
    };
    if !*in_step {
        *in_step = first.receiver() == slaves;
    }
    let r = slaves.accept(f);
    if *in_step {
        debug_assert!(
            {
                let mut own = first.receiver().clone();
                own.accept(f) == r && own == *slaves
            },
            "the monitor's receiver is not in the state of the slaves' whose telegram it takes"
        );
        first.receiver_mut().clone_from(slaves);
        first.hear(t, Heard::Received(&r));
    } else {
        first.on_frame(t, f);
    }
    for m in rest {
        m.on_frame(t, f);
    }
    r
}

/// From the first pulse of a request or response of `bits` bits to its last on the `half_bit`
/// grid: the last pulse is the return to idle after the end bit, at grid point `2 * bits`.
pub(super) fn last_pulse(half_bit: SimDuration, bits: u32) -> SimDuration {
    half_bit.saturating_mul(u64::from(2 * bits))
}

/// `Transmission::request(q, start, h).frame()`, the frame a clean line hands on for request
/// `q` sent at `start`, its last pulse `last` after the first ([`last_pulse`]): the pulse
/// count looked up ([`Request::pulses`]) instead of worked out from the bits at every
/// transaction. Held to `Transmission::frame` for every request by the test below.
#[inline]
pub(super) fn request_frame(q: Request, start: SimTime, last: SimDuration) -> Frame {
    Frame {
        start,
        end: start + last,
        pulses: q.pulses(),
        bit_count: Request::BITS,
        raw: u32::from(q.bits()),
        line_failed: Checks::NONE,
    }
}

/// [`request_frame`] of response `r`.
#[inline]
fn answer_frame(r: Response, start: SimTime, last: SimDuration) -> Frame {
    Frame {
        start,
        end: start + last,
        pulses: r.pulses(),
        bit_count: Response::BITS,
        raw: u32::from(r.bits()),
        line_failed: Checks::NONE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use asi_phy::{Address, Nibble};
    use asi_slaves::monitor::MonitorConfig;
    use proptest::prelude::*;

    /// What happens at a step of the test below.
    #[derive(Clone, Debug)]
    enum Step {
        /// A frame `gap` ns after the last one's end: a Data_Exchange to a monitored slave
        /// (`to` 11 or 12) or to another, or an answer with `data`; `failed` line checks.
        Frame {
            gap: u64,
            request: bool,
            to: u8,
            data: u8,
            failed: u8,
        },
        /// The slaves' receiver is reset (their power returns), which the bus lets happen
        /// only after clearing `in_step` (`Bus::release_held`).
        Reset,
    }

    fn step() -> impl Strategy<Value = Step> {
        prop_oneof![
            12 => (
                prop_oneof![0u64..40_000, 100_000u64..300_000],
                any::<bool>(),
                prop_oneof![Just(11u8), Just(12u8), 1u8..32],
                0u8..16,
                prop_oneof![4 => Just(0u8), 1 => any::<u8>()],
            )
                .prop_map(|(gap, request, to, data, failed)| Step::Frame {
                    gap,
                    request,
                    to,
                    data,
                    failed,
                }),
            1 => Just(Step::Reset),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(500))]

        /// The monitor that takes the slaves' telegrams while its receiver is in step with
        /// theirs ends every frame in the state of one that checks every frame itself, and
        /// the slaves' receiver in the state it would reach alone: Data_Exchanges to
        /// monitored slaves and others with their answers, broken frames, frames after too
        /// short a pause, and resets of the slaves' receiver that put the two out of step.
        #[test]
        fn a_monitor_in_step_takes_the_frames_as_its_own_receiver(
            steps in proptest::collection::vec(step(), 1..80),
        ) {
            let timing = BusTiming::default();
            let addresses = [Address::new(11).expect("a"), Address::new(12).expect("a")];
            let monitor = SafetyMonitor::new(&timing, MonitorConfig::default(), &addresses);
            let mut slaves = Listener::new(&timing.receiver(Expect::Both));
            let mut monitors = [monitor];
            let mut in_step = false;
            let (mut slaves_alone, mut alone) = (slaves.clone(), monitors[0].clone());
            let h = timing.half_bit();
            let mut t = SimTime::ZERO;
            for step in &steps {
                match *step {
                    Step::Frame { gap, request, to, data, failed } => {
                        let start = t + SimDuration::from_nanos(gap);
                        let d = Nibble::new(data).expect("a nibble");
                        let mut f = if request {
                            let a = Address::new(to).expect("an address");
                            let q = Request::data_exchange(a, d).expect("a request");
                            request_frame(q, start, last_pulse(h, Request::BITS))
                        } else {
                            answer_frame(Response::new(d), start, last_pulse(h, Response::BITS))
                        };
                        f.line_failed = Checks::from_bits(failed);
                        t = f.end;
                        let r = hear_in_step(&mut slaves, &mut monitors, &mut in_step, t, &f);
                        prop_assert_eq!(r, slaves_alone.accept(&f));
                        alone.on_frame(t, &f);
                    }
                    Step::Reset => {
                        in_step = false;
                        slaves.reset();
                        slaves_alone.reset();
                    }
                }
                prop_assert_eq!(&slaves, &slaves_alone);
                prop_assert!(monitors[0] == alone, "{:?}\n{:?}", monitors[0], alone);
            }
        }
    }

    proptest! {
        /// A quick transaction's held answer leaves the line quiet, as the line's path works
        /// it out (its frame handed on at its end plus the pause, quiet the rest of the slave
        /// pause later), exactly at the transaction's end: its start plus
        /// `BusTiming::transaction`. A request's and a response's last pulses are 28 and 14
        /// half bits after their first, which is the request's and the response's span for the
        /// even bit time of every valid timing, and the pauses are the same. Random valid
        /// timings, starts near the end of time too.
        #[test]
        fn quiet_line_after_a_held_answer_is_the_transactions_end(
            half_bit in prop_oneof![1u64..10_000, 1u64..u64::MAX / 4],
            tolerance in 0u64..1_000,
            pauses in proptest::collection::vec(prop_oneof![0u64..200_000, any::<u64>()], 7),
            start in prop_oneof![any::<u64>(), (u64::MAX - 10_000_000)..=u64::MAX],
        ) {
            let ns = SimDuration::from_nanos;
            let bit_time = 2 * half_bit;
            let min_pause = bit_time.saturating_add(2 * tolerance).saturating_add(1 + pauses[0]);
            let reply_min = min_pause.saturating_add(pauses[1]);
            let reply_max = reply_min.saturating_add(pauses[2]);
            let timing = BusTiming::builder()
                .bit_time(ns(bit_time))
                .tolerance(ns(tolerance))
                .min_pause(ns(min_pause))
                .slave_pause(ns(min_pause.saturating_add(2 * tolerance).saturating_add(pauses[3])))
                .async_pause(ns(min_pause.saturating_add(pauses[4])))
                .reply_min(ns(reply_min))
                .reply_max(ns(reply_max))
                .master_pause(ns(reply_min.saturating_add(pauses[5] % (reply_max - reply_min + 1))))
                .response_timeout(ns(reply_max.saturating_add(1 + pauses[6] % 1_000_000)))
                .build();
            prop_assume!(timing.is_ok());
            let timing = timing.expect("a valid timing");
            let h = timing.half_bit();
            let start = SimTime::from_nanos(start);
            let q = Request::data_exchange(asi_phy::Address::new(5).expect("a"), Nibble::ZERO)
                .expect("a request");
            let f = request_frame(q, start, last_pulse(h, Request::BITS));
            let a = answer_frame(
                Response::new(Nibble::ZERO),
                f.end + timing.master_pause(),
                last_pulse(h, Response::BITS),
            );
            let quiet = (a.end + timing.min_pause()) + (timing.slave_pause() - timing.min_pause());
            prop_assert_eq!(quiet, start + timing.transaction());
        }
    }

    /// Every receiver on the lab bus, after runs of clean quick transactions have been settled,
    /// is in the state of the same receiver on the pulse-exact bus, which took every frame
    /// from the line: the slaves' and the monitor's (which the lockstep test in
    /// `tests/quick.rs` also sees through what the bus does next), and the master's, which no
    /// output shows while it stays synchronised. Steps of every length, from within a
    /// transaction to many cycles, through the start-up and into normal operation.
    #[test]
    fn runs_settle_the_receivers_as_the_line_leaves_them() {
        let mut quick = crate::lab::LabLift::new().expect("the lab bus");
        let mut exact = crate::lab::LabLift::new().expect("the lab bus");
        exact.bus.set_pulse_exact(true);
        let mut t = SimTime::ZERO;
        let mut runs = 0;
        for step in (0..400u64).map(|i| (i * 7_919) % 3_301 + 1) {
            t += SimDuration::from_micros(step);
            quick.bus.advance_to(t);
            exact.bus.advance_to(t);
            let listeners = |b: &Bus| -> Vec<(Listener, u64)> {
                b.groups
                    .iter()
                    .map(|g| (g.listener.clone(), g.members))
                    .collect()
            };
            assert_eq!(listeners(&quick.bus), listeners(&exact.bus), "at {t}");
            assert_eq!(quick.bus.master_rx, exact.bus.master_rx, "at {t}");
            assert!(quick.bus.monitors == exact.bus.monitors, "at {t}");
            runs += usize::from(quick.bus.is_running());
        }
        assert!(
            runs > 300,
            "the bus ran in normal operation at {runs} of 400 steps"
        );
    }

    /// The quick path's frames are the transmissions' frames, for every request and every
    /// response, on the default grid and on odd ones, at the start of time and near its end.
    #[test]
    fn the_quick_frames_are_the_transmissions_frames() {
        for h in [3_000, 1, 2_999, u64::MAX / 64] {
            let h = SimDuration::from_nanos(h);
            let (rq, rs) = (last_pulse(h, Request::BITS), last_pulse(h, Response::BITS));
            for start in [
                SimTime::ZERO,
                SimTime::from_nanos(123_456_789),
                SimTime::MAX,
            ] {
                for body in 0u16..1 << 11 {
                    let q = Request::from_fields(
                        body & 0x400 != 0,
                        asi_phy::Address::new((body >> 5 & 0x1F) as u8).expect("an address"),
                        (body & 0x1F) as u8,
                    )
                    .expect("a request");
                    assert_eq!(
                        request_frame(q, start, rq),
                        Transmission::request(q, start, h).frame(),
                        "{q:?}"
                    );
                }
                for d in 0..16 {
                    let r = Response::new(Nibble::new(d).expect("a nibble"));
                    assert_eq!(
                        answer_frame(r, start, rs),
                        Transmission::response(r, start, h).frame(),
                        "{r:?}"
                    );
                }
            }
        }
    }
}
