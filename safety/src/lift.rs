//! The lift's safety project (docs/safety.md; docs/safety-logic.md §8.4): a KL6904 that owns the drive
//! contactor K1 and guards the lift for the cabin STOP button, the overtravel limits and
//! overload.
//!
//! ```text
//!  cabin KL1904 (addr 2) --conn 1 `cabin_stop`--+
//!    stop_ch1, stop_ch2 (NC)                    |   ESTOP `stop` (pair 1/2, 50 ms, delay)
//!                                               +-> EStopIn1/2   EStopOut ------> estop_out (to the PLC)
//!  std:controller_restart ------------------------> Restart      EStopDelOut --+
//!  cabinet KL1904 (addr 3) --conn 2 `cabinet`---+-> EDM1 (k1_aux)              |
//!    overtravel_bottom, overtravel_top,         |                              |  AND `k1`
//!    k1_aux                                     |   MON `overtravel` (manual)  +-> AndIn2
//!                                               +-> MonIn1/2     MonOut -------> AndIn3     AndOut -> Local-Out 1 = K1
//!  std:operator_reset ----------------------------> Restart                 std:overloaded -> AndIn1 (make contact)
//!                                               +-> EDM1 (k1_aux)
//!  std:err_ack -----> group `drive` ERR_ACK (RUN unconnected = TRUE); COM_ERR/FB_ERR/OUT_ERR -> PLC
//! ```
//!
//! K1 = AND(not overloaded, ESTOP.EStopDelOut, MON.MonOut). All of it is one group, `drive`: a
//! lost or corrupted telegram on either connection trips COM_ERR and K1 drops at once.

use asi_phy::{SimDuration, SimTime};
use core::fmt;

use crate::kl6904::connection::{ChannelFault, ConnDiag, PartnerKind};
use crate::kl6904::group::GroupErrors;
use crate::kl6904::logic::{
    ConnectionId, GroupId, GroupStatus, LogicEvent, LogicEventKind, ModuleId, ModuleStatus,
    StandardInput, StandardOutput,
};
use crate::kl6904::modules::{FbError, FbEvent, FbState};
use crate::kl6904::project::{ModuleDesc, ModuleKind, Project};
use crate::kl6904::signal::{Contact, GroupOutput, SignalRef};
use crate::kl6904::verify::VerifyError;
use crate::kl6904::TwinSafeLogic;

/// The safety scan period the rig should call [`LiftSafety::scan`] with: **1 ms**.
///
/// Why: the logic must see every change of its inputs at a finer grain than the times it
/// monitors. 1 ms resolves the 50 ms STOP discrepancy time to 2 % and the 100 ms watchdog to
/// 1 %; it is shorter than one AS-i cycle of the lab bus ((11 + 2) · 154 µs ≈ 2.0 ms for its
/// 11 slaves, docs/master.md §2.4), so the safety monitor's release state is sampled at least
/// once per bus cycle, and ten times finer than the controller's 10 ms scan, so a controller
/// pulse (≥ one controller scan) is always seen high and low. Each connection exchanges one telegram per scan; scanning much
/// slower than the watchdog (100 ms) would trip COM_ERR by itself.
pub const SAFETY_SCAN_PERIOD: SimDuration = SimDuration::from_millis(1);

/// How the default STOP delay (the time EStopDelOut keeps K1 closed after STOP) is derived from
/// the lift: the controller stops at the next floor in the direction of travel (docs/controller.md), so
/// the delay must cover the worst case of a STOP pressed just after leaving a floor.
///
/// Worst case = run at travel speed up to the approach point, creep over the approach
/// distance, brake, plus a margin:
///
/// `delay = (pitch − approach) / v_travel + approach / v_creep + v_creep / a_brake + margin`
///
/// With the defaults (docs/lift-plant.md: pitch 400 mm; Rychlost 10000 → 59.416 mm/s, 6000 → 20.550 mm/s;
/// the long vane track starts braking 40 mm before the level; 500 mm/s² brake; 1 s margin for
/// ramps and the controller's 10 ms reaction) that is 6.059 + 1.946 + 0.041 + 1 = 9.046 s,
/// rounded up to the next 100 ms: **9.1 s**. A plain "one pitch at travel speed plus braking"
/// (6.85 s) would drop K1 before a creeping cabin reaches the floor.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct StopDelayModel {
    /// Floor pitch in mm.
    pub floor_pitch_mm: f64,
    /// Travel speed in mm/s.
    pub travel_speed_mm_s: f64,
    /// Distance before the level where the controller slows to creep speed, in mm.
    pub approach_mm: f64,
    /// Creep (approach) speed in mm/s.
    pub approach_speed_mm_s: f64,
    /// Braking deceleration in mm/s².
    pub deceleration_mm_s2: f64,
    /// Margin added on top.
    pub margin: SimDuration,
}

impl Default for StopDelayModel {
    fn default() -> Self {
        StopDelayModel {
            floor_pitch_mm: 400.0,
            travel_speed_mm_s: 59.416,
            approach_mm: 40.0,
            approach_speed_mm_s: 20.550,
            deceleration_mm_s2: 500.0,
            margin: SimDuration::from_secs(1),
        }
    }
}

impl StopDelayModel {
    /// The delay, rounded up to the next 100 ms. Nonsensical numbers (zero or negative speeds)
    /// give the margin alone plus whatever terms are finite.
    pub fn delay(&self) -> SimDuration {
        let term = |num: f64, den: f64| if den > 0.0 { (num / den).max(0.0) } else { 0.0 };
        let secs = term(
            self.floor_pitch_mm - self.approach_mm,
            self.travel_speed_mm_s,
        ) + term(self.approach_mm, self.approach_speed_mm_s)
            + term(self.approach_speed_mm_s, self.deceleration_mm_s2);
        let tenths = (secs * 10.0).ceil();
        let base = SimDuration::from_secs_f64(tenths / 10.0).unwrap_or(SimDuration::ZERO);
        base + self.margin
    }
}

