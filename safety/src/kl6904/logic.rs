//! The KL6904 runtime: one safety scan at a time on injected time (§3 of the KL6904 manual;
//! docs/safety-logic.md §8.1, §8.3).
//!
//! A scan:
//! 1. reads the inputs: the standard inputs as last set, and one telegram exchange per
//!    TwinSAFE connection (whose TwinSAFE-Out data are those written by the previous scan);
//! 2. updates each group: error latching from its modules, connections and local outputs,
//!    RUN, and the ERR_ACK 0→1→0 acknowledgement;
//! 3. evaluates the function modules in their configured order; a module reads the values of
//!    modules before it from this scan and of modules after it from the previous scan;
//! 4. trips a group at once if one of its modules found an error in this scan (its outputs are
//!    0 in this scan's output image; a module of *another* group that already read one of them
//!    in this scan sees the 0 from the next scan on);
//! 5. writes every output: module safety outputs, local outputs and TwinSAFE-Out channels of a
//!    group that is not in RUN are 0 (a group error drives all its outputs to the safe state, §3.1
//!    of the KL6904 manual); modules' Error outputs and the group outputs FB_ERR/COM_ERR/OUT_ERR
//!    are diagnostics and are not switched off.
//!
//! An internal logic fault (time running backwards, or one injected) stops the whole logic: every
//! output 0 until the logic is created again (§3 of the KL6904 manual: "an error in the TwinSAFE
//! logic shuts down the whole logic").

use asi_phy::SimTime;
use core::fmt;

use super::connection::{ChannelFault, ConnDiag, ConnEvent, Connection};
use super::group::{Group, GroupErrors, GroupState};
use super::modules::{and_bits, or_bits, Core, Estop, FbEvent, FbState, Mon, OpMode};
use super::project::{ModuleKind, Project};
use super::signal::{ChannelRef, Contact, GroupOutput, SignalRef};
use super::verify::{
    self, input_specs, output_specs, Compiled, CompiledGroup, CompiledLocalOutput, CompiledModule,
    ModuleConfig, Slot, VerifyError,
};

/// A handle to a standard input of a logic (see [`TwinSafeLogic::standard_input`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StandardInput(Slot);

/// A handle to a connection of a logic.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ConnectionId(usize);

/// A handle to a module of a logic.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ModuleId(usize);

/// A handle to a group of a logic.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct GroupId(usize);

/// A handle to a standard output of a logic.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StandardOutput(usize);

/// The state of a module, for diagnostics.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ModuleStatus {
    /// The module type.
    pub kind: ModuleKind,
    /// Its state (AND, OR, DECOUPLE: RUN or STOP with their group).
    pub state: FbState,
    /// Its diagnostic bits (§3.3 of the KL6904 manual).
    pub diag: u8,
}

/// The state of a group, for diagnostics.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct GroupStatus {
    /// The group's state.
    pub state: GroupState,
    /// Its outputs FB_ERR, COM_ERR, OUT_ERR.
    pub errors: GroupErrors,
}

/// What happened in a scan, for the log (docs/safety-logic.md §1.4 diagnostics in words).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LogicEvent {
    /// The scan's time.
    pub at: SimTime,
    /// What happened.
    pub kind: LogicEventKind,
}

/// The kinds of [`LogicEvent`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LogicEventKind {
    /// A module did something.
    Module {
        /// The module, as [`TwinSafeLogic::module`] finds it by name.
        id: ModuleId,
        /// The module's name.
        module: String,
        /// Its type.
        kind: ModuleKind,
        /// What it did.
        event: FbEvent,
    },
    /// A connection reported something.
    Connection {
        /// 1-based number in the project.
        number: usize,
        /// Its name.
        connection: String,
        /// What it reported.
        event: ConnEvent,
    },
    /// A group entered ERROR: all its outputs are 0.
    GroupTripped {
        /// The group's name.
        group: String,
        /// The latched error classes.
        errors: GroupErrors,
    },
    /// A group's ERR_ACK acknowledged its errors.
    GroupAcknowledged {
        /// The group's name.
        group: String,
    },
    /// A group started (RUN) or stopped (STOP) by its RUN input.
    GroupRunning {
        /// The group's name.
        group: String,
        /// `true` = now running.
        running: bool,
    },
    /// A local output reported an error (OUT_ERR).
    LocalOutputFault {
        /// Terminal number 1..4.
        index: u8,
        /// Its name.
        name: String,
    },
    /// The whole logic stopped.
    LogicFault {
        /// Why.
        cause: String,
    },
}

impl LogicEvent {
    /// `true` for events that take power away or report a fault: a safe-state demand, a
    /// delayed output going off, a module, connection or local-output error, a group trip, a
    /// logic fault.
    pub fn is_trip(&self) -> bool {
        match &self.kind {
            LogicEventKind::Module { event, .. } => matches!(
                event,
                FbEvent::SafeStateDemanded { .. } | FbEvent::DelayedOutputOff | FbEvent::Error(_)
            ),
            LogicEventKind::Connection { event, .. } => matches!(event, ConnEvent::Error { .. }),
            LogicEventKind::GroupTripped { .. }
            | LogicEventKind::LocalOutputFault { .. }
            | LogicEventKind::LogicFault { .. } => true,
            LogicEventKind::GroupAcknowledged { .. } | LogicEventKind::GroupRunning { .. } => false,
        }
    }
}

/// The names of the inputs whose bits are set in `mask`, for a module kind.
fn input_names(kind: ModuleKind, mask: u8) -> String {
    let specs = input_specs(kind);
    let names: Vec<&str> = (0..8)
        .filter(|b| mask & 1 << b != 0)
        .filter_map(|b| specs.get(b).map(|s| s.name.as_str()))
        .collect();
    names.join(", ")
}

