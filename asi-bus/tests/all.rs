//! The integration tests of asi-bus, one module per file next to this one, built as one test
//! binary (`--test all`): one binary links the dependencies once instead of once per file.
//! A new test file is added here as a module (Cargo.toml has `autotests = false`).

mod common;

mod cycle_time;
mod faults;
mod handshake_pairs;
mod handshake_props;
mod handshakes;
mod image;
mod leds;
mod line_capture;
mod mailbox;
mod quick;
mod robust;
mod safety_noise;
mod sampling;
mod slave_stats;
mod startup;
mod tracing_out;
