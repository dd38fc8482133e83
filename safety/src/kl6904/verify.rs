//! The project verifier: the checks the TwinSAFE Verifier and the System Manager make before a
//! project is loaded into the KL6904 (seed 004 §2, §3, §4 signal tables), and the compiled form
//! the logic runs.
//!
//! Every problem found is reported (not only the first), each with the [`Rule`] it breaks and
//! the [`Item`] it concerns.

use std::collections::{BTreeMap, BTreeSet};

use asi_phy::SimDuration;
use core::fmt;

use super::modules::{EstopConfig, MonConfig, OpModeConfig};
use super::project::{ModuleDesc, ModuleKind, Project};
use super::signal::{ChannelRef, Contact, GroupOutput, SignalKind, SignalRef};

/// The verifier's rules.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Rule {
    /// Names of groups, connections, modules, channels and outputs are unique and well formed.
    UniqueName,
    /// Every connection, module and local output belongs to one existing group, and a
    /// connection's I/O and a local output are used only by modules of their group (seed 004
    /// §3, §3.1).
    OneGroup,
    /// Every output (local output, standard output, TwinSAFE-Out channel) is driven exactly once.
    DrivenOnce,
    /// Only the signal kinds the seed's tables allow are linked to each input and output (e.g.
    /// a standard signal only on AndIn1, seed 004 table 4-1).
    SignalKind,
    /// TwinSAFE addresses are unique and not 0 (seed 004 §3.2).
    UniqueAddress,
    /// No input is linked to something that does not exist, and no required input is left open.
    Dangling,
    /// Module parameters belong to the module's type and are in range.
    Parameter,
}

impl Rule {
    /// A short name for messages.
    pub const fn name(self) -> &'static str {
        match self {
            Rule::UniqueName => "unique names",
            Rule::OneGroup => "one group",
            Rule::DrivenOnce => "driven once",
            Rule::SignalKind => "signal kinds",
            Rule::UniqueAddress => "unique addresses",
            Rule::Dangling => "no dangling input",
            Rule::Parameter => "parameters",
        }
    }
}

/// The part of a project a problem concerns, by position in the project and by name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Item {
    /// The `[logic]` table.
    Logic,
    /// A group.
    Group {
        /// Position in the project's groups.
        index: usize,
        /// Its name.
        name: String,
    },
    /// RUN or ERR_ACK of a group.
    GroupInput {
        /// Position in the project's groups.
        index: usize,
        /// The group's name.
        name: String,
        /// `run` or `err_ack`.
        input: &'static str,
    },
    /// A connection.
    Connection {
        /// Position in the project's connections.
        index: usize,
        /// Its name.
        name: String,
    },
    /// A TwinSAFE-Out entry of a connection.
    ConnectionOutput {
        /// Position in the project's connections.
        index: usize,
        /// The connection's name.
        name: String,
        /// Position in the connection's outputs.
        output: usize,
    },
    /// A module.
    Module {
        /// Position in the project's modules.
        index: usize,
        /// Its name.
        name: String,
    },
    /// A module input.
    ModuleInput {
        /// Position in the project's modules.
        index: usize,
        /// The module's name.
        name: String,
        /// The input's name.
        input: String,
    },
    /// A module parameter.
    ModuleParam {
        /// Position in the project's modules.
        index: usize,
        /// The module's name.
        name: String,
        /// The parameter's key.
        param: &'static str,
    },
    /// A local output.
    LocalOutput {
        /// Position in the project's local outputs.
        index: usize,
        /// Its name.
        name: String,
    },
    /// A standard output.
    StandardOutput {
        /// Position in the project's standard outputs.
        index: usize,
        /// Its name.
        name: String,
    },
}

/// A step of a path into a project file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PathStep {
    /// A table key.
    Key(String),
    /// An array index.
    Index(usize),
}

impl Item {
    /// Where the item stands in a project file, e.g. `module[2].inputs.EStopIn1`.
    pub fn path(&self) -> Vec<PathStep> {
        use PathStep::{Index, Key};
        let key = |s: &str| Key(s.to_owned());
        match self {
            Item::Logic => vec![key("logic")],
            Item::Group { index, .. } => vec![key("group"), Index(*index)],
            Item::GroupInput { index, input, .. } => vec![key("group"), Index(*index), key(input)],
            Item::Connection { index, .. } => vec![key("connection"), Index(*index)],
            Item::ConnectionOutput { index, output, .. } => vec![
                key("connection"),
                Index(*index),
                key("outputs"),
                Index(*output),
            ],
            Item::Module { index, .. } => vec![key("module"), Index(*index)],
            Item::ModuleInput { index, input, .. } => {
                vec![key("module"), Index(*index), key("inputs"), key(input)]
            }
            Item::ModuleParam { index, param, .. } => {
                vec![key("module"), Index(*index), key(param)]
            }
            Item::LocalOutput { index, .. } => vec![key("local_output"), Index(*index)],
            Item::StandardOutput { index, .. } => vec![key("standard_output"), Index(*index)],
        }
    }
}

