//! The passengers: every press of a call button, which stop answered it, and the request
//! time of each served call (the report's `passengers` and `served`).

use crate::report::{CallSource, HallDirection, Passenger, Served};
use asi_phy::SimTime;
use controller::{HallDir, ServedCall, Source};
use lift_model::Button;

/// A passenger's press of a call button.
#[derive(Clone, Copy, Debug)]
struct Press {
    at: SimTime,
    button: Button,
    /// When a stop answered it.
    served: Option<SimTime>,
    /// Its call was the target STOP dropped: not the request of a later call.
    dropped: bool,
}

/// Every press of a call button in a run.
#[derive(Clone, Debug, Default)]
pub(super) struct Passengers {
    presses: Vec<Press>,
}

impl Passengers {
    /// How many presses so far (the index of the next).
    pub(super) fn len(&self) -> usize {
        self.presses.len()
    }

    /// When press `i` was made.
    pub(super) fn pressed_at(&self, i: usize) -> SimTime {
        self.presses[i].at
    }

    /// When a stop answered press `i`, if one did.
    pub(super) fn served_at(&self, i: usize) -> Option<SimTime> {
        self.presses.get(i).and_then(|p| p.served)
    }

    /// A press of `button` at `t`; the bell and STOP are no calls.
    pub(super) fn press(&mut self, t: SimTime, button: Button) {
        if button.floor().is_some() {
            self.presses.push(Press {
                at: t,
                button,
                served: None,
                dropped: false,
            });
        }
    }

    /// STOP dropped the target `floor` at `at`: its presses are not the request of a later
    /// call.
    pub(super) fn target_dropped(&mut self, floor: u8, at: SimTime) {
        for p in &mut self.presses {
            if p.button.floor() == Some(floor) && p.at <= at && p.served.is_none() {
                p.dropped = true;
            }
        }
    }

    /// The controller served `s` at `at`. The request: the earliest pending press of the
    /// served button up to the time the call was stored (else the storing time). Every
    /// pending press of that button until now is answered by this stop.
    pub(super) fn served(&mut self, s: &ServedCall, at: SimTime) -> Served {
        let calls = |p: &Press| {
            p.served.is_none()
                && match (s.hall, p.button) {
                    (None, Button::Cabin(f)) => f == s.floor,
                    (Some(HallDir::Up), Button::HallUp(f)) => f == s.floor,
                    (Some(HallDir::Down), Button::HallDown(f)) => f == s.floor,
                    _ => false,
                }
        };
        let requested = self
            .presses
            .iter()
            .filter(|p| calls(p) && !p.dropped && p.at <= s.stored_at)
            .map(|p| p.at)
            .min()
            .unwrap_or(s.stored_at);
        for p in &mut self.presses {
            if calls(p) && p.at <= at {
                p.served = Some(at);
            }
        }
        Served {
            floor: s.floor,
            source: match s.source {
                Source::Cabin => CallSource::Cabin,
                Source::Hall => CallSource::Hall,
            },
            direction: s.hall.map(|d| match d {
                HallDir::Up => HallDirection::Up,
                HallDir::Down => HallDirection::Down,
            }),
            requested_at_s: requested.as_secs_f64(),
            served_at_s: at.as_secs_f64(),
        }
    }

    /// The cabin stopped level at `floor` at `at` under an outside controller: every call
    /// waiting there is answered, one served call per button with its earliest press as the
    /// request, cabin calls first, then up, then down.
    pub(super) fn arrived(&mut self, floor: u8, at: SimTime) -> Vec<Served> {
        let mut served = Vec::new();
        for kind in [
            Button::Cabin(floor),
            Button::HallUp(floor),
            Button::HallDown(floor),
        ] {
            let waiting = |p: &Press| p.button == kind && p.served.is_none() && p.at <= at;
            let Some(requested) = self
                .presses
                .iter()
                .filter(|p| waiting(p))
                .map(|p| p.at)
                .min()
            else {
                continue;
            };
            for p in self.presses.iter_mut().filter(|p| waiting(p)) {
                p.served = Some(at);
            }
            served.push(Served {
                floor,
                source: match kind {
                    Button::Cabin(_) => CallSource::Cabin,
                    _ => CallSource::Hall,
                },
                direction: match kind {
                    Button::HallUp(_) => Some(HallDirection::Up),
                    Button::HallDown(_) => Some(HallDirection::Down),
                    _ => None,
                },
                requested_at_s: requested.as_secs_f64(),
                served_at_s: at.as_secs_f64(),
            });
        }
        served
    }

    /// The presses for the report, in the order they came.
    pub(super) fn report(&self) -> Vec<Passenger> {
        self.presses
            .iter()
            .map(|p| Passenger {
                button: p.button.key(),
                pressed_at_s: p.at.as_secs_f64(),
                served_at_s: p.served.map(|s| s.as_secs_f64()),
            })
            .collect()
    }
}
