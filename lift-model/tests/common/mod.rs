//! Helpers shared by the integration tests: drive the plant from edge to edge.
#![allow(dead_code)]

use asi_phy::{SimDuration, SimTime};
use lift_model::{Lift, LiftConfig, PlantEvent, PlantEventKind};

/// A lift with the default (lab) configuration, the cabin at `position_mm`.
pub fn lift_at(position_mm: f64) -> Lift {
    lift_with({
        let mut cfg = LiftConfig::default();
        cfg.initial_position_mm = position_mm;
        cfg
    })
}

/// A lift from `config`, which must be valid.
pub fn lift_with(config: LiftConfig) -> Lift {
    match Lift::new(config) {
        Ok(lift) => lift,
        Err(e) => panic!("test configuration rejected: {e}"),
    }
}

/// Seconds as simulated time.
pub fn secs(s: f64) -> SimTime {
    SimTime::ZERO + SimDuration::from_secs_f64(s).unwrap_or(SimDuration::MAX)
}

/// Jumps from edge to edge up to `until` (inclusive), collecting every edge.
pub fn events_until(lift: &mut Lift, until: SimTime) -> Vec<PlantEvent> {
    let mut all = Vec::new();
    while let Some(t) = lift.next_event().filter(|&t| t <= until) {
        all.extend(advance(lift, t));
    }
    all.extend(advance(lift, until));
    all
}

/// Jumps from edge to edge until an edge matches `wanted`; the plant stays at that edge's
/// time. Panics if the plant falls quiet or ten minutes pass first.
pub fn run_to(lift: &mut Lift, wanted: impl Fn(&PlantEventKind) -> bool) -> PlantEvent {
    let limit = lift.now() + SimDuration::from_secs(600);
    while let Some(t) = lift.next_event().filter(|&t| t <= limit) {
        if let Some(e) = advance(lift, t).into_iter().find(|e| wanted(&e.kind)) {
            return e;
        }
    }
    panic!("no such edge within ten minutes; plant at {}", lift.now());
}

/// `advance_to` that must succeed, collected.
pub fn advance(lift: &mut Lift, t: SimTime) -> Vec<PlantEvent> {
    match lift.advance_to(t) {
        Ok(events) => events.collect(),
        Err(e) => panic!("advance_to({t}) failed: {e}"),
    }
}

/// Panics with the error if an input is refused.
pub fn ok<T, E: std::fmt::Display>(r: Result<T, E>) -> T {
    match r {
        Ok(v) => v,
        Err(e) => panic!("input refused: {e}"),
    }
}

/// Like [`events_until`], with the cabin position at each edge.
pub fn trace_until(lift: &mut Lift, until: SimTime) -> Vec<(PlantEvent, f64)> {
    let mut all = Vec::new();
    while let Some(t) = lift.next_event().filter(|&t| t <= until) {
        for e in advance(lift, t) {
            all.push((e, lift.position_mm()));
        }
    }
    advance(lift, until);
    all
}

/// The vane edges of a trace as `(sensor, on, position)`.
pub fn vane_edges(trace: &[(PlantEvent, f64)]) -> Vec<(lift_model::VaneSensor, bool, f64)> {
    trace
        .iter()
        .filter_map(|(e, x)| match e.kind {
            PlantEventKind::Vane { sensor, on } => Some((sensor, on, *x)),
            _ => None,
        })
        .collect()
}

/// A lift at `position_mm` with K1 closed and the converter running up (`up`) or down at
/// `setpoint` µA from time zero.
pub fn driving(position_mm: f64, up: bool, setpoint: u16) -> Lift {
    driving_with(
        {
            let mut cfg = LiftConfig::default();
            cfg.initial_position_mm = position_mm;
            cfg
        },
        up,
        setpoint,
    )
}

/// [`driving`] with a whole configuration.
pub fn driving_with(config: LiftConfig, up: bool, setpoint: u16) -> Lift {
    let mut lift = lift_with(config);
    ok(lift.set_contactor(SimTime::ZERO, true));
    ok(lift.set_converter(SimTime::ZERO, true, up, setpoint));
    lift
}
