//! The catalogue of single faults: every kind the explorer injects, each as the scenario
//! events it stands for, so that a fork's fault and the same fault written into a scenario
//! file are one thing (the scenario's `Action` and `Fault` are the vocabulary; the campaign's
//! generator draws from the same actions).

use crate::scenario::{Action, Fault, Scenario, DEFAULT_HOLD};
use asi_phy::SimDuration;
use lift_model::{Button, LoadLevel, SensorFault, VaneSensor};
use std::fmt;
use std::str::FromStr;

/// One kind of fault of the catalogue.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FaultKind {
    /// A slave of the lab bus is taken off the bus and put back after the catalogue's
    /// [`Params::off_for`].
    SlaveOff(u8),
    /// A vane sensor's output is stuck on (`true`) or off, for good.
    VaneStuck(VaneSensor, bool),
    /// The AS-i supply fails for [`Params::power_fail`].
    PowerFail,
    /// The cabin STOP terminal's safe link is silent for [`Params::link_drop`].
    SafeLinkDrop,
    /// A burst of line noise: [`Params::noise_rate`] for [`Params::noise_for`].
    LineNoise,
    /// The converter runs away, up (`true`) or down, for good.
    Runaway(bool),
    /// The safe drive's encoder fails, for good (only in scenarios with the safe drive).
    EncoderFailed,
    /// The load becomes overloaded, and stays so.
    Overload,
    /// The door is opened by hand, and stays open.
    DoorOpen,
    /// STOP is pressed for a person's push ([`DEFAULT_HOLD`]).
    Stop,
    /// Someone tries the hand crank ([`Params::crank_mm`]): it turns only without power.
    Crank,
}

/// The sizes of the catalogue's faults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// How long a slave stays off the bus.
    pub off_for: SimDuration,
    /// How long a power fail lasts.
    pub power_fail: SimDuration,
    /// How long the safe link is silent.
    pub link_drop: SimDuration,
    /// A burst of line noise: the probability a pulse is corrupted.
    pub noise_rate: f64,
    /// How long a burst of line noise lasts.
    pub noise_for: SimDuration,
    /// How far the hand crank is turned, mm (up).
    pub crank_mm: f64,
}

impl Default for Params {
    fn default() -> Params {
        Params {
            off_for: SimDuration::from_secs(2),
            power_fail: SimDuration::from_secs(1),
            link_drop: SimDuration::from_millis(500),
            noise_rate: 0.01,
            noise_for: SimDuration::from_millis(500),
            crank_mm: 5.0,
        }
    }
}

impl FaultKind {
    /// Every kind the catalogue has for `sc`: each slave of the lab bus, each vane sensor
    /// stuck either way, the transient faults, both runaways, the encoder with the safe
    /// drive, and the people's.
    pub fn all_for(sc: &Scenario) -> Vec<FaultKind> {
        let mut kinds: Vec<FaultKind> = lab::address::ALL
            .iter()
            .map(|a| FaultKind::SlaveOff(*a))
            .collect();
        for sensor in [VaneSensor::Left, VaneSensor::Right] {
            for on in [true, false] {
                kinds.push(FaultKind::VaneStuck(sensor, on));
            }
        }
        kinds.extend([
            FaultKind::PowerFail,
            FaultKind::SafeLinkDrop,
            FaultKind::LineNoise,
            FaultKind::Runaway(true),
            FaultKind::Runaway(false),
        ]);
        if sc.safe_drive {
            kinds.push(FaultKind::EncoderFailed);
        }
        kinds.extend([
            FaultKind::Overload,
            FaultKind::DoorOpen,
            FaultKind::Stop,
            FaultKind::Crank,
        ]);
        kinds
    }

    /// Its name (`--kinds`, the lines): `slave-off:7`, `vane-left-stuck-on`, `power-fail`, …
    pub fn name(self) -> String {
        match self {
            FaultKind::SlaveOff(a) => format!("slave-off:{a}"),
            FaultKind::VaneStuck(s, on) => {
                format!("vane-{}-stuck-{}", side(s), if on { "on" } else { "off" })
            }
            FaultKind::PowerFail => "power-fail".into(),
            FaultKind::SafeLinkDrop => "safe-link-drop".into(),
            FaultKind::LineNoise => "line-noise".into(),
            FaultKind::Runaway(up) => format!("runaway-{}", if up { "up" } else { "down" }),
            FaultKind::EncoderFailed => "encoder-failed".into(),
            FaultKind::Overload => "overload".into(),
            FaultKind::DoorOpen => "door-open".into(),
            FaultKind::Stop => "stop".into(),
            FaultKind::Crank => "crank".into(),
        }
    }

