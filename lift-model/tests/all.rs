//! The integration tests of lift-model, one module per file next to this one, built as one test
//! binary (`--test all`): one binary links the dependencies once instead of once per file.
//! A new test file is added here as a module (Cargo.toml has `autotests = false`).

mod common;

mod config;
mod drive_table;
mod inputs;
mod safety_physics;
mod timing;
mod vanes;
