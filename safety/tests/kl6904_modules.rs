//! KL6904 function modules scan by scan: docs/safety-logic.md §9.2 "KL6904 ESTOP", MON with
//! manual restart, OPMODE with none, one and two inputs.

use asi_phy::{SimDuration, SimTime};
use safety::kl6904::modules::{
    Estop, EstopConfig, EstopInputs, FbError, FbEvent, FbState, Mon, MonConfig, MonInputs, OpMode,
    OpModeConfig, OpModeInputs,
};
use safety::kl6904::signal::Contact;

fn ms(n: u64) -> SimTime {
    SimTime::from_millis(n)
}

/// The §9.2 ESTOP: pair 1/2 with 50 ms discrepancy, delay 500 ms, EDM1 on.
fn estop() -> Estop {
    let mut inputs = [None; 8];
    inputs[0] = Some(Contact::Break);
    inputs[1] = Some(Contact::Break);
    Estop::new({
        let mut cfg = EstopConfig::default();
        cfg.inputs = inputs;
        cfg.discrepancy = [
            SimDuration::from_millis(50),
            SimDuration::ZERO,
            SimDuration::ZERO,
            SimDuration::ZERO,
        ];
        cfg.edm1 = true;
        cfg.edm2 = false;
        cfg.delay = SimDuration::from_millis(500);
        cfg
    })
}

fn ein(in1: bool, in2: bool, restart: bool, edm1: bool) -> EstopInputs {
    let mut estop_in = [false; 8];
    estop_in[0] = in1;
    estop_in[1] = in2;
    EstopInputs {
        estop_in,
        restart,
        edm1,
        edm2: false,
    }
}

/// Drive a 0→1→0 Restart pulse one scan per ms from `t`; returns the outputs after it.
fn restart_pulse(
    fb: &mut Estop,
    t: &mut u64,
    in1: bool,
    in2: bool,
    edm1: bool,
) -> (bool, bool, bool) {
    for r in [false, true, false] {
        fb.scan(ms(*t), true, &ein(in1, in2, r, edm1));
        *t += 1;
    }
    let o = fb.scan(ms(*t), true, &ein(in1, in2, false, edm1));
    *t += 1;
    (o.estop_out, o.estop_del_out, o.error)
}

#[test]
fn estop_starts_safe_and_a_restart_pulse_enables_on_its_falling_edge() {
    let mut fb = estop();
    let o = fb.scan(ms(0), true, &ein(true, true, false, true));
    assert_eq!(
        (o.estop_out, o.estop_del_out),
        (false, false),
        "power-up: safe"
    );
    let o = fb.scan(ms(1), true, &ein(true, true, true, true));
    assert!(!o.estop_out, "rising edge of Restart does nothing yet");
    let o = fb.scan(ms(2), true, &ein(true, true, true, true));
    assert!(!o.estop_out, "Restart held");
    let o = fb.scan(ms(3), true, &ein(true, true, false, true));
    assert_eq!(
        (o.estop_out, o.estop_del_out),
        (true, true),
        "falling edge releases"
    );
    assert_eq!(fb.events(), &[FbEvent::Restarted]);
}

#[test]
fn estop_demand_drops_out_at_once_and_del_out_after_the_delay() {
    let mut fb = estop();
    let mut t = 0;
    assert_eq!(
        restart_pulse(&mut fb, &mut t, true, true, true),
        (true, true, false)
    );
    let t0 = t;
    // both channels open (within the discrepancy time of each other)
    let o = fb.scan(ms(t0), true, &ein(false, true, false, true));
    assert_eq!(
        (o.estop_out, o.estop_del_out),
        (false, true),
        "immediate output drops at once"
    );
    assert_eq!(fb.events(), &[FbEvent::SafeStateDemanded { inputs: 0b01 }]);
    for dt in 1..500 {
        let o = fb.scan(ms(t0 + dt), true, &ein(false, false, false, true));
        assert_eq!(
            (o.estop_out, o.estop_del_out),
            (false, true),
            "{dt} ms into the delay"
        );
    }
    let o = fb.scan(ms(t0 + 500), true, &ein(false, false, false, true));
    assert_eq!(
        (o.estop_out, o.estop_del_out),
        (false, false),
        "delay 500 ms elapsed"
    );
    assert_eq!(fb.events(), &[FbEvent::DelayedOutputOff]);
    assert_eq!(fb.state(), FbState::Safe);
}

