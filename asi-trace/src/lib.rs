//! asi-trace: the files of asi-lift. Telegram records as machines read them ([`telegrams`]),
//! the transaction trace of a run as text or JSON lines ([`trace`]), Value Change Dumps read
//! and written ([`vcd`]), captures of the line decoded back into telegrams ([`capture`]), the
//! traffic of a capture as an analyser hears it ([`analyser`]: transactions and the statistics
//! per slave), and a master call shown on its way to the line ([`encode`]).
//!
//! A trace written by `asi-lift run` and a capture decoded by `asi-lift decode` share one
//! record shape, so that the two compare field by field.

pub mod analyser;
pub mod capture;
pub mod encode;
pub mod telegrams;
pub mod trace;
pub mod vcd;
