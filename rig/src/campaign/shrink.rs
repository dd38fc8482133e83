//! Shrinking a failing run to a minimal scenario that still fails the same way: the same
//! outcome and the same first violation kind ([`super::RunVerdict::signature`]).
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

use super::generate::{recovery_index, Probe, RECOVERY_NOT_BEFORE};
use super::{execute, judge, Execution, RunOutcome, RunVerdict};
use crate::report::ViolationKind;
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
    pub verdict: RunVerdict,
    /// Runs spent shrinking.
    pub attempts: u32,
}

/// Runs a case and judges it.
pub type Oracle<'a> = &'a dyn Fn(&Case) -> (Execution, RunVerdict);

struct Shrinker<'a> {
    oracle: Oracle<'a>,
    target: (RunOutcome, Option<ViolationKind>),
    budget: u32,
    attempts: u32,
    best: Case,
    execution: Execution,
    verdict: RunVerdict,
}

impl Shrinker<'_> {
    /// Runs `cand` if the budget allows; keeps it if it fails the same way.
    fn attempt(&mut self, cand: Case) -> bool {
        if self.attempts >= self.budget || cand == self.best {
            return false;
        }
        if self.target.0 == RunOutcome::OutOfService && !repaired(&cand) {
            return false;
        }
        self.attempts += 1;
        let (exec, verdict) = (self.oracle)(&cand);
        let (o, k) = verdict.signature();
        if (o, k) != self.target {
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
        // The recovery and the probe (the operator's start procedure, also kept, stays where
        // it is).
        let Some(first_tail) = recovery_index(&c.tail, &c.scenario.events) else {
            return;
        };
        let tail_at = c.scenario.events[first_tail].at;
        let last = c.scenario.events[..first_tail]
            .iter()
            .map(|e| e.at)
            .max()
            .unwrap_or(SimTime::ZERO);
        let to = (last + SimDuration::from_secs(6)).max(RECOVERY_NOT_BEFORE);
        if to >= tail_at {
            return;
        }
        let delta = tail_at - to;
        let mut cand = c.clone();
        for (e, t) in cand
            .scenario
            .events
            .iter_mut()
            .zip(&cand.tail)
            .skip(first_tail)
        {
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
        let keep_tail = self.target.0 == RunOutcome::OutOfService;
        // An out-of-service run keeps its acknowledge, reset, attendant and probe; a repair of the
        // recovery may go once nothing needs it ([`repaired`]).
        let droppable = |c: &Case| -> Vec<usize> {
            (0..c.scenario.events.len())
                .filter(|i| {
                    !(keep_tail
                        && c.tail[*i]
                        && matches!(
                            c.scenario.events[*i].action,
                            Action::Ack
                                | Action::Reset
                                | Action::Rescue
                                | Action::Attend
                                | Action::Press { .. }
                                | Action::Crank { .. }
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
pub fn shrink(case: Case, execution: Execution, verdict: RunVerdict, budget: u32) -> Shrunk {
    let oracle = |c: &Case| {
        let exec = execute(&c.scenario);
        let verdict = judge(&exec, c.probe.as_ref());
        (exec, verdict)
    };
    shrink_with(&oracle, case, execution, verdict, budget)
}

/// [`shrink`] with another way to run and judge a case (for tests of the shrinker).
pub fn shrink_with(
    oracle: Oracle<'_>,
    case: Case,
    execution: Execution,
    verdict: RunVerdict,
    budget: u32,
) -> Shrunk {
    let target = (verdict.outcome, verdict.first_violation);
    let mut s = Shrinker {
        oracle,
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
    use crate::report::Violation;
    use crate::scenario::ScenarioEvent;
    use lift_model::{Button, LoadLevel};
    use std::cell::Cell;

    fn ev(ms: u64, action: Action) -> ScenarioEvent {
        ScenarioEvent {
            at: SimTime::from_millis(ms),
            action,
            line: 0,
        }
    }

    fn press(ms: u64, floor: u8) -> Action {
        let _ = ms;
        Action::Press {
            button: Button::Cabin(floor),
            hold: crate::scenario::DEFAULT_HOLD,
        }
    }

    /// A generated-looking case: noise, twelve events, then the recovery and the probe.
    fn case() -> Case {
        let mut events: Vec<ScenarioEvent> = (0..12u64)
            .map(|i| ev(2_000 + i * 3_000, press(0, 1 + (i % 3) as u8)))
            .collect();
        events[4] = ev(14_000, Action::Fault(Fault::SlaveOffline { slave: 6 }));
        events[7] = ev(23_000, Action::Load(LoadLevel::Overloaded));
        events[9] = ev(29_000, Action::Fault(Fault::SlaveOffline { slave: 2 }));
        let mut tail = vec![false; events.len()];
        for e in [
            ev(60_000, Action::Fault(Fault::SlaveOnline { slave: 2 })),
            ev(60_000, Action::Fault(Fault::SlaveOnline { slave: 6 })),
            ev(60_000, Action::Load(LoadLevel::Empty)),
            ev(64_000, Action::Ack),
            ev(65_000, Action::Reset),
            ev(70_000, press(0, 3)),
        ] {
            events.push(e);
            tail.push(true);
        }
        Case {
            scenario: Scenario {
                name: "shrink me".into(),
                duration: SimDuration::from_secs(130),
                pulse_error_rate: 1e-3,
                extra_slaves: 5,
                events,
                ..Scenario::defaults()
            },
            tail,
            probe: Some(Probe {
                at: SimTime::from_millis(70_000),
                floor: 3,
                judged: true,
            }),
        }
    }

    /// A report to hand back: a real one of a short run, its violations replaced.
    fn report(violations: Vec<Violation>) -> Execution {
        let sc = Scenario {
            duration: SimDuration::from_millis(50),
            ..Scenario::defaults()
        };
        match execute(&sc) {
            Execution::Report(mut r) => {
                r.violations = violations;
                Execution::Report(r)
            }
            other => panic!("a short run: {other:?}"),
        }
    }

    fn verdict(outcome: RunOutcome, kind: Option<ViolationKind>) -> RunVerdict {
        RunVerdict {
            outcome,
            in_service: None,
            first_violation: kind,
        }
    }

    #[test]
    fn a_violation_shrinks_to_its_cause_and_its_moment() {
        // The stand-in lift breaks an invariant 2 s after an overload if slave 6 went offline
        // before, and only on a noisy line; it knows nothing else.
        let runs = Cell::new(0);
        let oracle = |c: &Case| {
            runs.set(runs.get() + 1);
            let sc = &c.scenario;
            let offline = sc
                .events
                .iter()
                .position(|e| e.action == Action::Fault(Fault::SlaveOffline { slave: 6 }));
            let overload = sc
                .events
                .iter()
                .position(|e| e.action == Action::Load(LoadLevel::Overloaded));
            match (offline, overload) {
                (Some(a), Some(b)) if a < b && sc.pulse_error_rate > 0.0 => {
                    let at = sc.events[b].at.as_secs_f64() + 2.0;
                    let v = Violation {
                        at_s: at,
                        kind: ViolationKind::OverloadedMoving,
                        detail: String::new(),
                    };
                    (
                        report(vec![v]),
                        verdict(RunOutcome::Violation, Some(ViolationKind::OverloadedMoving)),
                    )
                }
                _ => (report(vec![]), verdict(RunOutcome::Ok, None)),
            }
        };
        let c = case();
        let (exec, v) = oracle(&c);
        let s = shrink_with(&oracle, c.clone(), exec.clone(), v.clone(), 100);
        let kept: Vec<&Action> = s.case.scenario.events.iter().map(|e| &e.action).collect();
        assert_eq!(
            kept,
            [
                &Action::Fault(Fault::SlaveOffline { slave: 6 }),
                &Action::Load(LoadLevel::Overloaded)
            ]
        );
        // Cut 1 s after the whole second of the violation (25 s); noise kept, slaves gone.
        assert_eq!(s.case.scenario.duration, SimDuration::from_secs(26));
        assert_eq!(s.case.scenario.pulse_error_rate, 1e-3);
        assert_eq!(s.case.scenario.extra_slaves, 0);
        assert_eq!(s.case.probe, None);
        assert_eq!(s.verdict, v);
        assert_eq!(s.attempts, runs.get() - 1);
        // Deterministic, bounded by the budget, and a budget of 0 leaves the case alone.
        let again = shrink_with(&oracle, c.clone(), exec.clone(), v.clone(), 100);
        assert_eq!(again.case, s.case);
        let few = shrink_with(&oracle, c.clone(), exec.clone(), v.clone(), 5);
        assert_eq!(few.attempts, 5);
        let none = shrink_with(&oracle, c.clone(), exec, v, 0);
        assert_eq!((none.case, none.attempts), (c, 0));
    }

    #[test]
    fn an_out_of_service_run_keeps_what_makes_it_a_finding() {
        // The stand-in lift is out of service whenever slave 2 went offline at all.
        let oracle = |c: &Case| {
            let hit = c
                .scenario
                .events
                .iter()
                .any(|e| e.action == Action::Fault(Fault::SlaveOffline { slave: 2 }));
            let outcome = if hit {
                RunOutcome::OutOfService
            } else {
                RunOutcome::Ok
            };
            (report(vec![]), verdict(outcome, None))
        };
        let c = case();
        let (exec, v) = oracle(&c);
        assert_eq!(v.outcome, RunOutcome::OutOfService);
        let s = shrink_with(&oracle, c, exec, v, 200);
        let kept: Vec<(u64, &Action)> = s
            .case
            .scenario
            .events
            .iter()
            .map(|e| (e.at.as_nanos() / 1_000_000, &e.action))
            .collect();
        // Slave 2's fault and its repair, the acknowledge, the reset and the probe; the
        // recovery moved to 6 s after the fault, and the run as much shorter.
        assert_eq!(
            kept,
            [
                (29_000, &Action::Fault(Fault::SlaveOffline { slave: 2 })),
                (35_000, &Action::Fault(Fault::SlaveOnline { slave: 2 })),
                (39_000, &Action::Ack),
                (40_000, &Action::Reset),
                (45_000, &press(0, 3)),
            ]
        );
        assert_eq!(s.case.scenario.duration, SimDuration::from_secs(105));
        assert_eq!(
            s.case.probe.map(|p| (p.at, p.floor)),
            Some((SimTime::from_millis(45_000), 3))
        );
        assert!(repaired(&s.case));
    }
}