/// Parameters of the lift's safety project.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct LiftSafetyConfig {
    /// Delay of EStopDelOut: how long K1 stays closed after STOP (default: [`StopDelayModel`]).
    pub estop_delay: SimDuration,
    /// Discrepancy time of the two STOP channels (docs/safety.md: 50 ms).
    pub stop_discrepancy: SimDuration,
    /// Watchdog time of both TwinSAFE connections.
    ///
    /// **Decision**: 100 ms — a hundred scans, so single lost telegrams never trip, and short
    /// against the lift's stopping time, so a dead link removes power within 0.1 s.
    pub watchdog: SimDuration,
    /// The KL6904's TwinSAFE address.
    pub logic_address: u16,
    /// The cabin KL1904 (STOP contacts).
    pub stop_terminal_address: u16,
    /// The cabinet KL1904 (safety monitor outputs, K1 auxiliary contact).
    pub cabinet_terminal_address: u16,
}

impl Default for LiftSafetyConfig {
    fn default() -> Self {
        LiftSafetyConfig {
            estop_delay: StopDelayModel::default().delay(),
            stop_discrepancy: SimDuration::from_millis(50),
            watchdog: SimDuration::from_millis(100),
            logic_address: 1,
            stop_terminal_address: 2,
            cabinet_terminal_address: 3,
        }
    }
}

/// Names used in the project.
mod names {
    pub const GROUP: &str = "drive";
    pub const STOP_LINK: &str = "cabin_stop";
    pub const CABINET_LINK: &str = "cabinet";
    pub const ESTOP: &str = "stop";
    pub const MON: &str = "overtravel";
    pub const AND: &str = "k1";
}

impl LiftSafetyConfig {
    /// The lift's safety project for these parameters (the same as `safety/projects/lift.toml`
    /// with the defaults).
    pub fn project(&self) -> Project {
        use names::*;
        let ts = SignalRef::twinsafe;
        let std = SignalRef::standard;
        Project::new("asi-lift safety", self.logic_address)
            .group(GROUP, std("err_ack"))
            .connection(
                STOP_LINK,
                GROUP,
                PartnerKind::Kl1904,
                self.stop_terminal_address,
                self.watchdog,
                &["stop_ch1", "stop_ch2"],
            )
            .connection(
                CABINET_LINK,
                GROUP,
                PartnerKind::Kl1904,
                self.cabinet_terminal_address,
                self.watchdog,
                &["overtravel_bottom", "overtravel_top", "k1_aux"],
            )
            .module(
                ModuleDesc::new(ModuleKind::Estop, ESTOP, GROUP)
                    .input("EStopIn1", ts(STOP_LINK, "stop_ch1"))
                    .input("EStopIn2", ts(STOP_LINK, "stop_ch2"))
                    .input("Restart", std("controller_restart"))
                    .input("EDM1", ts(CABINET_LINK, "k1_aux"))
                    .pair_discrepancy(&[self.stop_discrepancy])
                    .delay(self.estop_delay),
            )
            .module(
                ModuleDesc::new(ModuleKind::Mon, MON, GROUP)
                    .input("MonIn1", ts(CABINET_LINK, "overtravel_bottom"))
                    .input("MonIn2", ts(CABINET_LINK, "overtravel_top"))
                    .input("Restart", std("operator_reset"))
                    .input("EDM1", ts(CABINET_LINK, "k1_aux"))
                    .manual_restart(true),
            )
            .module(
                ModuleDesc::new(ModuleKind::And, AND, GROUP)
                    .input_contact("AndIn1", std("overloaded"), Contact::Make)
                    .input("AndIn2", SignalRef::fb(ESTOP, "EStopDelOut"))
                    .input("AndIn3", SignalRef::fb(MON, "MonOut")),
            )
            .local_output(1, "K1", GROUP, SignalRef::fb(AND, "AndOut"))
            .standard_output("estop_out", SignalRef::fb(ESTOP, "EStopOut"))
            .standard_output("fb_err", SignalRef::group(GROUP, GroupOutput::FbErr))
            .standard_output("com_err", SignalRef::group(GROUP, GroupOutput::ComErr))
            .standard_output("out_err", SignalRef::group(GROUP, GroupOutput::OutErr))
    }
}

/// What the rig gives the safety logic each scan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LiftSafetyInputs {
    /// STOP button channel 1, NC contact: `true` = closed = not pressed. Travels over
    /// connection 1.
    pub stop_ch1: bool,
    /// STOP button channel 2, NC contact.
    pub stop_ch2: bool,
    /// The passive AS-i safety monitor releases for the bottom overtravel sensor (sensor free).
    pub overtravel_bottom_released: bool,
    /// The same for the top sensor.
    pub overtravel_top_released: bool,
    /// Load level 3 (overloaded), from the PLC: a standard signal.
    pub overloaded: bool,
    /// K1's auxiliary NC contact: `true` = K1 released (EDM feedback).
    pub k1_aux: bool,
    /// The operator's reset button (overtravel recovery), a standard signal.
    pub operator_reset: bool,
    /// The operator's acknowledge (group ERR_ACK), a standard signal.
    pub err_ack: bool,
    /// The controller's restart of the STOP circuit, pulsed on the next cabin request.
    pub controller_restart: bool,
}

impl LiftSafetyInputs {
    /// `==`, as one comparison of every input at once rather than one branch per field (the
    /// rig's inputs are compared with the last scan's every scan).
    fn same_as(&self, other: &LiftSafetyInputs) -> bool {
        let all = |i: &LiftSafetyInputs| {
            [
                i.stop_ch1,
                i.stop_ch2,
                i.overtravel_bottom_released,
                i.overtravel_top_released,
                i.overloaded,
                i.k1_aux,
                i.operator_reset,
                i.err_ack,
                i.controller_restart,
            ]
        };
        all(self) == all(other)
    }

