//! The latency samples on the lab rig: the lift shuttles between floors 1 and 2; on every trip
//! a hall call at the other floor is pressed at a seeded random moment after the lift is ready
//! (press → registered in the PLC → run bit on the bus), then STOP at a random moment during the
//! trip (press → EStopOut off → K1 open); the operator resets trips the samples did not cause.

use super::collector::{lock, Collector};
use super::options::TimingOptions;
use super::report::{HallSample, Latencies, StopSample};
use super::stats::{figure_of, ms};
use crate::rig::Rig;
use crate::scenario::Action;
use asi_phy::{SimDuration, SimTime};
use controller::State;
use lift_model::Button;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::sync::Mutex;

/// Whether the controller tells that it is in service ([`State::in_service`]: the built-in
/// program's `is_initialised`).
pub(super) fn in_service(rig: &Rig) -> bool {
    rig.controller_status().state.is_some_and(State::in_service)
}

/// Since when the controller has been in service without a break (the built-in program's
/// `initialised_at`): noted at every moment the study steps through.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct InService(pub(super) Option<SimTime>);

impl InService {
    /// Notes the controller's state at the moment reached.
    pub(super) fn note(&mut self, rig: &Rig) {
        if in_service(rig) {
            self.0.get_or_insert(rig.now());
        } else {
            self.0 = None;
        }
    }
}

/// The lift stands at `floor`, ready to depart: the program at the floor without a fault
/// (the state it tells; for the built-in program, its display shows neither moving nor a
/// fault exactly then), its target that floor, the converter's run bit off on the bus, the
/// drive powered and not moving, no STOP demand. Any controller that tells its state, floor
/// and target (the built-in program, a Structured Text program through the agreed variables)
/// can be timed.
pub(super) fn ready_at(rig: &Rig, floor: u8) -> bool {
    let status = rig.controller_status();
    status.state == Some(State::AtFloor)
        && status.floor == Some(floor)
        && status.target == Some(floor)
        && !run_bit(rig)
        && rig.lift().velocity_mm_s() == 0.0
        && rig.lift().k1_closed()
        && rig.lift().converter_ready()
        && rig.estop_out()
}

/// The converter's run bit (D0 of its slave) in the output image the controller wrote.
fn run_bit(rig: &Rig) -> bool {
    asi_phy::SlaveAddr::a(lab::address::CONVERTER)
        .is_some_and(|a| rig.lab().bus().image().output.nibble(a).bit(0))
}

/// Steps `rig` until `cond` holds (checked now and after every moment), at most `limit`.
fn wait_until(
    rig: &mut Rig,
    limit: SimDuration,
    mut cond: impl FnMut(&Rig) -> bool,
) -> Option<SimTime> {
    if cond(rig) {
        return Some(rig.now());
    }
    let deadline = rig.now() + limit;
    while let Some(t) = rig.step_until(deadline) {
        if cond(rig) {
            return Some(t);
        }
    }
    None
}

/// How long the operator takes to press the reset after an unexpected trip.
const OPERATOR_REACTION: SimDuration = SimDuration::from_millis(100);

/// [`wait_until`], with the operator resetting a trip that opens K1 without a STOP demand
/// (the Safety-at-Work monitor under line noise); counts the resets in `resets`. Before the
/// program is initialised, only a trip after K1 had closed in this wait counts (at power-on K1
/// is open until the operator's first reset).
pub(super) fn wait_resetting(
    rig: &mut Rig,
    limit: SimDuration,
    resets: &mut u32,
    mut cond: impl FnMut(&Rig) -> bool,
) -> Option<SimTime> {
    let deadline = rig.now() + limit;
    let mut reset_at: Option<SimTime> = None;
    let mut powered = false;
    loop {
        if cond(rig) {
            return Some(rig.now());
        }
        powered |= rig.lift().k1_closed();
        let tripped = (in_service(rig) || powered) && rig.estop_out() && !rig.lift().k1_closed();
        if tripped && reset_at.is_none_or(|t| rig.now() >= t + SimDuration::from_secs(1)) {
            let at = rig.now() + OPERATOR_REACTION;
            rig.schedule(at, Action::Reset);
            reset_at = Some(at);
            *resets += 1;
        }
        rig.step_until(deadline)?;
    }
}

/// Mixed into the options' seed for the press moments ("timing" in ASCII): the line noise is
/// a ChaCha8 stream seeded with the seed itself (asi-phy's `FaultInjector`), and the press
/// moments must not repeat its draws.
const PRESS_STREAM: u64 = 0x7469_6D69_6E67;

/// The seeded source of press moments.
/// The seeded source of press moments.
fn press_rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed ^ PRESS_STREAM)
}

