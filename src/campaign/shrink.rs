//! Shrinking a failing run to a minimal scenario that still fails the same way: the same
//! outcome and the same first violation kind ([`super::Verdict::signature`]).
//!
//! Deterministic, and bounded by a budget of runs. The steps, each kept only if the run
//! still fails the same way:
//!
//! 1. a run with a violation is cut to the whole second after its first violation plus 1 s
//!    (later events go);
//! 2. the line noise, the extra slaves and an unusual PLC scan are set back to 0, 0 and 10 ms;
//! 3. the recovery and the probe move earlier, to 6 s after the last other event;
//! 4. events are dropped in chunks, halving the chunk down to single events (delta
//!    debugging); an out-of-service run keeps its acknowledge, reset and probe, and drops a
//!    repair only where nothing is left broken without it (a lift left broken on purpose is
//!    no finding), other runs may lose them too;
//! 5. steps 3 and 1 again, for the smaller run.

use super::generate::Probe;
use super::{execute, judge, Execution, Outcome, Verdict};
use crate::scenario::{Action, Fault, Scenario};
use asi_phy::{SimDuration, SimTime};

/// A run to shrink: its scenario, which events are the recovery and the probe, the probe.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// The scenario.
    pub scenario: Scenario,
    /// `tail[i]`: event `i` belongs to the recovery or is the probe.
    pub tail: Vec<bool>,
    /// The probe, while its event is still there.
    pub probe: Option<Probe>,
}

/// The smallest case found, how it ran and what it cost.
#[derive(Clone, Debug)]
pub struct Shrunk {
    /// The case.
    pub case: Case,
    /// Its run.
    pub execution: Execution,
    /// Its judgement (the same signature as the original's).
    pub verdict: Verdict,
    /// Runs spent shrinking.
    pub attempts: u32,
}

struct Shrinker {
    target: (Outcome, Option<String>),
    budget: u32,
    attempts: u32,
    best: Case,
    execution: Execution,
    verdict: Verdict,
}

impl Shrinker {
    /// Runs `cand` if the budget allows; keeps it if it fails the same way.
    fn attempt(&mut self, cand: Case) -> bool {
        if self.attempts >= self.budget || cand == self.best {
            return false;
        }
        if self.target.0 == Outcome::OutOfService && !repaired(&cand) {
            return false;
        }
        self.attempts += 1;
        let exec = execute(&cand.scenario);
        let verdict = judge(&exec, cand.probe.as_ref());
        let (o, k) = verdict.signature();
        if (o, k) != (self.target.0, self.target.1.as_deref()) {
            return false;
        }
        self.best = cand;
        self.execution = exec;
        self.verdict = verdict;
        true
    }

    fn shorten(&mut self) {
        let Execution::Report(r) = &self.execution else {
            return;
        };
        let Some(v) = r.violations.first() else {
            return;
        };
        let end = SimDuration::from_secs(v.at_s.ceil() as u64 + 1);
        if end < self.best.scenario.duration {
            let cand = truncate(&self.best, end);
            self.attempt(cand);
        }
    }

    fn simplify(&mut self) {
        let steps: [fn(&mut Scenario) -> bool; 3] = [
            |s| std::mem::replace(&mut s.pulse_error_rate, 0.0) != 0.0,
            |s| std::mem::replace(&mut s.extra_slaves, 0) != 0,
            |s| {
                let ten = SimDuration::from_millis(10);
                std::mem::replace(&mut s.plc_scan, ten) != ten
            },
        ];
        for step in steps {
            let mut cand = self.best.clone();
            if step(&mut cand.scenario) {
                self.attempt(cand);
            }
        }
    }

