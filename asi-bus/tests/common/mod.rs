//! Helpers shared by the integration tests.
#![allow(dead_code)]

use asi_bus::lab::LabLift;
use asi_bus::Bus;
use asi_master::TransactionRecord;
use asi_phy::{Address, Call, SimDuration, SimTime, SlaveAddr};
use asi_slaves::devices::AC2726;

pub fn addr(n: u8) -> Address {
    Address::new(n).expect("address")
}

pub fn a(n: u8) -> SlaveAddr {
    SlaveAddr::a(n).expect("address")
}

pub fn b(n: u8) -> SlaveAddr {
    SlaveAddr::b(n).expect("address")
}

pub fn us(n: u64) -> SimDuration {
    SimDuration::from_micros(n)
}

pub fn ms(n: u64) -> SimTime {
    SimTime::from_millis(n)
}

/// A bus of `n` plain I/O modules at 1..=n, all projected.
pub fn io_bus(n: u8) -> Bus {
    asi_bus::lab::io_bus(n, AC2726).expect("bus")
}

/// The lab bus in normal operation at `at_ms`, tracing.
pub fn running_lab(at_ms: u64) -> LabLift {
    let mut lab = LabLift::new().expect("lab");
    lab.bus_mut().advance_to(ms(at_ms));
    assert!(lab.bus().is_running());
    lab.bus_mut().enable_trace(1_000_000);
    lab
}

/// The address a request is for (Address_Assignment: the new address).
pub fn target(r: &TransactionRecord) -> u8 {
    match r.request.call() {
        Call::AddressAssignment { new_address } => new_address.get(),
        _ => r.request.address().get(),
    }
}

/// Trace lines, one per record.
pub fn lines<'a>(records: impl IntoIterator<Item = &'a TransactionRecord>) -> String {
    let mut s = String::new();
    for r in records {
        s.push_str(r.to_string().trim_end());
        s.push('\n');
    }
    s
}

/// Trace lines with runs of identical exchanges (same request and outcome) folded into one
/// line with a count, so a handshake reads step by step.
pub fn folded<'a>(records: impl IntoIterator<Item = &'a TransactionRecord>) -> String {
    let mut out = String::new();
    let mut last: Option<(TransactionRecord, u32)> = None;
    let flush = |out: &mut String, r: &TransactionRecord, n: u32| {
        out.push_str(r.to_string().trim_end());
        if n > 1 {
            out.push_str(&format!("  (x{n})"));
        }
        out.push('\n');
    };
    for r in records {
        match &mut last {
            Some((l, n))
                if l.request == r.request
                    && l.response == r.response
                    && l.kind == r.kind
                    && l.repeat == r.repeat =>
            {
                *n += 1
            }
            _ => {
                if let Some((l, n)) = last.take() {
                    flush(&mut out, &l, n);
                }
                last = Some((*r, 1));
            }
        }
    }
    if let Some((l, n)) = last {
        flush(&mut out, &l, n);
    }
    out
}

/// The bits of the display word (lab crate) for `floor` and the four indicators.
pub fn display_bits(floor: u8, up: bool, down: bool, moving: bool, fault: bool) -> u16 {
    lab::DisplayWord {
        floor,
        up,
        down,
        moving,
        fault,
    }
    .encode()
    .expect("a floor 1..=24")
}
