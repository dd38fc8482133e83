//! A TwinSAFE project as data: groups, connections, function modules and their wiring
//! (§3 of the KL6904 manual; docs/safety-logic.md §1), written as a TOML file or built in code.
//!
//! A file looks like this (the lift's project is `safety/projects/lift.toml`):
//!
//! ```toml
//! [logic]
//! name = "example"
//! address = 1                      # the KL6904's TwinSAFE address (DIP switch)
//!
//! [[group]]
//! name = "machine"
//! err_ack = "std:ack"              # RUN left out: unconnected = TRUE
//!
//! [[connection]]
//! name = "door"
//! group = "machine"
//! partner = "KL1904"
//! partner_address = 2
//! watchdog = "100ms"
//! channels = ["s1", "s2"]          # names of the partner's safe inputs 1, 2, ...
//!
//! [[module]]                       # modules run in file order
//! kind = "ESTOP"
//! name = "estop"
//! group = "machine"
//! delay = "500ms"
//! pair_discrepancy = ["50ms"]      # pair 1/2
//! inputs.EStopIn1 = "ts:door.s1"   # break contact unless { signal = .., contact = "make" }
//! inputs.EStopIn2 = "ts:door.s2"
//! inputs.Restart = "std:restart"
//!
//! [[local_output]]
//! index = 1
//! name = "K1"
//! group = "machine"
//! source = "fb:estop.EStopDelOut"
//! ```
//!
//! Nothing here is checked beyond the syntax; [`Project::verify`] applies the rules of the
//! vendor's verifier, and [`Project::from_toml`] does both, with the place of each problem.

use std::collections::BTreeMap;

use asi_phy::SimDuration;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::connection::PartnerKind;
use super::signal::{Contact, SignalRef};
use super::verify::error::{PathStep, VerifyError};

/// A whole project for one KL6904.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Project {
    /// The logic terminal itself.
    pub logic: LogicDesc,
    /// TwinSAFE groups.
    #[serde(default, rename = "group", skip_serializing_if = "Vec::is_empty")]
    pub groups: Vec<GroupDesc>,
    /// TwinSAFE connections to partner terminals.
    #[serde(default, rename = "connection", skip_serializing_if = "Vec::is_empty")]
    pub connections: Vec<ConnectionDesc>,
    /// Function modules, in execution order (§3 of the KL6904 manual: the order of the project
    /// tree).
    #[serde(default, rename = "module", skip_serializing_if = "Vec::is_empty")]
    pub modules: Vec<ModuleDesc>,
    /// The KL6904's own safe outputs (Local-Out 1..4).
    #[serde(
        default,
        rename = "local_output",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub local_outputs: Vec<LocalOutputDesc>,
    /// Standard PLC variables fed from the logic (Standard-Out).
    #[serde(
        default,
        rename = "standard_output",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub standard_outputs: Vec<StandardOutputDesc>,
}

/// The logic terminal.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LogicDesc {
    /// A name for logs.
    pub name: String,
    /// Its TwinSAFE address (DIP switch), unique in the control system.
    pub address: u16,
}

/// A TwinSAFE group (table 3-1 of the KL6904 manual).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroupDesc {
    /// The group's name.
    pub name: String,
    /// RUN (FB-Out or Standard-In); unconnected = TRUE.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub run: Option<SignalRef>,
    /// ERR_ACK (FB-Out or Standard-In); must be connected.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub err_ack: Option<SignalRef>,
}

/// A TwinSAFE connection to a partner terminal (§3.2 of the KL6904 manual).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConnectionDesc {
    /// The connection's name.
    pub name: String,
    /// The one group it belongs to.
    pub group: String,
    /// The partner device.
    pub partner: PartnerKind,
    /// The partner's TwinSAFE address.
    pub partner_address: u16,
    /// Watchdog time.
    #[serde(with = "duration")]
    pub watchdog: SimDuration,
    /// Names for the partner's safe inputs 1, 2, ... (referred to as `ts:<connection>.<name>`;
    /// channels may also be referred to by number).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<String>,
    /// The logic's TwinSAFE-Out channels to the partner.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub outputs: Vec<ConnectionOutputDesc>,
}

/// One TwinSAFE-Out channel of a connection.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConnectionOutputDesc {
    /// Channel number, 1-based.
    pub channel: u8,
    /// What drives it (an FB or group output).
    pub source: SignalRef,
}