    /// Everything healthy and at rest: STOP closed, sensors free, not overloaded, K1 released,
    /// no buttons.
    pub const fn healthy() -> Self {
        LiftSafetyInputs {
            stop_ch1: true,
            stop_ch2: true,
            overtravel_bottom_released: true,
            overtravel_top_released: true,
            overloaded: false,
            k1_aux: true,
            operator_reset: false,
            err_ack: false,
            controller_restart: false,
        }
    }
}

/// Why K1 is open.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum K1Cause {
    /// The whole logic stopped on an internal fault.
    LogicFault,
    /// The group is in ERROR (or RESET) with these errors latched: waiting for ERR_ACK.
    GroupError(GroupErrors),
    /// The STOP button is pressed (a channel open) and its delay has elapsed.
    StopPressed,
    /// STOP released, but the STOP circuit waits for the controller's restart.
    StopRestartPending,
    /// An overtravel sensor is tripped.
    Overtravel {
        /// The bottom sensor is tripped.
        bottom: bool,
        /// The top sensor is tripped.
        top: bool,
    },
    /// The sensors are free again; the overtravel monitor waits for the operator's reset.
    OvertravelResetPending,
    /// The cabin is overloaded.
    Overloaded,
}

impl fmt::Display for K1Cause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            K1Cause::LogicFault => f.write_str("safety logic fault"),
            K1Cause::GroupError(e) => write!(f, "group error ({e}), waiting for ERR_ACK"),
            K1Cause::StopPressed => f.write_str("STOP pressed"),
            K1Cause::StopRestartPending => {
                f.write_str("STOP circuit waiting for the controller's restart")
            }
            K1Cause::Overtravel { bottom, top } => {
                let which = match (bottom, top) {
                    (true, true) => "bottom and top",
                    (true, false) => "bottom",
                    _ => "top",
                };
                write!(f, "overtravel {which} sensor tripped")
            }
            K1Cause::OvertravelResetPending => {
                f.write_str("overtravel monitor waiting for the operator's reset")
            }
            K1Cause::Overloaded => f.write_str("cabin overloaded"),
        }
    }
}

/// The kind of a [`LiftSafetyEvent`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LiftEventKind {
    /// A safety function tripped or a group tripped: the cause of a safety stop.
    Trip,
    /// An output went off as a trip's consequence: K1 opened, the STOP delay elapsed.
    PowerOff,
    /// An error was detected (FB_ERR, COM_ERR, OUT_ERR, logic fault).
    Error,
    /// A safety function was reset, K1 closed.
    Release,
    /// ERR_ACK accepted.
    Acknowledge,
    /// Anything else worth a log line (start-up).
    Info,
}

/// What the lift's safety logic reports, in the lift's terms: the SF_EmergencyStop module of
/// the STOP circuit, the SF_SafetyMonitor of the overtravel sensors, K1, or another event of
/// the logic in its own terms. `Display` gives the safety log's words, e.g. `tripped: STOP
/// demanded (channel 1 open); estop_out off, K1 off in 9.1 s`.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum LiftSafetyCause {
    /// The STOP circuit demanded the safe state: these channels open (bit 0: channel 1, bit
    /// 1: channel 2); estop_out off at once, K1 after `delay`.
    StopDemanded {
        /// The open channels.
        channels: u8,
        /// The STOP delay.
        delay: SimDuration,
    },
    /// The STOP delay elapsed: EStopDelOut off.
    StopDelayElapsed {
        /// The STOP delay.
        delay: SimDuration,
    },
    /// The controller restarted the STOP circuit.
    StopRestarted,
    /// FB_ERR: the STOP channels disagreed for longer than `limit`.
    StopDiscrepancy {
        /// The discrepancy time allowed.
        limit: SimDuration,
    },
    /// FB_ERR: K1's auxiliary contact was open at the STOP restart (K1 welded?).
    StopContactOpen,
    /// The overtravel monitor tripped: these sensors not released; K1 off.
    OvertravelTripped {
        /// The bottom sensor.
        bottom: bool,
        /// The top sensor.
        top: bool,
    },
    /// The operator reset the overtravel monitor.
    OvertravelReset,
    /// FB_ERR: K1's auxiliary contact was open at the overtravel reset (K1 welded?).
    OvertravelContactOpen,
    /// K1 closed: drive power on.
    K1Closed,
    /// K1 opened, for this cause.
    K1Opened(K1Cause),
    /// Another event of the logic, in its own terms (a connection's error, the group's
    /// state, a local output, a logic fault, the modules' other events).
    Logic(LogicEventKind),
}

impl fmt::Display for LiftSafetyCause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use LiftSafetyCause::*;
        match self {
            StopDemanded { channels, delay } => {
                let open: Vec<String> = (0..2)
                    .filter(|b| channels & 1 << b != 0)
                    .map(|b| (b + 1).to_string())
                    .collect();
                write!(
                    f,
                    "tripped: STOP demanded (channel {} open); estop_out off, K1 off in {delay}",
                    open.join(" and ")
                )
            }
            StopDelayElapsed { delay } => {
                write!(f, "STOP delay of {delay} elapsed: EStopDelOut off")
            }
            StopRestarted => f.write_str("STOP circuit restarted by the controller"),
            StopDiscrepancy { limit } => {
                write!(f, "FB_ERR: STOP channels disagree for longer than {limit}")
            }
            StopContactOpen => {
                f.write_str("FB_ERR: K1 auxiliary contact open at the STOP restart (K1 welded?)")
            }
            OvertravelTripped { bottom, top } => {
                let which = match (bottom, top) {
                    (true, true) => "bottom and top sensors",
                    (true, false) => "bottom sensor",
                    _ => "top sensor",
                };
                write!(
                    f,
                    "tripped: overtravel {which} (safety monitor not released); K1 off"
                )
            }
            OvertravelReset => f.write_str("overtravel monitor reset by the operator"),
            OvertravelContactOpen => f.write_str(
                "FB_ERR: K1 auxiliary contact open at the overtravel reset (K1 welded?)",
            ),
            K1Closed => f.write_str("K1 closed: drive power on"),
            K1Opened(c) => write!(f, "K1 opened: {c}"),
            Logic(e) => e.fmt(f),
        }
    }
}

