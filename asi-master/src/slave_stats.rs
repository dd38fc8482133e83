//! Statistics per slave, as an AS-i analyser shows them (docs/master.md §2.7, with the
//! decision on the traffic light).
//!
//! The AS-Interface Analyser of Bihl+Wiedemann (sold by Siemens as 3RK1 904-3AB01; its
//! manual, "Online Statistics": Overview, Overview with Hold Time, Advanced Statistics,
//! Consecutive Errors, Configuration) listens to the traffic and shows, per slave, the master's
//! calls, the repeats, single against consecutive errors, a traffic light by repeat rate and the
//! configuration read from the traffic. [`SlaveTable`] keeps the same figures for every list
//! place of the master (0..31 standard or A, 1B..31B) and one place for calls to no slave (the
//! broadcast reset), counted per transaction where the bus counts them; the bus-wide
//! [`BusStats`] counts are the sums over the places ([`SlaveTable::totals`]).
//!
//! **The light** ([`LightRule`]): the repeats of a slave over its calls in a window of one
//! second give green below 1 %, yellow from 1 % to 5 %, red above 5 % (the thresholds of the
//! Bihl+Wiedemann diagnostics as the EUCHNER AS-i Safety Monitor manual's table 11-7 gives
//! them; the analyser's rate is per second of telegrams); a slave the master should have in LAS
//! (projected, or once in LAS) and has not at the end of a window, or that dropped out of LAS
//! within it, is red, as the analyser shows a missing slave and a master gone offline. The light shown holds its worst colour for the hold time after the
//! window that caused it (the analyser's "Overview with Hold Time", 1 s to infinite); the
//! worst light of the whole run is kept apart (its "Overview").

use crate::lists::SlaveList;
use crate::record::{BusStats, TransactionRecord};
use asi_phy::{Call, Checks, Nibble, Request, Response, Select, SimDuration, SimTime, SlaveCodes};
use core::fmt;

/// Places in a [`SlaveTable`]: the 64 list bits (0..31 = 0A..31A, 32..63 = 0B..31B) and
/// [`NO_SLAVE`].
pub const PLACES: usize = 65;

/// The place of a call addressed to no single slave (the broadcast reset).
pub const NO_SLAVE: u8 = 64;

/// The list bit of the slave request `request` is for (0..31 standard or A, 33..63 B), or
/// [`NO_SLAVE`]. `ab` says that a Data_Exchange or Write_Parameter goes to an A/B slave, whose
/// I3 is then the select bit (1 = A, docs/master.md); Address_Assignment and
/// Write_Extended_ID1 go to address 0.
#[inline(always)]
pub fn slave_of(request: Request, ab: bool) -> u8 {
    match request.as_data_exchange() {
        Some((a, data)) => place(a.get(), ab && data.get() & 0x8 == 0),
        None => slave_of_call(request, ab),
    }
}

/// [`slave_of`] of a request that is not a Data_Exchange.
fn slave_of_call(request: Request, ab: bool) -> u8 {
    match request.call() {
        Call::DataExchange { address, data } => place(address.get(), ab && data.get() & 0x8 == 0),
        Call::WriteParameter { address, parameter } => {
            place(address.get(), ab && parameter.get() & 0x8 == 0)
        }
        Call::AddressAssignment { .. } | Call::WriteExtendedId1 { .. } => 0,
        Call::DeleteAddress { address, select }
        | Call::ResetSlave { address, select }
        | Call::ReadIoConfiguration { address, select }
        | Call::ReadIdCode { address, select }
        | Call::ReadId1 { address, select }
        | Call::ReadId2 { address, select }
        | Call::ReadStatus { address, select } => place(address.get(), select == Select::B),
        Call::BroadcastReset => NO_SLAVE,
        Call::Unknown { address, .. } => address.get(),
    }
}

/// The list bit of address `n`, B if `b` (0B does not exist: address 0 is always 0A).
#[inline(always)]
const fn place(n: u8, b: bool) -> u8 {
    if b && n != 0 {
        32 + (n & 31)
    } else {
        n & 31
    }
}

/// The colour of a slave's traffic light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Light {
    /// Repeats below the yellow threshold: the repeats put right momentary telegram errors.
    Green,
    /// Repeats from the yellow threshold up to the red one: the slave communicates "with
    /// effort" (a bad cable, an earth fault, EMC).
    Yellow,
    /// Repeats above the red threshold, or a slave the master should have in LAS and has not.
    Red,
}

