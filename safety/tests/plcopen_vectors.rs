//! Cycle-by-cycle vectors of docs/safety-logic.md §9.2 for the PLCopen blocks.

use asi_phy::{SimDuration, SimTime};
use safety::plcopen::{
    DiagCode, SfEdm, SfEdmInputs, SfEmergencyStop, SfEmergencyStopInputs, SfEquivalent,
    SfEquivalentInputs,
};

/// One row of a SF_EmergencyStop vector, in the column order of docs/safety-logic.md §9.2:
/// Activate, S_EStopIn, Reset → DiagCode, S_EStopOut, SafetyDemand, ResetRequest, Error.
type Row = (u8, u8, u8, u16, u8, u8, u8, u8);

fn run_estop(start_reset: bool, auto_reset: bool, rows: &[Row]) {
    let mut fb = SfEmergencyStop::new();
    for (scan, &(act, inp, reset, diag, out, demand, reset_req, err)) in rows.iter().enumerate() {
        let o = fb.call(SfEmergencyStopInputs {
            activate: act == 1,
            s_estop_in: inp == 1,
            s_start_reset: start_reset,
            s_auto_reset: auto_reset,
            reset: reset == 1,
        });
        let got = (
            o.diag_code,
            o.s_estop_out,
            o.safety_demand,
            o.reset_request,
            o.error,
            o.ready,
        );
        let want = (
            DiagCode(diag),
            out == 1,
            demand == 1,
            reset_req == 1,
            err == 1,
            diag != 0,
        );
        assert_eq!(
            got, want,
            "scan {scan}: (diag, out, demand, reset_req, err, ready)"
        );
    }
}

#[test]
fn estop_fig23_start_reset_demand_restart() {
    // docs/safety-logic.md §9.2, S_StartReset = 0, S_AutoReset = 0.
    run_estop(
        false,
        false,
        &[
            (0, 0, 0, 0x0000, 0, 0, 0, 0),
            (1, 0, 0, 0x8001, 0, 0, 0, 0),
            (1, 0, 0, 0x8802, 0, 1, 0, 0),
            (1, 1, 0, 0x8402, 0, 0, 1, 0),
            (1, 1, 1, 0x8000, 1, 0, 0, 0),
            (1, 1, 0, 0x8000, 1, 0, 0, 0),
            (1, 0, 0, 0x8804, 0, 1, 0, 0),
            (1, 1, 0, 0x8404, 0, 0, 1, 0),
            (1, 1, 1, 0x8000, 1, 0, 0, 0),
        ],
    );
}

#[test]
fn estop_fig24_start_reset_enables_without_reset_but_a_demand_needs_one() {
    run_estop(
        true,
        false,
        &[
            (0, 1, 0, 0x0000, 0, 0, 0, 0),
            (1, 1, 0, 0x8001, 0, 0, 0, 0),
            (1, 1, 0, 0x8000, 1, 0, 0, 0),
            (1, 0, 0, 0x8804, 0, 1, 0, 0),
            (1, 1, 0, 0x8404, 0, 0, 1, 0),
            (1, 1, 0, 0x8404, 0, 0, 1, 0),
            (1, 1, 1, 0x8000, 1, 0, 0, 0),
        ],
    );
}

#[test]
fn estop_fig24_start_reset_with_demand_at_start_waits_in_8804() {
    run_estop(
        true,
        false,
        &[
            (1, 0, 0, 0x8001, 0, 0, 0, 0),
            (1, 0, 0, 0x8804, 0, 1, 0, 0),
            (1, 1, 0, 0x8404, 0, 0, 1, 0),
        ],
    );
}

