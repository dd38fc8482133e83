//! Campaign profiles: the weights of the scenario generator ([`super::generate`]).
//!
//! A profile is a built-in (`default`, `quiet`, `noisy`, `smoke`) or a TOML file that starts
//! from a built-in (`base`, default `default`) and changes some of its settings; the format is
//! documented in README.md ("Campaigns"). A weight table in a file changes the weights it
//! names and keeps the others; a weight of 0 switches a choice off.

use crate::scenario::PLC_SCAN_RANGE;
use asi_phy::SimDuration;
use controller::Algorithm;
use lift_model::LoadLevel;
use rand::Rng;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt;

/// The kinds of random event the generator draws (the book, "Campaigns").
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum ActivityKind {
    /// A cabin call button (`press = "cabin:N"`).
    Cabin,
    /// A hall call button (`hall-up:N`, `hall-down:N`).
    Hall,
    /// The cabin STOP button, held 0.3..3 s.
    Stop,
    /// The bell button.
    Bell,
    /// The load changes to any level, overloaded included.
    Load,
    /// The door is opened by hand (and mostly closed again 2..20 s later).
    Door,
    /// STOP, then one or two small hand cranks while K1 is open (|sum| ≤ 40 mm per run).
    Crank,
    /// The operator's safety reset.
    Reset,
    /// The operator's acknowledge of a safety group error.
    Ack,
    /// A slave of the lab bus (1..8, 10, 11, 12) drops off, back 1..30 s later.
    Slave,
    /// The AS-i supply fails for 0.1..5 s.
    PowerFail,
    /// The STOP terminal's safe link is silent for 50 ms..2 s.
    SafeLinkDrop,
    /// A vane sensor sticks on or off, repaired 1..30 s later.
    Vane,
    /// The converter runs away (up or down, against its commands), repaired 1..20 s later:
    /// only the safe drive stops that at a floor (weight 0 but in `safe-drive`).
    Runaway,
    /// The safe drive's encoder fails, repaired 1..20 s later: its monitor trips to STO
    /// (weight 0 but in `safe-drive`; drawn only in runs with the safe drive).
    Encoder,
}

impl ActivityKind {
    /// Every kind, in the order of the profile format.
    pub const ALL: [ActivityKind; 15] = [
        ActivityKind::Cabin,
        ActivityKind::Hall,
        ActivityKind::Stop,
        ActivityKind::Bell,
        ActivityKind::Load,
        ActivityKind::Door,
        ActivityKind::Crank,
        ActivityKind::Reset,
        ActivityKind::Ack,
        ActivityKind::Slave,
        ActivityKind::PowerFail,
        ActivityKind::SafeLinkDrop,
        ActivityKind::Vane,
        ActivityKind::Runaway,
        ActivityKind::Encoder,
    ];

    /// The name in a profile's `[event]` table.
    pub fn name(self) -> &'static str {
        match self {
            ActivityKind::Cabin => "cabin",
            ActivityKind::Hall => "hall",
            ActivityKind::Stop => "stop",
            ActivityKind::Bell => "bell",
            ActivityKind::Load => "load",
            ActivityKind::Door => "door",
            ActivityKind::Crank => "crank",
            ActivityKind::Reset => "reset",
            ActivityKind::Ack => "ack",
            ActivityKind::Slave => "slave",
            ActivityKind::PowerFail => "power-fail",
            ActivityKind::SafeLinkDrop => "safe-link-drop",
            ActivityKind::Vane => "vane",
            ActivityKind::Runaway => "runaway",
            ActivityKind::Encoder => "encoder",
        }
    }

    /// `true` for the injected faults (what the `quiet` profile leaves out).
    pub fn is_fault(self) -> bool {
        matches!(
            self,
            ActivityKind::Slave
                | ActivityKind::PowerFail
                | ActivityKind::SafeLinkDrop
                | ActivityKind::Vane
                | ActivityKind::Runaway
                | ActivityKind::Encoder
        )
    }
}

/// Choices with integer weights; a choice is drawn with probability weight / total.
#[derive(Clone, Debug, PartialEq)]
pub struct Weights<T> {
    items: Vec<(T, u32)>,
}

