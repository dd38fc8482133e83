//! The fault explorer (`asi-lift explore`): every fault of the catalogue injected at every
//! instant of a grid over a scenario, each run on to a verdict (the book, "The fault
//! explorer").
//!
//! The scenario is run once (per worker thread) and copied ([`Rig`] is `Clone`: a copy goes on
//! exactly as the original) at each instant of the grid; each copy, a fork, gets one fault of
//! the catalogue ([`catalogue`]) at that instant, scheduled as the scenario's own events would
//! be, and runs on to its verdict ([`Verdict`]). Nothing is simulated twice from power-on:
//! the forks share the run up to their instant.
//!
//! A fork ends as soon as its verdict is certain, and only then (docs/dev/explorer.md says
//! why each shortcut is exact):
//!
//! - a **violation**: the invariant watch has named one; the first is the verdict;
//! - a **safe stop that needs a person**: K1 is open for a cause the safety logic holds until
//!   an operator acts (a group error waiting for ERR_ACK, the overtravel monitor waiting for
//!   its reset or a cabin on its sensor, a stopped logic), the cabin is at rest, and no person
//!   acts before the horizon (no reset, acknowledge, rescue or crank among the scenario's
//!   events to come, no attendant). Nothing else closes K1 again, and without power or a
//!   crank the cabin cannot move, so no invariant can be broken any more;
//! - otherwise at the **horizon**: back in service by itself (K1 closed, the door closed, not
//!   overloaded, the controller in a service state), or stopped for a person (the action
//!   named), or out of service.
//!
//! A panic of a fork is caught and is its verdict; it never stops the sweep.

pub mod catalogue;
pub mod summary;

use crate::campaign::run::Shard;
use crate::campaign::SERVICE_STATES;
use crate::report::{round3, ViolationKind};
use crate::rig::Rig;
use asi_phy::{SimDuration, SimTime};
use catalogue::{FaultKind, Params};
use controller::State;
use crossbeam_channel::unbounded;
use lift_model::LoadLevel;
use safety::lift::K1Cause;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;
use std::ops::ControlFlow;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// What the lift was doing when the fault came (from the run without the fault).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Phase {
    /// Looking for floor 1 after power-on (or waiting for the cabin's first word).
    Initialising,
    /// Standing at a floor, door closed.
    AtFloor,
    /// The door is open.
    DoorOpen,
    /// A run has begun: the cabin speeds up (or is about to start).
    Departing,
    /// Travelling at a steady speed.
    Travelling,
    /// Slowing down to a floor.
    Braking,
    /// Held: a bus fault, an overload, a STOP, or between floors.
    Halted,
}

impl Phase {
    /// Every phase, in the order of the summary.
    pub const ALL: [Phase; 7] = [
        Phase::Initialising,
        Phase::AtFloor,
        Phase::DoorOpen,
        Phase::Departing,
        Phase::Travelling,
        Phase::Braking,
        Phase::Halted,
    ];

    /// The name in the lines.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Initialising => "initialising",
            Phase::AtFloor => "at-floor",
            Phase::DoorOpen => "door-open",
            Phase::Departing => "departing",
            Phase::Travelling => "travelling",
            Phase::Braking => "braking",
            Phase::Halted => "halted",
        }
    }

    /// The phase of `rig` now, whose cabin moved at `v_before` mm/s a little earlier.
    pub fn of(rig: &Rig, v_before: f64) -> Phase {
        let lift = rig.lift();
        if !lift.door_closed() {
            return Phase::DoorOpen;
        }
        let v = lift.velocity_mm_s();
        let run = || {
            if v.abs() > v_before.abs() || v == 0.0 {
                Phase::Departing
            } else if v.abs() < v_before.abs() {
                Phase::Braking
            } else {
                Phase::Travelling
            }
        };
        match rig.controller_status().state {
            Some(State::WaitingForInputs | State::Initialising) => Phase::Initialising,
            Some(State::AtFloor) => Phase::AtFloor,
            Some(State::Braking) => Phase::Braking,
            Some(State::MovingUp | State::MovingDown) => run(),
            Some(_) => Phase::Halted,
            // A controller that tells no state: the plant alone.
            None if v == 0.0 && lift.in_level_zone() => Phase::AtFloor,
            None if v == 0.0 => Phase::Halted,
            None => run(),
        }
    }
}

impl fmt::Display for Phase {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.name())
    }
}

