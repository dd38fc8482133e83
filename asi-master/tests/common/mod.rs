//! Helpers shared by the integration tests.
#![allow(dead_code)]

use asi_master::devices::{IoModule, AC2726};
use asi_master::{
    Bus, MasterConfig, ProjectedConfig, ProjectedSlave, Slave, SlaveAddr, SlaveCodes,
    TransactionRecord,
};
use asi_phy::{Address, Call, Nibble, SimDuration, SimTime};

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
    io_bus_with(n, AC2726)
}

pub fn io_bus_with(n: u8, codes: SlaveCodes) -> Bus {
    let mut projected = Vec::new();
    let mut slaves = Vec::new();
    for k in 1..=n {
        projected.push(ProjectedSlave {
            addr: a(k),
            codes,
            parameter: Nibble::ALL,
        });
        slaves.push(Slave::new(
            format!("io {k}"),
            addr(k),
            codes,
            Box::new(IoModule::new()),
        ));
    }
    let p = ProjectedConfig::new(projected).expect("projection");
    Bus::new(MasterConfig::default(), p, slaves).expect("bus")
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
