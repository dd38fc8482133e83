//! The lift's safety project (docs/safety.md): K1 is never closed while STOP is demanded past the
//! delay, while overloaded, while an overtravel sensor is tripped, or after a group error
//! until acknowledged; and the rig's API around it.

use asi_phy::{SimDuration, SimTime};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use safety::kl6904::connection::{ChannelFault, ConnDiag};
use safety::kl6904::group::GroupState;
use safety::kl6904::logic::LogicEventKind;
use safety::kl6904::modules::FbState;
use safety::kl6904::Project;
use safety::lift::{K1Cause, LiftEventKind, StopDelayModel};
use safety::{
    LiftSafety, LiftSafetyCause, LiftSafetyConfig, LiftSafetyEvent, LiftSafetyInputs,
    LiftSafetyOutputs, SafeLink, SAFETY_SCAN_PERIOD,
};

const DELAY_MS: u64 = 9_100;

/// The lift's safety logic with a contactor model: K1's auxiliary NC contact follows the
/// command one scan later, unless the contactor is welded.
struct Sim {
    safety: LiftSafety,
    inputs: LiftSafetyInputs,
    t: u64,
    welded: bool,
    out: LiftSafetyOutputs,
    log: Vec<LiftSafetyEvent>,
}

impl Sim {
    fn new() -> Sim {
        let mut safety = LiftSafety::new(LiftSafetyConfig::default()).expect("lift project");
        let inputs = LiftSafetyInputs::healthy();
        let out = safety.scan(SimTime::ZERO, &inputs);
        let log = out.events.clone();
        Sim {
            safety,
            inputs,
            t: 1,
            welded: false,
            out,
            log,
        }
    }

    /// Started: both resets given, K1 closed.
    fn started() -> Sim {
        let mut sim = Sim::new();
        sim.run(5);
        sim.pulse(|i, v| i.controller_restart = v);
        sim.pulse(|i, v| i.operator_reset = v);
        assert!(sim.out.k1, "started: K1 closed");
        sim
    }

    fn now(&self) -> SimTime {
        SimTime::from_millis(self.t)
    }

    /// One scan of 1 ms.
    fn step(&mut self) -> &LiftSafetyOutputs {
        self.inputs.k1_aux = !(self.out.k1 || self.welded);
        self.out = self.safety.scan(self.now(), &self.inputs);
        self.log.extend(self.out.events.iter().cloned());
        self.t += 1;
        &self.out
    }

    fn run(&mut self, ms: u64) {
        for _ in 0..ms {
            self.step();
        }
    }

    /// Run `ms` scans and check that K1 is open in every one of them.
    fn run_k1_open(&mut self, ms: u64, why: &str) {
        for _ in 0..ms {
            let k1 = self.step().k1;
            assert!(!k1, "K1 closed at {} ms: {why}", self.t - 1);
        }
    }

    /// A 0→1→0 pulse of 20 ms high (two controller scans) and 20 ms low.
    fn pulse(&mut self, set: fn(&mut LiftSafetyInputs, bool)) {
        set(&mut self.inputs, true);
        self.run(20);
        set(&mut self.inputs, false);
        self.run(20);
    }

    /// `true` if the safety log has an event whose cause is `cause`.
    fn logged(&self, cause: &LiftSafetyCause) -> bool {
        self.log.iter().any(|e| e.cause == *cause)
    }
}

#[test]
fn the_scan_period_is_one_millisecond_and_the_default_delay_is_derived() {
    assert_eq!(SAFETY_SCAN_PERIOD, SimDuration::from_millis(1));
    assert_eq!(
        StopDelayModel::default().delay(),
        SimDuration::from_millis(DELAY_MS)
    );
    assert_eq!(
        LiftSafetyConfig::default().estop_delay,
        SimDuration::from_millis(DELAY_MS)
    );
    let flat = {
        let mut cfg = StopDelayModel::default();
        cfg.approach_mm = 0.0;
        cfg.margin = SimDuration::ZERO;
        cfg
    };
    // 400 mm at 59.416 mm/s = 6.732 s, + 20.55/500 s braking = 6.773 s, rounded up
    assert_eq!(flat.delay(), SimDuration::from_millis(6_800));
}

