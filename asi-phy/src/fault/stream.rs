//! The fault injector's random stream: exactly the numbers of `ChaCha8Rng`, drawn cheaper.
//!
//! The noisy line draws four numbers a pulse and compares each with a threshold; through
//! `ChaCha8Rng` each draw pays for rand's general bookkeeping (index checks, putting a number
//! together from two words, the end of the buffer). [`FaultStream`] keeps the words of the
//! stream in a buffer of its own, so that the injector can compare a whole run of numbers
//! straight out of it ([`FaultStream::all_miss`]), and draws everything else exactly as
//! `ChaCha8Rng` does: the same words in the same order, the same stream position.
//!
//! The words come from a `ChaCha8Rng` a buffer at a time. Generating them with
//! `rand_chacha::ChaCha8Core` directly would save copying a buffer, but rand_chacha 0.9 keeps
//! the core's block counter private, and the injector must be able to go back in the stream
//! by any number of words (a hit telegram is drawn again by `corrupt`): only `ChaCha8Rng`'s
//! `set_word_pos` can do that.

use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::fmt;

/// Words in the buffer: as many as `ChaCha8Rng` generates at once (four ChaCha blocks).
const WORDS: usize = 64;
/// Words in a ChaCha block.
const BLOCK_WORDS: u128 = 16;
/// A position in the stream, in words, is a 68-bit number: a 64-bit block counter and a word
/// of the block. It wraps there, as `ChaCha8Rng::get_word_pos` does.
const POSITION_MASK: u128 = (1 << 68) - 1;

/// `ChaCha8Rng`'s random stream with a buffer the fault injector can read directly.
///
/// Every draw takes the words `ChaCha8Rng` from the same seed takes, in the same order, with
/// the same result, and [`word_pos`](Self::word_pos) / [`set_word_pos`](Self::set_word_pos)
/// mean what they mean there: `next_u32` takes one word; `next_u64` takes two, the first as
/// the low half (also across the end of a buffer, as rand_core's `BlockRng` does);
/// `fill_bytes` takes a word for every four bytes or part of four, little-endian, and drops the
/// unused bytes of a last partial word.
#[derive(Clone)]
pub(crate) struct FaultStream {
    /// The stream's words `[end - 64, end)` in little-endian bytes, where `end` is `source`'s
    /// word position: `source` is always just past the buffer.
    buf: [u8; 4 * WORDS],
    /// The next word of `buf` to draw; `WORDS` when all are drawn.
    index: usize,
    source: ChaCha8Rng,
}

impl FaultStream {
    /// The stream of `ChaCha8Rng::seed_from_u64(seed)`.
    pub(crate) fn seed_from_u64(seed: u64) -> FaultStream {
        FaultStream {
            buf: [0; 4 * WORDS],
            index: WORDS,
            source: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    /// The position in the stream, in words: `ChaCha8Rng::get_word_pos`.
    pub(crate) fn word_pos(&self) -> u128 {
        (self.source.get_word_pos() + self.index as u128).wrapping_sub(WORDS as u128)
            & POSITION_MASK
    }

    /// Goes to position `pos` (in words) in the stream: `ChaCha8Rng::set_word_pos`, which
    /// ignores the bits above the 68th.
    pub(crate) fn set_word_pos(&mut self, pos: u128) {
        // From the start of pos's block the source's own buffer is the next 64 words, so the
        // refill below copies them without generating again.
        self.source.set_word_pos(pos & !(BLOCK_WORDS - 1));
        self.refill();
        self.index = (pos % BLOCK_WORDS) as usize;
    }

    /// Goes back `words` words in the stream.
    fn rewind(&mut self, words: u128) {
        if words <= self.index as u128 {
            self.index -= words as usize;
        } else {
            self.set_word_pos(self.word_pos().wrapping_sub(words));
        }
    }

    /// Draws the next `groups` groups of four numbers (`next_u64` each) if every number is at
    /// or above its group place's threshold in `thresholds`, and returns `true`. If one is
    /// below, returns `false` with the stream where it was before the call.
    ///
    /// Where a group's eight words lie in the buffer, they are read straight from it; a group
    /// across the end of the buffer is drawn with `next_u64`, which takes care of that case.
    pub(crate) fn all_miss(&mut self, thresholds: &[u64; 4], groups: u32) -> bool {
        let t = thresholds;
        let mut left = groups as usize;
        // Words drawn by this call, to go back by on a hit.
        let mut drawn = 0u128;
        while left > 0 {
            if self.index >= WORDS {
                // `next_u64` would refill here too.
                self.refill();
            }
            let room = (WORDS - self.index) / 8;
            if room == 0 {
                let hit = (self.next_u64() < t[0])
                    | (self.next_u64() < t[1])
                    | (self.next_u64() < t[2])
                    | (self.next_u64() < t[3]);
                drawn += 8;
                left -= 1;
                if hit {
                    self.rewind(drawn);
                    return false;
                }
                continue;
            }
            let n = room.min(left);
            let start = 4 * self.index;
            for (k, g) in self.buf[start..start + 32 * n].chunks_exact(32).enumerate() {
                let hit = (u64_at(g, 0) < t[0])
                    | (u64_at(g, 8) < t[1])
                    | (u64_at(g, 16) < t[2])
                    | (u64_at(g, 24) < t[3]);
                if hit {
                    self.index += 8 * (k + 1);
                    self.rewind(drawn + 8 * (k as u128 + 1));
                    return false;
                }
            }
            self.index += 8 * n;
            drawn += 8 * n as u128;
            left -= n;
        }
        true
    }

    /// The next 64 words of the stream into the buffer.
    fn refill(&mut self) {
        self.source.fill_bytes(&mut self.buf);
        self.index = 0;
    }

    /// The word at `index` of the buffer (`index` < 64).
    #[inline(always)]
    fn word(&self, index: usize) -> u32 {
        u32::from_le_bytes(
            self.buf[4 * index..4 * index + 4]
                .try_into()
                .unwrap_or_default(),
        )
    }
}

/// The little-endian number of the eight bytes at `at` of `bytes`: two words of the stream,
/// the first the low half, as `BlockRng::next_u64` puts them together.
#[inline(always)]
fn u64_at(bytes: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap_or_default())
}

impl RngCore for FaultStream {
    #[inline]
    fn next_u32(&mut self) -> u32 {
        if self.index >= WORDS {
            self.refill();
        }
        let value = self.word(self.index);
        self.index += 1;
        value
    }

