//! Value Change Dump files (IEEE 1364-2001 §18): a streaming [`read`]er that follows one signal
//! of a capture, and the [`write`](mod@write)r of the rig's waveform files.

pub mod read;
pub mod write;
