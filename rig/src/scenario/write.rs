//! Writing a scenario back as a file that reads back to an equal scenario.

use super::{Action, Fault, Scenario, ScenarioEvent, DEFAULT_HOLD};
use asi_phy::{SimDuration, SimTime};
use controller::Algorithm;
use lift_model::{SensorFault, VaneSensor};
use std::fmt::Write as _;

impl Scenario {
    /// The scenario as a scenario file that [`Scenario::from_toml`] reads back to an equal
    /// scenario, but for the events' `line`s: every setting is written (defaults too),
    /// durations exactly in the largest unit that divides them (`"1500ms"`), numbers in their
    /// shortest exact form, and the events in time order (stable, as the reader sorts them;
    /// so a scenario whose events are in time order comes back unchanged).
    pub fn to_toml(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "name = {}", toml_string(&self.name));
        let _ = writeln!(s, "seed = {}", self.seed);
        let _ = writeln!(s, "duration = \"{}\"", exact_duration(self.duration));
        let _ = writeln!(
            s,
            "algorithm = \"{}\"",
            match self.algorithm {
                Algorithm::Fifo => "fifo",
                Algorithm::Collective => "collective",
            }
        );
        let _ = writeln!(s, "\n[lift]\nfloors = {}", self.floors);
        let _ = writeln!(s, "start_mm = {}", toml_float(self.start_mm));
        let _ = writeln!(s, "load = \"{}\"", self.load.name());
        let _ = writeln!(
            s,
            "door = \"{}\"",
            if self.door_closed { "closed" } else { "open" }
        );
        let _ = writeln!(
            s,
            "\n[bus]\npulse_error_rate = {}",
            toml_float(self.pulse_error_rate)
        );
        let _ = writeln!(s, "extra_slaves = {}", self.extra_slaves);
        // Written only when not the default, so that the files of scenarios without it stay
        // as they were.
        if self.master_mode == asi_master::Mode::Configuration {
            let _ = writeln!(s, "master_mode = \"configuration\"");
        }
        let _ = writeln!(
            s,
            "\n[controller]\nscan = \"{}\"",
            exact_duration(self.plc_scan)
        );
        if let Some(p) = &self.program {
            // Absolute, so that the file written (a campaign's reproducer) finds the program
            // wherever it is put.
            let absolute = |p: &std::path::Path| {
                let p = std::path::absolute(p).unwrap_or_else(|_| p.to_owned());
                toml_string(&p.to_string_lossy())
            };
            let _ = writeln!(s, "program = {}", absolute(p.path()));
            let libraries: Vec<String> = p.libraries().map(absolute).collect();
            if !libraries.is_empty() {
                let _ = writeln!(s, "library = [{}]", libraries.join(", "));
            }
        }
        let _ = writeln!(s, "\n[safety]\npower_on_reset = {}", self.power_on_reset);
        // Written only when on, so that the files of scenarios without it stay as they were.
        if self.safe_drive {
            let _ = writeln!(s, "\n[drive]\nsafe = true");
        }
        let mut events: Vec<&ScenarioEvent> = self.events.iter().collect();
        events.sort_by_key(|e| e.at);
        for e in events {
            let at = exact_duration(e.at.saturating_duration_since(SimTime::ZERO));
            let _ = writeln!(s, "\n[[event]]\nat = \"{at}\"");
            let _ = match &e.action {
                Action::Press { button, hold } => {
                    let _ = writeln!(s, "press = \"{}\"", button.key());
                    if *hold != DEFAULT_HOLD {
                        let _ = writeln!(s, "hold = \"{}\"", exact_duration(*hold));
                    }
                    Ok(())
                }
                Action::Load(l) => writeln!(s, "load = \"{}\"", l.name()),
                Action::Door { closed } => {
                    writeln!(s, "door = \"{}\"", if *closed { "closed" } else { "open" })
                }
                Action::Crank { mm } => writeln!(s, "crank_mm = {}", toml_float(*mm)),
                Action::Reset => writeln!(s, "reset = true"),
                Action::Rescue => writeln!(s, "rescue = true"),
                Action::Ack => writeln!(s, "ack = true"),
                Action::Attend => writeln!(s, "attend = true"),
                Action::Fault(f) => writeln!(s, "fault = {}", fault_text(f)),
            };
        }
        for t in &self.traffic {
            let _ = writeln!(s, "\n[[traffic]]\npattern = \"{}\"", t.pattern.name());
            let _ = writeln!(s, "per_minute = {}", toml_float(t.per_minute));
            if let Some(seed) = t.seed {
                let _ = writeln!(s, "seed = {seed}");
            }
            let _ = writeln!(s, "start = \"{}\"", exact_duration(t.start));
            if let Some(d) = t.duration {
                let _ = writeln!(s, "duration = \"{}\"", exact_duration(d));
            }
        }
        s
    }
}