impl<T: Copy + PartialEq> Weights<T> {
    /// The choices and their weights (zero weights are kept but never drawn).
    pub fn new(items: Vec<(T, u32)>) -> Weights<T> {
        Weights { items }
    }

    /// The sum of the weights.
    pub fn total(&self) -> u64 {
        self.items.iter().map(|(_, w)| u64::from(*w)).sum()
    }

    /// The weight of `value` (0 if absent).
    pub fn weight(&self, value: T) -> u32 {
        self.items
            .iter()
            .find(|(v, _)| *v == value)
            .map_or(0, |(_, w)| *w)
    }

    /// Sets the weight of `value`, adding it if absent.
    pub fn set(&mut self, value: T, weight: u32) {
        match self.items.iter_mut().find(|(v, _)| *v == value) {
            Some(item) => item.1 = weight,
            None => self.items.push((value, weight)),
        }
    }

    /// The choices with a weight above zero.
    pub fn choices(&self) -> impl Iterator<Item = (T, u32)> + '_ {
        self.items.iter().copied().filter(|(_, w)| *w > 0)
    }

    /// Draws one choice; `None` if every weight is zero.
    pub fn pick(&self, rng: &mut impl Rng) -> Option<T> {
        let total = self.total();
        if total == 0 {
            return None;
        }
        let mut x = rng.random_range(0..total);
        for (v, w) in &self.items {
            if x < u64::from(*w) {
                return Some(*v);
            }
            x -= u64::from(*w);
        }
        None
    }
}

/// The generator's settings: what a campaign's scenarios look like.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    /// Its name (a built-in's, or the file's `name`, else the file's stem).
    pub name: String,
    /// Shortest and longest run, whole seconds drawn uniformly between them.
    pub duration: (SimDuration, SimDuration),
    /// The probe (a cabin call) comes this long before the end of a run.
    pub probe_lead: SimDuration,
    /// Fewest and most random events per run.
    pub events: (u32, u32),
    /// Floors of the lift (2..4, the lab bus has four floor stations).
    pub floors: Weights<u8>,
    /// The control algorithm.
    pub algorithm: Weights<Algorithm>,
    /// Line noise: probability per pulse.
    pub pulse_error_rate: Weights<f64>,
    /// The PLC scan period, within [`PLC_SCAN_RANGE`].
    pub scan: Weights<SimDuration>,
    /// The load at power-on.
    pub load: Weights<LoadLevel>,
    /// The random events.
    pub event: Weights<ActivityKind>,
    /// Chance that a run has extra I/O modules on the bus (then 1..20 of them).
    pub extra_slaves_chance: f64,
    /// Chance that the cabin starts level at a floor (else anywhere in the legal range).
    pub start_level_chance: f64,
    /// Chance that the door is open at power-on.
    pub door_open_chance: f64,
    /// Chance that the operator does not press the safety reset after power-on.
    pub no_power_on_reset_chance: f64,
    /// Chance that a call or bell button is held 0.5..5 s instead of 300 ms.
    pub long_hold_chance: f64,
    /// Chance that a run leaves a vane sensor broken to the end (in service: null).
    pub leave_vane_broken_chance: f64,
    /// Chance that a run has the safe drive (`[drive] safe = true`; docs/drive-safety.md §6).
    pub safe_drive_chance: f64,
}

/// Names of the built-in profiles.
pub const BUILT_IN: [&str; 5] = ["default", "quiet", "noisy", "smoke", "safe-drive"];

impl Profile {
    /// The built-in profile `name`, if there is one.
    pub fn built_in(name: &str) -> Option<Profile> {
        let mut p = Profile::default_profile();
        match name {
            "default" => {}
            "quiet" => {
                p.name = "quiet".into();
                for k in ActivityKind::ALL.iter().filter(|k| k.is_fault()) {
                    p.event.set(*k, 0);
                }
                p.pulse_error_rate = Weights::new(vec![(0.0, 1)]);
                p.leave_vane_broken_chance = 0.0;
            }
            "noisy" => {
                p.name = "noisy".into();
                // Rates a lift still serves its calls at (the book, "Line noise"): at 10⁻² no
                // call is served, so every run of it failed the campaign; at 5·10⁻³ the calls
                // are served, but with the generator's faults one run in 200 was not.
                p.pulse_error_rate = Weights::new(vec![(0.0, 1), (1e-3, 1), (2e-3, 1), (3e-3, 1)]);
            }
            "smoke" => {
                p.name = "smoke".into();
                p.duration = (SimDuration::from_secs(110), SimDuration::from_secs(130));
                p.probe_lead = SimDuration::from_secs(45);
                p.events = (1, 6);
            }
            "safe-drive" => {
                p.name = "safe-drive".into();
                p.safe_drive_chance = 1.0;
                p.event.set(ActivityKind::Runaway, 1);
                p.event.set(ActivityKind::Encoder, 1);
            }
            _ => return None,
        }
        Some(p)
    }