impl Light {
    /// `green`, `yellow` or `red`.
    pub const fn name(self) -> &'static str {
        match self {
            Light::Green => "green",
            Light::Yellow => "yellow",
            Light::Red => "red",
        }
    }
}

impl fmt::Display for Light {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How the light is worked out (**Decision**, docs/master.md "The traffic light").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightRule {
    /// The window the repeat rate is taken over; the light is evaluated at the end of each.
    pub window: SimDuration,
    /// How long the light shown stays at its worst colour after the window that caused it.
    pub hold: SimDuration,
    /// Yellow from this many repeats per thousand calls.
    pub yellow_from_permille: u32,
    /// Red above this many repeats per thousand calls.
    pub red_above_permille: u32,
}

impl Default for LightRule {
    /// One-second windows, 10 s hold, green below 1 %, yellow 1..5 %, red above 5 %.
    fn default() -> LightRule {
        LightRule {
            window: SimDuration::from_secs(1),
            hold: SimDuration::from_secs(10),
            yellow_from_permille: 10,
            red_above_permille: 50,
        }
    }
}

impl LightRule {
    /// The colour of `repeats` among `calls` (`calls` > 0).
    pub fn colour(&self, repeats: u64, calls: u64) -> Light {
        let per_mille = repeats.saturating_mul(1000);
        if per_mille > calls.saturating_mul(u64::from(self.red_above_permille)) {
            Light::Red
        } else if per_mille >= calls.saturating_mul(u64::from(self.yellow_from_permille)) {
            Light::Yellow
        } else {
            Light::Green
        }
    }
}

/// The identification codes of a slave as its answers to Read_IO_Configuration, Read_ID_Code,
/// Read_ID1 and Read_ID2 showed them in the traffic (the last answer of each), `None` for a
/// code never read.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SeenCodes {
    /// IO configuration.
    pub io: Option<Nibble>,
    /// ID code.
    pub id: Option<Nibble>,
    /// Extended ID code 1.
    pub id1: Option<Nibble>,
    /// Extended ID code 2.
    pub id2: Option<Nibble>,
}

impl SeenCodes {
    /// `true` if no code was seen.
    pub fn is_empty(&self) -> bool {
        *self == SeenCodes::default()
    }

    /// The four codes, once all four were seen.
    pub fn codes(&self) -> Option<SlaveCodes> {
        Some(SlaveCodes {
            io: self.io?,
            id: self.id?,
            id1: self.id1?,
            id2: self.id2?,
        })
    }

    /// `true` if the ID code seen is A (an A/B slave).
    pub fn is_ab(&self) -> bool {
        self.id.is_some_and(|n| n.get() == SlaveCodes::ID_AB)
    }
}

impl fmt::Display for SeenCodes {
    /// As [`SlaveCodes`] writes a profile, `?` for a code never seen: `S-7.0.F (ID1 F)`,
    /// `S-7.?.? (ID1 ?)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let h = |n: Option<Nibble>| n.map_or("?".to_owned(), |n| format!("{:X}", n.get()));
        write!(
            f,
            "S-{}.{}.{} (ID1 {})",
            h(self.io),
            h(self.id),
            h(self.id2),
            h(self.id1)
        )
    }
}

/// One transaction as the per-slave statistics count it: what the bus (or a decoded capture)
/// saw and how the master judged it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tally {
    /// The immediate repeat of a failed transaction.
    pub repeat: bool,
    /// Checks the request failed on the line.
    pub request_failed: Checks,
    /// Checks the response failed in the master's receiver.
    pub response_failed: Checks,
    /// The valid response, if any.
    pub response: Option<Response>,
    /// Nothing answered within the response timeout.
    pub no_response: bool,
    /// The outcome was a fault (a probe of an empty address that gets no response is not).
    pub error: bool,
    /// The transaction is repeated at once.
    pub will_repeat: bool,
}

