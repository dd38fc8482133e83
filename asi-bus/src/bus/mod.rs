//! The whole AS-i segment as one sans-IO object: master, slaves, medium, monitors (docs/architecture.md–3).
//!
//! Drive it from a discrete-event loop: [`Bus::poll_at`] is the time of the next bus event,
//! [`Bus::advance_to`] processes every event up to a time. Each transaction is three events:
//!
//! 1. the master starts its request (its pulses go on the line);
//! 2. the request frame completes (last pulse + the 9 µs pause): every slave's receiver judges
//!    it; the addressed slave samples its inputs and drives its outputs *at this time*, and its
//!    response goes on the line after the reply delay (18 µs after the request's last pulse);
//! 3. the line is quiet again (or the response timeout is over): the master's receiver judges
//!    the response, the master decides (repeat, next call), and the next request starts — at
//!    request start + 154 µs with the default timing, later if noise kept the line busy.
//!
//! **Quick transactions.** A telegram that the line takes clean ([`Medium::takes_clean`]: idle,
//! nothing recorded, no fault armed or the injector leaves it untouched) is not put on the line:
//! the bus holds its frame and hands it to the receivers at its event, and goes on to the next
//! event at once where it falls before the caller's horizon (`Bus::may_run_quick`). The
//! events, their times and their order are the same; only the line's bookkeeping is skipped.
//!
//! **Decision**: after a transaction whose line carried an erroneous frame (a corrupt request
//! that still reached the slaves, a corrupt or colliding response) the master starts its next
//! request no earlier than the asynchronous pause (18 µs) after the last pulse, instead of the
//! 10 µs slave pause: receivers that saw the error need that pause to accept the repeat
//! (A²SI; docs/asi.md §2.3). A repeat after a corrupt request (no response) still comes
//! 154 µs after the first try; after a corrupt response it comes 162 µs after.
//!
//! Device inputs set between `advance_to` calls are seen by the transactions after the call
//! that set them, so an application that wants exact sampling steps to `poll_at()`.
//!
//! **Receivers.** Every slave has its own receiver state (asi-phy [`Listener`]): after a
//! corrupt telegram it needs the asynchronous pause before it accepts the next. Slaves whose
//! receivers are in the same state share one `Listener` value: after a frame a `Listener`'s
//! state is a function of the frame, the kind it took the frame for and whether it is
//! synchronised afterwards, so two receivers that agree on those two are identical from then on
//! and are merged. A slave put (back) on the bus gets a fresh receiver of its own. This keeps
//! the cost of a frame independent of the number of slaves (tested against one listener per
//! slave in asi-phy's `tests/receivers.rs`). A safety monitor's receiver hears the same frames
//! as the slaves' and so, once in their state, stays in it: in a quick transaction the first
//! monitor then takes the slaves' telegram instead of checking the frame itself
//! (`quick::hear_in_step`). In a run of quick transactions whose frames are all clean, with
//! the slaves' and the master's receivers synchronised and the monitor's in step, no receiver
//! checks a frame: each would take it as the valid telegram its timing makes it, and the state
//! that leaves depends on the frame alone, so the run notes that state and writes it into the
//! receivers once (`quick::Unsettled`, `Bus::settle`), before anything else hears a frame and
//! at the end of every `advance_to` and `advance_before` call.

use asi_master::config::{ConfigError, MasterConfig, ProjectedConfig};
use asi_master::master::{Master, Outcome, Phase, Transmit, Verdict};
use asi_master::record::{TraceRing, TransactionRecord, TxKind};
use asi_master::slave_stats::{SlaveTable, Tally};
use asi_phy::line::{Line, Medium};
use asi_phy::{
    Address, BusTiming, Call, Checks, Expect, FaultInjector, FaultRates, Frame, Listener, Nibble,
    PulseFault, PulseTrain, Received, Request, Response, SimDuration, SimTime, Transmission,
};
use asi_slaves::monitor::{Heard, SafetyMonitor};
use asi_slaves::slave::{Peripheral, Slave};

mod access;
mod hooks;
mod outputs;
mod quick;
mod watch;

use outputs::NO_OUTPUT;
pub use watch::{Look, LookWatch, Stop, Watch};