    /// Moves the recovery and the probe earlier, to 6 s after the last other event (at
    /// least 10 s into the run), and ends the run as much earlier.
    fn compress(&mut self) {
        let c = &self.best;
        let Some(first_tail) = c.tail.iter().position(|t| *t) else {
            return;
        };
        let tail_at = c.scenario.events[first_tail].at;
        let last = c.scenario.events[..first_tail]
            .iter()
            .map(|e| e.at)
            .max()
            .unwrap_or(SimTime::ZERO);
        let to = (last + SimDuration::from_secs(6)).max(SimTime::from_millis(10_000));
        if to >= tail_at {
            return;
        }
        let delta = tail_at - to;
        let mut cand = c.clone();
        for (e, t) in cand.scenario.events.iter_mut().zip(&cand.tail) {
            if *t {
                e.at = SimTime::ZERO + e.at.saturating_duration_since(SimTime::ZERO + delta);
            }
        }
        if let Some(p) = cand.probe.as_mut() {
            p.at = SimTime::ZERO + p.at.saturating_duration_since(SimTime::ZERO + delta);
        }
        cand.scenario.duration = cand.scenario.duration.saturating_sub(delta);
        self.attempt(cand);
    }

    fn drop_events(&mut self) {
        let keep_tail = self.target.0 == Outcome::OutOfService;
        // An out-of-service run keeps its acknowledge, reset and probe; a repair of the
        // recovery may go once nothing needs it ([`repaired`]).
        let droppable = |c: &Case| -> Vec<usize> {
            (0..c.scenario.events.len())
                .filter(|i| {
                    !(keep_tail
                        && c.tail[*i]
                        && matches!(
                            c.scenario.events[*i].action,
                            Action::Ack | Action::Reset | Action::Press { .. }
                        ))
                })
                .collect()
        };
        let mut chunk = droppable(&self.best).len().div_ceil(2).max(1);
        loop {
            let mut i = 0;
            loop {
                let d = droppable(&self.best);
                if i >= d.len() || self.attempts >= self.budget {
                    break;
                }
                let gone = &d[i..(i + chunk).min(d.len())];
                let cand = without(&self.best, gone);
                if !self.attempt(cand) {
                    i += chunk;
                }
            }
            if chunk == 1 || self.attempts >= self.budget {
                break;
            }
            chunk = chunk.div_ceil(2);
        }
    }
}

/// `true` if nothing the scenario breaks is left broken at its end: every slave taken
/// offline is back, every vane sensor works (but one the probe does not judge), the load is
/// at most full and the door closed. Only such a scenario can show a lift out of service.
fn repaired(case: &Case) -> bool {
    let sc = &case.scenario;
    let mut offline = std::collections::BTreeSet::new();
    let mut vanes = 0usize;
    let mut broken = [false; 2];
    let (mut load, mut closed) = (sc.load, sc.door_closed);
    for e in &sc.events {
        match &e.action {
            Action::Fault(Fault::SlaveOffline { slave }) => {
                offline.insert(*slave);
            }
            Action::Fault(Fault::SlaveOnline { slave }) => {
                offline.remove(slave);
            }
            Action::Fault(Fault::Vane { sensor, fault }) => {
                let i = usize::from(*sensor == lift_model::VaneSensor::Right);
                broken[i] = *fault != lift_model::SensorFault::None;
            }
            Action::Load(l) => load = *l,
            Action::Door { closed: c } => closed = *c,
            _ => {}
        }
    }
    vanes += broken.iter().filter(|b| **b).count();
    let judged = case.probe.is_none_or(|p| p.judged);
    offline.is_empty()
        && (vanes == 0 || !judged)
        && load != lift_model::LoadLevel::Overloaded
        && closed
}

/// `case` without the events at the sorted indices `gone` (the probe goes with its event).
fn without(case: &Case, gone: &[usize]) -> Case {
    let mut out = Case {
        scenario: Scenario {
            events: Vec::new(),
            ..case.scenario.clone()
        },
        tail: Vec::new(),
        probe: None,
    };
    for (i, (e, t)) in case.scenario.events.iter().zip(&case.tail).enumerate() {
        if gone.binary_search(&i).is_err() {
            out.scenario.events.push(e.clone());
            out.tail.push(*t);
        }
    }
    out.probe = case.probe.filter(|p| has_probe_event(&out, p));
    out
}