/// The statistics of one slave (one list place), as the analyser's "Advanced Statistics" and
/// "Consecutive Errors" show them, with its light and the codes seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SlaveStats {
    /// Transactions addressed to it, repeats included (the analyser's master calls).
    pub calls: u64,
    /// Immediate repeats of a failed call.
    pub repeats: u64,
    /// Calls that still failed after their repeat (or were not repeated).
    pub failed_after_repeat: u64,
    /// Errors that followed an error on the same slave (the repeat failed too, and so on).
    pub consecutive_errors: u64,
    /// The most errors in a row (the analyser's worst failure class).
    pub longest_error_run: u32,
    /// Requests the slaves received corrupted, by primary check class (index = check).
    pub request_errors: [u64; 7],
    /// Failed responses by primary check class.
    pub response_errors: [u64; 7],
    /// Calls that got no response where one was due.
    pub no_response: u64,
    /// Times it left LAS while the master stayed in normal operation.
    pub dropouts: u32,
    /// Time out of LAS after those drop-outs, up to its return or the end of normal operation.
    pub out_of_las: SimDuration,
    /// The light shown (with the hold time); `None` before it was first evaluated.
    pub light: Option<Light>,
    /// The worst light since the start.
    pub worst_light: Option<Light>,
    /// The codes its answers showed.
    pub seen: SeenCodes,
    /// Calls without a valid response (faults, and the silence of an empty address).
    unanswered: u64,
    /// Faults among the calls that were no repeat.
    first_try_faults: u64,
    /// Runs of errors begun (an error after a call that was no fault, or the first call),
    /// and those of them that went on to a second error.
    runs: u64,
    long_runs: u64,
    /// The length of the last run of errors, and the call (by `calls`) of its last error.
    error_run: u32,
    last_error: u64,
    /// `calls` and `repeats` at the start of the light window.
    calls_at: u64,
    repeats_at: u64,
    out_since: Option<SimTime>,
    /// It left LAS during the current light window.
    left_in_window: bool,
    held_until: SimTime,
}

impl SlaveStats {
    /// Errors of one check class, requests and responses together.
    pub fn errors(&self, check: asi_phy::Check) -> u64 {
        self.response_errors[check as usize] + self.request_errors[check as usize]
    }

    /// Every call that was a fault: the first of each run of errors, and the consecutive.
    pub fn faults(&self) -> u64 {
        self.runs + self.consecutive_errors
    }

    /// Errors whose next call to the slave was no fault and whose call before was none
    /// either: the repeat put it right. An error that is the last call so far is not yet
    /// counted.
    pub fn single_errors(&self) -> u64 {
        let open = self.last_error == self.calls && self.error_run == 1;
        self.runs - self.long_runs - u64::from(open)
    }

    /// Repeats over calls, in per cent (0 without calls).
    pub fn repeat_percent(&self) -> f64 {
        if self.calls == 0 {
            0.0
        } else {
            self.repeats as f64 * 100.0 / self.calls as f64
        }
    }

    /// Calls that were no repeat and no fault.
    pub fn first_try_ok(&self) -> u64 {
        self.calls - self.repeats - self.first_try_faults
    }

    /// Calls answered with a valid response.
    pub fn answers(&self) -> u64 {
        self.calls - self.unanswered
    }

    /// `true` if it takes part in the traffic: it answered at least once. An address whose
    /// calls are all unanswered (the probes of an empty address, however noise corrupts
    /// them) is an empty address.
    pub fn takes_part(&self) -> bool {
        self.answers() > 0
    }

    /// Counts what a clean call (a valid response to a first try) does not change: repeats,
    /// missing answers, checks failed, faults. `self.calls` counts the call already.
    fn count_rest(&mut self, x: &Tally) {
        self.repeats += u64::from(x.repeat);
        self.unanswered += u64::from(x.response.is_none());
        if let Some(c) = x.request_failed.primary() {
            self.request_errors[c as usize] += 1;
        }
        if let Some(c) = x.response_failed.primary() {
            self.response_errors[c as usize] += 1;
        }
        if !x.error {
            return;
        }
        self.first_try_faults += u64::from(!x.repeat);
        if x.no_response && x.request_failed.is_empty() {
            self.no_response += 1;
        }
        if !x.will_repeat {
            self.failed_after_repeat += 1;
        }
        // Whether the call before was an error is told by its number: calls that were no
        // fault need not end a run.
        if self.last_error != 0 && self.last_error + 1 == self.calls {
            self.consecutive_errors += 1;
            self.error_run += 1;
            if self.error_run == 2 {
                self.long_runs += 1;
            }
        } else {
            self.runs += 1;
            self.error_run = 1;
        }
        self.last_error = self.calls;
        self.longest_error_run = self.longest_error_run.max(self.error_run);
    }
}

