//! One module's checks and compiled form: its inputs, parameters and the group of the
//! outputs it drives.

use asi_phy::SimDuration;

use super::compiled::{CompiledModule, ModuleConfig};
use super::error::{Item, Rule};
use super::specs::{allowed_params, input_specs, output_specs, params_set};
use super::Verifier;
use crate::kl6904::modules::{EstopConfig, MonConfig, OpModeConfig};
use crate::kl6904::project::{ModuleDesc, ModuleKind};
use crate::kl6904::signal::SignalRef;

/// A module output driving a group-owned output (local output, TwinSAFE-Out) must come from a
/// module of that group.
pub(super) fn check_source_group(
    v: &mut Verifier<'_>,
    source: &SignalRef,
    group: Option<usize>,
    item: &Item,
) {
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

pub(super) fn compile_module(v: &mut Verifier<'_>, index: usize, m: &ModuleDesc) -> CompiledModule {
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
                "AND needs at least two inputs (the KL6904 manual, §4.1)".into(),
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
                "Restart is not linked; ESTOP leaves the safe state only by a 0→1→0 Restart pulse (the KL6904 manual, §4.4)".into(),
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
