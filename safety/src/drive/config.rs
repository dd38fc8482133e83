//! The safe-drive parameters, named after tables 3.2–3.10 of the SafeMOTION thesis, and their
//! validation.

use asi_phy::SimDuration;

/// The axis's safe position source.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Encoder {
    /// No safe encoder: only STO, SBC and SS1 (time-monitored only) are available (§1.1.2 of the
    /// SafeMOTION thesis).
    None,
    /// A safe single-turn encoder (position counted from power-up): everything except SLP.
    SafeSingleTurn,
    /// A safe absolute multi-turn encoder (e.g. EnDat 2.2 as on the SafeMOTION thesis' stand):
    /// every function; SLP is fully functional only with this one (the drive manual).
    SafeMultiTurn,
}

impl Encoder {
    /// `true` if the encoder gives a safe speed and position.
    pub const fn is_safe(self) -> bool {
        !matches!(self, Encoder::None)
    }
}

/// The monitored stop of SS1 or SS2 (tables 3.3, 3.4 of the SafeMOTION thesis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StopRamp {
    /// "SSx - Ramp monitoring - Enable": also monitor the minimum deceleration (the envelope),
    /// not only the time.
    pub ramp_monitoring: bool,
    /// "SSx - Ramp monitoring - Time": the ramp window after the enable delay.
    pub ramp_time: SimDuration,
}

/// One SLS level (table 3.5 of the SafeMOTION thesis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlsLimit {
    /// "SLSx - Speed limit" in rev/s (magnitude, both directions).
    pub speed_limit: f64,
    /// "SLSx - Ramp monitoring - Time": the window to get below the limit.
    pub ramp_time: SimDuration,
}

/// SLP (table 3.9 of the SafeMOTION thesis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlpLimits {
    /// "SLP - Lower position limit" in rev.
    pub lower: f64,
    /// "SLP - Upper position limit" in rev.
    pub upper: f64,
    /// "SLP - Enable delay time".
    pub enable_delay: SimDuration,
}

/// SLI (table 3.6 of the SafeMOTION thesis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliLimit {
    /// "SLI - Position limit" in rev, either way from the position at the request.
    pub position_limit: f64,
    /// "SLI - Disable delay time": the function stays active this long after the request ends.
    pub disable_delay: SimDuration,
}

/// SLA (table 3.8 of the SafeMOTION thesis), all in rev/s².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlaLimits {
    /// "SLA - Acceleration limit in positive direction".
    pub accel_pos: f64,
    /// "SLA - Deceleration limit in positive direction".
    pub decel_pos: f64,
    /// "SLA - Acceleration limit in negative direction".
    pub accel_neg: f64,
    /// "SLA - Deceleration limit in negative direction".
    pub decel_neg: f64,
    /// "SLA - Enable delay time".
    pub enable_delay: SimDuration,
}

/// SLT (table 3.10 of the SafeMOTION thesis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SltLimit {
    /// "SLT - Torque limit" in mNm: the torque the drive must not exceed, either way.
    pub torque_limit: f64,
    /// "SLT - Enable delay time".
    pub enable_delay: SimDuration,
}