/// A uniform duration in [0, span).
fn below(rng: &mut ChaCha8Rng, span: SimDuration) -> SimDuration {
    match span.as_nanos() {
        0 => SimDuration::ZERO,
        n => SimDuration::from_nanos(rng.random_range(0..n)),
    }
}

/// How long a wait in the latency sampling may take before sampling gives up.
const STEP_LIMIT: SimDuration = SimDuration::from_secs(60);
const HOLD: SimDuration = SimDuration::from_millis(300);

/// The program has arrived at `floor` (it stands there, possibly in the STOP fault).
fn arrived(rig: &Rig, floor: u8) -> bool {
    let status = rig.controller_status();
    status.floor == Some(floor) && matches!(status.state, Some(State::AtFloor | State::StopFault))
}

/// Notes the first moment the program is seen arrived at `floor`.
fn track(rig: &Rig, floor: u8, arrival: &mut Option<SimTime>) {
    if arrival.is_none() && arrived(rig, floor) {
        *arrival = Some(rig.now());
    }
}

/// Shuttles the lift between floors 1 and 2 and times a hall call and a STOP on every trip.
pub(super) fn sample_latencies(
    rig: &mut Rig,
    shared: &Mutex<Collector>,
    opts: &TimingOptions,
    initialised_at: Option<SimTime>,
) -> Latencies {
    let mut s = Sampler {
        // The built-in program's dwell: the press moments need only its order of magnitude.
        dwell: controller::ControllerConfig::default().dwell,
        stop_delay: safety::LiftSafetyConfig::default().estop_delay,
        // When the program last arrived at a floor: it departs no earlier than a dwell later.
        arrival: initialised_at,
        rig,
        shared,
        rng: press_rng(opts.seed),
        out: Latencies::default(),
    };
    let mut here = 1u8;
    for k in 0..opts.samples as usize {
        let there = if here == 1 { 2 } else { 1 };
        if let Err(what) = s.trip(here, there) {
            s.out.incomplete = Some(format!(
                "sampling stopped after {k} samples: {what} not seen within {STEP_LIMIT}"
            ));
            break;
        }
        here = there;
    }
    let mut out = s.out;
    set_figures(&mut out);
    out
}

/// The latency sampling in progress.
struct Sampler<'a> {
    rig: &'a mut Rig,
    shared: &'a Mutex<Collector>,
    rng: ChaCha8Rng,
    /// The program's dwell at a floor.
    dwell: SimDuration,
    /// The safety logic's STOP delay.
    stop_delay: SimDuration,
    /// When the program last arrived at a floor.
    arrival: Option<SimTime>,
    out: Latencies,
}

/// What was not seen when a step of a trip gave up.
type Missing = &'static str;

