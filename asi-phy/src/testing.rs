//! Support for the workspace's tests.

/// The cases a fuzz-style property test runs: `default`, or `ASI_LIFT_FUZZ_CASES` when set, so
/// that a longer run needs no edit (`ASI_LIFT_FUZZ_CASES=100000 cargo test --release …`).
pub fn fuzz_cases(default: u32) -> u32 {
    std::env::var("ASI_LIFT_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// `text` after `edits`, each `(kind, at, byte)`: a byte changed, inserted or removed at `at`
/// (taken modulo the length), or a cut there; the fuzz-style tests' mutation of real inputs.
pub fn mutate(text: &[u8], edits: &[(u8, usize, u8)]) -> Vec<u8> {
    let mut b = text.to_vec();
    for &(kind, at, byte) in edits {
        let at = at % (b.len() + 1);
        match kind % 4 {
            0 if at < b.len() => b[at] = byte,
            1 => b.insert(at, byte),
            2 if at < b.len() => {
                b.remove(at);
            }
            _ => b.truncate(at),
        }
    }
    b
}
