//! The KL6904 runtime: one safety scan at a time on injected time (seed 004 §3;
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
//!    group that is not in RUN are 0 (a group error drives all its outputs to the safe state,
//!    seed 004 §3.1); modules' Error outputs and the group outputs FB_ERR/COM_ERR/OUT_ERR are
//!    diagnostics and are not switched off.
//!
//! An internal logic fault (time running backwards, or one injected) stops the whole logic:
//! every output 0 until the logic is created again (seed 004 §3: "an error in the TwinSAFE
//! logic shuts down the whole logic").

use asi_phy::SimTime;
use core::fmt;

use super::connection::{ChannelFault, ConnDiag, ConnEvent, Connection};
use super::group::{Group, GroupErrors, GroupState};
use super::modules::{
    and, decouple, or, Core, Estop, EstopInputs, FbEvent, FbState, Mon, MonInputs, OpMode,
    OpModeInputs,
};
use super::project::{ModuleKind, Project};
use super::signal::{ChannelRef, GroupOutput, SignalRef};
use super::verify::{self, input_specs, output_specs, Compiled, ModuleConfig, Slot, VerifyError};

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
    /// Its diagnostic bits (seed 004 §3.3).
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

/// A module's runtime state.
#[derive(Clone, Debug)]
enum ModuleRt {
    And,
    Or,
    OpMode(OpMode),
    Estop(Estop),
    Mon(Mon),
    Decouple,
}

impl ModuleRt {
    fn new(config: &ModuleConfig) -> Self {
        match config {
            ModuleConfig::And => ModuleRt::And,
            ModuleConfig::Or => ModuleRt::Or,
            ModuleConfig::OpMode(c) => ModuleRt::OpMode(OpMode::new(c.clone())),
            ModuleConfig::Estop(c) => ModuleRt::Estop(Estop::new(c.clone())),
            ModuleConfig::Mon(c) => ModuleRt::Mon(Mon::new(c.clone())),
            ModuleConfig::Decouple => ModuleRt::Decouple,
        }
    }