/// How a fork ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Back in service by itself at the horizon: K1 closed, the door closed, not overloaded,
    /// the controller in a service state, no violation.
    InService,
    /// A safe stop that needs a person: the action is named.
    NeedsPerson,
    /// Neither in service nor stopped for a person at the horizon (moving, or held by the
    /// controller for no cause a person answers), no violation.
    OutOfService,
    /// The invariant watch named a violation.
    Violation,
    /// The simulation panicked.
    Panic,
}

impl Verdict {
    /// Every verdict, in the order of the summary.
    pub const ALL: [Verdict; 5] = [
        Verdict::InService,
        Verdict::NeedsPerson,
        Verdict::OutOfService,
        Verdict::Violation,
        Verdict::Panic,
    ];

    /// The name in the lines.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::InService => "in-service",
            Verdict::NeedsPerson => "needs-person",
            Verdict::OutOfService => "out-of-service",
            Verdict::Violation => "violation",
            Verdict::Panic => "panic",
        }
    }
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.name())
    }
}

/// One line of an exploration's output (JSON): a fork and its verdict.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForkLine {
    /// The fork's index in the exploration: instant × kinds + kind, 0-based.
    pub index: u64,
    /// How many forks the exploration has (all shards together).
    pub forks: u64,
    /// The scenario's name.
    pub scenario: String,
    /// The fault's kind ([`FaultKind::name`]).
    pub fault: String,
    /// The instant of injection, seconds.
    pub at_s: f64,
    /// What the lift was doing then.
    pub phase: Phase,
    /// Where the cabin was then, mm above the floor-1 level (0.1 mm).
    pub position_mm: f64,
    /// How the fork ended.
    pub verdict: Verdict,
    /// The violation's kind, for a violation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub violation: Option<ViolationKind>,
    /// What a person must do, for a stop that needs one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub action: Option<String>,
    /// In words: the violation, the cause of the stop, the state at the horizon, the panic.
    pub detail: String,
    /// From the injection to the moment the verdict holds, seconds: the violation, the stop
    /// (or, at the horizon, the start of the last stretch in service or out of it).
    pub after_s: f64,
    /// Where the fork ended, seconds after the injection: the verdict's certainty (less
    /// than the horizon when it ended early).
    pub ran_s: f64,
    /// For a violation or a panic: the file name of the scenario that reproduces it (the
    /// fault written in), in the failures directory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reproducer: Option<String>,
}

impl ForkLine {
    /// The line as written: one JSON object, no line break.
    pub fn to_json_line(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string(self)
    }
}

/// What an exploration is: everything its lines depend on, besides the scenario.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The kinds injected at each instant, in the catalogue's order.
    pub kinds: Vec<FaultKind>,
    /// The faults' sizes.
    pub params: Params,
    /// The grid's step.
    pub every: SimDuration,
    /// The first and the last instant (inclusive) of the grid.
    pub window: (SimTime, SimTime),
    /// How long a fork runs after its fault at most.
    pub horizon: SimDuration,
    /// The part of the forks to run.
    pub shard: Shard,
}

impl Plan {
    /// The grid's instants.
    pub fn instants(&self) -> u64 {
        if self.window.1 < self.window.0 || self.every.is_zero() {
            return 0;
        }
        (self.window.1 - self.window.0).as_nanos() / self.every.as_nanos() + 1
    }

    /// The `i`-th instant.
    pub fn instant(&self, i: u64) -> SimTime {
        self.window.0 + self.every.saturating_mul(i)
    }

    /// Forks of the whole exploration.
    pub fn forks(&self) -> u64 {
        self.instants() * self.kinds.len() as u64
    }

    /// Forks of this plan's shard.
    pub fn count(&self) -> u64 {
        let (forks, k, n) = (self.forks(), self.shard.k - 1, self.shard.n);
        if forks <= k {
            0
        } else {
            (forks - 1 - k) / n + 1
        }
    }
}

/// How a fork was judged.
#[derive(Clone, Debug, PartialEq)]
pub struct Judged {
    /// The verdict.
    pub verdict: Verdict,
    /// The violation's kind.
    pub violation: Option<ViolationKind>,
    /// The person's action.
    pub action: Option<String>,
    /// In words.
    pub detail: String,
    /// When the verdict holds from.
    pub at: SimTime,
    /// Where the fork ended.
    pub ran_to: SimTime,
}

