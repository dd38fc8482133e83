//! The display word of seed 003 tables 4.2/4.4 is written by the PLC with asi-master's
//! encoder and read by the plant's displays with lift-model's decoder: the two must agree on
//! every word, and the displays must refuse a word with a broken parity.

use asi_phy::handshake_words::DisplayWord as Sent;
use lift_model::DisplayWord as Shown;

#[test]
fn every_word_the_plc_sends_is_shown_as_sent() {
    let mut n = 0;
    for floor in 1..=24u8 {
        for flags in 0..16u8 {
            let (up, down, moving, fault) = (
                flags & 8 != 0,
                flags & 4 != 0,
                flags & 2 != 0,
                flags & 1 != 0,
            );
            let sent = Sent::new(floor, up, down, moving, fault).expect("valid word");
            let shown = Shown::decode(sent.bits()).unwrap_or_else(|e| panic!("{sent:?}: {e}"));
            assert_eq!(
                (shown.floor, shown.up, shown.down, shown.moving, shown.fault),
                (floor, up, down, moving, fault),
                "{sent:?}"
            );
            // One flipped bit anywhere in D10..D1 is a parity error on the display.
            for bit in 0..10 {
                assert!(
                    Shown::decode(sent.bits() ^ (1 << bit)).is_err(),
                    "{sent:?} bit {bit}"
                );
            }
            n += 1;
        }
    }
    assert_eq!(n, 24 * 16);
}
