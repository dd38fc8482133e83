//! The line voltage: APM pulses rendered as sampled sin² pulses, and the comparator that turns
//! sampled voltage back into pulses (docs/physical-layer.md "Waveform"; docs/asi.md §1.1; §2.2.1 of
//! the lift thesis).
//!
//! The demodulator follows the receiver rule of the slave ICs: after a pause the comparators
//! re-arm; the first pulse of a telegram (normally the negative start pulse) sets the threshold
//! to a fraction (45..55 %, default 50 %) of its amplitude; disturbances below 30 % of the
//! nominal amplitude are never pulses. It tracks a slow DC baseline, so it works on captures
//! that did not come from this crate: an oscilloscope trace on top of the 30 V supply, with
//! uneven amplitudes, noise and an arbitrary start.
//!
//! - `render`: the settings, [`render`] and the [`Waveform`] with its noise bursts;
//! - `demod`: the comparator, [`Demodulator`] and [`DemodConfig`];
//! - `capture`: [`read_capture`] and [`CaptureReader`], captures from text files.

mod capture;
mod demod;
mod render;
#[cfg(test)]
mod tests;

pub use capture::{
    excerpt, read_capture, read_line_bounded, Capture, CaptureError, CaptureReader, MAX_LINE_BYTES,
};
pub use demod::{DemodConfig, Demodulator};
pub use render::{render, NoiseBurst, Waveform, WaveformConfig, WaveformError};
