//! No input makes the bus panic: heavy line noise, arbitrary process-image writes (host
//! flags, mailbox jobs, outputs), power cuts, slaves pulled and put back. Through all of it the
//! master keeps its repeat rule: a repeat comes only right after a failed first try to the same
//! slave, never twice in a row, and the statistics count exactly the repeats the records show.

use crate::common::*;
use asi_bus::lab::LabLift;
use asi_master::TransactionRecord;
use asi_phy::{FaultRates, SimDuration};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn the_lab_bus_survives_anything(
        seed in any::<u64>(),
        rate in 0.0f64..0.3,
        writes in proptest::collection::vec((0usize..244, any::<u16>(), 0u64..120), 0..40),
        volts in proptest::collection::vec((0u64..120, 0.0f64..35.0), 0..4),
        pulls in proptest::collection::vec((0u64..120, 1u8..13), 0..4),
    ) {
        let mut lab = LabLift::new().expect("lab");
        lab.bus_mut().enable_trace(4096);
        let mut previous: Option<TransactionRecord> = None;
        let mut repeats = 0u64;
        lab.bus_mut().set_line_faults(seed, FaultRates::uniform(asi_phy::PulseErrorRate::new(rate).expect("a probability")));
        for t in 0..120u64 {
            for (i, v, at) in &writes {
                if *at == t {
                    lab.bus_mut().image_mut().output.set_word(*i, *v);
                }
            }
            for (at, v) in &volts {
                if *at == t {
                    lab.bus_mut().set_supply_voltage(*v);
                }
            }
            for (at, n) in &pulls {
                if *at == t {
                    if let Some(id) = lab.slave_id(*n) {
                        if lab.bus().is_attached(id) {
                            lab.bus_mut().detach(id);
                        } else {
                            lab.bus_mut().attach(id);
                        }
                    }
                }
            }
            lab.bus_mut().advance_to(ms(t) + SimDuration::from_micros(500));
            for r in lab.bus_mut().drain_trace() {
                if r.repeat {
                    repeats += 1;
                    let first = previous.as_ref();
                    prop_assert!(
                        first.is_some_and(|f| !f.repeat
                            && !f.ok()
                            && f.kind == r.kind
                            && f.request.cb() == r.request.cb()
                            && f.request.address() == r.request.address()),
                        "repeat {r} after {first:?}"
                    );
                }
                previous = Some(r);
            }
        }
        let dropped = lab.bus_mut().trace_ring_mut().map_or(0, |ring| ring.dropped());
        prop_assert_eq!(dropped, 0);
        prop_assert_eq!(lab.bus().stats().repeats, repeats);
    }
}
