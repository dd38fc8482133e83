//! Support for the workspace's tests.

/// The cases a fuzz-style property test runs: `default`, or `ASI_LIFT_FUZZ_CASES` when set, so
/// that a longer run needs no edit (`ASI_LIFT_FUZZ_CASES=100000 cargo test --release …`).
pub fn fuzz_cases(default: u32) -> u32 {
    std::env::var("ASI_LIFT_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}
