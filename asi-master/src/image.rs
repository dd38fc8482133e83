//! The host interface: input and output data images in the word layout of table 4.1 of the lift
//! thesis (Bihl+Wiedemann BWU1488 master; docs/master.md "Input data image").
//!
//! | words | content |
//! |---|---|
//! | 0..15 | network 1: word 0 = flags F3..F0 (bits 15..12), then slaves 1, 2, 3 (a nibble each, D3..D0 high to low); word 1 = slaves 4..7; ...; word 7 = 28..31 (A); words 8..15 the B slaves the same way (word 15 = 28B..31B) |
//! | 16..31 | network 2 (not used by the lab lift; always 0) |
//! | 32..49 | network 1 parameters: word 32 = command (bits 15..8), toggle T (bit 7), result (bits 6..0); words 33..49 = parameter bytes 1..34, the odd byte in the high half |
//! | 50..67 | network 2 parameters (unused) |
//! | 68..155 | network 1 analog values, slave 10..31, 4 channels each: word 68 + 4·(addr − 10) + (channel − 1) (the lift thesis' "81" for slave 10 channel 4 is the typo for 71) |
//! | 156..243 | network 2 analog values (unused) |
//!
//! Input flags (the notes of table 4.1 of the lift thesis): F0 ConfigError (1 = error), F1 APF
//! (1 = power fail), F2 PeripheryFault (1 = fault), F3 ConfigurationActive **inverted as the lift
//! thesis says** (0 = configuration mode active, 1 = not active, i.e. protected mode).
//!
//! The output image mirrors the layout: output nibbles at the same positions, the command
//! mailbox at 32..49, analog output values at 68..155. Output word 0 bits 15..12 carry the
//! host flags ([`crate::HostFlags`]); word 8 bits 15..12 (slot "0B") are reserved and stay 0.

use asi_phy::Nibble;
use asi_phy::SlaveAddr;

/// Number of words in each image (§4 of the lift thesis: 244 words for master revision 1.3 and
/// later).
pub const IMAGE_WORDS: usize = 244;
/// First word of network 1's parameter (mailbox) area.
pub const MAILBOX_WORD: usize = 32;
/// Number of parameter bytes after the mailbox command word (words 33..49).
pub const MAILBOX_BYTES: usize = 34;
/// First analog word of network 1 (slave 10, channel 1).
pub const ANALOG_BASE: usize = 68;
/// The lowest address with analog words.
pub const ANALOG_FIRST_SLAVE: u8 = 10;

/// Input flag F0, ConfigError, in word 0.
pub const F0_CONFIG_ERROR: u16 = 1 << 12;
/// Input flag F1, APF, in word 0.
pub const F1_APF: u16 = 1 << 13;
/// Input flag F2, PeripheryFault, in word 0.
pub const F2_PERIPHERY_FAULT: u16 = 1 << 14;
/// Input flag F3, ConfigurationActive, in word 0 (0 = configuration mode active).
pub const F3_CONFIGURATION_NOT_ACTIVE: u16 = 1 << 15;

/// Where a slave's nibble sits: the word and the bit shift of D0 (table 4.1 of the lift thesis).
///
/// Slave `n` is slot `n` of its half (slot 0 is the flag nibble), 4 slots per word with the
/// lowest slot in the highest bits: word = n / 4 (+ 8 for B), shift = 12 − 4·(n mod 4).
/// Address 0 has no nibble.
///
/// Both come straight from the list bit `i` = n (A) or 32 + n (B): word = i / 4 (32 / 4 = 8
/// words for B), shift = 4 · (3 − i mod 4).
pub const fn nibble_position(a: SlaveAddr) -> Option<(usize, u32)> {
    // A list bit is 0..=63; the mask changes nothing but lets the compiler see that the
    // word is in the image (no bounds check where the position is used).
    let i = (a.index() & 63) as usize;
    if i % 32 == 0 {
        return None;
    }
    Some((i / 4, (4 * (3 - i % 4)) as u32))
}

