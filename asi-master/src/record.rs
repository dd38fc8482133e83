//! The transaction trace and the bus statistics (docs/timing.md).
//!
//! Every transaction gives one [`TransactionRecord`]: start time, what the master was doing,
//! the request, the checks the request failed on the line (as the slaves' receivers saw it),
//! the response or none, the checks the response failed in the master's receiver, and whether
//! it was the immediate repeat. Records go to `tracing` (target `asi_master::trace`, level
//! TRACE; formatted only when a subscriber wants them), to an optional bounded [`TraceRing`]
//! the application drains, and to an optional callback.

use asi_phy::{Call, Check, Checks, Request, Response, SimDuration, SimTime};
use core::fmt;
use std::collections::VecDeque;

/// What the master was doing in a transaction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TxKind {
    /// Start-up detection: reading IO, ID, ID1, ID2.
    Detection,
    /// Start-up activation: Write_Parameter and the first Data_Exchange.
    Activation,
    /// The data exchange phase of normal operation.
    DataExchange,
    /// The management phase (status read).
    Management,
    /// A host job from the command mailbox (in the management phase).
    HostJob,
    /// The inclusion phase.
    Inclusion,
    /// Automatic addressing of a replaced slave (in the inclusion phase).
    AutoAddress,
    /// Default outputs sent on the way to offline.
    Offline,
}

impl TxKind {
    /// A short label for traces.
    pub const fn label(self) -> &'static str {
        match self {
            TxKind::Detection => "detect",
            TxKind::Activation => "activate",
            TxKind::DataExchange => "data",
            TxKind::Management => "manage",
            TxKind::HostJob => "job",
            TxKind::Inclusion => "include",
            TxKind::AutoAddress => "auto-addr",
            TxKind::Offline => "offline",
        }
    }
}

/// One transaction on the bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TransactionRecord {
    /// Time of the request's first pulse.
    pub start: SimTime,
    /// What the master was doing.
    pub kind: TxKind,
    /// The request the master sent.
    pub request: Request,
    /// Checks the request failed on the line (empty: the slaves received it intact).
    pub request_failed: Checks,
    /// The response the master decoded, if valid.
    pub response: Option<Response>,
    /// Checks the response failed in the master's receiver.
    pub response_failed: Checks,
    /// `true` if nothing answered within the response timeout.
    pub no_response: bool,
    /// `true` for the immediate repeat of a failed transaction.
    pub repeat: bool,
    /// `true` if the request went to an A/B slave (I3 is the select bit).
    pub ab: bool,
}

impl TransactionRecord {
    /// `true` if the transaction succeeded (a valid response, or none where none is due).
    pub fn ok(&self) -> bool {
        self.response.is_some()
    }
}

/// The request as a readable call: `Data_Exchange 5 out=1010`, `Read_ID1 3A`; with `ab`
/// (an A/B slave) Data_Exchange and Write_Parameter show the select and three bits:
/// `Data_Exchange 5B out=011`.
pub fn describe_request(req: Request, ab: bool) -> String {
    let call = req.call();
    let name = call.name();
    if ab {
        if let Some((sel, d)) = req.ab_payload() {
            let address = req.address();
            let field = if matches!(call, Call::DataExchange { .. }) {
                "out"
            } else {
                "P"
            };
            return format!("{name} {address}{sel} {field}={:03b}", d.get());
        }
    }
    call.to_string()
}

/// A request's 14 bits grouped as docs/physical-layer.md writes them: `ST CB A4..A0 I4..I0 PB EB`.
pub fn request_bits(req: Request) -> String {
    let b = req.bits();
    format!(
        "{} {} {:05b} {:05b} {} {}",
        b >> 13 & 1,
        b >> 12 & 1,
        b >> 7 & 0x1F,
        b >> 2 & 0x1F,
        b >> 1 & 1,
        b & 1
    )
}

/// A response's 7 bits grouped as docs/physical-layer.md writes them: `ST I3..I0 PB EB`.
pub fn response_bits(resp: Response) -> String {
    let b = resp.bits();
    format!(
        "{} {:04b} {} {}",
        b >> 6 & 1,
        b >> 2 & 0xF,
        b >> 1 & 1,
        b & 1
    )
}

impl fmt::Display for TransactionRecord {
    /// One line: time, phase, the request's bits and call, and the response's bits:
    /// ` 0.005154000 s  detect    0 1 00001 10000 0 1  Read_IO_Configuration 1A        -> 0 0111 1 1`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:>14}  {:<9} {}  {:<30}",
            self.start.to_string(),
            self.kind.label(),
            request_bits(self.request),
            describe_request(self.request, self.ab)
        )?;
        if !self.request_failed.is_empty() {
            write!(f, " [request {}]", self.request_failed)?;
        }
        match (self.response, self.no_response) {
            (Some(r), _) => write!(f, " -> {}", response_bits(r))?,
            (None, true) => f.write_str(" -> no response")?,
            (None, false) => write!(f, " -> corrupt ({})", self.response_failed)?,
        }
        if self.repeat {
            f.write_str("  (repeat)")?;
        }
        Ok(())
    }
}

/// A bounded buffer of trace records the application drains; when full the oldest records are
/// dropped and counted.
#[derive(Clone, Debug, Default)]
pub struct TraceRing {
    buf: VecDeque<TransactionRecord>,
    capacity: usize,
    dropped: u64,
}