/// A cause for which the safety logic holds K1 open until a person acts: what they must do.
fn latched_action(cause: &K1Cause) -> Option<String> {
    match cause {
        K1Cause::GroupError(e) => Some(format!("acknowledge (ERR_ACK) the group error ({e})")),
        K1Cause::OvertravelResetPending => {
            Some("safety reset: the overtravel monitor waits for it".into())
        }
        K1Cause::Overtravel { top, .. } => Some(format!(
            "rescue: crank the cabin off the {} overtravel sensor, then the safety reset",
            if *top { "top" } else { "bottom" }
        )),
        K1Cause::LogicFault => Some("restart the safety logic (it stopped on a fault)".into()),
        K1Cause::StopPressed | K1Cause::StopRestartPending | K1Cause::Overloaded => None,
    }
}

/// What a person must do for a lift held for `cause`, at the horizon.
fn open_action(cause: &K1Cause) -> String {
    latched_action(cause).unwrap_or_else(|| match cause {
        K1Cause::StopPressed => "release STOP".into(),
        K1Cause::StopRestartPending => {
            "a cabin call: the STOP circuit waits for the controller's restart".into()
        }
        _ => "reduce the load".into(),
    })
}

/// The lift of `rig` is in service: K1 closed, door closed, not overloaded, the controller
/// in a service state (a controller that tells none: the plant alone).
fn in_service(rig: &Rig) -> bool {
    let lift = rig.lift();
    lift.k1_closed()
        && lift.door_closed()
        && lift.load() != LoadLevel::Overloaded
        && rig
            .controller_status()
            .state
            .is_none_or(|s| SERVICE_STATES.contains(&s))
}

/// The safe stop `rig` is in that only a person ends, if it is in one (module docs).
fn latched(rig: &Rig, until: SimTime) -> Option<(K1Cause, String)> {
    let lift = rig.lift();
    if lift.k1_closed() || lift.velocity_mm_s() != 0.0 || lift.hand_cranking() {
        return None;
    }
    let cause = rig.safety_diag()?.k1_open_cause?;
    let action = latched_action(&cause)?;
    (!rig.person_may_act_before(until)).then_some((cause, action))
}

/// Runs `rig`, which has its fault scheduled at `from`, on to its verdict: until a violation
/// after `from`, a safe stop only a person ends, or `from + horizon`.
pub fn judge(mut rig: Rig, from: SimTime, horizon: SimDuration) -> Judged {
    let end = from + horizon;
    rig.set_end(end);
    // Run to the fault first: the checks begin there.
    if rig.now() < from {
        while rig.step_until(from - SimDuration::from_nanos(1)).is_some() {}
    }
    let before = rig.violations().len();
    let mut stop: Option<(K1Cause, String)> = None;
    let mut state = in_service(&rig);
    let mut since = from;
    let ran_to = rig.run_while(&mut |r| {
        if r.violations().len() > before {
            return ControlFlow::Break(());
        }
        if let Some(s) = latched(r, end) {
            stop = Some(s);
            return ControlFlow::Break(());
        }
        let now = in_service(r);
        if now != state {
            state = now;
            since = r.now();
        }
        ControlFlow::Continue(())
    });
    if let Some(v) = rig.violations().get(before) {
        let at = SimTime::ZERO + SimDuration::from_secs_f64(v.at_s).unwrap_or(SimDuration::ZERO);
        return Judged {
            verdict: Verdict::Violation,
            violation: Some(v.kind),
            action: None,
            detail: v.detail.clone(),
            at: at.max(from),
            ran_to,
        };
    }
    if let Some((cause, action)) = stop {
        return Judged {
            verdict: Verdict::NeedsPerson,
            violation: None,
            action: Some(action),
            detail: format!("K1 open: {cause}"),
            at: ran_to,
            ran_to,
        };
    }
    let lift = rig.lift();
    let status = rig.controller_status();
    let state_name = status.state.map_or("none told", |s| s.name());
    let person = if lift.k1_closed() {
        if !lift.door_closed() {
            Some(("close the door".to_string(), "the door is open".to_string()))
        } else if lift.load() == LoadLevel::Overloaded {
            Some((
                "reduce the load".to_string(),
                "the cabin is overloaded".to_string(),
            ))
        } else {
            None
        }
    } else if lift.velocity_mm_s() == 0.0 {
        match rig.safety_diag().and_then(|d| d.k1_open_cause) {
            Some(c) => Some((open_action(&c), format!("K1 open: {c}"))),
            None => Some((
                "safety reset: the safe drive holds the torque off".to_string(),
                "K1 open by the safe drive".to_string(),
            )),
        }
    } else {
        None
    };
    let (verdict, action, detail) = if in_service(&rig) {
        (
            Verdict::InService,
            None,
            format!("in service, controller {state_name}"),
        )
    } else {
        match person {
            Some((action, why)) => (
                Verdict::NeedsPerson,
                Some(action),
                format!("{why}; controller {state_name}"),
            ),
            None => (
                Verdict::OutOfService,
                None,
                format!(
                    "controller {state_name}, K1 {}, cabin {}",
                    if lift.k1_closed() { "closed" } else { "open" },
                    if lift.velocity_mm_s() == 0.0 {
                        "at rest"
                    } else {
                        "moving"
                    }
                ),
            ),
        }
    };
    Judged {
        verdict,
        violation: None,
        action,
        detail,
        at: since,
        ran_to,
    }
}