/// The analog word of slave `address` (10..=31), `channel` (1..=4): 68 + 4·(addr − 10) +
/// (channel − 1) (table 4.1 of the lift thesis).
pub const fn analog_word(address: u8, channel: u8) -> Option<usize> {
    if address < ANALOG_FIRST_SLAVE || address > 31 || channel < 1 || channel > 4 {
        return None;
    }
    Some(ANALOG_BASE + 4 * (address - ANALOG_FIRST_SLAVE) as usize + (channel - 1) as usize)
}

/// One data image: [`IMAGE_WORDS`] 16-bit words.
///
/// The image notes that it was written (any word, by any of its setters), so the master
/// reads the host flags and the mailbox out of the output image only after a write. A new
/// or cloned image counts as written; two images are equal when their words are.
#[derive(Eq)]
pub struct Image {
    words: [u16; IMAGE_WORDS],
    /// A word was written since the master last took this (see [`Image::take_written`]).
    written: bool,
}

impl Default for Image {
    fn default() -> Self {
        Image {
            words: [0; IMAGE_WORDS],
            written: true,
        }
    }
}

impl Clone for Image {
    fn clone(&self) -> Self {
        Image {
            words: self.words,
            written: true,
        }
    }
}

impl PartialEq for Image {
    fn eq(&self, other: &Self) -> bool {
        self.words == other.words
    }
}

impl core::fmt::Debug for Image {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Image[0..16: {:04X?}]", &self.words[..16])
    }
}

impl Image {
    /// Word `i`, or 0 past the end.
    pub fn word(&self, i: usize) -> u16 {
        self.words.get(i).copied().unwrap_or(0)
    }

    /// Sets word `i`; ignored past the end.
    pub fn set_word(&mut self, i: usize, v: u16) {
        self.written = true;
        if let Some(w) = self.words.get_mut(i) {
            *w = v;
        }
    }

    /// Whether a word was written since the last call (or since the image was made or
    /// cloned); the note is cleared.
    pub(crate) fn take_written(&mut self) -> bool {
        core::mem::replace(&mut self.written, false)
    }

    /// Counts the image as written (the master's state changed so that it must read it again).
    pub(crate) fn mark_written(&mut self) {
        self.written = true;
    }

    /// All words.
    pub fn words(&self) -> &[u16; IMAGE_WORDS] {
        &self.words
    }

    /// The nibble of slave `a` (0000 for address 0).
    pub fn nibble(&self, a: SlaveAddr) -> Nibble {
        match nibble_position(a) {
            Some((w, s)) => Nibble::from_low_bits((self.words[w] >> s) as u8),
            None => Nibble::ZERO,
        }
    }

    /// The nibble of the slave of list bit `i` (1..=31 A, 33..=63 B): [`Image::nibble`]
    /// without going through the address.
    pub(crate) fn nibble_of_bit(&self, i: usize) -> Nibble {
        debug_assert!(i < 64 && i % 32 != 0, "no slave nibble at list bit {i}");
        let i = i & 63;
        Nibble::from_low_bits((self.words[i / 4] >> (4 * (3 - i % 4))) as u8)
    }

    /// Sets the nibble of slave `a` (ignored for address 0).
    pub fn set_nibble(&mut self, a: SlaveAddr, v: Nibble) {
        self.written = true;
        if let Some((w, s)) = nibble_position(a) {
            let word = &mut self.words[w];
            *word = (*word & !(0xF << s)) | ((v.get() as u16) << s);
        }
    }

    /// The analog word of `address`, `channel` (0 for positions outside 10..=31, 1..=4).
    pub fn analog(&self, address: u8, channel: u8) -> u16 {
        analog_word(address, channel).map_or(0, |i| self.words[i])
    }

    /// The analog words of `address`, channels 1..=4: `analog` of each, read as one block
    /// (all 0 outside 10..=31).
    pub fn analog_channels(&self, address: u8) -> [u16; 4] {
        match analog_word(address, 1) {
            Some(i) => {
                let mut v = [0; 4];
                v.copy_from_slice(&self.words[i..i + 4]);
                v
            }
            None => [0; 4],
        }
    }

    /// Sets the analog word of `address`, `channel` (ignored outside 10..=31, 1..=4).
    pub fn set_analog(&mut self, address: u8, channel: u8, v: u16) {
        self.written = true;
        if let Some(i) = analog_word(address, channel) {
            self.words[i] = v;
        }
    }