impl fmt::Display for LogicEventKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LogicEventKind::Module {
                module,
                kind,
                event,
                ..
            } => {
                let who = format!("{kind} `{module}`");
                match event {
                    FbEvent::SafeStateDemanded { inputs } if *kind == ModuleKind::OpMode => {
                        write!(
                            f,
                            "{who}: mode left, outputs safe (inputs set: {})",
                            input_names(*kind, *inputs)
                        )
                    }
                    FbEvent::SafeStateDemanded { inputs } => write!(
                        f,
                        "{who}: safe state demanded by {}",
                        input_names(*kind, *inputs)
                    ),
                    FbEvent::DelayedOutputOff => {
                        write!(f, "{who}: delayed output off after the delay time")
                    }
                    FbEvent::Restarted => write!(f, "{who}: safe state left (restart)"),
                    FbEvent::Error(e) => write!(f, "FB_ERR: {who}: {e}"),
                    FbEvent::Acknowledged => write!(f, "{who}: error acknowledged"),
                    FbEvent::Stopped => write!(f, "{who}: stopped with its group"),
                }
            }
            LogicEventKind::Connection {
                number,
                connection,
                event,
            } => match event {
                ConnEvent::Error { bit, detail } => {
                    let what = bit.names().next().unwrap_or("error");
                    write!(
                        f,
                        "COM_ERR: {what} on connection {number} `{connection}`: {detail}"
                    )
                }
                ConnEvent::Running => write!(f, "connection {number} `{connection}` running"),
                ConnEvent::Acknowledged => {
                    write!(f, "connection {number} `{connection}`: error acknowledged")
                }
            },
            LogicEventKind::GroupTripped { group, errors } => {
                write!(f, "group `{group}` tripped ({errors}): all its outputs off")
            }
            LogicEventKind::GroupAcknowledged { group } => {
                write!(f, "group `{group}`: ERR_ACK accepted, errors cleared")
            }
            LogicEventKind::GroupRunning { group, running } => {
                let s = if *running { "RUN" } else { "STOP" };
                write!(f, "group `{group}`: {s}")
            }
            LogicEventKind::LocalOutputFault { index, name } => {
                write!(f, "OUT_ERR: local output {index} `{name}` reports an error")
            }
            LogicEventKind::LogicFault { cause } => {
                write!(f, "logic fault: {cause}; the whole logic is stopped")
            }
        }
    }
}

impl fmt::Display for LogicEvent {
    /// `12.345000000 s: <what>`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.at, self.kind)
    }
}

/// A module as the scan runs it: its state, and what the scan needs of its compiled form.
#[derive(Clone, Debug)]
#[cfg_attr(test, derive(PartialEq))]
struct ModuleRt {
    kind: ModuleKind,
    /// Its group.
    group: usize,
    /// (position, slot) of each linked input: bit `position` of the module's input mask
    /// (positions in the order of [`input_specs`]) is the value of `slot`; an input not
    /// linked reads 0.
    links: Box<[(u32, Slot)]>,
    /// The slot of each output in the order of [`output_specs`]: bit `k` of the module's
    /// output mask goes to the `k`-th.
    outputs: Box<[Slot]>,
    /// Bit `k` set if output `k` is a safety output (0 unless the group runs).
    safety: u16,
    fb: Fb,
}

/// A module's function and state.
#[derive(Clone, Debug)]
#[cfg_attr(test, derive(PartialEq))]
enum Fb {
    /// AND: the input positions linked, and those of them with a make contact.
    And {
        linked: u16,
        make: u16,
    },
    /// OR: the same.
    Or {
        linked: u16,
        make: u16,
    },
    OpMode(OpMode),
    Estop(Estop),
    Mon(Mon),
    Decouple,
}

impl ModuleRt {
    fn new(cm: &CompiledModule) -> Self {
        let links = cm.inputs.iter().enumerate();
        let links = links.filter_map(|(k, input)| input.map(|(slot, _)| (k as u32, slot)));
        // Bit k set for each input position k that is linked, with `contact` if given.
        let mask = |contact: Option<Contact>| {
            let inputs = cm.inputs.iter().enumerate();
            inputs.fold(0u16, |m, (k, input)| match input {
                Some((_, c)) if contact.is_none_or(|want| *c == want) => m | 1 << k,
                _ => m,
            })
        };
        let fb = match &cm.config {
            ModuleConfig::And => Fb::And {
                linked: mask(None),
                make: mask(Some(Contact::Make)),
            },
            ModuleConfig::Or => Fb::Or {
                linked: mask(None),
                make: mask(Some(Contact::Make)),
            },
            ModuleConfig::OpMode(c) => Fb::OpMode(OpMode::new(c.clone())),
            ModuleConfig::Estop(c) => Fb::Estop(Estop::new(c.clone())),
            ModuleConfig::Mon(c) => Fb::Mon(Mon::new(c.clone())),
            ModuleConfig::Decouple => Fb::Decouple,
        };
        ModuleRt {
            kind: cm.kind,
            group: cm.group,
            links: links.collect(),
            outputs: cm.outputs.iter().copied().collect(),
            safety: (cm.safety_outputs.iter().enumerate())
                .fold(0, |m, (k, &safety)| m | u16::from(safety) << k),
            fb,
        }
    }

    /// One scan at `now`: reads the inputs from `image`, runs the function and writes the
    /// outputs (safety outputs 0 unless `run`). Returns whether the module has events to report
    /// ([`ModuleRt::events`]), and whether it is quiet: another scan with the same inputs and
    /// `run` would change nothing if it came before the time returned last, if any (the
    /// stateless modules always are; the others as [`Estop::quiet`] says; the time is the end
    /// of a running delay, [`Estop::delay_ends`]).
    fn scan(
        &mut self,
        now: SimTime,
        run: bool,
        image: &mut [bool],
    ) -> (bool, bool, Option<SimTime>) {
        let inputs = self
            .links
            .iter()
            .fold(0u16, |bits, &(k, slot)| bits | u16::from(image[slot]) << k);
        let mut until = None;
        let (outputs, events, quiet) = match &mut self.fb {
            Fb::And { linked, make } => (u16::from(and_bits(inputs, *linked, *make)), false, true),
            Fb::Or { linked, make } => (u16::from(or_bits(inputs, *linked, *make)), false, true),
            // DECOUPLE: DecOut n = DecIn n (`decouple`).
            Fb::Decouple => (inputs, false, true),
            Fb::OpMode(fb) => {
                let before = fb.state();
                let o = fb.scan_bits(now, run, inputs);
                let outs = o.op_out.iter().enumerate();
                let outs = outs.fold(0, |m, (k, &v)| m | u16::from(v) << k);
                let events = !fb.events().is_empty();
                (outs | u16::from(o.error) << 8, events, fb.quiet(before))
            }
            Fb::Estop(fb) => {
                let before = fb.state();
                let o = fb.scan_bits(now, run, inputs);
                let outs = u16::from(o.estop_out) | u16::from(o.estop_del_out) << 1;
                let events = !fb.events().is_empty();
                until = fb.delay_ends();
                (outs | u16::from(o.error) << 2, events, fb.quiet(before))
            }
            Fb::Mon(fb) => {
                let before = fb.state();
                let o = fb.scan_bits(now, run, inputs);
                let outs = u16::from(o.mon_out) | u16::from(o.mon_del_out) << 1;
                let events = !fb.events().is_empty();
                until = fb.delay_ends();
                (outs | u16::from(o.error) << 2, events, fb.quiet(before))
            }
        };
        let outputs = if run { outputs } else { outputs & !self.safety };
        for (k, &slot) in self.outputs.iter().enumerate() {
            image[slot] = outputs & 1 << k != 0;
        }
        (events, quiet, until)
    }

