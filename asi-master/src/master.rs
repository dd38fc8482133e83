//! The AS-i master: phases, lists, flags, the cycle and the process image (SPEC §2;
//! reference/asi.md §5; seed 003 §2.2.3, table 4.1).
//!
//! Sans-IO: the master never sees pulses or a clock. [`Master::poll_transmit`] gives the
//! request to start now, [`Master::handle_outcome`] takes what came back (a valid response, a
//! response that failed checks, or nothing), [`Master::poll_at`] says when an idle master wants
//! to be asked again. `asi_bus::Bus` drives it over the pulse-level line.
//!
//! **Phases** (reference/asi.md §5.1): offline → detection (Read_IO_Configuration, Read_ID_Code,
//! Read_ID1, Read_ID2 at 0A, 1A..31A, then 1B..31B where the A half does not hold a standard
//! slave; builds LDS; repeated until a slave is found) → activation (protected mode: the slaves
//! of LPS whose codes match PCD; configuration mode: every detected slave but 0; each gets
//! Write_Parameter with its projected parameter and a Data_Exchange with the default outputs
//! 1111, then joins LAS) → normal operation. A normal cycle is: Data_Exchange with every LAS
//! slot in ascending address; one management call (a mailbox job, else Read_Status of the next
//! LAS slave round-robin, which keeps LPF); one inclusion call to the next address that is not
//! activated (skipped when none is left).
//!
//! **Decisions beyond SPEC**:
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
use crate::lists::{EcFlags, HostFlags, SlaveList};
use crate::mailbox::{address_from_byte, Command, JobResult, Mailbox, MailboxRequest};
use crate::record::{BusStats, TxKind};
use asi_phy::slave_id::ACK_0110;
use asi_phy::{Checks, Nibble, Request, Response, Select, SimTime, SlaveAddr, SlaveCodes};

/// The master's phase (reference/asi.md §5.1).
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

    /// A probe whose silence means "no slave here".
    fn is_probe(self) -> bool {
        matches!(
            self,
            Tx::Detect(_, Read::Io) | Tx::Include(_, InclStep::Read(Read::Io))
        )
    }
}

#[derive(Clone, Copy, Debug)]
struct InFlight {
    tx: Tx,
    request: Request,
    repeated: bool,
}

#[derive(Clone, Copy, Debug)]
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

#[derive(Clone, Debug)]
enum AnalogEngine {
    Output(S73OutputMaster),
    Input(S73InputMaster),
}

const UNKNOWN_CODES: SlaveCodes = SlaveCodes::new(0xF, 0xF, 0xF, 0xF);