/// `case` cut to `duration`: the events from then on go.
fn truncate(case: &Case, duration: SimDuration) -> Case {
    let end = SimTime::ZERO + duration;
    let gone: Vec<usize> = (0..case.scenario.events.len())
        .filter(|i| case.scenario.events[*i].at >= end)
        .collect();
    let mut out = without(case, &gone);
    out.scenario.duration = duration;
    out
}

fn has_probe_event(case: &Case, p: &Probe) -> bool {
    case.scenario.events.iter().zip(&case.tail).any(|(e, t)| {
        *t && e.at == p.at
            && matches!(e.action, crate::scenario::Action::Press {
                    button: lift_model::Button::Cabin(f), ..
                } if f == p.floor)
    })
}

/// Shrinks `case`, which ran as `execution` and was judged `verdict` (a failure), spending
/// at most `budget` runs. With a budget of 0 the case comes back as it is.
pub fn shrink(case: Case, execution: Execution, verdict: Verdict, budget: u32) -> Shrunk {
    let target = (verdict.outcome, verdict.first_violation.clone());
    let mut s = Shrinker {
        target,
        budget,
        attempts: 0,
        best: case,
        execution,
        verdict,
    };
    s.shorten();
    s.simplify();
    s.compress();
    s.drop_events();
    s.compress();
    s.shorten();
    Shrunk {
        case: s.best,
        execution: s.execution,
        verdict: s.verdict,
        attempts: s.attempts,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::ScenarioEvent;
    use lift_model::{Button, LoadLevel};

    fn press(s: u64, button: Button) -> ScenarioEvent {
        ScenarioEvent {
            at: SimTime::from_millis(s * 1000),
            action: Action::Press {
                button,
                hold: crate::scenario::DEFAULT_HOLD,
            },
            line: 0,
        }
    }

    #[test]
    fn an_out_of_service_run_keeps_its_tail_and_loses_the_rest() {
        // Overloaded to the end: the probe cannot be served (a lift that is right to refuse,
        // which is all this test needs). The calls before are noise for the shrinker.
        let mut events = vec![
            press(2, Button::Cabin(2)),
            press(3, Button::HallUp(1)),
            press(4, Button::Cabin(1)),
        ];
        events.push(ScenarioEvent {
            at: SimTime::from_millis(5000),
            action: Action::Load(LoadLevel::Overloaded),
            line: 0,
        });
        events.push(press(8, Button::Cabin(2)));
        let tail = vec![false, false, false, false, true];
        let probe = Probe {
            at: SimTime::from_millis(8000),
            floor: 2,
            judged: true,
        };
        let case = Case {
            scenario: Scenario {
                name: "overloaded".into(),
                floors: 2,
                start_mm: 0.0,
                duration: SimDuration::from_secs(25),
                pulse_error_rate: 1e-3,
                events,
                ..Scenario::defaults()
            },
            tail,
            probe: Some(probe),
        };
        let exec = execute(&case.scenario);
        let verdict = judge(&exec, case.probe.as_ref());
        assert_eq!(verdict.outcome, Outcome::OutOfService, "{exec:?}");
        let s = shrink(case.clone(), exec.clone(), verdict.clone(), 0);
        assert_eq!((s.case, s.attempts), (case.clone(), 0));
        let s = shrink(case, exec, verdict, 40);
        assert_eq!(s.verdict.outcome, Outcome::OutOfService);
        assert_eq!(s.case.scenario.pulse_error_rate, 0.0);
        let kept: Vec<&Action> = s.case.scenario.events.iter().map(|e| &e.action).collect();
        assert_eq!(kept.len(), 2, "{kept:?}");
        assert_eq!(kept[0], &Action::Load(LoadLevel::Overloaded));
        assert_eq!(s.case.probe, Some(probe));
        assert!(s.attempts <= 40);
    }
}
