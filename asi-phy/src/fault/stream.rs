//! The fault injector's random stream: exactly the numbers of `ChaCha8Rng`, drawn cheaper.
//!
//! The noisy line draws four numbers a pulse and compares each with a threshold; through
//! `ChaCha8Rng` each draw pays for rand's general bookkeeping (index checks, putting a number
//! together from two words, the end of the buffer). [`FaultStream`] generates the same words
//! with the same generator (`ChaCha8Core`, four ChaCha blocks at a time, as `ChaCha8Rng` does)
//! into a buffer of its own, so that the injector can compare a whole run of numbers straight
//! out of it ([`FaultStream::all_miss`]), and draws everything else exactly as `ChaCha8Rng`
//! does: the same words in the same order, the same stream position.
//!
//! rand_chacha 0.9 keeps the generator's block counter private, so the stream cannot be set
//! to any position as `ChaCha8Rng::set_word_pos` can. It need not be: the injector only ever
//! goes back to where a run of draws began (a hit telegram is drawn again by `corrupt`), and
//! for that it keeps the generator as it was before it made the buffer, and makes the buffer
//! again from it.

use rand::rand_core::block::BlockRngCore;
use rand::{RngCore, SeedableRng};
use rand_chacha::{ChaCha8Core, ChaCha8Rng};
use std::fmt;

/// The buffer: four ChaCha blocks of 16 words, as `ChaCha8Rng` generates them at once.
type Words = <ChaCha8Core as BlockRngCore>::Results;
/// Words in the buffer.
const WORDS: usize = 64;
/// Blocks in the buffer.
const BLOCKS: u64 = 4;
/// A position in the stream, in words, is a 68-bit number: a 64-bit block counter and a word
/// of the block. It wraps there, as `ChaCha8Rng::get_word_pos` does.
const POSITION_MASK: u128 = (1 << 68) - 1;

/// `ChaCha8Rng`'s random stream with a buffer the fault injector can read directly.
///
/// Every draw takes the words `ChaCha8Rng` from the same seed takes, in the same order, with
/// the same result, and [`word_pos`](Self::word_pos) means what `get_word_pos` means there:
/// `next_u32` takes one word; `next_u64` takes two, the first as the low half (also across
/// the end of a buffer, as rand_core's `BlockRng` does); `fill_bytes` takes a word for every
/// four bytes or part of four, little-endian, and drops the unused bytes of a last partial
/// word.
#[derive(Clone)]
pub(crate) struct FaultStream {
    /// Blocks `block .. block + 4` of the stream, as `buf_core` generated them.
    buf: Words,
    /// The next word of `buf` to draw; `WORDS` when all are drawn.
    index: usize,
    /// The stream's block at the start of `buf` (the counter wraps at 2^64 blocks).
    block: u64,
    /// The generator, just past `buf`.
    core: ChaCha8Core,
    /// The generator as it was before it made `buf`: with it `buf` can be made again.
    buf_core: ChaCha8Core,
    /// The seed, for telling streams apart.
    seed: [u8; 32],
}

impl FaultStream {
    /// The stream of `ChaCha8Rng::seed_from_u64(seed)`.
    pub(crate) fn seed_from_u64(seed: u64) -> FaultStream {
        // The seed exactly as ChaCha8Rng makes it from a number; ChaCha8Rng::from_seed is
        // ChaCha8Core::from_seed behind a `BlockRng`.
        let seed = ChaCha8Rng::seed_from_u64(seed).get_seed();
        let core = ChaCha8Core::from_seed(seed);
        let mut stream = FaultStream {
            buf: Words::default(),
            index: 0,
            block: 0,
            buf_core: core.clone(),
            core,
            seed,
        };
        // The first buffer now, so that `buf_core` always made `buf` (`ChaCha8Rng` makes its
        // first on the first draw; the numbers are the same).
        stream.core.generate(&mut stream.buf);
        stream
    }

    /// The position in the stream, in words: `ChaCha8Rng::get_word_pos`.
    pub(crate) fn word_pos(&self) -> u128 {
        (u128::from(self.block) * 16 + self.index as u128) & POSITION_MASK
    }