#[test]
fn estop_released_button_needs_a_restart_pulse_and_a_pulse_during_the_delay_is_ignored() {
    let mut fb = estop();
    let mut t = 0;
    restart_pulse(&mut fb, &mut t, true, true, true);
    fb.scan(ms(t), true, &ein(false, false, false, true));
    t += 1;
    // button released again and restart pressed while EStopDelOut still runs its delay
    assert_eq!(
        restart_pulse(&mut fb, &mut t, true, true, true),
        (false, true, false)
    );
    for _ in 0..600 {
        let o = fb.scan(ms(t), true, &ein(true, true, false, true));
        t += 1;
        assert!(
            !o.estop_out,
            "inputs back to 1: outputs stay 0 without a restart"
        );
    }
    assert_eq!(
        restart_pulse(&mut fb, &mut t, true, true, true),
        (true, true, false)
    );
}

#[test]
fn estop_discrepancy_longer_than_50ms_is_an_error_until_acknowledged_and_restarted() {
    let mut fb = estop();
    let mut t = 0;
    restart_pulse(&mut fb, &mut t, true, true, true);
    let t0 = t;
    for dt in 0..=50 {
        let o = fb.scan(ms(t0 + dt), true, &ein(false, true, false, true));
        assert!(!o.error, "differing for {dt} ms is allowed");
    }
    let o = fb.scan(ms(t0 + 51), true, &ein(false, true, false, true));
    assert_eq!(
        (o.estop_out, o.estop_del_out, o.error),
        (false, false, true)
    );
    assert_eq!(fb.diag(), 0b0000_0001, "diag bit 0: pair 1");
    assert_eq!(
        fb.events(),
        &[FbEvent::Error(FbError::Discrepancy { pair: 1 })]
    );
    assert!(fb.error_cause_active(), "the pair still disagrees");
    t = t0 + 52;
    fb.scan(ms(t), true, &ein(true, true, false, true));
    assert!(!fb.error_cause_active(), "inputs restored");
    // a restart pulse alone does nothing in ERROR
    assert_eq!(
        restart_pulse(&mut fb, &mut t, true, true, true),
        (false, false, true)
    );
    fb.acknowledge();
    assert_eq!(fb.state(), FbState::Safe);
    assert_eq!(fb.diag(), 0);
    assert_eq!(
        restart_pulse(&mut fb, &mut t, true, true, true),
        (true, true, false)
    );
}

#[test]
fn estop_welded_contactor_is_an_edm_error_at_restart() {
    let mut fb = estop();
    let mut t = 0;
    assert_eq!(
        restart_pulse(&mut fb, &mut t, true, true, false),
        (false, false, true),
        "EDM1 = 0 at restart: refused, Error"
    );
    assert_eq!(fb.diag(), 0b0001_0000, "diag bit 4: EDM1");
    assert!(fb.error_cause_active(), "still welded");
    fb.scan(ms(t), true, &ein(true, true, false, true));
    t += 1;
    assert!(!fb.error_cause_active(), "contactor repaired");
    fb.acknowledge();
    assert_eq!(
        restart_pulse(&mut fb, &mut t, true, true, true),
        (true, true, false)
    );
}

#[test]
fn estop_is_stopped_with_its_group_and_starts_safe_again() {
    let mut fb = estop();
    let mut t = 0;
    restart_pulse(&mut fb, &mut t, true, true, true);
    let o = fb.scan(ms(t), false, &ein(true, true, false, true));
    assert_eq!(
        (o.estop_out, o.estop_del_out),
        (false, false),
        "group stopped: outputs 0 at once"
    );
    assert_eq!(fb.state(), FbState::Stop);
    t += 1;
    let o = fb.scan(ms(t), true, &ein(true, true, false, true));
    assert!(!o.estop_out, "restarted group: restart pulse needed");
    t += 1;
    assert_eq!(
        restart_pulse(&mut fb, &mut t, true, true, true),
        (true, true, false)
    );
}

