//! The nibble handshakes of the lab lift (seed 003 §4, tables 4.2–4.7; SPEC §3), both sides,
//! as plain state machines over 4-bit values with no dependency on the bus.
//!
//! **Nibble use** (SPEC §3 decision), two kinds of handshake:
//! - **The answerer owns K** (floor stations, table 4.3; cabin display, table 4.5; S-7.3 of
//!   [`crate::analog`]): the *requester* puts its 3-bit step code on D2..D0 (D3 = 0); the
//!   *answerer* puts 3 data bits on D2..D0 and the toggle bit K on D3. The answerer answers when
//!   it sees the requested code change, toggling K; a step completes when the requester sees K
//!   change; it then reads the data and puts out the next code ([`Requester`], [`Answerer`]).
//! - **The requester owns K** (cabin buttons, table 4.7: "K 1 1 1", "K 1 0 1", ...): the master
//!   puts K on D3 beside the step code on D2..D0 and toggles K with every request; the slave
//!   answers the 3 data bits on D2..D0 and, **Decision (SPEC §3, revised)**, echoes the K it
//!   answers to on D3. A step completes when the master sees its own K echoed
//!   ([`ToggleRequester`], [`EchoAnswerer`]).
//!
//! Every step is idempotent: a side may be stepped any number of times with the same input (a
//! PLC scan that is faster than the AS-i cycle, a repeated telegram, a lost response) without
//! advancing.
//!
//! **Decisions beyond SPEC**:
//! - Code `110` is used by no sequence of the seed; in the handshakes where the answerer owns
//!   K it is the *sync* code. A requester starts (and restarts after a reset) with `110`; the
//!   answerer acknowledges it with K toggled and data 000. This makes the first K change a
//!   requester sees after power-up harmless. A requester that sees no K change for
//!   `stall_limit` steps switches code (to `110`, or from `110` to the first step), so that a
//!   requester and an answerer that lost step (for example one of them was reset while the
//!   other waited) always recover.
//! - Where the requester owns K there is no sync code (table 4.7 has none): the requester
//!   starts with the K that differs from the D3 it sees, the answerer refuses requests out of
//!   sequence, and a requester without an echo for `stall_limit` steps starts a new word with K
//!   toggled (see [`ToggleRequester`] and [`EchoAnswerer`]).
//!
//! The engines are generic over the step sequence; the floor (table 4.3: 4 steps), cabin
//! display (table 4.5: 7 steps, S-7.3 layout) and cabin panel (tables 4.6/4.7: 7 steps, two
//! halves) protocols, and the S-7.3 analog transfer of [`crate::analog`], are built on them.
//! The master (PLC) side of each lab protocol is a `*Master` type the `controller` crate drives
//! from the process image; the device side is the `*Slave` type inside the slave devices of
//! [`crate::devices`].

use asi_phy::Nibble;

/// The sync code (used by no step sequence of seed 003).
pub const SYNC_CODE: u8 = 0b110;
/// Floor slave step codes, seed 003 table 4.3: D10..D8, D7..D5, D4..D2, D1 O V.
pub const FOUR_STEPS: [u8; 4] = [0b111, 0b010, 0b001, 0b000];
/// Seven-step codes, seed 003 tables 4.5 and 4.7 (the S-7.3 layout of table 2.2).
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
#[derive(Clone, Debug)]
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
#[derive(Clone, Debug)]
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
/// master side of the cabin button slave, seed 003 table 4.7 ("K 1 1 1", "K 1 0 1", ...).
///
/// The request nibble is K on D3 and the step code on D2..D0; K toggles with every new
/// request. **Decision** (SPEC §3, revised): the answerer echoes the K it answers to on D3
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

/// The answering side of a handshake whose requester owns K (seed 003 table 4.7): answers
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

/// The display word sent to the floor displays and the cabin display (seed 003 tables 4.2,
/// 4.4): D10..D6 floor number 1..24 (binary), D5 up, D4 down, D3 moving, D2 fault, D1 parity.
///
/// Held as a plain `u16` with Dn in bit n − 1 (bits 15..10 zero), so the rig can hand it to the
/// lift model. **Decision** (parity): D1 makes the number of ones in D10..D1 even.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct DisplayWord(u16);

/// A display word field out of range.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("display word: floor {0} is out of range 1..=24 (seed 003 table 4.2)")]
pub struct DisplayWordError(pub u8);

impl DisplayWord {
    /// The word for `floor` (1..=24) and the four indicator bits, with its parity bit.
    pub fn new(
        floor: u8,
        up: bool,
        down: bool,
        moving: bool,
        fault: bool,
    ) -> Result<DisplayWord, DisplayWordError> {
        if !(1..=24).contains(&floor) {
            return Err(DisplayWordError(floor));
        }
        let body = ((floor as u16) << 5)
            | ((up as u16) << 4)
            | ((down as u16) << 3)
            | ((moving as u16) << 2)
            | ((fault as u16) << 1);
        let parity = body.count_ones() as u16 & 1;
        Ok(DisplayWord(body | parity))
    }

