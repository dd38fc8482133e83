//! Where the cabin goes next: the lift thesis' FIFO memories or the collective selective control.
//!
//! - **FIFO** (§6.6 of the lift thesis, the "modified single-memory push-button control"): cabin
//!   requests first, in the order pressed; hall calls are stored meanwhile and served afterwards,
//!   in their order; both hall buttons call the cabin to their floor. The target is fixed when the
//!   cabin departs.
//! - **Collective selective** (§5.2.3 of the lift thesis, SIMPLEX): calls are served in the order
//!   the cabin reaches them, cabin and hall alike; a hall call is answered only in its direction,
//!   or when it is the last call that way; then the direction reverses. The decision to stop is
//!   taken floor by floor, at each floor's first vane edge.
//!
//! **Decision** (both): a stop at a floor serves every stored call for that floor that the stop
//! can serve, so a passenger who pressed twice (cabin and hall) is not served twice.

use crate::fifo::{Offer, RequestFifo};
use asi_phy::SimTime;
use serde::{Deserialize, Serialize};

/// The control algorithm.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Algorithm {
    /// §6.6 of the lift thesis: cabin FIFO first, then hall FIFO.
    #[default]
    Fifo,
    /// §5.2.3 of the lift thesis: collective selective in both directions.
    Collective,
}

/// Where a call came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Source {
    /// A button in the cabin.
    Cabin,
    /// A hall button at a floor.
    Hall,
}

/// A direction of travel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Dir {
    /// Towards higher floors.
    Up,
    /// Towards lower floors.
    Down,
}

impl Dir {
    /// The direction from `from` to `to`, `None` if equal.
    pub fn between(from: u8, to: u8) -> Option<Dir> {
        match to.cmp(&from) {
            core::cmp::Ordering::Greater => Some(Dir::Up),
            core::cmp::Ordering::Less => Some(Dir::Down),
            core::cmp::Ordering::Equal => None,
        }
    }

    /// The floor after `floor` in this direction (not checked against the shaft).
    pub fn next(self, floor: u8) -> u8 {
        match self {
            Dir::Up => floor.saturating_add(1),
            Dir::Down => floor.saturating_sub(1),
        }
    }
}

/// A hall call's direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HallDir {
    /// The up button.
    Up,
    /// The down button.
    Down,
}

/// A call served by a stop, for the report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ServedCall {
    /// The floor.
    pub floor: u8,
    /// Cabin or hall.
    pub source: Source,
    /// For a hall call, the button: up or down.
    pub hall: Option<HallDir>,
    /// When the program stored it.
    pub stored_at: SimTime,
}

/// The result of offering a call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stored {
    /// A new call.
    New,
    /// Already stored.
    Duplicate,
    /// The memory is full; the call is lost (FIFO only).
    Full,
}

const MAX_FLOORS: usize = 24;

/// The pending calls of either algorithm, with the time each was stored.
#[derive(Clone, Debug)]
pub struct Dispatcher {
    algorithm: Algorithm,
    floors: u8,
    fifo_cabin: RequestFifo<4>,
    fifo_hall: RequestFifo<4>,
    /// Collective: pending calls as bit sets, bit `f − 1` for floor `f`.
    cabin: u32,
    up: u32,
    down: u32,
    /// When each pending call was stored: [cabin, hall up, hall down][floor − 1].
    stored_at: [[Option<SimTime>; MAX_FLOORS]; 3],
    /// FIFO: where the current target came from.
    target_source: Option<Source>,
}

impl Dispatcher {
    /// An empty dispatcher for `floors` floors.
    pub fn new(algorithm: Algorithm, floors: u8) -> Dispatcher {
        Dispatcher {
            algorithm,
            floors,
            fifo_cabin: RequestFifo::new(),
            fifo_hall: RequestFifo::new(),
            cabin: 0,
            up: 0,
            down: 0,
            stored_at: [[None; MAX_FLOORS]; 3],
            target_source: None,
        }
    }

    /// The algorithm.
    pub fn algorithm(&self) -> Algorithm {
        self.algorithm
    }

    fn bit(floor: u8) -> u32 {
        1u32 << (floor.saturating_sub(1) & 31)
    }

    fn slot(&mut self, kind: usize, floor: u8) -> &mut Option<SimTime> {
        &mut self.stored_at[kind][(floor.clamp(1, MAX_FLOORS as u8) - 1) as usize]
    }

    /// Stores a cabin call for `floor`.
    pub fn cabin_call(&mut self, floor: u8, now: SimTime) -> Stored {
        let stored = match self.algorithm {
            Algorithm::Fifo => offer(&mut self.fifo_cabin, floor),
            Algorithm::Collective => set(&mut self.cabin, Self::bit(floor)),
        };
        if stored == Stored::New {
            *self.slot(0, floor) = Some(now);
        }
        stored
    }

