//! TwinSAFE groups (§3.1, tables 3-1 and 3-2 of the KL6904 manual; docs/safety-logic.md §1.2,
//! §6.1).

use core::fmt;

use crate::primitives::PulseDetector;

/// The state of a group (docs/safety-logic.md §6.1, the group states of the Beckhoff manual).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum GroupState {
    /// RUN = FALSE (or not yet started): all modules in STOP, all outputs safe.
    #[default]
    Stop,
    /// Everything in order: the modules run.
    Run,
    /// A module, connection or local output reported an error: all outputs of the group safe.
    Error,
    /// A rising edge of ERR_ACK was seen while no error cause is present; waiting for the
    /// falling edge, which acknowledges.
    Reset,
}

impl GroupState {
    /// Upper-case name.
    pub const fn name(self) -> &'static str {
        match self {
            GroupState::Stop => "STOP",
            GroupState::Run => "RUN",
            GroupState::Error => "ERROR",
            GroupState::Reset => "RESET",
        }
    }
}

impl fmt::Display for GroupState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Which error classes a group has latched: its outputs FB_ERR, COM_ERR, OUT_ERR (table 3-2 of the
/// KL6904 manual).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct GroupErrors {
    /// At least one module of the group has an error; FALSE means no module has one (the KL6904
    /// manual's Czech FALSE text, "all modules are faulty", is inverted: docs/source-errors.md).
    pub fb_err: bool,
    /// At least one connection of the group reports an error.
    pub com_err: bool,
    /// At least one local output of the group reports an error.
    pub out_err: bool,
}

impl GroupErrors {
    /// `true` if any class is set.
    pub const fn any(self) -> bool {
        self.fb_err || self.com_err || self.out_err
    }
}

impl fmt::Display for GroupErrors {
    /// The set outputs, e.g. `FB_ERR, COM_ERR`, or `none`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = [
            (self.fb_err, "FB_ERR"),
            (self.com_err, "COM_ERR"),
            (self.out_err, "OUT_ERR"),
        ]
        .into_iter()
        .filter_map(|(on, n)| on.then_some(n))
        .collect();
        if names.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&names.join(", "))
        }
    }
}

/// The group's state machine: RUN input, error latching and the ERR_ACK 0→1→0 acknowledgement.
///
/// - any error (module, connection, local output) puts the group in ERROR: all its outputs are
///   0 (the logic forces them);
/// - the safe state is released only when no error cause is present any more *and* ERR_ACK has gone
///   0→1→0 (§3.1 of the KL6904 manual): the rising edge, seen while no cause is present, enters
///   RESET; the falling edge acknowledges every error of the group at once (FB_ERR, COM_ERR and
///   OUT_ERR share the one ERR_ACK); if a cause returns in RESET, back to ERROR;
/// - acknowledgement is never automatic; an ERR_ACK held TRUE does nothing;
/// - RUN unconnected is TRUE (table 3-1); RUN = FALSE stops all modules.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Group {
    state: GroupState,
    errors: GroupErrors,
    ack: PulseDetector,
}

impl Group {
    /// A group in STOP.
    pub fn new() -> Self {
        Self::default()
    }

    /// The state.
    pub fn state(&self) -> GroupState {
        self.state
    }

    /// The latched error classes (the group outputs).
    pub fn errors(&self) -> GroupErrors {
        self.errors
    }

    /// `true` while the modules may run.
    pub fn running(&self) -> bool {
        self.state == GroupState::Run
    }

    /// Start of a scan: `errors` are the classes latched by its members, `cause_active` whether
    /// any of their causes is still present. Returns `true` when ERR_ACK acknowledges in this
    /// scan: the caller then clears every member's error and calls [`Group::acknowledged`].
    pub fn update(
        &mut self,
        run: bool,
        err_ack: bool,
        errors: GroupErrors,
        cause_active: bool,
    ) -> bool {
        self.errors = errors;
        let fired = self.ack.call(err_ack, errors.any() && !cause_active);
        if !errors.any() {
            self.state = if run {
                GroupState::Run
            } else {
                GroupState::Stop
            };
            return false;
        }
        if fired {
            return true;
        }
        self.state = if self.ack.is_armed() {
            GroupState::Reset
        } else {
            GroupState::Error
        };
        false
    }

    /// After the caller cleared the members' errors.
    pub fn acknowledged(&mut self, run: bool) {
        self.errors = GroupErrors::default();
        self.state = if run {
            GroupState::Run
        } else {
            GroupState::Stop
        };
    }

    /// `true` if a scan with these inputs (as for [`Group::update`]) and the same errors found
    /// again after the modules ([`Group::trip`]) leaves the group as it is and does not
    /// acknowledge: tried on a copy, so the answer is the scan's own.
    pub(crate) fn stays(
        &self,
        run: bool,
        err_ack: bool,
        errors: GroupErrors,
        cause_active: bool,
    ) -> bool {
        let mut g = self.clone();
        if g.update(run, err_ack, errors, cause_active) {
            return false;
        }
        g.trip(errors);
        g == *self
    }

    /// A member reported a new error during the scan: trip at once.
    pub fn trip(&mut self, errors: GroupErrors) {
        self.errors = errors;
        if errors.any() && self.state != GroupState::Reset {
            self.state = GroupState::Error;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const COM: GroupErrors = GroupErrors {
        fb_err: false,
        com_err: true,
        out_err: false,
    };

    #[test]
    fn run_unconnected_means_run() {
        let mut g = Group::new();
        assert!(!g.update(true, false, GroupErrors::default(), false));
        assert_eq!(g.state(), GroupState::Run);
        g.update(false, false, GroupErrors::default(), false);
        assert_eq!(g.state(), GroupState::Stop);
    }

    #[test]
    fn ack_needs_the_cause_gone_and_a_full_pulse() {
        let mut g = Group::new();
        g.update(true, false, GroupErrors::default(), false);
        g.trip(COM);
        assert_eq!(g.state(), GroupState::Error);
        // pulse while the cause is present: ignored
        assert!(!g.update(true, true, COM, true));
        assert!(!g.update(true, false, COM, false));
        assert_eq!(g.state(), GroupState::Error);
        // cause gone: rising edge enters RESET, falling edge acknowledges
        assert!(!g.update(true, true, COM, false));
        assert_eq!(g.state(), GroupState::Reset);
        assert!(!g.update(true, true, COM, false), "held: still waiting");
        assert!(g.update(true, false, COM, false));
        g.acknowledged(true);
        assert_eq!(g.state(), GroupState::Run);
    }

    #[test]
    fn cause_returning_in_reset_goes_back_to_error() {
        let mut g = Group::new();
        g.trip(COM);
        g.update(true, false, COM, false);
        g.update(true, true, COM, false);
        assert_eq!(g.state(), GroupState::Reset);
        assert!(!g.update(true, true, COM, true));
        assert_eq!(g.state(), GroupState::Error);
        assert!(
            !g.update(true, false, COM, false),
            "falling edge of a cancelled pulse"
        );
    }
}