    /// The word from its raw bits D10..D1 (bits 9..0; higher bits are dropped). The parity is
    /// taken as given: see [`DisplayWord::parity_ok`].
    pub const fn from_bits(bits: u16) -> DisplayWord {
        DisplayWord(bits & 0x3FF)
    }

    /// The raw bits, Dn in bit n − 1.
    pub const fn bits(self) -> u16 {
        self.0
    }

    /// The floor number D10..D6.
    pub const fn floor(self) -> u8 {
        (self.0 >> 5) as u8 & 0x1F
    }
    /// D5: travelling up.
    pub const fn up(self) -> bool {
        self.0 & (1 << 4) != 0
    }
    /// D4: travelling down.
    pub const fn down(self) -> bool {
        self.0 & (1 << 3) != 0
    }
    /// D3: moving (1) or standing (0).
    pub const fn moving(self) -> bool {
        self.0 & (1 << 2) != 0
    }
    /// D2: fault.
    pub const fn fault(self) -> bool {
        self.0 & (1 << 1) != 0
    }
    /// `true` if D10..D1 hold an even number of ones.
    pub const fn parity_ok(self) -> bool {
        self.0.count_ones() % 2 == 0
    }
}

/// **Decision** on O and V closing a word (seed 003 tables 4.3, 4.5; S-7.3 meaning of table
/// 2.2): O = 0 (value in range), V = 1 (valid data). A receiver ignores a word with V = 0, O = 1
/// or a parity error and keeps showing the last good one.
const OV_VALID: u32 = 0b01;

/// The 12 bits of a floor word transfer: D10..D1 O V.
const fn floor_transport(w: DisplayWord) -> u32 {
    ((w.0 as u32) << 2) | OV_VALID
}

/// The 21 bits of a 7-step transfer (S-7.3 layout, seed 003 table 2.2): E3..E1, D16..D1, O, V.
pub const fn seven_step_word(e: u8, d16: u16, overflow: bool, valid: bool) -> u32 {
    (((e & 7) as u32) << 18) | ((d16 as u32) << 2) | ((overflow as u32) << 1) | valid as u32
}

/// The fields of a 21-bit 7-step word: (E, D16..D1, O, V).
pub const fn split_seven_step_word(w: u32) -> (u8, u16, bool, bool) {
    (
        ((w >> 18) & 7) as u8,
        (w >> 2) as u16,
        w & 0b10 != 0,
        w & 1 != 0,
    )
}

/// Calls from a floor station, as reported between words (table 4.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FloorCalls {
    /// The up button was pressed.
    pub up: bool,
    /// The down button was pressed.
    pub down: bool,
}

/// The words a receiving side took and dropped, and the last good one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct WordLog<T> {
    last: Option<T>,
    good: u32,
    bad: u32,
}

impl<T> Default for WordLog<T> {
    fn default() -> Self {
        WordLog {
            last: None,
            good: 0,
            bad: 0,
        }
    }
}

impl<T: Copy> WordLog<T> {
    /// Records a received word: `Some` if it passed its checks, `None` if it was dropped.
    pub fn record(&mut self, w: Option<T>) {
        match w {
            Some(w) => {
                self.last = Some(w);
                self.good = self.good.wrapping_add(1);
            }
            None => self.bad = self.bad.wrapping_add(1),
        }
    }
    /// The last good word.
    pub fn last(&self) -> Option<T> {
        self.last
    }
    /// Good words received.
    pub fn good(&self) -> u32 {
        self.good
    }
    /// Words dropped (parity, O, V, channel, order).
    pub fn bad(&self) -> u32 {
        self.bad
    }
}

/// The sending (answering) side of a display word handshake: the word to send, a consistent
/// snapshot per transfer, and the count of words sent.
#[derive(Clone, Debug)]
struct DisplaySender {
    answerer: Answerer,
    word: DisplayWord,
    words_sent: u32,
}

impl DisplaySender {
    fn new(steps: &'static [u8]) -> DisplaySender {
        DisplaySender {
            answerer: Answerer::new(steps),
            word: DisplayWord::new(1, false, false, false, false).unwrap_or_default(),
            words_sent: 0,
        }
    }

    fn step(
        &mut self,
        input: Nibble,
        transport: fn(DisplayWord) -> u32,
    ) -> (Nibble, Option<AnswererEvent>) {
        let word = self.word;
        let (out, ev) = self.answerer.step_with(input, || transport(word));
        if ev == Some(AnswererEvent::WordDone) {
            self.words_sent = self.words_sent.wrapping_add(1);
        }
        (out, ev)
    }
}