/// The statistics of every slave of one bus, its lights, its drop-outs and the codes seen
/// ([`SlaveStats`] per list place).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SlaveTable {
    slaves: [SlaveStats; PLACES],
    /// Clean calls ([`SlaveTable::count_clean`]) and silent first tries
    /// ([`SlaveTable::count_silent`]) per list place, not yet in `slaves`: one compact
    /// counter per call instead of the slave's whole entry. Settled into `slaves` before
    /// anything else of the slave is counted, at every light window and in every copy handed
    /// out ([`SlaveTable::settle`]).
    clean_calls: [u64; 64],
    silent_calls: [u64; 64],
    rule: LightRule,
    /// The end of the current light window.
    window_end: SimTime,
    /// The LAS when last noted, and whether the master was in normal operation.
    las: SlaveList,
    normal: bool,
    /// The master has been in normal operation: from then on a slave it should have in LAS
    /// and has not is red.
    started: bool,
    /// Every slave that has been in LAS in normal operation.
    ever_las: SlaveList,
}

impl Default for SlaveTable {
    fn default() -> SlaveTable {
        SlaveTable::new(LightRule::default())
    }
}

impl SlaveTable {
    /// An empty table whose lights follow `rule`.
    pub fn new(rule: LightRule) -> SlaveTable {
        SlaveTable {
            slaves: [SlaveStats::default(); PLACES],
            clean_calls: [0; 64],
            silent_calls: [0; 64],
            rule,
            window_end: SimTime::ZERO + rule.window,
            las: SlaveList::EMPTY,
            normal: false,
            started: false,
            ever_las: SlaveList::EMPTY,
        }
    }

    /// The light rule.
    pub fn rule(&self) -> LightRule {
        self.rule
    }

    /// Works the lights out by `rule` from the next window on (the current window ends as
    /// it was going to).
    pub fn set_rule(&mut self, rule: LightRule) {
        self.rule = rule;
    }

    /// The clean and silent calls counted apart, into the slaves' entries.
    pub fn settle(&mut self) {
        for i in 0..64 {
            self.settle_place(i);
        }
    }

    fn settle_place(&mut self, i: usize) {
        let (Some(clean), Some(silent)) =
            (self.clean_calls.get_mut(i), self.silent_calls.get_mut(i))
        else {
            return;
        };
        let (clean, silent) = (core::mem::take(clean), core::mem::take(silent));
        let s = &mut self.slaves[i];
        s.calls += clean + silent;
        s.unanswered += silent;
    }

    /// The statistics of list place `i` (0..=63, or [`NO_SLAVE`]), of a settled table (a
    /// bus's table counts its clean calls apart until the next light window; the bus hands
    /// out settled copies, and [`SlaveTable::at`] and [`SlaveTable::since`] settle).
    pub fn get(&self, i: u8) -> Option<&SlaveStats> {
        self.slaves.get(i as usize)
    }

    /// The places with their statistics, 0A..31A, 0B..31B, then [`NO_SLAVE`].
    pub fn iter(&self) -> impl Iterator<Item = (u8, &SlaveStats)> {
        self.slaves.iter().enumerate().map(|(i, s)| (i as u8, s))
    }

    /// Counts transaction `x` to the slave at list place `place` ([`slave_of`] its request).
    pub fn count(&mut self, place: u8, x: Tally) {
        // The call numbers tell runs of errors apart: the calls counted apart come first.
        self.settle_place(usize::from(place));
        let Some(s) = self.slaves.get_mut(place as usize) else {
            return;
        };
        s.calls += 1;
        let clean = x.response.is_some() && !x.repeat && x.request_failed.is_empty();
        if !clean {
            s.count_rest(&x);
        }
    }

    /// [`SlaveTable::count`] of a clean call to the slave at list place `place` (0..=63; a
    /// valid response to a first try, no check failed): one call more.
    #[inline(always)]
    pub fn count_clean(&mut self, place: u8) {
        self.clean_calls[usize::from(place & 63)] += 1;
    }

    /// [`SlaveTable::count`] of a first try to the slave at list place `place` (0..=63) that
    /// nothing answered and that was no fault (the probe of an empty address), no check
    /// failed: one call more, without an answer.
    #[inline(always)]
    pub fn count_silent(&mut self, place: u8) {
        self.silent_calls[usize::from(place & 63)] += 1;
    }

