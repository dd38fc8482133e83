//! `safety::drive`: the SafeMOTION thesis' test guides (appendix A) with its demo parameters, the
//! decisions of docs/drive-safety.md, the no-encoder restriction and property tests of the
//! monitoring.

use asi_phy::{SimDuration, SimTime};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use safety::drive::{
    AxisFeedback, ControlBits, DriveConfigError, DriveEventKind, DriveSafetyConfig,
    DriveSafetyInputs, DriveSafetyOutputs, Encoder, Function, SafeDrive, SlsLevel, Violation,
};

/// 10 ms per scan: fine enough for the guides' seconds, coarse enough for fast tests.
const SCAN_MS: u64 = 10;
/// The request in every guide test comes at 2 s.
const T0_MS: u64 = 2_000;

const SLS1: Function = Function::Sls(SlsLevel::L1);
const SLS2: Function = Function::Sls(SlsLevel::L2);

/// A drive on the SafeMOTION thesis' stand: an axis whose speed the test sets (the standard motion
/// control) and whose position is integrated from it, scanned every 10 ms.
struct Stand {
    drive: SafeDrive,
    now_ms: u64,
    position: f64,
    speed: f64,
    control: ControlBits,
    encoder: bool,
    /// The drive's torque, mNm, as its current shows it (`None`: not reported).
    torque: Option<f64>,
    last: Option<DriveSafetyOutputs>,
    trips: Vec<(u64, Violation)>,
}

impl Stand {
    fn new(config: DriveSafetyConfig) -> Self {
        let encoder = config.encoder.is_safe();
        Self {
            drive: SafeDrive::new(config).expect("valid parameters"),
            now_ms: 0,
            position: 0.0,
            speed: 0.0,
            control: ControlBits::idle(),
            encoder,
            torque: Some(0.0),
            last: None,
            trips: Vec::new(),
        }
    }

    fn demo() -> Self {
        Self::new(DriveSafetyConfig::demo())
    }

    /// One scan at the current time, then time and position move on by one scan period.
    fn scan(&mut self) -> &DriveSafetyOutputs {
        let inputs = DriveSafetyInputs {
            control: self.control,
            feedback: self.encoder.then_some(AxisFeedback {
                position: self.position,
                speed: self.speed,
            }),
            torque: self.torque,
        };
        let out = self.drive.scan(SimTime::from_millis(self.now_ms), &inputs);
        for e in &out.events {
            if let DriveEventKind::Tripped(v) = e.kind {
                self.trips.push((self.now_ms, v));
            }
        }
        self.now_ms += SCAN_MS;
        self.position += self.speed * SCAN_MS as f64 / 1000.0;
        self.last = Some(out);
        self.out()
    }

    fn out(&self) -> &DriveSafetyOutputs {
        self.last.as_ref().expect("scanned")
    }

    /// Scans up to (not including) `t_ms`.
    fn run_until(&mut self, t_ms: u64) {
        while self.now_ms < t_ms {
            self.scan();
        }
    }

    /// Scans up to `limit_ms` with `speed(t)` set before each scan; the first scan time at
    /// which `pred` holds.
    fn first(
        &mut self,
        limit_ms: u64,
        speed: impl Fn(u64) -> f64,
        pred: impl Fn(&DriveSafetyOutputs) -> bool,
    ) -> Option<u64> {
        while self.now_ms < limit_ms {
            self.speed = speed(self.now_ms);
            let t = self.now_ms;
            if pred(self.scan()) {
                return Some(t);
            }
        }
        None
    }

    fn request(&mut self, f: Function) {
        self.control = self.control.with_request(f);
    }

    fn release(&mut self, f: Function) {
        self.control = self.control.without_request(f);
    }

    /// A Reset pulse: one scan TRUE, one FALSE.
    fn reset(&mut self) {
        self.control.reset = true;
        self.scan();
        self.control.reset = false;
        self.scan();
    }

    fn status(&self, f: Function) -> bool {
        self.out().status.of(f)
    }
}

/// Seconds after the request, in ms of simulated time.
const fn at(s: f64) -> u64 {
    T0_MS + (s * 1000.0) as u64
}

// ---------------------------------------------------------------------------------------------
// The SafeMOTION thesis, appendix A: one test per guide, demo parameters.
// ---------------------------------------------------------------------------------------------

/// A.2: STO de-energises at once and stays off while requested; the status is TRUE.
#[test]
fn guide_sto_torque_off_at_once_while_requested() {
    let mut s = Stand::demo();
    s.speed = 5.0;
    s.run_until(T0_MS);
    assert!(s.out().torque_enabled && s.out().brake_released);
    s.request(Function::Sto);
    s.scan();
    assert!(!s.out().torque_enabled, "off in the scan of the request");
    assert!(!s.out().brake_released);
    assert!(s.status(Function::Sto));
    assert!(s.out().status.not_err_func, "STO is not an error");
    s.run_until(at(30.0));
    assert!(!s.out().torque_enabled && s.status(Function::Sto));
    s.release(Function::Sto);
    s.scan();
    assert!(s.out().torque_enabled && !s.status(Function::Sto));
}

/// A.3 steps 4–5: SOS requested below 2 rev/s is OK at once, torque stays on.
#[test]
fn guide_sos_ok_below_speed_tolerance() {
    let mut s = Stand::demo();
    s.speed = 1.0;
    s.run_until(T0_MS);
    s.request(Function::Sos);
    s.scan();
    assert!(s.status(Function::Sos) && s.out().torque_enabled);
    assert_eq!(s.out().speed_command_limit, Some(0.0));
    s.run_until(at(60.0)); // 60 rev, inside 100 rev
    assert!(s.status(Function::Sos) && s.out().status.not_err_func);
    assert!(s.trips.is_empty());
}