    /// The state machine of a stateful module; AND, OR and DECOUPLE have none.
    fn core(&self) -> Option<&Core> {
        match self {
            ModuleRt::OpMode(m) => Some(m.core()),
            ModuleRt::Estop(m) => Some(m.core()),
            ModuleRt::Mon(m) => Some(m.core()),
            ModuleRt::And | ModuleRt::Or | ModuleRt::Decouple => None,
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
        let core = match self {
            ModuleRt::OpMode(m) => m.core_mut(),
            ModuleRt::Estop(m) => m.core_mut(),
            ModuleRt::Mon(m) => m.core_mut(),
            ModuleRt::And | ModuleRt::Or | ModuleRt::Decouple => return,
        };
        core.acknowledge();
    }
}

/// A local output's error state (OUT_ERR).
#[derive(Clone, Copy, Debug, Default)]
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
            modules: c.modules.iter().map(|m| ModuleRt::new(&m.config)).collect(),
            local_faults: vec![LocalFault::default(); c.local_outputs.len()],
            local_values: vec![false; c.local_outputs.len()],
            twinsafe_out: vec![0; c.connections.len()],
            standard_values: vec![false; c.standard_outputs.len()],
            last_now: None,
            fault: None,
            pending_fault: None,
            events: Vec::new(),
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
        self.image[input.0] = value;
    }

    /// Set the partner's safe inputs of connection `c` (bit `n-1` = channel `n`); they reach
    /// the logic with the next exchange.
    pub fn set_partner_inputs(&mut self, c: ConnectionId, bits: u8) {
        self.connections[c.0].set_partner_inputs(bits);
    }

    /// Schedule a fault on connection `c`'s black channel at `at`.
    pub fn inject(&mut self, c: ConnectionId, at: SimTime, fault: ChannelFault) {
        self.connections[c.0].inject(at, fault);
    }

    /// Make local output `index` (1..4) report an error (e.g. a cross-circuit seen on its
    /// read-back) while `faulty`; it latches OUT_ERR in its group. Unknown indices are ignored.
    pub fn set_local_output_fault(&mut self, index: u8, faulty: bool) {
        if let Some(k) = self.c.local_outputs.iter().position(|o| o.index == index) {
            self.local_faults[k].present = faulty;
        }
    }

    /// Raise an internal logic fault at the next scan: the whole logic stops for good.
    pub fn inject_logic_fault(&mut self, cause: &str) {
        self.pending_fault = Some(cause.to_owned());
    }

    // ---- the scan ----------------------------------------------------------------------------

    /// One safety scan at `now`; returns what happened in it.
    pub fn scan(&mut self, now: SimTime) -> &[LogicEvent] {
        self.events.clear();
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
                self.push(
                    now,
                    LogicEventKind::LogicFault {
                        cause: cause.clone(),
                    },
                );
                self.fault = Some(cause);
            }
        }
        if self.fault.is_some() {
            self.local_values.iter_mut().for_each(|v| *v = false);
            self.standard_values.iter_mut().for_each(|v| *v = false);
            self.twinsafe_out.iter_mut().for_each(|v| *v = 0);
            return &self.events;
        }
        self.last_now = Some(now);

        // 1. Inputs: one exchange per connection.
        for k in 0..self.connections.len() {
            let out = self.twinsafe_out[k];
            // Almost every exchange reports nothing: copy its events only when there are some.
            let events = self.connections[k].exchange(now, out);
            if !events.is_empty() {
                let events = events.to_vec();
                self.push_connection_events(now, k, events);
            }
        }
        for k in 0..self.local_faults.len() {
            let f = &mut self.local_faults[k];
            if f.present && !f.latched {
                f.latched = true;
                let o = &self.c.local_outputs[k];
                let kind = LogicEventKind::LocalOutputFault {
                    index: o.index,
                    name: o.name.clone(),
                };
                self.push(now, kind);
            }
        }

        // 2. Groups.
        for g in 0..self.groups.len() {
            self.update_group(now, g);
        }
        for k in 0..self.connections.len() {
            let bits = self.connections[k].inputs();
            for (ch, &slot) in self.c.connections[k].inputs.iter().enumerate() {
                self.image[slot] = bits & 1 << ch != 0;
            }
        }

        // 3. Modules in their order.
        for m in 0..self.modules.len() {
            self.scan_module(now, m);
        }

        // 4. Errors found in this scan trip their group at once.
        for g in 0..self.groups.len() {
            let (errors, _) = self.collect(g);
            let before = self.groups[g].state();
            self.groups[g].trip(errors);
            self.after_group_change(now, g, before);
        }

        // 5. Outputs.
        for m in 0..self.modules.len() {
            if !self.groups[self.c.modules[m].group].running() {
                let cm = &self.c.modules[m];
                for (k, &slot) in cm.outputs.iter().enumerate() {
                    if cm.safety_outputs[k] {
                        self.image[slot] = false;
                    }
                }
            }
        }
        for k in 0..self.c.local_outputs.len() {
            let o = &self.c.local_outputs[k];
            self.local_values[k] = self.image[o.source]
                && self.groups[o.group].running()
                && !self.local_faults[k].latched;
        }
        for k in 0..self.c.standard_outputs.len() {
            self.standard_values[k] = self.image[self.c.standard_outputs[k].1];
        }
        for k in 0..self.c.connections.len() {
            let cc = &self.c.connections[k];
            self.twinsafe_out[k] = if self.groups[cc.group].running() {
                cc.outputs
                    .iter()
                    .filter(|&&(_, slot)| self.image[slot])
                    .fold(0, |bits, &(ch, _)| bits | 1 << (ch - 1))
            } else {
                0
            };
        }
        &self.events
    }

    fn push(&mut self, at: SimTime, kind: LogicEventKind) {
        self.events.push(LogicEvent { at, kind });
    }

    fn push_connection_events(&mut self, now: SimTime, k: usize, events: Vec<ConnEvent>) {
        for event in events {
            let kind = LogicEventKind::Connection {
                number: k + 1,
                connection: self.c.connections[k].name.clone(),
                event,
            };
            self.push(now, kind);
        }
    }

    /// The error classes latched by group `g`'s members, and whether any cause is present.
    fn collect(&self, g: usize) -> (GroupErrors, bool) {
        let mut errors = GroupErrors::default();
        let mut cause = false;
        for (cm, m) in self.c.modules.iter().zip(&self.modules) {
            if cm.group == g && m.has_error() {
                errors.fb_err = true;
                cause |= m.error_cause_active();
            }
        }
        for (cc, c) in self.c.connections.iter().zip(&self.connections) {
            if cc.group == g && c.has_error() {
                errors.com_err = true;
                cause |= c.error_cause_active();
            }
        }
        for (o, f) in self.c.local_outputs.iter().zip(&self.local_faults) {
            if o.group == g && f.latched {
                errors.out_err = true;
                cause |= f.present;
            }
        }
        (errors, cause)
    }

    fn update_group(&mut self, now: SimTime, g: usize) {
        let cg = &self.c.groups[g];
        let run = cg.run.is_none_or(|s| self.image[s]);
        let ack = cg.err_ack.is_some_and(|s| self.image[s]);
        let (errors, cause) = self.collect(g);
        let before = self.groups[g].state();
        if self.groups[g].update(run, ack, errors, cause) {
            for m in 0..self.modules.len() {
                if self.c.modules[m].group == g {
                    self.modules[m].acknowledge();
                }
            }
            for k in 0..self.connections.len() {
                if self.c.connections[k].group == g && self.connections[k].has_error() {
                    self.connections[k].acknowledge();
                    self.push_connection_events(now, k, vec![ConnEvent::Acknowledged]);
                }
            }
            for k in 0..self.local_faults.len() {
                if self.c.local_outputs[k].group == g {
                    self.local_faults[k].latched = false;
                }
            }
            self.groups[g].acknowledged(run);
            let group = self.c.groups[g].name.clone();
            self.push(now, LogicEventKind::GroupAcknowledged { group });
        }
        self.after_group_change(now, g, before);
    }

    /// Log a state change of group `g` and refresh its output signals.
    fn after_group_change(&mut self, now: SimTime, g: usize, before: GroupState) {
        let group = &self.groups[g];
        let (state, errors) = (group.state(), group.errors());
        let [fb, com, out] = self.c.groups[g].outputs;
        self.image[fb] = errors.fb_err;
        self.image[com] = errors.com_err;
        self.image[out] = errors.out_err;
        let name = || self.c.groups[g].name.clone();
        let entered_error =
            state == GroupState::Error && !matches!(before, GroupState::Error | GroupState::Reset);
        if entered_error {
            self.push(
                now,
                LogicEventKind::GroupTripped {
                    group: name(),
                    errors,
                },
            );
        } else if state != before
            && matches!(state, GroupState::Run | GroupState::Stop)
            && matches!(before, GroupState::Run | GroupState::Stop)
        {
            let running = state == GroupState::Run;
            self.push(
                now,
                LogicEventKind::GroupRunning {
                    group: name(),
                    running,
                },
            );
        }
    }

    fn scan_module(&mut self, now: SimTime, m: usize) {
        let cm = &self.c.modules[m];
        let run = self.groups[cm.group].running();
        let value = |k: usize| -> bool { cm.inputs[k].is_some_and(|(s, _)| self.image[s]) };
        let linked = |k: usize| cm.inputs[k].map(|(s, c)| (c, self.image[s]));
        // At most 9 outputs (OPMODE: 8 and Error), kept on the stack: a scan runs every 1 ms.
        let mut outputs = Outputs::default();
        match &mut self.modules[m] {
            ModuleRt::And => outputs.push(and((0..8).filter_map(linked))),
            ModuleRt::Or => outputs.push(or((0..8).filter_map(linked))),
            ModuleRt::Decouple => outputs.extend(decouple(core::array::from_fn(value))),
            ModuleRt::OpMode(fb) => {
                let o = fb.scan(
                    now,
                    run,
                    &OpModeInputs {
                        op_in: core::array::from_fn(value),
                        restart: value(8),
                    },
                );
                outputs.extend(o.op_out.iter().copied().chain([o.error]));
            }
            ModuleRt::Estop(fb) => {
                let o = fb.scan(
                    now,
                    run,
                    &EstopInputs {
                        estop_in: core::array::from_fn(value),
                        restart: value(8),
                        edm1: value(9),
                        edm2: value(10),
                    },
                );
                outputs.extend([o.estop_out, o.estop_del_out, o.error]);
            }
            ModuleRt::Mon(fb) => {
                let o = fb.scan(
                    now,
                    run,
                    &MonInputs {
                        mon_in: core::array::from_fn(value),
                        secure: [value(4), value(5)],
                        restart: value(6),
                        edm1: value(7),
                        edm2: value(8),
                    },
                );
                outputs.extend([o.mon_out, o.mon_del_out, o.error]);
            }
        };
        for (k, &v) in outputs.as_slice().iter().enumerate() {
            let gated = v && (run || !cm.safety_outputs[k]);
            self.image[cm.outputs[k]] = gated;
        }
        // Events are rare: walk them in place rather than copying them every scan.
        for k in 0..self.modules[m].events().len() {
            let event = self.modules[m].events()[k];
            let kind = LogicEventKind::Module {
                module: cm.name.clone(),
                kind: cm.kind,
                event,
            };
            self.events.push(LogicEvent { at: now, kind });
        }
    }

    // ---- outputs and diagnostics -------------------------------------------------------------

    /// Local output `index` (1..4) as written by the last scan; `false` if not in the project.
    pub fn local_output(&self, index: u8) -> bool {
        self.c
            .local_outputs
            .iter()
            .position(|o| o.index == index)
            .is_some_and(|k| self.local_values[k])
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
        let running = self.groups[self.c.modules[m.0].group].running();
        ModuleStatus {
            kind: self.c.modules[m.0].kind,
            state: self.modules[m.0].state(running),
            diag: self.modules[m.0].diag(),
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

/// A module's outputs in one scan, in their order, on the stack.
#[derive(Default)]
struct Outputs {
    values: [bool; 12],
    len: usize,
}

impl Outputs {
    fn push(&mut self, v: bool) {
        // A module has at most 9 outputs (verify::output_specs); more would be a logic slip,
        // and the outputs past the array would be lost rather than panic in a safety scan.
        if let Some(slot) = self.values.get_mut(self.len) {
            *slot = v;
            self.len += 1;
        }
    }

    fn extend(&mut self, vs: impl IntoIterator<Item = bool>) {
        vs.into_iter().for_each(|v| self.push(v));
    }

    fn as_slice(&self) -> &[bool] {
        &self.values[..self.len]
    }
}
