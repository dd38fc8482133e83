//! The safe drive of `[drive] safe = true` (docs/drive-safety.md §6): the rig's side of
//! [`safety::lift_drive`]. Every safety scan it gives the monitor the safety logic's signals
//! and the encoder (the plant's cabin position and velocity), and puts the monitor's torque-off
//! output in series with the safety logic's K1 output: STO (with SBC) is K1 opening, the
//! converter losing power and the brake falling.

use crate::report::{round3, DriveReport, DriveTrip, Ss1Stop, Trip, TripCause, TripKind};
use crate::waves::DriveSample;
use asi_phy::SimTime;
use controller::ControllerConfig;
use lab::setpoint::STANDSTILL_UA;
use lift_model::{End, Lift};
use safety::drive::{DriveConfigError, DriveEventKind, Function, Violation};
use safety::lift_drive::{LiftDriveConfig, LiftDriveInputs, LiftDriveSafety};

/// The safe drive and what it has done.
#[derive(Clone)]
pub(super) struct SafeDriveGuard {
    safety: LiftDriveSafety,
    /// At or below this set-point the converter creeps (SLS2).
    creep_ua: u16,
    /// The encoder cannot be read (the scenario's `encoder-failed`).
    encoder_failed: bool,
    report: DriveReport,
}

impl SafeDriveGuard {
    /// The lab lift's safe drive for `lift` (docs/drive-safety.md §6.2).
    pub(super) fn new(lift: &Lift) -> Result<SafeDriveGuard, DriveConfigError> {
        let c = lift.config();
        let d = &c.drive;
        let mm_per_rev = core::f64::consts::PI * d.sprocket_diameter_mm / d.gear_ratio;
        let config = LiftDriveConfig::lab(
            mm_per_rev,
            (
                c.trip_position_mm(End::Bottom),
                c.trip_position_mm(End::Top),
            ),
        );
        Ok(SafeDriveGuard {
            safety: LiftDriveSafety::new(config)?,
            creep_ua: ControllerConfig::default().creep_ua,
            encoder_failed: false,
            report: DriveReport::default(),
        })
    }

    /// What the VCD shows of it.
    pub(super) fn sample(&self) -> DriveSample {
        let out = self.safety.outputs();
        DriveSample {
            control: *self.safety.control(),
            status: out.map(|o| o.status).unwrap_or_default(),
            torque: out.is_some_and(|o| o.torque_enabled),
        }
    }

    /// Why the torque is off, if it is.
    pub(super) fn torque_off_cause(&self) -> Option<String> {
        self.safety.torque_off_cause()
    }

    /// The encoder fails (`true`) or reads again: from the next scan on, the monitor gets no
    /// position and speed, which it counts as unsafe and trips on.
    pub(super) fn set_encoder_failed(&mut self, failed: bool) {
        self.encoder_failed = failed;
    }

    /// The latched trip, if any.
    pub(super) fn error(&self) -> Option<Violation> {
        self.safety.error()
    }

    /// The record of the run.
    pub(super) fn finish(&mut self) -> DriveReport {
        std::mem::take(&mut self.report)
    }
}

/// What the rig gives the safe drive in one scan: the safety logic's and the controller's
/// signals, the operator's reset and the encoder (the plant's cabin).
pub(super) struct Signals {
    /// The safety logic's EStopOut (`false` = STOP demanded).
    pub estop_out: bool,
    /// The built-in controller initialises.
    pub initialising: bool,
    /// What the converter is told: run, up, set-point.
    pub run: bool,
    pub up: bool,
    pub setpoint_ua: u16,
    /// The operator's safety reset.
    pub reset: bool,
    /// The door contact.
    pub door_closed: bool,
    /// The cabin's height (mm) and velocity (mm/s).
    pub position_mm: f64,
    pub velocity_mm_s: f64,
}

impl SafeDriveGuard {
    /// One scan at `t`: the monitor's requests from `s`, its trips recorded (also in `trips`,
    /// the report's safety trips); returns the torque enable (in series with K1) and the
    /// events for the log.
    pub(super) fn scan(
        &mut self,
        t: SimTime,
        s: &Signals,
        trips: &mut Vec<Trip>,
    ) -> (bool, Vec<(SimTime, DriveEventKind)>) {
        let inputs = LiftDriveInputs {
            estop_out: s.estop_out,
            door_closed: s.door_closed,
            initialising: s.initialising,
            init_down: s.initialising && s.run && !s.up,
            creeping: s.run && s.setpoint_ua > STANDSTILL_UA && s.setpoint_ua <= self.creep_ua,
            reset: s.reset,
            encoder: (!self.encoder_failed).then_some((s.position_mm, s.velocity_mm_s)),
        };
        let out = self.safety.scan(t, &inputs).clone();
        let position_mm = round3(s.position_mm);
        let mut lines = Vec::new();
        for e in &out.events {
            let at_s = e.at.as_secs_f64();
            match e.kind {
                DriveEventKind::Tripped(v) => {
                    let function = v.function().map_or("encoder".into(), |f| f.to_string());
                    let cause = v.to_string();
                    self.report.trips.push(DriveTrip {
                        at_s,
                        function,
                        cause: cause.clone(),
                        position_mm,
                    });
                    trips.push(Trip {
                        at_s,
                        kind: TripKind::Trip,
                        cause: TripCause::Drive(v),
                    });
                }
                DriveEventKind::Requested(Function::Ss1) => {
                    self.report.ss1_stops.push(Ss1Stop {
                        requested_at_s: at_s,
                        torque_off_at_s: None,
                        took_s: None,
                        released_at_s: None,
                    });
                }
                DriveEventKind::SafeStateReached(Function::Ss1) => {
                    if let Some(s) = self.report.ss1_stops.last_mut() {
                        s.torque_off_at_s = Some(at_s);
                        s.took_s = Some(round3(at_s - s.requested_at_s));
                    }
                }
                DriveEventKind::Released(Function::Ss1) => {
                    if let Some(s) = self.report.ss1_stops.last_mut() {
                        s.released_at_s = Some(at_s);
                    }
                }
                _ => {}
            }
            // SLS2 comes and goes with every creep, SLP is always requested: their requests
            // and releases would only fill the log.
            let chatter = matches!(
                e.kind,
                DriveEventKind::Requested(Function::Sls(_) | Function::Slp)
                    | DriveEventKind::Released(Function::Sls(_) | Function::Slp)
                    | DriveEventKind::SafeStateReached(Function::Sls(_) | Function::Slp)
            );
            if !chatter {
                lines.push((e.at, e.kind));
            }
        }
        (out.torque_enabled, lines)
    }

    /// The attendant's rescue for a car the safe drive's SLP stopped beyond its limit but
    /// short of the overtravel sensor: a crank back to the nearer end floor's level, only with
    /// K1 open. `None` when SLP did not trip.
    pub(super) fn slp_rescue_mm(&self, lift: &Lift, floors: u8) -> Option<f64> {
        if !matches!(self.error(), Some(Violation::OutsidePositionLimits { .. })) {
            return None;
        }
        let x = lift.position_mm();
        let floor = if x < 0.0 { 1 } else { floors };
        let to = lift.config().floor_level_mm(floor)?;
        (!lift.k1_closed()).then_some(to - x)
    }
}
