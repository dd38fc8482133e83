//! The invariants of docs/safety-logic.md §9.1 as property tests over random input traces.

use asi_phy::{SimDuration, SimTime};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use safety::plcopen::{
    DiagCode, SfEdm, SfEdmInputs, SfEmergencyStop, SfEmergencyStopInputs, SfEquivalent,
    SfEquivalentInputs,
};

/// The DiagCodes SF_EmergencyStop may show (tables 24/25 of the SF_EmergencyStop help).
const ESTOP_CODES: [u16; 9] = [
    0x0000, 0x8001, 0x8802, 0x8402, 0x8804, 0x8404, 0x8000, 0xC001, 0xC011,
];

fn estop_inputs() -> impl Strategy<Value = SfEmergencyStopInputs> {
    // Activate mostly TRUE so that traces get deep into the state machine.
    (prop::bool::weighted(0.9), any::<bool>(), any::<bool>()).prop_map(
        |(activate, s_estop_in, reset)| SfEmergencyStopInputs {
            activate,
            s_estop_in,
            reset,
            ..Default::default()
        },
    )
}

proptest! {
    // A fixed seed: the suite explores the same 512 traces per property on every run.
    #![proptest_config(ProptestConfig {
        cases: 512,
        rng_seed: RngSeed::Fixed(0x5AFE_0002),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn emergency_stop_invariants(
        start_reset in any::<bool>(),
        auto_reset in any::<bool>(),
        trace in prop::collection::vec(estop_inputs(), 1..80),
    ) {
        let mut fb = SfEmergencyStop::new();
        let mut prev_reset = false;
        let mut prev_out = false;
        for mut i in trace {
            i.s_start_reset = start_reset;
            i.s_auto_reset = auto_reset;
            let o = fb.call(i);
            prop_assert!(i.s_estop_in || !o.s_estop_out, "AG(¬In ⇒ ¬Out)");
            prop_assert!(!o.error || o.ready, "AG(Error ⇒ Ready)");
            prop_assert!(!o.error || !o.s_estop_out, "AG(Error ⇒ ¬Out)");
            prop_assert!(ESTOP_CODES.contains(&o.diag_code.0), "code {}", o.diag_code);
            prop_assert!(!(o.diag_code == DiagCode(0x8000) && o.error), "8000 ∧ Error unreachable");
            prop_assert_eq!(o.error, o.diag_code.is_error());
            if !i.activate {
                prop_assert_eq!(o, Default::default(), "AG(¬Activate ⇒ all 0, 0000)");
            }
            if !start_reset && !auto_reset && o.s_estop_out && !prev_out {
                prop_assert!(i.reset && !prev_reset, "without auto resets, only a Reset edge enables");
            }
            prev_reset = i.reset;
            prev_out = o.s_estop_out;
        }
    }

    #[test]
    fn equivalent_invariants(
        disc_ms in 0u64..60,
        trace in prop::collection::vec((prop::bool::weighted(0.9), any::<bool>(), any::<bool>()), 1..80),
    ) {
        let mut fb = SfEquivalent::new();
        for (k, (activate, a, b)) in trace.into_iter().enumerate() {
            let o = fb.call(
                SimTime::from_millis(10 * k as u64),
                SfEquivalentInputs {
                    activate,
                    s_channel_a: a,
                    s_channel_b: b,
                    discrepancy_time: SimDuration::from_millis(disc_ms),
                },
            );
            prop_assert!(!o.error || !o.s_equivalent_out, "AG(Error ⇒ ¬Out)");
            prop_assert!(!o.s_equivalent_out || (a && b), "Out only with both channels TRUE");
            prop_assert!(!o.error || o.ready);
            if !activate {
                prop_assert_eq!(o, Default::default(), "AG(¬Activate ⇒ all 0, 0000)");
            }
        }
    }

    #[test]
    fn edm_invariants(
        trace in prop::collection::vec(
            (prop::bool::weighted(0.9), any::<bool>(), any::<bool>(), any::<bool>(), any::<bool>()),
            1..80,
        ),
    ) {
        let mut fb = SfEdm::new();
        for (k, (activate, control, edm1, edm2, reset)) in trace.into_iter().enumerate() {
            let o = fb.call(
                SimTime::from_millis(10 * k as u64),
                SfEdmInputs {
                    activate,
                    s_out_control: control,
                    s_edm1: edm1,
                    s_edm2: edm2,
                    monitoring_time: SimDuration::from_millis(30),
                    s_start_reset: false,
                    reset,
                },
            );
            prop_assert!(!o.error || !o.s_edm_out, "AG(Error ⇒ ¬Out)");
            prop_assert!(!o.s_edm_out || control, "never on without S_OutControl");
            if !activate {
                prop_assert_eq!(o, Default::default(), "AG(¬Activate ⇒ all 0, 0000)");
            }
        }
    }

    /// The composite "DiagnosticsConcept" of docs/safety-logic.md §9.1 as the lift's STOP chain:
    /// two NC channels → SF_Equivalent → SF_EmergencyStop → SF_EDM → contactor.
    #[test]
    fn stop_chain_invariants(
        trace in prop::collection::vec((any::<bool>(), any::<bool>(), any::<bool>(), any::<bool>()), 1..120),
    ) {
        let mut equivalent = SfEquivalent::new();
        let mut estop = SfEmergencyStop::new();
        let mut edm = SfEdm::new();
        let mut k1 = false;
        for (k, (ch1, ch2, reset, welded)) in trace.into_iter().enumerate() {
            let now = SimTime::from_millis(10 * k as u64);
            let eq = equivalent.call(now, SfEquivalentInputs {
                activate: true,
                s_channel_a: ch1,
                s_channel_b: ch2,
                discrepancy_time: SimDuration::from_millis(50),
            });
            let es = estop.call(SfEmergencyStopInputs {
                activate: true,
                s_estop_in: eq.s_equivalent_out,
                s_start_reset: false,
                s_auto_reset: false,
                reset,
            });
            // K1's NC auxiliary contact: closed (TRUE) when K1 is released, unless welded.
            let aux = !(k1 || welded);
            let out = edm.call(now, SfEdmInputs {
                activate: true,
                s_out_control: es.s_estop_out,
                s_edm1: aux,
                s_edm2: aux,
                monitoring_time: SimDuration::from_millis(30),
                s_start_reset: false,
                reset,
            });
            k1 = out.s_edm_out;
            prop_assert!(!es.error || !es.s_estop_out, "AG(EStop.Error ⇒ ¬S_EStopOut)");
            prop_assert!(!es.s_estop_out || eq.s_equivalent_out);
            prop_assert!(!k1 || (ch1 && ch2), "K1 closed only while both STOP channels are closed");
        }
    }
}
