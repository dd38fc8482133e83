//! The engines of the lab lift's nibble handshakes (§4, tables 4.2–4.7 of the lift thesis;
//! docs/lab-bus.md), both sides, as plain state machines over 4-bit values with no dependency on
//! the bus.
//!
//! **Nibble use** (docs/lab-bus.md decision), two kinds of handshake:
//! - **The answerer owns K** (floor stations, table 4.3; cabin display, table 4.5; S-7.3 of
//!   `asi_master::integrated_analog` and `asi_slaves::analog_firmware`): the *requester* puts
//!   its 3-bit step code on D2..D0 (D3 = 0); the *answerer* puts 3 data bits on D2..D0 and
//!   the toggle bit K on D3. The answerer answers when it sees the requested code change,
//!   toggling K; a step completes when the requester sees K change; it then reads the data
//!   and puts out the next code ([`Requester`], [`Answerer`]).
//! - **The requester owns K** (cabin buttons, table 4.7: "K 1 1 1", "K 1 0 1", ...): the master
//!   puts K on D3 beside the step code on D2..D0 and toggles K with every request; the slave
//!   answers the 3 data bits on D2..D0 and, **Decision (docs/lab-bus.md, revised)**, echoes the K it
//!   answers to on D3. A step completes when the master sees its own K echoed
//!   ([`ToggleRequester`], [`EchoAnswerer`]).
//!
//! Every step is idempotent: a side may be stepped any number of times with the same input (a
//! PLC scan that is faster than the AS-i cycle, a repeated telegram, a lost response) without
//! advancing.
//!
//! **Decisions beyond the source documents**:
//! - Code `110` is used by no sequence of the lift thesis; in the handshakes where the answerer
//!   owns K it is the *sync* code. A requester starts (and restarts after a reset) with `110`; the
//!   answerer acknowledges it with K toggled and data 000. This makes the first K change a
//!   requester sees after power-up harmless. A requester that sees no K change for `stall_limit`
//!   steps switches code (to `110`, or from `110` to the first step), so that a requester and an
//!   answerer that lost step (for example one of them was reset while the other waited) always
//!   recover.
//! - Where the requester owns K there is no sync code (table 4.7 has none): the requester
//!   starts with the K that differs from the D3 it sees, the answerer refuses requests out of
//!   sequence, and a requester without an echo for `stall_limit` steps starts a new word with K
//!   toggled (see [`ToggleRequester`] and [`EchoAnswerer`]).
//!
//! The engines are generic over the step sequence; the floor (table 4.3: 4 steps), cabin
//! display (table 4.5: 7 steps, S-7.3 layout) and cabin panel (tables 4.6/4.7: 7 steps, two
//! halves) protocols, and the S-7.3 analog transfer, are built on them.
//! The engines and the words they carry ([`crate::handshake_words`]) are shared by both sides:
//! the master (PLC) side of each lab protocol is a `*Master` type of
//! `asi_master::plc_handshake` that the `controller` crate drives from the process image; the
//! device side is the `*Slave` type of `asi_slaves::device_handshake` inside the slave devices.

use crate::Nibble;

/// The sync code (used by no step sequence of the lift thesis).
pub const SYNC_CODE: u8 = 0b110;
/// Floor slave step codes, table 4.3 of the lift thesis: D10..D8, D7..D5, D4..D2, D1 O V.
pub const FOUR_STEPS: [u8; 4] = [0b111, 0b010, 0b001, 0b000];
/// Seven-step codes, tables 4.5 and 4.7 of the lift thesis (the S-7.3 layout of table 2.2).
pub const SEVEN_STEPS: [u8; 7] = [0b111, 0b101, 0b100, 0b011, 0b010, 0b001, 0b000];
/// Floor slave code between words: the up button is pressed (table 4.3).
pub const CODE_UP: u8 = 0b101;
/// Floor slave code between words: the down button is pressed (table 4.3).
pub const CODE_DOWN: u8 = 0b100;
/// Floor slave code between words: both buttons are pressed (table 4.3).
pub const CODE_BOTH: u8 = 0b011;
/// Default number of steps without progress after which a requester resynchronises.
pub const DEFAULT_STALL_LIMIT: u32 = 250;

/// What a requester step completed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RequesterEvent {
    /// A whole word: 3 bits per step, first step in the highest bits.
    Word(u32),
    /// An extra code between words was acknowledged (floor buttons).
    Extra(u8),
    /// The sync code was acknowledged.
    Synced,
}

/// The requesting side of a handshake: puts step codes out, collects the answers.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Requester {
    steps: &'static [u8],
    pos: usize,
    code: u8,
    k_ref: Option<bool>,
    acc: u32,
    extra: Option<u8>,
    stall: u32,
    stall_limit: u32,
}

