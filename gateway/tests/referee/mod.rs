//! A second, simple referee of the judge's hazards (docs SPEC §6b: "a second, simpler referee
//! computes the same judgements from the plant's state alone in tests"), for the hostile
//! suite's property test.
//!
//! It knows nothing of the invariant watch's code: it is fed the plant's ground truth every
//! 1 ms of simulated time through the rig's public API ([`Sample::of`]: the cabin's height and
//! velocity, the door, the load, K1, the STOP channels, the overtravel sensors and the hand
//! crank from [`Rig::lift`], EStopOut from [`Rig::estop_out`]) and keeps, for every kind, two
//! verdicts with a margin between them:
//!
//! - **definite**: the hazard certainly happened, with room to spare, so the watch must name
//!   the kind;
//! - **possible**: something close to it happened, so the watch may name the kind.
//!
//! A run is judged right when `definite ⊆ named ⊆ possible` ([`Referee::check`]). The margins
//! (all counted on 1 ms samples, so a sample stands for the millisecond before it):
//!
//! | kind | definite | possible |
//! |---|---|---|
//! | door-open-moving | door open, K1 closed and the cabin moving for more than 1.05 s within a sliding 10 s | door open and moving (K1 or not, crank or not) for more than 0.95 s within 10 s |
//! | overloaded-moving | the same with the load at "overloaded" | the same |
//! | k1-in-overtravel | an overtravel sensor tripped with K1 closed for 56 consecutive samples | for 40 |
//! | mechanical-end | the plant recorded a crash at a mechanical end | the cabin within 1 mm of an end |
//! | stop-ignored | a STOP channel opened and K1 stayed closed in every sample of the 9.35 s after | K1 closed for 9.25 s after a sample with a STOP channel open |
//! | stop-overrun | while EStopOut is off: with K1 closed, the cabin passes the first floor level more than 40 mm (± 2 mm, else undecided) ahead of where it was when EStopOut went off, in the direction it moved then, by more than 45 mm; or it goes back more than 45 mm from the farthest point in that direction; or, at rest when EStopOut went off with no run commanded, or at rest after moving, it moves more than 45 mm from where it rested (K1 closed) | the cabin moves at all while EStopOut is off |
//!
//! "Moving" is a velocity other than zero. The referee reads motion with K1 closed as powered
//! (SPEC §6b: motion with K1 closed is always judged), which is why its definite verdicts need
//! K1 closed and its possible ones do not.

use asi_phy::{SimDuration, SimTime};
use lift_model::{End, LoadLevel};
use rig::report::ViolationKind;
use rig::Rig;
use std::collections::{BTreeSet, VecDeque};

/// What the referee reads of the plant at one moment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The cabin's height, mm.
    pub position_mm: f64,
    /// The cabin's velocity, mm/s.
    pub velocity_mm_s: f64,
    pub door_open: bool,
    pub overloaded: bool,
    pub k1_closed: bool,
    /// A STOP channel is open (the button pressed, or a channel fault).
    pub stop: bool,
    /// The safety logic's EStopOut as the controller gets it (`false`: STOP demand).
    pub estop_out: bool,
    /// The converter's run bit in the output image as the controller last wrote it (a run
    /// commanded before STOP is under way even if the cabin starts later).
    pub run_commanded: bool,
    /// An overtravel sensor is tripped.
    pub overtravel: bool,
    /// The plant's count of crashes at a mechanical end.
    pub crashes: usize,
}

impl Sample {
    /// The plant's ground truth now.
    pub fn of(rig: &Rig) -> Sample {
        let l = rig.lift();
        Sample {
            position_mm: l.position_mm(),
            velocity_mm_s: l.velocity_mm_s(),
            door_open: !l.door_closed(),
            overloaded: l.load() == LoadLevel::Overloaded,
            k1_closed: l.k1_closed(),
            stop: l.stop_channels() != [true, true],
            estop_out: rig.estop_out(),
            run_commanded: rig.run_commanded(),
            overtravel: !l.overtravel_bottom_free() || !l.overtravel_top_free(),
            crashes: l.crashes().len(),
        }
    }

    fn moving(&self) -> bool {
        self.velocity_mm_s != 0.0
    }

    fn powered_moving(&self) -> bool {
        self.moving() && self.k1_closed
    }
}