impl fmt::Display for Item {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Item::Logic => f.write_str("logic"),
            Item::Group { name, .. } => write!(f, "group `{name}`"),
            Item::GroupInput { name, input, .. } => write!(f, "group `{name}`, input `{input}`"),
            Item::Connection { name, .. } => write!(f, "connection `{name}`"),
            Item::ConnectionOutput { name, output, .. } => {
                write!(f, "connection `{name}`, output #{}", output + 1)
            }
            Item::Module { name, .. } => write!(f, "module `{name}`"),
            Item::ModuleInput { name, input, .. } => write!(f, "module `{name}`, input `{input}`"),
            Item::ModuleParam { name, param, .. } => {
                write!(f, "module `{name}`, parameter `{param}`")
            }
            Item::LocalOutput { name, .. } => write!(f, "local output `{name}`"),
            Item::StandardOutput { name, .. } => write!(f, "standard output `{name}`"),
        }
    }
}

/// One problem the verifier found.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{item}: {message} [rule: {}]", rule.name())]
pub struct VerifyError {
    /// The rule broken.
    pub rule: Rule,
    /// Where.
    pub item: Item,
    /// What is wrong, in words.
    pub message: String,
}

/// An index into the logic's signal image.
pub(crate) type Slot = usize;

/// How one kind of module input may be linked.
#[derive(Clone, Debug)]
pub(crate) struct InputSpec {
    pub(crate) name: String,
    pub(crate) kinds: &'static [SignalKind],
    pub(crate) contact: bool,
}

const SAFE: &[SignalKind] = &[SignalKind::TwinSafeIn, SignalKind::FbOut];
const ANY: &[SignalKind] = &[
    SignalKind::TwinSafeIn,
    SignalKind::FbOut,
    SignalKind::StandardIn,
];
const GROUP_IN: &[SignalKind] = &[SignalKind::FbOut, SignalKind::StandardIn];

fn numbered(
    prefix: &'static str,
    n: usize,
    kinds: &'static [SignalKind],
    contact: bool,
) -> impl Iterator<Item = InputSpec> {
    (1..=n).map(move |k| InputSpec {
        name: format!("{prefix}{k}"),
        kinds,
        contact,
    })
}

fn single(name: &str, kinds: &'static [SignalKind], contact: bool) -> InputSpec {
    InputSpec {
        name: name.to_owned(),
        kinds,
        contact,
    }
}

/// The inputs of a module kind, in a fixed order (seed 004 tables 4-1, 4-4, 4-7, 4-10, 4-13,
/// 4-16).
pub(crate) fn input_specs(kind: ModuleKind) -> Vec<InputSpec> {
    match kind {
        ModuleKind::And => core::iter::once(single("AndIn1", ANY, true))
            .chain(numbered("AndIn", 8, SAFE, true).skip(1))
            .collect(),
        ModuleKind::Or => numbered("OrIn", 8, SAFE, true).collect(),
        ModuleKind::OpMode => numbered("OpIn", 8, SAFE, false)
            .chain([single("Restart", ANY, false)])
            .collect(),
        ModuleKind::Estop => numbered("EStopIn", 8, SAFE, true)
            .chain([
                single("Restart", ANY, false),
                single("EDM1", ANY, false),
                single("EDM2", ANY, false),
            ])
            .collect(),
        ModuleKind::Mon => numbered("MonIn", 4, SAFE, true)
            .chain([
                single("Secure1", SAFE, true),
                single("Secure2", SAFE, true),
                single("Restart", ANY, false),
                single("EDM1", ANY, false),
                single("EDM2", ANY, false),
            ])
            .collect(),
        ModuleKind::Decouple => numbered("DecIn", 8, SAFE, false).collect(),
    }
}

/// The outputs of a module kind and whether each is a safety output (switched off with the
/// group) or the Error output (seed 004 tables 4-2, 4-5, 4-8, 4-11, 4-14, 4-17).
pub(crate) fn output_specs(kind: ModuleKind) -> Vec<(String, bool)> {
    let numbered = |p: &'static str, n: usize| (1..=n).map(move |k| (format!("{p}{k}"), true));
    let named = |names: &[&str]| -> Vec<(String, bool)> {
        names
            .iter()
            .map(|n| ((*n).to_owned(), *n != "Error"))
            .collect()
    };
    match kind {
        ModuleKind::And => named(&["AndOut"]),
        ModuleKind::Or => named(&["OrOut"]),
        ModuleKind::OpMode => numbered("OpOut", 8).chain(named(&["Error"])).collect(),
        ModuleKind::Estop => named(&["EStopOut", "EStopDelOut", "Error"]),
        ModuleKind::Mon => named(&["MonOut", "MonDelOut", "Error"]),
        ModuleKind::Decouple => numbered("DecOut", 8).collect(),
    }
}