impl Requester {
    /// A requester over `steps`, starting with the sync code.
    pub fn new(steps: &'static [u8]) -> Requester {
        Requester {
            steps,
            pos: 0,
            code: SYNC_CODE,
            k_ref: None,
            acc: 0,
            extra: None,
            stall: 0,
            stall_limit: DEFAULT_STALL_LIMIT,
        }
    }

    /// Sets the stall limit in steps (0 = never resynchronise).
    pub fn with_stall_limit(mut self, limit: u32) -> Requester {
        self.stall_limit = limit;
        self
    }

    /// Back to the power-up state (sync code, nothing collected).
    pub fn reset(&mut self) {
        let (steps, limit) = (self.steps, self.stall_limit);
        *self = Requester::new(steps).with_stall_limit(limit);
    }

    /// Queues a code to request after the current word (once). Codes of the sequence and the
    /// sync code are refused (`false`).
    pub fn queue_extra(&mut self, code: u8) -> bool {
        let code = code & 7;
        if code == SYNC_CODE || self.steps.contains(&code) {
            return false;
        }
        self.extra = Some(code);
        true
    }

    /// `true` while an extra code is queued or being requested.
    pub fn extra_pending(&self) -> bool {
        self.extra.is_some() || !(self.code == SYNC_CODE || self.steps.contains(&self.code))
    }

    /// The nibble this side puts out: D3 = 0, D2..D0 = the requested code.
    pub fn output(&self) -> Nibble {
        Nibble::from_low_bits(self.code)
    }

    /// The code currently requested.
    pub fn code(&self) -> u8 {
        self.code
    }

    /// One step with the answerer's nibble; returns the nibble to put out and what completed.
    ///
    /// Inlined into its callers: the devices' handshakes and the master's S-7.3 input step it
    /// at every Data_Exchange, mostly to count a stall, and a call of its own, its answer
    /// returned through memory, added half again to the cost of a stall (the 20 s lab run
    /// takes 0.9 M fewer instructions this way).
    #[inline(always)]
    pub fn step(&mut self, from_answerer: Nibble) -> (Nibble, Option<RequesterEvent>) {
        let k = from_answerer.bit(3);
        let Some(k_ref) = self.k_ref else {
            self.k_ref = Some(k);
            return (self.output(), None);
        };
        if k == k_ref {
            self.stall = self.stall.saturating_add(1);
            if self.stall_limit > 0 && self.stall >= self.stall_limit {
                self.stall = 0;
                self.acc = 0;
                self.pos = 0;
                self.code = if self.code == SYNC_CODE {
                    self.steps.first().copied().unwrap_or(SYNC_CODE)
                } else {
                    SYNC_CODE
                };
            }
            return (self.output(), None);
        }
        self.stall = 0;
        self.k_ref = Some(k);
        let data = (from_answerer.get() & 7) as u32;
        let event = if self.code == SYNC_CODE {
            self.pos = 0;
            self.acc = 0;
            Some(RequesterEvent::Synced)
        } else if self.steps.get(self.pos) == Some(&self.code) {
            self.acc = (self.acc << 3) | data;
            self.pos += 1;
            if self.pos == self.steps.len() {
                let w = self.acc;
                self.acc = 0;
                self.pos = 0;
                Some(RequesterEvent::Word(w))
            } else {
                None
            }
        } else {
            Some(RequesterEvent::Extra(self.code))
        };
        self.code = if self.pos == 0 {
            match self.extra.take() {
                Some(x) => x,
                None => self.steps.first().copied().unwrap_or(SYNC_CODE),
            }
        } else {
            self.steps[self.pos]
        };
        (self.output(), event)
    }
}

/// What an answerer step did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnswererEvent {
    /// The first step of a word was answered (the word was taken).
    WordStarted,
    /// The last step of a word was answered.
    WordDone,
    /// An extra (non-sequence) code was answered with 000.
    Extra(u8),
    /// The sync code was answered with 000.
    Sync,
}

/// The answering side of a handshake: answers each new code with K toggled and 3 data bits.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Answerer {
    steps: &'static [u8],
    last_code: Option<u8>,
    k: bool,
    data: u8,
    word: u32,
}

impl Answerer {
    /// An answerer over `steps`, K = 0.
    pub fn new(steps: &'static [u8]) -> Answerer {
        Answerer {
            steps,
            last_code: None,
            k: false,
            data: 0,
            word: 0,
        }
    }

