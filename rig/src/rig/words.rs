//! The report's words and figures for the bus and the safety monitor: why the monitor did not
//! release a sensor, why K1 is open, the bus's counts and cycle times.

use crate::report::{
    round3, BusReport, CheckCounts, CycleTimes, ErrorCounts, SlaveDropouts, SlaveReport,
};
use asi_bus::Bus;
use asi_master::BusStats;
use asi_slaves::monitor::{NotReleased, SafetyMonitor};
use lab::address::{SAFETY_BOTTOM, SAFETY_TOP};
use safety::lift::K1Cause;

/// Why K1 is open, in words; an overtravel sensor the monitor does not release is told
/// apart: tripped (0000) or not heard.
pub(super) fn k1_open_cause(c: K1Cause, monitor: Option<&SafetyMonitor>) -> String {
    let K1Cause::Overtravel { bottom, top } = c else {
        return c.to_string();
    };
    let why = |address: u8| {
        let state = asi_phy::Address::new(address).and_then(|a| monitor.and_then(|m| m.state(a)));
        match state {
            Some(Err(NotReleased::Tripped)) => "tripped",
            Some(Err(NotReleased::Missing)) => "not heard for the monitor's tolerance time",
            Some(Err(NotReleased::WrongCode { .. } | NotReleased::Frozen { .. })) => {
                "sending a wrong code sequence"
            }
            _ => "not yet released again by the monitor",
        }
    };
    let mut parts = Vec::new();
    if bottom {
        parts.push(format!(
            "overtravel bottom sensor ({SAFETY_BOTTOM}) {}",
            why(SAFETY_BOTTOM)
        ));
    }
    if top {
        parts.push(format!(
            "overtravel top sensor ({SAFETY_TOP}) {}",
            why(SAFETY_TOP)
        ));
    }
    parts.join("; ")
}

/// The bus's part of the report.
pub(super) fn bus_report(stats: BusStats, dropouts: Vec<SlaveDropouts>) -> BusReport {
    let (min, mean, max) = stats.cycle_time_us();
    BusReport {
        transactions: stats.transactions,
        repeats: stats.repeats,
        errors: ErrorCounts {
            checks: CheckCounts::from_fn(|k| stats.errors(k)),
            no_response: stats.no_response,
        },
        cycle_us: CycleTimes {
            min: round3(min),
            mean: round3(mean),
            max: round3(max),
        },
        dropouts,
        slaves: Vec::new(),
        master_leds: Default::default(),
    }
}

/// The bus's statistics per slave for the report, against the master's projected
/// configuration.
pub(super) fn slave_reports(bus: &Bus) -> Vec<SlaveReport> {
    crate::report::slave_reports(&bus.slave_stats(), Some(bus.master().projected()))
}