    /// The state machine of a stateful module; AND, OR and DECOUPLE have none.
    fn core(&self) -> Option<&Core> {
        match &self.fb {
            Fb::OpMode(m) => Some(m.core()),
            Fb::Estop(m) => Some(m.core()),
            Fb::Mon(m) => Some(m.core()),
            Fb::And { .. } | Fb::Or { .. } | Fb::Decouple => None,
        }
    }

    fn state(&self, running: bool) -> FbState {
        let stateless = if running { FbState::Run } else { FbState::Stop };
        self.core().map_or(stateless, |c| c.state)
    }

    fn diag(&self) -> u8 {
        self.core().map_or(0, |c| c.diag)
    }

    fn events(&self) -> &[FbEvent] {
        self.core().map_or(&[], |c| &c.events)
    }

    fn has_error(&self) -> bool {
        self.core().is_some_and(|c| c.state == FbState::Error)
    }

    fn error_cause_active(&self) -> bool {
        self.core().is_some_and(Core::error_cause_active)
    }

    fn acknowledge(&mut self) {
        let core = match &mut self.fb {
            Fb::OpMode(m) => m.core_mut(),
            Fb::Estop(m) => m.core_mut(),
            Fb::Mon(m) => m.core_mut(),
            Fb::And { .. } | Fb::Or { .. } | Fb::Decouple => return,
        };
        core.acknowledge();
    }
}

/// A local output's error state (OUT_ERR).
#[derive(Clone, Copy, Debug, Default)]
#[cfg_attr(test, derive(PartialEq))]
struct LocalFault {
    present: bool,
    latched: bool,
}

/// A running KL6904 with its project, groups, connections (with their partner terminals and
/// black channels) and function modules.
#[derive(Clone, Debug)]
pub struct TwinSafeLogic {
    c: Compiled,
    image: Vec<bool>,
    groups: Vec<Group>,
    connections: Vec<Connection>,
    modules: Vec<ModuleRt>,
    local_faults: Vec<LocalFault>,
    local_values: Vec<bool>,
    twinsafe_out: Vec<u8>,
    standard_values: Vec<bool>,
    last_now: Option<SimTime>,
    fault: Option<String>,
    pending_fault: Option<String>,
    events: Vec<LogicEvent>,
    /// `true` while the last scan left the logic at rest for its inputs: a scan with the same
    /// inputs (standard inputs, partner inputs, faults) changes nothing but the connections'
    /// sequence numbers and times ([`TwinSafeLogic::quiet_scan`]). Set by a full scan that
    /// finds so; cleared by every change of an input or a fault.
    settled: bool,
    /// While settled: when the first fault scheduled on a connection falls due or a module's
    /// delay ends, whichever comes first (`None`: neither); a scan from then on is taken in
    /// full.
    quiet_until: Option<SimTime>,
    /// The image as a full scan found it, to tell whether the scan changed it (kept here so
    /// that the comparison allocates nothing).
    image_before: Vec<bool>,
}

impl TwinSafeLogic {
    /// Verify `project` and load it. All groups start in STOP and enter RUN in the first scan;
    /// every module starts in its safe state.
    pub fn new(project: &Project) -> Result<Self, Vec<VerifyError>> {
        let c = verify::verify(project)?;
        let connections = c
            .connections
            .iter()
            .map(|k| Connection::new(c.address, k.partner_address, k.watchdog))
            .collect();
        Ok(TwinSafeLogic {
            image: vec![false; c.slots],
            groups: vec![Group::new(); c.groups.len()],
            connections,
            modules: c.modules.iter().map(ModuleRt::new).collect(),
            local_faults: vec![LocalFault::default(); c.local_outputs.len()],
            local_values: vec![false; c.local_outputs.len()],
            twinsafe_out: vec![0; c.connections.len()],
            standard_values: vec![false; c.standard_outputs.len()],
            last_now: None,
            fault: None,
            pending_fault: None,
            events: Vec::new(),
            settled: false,
            quiet_until: None,
            image_before: vec![false; c.slots],
            c,
        })
    }

    /// The logic's name from the project.
    pub fn name(&self) -> &str {
        &self.c.name
    }

    // ---- handles -------------------------------------------------------------------------

    /// The standard input `name` (a PLC variable read by the project), if the project reads it.
    pub fn standard_input(&self, name: &str) -> Option<StandardInput> {
        self.c
            .standard_inputs
            .iter()
            .find(|(n, _)| n == name)
            .map(|&(_, s)| StandardInput(s))
    }

    /// The connection `name`.
    pub fn connection(&self, name: &str) -> Option<ConnectionId> {
        self.c
            .connections
            .iter()
            .position(|k| k.name == name)
            .map(ConnectionId)
    }

    /// The module `name`.
    pub fn module(&self, name: &str) -> Option<ModuleId> {
        self.c
            .modules
            .iter()
            .position(|m| m.name == name)
            .map(ModuleId)
    }

    /// The group `name`.
    pub fn group(&self, name: &str) -> Option<GroupId> {
        self.c
            .groups
            .iter()
            .position(|g| g.name == name)
            .map(GroupId)
    }

    /// The standard output `name`.
    pub fn standard_output(&self, name: &str) -> Option<StandardOutput> {
        self.c
            .standard_outputs
            .iter()
            .position(|(n, _)| n == name)
            .map(StandardOutput)
    }

    // ---- inputs and faults -----------------------------------------------------------------

