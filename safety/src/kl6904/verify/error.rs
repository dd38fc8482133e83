//! What the verifier reports: the [`Rule`] broken, the [`Item`] it concerns (with its path in
//! the project file), and the message.

use core::fmt;

/// The verifier's rules.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Rule {
    /// Names of groups, connections, modules, channels and outputs are unique and well formed.
    UniqueName,
    /// Every connection, module and local output belongs to one existing group, and a connection's
    /// I/O and a local output are used only by modules of their group (§3, §3.1 of the KL6904
    /// manual).
    OneGroup,
    /// Every output (local output, standard output, TwinSAFE-Out channel) is driven exactly once.
    DrivenOnce,
    /// Only the signal kinds the KL6904 manual's tables allow are linked to each input and output
    /// (e.g. a standard signal only on AndIn1, table 4-1 of the KL6904 manual).
    SignalKind,
    /// TwinSAFE addresses are unique and not 0 (§3.2 of the KL6904 manual).
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