/// A.3 step 6: a speed above 2 rev/s de-energises at once (NOK).
#[test]
fn guide_sos_nok_above_speed_tolerance() {
    let mut s = Stand::demo();
    s.speed = 1.0;
    s.run_until(T0_MS);
    s.request(Function::Sos);
    s.run_until(at(3.0));
    let t = s.first(at(10.0), |_| 2.5, |o| !o.torque_enabled);
    assert_eq!(t, Some(at(3.0)));
    assert!(!s.out().status.not_err_func && !s.status(Function::Sos));
    assert!(matches!(
        s.trips[..],
        [(_, Violation::SpeedAbove { function: Function::Sos, limit, .. })] if limit == 2.0
    ));
}

/// A.3 step 6, alternative: more than 100 rev in one direction since the request (NOK).
#[test]
fn guide_sos_nok_after_100_rev_in_one_direction() {
    let mut s = Stand::demo();
    s.run_until(T0_MS);
    s.request(Function::Sos);
    // 1.5 rev/s: 100 rev after 66.67 s.
    let t = s
        .first(at(100.0), |_| 1.5, |o| !o.torque_enabled)
        .expect("trips");
    assert!((at(66.66)..=at(66.68)).contains(&t), "tripped at {t} ms");
    assert!(matches!(
        s.trips[..],
        [(_, Violation::MovedTooFar { function: Function::Sos, travel, .. })] if travel > 100.0
    ));
}

/// A.4 step 5: the axis keeps running, SS1 de-energises at enable delay + ramp time = 15 s;
/// "Del+Decel" (SDC) until then; not an error.
#[test]
fn guide_ss1_running_axis_de_energised_at_15_s() {
    let mut s = Stand::demo();
    s.speed = 10.0;
    s.run_until(T0_MS);
    s.request(Function::Ss1);
    let t = s.first(at(30.0), |_| 10.0, |o| !o.torque_enabled);
    assert_eq!(t, Some(at(15.0)));
    assert!(s.status(Function::Ss1) && !s.out().status.sdc);
    assert!(s.out().status.not_err_func && s.trips.is_empty());
}

/// A.4 step 5: SDC is TRUE from the request until the torque is off.
#[test]
fn guide_ss1_sdc_from_request_to_safe_state() {
    let mut s = Stand::demo();
    s.speed = 10.0;
    s.run_until(T0_MS);
    s.request(Function::Ss1);
    s.scan();
    assert!(s.out().status.sdc && !s.status(Function::Ss1) && s.out().torque_enabled);
    s.run_until(at(15.0));
    assert!(s.out().status.sdc, "still Del+Decel just before 15 s");
    s.scan();
    assert!(!s.out().status.sdc && s.status(Function::Ss1));
}

/// A.4 step 5, early limit — **Decision**: the early-limit timer runs from the end of the
/// enable delay, so an axis under 2 rev/s from the request is de-energised at 5 + 5 = 10 s.
#[test]
fn guide_ss1_early_limit_under_2_rev_s_for_5_s() {
    let mut s = Stand::demo();
    s.speed = 1.0;
    s.run_until(T0_MS);
    s.request(Function::Ss1);
    let t = s.first(at(30.0), |_| 1.0, |o| !o.torque_enabled);
    assert_eq!(t, Some(at(10.0)));
}

/// The standard control brakes 10 → 0 rev/s at 1 rev/s² from the request: under 2 rev/s at
/// 8 s, so the early limit ends the window at 13 s.
#[test]
fn ss1_braking_axis_early_limit_after_5_s_under_tolerance() {
    let mut s = Stand::demo();
    s.speed = 10.0;
    s.run_until(T0_MS);
    s.request(Function::Ss1);
    let brake = |t: u64| (10.0 - (t - T0_MS) as f64 / 1000.0).max(0.0);
    let t = s.first(at(30.0), brake, |o| !o.torque_enabled);
    assert_eq!(t, Some(at(13.0)));
}

/// The early limit needs the condition without a break: a burst above 2 rev/s restarts it.
#[test]
fn ss1_early_limit_restarts_after_a_burst() {
    let mut s = Stand::demo();
    s.run_until(T0_MS);
    s.request(Function::Ss1);
    let profile = |t: u64| {
        if (at(8.0)..at(9.0)).contains(&t) {
            3.0
        } else {
            1.0
        }
    };
    let t = s.first(at(30.0), profile, |o| !o.torque_enabled);
    assert_eq!(t, Some(at(14.0)));
}

/// A.5: the axis at −7 rev/s is braked at 1 rev/s² by the standard control; under 2 rev/s at
/// 5 s, so OK at 10 s (early limit from the end of the enable delay). The torque stays on.
#[test]
fn guide_ss2_reaches_standstill_then_holds_with_torque_on() {
    let mut s = Stand::demo();
    s.speed = -7.0;
    s.run_until(T0_MS);
    s.request(Function::Ss2);
    let brake = |t: u64| (-7.0 + (t - T0_MS) as f64 / 1000.0).min(0.0);
    let t = s.first(at(30.0), brake, |o| o.status.of(Function::Ss2));
    assert_eq!(t, Some(at(10.0)));
    assert!(s.out().torque_enabled && !s.out().status.sdc);
    s.run_until(at(40.0));
    assert!(s.status(Function::Ss2) && s.trips.is_empty());
}