    /// [`SlaveTable::count`] of a trace record, the codes its answer shows included.
    pub fn record(&mut self, r: &TransactionRecord, error: bool, will_repeat: bool) {
        let place = slave_of(r.request, r.ab);
        self.count(
            place,
            Tally {
                repeat: r.repeat,
                request_failed: r.request_failed,
                response_failed: r.response_failed,
                response: r.response,
                no_response: r.no_response,
                error,
                will_repeat,
            },
        );
        if let Some(answer) = r.response {
            self.note_codes(place, r.request, answer);
        }
    }

    /// The answer `r` to `request`, a call to list place `i`: an answered code read is the
    /// analyser's configuration from the traffic (any other call changes nothing).
    pub fn note_codes(&mut self, i: u8, request: Request, r: Response) {
        if request.as_data_exchange().is_some() {
            return;
        }
        let Some(s) = self.slaves.get_mut(i as usize) else {
            return;
        };
        let code = Some(r.data());
        match request.call() {
            Call::ReadIoConfiguration { .. } => s.seen.io = code,
            Call::ReadIdCode { .. } => s.seen.id = code,
            Call::ReadId1 { .. } => s.seen.id1 = code,
            Call::ReadId2 { .. } => s.seen.id2 = code,
            _ => {}
        }
    }

    /// `true` once `t` has reached the end of the light window: [`SlaveTable::roll`] is due.
    #[inline(always)]
    pub fn window_due(&self, t: SimTime) -> bool {
        t >= self.window_end
    }

    /// Evaluates the lights of every window that has ended by `t`, with the master's LAS, LPS
    /// and phase as they are now (`normal`: in normal operation).
    #[inline(never)]
    pub fn roll(&mut self, t: SimTime, las: SlaveList, lps: SlaveList, normal: bool) {
        self.note_las(t, las, normal);
        self.settle();
        let window = self.rule.window.max(SimDuration::from_nanos(1));
        let mut rounds = 0u32;
        while self.window_end <= t {
            let end = self.window_end;
            self.evaluate(end, las, lps);
            self.window_end = end + window;
            rounds += 1;
            if rounds >= 2 && self.window_end <= t {
                // After a long silence (no power) the windows left have no calls and would
                // each give the last one's lights: only the last of them is evaluated, for
                // the hold times that ran out meanwhile.
                let behind = (t.as_nanos() - self.window_end.as_nanos()) / window.as_nanos();
                let last =
                    SimTime::from_nanos(self.window_end.as_nanos() + behind * window.as_nanos());
                self.evaluate(last, las, lps);
                self.window_end = last + window;
            }
        }
    }

    /// The lights at the end `end` of a window.
    fn evaluate(&mut self, end: SimTime, las: SlaveList, lps: SlaveList) {
        let expected = if self.started {
            (lps.bits() | self.ever_las.bits()) & !1
        } else {
            0
        };
        let missing = expected & !las.bits();
        let rule = self.rule;
        for (i, s) in self.slaves.iter_mut().take(64).enumerate() {
            let (calls, repeats) = (s.calls - s.calls_at, s.repeats - s.repeats_at);
            s.calls_at = s.calls;
            s.repeats_at = s.repeats;
            let left = core::mem::take(&mut s.left_in_window);
            let colour = if missing >> i & 1 != 0 || left {
                Light::Red
            } else if calls == 0 || !(s.takes_part() || expected >> i & 1 != 0) {
                continue;
            } else {
                rule.colour(repeats, calls)
            };
            match s.light {
                Some(held) if held > colour && end < s.held_until => {}
                _ => {
                    s.light = Some(colour);
                    s.held_until = end + rule.hold;
                }
            }
            s.worst_light = s.worst_light.max(Some(colour));
        }
    }

    /// The master's LAS at `t`, in normal operation or not: drop-outs and time out of LAS
    /// (a slave that leaves LAS while the master stays in normal operation has dropped out;
    /// leaving normal operation ends every absence without counting a drop-out).
    pub fn note_las(&mut self, t: SimTime, las: SlaveList, normal: bool) {
        if las == self.las && normal == self.normal {
            return;
        }
        if !normal {
            self.close_absences(t);
        } else if self.normal {
            let left = self.las.bits() & !las.bits();
            let back = las.bits() & !self.las.bits();
            let mut changed = left | back;
            while changed != 0 {
                let i = changed.trailing_zeros() as usize;
                changed &= changed - 1;
                let s = &mut self.slaves[i];
                if left >> i & 1 != 0 {
                    s.dropouts += 1;
                    s.out_since = Some(t);
                    s.left_in_window = true;
                } else if let Some(since) = s.out_since.take() {
                    s.out_of_las += t.saturating_duration_since(since);
                }
            }
        }
        if normal {
            self.started = true;
            self.ever_las = SlaveList::from_bits(self.ever_las.bits() | las.bits());
        }
        self.las = las;
        self.normal = normal;
    }