/// The parameters of a module kind.
fn allowed_params(kind: ModuleKind) -> &'static [&'static str] {
    match kind {
        ModuleKind::And | ModuleKind::Or | ModuleKind::Decouple => &[],
        ModuleKind::OpMode => &["discrepancy"],
        ModuleKind::Estop => &["delay", "pair_discrepancy"],
        ModuleKind::Mon => &[
            "delay",
            "pair_discrepancy",
            "secure_discrepancy",
            "manual_restart",
            "function_test",
        ],
    }
}

/// The module parameters that are set, by key.
fn params_set(m: &ModuleDesc) -> Vec<&'static str> {
    [
        ("delay", m.delay.is_some()),
        ("pair_discrepancy", m.pair_discrepancy.is_some()),
        ("secure_discrepancy", m.secure_discrepancy.is_some()),
        ("discrepancy", m.discrepancy.is_some()),
        ("manual_restart", m.manual_restart.is_some()),
        ("function_test", m.function_test.is_some()),
    ]
    .into_iter()
    .filter_map(|(k, set)| set.then_some(k))
    .collect()
}

/// The runtime parameters of a module.
#[derive(Clone, Debug)]
pub(crate) enum ModuleConfig {
    And,
    Or,
    OpMode(OpModeConfig),
    Estop(EstopConfig),
    Mon(MonConfig),
    Decouple,
}

/// A module ready to run: resolved inputs (by [`input_specs`] position) and output slots (by
/// [`output_specs`] position).
#[derive(Clone, Debug)]
pub(crate) struct CompiledModule {
    pub(crate) name: String,
    pub(crate) kind: ModuleKind,
    pub(crate) group: usize,
    pub(crate) inputs: Vec<Option<(Slot, Contact)>>,
    pub(crate) outputs: Vec<Slot>,
    pub(crate) safety_outputs: Vec<bool>,
    pub(crate) config: ModuleConfig,
}

/// A group ready to run.
#[derive(Clone, Debug)]
pub(crate) struct CompiledGroup {
    pub(crate) name: String,
    pub(crate) run: Option<Slot>,
    pub(crate) err_ack: Option<Slot>,
    /// FB_ERR, COM_ERR, OUT_ERR.
    pub(crate) outputs: [Slot; 3],
}

/// A connection ready to run.
#[derive(Clone, Debug)]
pub(crate) struct CompiledConnection {
    pub(crate) name: String,
    pub(crate) group: usize,
    pub(crate) partner_address: u16,
    pub(crate) watchdog: SimDuration,
    pub(crate) channel_names: Vec<String>,
    /// One slot per partner input channel.
    pub(crate) inputs: Vec<Slot>,
    /// (channel 1-based, source).
    pub(crate) outputs: Vec<(u8, Slot)>,
}

/// A local output ready to run.
#[derive(Clone, Debug)]
pub(crate) struct CompiledLocalOutput {
    pub(crate) index: u8,
    pub(crate) name: String,
    pub(crate) group: usize,
    pub(crate) source: Slot,
}

/// A verified project, ready to run.
#[derive(Clone, Debug)]
pub(crate) struct Compiled {
    pub(crate) name: String,
    pub(crate) address: u16,
    pub(crate) slots: usize,
    pub(crate) standard_inputs: Vec<(String, Slot)>,
    pub(crate) groups: Vec<CompiledGroup>,
    pub(crate) connections: Vec<CompiledConnection>,
    pub(crate) modules: Vec<CompiledModule>,
    pub(crate) local_outputs: Vec<CompiledLocalOutput>,
    pub(crate) standard_outputs: Vec<(String, Slot)>,
}

/// The KL6904 has four local safe outputs.
pub const LOCAL_OUTPUTS: u8 = 4;

fn is_name(s: &str) -> bool {
    !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

struct Verifier<'p> {
    p: &'p Project,
    errors: Vec<VerifyError>,
    groups: BTreeMap<&'p str, usize>,
    connections: BTreeMap<&'p str, usize>,
    modules: BTreeMap<&'p str, usize>,
    next_slot: Slot,
    standard_inputs: BTreeMap<String, Slot>,
    conn_inputs: Vec<Vec<Slot>>,
    module_outputs: Vec<Vec<Slot>>,
    group_outputs: Vec<[Slot; 3]>,
    /// (module, output position) of every module output that something reads.
    consumed: BTreeSet<(usize, usize)>,
}

