//! The second referee: a check on the invariant watch (docs/safety.md, "What the judge calls a
//! hazard"). It samples the plant's ground truth alone (position, velocity, door, load, K1,
//! the overtravel sensors and the STOP button) every millisecond, apart from the rig's moments,
//! and names the hazards it finds beyond doubt: each judgement allows a margin for its
//! sampling, and the STOP judgements ask only what the plant can show (the button held).
//! Where it names a hazard the watch must have named the same kind; where the two differ one of
//! them has a blind spot. The tests and the campaign's `--referee` run it beside the watch.

use crate::report::{Report, ViolationKind};
use crate::rig::Rig;
use asi_phy::{SimDuration, SimTime};
use lift_model::{End, Lift, LoadLevel};
use std::collections::VecDeque;

/// How often the referee looks at the plant.
pub const SAMPLE: SimDuration = SimDuration::from_millis(1);
/// The window and the budgets of the door and load judgements (docs/safety.md).
const WINDOW_SAMPLES: u64 = 10_000;
const BUDGET_SAMPLES: usize = 1_000;
/// The margin of the sampled judgements: what a sample may miss at each change, times a few.
const MARGIN_SAMPLES: usize = 50;
/// K1 closed with an overtravel sensor tripped: the watch's 50 ms, and the margin.
const OVERTRAVEL_SAMPLES: u64 = 50 + 50;
/// After STOP, K1 must be open by the safety logic's delay and 200 ms; and the margin.
const STOP_MARGIN_SAMPLES: u64 = 200 + 50;
/// A cabin at rest this long after STOP that then moves, with K1 closed and the button still
/// held, more than a vane's half-length and this margin has started a new run.
const REST_SAMPLES: u64 = 300;
const NEW_RUN_MARGIN_MM: f64 = 10.0;
/// With the safe drive: how far a car that rested with the door open may move (the watch's
/// 10 mm), and the margin.
const UNINTENDED_MM: f64 = 10.0 + 2.0;

/// What the referee found: a kind and the first time, seconds.
pub type Called = (ViolationKind, f64);

/// A door or load condition counted over the last [`WINDOW_SAMPLES`] samples.
#[derive(Clone, Debug, Default)]
struct Count(VecDeque<u64>);

impl Count {
    /// Sample `n`: the condition holds or not; returns how many of the window's samples held.
    fn see(&mut self, n: u64, holds: bool) -> usize {
        if holds {
            self.0.push_back(n);
        }
        while self.0.front().is_some_and(|&m| m + WINDOW_SAMPLES <= n) {
            self.0.pop_front();
        }
        self.0.len()
    }
}

/// The STOP button held: since which sample, from where, and what K1 and the cabin did since.
#[derive(Clone, Debug)]
struct Held {
    since: u64,
    /// Where the cabin was at the press, or where the crank last left it.
    from_mm: f64,
    k1_open_seen: bool,
    /// Where the cabin came to rest after the grace of a run under way.
    rest_mm: Option<f64>,
}

/// The second referee (module docs).
#[derive(Clone, Debug)]
pub struct Referee {
    pitch_mm: f64,
    vane_half_mm: f64,
    ends_mm: (f64, f64),
    stop_delay_samples: u64,
    /// The safe drive is on: a car that rested with the door open is judged by how far it
    /// moves.
    safe_drive: bool,
    /// Where the car rested with the door open (with the safe drive).
    door_rest_mm: Option<f64>,
    n: u64,
    door: Count,
    load: Count,
    overtravel_k1: u64,
    held: Option<Held>,
    called: Vec<Called>,
}

impl Referee {
    /// A referee of `lift`'s shaft, with the safety logic's STOP delay `stop_delay`, with or
    /// without the safe drive.
    pub fn new(lift: &Lift, stop_delay: SimDuration, safe_drive: bool) -> Referee {
        let c = lift.config();
        Referee {
            pitch_mm: c.floor_pitch_mm,
            vane_half_mm: c.long_track_half_mm,
            ends_mm: (c.end_position_mm(End::Bottom), c.end_position_mm(End::Top)),
            stop_delay_samples: stop_delay.as_nanos() / SAMPLE.as_nanos(),
            safe_drive,
            door_rest_mm: None,
            n: 0,
            door: Count::default(),
            load: Count::default(),
            overtravel_k1: 0,
            held: None,
            called: Vec::new(),
        }
    }

    fn call(&mut self, kind: ViolationKind) {
        if !self.called.iter().any(|(k, _)| *k == kind) {
            let at = (self.n * SAMPLE.as_nanos()) as f64 / 1e9;
            self.called.push((kind, at));
        }
    }

