//! The traffic of a capture as an AS-i analyser hears it: telegrams paired into transactions,
//! and the statistics per slave of those (docs/master.md, "Statistics per slave"; the
//! AS-Interface Analyser's "Online Statistics", which it works out from the telegrams alone).
//!
//! A listener knows the master's rules but not its state, so it pairs by time and by the
//! master's rule of the immediate repeat (docs/master.md):
//! - a telegram that starts less than [`RESPONSE_WITHIN_NS`] after a request's first pulse is
//!   that request's response (a second one, or one that failed a check, makes it corrupt);
//!   any later one starts the next transaction;
//! - a request that failed a check never reached the slaves: when its first bits (up to the
//!   12 of ST, CB, address and information) differ from the next valid request's in at most
//!   [`SAME_CALL_BITS`] places it is taken as that call's first try, and the valid one as its repeat (the master repeats a failed call at once);
//!   else it is a request error of a slave the listener cannot name (the unanswered probe
//!   of an empty address is not repeated, so the next call is another);
//! - a valid request equal to the one before, which failed, is its repeat;
//! - the verdicts are the master's ([`judged_error`]): a missing answer to
//!   Read_IO_Configuration is the silence of an empty address, not a fault.
//!
//! A Data_Exchange goes to an A/B slave when the slave's ID code seen so far is A.

use crate::telegrams::{check_key, TelegramRecord, TelegramType};
use asi_master::record::{TransactionRecord, TxKind};
use asi_master::slave_stats::{judged_error, RecordTally, SlaveTable};
use asi_master::LightRule;
use asi_phy::{Check, Checks, Request, Response, SimTime};

/// From a request's first pulse to the latest start of its response: the request (84 µs),
/// the longest slave pause (5 bit times, 30 µs) and margin, under the 154 µs of a
/// transaction (docs/physical-layer.md, the timing).
pub const RESPONSE_WITHIN_NS: i64 = 140_000;

/// The most bits in which a corrupt request may differ from the next valid one to be taken
/// for its first try (of its first 12 bits: ST, CB, A4..A0, I4..I0).
pub const SAME_CALL_BITS: u32 = 2;

/// `true` if the corrupt request with the bits `bits` (ST first) may be a first try of `q`:
/// at least its start bit, control bit and address were heard, and its first bits, up to
/// the 12 before the parity bit, differ from `q`'s in at most [`SAME_CALL_BITS`].
fn may_be_first_try(bits: &str, q: Request) -> bool {
    let mine = bits.as_bytes();
    let n = mine.len().min(12);
    if n < 7 {
        return false;
    }
    let theirs = q.bits();
    let differ = (0..n)
        .filter(|&i| {
            let bit = theirs >> (13 - i) & 1;
            (mine[i] == b'1') != (bit == 1)
        })
        .count();
    differ as u32 <= SAME_CALL_BITS
}

/// A transaction being heard.
#[derive(Clone, Debug)]
struct Open {
    start_ns: i64,
    request: Request,
    request_failed: Checks,
    repeat: bool,
    responses: u32,
    response: Option<Response>,
    response_failed: Checks,
}

/// Telegrams in, transactions and the statistics per slave out.
#[derive(Clone, Debug)]
pub struct TrafficAnalyser {
    tally: RecordTally,
    open: Option<Open>,
    /// A request that failed a check, its first pulse, checks and bits, waiting for its
    /// repeat.
    corrupt: Option<(i64, Checks, String)>,
    /// The last transaction's request, if it was a first try that failed.
    failed: Option<Request>,
    transactions: u64,
    last_ns: i64,
}

impl Default for TrafficAnalyser {
    fn default() -> TrafficAnalyser {
        TrafficAnalyser::new(LightRule::default())
    }
}

/// `t_ns` as the time of a record (a capture's time base may start below zero).
fn at(t_ns: i64) -> SimTime {
    SimTime::from_nanos(t_ns.max(0) as u64)
}

/// The checks of a telegram record's error keys.
fn checks_of(t: &TelegramRecord) -> Checks {
    let mut c = Checks::NONE;
    for k in &t.errors {
        if let Some(check) = Check::ALL.into_iter().find(|&x| check_key(x) == *k) {
            c = c.with(check);
        }
    }
    c
}

/// The bits of a record (ST first) as a number.
fn bits_of(t: &TelegramRecord) -> Option<u16> {
    u16::from_str_radix(&t.bits, 2).ok()
}

