//! The stand scenarios of the repository's `scenarios/stand/` directory (this package's own
//! `scenarios/stand/`, like the built-in scenarios), one per test guide of appendix A of the
//! SafeMOTION thesis, built into the library: `asi-lift stand` lists them, `asi-lift stand
//! NAME` runs one.

use super::StandScenario;
use crate::scenario::builtin::Builtin;
use crate::scenario::ScenarioError;

macro_rules! stand_builtins {
    ($($name:literal),* $(,)?) => {
        /// Every built-in stand scenario, by name, in the order of the HMI's buttons.
        pub const STAND_BUILTINS: &[Builtin] = &[
            $(Builtin {
                name: $name,
                text: include_str!(concat!("../../scenarios/stand/", $name, ".toml")),
            }),*
        ];
    };
}

stand_builtins!("sto", "sos", "ss1", "ss2", "sls1", "sls2", "sli", "sdi-p", "sdi-n");

/// The built-in stand scenario called `name`.
pub fn find(name: &str) -> Option<&'static Builtin> {
    STAND_BUILTINS.iter().find(|b| b.name == name)
}

/// The stand scenario of built-in `b`.
pub fn stand_scenario(b: &Builtin) -> Result<StandScenario, ScenarioError> {
    StandScenario::from_toml(&format!("<built-in stand {}>", b.name), b.text)
}