    /// Stores a hall call at `floor`.
    pub fn hall_call(&mut self, floor: u8, dir: HallDir, now: SimTime) -> Stored {
        let kind = if dir == HallDir::Up { 1 } else { 2 };
        let stored = match self.algorithm {
            Algorithm::Fifo => offer(&mut self.fifo_hall, floor),
            Algorithm::Collective => match dir {
                HallDir::Up => set(&mut self.up, Self::bit(floor)),
                HallDir::Down => set(&mut self.down, Self::bit(floor)),
            },
        };
        // The FIFO keeps one hall entry per floor, but each button's first press is remembered
        // so that a stop serves both passengers.
        let record = match stored {
            Stored::New => true,
            Stored::Duplicate => self.algorithm == Algorithm::Fifo,
            Stored::Full => false,
        };
        if record && self.slot(kind, floor).is_none() {
            *self.slot(kind, floor) = Some(now);
        }
        stored
    }

    /// `true` if any call is pending.
    pub fn has_calls(&self) -> bool {
        !self.fifo_cabin.is_empty()
            || !self.fifo_hall.is_empty()
            || self.cabin | self.up | self.down != 0
    }

    /// The next target for a cabin standing at `at` (FIFO Unload; for the collective control
    /// the first stop in the chosen direction). `preferred` is the direction of the last trip.
    pub fn next_target(&mut self, at: u8, preferred: Option<Dir>) -> Option<u8> {
        match self.algorithm {
            Algorithm::Fifo => {
                if let Some(f) = self.fifo_cabin.unload() {
                    self.target_source = Some(Source::Cabin);
                    Some(f)
                } else if let Some(f) = self.fifo_hall.unload() {
                    self.target_source = Some(Source::Hall);
                    Some(f)
                } else {
                    None
                }
            }
            Algorithm::Collective => {
                let all = self.cabin | self.up | self.down;
                if all == 0 {
                    return None;
                }
                if all & Self::bit(at) != 0 {
                    return Some(at);
                }
                let dir = self.choose_direction(at, preferred)?;
                self.first_stop(at, dir)
            }
        }
    }

    /// Collective: keep the last direction while calls lie ahead, else go towards the nearest
    /// call (up on a tie).
    fn choose_direction(&self, at: u8, preferred: Option<Dir>) -> Option<Dir> {
        let all = self.cabin | self.up | self.down;
        let above = all & !(Self::bit(at) | (Self::bit(at) - 1)) != 0;
        let below = all & (Self::bit(at) - 1) != 0;
        match preferred {
            Some(Dir::Up) if above => return Some(Dir::Up),
            Some(Dir::Down) if below => return Some(Dir::Down),
            _ => {}
        }
        let nearest = (1..=self.floors)
            .filter(|f| all & Self::bit(*f) != 0)
            .min_by_key(|f| ((*f as i32 - at as i32).abs(), *f < at))?;
        Dir::between(at, nearest)
    }

    fn calls_beyond(&self, floor: u8, dir: Dir) -> bool {
        let all = self.cabin | self.up | self.down;
        match dir {
            Dir::Up => all & !(Self::bit(floor) | (Self::bit(floor) - 1)) != 0,
            Dir::Down => all & (Self::bit(floor) - 1) != 0,
        }
    }

    /// Collective: whether a cabin travelling `dir` stops at `floor`.
    pub fn should_stop(&self, floor: u8, dir: Dir) -> bool {
        let b = Self::bit(floor);
        let hall_same = match dir {
            Dir::Up => self.up & b != 0,
            Dir::Down => self.down & b != 0,
        };
        let hall_any = (self.up | self.down) & b != 0;
        self.cabin & b != 0 || hall_same || (hall_any && !self.calls_beyond(floor, dir))
    }

    fn first_stop(&self, at: u8, dir: Dir) -> Option<u8> {
        let mut f = at;
        loop {
            f = dir.next(f);
            if f < 1 || f > self.floors {
                return None;
            }
            if self.should_stop(f, dir) {
                return Some(f);
            }
        }
    }

    /// The calls a stop at `floor` serves, removed from the memories. `dir` is the direction
    /// the cabin arrived in (`None` when it did not move).
    pub fn serve(&mut self, floor: u8, dir: Option<Dir>, out: &mut Vec<ServedCall>) {
        let b = Self::bit(floor);
        let mut take = |s: &mut Self, kind: usize| {
            let (source, hall) = match kind {
                0 => (Source::Cabin, None),
                1 => (Source::Hall, Some(HallDir::Up)),
                _ => (Source::Hall, Some(HallDir::Down)),
            };
            if let Some(stored_at) = s.slot(kind, floor).take() {
                out.push(ServedCall {
                    floor,
                    source,
                    hall,
                    stored_at,
                });
            }
        };
        match self.algorithm {
            Algorithm::Fifo => {
                self.fifo_cabin.remove(floor);
                self.fifo_hall.remove(floor);
                take(self, 0);
                take(self, 1);
                take(self, 2);
            }
            Algorithm::Collective => {
                self.cabin &= !b;
                take(self, 0);
                // The hall call in the direction of travel; both when the cabin turns here or
                // stood still.
                let turning = dir.is_none_or(|d| !self.calls_beyond(floor, d));
                if dir == Some(Dir::Up) || turning {
                    self.up &= !b;
                    take(self, 1);
                }
                if dir == Some(Dir::Down) || turning {
                    self.down &= !b;
                    take(self, 2);
                }
            }
        }
    }