/// A TOML basic string: quoted, with `"`, `\\` and control characters escaped.
fn toml_string(text: &str) -> String {
    let mut s = String::with_capacity(text.len() + 2);
    s.push('"');
    for c in text.chars() {
        match c {
            '"' => s.push_str("\\\""),
            '\\' => s.push_str("\\\\"),
            '\n' => s.push_str("\\n"),
            '\t' => s.push_str("\\t"),
            '\r' => s.push_str("\\r"),
            c if c.is_control() => {
                let _ = write!(s, "\\u{:04X}", c as u32);
            }
            c => s.push(c),
        }
    }
    s.push('"');
    s
}

/// A finite number as TOML reads it back exactly: Rust's shortest round-trip form, which
/// always has a decimal point or an exponent (`650.0`, `0.001`, `1e-5`).
fn toml_float(v: f64) -> String {
    format!("{v:?}")
}

/// A duration in the largest unit that divides it, so that it reads back exactly.
fn exact_duration(d: SimDuration) -> String {
    let ns = d.as_nanos();
    for (scale, unit) in [(1_000_000_000, "s"), (1_000_000, "ms"), (1_000, "us")] {
        if ns % scale == 0 {
            return format!("{}{unit}", ns / scale);
        }
    }
    format!("{ns}ns")
}

/// A fault as the scenario file's inline table.
fn fault_text(f: &Fault) -> String {
    let side = |s: &VaneSensor| match s {
        VaneSensor::Left => "left",
        VaneSensor::Right => "right",
    };
    match f {
        Fault::SlaveOffline { slave } => format!("{{ kind = \"slave-offline\", slave = {slave} }}"),
        Fault::SlaveOnline { slave } => format!("{{ kind = \"slave-online\", slave = {slave} }}"),
        Fault::PowerFail { duration } => format!(
            "{{ kind = \"power-fail\", duration = \"{}\" }}",
            exact_duration(*duration)
        ),
        Fault::SafeLinkDrop { duration } => format!(
            "{{ kind = \"safe-link-drop\", duration = \"{}\" }}",
            exact_duration(*duration)
        ),
        Fault::Vane { sensor, fault } => {
            let kind = match fault {
                SensorFault::StuckOn => "vane-stuck-on",
                SensorFault::StuckOff => "vane-stuck-off",
                SensorFault::None => "vane-repaired",
            };
            format!("{{ kind = \"{kind}\", sensor = \"{}\" }}", side(sensor))
        }
        Fault::ConverterRunaway { up } => format!(
            "{{ kind = \"converter-runaway\", direction = \"{}\" }}",
            if *up { "up" } else { "down" }
        ),
        Fault::ConverterRepaired => "{ kind = \"converter-repaired\" }".into(),
        Fault::EncoderFailed => "{ kind = \"encoder-failed\" }".into(),
        Fault::EncoderRepaired => "{ kind = \"encoder-repaired\" }".into(),
        Fault::LineNoise { rate, duration } => format!(
            "{{ kind = \"line-noise\", rate = {rate:?}, duration = \"{}\" }}",
            exact_duration(*duration)
        ),
    }
}
