//! asi-phy: the AS-Interface physical and link layer of asi-lift (docs/physical-layer.md, §2.2 of
//! the lift thesis).
//!
//! Telegrams ([`Request`], [`Response`]) become Manchester half-bits ([`HalfBits`]), then APM
//! pulses on the 3 µs grid ([`PulseTrain`]), then a sampled line voltage ([`waveform`]); the
//! way back goes through the comparator demodulator and the [`Receiver`] with its seven checks.
//! Everything runs on the simulated clock of [`time`]; nothing reads the wall clock.
//!
//! ```
//! use asi_phy::{Address, BusTiming, Expect, Nibble, PulseTrain, Receiver, Request, SimTime};
//!
//! let timing = BusTiming::default();
//! let req = Request::data_exchange(Address::new(5).unwrap(), Nibble::new(0b1010).unwrap()).unwrap();
//! let train = PulseTrain::request(req, SimTime::ZERO, timing.half_bit());
//! assert_eq!(train.to_string(), "0- 1+ 2- 3+ 4- 5+ 6- 7+ 9- 11+ 13- 15+ 17- 19+ 21- 23+ 24- 25+ 27- 28+");
//!
//! let mut rx = Receiver::new(timing.receiver(Expect::Requests));
//! let got: Vec<_> = rx.decode(train).collect();
//! assert_eq!(got[0].request(), Some(req));
//! ```

pub mod fault;
pub mod handshake;
pub mod handshake_words;
pub mod line;
pub mod manchester;
pub mod message;
pub mod pulse;
pub mod receiver;
pub mod slave_id;
pub mod telegram;
pub mod testing;
pub mod time;
pub mod timing;
pub mod waveform;

pub use fault::{FaultInjector, FaultRates, PulseErrorRate, PulseErrorRateError, PulseFault};
pub use line::Transmission;
pub use manchester::{HalfBits, Level};
pub use message::short_number;
pub use pulse::{Polarity, Pulse, PulseTrain};
pub use receiver::{
    Check, Checks, Expect, Frame, LineDecoder, Listener, Received, Receiver, ReceiverConfig,
    TelegramKind,
};
pub use slave_id::{SlaveAddr, SlaveCodes};
pub use telegram::{Address, Call, Nibble, Request, Response, Select, TelegramError};
pub use time::{SimDuration, SimTime};
pub use timing::{BusTiming, TimingError};