    /// Goes back to word `index` of the buffer of the stream's blocks from `block`, which
    /// `core` generated: a place this stream was at before, with `buf_core` as it was then.
    fn go_back(&mut self, core: &ChaCha8Core, block: u64, index: usize) {
        if block != self.block {
            self.core.clone_from(core);
            self.buf_core.clone_from(core);
            self.core.generate(&mut self.buf);
            self.block = block;
        }
        self.index = index;
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
        // Where the call began, to go back to on a hit; the generator of that buffer is kept
        // only when a new buffer is made (most calls stay in one buffer).
        let (start_block, start_index) = (self.block, self.index);
        let mut start_core = None;
        while left > 0 {
            let room = WORDS.saturating_sub(self.index) / 8;
            if room == 0 {
                // The next group crosses the end of the buffer, or the buffer is drawn out.
                if start_core.is_none() {
                    start_core = Some(self.buf_core.clone());
                }
                if self.index >= WORDS {
                    // `next_u64` would make the next buffer here too.
                    self.refill();
                    continue;
                }
                let hit = (self.next_u64() < t[0])
                    | (self.next_u64() < t[1])
                    | (self.next_u64() < t[2])
                    | (self.next_u64() < t[3]);
                if hit {
                    self.back_to_start(start_core.as_ref(), start_block, start_index);
                    return false;
                }
                left -= 1;
                continue;
            }
            let n = room.min(left);
            let start = self.index;
            let hit = self.buf.as_ref()[start..start + 8 * n]
                .chunks_exact(8)
                .any(|g| {
                    (u64_of(g[0], g[1]) < t[0])
                        | (u64_of(g[2], g[3]) < t[1])
                        | (u64_of(g[4], g[5]) < t[2])
                        | (u64_of(g[6], g[7]) < t[3])
                });
            if hit {
                self.back_to_start(start_core.as_ref(), start_block, start_index);
                return false;
            }
            self.index = start + 8 * n;
            left -= n;
        }
        true
    }

    /// Goes back to where [`all_miss`](Self::all_miss) began: word `index` of the buffer from
    /// stream block `block`, made by `core` if the call has made a buffer since.
    fn back_to_start(&mut self, core: Option<&ChaCha8Core>, block: u64, index: usize) {
        match core {
            Some(core) => self.go_back(core, block, index),
            None => self.index = index,
        }
    }

    /// The next four blocks of the stream into the buffer.
    fn refill(&mut self) {
        self.buf_core.clone_from(&self.core);
        self.core.generate(&mut self.buf);
        self.block = self.block.wrapping_add(BLOCKS);
        self.index = 0;
    }

    /// The word at `index` of the buffer.
    #[inline(always)]
    fn word(&self, index: usize) -> u32 {
        self.buf.as_ref()[index]
    }
}

/// Two words of the stream as one number, the first the low half, as `BlockRng::next_u64`
/// puts them together.
#[inline(always)]
fn u64_of(low: u32, high: u32) -> u64 {
    (u64::from(high) << 32) | u64::from(low)
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
            u64_of(self.word(i), self.word(i + 1))
        } else if i >= WORDS {
            self.refill();
            self.index = 2;
            u64_of(self.word(0), self.word(1))
        } else {
            // The last word of this buffer is the low half, the first of the next the high.
            let low = self.word(WORDS - 1);
            self.refill();
            self.index = 1;
            u64_of(low, self.word(0))
        }
    }

    fn fill_bytes(&mut self, dst: &mut [u8]) {
        // A word for every four bytes; a last partial word is used up all the same.
        for chunk in dst.chunks_mut(4) {
            if self.index >= WORDS {
                self.refill();
            }
            let bytes = self.word(self.index).to_le_bytes();
            chunk.copy_from_slice(&bytes[..chunk.len()]);
            self.index += 1;
        }
    }
}

/// The same stream: the same seed and position (the stream number is always 0).
impl PartialEq for FaultStream {
    fn eq(&self, other: &FaultStream) -> bool {
        self.seed == other.seed && self.word_pos() == other.word_pos()
    }
}

impl Eq for FaultStream {}

/// The same stream as a `ChaCha8Rng`: the same seed, stream number and position, so the same
/// numbers from here on.
impl PartialEq<ChaCha8Rng> for FaultStream {
    fn eq(&self, other: &ChaCha8Rng) -> bool {
        self.seed == other.get_seed()
            && other.get_stream() == 0
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
        /// This many `next_u32`, to get anywhere in a buffer quickly.
        Skip(usize),
        /// Remember the place.
        Mark,
        /// Go back to the place last remembered.
        Back,
        /// `all_miss` with these thresholds and groups.
        AllMiss([u64; 4], u32),
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
            1 => (0..300usize).prop_map(Op::Skip),
            1 => Just(Op::Mark),
            1 => Just(Op::Back),
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
            let mut mark = None;
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
                    Op::Skip(n) => {
                        for _ in 0..n {
                            prop_assert_eq!(got.next_u32(), want.next_u32());
                        }
                    }
                    Op::Mark => {
                        mark = Some((got.buf_core.clone(), got.block, got.index, want.get_word_pos()));
                    }
                    Op::Back => {
                        if let Some((core, block, index, pos)) = &mark {
                            got.go_back(core, *block, *index);
                            want.set_word_pos(*pos);
                        }
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
