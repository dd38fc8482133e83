//! The integration tests of safety, one module per file next to this one, built as one test
//! binary (`--test all`): one binary links the dependencies once instead of once per file.
//! A new test file is added here as a module (Cargo.toml has `autotests = false`).

mod drive;
mod kl6904_logic;
mod kl6904_modules;
mod lift;
mod lift_drive;
mod plcopen_invariants;
mod plcopen_vectors;
mod project_files;
mod verifier;
