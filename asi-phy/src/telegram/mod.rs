//! AS-i telegrams: the 14-bit master request and the 7-bit slave response (docs/physical-layer.md, §2;
//! docs/asi.md §2.1, §4; §2.2.2 of the lift thesis).
//!
//! Both are validated representations over plain integers, in transmission order with the first
//! bit sent in the most significant used position:
//!
//! ```text
//! Request  (u16, bits 13..0):  ST CB A4 A3 A2 A1 A0 I4 I3 I2 I1 I0 PB EB
//! Response (u8,  bits  6..0):  ST I3 I2 I1 I0 PB EB
//! ```
//!
//! ST is always 0, EB always 1, and the parity is even: CB + A4..A0 + I4..I0 + PB (request) and
//! I3..I0 + PB (response) hold an even number of ones. A value of these types is always a
//! telegram a correct transmitter could send.
//!
//! - `fields`: [`Nibble`], [`Address`], [`Select`];
//! - `frames`: [`Request`], [`Response`] and [`TelegramError`];
//! - `call`: what a request asks for, [`Call`].

mod call;
mod fields;
mod frames;
#[cfg(test)]
mod tests;

pub use call::Call;
pub use fields::{Address, Nibble, Select};
pub use frames::{Request, Response, TelegramError};