    /// An answerer whose K starts at `k`: the K the requester saw last (for example 1 after
    /// the master's activation Data_Exchange with the default outputs 1111), so that the first
    /// answer is a visible toggle.
    pub fn with_k(steps: &'static [u8], k: bool) -> Answerer {
        Answerer {
            k,
            ..Answerer::new(steps)
        }
    }

    /// Back to the power-up state.
    pub fn reset(&mut self) {
        *self = Answerer::new(self.steps);
    }

    /// The nibble this side puts out: K on D3, data on D2..D0.
    pub fn output(&self) -> Nibble {
        Nibble::from_low_bits(((self.k as u8) << 3) | self.data)
    }

    /// One step with the requester's nibble. `word` is asked for the word to send when the
    /// first step code arrives (so each word is a consistent snapshot).
    pub fn step_with(
        &mut self,
        from_requester: Nibble,
        word: impl FnOnce() -> u32,
    ) -> (Nibble, Option<AnswererEvent>) {
        let code = from_requester.get() & 7;
        if self.last_code == Some(code) {
            return (self.output(), None);
        }
        self.last_code = Some(code);
        self.k = !self.k;
        let n = self.steps.len();
        let event = match self.steps.iter().position(|&c| c == code) {
            Some(i) => {
                if i == 0 {
                    self.word = word();
                }
                self.data = ((self.word >> (3 * (n - 1 - i))) & 7) as u8;
                if i == 0 {
                    Some(AnswererEvent::WordStarted)
                } else if i == n - 1 {
                    Some(AnswererEvent::WordDone)
                } else {
                    None
                }
            }
            None if code == SYNC_CODE => {
                self.data = 0;
                Some(AnswererEvent::Sync)
            }
            None => {
                self.data = 0;
                Some(AnswererEvent::Extra(code))
            }
        };
        (self.output(), event)
    }
}

/// The requesting side of a handshake in which the *requester* owns the toggle bit K: the
/// master side of the cabin button slave, table 4.7 of the lift thesis ("K 1 1 1", "K 1 0 1", ...).
///
/// The request nibble is K on D3 and the step code on D2..D0; K toggles with every new
/// request. **Decision** (docs/lab-bus.md, revised): the answerer echoes the K it answers to on D3
/// beside its 3 data bits, and a step completes when the requester sees its own K echoed.
///
/// - **Start** (power-up, [`ToggleRequester::reset`]): the first step only looks at the
///   answerer's D3 and puts out the first step code with the *other* K, so an answer that was
///   standing in the input image before the start can never pass for an echo.
/// - **Stall**: after `stall_limit` steps without the echo the requester abandons the word and
///   starts a new one: first step code, K toggled. An answerer always answers such a request
///   (see [`EchoAnswerer`]), so a requester and an answerer that lost step recover within one
///   stall period.
///
/// Idempotent like [`Requester`]: stepping with the same input any number of times (a scan
/// faster than the AS-i cycle, a repeated telegram, a lost response) does not advance.
#[derive(Clone, Debug)]
pub struct ToggleRequester {
    steps: &'static [u8],
    pos: usize,
    /// K of the request put out; `None` before the first step.
    k: Option<bool>,
    acc: u32,
    stall: u32,
    stall_limit: u32,
    restarts: u32,
}

impl ToggleRequester {
    /// A requester over `steps` that has not yet looked at the answerer.
    pub fn new(steps: &'static [u8]) -> ToggleRequester {
        ToggleRequester {
            steps,
            pos: 0,
            k: None,
            acc: 0,
            stall: 0,
            stall_limit: DEFAULT_STALL_LIMIT,
            restarts: 0,
        }
    }

    /// Sets the stall limit in steps (0 = never restart a word).
    pub fn with_stall_limit(mut self, limit: u32) -> ToggleRequester {
        self.stall_limit = limit;
        self
    }

    /// The stall limit in steps.
    pub fn stall_limit(&self) -> u32 {
        self.stall_limit
    }

    /// Back to the power-up state (keeps the stall limit; the restart count restarts at 0).
    pub fn reset(&mut self) {
        *self = ToggleRequester::new(self.steps).with_stall_limit(self.stall_limit);
    }

    /// The nibble this side puts out: K on D3, the step code on D2..D0 (before the first
    /// step: the first code with D3 = 0).
    pub fn output(&self) -> Nibble {
        let code = self.steps.get(self.pos).copied().unwrap_or(0);
        Nibble::from_low_bits(((self.k.unwrap_or(false) as u8) << 3) | code)
    }

    /// Words abandoned after a stall since the last reset.
    pub fn restarts(&self) -> u32 {
        self.restarts
    }