#[test]
fn estop_fig25_auto_reset_needs_reset_at_start_only() {
    run_estop(
        false,
        true,
        &[
            (1, 0, 0, 0x8001, 0, 0, 0, 0),
            (1, 0, 0, 0x8802, 0, 1, 0, 0),
            (1, 1, 0, 0x8402, 0, 0, 1, 0),
            (1, 1, 0, 0x8402, 0, 0, 1, 0),
            (1, 1, 1, 0x8000, 1, 0, 0, 0),
            (1, 0, 0, 0x8804, 0, 1, 0, 0),
            (1, 0, 0, 0x8804, 0, 1, 0, 0),
            (1, 1, 0, 0x8000, 1, 0, 0, 0),
        ],
    );
}

#[test]
fn estop_stuck_reset_on_the_start_path_gives_c001_until_released() {
    run_estop(
        false,
        false,
        &[
            (1, 0, 0, 0x8001, 0, 0, 0, 0),
            (1, 0, 0, 0x8802, 0, 1, 0, 0),
            (1, 0, 1, 0xC001, 0, 0, 0, 1),
            (1, 1, 1, 0xC001, 0, 0, 0, 1),
            (1, 1, 0, 0x8802, 0, 1, 0, 0),
            (1, 1, 0, 0x8402, 0, 0, 1, 0),
            // no acknowledgement until a new edge
            (1, 1, 0, 0x8402, 0, 0, 1, 0),
            (1, 1, 1, 0x8000, 1, 0, 0, 0),
        ],
    );
}

#[test]
fn estop_reset_held_from_power_up_is_static_and_never_enables() {
    run_estop(
        false,
        false,
        &[
            (0, 1, 1, 0x0000, 0, 0, 0, 0),
            (1, 1, 1, 0x8001, 0, 0, 0, 0),
            (1, 1, 1, 0x8802, 0, 1, 0, 0),
            (1, 1, 1, 0xC001, 0, 0, 0, 1),
            (1, 1, 1, 0xC001, 0, 0, 0, 1),
        ],
    );
}

#[test]
fn estop_stuck_reset_after_a_demand_gives_c011() {
    run_estop(
        true,
        false,
        &[
            (1, 1, 0, 0x8001, 0, 0, 0, 0),
            (1, 1, 0, 0x8000, 1, 0, 0, 0),
            (1, 0, 1, 0x8804, 0, 1, 0, 0),
            (1, 1, 1, 0xC011, 0, 0, 0, 1),
            (1, 1, 0, 0x8804, 0, 1, 0, 0),
            (1, 1, 0, 0x8404, 0, 0, 1, 0),
            (1, 1, 1, 0x8000, 1, 0, 0, 0),
        ],
    );
}