#[test]
fn the_project_file_is_the_default_project() {
    let file = include_str!("../projects/lift.toml");
    let from_file =
        Project::from_toml("projects/lift.toml", file).expect("the shipped file is valid");
    assert_eq!(from_file, LiftSafetyConfig::default().project());
}

#[test]
fn start_up_needs_the_controller_restart_and_the_operator_reset() {
    let mut sim = Sim::new();
    sim.run(100);
    assert!(!sim.out.k1 && !sim.out.estop_out);
    assert_eq!(sim.out.diag.group.state, GroupState::Run);
    assert_eq!(
        sim.out.diag.k1_open_cause,
        Some(K1Cause::StopRestartPending)
    );
    sim.pulse(|i, v| i.controller_restart = v);
    assert!(sim.out.estop_out, "STOP circuit enabled");
    assert!(!sim.out.k1);
    assert_eq!(
        sim.out.diag.k1_open_cause,
        Some(K1Cause::OvertravelResetPending)
    );
    sim.pulse(|i, v| i.operator_reset = v);
    assert!(sim.out.k1);
    assert!(sim.logged(&LiftSafetyCause::K1Closed));
}

#[test]
fn stop_drops_estop_out_at_once_and_k1_after_the_delay_then_the_controller_restarts() {
    let mut sim = Sim::started();
    sim.inputs.stop_ch1 = false;
    sim.inputs.stop_ch2 = false;
    let t0 = sim.t;
    let out = sim.step().clone();
    assert!(!out.estop_out, "EStopOut off in the same scan");
    assert!(out.k1, "K1 kept for the time-monitored stop");
    assert_eq!(out.events.len(), 1, "{:?}", out.events);
    assert_eq!(
        out.events[0].cause,
        LiftSafetyCause::StopDemanded {
            channels: 0b11,
            delay: SimDuration::from_millis(DELAY_MS)
        }
    );
    assert_eq!(
        out.events[0].cause.to_string(),
        "tripped: STOP demanded (channel 1 and 2 open); estop_out off, K1 off in 9.1 s"
    );
    assert_eq!(out.events[0].kind, LiftEventKind::Trip);
    assert_eq!(out.events[0].at_s(), t0 as f64 / 1000.0);
    // STOP released while the cabin creeps to the floor; the controller's restart pulse
    // during the delay is ignored
    sim.run(3_000);
    sim.inputs.stop_ch1 = true;
    sim.inputs.stop_ch2 = true;
    sim.pulse(|i, v| i.controller_restart = v);
    while sim.t < t0 + DELAY_MS {
        assert!(sim.step().k1, "within the delay at {} ms", sim.t - 1);
    }
    let out = sim.step().clone();
    assert!(!out.k1, "K1 off exactly at the end of the delay");
    let causes: Vec<&LiftSafetyCause> = out.events.iter().map(|e| &e.cause).collect();
    assert_eq!(
        causes,
        [
            &LiftSafetyCause::StopDelayElapsed {
                delay: SimDuration::from_millis(DELAY_MS)
            },
            &LiftSafetyCause::K1Opened(K1Cause::StopRestartPending)
        ]
    );
    let words: Vec<String> = causes.iter().map(|c| c.to_string()).collect();
    assert_eq!(
        words,
        [
            "STOP delay of 9.1 s elapsed: EStopDelOut off",
            "K1 opened: STOP circuit waiting for the controller's restart"
        ]
    );
    // Both are the trip's consequences, not trips of their own.
    assert!(out
        .events
        .iter()
        .all(|e| e.kind == LiftEventKind::PowerOff && e.is_trip()));
    sim.run_k1_open(2_000, "no restart yet");
    sim.pulse(|i, v| i.controller_restart = v);
    assert!(
        sim.out.k1 && sim.out.estop_out,
        "restarted by the next cabin request"
    );
    assert!(sim.logged(&LiftSafetyCause::StopRestarted));
}

