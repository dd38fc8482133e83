//! The AS-i master: phases, lists, flags, the cycle and the process image (docs/master.md;
//! docs/asi.md §5; §2.2.3, table 4.1 of the lift thesis).
//!
//! Sans-IO: the master never sees pulses or a clock. [`Master::poll_transmit`] gives the
//! request to start now, [`Master::handle_outcome`] takes what came back (a valid response, a
//! response that failed checks, or nothing), [`Master::poll_at`] says when an idle master wants
//! to be asked again. `asi_bus::Bus` drives it over the pulse-level line.
//!
//! The implementation is split by concern: `host` the mailbox jobs, `schedule` the next
//! call of each phase, `requests` the telegrams, `outcomes` what a response changes.
//!
//! **Phases** (docs/asi.md §5.1): offline → detection (Read_IO_Configuration, Read_ID_Code,
//! Read_ID1, Read_ID2 at 0A, 1A..31A, then 1B..31B where the A half does not hold a standard
//! slave; builds LDS; repeated until a slave is found) → activation (protected mode: the slaves
//! of LPS whose codes match PCD; configuration mode: every detected slave but 0; each gets
//! Write_Parameter with its projected parameter and a Data_Exchange with the default outputs
//! 1111, the slave IC's passive output state (docs/lab-bus.md §3.6), then joins LAS) → normal
//! operation. A normal cycle is: Data_Exchange with every LAS slot in ascending address; one
//! management call (a mailbox job, else Read_Status of the next LAS slave round-robin, which
//! keeps LPF); one inclusion call to the next address that is not activated (skipped when none
//! is left).
//!
//! **Decisions beyond the source documents**:
//! - Address 0 is an inclusion address only while some address 1..31 is free: with 31
//!   standard slaves there is nothing left to include and the cycle is (31 + 1) · 154 µs.
//! - A/B: an address with an A and a B slave in LAS is one slot, serving A in even and B in odd
//!   cycles; a slot with only one of them serves it every cycle.
//! - The repeat: any failed transaction is repeated once at once, except a probe
//!   (Read_IO_Configuration in detection or inclusion) that gets no response, which is the
//!   normal answer of an empty address. A corrupt probe answer is repeated.
//! - Drop-out counts failed Data_Exchanges (after their repeat); `max_failed_cycles`
//!   consecutive ones remove the slave from LAS and LDS, set it in LCS, and zero its input
//!   nibble. A detected but not activated slave that no longer answers its inclusion probe
//!   leaves LDS.
//! - Data_Exchange_Active = 0 sends the default outputs 1111 (A/B: 111) instead of the image;
//!   inputs are still updated.
//! - Host Offline: one Data_Exchange with the default outputs to every LAS slave, then the
//!   offline phase (LAS, LDS, LPF cleared, input nibbles 0). APF: offline at once.
//! - Integrated analog (CTT1, master profile M3/M4): for an S-7.3 slave (ID 3, ID2 bit 2) the
//!   master drives the output nibble itself ([`crate::integrated_analog`]); the PLC's output nibble for
//!   that slave is ignored, the input nibble still shows the raw handshake.

use crate::config::{ConfigError, MasterConfig, Mode, ProjectedConfig};
use crate::image::{
    ProcessImage, F0_CONFIG_ERROR, F1_APF, F2_PERIPHERY_FAULT, F3_CONFIGURATION_NOT_ACTIVE,
};
use crate::integrated_analog::{S73InputMaster, S73OutputMaster, OVERFLOW_VALUE};
use crate::leds::{LedWatch, MasterLeds, PlcLink};
use crate::lists::{EcFlags, HostFlags, SlaveList};
use crate::mailbox::{address_from_byte, Command, JobResult, Mailbox, MailboxRequest};
use crate::record::{BusStats, TxKind};
use asi_phy::slave_id::ACK_0110;
use asi_phy::{Checks, Nibble, Request, Response, Select, SimTime, SlaveAddr, SlaveCodes};

mod cycle;
mod host;
mod outcomes;
mod requests;
mod schedule;
#[cfg(test)]
mod tests;

/// The master's phase (docs/asi.md §5.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Phase {
    /// No traffic (power-on, APF, host Offline).
    Offline,
    /// Start-up: reading the codes of every address.
    Detection,
    /// Start-up: activating the detected slaves.
    Activation,
    /// Normal operation: data exchange, management and inclusion phases.
    NormalOperation,
}