    /// Set a standard input for the next scan.
    pub fn set_standard_input(&mut self, input: StandardInput, value: bool) {
        if self.image[input.0] != value {
            self.image[input.0] = value;
            self.settled = false;
        }
    }

    /// Set the partner's safe inputs of connection `c` (bit `n-1` = channel `n`); they reach
    /// the logic with the next exchange.
    pub fn set_partner_inputs(&mut self, c: ConnectionId, bits: u8) {
        let conn = &mut self.connections[c.0];
        if conn.partner_inputs() != bits {
            conn.set_partner_inputs(bits);
            self.settled = false;
        }
    }

    /// Schedule a fault on connection `c`'s black channel at `at`.
    pub fn inject(&mut self, c: ConnectionId, at: SimTime, fault: ChannelFault) {
        self.connections[c.0].inject(at, fault);
        self.settled = false;
    }

    /// Make local output `index` (1..4) report an error (e.g. a cross-circuit seen on its
    /// read-back) while `faulty`; it latches OUT_ERR in its group. Unknown indices are ignored.
    pub fn set_local_output_fault(&mut self, index: u8, faulty: bool) {
        if let Some(k) = self.c.local_outputs.iter().position(|o| o.index == index) {
            self.local_faults[k].present = faulty;
            self.settled = false;
        }
    }

    /// Raise an internal logic fault at the next scan: the whole logic stops for good.
    pub fn inject_logic_fault(&mut self, cause: &str) {
        self.pending_fault = Some(cause.to_owned());
        self.settled = false;
    }

    // ---- the scan ----------------------------------------------------------------------------

    /// One safety scan at `now`; returns what happened in it.
    ///
    /// Almost every scan finds the logic at rest with the inputs of the last one: then it is
    /// taken the quiet way ([`TwinSafeLogic::quiet_scan`]), else in full
    /// ([`TwinSafeLogic::full_scan`]). Both leave the same state and report the same.
    pub fn scan(&mut self, now: SimTime) -> &[LogicEvent] {
        if self.quiet_scan(now) {
            return &self.events;
        }
        self.full_scan(now)
    }

    /// The time before which every scan not before the last one is a quiet one
    /// ([`TwinSafeLogic::quiet_scan`]) while no input or fault changes: when the first
    /// scheduled fault falls due or a module's delay ends ([`SimTime::MAX`] if neither will);
    /// `None` if the last scan did not leave the logic settled, or there was none.
    pub(crate) fn quiet_before(&self) -> Option<SimTime> {
        (self.settled && self.last_now.is_some()).then(|| self.quiet_until.unwrap_or(SimTime::MAX))
    }

    /// The scan at `now` if it can change nothing but the connections' sequence numbers and
    /// times, done directly; `true` if so (it then reported nothing), `false` with nothing
    /// touched if a full scan is needed.
    ///
    /// Why this is the full scan's result: the last scan, at a time not after `now`, left the
    /// logic settled ([`TwinSafeLogic::full_scan`] says when), and no input or fault changed
    /// since. The full scan would then see the image it saw last time, every group and module
    /// would do nothing (none has a timer running, none an edge to see), and every connection
    /// would exchange one good telegram with the same data ([`Connection::rests`], which a
    /// quiet exchange keeps true), unless a scheduled fault falls due or a module's delay
    /// ends by `now`: the things time can bring, checked here. The logic's events are empty
    /// already (a settled scan reported nothing).
    pub(crate) fn quiet_scan(&mut self, now: SimTime) -> bool {
        self.quiet_scans(now, now, 1)
    }

    /// `n` (at least one) scans from `first` to `last`, in time order, taken as
    /// [`TwinSafeLogic::quiet_scan`] takes each, all or none: `true` if each is a quiet one
    /// (the first not before the last scan, the last before the logic's quiet ends), else
    /// `false` with nothing touched.
    pub(crate) fn quiet_scans(&mut self, first: SimTime, last: SimTime, n: u32) -> bool {
        let quiet = self.last_now.is_some_and(|l| first >= l)
            && self.quiet_before().is_some_and(|end| last < end);
        if !quiet {
            return false;
        }
        debug_assert!(self.events.is_empty());
        self.last_now = Some(last);
        for (conn, &out) in self.connections.iter_mut().zip(&self.twinsafe_out) {
            debug_assert!(conn.is_quiet(last, out));
            conn.quiet_exchanges(last, n);
        }
        true
    }