/// The function module types of the KL6904 (§4 of the KL6904 manual).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ModuleKind {
    /// AND (§4.1).
    #[serde(rename = "AND")]
    And,
    /// OR (§4.2).
    #[serde(rename = "OR")]
    Or,
    /// OPMODE (§4.3).
    #[serde(rename = "OPMODE")]
    OpMode,
    /// ESTOP (§4.4).
    #[serde(rename = "ESTOP")]
    Estop,
    /// MON (§4.5).
    #[serde(rename = "MON")]
    Mon,
    /// DECOUPLE (§4.6).
    #[serde(rename = "DECOUPLE")]
    Decouple,
}

impl ModuleKind {
    /// The name as in the KL6904 manual, e.g. `ESTOP`.
    pub const fn name(self) -> &'static str {
        match self {
            ModuleKind::And => "AND",
            ModuleKind::Or => "OR",
            ModuleKind::OpMode => "OPMODE",
            ModuleKind::Estop => "ESTOP",
            ModuleKind::Mon => "MON",
            ModuleKind::Decouple => "DECOUPLE",
        }
    }
}

impl core::fmt::Display for ModuleKind {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// One function module with its parameters and input links. Parameters that do not belong to
/// the module's kind are rejected by the verifier.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModuleDesc {
    /// The module type.
    pub kind: ModuleKind,
    /// The module's name, unique in the project.
    pub name: String,
    /// Its group.
    pub group: String,
    /// Input name (e.g. `EStopIn1`, `Restart`, `EDM1`) → its source.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub inputs: BTreeMap<String, InputDesc>,
    /// ESTOP, MON: Delay Time of the delayed output.
    #[serde(
        default,
        with = "opt_duration",
        skip_serializing_if = "Option::is_none"
    )]
    pub delay: Option<SimDuration>,
    /// ESTOP (4 pairs), MON (2 pairs): discrepancy time per input pair; non-zero makes a pair.
    #[serde(
        default,
        with = "opt_durations",
        skip_serializing_if = "Option::is_none"
    )]
    pub pair_discrepancy: Option<Vec<SimDuration>>,
    /// MON: discrepancy time of Secure1/Secure2.
    #[serde(
        default,
        with = "opt_duration",
        skip_serializing_if = "Option::is_none"
    )]
    pub secure_discrepancy: Option<SimDuration>,
    /// OPMODE: discrepancy time of a mode change.
    #[serde(
        default,
        with = "opt_duration",
        skip_serializing_if = "Option::is_none"
    )]
    pub discrepancy: Option<SimDuration>,
    /// MON: manual restart ("Manual" checkbox).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub manual_restart: Option<bool>,
    /// MON: manual function test.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub function_test: Option<bool>,
}

/// What feeds a module input, and how it reads it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputDesc {
    /// The source.
    pub signal: SignalRef,
    /// The contact type, for inputs that have one (AND, OR, ESTOP, MON inputs); `None` = the
    /// default, break contact.
    pub contact: Option<Contact>,
}

impl From<SignalRef> for InputDesc {
    fn from(signal: SignalRef) -> Self {
        InputDesc {
            signal,
            contact: None,
        }
    }
}