/// The master (PLC) side of a floor station, seed 003 table 4.3: answers the slave's word
/// requests with the display word and collects button reports.
#[derive(Clone, Debug)]
pub struct FloorStationMaster {
    sender: DisplaySender,
    calls: FloorCalls,
    /// Buttons reported after the last word but one: held, if reported again.
    held: FloorCalls,
    /// A report arrived since the last word.
    reported: bool,
    presses: FloorCalls,
}

impl Default for FloorStationMaster {
    fn default() -> Self {
        Self::new()
    }
}

impl FloorStationMaster {
    /// A fresh engine; it sends floor 1, standing, until told otherwise.
    pub fn new() -> FloorStationMaster {
        FloorStationMaster {
            sender: DisplaySender::new(&FOUR_STEPS),
            calls: FloorCalls::default(),
            held: FloorCalls::default(),
            reported: false,
            presses: FloorCalls::default(),
        }
    }

    /// The display word to send from the next word on.
    pub fn set_word(&mut self, w: DisplayWord) {
        self.sender.word = w;
    }

    /// One step: the slave's input nibble from the input image in, the output nibble for the
    /// output image out.
    pub fn step(&mut self, input: Nibble) -> Nibble {
        let (out, ev) = self.sender.step(input, floor_transport);
        match ev {
            Some(AnswererEvent::Extra(c)) => {
                let now = FloorCalls {
                    up: c == CODE_UP || c == CODE_BOTH,
                    down: c == CODE_DOWN || c == CODE_BOTH,
                };
                self.calls.up |= now.up;
                self.calls.down |= now.down;
                self.presses.up |= now.up && !self.held.up;
                self.presses.down |= now.down && !self.held.down;
                self.held = now;
                self.reported = true;
            }
            Some(AnswererEvent::WordDone) => {
                // A word with no report after the one before: the buttons are released.
                let reported = core::mem::take(&mut self.reported);
                if !reported {
                    self.held = FloorCalls::default();
                }
            }
            _ => {}
        }
        out
    }

    /// The calls reported since the last take, cleared: a held button is in every take
    /// after a word.
    pub fn take_calls(&mut self) -> FloorCalls {
        core::mem::take(&mut self.calls)
    }

    /// The presses since the last take, cleared: a button counts again only after a word
    /// went by without it (released), so a held button is one press.
    pub fn take_presses(&mut self) -> FloorCalls {
        core::mem::take(&mut self.presses)
    }

    /// Number of whole words sent.
    pub fn words_sent(&self) -> u32 {
        self.sender.words_sent
    }

    /// Back to the power-up state (keeps the word to send).
    pub fn reset(&mut self) {
        self.sender.answerer.reset();
        self.calls = FloorCalls::default();
        self.held = FloorCalls::default();
        self.reported = false;
        self.presses = FloorCalls::default();
    }
}

/// The device side of a floor station, seed 003 table 4.3: requests the display word in four
/// steps and reports the buttons between words.
///
/// A button press is latched until it has been reported, so a press shorter than a word is
/// not lost; a held button is reported after every word.
#[derive(Clone, Debug)]
pub struct FloorStationSlave {
    requester: Requester,
    up_pressed: bool,
    down_pressed: bool,
    up_latched: bool,
    down_latched: bool,
    words: WordLog<DisplayWord>,
}

impl Default for FloorStationSlave {
    fn default() -> Self {
        Self::new()
    }
}

impl FloorStationSlave {
    /// A device that has just powered up: no word shown yet.
    pub fn new() -> FloorStationSlave {
        FloorStationSlave {
            requester: Requester::new(&FOUR_STEPS),
            up_pressed: false,
            down_pressed: false,
            up_latched: false,
            down_latched: false,
            words: WordLog::default(),
        }
    }

    /// Sets the button levels (pressed = `true`); a press is latched.
    pub fn set_buttons(&mut self, up: bool, down: bool) {
        self.up_pressed = up;
        self.down_pressed = down;
        self.up_latched |= up;
        self.down_latched |= down;
    }

    /// One step with the output nibble the master sent; returns the input nibble to present.
    pub fn step(&mut self, outputs: Nibble) -> Nibble {
        if !self.requester.extra_pending() {
            let code = match (self.up_latched, self.down_latched) {
                (true, true) => Some(CODE_BOTH),
                (true, false) => Some(CODE_UP),
                (false, true) => Some(CODE_DOWN),
                (false, false) => None,
            };
            if let Some(c) = code {
                self.requester.queue_extra(c);
            }
        }
        let (out, ev) = self.requester.step(outputs);
        match ev {
            Some(RequesterEvent::Word(bits)) => {
                let w = DisplayWord::from_bits((bits >> 2) as u16);
                let ok = bits & 0b11 == OV_VALID && w.parity_ok();
                self.words.record(ok.then_some(w));
            }
            Some(RequesterEvent::Extra(c)) => {
                if c == CODE_UP || c == CODE_BOTH {
                    self.up_latched = self.up_pressed;
                }
                if c == CODE_DOWN || c == CODE_BOTH {
                    self.down_latched = self.down_pressed;
                }
            }
            _ => {}
        }
        out
    }

