//! The shaft as the cabin's sensors see it: vane tracks, overtravel trip zones and mechanical ends,
//! flattened into one sorted list of boundaries (docs/lift-plant.md; §6.3, §6.4 of the lift
//! thesis).
//!
//! Every zone is a closed interval of cabin position: a vane sensor is on for `from ≤ x ≤ to`,
//! an overtravel sensor is tripped at its trip point and beyond, the cabin may touch a
//! mechanical end but not pass it. Each zone edge is a [`Boundary`]; the plant keeps one
//! index (`split`) into the sorted list, the boundaries below it are the ones the cabin has
//! passed, so the next edge in either direction is one step away.

use crate::config::LiftConfig;
use crate::event::PlantEventKind;
use crate::sensor::{End, VaneSensor};

/// What changes when the cabin crosses a boundary.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Signal {
    Vane(VaneSensor),
    Overtravel(End),
    MechanicalEnd(End),
}

/// Which side of a boundary belongs to its closed zone.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Side {
    /// The zone is `x ≥ pos` (the lower edge of a zone).
    Lower,
    /// The zone is `x ≤ pos` (the upper edge of a zone).
    Upper,
}

/// One zone edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Boundary {
    pub pos: f64,
    pub side: Side,
    pub signal: Signal,
}

impl Boundary {
    /// Whether the cabin at `x`, moving up (`up`) or down, is past this boundary.
    ///
    /// This is the single rule that decides every edge: moving up the cabin enters a zone at
    /// `x ≥ from` and leaves it at `x > to`; moving down it enters at `x ≤ to` and leaves at
    /// `x < from`. So the boundary point itself always belongs to the zone.
    pub fn passed(&self, x: f64, up: bool) -> bool {
        match (up, self.side) {
            (true, Side::Lower) => x >= self.pos,
            (true, Side::Upper) => x > self.pos,
            (false, Side::Upper) => x <= self.pos,
            (false, Side::Lower) => x < self.pos,
        }
    }

    /// The signal level just above the boundary: in the zone above a lower edge, out of it
    /// above an upper edge. (For an overtravel zone "in" means tripped.)
    fn level_above(&self) -> bool {
        self.side == Side::Lower
    }
}

/// The levels of the position sensors, which change only at boundaries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Levels {
    pub left: bool,
    pub right: bool,
    pub bottom_tripped: bool,
    pub top_tripped: bool,
}

impl Levels {
    /// The levels far below the shaft: vanes off, bottom overtravel tripped.
    const BELOW_ALL: Levels = Levels {
        left: false,
        right: false,
        bottom_tripped: true,
        top_tripped: false,
    };

    /// Applies the crossing of `b` moving up or down and says what changed, or which
    /// mechanical end the cabin hit (that changes no level: the cabin stops at the end).
    pub fn cross(&mut self, b: &Boundary, up: bool) -> Result<PlantEventKind, End> {
        let level = if up {
            b.level_above()
        } else {
            !b.level_above()
        };
        let (slot, kind) = match b.signal {
            Signal::Vane(sensor) => {
                let slot = match sensor {
                    VaneSensor::Left => &mut self.left,
                    VaneSensor::Right => &mut self.right,
                };
                (slot, PlantEventKind::Vane { sensor, on: level })
            }
            Signal::Overtravel(end) => {
                let slot = match end {
                    End::Bottom => &mut self.bottom_tripped,
                    End::Top => &mut self.top_tripped,
                };
                (
                    slot,
                    PlantEventKind::Overtravel {
                        end,
                        tripped: level,
                    },
                )
            }
            Signal::MechanicalEnd(end) => return Err(end),
        };
        *slot = level;
        Ok(kind)
    }
}

/// The sorted boundaries of a validated configuration.
#[derive(Clone, Debug)]
pub(crate) struct Shaft {
    pub boundaries: Vec<Boundary>,
}