    /// The flag nibble of word 0 (bits 15..12).
    pub fn flag_nibble(&self) -> Nibble {
        Nibble::from_low_bits((self.words[0] >> 12) as u8)
    }

    /// Sets the flag nibble of word 0 (bits 15..12).
    pub fn set_flag_nibble(&mut self, v: Nibble) {
        self.written = true;
        self.words[0] = (self.words[0] & 0x0FFF) | ((v.get() as u16) << 12);
    }

    /// Mailbox byte `k` (1..=34) of words 33..49: odd bytes in the high half; 0 outside.
    pub fn mailbox_byte(&self, k: usize) -> u8 {
        if !(1..=MAILBOX_BYTES).contains(&k) {
            return 0;
        }
        let w = self.words[MAILBOX_WORD + 1 + (k - 1) / 2];
        if k % 2 == 1 {
            (w >> 8) as u8
        } else {
            w as u8
        }
    }

    /// Sets mailbox byte `k` (1..=34); ignored outside.
    pub fn set_mailbox_byte(&mut self, k: usize, v: u8) {
        if !(1..=MAILBOX_BYTES).contains(&k) {
            return;
        }
        self.written = true;
        let w = &mut self.words[MAILBOX_WORD + 1 + (k - 1) / 2];
        *w = if k % 2 == 1 {
            (*w & 0x00FF) | ((v as u16) << 8)
        } else {
            (*w & 0xFF00) | v as u16
        };
    }
}

/// The two images of the host interface: inputs (master → PLC) and outputs (PLC → master).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ProcessImage {
    /// What the PLC reads: input nibbles, flags, mailbox results, analog inputs.
    pub input: Image,
    /// What the PLC writes: output nibbles, host flags, mailbox commands, analog outputs.
    pub output: Image,
}

#[cfg(test)]
mod tests {
    use super::*;
    use asi_phy::Select;

    fn a(n: u8) -> SlaveAddr {
        SlaveAddr::a(n).expect("address")
    }
    fn b(n: u8) -> SlaveAddr {
        SlaveAddr::b(n).expect("address")
    }

    /// Table 4.1 of the lift thesis, row by row: word 0 = flags, 1/1A, 2/2A, 3/3A; word 1 = 4..7;
    /// word 7 = 28..31; word 15 = 28B..31B.
    #[test]
    fn slave_nibbles_sit_where_table_4_1_puts_them() {
        assert_eq!(nibble_position(a(1)), Some((0, 8)));
        assert_eq!(nibble_position(a(2)), Some((0, 4)));
        assert_eq!(nibble_position(a(3)), Some((0, 0)));
        assert_eq!(nibble_position(a(4)), Some((1, 12)));
        assert_eq!(nibble_position(a(7)), Some((1, 0)));
        assert_eq!(nibble_position(a(28)), Some((7, 12)));
        assert_eq!(nibble_position(a(31)), Some((7, 0)));
        assert_eq!(nibble_position(b(1)), Some((8, 8)));
        assert_eq!(nibble_position(b(28)), Some((15, 12)));
        assert_eq!(nibble_position(b(31)), Some((15, 0)));
        assert_eq!(nibble_position(a(0)), None);
        // Every slave nibble of network 1 has its own 4 bits, none overlaps the flags.
        let mut used = [0u16; 16];
        used[0] = 0xF000;
        for i in 1..64u8 {
            if let Some(s) = SlaveAddr::from_index(i) {
                if let Some((w, sh)) = nibble_position(s) {
                    assert_eq!(used[w] & (0xF << sh), 0, "{s}");
                    used[w] |= 0xF << sh;
                }
            }
        }
        assert_eq!(&used[..8], &[0xFFFF; 8]);
        assert_eq!(used[8], 0x0FFF);
    }

    /// The position from the list bit is table 4.1's from the address and select: word
    /// n / 4, plus 8 for B, shift 12 − 4 · (n mod 4).
    #[test]
    fn nibble_positions_from_the_list_bit_are_the_tables() {
        for i in 0..64u8 {
            let Some(s) = SlaveAddr::from_index(i) else {
                continue;
            };
            let n = s.address.get() as usize;
            let base = match s.select {
                Select::A => 0,
                Select::B => 8,
            };
            let want = (n != 0).then(|| (base + n / 4, (12 - 4 * (n % 4)) as u32));
            assert_eq!(nibble_position(s), want, "{s}");
        }
    }