impl Serialize for InputDesc {
    /// A bare string without a contact type, else `{ signal = .., contact = .. }`.
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Full<'a> {
            signal: &'a SignalRef,
            contact: Contact,
        }
        match self.contact {
            None => self.signal.serialize(s),
            Some(contact) => Full {
                signal: &self.signal,
                contact,
            }
            .serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for InputDesc {
    /// Accepts `"ts:door.s1"` or `{ signal = "ts:door.s1", contact = "make" }`.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Full {
            signal: SignalRef,
            #[serde(default)]
            contact: Option<Contact>,
        }
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = InputDesc;
            fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str("a signal such as \"ts:door.s1\" or a table { signal = .., contact = \"break\" | \"make\" }")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<InputDesc, E> {
                v.parse::<SignalRef>()
                    .map(InputDesc::from)
                    .map_err(E::custom)
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<InputDesc, A::Error> {
                let full = Full::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(InputDesc {
                    signal: full.signal,
                    contact: full.contact,
                })
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// A safe output of the KL6904 itself (Local-Out).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LocalOutputDesc {
    /// Terminal number 1..4.
    pub index: u8,
    /// A name for logs (e.g. the contactor it drives).
    pub name: String,
    /// The one group it belongs to.
    pub group: String,
    /// The module output that drives it.
    pub source: SignalRef,
}

/// A standard PLC variable written by the logic (Standard-Out).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StandardOutputDesc {
    /// The variable's name.
    pub name: String,
    /// The module or group output that drives it.
    pub source: SignalRef,
}

impl Project {
    /// An empty project for the logic `name` at TwinSAFE address `address`.
    pub fn new(name: &str, address: u16) -> Self {
        Project {
            logic: LogicDesc {
                name: name.to_owned(),
                address,
            },
            groups: Vec::new(),
            connections: Vec::new(),
            modules: Vec::new(),
            local_outputs: Vec::new(),
            standard_outputs: Vec::new(),
        }
    }

    /// Add a group with its ERR_ACK source (RUN unconnected).
    pub fn group(mut self, name: &str, err_ack: SignalRef) -> Self {
        self.groups.push(GroupDesc {
            name: name.to_owned(),
            run: None,
            err_ack: Some(err_ack),
        });
        self
    }

    /// Add a connection with named input channels.
    pub fn connection(
        mut self,
        name: &str,
        group: &str,
        partner: PartnerKind,
        partner_address: u16,
        watchdog: SimDuration,
        channels: &[&str],
    ) -> Self {
        self.connections.push(ConnectionDesc {
            name: name.to_owned(),
            group: group.to_owned(),
            partner,
            partner_address,
            watchdog,
            channels: channels.iter().map(|c| (*c).to_owned()).collect(),
            outputs: Vec::new(),
        });
        self
    }

    /// Append a module (execution order = order of appending).
    pub fn module(mut self, module: ModuleDesc) -> Self {
        self.modules.push(module);
        self
    }

    /// Add a local output driven by `source`.
    pub fn local_output(mut self, index: u8, name: &str, group: &str, source: SignalRef) -> Self {
        self.local_outputs.push(LocalOutputDesc {
            index,
            name: name.to_owned(),
            group: group.to_owned(),
            source,
        });
        self
    }

    /// Add a standard output driven by `source`.
    pub fn standard_output(mut self, name: &str, source: SignalRef) -> Self {
        self.standard_outputs.push(StandardOutputDesc {
            name: name.to_owned(),
            source,
        });
        self
    }

    /// Read a project file and verify it. `origin` names the file in messages. Every problem
    /// is reported with its line and column.
    pub fn from_toml(origin: &str, text: &str) -> Result<Project, ProjectError> {
        let project: Project = toml::from_str(text).map_err(|e| ProjectError::Syntax {
            origin: origin.to_owned(),
            place: e.span().map(|s| Place::of(text, s.start)),
            message: e.message().trim().to_owned(),
        })?;
        if let Err(errors) = project.verify() {
            let doc = toml::de::DeTable::parse(text).ok();
            let errors = errors
                .into_iter()
                .map(|error| {
                    let span = doc
                        .as_ref()
                        .and_then(|d| locate(d.get_ref(), &error.item.path()));
                    (span.map(|s| Place::of(text, s)), error)
                })
                .collect();
            return Err(ProjectError::Rejected {
                origin: origin.to_owned(),
                errors,
            });
        }
        Ok(project)
    }

    /// The project as TOML text (readable by [`Project::from_toml`]).
    pub fn to_toml(&self) -> Result<String, toml::ser::Error> {
        toml::to_string(self)
    }
}

impl ModuleDesc {
    /// A module of `kind` named `name` in `group`, without inputs or parameters.
    pub fn new(kind: ModuleKind, name: &str, group: &str) -> Self {
        ModuleDesc {
            kind,
            name: name.to_owned(),
            group: group.to_owned(),
            inputs: BTreeMap::new(),
            delay: None,
            pair_discrepancy: None,
            secure_discrepancy: None,
            discrepancy: None,
            manual_restart: None,
            function_test: None,
        }
    }

    /// Link input `input` to `signal` (break contact).
    pub fn input(mut self, input: &str, signal: SignalRef) -> Self {
        self.inputs.insert(input.to_owned(), signal.into());
        self
    }

    /// Link input `input` to `signal` with an explicit contact type.
    pub fn input_contact(mut self, input: &str, signal: SignalRef, contact: Contact) -> Self {
        self.inputs.insert(
            input.to_owned(),
            InputDesc {
                signal,
                contact: Some(contact),
            },
        );
        self
    }

    /// Set the Delay Time (ESTOP, MON).
    pub fn delay(mut self, delay: SimDuration) -> Self {
        self.delay = Some(delay);
        self
    }

    /// Set the discrepancy times of the input pairs (ESTOP, MON).
    pub fn pair_discrepancy(mut self, times: &[SimDuration]) -> Self {
        self.pair_discrepancy = Some(times.to_vec());
        self
    }

    /// Set the OPMODE discrepancy time.
    pub fn discrepancy(mut self, time: SimDuration) -> Self {
        self.discrepancy = Some(time);
        self
    }

    /// MON: manual restart.
    pub fn manual_restart(mut self, on: bool) -> Self {
        self.manual_restart = Some(on);
        self
    }
}

/// `SimDuration` as text such as `"50ms"` in a project file.
mod duration {
    use asi_phy::SimDuration;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(d: &SimDuration, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(d)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<SimDuration, D::Error> {
        let text = String::deserialize(d)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

mod opt_duration {
    use asi_phy::SimDuration;
    use serde::{Deserializer, Serializer};

    pub fn serialize<S: Serializer>(d: &Option<SimDuration>, s: S) -> Result<S::Ok, S::Error> {
        match d {
            Some(d) => super::duration::serialize(d, s),
            None => s.serialize_none(),
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<SimDuration>, D::Error> {
        super::duration::deserialize(d).map(Some)
    }
}

mod opt_durations {
    use asi_phy::SimDuration;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(d: &Option<Vec<SimDuration>>, s: S) -> Result<S::Ok, S::Error> {
        match d {
            Some(v) => s.collect_seq(v.iter().map(|d| d.to_string())),
            None => s.serialize_none(),
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Option<Vec<SimDuration>>, D::Error> {
        let texts = Vec::<String>::deserialize(d)?;
        texts
            .iter()
            .map(|t| t.parse().map_err(serde::de::Error::custom))
            .collect::<Result<_, _>>()
            .map(Some)
    }
}

/// A place in a project file (1-based line and column).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Place {
    /// Line, from 1.
    pub line: usize,
    /// Column in characters, from 1.
    pub column: usize,
}

impl Place {
    /// The place of byte offset `offset` in `text`.
    pub fn of(text: &str, offset: usize) -> Place {
        let before = text.get(..offset).unwrap_or(text);
        let line_start = before.rfind('\n').map_or(0, |k| k + 1);
        Place {
            line: before.matches('\n').count() + 1,
            column: before[line_start..].chars().count() + 1,
        }
    }
}

impl core::fmt::Display for Place {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}:{}", self.line, self.column)
    }
}

/// Why a project file cannot run.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ProjectError {
    /// The text is not TOML, or not shaped like a project (unknown key, wrong type, bad signal
    /// or duration text).
    #[error("{origin}:{}: {message}", place.map_or_else(|| "?".to_owned(), |p| p.to_string()))]
    Syntax {
        /// The file.
        origin: String,
        /// Where, if known.
        place: Option<Place>,
        /// What is wrong.
        message: String,
    },
    /// The verifier rejected the project.
    #[error("{}", rejected(origin, errors))]
    Rejected {
        /// The file.
        origin: String,
        /// Each problem with its place in the file.
        errors: Vec<(Option<Place>, VerifyError)>,
    },
}

fn rejected(origin: &str, errors: &[(Option<Place>, VerifyError)]) -> String {
    let mut s = format!(
        "{origin}: the verifier rejected the project ({} problem{}):",
        errors.len(),
        if errors.len() == 1 { "" } else { "s" }
    );
    for (place, e) in errors {
        let at = place.map_or_else(String::new, |p| format!(":{p}"));
        s.push_str(&format!("\n  {origin}{at}: {e}"));
    }
    s
}

/// The start of the deepest part of `path` found in the parsed file.
fn locate(table: &toml::de::DeTable<'_>, path: &[PathStep]) -> Option<usize> {
    use toml::de::DeValue;
    let mut here: Option<&DeValue<'_>> = None;
    let mut found = None;
    for step in path {
        let next = match (step, here) {
            (PathStep::Key(k), None) => table
                .iter()
                .find(|(key, _)| key.get_ref() == k)
                .map(|(_, v)| v),
            (PathStep::Key(k), Some(DeValue::Table(t))) => {
                t.iter().find(|(key, _)| key.get_ref() == k).map(|(_, v)| v)
            }
            (PathStep::Index(i), Some(DeValue::Array(a))) => a.get(*i),
            _ => None,
        };
        let Some(v) = next else { break };
        found = Some(v.span().start);
        here = Some(v.get_ref());
    }
    found
}