    /// The last good display word received.
    pub fn display(&self) -> Option<DisplayWord> {
        self.words.last()
    }

    /// Words received and dropped.
    pub fn words(&self) -> &WordLog<DisplayWord> {
        &self.words
    }

    /// Power-up reset: the display goes blank, latches are cleared.
    pub fn reset(&mut self) {
        *self = FloorStationSlave::new();
    }
}

/// **Decision**: the cabin display word travels as S-7.3 channel E = 001 (table 4.5 gives the
/// layout E3E2E1 D16..D1 O V; the display word occupies D10..D1, D16..D11 = 0).
pub const CABIN_DISPLAY_CHANNEL: u8 = 1;

fn cabin_transport(w: DisplayWord) -> u32 {
    seven_step_word(CABIN_DISPLAY_CHANNEL, w.bits(), false, true)
}

/// The master (PLC) side of the cabin display, seed 003 tables 4.4/4.5: answers the slave's
/// seven step requests with the display word.
#[derive(Clone, Debug)]
pub struct CabinDisplayMaster {
    sender: DisplaySender,
}

impl Default for CabinDisplayMaster {
    fn default() -> Self {
        Self::new()
    }
}

impl CabinDisplayMaster {
    /// A fresh engine sending floor 1, standing.
    pub fn new() -> CabinDisplayMaster {
        CabinDisplayMaster {
            sender: DisplaySender::new(&SEVEN_STEPS),
        }
    }

    /// The display word to send from the next word on.
    pub fn set_word(&mut self, w: DisplayWord) {
        self.sender.word = w;
    }

    /// One step: input nibble in, output nibble out.
    pub fn step(&mut self, input: Nibble) -> Nibble {
        self.sender.step(input, cabin_transport).0
    }

    /// Number of whole words sent.
    pub fn words_sent(&self) -> u32 {
        self.sender.words_sent
    }

    /// Back to the power-up state (keeps the word).
    pub fn reset(&mut self) {
        self.sender.answerer.reset();
    }
}

/// The device side of the cabin display (seed 003 table 4.5): requests the word in 7 steps.
#[derive(Clone, Debug)]
pub struct CabinDisplaySlave {
    requester: Requester,
    words: WordLog<DisplayWord>,
}

impl Default for CabinDisplaySlave {
    fn default() -> Self {
        Self::new()
    }
}

impl CabinDisplaySlave {
    /// A device that has just powered up.
    pub fn new() -> CabinDisplaySlave {
        CabinDisplaySlave {
            requester: Requester::new(&SEVEN_STEPS),
            words: WordLog::default(),
        }
    }

    /// One step with the master's output nibble; returns the input nibble to present.
    pub fn step(&mut self, outputs: Nibble) -> Nibble {
        let (out, ev) = self.requester.step(outputs);
        if let Some(RequesterEvent::Word(bits)) = ev {
            let (e, d, o, v) = split_seven_step_word(bits);
            let w = DisplayWord::from_bits(d);
            let ok = e == CABIN_DISPLAY_CHANNEL && v && !o && d >> 10 == 0 && w.parity_ok();
            self.words.record(ok.then_some(w));
        }
        out
    }

    /// The last good display word.
    pub fn display(&self) -> Option<DisplayWord> {
        self.words.last()
    }

    /// Words received and dropped.
    pub fn words(&self) -> &WordLog<DisplayWord> {
        &self.words
    }

    /// Power-up reset.
    pub fn reset(&mut self) {
        *self = CabinDisplaySlave::new();
    }
}

/// The cabin's buttons and sensors as one 32-bit word travels them (seed 003 table 4.6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct CabinPanelState {
    /// Floor buttons 1..24: bit n − 1 = floor n.
    pub floor_buttons: u32,
    /// Bell (Zvonek).
    pub bell: bool,
    /// STOP.
    pub stop: bool,
    /// Door closed (SnZavD).
    pub door_closed: bool,
    /// Left vane sensor, Snimac_1 (table 4.6 "Sním 1", D9 of the second half).
    pub vane_left: bool,
    /// Right vane sensor, Snimac_2 (table 4.6 "Sním 2", D10 of the second half).
    pub vane_right: bool,
}

impl CabinPanelState {
    /// `true` if the button of `floor` (1..=24) is pressed.
    pub fn floor_button(&self, floor: u8) -> bool {
        (1..=24).contains(&floor) && self.floor_buttons & (1 << (floor - 1)) != 0
    }

