//! The lab lift's safe drive (docs/drive-safety.md §6): a [`SafeDrive`] on the lift's motor
//! with the safety logic's requests, in the lift's units.
//!
//! The lab's drive is a converter behind contactor K1 (docs/lift-plant.md §4.1, §4.5). The
//! option `[drive] safe = true` of a scenario adds a safe multi-turn encoder on the motor shaft
//! and a drive safety monitor; [`LiftDriveSafety`] is that monitor with the requests the lift's
//! safety logic makes of it:
//!
//! | request (control bit FALSE) | while |
//! |---|---|
//! | SS1 | the STOP circuit demands a stop (the ESTOP module's EStopOut is FALSE) |
//! | SOS | the door is open |
//! | SLS1 (initialisation speed) | the controller initialises |
//! | SLS2 (creep speed) | the converter is told to run at the creep set-point or below |
//! | SDI-N | the controller initialises and tells the converter to run down |
//! | SLP | always: the car stays just inside the overtravel sensors |
//!
//! STO (and SBC) is the monitor's torque-off output: it opens K1 (the rig puts it in series
//! with the safety logic's K1 output), so the converter loses power and the brake falls.
//! Sans-IO like the rest of the crate: the caller passes the time, the signals and the
//! encoder's reading in the lift's units (mm, mm/s); the monitor converts them to motor
//! revolutions.

use asi_phy::{SimDuration, SimTime};

use crate::drive::{
    AxisFeedback, ControlBits, DriveConfigError, DriveSafetyConfig, DriveSafetyInputs,
    DriveSafetyOutputs, Encoder, Function, SafeDrive, SlaLimits, SliLimit, SlpLimits, SlsLevel,
    SlsLimit, SltLimit, StopRamp, Violation,
};

/// The SLS level the safety logic requests during initialisation.
pub const SLS_INIT: SlsLevel = SlsLevel::L1;
/// The SLS level the safety logic requests while the car creeps.
pub const SLS_CREEP: SlsLevel = SlsLevel::L2;

/// How far inside each overtravel sensor's trip point SLP's limit lies, mm.
pub const SLP_INSIDE_OVERTRAVEL_MM: f64 = 10.0;

/// The lift's safe drive: its parameters and the encoder's scale.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct LiftDriveConfig {
    /// The safe drive's parameters, in motor revolutions.
    pub drive: DriveSafetyConfig,
    /// Cabin travel per motor revolution, mm (the lab lift: π · 79 mm / 25 = 9.927 mm).
    pub mm_per_rev: f64,
}

impl LiftDriveConfig {
    /// The lab lift's parameters (**Decisions**, docs/drive-safety.md §6.2), for a motor
    /// that moves the car `mm_per_rev` per revolution and overtravel sensors that trip at
    /// `overtravel_mm` = (below floor 1, above the top floor) in mm above floor 1's level:
    ///
    /// - standstill: 0.2 rev/s (2.0 mm/s) and 0.5 rev (5.0 mm);
    /// - enable delay 100 ms (the controller sees EStopOut within a PLC scan and the bus);
    /// - early limit on, 500 ms;
    /// - SS1: time-monitored, 9 s ramp window (with the enable delay the 9.1 s of the STOP
    ///   circuit's delayed output, the longest stop at the next floor); the early limit ends
    ///   it 0.5 s after the car stands;
    /// - SLS1 (initialisation): 7.5 rev/s (74.5 mm/s, the initialisation run is 6.93 rev/s);
    ///   SLS2 (creep): 2.5 rev/s (24.8 mm/s, the creep is 2.07 rev/s); 1 s ramp each;
    ///   SLS3/SLS4 unused (1.0 and 0.5 rev/s);
    /// - SLP: 10 mm inside each overtravel sensor's trip point;
    /// - SDI, SBC and SLP without delay; SLI and SLA unused (10 rev, 50 rev/s²).
    pub fn lab(mm_per_rev: f64, overtravel_mm: (f64, f64)) -> LiftDriveConfig {
        let ms = SimDuration::from_millis;
        let rev = |mm: f64| mm / mm_per_rev;
        let sls = |speed_limit: f64| SlsLimit {
            speed_limit,
            ramp_time: ms(1_000),
        };
        let stop = StopRamp {
            ramp_monitoring: false,
            ramp_time: ms(9_000),
        };
        LiftDriveConfig {
            mm_per_rev,
            drive: DriveSafetyConfig {
                encoder: Encoder::SafeMultiTurn,
                standstill_speed_tolerance: 0.2,
                standstill_position_tolerance: 0.5,
                ramp_decel_limit: 0.0,
                ramp_enable_delay: ms(100),
                early_limit_enabled: true,
                early_limit_time: ms(500),
                ss1: stop,
                ss2: stop,
                sls_ramp_monitoring: false,
                sls: [sls(7.5), sls(2.5), sls(1.0), sls(0.5)],
                slp: SlpLimits {
                    lower: rev(overtravel_mm.0 + SLP_INSIDE_OVERTRAVEL_MM),
                    upper: rev(overtravel_mm.1 - SLP_INSIDE_OVERTRAVEL_MM),
                    enable_delay: SimDuration::ZERO,
                },
                sdi_enable_delay: SimDuration::ZERO,
                sli: SliLimit {
                    position_limit: 10.0,
                    disable_delay: SimDuration::ZERO,
                },
                sbc_enable_delay: SimDuration::ZERO,
                sla: SlaLimits {
                    accel_pos: 50.0,
                    decel_pos: 50.0,
                    accel_neg: 50.0,
                    decel_neg: 50.0,
                    enable_delay: SimDuration::ZERO,
                },
                // Never requested on the lift (the lab converter reports no torque).
                slt: SltLimit {
                    torque_limit: 1000.0,
                    enable_delay: SimDuration::ZERO,
                },
            },
        }
    }