/// A.5 step 6: after the standstill, a speed above 2 rev/s is NOK.
#[test]
fn guide_ss2_nok_above_speed_tolerance_after_standstill() {
    let mut s = Stand::demo();
    s.run_until(T0_MS);
    s.request(Function::Ss2);
    s.run_until(at(12.0));
    assert!(s.status(Function::Ss2));
    let t = s.first(at(20.0), |_| -3.0, |o| !o.torque_enabled);
    assert_eq!(t, Some(at(12.0)));
    assert!(matches!(
        s.trips[..],
        [(
            _,
            Violation::SpeedAbove {
                function: Function::Ss2,
                ..
            }
        )]
    ));
}

/// A.5 step 6, alternative: more than 100 rev from the standstill position is NOK.
#[test]
fn guide_ss2_nok_after_100_rev_from_standstill() {
    let mut s = Stand::demo();
    s.run_until(T0_MS);
    s.request(Function::Ss2);
    s.run_until(at(10.0) + SCAN_MS);
    assert!(s.status(Function::Ss2));
    // 1.9 rev/s from 10 s: 100 rev after 52.63 s.
    let t = s
        .first(at(100.0), |_| 1.9, |o| !o.torque_enabled)
        .expect("trips");
    assert!((at(62.62)..=at(62.65)).contains(&t), "tripped at {t} ms");
}

/// A.5 step 5: if the axis is not under 2 rev/s when the 15 s are over, NOK.
#[test]
fn guide_ss2_not_slowed_in_time_trips_at_window_end() {
    let mut s = Stand::demo();
    s.speed = 7.0;
    s.run_until(T0_MS);
    s.request(Function::Ss2);
    let t = s.first(at(30.0), |_| 7.0, |o| !o.torque_enabled);
    assert_eq!(t, Some(at(15.0)));
    assert!(matches!(
        s.trips[..],
        [(
            _,
            Violation::NotSlowedInTime {
                function: Function::Ss2,
                ..
            }
        )]
    ));
}

/// A.6 SLS1: slowed from 10 to 7 rev/s, OK at 10 s (early limit), then 9 rev/s is NOK.
#[test]
fn guide_sls1_ok_under_8_rev_s_then_nok_above() {
    let mut s = Stand::demo();
    s.speed = 10.0;
    s.run_until(T0_MS);
    s.request(SLS1);
    let slow = |t: u64| if t < at(2.0) { 10.0 } else { 7.0 };
    let t = s.first(at(30.0), slow, |o| o.status.of(SLS1));
    assert_eq!(t, Some(at(10.0)));
    assert_eq!(s.out().speed_command_limit, Some(8.0));
    let t = s.first(at(40.0), |_| 9.0, |o| !o.torque_enabled);
    assert_eq!(t, Some(at(10.01)));
}

/// A.6 SLS2: still above 5 rev/s when the window ends at 15 s: NOK.
#[test]
fn guide_sls2_not_slowed_in_time_trips_at_15_s() {
    let mut s = Stand::demo();
    s.speed = 6.0;
    s.run_until(T0_MS);
    s.request(SLS2);
    let t = s.first(at(30.0), |_| 6.0, |o| !o.torque_enabled);
    assert_eq!(t, Some(at(15.0)));
    assert!(matches!(
        s.trips[..],
        [(_, Violation::NotSlowedInTime { function: SLS2, target, .. })] if target == 5.0
    ));
}

/// §3.5 of the SafeMOTION thesis: with several levels active the lowest limit holds.
#[test]
fn sls_lowest_active_limit_holds() {
    let mut s = Stand::demo();
    s.speed = 4.0;
    s.run_until(T0_MS);
    s.request(SLS1);
    s.request(SLS2);
    s.run_until(at(12.0));
    assert!(s.status(SLS1) && s.status(SLS2));
    assert_eq!(s.out().speed_command_limit, Some(5.0));
    let t = s.first(at(20.0), |_| 6.0, |o| !o.torque_enabled);
    assert_eq!(t, Some(at(12.0)));
    assert!(matches!(
        s.trips[..],
        [(_, Violation::SpeedAbove { function: SLS2, .. })]
    ));
}

/// A.7: SLI requested at standstill is OK; after more than 50 rev it is NOK.
#[test]
fn guide_sli_nok_after_50_rev() {
    let mut s = Stand::demo();
    s.run_until(T0_MS);
    s.request(Function::Sli);
    s.scan();
    assert!(s.status(Function::Sli) && s.out().torque_enabled);
    // The drive starts at 1 s at 2 rev/s: 50 rev after 25 s more.
    let run = |t: u64| if t < at(1.0) { 0.0 } else { 2.0 };
    let t = s
        .first(at(60.0), run, |o| !o.torque_enabled)
        .expect("trips");
    assert!((at(26.0)..=at(26.02)).contains(&t), "tripped at {t} ms");
    assert!(matches!(
        s.trips[..],
        [(_, Violation::MovedTooFar { function: Function::Sli, limit, .. })] if limit == 50.0
    ));
}

/// §3.6 of the SafeMOTION thesis: SLI requested while the axis turns faster than 2 rev/s
/// de-energises.
#[test]
fn sli_requested_while_moving_trips() {
    let mut s = Stand::demo();
    s.speed = 3.0;
    s.run_until(T0_MS);
    s.request(Function::Sli);
    s.scan();
    assert!(!s.out().torque_enabled);
    assert!(matches!(
        s.trips[..],
        [(
            _,
            Violation::NotAtStandstill {
                function: Function::Sli,
                ..
            }
        )]
    ));
}