    /// The two halves D16..D1 (table 4.6): half 0 (E = 000) = floors 16..1; half 1 (E = 001)
    /// = D14 parity, D13 door closed, D12 bell, D11 STOP, D10 right vane, D9 left vane, D8..D1
    /// floors 24..17. **Decision** (parity): D14 makes the 32 data bits of both halves hold an
    /// even number of ones.
    pub fn halves(&self) -> (u16, u16) {
        let h0 = (self.floor_buttons & 0xFFFF) as u16;
        let mut h1 = ((self.floor_buttons >> 16) & 0xFF) as u16
            | (self.vane_left as u16) << 8
            | (self.vane_right as u16) << 9
            | (self.stop as u16) << 10
            | (self.bell as u16) << 11
            | (self.door_closed as u16) << 12;
        if (h0.count_ones() + h1.count_ones()) % 2 == 1 {
            h1 |= 1 << 13;
        }
        (h0, h1)
    }

    /// The state from two halves, or `None` if the parity fails or D16, D15 of half 1 are set.
    pub fn from_halves(h0: u16, h1: u16) -> Option<CabinPanelState> {
        if (h0.count_ones() + h1.count_ones()) % 2 == 1 || h1 >> 14 != 0 {
            return None;
        }
        Some(CabinPanelState {
            floor_buttons: h0 as u32 | ((h1 as u32 & 0xFF) << 16),
            vane_left: h1 & (1 << 8) != 0,
            vane_right: h1 & (1 << 9) != 0,
            stop: h1 & (1 << 10) != 0,
            bell: h1 & (1 << 11) != 0,
            door_closed: h1 & (1 << 12) != 0,
        })
    }
}

/// The master (PLC) side of the cabin panel, seed 003 table 4.7: requests the 32-bit word in
/// two 7-step halves (E = 000, then E = 001) with K in its own request, and checks its parity.
///
/// On the bus, one half is the request sequence `K111`, `K101`, `K100`, `K011`, `K010`, `K001`,
/// `K000` with K toggling at every step (for example `0111`, `1101`, `0100`, `1011`, `0010`,
/// `1001`, `0000`), each answered by the slave with the same K on D3 and 3 data bits
/// ([`ToggleRequester`]). A half 1 is taken only after a half 0; a half that fails E, O or V
/// drops the half 0 before it.
#[derive(Clone, Debug)]
pub struct CabinPanelMaster {
    requester: ToggleRequester,
    half0: Option<u16>,
    words: WordLog<CabinPanelState>,
    fresh: bool,
}

impl Default for CabinPanelMaster {
    fn default() -> Self {
        Self::new()
    }
}

impl CabinPanelMaster {
    /// A fresh engine.
    pub fn new() -> CabinPanelMaster {
        CabinPanelMaster {
            requester: ToggleRequester::new(&SEVEN_STEPS),
            half0: None,
            words: WordLog::default(),
            fresh: false,
        }
    }

    /// Sets the requester's stall limit in steps (PLC scans).
    pub fn with_stall_limit(mut self, limit: u32) -> CabinPanelMaster {
        self.requester = self.requester.with_stall_limit(limit);
        self
    }

    /// One step: the slave's input nibble in, the output nibble out.
    pub fn step(&mut self, input: Nibble) -> Nibble {
        let (out, word) = self.requester.step(input);
        if let Some(bits) = word {
            let (e, d, o, v) = split_seven_step_word(bits);
            match (e, v && !o) {
                (0, true) => self.half0 = Some(d),
                (1, true) => {
                    let w = self
                        .half0
                        .take()
                        .and_then(|h0| CabinPanelState::from_halves(h0, d));
                    self.fresh |= w.is_some();
                    self.words.record(w);
                }
                _ => {
                    self.half0 = None;
                    self.words.record(None);
                }
            }
        }
        out
    }

    /// The nibble put out by the last step.
    pub fn output(&self) -> Nibble {
        self.requester.output()
    }

    /// The last good 32-bit word.
    pub fn state(&self) -> Option<CabinPanelState> {
        self.words.last()
    }

    /// The last good word if it arrived since the last take.
    pub fn take_update(&mut self) -> Option<CabinPanelState> {
        if core::mem::take(&mut self.fresh) {
            self.words.last()
        } else {
            None
        }
    }

    /// 32-bit words received and halves or words dropped (parity, O, V, order).
    pub fn words(&self) -> &WordLog<CabinPanelState> {
        &self.words
    }

    /// Words abandoned after a stall (no echo for the stall limit) since the last reset.
    pub fn restarts(&self) -> u32 {
        self.requester.restarts()
    }

    /// Back to the power-up state: the half in progress is dropped, the next step looks at the
    /// slave's D3 again and starts a new word with the other K. The word log is kept.
    pub fn reset(&mut self) {
        self.requester.reset();
        self.half0 = None;
        self.fresh = false;
    }
}

/// The device side of the cabin panel (seed 003 tables 4.6/4.7): answers the master's step
/// requests ([`EchoAnswerer`]); the two halves of one 32-bit word are sampled together when
/// half 0 starts, and the halves alternate with every half answered to its last step.
#[derive(Clone, Debug)]
pub struct CabinPanelSlave {
    answerer: EchoAnswerer,
    signals: CabinPanelState,
    snapshot: (u16, u16),
    next_half: u8,
    refused: u32,
}