    /// One safety scan at `now` with every step taken, whatever the state; returns what
    /// happened in it. At its end it notes whether the logic is settled: it reported nothing,
    /// no group or stateful module changed its state, no module has a discrepancy time
    /// running ([`Estop::quiet`]; a running delay only bounds the settled time), the image is the one the scan started with (so a
    /// module that reads another later in the order sees the same value next time), every
    /// connection's next exchange would be a good one with nothing new
    /// ([`Connection::rests`]), and every group would stay as it is with its members as they
    /// are now ([`Group::stays`]).
    pub(crate) fn full_scan(&mut self, now: SimTime) -> &[LogicEvent] {
        self.events.clear();
        self.settled = false;
        let backwards = self.last_now.is_some_and(|last| now < last);
        if (self.fault.is_some() || self.pending_fault.is_some() || backwards) && self.stopped(now)
        {
            return &self.events;
        }
        self.last_now = Some(now);
        self.image_before.copy_from_slice(&self.image);
        let mut quiet = true;
        let mut delays_end = None;
        // The parts one at a time: a write to the image then cannot change the others.
        let TwinSafeLogic {
            c,
            image,
            groups,
            connections,
            modules,
            local_faults,
            local_values,
            twinsafe_out,
            standard_values,
            events,
            ..
        } = self;
        let image: &mut [bool] = image;

        // 1. Inputs: one exchange per connection.
        for (k, (conn, &out)) in connections.iter_mut().zip(&*twinsafe_out).enumerate() {
            let reported = conn.exchange(now, out);
            // Almost every exchange reports nothing.
            if !reported.is_empty() {
                push_connection_events(events, now, k, &c.connections[k].name, reported);
            }
        }
        for (f, o) in local_faults.iter_mut().zip(&c.local_outputs) {
            if f.present && !f.latched {
                f.latched = true;
                push_local_output_fault(events, now, o);
            }
        }

        // 2. Groups.
        for (g, cg) in c.groups.iter().enumerate() {
            let run = cg.run.is_none_or(|s| image[s]);
            let ack = cg.err_ack.is_some_and(|s| image[s]);
            let (errors, cause) = collect(g, c, modules, connections, local_faults);
            let group = &mut groups[g];
            let before = group.state();
            if group.update(run, ack, errors, cause) {
                let members = (&mut **modules, &mut **connections, &mut **local_faults);
                acknowledge_group(events, now, g, run, c, group, members);
            }
            quiet &= group.state() == before;
            refresh_group(image, events, now, cg, group, before);
        }
        for (cc, conn) in c.connections.iter().zip(&*connections) {
            let bits = conn.inputs();
            for (ch, &slot) in cc.inputs.iter().enumerate() {
                image[slot] = bits & 1 << ch != 0;
            }
        }

        // 3. Modules in their order.
        for (m, rt) in modules.iter_mut().enumerate() {
            let run = groups[rt.group].running();
            // Events are rare: walk them in place rather than copying them every scan.
            let (reported, at_rest, until) = rt.scan(now, run, image);
            if reported {
                push_module_events(events, now, ModuleId(m), &c.modules[m], rt.events());
            }
            quiet &= at_rest;
            delays_end = earliest(delays_end, until);
        }

        // 4. Errors found in this scan trip their group at once.
        for (g, cg) in c.groups.iter().enumerate() {
            let (errors, _) = collect(g, c, modules, connections, local_faults);
            let group = &mut groups[g];
            let before = group.state();
            group.trip(errors);
            quiet &= group.state() == before;
            refresh_group(image, events, now, cg, group, before);
        }

        // 5. Outputs.
        for m in &*modules {
            if !groups[m.group].running() {
                for (k, &slot) in m.outputs.iter().enumerate() {
                    if m.safety & 1 << k != 0 {
                        image[slot] = false;
                    }
                }
            }
        }
        let locals = c.local_outputs.iter().zip(&*local_faults);
        for ((o, f), v) in locals.zip(local_values) {
            *v = image[o.source] && groups[o.group].running() && !f.latched;
        }
        for ((_, slot), v) in c.standard_outputs.iter().zip(standard_values) {
            *v = image[*slot];
        }
        for (cc, out) in c.connections.iter().zip(twinsafe_out) {
            // A connection without TwinSAFE-Out channels (to an input terminal) sends 0.
            *out = if !cc.outputs.is_empty() && groups[cc.group].running() {
                cc.outputs
                    .iter()
                    .filter(|&&(_, slot)| image[slot])
                    .fold(0, |bits, &(ch, _)| bits | 1 << (ch - 1))
            } else {
                0
            };
        }
        if quiet && events.is_empty() && *image == *self.image_before {
            self.settled = self.connections_rest(delays_end) && self.groups_stay();
        }
        &self.events
    }

    /// `true` if every connection's next exchange, with the TwinSAFE-Out data this scan
    /// wrote, would be a quiet one apart from time ([`Connection::rests`]); then notes when
    /// the first scheduled fault falls due or, if earlier, `delays_end`.
    #[cold]
    fn connections_rest(&mut self, delays_end: Option<SimTime>) -> bool {
        let mut conns = self.connections.iter().zip(&self.twinsafe_out);
        if !conns.all(|(conn, &out)| conn.rests(out)) {
            return false;
        }
        let faults = self.connections.iter().map(Connection::next_fault_at);
        self.quiet_until = faults.fold(delays_end, earliest);
        true
    }

    /// `true` if every group, seeing the image and its members as they are now, would stay as
    /// it is in the next scan (for [`TwinSafeLogic::full_scan`]'s settled state).
    #[cold]
    fn groups_stay(&self) -> bool {
        let (c, image) = (&self.c, &self.image);
        (c.groups.iter().zip(&self.groups))
            .enumerate()
            .all(|(g, (cg, group))| {
                let run = cg.run.is_none_or(|s| image[s]);
                let ack = cg.err_ack.is_some_and(|s| image[s]);
                let (errors, cause) =
                    collect(g, c, &self.modules, &self.connections, &self.local_faults);
                group.stays(run, ack, errors, cause)
            })
    }

    /// The start of a scan at `now` when the logic has stopped, or has to stop now on a
    /// pending or detected fault; `true` if it is stopped (then every output is 0).
    #[cold]
    fn stopped(&mut self, now: SimTime) -> bool {
        if self.fault.is_none() {
            let backwards = self.last_now.filter(|&last| now < last);
            let cause = match (self.pending_fault.take(), backwards) {
                (Some(cause), _) => Some(cause),
                (None, Some(last)) => Some(format!(
                    "scan time {now} is before the previous scan at {last}"
                )),
                _ => None,
            };
            if let Some(cause) = cause {
                let kind = LogicEventKind::LogicFault {
                    cause: cause.clone(),
                };
                self.events.push(LogicEvent { at: now, kind });
                self.fault = Some(cause);
            }
        }
        if self.fault.is_some() {
            self.local_values.iter_mut().for_each(|v| *v = false);
            self.standard_values.iter_mut().for_each(|v| *v = false);
            self.twinsafe_out.iter_mut().for_each(|v| *v = 0);
            return true;
        }
        false
    }

    // ---- outputs and diagnostics -------------------------------------------------------------

    /// Local output `index` (1..4) as written by the last scan; `false` if not in the project.
    pub fn local_output(&self, index: u8) -> bool {
        self.local_output_position(index)
            .is_some_and(|k| self.local_output_at(k))
    }

    /// Where local output `index` (1..4) stands among the project's local outputs, for
    /// [`TwinSafeLogic::local_output_at`].
    pub(crate) fn local_output_position(&self, index: u8) -> Option<usize> {
        self.c.local_outputs.iter().position(|o| o.index == index)
    }

    /// The local output at `position` ([`TwinSafeLogic::local_output_position`]) as written by
    /// the last scan.
    pub(crate) fn local_output_at(&self, position: usize) -> bool {
        self.local_values[position]
    }

    /// A standard output as written by the last scan.
    pub fn standard_output_value(&self, o: StandardOutput) -> bool {
        self.standard_values[o.0]
    }

    /// The safe outputs a connection's partner drives (a KL2904's terminals).
    pub fn partner_outputs(&self, c: ConnectionId) -> u8 {
        self.connections[c.0].partner_outputs()
    }

