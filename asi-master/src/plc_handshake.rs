//! The master (PLC) side of the lab lift's nibble handshakes (tables 4.2–4.7 of the lift thesis):
//! the `*Master` types the `controller` crate drives from the process image, built on the engines
//! of [`asi_phy::handshake`] and the words of [`asi_phy::handshake_words`]. The device side is
//! `asi_slaves::device_handshake`.

use asi_phy::handshake::{
    Answerer, AnswererEvent, ToggleRequester, CODE_BOTH, CODE_DOWN, CODE_UP, FOUR_STEPS,
    SEVEN_STEPS,
};
use asi_phy::handshake_words::{
    cabin_transport, floor_transport, split_seven_step_word, CabinPanelState, WordLog,
};
use asi_phy::Nibble;

/// Calls from a floor station, as reported between words (table 4.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FloorCalls {
    /// The up button was pressed.
    pub up: bool,
    /// The down button was pressed.
    pub down: bool,
}

/// The sending (answering) side of a display word handshake: the word to send, a consistent
/// snapshot per transfer, and the count of words sent.
#[derive(Clone, Debug)]
struct DisplaySender {
    answerer: Answerer,
    /// The display word's bits D10..D1.
    word: u16,
    words_sent: u32,
}

impl DisplaySender {
    fn new(steps: &'static [u8]) -> DisplaySender {
        DisplaySender {
            answerer: Answerer::new(steps),
            word: lab::display::FLOOR_1_AT_REST,
            words_sent: 0,
        }
    }

    fn step(
        &mut self,
        input: Nibble,
        transport: fn(u16) -> u32,
    ) -> (Nibble, Option<AnswererEvent>) {
        let word = self.word;
        let (out, ev) = self.answerer.step_with(input, || transport(word));
        if ev == Some(AnswererEvent::WordDone) {
            self.words_sent = self.words_sent.wrapping_add(1);
        }
        (out, ev)
    }
}

/// The master (PLC) side of a floor station, table 4.3 of the lift thesis: answers the slave's word
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

    /// The display word to send from the next word on: its bits D10..D1 (`lab::DisplayWord::encode`).
    pub fn set_word(&mut self, w: u16) {
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

/// The master (PLC) side of the cabin display, tables 4.4/4.5 of the lift thesis: answers the
/// slave's seven step requests with the display word.
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

    /// The display word to send from the next word on: its bits D10..D1 (`lab::DisplayWord::encode`).
    pub fn set_word(&mut self, w: u16) {
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

/// The master (PLC) side of the cabin panel, table 4.7 of the lift thesis: requests the 32-bit
/// word in two 7-step halves (E = 000, then E = 001) with K in its own request, and checks its
/// parity.
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