    /// What the fault is, as scenario actions at offsets from its injection (in time order).
    pub fn actions(self, p: &Params) -> Vec<(SimDuration, Action)> {
        let now = SimDuration::ZERO;
        let fault = |f: Fault| Action::Fault(f);
        match self {
            FaultKind::SlaveOff(slave) => vec![
                (now, fault(Fault::SlaveOffline { slave })),
                (p.off_for, fault(Fault::SlaveOnline { slave })),
            ],
            FaultKind::VaneStuck(sensor, on) => vec![(
                now,
                fault(Fault::Vane {
                    sensor,
                    fault: if on {
                        SensorFault::StuckOn
                    } else {
                        SensorFault::StuckOff
                    },
                }),
            )],
            FaultKind::PowerFail => vec![(
                now,
                fault(Fault::PowerFail {
                    duration: p.power_fail,
                }),
            )],
            FaultKind::SafeLinkDrop => vec![(
                now,
                fault(Fault::SafeLinkDrop {
                    duration: p.link_drop,
                }),
            )],
            FaultKind::LineNoise => vec![(
                now,
                fault(Fault::LineNoise {
                    rate: p.noise_rate,
                    duration: p.noise_for,
                }),
            )],
            FaultKind::Runaway(up) => vec![(now, fault(Fault::ConverterRunaway { up }))],
            FaultKind::EncoderFailed => vec![(now, fault(Fault::EncoderFailed))],
            FaultKind::Overload => vec![(now, Action::Load(LoadLevel::Overloaded))],
            FaultKind::DoorOpen => vec![(now, Action::Door { closed: false })],
            FaultKind::Stop => vec![(
                now,
                Action::Press {
                    button: Button::Stop,
                    hold: DEFAULT_HOLD,
                },
            )],
            FaultKind::Crank => vec![(now, Action::Crank { mm: p.crank_mm })],
        }
    }
}

fn side(s: VaneSensor) -> &'static str {
    match s {
        VaneSensor::Left => "left",
        VaneSensor::Right => "right",
    }
}

impl fmt::Display for FaultKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

/// The names `--kinds` takes besides each kind's own: a group of kinds.
pub const GROUPS: [(&str, &str); 3] = [
    ("slave-off", "every slave of the lab bus off"),
    ("vane", "each vane sensor stuck on and off"),
    ("runaway", "the converter running away up and down"),
];

impl FromStr for FaultKind {
    type Err = String;

    fn from_str(s: &str) -> Result<FaultKind, String> {
        let all = every_name();
        if let Some(a) = s.strip_prefix("slave-off:") {
            return match a.parse::<u8>() {
                Ok(a) if lab::address::ALL.contains(&a) => Ok(FaultKind::SlaveOff(a)),
                _ => Err(format!(
                    "`{s}`: no slave {a} on the lab bus (its slaves: {})",
                    lab::address::ALL.map(|a| a.to_string()).join(", ")
                )),
            };
        }
        all.into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("`{s}`: unknown fault kind ({})", known_kinds()))
    }
}

/// Every kind of the catalogue, the encoder's included.
fn every_name() -> Vec<FaultKind> {
    let mut sc = Scenario::defaults();
    sc.safe_drive = true;
    FaultKind::all_for(&sc)
}

/// The names `--kinds` knows, in words.
pub fn known_kinds() -> String {
    let mut names: Vec<String> = vec!["slave-off:N".into()];
    names.extend(
        every_name()
            .into_iter()
            .filter(|k| !matches!(k, FaultKind::SlaveOff(_)))
            .map(FaultKind::name),
    );
    names.extend(GROUPS.iter().map(|(g, _)| g.to_string()));
    format!("use {}", names.join(", "))
}

