//! Bad project files give an error, never a panic: random damage to the lift's project file.

use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use safety::kl6904::Project;

const LIFT: &str = include_str!("../projects/lift.toml");

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 512,
        rng_seed: RngSeed::Fixed(0x5AFE_F11E),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn damaged_lines_never_panic(
        drop in prop::collection::vec(0usize..120, 0..4),
        edits in prop::collection::vec((0usize..120, "[a-zA-Z0-9_.:\" =\\[\\]{}-]{0,12}"), 0..4),
    ) {
        let mut lines: Vec<String> = LIFT.lines().map(str::to_owned).collect();
        for (k, text) in edits {
            let n = lines.len();
            if n > 0 {
                lines[k % n] = text;
            }
        }
        for k in drop {
            let n = lines.len();
            if n > 0 {
                lines.remove(k % n);
            }
        }
        let text = lines.join("\n");
        if let Err(e) = Project::from_toml("lift.toml", &text) {
            prop_assert!(e.to_string().starts_with("lift.toml"), "{e}");
        }
    }

    #[test]
    fn any_text_never_panics(text in "\\PC{0,200}") {
        let _ = Project::from_toml("x.toml", &text);
    }
}
