//! The stateless modules AND, OR (seed 004 §4.1, §4.2) and DECOUPLE (§4.6).

use crate::kl6904::signal::Contact;

/// AND: every activated input, after its contact type, must be 1. Inputs not activated are
/// neutral (docs/safety-logic.md §1.5 INFER). No error output, no discrepancy check.
///
/// `inputs` pairs each activated input's contact type with its raw value.
pub fn and(inputs: impl IntoIterator<Item = (Contact, bool)>) -> bool {
    inputs.into_iter().all(|(c, v)| c.normalise(v))
}

/// OR: at least one activated input, after its contact type, is 1. Inputs not activated count
/// as 0.
pub fn or(inputs: impl IntoIterator<Item = (Contact, bool)>) -> bool {
    inputs.into_iter().any(|(c, v)| c.normalise(v))
}

/// DECOUPLE: DecIn*n* → DecOut*n*, one to one. Its point is the group boundary: the outputs
/// are switched off with the module's own group (docs/safety-logic.md §1.7), which the logic
/// does for every module output.
pub fn decouple(inputs: [bool; 8]) -> [bool; 8] {
    inputs
}

#[cfg(test)]
mod tests {
    use super::*;
    use Contact::{Break, Make};

    #[test]
    fn and_inverts_make_contacts_and_needs_all() {
        assert!(and([(Break, true), (Make, false)]));
        assert!(
            !and([(Break, true), (Make, true)]),
            "overloaded on a make AndIn1"
        );
        assert!(!and([(Break, false), (Break, true)]));
    }

    #[test]
    fn or_needs_one() {
        assert!(or([(Break, false), (Make, false)]));
        assert!(!or([(Break, false), (Make, true)]));
        assert!(!or(core::iter::empty()));
    }
}
