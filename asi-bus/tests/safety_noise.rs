//! The Safety-at-Work monitor under random line noise: noise never makes a free sensor look
//! tripped while the master keeps it in LAS, and never makes a tripped sensor look free.

use crate::common::{a, addr};
use asi_bus::lab::LabLift;
use asi_phy::fault::FaultRates;
use asi_phy::{SimDuration, SimTime};
use asi_slaves::monitor::NotReleased;
use proptest::prelude::*;

const SENSORS: [u8; 2] = [11, 12];

/// The lab bus with line noise `p` from power-on, run until both sensors are released.
fn noisy_lab(seed: u64, p: f64) -> LabLift {
    let mut lab = LabLift::new().expect("lab");
    lab.bus_mut().set_line_faults(
        seed,
        FaultRates::uniform(asi_phy::PulseErrorRate::new(p).expect("a probability")),
    );
    let mut t = SimTime::ZERO;
    while !(lab.released(11) && lab.released(12)) {
        t += SimDuration::from_millis(1);
        assert!(
            t < SimTime::from_millis(2000),
            "taught within 2 s at p = {p}"
        );
        lab.bus_mut().advance_to(t);
    }
    lab
}

fn in_las(lab: &LabLift, n: u8) -> bool {
    lab.bus().master().las().contains(a(n))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// At one faulty pulse in a thousand (and in two hundred) the monitor of a free sensor
    /// never drops its release while the master keeps the sensor in LAS.
    #[test]
    fn noise_never_drops_a_free_sensor_that_stays_in_las(
        seed in any::<u64>(),
        p in prop_oneof![Just(1e-3), Just(5e-3)],
    ) {
        let mut lab = noisy_lab(seed, p);
        let start = lab.bus().now();
        let mut left_las = [false; 2];
        for k in 1..=3000u64 {
            lab.bus_mut().advance_to(start + SimDuration::from_millis(k));
            for (i, &n) in SENSORS.iter().enumerate() {
                left_las[i] |= !in_las(&lab, n);
                prop_assert!(
                    lab.released(n) || left_las[i],
                    "sensor {} dropped at {} while in LAS: {:?}",
                    n,
                    lab.bus().now(),
                    lab.monitor().and_then(|m| m.state(addr(n)))
                );
            }
        }
        let m = lab.monitor().expect("monitor");
        prop_assert!(left_las.iter().any(|&l| l)
            || SENSORS.iter().all(|&n| m.bad_codes(addr(n)) == 0));
    }

    /// Whatever the noise, a tripped sensor (0000) is never released.
    #[test]
    fn noise_never_releases_a_tripped_sensor(seed in any::<u64>(), p in 1e-3f64..3e-2) {
        let mut lab = noisy_lab(seed, 1e-3);
        lab.bus_mut().set_line_faults(seed ^ 0x5a5a, FaultRates::uniform(asi_phy::PulseErrorRate::new(p).expect("a probability")));
        for n in SENSORS {
            lab.safety_sensor_mut(n).expect("sensor").set_free(false);
        }
        let start = lab.bus().now();
        // The 0000 reaches the monitor within the tolerance time at the latest.
        lab.bus_mut().advance_to(start + SimDuration::from_millis(45));
        for k in 46..=1500u64 {
            lab.bus_mut().advance_to(start + SimDuration::from_millis(k));
            for n in SENSORS {
                prop_assert!(!lab.released(n), "sensor {} released at {}", n, lab.bus().now());
            }
        }
        for n in SENSORS {
            let state = lab.monitor().and_then(|m| m.state(addr(n)));
            prop_assert!(
                matches!(
                    state,
                    Some(Err(NotReleased::Tripped | NotReleased::Missing))
                ),
                "{:?}",
                state
            );
        }
    }
}