/// Reads `--kinds`: comma-separated kinds or groups, in the catalogue's order, each once;
/// `encoder-failed` only for a scenario with the safe drive.
pub fn parse_kinds(text: &str, sc: &Scenario) -> Result<Vec<FaultKind>, String> {
    let all = FaultKind::all_for(sc);
    let mut chosen: Vec<FaultKind> = Vec::new();
    for word in text.split(',').map(str::trim) {
        if word.is_empty() {
            return Err(format!("`{text}`: an empty kind between commas"));
        }
        let group: Vec<FaultKind> = match word {
            "slave-off" => all
                .iter()
                .copied()
                .filter(|k| matches!(k, FaultKind::SlaveOff(_)))
                .collect(),
            "vane" => all
                .iter()
                .copied()
                .filter(|k| matches!(k, FaultKind::VaneStuck(..)))
                .collect(),
            "runaway" => vec![FaultKind::Runaway(true), FaultKind::Runaway(false)],
            _ => {
                let k: FaultKind = word.parse()?;
                if !all.contains(&k) {
                    return Err(format!(
                        "`{word}`: needs `[drive] safe = true` in the scenario (the lab lift's only encoder is the safe drive's)"
                    ));
                }
                vec![k]
            }
        };
        chosen.extend(group);
    }
    // The catalogue's order, whatever the order given: the lines do not depend on it.
    let mut kinds: Vec<FaultKind> = all.into_iter().filter(|k| chosen.contains(k)).collect();
    kinds.dedup();
    Ok(kinds)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of the catalogue for each kind: its name, and the scenario events it stands for.
    #[test]
    fn the_catalogue_row_by_row() {
        let p = Params::default();
        let mut sc = Scenario::defaults();
        sc.safe_drive = true;
        let rows: Vec<String> = FaultKind::all_for(&sc)
            .into_iter()
            .map(|k| {
                let acts: Vec<String> = k
                    .actions(&p)
                    .iter()
                    .map(|(at, a)| format!("+{at}: {a}"))
                    .collect();
                format!("{}: {}", k.name(), acts.join("; "))
            })
            .collect();
        let want = [
            "slave-off:1: +0 ns: fault: slave 1 taken off the bus; +2 s: fault cleared: slave 1 back on the bus",
            "slave-off:2: +0 ns: fault: slave 2 taken off the bus; +2 s: fault cleared: slave 2 back on the bus",
            "slave-off:3: +0 ns: fault: slave 3 taken off the bus; +2 s: fault cleared: slave 3 back on the bus",
            "slave-off:4: +0 ns: fault: slave 4 taken off the bus; +2 s: fault cleared: slave 4 back on the bus",
            "slave-off:5: +0 ns: fault: slave 5 taken off the bus; +2 s: fault cleared: slave 5 back on the bus",
            "slave-off:6: +0 ns: fault: slave 6 taken off the bus; +2 s: fault cleared: slave 6 back on the bus",
            "slave-off:7: +0 ns: fault: slave 7 taken off the bus; +2 s: fault cleared: slave 7 back on the bus",
            "slave-off:8: +0 ns: fault: slave 8 taken off the bus; +2 s: fault cleared: slave 8 back on the bus",
            "slave-off:10: +0 ns: fault: slave 10 taken off the bus; +2 s: fault cleared: slave 10 back on the bus",
            "slave-off:11: +0 ns: fault: slave 11 taken off the bus; +2 s: fault cleared: slave 11 back on the bus",
            "slave-off:12: +0 ns: fault: slave 12 taken off the bus; +2 s: fault cleared: slave 12 back on the bus",
            "vane-left-stuck-on: +0 ns: fault: the Snimac_1 (left) vane sensor is stuck on",
            "vane-left-stuck-off: +0 ns: fault: the Snimac_1 (left) vane sensor is stuck off",
            "vane-right-stuck-on: +0 ns: fault: the Snimac_2 (right) vane sensor is stuck on",
            "vane-right-stuck-off: +0 ns: fault: the Snimac_2 (right) vane sensor is stuck off",
            "power-fail: +0 ns: fault: AS-i power fails for 1 s",
            "safe-link-drop: +0 ns: fault: the cabin STOP safe link is silent for 500 ms",
            "line-noise: +0 ns: fault: a burst of line noise, pulse error rate 0.01, for 500 ms",
            "runaway-up: +0 ns: fault: the converter runs away up, against its commands",
            "runaway-down: +0 ns: fault: the converter runs away down, against its commands",
            "encoder-failed: +0 ns: fault: the safe drive's encoder cannot be read",
            "overload: +0 ns: load becomes overloaded",
            "door-open: +0 ns: door opened",
            "stop: +0 ns: STOP pressed for 300 ms",
            "crank: +0 ns: hand crank +5.0 mm",
        ];
        assert_eq!(rows, want);
        // Every name reads back as its kind.
        for k in FaultKind::all_for(&sc) {
            assert_eq!(k.name().parse::<FaultKind>(), Ok(k));
        }
        // Without the safe drive there is no encoder to fail.
        assert!(!FaultKind::all_for(&Scenario::defaults()).contains(&FaultKind::EncoderFailed));
    }

    #[test]
    fn kinds_are_read_in_the_catalogues_order() {
        let sc = Scenario::defaults();
        let k = parse_kinds("stop,slave-off:7,power-fail,stop", &sc).expect("kinds");
        assert_eq!(
            k,
            [
                FaultKind::SlaveOff(7),
                FaultKind::PowerFail,
                FaultKind::Stop
            ]
        );
        assert_eq!(parse_kinds("vane", &sc).expect("vane").len(), 4);
        assert_eq!(parse_kinds("slave-off", &sc).expect("all").len(), 11);
        let e = parse_kinds("stop,,crank", &sc).expect_err("empty");
        assert!(e.contains("empty kind"), "{e}");
        let e = parse_kinds("slave-off:9", &sc).expect_err("no slave 9");
        assert!(
            e.contains(
                "no slave 9 on the lab bus (its slaves: 1, 2, 3, 4, 5, 6, 7, 8, 10, 11, 12)"
            ),
            "{e}"
        );
        let e = parse_kinds("door-close", &sc).expect_err("unknown");
        assert!(
            e.starts_with("`door-close`: unknown fault kind (use slave-off:N, vane-left-stuck-on"),
            "{e}"
        );
        let e = parse_kinds("encoder-failed", &sc).expect_err("no safe drive");
        assert!(e.contains("[drive] safe = true"), "{e}");
    }
}