#[test]
fn a_welded_k1_is_caught_at_the_stop_restart() {
    let mut sim = Sim::started();
    sim.welded = true;
    sim.inputs.stop_ch1 = false;
    sim.inputs.stop_ch2 = false;
    sim.run(DELAY_MS + 10);
    sim.inputs.stop_ch1 = true;
    sim.inputs.stop_ch2 = true;
    sim.run(10);
    sim.pulse(|i, v| i.controller_restart = v);
    assert!(!sim.out.k1);
    assert_eq!(sim.out.diag.estop.state, FbState::Error);
    assert_eq!(sim.out.diag.estop.diag, 1 << 4, "EDM1");
    assert!(sim.logged(&LiftSafetyCause::StopContactOpen));
    sim.pulse(|i, v| i.err_ack = v);
    assert_eq!(
        sim.out.diag.group.state,
        GroupState::Error,
        "still welded: ERR_ACK refused"
    );
    sim.welded = false;
    sim.run(5);
    sim.pulse(|i, v| i.err_ack = v);
    assert_eq!(sim.out.diag.group.state, GroupState::Run);
    sim.pulse(|i, v| i.controller_restart = v);
    sim.pulse(|i, v| i.operator_reset = v);
    assert!(sim.out.k1);
}

#[test]
fn the_safe_link_drop_trips_com_err_and_k1_until_acknowledged() {
    let mut sim = Sim::started();
    let at = sim.now();
    sim.safety
        .drop_link(SafeLink::CabinStop, at, SimDuration::from_millis(500));
    sim.run(100);
    assert!(sim.out.k1, "100 ms without telegrams: within the watchdog");
    sim.step();
    assert!(
        !sim.out.k1 && !sim.out.estop_out,
        "watchdog expired: K1 and estop_out off at once"
    );
    assert!(sim.out.diag.stop_link.contains(ConnDiag::WATCHDOG));
    assert!(sim.out.diag.group.errors.com_err);
    let events: Vec<String> = sim.out.events.iter().map(|e| e.cause.to_string()).collect();
    assert!(
        events.contains(
            &"COM_ERR: watchdog expired on connection 1 `cabin_stop`: no valid telegram for 101 ms (watchdog 100 ms)".to_owned()
        ),
        "{events:#?}"
    );
    assert!(events
        .iter()
        .any(|c| c == "K1 opened: group error (COM_ERR), waiting for ERR_ACK"));
    sim.run_k1_open(2_000, "link back, but not acknowledged");
    sim.pulse(|i, v| i.err_ack = v);
    assert_eq!(sim.out.diag.group.state, GroupState::Run);
    assert_eq!(sim.out.diag.stop_link, ConnDiag(0));
    sim.run_k1_open(100, "acknowledged: each module's own restart rule applies");
    sim.pulse(|i, v| i.controller_restart = v);
    sim.pulse(|i, v| i.operator_reset = v);
    assert!(sim.out.k1);
}

/// One hazard of the table: how to raise it, how long K1 may stay closed after it, how to
/// remove it and what brings K1 back.
struct Hazard {
    name: &'static str,
    raise: fn(&mut Sim),
    /// Scans K1 may still be closed after the hazard is raised.
    grace_ms: u64,
    clear: fn(&mut Sim),
    recover: fn(&mut Sim),
    /// Cause reported while K1 is open (checked in the scan before recovery).
    cause: fn(&K1Cause) -> bool,
}

fn restart(sim: &mut Sim) {
    sim.pulse(|i, v| i.controller_restart = v);
}

fn ack_and_restart_all(sim: &mut Sim) {
    sim.pulse(|i, v| i.err_ack = v);
    sim.pulse(|i, v| i.controller_restart = v);
    sim.pulse(|i, v| i.operator_reset = v);
}