/// §3.6 of the SafeMOTION thesis: after the request ends SLI stays active for the 10 s disable
/// delay.
#[test]
fn sli_stays_active_for_its_disable_delay() {
    let mut s = Stand::demo();
    s.run_until(T0_MS);
    s.request(Function::Sli);
    s.scan(); // requested at standstill
    s.speed = 5.0;
    s.run_until(at(2.0)); // 10 rev
    s.release(Function::Sli);
    // 40 rev more at 5 rev/s: 8 s, inside the 10 s disable delay.
    let t = s
        .first(at(30.0), |_| 5.0, |o| !o.torque_enabled)
        .expect("trips");
    assert!((at(10.0)..=at(10.02)).contains(&t), "tripped at {t} ms");

    // Released and slow: no longer monitored after 10 s.
    let mut s = Stand::demo();
    s.run_until(T0_MS);
    s.request(Function::Sli);
    s.run_until(at(1.0));
    s.release(Function::Sli);
    s.speed = 1.0;
    s.run_until(at(11.0) + SCAN_MS);
    assert!(!s.status(Function::Sli));
    s.run_until(at(200.0));
    assert!(s.trips.is_empty() && s.out().torque_enabled);
}

/// A.8 SDI-P: turning forwards is OK; backwards, NOK after 100 rev.
#[test]
fn guide_sdi_p_nok_after_100_rev_backwards() {
    let mut s = Stand::demo();
    s.run_until(T0_MS);
    s.request(Function::SdiPos);
    s.scan();
    assert!(s.status(Function::SdiPos));
    s.speed = 5.0;
    s.run_until(at(100.0));
    assert!(s.trips.is_empty());
    let t = s
        .first(at(200.0), |_| -5.0, |o| !o.torque_enabled)
        .expect("trips");
    assert!((at(120.0)..=at(120.02)).contains(&t), "tripped at {t} ms");
    assert!(matches!(
        s.trips[..],
        [(
            _,
            Violation::WrongDirection {
                function: Function::SdiPos,
                ..
            }
        )]
    ));
}

/// A.8 SDI-N: turning backwards is OK; forwards at 5 rev/s, NOK after 100 rev (20 s).
#[test]
fn guide_sdi_n_nok_after_100_rev_forwards() {
    let mut s = Stand::demo();
    s.speed = -5.0;
    s.run_until(T0_MS);
    s.request(Function::SdiNeg);
    s.run_until(at(50.0));
    assert!(s.trips.is_empty() && s.status(Function::SdiNeg));
    let t = s
        .first(at(100.0), |_| 5.0, |o| !o.torque_enabled)
        .expect("trips");
    assert!((at(70.0)..=at(70.02)).contains(&t), "tripped at {t} ms");
}

/// **Decision**: SDI measures the travel back from the furthest point reached.
#[test]
fn sdi_counts_back_travel_from_the_furthest_point() {
    let mut s = Stand::demo();
    s.run_until(T0_MS);
    s.request(Function::SdiPos);
    s.speed = 10.0;
    s.run_until(at(50.0)); // 500 rev forwards
    let t = s
        .first(at(100.0), |_| -10.0, |o| !o.torque_enabled)
        .expect("trips");
    assert!((at(60.0)..=at(60.02)).contains(&t), "tripped at {t} ms");
}

/// §3.9 of the SafeMOTION thesis: SLP trips when the position leaves [lower, upper] after its
/// enable delay.
#[test]
fn slp_trips_outside_its_position_limits() {
    let mut config = DriveSafetyConfig::demo();
    config.slp.lower = -10.0;
    config.slp.upper = 20.0;
    config.slp.enable_delay = SimDuration::from_secs(1);
    let mut s = Stand::new(config);
    s.run_until(T0_MS);
    s.request(Function::Slp);
    s.scan();
    assert!(!s.status(Function::Slp) && s.out().status.sdc);
    s.run_until(at(1.0) + SCAN_MS);
    assert!(s.status(Function::Slp));
    let t = s
        .first(at(100.0), |_| 2.0, |o| !o.torque_enabled)
        .expect("trips");
    assert!((at(11.0)..=at(11.02)).contains(&t), "tripped at {t} ms");
    assert!(matches!(
        s.trips[..],
        [(_, Violation::OutsidePositionLimits { .. })]
    ));
}

/// **Decision**: SBC applies the brake and takes the torque off after its enable delay.
#[test]
fn sbc_applies_the_brake_after_its_delay() {
    let mut config = DriveSafetyConfig::demo();
    config.sbc_enable_delay = SimDuration::from_millis(200);
    let mut s = Stand::new(config);
    s.run_until(T0_MS);
    s.request(Function::Sbc);
    let t = s.first(at(5.0), |_| 0.0, |o| !o.brake_released);
    assert_eq!(t, Some(at(0.2)));
    assert!(s.status(Function::Sbc) && !s.out().torque_enabled);
}

/// SLA (reaction neither in the SafeMOTION thesis nor in the drive manual, **Decision**: trip): a
/// jump faster than 100 rev/s² trips.
#[test]
fn sla_trips_on_too_fast_a_speed_change() {
    let mut s = Stand::demo();
    s.speed = 5.0;
    s.run_until(T0_MS);
    s.request(Function::Sla);
    s.run_until(at(1.0));
    // +0.5 rev/s per 10 ms = 50 rev/s²: fine.
    let ramp = |t: u64| 5.0 + 0.5 * ((t - at(1.0)) / SCAN_MS) as f64;
    assert_eq!(s.first(at(1.1), ramp, |o| !o.torque_enabled), None);
    // +2 rev/s in one scan = 200 rev/s²: trips.
    let last = s.speed;
    let t = s.first(at(2.0), |_| last + 2.0, |o| !o.torque_enabled);
    assert_eq!(t, Some(at(1.1)));
    assert!(matches!(
        s.trips[..],
        [(_, Violation::AccelerationAbove { limit, .. })] if limit == 100.0
    ));
}