/// One line of the safety log.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LiftSafetyEvent {
    /// When (the scan's time).
    pub at: SimTime,
    /// What kind.
    pub kind: LiftEventKind,
    /// What happened ([`LiftSafetyCause`]; its `Display` is the log's words).
    pub cause: LiftSafetyCause,
}

impl LiftSafetyEvent {
    /// The time in seconds, for the rig's `at_s`.
    pub fn at_s(&self) -> f64 {
        self.at.as_secs_f64()
    }

    /// `true` for trips, errors and the outputs they switch off.
    pub fn is_trip(&self) -> bool {
        matches!(
            self.kind,
            LiftEventKind::Trip | LiftEventKind::Error | LiftEventKind::PowerOff
        )
    }
}

impl fmt::Display for LiftSafetyEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.at, self.cause)
    }
}

/// The state of the safety logic after a scan, for displays and logs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LiftSafetyDiag {
    /// The `drive` group: state and FB_ERR/COM_ERR/OUT_ERR.
    pub group: GroupStatus,
    /// Diag byte of connection 1 (cabin STOP terminal).
    pub stop_link: ConnDiag,
    /// Diag byte of connection 2 (cabinet terminal).
    pub cabinet_link: ConnDiag,
    /// The ESTOP module (STOP): state and diag bits (0 = STOP pair discrepancy, 4 = EDM1).
    pub estop: ModuleStatus,
    /// The MON module (overtravel): state and diag bits (4 = EDM1).
    pub overtravel: ModuleStatus,
    /// Why K1 is open, or `None` while it is closed.
    pub k1_open_cause: Option<K1Cause>,
    /// `true` once the logic has stopped on an internal fault.
    pub logic_fault: bool,
}

/// What the safety logic gives the rig each scan.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LiftSafetyOutputs {
    /// Command of contactor K1 (drive power): `true` = closed.
    pub k1: bool,
    /// ESTOP's immediate output to the controller: `false` = STOP demanded, stop at the next
    /// floor (or not yet restarted).
    pub estop_out: bool,
    /// The logic's state.
    pub diag: LiftSafetyDiag,
    /// What happened in this scan.
    pub events: Vec<LiftSafetyEvent>,
}

/// Which safe link a fault is injected into.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SafeLink {
    /// Connection 1: the cabin KL1904 with the STOP contacts.
    CabinStop,
    /// Connection 2: the cabinet KL1904 with the overtravel monitor and K1's auxiliary contact.
    Cabinet,
}

/// Why the lift's safety project cannot be built.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LiftSafetyError {
    /// The configuration gives a project the verifier rejects (e.g. two equal addresses).
    #[error("the lift's safety project was rejected: {}", .0.iter().map(ToString::to_string).collect::<Vec<_>>().join("; "))]
    Rejected(Vec<VerifyError>),
    /// The built project lacks an item the lift needs (a defect of this crate).
    #[error("the lift's safety project lacks `{0}`")]
    Missing(&'static str),
}

/// Handles into the running logic.
#[derive(Clone, Copy, Debug)]
struct Ids {
    group: GroupId,
    stop_link: ConnectionId,
    cabinet_link: ConnectionId,
    estop: ModuleId,
    mon: ModuleId,
    overloaded: StandardInput,
    operator_reset: StandardInput,
    err_ack: StandardInput,
    controller_restart: StandardInput,
    estop_out: StandardOutput,
    /// K1, local output 1 ([`TwinSafeLogic::local_output_position`]).
    k1: Option<usize>,
}

/// The lift's safety logic: call [`LiftSafety::scan`] every [`SAFETY_SCAN_PERIOD`].
#[derive(Clone, Debug)]
pub struct LiftSafety {
    config: LiftSafetyConfig,
    logic: TwinSafeLogic,
    ids: Ids,
    k1: bool,
    /// The inputs and outputs of the last scan (its events aside), for a scan that changes
    /// nothing ([`LiftSafety::scan`]).
    last: Option<LastScan>,
    /// The time of the last scan, a left-out one ([`LiftSafety::skip_through`]) included.
    scanned: Option<SimTime>,
}

/// What a scan was given and gave, its events aside.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct LastScan {
    inputs: LiftSafetyInputs,
    k1: bool,
    estop_out: bool,
    diag: LiftSafetyDiag,
}

impl LiftSafety {
    /// Build and verify the project for `config`. K1 starts open; it closes once the group
    /// runs, the controller has pulsed `controller_restart` and the operator `operator_reset`
    /// (a start-up needs both resets, like the real rig after power-on).
    pub fn new(config: LiftSafetyConfig) -> Result<Self, LiftSafetyError> {
        let logic = TwinSafeLogic::new(&config.project()).map_err(LiftSafetyError::Rejected)?;
        fn find<T>(what: Option<T>, name: &'static str) -> Result<T, LiftSafetyError> {
            what.ok_or(LiftSafetyError::Missing(name))
        }
        let ids = Ids {
            group: find(logic.group(names::GROUP), names::GROUP)?,
            stop_link: find(logic.connection(names::STOP_LINK), names::STOP_LINK)?,
            cabinet_link: find(logic.connection(names::CABINET_LINK), names::CABINET_LINK)?,
            estop: find(logic.module(names::ESTOP), names::ESTOP)?,
            mon: find(logic.module(names::MON), names::MON)?,
            overloaded: find(logic.standard_input("overloaded"), "overloaded")?,
            operator_reset: find(logic.standard_input("operator_reset"), "operator_reset")?,
            err_ack: find(logic.standard_input("err_ack"), "err_ack")?,
            controller_restart: find(
                logic.standard_input("controller_restart"),
                "controller_restart",
            )?,
            estop_out: find(logic.standard_output("estop_out"), "estop_out")?,
            k1: logic.local_output_position(1),
        };
        Ok(LiftSafety {
            config,
            logic,
            ids,
            k1: false,
            last: None,
            scanned: None,
        })
    }

