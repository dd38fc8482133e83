//! The project verifier: the checks the TwinSAFE Verifier and the System Manager make before a
//! project is loaded into the KL6904 (the signal tables of §2, §3 and §4 of the KL6904 manual), and
//! the compiled form the logic runs.
//!
//! Every problem found is reported (not only the first), each with the [`Rule`] it breaks and
//! the [`Item`] it concerns.
//!
//! - this file: the verifier's state and what it resolves, and `verify()` in its steps;
//! - `error`: [`Rule`], [`Item`], [`PathStep`], [`VerifyError`];
//! - `specs`: each module kind's inputs, outputs and parameters;
//! - `steps`: the steps of `verify()`;
//! - `module`: one module's checks and compiled form;
//! - `compiled`: the compiled project the logic runs.

mod compiled;
pub(super) mod error;
mod module;
mod specs;
mod steps;

pub use compiled::LOCAL_OUTPUTS;
pub(crate) use compiled::{
    Compiled, CompiledGroup, CompiledLocalOutput, CompiledModule, ModuleConfig, Slot,
};
pub use error::{Item, PathStep, Rule, VerifyError};
pub(crate) use specs::{input_specs, output_specs};

use std::collections::{BTreeMap, BTreeSet};

use super::project::Project;
use super::signal::{ChannelRef, GroupOutput, SignalKind, SignalRef};

pub(super) fn is_name(s: &str) -> bool {
    !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

pub(super) struct Verifier<'p> {
    pub(super) p: &'p Project,
    pub(super) errors: Vec<VerifyError>,
    pub(super) groups: BTreeMap<&'p str, usize>,
    pub(super) connections: BTreeMap<&'p str, usize>,
    pub(super) modules: BTreeMap<&'p str, usize>,
    pub(super) next_slot: Slot,
    pub(super) standard_inputs: BTreeMap<String, Slot>,
    pub(super) conn_inputs: Vec<Vec<Slot>>,
    pub(super) module_outputs: Vec<Vec<Slot>>,
    pub(super) group_outputs: Vec<[Slot; 3]>,
    /// (module, output position) of every module output that something reads.
    pub(super) consumed: BTreeSet<(usize, usize)>,
}

impl<'p> Verifier<'p> {
    pub(super) fn err(&mut self, rule: Rule, item: Item, message: String) {
        self.errors.push(VerifyError {
            rule,
            item,
            message,
        });
    }

    pub(super) fn slot(&mut self) -> Slot {
        self.next_slot += 1;
        self.next_slot - 1
    }

    /// Index names; reports duplicates and malformed names.
    pub(super) fn index_names(
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
    pub(super) fn resolve(
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

    pub(super) fn group_of(&mut self, name: &str, item: Item) -> Option<usize> {
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
    v.index_all_names();
    v.check_addresses();
    v.allocate_slots();
    let groups = v.compile_groups();
    let connections = v.compile_connections();
    let modules = v.compile_modules();
    let local_outputs = v.compile_local_outputs();
    let standard_outputs = v.compile_standard_outputs();
    v.check_decouple();

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

impl Project {
    /// Check the project against every rule of the verifier ([`Rule`]); all problems are
    /// reported.
    pub fn verify(&self) -> Result<(), Vec<VerifyError>> {
        verify(self).map(|_| ())
    }
}
