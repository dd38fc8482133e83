//! The line as the bus records it (its tap) decodes to the bus's transaction trace.

use asi_phy::{BusTiming, Expect, SimDuration, SimTime};

use asi_bus::lab::LabLift;
use asi_phy::{FaultRates, Receiver};

fn us(n: u64) -> SimDuration {
    SimDuration::from_micros(n)
}

/// What the bus records of its line decodes, with a plain receiver, to exactly the requests
/// and responses of its trace: clean, and with line faults (where the receiver sees what the
/// master and the slaves saw).
#[test]
fn the_recorded_line_decodes_to_the_trace() {
    for rate in [0.0, 0.002] {
        let mut lab = LabLift::new().expect("lab bus");
        if rate > 0.0 {
            lab.bus_mut().set_line_faults(
                7,
                FaultRates::uniform(asi_phy::PulseErrorRate::new(rate).expect("a probability")),
            );
        }
        lab.bus_mut().enable_trace(100_000);
        lab.bus_mut().record_line(true);
        lab.bus_mut().advance_to(SimTime::from_millis(200));
        let mut pulses = lab.bus_mut().take_line_pulses();
        pulses.sort_by_key(|p| p.at);
        let rx = Receiver::new(BusTiming::default().receiver(Expect::Both));
        let decoded: Vec<_> = Receiver::decode(&mut { rx }, pulses).collect();
        let trace = lab.bus_mut().drain_trace();
        assert!(trace.len() > 1000);
        // Every transaction whose telegrams arrived intact is in the decoded line, in order.
        let mut i = 0;
        let mut matched = 0;
        for r in trace.iter().filter(|r| r.request_failed.is_empty()) {
            while i < decoded.len() && decoded[i].start < r.start {
                i += 1;
            }
            let d = decoded.get(i).expect("the request on the line");
            assert_eq!(d.start, r.start, "rate {rate}");
            assert_eq!(d.request(), Some(r.request), "rate {rate} at {}", r.start);
            if let Some(resp) = r.response {
                let next = decoded.get(i + 1).expect("the response on the line");
                assert_eq!(next.response(), Some(resp), "rate {rate} at {}", r.start);
            }
            matched += 1;
        }
        if rate == 0.0 {
            assert_eq!(matched, trace.len());
            // The request in flight at the end is on the line but not yet in the trace.
            let last = trace.last().map(|r| r.start).unwrap_or_default();
            let finished = decoded.iter().filter(|d| d.start < last + us(154)).count();
            assert_eq!(
                finished,
                trace.len() + trace.iter().filter(|r| r.response.is_some()).count()
            );
        } else {
            assert!(matched < trace.len(), "faults must have hit some requests");
        }
    }
}