impl<'p> Verifier<'p> {
    fn err(&mut self, rule: Rule, item: Item, message: String) {
        self.errors.push(VerifyError {
            rule,
            item,
            message,
        });
    }

    fn slot(&mut self) -> Slot {
        self.next_slot += 1;
        self.next_slot - 1
    }

    /// Index names; reports duplicates and malformed names.
    fn index_names(
        &mut self,
        names: impl Iterator<Item = (&'p str, Item)>,
        what: &str,
    ) -> BTreeMap<&'p str, usize> {
        let mut map = BTreeMap::new();
        for (k, (name, item)) in names.enumerate() {
            if !is_name(name) {
                self.err(
                    Rule::UniqueName,
                    item,
                    format!(
                        "`{name}` is not a valid {what} name: use letters, digits, `_` and `-`"
                    ),
                );
            } else if map.insert(name, k).is_some() {
                self.err(
                    Rule::UniqueName,
                    item,
                    format!("the {what} name `{name}` is used twice"),
                );
            }
        }
        map
    }

    /// Resolve `sig` read by `reader` (in group `group`, if any) where `kinds` are allowed.
    fn resolve(
        &mut self,
        sig: &SignalRef,
        kinds: &[SignalKind],
        group: Option<usize>,
        reader: &Item,
        what: &str,
    ) -> Option<Slot> {
        if !kinds.contains(&sig.kind()) {
            let allowed: Vec<&str> = kinds.iter().map(|k| k.name()).collect();
            self.err(
                Rule::SignalKind,
                reader.clone(),
                format!(
                    "{what} may be linked to {} only, not to the {} `{sig}`",
                    allowed.join(" or "),
                    sig.kind()
                ),
            );
            return None;
        }
        match sig {
            SignalRef::StandardIn { name } => {
                let next = self.next_slot;
                let slot = *self.standard_inputs.entry(name.clone()).or_insert(next);
                if slot == next {
                    self.next_slot += 1;
                }
                Some(slot)
            }
            SignalRef::TwinSafeIn {
                connection,
                channel,
            } => {
                let Some(&c) = self.connections.get(connection.as_str()) else {
                    self.err(
                        Rule::Dangling,
                        reader.clone(),
                        format!("`{sig}`: there is no connection `{connection}`"),
                    );
                    return None;
                };
                let desc = &self.p.connections[c];
                let n = match channel {
                    ChannelRef::Number(n) => usize::from(*n),
                    ChannelRef::Name(name) => desc
                        .channels
                        .iter()
                        .position(|c| c == name)
                        .map_or(0, |k| k + 1),
                };
                if n == 0 || n > self.conn_inputs[c].len() {
                    self.err(
                        Rule::Dangling,
                        reader.clone(),
                        format!(
                            "`{sig}`: connection `{connection}` to a {} has no input channel `{channel}` (channels 1..{}{})",
                            desc.partner.name(),
                            desc.partner.inputs(),
                            if desc.channels.is_empty() {
                                String::new()
                            } else {
                                format!(" or {}", desc.channels.join(", "))
                            }
                        ),
                    );
                    return None;
                }
                let conn_group = self.groups.get(desc.group.as_str()).copied();
                if let (Some(g), Some(cg)) = (group, conn_group) {
                    if g != cg {
                        self.err(
                            Rule::OneGroup,
                            reader.clone(),
                            format!(
                                "`{sig}` belongs to group `{}`; only modules of that group may use it (use a DECOUPLE module)",
                                desc.group
                            ),
                        );
                    }
                }
                Some(self.conn_inputs[c][n - 1])
            }
            SignalRef::FbOut { module, output } => {
                let Some(&m) = self.modules.get(module.as_str()) else {
                    self.err(
                        Rule::Dangling,
                        reader.clone(),
                        format!("`{sig}`: there is no module `{module}`"),
                    );
                    return None;
                };
                let kind = self.p.modules[m].kind;
                let outs = output_specs(kind);
                let Some(k) = outs.iter().position(|(n, _)| n == output) else {
                    let names: Vec<&str> = outs.iter().map(|(n, _)| n.as_str()).collect();
                    self.err(
                        Rule::Dangling,
                        reader.clone(),
                        format!(
                            "`{sig}`: {kind} module `{module}` has no output `{output}` (it has {})",
                            names.join(", ")
                        ),
                    );
                    return None;
                };
                self.consumed.insert((m, k));
                Some(self.module_outputs[m][k])
            }
            SignalRef::Group { group: g, output } => {
                let Some(&gi) = self.groups.get(g.as_str()) else {
                    self.err(
                        Rule::Dangling,
                        reader.clone(),
                        format!("`{sig}`: there is no group `{g}`"),
                    );
                    return None;
                };
                let k = GroupOutput::ALL
                    .iter()
                    .position(|o| o == output)
                    .unwrap_or_default();
                Some(self.group_outputs[gi][k])
            }
        }
    }