/// A request taken by a slave, as the bus tells it: a Data_Exchange from its bits
/// ([`Request::as_data_exchange`]), the cycle's Read_Status from its bits too, every other by
/// its call, decoded once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Told {
    /// A Data_Exchange to this address with these output bits.
    Exchange(Address, Nibble),
    /// Any other call.
    Call(Call),
}

impl Told {
    #[inline(always)]
    fn of(req: Request) -> Told {
        match req.as_data_exchange() {
            Some((a, data)) => Told::Exchange(a, data),
            // CB 1, I4..I0 = 11110: Read_Status of an A (or single) slave at any address,
            // the call the master's cycle makes once (asi-phy's decoder, `Request::call`;
            // held to it for every request by the test below).
            None if req.cb() && req.info() == 0b11110 => Told::Call(Call::ReadStatus {
                address: req.address(),
                select: asi_phy::Select::A,
            }),
            None => Told::Call(req.call()),
        }
    }
}

#[cfg(test)]
mod told_tests {
    use super::*;

    /// Every request the 14 bits can hold is told as its call: a Data_Exchange by its
    /// address and data, every other call as `Request::call` decodes it.
    #[test]
    fn every_request_is_told_as_its_call() {
        let mut status = 0;
        for bits in 0u16..1 << 14 {
            let Ok(q) = Request::from_bits(bits) else {
                continue;
            };
            let want = match q.call() {
                Call::DataExchange { address, data } if q.as_data_exchange().is_some() => {
                    Told::Exchange(address, data)
                }
                call => Told::Call(call),
            };
            status += usize::from(matches!(want, Told::Call(Call::ReadStatus { .. })));
            assert_eq!(Told::of(q), want, "{bits:014b}");
        }
        assert!(status >= 31, "{status} Read_Status requests");
    }
}

/// A slave's place on the bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SlaveId(pub(crate) usize);

/// A monitor's place on the bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct MonitorId(pub(crate) usize);

/// **Decision**: slave ICs work down to 16 V (docs/asi.md §1.1: ~16..33 V); below that
/// they lose power and reset.
pub const SLAVE_MIN_VOLTS: f64 = 16.0;
/// The nominal AS-i supply (§2.2.1 of the lift thesis: 29.5..31.6 V).
pub const NOMINAL_VOLTS: f64 = 30.0;

#[derive(Clone, Debug)]
struct SlaveSlot {
    slave: Slave,
    attached: bool,
}

#[derive(Clone, Debug)]
struct Group {
    listener: Listener,
    members: u64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    AwaitRequestFrame,
    AwaitResponse,
}

#[derive(Clone, Copy, Debug)]
enum Role {
    Request,
    Response,
}

#[derive(Clone, Copy, Debug)]
struct Current {
    tx: Transmit,
    start: SimTime,
    req_end: SimTime,
    request_failed: Checks,
    request_frames: u32,
    responses: u32,
    response_failed: Checks,
    response: Option<Response>,
    line_end: SimTime,
    line_error: bool,
    /// Its telegrams are held off the line ([`Bus::may_run_quick`]).
    quick: bool,
}

impl Current {
    /// Transaction `tx`, its request from `start` to `req_end`, nothing heard yet; `quick`
    /// if its telegrams are held off the line.
    fn new(tx: Transmit, start: SimTime, req_end: SimTime, quick: bool) -> Current {
        Current {
            tx,
            start,
            req_end,
            request_failed: Checks::NONE,
            request_frames: 0,
            responses: 0,
            response_failed: Checks::NONE,
            response: None,
            line_end: req_end,
            line_error: false,
            quick,
        }
    }

    /// The master's receiver `rx` hears frame `f` of the answering side: a frame that starts
    /// within the response window counts as a response (a second one makes the outcome
    /// corrupt, as does any that fails a check).
    fn master_hears(&mut self, rx: &mut Listener, timing: &BusTiming, f: &Frame) {
        self.master_hears_as(rx, timing, f, Received::response);
    }

    /// [`Current::master_hears`], with `decode` telling the response a valid telegram is
    /// ([`Received::response`], or the answer a held frame was made of).
    #[inline(always)]
    fn master_hears_as(
        &mut self,
        rx: &mut Listener,
        timing: &BusTiming,
        f: &Frame,
        decode: impl FnOnce(&Received) -> Option<Response>,
    ) {
        let window_end = self.req_end + timing.response_timeout();
        if f.start > self.req_end && f.start <= window_end {
            let r = rx.accept(f);
            self.responses += 1;
            self.line_error |= !r.is_valid();
            if r.is_valid() && self.responses == 1 {
                self.response = decode(&r);
            } else {
                self.response = None;
                self.response_failed = cur_checks(self.response_failed, r.failed);
            }
        }
    }
}