    /// Pending cabin calls: the FIFO in order, or the collective's floors ascending.
    pub fn cabin_calls(&self) -> Vec<u8> {
        match self.algorithm {
            Algorithm::Fifo => self.fifo_cabin.as_slice().to_vec(),
            Algorithm::Collective => floors_of(self.cabin, self.floors),
        }
    }

    /// Pending hall calls: the FIFO in order, or the collective's floors ascending.
    pub fn hall_calls(&self) -> Vec<u8> {
        match self.algorithm {
            Algorithm::Fifo => self.fifo_hall.as_slice().to_vec(),
            Algorithm::Collective => floors_of(self.up | self.down, self.floors),
        }
    }

    /// Stores `floor` again as the next target, after a trip the program had to give up
    /// without losing the call (a bus fault that needs a new initialisation). FIFO: at the
    /// front of the memory the target came from; collective: its call is still pending.
    pub fn requeue(&mut self, floor: u8) {
        if self.algorithm == Algorithm::Fifo {
            let fifo = match self.target_source {
                Some(Source::Hall) => &mut self.fifo_hall,
                _ => &mut self.fifo_cabin,
            };
            fifo.offer_front(floor);
        }
    }
}

fn offer(fifo: &mut RequestFifo<4>, floor: u8) -> Stored {
    match fifo.offer(floor) {
        Offer::Stored => Stored::New,
        Offer::AlreadyQueued => Stored::Duplicate,
        Offer::Full => Stored::Full,
    }
}

fn set(bits: &mut u32, b: u32) -> Stored {
    if *bits & b != 0 {
        Stored::Duplicate
    } else {
        *bits |= b;
        Stored::New
    }
}

fn floors_of(bits: u32, floors: u8) -> Vec<u8> {
    (1..=floors)
        .filter(|f| bits & (1 << (f - 1)) != 0)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: SimTime = SimTime::ZERO;

    #[test]
    fn fifo_serves_cabin_calls_first_then_hall_calls_in_order() {
        let mut d = Dispatcher::new(Algorithm::Fifo, 4);
        d.hall_call(2, HallDir::Up, T);
        d.cabin_call(4, T);
        d.hall_call(3, HallDir::Down, T);
        d.cabin_call(1, T);
        let mut order = Vec::new();
        let mut at = 2;
        while let Some(t) = d.next_target(at, None) {
            order.push(t);
            let mut served = Vec::new();
            d.serve(t, Dir::between(at, t), &mut served);
            at = t;
        }
        assert_eq!(order, [4, 1, 2, 3]);
    }

    #[test]
    fn collective_serves_in_the_order_the_cabin_reaches_the_floors() {
        let mut d = Dispatcher::new(Algorithm::Collective, 4);
        // At floor 1: a cabin call to 4, a hall call down at 3 and up at 2.
        d.cabin_call(4, T);
        d.hall_call(3, HallDir::Down, T);
        d.hall_call(2, HallDir::Up, T);
        assert_eq!(d.next_target(1, None), Some(2));
        assert!(d.should_stop(2, Dir::Up));
        // Going up, the down call at 3 is passed (calls lie beyond it) ...
        assert!(!d.should_stop(3, Dir::Up));
        let mut served = Vec::new();
        d.serve(2, Some(Dir::Up), &mut served);
        assert_eq!(
            served
                .iter()
                .map(|s| (s.floor, s.source))
                .collect::<Vec<_>>(),
            [(2, Source::Hall)]
        );
        assert!(d.should_stop(4, Dir::Up));
        d.serve(4, Some(Dir::Up), &mut served);
        // ... and answered on the way down.
        assert_eq!(d.next_target(4, Some(Dir::Up)), Some(3));
        d.serve(3, Some(Dir::Down), &mut served);
        assert!(!d.has_calls());
        assert_eq!(served.len(), 3);
    }

    #[test]
    fn collective_answers_the_last_call_whatever_its_direction() {
        let mut d = Dispatcher::new(Algorithm::Collective, 4);
        d.hall_call(3, HallDir::Down, T);
        assert_eq!(d.next_target(1, None), Some(3));
        assert!(d.should_stop(3, Dir::Up));
    }
}
