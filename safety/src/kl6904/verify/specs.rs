//! How each module's inputs may be linked, its outputs and parameters (the signal tables
//! of §4 of the KL6904 manual).

use crate::kl6904::project::{ModuleDesc, ModuleKind};
use crate::kl6904::signal::SignalKind;

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
pub(super) const GROUP_IN: &[SignalKind] = &[SignalKind::FbOut, SignalKind::StandardIn];

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

/// The inputs of a module kind, in a fixed order (tables 4-1, 4-4, 4-7, 4-10, 4-13
/// and 4-16 of the KL6904 manual).
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
/// group) or the Error output (tables 4-2, 4-5, 4-8, 4-11, 4-14, 4-17 of the KL6904 manual).
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
pub(super) fn allowed_params(kind: ModuleKind) -> &'static [&'static str] {
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
pub(super) fn params_set(m: &ModuleDesc) -> Vec<&'static str> {
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
