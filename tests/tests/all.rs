//! The integration tests of the end-to-end tests (asi-lift-tests), one module per file next to this one, built as one test
//! binary (`--test all`): one binary links the dependencies once instead of once per file.
//! A new test file is added here as a module (Cargo.toml has `autotests = false`).

mod cabin_handshake;
mod campaign;
mod clones;
mod controllers;
mod display_word;
mod end_to_end;
mod explore;
mod fast_path;
mod line_noise;
mod master_leds;
mod referee;
mod roundtrip;
mod safe_drive;
mod safety_regressions;
mod snapshots;
mod st_library;
mod st_reference;
mod structured_text;
mod traces;
mod traffic;