/// The scenario `sc` with `kind`'s events written in from `at`, as its own events (after the
/// scenario's events at the same times, where [`Rig::schedule`] puts them), lasting to the
/// fork's horizon: run from power-on it is the fork (tested), so it reproduces the fork's
/// verdict with `asi-lift run`.
pub fn written_in(
    mut sc: crate::Scenario,
    kind: FaultKind,
    params: &Params,
    at: SimTime,
    horizon: SimDuration,
) -> crate::Scenario {
    for (offset, action) in kind.actions(params) {
        let t = at + offset;
        let pos = sc.events.partition_point(|e| e.at <= t);
        sc.events.insert(
            pos,
            crate::scenario::ScenarioEvent {
                at: t,
                action,
                line: 0,
            },
        );
    }
    sc.duration = (at + horizon) - SimTime::ZERO;
    sc
}

/// Schedules `kind`'s events on `rig` from `at`.
pub fn inject(rig: &mut Rig, kind: FaultKind, params: &Params, at: SimTime) {
    for (offset, action) in kind.actions(params) {
        rig.schedule(at + offset, action);
    }
}

/// The message of a caught panic.
pub fn panic_message(payload: &Box<dyn std::any::Any + Send>) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".into())
}

/// Forks `snapshot` at `at` with `kind`, and judges the fork; a panic is its verdict.
pub fn fork(snapshot: &Rig, kind: FaultKind, plan: &Plan, at: SimTime) -> Judged {
    catch_unwind(AssertUnwindSafe(|| {
        let mut rig = snapshot.clone();
        inject(&mut rig, kind, &plan.params, at);
        judge(rig, at, plan.horizon)
    }))
    .unwrap_or_else(|p| Judged {
        verdict: Verdict::Panic,
        violation: None,
        action: None,
        detail: panic_message(&p),
        at,
        ran_to: at,
    })
}

/// The run without faults, stepped from instant to instant of the grid.
struct Baseline {
    rig: Rig,
}

impl Baseline {
    /// Steps to just before `t` (every moment before it taken); the phase there.
    fn step_to(&mut self, t: SimTime, every: SimDuration) -> Phase {
        let before = |t: SimTime, d: SimDuration| t.checked_sub(d).unwrap_or(SimTime::ZERO);
        let look = every.min(SimDuration::from_millis(10));
        if t.as_nanos() > look.as_nanos() {
            while self.rig.step_until(before(t, look)).is_some() {}
        }
        let v_before = self.rig.lift().velocity_mm_s();
        if t > SimTime::ZERO {
            while self
                .rig
                .step_until(before(t, SimDuration::from_nanos(1)))
                .is_some()
            {}
        }
        Phase::of(&self.rig, v_before)
    }
}

/// Why an exploration stopped early.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Stopped(pub String);