    /// A connection's diag byte.
    pub fn connection_diag(&self, c: ConnectionId) -> ConnDiag {
        self.connections[c.0].diag()
    }

    /// A group's state and error outputs.
    pub fn group_status(&self, g: GroupId) -> GroupStatus {
        GroupStatus {
            state: self.groups[g.0].state(),
            errors: self.groups[g.0].errors(),
        }
    }

    /// A module's state and diagnostic bits.
    pub fn module_status(&self, m: ModuleId) -> ModuleStatus {
        let rt = &self.modules[m.0];
        let running = self.groups[rt.group].running();
        ModuleStatus {
            kind: rt.kind,
            state: rt.state(running),
            diag: rt.diag(),
        }
    }

    /// The cause of the logic fault that stopped the logic, if any.
    pub fn logic_fault(&self) -> Option<&str> {
        self.fault.as_deref()
    }

    /// Any signal of the logic's image as of the last scan (module and group outputs as
    /// written, connection inputs as the modules saw them, standard inputs as set); `None` if
    /// the signal is not part of the project.
    pub fn signal(&self, sig: &SignalRef) -> Option<bool> {
        let slot = match sig {
            SignalRef::StandardIn { name } => self.standard_input(name).map(|s| s.0),
            SignalRef::TwinSafeIn {
                connection,
                channel,
            } => {
                let k = self.connection(connection)?.0;
                let cc = &self.c.connections[k];
                let n = match channel {
                    ChannelRef::Number(n) => usize::from(*n),
                    ChannelRef::Name(name) => cc.channel_names.iter().position(|c| c == name)? + 1,
                };
                cc.inputs.get(n.checked_sub(1)?).copied()
            }
            SignalRef::FbOut { module, output } => {
                let m = self.module(module)?.0;
                let k = output_specs(self.c.modules[m].kind)
                    .iter()
                    .position(|(n, _)| n == output)?;
                Some(self.c.modules[m].outputs[k])
            }
            SignalRef::Group { group, output } => {
                let g = self.group(group)?.0;
                let k = GroupOutput::ALL.iter().position(|o| o == output)?;
                Some(self.c.groups[g].outputs[k])
            }
        }?;
        self.image.get(slot).copied()
    }
}

#[cfg(test)]
impl TwinSafeLogic {
    /// Whether the last scan left the logic settled (see the field).
    pub(crate) fn settled(&self) -> bool {
        self.settled
    }

    /// `true` if the two logics (of the same project) are in the same state: every field that
    /// a scan or a setter changes.
    pub(crate) fn same_state(&self, other: &TwinSafeLogic) -> bool {
        self.image == other.image
            && self.groups == other.groups
            && self.connections == other.connections
            && self.modules == other.modules
            && self.local_faults == other.local_faults
            && self.local_values == other.local_values
            && self.twinsafe_out == other.twinsafe_out
            && self.standard_values == other.standard_values
            && self.last_now == other.last_now
            && self.fault == other.fault
            && self.pending_fault == other.pending_fault
            && self.events == other.events
            && self.settled == other.settled
            && self.image_before == other.image_before
    }
}

/// The earlier of two times, where `None` is no time at all (never).
fn earliest(a: Option<SimTime>, b: Option<SimTime>) -> Option<SimTime> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, None) => a,
        (None, b) => b,
    }
}

/// The error classes latched by group `g`'s members, and whether any cause is present.
#[inline(always)]
fn collect(
    g: usize,
    c: &Compiled,
    modules: &[ModuleRt],
    connections: &[Connection],
    local_faults: &[LocalFault],
) -> (GroupErrors, bool) {
    let mut errors = GroupErrors::default();
    let mut cause = false;
    for m in modules {
        if m.group == g && m.has_error() {
            errors.fb_err = true;
            cause |= m.error_cause_active();
        }
    }
    for (cc, conn) in c.connections.iter().zip(connections) {
        if cc.group == g && conn.has_error() {
            errors.com_err = true;
            cause |= conn.error_cause_active();
        }
    }
    for (o, f) in c.local_outputs.iter().zip(local_faults) {
        if o.group == g && f.latched {
            errors.out_err = true;
            cause |= f.present;
        }
    }
    (errors, cause)
}

/// Group `g`'s ERR_ACK acknowledged its errors: clear every member's (modules, connections,
/// local outputs).
#[cold]
fn acknowledge_group(
    events: &mut Vec<LogicEvent>,
    now: SimTime,
    g: usize,
    run: bool,
    c: &Compiled,
    group: &mut Group,
    (modules, connections, local_faults): (&mut [ModuleRt], &mut [Connection], &mut [LocalFault]),
) {
    for m in modules.iter_mut() {
        if m.group == g {
            m.acknowledge();
        }
    }
    for (k, (cc, conn)) in c.connections.iter().zip(connections).enumerate() {
        if cc.group == g && conn.has_error() {
            conn.acknowledge();
            push_connection_events(events, now, k, &cc.name, &[ConnEvent::Acknowledged]);
        }
    }
    for (o, f) in c.local_outputs.iter().zip(local_faults) {
        if o.group == g {
            f.latched = false;
        }
    }
    group.acknowledged(run);
    let name = c.groups[g].name.clone();
    let kind = LogicEventKind::GroupAcknowledged { group: name };
    events.push(LogicEvent { at: now, kind });
}

/// Refresh a group's output signals after a possible change of its state from `before`, and
/// log the change.
fn refresh_group(
    image: &mut [bool],
    events: &mut Vec<LogicEvent>,
    now: SimTime,
    cg: &CompiledGroup,
    group: &Group,
    before: GroupState,
) {
    let errors = group.errors();
    let [fb, com, out] = cg.outputs;
    image[fb] = errors.fb_err;
    image[com] = errors.com_err;
    image[out] = errors.out_err;
    if group.state() != before {
        log_group_change(events, now, cg, group, before);
    }
}

/// The event of a group's change of state from `before`, if it is one to report.
#[cold]
fn log_group_change(
    events: &mut Vec<LogicEvent>,
    now: SimTime,
    cg: &CompiledGroup,
    group: &Group,
    before: GroupState,
) {
    let (state, errors) = (group.state(), group.errors());
    let name = || cg.name.clone();
    let entered_error =
        state == GroupState::Error && !matches!(before, GroupState::Error | GroupState::Reset);
    let kind = if entered_error {
        LogicEventKind::GroupTripped {
            group: name(),
            errors,
        }
    } else if state != before
        && matches!(state, GroupState::Run | GroupState::Stop)
        && matches!(before, GroupState::Run | GroupState::Stop)
    {
        LogicEventKind::GroupRunning {
            group: name(),
            running: state == GroupState::Run,
        }
    } else {
        return;
    };
    events.push(LogicEvent { at: now, kind });
}