    /// Looks at the plant at the next sample.
    pub fn sample(&mut self, lift: &Lift) {
        self.n += 1;
        let n = self.n;
        let v = lift.velocity_mm_s();
        let x = lift.position_mm();
        let k1 = lift.k1_closed();
        let powered_motion = k1 && v != 0.0;
        let door_open = !lift.door_closed();
        let mut door_judged = door_open;
        if self.safe_drive {
            if !door_open || (!k1 && v != 0.0) {
                self.door_rest_mm = None;
            } else if v == 0.0 && self.door_rest_mm.is_none() {
                self.door_rest_mm = Some(x);
            }
            if let Some(rest) = self.door_rest_mm {
                door_judged = false;
                if (x - rest).abs() > UNINTENDED_MM {
                    self.call(ViolationKind::UnintendedMovement);
                }
            }
        }
        let door = self.door.see(n, powered_motion && door_judged);
        if door > BUDGET_SAMPLES + MARGIN_SAMPLES {
            self.call(ViolationKind::DoorOpenMoving);
        }
        let overloaded = lift.load() == LoadLevel::Overloaded;
        if self.load.see(n, powered_motion && overloaded) > BUDGET_SAMPLES + MARGIN_SAMPLES {
            self.call(ViolationKind::OverloadedMoving);
        }
        let tripped = !lift.overtravel_bottom_free() || !lift.overtravel_top_free();
        self.overtravel_k1 = if tripped && k1 {
            self.overtravel_k1 + 1
        } else {
            0
        };
        if self.overtravel_k1 > OVERTRAVEL_SAMPLES {
            self.call(ViolationKind::K1InOvertravel);
        }
        if k1 && (x <= self.ends_mm.0 || x >= self.ends_mm.1) {
            self.call(ViolationKind::MechanicalEnd);
        }
        self.stop(n, x, v, k1, lift.stop_channels() != [true, true]);
    }

    /// The STOP judgements, while the button is held (the circuit cannot be restarted then).
    fn stop(&mut self, n: u64, x: f64, v: f64, k1: bool, pressed: bool) {
        if !pressed {
            self.held = None;
            return;
        }
        let h = self.held.get_or_insert(Held {
            since: n,
            from_mm: x,
            k1_open_seen: !k1,
            rest_mm: None,
        });
        h.k1_open_seen |= !k1;
        if !k1 && v != 0.0 {
            // Moved by hand: the crank's place is the new start.
            h.from_mm = x;
            h.rest_mm = None;
        } else if v == 0.0 && n - h.since > REST_SAMPLES {
            h.rest_mm = h.rest_mm.or(Some(x));
        }
        let ignored =
            !h.k1_open_seen && n - h.since > self.stop_delay_samples + STOP_MARGIN_SAMPLES;
        // The next floor more than a vane's half-length ahead is at most a pitch and that
        // half-length away, and the cabin may pass it by the half-length again.
        let reach = self.pitch_mm + 2.0 * self.vane_half_mm + 10.0;
        let overrun = k1 && (x - h.from_mm).abs() > reach;
        let new_run = k1
            && h.rest_mm
                .is_some_and(|rest| (x - rest).abs() > self.vane_half_mm + NEW_RUN_MARGIN_MM);
        if ignored {
            self.call(ViolationKind::StopIgnored);
        }
        if overrun || new_run {
            self.call(ViolationKind::StopOverrun);
        }
    }

    /// What the referee found, in the order found.
    pub fn called(&self) -> &[Called] {
        &self.called
    }

    /// The kinds the referee found beyond doubt that `report`'s watch did not name, in words;
    /// empty when the two agree.
    pub fn disagreements(&self, report: &Report) -> Vec<String> {
        self.called
            .iter()
            .filter(|(kind, _)| !report.violations.iter().any(|v| v.kind == *kind))
            .map(|(kind, at)| {
                format!("the referee finds {kind} at {at:.3} s from the plant alone; the invariant watch names no {kind}")
            })
            .collect()
    }

    /// Runs `rig` to its end (or `until`) with a referee beside it; the report and the
    /// referee.
    pub fn run(mut rig: Rig, until: Option<SimDuration>) -> (Report, Referee) {
        if let Some(u) = until {
            let end = rig.end().min(SimTime::ZERO + u);
            rig.set_end(end);
        }
        let mut referee = Referee::new(rig.lift(), rig.estop_delay(), rig.drive_sample().is_some());
        let mut t = SimTime::ZERO + SAMPLE;
        while t < rig.end() {
            while rig.step_until(t).is_some() {}
            referee.sample(rig.lift());
            t += SAMPLE;
        }
        // The rest of the run as it would go without the referee: the same report.
        (rig.run(None), referee)
    }
}