/// The time a condition held within the last 10 s, from 1 ms samples.
#[derive(Clone, Debug, Default)]
struct Budget {
    /// The last 10 000 samples: (definite, possible).
    ring: VecDeque<(bool, bool)>,
    definite_ms: u32,
    possible_ms: u32,
}

impl Budget {
    const WINDOW_MS: usize = 10_000;

    /// One sample; returns (definite, possible) past the budget.
    fn see(&mut self, definite: bool, possible: bool) -> (bool, bool) {
        self.ring.push_back((definite, possible));
        self.definite_ms += u32::from(definite);
        self.possible_ms += u32::from(possible);
        if self.ring.len() > Self::WINDOW_MS {
            if let Some((d, p)) = self.ring.pop_front() {
                self.definite_ms -= u32::from(d);
                self.possible_ms -= u32::from(p);
            }
        }
        (self.definite_ms > 1_050, self.possible_ms > 950)
    }
}

/// One EStopOut-off episode.
#[derive(Clone, Debug)]
struct StopEpisode {
    since: SimTime,
    /// The direction of powered motion when it began (`Some(up)`), and the height the cabin
    /// may not pass (`None`: the next floor was too close to a vane's edge to decide).
    direction: Option<(bool, Option<f64>)>,
    /// At rest when it began, with no run commanded.
    at_rest: bool,
    /// Where the cabin rests (after its run, or from the start when at rest): a run from here
    /// is a new run.
    rest_mm: Option<f64>,
    /// The farthest height reached in the direction of travel.
    far_mm: f64,
    /// Came to rest after moving in its direction.
    rested: bool,
}

/// The referee: feed it a [`Sample`] every 1 ms, then [`Referee::check`] the watch's kinds.
#[derive(Clone, Debug)]
pub struct Referee {
    levels_mm: Vec<f64>,
    ends_mm: (f64, f64),
    door: Budget,
    load: Budget,
    overtravel_run: u32,
    /// Since when K1 has been closed, and the first STOP (rising edge, any sample) in that
    /// span.
    k1_since: Option<SimTime>,
    stop_edge_in_span: Option<SimTime>,
    stop_any_in_span: Option<SimTime>,
    last_stop: bool,
    episode: Option<StopEpisode>,
    /// The verdicts.
    pub definite: BTreeSet<ViolationKind>,
    pub possible: BTreeSet<ViolationKind>,
    /// Samples seen.
    pub samples: u64,
}

/// A vane's long track's half-length, mm: the stop-overrun allowance (SPEC §6b).
const VANE_HALF_MM: f64 = 40.0;

impl Referee {
    /// A referee of the shaft of `rig`.
    pub fn new(rig: &Rig) -> Referee {
        let c = rig.lift().config();
        Referee::of_shaft(
            (1..=c.floors).filter_map(|f| c.floor_level_mm(f)).collect(),
            (c.end_position_mm(End::Bottom), c.end_position_mm(End::Top)),
        )
    }

    /// A referee of a shaft with the floors' levels `levels_mm` and the mechanical ends
    /// `ends_mm` (bottom, top).
    fn of_shaft(levels_mm: Vec<f64>, ends_mm: (f64, f64)) -> Referee {
        Referee {
            levels_mm,
            ends_mm,
            door: Budget::default(),
            load: Budget::default(),
            overtravel_run: 0,
            k1_since: None,
            stop_edge_in_span: None,
            stop_any_in_span: None,
            last_stop: false,
            episode: None,
            definite: BTreeSet::new(),
            possible: BTreeSet::new(),
            samples: 0,
        }
    }

    fn flag(&mut self, kind: ViolationKind, definite: bool, possible: bool) {
        if definite {
            self.definite.insert(kind);
        }
        if possible || definite {
            self.possible.insert(kind);
        }
    }

