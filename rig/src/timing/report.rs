//! The report's types: what `asi-lift timing` prints as text, JSON and SVG.

use super::error_model::ErrorModel;
use super::stats::{Figure, Histogram};
use serde::Serialize;

/// Repeats: counted in simulation and expected from the error model.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Repeats {
    /// Immediate repeats in the measured cycles.
    pub count: u64,
    /// Expected from the error model, given the telegrams sent.
    pub expected: f64,
    /// Standard deviation of the count under the error model.
    pub standard_error: f64,
    /// Repeats per cycle.
    pub per_cycle: Figure,
    /// Repeats as a fraction of all transactions.
    pub fraction: Figure,
    /// Transactions that still failed after their repeat.
    pub failed_after_repeat: u64,
    /// Slaves dropped from LAS (failed in consecutive cycles).
    pub dropouts: u64,
}

/// One hall call: press → registered in the PLC → run bit on the bus.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HallSample {
    /// When the button was pressed, s.
    pub pressed_s: f64,
    /// Press → call registered, ms.
    pub registered_ms: f64,
    /// Call registered → run bit first seen on the bus, ms.
    pub run_bit_ms: f64,
}

/// One STOP: press → EStopOut drops → K1 opens.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StopSample {
    /// When STOP was pressed, s.
    pub pressed_s: f64,
    /// Press → EStopOut off, ms.
    pub estop_out_ms: f64,
    /// EStopOut off → K1 open, ms.
    pub k1_open_ms: f64,
}

/// End-to-end latencies on the lab bus, ms.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Latencies {
    /// Hall button press → call registered in the PLC.
    pub press_to_registered_ms: Figure,
    /// Call registered → converter run bit first seen on the bus.
    pub registered_to_run_bit_ms: Figure,
    /// Hall button press → run bit on the bus.
    pub press_to_run_bit_ms: Figure,
    /// STOP pressed → the safety logic's EStopOut off.
    pub stop_to_estop_out_ms: Figure,
    /// EStopOut off → K1 open.
    pub estop_out_to_k1_open_ms: Figure,
    /// STOP pressed → K1 open.
    pub stop_to_k1_open_ms: Figure,
    /// The hall call samples.
    pub hall: Vec<HallSample>,
    /// The STOP samples.
    pub stop: Vec<StopSample>,
    /// Trips the samples did not cause (the Safety-at-Work monitor under line noise), each
    /// reset by the operator; a STOP sample with such a trip is not counted.
    pub operator_resets: u32,
    /// Why sampling ended early, if it did.
    pub incomplete: Option<String>,
}

/// The lab bus's own figures, ms.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LabTiming {
    /// The PLC scan, ms.
    pub plc_scan_ms: f64,
    /// The safety logic's scan, ms.
    pub safety_scan_ms: f64,
    /// The STOP delay of EStopDelOut, ms.
    pub stop_delay_ms: f64,
    /// S-7.3 value period of the current-loop output (7 cycles per value, any channel).
    pub analog_value_ms: Figure,
    /// Refresh of one channel of the two-channel AC2618 (the speed set-point): 14 cycles.
    pub setpoint_refresh_ms: Figure,
    /// Floor station display word (4 handshake steps), per station.
    pub floor_word_ms: Figure,
    /// Cabin display word (7 steps).
    pub cabin_display_word_ms: Figure,
    /// Cabin panel 32-bit word (two halves of 7 steps).
    pub cabin_panel_word_ms: Figure,
    /// End-to-end latencies.
    pub latencies: Latencies,
}

/// The timing analysis of one bus configuration (docs/timing.md).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TimingReport {
    /// The bus, in words.
    pub bus: String,
    /// Slaves n (of the lift thesis' formula).
    pub slaves: u32,
    /// LAS slots (addresses in use).
    pub slots: u32,
    /// Whether an inclusion call is part of every cycle (an address is free).
    pub inclusion_call: bool,
    /// Pulse error rate.
    pub pulse_error_rate: f64,
    /// Seed.
    pub seed: u64,
    /// The measurement window, s.
    pub window_s: f64,
    /// Complete cycles measured.
    pub cycles: u64,
    /// Transactions in them.
    pub transactions: u64,
    /// Transaction time (start to start), µs.
    pub transaction_us: Figure,
    /// The lift thesis' cycle T = (n + 2) · 154 µs.
    pub thesis_cycle_us: f64,
    /// Cycle time: analytic = the model's formula (plus the expected repeats with errors).
    pub cycle_us: Figure,
    /// Cycle times, µs.
    pub cycle_histogram: Histogram,
    /// Time between successive successful Data_Exchanges with one slave, µs.
    pub slave_update_us: Figure,
    /// Repeats and drop-outs.
    pub repeats: Repeats,
    /// The error model's numbers (with a pulse error rate).
    pub error_model: Option<ErrorModel>,
    /// The lab bus's handshakes and latencies.
    pub lab: Option<LabTiming>,
    /// Why the model's cycle formula does not apply to this run (the LAS changed), if it does
    /// not: then the cycle and what follows from it have no analytic value.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model_note: Option<String>,
    /// Statistics per slave over the measurement window, as the report's `bus.slaves[]`
    /// (the lights as they are at its end).
    pub per_slave: Vec<crate::report::SlaveReport>,
}
