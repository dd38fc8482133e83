//! The scenarios of the repository's `scenarios/` directory, built into the library (and so
//! into the `asi-lift` command after `cargo install`): `asi-lift scenarios` lists them,
//! `asi-lift run NAME` runs one. The files live in this package's own `scenarios/` (the
//! repository's is a link to it), so that the published package holds the files it builds in.

use super::{Scenario, ScenarioError};

/// A built-in scenario: its name (the file name without `.toml`) and its file.
#[derive(Clone, Copy, Debug)]
pub struct Builtin {
    /// The name `asi-lift run NAME` takes.
    pub name: &'static str,
    /// The scenario file, comments and all.
    pub text: &'static str,
}

macro_rules! builtins {
    ($($name:literal),* $(,)?) => {
        /// Every built-in scenario, by name; the first is the demo.
        pub const BUILTINS: &[Builtin] = &[
            $(Builtin {
                name: $name,
                text: include_str!(concat!("../../scenarios/", $name, ".toml")),
            }),*
        ];
    };
}

builtins!(
    "demo",
    "busy",
    "door",
    "fifo",
    "lost-cabin-slave",
    "noise",
    "noise-5e-3",
    "noise-1e-2",
    "overload",
    "overtravel",
    "power-fail",
    "safe-drive",
    "safe-drive-encoder",
    "safe-drive-runaway",
    "safe-link-drop",
    "stop",
    "vane-sensor-broken",
);

impl Scenario {
    /// The built-in demo: power-on between floors 2 and 3, initialisation, a cabin call, a
    /// hall call stored meanwhile, and one more cabin call.
    pub fn demo() -> Result<Scenario, ScenarioError> {
        BUILTINS[0].scenario()
    }
}

impl Builtin {
    /// The built-in scenario called `name`.
    pub fn find(name: &str) -> Option<&'static Builtin> {
        BUILTINS.iter().find(|b| b.name == name)
    }

    /// What it shows, in one line: the first sentence of the file's leading comment.
    pub fn summary(&self) -> String {
        let comment: Vec<&str> = self
            .text
            .lines()
            .take_while(|l| l.starts_with('#'))
            .map(|l| l.trim_start_matches('#').trim())
            .collect();
        let text = comment.join(" ");
        match text
            .find(". ")
            .or_else(|| text.strip_suffix('.').map(str::len))
        {
            Some(end) => text[..=end.min(text.len() - 1)].trim_end().to_owned(),
            None => text,
        }
    }

    /// The scenario.
    pub fn scenario(&self) -> Result<Scenario, ScenarioError> {
        Scenario::from_toml(&format!("<built-in {}>", self.name), self.text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_file_of_the_scenarios_directory_is_built_in_and_reads() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
        let mut files: Vec<String> = std::fs::read_dir(&dir)
            .expect("scenarios/")
            .filter_map(|e| {
                let name = e.ok()?.file_name().to_string_lossy().into_owned();
                name.strip_suffix(".toml").map(str::to_owned)
            })
            .collect();
        files.sort();
        let mut names: Vec<String> = BUILTINS.iter().map(|b| b.name.to_owned()).collect();
        names.sort();
        assert_eq!(names, files);
        for b in BUILTINS {
            let sc = b.scenario().unwrap_or_else(|e| panic!("{e}"));
            assert!(sc.late_events().next().is_none(), "{}", b.name);
            let s = b.summary();
            assert!(s.ends_with('.') && s.len() < 250, "{}: {s}", b.name);
        }
    }

    #[test]
    fn a_summary_is_the_first_sentence_of_the_comment() {
        let b = Builtin::find("door").expect("door");
        assert_eq!(
            b.summary(),
            "An open door blocks departure; closing it lets the cabin go."
        );
        assert!(Builtin::find("nonesuch").is_none());
    }
}