    fn group_of(&mut self, name: &str, item: Item) -> Option<usize> {
        let g = self.groups.get(name).copied();
        if g.is_none() {
            self.err(
                Rule::OneGroup,
                item,
                format!("belongs to group `{name}`, which does not exist"),
            );
        }
        g
    }
}

/// Check `p` against every rule; compile it if it passes.
pub(crate) fn verify(p: &Project) -> Result<Compiled, Vec<VerifyError>> {
    let mut v = Verifier {
        p,
        errors: Vec::new(),
        groups: BTreeMap::new(),
        connections: BTreeMap::new(),
        modules: BTreeMap::new(),
        next_slot: 0,
        standard_inputs: BTreeMap::new(),
        conn_inputs: Vec::new(),
        module_outputs: Vec::new(),
        group_outputs: Vec::new(),
        consumed: BTreeSet::new(),
    };

    // Names.
    v.groups = v.index_names(
        p.groups.iter().enumerate().map(|(index, g)| {
            (
                g.name.as_str(),
                Item::Group {
                    index,
                    name: g.name.clone(),
                },
            )
        }),
        "group",
    );
    v.connections = v.index_names(
        p.connections.iter().enumerate().map(|(index, c)| {
            (
                c.name.as_str(),
                Item::Connection {
                    index,
                    name: c.name.clone(),
                },
            )
        }),
        "connection",
    );
    v.modules = v.index_names(
        p.modules.iter().enumerate().map(|(index, m)| {
            (
                m.name.as_str(),
                Item::Module {
                    index,
                    name: m.name.clone(),
                },
            )
        }),
        "module",
    );

    // Addresses.
    let mut addresses: BTreeMap<u16, String> = BTreeMap::new();
    if p.logic.address == 0 {
        v.err(
            Rule::UniqueAddress,
            Item::Logic,
            "TwinSAFE address 0 is not valid".into(),
        );
    }
    addresses.insert(p.logic.address, format!("the logic `{}`", p.logic.name));
    for (index, c) in p.connections.iter().enumerate() {
        let item = Item::Connection {
            index,
            name: c.name.clone(),
        };
        if c.partner_address == 0 {
            v.err(
                Rule::UniqueAddress,
                item,
                "partner address 0 is not valid".into(),
            );
        } else if let Some(other) = addresses.get(&c.partner_address).cloned() {
            v.err(
                Rule::UniqueAddress,
                item,
                format!(
                    "partner address {} is already used by {other}",
                    c.partner_address
                ),
            );
        } else {
            addresses.insert(c.partner_address, format!("connection `{}`", c.name));
        }
    }

    // Slots of everything that can be read: connection inputs, module and group outputs.
    v.conn_inputs = p
        .connections
        .iter()
        .map(|c| (0..c.partner.inputs()).map(|_| 0).collect())
        .collect();
    for c in 0..v.conn_inputs.len() {
        for k in 0..v.conn_inputs[c].len() {
            v.conn_inputs[c][k] = v.slot();
        }
    }
    v.module_outputs = p
        .modules
        .iter()
        .map(|m| vec![0; output_specs(m.kind).len()])
        .collect();
    for m in 0..v.module_outputs.len() {
        for k in 0..v.module_outputs[m].len() {
            v.module_outputs[m][k] = v.slot();
        }
    }
    for _ in &p.groups {
        let slots = [v.slot(), v.slot(), v.slot()];
        v.group_outputs.push(slots);
    }

    // Groups.
    let mut groups = Vec::new();
    for (index, g) in p.groups.iter().enumerate() {
        let item = |input| Item::GroupInput {
            index,
            name: g.name.clone(),
            input,
        };
        let run = g
            .run
            .as_ref()
            .and_then(|s| v.resolve(s, GROUP_IN, None, &item("run"), "RUN"));
        let err_ack = match &g.err_ack {
            Some(s) => v.resolve(s, GROUP_IN, None, &item("err_ack"), "ERR_ACK"),
            None => {
                v.err(
                    Rule::Dangling,
                    Item::Group { index, name: g.name.clone() },
                    "ERR_ACK is not connected; acknowledgement is never automatic, so it must be (seed 004 §3.1)".into(),
                );
                None
            }
        };
        groups.push(CompiledGroup {
            name: g.name.clone(),
            run,
            err_ack,
            outputs: v.group_outputs[index],
        });
    }

    // Connections.
    let mut connections = Vec::new();
    for (index, c) in p.connections.iter().enumerate() {
        let item = Item::Connection {
            index,
            name: c.name.clone(),
        };
        let group = v.group_of(&c.group, item.clone());
        if c.watchdog.is_zero() {
            v.err(
                Rule::Parameter,
                item.clone(),
                "the watchdog time must not be 0".into(),
            );
        }
        if c.channels.len() > usize::from(c.partner.inputs()) {
            v.err(
                Rule::Parameter,
                item.clone(),
                format!(
                    "{} channel names given, but a {} has {} safe inputs",
                    c.channels.len(),
                    c.partner.name(),
                    c.partner.inputs()
                ),
            );
        }
        let mut seen = BTreeSet::new();
        for ch in &c.channels {
            if !is_name(ch) || ch.parse::<u8>().is_ok() {
                v.err(
                    Rule::UniqueName,
                    item.clone(),
                    format!("`{ch}` is not a valid channel name"),
                );
            } else if !seen.insert(ch) {
                v.err(
                    Rule::UniqueName,
                    item.clone(),
                    format!("the channel name `{ch}` is used twice"),
                );
            }
        }
        let mut outputs = Vec::new();
        let mut driven = BTreeSet::new();
        for (k, o) in c.outputs.iter().enumerate() {
            let oitem = Item::ConnectionOutput {
                index,
                name: c.name.clone(),
                output: k,
            };
            if o.channel == 0 || o.channel > c.partner.outputs() {
                v.err(
                    Rule::Dangling,
                    oitem.clone(),
                    format!(
                        "a {} has no TwinSAFE-Out channel {} (it has {})",
                        c.partner.name(),
                        o.channel,
                        c.partner.outputs()
                    ),
                );
            } else if !driven.insert(o.channel) {
                v.err(
                    Rule::DrivenOnce,
                    oitem.clone(),
                    format!("TwinSAFE-Out channel {} is driven twice", o.channel),
                );
            }
            if let Some(slot) = v.resolve(
                &o.source,
                &[SignalKind::FbOut],
                None,
                &oitem,
                "a TwinSAFE-Out",
            ) {
                check_source_group(&mut v, &o.source, group, &oitem);
                outputs.push((o.channel, slot));
            }
        }
        connections.push(CompiledConnection {
            name: c.name.clone(),
            group: group.unwrap_or_default(),
            partner_address: c.partner_address,
            watchdog: c.watchdog,
            channel_names: c.channels.clone(),
            inputs: v.conn_inputs[index].clone(),
            outputs,
        });
    }

    // Modules.
    let mut modules = Vec::new();
    for (index, m) in p.modules.iter().enumerate() {
        modules.push(compile_module(&mut v, index, m));
    }

    // Local outputs.
    let mut local_outputs = Vec::new();
    let mut driven: BTreeMap<u8, &str> = BTreeMap::new();
    for (index, o) in p.local_outputs.iter().enumerate() {
        let item = Item::LocalOutput {
            index,
            name: o.name.clone(),
        };
        let group = v.group_of(&o.group, item.clone());
        if o.index == 0 || o.index > LOCAL_OUTPUTS {
            v.err(
                Rule::Dangling,
                item.clone(),
                format!(
                    "the KL6904 has local outputs 1..{LOCAL_OUTPUTS}, not {}",
                    o.index
                ),
            );
        } else if let Some(other) = driven.insert(o.index, &o.name) {
            v.err(
                Rule::DrivenOnce,
                item.clone(),
                format!("local output {} is already driven as `{other}`", o.index),
            );
        }
        if matches!(o.source, SignalRef::Group { .. }) {
            v.err(
                Rule::SignalKind,
                item.clone(),
                format!("a Local-Out takes a module output, not the group output `{}` (seed 004 table 3-2)", o.source),
            );
            continue;
        }
        if let Some(source) = v.resolve(&o.source, &[SignalKind::FbOut], None, &item, "a Local-Out")
        {
            check_source_group(&mut v, &o.source, group, &item);
            local_outputs.push(CompiledLocalOutput {
                index: o.index,
                name: o.name.clone(),
                group: group.unwrap_or_default(),
                source,
            });
        }
    }

    // Standard outputs.
    let mut standard_outputs = Vec::new();
    let mut names = BTreeSet::new();
    for (index, o) in p.standard_outputs.iter().enumerate() {
        let item = Item::StandardOutput {
            index,
            name: o.name.clone(),
        };
        if !is_name(&o.name) {
            v.err(
                Rule::UniqueName,
                item.clone(),
                format!("`{}` is not a valid variable name", o.name),
            );
        } else if !names.insert(o.name.as_str()) {
            v.err(
                Rule::DrivenOnce,
                item.clone(),
                format!("standard output `{}` is driven twice", o.name),
            );
        }
        if let Some(source) = v.resolve(
            &o.source,
            &[SignalKind::FbOut],
            None,
            &item,
            "a Standard-Out",
        ) {
            standard_outputs.push((o.name.clone(), source));
        }
    }

    // DECOUPLE: an input used needs its output linked, and the other way round (seed 004 §4.6).
    for (index, m) in p.modules.iter().enumerate() {
        if m.kind != ModuleKind::Decouple {
            continue;
        }
        for k in 0..8 {
            let input = format!("DecIn{}", k + 1);
            let used = m.inputs.contains_key(&input);
            let linked = v.consumed.contains(&(index, k));
            if used != linked {
                let message = if used {
                    format!(
                        "{input} is used but DecOut{} is not linked to anything",
                        k + 1
                    )
                } else {
                    format!("DecOut{} is linked but {input} is not used", k + 1)
                };
                v.err(
                    Rule::Dangling,
                    Item::Module {
                        index,
                        name: m.name.clone(),
                    },
                    message,
                );
            }
        }
    }

    if !v.errors.is_empty() {
        return Err(v.errors);
    }
    Ok(Compiled {
        name: p.logic.name.clone(),
        address: p.logic.address,
        slots: v.next_slot,
        standard_inputs: v.standard_inputs.into_iter().collect(),
        groups,
        connections,
        modules,
        local_outputs,
        standard_outputs,
    })
}