/// Callback sink for trace records.
pub type TraceCallback = Box<dyn FnMut(&TransactionRecord) + Send>;

/// The bus's trace callback, a writer of the one bus it was given to: a copy of the bus
/// (a snapshot) has none.
#[derive(Default)]
struct Callback(Option<TraceCallback>);

impl Clone for Callback {
    fn clone(&self) -> Callback {
        Callback(None)
    }
}

/// An AS-i segment: master, slaves, line, passive monitors.
///
/// A copy ([`Clone`]) goes on exactly as the original from the moment it was taken (the same
/// transactions, the same line noise); it has no trace callback ([`Bus::set_trace_callback`]).
#[derive(Clone)]
pub struct Bus {
    timing: BusTiming,
    /// `timing.transaction()`, worked out once: the timing of a bus never changes, and the
    /// quick path needs it at every transaction.
    transaction: SimDuration,
    /// From the first pulse of a request to its last, and of a response
    /// ([`quick::last_pulse`]), worked out once as `transaction` is.
    request_last: SimDuration,
    response_last: SimDuration,
    /// From a quick request's first pulse to its frame's event: `request_last` and the pause
    /// after it (time saturates, so adding the two at once is adding each in turn).
    request_event: SimDuration,
    master: Master,
    slaves: Vec<SlaveSlot>,
    addr_index: [u64; 32],
    medium: Medium,
    /// The medium is plain ([`Medium::is_plain`]): a telegram passes its faults untouched
    /// without a draw, and the line takes it clean when it is idle. Worked out again
    /// wherever the bus arms faults, records or sets the pulse-exact mode
    /// ([`Bus::line_changed`]), and after a telegram went on the line (which may use up a
    /// one-shot fault); `false` only costs the full check.
    line_plain: bool,
    master_rx: Listener,
    groups: Vec<Group>,
    monitors: Vec<SafetyMonitor>,
    state: State,
    now: SimTime,
    next_event: SimTime,
    /// The last time (inclusive) the current `advance_to`/`advance_before` call may process
    /// events at: a quick transaction goes on to its next event at once when it falls within.
    horizon: SimTime,
    /// The frame of a quick transaction's telegram held off the line ([`Bus::may_run_quick`]):
    /// the frame the clean line would hand on.
    held: Option<Frame>,
    /// The slave's answer that `held` was made of, while it is held.
    held_answer: Option<Response>,
    /// The first monitor's receiver is in the state of the slaves' receiver, so it takes each
    /// frame of a quick transaction as that one does (`quick::hear_in_step`). They hear the
    /// same frames from then on; whatever may change the slaves' receivers (power, plugging,
    /// a new slave) releases the held telegrams first, which clears this, as a new monitor
    /// and the application's access to a monitor do.
    monitor_in_step: bool,
    /// The receivers' state a run of clean quick transactions has left, while it is not yet
    /// written into them ([`quick::Unsettled`]): only within an `advance_to` or
    /// `advance_before` call.
    unsettled: Option<quick::Unsettled>,
    volts: f64,
    slaves_powered: bool,
    cur: Option<Current>,
    /// The statistics per slave, counted at every transaction; the bus-wide counts of
    /// [`Bus::stats`] are their sums.
    tally: SlaveTable,
    /// What the application watches: where [`Bus::advance_before`] ends early.
    watch: Watch,
    /// The last output nibble each address took in a Data_Exchange.
    last_out: [u8; 32],
    /// A watched address took a new output nibble in the current event.
    output_taken: bool,
    /// The drive count ([`Bus::drive_count`]): the calls into the slaves in which what a
    /// counting device drives may have changed, and the application's mutable accesses and
    /// fault hooks, which may change anything.
    drive_total: u64,
    /// A slave's device counts its drive changes ([`Slave::drive_counted`]).
    drive_counted: bool,
    /// The drive count when the bus last looked ([`Watch::drives_only_through`]).
    drive_seen: u64,
    ring: Option<TraceRing>,
    callback: Callback,
    /// The frames of a response, kept between transactions so that none allocates.
    response_frames: Vec<Frame>,
}

