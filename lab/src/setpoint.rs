//! The speed set-point the PLC writes to the S-7.3 current-loop output (slave 10) and the
//! converter reads (§6.4 of the lift thesis; docs/lift-plant.md §4.1).

/// The set-point that means standstill: 4000 µA = 4 mA, the live zero of the 4–20 mA loop (§6.4 of
/// the lift thesis: "hodnota 4000 odpovídá klidovému stavu kabiny"). The PLC program writes it to
/// stop the cabin; the converter stands still at it; the rig counts a stop as an arrival only with
/// the drive commanded to it.
pub const STANDSTILL_UA: u16 = 4000;