/// SLT (§3.10 of the SafeMOTION thesis): after its enable delay the status is TRUE while the torque
/// stays at most the limit either way; a torque above it trips (decision: like every other
/// violation, the SafeMOTION thesis states no reaction), and so does a scan without a valid torque.
#[test]
fn slt_holds_its_status_within_the_limit_and_trips_above_it_either_way() {
    let mut config = DriveSafetyConfig::demo();
    config.slt.enable_delay = SimDuration::from_millis(500);
    for sign in [1.0, -1.0] {
        let mut s = Stand::new(config);
        s.speed = 2.0;
        s.run_until(T0_MS);
        s.request(Function::Slt);
        // Above the limit during the enable delay: nothing is checked yet.
        s.torque = Some(sign * 1500.0);
        s.run_until(at(0.5));
        assert!(s.trips.is_empty() && !s.status(Function::Slt));
        // Within it after the delay: the safe state, torque on.
        s.torque = Some(sign * 1000.0);
        s.scan();
        assert!(s.status(Function::Slt) && s.out().torque_enabled);
        s.run_until(at(2.0));
        assert!(s.trips.is_empty());
        // One scan above it: torque off at once, the violation names SLT.
        s.torque = Some(sign * 1000.5);
        s.scan();
        assert!(!s.out().torque_enabled && !s.out().status.not_err_func);
        assert!(matches!(
            s.trips[..],
            [(t, Violation::TorqueAbove { torque, limit })]
                if t == at(2.0) && torque == sign * 1000.5 && limit == 1000.0
        ));
        assert_eq!(s.trips[0].1.function(), Some(Function::Slt));
    }
}

#[test]
fn slt_counts_a_missing_torque_as_above_the_limit() {
    for missing in [None, Some(f64::NAN), Some(f64::INFINITY)] {
        let mut s = Stand::demo();
        s.run_until(T0_MS);
        // Not requested: a missing torque is nobody's business.
        s.torque = missing;
        s.run_until(at(1.0));
        assert!(s.trips.is_empty(), "{missing:?}");
        s.request(Function::Slt);
        s.scan();
        assert!(!s.out().torque_enabled, "{missing:?}");
        assert!(
            matches!(s.trips[..], [(_, Violation::TorqueLost)]),
            "{missing:?}"
        );
    }
}

/// **Decision** (ramp monitoring): the envelope starts at the end of the enable delay from the
/// speed measured then and falls at the deceleration limit.
#[test]
fn ss1_ramp_monitoring_envelope_from_end_of_enable_delay() {
    let mut config = DriveSafetyConfig::demo();
    config.ss1.ramp_monitoring = true;
    config.ramp_decel_limit = 1.0;
    // Braking at 2 rev/s² from the end of the delay stays under the envelope: early limit at
    // 5 + 4 + 5 = 14 s.
    let mut s = Stand::new(config);
    s.speed = 10.0;
    s.run_until(T0_MS);
    s.request(Function::Ss1);
    let brake = |rate: f64| {
        move |t: u64| {
            let e = t.saturating_sub(at(5.0)) as f64 / 1000.0;
            (10.0 - rate * e).max(0.0)
        }
    };
    assert_eq!(
        s.first(at(30.0), brake(2.0), |o| !o.torque_enabled),
        Some(at(14.0))
    );
    assert!(s.trips.is_empty());
    // Braking at 0.5 rev/s² is too slow: above the envelope at the second scan of the window.
    let mut s = Stand::new(config);
    s.speed = 10.0;
    s.run_until(T0_MS);
    s.request(Function::Ss1);
    let t = s.first(at(30.0), brake(0.5), |o| !o.torque_enabled);
    assert_eq!(t, Some(at(5.01)));
    assert!(matches!(
        s.trips[..],
        [(
            _,
            Violation::AboveEnvelope {
                function: Function::Ss1,
                ..
            }
        )]
    ));
}

// ---------------------------------------------------------------------------------------------
// Reset, Activate, feedback.
// ---------------------------------------------------------------------------------------------

/// An error holds the torque off until a Reset edge, even after the request ends; a Reset held
/// TRUE does not acknowledge the next error.
#[test]
fn reset_is_the_only_way_out_of_an_error() {
    let mut s = Stand::demo();
    s.speed = 3.0;
    s.run_until(T0_MS);
    s.request(Function::Sos);
    s.scan();
    assert!(!s.out().torque_enabled && !s.out().status.not_err_func);
    s.release(Function::Sos);
    s.speed = 0.0;
    s.run_until(at(5.0));
    assert!(
        !s.out().torque_enabled,
        "releasing the request does not clear the error"
    );
    s.control.reset = true;
    s.scan();
    assert!(s.out().torque_enabled && s.out().status.not_err_func);
    assert!(s
        .out()
        .events
        .iter()
        .any(|e| e.kind == DriveEventKind::Reset));
    // Reset stays TRUE; a new violation latches again and is not acknowledged by it.
    s.speed = 3.0;
    s.request(Function::Sos);
    s.run_until(at(8.0));
    assert!(!s.out().torque_enabled && s.drive.error().is_some());
    s.control.reset = false;
    s.scan();
    s.speed = 0.0;
    s.release(Function::Sos);
    s.reset();
    assert!(s.out().torque_enabled && s.drive.error().is_none());
}

/// **Decision**: a function still requested at the Reset starts afresh (new reference).
#[test]
fn reset_restarts_a_still_requested_function() {
    let mut s = Stand::demo();
    s.run_until(T0_MS);
    s.request(Function::Sos);
    s.speed = 3.0;
    s.scan();
    assert!(!s.out().torque_enabled);
    s.speed = 0.0;
    s.position = 500.0; // moved while de-energised
    s.reset();
    assert!(
        s.out().torque_enabled && s.status(Function::Sos),
        "SOS holds the new position"
    );
}