/// The parameters of one safe axis. Speeds in rev/s, positions in rev (the SafeMOTION thesis'
/// "units" are revolutions on its stand), times as [`SimDuration`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct DriveSafetyConfig {
    /// The safe position source.
    pub encoder: Encoder,
    /// "Standstill monitoring - Speed tolerance": the highest speed that counts as standstill.
    pub standstill_speed_tolerance: f64,
    /// "Standstill monitoring - Position tolerance": the largest travel allowed at standstill
    /// (SOS, SS2) and against the permitted direction (SDI).
    pub standstill_position_tolerance: f64,
    /// "Ramp monitoring - Speed deceleration limit": the minimum deceleration of the envelope
    /// in rev/s², used where ramp monitoring is enabled.
    pub ramp_decel_limit: f64,
    /// "Ramp monitoring - Enable delay time": after a request of SS1, SS2 or SLS nothing is
    /// checked for this long (it covers the differing run times of the standard and the safety
    /// program).
    pub ramp_enable_delay: SimDuration,
    /// "Early limit monitoring - Enable".
    pub early_limit_enabled: bool,
    /// "Early limit monitoring - Time": how long the safe condition must hold to end the ramp
    /// window early.
    pub early_limit_time: SimDuration,
    /// SS1's ramp.
    pub ss1: StopRamp,
    /// SS2's ramp.
    pub ss2: StopRamp,
    /// "SLS - Ramp monitoring - Enable" (one switch for the four levels).
    pub sls_ramp_monitoring: bool,
    /// SLS1..SLS4.
    pub sls: [SlsLimit; 4],
    /// SLP.
    pub slp: SlpLimits,
    /// "SDI - Enable delay time".
    pub sdi_enable_delay: SimDuration,
    /// SLI.
    pub sli: SliLimit,
    /// "SBC - Enable delay time".
    pub sbc_enable_delay: SimDuration,
    /// SLA.
    pub sla: SlaLimits,
    /// SLT.
    pub slt: SltLimit,
}

/// A parameter that breaks a rule: the field, its value and the rule.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("drive safety parameter `{field}` = {value}: {rule}")]
pub struct DriveConfigError {
    /// The field, as in [`DriveSafetyConfig`] (e.g. `sls[1].speed_limit`).
    pub field: String,
    /// Its value as written.
    pub value: String,
    /// The rule it breaks.
    pub rule: &'static str,
}

impl DriveSafetyConfig {
    /// The demo parameters of the SafeMOTION thesis' teaching stand (§5, the axis parameter table,
    /// and the HMI pages of appendix A): standstill 2 rev/s and 100 rev, early limit on with 5 s,
    /// ramp enable delay 5 s, SS1/SS2 ramp time 10 s with ramp monitoring off, SLS1 8 rev/s and
    /// SLS2 5 rev/s with 10 s each, SLI 50 rev with a 10 s disable delay, SDI and SBC delays 0, SLA
    /// 100 rev/s² each way with delay 0, deceleration limit 1 rev/s² (unused while ramp monitoring
    /// is off).
    ///
    /// Not in the SafeMOTION thesis, filled in by asi-lift: SLS3 3 rev/s and SLS4 1 rev/s with 10 s
    /// each, SLP from −1000 to +1000 rev with delay 0. The encoder is the stand's EnDat 2.2
    /// (multi-turn).
    pub fn demo() -> Self {
        let s = SimDuration::from_secs;
        Self {
            encoder: Encoder::SafeMultiTurn,
            standstill_speed_tolerance: 2.0,
            standstill_position_tolerance: 100.0,
            ramp_decel_limit: 1.0,
            ramp_enable_delay: s(5),
            early_limit_enabled: true,
            early_limit_time: s(5),
            ss1: StopRamp {
                ramp_monitoring: false,
                ramp_time: s(10),
            },
            ss2: StopRamp {
                ramp_monitoring: false,
                ramp_time: s(10),
            },
            sls_ramp_monitoring: false,
            sls: [
                SlsLimit {
                    speed_limit: 8.0,
                    ramp_time: s(10),
                },
                SlsLimit {
                    speed_limit: 5.0,
                    ramp_time: s(10),
                },
                SlsLimit {
                    speed_limit: 3.0,
                    ramp_time: s(10),
                },
                SlsLimit {
                    speed_limit: 1.0,
                    ramp_time: s(10),
                },
            ],
            slp: SlpLimits {
                lower: -1000.0,
                upper: 1000.0,
                enable_delay: SimDuration::ZERO,
            },
            sdi_enable_delay: SimDuration::ZERO,
            sli: SliLimit {
                position_limit: 50.0,
                disable_delay: s(10),
            },
            sbc_enable_delay: SimDuration::ZERO,
            sla: SlaLimits {
                accel_pos: 100.0,
                decel_pos: 100.0,
                accel_neg: 100.0,
                decel_neg: 100.0,
                enable_delay: SimDuration::ZERO,
            },
            // The SafeMOTION thesis gives no SLT value for its stand (its HMI has no SLT page):
            // 1 N·m is asi-lift's, a little above what its ramps need of a small servo.
            slt: SltLimit {
                torque_limit: 1000.0,
                enable_delay: SimDuration::ZERO,
            },
        }
    }