impl Sampler<'_> {
    /// One trip from `here` to `there`: a hall call sample, a STOP sample, and the restart.
    fn trip(&mut self, here: u8, there: u8) -> Result<(), Missing> {
        let ready = self.ready(here)?;
        let rise = self.hall_call(ready, there)?;
        self.arrival = None;
        self.stop(rise, there)?;
        self.resume(there)
    }

    /// Waits until the lift stands ready at `here`.
    fn ready(&mut self, here: u8) -> Result<SimTime, Missing> {
        let mut resets = 0;
        let arrival = &mut self.arrival;
        let ready = wait_resetting(self.rig, STEP_LIMIT, &mut resets, |r| {
            track(r, here, arrival);
            ready_at(r, here)
        });
        self.out.operator_resets += resets;
        ready.ok_or("the lift ready at its floor")
    }

    /// Presses the hall button at `there` at a random moment after the lift is `ready` and its
    /// dwell is over; times registration and the run bit. Returns the run bit's rise.
    fn hall_call(&mut self, ready: SimTime, there: u8) -> Result<SimTime, Missing> {
        let earliest =
            ready.max(self.arrival.unwrap_or(ready) + self.dwell) + SimDuration::from_millis(100);
        let press = earliest + below(&mut self.rng, SimDuration::from_millis(500));
        let button = if there == 1 {
            Button::HallUp(1)
        } else {
            Button::HallDown(there)
        };
        self.rig
            .schedule(press, Action::Press { button, hold: HOLD });
        // Registered: the program holds the call (as its target or in FIFO_Patra).
        let mut resets = 0;
        let registered = wait_resetting(self.rig, STEP_LIMIT, &mut resets, |r| {
            r.now() >= press
                && (r.controller_status().target == Some(there)
                    || r.controller_calls()
                        .is_some_and(|c| c.hall.contains(&there)))
        });
        let shared = self.shared;
        let rig = &mut *self.rig;
        let rise = registered.and_then(|registered| {
            wait_resetting(rig, STEP_LIMIT, &mut resets, |_| {
                lock(shared).run_rises.iter().any(|&t| t >= registered)
            })?;
            lock(shared)
                .run_rises
                .iter()
                .copied()
                .find(|&t| t >= registered)
        });
        self.out.operator_resets += resets;
        let (Some(registered), Some(rise)) = (registered, rise) else {
            return Err("the hall call registered and the run bit on the bus");
        };
        // A trip reset on the way held the departure: that sample is not counted.
        if resets == 0 {
            self.out.hall.push(HallSample {
                pressed_s: press.as_secs_f64(),
                registered_ms: ms(registered - press),
                run_bit_ms: ms(rise - registered),
            });
        }
        Ok(rise)
    }

    /// Presses STOP at a random moment during the trip to `there`; times EStopOut and K1.
    fn stop(&mut self, rise: SimTime, there: u8) -> Result<(), Missing> {
        let stop = rise.max(self.rig.now())
            + SimDuration::from_millis(300)
            + below(&mut self.rng, SimDuration::from_millis(700));
        self.rig.schedule(
            stop,
            Action::Press {
                button: Button::Stop,
                hold: HOLD,
            },
        );
        let arrival = &mut self.arrival;
        let estop = wait_until(self.rig, STEP_LIMIT, |r| {
            track(r, there, arrival);
            r.now() >= stop && !r.estop_out()
        })
        .ok_or("EStopOut off after STOP")?;
        let (k1, spoiled) = self.k1_open(estop, there)?;
        if !spoiled {
            self.out.stop.push(StopSample {
                pressed_s: stop.as_secs_f64(),
                estop_out_ms: ms(estop - stop),
                k1_open_ms: ms(k1 - estop),
            });
        }
        Ok(())
    }

    /// Waits for K1 to open after EStopOut dropped at `estop`; whether a trip spoiled the
    /// sample. K1 opens when the STOP delay has run out. Opening earlier is a trip the sample
    /// did not cause (the Safety-at-Work monitor under line noise): the operator resets it, K1
    /// closes again until the delay runs out, and the sample is not counted.
    fn k1_open(&mut self, estop: SimTime, there: u8) -> Result<(SimTime, bool), Missing> {
        const MISSING: Missing = "K1 open after STOP";
        let mut spoiled = false;
        loop {
            let arrival = &mut self.arrival;
            let k1 = wait_until(self.rig, STEP_LIMIT, |r| {
                track(r, there, arrival);
                !r.lift().k1_closed()
            })
            .ok_or(MISSING)?;
            if k1 - estop + safety::SAFETY_SCAN_PERIOD >= self.stop_delay {
                return Ok((k1, spoiled));
            }
            spoiled = true;
            self.out.operator_resets += 1;
            self.rig.schedule(k1 + OPERATOR_REACTION, Action::Reset);
            // The STOP delay may run out before the reset takes effect: then K1 stays open.
            let delay_over = estop + self.stop_delay + safety::SAFETY_SCAN_PERIOD;
            let arrival = &mut self.arrival;
            let closed = wait_until(self.rig, STEP_LIMIT, |r| {
                track(r, there, arrival);
                r.lift().k1_closed() || r.now() >= delay_over
            })
            .ok_or(MISSING)?;
            if !self.rig.lift().k1_closed() {
                return Ok((closed, spoiled));
            }
        }
    }

    /// The cabin stands at the floor it was heading for (or, after a trip, held short of it):
    /// a cabin request for that floor restarts the STOP circuit and service resumes.
    fn resume(&mut self, there: u8) -> Result<(), Missing> {
        let arrival = &mut self.arrival;
        wait_until(self.rig, STEP_LIMIT, |r| {
            track(r, there, arrival);
            r.lift().velocity_mm_s() == 0.0
        })
        .ok_or("the cabin at rest after STOP")?;
        self.rig.schedule(
            self.rig.now() + OPERATOR_REACTION,
            Action::Press {
                button: Button::Cabin(there),
                hold: HOLD,
            },
        );
        Ok(())
    }
}

/// The latencies' figures from their samples.
fn set_figures(out: &mut Latencies) {
    let hall = |f: fn(&HallSample) -> f64| figure_of(&out.hall.iter().map(f).collect::<Vec<_>>());
    let stop = |f: fn(&StopSample) -> f64| figure_of(&out.stop.iter().map(f).collect::<Vec<_>>());
    let figures = (
        hall(|s| s.registered_ms),
        hall(|s| s.run_bit_ms),
        hall(|s| s.registered_ms + s.run_bit_ms),
        stop(|s| s.estop_out_ms),
        stop(|s| s.k1_open_ms),
        stop(|s| s.estop_out_ms + s.k1_open_ms),
    );
    (
        out.press_to_registered_ms,
        out.registered_to_run_bit_ms,
        out.press_to_run_bit_ms,
        out.stop_to_estop_out_ms,
        out.estop_out_to_k1_open_ms,
        out.stop_to_k1_open_ms,
    ) = figures;
}
