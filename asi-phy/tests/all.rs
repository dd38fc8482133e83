//! The integration tests of asi-phy, one module per file next to this one, built as one test
//! binary (`--test all`): one binary links the dependencies once instead of once per file.
//! A new test file is added here as a module (Cargo.toml has `autotests = false`).

mod exhaustive;
mod line;
mod properties;
mod receivers;