    /// One step with the answerer's nibble; returns the nibble to put out and, when the last
    /// step of a word was echoed, the word (3 bits per step, first step in the highest bits).
    pub fn step(&mut self, from_answerer: Nibble) -> (Nibble, Option<u32>) {
        let echo = from_answerer.bit(3);
        let Some(k) = self.k else {
            self.k = Some(!echo);
            return (self.output(), None);
        };
        if echo != k {
            self.stall = self.stall.saturating_add(1);
            if self.stall_limit > 0 && self.stall >= self.stall_limit {
                self.stall = 0;
                self.pos = 0;
                self.acc = 0;
                self.k = Some(!k);
                self.restarts = self.restarts.wrapping_add(1);
            }
            return (self.output(), None);
        }
        self.stall = 0;
        self.acc = (self.acc << 3) | (from_answerer.get() & 7) as u32;
        self.pos += 1;
        let word = if self.pos == self.steps.len() {
            let w = self.acc;
            self.acc = 0;
            self.pos = 0;
            Some(w)
        } else {
            None
        };
        self.k = Some(!k);
        (self.output(), word)
    }
}

/// What an [`EchoAnswerer`] step did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EchoEvent {
    /// The first step of a word was answered (the word was taken).
    WordStarted,
    /// The last step of a word was answered.
    WordDone,
    /// A request out of sequence was refused: D3 = the other K, data 000.
    Refused {
        /// The request nibble.
        request: u8,
    },
}

/// The answering side of a handshake whose requester owns K (table 4.7 of the lift thesis): answers
/// each request with the K it answers to on D3 (the echo) and 3 data bits on D2..D0.
///
/// **Decision** on which requests are answered, so that the requester never takes an answer
/// to a request it did not make (two nibbles the AS-i master puts on the line by itself are
/// beyond this engine: the default outputs 1111 at activation look like "K = 1, first step",
/// and the zeroed input of a slave that left LAS like an echo of K = 0; the PLC starts a new
/// word when the master's flags F0/F1 change, see `controller::plc`):
/// - the first step code, whenever the request nibble changes to it: a new word, sampled now;
/// - the next step code of the word in progress, with K toggled;
/// - nothing else. A request out of sequence (the requester restarted or was re-admitted
///   mid-word, or this side was reset) is *refused*: D3 = the other K, data 000, and the word
///   in progress is abandoned. The requester sees no echo, stalls and starts a new word.
///
/// After a reset the pins read 0000 and the last request is unknown, so the first request seen
/// is answered only if it is the first step code.
#[derive(Clone, Debug)]
pub struct EchoAnswerer {
    steps: &'static [u8],
    last: Option<u8>,
    /// Index of the last step answered in the word in progress.
    pos: Option<usize>,
    word: u32,
    out: Nibble,
}

impl EchoAnswerer {
    /// An answerer over `steps` that has just powered up.
    pub fn new(steps: &'static [u8]) -> EchoAnswerer {
        EchoAnswerer {
            steps,
            last: None,
            pos: None,
            word: 0,
            out: Nibble::ZERO,
        }
    }

    /// Back to the power-up state.
    pub fn reset(&mut self) {
        *self = EchoAnswerer::new(self.steps);
    }

    /// The nibble this side puts out: the echoed K on D3, data on D2..D0.
    pub fn output(&self) -> Nibble {
        self.out
    }

    /// One step with the requester's nibble. `word` is asked for the word to send when the
    /// first step code arrives (so each word is a consistent snapshot).
    pub fn step_with(
        &mut self,
        from_requester: Nibble,
        word: impl FnOnce() -> u32,
    ) -> (Nibble, Option<EchoEvent>) {
        let request = from_requester.get();
        if self.last == Some(request) {
            return (self.out, None);
        }
        let toggled = self.last.map(|l| (l ^ request) & 0b1000 != 0);
        self.last = Some(request);
        let k = request & 0b1000;
        let code = request & 7;
        let n = self.steps.len();
        let next = self
            .pos
            .and_then(|p| self.steps.get(p + 1).map(|&c| (p + 1, c)));
        let i = if self.steps.first() == Some(&code) {
            self.word = word();
            Some(0)
        } else {
            match next {
                Some((i, c)) if c == code && toggled == Some(true) => Some(i),
                _ => None,
            }
        };
        self.pos = i;
        let Some(i) = i else {
            self.out = Nibble::from_low_bits(k ^ 0b1000);
            return (self.out, Some(EchoEvent::Refused { request }));
        };
        let data = ((self.word >> (3 * (n - 1 - i))) & 7) as u8;
        self.out = Nibble::from_low_bits(k | data);
        let event = if i == 0 {
            Some(EchoEvent::WordStarted)
        } else if i == n - 1 {
            Some(EchoEvent::WordDone)
        } else {
            None
        };
        (self.out, event)
    }
}