impl core::fmt::Debug for Bus {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Bus")
            .field("now", &self.now)
            .field("phase", &self.master.phase())
            .field("slaves", &self.slaves.len())
            .finish()
    }
}

impl Bus {
    /// A bus with a master of `cfg` and `projected` configuration and these `slaves`, all
    /// powered up at time 0.
    pub fn new(
        cfg: MasterConfig,
        projected: ProjectedConfig,
        slaves: Vec<Slave>,
    ) -> Result<Bus, ConfigError> {
        let timing = cfg.timing;
        let master = Master::new(cfg, projected)?;
        let mut bus = Bus {
            timing,
            transaction: timing.transaction(),
            request_last: quick::last_pulse(timing.half_bit(), Request::BITS),
            response_last: quick::last_pulse(timing.half_bit(), Response::BITS),
            request_event: quick::last_pulse(timing.half_bit(), Request::BITS) + timing.min_pause(),
            master_rx: Listener::new(&timing.receiver(Expect::Responses)),
            medium: Medium::quiet(&timing),
            line_plain: true,
            master,
            slaves: Vec::new(),
            addr_index: [0; 32],
            groups: Vec::new(),
            monitors: Vec::new(),
            state: State::Idle,
            now: SimTime::ZERO,
            next_event: SimTime::ZERO,
            horizon: SimTime::ZERO,
            held: None,
            held_answer: None,
            monitor_in_step: false,
            unsettled: None,
            volts: NOMINAL_VOLTS,
            slaves_powered: true,
            cur: None,
            tally: SlaveTable::default(),
            watch: Watch::default(),
            last_out: [NO_OUTPUT; 32],
            output_taken: false,
            drive_total: 0,
            drive_counted: false,
            drive_seen: 0,
            ring: None,
            callback: Callback(None),
            response_frames: Vec::new(),
        };
        for s in slaves {
            bus.add_slave(s)?;
        }
        bus.reschedule_idle();
        Ok(bus)
    }

    /// Adds a slave, attached and powered (it gets a fresh receiver).
    pub fn add_slave(&mut self, mut slave: Slave) -> Result<SlaveId, ConfigError> {
        self.release_held();
        if self.slaves.len() >= 64 {
            return Err(ConfigError::TooManyDevices(self.slaves.len() + 1));
        }
        slave.reset();
        let id = self.slaves.len();
        self.slaves.push(SlaveSlot {
            slave,
            attached: true,
        });
        self.drive_counted |= self.slaves[id].slave.drive_counted();

        self.join(id);
        self.reindex();
        Ok(SlaveId(id))
    }

    /// Adds a passive monitor that hears every frame.
    pub fn add_monitor(&mut self, m: SafetyMonitor) -> MonitorId {
        self.monitor_in_step = false;
        self.monitors.push(m);
        MonitorId(self.monitors.len() - 1)
    }

    fn join(&mut self, id: usize) {
        self.groups.push(Group {
            listener: Listener::new(&self.timing.receiver(Expect::Both)),
            members: 1 << id,
        });
    }

    fn leave(&mut self, id: usize) {
        for g in &mut self.groups {
            g.members &= !(1 << id);
        }
        self.groups.retain(|g| g.members != 0);
    }

    fn reindex(&mut self) {
        self.addr_index = [0; 32];
        for (i, s) in self.slaves.iter().enumerate() {
            self.addr_index[s.slave.addr().number() as usize] |= 1 << i;
        }
    }

    // ----- the event loop -------------------------------------------------------------

    /// The time of the next bus event ([`SimTime::MAX`] if the bus waits for the application,
    /// e.g. without power).
    pub fn poll_at(&self) -> SimTime {
        self.next_event
    }

    /// The bus time: the last time given to [`Bus::advance_to`].
    pub fn now(&self) -> SimTime {
        self.now
    }

    /// Processes every event up to and including `now`. A new output a watched slave took in
    /// them ([`Watch::outputs`]) is the caller's to hand on now: it does not end the next
    /// [`Bus::advance_before`] early.
    pub fn advance_to(&mut self, now: SimTime) {
        self.run_to(now);
        self.settle();
    }