fn overtravel_mon() -> Mon {
    Mon::new({
        let mut cfg = MonConfig::default();
        cfg.inputs = [Some(Contact::Break), Some(Contact::Break), None, None];
        cfg.manual_restart = true;
        cfg.edm1 = true;
        cfg
    })
}

fn min(bottom: bool, top: bool, restart: bool, edm1: bool) -> MonInputs {
    MonInputs {
        mon_in: [bottom, top, false, false],
        restart,
        edm1,
        ..Default::default()
    }
}

#[test]
fn mon_with_manual_restart_needs_the_operator_after_every_demand() {
    let mut fb = overtravel_mon();
    assert!(
        !fb.scan(ms(0), true, &min(true, true, false, true)).mon_out,
        "start: safe"
    );
    fb.scan(ms(1), true, &min(true, true, true, true));
    assert!(
        fb.scan(ms(2), true, &min(true, true, false, true)).mon_out,
        "operator reset"
    );
    let o = fb.scan(ms(3), true, &min(false, true, false, true));
    assert_eq!(
        (o.mon_out, o.mon_del_out),
        (false, false),
        "bottom sensor tripped: no delay"
    );
    for t in 4..20 {
        assert!(
            !fb.scan(ms(t), true, &min(true, true, false, true)).mon_out,
            "cranked back: still off"
        );
    }
    // the operator presses reset while the sensor is still tripped: ignored
    fb.scan(ms(20), true, &min(false, true, true, true));
    assert!(!fb.scan(ms(21), true, &min(true, true, false, true)).mon_out);
    fb.scan(ms(22), true, &min(true, true, true, true));
    assert!(fb.scan(ms(23), true, &min(true, true, false, true)).mon_out);
}

#[test]
fn mon_with_manual_restart_detects_a_welded_contactor() {
    let mut fb = overtravel_mon();
    fb.scan(ms(0), true, &min(true, true, false, false));
    fb.scan(ms(1), true, &min(true, true, true, false));
    let o = fb.scan(ms(2), true, &min(true, true, false, false));
    assert_eq!((o.mon_out, o.error), (false, true));
    assert_eq!(fb.diag(), 1 << 4);
}

#[test]
fn mon_with_automatic_restart_stays_safe_without_error_on_a_bad_edm() {
    let mut fb = Mon::new({
        let mut cfg = MonConfig::default();
        cfg.inputs = [Some(Contact::Break), None, None, None];
        cfg.edm1 = true;
        cfg
    });
    assert!(
        fb.scan(ms(0), true, &min(true, false, false, true)).mon_out,
        "automatic start"
    );
    assert!(
        !fb.scan(ms(1), true, &min(false, false, false, true))
            .mon_out
    );
    let o = fb.scan(ms(2), true, &min(true, false, false, false));
    assert_eq!(
        (o.mon_out, o.error),
        (false, false),
        "EDM 0: stays safe, no error"
    );
    assert!(fb.scan(ms(3), true, &min(true, false, false, true)).mon_out);
}

#[test]
fn mon_secure_inputs_mute_the_demand() {
    let mut fb = Mon::new({
        let mut cfg = MonConfig::default();
        cfg.inputs = [Some(Contact::Break), None, None, None];
        cfg.secure = Some(Contact::Break);
        cfg
    });
    let muted = |door: bool, s1: bool, s2: bool| MonInputs {
        mon_in: [door, false, false, false],
        secure: [s1, s2],
        ..Default::default()
    };
    assert!(fb.scan(ms(0), true, &muted(true, false, false)).mon_out);
    assert!(
        fb.scan(ms(1), true, &muted(false, true, true)).mon_out,
        "door open but muted"
    );
    assert!(
        !fb.scan(ms(2), true, &muted(false, true, false)).mon_out,
        "one Secure off: demand"
    );
}

#[test]
fn mon_function_test_requires_each_input_to_demand_once_after_start() {
    let mut fb = Mon::new({
        let mut cfg = MonConfig::default();
        cfg.inputs = [Some(Contact::Break), Some(Contact::Break), None, None];
        cfg.manual_restart = true;
        cfg.function_test = true;
        cfg
    });
    let pulse = |fb: &mut Mon, t0: u64| {
        for (k, r) in [false, true, false].into_iter().enumerate() {
            fb.scan(ms(t0 + k as u64), true, &min(true, true, r, false));
        }
        fb.state()
    };
    assert_eq!(pulse(&mut fb, 0), FbState::Safe, "no input tested yet");
    fb.scan(ms(100), true, &min(false, true, false, false));
    assert_eq!(pulse(&mut fb, 101), FbState::Safe, "MonIn2 not tested yet");
    fb.scan(ms(200), true, &min(true, false, false, false));
    assert_eq!(pulse(&mut fb, 201), FbState::Run);
}