/// Explores `plan` over the scenario `make` builds at power-on (with whatever controller it
/// puts in the rig), on `jobs` worker threads; hands the shard's lines to `sink` in index
/// order, and tells `progress` of each instant's lines as they come (in any order). Each
/// worker runs the scenario once and forks it at the instants it takes.
pub fn explore(
    make: &(dyn Fn() -> Result<Rig, String> + Sync),
    plan: &Plan,
    jobs: usize,
    sink: &mut dyn FnMut(ForkLine) -> Result<(), String>,
    progress: &mut dyn FnMut(&[ForkLine]),
) -> Result<(), Stopped> {
    let instants = plan.instants();
    let kinds = plan.kinds.len() as u64;
    let forks = plan.forks();
    let first = make().map_err(Stopped)?;
    let name = first.scenario().name.clone();
    if plan.window.1 >= first.end() {
        return Err(Stopped(format!(
            "--window: the last instant {} is not before the scenario's end {}",
            plan.window.1 - SimTime::ZERO,
            first.end() - SimTime::ZERO
        )));
    }
    drop(first);
    // The instants that hold a fork of the shard.
    let mine = |i: u64| (0..kinds).any(|k| plan.shard.contains(i * kinds + k));
    let jobs = jobs.clamp(1, usize::try_from(instants).unwrap_or(usize::MAX).max(1));
    let taken = AtomicU64::new(0);
    let cancel = AtomicBool::new(false);
    let (done_tx, done_rx) = unbounded::<Result<(u64, Vec<ForkLine>), String>>();
    std::thread::scope(|scope| {
        for w in 0..jobs {
            let (done_tx, cancel, taken, name) = (done_tx.clone(), &cancel, &taken, &name);
            let spawned = std::thread::Builder::new()
                .name(format!("explore-worker-{w}"))
                .spawn_scoped(scope, move || {
                    let mut base = match make() {
                        Ok(rig) => Baseline { rig },
                        Err(e) => {
                            let _ = done_tx.send(Err(e));
                            return;
                        }
                    };
                    loop {
                        let i = taken.fetch_add(1, Ordering::Relaxed);
                        if i >= instants || cancel.load(Ordering::Relaxed) {
                            break;
                        }
                        if !mine(i) {
                            if done_tx.send(Ok((i, Vec::new()))).is_err() {
                                break;
                            }
                            continue;
                        }
                        let at = plan.instant(i);
                        let stepped =
                            catch_unwind(AssertUnwindSafe(|| base.step_to(at, plan.every)));
                        let phase = match stepped {
                            Ok(p) => p,
                            Err(p) => {
                                let _ = done_tx.send(Err(format!(
                                    "the scenario without faults panics before {}: {}",
                                    at - SimTime::ZERO,
                                    panic_message(&p)
                                )));
                                return;
                            }
                        };
                        let position_mm = (base.rig.lift().position_mm() * 10.0).round() / 10.0;
                        let mut lines = Vec::new();
                        for (k, kind) in plan.kinds.iter().enumerate() {
                            let index = i * kinds + k as u64;
                            if !plan.shard.contains(index) {
                                continue;
                            }
                            let j = fork(&base.rig, *kind, plan, at);
                            lines.push(ForkLine {
                                index,
                                forks,
                                scenario: name.clone(),
                                fault: kind.name(),
                                at_s: round3(at.as_secs_f64()),
                                phase,
                                position_mm,
                                verdict: j.verdict,
                                violation: j.violation,
                                action: j.action,
                                detail: j.detail,
                                after_s: round3((j.at.max(at) - at).as_secs_f64()),
                                ran_s: round3((j.ran_to.max(at) - at).as_secs_f64()),
                                reproducer: None,
                            });
                        }
                        if done_tx.send(Ok((i, lines))).is_err() {
                            break;
                        }
                    }
                });
            if let Err(e) = spawned {
                cancel.store(true, Ordering::Relaxed);
                return Err(Stopped(format!("cannot start a worker thread: {e}")));
            }
        }
        drop(done_tx);
        let mut pending: BTreeMap<u64, Vec<ForkLine>> = BTreeMap::new();
        let mut next = 0u64;
        for done in done_rx.iter() {
            let (i, lines) = match done {
                Ok(d) => d,
                Err(e) => {
                    cancel.store(true, Ordering::Relaxed);
                    return Err(Stopped(e));
                }
            };
            progress(&lines);
            pending.insert(i, lines);
            while let Some(lines) = pending.remove(&next) {
                next += 1;
                for l in lines {
                    if let Err(e) = sink(l) {
                        cancel.store(true, Ordering::Relaxed);
                        return Err(Stopped(e));
                    }
                }
            }
        }
        if next < instants {
            return Err(Stopped(format!(
                "only {next} of {instants} instants finished (a worker thread died)"
            )));
        }
        Ok(())
    })
}
