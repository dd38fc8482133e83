//! Value Change Dump files (IEEE 1364-2001 §18): a streaming [`read`]er that follows one signal
//! of a capture, and the [`write`](mod@write)r of the rig's waveform files.

pub mod read;
pub mod write;

/// The scope of the bus's signals in asi-lift's own VCD files.
pub const BUS_SCOPE: &[&str] = &["rig", "bus"];

/// The demodulated line in asi-lift's own VCD files: a 1-bit wire in [`BUS_SCOPE`], one record
/// per pulse for the whole run. `asi-lift decode` reads it when no signal is named.
pub const PULSE_WIRE: &str = "manchester";

/// The line's voltage in asi-lift's own VCD files: a real variable in [`BUS_SCOPE`], written
/// only within the waveform window.
pub const LINE_VOLTAGE: &str = "line_voltage";