    #[inline]
    fn next_u64(&mut self) -> u64 {
        let i = self.index;
        if i < WORDS - 1 {
            self.index += 2;
            u64_at(&self.buf, 4 * i)
        } else if i >= WORDS {
            self.refill();
            self.index = 2;
            u64_at(&self.buf, 0)
        } else {
            // The last word of this buffer is the low half, the first of the next the high.
            let low = self.word(WORDS - 1);
            self.refill();
            self.index = 1;
            (u64::from(self.word(0)) << 32) | u64::from(low)
        }
    }

    fn fill_bytes(&mut self, dst: &mut [u8]) {
        let mut filled = 0;
        while filled < dst.len() {
            if self.index >= WORDS {
                self.refill();
            }
            let from = &self.buf[4 * self.index..];
            let n = from.len().min(dst.len() - filled);
            dst[filled..filled + n].copy_from_slice(&from[..n]);
            // A partial word is used up all the same.
            self.index += n.div_ceil(4);
            filled += n;
        }
    }
}

/// The same stream: the same seed and position (the stream number is always 0).
impl PartialEq for FaultStream {
    fn eq(&self, other: &FaultStream) -> bool {
        self.source.get_seed() == other.source.get_seed()
            && self.source.get_stream() == other.source.get_stream()
            && self.word_pos() == other.word_pos()
    }
}

impl Eq for FaultStream {}

/// The same stream as a `ChaCha8Rng`: the same seed, stream number and position, so the same
/// numbers from here on.
impl PartialEq<ChaCha8Rng> for FaultStream {
    fn eq(&self, other: &ChaCha8Rng) -> bool {
        self.source.get_seed() == other.get_seed()
            && self.source.get_stream() == other.get_stream()
            && self.word_pos() == other.get_word_pos()
    }
}

// Not the buffer: the numbers to come are nobody's business in a log.
impl fmt::Debug for FaultStream {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FaultStream")
            .field("word_pos", &self.word_pos())
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::{any, prop_assert_eq, prop_oneof, proptest, Just, ProptestConfig};
    use proptest::strategy::Strategy;

    /// One thing to do to both streams.
    #[derive(Clone, Debug)]
    enum Op {
        U32,
        U64,
        /// `fill_bytes` with this many bytes.
        Fill(usize),
        /// `set_word_pos`.
        Seek(u128),
        /// Back by this many words (at most the position).
        Back(u128),
        /// `all_miss` with these thresholds and groups.
        AllMiss([u64; 4], u32),
    }