#[test]
fn estop_activate_dropped_in_every_state_goes_idle_in_the_same_scan() {
    // Reach each state with a prefix, then drop Activate: 0000 and all outputs 0 at once.
    // (state reached, S_StartReset, [(S_EStopIn, Reset)] scans from Idle with Activate = 1)
    type Prefix = (u16, bool, &'static [(u8, u8)]);
    let prefixes: [Prefix; 8] = [
        (0x8001, false, &[(0, 0)]),
        (0x8802, false, &[(0, 0), (0, 0)]),
        (0x8402, false, &[(0, 0), (0, 0), (1, 0)]),
        (0x8000, false, &[(0, 0), (0, 0), (1, 0), (1, 1)]),
        (0x8804, true, &[(0, 0), (0, 0)]),
        (0x8404, true, &[(0, 0), (0, 0), (1, 0)]),
        (0xC001, false, &[(0, 0), (0, 0), (0, 1)]),
        (0xC011, true, &[(0, 0), (0, 0), (0, 1)]),
    ];
    let auto_reset = false;
    for (code, start_reset, steps) in prefixes {
        let mut fb = SfEmergencyStop::new();
        let mut last = None;
        for &(inp, reset) in steps {
            last = Some(fb.call(SfEmergencyStopInputs {
                activate: true,
                s_estop_in: inp == 1,
                s_start_reset: start_reset,
                s_auto_reset: auto_reset,
                reset: reset == 1,
            }));
        }
        assert_eq!(
            last.map(|o| o.diag_code),
            Some(DiagCode(code)),
            "prefix reaches {code:04X}"
        );
        let o = fb.call(SfEmergencyStopInputs {
            activate: false,
            s_estop_in: true,
            s_start_reset: start_reset,
            s_auto_reset: auto_reset,
            reset: false,
        });
        assert_eq!(o.diag_code, DiagCode::IDLE, "from {code:04X}");
        assert!(!(o.ready || o.s_estop_out || o.safety_demand || o.reset_request || o.error));
    }
}

fn ms(n: u64) -> SimTime {
    SimTime::from_millis(n)
}

fn equivalent(fb: &mut SfEquivalent, t: u64, a: bool, b: bool) -> (u16, bool, bool) {
    let o = fb.call(
        ms(t),
        SfEquivalentInputs {
            activate: true,
            s_channel_a: a,
            s_channel_b: b,
            discrepancy_time: SimDuration::from_millis(100),
        },
    );
    (o.diag_code.0, o.s_equivalent_out, o.error)
}

#[test]
fn equivalent_b_follows_a_within_the_discrepancy_time() {
    // docs/safety-logic.md §9.2: DiscrepancyTime 100 ms, scan 10 ms.
    let mut fb = SfEquivalent::new();
    assert_eq!(equivalent(&mut fb, 0, false, false), (0x8801, false, false));
    assert_eq!(equivalent(&mut fb, 10, true, false), (0x8802, false, false));
    for t in (20..70).step_by(10) {
        assert_eq!(equivalent(&mut fb, t, true, false).0, 0x8802);
    }
    assert_eq!(equivalent(&mut fb, 70, true, true), (0x8000, true, false));
}

#[test]
fn equivalent_errors_one_scan_after_the_timer_expires_and_clears_with_both_false() {
    let mut fb = SfEquivalent::new();
    equivalent(&mut fb, 0, false, false);
    assert_eq!(equivalent(&mut fb, 10, true, false).0, 0x8802); // timer starts at 10 ms
    for t in (20..=100).step_by(10) {
        assert_eq!(equivalent(&mut fb, t, true, false).0, 0x8802, "t = {t} ms");
    }
    assert_eq!(
        equivalent(&mut fb, 110, true, false).0,
        0x8802,
        "timer.Q set at 110"
    );
    assert!(
        fb.timer_q(),
        "timer expired, error not yet shown: the one-scan lag"
    );
    assert_eq!(equivalent(&mut fb, 120, true, false), (0xC010, false, true));
    assert_eq!(
        equivalent(&mut fb, 130, true, true),
        (0xC010, false, true),
        "no way back up"
    );
    assert_eq!(
        equivalent(&mut fb, 140, false, false),
        (0x8801, false, false)
    );
}

#[test]
fn equivalent_drop_of_one_channel_opens_at_once_and_needs_both_low() {
    let mut fb = SfEquivalent::new();
    equivalent(&mut fb, 0, false, false);
    equivalent(&mut fb, 10, true, true);
    assert_eq!(equivalent(&mut fb, 20, true, true), (0x8000, true, false));
    assert_eq!(equivalent(&mut fb, 30, false, true), (0x8806, false, false));
    assert_eq!(
        equivalent(&mut fb, 40, true, true),
        (0x8806, false, false),
        "A back is not enough"
    );
    assert_eq!(
        equivalent(&mut fb, 50, false, false),
        (0x8801, false, false)
    );
    // and the same drop without B following
    equivalent(&mut fb, 60, true, true);
    equivalent(&mut fb, 70, false, true);
    for t in (80..=170).step_by(10) {
        assert_eq!(equivalent(&mut fb, t, false, true).0, 0x8806, "t = {t} ms");
    }
    assert_eq!(equivalent(&mut fb, 180, false, true), (0xC030, false, true));
}

#[test]
fn equivalent_b_first_waits_for_a_and_times_out_with_c020() {
    let mut fb = SfEquivalent::new();
    equivalent(&mut fb, 0, false, false);
    assert_eq!(equivalent(&mut fb, 10, false, true).0, 0x8804);
    assert_eq!(equivalent(&mut fb, 110, false, true).0, 0x8804);
    assert_eq!(equivalent(&mut fb, 120, false, true).0, 0xC020);
}

fn edm(fb: &mut SfEdm, t: u64, control: bool, edm: bool, reset: bool) -> (u16, bool) {
    let o = fb.call(
        ms(t),
        SfEdmInputs {
            activate: true,
            s_out_control: control,
            s_edm1: edm,
            s_edm2: edm,
            monitoring_time: SimDuration::from_millis(50),
            s_start_reset: false,
            reset,
        },
    );
    (o.diag_code.0, o.s_edm_out)
}

#[test]
fn edm_enables_a_healthy_contactor_and_follows_its_feedback() {
    let mut fb = SfEdm::new();
    assert_eq!(edm(&mut fb, 0, false, true, false), (0x8401, false));
    assert_eq!(edm(&mut fb, 10, false, true, true), (0x8810, false));
    assert_eq!(edm(&mut fb, 20, true, true, false), (0x8000, true));
    // the contactor pulls in: its NC auxiliary contact opens within 50 ms
    assert_eq!(edm(&mut fb, 40, true, false, false), (0x8000, true));
    assert_eq!(edm(&mut fb, 200, true, false, false), (0x8000, true));
    assert_eq!(edm(&mut fb, 210, false, false, false), (0x8810, false));
    assert_eq!(edm(&mut fb, 230, false, true, false), (0x8810, false));
    assert_eq!(edm(&mut fb, 400, false, true, false), (0x8810, false));
}

#[test]
fn edm_detects_a_welded_contactor_after_switch_off() {
    let mut fb = SfEdm::new();
    edm(&mut fb, 0, false, true, false);
    edm(&mut fb, 10, false, true, true);
    edm(&mut fb, 20, true, true, false);
    edm(&mut fb, 30, true, false, false);
    assert_eq!(edm(&mut fb, 100, false, false, false), (0x8810, false));
    assert_eq!(
        edm(&mut fb, 150, false, false, false),
        (0x8810, false),
        "timer Q set now"
    );
    assert_eq!(edm(&mut fb, 160, false, false, false), (0xC060, false));
    // welded: enabling is refused; the error stays until a reset edge
    assert_eq!(edm(&mut fb, 170, true, false, false), (0xC060, false));
}

#[test]
fn edm_refuses_to_enable_while_the_feedback_is_not_released() {
    let mut fb = SfEdm::new();
    edm(&mut fb, 0, false, false, false);
    edm(&mut fb, 10, false, false, true);
    assert_eq!(edm(&mut fb, 20, true, false, false), (0xC030, false));
    edm(&mut fb, 30, false, true, false);
    assert_eq!(
        edm(&mut fb, 40, false, true, true),
        (0x8810, false),
        "reset edge"
    );
}

#[test]
fn edm_detects_a_contactor_that_does_not_pull_in() {
    let mut fb = SfEdm::new();
    edm(&mut fb, 0, false, true, false);
    edm(&mut fb, 10, false, true, true);
    assert_eq!(edm(&mut fb, 20, true, true, false), (0x8000, true));
    assert_eq!(edm(&mut fb, 70, true, true, false), (0x8000, true));
    assert_eq!(edm(&mut fb, 80, true, true, false), (0xC090, false));
}

#[test]
fn edm_static_reset_and_simultaneous_edges_are_errors() {
    let mut fb = SfEdm::new();
    assert_eq!(edm(&mut fb, 0, false, true, true), (0x8401, false));
    assert_eq!(edm(&mut fb, 10, false, true, true), (0xC001, false));
    assert_eq!(edm(&mut fb, 20, false, true, false), (0x8401, false));
    assert_eq!(edm(&mut fb, 30, true, true, true), (0xC100, false));
}