    fn default_profile() -> Profile {
        use ActivityKind as K;
        Profile {
            name: "default".into(),
            duration: (SimDuration::from_secs(120), SimDuration::from_secs(240)),
            probe_lead: SimDuration::from_secs(60),
            events: (3, 24),
            floors: Weights::new(vec![(2, 1), (3, 1), (4, 2)]),
            algorithm: Weights::new(vec![(Algorithm::Fifo, 1), (Algorithm::Collective, 1)]),
            pulse_error_rate: Weights::new(vec![(0.0, 2), (1e-3, 1)]),
            scan: Weights::new(vec![
                (SimDuration::from_millis(10), 24),
                (SimDuration::from_millis(1), 1),
                (SimDuration::from_millis(2), 1),
                (SimDuration::from_millis(5), 1),
                (SimDuration::from_millis(15), 1),
                (SimDuration::from_millis(20), 1),
            ]),
            load: Weights::new(vec![
                (LoadLevel::Empty, 4),
                (LoadLevel::Loaded, 4),
                (LoadLevel::Full, 2),
                (LoadLevel::Overloaded, 1),
            ]),
            event: Weights::new(vec![
                (K::Cabin, 12),
                (K::Hall, 12),
                (K::Stop, 2),
                (K::Bell, 1),
                (K::Load, 3),
                (K::Door, 2),
                (K::Crank, 1),
                (K::Reset, 1),
                (K::Ack, 1),
                (K::Slave, 2),
                (K::PowerFail, 1),
                (K::SafeLinkDrop, 1),
                (K::Vane, 1),
                // Last and 0: the draws of the other kinds stay as they were.
                (K::Runaway, 0),
                (K::Encoder, 0),
            ]),
            extra_slaves_chance: 0.1,
            start_level_chance: 0.25,
            door_open_chance: 0.05,
            no_power_on_reset_chance: 0.05,
            long_hold_chance: 0.1,
            leave_vane_broken_chance: 0.02,
            safe_drive_chance: 0.0,
        }
    }

    /// A built-in by name, or else the profile file at `arg`.
    pub fn resolve(arg: &str) -> Result<Profile, ProfileError> {
        if let Some(p) = Profile::built_in(arg) {
            return Ok(p);
        }
        let path = std::path::Path::new(arg);
        if !path.exists() {
            return Err(ProfileError::new(
                arg,
                format!(
                    "no such built-in profile or file: use {} or a profile file",
                    BUILT_IN.join(", ")
                ),
            ));
        }
        let text = read_bounded(path).map_err(|e| ProfileError::new(arg, e))?;
        let stem = path
            .file_stem()
            .map_or_else(|| arg.to_owned(), |s| s.to_string_lossy().into_owned());
        Profile::from_toml(arg, &stem, &text)
    }