    /// The sample `s` at `t` (1 ms after the last one).
    pub fn see(&mut self, t: SimTime, s: Sample) {
        self.samples += 1;
        // Door and load budgets.
        let (d, p) = self
            .door
            .see(s.door_open && s.powered_moving(), s.door_open && s.moving());
        self.flag(ViolationKind::DoorOpenMoving, d, p);
        let (d, p) = self.load.see(
            s.overloaded && s.powered_moving(),
            s.overloaded && s.moving(),
        );
        self.flag(ViolationKind::OverloadedMoving, d, p);
        // K1 with an overtravel sensor tripped.
        self.overtravel_run = if s.overtravel && s.k1_closed {
            self.overtravel_run + 1
        } else {
            0
        };
        let run = self.overtravel_run;
        self.flag(ViolationKind::K1InOvertravel, run >= 56, run >= 40);
        // Mechanical ends.
        let near_end =
            s.position_mm <= self.ends_mm.0 + 1.0 || s.position_mm >= self.ends_mm.1 - 1.0;
        self.flag(ViolationKind::MechanicalEnd, s.crashes > 0, near_end);
        // STOP and K1.
        let edge = s.stop && !self.last_stop;
        self.last_stop = s.stop;
        if s.k1_closed {
            self.k1_since.get_or_insert(t);
            if edge {
                self.stop_edge_in_span.get_or_insert(t);
            }
            if s.stop {
                self.stop_any_in_span.get_or_insert(t);
            }
        } else {
            self.k1_since = None;
            self.stop_edge_in_span = None;
            self.stop_any_in_span = None;
        }
        let held = |since: Option<SimTime>, ms: u64| {
            since.is_some_and(|s0| t.saturating_duration_since(s0) >= SimDuration::from_millis(ms))
        };
        let (d, p) = (
            held(self.stop_edge_in_span, 9_350),
            held(self.stop_any_in_span, 9_250),
        );
        self.flag(ViolationKind::StopIgnored, d, p);
        // STOP's episodes.
        self.stop_overrun(t, &s);
    }

    fn stop_overrun(&mut self, t: SimTime, s: &Sample) {
        if s.estop_out {
            self.episode = None;
            return;
        }
        let x = s.position_mm;
        let e = self.episode.get_or_insert_with(|| StopEpisode {
            since: t,
            direction: None,
            at_rest: !s.moving() && !s.run_commanded,
            rest_mm: None,
            far_mm: x,
            rested: false,
        });
        let first = e.since == t;
        if first && s.powered_moving() {
            let up = s.velocity_mm_s > 0.0;
            let limit = next_limit(&self.levels_mm, x, up);
            e.direction = Some((up, limit));
        }
        if !s.moving() && (e.at_rest || e.direction.is_some()) {
            e.rest_mm = e.rest_mm.or(Some(x));
            e.rested |= e.direction.is_some();
        }
        if !s.k1_closed && s.moving() {
            // Moved by hand: no reference until it rests again.
            e.rest_mm = None;
        }
        // Each rule allows a vane's half-length (40 mm), and 5 mm of margin here.
        let allowance = VANE_HALF_MM + 5.0;
        let mut definite = false;
        if s.k1_closed && s.moving() {
            if let Some(rest) = e.rest_mm {
                definite |= (x - rest).abs() > allowance;
            }
            if let Some((up, limit)) = e.direction {
                e.far_mm = if up { e.far_mm.max(x) } else { e.far_mm.min(x) };
                let back = if up { e.far_mm - x } else { x - e.far_mm };
                let passes = limit.is_some_and(|l| if up { x > l + 5.0 } else { x < l - 5.0 });
                definite |= back > allowance || passes;
            }
        }
        let possible = s.moving();
        self.flag(ViolationKind::StopOverrun, definite, possible);
    }

    /// Whether the watch's `named` kinds agree: every definite kind named, every named kind
    /// possible. The error says what disagrees.
    pub fn check(&self, named: &BTreeSet<ViolationKind>) -> Result<(), String> {
        let missed: Vec<_> = self.definite.difference(named).collect();
        let extra: Vec<_> = named.difference(&self.possible).collect();
        if missed.is_empty() && extra.is_empty() {
            Ok(())
        } else {
            Err(format!(
                "the watch missed {missed:?} and named {extra:?} beyond the margin (definite {:?}, possible {:?}, named {named:?})",
                self.definite, self.possible
            ))
        }
    }
}