    /// The parameters.
    pub fn config(&self) -> &LiftSafetyConfig {
        &self.config
    }

    /// The underlying KL6904, for deeper diagnostics.
    pub fn logic(&self) -> &TwinSafeLogic {
        &self.logic
    }

    fn link(&self, link: SafeLink) -> ConnectionId {
        match link {
            SafeLink::CabinStop => self.ids.stop_link,
            SafeLink::Cabinet => self.ids.cabinet_link,
        }
    }

    /// The rig's "safe-link-drop" fault: `link` delivers no telegrams from `at` for
    /// `duration`. Longer than the watchdog (100 ms) trips COM_ERR and drops K1.
    pub fn drop_link(&mut self, link: SafeLink, at: SimTime, duration: SimDuration) {
        self.inject_link_fault(link, at, ChannelFault::Drop { duration });
    }

    /// Any black-channel fault on `link` at `at` (corrupted CRC, replay, wrong address, null
    /// telegram, drop).
    pub fn inject_link_fault(&mut self, link: SafeLink, at: SimTime, fault: ChannelFault) {
        let c = self.link(link);
        self.logic.inject(c, at, fault);
    }

    /// Make local output 1 (K1) report an error (OUT_ERR) while `faulty`.
    pub fn set_k1_output_fault(&mut self, faulty: bool) {
        self.logic.set_local_output_fault(1, faulty);
    }

    /// Stop the whole logic at the next scan (internal logic fault).
    pub fn inject_logic_fault(&mut self, cause: &str) {
        self.logic.inject_logic_fault(cause);
    }

    /// One safety scan at `now` with `inputs`.
    ///
    /// Almost every scan has the inputs of the last one and finds the logic at rest: the logic
    /// then takes it the quiet way ([`TwinSafeLogic::quiet_scan`]), which changes nothing this
    /// reads, and the outputs are the last scan's with no events (K1 did not change either).
    /// Every other scan is taken in full ([`LiftSafety::full_scan`]).
    pub fn scan(&mut self, now: SimTime, inputs: &LiftSafetyInputs) -> LiftSafetyOutputs {
        let same = self.last.as_ref().is_some_and(|l| l.inputs.same_as(inputs));
        if same && self.logic.quiet_scan(now) {
            self.scanned = Some(now);
            if let Some(last) = &self.last {
                return LiftSafetyOutputs {
                    k1: last.k1,
                    estop_out: last.estop_out,
                    diag: last.diag,
                    events: Vec::new(),
                };
            }
        }
        self.full_scan(now, inputs)
    }

    /// The time of the next scan that may give anything new with `inputs`, for a caller that
    /// scans every [`SAFETY_SCAN_PERIOD`]: the next period after the last scan, or, where
    /// `inputs` are the last scan's and that scan left the logic at rest, the first scan time
    /// on that grid at which the rest may end (a scheduled fault falls due or a delay ends;
    /// [`SimTime::MAX`]: not before an input changes or a fault is injected). Every scan
    /// before it would be a quiet one, with the last scan's outputs and no events: the
    /// caller may leave those out and tell the logic so ([`LiftSafety::skip_through`]).
    /// [`SimTime::ZERO`] before the first scan.
    pub fn poll_at(&self, inputs: &LiftSafetyInputs) -> SimTime {
        let Some(scanned) = self.scanned else {
            return SimTime::ZERO;
        };
        let period = SAFETY_SCAN_PERIOD.as_nanos();
        let next = scanned.as_nanos().saturating_add(period);
        let same = self.last.as_ref().is_some_and(|l| l.inputs.same_as(inputs));
        let rest_ends = match self.logic.quiet_before() {
            Some(end) if same => end.as_nanos(),
            _ => next,
        };
        if rest_ends <= next {
            return SimTime::from_nanos(next);
        }
        if rest_ends == u64::MAX {
            return SimTime::MAX;
        }
        // The first grid time not before the rest's end.
        let periods = (rest_ends - scanned.as_nanos()).div_ceil(period);
        SimTime::from_nanos(
            periods
                .checked_mul(period)
                .and_then(|d| d.checked_add(scanned.as_nanos()))
                .unwrap_or(u64::MAX),
        )
    }

    /// The caller left out its scans on the grid after the last scan (every
    /// [`SAFETY_SCAN_PERIOD`]) up to `through` (inclusive), with the last scan's inputs,
    /// each before [`LiftSafety::poll_at`] of them: they are taken now, as the quiet scans
    /// they are, all or none. `true` if so (or there was none to take); `false`, with
    /// nothing changed, if one of them would not be quiet: the caller must scan it.
    pub fn skip_through(&mut self, through: SimTime) -> bool {
        // Before the first scan there is no grid, and no scan to take.
        let Some(scanned) = self.scanned else {
            return true;
        };
        let period = SAFETY_SCAN_PERIOD.as_nanos();
        let Some(since) = through.checked_duration_since(scanned) else {
            return true;
        };
        let periods = since.as_nanos() / period;
        if periods == 0 {
            return true;
        }
        let (Ok(n), Some(first), Some(last)) = (
            u32::try_from(periods),
            scanned.checked_add(SAFETY_SCAN_PERIOD),
            scanned.checked_add(SimDuration::from_nanos(periods * period)),
        ) else {
            return false;
        };
        if self.last.is_none() || !self.logic.quiet_scans(first, last, n) {
            return false;
        }
        self.scanned = Some(last);
        true
    }