    /// Reads a profile file's `text`; `file` names it in errors, `stem` is the name it takes
    /// when it gives none.
    pub fn from_toml(file: &str, stem: &str, text: &str) -> Result<Profile, ProfileError> {
        let err = |m: String| ProfileError::new(file, m);
        let raw: RawProfile = toml::from_str(text).map_err(|e| err(e.to_string()))?;
        let base = raw.base.as_deref().unwrap_or("default");
        let mut p = Profile::built_in(base).ok_or_else(|| {
            err(format!(
                "base: unknown built-in profile `{base}`: use {}",
                BUILT_IN.join(", ")
            ))
        })?;
        p.name = raw.name.unwrap_or_else(|| stem.to_owned());
        let dur = |field: &str, s: &str| -> Result<SimDuration, ProfileError> {
            s.parse::<SimDuration>()
                .map_err(|e| err(format!("{field}: {e}")))
        };
        if let Some([a, b]) = &raw.duration {
            p.duration = (dur("duration", a)?, dur("duration", b)?);
        }
        if let Some(l) = &raw.probe_lead {
            p.probe_lead = dur("probe_lead", l)?;
        }
        if let Some([a, b]) = raw.events {
            p.events = (a, b);
        }
        for (field, value, target) in [
            (
                "extra_slaves_chance",
                raw.extra_slaves_chance,
                &mut p.extra_slaves_chance,
            ),
            (
                "start_level_chance",
                raw.start_level_chance,
                &mut p.start_level_chance,
            ),
            (
                "door_open_chance",
                raw.door_open_chance,
                &mut p.door_open_chance,
            ),
            (
                "no_power_on_reset_chance",
                raw.no_power_on_reset_chance,
                &mut p.no_power_on_reset_chance,
            ),
            (
                "long_hold_chance",
                raw.long_hold_chance,
                &mut p.long_hold_chance,
            ),
            (
                "leave_vane_broken_chance",
                raw.leave_vane_broken_chance,
                &mut p.leave_vane_broken_chance,
            ),
            (
                "safe_drive_chance",
                raw.safe_drive_chance,
                &mut p.safe_drive_chance,
            ),
        ] {
            if let Some(v) = value {
                if !(0.0..=1.0).contains(&v) {
                    return Err(err(format!(
                        "{field}: {}: a chance is 0..1",
                        asi_phy::short_number(v)
                    )));
                }
                *target = v;
            }
        }
        merge(&mut p.floors, &raw.floors, "floors", |k| {
            match k.parse::<u8>() {
                Ok(f @ 2..=4) => Ok(f),
                _ => Err(format!(
                    "`{k}`: the lab bus has floor stations for 2..4 floors"
                )),
            }
        })
        .map_err(err)?;
        merge(&mut p.algorithm, &raw.algorithm, "algorithm", |k| match k {
            "fifo" => Ok(Algorithm::Fifo),
            "collective" => Ok(Algorithm::Collective),
            _ => Err(format!("`{k}`: use fifo or collective")),
        })
        .map_err(err)?;
        merge(
            &mut p.pulse_error_rate,
            &raw.pulse_error_rate,
            "pulse_error_rate",
            |k| match k.parse::<f64>().map(asi_phy::PulseErrorRate::new) {
                Ok(Ok(rate)) => Ok(rate.get()),
                Ok(Err(e)) => Err(format!("`{k}`: {e}")),
                Err(_) => Err(format!("`{k}`: not a number; a pulse error rate is 0..=1")),
            },
        )
        .map_err(err)?;
        merge(&mut p.scan, &raw.scan, "scan", |k| {
            match k.parse::<SimDuration>() {
                Ok(d) if PLC_SCAN_RANGE.contains(&d) => Ok(d),
                Ok(_) => Err(format!("`{k}`: a PLC scan is 1..20 ms")),
                Err(e) => Err(format!("`{k}`: {e}")),
            }
        })
        .map_err(err)?;
        merge(&mut p.load, &raw.load, "load", |k| match k {
            "empty" => Ok(LoadLevel::Empty),
            "loaded" => Ok(LoadLevel::Loaded),
            "full" => Ok(LoadLevel::Full),
            "overloaded" => Ok(LoadLevel::Overloaded),
            _ => Err(format!("`{k}`: use empty, loaded, full or overloaded")),
        })
        .map_err(err)?;
        merge(&mut p.event, &raw.event, "event", |k| {
            ActivityKind::ALL
                .iter()
                .find(|e| e.name() == k)
                .copied()
                .ok_or_else(|| {
                    let names: Vec<&str> = ActivityKind::ALL.iter().map(|e| e.name()).collect();
                    format!("`{k}`: unknown event kind: use {}", names.join(", "))
                })
        })
        .map_err(err)?;
        p.check().map_err(err)?;
        Ok(p)
    }