/// S_Control_Activate FALSE: torque off, every status FALSE, no error.
#[test]
fn activate_false_keeps_the_torque_off() {
    let mut s = Stand::demo();
    s.control.activate = false;
    s.request(Function::Sos);
    s.scan();
    assert!(!s.out().torque_enabled && !s.status(Function::Sos));
    assert!(s.out().status.not_err_func);
    s.control.activate = true;
    s.scan();
    assert!(s.out().torque_enabled && s.status(Function::Sos));
}

/// An axis with a safe encoder that gets no reading trips.
#[test]
fn lost_encoder_feedback_trips() {
    let mut drive = SafeDrive::new(DriveSafetyConfig::demo()).expect("valid");
    let out = drive.scan(SimTime::ZERO, &DriveSafetyInputs::default());
    assert!(!out.torque_enabled && !out.status.not_err_func);
    assert_eq!(drive.error(), Some(Violation::FeedbackLost));
    let nan = DriveSafetyInputs {
        feedback: Some(AxisFeedback {
            position: f64::NAN,
            speed: 0.0,
        }),
        ..Default::default()
    };
    let mut drive = SafeDrive::new(DriveSafetyConfig::demo()).expect("valid");
    assert!(!drive.scan(SimTime::ZERO, &nan).torque_enabled);
}

/// The event log says what tripped, when and why in plain words.
#[test]
fn events_say_what_tripped_when_and_why() {
    let mut s = Stand::demo();
    s.speed = 3.0;
    s.run_until(T0_MS);
    s.request(Function::Sos);
    s.scan();
    let lines: Vec<String> = s.out().events.iter().map(ToString::to_string).collect();
    assert_eq!(
        lines,
        [
            "2.000000000 s: SOS requested (control bit FALSE)",
            "2.000000000 s: tripped, torque off: SOS: the axis turns at 3.000 rev/s, faster than the allowed 2 rev/s",
            "2.000000000 s: torque off",
        ]
    );
}

// ---------------------------------------------------------------------------------------------
// No encoder (§1.1.2 of the SafeMOTION thesis) and parameters.
// ---------------------------------------------------------------------------------------------

/// Without a safe encoder only STO, SBC and SS1 are available; requesting another function
/// trips with a message that says so.
#[test]
fn no_encoder_only_sto_sbc_and_ss1() {
    let config = DriveSafetyConfig::demo_without_encoder();
    for f in Function::ALL {
        let ok = SafeDrive::check_available(&config, f).is_ok();
        assert_eq!(
            ok,
            matches!(f, Function::Sto | Function::Sbc | Function::Ss1),
            "{f}"
        );
    }
    for f in Function::ALL
        .into_iter()
        .filter(|f| !f.works_without_encoder())
    {
        let mut s = Stand::new(config);
        s.run_until(T0_MS);
        s.request(f);
        s.scan();
        assert!(!s.out().torque_enabled, "{f}");
        assert_eq!(
            s.trips[..],
            [(T0_MS, Violation::NeedsEncoder { function: f })]
        );
        let text = Violation::NeedsEncoder { function: f }.to_string();
        assert!(text.contains("no safe encoder") && text.contains("only STO, SBC and SS1"));
    }
}

/// Without an encoder SS1 is time-monitored only: torque off at enable delay + ramp time even
/// at standstill.
#[test]
fn no_encoder_ss1_is_time_monitored_only() {
    let mut s = Stand::new(DriveSafetyConfig::demo_without_encoder());
    s.run_until(T0_MS);
    s.request(Function::Ss1);
    let t = s.first(at(30.0), |_| 0.0, |o| !o.torque_enabled);
    assert_eq!(t, Some(at(15.0)));
    assert!(s.trips.is_empty() && s.status(Function::Ss1));
}

/// SLP needs an absolute multi-turn encoder (the drive manual).
#[test]
fn slp_needs_a_multi_turn_encoder() {
    let config = {
        let mut cfg = DriveSafetyConfig::demo();
        cfg.encoder = Encoder::SafeSingleTurn;
        cfg
    };
    assert_eq!(
        SafeDrive::check_available(&config, Function::Slp),
        Err(Violation::NeedsAbsoluteEncoder)
    );
    assert!(SafeDrive::check_available(&config, Function::Sos).is_ok());
}

#[test]
fn demo_parameters_are_valid_and_as_in_the_safemotion_thesis() {
    let c = DriveSafetyConfig::demo();
    assert_eq!(c.validate(), Ok(()));
    assert_eq!(DriveSafetyConfig::demo_without_encoder().validate(), Ok(()));
    assert_eq!(c.standstill_speed_tolerance, 2.0);
    assert_eq!(c.standstill_position_tolerance, 100.0);
    assert!(c.early_limit_enabled);
    assert_eq!(c.early_limit_time, SimDuration::from_secs(5));
    assert_eq!(c.ramp_enable_delay, SimDuration::from_secs(5));
    assert_eq!(c.ss1.ramp_time, SimDuration::from_secs(10));
    assert!(!c.ss1.ramp_monitoring && !c.ss2.ramp_monitoring && !c.sls_ramp_monitoring);
    assert_eq!((c.sls[0].speed_limit, c.sls[1].speed_limit), (8.0, 5.0));
    assert_eq!(c.sli.position_limit, 50.0);
    assert_eq!(c.sli.disable_delay, SimDuration::from_secs(10));
    assert!(c.sdi_enable_delay.is_zero() && c.sbc_enable_delay.is_zero());
}