impl TraceRing {
    /// A ring holding at most `capacity` records (allocated once, up front).
    pub fn new(capacity: usize) -> TraceRing {
        TraceRing {
            buf: VecDeque::with_capacity(capacity),
            capacity,
            dropped: 0,
        }
    }

    /// Adds a record, dropping the oldest if full.
    pub fn push(&mut self, r: TransactionRecord) {
        if self.capacity == 0 {
            self.dropped += 1;
            return;
        }
        if self.buf.len() == self.capacity {
            self.buf.pop_front();
            self.dropped += 1;
        }
        self.buf.push_back(r);
    }

    /// Takes every record, oldest first.
    pub fn drain(&mut self) -> impl Iterator<Item = TransactionRecord> + '_ {
        self.buf.drain(..)
    }

    /// Records waiting.
    pub fn len(&self) -> usize {
        self.buf.len()
    }

    /// `true` if no record waits.
    pub fn is_empty(&self) -> bool {
        self.buf.is_empty()
    }

    /// Records dropped because the ring was full.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }
}

/// Cumulative bus statistics (docs/timing.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BusStats {
    /// Transactions (requests sent), repeats included.
    pub transactions: u64,
    /// Immediate repeats.
    pub repeats: u64,
    /// Transactions that still failed after their repeat (or were not repeated).
    pub failed_after_repeat: u64,
    /// Failed responses by primary check class (index = [`Check`] as u8).
    pub response_errors: [u64; 7],
    /// Requests the slaves received corrupted, by primary check class.
    pub request_errors: [u64; 7],
    /// Transactions without any response where one was due.
    pub no_response: u64,
    /// Slaves dropped from LAS after failing in consecutive cycles.
    pub dropouts: u64,
    /// Complete normal-operation cycles measured.
    pub cycles: u64,
    /// Shortest cycle.
    pub cycle_min: SimDuration,
    /// Longest cycle.
    pub cycle_max: SimDuration,
    /// Sum of all cycles (for the mean).
    pub cycle_total: SimDuration,
}

impl BusStats {
    /// Errors of one check class, requests and responses together.
    pub fn errors(&self, check: Check) -> u64 {
        self.response_errors[check as usize] + self.request_errors[check as usize]
    }

    /// Cycle time (min, mean, max) in µs; zeros before the first complete cycle.
    pub fn cycle_time_us(&self) -> (f64, f64, f64) {
        if self.cycles == 0 {
            return (0.0, 0.0, 0.0);
        }
        (
            self.cycle_min.as_micros_f64(),
            self.cycle_total.as_micros_f64() / self.cycles as f64,
            self.cycle_max.as_micros_f64(),
        )
    }

    pub(crate) fn record_cycle(&mut self, d: SimDuration) {
        if self.cycles == 0 || d < self.cycle_min {
            self.cycle_min = d;
        }
        if d > self.cycle_max {
            self.cycle_max = d;
        }
        self.cycle_total += d;
        self.cycles += 1;
    }

    /// Counts one transaction; `error` says whether its outcome was a fault (a probe of an
    /// empty address that gets no response is not), `will_repeat` whether it is repeated.
    pub fn record(&mut self, r: &TransactionRecord, error: bool, will_repeat: bool) {
        self.count(
            r.repeat,
            r.request_failed,
            r.response_failed,
            r.no_response,
            error,
            will_repeat,
        );
    }

    /// [`BusStats::record`] of a transaction with these fields of its record, for a caller
    /// that builds the record only where it keeps it.
    #[inline]
    pub fn count(
        &mut self,
        repeat: bool,
        request_failed: Checks,
        response_failed: Checks,
        no_response: bool,
        error: bool,
        will_repeat: bool,
    ) {
        self.transactions += 1;
        if repeat {
            self.repeats += 1;
        }
        if let Some(c) = request_failed.primary() {
            self.request_errors[c as usize] += 1;
        }
        if let Some(c) = response_failed.primary() {
            self.response_errors[c as usize] += 1;
        }
        if error && no_response && request_failed.is_empty() {
            self.no_response += 1;
        }
        if error && !will_repeat {
            self.failed_after_repeat += 1;
        }
    }
}

impl fmt::Display for BusStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (min, mean, max) = self.cycle_time_us();
        write!(
            f,
            "transactions {} repeats {} failed {} no_response {} dropouts {}",
            self.transactions,
            self.repeats,
            self.failed_after_repeat,
            self.no_response,
            self.dropouts
        )?;
        for c in Check::ALL {
            let n = self.errors(c);
            if n > 0 {
                write!(f, " {}={}", c.name().replace(' ', "_"), n)?;
            }
        }
        write!(
            f,
            " cycles {} cycle_us min {min:.0} mean {mean:.1} max {max:.0}",
            self.cycles
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use asi_phy::{Address, Nibble};

    #[test]
    fn bits_are_grouped_as_the_spec_writes_them() {
        // docs/physical-layer.md worked vectors.
        let q = Request::data_exchange(
            Address::new(5).expect("address"),
            Nibble::from_low_bits(0b1010),
        )
        .expect("valid");
        assert_eq!(request_bits(q), "0 0 00101 01010 0 1");
        assert_eq!(
            request_bits(Request::broadcast_reset()),
            "0 1 11111 10101 1 1"
        );
        assert_eq!(
            response_bits(Response::new(Nibble::from_low_bits(0b0110))),
            "0 0110 0 1"
        );
        assert_eq!(
            response_bits(Response::new(Nibble::from_low_bits(0))),
            "0 0000 0 1"
        );
    }
}