impl TrafficAnalyser {
    /// An analyser whose lights follow `rule`.
    pub fn new(rule: LightRule) -> TrafficAnalyser {
        TrafficAnalyser {
            tally: RecordTally::new(rule),
            open: None,
            corrupt: None,
            failed: None,
            transactions: 0,
            last_ns: 0,
        }
    }

    /// The next telegram, in time order.
    pub fn push(&mut self, t: &TelegramRecord) {
        self.last_ns = self.last_ns.max(t.t_ns);
        let answering = self
            .open
            .as_ref()
            .is_some_and(|o| t.t_ns - o.start_ns < RESPONSE_WITHIN_NS);
        if answering {
            if let Some(o) = self.open.as_mut() {
                o.responses += 1;
                let valid = t.is_valid() && t.kind == TelegramType::Response;
                match bits_of(t).and_then(|b| Response::from_bits(b as u8).ok()) {
                    Some(r) if valid && o.responses == 1 => o.response = Some(r),
                    _ => {
                        o.response = None;
                        let c = checks_of(t);
                        o.response_failed = o.response_failed.union(if c.is_empty() {
                            Checks::only(Check::Length)
                        } else {
                            c
                        });
                    }
                }
            }
            return;
        }
        self.close();
        let request = (t.is_valid() && t.kind == TelegramType::Request)
            .then(|| bits_of(t).and_then(|b| Request::from_bits(b).ok()))
            .flatten();
        let Some(q) = request else {
            // A corrupt request, or a response heard without its request: the start of a
            // failed first try (two in a row: the first is lost in the second).
            let c = checks_of(t);
            if let Some((start_ns, failed, _)) = self.corrupt.as_mut() {
                // A piece of the same corrupt request (a pause inside it cut it in two).
                if t.t_ns - *start_ns < RESPONSE_WITHIN_NS {
                    *failed = failed.union(c);
                    return;
                }
            }
            self.unattributed();
            self.corrupt = Some((
                t.t_ns,
                if c.is_empty() {
                    Checks::only(Check::Length)
                } else {
                    c
                },
                t.bits.clone(),
            ));
            return;
        };
        let mut repeat = self.failed.take() == Some(q);
        let first_try = self
            .corrupt
            .take_if(|(_, _, bits)| may_be_first_try(bits, q));
        self.unattributed();
        if let Some((start_ns, failed, _)) = first_try {
            self.emit(TransactionRecord {
                start: at(start_ns),
                kind: kind_of(q),
                request: q,
                request_failed: failed,
                response: None,
                response_failed: Checks::NONE,
                no_response: true,
                repeat: false,
                ab: self.ab(q),
            });
            repeat = true;
        }
        self.open = Some(Open {
            start_ns: t.t_ns,
            request: q,
            request_failed: Checks::NONE,
            repeat,
            responses: 0,
            response: None,
            response_failed: Checks::NONE,
        });
    }

    /// A corrupt request that is no call the listener can name: counted at no slave.
    fn unattributed(&mut self) {
        if let Some((start_ns, failed, _)) = self.corrupt.take() {
            self.emit(TransactionRecord {
                start: at(start_ns),
                kind: TxKind::Management,
                request: Request::broadcast_reset(),
                request_failed: failed,
                response: None,
                response_failed: Checks::NONE,
                no_response: true,
                repeat: false,
                ab: false,
            });
        }
    }

    /// Whether request `q` goes to an A/B slave: its ID code seen so far is A.
    fn ab(&self, q: Request) -> bool {
        let n = q.address().get();
        self.tally.table().get(n).is_some_and(|s| s.seen.is_ab())
    }

    /// Ends the transaction being heard.
    fn close(&mut self) {
        let Some(o) = self.open.take() else {
            return;
        };
        let r = TransactionRecord {
            start: at(o.start_ns),
            kind: kind_of(o.request),
            request: o.request,
            request_failed: o.request_failed,
            response: o.response,
            response_failed: o.response_failed,
            no_response: o.responses == 0,
            repeat: o.repeat,
            ab: self.ab(o.request),
        };
        self.failed = (judged_error(&r) && !r.repeat).then_some(r.request);
        self.emit(r);
    }

    fn emit(&mut self, r: TransactionRecord) {
        self.transactions += 1;
        self.tally.push(r);
    }

