//! The statistics fed by every transaction record of a bus run: cycles, transaction spacing,
//! per-slave update periods, repeats, the error model's expectation for the telegrams sent, and
//! the converter's run bit as seen on the bus.

use super::error_model::{Expect, LineNoise};
use super::stats::Summary;
use asi_master::{TransactionRecord, TxKind};
use asi_phy::{BusTiming, Call, PulseTrain, Request, Response, Select, SimDuration, SimTime};
use std::collections::HashMap;
use std::sync::{Mutex, MutexGuard};

/// The statistics fed by every transaction record.
#[derive(Debug)]
pub(super) struct Collector {
    half_bit: SimDuration,
    pub(super) noise: LineNoise,
    converter: Option<u8>,
    active: bool,
    last_kind: Option<TxKind>,
    prev_start: Option<SimTime>,
    cycle_start: Option<SimTime>,
    pending: Option<(TransactionRecord, bool)>,
    responses: HashMap<u16, u32>,
    response_pulses: Summary,
    // The open cycle.
    cur: Expect,
    cur_first: u64,
    cur_repeats: u64,
    // Committed complete cycles.
    pub(super) cycles: Vec<u64>,
    pub(super) expect: Expect,
    pub(super) first_tries: u64,
    pub(super) repeats: u64,
    pub(super) spacing: Summary,
    last_ok: HashMap<(u8, bool), SimTime>,
    pub(super) update: Summary,
    // The converter's run bit as the slave last took it, and its rising edges on the bus.
    run: bool,
    pub(super) run_rises: Vec<SimTime>,
}

impl Collector {
    pub(super) fn new(
        timing: &BusTiming,
        pulse_error_rate: f64,
        converter: Option<u8>,
    ) -> Collector {
        Collector {
            half_bit: timing.half_bit(),
            noise: LineNoise::new(timing, pulse_error_rate),
            converter,
            active: false,
            last_kind: None,
            prev_start: None,
            cycle_start: None,
            pending: None,
            responses: HashMap::new(),
            response_pulses: Summary::default(),
            cur: Expect::default(),
            cur_first: 0,
            cur_repeats: 0,
            cycles: Vec::new(),
            expect: Expect::default(),
            first_tries: 0,
            repeats: 0,
            spacing: Summary::default(),
            last_ok: HashMap::new(),
            update: Summary::default(),
            run: false,
            run_rises: Vec::new(),
        }
    }

    pub(super) fn start_window(&mut self) {
        self.active = true;
        self.prev_start = None;
        self.cycle_start = None;
        self.pending = None;
        self.last_ok.clear();
    }

    pub(super) fn end_window(&mut self) {
        self.active = false;
        self.pending = None;
    }

    pub(super) fn record(&mut self, r: &TransactionRecord) {
        self.watch_converter(r);
        if let Some((p, in_cycle)) = self.pending.take() {
            self.resolve(&p, r.repeat.then_some(r), in_cycle);
        }
        let boundary = r.kind == TxKind::DataExchange
            && !r.repeat
            && self.last_kind.is_some_and(|k| k != TxKind::DataExchange);
        self.last_kind = Some(r.kind);
        if !self.active {
            return;
        }
        if boundary {
            if let Some(s) = self.cycle_start {
                self.cycles.push((r.start - s).as_nanos());
                self.expect.add(&self.cur);
                self.first_tries += self.cur_first;
                self.repeats += self.cur_repeats;
            }
            self.cycle_start = Some(r.start);
            self.cur = Expect::default();
            self.cur_first = 0;
            self.cur_repeats = 0;
        }
        if let Some(p) = self.prev_start {
            self.spacing.add((r.start - p).as_nanos() as f64);
        }
        self.prev_start = Some(r.start);
        if r.repeat {
            self.cur_repeats += 1;
        } else {
            self.cur_first += 1;
            self.pending = Some((*r, self.cycle_start.is_some()));
        }
        let exchange = r.kind == TxKind::DataExchange && r.response.is_some();
        if let (Call::DataExchange { address, .. }, true) = (r.request.call(), exchange) {
            let b = r.ab && r.request.ab_payload().is_some_and(|(s, _)| s == Select::B);
            if let Some(last) = self.last_ok.insert((address.get(), b), r.start) {
                self.update.add((r.start - last).as_nanos() as f64);
            }
        }
    }

    fn watch_converter(&mut self, r: &TransactionRecord) {
        let Some(conv) = self.converter else {
            return;
        };
        if let Call::DataExchange { address, data } = r.request.call() {
            if address.get() == conv && r.request_failed.is_empty() {
                let run = data.bit(0);
                if run && !self.run {
                    self.run_rises.push(r.start);
                }
                self.run = run;
            }
        }
    }

    fn request_pulses(&self, q: Request) -> u32 {
        PulseTrain::request(q, SimTime::ZERO, self.half_bit).len()
    }

    fn response_pulses_of(&self, r: Response) -> u32 {
        PulseTrain::response(r, SimTime::ZERO, self.half_bit).len()
    }

    /// Adds the error model's expectation for first try `p`; `repeat` is the record after it
    /// if that is its repeat.
    fn resolve(
        &mut self,
        p: &TransactionRecord,
        repeat: Option<&TransactionRecord>,
        in_cycle: bool,
    ) {
        let bits = p.request.bits();
        let known = p
            .response
            .or_else(|| repeat.and_then(|r| r.response))
            .map(|r| self.response_pulses_of(r));
        if let Some(s) = known {
            self.responses.insert(bits, s);
            self.response_pulses.add(s as f64);
        }
        // A first try that failed without a repeat was a probe answered by silence, which is
        // never repeated: it adds nothing.
        let s = match (known, p.response.is_some() || repeat.is_some()) {
            (Some(s), _) => s,
            (None, true) => self.responses.get(&bits).copied().unwrap_or_else(|| {
                if self.response_pulses.n > 0 {
                    (self.response_pulses.sum / self.response_pulses.n as f64).round() as u32
                } else {
                    12
                }
            }),
            (None, false) => return,
        };
        if !in_cycle {
            return;
        }
        let m = self.request_pulses(p.request);
        let data_exchange = matches!(p.request.call(), Call::DataExchange { .. });
        let e = self.noise.first_try(m, s, data_exchange);
        self.cur.add(&e);
    }
}

pub(super) fn lock(c: &Mutex<Collector>) -> MutexGuard<'_, Collector> {
    c.lock().unwrap_or_else(|e| e.into_inner())
}

/// The statistics out of their shared place (the bus holds a clone of it until its trace
/// callback is removed).
pub(super) fn take(shared: &Mutex<Collector>) -> Collector {
    std::mem::replace(
        &mut *lock(shared),
        Collector::new(&BusTiming::default(), 0.0, None),
    )
}

/// What the bus statistics say about the window.
#[derive(Clone, Debug, Default)]
pub(super) struct BusWindow {
    pub(super) failed_after_repeat: u64,
    pub(super) dropouts: u64,
    /// The statistics per slave over the window.
    pub(super) slaves: Vec<crate::report::SlaveReport>,
    /// Slaves in LAS when the window began.
    pub(super) las_at_start: u32,
}