    /// Ends every open absence from LAS at `t`.
    pub fn close_absences(&mut self, t: SimTime) {
        for s in &mut self.slaves {
            if let Some(since) = s.out_since.take() {
                s.out_of_las += t.saturating_duration_since(since);
            }
        }
    }

    /// The bus-wide counts as sums over the places: transactions, repeats, failed after repeat,
    /// errors by check class, no response (the cycle figures and drop-outs are the master's).
    pub fn totals(&self) -> BusStats {
        let mut b = BusStats {
            transactions: self.clean_calls.iter().chain(&self.silent_calls).sum(),
            ..BusStats::default()
        };
        for s in &self.slaves {
            b.transactions += s.calls;
            b.repeats += s.repeats;
            b.failed_after_repeat += s.failed_after_repeat;
            b.no_response += s.no_response;
            for c in 0..7 {
                b.request_errors[c] += s.request_errors[c];
                b.response_errors[c] += s.response_errors[c];
            }
        }
        b
    }

    /// The counts since `earlier` (a copy of this table taken before): calls, repeats, errors,
    /// drop-outs and time out of LAS are differences; the lights, the longest run of errors
    /// and the codes seen are this table's.
    pub fn since(&self, earlier: &SlaveTable) -> SlaveTable {
        let mut t = self.clone();
        t.settle();
        let mut earlier = earlier.clone();
        earlier.settle();
        for (s, e) in t.slaves.iter_mut().zip(earlier.slaves.iter()) {
            let sub = |a: u64, b: u64| a.saturating_sub(b);
            s.calls = sub(s.calls, e.calls);
            s.repeats = sub(s.repeats, e.repeats);
            s.failed_after_repeat = sub(s.failed_after_repeat, e.failed_after_repeat);
            s.consecutive_errors = sub(s.consecutive_errors, e.consecutive_errors);
            s.no_response = sub(s.no_response, e.no_response);
            s.unanswered = sub(s.unanswered, e.unanswered);
            s.first_try_faults = sub(s.first_try_faults, e.first_try_faults);
            s.runs = sub(s.runs, e.runs);
            s.long_runs = sub(s.long_runs, e.long_runs);
            for c in 0..7 {
                s.request_errors[c] = sub(s.request_errors[c], e.request_errors[c]);
                s.response_errors[c] = sub(s.response_errors[c], e.response_errors[c]);
            }
            s.dropouts = s.dropouts.saturating_sub(e.dropouts);
            s.out_of_las = s.out_of_las.saturating_sub(e.out_of_las);
            // The call numbers start again: the last error keeps its place among them.
            s.last_error = sub(s.last_error, e.calls);
        }
        t
    }

    /// The table as it is at `now`: the windows ended by then evaluated, and the absences
    /// from LAS counted up to `now` (left open in the copy's `out_since` no more).
    pub fn at(&self, now: SimTime, las: SlaveList, lps: SlaveList, normal: bool) -> SlaveTable {
        let mut t = self.clone();
        t.roll(now, las, lps, normal);
        t.settle();
        t.close_absences(now);
        t
    }
}

/// `true` if the master judges the transaction of record `r` a fault: no valid response,
/// except the silence that answers a probe of an empty address (Read_IO_Configuration, the
/// only call the master does not repeat when nothing answers; docs/master.md).
pub fn judged_error(r: &TransactionRecord) -> bool {
    r.response.is_none()
        && !(r.no_response && matches!(r.request.call(), Call::ReadIoConfiguration { .. }))
}

/// The statistics per slave of a stream of trace records, as a passive analyser works them
/// out: the master's verdict from the record ([`judged_error`]) and whether it was repeated
/// from the next record. The lights go by the repeat rate alone (a listener does not know
/// the master's LAS).
#[derive(Clone, Debug, Default)]
pub struct RecordTally {
    table: SlaveTable,
    pending: Option<TransactionRecord>,
}

impl RecordTally {
    /// An empty tally whose lights follow `rule`.
    pub fn new(rule: LightRule) -> RecordTally {
        RecordTally {
            table: SlaveTable::new(rule),
            pending: None,
        }
    }