    /// [`Bus::advance_to`], the receivers left unsettled ([`Bus::settle`]); `true` if a
    /// watched slave took a new output nibble in it (one that did not pass,
    /// [`Watch::drives_only_through`]).
    #[inline]
    fn run_to(&mut self, now: SimTime) -> bool {
        self.horizon = now;
        self.events_through(now, false);
        let taken = core::mem::take(&mut self.output_taken);
        if now > self.now {
            self.now = now;
            for m in &mut self.monitors {
                m.poll(now);
            }
        }
        taken
    }

    /// Processes the events before `until`, returning early where something the application
    /// watches ([`Bus::watch`]) happened ([`Stop`]); `None` when every event before `until` is
    /// done. The bus's time stays at the last event processed, so an application that drives
    /// the bus this way runs long stretches without stepping at every event, and still sees
    /// every change it watches at its moment.
    pub fn advance_before(&mut self, until: SimTime) -> Option<Stop> {
        let stop = match self.watch.look {
            Some(w) => self.run_watching(w, until),
            None => self.run_before(until).map(Stop::Output),
        };
        self.settle();
        stop
    }

    /// [`Bus::advance_before`], the receivers left unsettled ([`Bus::settle`]).
    #[inline]
    fn run_before(&mut self, until: SimTime) -> Option<SimTime> {
        // Nothing comes before time zero.
        let last = until.as_nanos().checked_sub(1)?;
        self.horizon = SimTime::from_nanos(last);
        if self.events_through(self.horizon, true) {
            self.output_taken = false;
            return Some(self.now);
        }
        None
    }

    /// Processes the events up to `last` (inclusive) one after another; with `stop_at_output`,
    /// returns `true` after the first in which a watched slave took a new output (the note
    /// left set). The event is inlined into this one loop, so that the many events of a long
    /// call do not each pay a call of their own.
    #[inline(never)]
    fn events_through(&mut self, last: SimTime, stop_at_output: bool) -> bool {
        while self.next_event <= last {
            self.event();
            if stop_at_output && self.output_taken {
                return true;
            }
        }
        false
    }

    /// Processes the next event. A transaction is started at one place only, so that
    /// [`Bus::start_transaction`] (and with it the quick transaction that most starts run to
    /// its end) is inlined here rather than called.
    #[inline(always)]
    fn event(&mut self) {
        let t = self.next_event;
        self.now = t;
        let start = match self.state {
            State::Idle => true,
            State::AwaitRequestFrame => {
                self.request_frame(t);
                false
            }
            State::AwaitResponse => match self.finish_transaction(t) {
                Some(resync) if resync > t => {
                    self.state = State::Idle;
                    self.next_event = resync;
                    false
                }
                _ => true,
            },
        };
        if start {
            self.start_transaction(t);
        }
    }

    fn reschedule_idle(&mut self) {
        if self.state == State::Idle {
            self.next_event = self.master.poll_at(self.now).unwrap_or(SimTime::MAX);
        }
    }

    #[inline(always)]
    fn start_transaction(&mut self, t: SimTime) {
        // Mostly one monitor (the lab bus) or none: those without the loop.
        match self.monitors.as_mut_slice() {
            [] => {}
            [m] => m.poll(t),
            all => {
                for m in all {
                    m.poll(t);
                }
            }
        }
        let Some(tx) = self.master.poll_transmit(t) else {
            self.state = State::Idle;
            self.next_event = self.master.poll_at(t).unwrap_or(SimTime::MAX);
            return;
        };
        if let Some(who) = self
            .may_run_quick(tx.request)
            .filter(|_| self.line_takes_clean(tx.request, t))
        {
            // As the clean line would: the frame at its end plus the pause. The frame itself
            // ([`quick::request_frame`]) is built only where the bus keeps it.
            let end = t + self.request_last;
            let cur = Current::new(tx, t, end, true);
            let at = t + self.request_event;
            debug_assert_eq!(at, (end + self.timing.min_pause()).max(t));
            if at <= self.horizon && !self.output_taken {
                // Its request frame's event falls within: the transaction goes on at once,
                // held in locals rather than in the bus until it has to wait.
                self.now = at;
                self.quick_from(at, cur, who);
            } else {
                self.cur = Some(cur);
                self.held = Some(quick::request_frame(tx.request, t, self.request_last));
                self.state = State::AwaitRequestFrame;
                self.next_event = at;
            }
            return;
        }
        let tg = Transmission::request(tx.request, t, self.timing.half_bit());
        let req_end = tg.end();
        self.cur = Some(Current::new(tx, t, req_end, false));
        let mut frames: [Option<Frame>; 4] = [None; 4];
        let mut n = 0;
        self.medium.transmit(&tg, &mut |f| {
            if n < frames.len() {
                frames[n] = Some(f);
                n += 1;
            }
        });
        self.line_changed();
        // Borrowed: moving the array out would copy all four slots for every request.
        for f in frames[..n].iter().flatten() {
            self.hear(t, f, Role::Request);
        }
        self.state = State::AwaitRequestFrame;
        self.next_event = self
            .medium
            .poll_at()
            .unwrap_or(req_end + self.timing.min_pause())
            .max(t);
    }

