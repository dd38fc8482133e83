//! Helpers of the end-to-end tests: run a scenario file of `scenarios/` or a built scenario on
//! the whole rig and read its report.

use controller::ProgramEventKind;
use rig::report::{LogEvent, Report};
use rig::rig::Rig;
use rig::scenario::Scenario;
use safety::LiftSafetyCause;
use std::path::PathBuf;

/// The scenario `scenarios/<name>.toml` of the repository.
pub fn scenario(name: &str) -> Scenario {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("scenarios")
        .join(format!("{name}.toml"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Scenario::from_toml(&path.display().to_string(), &text).unwrap_or_else(|e| panic!("{e}"))
}

/// Runs `sc` to its end.
pub fn run(sc: Scenario) -> Report {
    Rig::new(sc)
        .unwrap_or_else(|e| panic!("rig: {e}"))
        .run(None)
}

/// Runs a scenario given as the body of a scenario file (a reproducer pasted from an issue or
/// a campaign).
pub fn run_toml(name: &str, body: &str) -> Report {
    run(Scenario::from_toml(name, body).unwrap_or_else(|e| panic!("{e}")))
}

/// Runs the scenario file `name`.
pub fn run_file(name: &str) -> Report {
    run(scenario(name))
}

/// The floors the cabin came to rest at, in order.
pub fn stops(r: &Report) -> Vec<u8> {
    r.arrivals.iter().map(|a| a.floor).collect()
}

/// The floors the cabin came to rest at within `from_s..to_s`.
pub fn stops_between(r: &Report, from_s: f64, to_s: f64) -> Vec<u8> {
    r.arrivals
        .iter()
        .filter(|a| a.at_s >= from_s && a.at_s < to_s)
        .map(|a| a.floor)
        .collect()
}

/// The calls served as (floor, source), in order.
pub fn served(r: &Report) -> Vec<(u8, String)> {
    r.served
        .iter()
        .map(|s| (s.floor, s.source.to_string()))
        .collect()
}

/// The first time the log has an event `is` accepts.
pub fn event_at(r: &Report, is: impl Fn(&LogEvent) -> bool) -> Option<f64> {
    r.log.iter().find(|l| is(&l.event)).map(|l| l.at_s)
}

/// The first time after `after_s` the log has an event `is` accepts.
pub fn event_after(r: &Report, is: impl Fn(&LogEvent) -> bool, after_s: f64) -> Option<f64> {
    r.log
        .iter()
        .find(|l| l.at_s > after_s && is(&l.event))
        .map(|l| l.at_s)
}

/// `true` if the log has an event `is` accepts.
pub fn has_event(r: &Report, is: impl Fn(&LogEvent) -> bool) -> bool {
    event_at(r, is).is_some()
}

/// The built-in program's event `e`.
pub fn program(e: ProgramEventKind) -> impl Fn(&LogEvent) -> bool {
    move |l| *l == LogEvent::Controller(e)
}

/// A safety-logic event `is` accepts.
pub fn safety_event(is: impl Fn(&LiftSafetyCause) -> bool) -> impl Fn(&LogEvent) -> bool {
    move |l| matches!(l, LogEvent::Safety(c) if is(c))
}

/// Asserts that the run broke no safety invariant, printing the log if it did.
pub fn assert_no_violations(r: &Report) {
    assert!(
        r.violations.is_empty(),
        "violations: {:?}\n{}",
        r.violations,
        r.to_text()
    );
}

/// A writer the test can read back after the rig has written to it.
#[derive(Clone, Default)]
pub struct Shared(pub std::rc::Rc<std::cell::RefCell<Vec<u8>>>);

impl std::io::Write for Shared {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.borrow_mut().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Shared {
    /// Everything written so far.
    pub fn bytes(&self) -> Vec<u8> {
        self.0.borrow().clone()
    }
}