/// Every rule's error names the field, the value and the rule.
#[test]
fn config_errors_name_the_field_and_the_rule() {
    let check = |edit: fn(&mut DriveSafetyConfig), field: &str, rule_part: &str| {
        let mut c = DriveSafetyConfig::demo();
        edit(&mut c);
        let e: DriveConfigError = c.validate().expect_err(field);
        assert_eq!(e.field, field);
        assert!(e.rule.contains(rule_part), "{e}");
        assert!(SafeDrive::new(c).is_err());
    };
    check(
        |c| c.standstill_speed_tolerance = 0.0,
        "standstill_speed_tolerance",
        "> 0",
    );
    check(
        |c| c.standstill_position_tolerance = f64::NAN,
        "standstill_position_tolerance",
        "finite",
    );
    check(|c| c.sls[2].speed_limit = -1.0, "sls[2].speed_limit", "> 0");
    check(
        |c| c.slp.upper = c.slp.lower,
        "slp.lower",
        "below slp.upper",
    );
    check(|c| c.sli.position_limit = 0.0, "sli.position_limit", "> 0");
    check(|c| c.slt.torque_limit = -5.0, "slt.torque_limit", "> 0");
    check(
        |c| c.sla.decel_neg = f64::INFINITY,
        "sla.decel_neg",
        "finite",
    );
    check(
        |c| c.early_limit_time = SimDuration::ZERO,
        "early_limit_time",
        "enabled",
    );
    check(
        |c| {
            c.sls_ramp_monitoring = true;
            c.ramp_decel_limit = 0.0;
        },
        "ramp_decel_limit",
        "ramp monitoring",
    );
    check(
        |c| c.encoder = Encoder::None,
        "early_limit_enabled",
        "safe encoder",
    );
    check(
        |c| {
            c.encoder = Encoder::None;
            c.early_limit_enabled = false;
            c.ss1.ramp_monitoring = true;
        },
        "ss1.ramp_monitoring",
        "safe encoder",
    );
    let mut c = DriveSafetyConfig::demo();
    c.sls[1].speed_limit = -5.0;
    assert_eq!(
        c.validate().expect_err("bad").to_string(),
        "drive safety parameter `sls[1].speed_limit` = -5: must be a finite number > 0"
    );
}

// ---------------------------------------------------------------------------------------------
// Property tests of the monitoring.
// ---------------------------------------------------------------------------------------------

/// Piecewise-constant speed profiles: (duration in scans, speed as a fraction of `max`).
fn profile() -> impl Strategy<Value = Vec<(u64, f64)>> {
    prop::collection::vec((1u64..300, -1.0f64..=1.0), 1..12)
}

fn speed_at(profile: &[(u64, f64)], scan: u64, max: f64) -> f64 {
    let mut left = scan;
    for &(n, frac) in profile {
        if left < n {
            return frac * max;
        }
        left -= n;
    }
    0.0
}

