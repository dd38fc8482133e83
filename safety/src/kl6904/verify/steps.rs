//! The steps of [`verify`](super::verify), in the order it takes them: names, addresses,
//! signal slots, groups, connections, modules, local and standard outputs, DECOUPLE links.

use std::collections::{BTreeMap, BTreeSet};

use super::compiled::{
    CompiledConnection, CompiledGroup, CompiledLocalOutput, CompiledModule, Slot, LOCAL_OUTPUTS,
};
use super::error::{Item, Rule};
use super::module::{check_source_group, compile_module};
use super::specs::{output_specs, GROUP_IN};
use super::{is_name, Verifier};
use crate::kl6904::project::ModuleKind;
use crate::kl6904::signal::{SignalKind, SignalRef};

impl<'p> Verifier<'p> {
    /// Names: unique and well formed, indexed for the steps that follow.
    pub(super) fn index_all_names(&mut self) {
        let p = self.p;
        self.groups = self.index_names(
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
        self.connections = self.index_names(
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
        self.modules = self.index_names(
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
    }

    /// Addresses: TwinSAFE addresses unique and not 0.
    pub(super) fn check_addresses(&mut self) {
        let p = self.p;
        let mut addresses: BTreeMap<u16, String> = BTreeMap::new();
        if p.logic.address == 0 {
            self.err(
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
                self.err(
                    Rule::UniqueAddress,
                    item,
                    "partner address 0 is not valid".into(),
                );
            } else if let Some(other) = addresses.get(&c.partner_address).cloned() {
                self.err(
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
    }

    /// Slots of everything that can be read: connection inputs, module and group outputs.
    pub(super) fn allocate_slots(&mut self) {
        let p = self.p;
        self.conn_inputs = p
            .connections
            .iter()
            .map(|c| (0..c.partner.inputs()).map(|_| 0).collect())
            .collect();
        for c in 0..self.conn_inputs.len() {
            for k in 0..self.conn_inputs[c].len() {
                self.conn_inputs[c][k] = self.slot();
            }
        }
        self.module_outputs = p
            .modules
            .iter()
            .map(|m| vec![0; output_specs(m.kind).len()])
            .collect();
        for m in 0..self.module_outputs.len() {
            for k in 0..self.module_outputs[m].len() {
                self.module_outputs[m][k] = self.slot();
            }
        }
        for _ in &p.groups {
            let slots = [self.slot(), self.slot(), self.slot()];
            self.group_outputs.push(slots);
        }
    }

    /// Groups: RUN and ERR_ACK resolved.
    pub(super) fn compile_groups(&mut self) -> Vec<CompiledGroup> {
        let p = self.p;
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
                .and_then(|s| self.resolve(s, GROUP_IN, None, &item("run"), "RUN"));
            let err_ack = match &g.err_ack {
                Some(s) => self.resolve(s, GROUP_IN, None, &item("err_ack"), "ERR_ACK"),
                None => {
                    self.err(
                        Rule::Dangling,
                        Item::Group { index, name: g.name.clone() },
                        "ERR_ACK is not connected; acknowledgement is never automatic, so it must be (the KL6904 manual, §3.1)".into(),
                    );
                    None
                }
            };
            groups.push(CompiledGroup {
                name: g.name.clone(),
                run,
                err_ack,
                outputs: self.group_outputs[index],
            });
        }
        groups
    }

    /// Connections: watchdog, channel names, TwinSAFE-Out channels.
    pub(super) fn compile_connections(&mut self) -> Vec<CompiledConnection> {
        let p = self.p;
        let mut connections = Vec::new();
        for (index, c) in p.connections.iter().enumerate() {
            let item = Item::Connection {
                index,
                name: c.name.clone(),
            };
            let group = self.group_of(&c.group, item.clone());
            if c.watchdog.is_zero() {
                self.err(
                    Rule::Parameter,
                    item.clone(),
                    "the watchdog time must not be 0".into(),
                );
            }
            if c.channels.len() > usize::from(c.partner.inputs()) {
                self.err(
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
                    self.err(
                        Rule::UniqueName,
                        item.clone(),
                        format!("`{ch}` is not a valid channel name"),
                    );
                } else if !seen.insert(ch) {
                    self.err(
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
                    self.err(
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
                    self.err(
                        Rule::DrivenOnce,
                        oitem.clone(),
                        format!("TwinSAFE-Out channel {} is driven twice", o.channel),
                    );
                }
                if let Some(slot) = self.resolve(
                    &o.source,
                    &[SignalKind::FbOut],
                    None,
                    &oitem,
                    "a TwinSAFE-Out",
                ) {
                    check_source_group(self, &o.source, group, &oitem);
                    outputs.push((o.channel, slot));
                }
            }
            connections.push(CompiledConnection {
                name: c.name.clone(),
                group: group.unwrap_or_default(),
                partner_address: c.partner_address,
                watchdog: c.watchdog,
                channel_names: c.channels.clone(),
                inputs: self.conn_inputs[index].clone(),
                outputs,
            });
        }
        connections
    }

    /// Modules, each by [`compile_module`].
    pub(super) fn compile_modules(&mut self) -> Vec<CompiledModule> {
        let p = self.p;
        let mut modules = Vec::new();
        for (index, m) in p.modules.iter().enumerate() {
            modules.push(compile_module(self, index, m));
        }
        modules
    }

    /// Local outputs: index in range, driven once, by a module of their group.
    pub(super) fn compile_local_outputs(&mut self) -> Vec<CompiledLocalOutput> {
        let p = self.p;
        let mut local_outputs = Vec::new();
        let mut driven: BTreeMap<u8, &str> = BTreeMap::new();
        for (index, o) in p.local_outputs.iter().enumerate() {
            let item = Item::LocalOutput {
                index,
                name: o.name.clone(),
            };
            let group = self.group_of(&o.group, item.clone());
            if o.index == 0 || o.index > LOCAL_OUTPUTS {
                self.err(
                    Rule::Dangling,
                    item.clone(),
                    format!(
                        "the KL6904 has local outputs 1..{LOCAL_OUTPUTS}, not {}",
                        o.index
                    ),
                );
            } else if let Some(other) = driven.insert(o.index, &o.name) {
                self.err(
                    Rule::DrivenOnce,
                    item.clone(),
                    format!("local output {} is already driven as `{other}`", o.index),
                );
            }
            if matches!(o.source, SignalRef::Group { .. }) {
                self.err(
                    Rule::SignalKind,
                    item.clone(),
                    format!("a Local-Out takes a module output, not the group output `{}` (the KL6904 manual, §2–§3)", o.source),
                );
                continue;
            }
            if let Some(source) =
                self.resolve(&o.source, &[SignalKind::FbOut], None, &item, "a Local-Out")
            {
                check_source_group(self, &o.source, group, &item);
                local_outputs.push(CompiledLocalOutput {
                    index: o.index,
                    name: o.name.clone(),
                    group: group.unwrap_or_default(),
                    source,
                });
            }
        }
        local_outputs
    }

    /// Standard outputs: well-formed names, driven once.
    pub(super) fn compile_standard_outputs(&mut self) -> Vec<(String, Slot)> {
        let p = self.p;
        let mut standard_outputs = Vec::new();
        let mut names = BTreeSet::new();
        for (index, o) in p.standard_outputs.iter().enumerate() {
            let item = Item::StandardOutput {
                index,
                name: o.name.clone(),
            };
            if !is_name(&o.name) {
                self.err(
                    Rule::UniqueName,
                    item.clone(),
                    format!("`{}` is not a valid variable name", o.name),
                );
            } else if !names.insert(o.name.as_str()) {
                self.err(
                    Rule::DrivenOnce,
                    item.clone(),
                    format!("standard output `{}` is driven twice", o.name),
                );
            }
            if let Some(source) = self.resolve(
                &o.source,
                &[SignalKind::FbOut],
                None,
                &item,
                "a Standard-Out",
            ) {
                standard_outputs.push((o.name.clone(), source));
            }
        }
        standard_outputs
    }

    /// DECOUPLE: an input used needs its output linked, and the other way round (§4.6 of the KL6904
    /// manual).
    pub(super) fn check_decouple(&mut self) {
        let p = self.p;
        for (index, m) in p.modules.iter().enumerate() {
            if m.kind != ModuleKind::Decouple {
                continue;
            }
            for k in 0..8 {
                let input = format!("DecIn{}", k + 1);
                let used = m.inputs.contains_key(&input);
                let linked = self.consumed.contains(&(index, k));
                if used != linked {
                    let message = if used {
                        format!(
                            "{input} is used but DecOut{} is not linked to anything",
                            k + 1
                        )
                    } else {
                        format!("DecOut{} is linked but {input} is not used", k + 1)
                    };
                    self.err(
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
    }
}