    /// [`Medium::takes_clean`] of request `q` sent at `t`: on a plain line
    /// ([`Bus::line_plain`]) only whether it is idle.
    #[inline(always)]
    fn line_takes_clean(&mut self, q: Request, t: SimTime) -> bool {
        debug_assert!(
            !self.line_plain || self.medium.is_plain(),
            "line_plain is stale"
        );
        if self.line_plain {
            self.medium.is_idle()
        } else {
            self.medium
                .takes_clean(&Transmission::request(q, t, self.timing.half_bit()))
        }
    }

    /// Works out [`Bus::line_plain`] again, after the medium changed.
    fn line_changed(&mut self) {
        self.line_plain = self.medium.is_plain();
    }

    fn request_frame(&mut self, t: SimTime) {
        if self.cur.is_some_and(|c| c.quick) {
            self.quick_request(t);
            return;
        }
        if let Some(f) = self.medium.poll(t) {
            self.hear(t, &f, Role::Request);
        }
        let Some(cur) = self.cur else {
            self.state = State::Idle;
            self.reschedule_idle();
            return;
        };
        self.state = State::AwaitResponse;
        let base = cur.start + self.transaction;
        let quiet = self
            .medium
            .poll_at()
            .map(|p| p + (self.timing.slave_pause() - self.timing.min_pause()));
        self.next_event = quiet.map_or(base, |q| q.max(base)).max(t);
    }

    /// Ends the transaction; returns the earliest start of the next request when the line
    /// carried an error (the receivers need the asynchronous pause to resynchronise).
    fn finish_transaction(&mut self, t: SimTime) -> Option<SimTime> {
        if self.cur.is_some_and(|c| c.quick) {
            return self.quick_finish(t);
        }
        if let Some(f) = self.medium.poll(t) {
            self.hear(t, &f, Role::Response);
        }
        let cur = self.cur.take()?;
        self.close(t, &cur)
    }

    /// The master judges transaction `cur` at `t`, and it is counted and traced; returns the
    /// earliest start of the next request when the line carried an error.
    #[inline(always)]
    fn close(&mut self, t: SimTime, cur: &Current) -> Option<SimTime> {
        let outcome = match (cur.responses, cur.response) {
            (0, _) => Outcome::NoResponse,
            (1, Some(r)) => Outcome::Response(r),
            _ => Outcome::Corrupt(if cur.response_failed.is_empty() {
                Checks::only(asi_phy::Check::Length)
            } else {
                cur.response_failed
            }),
        };
        let verdict = self.master.handle_outcome(t, outcome);
        let response_failed = match outcome {
            Outcome::Corrupt(c) => c,
            _ => Checks::NONE,
        };
        let no_response = outcome == Outcome::NoResponse;
        let response = match outcome {
            Outcome::Response(r) => Some(r),
            _ => None,
        };
        debug_assert_eq!(
            cur.tx.slave,
            asi_master::slave_stats::slave_of(cur.tx.request, cur.tx.ab),
            "the master's slave of {:?}",
            cur.tx
        );
        // What `SlaveTable::record` counts of the record, without the record. Almost every
        // call is a clean, answered Data_Exchange, the cycle's Read_Status or its probe of
        // an empty address: one call more.
        // Only other calls and faults can change LAS or the phase; the light windows are
        // closed at the management call every cycle has, and at those.
        let first_try = !cur.tx.repeat && cur.request_failed.is_empty();
        let clean = first_try && response.is_some();
        match cur.tx.kind {
            TxKind::DataExchange if clean => self.tally.count_clean(cur.tx.slave),
            TxKind::Management if clean => {
                self.tally.count_clean(cur.tx.slave);
                if self.tally.window_due(t) {
                    self.note_master(t);
                }
            }
            // The probe of an empty address, once a cycle: it changes neither LAS nor the
            // phase.
            TxKind::Inclusion if first_try && no_response && !verdict.error => {
                self.tally.count_silent(cur.tx.slave)
            }
            _ => self.note_call(t, cur, outcome, verdict),
        }
        // Most runs keep no record: no ring, no callback, no subscriber at TRACE. The record
        // is then only counted, and never stored for them. `tracing::trace!` itself checks
        // first that TRACE is within the static and the current maximum level (its
        // `level_enabled!`), and does nothing else when it is not (without the `log` feature,
        // which asi-lift does not turn on); the same test here lets every subscriber that
        // could see the event see it.
        let traced = tracing::Level::TRACE <= tracing::level_filters::STATIC_MAX_LEVEL
            && tracing::Level::TRACE <= tracing::level_filters::LevelFilter::current();
        if traced || self.ring.is_some() || self.callback.0.is_some() {
            self.publish(TransactionRecord {
                start: cur.start,
                kind: cur.tx.kind,
                request: cur.tx.request,
                request_failed: cur.request_failed,
                response,
                response_failed,
                no_response,
                repeat: cur.tx.repeat,
                ab: cur.tx.ab,
            });
        }
        cur.line_error
            .then(|| cur.line_end + self.timing.async_pause())
    }