#[test]
fn mon_pair_discrepancy_sets_diag_bit_0() {
    let mut fb = Mon::new({
        let mut cfg = MonConfig::default();
        cfg.inputs = [Some(Contact::Break), Some(Contact::Break), None, None];
        cfg.discrepancy = [SimDuration::from_millis(20), SimDuration::ZERO];
        cfg
    });
    for t in 0..=20 {
        assert!(!fb.scan(ms(t), true, &min(true, false, false, false)).error);
    }
    assert!(fb.scan(ms(21), true, &min(true, false, false, false)).error);
    assert_eq!(fb.diag(), 1);
}

fn opmode(restart: bool, discrepancy_ms: u64) -> OpMode {
    OpMode::new({
        let mut cfg = OpModeConfig::default();
        cfg.inputs = [true, true, true, false, false, false, false, false];
        cfg.restart = restart;
        cfg.discrepancy = SimDuration::from_millis(discrepancy_ms);
        cfg
    })
}

fn sel(a: bool, b: bool, c: bool, restart: bool) -> OpModeInputs {
    OpModeInputs {
        op_in: [a, b, c, false, false, false, false, false],
        restart,
    }
}

#[test]
fn opmode_exactly_one_input_selects_its_output_none_or_two_make_all_safe() {
    let mut fb = opmode(false, 0);
    let out = |fb: &mut OpMode, t, a, b, c| {
        fb.scan(ms(t), true, &sel(a, b, c, false)).op_out[..3].to_vec()
    };
    assert_eq!(
        out(&mut fb, 0, false, false, false),
        [false, false, false],
        "none"
    );
    assert_eq!(
        out(&mut fb, 1, false, true, false),
        [false, true, false],
        "one"
    );
    assert_eq!(
        out(&mut fb, 2, true, true, false),
        [false, false, false],
        "two"
    );
    assert_eq!(out(&mut fb, 3, true, false, false), [true, false, false]);
    assert_eq!(
        out(&mut fb, 4, false, false, true),
        [false, false, true],
        "direct change"
    );
    assert!(
        !fb.scan(ms(5), true, &sel(true, true, true, false)).error,
        "no discrepancy time: no error"
    );
}

#[test]
fn opmode_with_restart_needs_a_pulse_at_start_and_after_each_mode_change() {
    let mut fb = opmode(true, 0);
    assert!(!fb.scan(ms(0), true, &sel(true, false, false, false)).op_out[0]);
    fb.scan(ms(1), true, &sel(true, false, false, true));
    assert!(fb.scan(ms(2), true, &sel(true, false, false, false)).op_out[0]);
    assert_eq!(fb.mode(), Some(0));
    let o = fb.scan(ms(3), true, &sel(false, true, false, false));
    assert_eq!(
        o.op_out[..2],
        [false, false],
        "mode change: safe until restart"
    );
    fb.scan(ms(4), true, &sel(false, true, false, true));
    assert!(fb.scan(ms(5), true, &sel(false, true, false, false)).op_out[1]);
}

#[test]
fn opmode_invalid_selection_longer_than_the_discrepancy_time_is_an_error() {
    let mut fb = opmode(false, 30);
    fb.scan(ms(0), true, &sel(true, false, false, false));
    for t in 1..=31 {
        assert!(
            !fb.scan(ms(t), true, &sel(true, true, false, false)).error,
            "t = {t}"
        );
    }
    let o = fb.scan(ms(32), true, &sel(true, true, false, false));
    assert!(o.error);
    assert_eq!(fb.diag(), 1);
    assert!(fb.error_cause_active());
    fb.scan(ms(33), true, &sel(false, true, false, false));
    assert!(!fb.error_cause_active());
    fb.acknowledge();
    assert!(
        fb.scan(ms(34), true, &sel(false, true, false, false))
            .op_out[1]
    );
}