const HAZARDS: &[Hazard] = &[
    Hazard {
        name: "STOP pressed, both channels",
        raise: |s| {
            s.inputs.stop_ch1 = false;
            s.inputs.stop_ch2 = false;
        },
        grace_ms: DELAY_MS,
        clear: |s| {
            s.inputs.stop_ch1 = true;
            s.inputs.stop_ch2 = true;
        },
        recover: restart,
        cause: |c| matches!(c, K1Cause::StopPressed | K1Cause::StopRestartPending),
    },
    Hazard {
        name: "STOP channel 2 stuck closed (discrepancy)",
        raise: |s| s.inputs.stop_ch1 = false,
        grace_ms: 51,
        clear: |s| s.inputs.stop_ch1 = true,
        recover: ack_and_restart_all,
        cause: |c| matches!(c, K1Cause::GroupError(e) if e.fb_err),
    },
    Hazard {
        name: "overloaded",
        raise: |s| s.inputs.overloaded = true,
        grace_ms: 0,
        clear: |s| s.inputs.overloaded = false,
        recover: |_| {},
        cause: |c| *c == K1Cause::Overloaded,
    },
    Hazard {
        name: "overtravel bottom sensor tripped",
        raise: |s| s.inputs.overtravel_bottom_released = false,
        grace_ms: 0,
        clear: |s| s.inputs.overtravel_bottom_released = true,
        recover: |s| s.pulse(|i, v| i.operator_reset = v),
        cause: |c| {
            matches!(
                c,
                K1Cause::Overtravel { bottom: true, .. } | K1Cause::OvertravelResetPending
            )
        },
    },
    Hazard {
        name: "overtravel top sensor tripped",
        raise: |s| s.inputs.overtravel_top_released = false,
        grace_ms: 0,
        clear: |s| s.inputs.overtravel_top_released = true,
        recover: |s| s.pulse(|i, v| i.operator_reset = v),
        cause: |c| {
            matches!(
                c,
                K1Cause::Overtravel { top: true, .. } | K1Cause::OvertravelResetPending
            )
        },
    },
    Hazard {
        name: "cabin STOP link lost (watchdog)",
        raise: |s| {
            let at = s.now();
            s.safety
                .drop_link(SafeLink::CabinStop, at, SimDuration::from_millis(300));
        },
        grace_ms: 100,
        clear: |_| {},
        recover: ack_and_restart_all,
        cause: |c| matches!(c, K1Cause::GroupError(e) if e.com_err),
    },
    Hazard {
        name: "cabinet link: one corrupted CRC",
        raise: |s| {
            let at = s.now();
            s.safety
                .inject_link_fault(SafeLink::Cabinet, at, ChannelFault::CorruptCrc);
        },
        grace_ms: 0,
        clear: |_| {},
        recover: ack_and_restart_all,
        cause: |c| matches!(c, K1Cause::GroupError(e) if e.com_err),
    },
    Hazard {
        name: "cabinet link: one replayed telegram",
        raise: |s| {
            let at = s.now();
            s.safety
                .inject_link_fault(SafeLink::Cabinet, at, ChannelFault::Replay { age: 3 });
        },
        grace_ms: 0,
        clear: |_| {},
        recover: ack_and_restart_all,
        cause: |c| matches!(c, K1Cause::GroupError(e) if e.com_err),
    },
    Hazard {
        name: "K1 output error",
        raise: |s| s.safety.set_k1_output_fault(true),
        grace_ms: 0,
        clear: |s| s.safety.set_k1_output_fault(false),
        recover: ack_and_restart_all,
        cause: |c| matches!(c, K1Cause::GroupError(e) if e.out_err),
    },
];

#[test]
fn k1_is_never_closed_while_a_hazard_lasts_nor_before_its_reset() {
    for h in HAZARDS {
        let mut sim = Sim::started();
        (h.raise)(&mut sim);
        sim.run(h.grace_ms);
        sim.run_k1_open(2_000, &format!("{}: hazard present", h.name));
        let cause = sim.out.diag.k1_open_cause;
        assert!(
            cause.as_ref().is_some_and(h.cause),
            "{}: cause {cause:?}",
            h.name
        );
        (h.clear)(&mut sim);
        if h.name != "overloaded" {
            sim.run_k1_open(2_000, &format!("{}: hazard gone, not reset", h.name));
            let cause = sim.out.diag.k1_open_cause;
            assert!(
                cause.as_ref().is_some_and(h.cause),
                "{}: cause {cause:?}",
                h.name
            );
        }
        (h.recover)(&mut sim);
        sim.run(5);
        assert!(
            sim.out.k1,
            "{}: K1 back after the reset; log {:#?}",
            h.name, sim.log
        );
        assert!(
            sim.log
                .iter()
                .any(|e| matches!(e.cause, LiftSafetyCause::K1Opened(_))),
            "{}: the trip is logged",
            h.name
        );
    }
}

#[test]
fn a_group_error_is_not_released_by_the_function_resets_alone() {
    let mut sim = Sim::started();
    sim.inputs.stop_ch1 = false;
    sim.run(60);
    assert!(sim.out.diag.group.errors.fb_err);
    sim.inputs.stop_ch1 = true;
    for _ in 0..3 {
        sim.pulse(|i, v| i.controller_restart = v);
        sim.pulse(|i, v| i.operator_reset = v);
        assert!(!sim.out.k1, "no ERR_ACK yet");
    }
    ack_and_restart_all(&mut sim);
    assert!(sim.out.k1);
}