impl Default for CabinPanelSlave {
    fn default() -> Self {
        Self::new()
    }
}

impl CabinPanelSlave {
    /// A device that has just powered up.
    pub fn new() -> CabinPanelSlave {
        CabinPanelSlave {
            answerer: EchoAnswerer::new(&SEVEN_STEPS),
            signals: CabinPanelState::default(),
            snapshot: (0, 0),
            next_half: 0,
            refused: 0,
        }
    }

    /// The current signal levels (read by the next word).
    pub fn signals_mut(&mut self) -> &mut CabinPanelState {
        &mut self.signals
    }

    /// The current signal levels.
    pub fn signals(&self) -> &CabinPanelState {
        &self.signals
    }

    /// Requests refused as out of sequence since power-up.
    pub fn refused(&self) -> u32 {
        self.refused
    }

    /// One step with the master's output nibble; returns the input nibble to present.
    pub fn step(&mut self, outputs: Nibble) -> Nibble {
        let signals = self.signals;
        let half = self.next_half;
        let snapshot = &mut self.snapshot;
        let (out, ev) = self.answerer.step_with(outputs, || {
            if half == 0 {
                *snapshot = signals.halves();
                seven_step_word(0, snapshot.0, false, true)
            } else {
                seven_step_word(1, snapshot.1, false, true)
            }
        });
        match ev {
            // The next half only after this one was answered to its end: a word the master
            // abandoned (or the activation's default 1111, which looks like a first step) is
            // sent again from its start.
            Some(EchoEvent::WordDone) => self.next_half ^= 1,
            Some(EchoEvent::Refused { .. }) => self.refused = self.refused.wrapping_add(1),
            _ => {}
        }
        out
    }