    /// The table so far (without the last record, whose verdict waits for the next).
    pub fn table(&self) -> &SlaveTable {
        &self.table
    }

    /// The next record, in the order of the transactions.
    pub fn push(&mut self, r: TransactionRecord) {
        if let Some(p) = self.pending.take() {
            self.close(&p, r.repeat);
        }
        if self.table.window_due(r.start) {
            self.table
                .roll(r.start, SlaveList::EMPTY, SlaveList::EMPTY, false);
        }
        self.pending = Some(r);
    }

    fn close(&mut self, r: &TransactionRecord, repeated: bool) {
        let error = judged_error(r);
        self.table.record(r, error, error && repeated);
    }

    /// The table after the last record, its lights evaluated up to `end`.
    pub fn finish(mut self, end: SimTime) -> SlaveTable {
        if let Some(p) = self.pending.take() {
            self.close(&p, false);
        }
        self.table
            .at(end, SlaveList::EMPTY, SlaveList::EMPTY, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use asi_phy::{Address, Check};

    fn dexg(n: u8) -> Request {
        Request::data_exchange(Address::new(n).expect("address"), Nibble::ZERO).expect("request")
    }

    fn ok() -> Tally {
        Tally {
            repeat: false,
            request_failed: Checks::NONE,
            response_failed: Checks::NONE,
            response: Some(Response::new(Nibble::ZERO)),
            no_response: false,
            error: false,
            will_repeat: false,
        }
    }

    fn failed(repeat: bool, will_repeat: bool) -> Tally {
        Tally {
            repeat,
            response: None,
            no_response: true,
            error: true,
            will_repeat,
            ..ok()
        }
    }

    #[test]
    fn single_and_consecutive_errors_of_a_worked_sequence() {
        // Slave 5: ok; an error put right by its repeat (single); ok; an error whose repeat
        // fails too, and the next cycle's call as well, then its repeat answers (three
        // consecutive... the first of the run is not single: its next call failed).
        let mut t = SlaveTable::default();
        let q = dexg(5);
        let seq = [
            ok(),
            failed(false, true),
            Tally {
                repeat: true,
                ..ok()
            },
            ok(),
            failed(false, true),
            failed(true, false),
            failed(false, true),
            Tally {
                repeat: true,
                ..ok()
            },
            ok(),
        ];
        for x in seq {
            t.count(slave_of(q, false), x);
        }
        let s = t.get(5).expect("slave 5");
        assert_eq!(s.calls, 9);
        assert_eq!(s.repeats, 3);
        assert_eq!(s.first_try_ok(), 3);
        assert_eq!(s.single_errors(), 1);
        // The run of three: the second and the third follow an error.
        assert_eq!(s.consecutive_errors, 2);
        assert_eq!(s.longest_error_run, 3);
        assert_eq!(s.failed_after_repeat, 1);
        assert_eq!(s.no_response, 4);
        // Other slaves saw nothing.
        assert_eq!(t.get(4).expect("slave 4").calls, 0);
    }

    #[test]
    fn a_lone_error_at_the_end_is_neither_single_nor_consecutive_yet() {
        let mut t = SlaveTable::default();
        t.count(3, ok());
        t.count(3, failed(false, true));
        let s = t.get(3).expect("slave 3");
        assert_eq!((s.single_errors(), s.consecutive_errors), (0, 0));
        assert_eq!(s.faults(), 1);
        t.count(
            3,
            Tally {
                repeat: true,
                ..ok()
            },
        );
        assert_eq!(t.get(3).expect("slave 3").single_errors(), 1);
    }

    #[test]
    fn checks_count_by_side_and_sum_to_the_bus_totals() {
        let mut t = SlaveTable::default();
        let mut bus = BusStats::default();
        let corrupt = Tally {
            response: None,
            response_failed: Checks::only(Check::Parity),
            error: true,
            will_repeat: true,
            ..ok()
        };
        let lost = Tally {
            request_failed: Checks::only(Check::Pause).with(Check::Length),
            response: None,
            no_response: true,
            error: true,
            will_repeat: true,
            ..ok()
        };
        for (n, x) in [(1, ok()), (2, corrupt), (2, lost), (7, ok()), (1, lost)] {
            t.count(slave_of(dexg(n), false), x);
            bus.count(
                x.repeat,
                x.request_failed,
                x.response_failed,
                x.no_response,
                x.error,
                x.will_repeat,
            );
        }
        assert_eq!(t.totals(), bus);
        let s2 = t.get(2).expect("slave 2");
        assert_eq!(s2.response_errors[Check::Parity as usize], 1);
        assert_eq!(s2.request_errors[Check::Pause as usize], 1);
        assert_eq!(s2.errors(Check::Length), 0);
        // A corrupt request gets no answer, but the slave never heard it: not "no response".
        assert_eq!(s2.no_response, 0);
    }

    #[test]
    fn calls_go_to_the_slave_they_address() {
        let a = |n| Address::new(n).expect("address");
        let b5 = Request::read_id_code(a(5), Select::B).expect("request");
        assert_eq!(slave_of(b5, false), 37);
        let a5 = Request::read_id_code(a(5), Select::A).expect("request");
        assert_eq!(slave_of(a5, false), 5);
        // A/B Data_Exchange: I3 = 0 is the B slave.
        let q = Request::data_exchange(a(9), Nibble::from_low_bits(0b0101)).expect("request");
        assert_eq!(slave_of(q, true), 41);
        assert_eq!(slave_of(q, false), 9);
        let q = Request::data_exchange(a(9), Nibble::from_low_bits(0b1101)).expect("request");
        assert_eq!(slave_of(q, true), 9);
        assert_eq!(slave_of(Request::address_assignment(a(4)), false), 0);
        assert_eq!(slave_of(Request::broadcast_reset(), false), NO_SLAVE);
    }

    #[test]
    fn the_light_follows_the_thresholds() {
        let r = LightRule::default();
        assert_eq!(r.colour(0, 500), Light::Green);
        assert_eq!(r.colour(4, 500), Light::Green);
        assert_eq!(r.colour(5, 500), Light::Yellow);
        assert_eq!(r.colour(25, 500), Light::Yellow);
        assert_eq!(r.colour(26, 500), Light::Red);
    }

    #[test]
    fn the_light_holds_its_worst_colour_for_the_hold_time() {
        let rule = LightRule {
            hold: SimDuration::from_secs(3),
            ..LightRule::default()
        };
        let mut t = SlaveTable::new(rule);
        let q = dexg(4);
        let las = SlaveList::from_bits(1 << 4);
        t.note_las(SimTime::ZERO, las, true);
        // Second 0: clean. Second 1: 10 % repeats. Seconds 2..: clean again. The light
        // after the window that ends at each second:
        let mut lights = Vec::new();
        for s in 0..8u64 {
            for k in 0..100u64 {
                let now = SimTime::from_millis(s * 1000 + k * 10);
                if t.window_due(now) {
                    t.roll(now, las, las, true);
                    lights.push(t.get(4).and_then(|x| x.light));
                }
                let repeat = s == 1 && k % 10 == 0;
                t.count(slave_of(q, false), Tally { repeat, ..ok() });
            }
        }
        let (g, r) = (Some(Light::Green), Some(Light::Red));
        // At 1 s the window of second 0; at 2 s that of second 1: red, held 3 s from then.
        assert_eq!(lights, [g, r, r, r, g, g, g]);
        let s = t.get(4).expect("slave 4");
        assert_eq!(s.worst_light, r);
    }

    #[test]
    fn a_slave_out_of_las_is_red_and_its_absence_is_timed() {
        let mut t = SlaveTable::default();
        let both = SlaveList::from_bits(0b110);
        let one = SlaveList::from_bits(0b100);
        t.note_las(SimTime::from_millis(100), both, true);
        t.note_las(SimTime::from_millis(1500), one, true);
        t.note_las(SimTime::from_millis(1700), both, true);
        t.note_las(SimTime::from_millis(2000), one, true);
        // The master goes offline: the absence ends, and counts no drop-out.
        t.note_las(SimTime::from_millis(2600), SlaveList::EMPTY, false);
        let s = t.get(1).expect("slave 1");
        assert_eq!(s.dropouts, 2);
        assert_eq!(s.out_of_las, SimDuration::from_millis(800));
        let mut t = SlaveTable::default();
        t.note_las(SimTime::from_millis(100), both, true);
        t.note_las(SimTime::from_millis(500), one, true);
        let seen = t.at(SimTime::from_millis(1000), one, both, true);
        assert_eq!(seen.get(1).and_then(|s| s.light), Some(Light::Red));
        assert_eq!(
            seen.get(1).map(|s| s.out_of_las),
            Some(SimDuration::from_millis(500))
        );
    }
}