    /// Transactions heard so far (the one being heard not yet).
    pub fn transactions(&self) -> u64 {
        self.transactions
    }

    /// The statistics per slave after the last telegram, the lights evaluated up to it. A
    /// request still unanswered at the end of the capture is left out: its answer may have
    /// come after the capture ended.
    pub fn finish(mut self) -> SlaveTable {
        if self.open.as_ref().is_some_and(|o| o.responses == 0) {
            self.open = None;
        }
        self.close();
        self.unattributed();
        self.tally.finish(at(self.last_ns))
    }
}

/// What a listener takes a call for: a Data_Exchange is the data exchange phase, anything
/// else the master's other calls.
fn kind_of(q: Request) -> TxKind {
    if q.as_data_exchange().is_some() {
        TxKind::DataExchange
    } else {
        TxKind::Management
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use asi_phy::{Address, Nibble, Select};

    fn q5() -> Request {
        Request::data_exchange(Address::new(5).expect("5"), Nibble::from_low_bits(0b1010))
            .expect("request")
    }

    fn answer(t_ns: i64) -> TelegramRecord {
        TelegramRecord::response(t_ns, Response::new(Nibble::from_low_bits(0b0110)))
    }

    fn corrupt(t_ns: i64, kind: TelegramType) -> TelegramRecord {
        TelegramRecord {
            errors: vec!["parity"],
            kind,
            ..TelegramRecord::request(t_ns, q5())
        }
    }

    #[test]
    fn a_worked_exchange_with_a_corrupt_response_and_its_repeat() {
        let mut a = TrafficAnalyser::default();
        let step = 154_000;
        // Call 1 answered; call 2's answer corrupt, repeated and answered; call 3 lost on
        // the way (corrupt request), repeated and answered; call 4 unanswered twice; call 5
        // answered.
        let mut t = 0;
        let mut seq = Vec::new();
        seq.push(TelegramRecord::request(t, q5()));
        seq.push(answer(t + 102_000));
        t += step;
        seq.push(TelegramRecord::request(t, q5()));
        seq.push(corrupt(t + 102_000, TelegramType::Response));
        t += step + 8_000;
        seq.push(TelegramRecord::request(t, q5()));
        seq.push(answer(t + 102_000));
        t += step;
        seq.push(corrupt(t, TelegramType::Request));
        t += step;
        seq.push(TelegramRecord::request(t, q5()));
        seq.push(answer(t + 102_000));
        t += step;
        seq.push(TelegramRecord::request(t, q5()));
        t += step;
        seq.push(TelegramRecord::request(t, q5()));
        t += step;
        seq.push(TelegramRecord::request(t, q5()));
        seq.push(answer(t + 102_000));
        // Cut off by the end of the capture: not counted.
        seq.push(TelegramRecord::request(t + step, q5()));
        for r in &seq {
            a.push(r);
        }
        let table = a.finish();
        let s = table.get(5).expect("slave 5");
        assert_eq!(s.calls, 8);
        assert_eq!(s.repeats, 3);
        assert_eq!(s.first_try_ok(), 2);
        assert_eq!(s.response_errors[Check::Parity as usize], 1);
        assert_eq!(s.request_errors[Check::Parity as usize], 1);
        assert_eq!(s.no_response, 2);
        assert_eq!(s.single_errors(), 2);
        assert_eq!(s.consecutive_errors, 1);
        assert_eq!(s.failed_after_repeat, 1);
    }

    #[test]
    fn an_empty_address_probed_is_no_fault_and_codes_are_seen() {
        let a9 = Address::new(9).expect("9");
        let a3 = Address::new(3).expect("3");
        let mut a = TrafficAnalyser::default();
        let probe = Request::read_io_configuration(a9, Select::A).expect("request");
        let id = Request::read_id_code(a3, Select::A).expect("request");
        a.push(&TelegramRecord::request(0, probe));
        a.push(&TelegramRecord::request(154_000, id));
        a.push(&TelegramRecord::response(
            256_000,
            Response::new(Nibble::from_low_bits(0xF)),
        ));
        let table = a.finish();
        let nine = table.get(9).expect("9");
        assert_eq!((nine.calls, nine.faults(), nine.repeats), (1, 0, 0));
        assert!(!nine.takes_part());
        assert_eq!(
            table.get(3).and_then(|s| s.seen.id).map(|n| n.get()),
            Some(0xF)
        );
    }
}
