//! The floor displays and the cabin display as the plant shows them (docs/lab-bus.md §3.3;
//! tables 4.2 and 4.4 of the lift thesis): each shows the last complete word it was handed, or an
//! error for a word that fails its checks. The word itself is the lab crate's [`DisplayWord`].

use serde::{Deserialize, Serialize};

use lab::{DisplayWord, DisplayWordError};

/// Which display: one per floor, one in the cabin (docs/lab-bus.md: slaves 1..4 and 5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum DisplayId {
    /// The display at floor `n` (1-based).
    Floor(u8),
    /// The display in the cabin.
    Cabin,
}

/// What a display shows now: the last complete word it was handed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DisplayState {
    /// No complete word yet since the start.
    Blank,
    /// A valid word.
    Showing(DisplayWord),
    /// The last word failed its checks; a viewer shows an error, not the bits.
    BadWord {
        /// The word as received.
        raw: u16,
        /// What is wrong with it.
        error: DisplayWordError,
    },
}

impl DisplayState {
    /// The state for a received word.
    pub fn from_raw(raw: u16) -> DisplayState {
        match DisplayWord::decode(raw) {
            Ok(word) => DisplayState::Showing(word),
            Err(error) => DisplayState::BadWord { raw, error },
        }
    }
}
