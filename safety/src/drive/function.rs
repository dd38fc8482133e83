//! The safety functions, their active-low control bits and their status bits (§5.1 of the
//! SafeMOTION thesis, the inputs and outputs of the SafeMOTION function block).

use std::fmt;

/// A drive safety function (§3 of the SafeMOTION thesis; docs/drive-safety.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Function {
    /// Safe Torque Off: torque off at once, as long as requested (§3.1 of the SafeMOTION thesis).
    Sto,
    /// Safe Brake Control: the holding brake applied (§3 of the SafeMOTION thesis, SBC enable
    /// delay).
    Sbc,
    /// Safe Stop 1: a monitored stop, then torque off (§3.3 of the SafeMOTION thesis).
    Ss1,
    /// Safe Stop 2: a monitored stop, then standstill held with torque on (§3.4 of the SafeMOTION
    /// thesis).
    Ss2,
    /// Safe Operating Stop: standstill held with torque on (§3.2 of the SafeMOTION thesis).
    Sos,
    /// Safely Limited Speed, level 1..=4 (§3.5 of the SafeMOTION thesis).
    Sls(SlsLevel),
    /// Safely Limited Position: the position within [lower, upper] (§3.9 of the SafeMOTION thesis).
    Slp,
    /// Safe Direction, positive: no motion backwards beyond the position tolerance (§3.7 of the
    /// SafeMOTION thesis).
    SdiPos,
    /// Safe Direction, negative.
    SdiNeg,
    /// Safely Limited Increment: at most a given travel from the request's position (§3.6 of the
    /// SafeMOTION thesis).
    Sli,
    /// Safely Limited Acceleration: four limits, by direction (§3.8 of the SafeMOTION thesis).
    Sla,
    /// Safely Limited Torque: the drive's torque at most the limit, either way (§3.10 of the
    /// SafeMOTION thesis).
    Slt,
}

/// One of the four SLS levels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SlsLevel {
    /// SLS1.
    L1,
    /// SLS2.
    L2,
    /// SLS3.
    L3,
    /// SLS4.
    L4,
}

impl SlsLevel {
    /// The four levels in order.
    pub const ALL: [SlsLevel; 4] = [SlsLevel::L1, SlsLevel::L2, SlsLevel::L3, SlsLevel::L4];

    /// 0 for SLS1 … 3 for SLS4.
    pub const fn index(self) -> usize {
        match self {
            SlsLevel::L1 => 0,
            SlsLevel::L2 => 1,
            SlsLevel::L3 => 2,
            SlsLevel::L4 => 3,
        }
    }
}

impl Function {
    /// Every function, in the order of the status word.
    pub const ALL: [Function; 15] = [
        Function::Sto,
        Function::Sbc,
        Function::Ss1,
        Function::Ss2,
        Function::Sos,
        Function::Sls(SlsLevel::L1),
        Function::Sls(SlsLevel::L2),
        Function::Sls(SlsLevel::L3),
        Function::Sls(SlsLevel::L4),
        Function::Slp,
        Function::SdiPos,
        Function::SdiNeg,
        Function::Sli,
        Function::Sla,
        Function::Slt,
    ];

    /// The number of functions.
    pub const COUNT: usize = Function::ALL.len();

    /// The position in [`Function::ALL`].
    pub const fn index(self) -> usize {
        match self {
            Function::Sto => 0,
            Function::Sbc => 1,
            Function::Ss1 => 2,
            Function::Ss2 => 3,
            Function::Sos => 4,
            Function::Sls(l) => 5 + l.index(),
            Function::Slp => 9,
            Function::SdiPos => 10,
            Function::SdiNeg => 11,
            Function::Sli => 12,
            Function::Sla => 13,
            Function::Slt => 14,
        }
    }

    /// `true` for STO, SBC and SS1, the functions that work without a safe encoder
    /// (§1.1.2 of the SafeMOTION thesis: "without a suitable encoder only STO, SBC and SS1").
    pub const fn works_without_encoder(self) -> bool {
        matches!(self, Function::Sto | Function::Sbc | Function::Ss1)
    }

    /// `true` for SLP, which needs an absolute multi-turn encoder (the drive manual).
    pub const fn needs_absolute_position(self) -> bool {
        matches!(self, Function::Slp)
    }
}

impl fmt::Display for Function {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Function::Sto => f.write_str("STO"),
            Function::Sbc => f.write_str("SBC"),
            Function::Ss1 => f.write_str("SS1"),
            Function::Ss2 => f.write_str("SS2"),
            Function::Sos => f.write_str("SOS"),
            Function::Sls(l) => write!(f, "SLS{}", l.index() + 1),
            Function::Slp => f.write_str("SLP"),
            Function::SdiPos => f.write_str("SDI-P"),
            Function::SdiNeg => f.write_str("SDI-N"),
            Function::Sli => f.write_str("SLI"),
            Function::Sla => f.write_str("SLA"),
            Function::Slt => f.write_str("SLT"),
        }
    }
}

/// The control inputs of one scan (§5.1 of the SafeMOTION thesis).
///
/// The function bits are **active-low** (closed-circuit principle): a function is requested
/// while its bit is FALSE, so a broken wire or a lost telegram requests it. [`Default`] is
/// "running, nothing requested": Activate TRUE, every function bit TRUE, Reset FALSE.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ControlBits {
    /// S_Control_Activate: TRUE lets the drive run; FALSE keeps the torque off and every
    /// function inactive.
    pub activate: bool,
    /// S_Control_Reset: acknowledges an error on its rising edge, the only way out of it.
    pub reset: bool,
    /// `S_Control_<function>`, indexed by [`Function::index`]: FALSE = requested.
    pub function: [bool; Function::COUNT],
}

impl Default for ControlBits {
    fn default() -> Self {
        Self {
            activate: true,
            reset: false,
            function: [true; Function::COUNT],
        }
    }
}

impl ControlBits {
    /// Running, nothing requested (the same as [`Default`]).
    pub fn idle() -> Self {
        Self::default()
    }

    /// These bits with `f` requested (its bit FALSE).
    #[must_use]
    pub fn with_request(mut self, f: Function) -> Self {
        self.function[f.index()] = false;
        self
    }

    /// These bits with `f` no longer requested (its bit TRUE).
    #[must_use]
    pub fn without_request(mut self, f: Function) -> Self {
        self.function[f.index()] = true;
        self
    }

    /// These bits with S_Control_Reset at `reset`.
    #[must_use]
    pub fn with_reset(mut self, reset: bool) -> Self {
        self.reset = reset;
        self
    }

    /// `true` while `f` is requested (its bit is FALSE).
    pub fn requested(&self, f: Function) -> bool {
        !self.function[f.index()]
    }
}

/// The status outputs of one scan (§5.1 of the SafeMOTION thesis).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StatusBits {
    /// `S_Status_<function>`, indexed by [`Function::index`]: TRUE = the function is active and
    /// its safe state is reached; FALSE = inactive, not yet safe, or an error.
    pub function: [bool; Function::COUNT],
    /// S_Status_SDC: TRUE from a request until the function's safe state is reached.
    pub sdc: bool,
    /// S_Status_NotErrFunc: FALSE while an error (a violation) is latched.
    pub not_err_func: bool,
}

impl StatusBits {
    /// `S_Status_<f>`.
    pub fn of(&self, f: Function) -> bool {
        self.function[f.index()]
    }
}
