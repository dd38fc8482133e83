//! The traffic templates' passengers in the rig (`scenario::traffic`): each comes to their
//! origin at their time and presses the hall button of their direction; once a stop answers
//! it, they step aboard and press the cabin button of their destination.
//!
//! The lab door is moved by hand and no passenger here moves it: a passenger boards during
//! the controller's dwell at the stop that answers their hall call (2 s, `ControllerConfig`),
//! and presses the cabin button [`BOARDING`] after the stop, so that the cabin's word carries
//! the press to the PLC before the cabin leaves.

use super::*;
use crate::report::traffic::{TrafficReport, TripReport};
use crate::scenario::traffic::{self, Trip};
use crate::scenario::DEFAULT_HOLD;
use lift_model::Button;

/// From the stop that answers a passenger's hall call to their cabin press: a step aboard.
/// The press (held [`DEFAULT_HOLD`]) and the cabin word's 14 scans end within the 2 s dwell.
pub(super) const BOARDING: SimDuration = SimDuration::from_secs(1);

/// The passengers of the traffic templates.
#[derive(Clone, Debug, Default)]
pub(super) struct Riders {
    /// Everyone who will come, in time order.
    trips: Vec<Trip>,
    /// The next to come, an index into `trips`.
    next: usize,
    /// Those who came.
    came: Vec<Rider>,
    /// Those at their origin whose hall call no stop has answered yet (indices into `came`).
    waiting: Vec<usize>,
    /// Those who board: when each presses the cabin button.
    boarding: Vec<(SimTime, usize)>,
    /// Whether the scenario has traffic at all (the report's `traffic` only then).
    on: bool,
    /// The span of the handling capacity's mean: the first template's start and the last
    /// template's end.
    span: (SimTime, SimTime),
}

/// A passenger who came, with their presses (indices into the rig's [`Passengers`]).
#[derive(Clone, Debug)]
struct Rider {
    trip: Trip,
    hall: usize,
    cabin: Option<usize>,
}

impl Riders {
    /// The passengers of `sc`'s templates.
    pub(super) fn of(sc: &Scenario) -> Riders {
        let end = SimTime::ZERO + sc.duration;
        let start = sc.traffic.iter().map(|t| SimTime::ZERO + t.start).min();
        let last = sc
            .traffic
            .iter()
            .map(|t| {
                t.duration
                    .map_or(end, |d| (SimTime::ZERO + t.start + d).min(end))
            })
            .max();
        Riders {
            trips: traffic::trips(&sc.traffic, sc.seed, sc.floors, end),
            on: !sc.traffic.is_empty(),
            span: (start.unwrap_or(end), last.unwrap_or(end)),
            ..Riders::default()
        }
    }

    /// When a passenger next comes or presses a cabin button.
    #[inline]
    pub(super) fn next_at(&self) -> Option<SimTime> {
        let boarding = self.boarding.iter().map(|(at, _)| *at).min();
        match (self.trips.get(self.next).map(|t| t.at), boarding) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

impl Rig {
    /// The passengers due at `t`: those who come press their hall button, those who board
    /// their cabin button.
    pub(super) fn riders_due(&mut self, t: SimTime) {
        if self.people.riders.next_at().is_none_or(|at| at > t) {
            return;
        }
        while let Some(trip) = self
            .people
            .riders
            .trips
            .get(self.people.riders.next)
            .filter(|trip| trip.at <= t)
            .copied()
        {
            self.people.riders.next += 1;
            let button = if trip.up() {
                Button::HallUp(trip.origin)
            } else {
                Button::HallDown(trip.origin)
            };
            let hall = self.press_for_rider(t, button);
            let r = &mut self.people.riders;
            r.waiting.push(r.came.len());
            r.came.push(Rider {
                trip,
                hall,
                cabin: None,
            });
        }
        let mut due = Vec::new();
        self.people.riders.boarding.retain(|&(at, i)| {
            if at <= t {
                due.push(i);
            }
            at > t
        });
        for i in due {
            let button = Button::Cabin(self.people.riders.came[i].trip.destination);
            let cabin = self.press_for_rider(t, button);
            self.people.riders.came[i].cabin = Some(cabin);
        }
    }

    /// A passenger's press of `button` at `t`; its index among the rig's presses.
    fn press_for_rider(&mut self, t: SimTime, button: Button) -> usize {
        let index = self.people.passengers.len();
        let press = Action::Press {
            button,
            hold: DEFAULT_HOLD,
        };
        self.act(t, Actor::Scenario, &press);
        index
    }

    /// A stop answered calls: the waiting passengers whose hall call it answered board.
    pub(super) fn riders_answered(&mut self) {
        if self.people.riders.waiting.is_empty() {
            return;
        }
        let now = self.agenda.now;
        let r = &mut self.people.riders;
        let passengers = &self.people.passengers;
        let mut boarded = false;
        r.waiting
            .retain(|&i| match passengers.served_at(r.came[i].hall) {
                Some(at) => {
                    r.boarding.push(((at + BOARDING).max(now), i));
                    boarded = true;
                    false
                }
                None => true,
            });
        if boarded {
            self.own_moments_changed();
        }
    }

    /// The report's `traffic`, if the scenario has templates.
    pub(super) fn traffic_report(&self) -> Option<TrafficReport> {
        let r = &self.people.riders;
        if !r.on {
            return None;
        }
        let p = &self.people.passengers;
        let secs = |t: SimTime| round3(t.as_secs_f64());
        let trips = r
            .came
            .iter()
            .map(|c| TripReport {
                origin: c.trip.origin,
                destination: c.trip.destination,
                hall_pressed_s: secs(c.trip.at),
                hall_answered_s: p.served_at(c.hall).map(secs),
                cabin_pressed_s: c.cabin.map(|i| secs(p.pressed_at(i))),
                delivered_s: c.cabin.and_then(|i| p.served_at(i)).map(secs),
            })
            .collect();
        let end = r.span.1.min(self.agenda.now);
        let span = end.saturating_duration_since(r.span.0).as_secs_f64();
        Some(TrafficReport::of(trips, span))
    }
}