/// Log a connection's events of a scan (rare: almost every exchange reports nothing).
#[cold]
fn push_connection_events(
    out: &mut Vec<LogicEvent>,
    now: SimTime,
    k: usize,
    name: &str,
    events: &[ConnEvent],
) {
    for event in events {
        let kind = LogicEventKind::Connection {
            number: k + 1,
            connection: name.to_owned(),
            event: event.clone(),
        };
        out.push(LogicEvent { at: now, kind });
    }
}

/// Log a module's events of a scan.
#[cold]
fn push_module_events(
    out: &mut Vec<LogicEvent>,
    now: SimTime,
    id: ModuleId,
    cm: &CompiledModule,
    events: &[FbEvent],
) {
    for &event in events {
        let kind = LogicEventKind::Module {
            id,
            module: cm.name.clone(),
            kind: cm.kind,
            event,
        };
        out.push(LogicEvent { at: now, kind });
    }
}

/// Log a local output's error.
#[cold]
fn push_local_output_fault(out: &mut Vec<LogicEvent>, now: SimTime, o: &CompiledLocalOutput) {
    let kind = LogicEventKind::LocalOutputFault {
        index: o.index,
        name: o.name.clone(),
    };
    out.push(LogicEvent { at: now, kind });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kl6904::connection::ChannelFault;
    use asi_phy::SimDuration;

    /// Every kind of module, two groups (one with RUN), connections to an input terminal, a
    /// KL6904 partner and an output terminal with TwinSAFE-Out channels, modules that read
    /// modules later in the order, delays, discrepancy times, EDM, muting and the function
    /// test: for the quiet scan against the full scan on more than the lift's project.
    const PLANT: &str = r#"
[logic]
name = "plant"
address = 1

[[group]]
name = "main"
err_ack = "std:ack"
run = "std:run"

[[group]]
name = "aux"
err_ack = "std:ack2"

[[connection]]
name = "inA"
group = "main"
partner = "KL1904"
partner_address = 2
watchdog = "30ms"

[[connection]]
name = "peer"
group = "aux"
partner = "KL6904"
partner_address = 3
watchdog = "40ms"
outputs = [
    { channel = 1, source = "fb:either.OrOut" },
    { channel = 2, source = "fb:mode.OpOut1" },
    { channel = 3, source = "fb:dec.DecOut1" },
]

[[connection]]
name = "outB"
group = "main"
partner = "KL2904"
partner_address = 4
watchdog = "30ms"
outputs = [{ channel = 1, source = "fb:guard.MonDelOut" }]

[[module]]
kind = "AND"
name = "k"
group = "main"
inputs.AndIn1 = { signal = "std:blocked", contact = "make" }
inputs.AndIn2 = "fb:stop.EStopDelOut"
inputs.AndIn3 = "fb:guard.MonOut"

[[module]]
kind = "ESTOP"
name = "stop"
group = "main"
delay = "40ms"
pair_discrepancy = ["20ms"]
inputs.EStopIn1 = "ts:inA.1"
inputs.EStopIn2 = "ts:inA.2"
inputs.Restart = "std:restart"
inputs.EDM1 = "ts:inA.4"

[[module]]
kind = "MON"
name = "guard"
group = "main"
delay = "30ms"
pair_discrepancy = ["25ms"]
secure_discrepancy = "15ms"
manual_restart = false
function_test = true
inputs.MonIn1 = "ts:inA.3"
inputs.MonIn2 = "fb:dec.DecOut2"
inputs.Secure1 = "fb:dec.DecOut3"
inputs.Secure2 = "fb:dec.DecOut4"
inputs.EDM1 = "std:edm"

[[module]]
kind = "OPMODE"
name = "mode"
group = "aux"
discrepancy = "10ms"
inputs.OpIn1 = "ts:peer.4"
inputs.OpIn2 = "ts:peer.5"
inputs.OpIn3 = "ts:peer.6"
inputs.Restart = "std:restart2"

[[module]]
kind = "OR"
name = "either"
group = "aux"
inputs.OrIn1 = "fb:mode.OpOut1"
inputs.OrIn2 = { signal = "fb:k.AndOut", contact = "make" }

[[module]]
kind = "DECOUPLE"
name = "dec"
group = "aux"
inputs.DecIn1 = "fb:k.AndOut"
inputs.DecIn2 = "ts:peer.1"
inputs.DecIn3 = "ts:peer.2"
inputs.DecIn4 = "ts:peer.3"

[[local_output]]
index = 1
name = "K1"
group = "main"
source = "fb:k.AndOut"

[[local_output]]
index = 2
name = "lamp"
group = "aux"
source = "fb:either.OrOut"

[[standard_output]]
name = "stop_ok"
source = "fb:stop.EStopOut"

[[standard_output]]
name = "com_err"
source = "group:aux.COM_ERR"
"#;

    /// A small seeded generator (xorshift64*).
    struct Rng(u64);

    impl Rng {
        fn below(&mut self, n: u64) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) % n
        }
    }

    /// A stretch of quiet scans taken together is those scans taken one by one: the same
    /// state after, whatever the stretch's length (past the connections' reply history too);
    /// and [`TwinSafeLogic::quiet_before`] is where the quiet way ends, with a channel fault
    /// scheduled: a stretch that reaches it is refused and changes nothing.
    #[test]
    fn quiet_scans_taken_together_are_quiet_scans_one_by_one() {
        let project = Project::from_toml("plant.toml", PLANT).expect("the plant project");
        let mut settled = TwinSafeLogic::new(&project).expect("valid");
        let mut now = SimTime::ZERO;
        while settled.quiet_before().is_none() {
            now += SimDuration::from_millis(1);
            settled.full_scan(now);
            assert!(now < SimTime::from_millis(200), "the logic never settles");
        }
        assert_eq!(settled.quiet_before(), Some(SimTime::MAX));
        let ms = SimDuration::from_millis(1);
        for n in [1u32, 2, 9, 15, 16, 17, 40] {
            let (mut together, mut one_by_one) = (settled.clone(), settled.clone());
            let first = now + ms;
            let mut last = first;
            for k in 0..n {
                if k > 0 {
                    last += ms;
                }
                assert!(one_by_one.quiet_scan(last), "scan {k} of {n}");
            }
            assert!(together.quiet_scans(first, last, n), "{n} scans");
            assert!(together.same_state(&one_by_one), "{n} scans");
        }
        let peer = settled.connection("peer").expect("peer");
        let due = now + SimDuration::from_millis(5);
        settled.inject(peer, due, ChannelFault::CorruptCrc);
        assert_eq!(
            settled.quiet_before(),
            None,
            "a new fault unsettles the logic"
        );
        now += ms;
        assert!(settled.full_scan(now).is_empty());
        assert_eq!(settled.quiet_before(), Some(due));
        let before = settled.clone();
        assert!(!settled.quiet_scans(now + ms, due, 4));
        assert!(
            settled.same_state(&before),
            "a refused stretch changed the logic"
        );
        assert!(settled.quiet_scans(now + ms, due - ms, 3));
        assert!(!settled.quiet_scan(due));
    }

    /// Two copies of the plant side by side over long random runs, one scanned with
    /// [`TwinSafeLogic::scan`] (quiet when it can), one with [`TwinSafeLogic::full_scan`]
    /// (the reference): the same events and the same whole state after every scan. The
    /// inputs change now and then (a standard input toggled, a partner's channel flipped,
    /// held for stretches), with channel faults of every kind, local output faults and
    /// irregular scan times.
    #[test]
    fn a_quiet_scan_is_the_full_scan_on_every_kind_of_module() {
        let project = Project::from_toml("plant.toml", PLANT).expect("the plant project");
        let names = [
            "ack", "ack2", "run", "restart", "restart2", "blocked", "edm",
        ];
        let mut settled = 0u64;
        for seed in 1..=30u64 {
            let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
            let mut fast = TwinSafeLogic::new(&project).expect("valid");
            let inputs: Vec<StandardInput> = names
                .iter()
                .map(|n| fast.standard_input(n).expect(n))
                .collect();
            let conns: Vec<ConnectionId> = ["inA", "peer", "outB"]
                .iter()
                .map(|n| fast.connection(n).expect(n))
                .collect();
            let mut values = [false, false, true, false, false, false, true];
            let mut partner = [0b1111u8, 0b0000_1001, 0];
            // When each held standard input (a button) is let go.
            let mut release: [Option<SimTime>; 7] = [None; 7];
            let mut full = fast.clone();
            let mut now = SimTime::from_millis(rng.below(5));
            for step in 0..3000 {
                for (k, r) in release.iter_mut().enumerate() {
                    if r.is_some_and(|at| at <= now) {
                        values[k] = false;
                        *r = None;
                    }
                }
                match rng.below(400) {
                    // ERR_ACK and restart pulses, the most common act.
                    0..=11 => {
                        let k = [0, 1, 3, 4][rng.below(4) as usize];
                        values[k] = true;
                        release[k] = Some(now + SimDuration::from_millis(1 + rng.below(10)));
                    }
                    12 => values[2] = !values[2] || rng.below(4) == 0,
                    13 | 14 => values[5] = !values[5],
                    15 => values[6] = !values[6],
                    // The E-stop's two channels together, now and then one alone.
                    16..=18 => {
                        let both = 0b11 * u8::from(partner[0] & 0b11 == 0);
                        partner[0] = partner[0] & !0b11 | both;
                    }
                    19 => partner[0] ^= 1 << rng.below(2),
                    // MON's pair, on two connections: together, now and then one alone.
                    20 | 21 => {
                        partner[0] ^= 0b100;
                        partner[1] ^= 1;
                    }
                    22 => partner[0] ^= 0b1000,
                    23 if rng.below(4) == 0 => partner[1] ^= 1,
                    // The KL6904 partner: the Secure pair (together or not), the mode.
                    24 | 25 => partner[1] ^= 0b110,
                    26 if rng.below(4) == 0 => partner[1] ^= 0b010,
                    27..=29 => {
                        let mode = [0b0000_1000, 0b0001_0000, 0b0010_0000, 0, 0b0011_0000];
                        partner[1] = partner[1] & !0b11_1000 | mode[rng.below(5) as usize];
                    }
                    30 if rng.below(8) == 0 => {
                        let c = conns[rng.below(3) as usize];
                        let at = now + SimDuration::from_millis(rng.below(20));
                        let fault = match rng.below(6) {
                            0 | 1 => ChannelFault::Drop {
                                duration: SimDuration::from_millis(rng.below(60)),
                            },
                            2 => ChannelFault::CorruptCrc,
                            3 => ChannelFault::Replay {
                                age: rng.below(5) as u8,
                            },
                            4 => ChannelFault::WrongAddress { sender: 9 },
                            _ => ChannelFault::NullTelegram,
                        };
                        fast.inject(c, at, fault);
                        full.inject(c, at, fault);
                    }
                    31 if rng.below(20) == 0 => {
                        let (index, faulty) = (1 + rng.below(2) as u8, rng.below(3) == 0);
                        fast.set_local_output_fault(index, faulty);
                        full.set_local_output_fault(index, faulty);
                    }
                    _ => {}
                }
                for (k, &input) in inputs.iter().enumerate() {
                    fast.set_standard_input(input, values[k]);
                    full.set_standard_input(input, values[k]);
                }
                for (k, &c) in conns.iter().enumerate() {
                    fast.set_partner_inputs(c, partner[k]);
                    full.set_partner_inputs(c, partner[k]);
                }
                settled += u64::from(fast.settled);
                let a = fast.scan(now).to_vec();
                let b = full.full_scan(now).to_vec();
                assert_eq!(a, b, "seed {seed} step {step} at {now}");
                assert!(fast.same_state(&full), "seed {seed} step {step} at {now}");
                now += match rng.below(100) {
                    0 => SimDuration::ZERO,
                    1 => SimDuration::from_millis(2 + rng.below(50)),
                    2 => SimDuration::from_micros(1 + rng.below(3000)),
                    _ => SimDuration::from_millis(1),
                };
            }
        }
        // The quiet way must be taken often, or the test shows nothing.
        assert!(settled > 20_000, "{settled} settled scans");
    }
}
