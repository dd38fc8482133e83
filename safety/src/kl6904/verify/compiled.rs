//! The compiled form of a verified project, as the logic runs it.

use asi_phy::SimDuration;

use crate::kl6904::modules::{EstopConfig, MonConfig, OpModeConfig};
use crate::kl6904::project::ModuleKind;
use crate::kl6904::signal::Contact;

/// An index into the logic's signal image.
pub(crate) type Slot = usize;

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