/// What came back for a request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// A response that passed all seven checks.
    Response(Response),
    /// A response that failed these checks (two slaves answering at once, noise).
    Corrupt(Checks),
    /// Nothing within the response timeout.
    NoResponse,
}

/// A request the master starts now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Transmit {
    /// The request.
    pub request: Request,
    /// What it is for.
    pub kind: TxKind,
    /// `true` for the immediate repeat of a failed transaction.
    pub repeat: bool,
    /// `true` if the request goes to an A/B slave (I3 of a Data_Exchange or Write_Parameter is
    /// then the select bit).
    pub ab: bool,
    /// The list bit of the slave it is for (0..31 standard or A, 33..63 B; 0 for the calls to
    /// address 0 of auto-addressing), as [`crate::slave_stats::slave_of`] reads the request.
    pub slave: u8,
}

/// How the master judged an outcome.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Verdict {
    /// The transaction will be repeated at once.
    pub repeat: bool,
    /// The outcome was a fault (not the normal silence of an empty address).
    pub error: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Read {
    Io,
    Id,
    Id1,
    Id2,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum InclStep {
    Read(Read),
    Param,
    Dexg,
    AutoId1(SlaveAddr, Nibble),
    AutoAssign(SlaveAddr),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum JobStep {
    Param(SlaveAddr, Nibble),
    Status(SlaveAddr),
    Delete(SlaveAddr, SlaveAddr),
    Assign(SlaveAddr),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Tx {
    Detect(SlaveAddr, Read),
    ActivateParam(SlaveAddr),
    ActivateDexg(SlaveAddr),
    Exchange(SlaveAddr),
    Status(SlaveAddr),
    Include(SlaveAddr, InclStep),
    Job(JobStep),
    OfflineDefault(SlaveAddr),
}

impl Tx {
    fn kind(self) -> TxKind {
        match self {
            Tx::Detect(..) => TxKind::Detection,
            Tx::ActivateParam(_) | Tx::ActivateDexg(_) => TxKind::Activation,
            Tx::Exchange(_) => TxKind::DataExchange,
            Tx::Status(_) => TxKind::Management,
            Tx::Include(_, InclStep::AutoId1(..) | InclStep::AutoAssign(_)) => TxKind::AutoAddress,
            Tx::Include(..) => TxKind::Inclusion,
            Tx::Job(_) => TxKind::HostJob,
            Tx::OfflineDefault(_) => TxKind::Offline,
        }
    }

    /// The list bit of the slave the call goes to (the calls of auto-addressing go to the
    /// slave at address 0).
    fn slave(self) -> u8 {
        match self {
            Tx::Detect(a, _)
            | Tx::ActivateParam(a)
            | Tx::ActivateDexg(a)
            | Tx::Exchange(a)
            | Tx::Status(a)
            | Tx::OfflineDefault(a)
            | Tx::Include(a, InclStep::Read(_) | InclStep::Param | InclStep::Dexg)
            | Tx::Job(JobStep::Param(a, _) | JobStep::Status(a) | JobStep::Delete(a, _)) => {
                a.index()
            }
            Tx::Include(_, InclStep::AutoId1(..) | InclStep::AutoAssign(_))
            | Tx::Job(JobStep::Assign(_)) => 0,
        }
    }

    /// A probe whose silence means "no slave here".
    fn is_probe(self) -> bool {
        matches!(
            self,
            Tx::Detect(_, Read::Io) | Tx::Include(_, InclStep::Read(Read::Io))
        )
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct InFlight {
    tx: Tx,
    request: Request,
    repeated: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Probe {
    a: SlaveAddr,
    step: Read,
    codes: SlaveCodes,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Data,
    Management,
    Inclusion,
}

#[derive(Clone, Debug, PartialEq)]
enum AnalogEngine {
    Output(S73OutputMaster),
    Input(S73InputMaster),
}

/// The host flags' bits in output word 0.
const HOST_FLAG_BITS: u16 = HostFlags::WORD0_LOCK_DATA_EXCHANGE
    | HostFlags::WORD0_OFFLINE
    | HostFlags::WORD0_NO_AUTO_ADDRESS;

const UNKNOWN_CODES: SlaveCodes = SlaveCodes::new(0xF, 0xF, 0xF, 0xF);

/// The AS-i master.
#[derive(Clone, Debug, PartialEq)]
pub struct Master {
    cfg: MasterConfig,
    projected: ProjectedConfig,
    mode: Mode,
    phase: Phase,
    lds: SlaveList,
    las: SlaveList,
    lcs: SlaveList,
    lpf: SlaveList,
    detected: [SlaveCodes; 64],
    /// The list bits `i` whose `detected[i]` are the codes of an A/B slave: the inclusion
    /// scan reads which addresses a standard slave holds whole from it.
    ab_mask: u64,
    pi: [Nibble; 64],
    fails: [u8; 64],
    image: ProcessImage,
    host: HostFlags,
    /// The bits of output word 0 that `host` was read from.
    host_bits: u16,
    power_ok: bool,
    wake_at: SimTime,
    in_flight: Option<InFlight>,
    repeat_pending: bool,
    det_cursor: u8,
    det_probe: Option<Probe>,
    act_todo: SlaveList,
    act_param_done: bool,
    stage: Stage,
    cursor: u8,
    odd_cycle: bool,
    cycle_open: bool,
    cycle_start: Option<SimTime>,
    status_cursor: u8,
    incl_cursor: u8,
    incl: Option<Probe>,
    incl_step: Option<InclStep>,
    incl_priority: Option<SlaveAddr>,
    analog: Vec<Option<AnalogEngine>>,
    /// The list bits `i` with an engine in `analog[i]`: asked at every Data_Exchange, so
    /// one bit test instead of a look into the vector.
    analog_mask: u64,
    analog_out: [Nibble; 64],
    /// What the application last told about its PLC (the SYS and OK LEDs).
    plc: PlcLink,
    /// The LEDs over the run.
    led_watch: LedWatch,
    mailbox: Mailbox,
    job: Option<(MailboxRequest, JobStep)>,
    offline_cursor: u8,
    stats: BusStats,
    flags: EcFlags,
    /// The flags' inputs as they were when last looked at (at the start or end of a
    /// transaction); up to date unless `inputs_touched`.
    inputs_seen: Signature,
    /// Set by every write to LDS, LAS, LPF, the projected configuration, the phase, the mode,
    /// the power or the host flags: only then can the flags' inputs differ from
    /// `inputs_seen`. Most transactions (a Data_Exchange that is answered) touch none of them,
    /// so they skip building and comparing the signature. Debug builds (and so the tests)
    /// check at every transaction that no write was left unmarked.
    inputs_touched: bool,
}

/// What the flags depend on, to recompute them only when it changes.
type Signature = (u64, u64, u64, u64, Phase, Mode, bool, HostFlags);

impl Master {
    /// A master with `cfg` and the projected configuration `projected`, powered up now (it
    /// starts detection after `cfg.startup_delay`).
    pub fn new(cfg: MasterConfig, projected: ProjectedConfig) -> Result<Master, ConfigError> {
        cfg.check()?;
        let mut m = Master {
            mode: cfg.mode,
            wake_at: SimTime::ZERO + cfg.startup_delay,
            cfg,
            projected,
            phase: Phase::Offline,
            lds: SlaveList::EMPTY,
            las: SlaveList::EMPTY,
            lcs: SlaveList::EMPTY,
            lpf: SlaveList::EMPTY,
            detected: [UNKNOWN_CODES; 64],
            ab_mask: 0,
            pi: [Nibble::ALL; 64],
            fails: [0; 64],
            image: ProcessImage::default(),
            host: HostFlags::from_output_word0(0),
            host_bits: 0,
            power_ok: true,
            in_flight: None,
            repeat_pending: false,
            det_cursor: 0,
            det_probe: None,
            act_todo: SlaveList::EMPTY,
            act_param_done: false,
            stage: Stage::Data,
            cursor: 1,
            odd_cycle: false,
            cycle_open: false,
            cycle_start: None,
            status_cursor: 0,
            incl_cursor: 1,
            incl: None,
            incl_step: None,
            incl_priority: None,
            analog: vec![None; 64],
            analog_mask: 0,
            analog_out: [Nibble::ZERO; 64],
            plc: PlcLink::NONE,
            led_watch: LedWatch::new(SimTime::ZERO, MasterLeds::default()),
            mailbox: Mailbox::default(),
            job: None,
            offline_cursor: 0,
            stats: BusStats::default(),
            flags: EcFlags::default(),
            // Taken from the master itself at its first transaction.
            inputs_seen: (
                0,
                0,
                0,
                0,
                Phase::Offline,
                Mode::Protected,
                false,
                HostFlags::default(),
            ),
            inputs_touched: true,
        };
        m.update_flags();
        m.leds_changed(SimTime::ZERO);
        Ok(m)
    }

    /// The settings.
    pub fn config(&self) -> &MasterConfig {
        &self.cfg
    }
    /// The phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }
    /// Protected or configuration mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }
    /// List of detected slaves.
    pub fn lds(&self) -> SlaveList {
        self.lds
    }
    /// List of activated slaves.
    pub fn las(&self) -> SlaveList {
        self.las
    }
    /// List of projected slaves.
    pub fn lps(&self) -> SlaveList {
        self.projected.lps()
    }
    /// List of corrupted slaves (slaves that dropped out, bit 0 = power fail) since last read.
    pub fn lcs(&self) -> SlaveList {
        self.lcs
    }
    /// Reads and clears LCS.
    pub fn take_lcs(&mut self) -> SlaveList {
        core::mem::take(&mut self.lcs)
    }
    /// List of peripheral faults.
    pub fn lpf(&self) -> SlaveList {
        self.lpf
    }
    /// The projected configuration.
    pub fn projected(&self) -> &ProjectedConfig {
        &self.projected
    }
    /// The codes read from `a` when it was last detected.
    pub fn detected_codes(&self, a: SlaveAddr) -> Option<SlaveCodes> {
        self.lds
            .contains(a)
            .then(|| self.detected[a.index() as usize])
    }
    /// The parameter image (last parameter echo) of `a`.
    pub fn parameter_image(&self, a: SlaveAddr) -> Nibble {
        self.pi[a.index() as usize]
    }
    /// The host flags in force (from output word 0).
    pub fn host_flags(&self) -> HostFlags {
        self.host
    }
    /// The process image.
    pub fn image(&self) -> &ProcessImage {
        &self.image
    }
    /// The process image, for the PLC to write its outputs.
    pub fn image_mut(&mut self) -> &mut ProcessImage {
        &mut self.image
    }
    /// Cycle statistics and drop-outs (the bus adds the transaction counts).
    pub fn cycle_stats(&self) -> &BusStats {
        &self.stats
    }

    /// The execution-control flags (docs/asi.md §5.3).
    pub fn flags(&self) -> EcFlags {
        self.flags
    }

    /// The LEDs as the master shows them now (seed 003 table 3.2; [`crate::leds`]).
    pub fn leds(&self) -> MasterLeds {
        MasterLeds::of(self.flags, self.plc)
    }

    /// The LEDs over the run: changes and time away from normal.
    pub fn led_watch(&self) -> &LedWatch {
        &self.led_watch
    }

    /// What the application tells about its PLC from `now` on: connected, in run mode (the
    /// SYS and OK LEDs). Nothing of the master's work depends on it.
    pub fn set_plc_link(&mut self, now: SimTime, plc: PlcLink) {
        if plc != self.plc {
            self.plc = plc;
            self.leds_changed(now);
        }
    }

    /// What the application last told about its PLC.
    pub fn plc_link(&self) -> PlcLink {
        self.plc
    }

    fn signature(&self) -> Signature {
        (
            self.lds.bits(),
            self.las.bits(),
            self.lpf.bits(),
            self.projected.lps().bits(),
            self.phase,
            self.mode,
            self.power_ok,
            self.host,
        )
    }

    /// Brings `inputs_seen` up to date: the signature before a transaction.
    #[inline(always)]
    fn inputs_before(&mut self) {
        if self.inputs_touched {
            self.inputs_touched = false;
            self.inputs_seen = self.signature();
        }
        debug_assert_eq!(
            self.inputs_seen,
            self.signature(),
            "a write missed touch_inputs"
        );
    }

    /// Recomputes the flags if the signature differs from the one before the transaction.
    /// Only the check is inlined: most transactions touch nothing.
    #[inline(always)]
    fn inputs_after(&mut self, now: SimTime) {
        if self.inputs_touched {
            self.inputs_changed(now);
        }
        debug_assert_eq!(
            self.inputs_seen,
            self.signature(),
            "a write missed touch_inputs"
        );
    }

    /// `inputs_after` when something was touched.
    #[inline(never)]
    fn inputs_changed(&mut self, now: SimTime) {
        self.inputs_touched = false;
        let seen = self.signature();
        if seen != self.inputs_seen {
            self.inputs_seen = seen;
            self.update_flags();
            self.leds_changed(now);
        }
    }

    /// The LEDs may show something new from `now` (the flags or the PLC link changed).
    fn leds_changed(&mut self, now: SimTime) {
        self.led_watch.observe(now, self.leds());
    }

    /// Notes a write to something the flags depend on (see `inputs_touched`).
    fn touch_inputs(&mut self) {
        self.inputs_touched = true;
    }

    fn compute_flags(&self) -> EcFlags {
        let mut f = EcFlags::default();
        let found = self.lds.without_zero();
        let wrong = found.iter().any(|a| !self.matches_projection(a));
        let missing = SlaveList::from_bits(self.projected.lps().bits() & !self.lds.bits());
        f.set(EcFlags::CONFIG_OK, !wrong && missing.is_empty());
        f.set(EcFlags::LDS0, self.lds.contains(ZERO_A));
        let assign = self.host.auto_address_enable && self.mode == Mode::Protected && !wrong;
        f.set(EcFlags::AUTO_ADDRESS_ASSIGN, assign);
        f.set(
            EcFlags::AUTO_ADDRESS_AVAILABLE,
            assign && missing.len() == 1,
        );
        f.set(
            EcFlags::CONFIGURATION_ACTIVE,
            self.mode == Mode::Configuration,
        );
        f.set(
            EcFlags::NORMAL_OPERATION_ACTIVE,
            self.phase == Phase::NormalOperation,
        );
        f.set(EcFlags::APF, !self.power_ok);
        f.set(EcFlags::OFFLINE_READY, self.phase == Phase::Offline);
        f.set(EcFlags::PERIPHERY_OK, self.lpf.is_empty());
        f
    }

    fn matches_projection(&self, a: SlaveAddr) -> bool {
        self.projected.lps().contains(a)
            && self.detected[a.index() as usize].matches(&self.projected.codes(a))
    }

    fn eligible(&self, a: SlaveAddr) -> bool {
        a.number() != 0
            && match self.mode {
                Mode::Protected => self.matches_projection(a),
                Mode::Configuration => true,
            }
    }

    /// The codes read from the slave of list bit `i`, noted in `detected` and `ab_mask`.
    fn set_detected(&mut self, i: usize, codes: SlaveCodes) {
        self.ab_mask = with_bit(self.ab_mask, i, codes.is_ab());
        self.detected[i] = codes;
    }

    /// `analog[i]` holds an engine.
    #[inline(always)]
    fn has_analog(&self, i: usize) -> bool {
        let has = self.analog_mask >> (i & 63) & 1 != 0;
        debug_assert_eq!(has, self.analog[i].is_some(), "analog_mask out of step");
        has
    }

    /// Puts `e` (or none) into `analog[i]`, and marks it in `analog_mask`.
    fn set_analog(&mut self, i: usize, e: Option<AnalogEngine>) {
        self.analog_mask = with_bit(self.analog_mask, i, e.is_some());
        self.analog[i] = e;
    }

    fn update_flags(&mut self) {
        let f = self.compute_flags();
        self.flags = f;
        let mut n = 0u16;
        if !f.config_ok() {
            n |= F0_CONFIG_ERROR;
        }
        if f.apf() {
            n |= F1_APF;
        }
        if !f.periphery_ok() {
            n |= F2_PERIPHERY_FAULT;
        }
        if !f.configuration_active() {
            n |= F3_CONFIGURATION_NOT_ACTIVE;
        }
        self.image
            .input
            .set_flag_nibble(Nibble::from_low_bits((n >> 12) as u8));
    }

    /// The AS-i supply is (`true`) or is not above the APF threshold, from `now`.
    pub fn set_power(&mut self, now: SimTime, ok: bool) {
        if ok == self.power_ok {
            return;
        }
        self.power_ok = ok;
        self.touch_inputs();
        if ok {
            self.wake_at = now + self.cfg.startup_delay;
        } else {
            self.go_offline();
            self.lcs.set(ZERO_A, true);
        }
        self.update_flags();
        self.leds_changed(now);
    }

    /// `true` while the supply is above the APF threshold.
    pub fn power_ok(&self) -> bool {
        self.power_ok
    }

    /// When an idle master (one that returned `None` from [`Master::poll_transmit`]) wants to
    /// be asked again; `None` until something changes from outside (power, image).
    pub fn poll_at(&self, now: SimTime) -> Option<SimTime> {
        match self.phase {
            Phase::Offline if !self.power_ok || self.host.offline => None,
            Phase::Offline => Some(self.wake_at.max(now)),
            _ => Some(now + self.cfg.timing.transaction()),
        }
    }

    /// The request to start at `now`, or `None` if the master sends nothing now.
    ///
    /// The cycle's common call, a Data_Exchange with the next LAS slot, takes the short path
    /// [`Master::next_exchange`]; every other call goes through the general scheduler.
    pub fn poll_transmit(&mut self, now: SimTime) -> Option<Transmit> {
        if self.in_flight.is_some() {
            if let Some(t) = self.repeat_or_forget() {
                return Some(t);
            }
        }
        self.inputs_before();
        self.service_host(now);
        let t = match self.next_exchange(now) {
            Some(t) => Some(t),
            None => self.next_cycle_call(now),
        };
        self.inputs_after(now);
        t
    }

    /// With a transaction still in flight at the next poll: its repeat if one is pending,
    /// else (its outcome was never delivered) it is forgotten and `None` is returned.
    #[inline(never)]
    fn repeat_or_forget(&mut self) -> Option<Transmit> {
        let f = self.in_flight?;
        if self.repeat_pending {
            self.repeat_pending = false;
            return Some(Transmit {
                request: f.request,
                kind: f.tx.kind(),
                repeat: true,
                ab: self.is_ab_call(f.tx),
                slave: f.tx.slave(),
            });
        }
        self.in_flight = None;
        None
    }

    #[inline(never)]
    fn next_transmit(&mut self, now: SimTime) -> Option<Transmit> {
        for _ in 0..4 {
            let tx = self.next_tx(now)?;
            match self.request_for(tx) {
                Some(request) => {
                    self.in_flight = Some(InFlight {
                        tx,
                        request,
                        repeated: false,
                    });
                    return Some(Transmit {
                        request,
                        kind: tx.kind(),
                        repeat: false,
                        ab: self.is_ab_call(tx),
                        slave: tx.slave(),
                    });
                }
                None => self.apply(tx, None),
            }
        }
        None
    }

    /// What came back for the request in flight, known at `now` (part of the sans-IO
    /// interface; no decision depends on the time yet).
    ///
    /// The common outcome, a Data_Exchange answered, takes a short path; every other goes
    /// through the general judgement and [`Master::apply`].
    #[inline(always)]
    pub fn handle_outcome(&mut self, now: SimTime, outcome: Outcome) -> Verdict {
        if let (
            Some(InFlight {
                tx: Tx::Exchange(a),
                ..
            }),
            Outcome::Response(r),
        ) = (&self.in_flight, outcome)
        {
            // A valid response is no failure, repeat or not: what `apply` does with it.
            //
            // `exchange_answered` writes none of the flags' inputs (only the failure count,
            // the input image and the analog engine), so the signature is not looked at
            // before and after it: nothing can have changed across it. Where the inputs were
            // touched before this outcome, `inputs_touched` stays set, and the next
            // transaction's `inputs_before` takes the signature then; every write in between
            // touches the inputs too, so that is the signature the general path's next look
            // starts from as well. Held to the general path by the test
            // `an_answered_data_exchange_leaves_the_flags_to_the_next_look`.
            let a = *a;
            self.in_flight = None;
            self.exchange_answered(a, r.data());
            debug_assert!(
                self.inputs_touched || self.inputs_seen == self.signature(),
                "an answered Data_Exchange changed the flags' inputs"
            );
            return Verdict {
                repeat: false,
                error: false,
            };
        }
        self.judge_cycle_call(now, outcome)
    }

    /// [`Master::handle_outcome`] for every outcome but an answered Data_Exchange.
    #[inline(never)]
    fn judge_outcome(&mut self, now: SimTime, outcome: Outcome) -> Verdict {
        let _ = now;
        let Some(mut f) = self.in_flight else {
            return Verdict {
                repeat: false,
                error: false,
            };
        };
        let resp = match outcome {
            Outcome::Response(r) => Some(r.data()),
            _ => None,
        };
        let silence_ok = f.tx.is_probe() && outcome == Outcome::NoResponse;
        let failed = resp.is_none() && !silence_ok;
        if failed && !f.repeated {
            f.repeated = true;
            self.in_flight = Some(f);
            self.repeat_pending = true;
            return Verdict {
                repeat: true,
                error: true,
            };
        }
        self.in_flight = None;
        self.inputs_before();
        self.apply(f.tx, resp);
        self.inputs_after(now);
        Verdict {
            repeat: false,
            error: failed,
        }
    }
}

/// `mask` with list bit `i` set to `on`.
fn with_bit(mask: u64, i: usize, on: bool) -> u64 {
    let bit = 1u64 << (i & 63);
    if on {
        mask | bit
    } else {
        mask & !bit
    }
}

const ZERO_A: SlaveAddr = SlaveAddr {
    address: asi_phy::Address::ZERO,
    select: Select::A,
};