    /// Transaction `cur`, its `outcome` and the master's `verdict`, as the statistics per
    /// slave count it when it is not a clean Data_Exchange or Read_Status: the call, the codes
    /// an answer to a start-up, inclusion or host call shows, the master's LAS and phase after
    /// it and the light windows ended ([`Bus::note_master`]).
    #[inline(never)]
    fn note_call(&mut self, t: SimTime, cur: &Current, outcome: Outcome, verdict: Verdict) {
        let tx = cur.tx;
        let response = match outcome {
            Outcome::Response(r) => Some(r),
            _ => None,
        };
        let tally = Tally {
            repeat: tx.repeat,
            request_failed: cur.request_failed,
            response_failed: match outcome {
                Outcome::Corrupt(c) => c,
                _ => Checks::NONE,
            },
            response,
            no_response: outcome == Outcome::NoResponse,
            error: verdict.error,
            will_repeat: verdict.repeat,
        };
        self.tally.count(tx.slave, tally);
        if let Some(r) = response {
            if !matches!(tx.kind, TxKind::DataExchange | TxKind::Management) {
                self.tally.note_codes(tx.slave, tx.request, r);
            }
        }
        self.note_master(t);
    }

    /// The master's LAS and phase at `t` to the statistics per slave (drop-outs, time out of
    /// LAS), and the lights of the windows ended by `t`.
    #[inline(never)]
    fn note_master(&mut self, t: SimTime) {
        let las = self.master.las();
        let normal = self.master.phase() == Phase::NormalOperation;
        if self.tally.window_due(t) {
            self.tally.roll(t, las, self.master.lps(), normal);
        } else {
            self.tally.note_las(t, las, normal);
        }
    }

    /// Trace record `rec` to `tracing` (target `asi_master::trace`, level TRACE), to the ring
    /// and to the callback.
    #[inline(never)]
    fn publish(&mut self, rec: TransactionRecord) {
        tracing::trace!(target: "asi_master::trace", "{rec}");
        if let Some(r) = &mut self.ring {
            r.push(rec);
        }
        if let Some(cb) = &mut self.callback.0 {
            cb(&rec);
        }
    }