    /// `mm` of cabin travel in motor revolutions.
    pub fn rev(&self, mm: f64) -> f64 {
        mm / self.mm_per_rev
    }
}

/// What the lift's safety logic tells the monitor, and the encoder's reading, in one scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiftDriveInputs {
    /// The STOP circuit's immediate output (the ESTOP module's EStopOut): FALSE = a stop is
    /// demanded (SS1).
    pub estop_out: bool,
    /// The door contact: FALSE = open (SOS).
    pub door_closed: bool,
    /// The controller initialises (SLS1). A standard signal: it can only request.
    pub initialising: bool,
    /// The controller initialises and tells the converter to run down (SDI-N).
    pub init_down: bool,
    /// The converter is told to run at the creep set-point or below (SLS2).
    pub creeping: bool,
    /// The operator's safety reset (S_Control_Reset: acknowledges a trip on its rising edge).
    pub reset: bool,
    /// The encoder: the car's height above floor 1's level (mm) and velocity (mm/s, + up);
    /// `None` (or a value that is not a number) when it cannot be read, which trips.
    pub encoder: Option<(f64, f64)>,
}

/// The monitor of the lift's drive.
#[derive(Clone, Debug)]
pub struct LiftDriveSafety {
    config: LiftDriveConfig,
    drive: SafeDrive,
    control: ControlBits,
    last: Option<DriveSafetyOutputs>,
}

impl LiftDriveSafety {
    /// A monitor with validated parameters; the torque is off until the first scan.
    pub fn new(config: LiftDriveConfig) -> Result<LiftDriveSafety, DriveConfigError> {
        if !(config.mm_per_rev.is_finite() && config.mm_per_rev > 0.0) {
            return Err(DriveConfigError {
                field: "mm_per_rev".into(),
                value: config.mm_per_rev.to_string(),
                rule: "must be a finite number > 0",
            });
        }
        Ok(LiftDriveSafety {
            drive: SafeDrive::new(config.drive)?,
            config,
            control: ControlBits::idle(),
            last: None,
        })
    }

    /// The parameters.
    pub fn config(&self) -> &LiftDriveConfig {
        &self.config
    }

    /// The control bits the safety logic sets for `inputs` (active-low: FALSE = requested).
    pub fn requests(inputs: &LiftDriveInputs) -> ControlBits {
        let mut c = ControlBits::idle().with_reset(inputs.reset);
        for (wanted, f) in [
            (!inputs.estop_out, Function::Ss1),
            (!inputs.door_closed, Function::Sos),
            (inputs.initialising, Function::Sls(SLS_INIT)),
            (inputs.creeping, Function::Sls(SLS_CREEP)),
            (inputs.init_down, Function::SdiNeg),
            (true, Function::Slp),
        ] {
            if wanted {
                c = c.with_request(f);
            }
        }
        c
    }

    /// One scan at `now`.
    pub fn scan(&mut self, now: SimTime, inputs: &LiftDriveInputs) -> &DriveSafetyOutputs {
        self.control = Self::requests(inputs);
        let feedback = inputs.encoder.map(|(mm, mm_s)| AxisFeedback {
            position: self.config.rev(mm),
            speed: self.config.rev(mm_s),
        });
        let out = self.drive.scan(
            now,
            &DriveSafetyInputs {
                control: self.control,
                feedback,
                // The lab converter reports no torque; SLT is never requested here.
                torque: None,
            },
        );
        self.last.insert(out)
    }

    /// The control bits of the last scan.
    pub fn control(&self) -> &ControlBits {
        &self.control
    }

    /// The outputs of the last scan (absent before the first).
    pub fn outputs(&self) -> Option<&DriveSafetyOutputs> {
        self.last.as_ref()
    }

    /// The latched trip, if any.
    pub fn error(&self) -> Option<Violation> {
        self.drive.error()
    }

    /// Why the monitor holds the torque off now, in words; `None` while it lets the drive run.
    pub fn torque_off_cause(&self) -> Option<String> {
        let out = self.last.as_ref()?;
        if out.torque_enabled {
            return None;
        }
        Some(match self.drive.error() {
            Some(v) => {
                format!("the safe drive tripped ({v}); the operator's reset acknowledges it")
            }
            None if out.status.of(Function::Ss1) => {
                "the safe drive's SS1 ended the STOP with torque off".into()
            }
            None => "the safe drive holds the torque off".into(),
        })
    }
}