    /// The nibble read by list bit is the one read by address, for every slave.
    #[test]
    fn nibble_of_bit_is_the_slaves_nibble() {
        let mut img = Image::default();
        for (i, w) in img.words.iter_mut().enumerate() {
            *w = (i as u16).wrapping_mul(0x9E37) ^ 0x5A5A;
        }
        for i in (1..64u8).filter(|i| i % 32 != 0) {
            let s = SlaveAddr::from_index(i).expect("a slave's list bit");
            assert_eq!(img.nibble_of_bit(i as usize), img.nibble(s), "{s}");
        }
    }

    #[test]
    fn set_nibble_touches_only_its_bits() {
        let mut img = Image::default();
        img.set_nibble(a(2), Nibble::from_low_bits(0b1010));
        assert_eq!(img.word(0), 0b1010 << 4);
        img.set_nibble(a(1), Nibble::ALL);
        img.set_nibble(a(2), Nibble::ZERO);
        assert_eq!(img.word(0), 0x0F00);
        assert_eq!(img.nibble(a(1)), Nibble::ALL);
        img.set_flag_nibble(Nibble::from_low_bits(0b1001));
        assert_eq!(img.word(0), 0x9F00);
        assert_eq!(img.nibble(a(1)), Nibble::ALL);
    }

    #[test]
    fn flags_sit_in_word_0_bits_15_to_12() {
        assert_eq!(F0_CONFIG_ERROR, 0x1000);
        assert_eq!(F1_APF, 0x2000);
        assert_eq!(F2_PERIPHERY_FAULT, 0x4000);
        assert_eq!(F3_CONFIGURATION_NOT_ACTIVE, 0x8000);
    }

    /// Table 4.1 of the lift thesis: analog words of slaves 10..31 from word 68, four per slave,
    /// slave 31 channel 4 at word 155 (and slave 10 channel 4 at 71, not the lift thesis' typo 81).
    #[test]
    fn analog_words_of_slaves_10_to_31() {
        assert_eq!(analog_word(10, 1), Some(68));
        assert_eq!(analog_word(10, 2), Some(69));
        assert_eq!(analog_word(10, 3), Some(70));
        assert_eq!(analog_word(10, 4), Some(71));
        assert_eq!(analog_word(11, 1), Some(72));
        assert_eq!(analog_word(31, 4), Some(155));
        for addr in 10..=31u8 {
            for ch in 1..=4u8 {
                let w = analog_word(addr, ch).expect("in range");
                assert_eq!(w, 68 + 4 * (addr as usize - 10) + ch as usize - 1);
                assert!((68..=155).contains(&w));
            }
        }
        assert_eq!(analog_word(9, 1), None);
        assert_eq!(analog_word(10, 0), None);
        assert_eq!(analog_word(10, 5), None);
        assert_eq!(analog_word(32, 1), None);
    }

    /// The block read of a slave's four analog words is the four single reads.
    #[test]
    fn analog_channels_are_the_four_analog_words() {
        let mut img = Image::default();
        for (i, w) in img.words.iter_mut().enumerate() {
            *w = (i as u16).wrapping_mul(0x9E37) ^ 0x5A5A;
        }
        for address in 0..=40u8 {
            let want = [1, 2, 3, 4].map(|ch| img.analog(address, ch));
            assert_eq!(img.analog_channels(address), want, "slave {address}");
        }
    }

    #[test]
    fn mailbox_bytes_pair_into_words_33_to_49() {
        let mut img = Image::default();
        img.set_mailbox_byte(1, 0xAB);
        img.set_mailbox_byte(2, 0xCD);
        img.set_mailbox_byte(34, 0x11);
        img.set_mailbox_byte(35, 0x22);
        assert_eq!(img.word(33), 0xABCD);
        assert_eq!(img.word(49), 0x0011);
        assert_eq!(img.word(50), 0);
        assert_eq!(img.mailbox_byte(2), 0xCD);
        assert_eq!(img.mailbox_byte(0), 0);
    }
}
