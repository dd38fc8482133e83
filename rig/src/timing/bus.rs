//! The plain buses (standard slaves or 62 A/B slaves): built, brought up, and measured for the
//! window.

use super::collector::{lock, take, BusWindow, Collector};
use super::options::{analysable_error_rate, AnalysisError, BusChoice, TimingOptions};
use asi_bus::lab::io_bus;
use asi_bus::Bus;
use asi_master::{ConfigError, MasterConfig, ProjectedConfig, ProjectedSlave};
use asi_phy::{FaultRates, Nibble, SimDuration, SimTime, SlaveAddr, SlaveCodes};
use asi_slaves::devices::{IoModule, AB_MODULE, AC2726};
use asi_slaves::Slave;
use std::sync::{Arc, Mutex};

/// 62 A/B I/O modules, all projected (as in asi-bus's cycle-time test).
fn ab_bus() -> Result<Bus, ConfigError> {
    let b_codes = SlaveCodes {
        id1: Nibble::from_low_bits(0xF),
        ..AB_MODULE
    };
    let mut projected = Vec::new();
    let mut slaves = Vec::new();
    for n in 1..=31u8 {
        let address = asi_phy::Address::new(n).ok_or_else(|| ConfigError::Slave {
            name: format!("address {n}"),
            why: "out of range".into(),
        })?;
        for (sel, codes) in [(SlaveAddr::a(n), AB_MODULE), (SlaveAddr::b(n), b_codes)] {
            let Some(sel) = sel else { continue };
            projected.push(ProjectedSlave {
                addr: sel,
                codes,
                parameter: Nibble::from_low_bits(7),
            });
            slaves.push(Slave::new(
                format!("{sel}"),
                address,
                codes,
                Box::new(IoModule::new()),
            ));
        }
    }
    Bus::new(
        MasterConfig::default(),
        ProjectedConfig::new(projected)?,
        slaves,
    )
}

/// How long a bus or the rig may take to get ready.
pub(super) const READY_WITHIN: SimDuration = SimDuration::from_secs(60);

pub(super) fn run_plain(opts: &TimingOptions) -> Result<(Collector, BusWindow), AnalysisError> {
    let mut bus = match opts.bus {
        BusChoice::Standard { n } => io_bus(n, AC2726)?,
        _ => ab_bus()?,
    };
    let rate =
        analysable_error_rate(opts.pulse_error_rate).map_err(|rule| AnalysisError::Option {
            option: "pulse error rate",
            value: opts.pulse_error_rate.to_string(),
            rule,
        })?;
    if rate.get() > 0.0 {
        bus.set_line_faults(opts.seed, FaultRates::uniform(rate));
    }
    let shared = Arc::new(Mutex::new(Collector::new(
        bus.timing(),
        opts.pulse_error_rate,
        None,
    )));
    let sink = Arc::clone(&shared);
    bus.set_trace_callback(Some(Box::new(move |r| lock(&sink).record(r))));
    let want = opts.bus.slaves();
    let deadline = SimTime::ZERO + READY_WITHIN;
    let mut t = SimTime::ZERO;
    while !(bus.is_running() && bus.master().las().len() == want) {
        if t >= deadline {
            return Err(AnalysisError::NotReady {
                what: "the master did not activate every slave",
                within: READY_WITHIN,
            });
        }
        t += SimDuration::from_millis(10);
        bus.advance_to(t);
    }
    // A few cycles of normal operation before measuring.
    let start = t + SimDuration::from_millis(50);
    bus.advance_to(start);
    lock(&shared).start_window();
    let before = bus.stats();
    let slaves_before = bus.slave_stats();
    let las_at_start = bus.master().las().len();
    bus.advance_to(start + opts.duration);
    lock(&shared).end_window();
    let after = bus.stats();
    let slaves = crate::report::slave_reports(
        &bus.slave_stats().since(&slaves_before),
        Some(bus.master().projected()),
    );
    bus.set_trace_callback(None);
    drop(bus);
    let collector = take(&shared);
    Ok((
        collector,
        BusWindow {
            failed_after_repeat: after.failed_after_repeat - before.failed_after_repeat,
            dropouts: after.dropouts - before.dropouts,
            slaves,
            las_at_start,
        },
    ))
}