    /// Power-up reset (keeps the signal levels, which are the plant's).
    pub fn reset(&mut self) {
        let s = self.signals;
        *self = CabinPanelSlave::new();
        self.signals = s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs a PLC-side and a device-side step function against each other: the device steps
    /// `dev_per_plc` times per PLC step (cycles per scan).
    fn run<F, G>(mut plc: F, mut dev: G, scans: usize, dev_per_plc: usize)
    where
        F: FnMut(Nibble) -> Nibble,
        G: FnMut(Nibble) -> Nibble,
    {
        let mut input = Nibble::ZERO; // slave -> master
        let mut output; // master -> slave
        for _ in 0..scans {
            output = plc(input);
            for _ in 0..dev_per_plc {
                input = dev(output);
            }
        }
    }

    #[test]
    #[allow(clippy::unusual_byte_groupings)] // grouped by the fields of table 4.2
    fn display_word_layout_of_table_4_2() {
        let w = DisplayWord::new(3, true, false, true, false).expect("ok");
        // D10..D6 = 00011, D5 up = 1, D4 = 0, D3 moving = 1, D2 = 0, D1 parity.
        assert_eq!(w.bits() >> 1, 0b00011_1_0_1_0);
        assert!(w.parity_ok());
        assert_eq!(w.bits() & 1, 0, "four ones already: parity 0");
        let w = DisplayWord::new(1, false, true, false, false).expect("ok");
        assert_eq!(w.bits(), 0b00001_0_1_0_0_0);
        let w = DisplayWord::new(2, false, false, false, false).expect("ok");
        assert_eq!(w.bits(), 0b00010_0_0_0_0_1, "one 1: parity 1");
        assert_eq!((w.floor(), w.up(), w.down()), (2, false, false));
        assert_eq!(
            DisplayWord::new(25, false, false, false, false),
            Err(DisplayWordError(25))
        );
        assert!(!DisplayWord::from_bits(0b1).parity_ok());
    }

    #[test]
    fn floor_word_and_buttons_pass_in_both_directions() {
        let mut m = FloorStationMaster::new();
        let mut s = FloorStationSlave::new();
        let w = DisplayWord::new(4, false, true, true, false).expect("ok");
        m.set_word(w);
        s.set_buttons(true, false);
        s.set_buttons(false, false); // a short press, latched
        let mut calls = FloorCalls::default();
        let mut dev = |o| s.step(o);
        run(
            |i| {
                let o = m.step(i);
                let c = m.take_calls();
                calls.up |= c.up;
                calls.down |= c.down;
                o
            },
            &mut dev,
            20,
            3,
        );
        assert_eq!(s.display(), Some(w));
        assert!(calls.up && !calls.down);
        assert!(m.words_sent() >= 2);
    }

    #[test]
    fn a_floor_step_needs_the_k_toggle() {
        let mut s = FloorStationSlave::new();
        assert_eq!(s.step(Nibble::ZERO).get(), SYNC_CODE);
        // Same K: still syncing.
        assert_eq!(s.step(Nibble::from_low_bits(0b0111)).get(), SYNC_CODE);
        // K toggled: sync acknowledged, first step 111.
        assert_eq!(s.step(Nibble::from_low_bits(0b1000)).get(), 0b111);
        // K toggled with D10..D8 = 000: next code 010.
        assert_eq!(s.step(Nibble::from_low_bits(0b0000)).get(), 0b010);
        assert_eq!(s.step(Nibble::from_low_bits(0b0000)).get(), 0b010);
    }

    #[test]
    fn cabin_display_word_passes_in_seven_steps() {
        let mut m = CabinDisplayMaster::new();
        let mut s = CabinDisplaySlave::new();
        let w = DisplayWord::new(17, true, false, true, true).expect("ok");
        m.set_word(w);
        let mut dev = |o| s.step(o);
        run(|i| m.step(i), &mut dev, 40, 2);
        assert_eq!(s.display(), Some(w));
        assert_eq!(s.words().bad(), 0);
    }

    #[test]
    fn cabin_panel_word_passes_in_two_halves() {
        let mut m = CabinPanelMaster::new();
        let mut s = CabinPanelSlave::new();
        let want = CabinPanelState {
            floor_buttons: (1 << 2) | (1 << 20),
            bell: true,
            stop: false,
            door_closed: true,
            vane_left: true,
            vane_right: false,
        };
        *s.signals_mut() = want;
        let mut dev = |o| s.step(o);
        run(|i| m.step(i), &mut dev, 60, 2);
        assert_eq!(m.state(), Some(want));
        assert!(m.state().expect("state").floor_button(3));
        assert!(m.state().expect("state").floor_button(21));
        assert_eq!(m.words().bad(), 0);
    }

    #[test]
    fn cabin_panel_parity_rejects_a_flipped_bit() {
        let s = CabinPanelState {
            floor_buttons: 0b101,
            ..Default::default()
        };
        let (h0, h1) = s.halves();
        assert_eq!(CabinPanelState::from_halves(h0, h1), Some(s));
        assert_eq!(CabinPanelState::from_halves(h0 ^ 1, h1), None);
    }

    /// A panel state whose two halves are easy to read off table 4.6: floors 1, 3, 16 and 24,
    /// STOP and door closed (parity D14 = 0: six ones).
    fn table_4_6_example() -> CabinPanelState {
        CabinPanelState {
            floor_buttons: (1 << 23) | (1 << 15) | 0b101,
            stop: true,
            door_closed: true,
            ..Default::default()
        }
    }

    /// Seed 003 table 4.7, worked vector: the master's requests `K111`, `K101`, `K100`, `K011`,
    /// `K010`, `K001`, `K000` with K toggling at every step, and the slave's answers: the K it
    /// answers to on D3, then E3E2E1, D16..D14, ..., D1 O V of table 4.6.
    #[test]
    fn table_4_7_request_and_answer_nibbles() {
        let want = table_4_6_example();
        assert_eq!(want.halves(), (0x8005, 0x1480));
        let mut m = CabinPanelMaster::new();
        let mut s = CabinPanelSlave::new();
        *s.signals_mut() = want;
        // Before its first step the master looks at the slave's D3 (0 after power-up) and
        // starts with the other K.
        let mut out = m.step(Nibble::ZERO);
        let mut pairs = Vec::new();
        for _ in 0..14 {
            let answer = s.step(out);
            pairs.push((out.get(), answer.get()));
            out = m.step(answer);
        }
        #[rustfmt::skip]
        let expected: [(u8, u8); 14] = [
            // Half 0 (E = 000): D16..D1 = floors 16..1 = 1000 0000 0000 0101, O = 0, V = 1.
            (0b1_111, 0b1_000), // K 111 -> E3 E2 E1     = 000
            (0b0_101, 0b0_100), // K 101 -> D16 D15 D14  = 100
            (0b1_100, 0b1_000), // K 100 -> D13 D12 D11  = 000
            (0b0_011, 0b0_000), // K 011 -> D10 D9 D8    = 000
            (0b1_010, 0b1_000), // K 010 -> D7 D6 D5     = 000
            (0b0_001, 0b0_010), // K 001 -> D4 D3 D2     = 010
            (0b1_000, 0b1_101), // K 000 -> D1 O V       = 101
            // Half 1 (E = 001): parity 0, door closed, bell 0, STOP, vanes 00, floors 24..17.
            (0b0_111, 0b0_001), // K 111 -> E3 E2 E1     = 001
            (0b1_101, 0b1_000), // K 101 -> D16 D15 D14  = 000 (D14 parity)
            (0b0_100, 0b0_101), // K 100 -> D13 D12 D11  = SnZavD Zvonek Stop = 101
            (0b1_011, 0b1_001), // K 011 -> D10 D9 D8    = Snim2 Snim1 floor 24 = 001
            (0b0_010, 0b0_000), // K 010 -> D7 D6 D5     = floors 23..21
            (0b1_001, 0b1_000), // K 001 -> D4 D3 D2     = floors 20..18
            (0b0_000, 0b0_001), // K 000 -> D1 O V       = floor 17, O = 0, V = 1
        ];
        assert_eq!(pairs, expected);
        assert_eq!(m.state(), Some(want));
        assert_eq!((m.words().good(), m.words().bad()), (1, 0));
        // The next word starts with the other K again.
        assert_eq!(out.get(), 0b1_111);
    }

    /// The master completes a step only on its own K echoed: a stale answer (the other K) or
    /// the same request stepped again does not advance it.
    #[test]
    fn a_cabin_panel_step_needs_the_echo() {
        let mut m = CabinPanelMaster::new();
        assert_eq!(
            m.step(Nibble::from_low_bits(0b1_010)).get(),
            0b0_111,
            "K = !D3"
        );
        assert_eq!(
            m.step(Nibble::from_low_bits(0b1_000)).get(),
            0b0_111,
            "no echo"
        );
        assert_eq!(
            m.step(Nibble::from_low_bits(0b0_000)).get(),
            0b1_101,
            "echo: next step"
        );
        assert_eq!(
            m.step(Nibble::from_low_bits(0b0_000)).get(),
            0b1_101,
            "stale: wait"
        );
        let mut s = CabinPanelSlave::new();
        let a = s.step(Nibble::from_low_bits(0b0_111));
        assert_eq!(a.get(), 0b0_000);
        assert_eq!(s.step(Nibble::from_low_bits(0b0_111)), a, "idempotent");
        // Out of sequence (K not toggled): refused with the other K.
        assert_eq!(s.step(Nibble::from_low_bits(0b0_101)).get(), 0b1_000);
        assert_eq!(s.refused(), 1);
        // ... until a new word starts.
        // (half 0 again: the abandoned word is sent again from its start).
        assert_eq!(s.step(Nibble::from_low_bits(0b1_111)).get(), 0b1_000);
    }

    /// The slave is reset (power cycle, re-admission) in the middle of a word: it refuses the
    /// master's request out of sequence, the master gets no echo, starts a new word after its
    /// stall limit, and the next word arrives whole; no word is taken from the torn one.
    #[test]
    fn cabin_panel_slave_reset_mid_word_resynchronises() {
        let want = table_4_6_example();
        let mut m = CabinPanelMaster::new().with_stall_limit(5);
        let mut s = CabinPanelSlave::new();
        *s.signals_mut() = want;
        let mut input = Nibble::ZERO;
        let mut updates = Vec::new();
        for i in 0..60 {
            let out = m.step(input);
            if i == 4 {
                s.reset();
            }
            input = s.step(out);
            updates.extend(m.take_update());
        }
        assert_eq!(s.refused(), 1);
        assert_eq!(m.restarts(), 1);
        assert_eq!(m.words().bad(), 0);
        assert!(!updates.is_empty() && updates.iter().all(|&u| u == want));
    }

    /// The PLC restarts in the middle of a word: the master starts a new word with the K that
    /// differs from the D3 it sees, the slave takes it as a new word at once (no stall).
    #[test]
    fn cabin_panel_master_restart_mid_word_needs_no_stall() {
        let want = table_4_6_example();
        let mut m = CabinPanelMaster::new().with_stall_limit(5);
        let mut s = CabinPanelSlave::new();
        *s.signals_mut() = want;
        let mut input = Nibble::ZERO;
        let mut updates = Vec::new();
        for i in 0..60 {
            if i == 4 {
                // In the middle of half 0.
                m.reset();
            }
            let out = m.step(input);
            input = s.step(out);
            updates.extend(m.take_update());
        }
        assert_eq!((m.restarts(), s.refused()), (0, 0));
        // The slave sends the abandoned half 0 again from its start: nothing is dropped.
        assert_eq!(m.words().bad(), 0);
        assert!(updates.len() >= 2 && updates.iter().all(|&u| u == want));
    }

    #[test]
    fn a_requester_reset_mid_word_recovers() {
        let mut m = CabinDisplayMaster::new();
        let mut s = CabinDisplaySlave::new();
        let w = DisplayWord::new(2, false, false, false, false).expect("ok");
        m.set_word(w);
        let mut input = Nibble::ZERO;
        for i in 0..400 {
            let out = m.step(input);
            if i == 9 {
                s.reset();
            }
            input = s.step(out);
        }
        assert_eq!(s.display(), Some(w));
    }

    #[test]
    fn an_answerer_is_idempotent() {
        let mut a = Answerer::new(&FOUR_STEPS);
        let (o1, e1) = a.step_with(Nibble::from_low_bits(0b111), || 0b101_000_000_000);
        assert_eq!(e1, Some(AnswererEvent::WordStarted));
        assert_eq!(o1.get(), 0b1101);
        let (o2, e2) = a.step_with(Nibble::from_low_bits(0b111), || 0);
        assert_eq!((o2, e2), (o1, None));
    }
}