    /// One safety scan at `now` with `inputs`, every step taken: the inputs set, the logic's
    /// full scan ([`TwinSafeLogic::full_scan`]), the outputs read back.
    fn full_scan(&mut self, now: SimTime, inputs: &LiftSafetyInputs) -> LiftSafetyOutputs {
        let i = inputs;
        let ids = self.ids;
        self.logic.set_standard_input(ids.overloaded, i.overloaded);
        self.logic
            .set_standard_input(ids.operator_reset, i.operator_reset);
        self.logic.set_standard_input(ids.err_ack, i.err_ack);
        self.logic
            .set_standard_input(ids.controller_restart, i.controller_restart);
        self.logic.set_partner_inputs(
            ids.stop_link,
            u8::from(i.stop_ch1) | u8::from(i.stop_ch2) << 1,
        );
        self.logic.set_partner_inputs(
            ids.cabinet_link,
            u8::from(i.overtravel_bottom_released)
                | u8::from(i.overtravel_top_released) << 1
                | u8::from(i.k1_aux) << 2,
        );
        let logged = self.logic.full_scan(now);
        // Almost every scan logs nothing.
        let mut events: Vec<LiftSafetyEvent> = if logged.is_empty() {
            Vec::new()
        } else {
            logged
                .iter()
                .map(|e| describe(e, &self.config, &ids))
                .collect()
        };

        let k1 = ids.k1.is_some_and(|k| self.logic.local_output_at(k));
        let estop_out = self.logic.standard_output_value(ids.estop_out);
        let diag = LiftSafetyDiag {
            group: self.logic.group_status(ids.group),
            stop_link: self.logic.connection_diag(ids.stop_link),
            cabinet_link: self.logic.connection_diag(ids.cabinet_link),
            estop: self.logic.module_status(ids.estop),
            overtravel: self.logic.module_status(ids.mon),
            k1_open_cause: (!k1).then(|| self.k1_cause(i)),
            logic_fault: self.logic.logic_fault().is_some(),
        };
        if k1 != self.k1 {
            let (kind, cause) = match diag.k1_open_cause {
                None => (LiftEventKind::Release, LiftSafetyCause::K1Closed),
                Some(c) => (LiftEventKind::PowerOff, LiftSafetyCause::K1Opened(c)),
            };
            events.push(LiftSafetyEvent {
                at: now,
                kind,
                cause,
            });
            self.k1 = k1;
        }
        self.last = Some(LastScan {
            inputs: *inputs,
            k1,
            estop_out,
            diag,
        });
        self.scanned = Some(now);
        LiftSafetyOutputs {
            k1,
            estop_out,
            diag,
            events,
        }
    }

    /// The highest-priority reason K1 is open now.
    fn k1_cause(&self, i: &LiftSafetyInputs) -> K1Cause {
        let group = self.logic.group_status(self.ids.group);
        let estop = self.logic.module_status(self.ids.estop).state;
        let mon = self.logic.module_status(self.ids.mon).state;
        if self.logic.logic_fault().is_some() {
            K1Cause::LogicFault
        } else if group.errors.any() {
            K1Cause::GroupError(group.errors)
        } else if !matches!(estop, FbState::Run | FbState::DelayOut) {
            if i.stop_ch1 && i.stop_ch2 {
                K1Cause::StopRestartPending
            } else {
                K1Cause::StopPressed
            }
        } else if mon != FbState::Run {
            if i.overtravel_bottom_released && i.overtravel_top_released {
                K1Cause::OvertravelResetPending
            } else {
                K1Cause::Overtravel {
                    bottom: !i.overtravel_bottom_released,
                    top: !i.overtravel_top_released,
                }
            }
        } else {
            K1Cause::Overloaded
        }
    }
}