    /// Checks that the settings make sense together.
    pub fn check(&self) -> Result<(), String> {
        let (lo, hi) = self.duration;
        let least = self.probe_lead + MIN_ACTIVITY_AND_RECOVERY;
        if lo > hi {
            return Err(format!("duration: {lo} is longer than {hi}"));
        }
        if lo < least {
            return Err(format!(
                "duration: {lo} is too short: runs need the probe lead ({}) plus {MIN_ACTIVITY_AND_RECOVERY} for events and the recovery",
                self.probe_lead
            ));
        }
        if hi > SimDuration::from_secs(3600) {
            return Err(format!("duration: {hi}: at most 1 h per run"));
        }
        if self.probe_lead < SimDuration::from_secs(10) {
            return Err(format!(
                "probe_lead: {}: give the lift at least 10 s to serve the probe",
                self.probe_lead
            ));
        }
        if self.events.0 > self.events.1 || self.events.1 > 1000 {
            return Err(format!(
                "events: [{}, {}]: give the fewest and the most events per run, at most 1000",
                self.events.0, self.events.1
            ));
        }
        for (name, total) in [
            ("floors", self.floors.total()),
            ("algorithm", self.algorithm.total()),
            ("pulse_error_rate", self.pulse_error_rate.total()),
            ("scan", self.scan.total()),
            ("load", self.load.total()),
        ] {
            if total == 0 {
                return Err(format!("{name}: every weight is zero"));
            }
        }
        if self.events.1 > 0 && self.event.total() == 0 {
            return Err("event: every weight is zero but events are wanted".into());
        }
        Ok(())
    }
}

/// What a run needs besides the probe lead: the operator's procedure for a start beyond what
/// initialisation can find (20 s), the shortest window of random events (10 s), the quiet gap
/// before the recovery (6 s) and the recovery before the probe (22 s), with room.
pub const MIN_ACTIVITY_AND_RECOVERY: SimDuration = SimDuration::from_secs(60);

fn merge<T: Copy + PartialEq>(
    into: &mut Weights<T>,
    table: &Option<BTreeMap<String, u32>>,
    name: &str,
    parse: impl Fn(&str) -> Result<T, String>,
) -> Result<(), String> {
    for (k, w) in table.iter().flatten() {
        let v = parse(k).map_err(|e| format!("[{name}] {e}"))?;
        into.set(v, *w);
    }
    Ok(())
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawProfile {
    base: Option<String>,
    name: Option<String>,
    duration: Option<[String; 2]>,
    probe_lead: Option<String>,
    events: Option<[u32; 2]>,
    extra_slaves_chance: Option<f64>,
    start_level_chance: Option<f64>,
    door_open_chance: Option<f64>,
    no_power_on_reset_chance: Option<f64>,
    long_hold_chance: Option<f64>,
    leave_vane_broken_chance: Option<f64>,
    safe_drive_chance: Option<f64>,
    floors: Option<BTreeMap<String, u32>>,
    algorithm: Option<BTreeMap<String, u32>>,
    pulse_error_rate: Option<BTreeMap<String, u32>>,
    scan: Option<BTreeMap<String, u32>>,
    load: Option<BTreeMap<String, u32>>,
    event: Option<BTreeMap<String, u32>>,
}

/// Why a profile cannot be used.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ProfileError {
    /// The profile as given (`--profile`).
    pub profile: String,
    /// What is wrong.
    pub message: String,
}

impl ProfileError {
    fn new(profile: &str, message: impl fmt::Display) -> ProfileError {
        ProfileError {
            profile: profile.to_owned(),
            message: message.to_string().trim_end().to_owned(),
        }
    }
}

impl fmt::Display for ProfileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "--profile {}: {}", self.profile, self.message)
    }
}

impl std::error::Error for ProfileError {}

/// The largest profile file read: a profile is a few hundred bytes, so a larger file
/// (`/dev/zero`, a result file given by mistake) is refused before it fills memory.
pub const MAX_PROFILE_BYTES: u64 = 16 << 20;