/// The AS-i master.
#[derive(Clone, Debug)]
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
    pi: [Nibble; 64],
    fails: [u8; 64],
    image: ProcessImage,
    host: HostFlags,
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
    analog_out: [Nibble; 64],
    mailbox: Mailbox,
    job: Option<(MailboxRequest, JobStep)>,
    offline_cursor: u8,
    stats: BusStats,
    flags: EcFlags,
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
            pi: [Nibble::ALL; 64],
            fails: [0; 64],
            image: ProcessImage::default(),
            host: HostFlags::default(),
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
            analog_out: [Nibble::ZERO; 64],
            mailbox: Mailbox::default(),
            job: None,
            offline_cursor: 0,
            stats: BusStats::default(),
            flags: EcFlags::default(),
        };
        m.update_flags();
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

    /// The execution-control flags (reference/asi.md §5.3).
    pub fn flags(&self) -> EcFlags {
        self.flags
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
        if ok {
            self.wake_at = now + self.cfg.startup_delay;
        } else {
            self.go_offline();
            self.lcs.set(ZERO_A, true);
        }
        self.update_flags();
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
    pub fn poll_transmit(&mut self, now: SimTime) -> Option<Transmit> {
        if let Some(f) = self.in_flight {
            if self.repeat_pending {
                self.repeat_pending = false;
                return Some(Transmit {
                    request: f.request,
                    kind: f.tx.kind(),
                    repeat: true,
                    ab: self.is_ab_call(f.tx),
                });
            }
            // An outcome was never delivered: forget the transaction.
            self.in_flight = None;
        }
        let before = self.signature();
        self.service_host(now);
        let t = self.next_transmit(now);
        if self.signature() != before {
            self.update_flags();
        }
        t
    }

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
                    });
                }
                None => self.apply(tx, None),
            }
        }
        None
    }

    /// What came back for the request in flight, known at `now` (part of the sans-IO
    /// interface; no decision depends on the time yet).
    pub fn handle_outcome(&mut self, now: SimTime, outcome: Outcome) -> Verdict {
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
        let before = self.signature();
        self.apply(f.tx, resp);
        if self.signature() != before {
            self.update_flags();
        }
        Verdict {
            repeat: false,
            error: failed,
        }
    }

    // ----- host interface -------------------------------------------------------------

    fn service_host(&mut self, now: SimTime) {
        let host = HostFlags::from_output_word0(self.image.output.word(0));
        if self.host.offline && !host.offline && self.phase == Phase::Offline {
            self.wake_at = self.wake_at.max(now);
        }
        self.host = host;
        if self.job.is_none() {
            if let Some(req) = self.mailbox.take(&self.image.output) {
                self.start_job(req);
                self.update_flags();
            }
        }
    }

    fn finish_job(&mut self, req: &MailboxRequest, result: JobResult, response: &[u8]) {
        self.mailbox
            .finish(&mut self.image.input, req, result, response);
        self.job = None;
    }

    fn start_job(&mut self, req: MailboxRequest) {
        use JobResult as R;
        let b = req.bytes;
        let addr = address_from_byte(b[0]);
        let codes_bytes = |c: SlaveCodes| {
            [
                (c.io.get() << 4) | c.id.get(),
                (c.id1.get() << 4) | c.id2.get(),
            ]
        };
        let Some(cmd) = Command::from_code(req.command) else {
            return self.finish_job(&req, R::UnknownCommand, &[]);
        };
        let bus_phase = self.phase == Phase::NormalOperation;
        match cmd {
            Command::WriteParameter | Command::ReadStatus => {
                let Some(a) = addr.filter(|a| a.number() != 0) else {
                    return self.finish_job(&req, R::InvalidArgument, &[]);
                };
                if !bus_phase {
                    return self.finish_job(&req, R::NotAllowed, &[]);
                }
                if !self.lds.contains(a) {
                    return self.finish_job(&req, R::SlaveNotFound, &[]);
                }
                let step = if cmd == Command::WriteParameter {
                    let max = if self.detected[a.index() as usize].is_ab() {
                        7
                    } else {
                        15
                    };
                    if b[1] > max {
                        return self.finish_job(&req, R::InvalidArgument, &[]);
                    }
                    JobStep::Param(a, Nibble::from_low_bits(b[1]))
                } else {
                    JobStep::Status(a)
                };
                self.job = Some((req, step));
            }
            Command::ChangeAddress => {
                let (Some(from), Some(to)) = (addr, address_from_byte(b[1])) else {
                    return self.finish_job(&req, R::InvalidArgument, &[]);
                };
                if from.number() == 0
                    || from == to
                    || (to.number() != 0 && to.select != from.select)
                {
                    return self.finish_job(&req, R::InvalidArgument, &[]);
                }
                if !bus_phase {
                    return self.finish_job(&req, R::NotAllowed, &[]);
                }
                if !self.lds.contains(from) {
                    return self.finish_job(&req, R::SlaveNotFound, &[]);
                }
                if self.lds.contains(ZERO_A) {
                    return self.finish_job(&req, R::NotAllowed, &[]);
                }
                if to.number() != 0 && (self.lds.contains(to) || self.occupies_whole(to.number())) {
                    return self.finish_job(&req, R::AddressOccupied, &[]);
                }
                self.job = Some((req, JobStep::Delete(from, to)));
            }
            Command::ReadProjected => {
                let Some(a) = addr else {
                    return self.finish_job(&req, R::InvalidArgument, &[]);
                };
                let c = codes_bytes(self.projected.codes(a));
                let r = [
                    self.projected.lps().contains(a) as u8,
                    c[0],
                    c[1],
                    self.projected.parameter(a).get(),
                ];
                self.finish_job(&req, R::Ok, &r);
            }
            Command::ReadActual => {
                let Some(a) = addr else {
                    return self.finish_job(&req, R::InvalidArgument, &[]);
                };
                let c = codes_bytes(self.detected[a.index() as usize]);
                let r = [
                    self.lds.contains(a) as u8,
                    c[0],
                    c[1],
                    self.pi[a.index() as usize].get(),
                ];
                self.finish_job(&req, R::Ok, &r);
            }
            Command::WriteProjected => {
                if self.mode != Mode::Configuration {
                    return self.finish_job(&req, R::NotAllowed, &[]);
                }
                let Some(a) = addr.filter(|a| a.number() != 0) else {
                    return self.finish_job(&req, R::InvalidArgument, &[]);
                };
                let mut p = self.projected.clone();
                p.remove(a);
                if b[1] != 0 {
                    let s = crate::config::ProjectedSlave {
                        addr: a,
                        codes: SlaveCodes::new(b[2] >> 4, b[2], b[3] >> 4, b[3]),
                        parameter: Nibble::from_low_bits(b[4]),
                    };
                    if p.insert(s).is_err() {
                        return self.finish_job(&req, R::InvalidArgument, &[]);
                    }
                }
                self.projected = p;
                self.finish_job(&req, R::Ok, &[]);
            }
            Command::StoreActual => {
                if self.mode != Mode::Configuration {
                    return self.finish_job(&req, R::NotAllowed, &[]);
                }
                let mut p = ProjectedConfig::default();
                for a in self.lds.without_zero().iter() {
                    let s = crate::config::ProjectedSlave {
                        addr: a,
                        codes: self.detected[a.index() as usize],
                        parameter: self.pi[a.index() as usize],
                    };
                    if p.insert(s).is_err() {
                        return self.finish_job(&req, R::InvalidArgument, &[]);
                    }
                }
                self.projected = p;
                self.finish_job(&req, R::Ok, &[]);
            }
            Command::SetMode => {
                let mode = match b[0] {
                    0 => Mode::Protected,
                    1 => Mode::Configuration,
                    _ => return self.finish_job(&req, R::InvalidArgument, &[]),
                };
                self.mode = mode;
                if mode == Mode::Protected {
                    // Slaves that are active but not projected (or wrong) leave LAS.
                    for a in self.las.iter() {
                        if !self.eligible(a) {
                            self.deactivate(a);
                        }
                    }
                }
                self.finish_job(&req, R::Ok, &[]);
            }
            Command::ReadList => {
                let list = match b[0] {
                    0 => self.lds,
                    1 => self.las,
                    2 => self.projected.lps(),
                    3 => self.take_lcs(),
                    4 => self.lpf,
                    _ => return self.finish_job(&req, R::InvalidArgument, &[]),
                };
                self.finish_job(&req, R::Ok, &list.to_bytes());
            }
            Command::ReadFlags => {
                let f = self.compute_flags().bits();
                self.finish_job(&req, R::Ok, &f.to_be_bytes());
            }
        }
    }

    // ----- scheduling -----------------------------------------------------------------

    fn next_tx(&mut self, now: SimTime) -> Option<Tx> {
        for _ in 0..4 {
            match self.phase {
                Phase::Offline => {
                    if !self.power_ok || self.host.offline || now < self.wake_at {
                        return None;
                    }
                    self.start_detection();
                }
                Phase::Detection => {
                    if self.host.offline {
                        self.go_offline();
                        return None;
                    }
                    if let Some(tx) = self.detect_next() {
                        return Some(tx);
                    }
                }
                Phase::Activation => {
                    if self.host.offline {
                        self.go_offline();
                        return None;
                    }
                    if let Some(tx) = self.activation_next() {
                        return Some(tx);
                    }
                }
                Phase::NormalOperation => {
                    if self.host.offline {
                        return self.offline_next();
                    }
                    return self.normal_next(now);
                }
            }
        }
        None
    }

    fn start_detection(&mut self) {
        self.phase = Phase::Detection;
        self.det_cursor = 0;
        self.det_probe = None;
        self.lds = SlaveList::EMPTY;
        self.las = SlaveList::EMPTY;
        self.lpf = SlaveList::EMPTY;
        self.update_flags();
    }

    fn occupies_whole(&self, n: u8) -> bool {
        match SlaveAddr::a(n) {
            Some(a) => self.lds.contains(a) && !self.detected[a.index() as usize].is_ab(),
            None => false,
        }
    }

    fn detect_next(&mut self) -> Option<Tx> {
        for _ in 0..=65 {
            if let Some(p) = self.det_probe {
                return Some(Tx::Detect(p.a, p.step));
            }
            if self.det_cursor >= 64 {
                if self.lds.is_empty() {
                    self.det_cursor = 0;
                    continue;
                }
                self.act_todo = self.lds.iter().filter(|&a| self.eligible(a)).collect();
                self.act_param_done = false;
                self.phase = Phase::Activation;
                return None;
            }
            let i = self.det_cursor;
            self.det_cursor += 1;
            let Some(a) = SlaveAddr::from_index(i) else {
                continue;
            };
            if a.select == Select::B && self.occupies_whole(a.number()) {
                continue;
            }
            self.det_probe = Some(Probe {
                a,
                step: Read::Io,
                codes: UNKNOWN_CODES,
            });
        }
        None
    }

    fn activation_next(&mut self) -> Option<Tx> {
        let Some(a) = self.act_todo.iter().next() else {
            self.phase = Phase::NormalOperation;
            self.stage = Stage::Data;
            self.cursor = 1;
            self.cycle_open = false;
            self.cycle_start = None;
            return None;
        };
        Some(if self.act_param_done {
            Tx::ActivateDexg(a)
        } else {
            Tx::ActivateParam(a)
        })
    }

    fn slot(&self, n: u8) -> Option<SlaveAddr> {
        let a = SlaveAddr::a(n)?;
        let b = SlaveAddr::b(n);
        let has_b = b.is_some_and(|b| self.las.contains(b));
        match (self.las.contains(a), has_b) {
            (true, true) if self.odd_cycle => b,
            (true, _) => Some(a),
            (false, true) => b,
            (false, false) => None,
        }
    }

    fn normal_next(&mut self, now: SimTime) -> Option<Tx> {
        for _ in 0..4 {
            match self.stage {
                Stage::Data => {
                    if !self.cycle_open {
                        self.cycle_open = true;
                        if let Some(s) = self.cycle_start {
                            self.stats.record_cycle(now.saturating_duration_since(s));
                        }
                        self.cycle_start = Some(now);
                    }
                    while self.cursor <= 31 {
                        let n = self.cursor;
                        self.cursor += 1;
                        if let Some(a) = self.slot(n) {
                            return Some(Tx::Exchange(a));
                        }
                    }
                    self.stage = Stage::Management;
                }
                Stage::Management => {
                    self.stage = Stage::Inclusion;
                    if let Some(tx) = self.management_next() {
                        return Some(tx);
                    }
                }
                Stage::Inclusion => {
                    self.stage = Stage::Data;
                    self.cursor = 1;
                    self.cycle_open = false;
                    self.odd_cycle = !self.odd_cycle;
                    if let Some(tx) = self.inclusion_next() {
                        return Some(tx);
                    }
                }
            }
        }
        None
    }

    fn management_next(&mut self) -> Option<Tx> {
        if let Some((_, step)) = self.job {
            return Some(Tx::Job(step));
        }
        if self.las.is_empty() {
            return None;
        }
        for _ in 0..64 {
            let i = self.status_cursor;
            self.status_cursor = (self.status_cursor + 1) % 64;
            if let Some(a) = SlaveAddr::from_index(i) {
                if self.las.contains(a) {
                    return Some(Tx::Status(a));
                }
            }
        }
        None
    }

    fn is_inclusion_candidate(&self, a: SlaveAddr) -> bool {
        if self.las.contains(a) {
            return false;
        }
        match (a.number(), a.select) {
            (0, _) => (1..=31u8).any(|n| {
                !self.occupies_whole(n) && SlaveAddr::a(n).is_some_and(|x| !self.las.contains(x))
            }),
            (n, Select::B) => !self.occupies_whole(n),
            _ => true,
        }
    }

    fn inclusion_next(&mut self) -> Option<Tx> {
        if let (Some(p), Some(step)) = (self.incl, self.incl_step) {
            return Some(Tx::Include(p.a, step));
        }
        if let Some(a) = self.incl_priority.take() {
            return Some(self.begin_inclusion(a));
        }
        for _ in 0..64 {
            let i = self.incl_cursor;
            self.incl_cursor = (self.incl_cursor + 1) % 64;
            if let Some(a) = SlaveAddr::from_index(i) {
                if self.is_inclusion_candidate(a) {
                    return Some(self.begin_inclusion(a));
                }
            }
        }
        None
    }

    fn begin_inclusion(&mut self, a: SlaveAddr) -> Tx {
        self.incl = Some(Probe {
            a,
            step: Read::Io,
            codes: UNKNOWN_CODES,
        });
        self.incl_step = Some(InclStep::Read(Read::Io));
        Tx::Include(a, InclStep::Read(Read::Io))
    }

    fn offline_next(&mut self) -> Option<Tx> {
        while self.offline_cursor < 64 {
            let i = self.offline_cursor;
            self.offline_cursor += 1;
            if let Some(a) = SlaveAddr::from_index(i) {
                if self.las.contains(a) {
                    return Some(Tx::OfflineDefault(a));
                }
            }
        }
        self.go_offline();
        None
    }

    fn go_offline(&mut self) {
        self.phase = Phase::Offline;
        self.in_flight = None;
        self.repeat_pending = false;
        self.lds = SlaveList::EMPTY;
        self.las = SlaveList::EMPTY;
        self.lpf = SlaveList::EMPTY;
        for w in 0..16 {
            let keep = if w == 0 { 0xF000 } else { 0 };
            let v = self.image.input.word(w) & keep;
            self.image.input.set_word(w, v);
        }
        for e in self.analog.iter_mut() {
            *e = None;
        }
        self.det_probe = None;
        self.incl = None;
        self.incl_step = None;
        self.incl_priority = None;
        self.stage = Stage::Data;
        self.cursor = 1;
        self.cycle_open = false;
        self.cycle_start = None;
        self.offline_cursor = 0;
        if let Some((req, _)) = self.job.take() {
            self.mailbox.abort(&mut self.image.input, &req);
        }
        self.update_flags();
    }

    // ----- requests -------------------------------------------------------------------

    fn data_exchange(&self, a: SlaveAddr, out: Nibble) -> Option<Request> {
        if self.detected[a.index() as usize].is_ab() {
            Request::data_exchange_ab(a.address, a.select, Nibble::from_low_bits(out.get() & 7))
                .ok()
        } else {
            Request::data_exchange(a.address, out).ok()
        }
    }

    fn write_parameter(&self, a: SlaveAddr, p: Nibble) -> Option<Request> {
        if self.detected[a.index() as usize].is_ab() {
            Request::write_parameter_ab(a.address, a.select, Nibble::from_low_bits(p.get() & 7))
                .ok()
        } else {
            Request::write_parameter(a.address, p).ok()
        }
    }

    fn is_ab_call(&self, tx: Tx) -> bool {
        match tx {
            Tx::ActivateParam(a)
            | Tx::ActivateDexg(a)
            | Tx::Exchange(a)
            | Tx::OfflineDefault(a)
            | Tx::Include(a, InclStep::Param | InclStep::Dexg)
            | Tx::Job(JobStep::Param(a, _)) => self.detected[a.index() as usize].is_ab(),
            _ => false,
        }
    }

    fn activation_parameter(&self, a: SlaveAddr) -> Nibble {
        if self.projected.lps().contains(a) {
            self.projected.parameter(a)
        } else {
            self.pi[a.index() as usize]
        }
    }

    fn read(a: SlaveAddr, r: Read) -> Option<Request> {
        let (ad, s) = (a.address, a.select);
        match r {
            Read::Io => Request::read_io_configuration(ad, s),
            Read::Id => Request::read_id_code(ad, s),
            Read::Id1 => Request::read_id1(ad, s),
            Read::Id2 => Request::read_id2(ad, s),
        }
        .ok()
    }

    fn request_for(&self, tx: Tx) -> Option<Request> {
        match tx {
            Tx::Detect(a, r) | Tx::Include(a, InclStep::Read(r)) => Self::read(a, r),
            Tx::ActivateParam(a) | Tx::Include(a, InclStep::Param) => {
                self.write_parameter(a, self.activation_parameter(a))
            }
            Tx::ActivateDexg(a) | Tx::Include(a, InclStep::Dexg) | Tx::OfflineDefault(a) => {
                self.data_exchange(a, Nibble::ALL)
            }
            Tx::Exchange(a) => {
                let out = if !self.host.data_exchange_active {
                    Nibble::ALL
                } else if self.analog[a.index() as usize].is_some() {
                    self.analog_out[a.index() as usize]
                } else {
                    self.image.output.nibble(a)
                };
                self.data_exchange(a, out)
            }
            Tx::Status(a) | Tx::Job(JobStep::Status(a)) => {
                Request::read_status(a.address, a.select).ok()
            }
            Tx::Include(_, InclStep::AutoId1(_, id1)) => Some(Request::write_extended_id1(id1)),
            Tx::Include(_, InclStep::AutoAssign(t)) | Tx::Job(JobStep::Assign(t)) => {
                Some(Request::address_assignment(t.address))
            }
            Tx::Job(JobStep::Param(a, p)) => self.write_parameter(a, p),
            Tx::Job(JobStep::Delete(from, _)) => {
                Request::delete_address(from.address, from.select).ok()
            }
        }
    }

    // ----- outcomes -------------------------------------------------------------------

    fn apply(&mut self, tx: Tx, resp: Option<Nibble>) {
        match tx {
            Tx::Detect(a, r) => self.detect_result(a, r, resp),
            Tx::ActivateParam(a) => match resp {
                Some(p) => {
                    self.pi[a.index() as usize] = p;
                    self.act_param_done = true;
                }
                None => self.act_todo.set(a, false),
            },
            Tx::ActivateDexg(a) => {
                self.act_todo.set(a, false);
                self.act_param_done = false;
                if let Some(d) = resp {
                    self.activate(a, d);
                }
            }
            Tx::Exchange(a) => self.exchange_result(a, resp),
            Tx::Status(a) => {
                if let Some(s) = resp {
                    self.lpf.set(a, s.bit(1));
                }
            }
            Tx::Include(a, step) => self.include_result(a, step, resp),
            Tx::Job(step) => self.job_result(step, resp),
            Tx::OfflineDefault(_) => {}
        }
    }

    fn detect_result(&mut self, a: SlaveAddr, r: Read, resp: Option<Nibble>) {
        let Some(mut p) = self.det_probe.filter(|p| p.a == a) else {
            return;
        };
        let Some(v) = resp else {
            self.det_probe = None;
            return;
        };
        match r {
            Read::Io => {
                p.codes.io = v;
                p.step = Read::Id;
            }
            Read::Id => {
                p.codes.id = v;
                p.step = Read::Id1;
            }
            Read::Id1 => {
                p.codes.id1 = v;
                p.step = Read::Id2;
            }
            Read::Id2 => {
                p.codes.id2 = v;
                self.lds.set(a, true);
                self.detected[a.index() as usize] = p.codes;
                self.det_probe = None;
                return;
            }
        }
        self.det_probe = Some(p);
    }

    fn activate(&mut self, a: SlaveAddr, inputs: Nibble) {
        let i = a.index() as usize;
        self.las.set(a, true);
        self.fails[i] = 0;
        self.image.input.set_nibble(a, inputs);
        let codes = self.detected[i];
        self.analog[i] = codes.is_analog_7_3().then(|| {
            if codes.analog_is_input() {
                AnalogEngine::Input(S73InputMaster::new())
            } else {
                AnalogEngine::Output(S73OutputMaster::new(codes.analog_channels()))
            }
        });
        self.analog_out[i] = Nibble::ZERO;
        if self.analog[i].is_some() {
            self.step_analog(a, inputs);
        }
    }

    fn deactivate(&mut self, a: SlaveAddr) {
        let i = a.index() as usize;
        self.las.set(a, false);
        self.lpf.set(a, false);
        self.image.input.set_nibble(a, Nibble::ZERO);
        self.analog[i] = None;
        self.fails[i] = 0;
    }

    fn step_analog(&mut self, a: SlaveAddr, input: Nibble) {
        let i = a.index() as usize;
        let n = a.number();
        match &mut self.analog[i] {
            Some(AnalogEngine::Output(e)) => {
                for ch in 1..=4 {
                    e.set_value(ch, self.image.output.analog(n, ch));
                }
                self.analog_out[i] = e.step(input);
            }
            Some(AnalogEngine::Input(e)) => {
                let (out, done) = e.step(input);
                self.analog_out[i] = out;
                if let Some((ch, v)) = done {
                    if v.valid {
                        let word = if v.overflow { OVERFLOW_VALUE } else { v.value };
                        self.image.input.set_analog(n, ch, word);
                    }
                }
            }
            None => {}
        }
    }

    fn exchange_result(&mut self, a: SlaveAddr, resp: Option<Nibble>) {
        if !self.las.contains(a) {
            return;
        }
        let i = a.index() as usize;
        match resp {
            Some(d) => {
                self.fails[i] = 0;
                self.image.input.set_nibble(a, d);
                if self.analog[i].is_some() {
                    self.step_analog(a, d);
                }
            }
            None => {
                self.fails[i] = self.fails[i].saturating_add(1);
                if self.fails[i] >= self.cfg.max_failed_cycles {
                    self.deactivate(a);
                    self.lds.set(a, false);
                    self.lcs.set(a, true);
                    self.stats.dropouts += 1;
                }
            }
        }
    }

    fn auto_address_target(&self, codes: SlaveCodes) -> Option<(SlaveAddr, Option<Nibble>)> {
        if !self.compute_flags().auto_address_available() {
            return None;
        }
        let missing = SlaveList::from_bits(self.projected.lps().bits() & !self.lds.bits());
        let target = missing.iter().next()?;
        let want = self.projected.codes(target);
        if !codes.matches(&want) {
            return None;
        }
        let id1 = if want.is_ab() {
            let sel = if target.select == Select::B { 8 } else { 0 };
            Nibble::from_low_bits((codes.id1.get() & 7) | sel)
        } else {
            want.id1
        };
        Some((target, (id1 != codes.id1).then_some(id1)))
    }

    fn include_result(&mut self, a: SlaveAddr, step: InclStep, resp: Option<Nibble>) {
        let Some(mut p) = self.incl.filter(|p| p.a == a) else {
            return;
        };
        let end = |m: &mut Master| {
            m.incl = None;
            m.incl_step = None;
        };
        let Some(v) = resp else {
            if matches!(step, InclStep::Read(_)) && self.lds.contains(a) && !self.las.contains(a) {
                self.lds.set(a, false);
                self.lcs.set(a, true);
            }
            return end(self);
        };
        let next = match step {
            InclStep::Read(Read::Io) => {
                p.codes.io = v;
                InclStep::Read(Read::Id)
            }
            InclStep::Read(Read::Id) => {
                p.codes.id = v;
                InclStep::Read(Read::Id1)
            }
            InclStep::Read(Read::Id1) => {
                p.codes.id1 = v;
                InclStep::Read(Read::Id2)
            }
            InclStep::Read(Read::Id2) => {
                p.codes.id2 = v;
                self.lds.set(a, true);
                self.detected[a.index() as usize] = p.codes;
                if a.number() == 0 {
                    match self.auto_address_target(p.codes) {
                        Some((t, Some(id1))) => InclStep::AutoId1(t, id1),
                        Some((t, None)) => InclStep::AutoAssign(t),
                        None => return end(self),
                    }
                } else if self.eligible(a) {
                    InclStep::Param
                } else {
                    return end(self);
                }
            }
            InclStep::Param => {
                self.pi[a.index() as usize] = v;
                InclStep::Dexg
            }
            InclStep::Dexg => {
                self.activate(a, v);
                return end(self);
            }
            InclStep::AutoId1(t, _) => InclStep::AutoAssign(t),
            InclStep::AutoAssign(t) => {
                if v == ACK_0110 {
                    self.lds.set(ZERO_A, false);
                    self.incl_priority = Some(t);
                }
                return end(self);
            }
        };
        self.incl = Some(p);
        self.incl_step = Some(next);
    }

    fn job_result(&mut self, step: JobStep, resp: Option<Nibble>) {
        let Some((req, _)) = self.job else {
            return;
        };
        let Some(v) = resp else {
            return self.finish_job(&req, JobResult::NoResponse, &[]);
        };
        match step {
            JobStep::Param(a, _) => {
                self.pi[a.index() as usize] = v;
                self.finish_job(&req, JobResult::Ok, &[v.get()]);
            }
            JobStep::Status(a) => {
                if self.las.contains(a) {
                    self.lpf.set(a, v.bit(1));
                }
                self.finish_job(&req, JobResult::Ok, &[v.get()]);
            }
            JobStep::Delete(from, to) => {
                self.deactivate(from);
                self.lds.set(from, false);
                if to.number() == 0 {
                    self.finish_job(&req, JobResult::Ok, &[]);
                } else {
                    self.job = Some((req, JobStep::Assign(to)));
                }
            }
            JobStep::Assign(to) => {
                if v == ACK_0110 {
                    self.incl_priority = Some(to);
                    self.finish_job(&req, JobResult::Ok, &[]);
                } else {
                    self.finish_job(&req, JobResult::NoResponse, &[]);
                }
            }
        }
    }
}

const ZERO_A: SlaveAddr = SlaveAddr {
    address: asi_phy::Address::ZERO,
    select: Select::A,
};