    /// Positions that matter: the start, block and buffer ends and the words either side of
    /// them (odd ones among them), the end of the 68-bit range, anything.
    fn position() -> impl Strategy<Value = u128> {
        prop_oneof![
            0..200u128,
            (0..1000u128, -2..=2i32).prop_map(|(b, d)| (16 * b).saturating_add_signed(d as i128)),
            (0..70u128).prop_map(|k| POSITION_MASK - k),
            any::<u64>().prop_map(u128::from),
            any::<u128>(),
        ]
    }

    /// A threshold: none ever hit, all hit, a real line's odds, any.
    fn threshold() -> impl Strategy<Value = u64> {
        prop_oneof![
            Just(0u64),
            Just(u64::MAX),
            Just(1u64 << 52),
            Just(1u64 << 60),
            any::<u64>(),
        ]
    }

    fn op() -> impl Strategy<Value = Op> {
        prop_oneof![
            4 => Just(Op::U32),
            4 => Just(Op::U64),
            // Lengths of every remainder mod 4, within a buffer and across several.
            2 => (0..20usize).prop_map(Op::Fill),
            1 => (0..700usize).prop_map(Op::Fill),
            1 => position().prop_map(Op::Seek),
            1 => (0..300u128).prop_map(Op::Back),
            3 => (proptest::array::uniform4(threshold()), 0..40u32)
                .prop_map(|(t, g)| Op::AllMiss(t, g)),
        ]
    }

    /// `all_miss` as `FaultInjector::pass_untouched` did it on `ChaCha8Rng`.
    fn all_miss_by_next_u64(rng: &mut ChaCha8Rng, t: &[u64; 4], groups: u32) -> bool {
        for k in 0..groups as u128 {
            let hit = (rng.next_u64() < t[0])
                | (rng.next_u64() < t[1])
                | (rng.next_u64() < t[2])
                | (rng.next_u64() < t[3]);
            if hit {
                let end = rng.get_word_pos();
                rng.set_word_pos(end.wrapping_sub(8 * (k + 1)));
                return false;
            }
        }
        true
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1024))]
        #[test]
        fn the_stream_draws_as_chacha8rng_does(
            seed in any::<u64>(),
            ops in proptest::collection::vec(op(), 0..120),
        ) {
            let mut got = FaultStream::seed_from_u64(seed);
            let mut want = ChaCha8Rng::seed_from_u64(seed);
            prop_assert_eq!(&got, &want);
            for op in ops {
                match op {
                    Op::U32 => prop_assert_eq!(got.next_u32(), want.next_u32()),
                    Op::U64 => prop_assert_eq!(got.next_u64(), want.next_u64()),
                    Op::Fill(n) => {
                        // Bytes past the end must stay as they were.
                        let mut a = vec![0xa5u8; n + 3];
                        let mut b = a.clone();
                        got.fill_bytes(&mut a[..n]);
                        want.fill_bytes(&mut b[..n]);
                        prop_assert_eq!(a, b);
                    }
                    Op::Seek(pos) => {
                        got.set_word_pos(pos);
                        want.set_word_pos(pos);
                    }
                    Op::Back(words) => {
                        let words = words.min(want.get_word_pos());
                        got.rewind(words);
                        want.set_word_pos(want.get_word_pos() - words);
                    }
                    Op::AllMiss(t, groups) => {
                        prop_assert_eq!(
                            got.all_miss(&t, groups),
                            all_miss_by_next_u64(&mut want, &t, groups)
                        );
                    }
                }
                prop_assert_eq!(got.word_pos(), want.get_word_pos());
                prop_assert_eq!(&got, &want);
            }
            let mut a = [0u8; 300];
            let mut b = [0u8; 300];
            got.fill_bytes(&mut a);
            want.fill_bytes(&mut b);
            prop_assert_eq!(a, b);
        }
    }

    /// Around the end of a buffer, at each word position: a `next_u64` at the last word of a
    /// buffer takes that word as the low half and the next buffer's first as the high one.
    #[test]
    fn next_u64_at_every_word_of_a_buffer_edge() {
        for skip in 0..2 * WORDS as u32 + 3 {
            let mut got = FaultStream::seed_from_u64(9);
            let mut want = ChaCha8Rng::seed_from_u64(9);
            for _ in 0..skip {
                assert_eq!(got.next_u32(), want.next_u32());
            }
            for _ in 0..70 {
                assert_eq!(got.next_u64(), want.next_u64(), "after {skip} words");
                assert_eq!(got, want);
            }
        }
    }
}