    /// Every receiver on the line hears frame `f` at `now`. The transaction in progress is
    /// updated in place: `respond` may hear the answer's frames before this returns.
    fn hear(&mut self, now: SimTime, f: &Frame, role: Role) {
        self.settle();
        let Some(cur) = self.cur.as_mut() else {
            return;
        };
        cur.line_end = cur.line_end.max(f.end);
        let is_request = matches!(role, Role::Request);
        if !is_request {
            cur.master_hears(&mut self.master_rx, &self.timing, f);
        }
        if !f.line_failed.is_empty() && !self.groups.is_empty() {
            cur.line_error = true;
        }
        let mut responders = 0u64;
        let mut request = None;
        for (gi, g) in self.groups.iter_mut().enumerate() {
            let r = g.listener.accept(f);
            if is_request {
                if gi == 0 {
                    cur.request_frames += 1;
                    cur.request_failed = cur_checks(cur.request_failed, r.failed);
                }
                if let Some(q) = r.request() {
                    let mask = if q.is_broadcast_reset() {
                        u64::MAX
                    } else {
                        self.addr_index[q.address().get() as usize]
                    };
                    responders |= g.members & mask;
                    request = Some(q);
                }
            }
        }
        if is_request && cur.request_frames > 1 {
            // A request split in pieces is no request.
            request = None;
        }
        if self.groups.len() > 1 {
            self.merge_groups();
        }
        for m in &mut self.monitors {
            m.on_frame(now, f);
        }
        if let (Some(q), true) = (request, responders != 0 && self.slaves_powered) {
            self.respond(now, f.end, q, responders);
        }
    }

    /// Merges slave groups whose listeners have come to the same state: from then on they
    /// react alike to every frame.
    fn merge_groups(&mut self) {
        let mut i = self.groups.len();
        while i > 1 {
            i -= 1;
            if let Some(j) = (0..i).find(|&j| self.groups[j].listener == self.groups[i].listener) {
                let m = self.groups[i].members;
                self.groups[j].members |= m;
                self.groups.remove(i);
            }
        }
    }

    fn respond(&mut self, now: SimTime, req_end: SimTime, req: Request, who: u64) {
        let start = req_end + self.timing.master_pause();
        let h = self.timing.half_bit();
        // Up to four answers without allocating; more are rare (a collision of many).
        let mut answers = [Transmission::new(0, 0, start, h); 4];
        let mut n = 0usize;
        let mut extra = Vec::new();
        self.ask_slaves(now, req, who, |r| {
            let tg = Transmission::response(r, start, h);
            match answers.get_mut(n) {
                Some(slot) => *slot = tg,
                None => extra.push(tg),
            }
            n += 1;
        });
        if extra.is_empty() {
            self.transmit_answers(now, &answers[..n]);
        } else {
            let all: Vec<Transmission> = answers.iter().copied().chain(extra).collect();
            self.transmit_answers(now, &all);
        }
    }

    /// The slaves' answers `answers` go on the line at once (superimposed when there is more
    /// than one); the frames the line hands on now are heard at `now`.
    fn transmit_answers(&mut self, now: SimTime, answers: &[Transmission]) {
        let mut frames = core::mem::take(&mut self.response_frames);
        frames.clear();
        let mut collect = |f| frames.push(f);
        match answers {
            [] => {}
            [tg] => self.medium.transmit(tg, &mut collect),
            _ => {
                let all: Vec<PulseTrain> = answers.iter().map(Transmission::train).collect();
                self.medium.transmit_merged(&all, &mut collect);
            }
        }
        self.line_changed();
        for f in &frames {
            self.hear(now, f, Role::Response);
        }
        self.response_frames = frames;
    }

    /// The attached slaves among `who` take request `req` at `now`; `answer` gets each
    /// answer, in the order of the slaves. What the call changes on the bus's side follows:
    /// the outputs noted for the plant, the address index after a new address or a reset.
    fn ask_slaves(
        &mut self,
        now: SimTime,
        req: Request,
        mut who: u64,
        mut answer: impl FnMut(Response),
    ) {
        let mut readdressed = false;
        // A Data_Exchange (told from its bits) never changes an address.
        let told = Told::of(req);
        let exchange = matches!(told, Told::Exchange(..));
        let mut moved = false;
        while who != 0 {
            let i = who.trailing_zeros() as usize;
            who &= who - 1;
            let Some(slot) = self.slaves.get_mut(i) else {
                continue;
            };
            if !slot.attached {
                continue;
            }
            let before = (!exchange).then(|| slot.slave.addr());
            let r = slot.slave.handle(now, req);
            moved |= slot.slave.take_drive_moved();
            readdressed |= before.is_some_and(|b| slot.slave.addr() != b);
            if let Some(r) = r {
                answer(r);
            }
        }
        self.drive_total += u64::from(moved);
        self.note_output(req, told);
        let reset = matches!(
            told,
            Told::Call(Call::BroadcastReset | Call::ResetSlave { .. })
        );
        if readdressed || reset {
            self.reindex();
        }
    }
}

fn cur_checks(acc: Checks, new: Checks) -> Checks {
    acc | new
}