impl Shaft {
    /// Builds the boundary list; `config` must have passed [`LiftConfig::validate`].
    pub fn new(config: &LiftConfig) -> Shaft {
        let mut boundaries = Vec::with_capacity(4 * usize::from(config.floors) + 4);
        for sensor in [VaneSensor::Left, VaneSensor::Right] {
            for floor in 1..=config.floors {
                if let Some((from, to)) = config.vane_track_mm(sensor, floor) {
                    boundaries.push(zone_edge(from, Side::Lower, Signal::Vane(sensor)));
                    boundaries.push(zone_edge(to, Side::Upper, Signal::Vane(sensor)));
                }
            }
        }
        for end in [End::Bottom, End::Top] {
            // The bottom zones lie below their points, the top zones above.
            let side = match end {
                End::Bottom => Side::Upper,
                End::Top => Side::Lower,
            };
            let trip = config.trip_position_mm(end);
            boundaries.push(zone_edge(trip, side, Signal::Overtravel(end)));
            // The mechanical "zone" is the legal travel, so its sides are the other way round.
            let legal = match end {
                End::Bottom => Side::Lower,
                End::Top => Side::Upper,
            };
            let stop = config.end_position_mm(end);
            boundaries.push(zone_edge(stop, legal, Signal::MechanicalEnd(end)));
        }
        // By position; at one position a lower edge is passed before an upper one moving up
        // (x ≥ p before x > p), and after it moving down, which matches `split` below.
        boundaries.sort_by(|a, b| a.pos.total_cmp(&b.pos).then(a.side.cmp(&b.side)));
        Shaft { boundaries }
    }

    /// How many boundaries lie below the cabin at `x`: those passed moving up to `x`.
    pub fn split_at(&self, x: f64) -> usize {
        self.boundaries.partition_point(|b| b.passed(x, true))
    }

    /// The sensor levels with the cabin at `x`, `split` being [`Shaft::split_at`]`(x)`.
    pub fn levels_below(&self, split: usize) -> Levels {
        let mut levels = Levels::BELOW_ALL;
        for b in &self.boundaries[..split] {
            // A mechanical end below the cabin changes no level.
            let _ = levels.cross(b, true);
        }
        levels
    }
}

fn zone_edge(pos: f64, side: Side, signal: Signal) -> Boundary {
    Boundary { pos, side, signal }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn levels_at(x: f64) -> Levels {
        let shaft = Shaft::new(&LiftConfig::default());
        shaft.levels_below(shaft.split_at(x))
    }

    #[test]
    fn track_ends_belong_to_the_track() {
        // Floor 1: left long ±40, right short ±10 (docs/lift-plant.md).
        assert!(levels_at(40.0).left && !levels_at(40.0).right);
        assert!(!levels_at(40.000_001).left);
        assert!(levels_at(-10.0).right && levels_at(10.0).right);
        assert!(!levels_at(10.000_001).right);
        // Floor 2 at 400: right long ±40, left short ±10.
        assert!(levels_at(360.0).right && !levels_at(360.0).left);
        assert!(!levels_at(359.999_999).right);
        assert!(levels_at(390.0).left && levels_at(410.0).left);
    }

    #[test]
    fn overtravel_zones_include_their_trip_points() {
        assert!(levels_at(-60.0).bottom_tripped);
        assert!(!levels_at(-59.999_999).bottom_tripped);
        assert!(levels_at(1260.0).top_tripped);
        assert!(!levels_at(1_259.999_999).top_tripped);
        assert!(!levels_at(0.0).bottom_tripped && !levels_at(0.0).top_tripped);
    }

    #[test]
    fn boundaries_are_sorted_with_the_ends_outermost() {
        let shaft = Shaft::new(&LiftConfig::default());
        let b = &shaft.boundaries;
        assert_eq!(b.len(), 4 * 4 + 4);
        assert!(b.windows(2).all(|w| w[0].pos <= w[1].pos));
        assert_eq!(b[0].signal, Signal::MechanicalEnd(End::Bottom));
        assert_eq!(b[0].pos, -140.0);
        assert_eq!(b[b.len() - 1].signal, Signal::MechanicalEnd(End::Top));
        assert_eq!(b[b.len() - 1].pos, 1340.0);
        // At the mechanical ends the cabin is inside the legal travel.
        assert_eq!(shaft.split_at(-140.0), 1);
        assert_eq!(shaft.split_at(1340.0), b.len() - 1);
    }
}