/// The text of the file at `path`, at most [`MAX_PROFILE_BYTES`] of it.
fn read_bounded(path: &std::path::Path) -> Result<String, String> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_PROFILE_BYTES + 1).read_to_end(&mut bytes))
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > MAX_PROFILE_BYTES {
        return Err(format!(
            "larger than {} MiB: not a profile file",
            MAX_PROFILE_BYTES >> 20
        ));
    }
    String::from_utf8(bytes).map_err(|e| format!("not UTF-8 text: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        Profile::from_toml("p.toml", "p", text)
            .expect_err("must fail")
            .to_string()
    }

    #[test]
    fn the_built_ins_are_consistent() {
        for name in BUILT_IN {
            let p = Profile::built_in(name).expect(name);
            assert_eq!(p.name, name);
            assert_eq!(p.check(), Ok(()), "{name}");
        }
        let quiet = Profile::built_in("quiet").expect("quiet");
        assert!(ActivityKind::ALL
            .iter()
            .filter(|k| k.is_fault())
            .all(|k| quiet.event.weight(*k) == 0));
        assert_eq!(quiet.pulse_error_rate.choices().count(), 1);
        // The noisy profile's line noise stays where a lift serves its calls.
        let noisy = Profile::built_in("noisy").expect("noisy");
        assert!(noisy.pulse_error_rate.choices().all(|(r, _)| r <= 3e-3));
        assert_eq!(noisy.pulse_error_rate.weight(3e-3), 1);
        assert!(Profile::built_in("loud").is_none());
    }

    #[test]
    fn a_file_changes_its_base() {
        let p = Profile::from_toml(
            "p.toml",
            "mine",
            "base = \"quiet\"\nduration = [\"2min\", \"3min\"]\nevents = [0, 5]\n\
             [floors]\n2 = 0\n[event]\nslave = 4\n[scan]\n\"2ms\" = 3\n",
        )
        .expect("valid");
        assert_eq!(p.name, "mine");
        assert_eq!(
            p.duration,
            (SimDuration::from_secs(120), SimDuration::from_secs(180))
        );
        assert_eq!(p.floors.weight(2), 0);
        assert_eq!(p.floors.weight(4), 2);
        assert_eq!(p.event.weight(ActivityKind::Slave), 4);
        assert_eq!(p.event.weight(ActivityKind::Vane), 0);
        assert_eq!(p.scan.weight(SimDuration::from_millis(2)), 3);
    }

    #[test]
    fn bad_profiles_are_named() {
        assert!(err("floors = 3\n").starts_with("--profile p.toml: "));
        assert!(err("speed = 3\n").contains("unknown field `speed`"));
        assert!(err("base = \"loud\"\n").contains("base: unknown built-in profile `loud`"));
        assert!(err("[floors]\n5 = 1\n").contains("[floors] `5`"));
        assert!(err("[event]\nmeteor = 1\n").contains("[event] `meteor`: unknown event kind"));
        assert!(err("[scan]\n\"30ms\" = 1\n").contains("1..20 ms"));
        assert!(
            err("[pulse_error_rate]\n\"2\" = 1\n").contains("a pulse error rate is a probability")
        );
        assert!(err("duration = [\"3min\", \"2min\"]\n")
            .contains("duration: 180 s is longer than 120 s"));
        assert!(err("duration = [\"40s\", \"2min\"]\n").contains("too short"));
        assert!(err("duration = [\"2 fortnights\", \"2min\"]\n").contains("duration: unknown unit"));
        assert!(err("events = [9, 3]\n").contains("events: [9, 3]"));
        assert!(err("door_open_chance = 1.5\n").contains("door_open_chance: 1.5"));
        assert!(err("[algorithm]\nfifo = 0\ncollective = 0\n")
            .contains("algorithm: every weight is zero"));
        let missing = Profile::resolve("no/such/profile.toml").expect_err("missing");
        assert!(
            missing
                .to_string()
                .contains("no such built-in profile or file"),
            "{missing}"
        );
        assert!(
            missing.to_string().contains("default, quiet, noisy"),
            "{missing}"
        );
    }

    #[test]
    fn weights_draw_only_weighted_choices() {
        use rand::SeedableRng;
        let w = Weights::new(vec![(1u8, 0), (2, 3), (3, 1)]);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut seen = [0u32; 4];
        for _ in 0..4000 {
            seen[w.pick(&mut rng).expect("weighted") as usize] += 1;
        }
        assert_eq!(seen[1], 0);
        assert!((2800..3200).contains(&seen[2]), "{seen:?}");
        assert_eq!(Weights::new(vec![(1u8, 0)]).pick(&mut rng), None);
    }
}