/// A module output driving a group-owned output (local output, TwinSAFE-Out) must come from a
/// module of that group.
fn check_source_group(v: &mut Verifier<'_>, source: &SignalRef, group: Option<usize>, item: &Item) {
    let source_group = match source {
        SignalRef::FbOut { module, .. } => v
            .modules
            .get(module.as_str())
            .and_then(|&m| v.groups.get(v.p.modules[m].group.as_str()).copied()),
        SignalRef::Group { group, .. } => v.groups.get(group.as_str()).copied(),
        _ => None,
    };
    if let (Some(g), Some(sg)) = (group, source_group) {
        if g != sg {
            v.err(
                Rule::OneGroup,
                item.clone(),
                format!(
                    "`{source}` is in group `{}`, but this output belongs to group `{}`",
                    v.p.groups[sg].name, v.p.groups[g].name
                ),
            );
        }
    }
}

fn compile_module(v: &mut Verifier<'_>, index: usize, m: &ModuleDesc) -> CompiledModule {
    let item = Item::Module {
        index,
        name: m.name.clone(),
    };
    let param = |param| Item::ModuleParam {
        index,
        name: m.name.clone(),
        param,
    };
    let group = v.group_of(&m.group, item.clone());
    let specs = input_specs(m.kind);

    // Unknown inputs and parameters.
    for input in m.inputs.keys() {
        if !specs.iter().any(|s| &s.name == input) {
            let names: Vec<&str> = specs.iter().map(|s| s.name.as_str()).collect();
            v.err(
                Rule::Dangling,
                Item::ModuleInput {
                    index,
                    name: m.name.clone(),
                    input: input.clone(),
                },
                format!(
                    "{} has no input `{input}` (it has {})",
                    m.kind,
                    names.join(", ")
                ),
            );
        }
    }
    let allowed = allowed_params(m.kind);
    for p in params_set(m) {
        if !allowed.contains(&p) {
            v.err(
                Rule::Parameter,
                param(p),
                format!("{} has no parameter `{p}`", m.kind),
            );
        }
    }

    // Inputs.
    let mut inputs = Vec::with_capacity(specs.len());
    for spec in &specs {
        let Some(desc) = m.inputs.get(&spec.name) else {
            inputs.push(None);
            continue;
        };
        let iitem = Item::ModuleInput {
            index,
            name: m.name.clone(),
            input: spec.name.clone(),
        };
        if desc.contact.is_some() && !spec.contact {
            v.err(
                Rule::Parameter,
                iitem.clone(),
                format!("{} has no contact type (break/make) setting", spec.name),
            );
        }
        let what = format!("{} of {}", spec.name, m.kind);
        let slot = v.resolve(&desc.signal, spec.kinds, group, &iitem, &what);
        inputs.push(slot.map(|s| (s, desc.contact.unwrap_or_default())));
    }
    let linked = |name: &str| m.inputs.contains_key(name);
    let contact = |name: &str| m.inputs.get(name).map(|d| d.contact.unwrap_or_default());
    let count =
        |prefix: &str, n: usize| (1..=n).filter(|k| linked(&format!("{prefix}{k}"))).count();

    let require = |v: &mut Verifier<'_>, ok: bool, message: String| {
        if !ok {
            v.err(Rule::Dangling, item.clone(), message);
        }
    };
    let pairs = |v: &mut Verifier<'_>, prefix: &str, n: usize| -> Vec<SimDuration> {
        let times = m.pair_discrepancy.clone().unwrap_or_default();
        if times.len() > n {
            v.err(
                Rule::Parameter,
                param("pair_discrepancy"),
                format!(
                    "{} has {n} input pairs, {} discrepancy times given",
                    m.kind,
                    times.len()
                ),
            );
        }
        let mut out = vec![SimDuration::ZERO; n];
        for (k, t) in times.into_iter().take(n).enumerate() {
            out[k] = t;
            let (a, b) = (
                format!("{prefix}{}", 2 * k + 1),
                format!("{prefix}{}", 2 * k + 2),
            );
            let both = linked(&a) && linked(&b);
            if !t.is_zero() && !both {
                v.err(
                    Rule::Dangling,
                    item.clone(),
                    format!(
                        "pair {a}/{b} has a discrepancy time of {t}, so both inputs must be linked"
                    ),
                );
            }
        }
        out
    };

    let config = match m.kind {
        ModuleKind::And => {
            require(
                v,
                count("AndIn", 8) >= 2,
                "AND needs at least two inputs (seed 004 §4.1.1)".into(),
            );
            ModuleConfig::And
        }
        ModuleKind::Or => {
            require(
                v,
                count("OrIn", 8) >= 1,
                "OR needs at least one input".into(),
            );
            ModuleConfig::Or
        }
        ModuleKind::OpMode => {
            require(
                v,
                count("OpIn", 8) >= 2,
                "OPMODE needs at least two inputs (EL6900 FB_MODE)".into(),
            );
            ModuleConfig::OpMode(OpModeConfig {
                inputs: core::array::from_fn(|k| linked(&format!("OpIn{}", k + 1))),
                restart: linked("Restart"),
                discrepancy: m.discrepancy.unwrap_or_default(),
            })
        }
        ModuleKind::Estop => {
            require(
                v,
                count("EStopIn", 8) >= 1,
                "ESTOP needs at least one EStopIn input".into(),
            );
            require(
                v,
                linked("Restart"),
                "Restart is not linked; ESTOP leaves the safe state only by a 0→1→0 Restart pulse (seed 004 table 4-10)".into(),
            );
            let discrepancy = pairs(v, "EStopIn", 4);
            ModuleConfig::Estop(EstopConfig {
                inputs: core::array::from_fn(|k| contact(&format!("EStopIn{}", k + 1))),
                discrepancy: core::array::from_fn(|k| discrepancy[k]),
                edm1: linked("EDM1"),
                edm2: linked("EDM2"),
                delay: m.delay.unwrap_or_default(),
            })
        }
        ModuleKind::Mon => {
            let manual = m.manual_restart.unwrap_or(false);
            require(
                v,
                count("MonIn", 4) >= 1,
                "MON needs at least one MonIn input".into(),
            );
            if manual && !linked("Restart") {
                v.err(
                    Rule::Dangling,
                    item.clone(),
                    "manual restart is on but Restart is not linked".into(),
                );
            }
            if !manual && linked("Restart") {
                v.err(
                    Rule::Parameter,
                    param("manual_restart"),
                    "Restart is linked but manual restart is off; for automatic restart remove the Restart link".into(),
                );
            }
            let secure = match (contact("Secure1"), contact("Secure2")) {
                (None, None) => None,
                (Some(a), Some(b)) if a == b => Some(a),
                (Some(_), Some(_)) => {
                    v.err(
                        Rule::Parameter,
                        item.clone(),
                        "Secure1 and Secure2 form a pair and must have the same contact type"
                            .into(),
                    );
                    None
                }
                _ => {
                    v.err(
                        Rule::Dangling,
                        item.clone(),
                        "Secure1 and Secure2 form a pair: link both or neither".into(),
                    );
                    None
                }
            };
            let discrepancy = pairs(v, "MonIn", 2);
            ModuleConfig::Mon(MonConfig {
                inputs: core::array::from_fn(|k| contact(&format!("MonIn{}", k + 1))),
                discrepancy: [discrepancy[0], discrepancy[1]],
                secure,
                secure_discrepancy: m.secure_discrepancy.unwrap_or_default(),
                manual_restart: manual,
                function_test: m.function_test.unwrap_or(false),
                edm1: linked("EDM1"),
                edm2: linked("EDM2"),
                delay: m.delay.unwrap_or_default(),
            })
        }
        ModuleKind::Decouple => ModuleConfig::Decouple,
    };

    let outs = output_specs(m.kind);
    CompiledModule {
        name: m.name.clone(),
        kind: m.kind,
        group: group.unwrap_or_default(),
        inputs,
        outputs: v.module_outputs[index].clone(),
        safety_outputs: outs.iter().map(|(_, s)| *s).collect(),
        config,
    }
}