    /// The demo parameters for an axis without a safe encoder: early limit off (it needs a
    /// speed), everything else as [`DriveSafetyConfig::demo`].
    pub fn demo_without_encoder() -> Self {
        Self {
            encoder: Encoder::None,
            early_limit_enabled: false,
            ..Self::demo()
        }
    }

    /// Checks every rule; the first broken one is returned.
    ///
    /// Rules: tolerances, limits and decelerations finite and > 0 (the deceleration limit only
    /// where ramp monitoring is enabled, else ≥ 0); the early-limit time > 0 when enabled;
    /// SLP lower < upper; without a safe encoder neither the early limit nor SS1 ramp
    /// monitoring (both need a measured speed).
    pub fn validate(&self) -> Result<(), DriveConfigError> {
        fn err(
            field: impl Into<String>,
            value: impl ToString,
            rule: &'static str,
        ) -> DriveConfigError {
            DriveConfigError {
                field: field.into(),
                value: value.to_string(),
                rule,
            }
        }
        fn positive(field: impl Into<String>, v: f64) -> Result<(), DriveConfigError> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(err(field, v, "must be a finite number > 0"))
            }
        }
        positive(
            "standstill_speed_tolerance",
            self.standstill_speed_tolerance,
        )?;
        positive(
            "standstill_position_tolerance",
            self.standstill_position_tolerance,
        )?;
        let ramp_used =
            self.ss1.ramp_monitoring || self.ss2.ramp_monitoring || self.sls_ramp_monitoring;
        if ramp_used {
            if !(self.ramp_decel_limit.is_finite() && self.ramp_decel_limit > 0.0) {
                return Err(err(
                    "ramp_decel_limit",
                    self.ramp_decel_limit,
                    "must be a finite number > 0 while ramp monitoring is enabled",
                ));
            }
        } else if !(self.ramp_decel_limit.is_finite() && self.ramp_decel_limit >= 0.0) {
            return Err(err(
                "ramp_decel_limit",
                self.ramp_decel_limit,
                "must be a finite number ≥ 0",
            ));
        }
        if self.early_limit_enabled && self.early_limit_time.is_zero() {
            return Err(err(
                "early_limit_time",
                self.early_limit_time,
                "must be > 0 while the early limit is enabled",
            ));
        }
        for (k, l) in self.sls.iter().enumerate() {
            positive(format!("sls[{k}].speed_limit"), l.speed_limit)?;
        }
        for (field, v) in [("slp.lower", self.slp.lower), ("slp.upper", self.slp.upper)] {
            if !v.is_finite() {
                return Err(err(field, v, "must be a finite number"));
            }
        }
        if self.slp.lower >= self.slp.upper {
            return Err(err("slp.lower", self.slp.lower, "must be below slp.upper"));
        }
        positive("sli.position_limit", self.sli.position_limit)?;
        positive("sla.accel_pos", self.sla.accel_pos)?;
        positive("sla.decel_pos", self.sla.decel_pos)?;
        positive("sla.accel_neg", self.sla.accel_neg)?;
        positive("sla.decel_neg", self.sla.decel_neg)?;
        positive("slt.torque_limit", self.slt.torque_limit)?;
        if !self.encoder.is_safe() {
            if self.early_limit_enabled {
                return Err(err(
                    "early_limit_enabled",
                    true,
                    "needs a safe encoder (it watches the speed); set encoder or disable it",
                ));
            }
            if self.ss1.ramp_monitoring {
                return Err(err(
                    "ss1.ramp_monitoring",
                    true,
                    "needs a safe encoder (it watches the speed); without one SS1 is time-monitored only",
                ));
            }
        }
        Ok(())
    }
}