fn level() -> impl Strategy<Value = SlsLevel> {
    prop::sample::select(SlsLevel::ALL.to_vec())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 128,
        rng_seed: RngSeed::Fixed(0x5AFE_D21E),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Any trajectory whose speed stays within the SLS level's limit never trips, whenever the
    /// request comes, and the status is TRUE from the end of the ramp window on.
    #[test]
    fn sls_inside_the_limit_never_trips(l in level(), p in profile(), t0 in 0u64..500) {
        let limit = DriveSafetyConfig::demo().sls[l.index()].speed_limit;
        let mut s = Stand::demo();
        let f = Function::Sls(l);
        for k in 0..3_000u64 {
            if k == t0 { s.request(f); }
            s.speed = speed_at(&p, k, limit);
            s.scan();
            prop_assert!(s.trips.is_empty(), "{:?}", s.trips);
            if k >= t0 + 1_500 { prop_assert!(s.status(f)); }
        }
    }

    /// A speed above the level's limit from the request on trips exactly when the window ends
    /// (enable delay + ramp time = 15 s), never earlier.
    #[test]
    fn sls_above_the_limit_trips_at_the_window_end(l in level(), over in 1.001f64..3.0, t0 in 0u64..500, sign in prop::bool::ANY) {
        let limit = DriveSafetyConfig::demo().sls[l.index()].speed_limit;
        let v = if sign { over * limit } else { -over * limit };
        let mut s = Stand::demo();
        s.run_until(t0 * SCAN_MS);
        s.request(Function::Sls(l));
        let t = s.first(t0 * SCAN_MS + 30_000, |_| v, |o| !o.torque_enabled);
        prop_assert_eq!(t, Some(t0 * SCAN_MS + 15_000));
    }

    /// Once SLS is monitoring, the first scan above the limit trips.
    #[test]
    fn sls_monitoring_trips_in_the_first_scan_above(l in level(), after in 0u64..1_000, over in 1.001f64..3.0) {
        let limit = DriveSafetyConfig::demo().sls[l.index()].speed_limit;
        let mut s = Stand::demo();
        s.run_until(T0_MS);
        s.request(Function::Sls(l));
        s.run_until(at(15.0) + after * SCAN_MS);
        prop_assert!(s.status(Function::Sls(l)));
        let t = s.first(at(100.0), |_| over * limit, |o| !o.torque_enabled);
        prop_assert_eq!(t, Some(at(15.0) + after * SCAN_MS));
    }

    /// SOS: any trajectory within 2 rev/s that stays within 100 rev of the request's position
    /// never trips (40 s at ≤ 2 rev/s is at most 80 rev).
    #[test]
    fn slt_inside_the_limit_never_trips_and_one_scan_above_always_does(
        torques in prop::collection::vec(-1000.0f64..=1000.0, 1..200),
        over in 1000.001f64..5000.0,
        sign in prop::bool::ANY,
    ) {
        let mut s = Stand::demo();
        s.run_until(T0_MS);
        s.request(Function::Slt);
        for &t in &torques {
            s.torque = Some(t);
            s.scan();
        }
        prop_assert!(s.trips.is_empty());
        prop_assert!(s.status(Function::Slt));
        s.torque = Some(if sign { over } else { -over });
        s.scan();
        prop_assert!(!s.out().torque_enabled);
        prop_assert_eq!(s.trips.len(), 1);
    }

    #[test]
    fn sos_inside_the_tolerances_never_trips(p in profile()) {
        let mut s = Stand::demo();
        s.request(Function::Sos);
        for k in 0..4_000u64 {
            s.speed = speed_at(&p, k, 2.0);
            s.scan();
            prop_assert!(s.trips.is_empty(), "{:?}", s.trips);
            prop_assert!(s.status(Function::Sos) && s.out().torque_enabled);
        }
    }

    /// SOS: a speed above 2 rev/s trips in the very scan it is seen.
    #[test]
    fn sos_above_the_speed_tolerance_trips_at_once(after in 0u64..1_000, v in 2.001f64..50.0, sign in prop::bool::ANY) {
        let mut s = Stand::demo();
        s.request(Function::Sos);
        s.run_until(after * SCAN_MS);
        let v = if sign { v } else { -v };
        let t = s.first(after * SCAN_MS + 1_000, |_| v, |o| !o.torque_enabled);
        prop_assert_eq!(t, Some(after * SCAN_MS));
    }

    /// SS1: whatever the axis does, the torque is off no later than 15 s after the request and
    /// no earlier than 10 s (enable delay + early limit), and SS1 never reports an error.
    #[test]
    fn ss1_torque_off_between_10_and_15_s(p in profile(), max in 0.0f64..20.0) {
        let mut s = Stand::demo();
        s.run_until(T0_MS);
        s.request(Function::Ss1);
        let t = s.first(at(20.0), |t| speed_at(&p, (t - T0_MS) / SCAN_MS, max), |o| !o.torque_enabled);
        let t = t.expect("SS1 always de-energises");
        prop_assert!((at(10.0)..=at(15.0)).contains(&t), "off at {} ms", t);
        prop_assert!(s.trips.is_empty());
    }

    /// SDI-P: motion in the permitted direction never trips; backwards at a constant speed it
    /// trips once the travel back exceeds 100 rev, within one scan.
    #[test]
    fn sdi_pos_trips_only_beyond_the_tolerance_backwards(fwd in prop::collection::vec(0.0f64..20.0, 1..20), back in 0.5f64..20.0) {
        let mut s = Stand::demo();
        s.request(Function::SdiPos);
        for (k, v) in fwd.iter().enumerate() {
            s.speed = *v;
            s.run_until((k as u64 + 1) * 500);
            prop_assert!(s.trips.is_empty());
        }
        let start = s.now_ms;
        let t = s.first(start + 1_000_000, |_| -back, |o| !o.torque_enabled).expect("trips");
        let expected = start as f64 + 100.0 / back * 1000.0;
        prop_assert!((t as f64 - expected).abs() <= 2.0 * SCAN_MS as f64, "{} vs {}", t, expected);
    }
}

mod two_channel {
    //! The drive manual's two-channel activation (docs/drive-safety.md §3.5).

    use asi_phy::SimTime;
    use proptest::prelude::*;
    use proptest::test_runner::RngSeed;
    use safety::drive::TwoChannelActivation;

    fn ms(t: u64) -> SimTime {
        SimTime::from_millis(t)
    }

    /// Scans every 1 ms from 0 to `end`; input a falls at `fall_a` and rises at `rise_a`,
    /// b likewise; returns the control bit per ms.
    fn run(fall: (u64, u64), rise: (u64, u64), end: u64) -> (Vec<bool>, bool) {
        let mut act = TwoChannelActivation::default();
        let bits = (0..=end)
            .map(|t| {
                let a = !(fall.0..rise.0).contains(&t);
                let b = !(fall.1..rise.1).contains(&t);
                act.scan(ms(t), a, b)
            })
            .collect();
        (bits, act.latched())
    }

    #[test]
    fn one_channel_requests_both_release_and_10_ms_apart_is_within() {
        let (bits, latched) = run((100, 110), (500, 490), 600);
        assert!(!latched);
        assert!(bits[99] && !bits[100], "requested with the first channel");
        assert!(!bits[499] && bits[500], "released with the second");
    }

    #[test]
    fn a_discrepancy_beyond_10_ms_latches_until_the_restart() {
        let mut act = TwoChannelActivation::default();
        assert!(act.scan(ms(0), true, true));
        assert!(!act.scan(ms(100), false, true));
        assert!(!act.scan(ms(109), false, true));
        assert!(!act.latched());
        assert!(!act.scan(ms(110), false, true));
        assert!(act.latched(), "still different 10 ms after");
        // Both channels agree again: still requested.
        assert!(!act.scan(ms(200), true, true));
        act.restart();
        assert!(act.scan(ms(201), true, true));
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 128,
            rng_seed: RngSeed::Fixed(1),
            failure_persistence: None,
            ..ProptestConfig::default()
        })]

        /// Edges at most 10 ms apart never latch; more than 10 ms apart always do.
        #[test]
        fn the_10_ms_rule(first in 10u64..200, skew in 0u64..40, rise_skew in 0u64..40) {
            let (_, latched) = run((first, first + skew), (400, 400 + rise_skew), 500);
            prop_assert_eq!(latched, skew > 10 || rise_skew > 10);
        }
    }
}
