//! The stateless modules AND, OR (§4.1, §4.2 of the KL6904 manual) and DECOUPLE (§4.6).

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

/// [`and`] with the inputs as masks, as the logic reads them: bit `k` of `inputs` is input
/// *k+1*'s raw value, of `linked` whether it is activated, of `make` whether it has a make
/// contact.
pub(crate) fn and_bits(inputs: u16, linked: u16, make: u16) -> bool {
    (inputs ^ make) & linked == linked
}

/// [`or`] with the inputs as masks, as for [`and_bits`].
pub(crate) fn or_bits(inputs: u16, linked: u16, make: u16) -> bool {
    (inputs ^ make) & linked != 0
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

    /// Every choice of 8 inputs' values, activation and contacts, as the masks give them and
    /// as the gates take them.
    #[test]
    fn the_gates_on_masks_are_the_gates() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let (inputs, linked, make) = (x as u8, (x >> 8) as u8, (x >> 16) as u8);
            let pairs = (0..8).filter(|k| linked & 1 << k != 0).map(|k| {
                let contact = if make & 1 << k != 0 { Make } else { Break };
                (contact, inputs & 1 << k != 0)
            });
            let (inputs, linked, make) = (inputs.into(), linked.into(), make.into());
            assert_eq!(and_bits(inputs, linked, make), and(pairs.clone()));
            assert_eq!(or_bits(inputs, linked, make), or(pairs));
        }
    }

    #[test]
    fn or_needs_one() {
        assert!(or([(Break, false), (Make, false)]));
        assert!(!or([(Break, false), (Make, true)]));
        assert!(!or(core::iter::empty()));
    }
}