/// A logic event in the lift's terms: the events of the lift's two safety functions (the
/// modules `ids` names) as what they mean for the lift, the rest as the logic tells them.
fn describe(e: &LogicEvent, config: &LiftSafetyConfig, ids: &Ids) -> LiftSafetyEvent {
    use LiftEventKind::*;
    use LiftSafetyCause as C;
    let other = || C::Logic(e.kind.clone());
    let (kind, cause) = match &e.kind {
        LogicEventKind::Module { id, event, .. } if *id == ids.estop => match event {
            FbEvent::SafeStateDemanded { inputs } => (
                Trip,
                C::StopDemanded {
                    channels: inputs & 0b11,
                    delay: config.estop_delay,
                },
            ),
            FbEvent::DelayedOutputOff => (
                PowerOff,
                C::StopDelayElapsed {
                    delay: config.estop_delay,
                },
            ),
            FbEvent::Restarted => (Release, C::StopRestarted),
            FbEvent::Error(FbError::Discrepancy { .. }) => (
                Error,
                C::StopDiscrepancy {
                    limit: config.stop_discrepancy,
                },
            ),
            FbEvent::Error(FbError::Edm { .. }) => (Error, C::StopContactOpen),
            _ => (Info, other()),
        },
        LogicEventKind::Module { id, event, .. } if *id == ids.mon => match event {
            FbEvent::SafeStateDemanded { inputs } => (
                Trip,
                C::OvertravelTripped {
                    bottom: inputs & 0b01 != 0,
                    top: inputs & 0b10 != 0,
                },
            ),
            FbEvent::Restarted => (Release, C::OvertravelReset),
            FbEvent::Error(FbError::Edm { .. }) => (Error, C::OvertravelContactOpen),
            _ => (Info, other()),
        },
        LogicEventKind::Connection { .. } if e.is_trip() => (Error, other()),
        LogicEventKind::GroupTripped { .. } => (Trip, other()),
        LogicEventKind::GroupAcknowledged { .. } => (Acknowledge, other()),
        LogicEventKind::LocalOutputFault { .. } | LogicEventKind::LogicFault { .. } => {
            (Error, other())
        }
        _ => (Info, other()),
    };
    LiftSafetyEvent {
        at: e.at,
        kind,
        cause,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small seeded generator (xorshift64*), so every run of the test is the same.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
        }

        /// `true` once in `n` on average.
        fn one_in(&mut self, n: u64) -> bool {
            self.next() % n == 0
        }

        fn below(&mut self, n: u64) -> u64 {
            self.next() % n
        }
    }

    /// An input of [`LiftSafetyInputs`], for a change planned ahead.
    #[derive(Clone, Copy)]
    enum Field {
        Stop1,
        Stop2,
        OperatorReset,
        ErrAck,
        Restart,
    }

    fn set(i: &mut LiftSafetyInputs, field: Field, value: bool) {
        match field {
            Field::Stop1 => i.stop_ch1 = value,
            Field::Stop2 => i.stop_ch2 = value,
            Field::OperatorReset => i.operator_reset = value,
            Field::ErrAck => i.err_ack = value,
            Field::Restart => i.controller_restart = value,
        }
    }

    /// The rig around the safety logic, at random: the inputs held for stretches and changed
    /// now and then as a lift would change them (buttons pulsed for a few scans, STOP pressed
    /// and released on both channels with a skew that is now and then longer than the
    /// discrepancy time, sensors tripped, overload, K1's auxiliary contact following K1 a few
    /// scans late or sticking), link faults of every kind at random times, a faulty K1
    /// output.
    struct Driver {
        rng: Rng,
        planned: Vec<(SimTime, Field, bool)>,
    }

    impl Driver {
        fn plan(&mut self, now: SimTime, in_ms: u64, field: Field, value: bool) {
            let at = now + SimDuration::from_millis(in_ms);
            self.planned.push((at, field, value));
        }

        /// Changes the inputs for the scan at `now` (`k1`: K1 after the last scan); returns
        /// the faults to inject before it.
        fn step(&mut self, i: &mut LiftSafetyInputs, k1: bool, now: SimTime) -> Vec<Fault> {
            let mut k = 0;
            while k < self.planned.len() {
                let (at, field, value) = self.planned[k];
                if at <= now {
                    set(i, field, value);
                    self.planned.swap_remove(k);
                } else {
                    k += 1;
                }
            }
            let rng = &mut self.rng;
            let pulse = match rng.below(if k1 { 2000 } else { 60 }) {
                0 => Some(Field::Restart),
                1 => Some(Field::OperatorReset),
                2 => Some(Field::ErrAck),
                _ => None,
            };
            if let Some(field) = pulse {
                let len = 1 + rng.below(30);
                set(i, field, true);
                self.plan(now, len, field, false);
            }
            let rng = &mut self.rng;
            let stop_closed = i.stop_ch1 && i.stop_ch2;
            if rng.one_in(if stop_closed { 1500 } else { 300 }) {
                let skew = if rng.one_in(4) { rng.below(80) } else { 0 };
                let (first, second) = if rng.one_in(2) {
                    (Field::Stop1, Field::Stop2)
                } else {
                    (Field::Stop2, Field::Stop1)
                };
                set(i, first, !stop_closed);
                self.plan(now, skew, second, !stop_closed);
            }
            let rng = &mut self.rng;
            if rng.one_in(if i.overtravel_bottom_released {
                4000
            } else {
                200
            }) {
                i.overtravel_bottom_released = !i.overtravel_bottom_released;
            }
            if rng.one_in(if i.overtravel_top_released { 6000 } else { 200 }) {
                i.overtravel_top_released = !i.overtravel_top_released;
            }
            if rng.one_in(if i.overloaded { 300 } else { 4000 }) {
                i.overloaded = !i.overloaded;
            }
            // The contact mostly follows K1, a few scans late; now and then it sticks.
            if i.k1_aux == k1 && rng.one_in(3) && !rng.one_in(300) {
                i.k1_aux = !k1;
            }
            let mut faults = Vec::new();
            if rng.one_in(1500) {
                let link = if rng.one_in(2) {
                    SafeLink::CabinStop
                } else {
                    SafeLink::Cabinet
                };
                let at = now + SimDuration::from_millis(rng.below(30));
                let fault = match rng.below(8) {
                    0..=3 => ChannelFault::Drop {
                        duration: SimDuration::from_millis(rng.below(250)),
                    },
                    4 => ChannelFault::CorruptCrc,
                    5 => ChannelFault::Replay {
                        age: rng.below(20) as u8,
                    },
                    6 => ChannelFault::WrongAddress { sender: 7 },
                    _ => ChannelFault::NullTelegram,
                };
                faults.push(Fault::Link(link, at, fault));
            }
            if rng.one_in(4000) {
                faults.push(Fault::K1Output(rng.one_in(3)));
            }
            faults
        }
    }

    enum Fault {
        Link(SafeLink, SimTime, ChannelFault),
        K1Output(bool),
    }

    /// `true` if the two are in the same state: the logic field by field and the wrapper's own.
    fn same(a: &LiftSafety, b: &LiftSafety) -> bool {
        a.k1 == b.k1 && a.last == b.last && a.scanned == b.scanned && a.logic.same_state(&b.logic)
    }

    /// The scan with its quiet way against the full scan (the reference, every step taken
    /// every time): two `LiftSafety` side by side over long random runs, the same outputs
    /// and the same whole state after every scan. Runs with the default STOP delay and with a
    /// short one (so the delay elapses often), with a logic fault injected or a scan time
    /// going backwards near the end of some, and one run long enough for the connections'
    /// sequence numbers to wrap.
    #[test]
    fn a_quiet_scan_is_the_full_scan() {
        let mut quiet = 0u64;
        let mut scans = 0u64;
        for seed in 1..=100u64 {
            let mut driver = Driver {
                rng: Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1),
                planned: Vec::new(),
            };
            let rng = &mut driver.rng;
            let mut config = LiftSafetyConfig::default();
            if seed % 2 == 0 {
                config.estop_delay = SimDuration::from_millis(rng.below(300));
            }
            let mut fast = LiftSafety::new(config.clone()).expect("the lift project");
            let mut full = LiftSafety::new(config).expect("the lift project");
            let mut inputs = LiftSafetyInputs::healthy();
            let mut now = SimTime::from_millis(rng.below(5));
            let mut k1 = false;
            let mut last_now = now;
            // One long run, past the sequence numbers' wrap at 65535.
            let steps = if seed == 1 { 70_000 } else { 3000 };
            for step in 0..steps {
                for fault in driver.step(&mut inputs, k1, now) {
                    match fault {
                        Fault::Link(link, at, f) => {
                            fast.inject_link_fault(link, at, f);
                            full.inject_link_fault(link, at, f);
                        }
                        Fault::K1Output(faulty) => {
                            fast.set_k1_output_fault(faulty);
                            full.set_k1_output_fault(faulty);
                        }
                    }
                }
                if seed % 5 == 0 && step == 2900 {
                    fast.inject_logic_fault("test");
                    full.inject_logic_fault("test");
                }
                if seed % 7 == 0 && step == 2500 {
                    // A scan time before the last one stops the logic.
                    now = last_now
                        .checked_sub(SimDuration::from_millis(1))
                        .unwrap_or(now);
                }
                let may_rest =
                    fast.logic.settled() && fast.last.is_some_and(|l| l.inputs == inputs);
                let a = fast.scan(now, &inputs);
                let b = full.full_scan(now, &inputs);
                assert_eq!(a, b, "seed {seed} step {step} at {now}");
                assert!(same(&fast, &full), "seed {seed} step {step} at {now}");
                quiet += u64::from(may_rest);
                scans += 1;
                k1 = a.k1;
                last_now = now;
                let rng = &mut driver.rng;
                now += match rng.below(100) {
                    0 => SimDuration::ZERO,
                    1 => SimDuration::from_millis(2 + rng.below(150)),
                    2 => SimDuration::from_micros(1 + rng.below(3000)),
                    _ => SAFETY_SCAN_PERIOD,
                };
            }
        }
        // The quiet way must be taken often, or the test shows nothing.
        assert!(quiet * 2 > scans, "{quiet} of {scans} scans quiet");
    }

    /// A caller that leaves out the scans before [`LiftSafety::poll_at`] and tells the logic
    /// so ([`LiftSafety::skip_through`]) gets what a caller that scans every period gets: two
    /// `LiftSafety` side by side over long random runs on the 1 ms grid, one scanned every
    /// period, the other only where its inputs changed, a fault was injected or its deadline
    /// came; the same outputs at each of its scans and the same whole state after them.
    #[test]
    fn scans_left_out_before_the_deadline_are_the_scans_taken() {
        let (mut left_out, mut scans) = (0u64, 0u64);
        for seed in 1..=60u64 {
            let mut driver = Driver {
                rng: Rng(seed.wrapping_mul(0x2545_f491_4f6c_dd1d) | 1),
                planned: Vec::new(),
            };
            let mut config = LiftSafetyConfig::default();
            if seed % 2 == 0 {
                config.estop_delay = SimDuration::from_millis(driver.rng.below(300));
            }
            let mut every = LiftSafety::new(config.clone()).expect("the lift project");
            let mut lazy = LiftSafety::new(config).expect("the lift project");
            let mut inputs = LiftSafetyInputs::healthy();
            let mut now = SimTime::from_millis(driver.rng.below(5));
            let mut k1 = false;
            for step in 0..4000 {
                let faults = driver.step(&mut inputs, k1, now);
                let changed = !faults.is_empty()
                    || lazy.last.is_none_or(|l| l.inputs != inputs)
                    || now >= lazy.poll_at(&inputs);
                if changed {
                    // The scans left out come before the fault and this scan.
                    let before = now - SAFETY_SCAN_PERIOD;
                    assert!(
                        lazy.skip_through(before),
                        "seed {seed} step {step} at {now}"
                    );
                }
                for fault in faults {
                    match fault {
                        Fault::Link(link, at, f) => {
                            every.inject_link_fault(link, at, f);
                            lazy.inject_link_fault(link, at, f);
                        }
                        Fault::K1Output(faulty) => {
                            every.set_k1_output_fault(faulty);
                            lazy.set_k1_output_fault(faulty);
                        }
                    }
                }
                let a = every.scan(now, &inputs);
                if changed {
                    let b = lazy.scan(now, &inputs);
                    assert_eq!(a, b, "seed {seed} step {step} at {now}");
                    assert!(same(&every, &lazy), "seed {seed} step {step} at {now}");
                } else {
                    assert!(
                        a.events.is_empty(),
                        "seed {seed} step {step}: left out {a:?}"
                    );
                    left_out += 1;
                }
                scans += 1;
                k1 = a.k1;
                now += SAFETY_SCAN_PERIOD;
            }
            assert!(
                lazy.skip_through(now - SAFETY_SCAN_PERIOD),
                "seed {seed} at the end"
            );
            assert!(same(&every, &lazy), "seed {seed} at the end");
        }
        // Most scans must be left out, or the test shows nothing.
        assert!(left_out * 2 > scans, "{left_out} of {scans} scans left out");
    }
}