#[test]
fn a_logic_fault_keeps_k1_open_for_good() {
    let mut sim = Sim::started();
    sim.safety.inject_logic_fault("self-test failed");
    sim.step();
    assert!(!sim.out.k1 && sim.out.diag.logic_fault);
    let fault = LiftSafetyCause::Logic(LogicEventKind::LogicFault {
        cause: "self-test failed".into(),
    });
    assert!(sim.logged(&fault));
    assert_eq!(
        fault.to_string(),
        "logic fault: self-test failed; the whole logic is stopped"
    );
    ack_and_restart_all(&mut sim);
    assert!(!sim.out.k1);
    assert_eq!(sim.out.diag.k1_open_cause, Some(K1Cause::LogicFault));
}

#[test]
fn runs_are_deterministic() {
    let run = || {
        let mut sim = Sim::started();
        let at = sim.now();
        sim.safety
            .drop_link(SafeLink::CabinStop, at, SimDuration::from_millis(250));
        sim.safety.inject_link_fault(
            SafeLink::Cabinet,
            at + SimDuration::from_millis(400),
            ChannelFault::NullTelegram,
        );
        sim.run(1_000);
        ack_and_restart_all(&mut sim);
        sim.inputs.stop_ch1 = false;
        sim.run(200);
        sim.log.iter().map(ToString::to_string).collect::<Vec<_>>()
    };
    let first = run();
    assert!(first.len() > 10);
    assert_eq!(first, run());
}

/// One scan's inputs for the property test (K1's aux contact is modelled, not random).
fn scan_inputs() -> impl Strategy<Value = (bool, bool, bool, bool, bool, bool, bool, bool)> {
    (
        prop::bool::weighted(0.97),
        prop::bool::weighted(0.97),
        prop::bool::weighted(0.98),
        prop::bool::weighted(0.98),
        prop::bool::weighted(0.03),
        prop::bool::weighted(0.3),
        prop::bool::weighted(0.3),
        prop::bool::weighted(0.3),
    )
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: RngSeed::Fixed(0x5AFE_0006),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Over random input traces (each value held 10 ms, like the controller's scan), with a
    /// short STOP delay so that it matters within a trace: K1 is never closed while overloaded,
    /// while an overtravel sensor is tripped, while the group has an error, or while STOP has
    /// been demanded for longer than the delay.
    #[test]
    fn k1_invariants(trace in prop::collection::vec(scan_inputs(), 1..300)) {
        let delay = SimDuration::from_millis(200);
        let mut safety = LiftSafety::new({
            let mut cfg = LiftSafetyConfig::default();
            cfg.estop_delay = delay;
            cfg
        }).expect("project");
        let mut k1 = false;
        let mut t = 0u64;
        // start of the current uninterrupted STOP demand (a channel open)
        let mut demand_since: Option<u64> = None;
        for (ch1, ch2, bottom, top, overloaded, reset, ack, restart) in trace {
            for _ in 0..10 {
                let i = LiftSafetyInputs {
                    stop_ch1: ch1,
                    stop_ch2: ch2,
                    overtravel_bottom_released: bottom,
                    overtravel_top_released: top,
                    overloaded,
                    k1_aux: !k1,
                    operator_reset: reset,
                    err_ack: ack,
                    controller_restart: restart,
                };
                let out = safety.scan(SimTime::from_millis(t), &i);
                k1 = out.k1;
                demand_since = if ch1 && ch2 { None } else { demand_since.or(Some(t)) };
                if k1 {
                    prop_assert!(!overloaded, "K1 closed while overloaded at {t} ms");
                    prop_assert!(bottom && top, "K1 closed with an overtravel sensor tripped at {t} ms");
                    prop_assert!(!out.diag.group.errors.any(), "K1 closed with a group error at {t} ms");
                    prop_assert!(
                        demand_since.is_none_or(|s| t < s + 200),
                        "K1 closed at {t} ms, STOP demanded since {demand_since:?}"
                    );
                    prop_assert!(out.diag.k1_open_cause.is_none());
                } else {
                    prop_assert!(out.diag.k1_open_cause.is_some());
                }
                t += 1;
            }
        }
    }
}