/// The height a cabin at `x` going up (or down) may not pass after STOP: the first floor level
/// more than a vane's half-length ahead, plus that half-length; `None` if a level is within
/// 2 mm of that edge (the referee's sample and the watch's moment could pick different floors)
/// or there is no such floor.
fn next_limit(levels_mm: &[f64], x: f64, up: bool) -> Option<f64> {
    if levels_mm
        .iter()
        .any(|&l| ((l - x).abs() - VANE_HALF_MM).abs() < 2.0)
    {
        return None;
    }
    if up {
        levels_mm
            .iter()
            .find(|&&l| l - x > VANE_HALF_MM)
            .map(|l| l + VANE_HALF_MM)
    } else {
        levels_mm
            .iter()
            .rev()
            .find(|&&l| x - l > VANE_HALF_MM)
            .map(|l| l - VANE_HALF_MM)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A referee of the lab shaft (floors at 0, 400, 800, 1200 mm; ends at −140 and 1340 mm).
    fn lab() -> Referee {
        Referee::of_shaft(vec![0.0, 400.0, 800.0, 1_200.0], (-140.0, 1_340.0))
    }

    fn moving(position_mm: f64, velocity_mm_s: f64) -> Sample {
        Sample {
            position_mm,
            velocity_mm_s,
            door_open: false,
            overloaded: false,
            k1_closed: true,
            stop: false,
            estop_out: true,
            run_commanded: false,
            overtravel: false,
            crashes: 0,
        }
    }

    /// Feeds `n` samples from `from_ms`, 1 ms apart, made by `f(ms)`.
    fn feed(r: &mut Referee, from_ms: u64, n: u64, f: impl Fn(u64) -> Sample) {
        for k in from_ms..from_ms + n {
            r.see(SimTime::from_millis(k), f(k));
        }
    }

    #[test]
    fn door_open_under_power_is_definite_past_1050_ms_and_possible_past_950() {
        let open = |_| Sample {
            door_open: true,
            ..moving(100.0, 30.0)
        };
        let mut r = lab();
        feed(&mut r, 1, 951, open);
        assert!(r.possible.contains(&ViolationKind::DoorOpenMoving));
        assert!(r.definite.is_empty());
        feed(&mut r, 952, 99, open);
        assert!(r.definite.is_empty());
        feed(&mut r, 1_051, 1, open);
        assert!(r.definite.contains(&ViolationKind::DoorOpenMoving));
        // With K1 open (the brake, the crank) it is never definite.
        let mut r = lab();
        feed(&mut r, 1, 5_000, |_| Sample {
            door_open: true,
            k1_closed: false,
            ..moving(100.0, 30.0)
        });
        assert!(r.definite.is_empty());
        assert!(r.check(&[ViolationKind::DoorOpenMoving].into()).is_ok());
        assert!(r.check(&BTreeSet::new()).is_ok());
        assert!(r.check(&[ViolationKind::StopOverrun].into()).is_err());
    }

    #[test]
    fn the_budget_slides_over_10_s() {
        // 0.9 s open now and 0.9 s open 10 s later: never more than 1.05 s within 10 s.
        let mut r = lab();
        let at = |k: u64| Sample {
            door_open: k % 10_000 < 900,
            ..moving(100.0, 30.0)
        };
        feed(&mut r, 0, 20_000, at);
        assert!(r.definite.is_empty() && r.possible.is_empty());
    }

    #[test]
    fn after_stop_the_next_floor_ahead_plus_40_mm_is_the_limit() {
        assert_eq!(next_limit(&lab().levels_mm, 120.0, true), Some(440.0));
        assert_eq!(next_limit(&lab().levels_mm, 370.0, true), Some(840.0));
        assert_eq!(next_limit(&lab().levels_mm, 1_000.0, false), Some(760.0));
        // 41 mm below a floor: the watch's sample and the referee's may differ; undecided.
        assert_eq!(next_limit(&lab().levels_mm, 359.0, true), None);
        // Passing 440 + 5 mm going up after STOP is definite; a stop short of it is not.
        let stopped = |x: f64, v: f64| Sample {
            estop_out: false,
            ..moving(x, v)
        };
        let mut r = lab();
        feed(&mut r, 0, 100, |k| stopped(120.0 + k as f64, 100.0));
        feed(&mut r, 100, 1, |_| stopped(444.0, 100.0));
        assert!(r.definite.is_empty());
        feed(&mut r, 101, 1, |_| stopped(446.0, 100.0));
        assert!(r.definite.contains(&ViolationKind::StopOverrun));
        // Reversing is definite once the cabin is more than 45 mm back from its farthest point.
        let mut r = lab();
        feed(&mut r, 0, 10, |_| stopped(200.0, 100.0));
        feed(&mut r, 10, 1, |_| stopped(156.0, -2.0));
        assert!(r.definite.is_empty());
        feed(&mut r, 11, 1, |_| stopped(154.0, -2.0));
        assert!(r.definite.contains(&ViolationKind::StopOverrun));
    }
}
