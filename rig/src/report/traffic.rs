//! The report's `traffic`: the passengers of a scenario's traffic templates measured as lift
//! planners measure them (the book, "Traffic as planners measure it"): waiting time per call
//! kind, journey time, their mean, 95th percentile and maximum, and the handling capacity per
//! five minutes (the ELEVATE manual, "Passenger Demand": persons per five minutes; Barney and
//! Al-Sharif, "Elevator Traffic Handbook").

use serde::Serialize;
use std::fmt::Write as _;

/// `x` rounded to the millisecond, the precision of the report's times (as `report::round3`;
/// not named here, so that this module depends on nothing of its parent).
fn round3(x: f64) -> f64 {
    (x * 1000.0).round() / 1000.0
}

/// What the passengers of the traffic templates met.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct TrafficReport {
    /// Passengers who came to their origin during the run.
    pub passengers: usize,
    /// Those whose hall call a stop answered: they boarded and pressed their cabin button.
    pub boarded: usize,
    /// Those the cabin brought to their destination.
    pub delivered: usize,
    /// Waiting times per call kind: `hall`, from the hall press to the stop that answers it
    /// (the planners' waiting time); `cabin`, from the cabin press aboard to the stop at the
    /// destination (the planners' transit time, here counted from the press).
    pub waiting: CallKinds,
    /// Journey times: from the hall press to the stop at the destination (the planners' time
    /// to destination: waiting and transit, boarding included).
    pub journey: Times,
    /// Passengers delivered per five minutes.
    pub handling_capacity: HandlingCapacity,
    /// Every passenger, in the order they came.
    pub trips: Vec<TripReport>,
}

/// Figures per call kind.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CallKinds {
    /// Hall calls.
    pub hall: Times,
    /// Cabin calls.
    pub cabin: Times,
}

/// The times of the answered calls (or completed journeys), seconds; `None` without any.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Times {
    /// How many were answered.
    pub count: usize,
    /// How many were made but not answered by the end of the run.
    pub unanswered: usize,
    /// The mean.
    pub mean_s: Option<f64>,
    /// The 95th percentile by the nearest-rank method ([`nearest_rank`]).
    pub p95_s: Option<f64>,
    /// The maximum.
    pub max_s: Option<f64>,
}

/// Passengers delivered per five minutes.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HandlingCapacity {
    /// The mean: delivered passengers × 300 s / `span_s`.
    pub mean_per_5min: f64,
    /// The most delivered within any five minutes of the run (a window ending at each
    /// delivery): the planners' peak five-minute figure.
    pub peak_per_5min: usize,
    /// The span the mean is over, seconds: from the first template's start to the run's end
    /// (or the last template's end, if earlier).
    pub span_s: f64,
}

/// One passenger.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TripReport {
    /// The origin floor.
    pub origin: u8,
    /// The destination floor.
    pub destination: u8,
    /// When they pressed the hall button at the origin, seconds.
    pub hall_pressed_s: f64,
    /// When a stop answered it, or null.
    pub hall_answered_s: Option<f64>,
    /// When they pressed the cabin button aboard, or null.
    pub cabin_pressed_s: Option<f64>,
    /// When the cabin stopped at their destination, or null.
    pub delivered_s: Option<f64>,
}

/// The `p`-th percentile (0 < `p` ≤ 100) of `values` by the nearest-rank method: the smallest
/// value with at least `p` % of the values at or below it, i.e. the ⌈p/100 × n⌉-th smallest
/// (a value of the data, never an interpolation). `None` for no values.
pub fn nearest_rank(values: &[f64], p: f64) -> Option<f64> {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    // The product is rounded first so that 95 % of 20 is rank 19, not 19.000000000000004.
    let rank = ((p / 100.0 * n as f64 * 1e9).round() / 1e9).ceil() as usize;
    sorted.get(rank.clamp(1, n.max(1)) - 1).copied()
}

impl Times {
    /// The figures of `answered` times, with `unanswered` calls besides.
    pub fn of(answered: &[f64], unanswered: usize) -> Times {
        let n = answered.len();
        Times {
            count: n,
            unanswered,
            mean_s: (n > 0).then(|| round3(answered.iter().sum::<f64>() / n as f64)),
            p95_s: nearest_rank(answered, 95.0).map(round3),
            max_s: answered.iter().copied().reduce(f64::max).map(round3),
        }
    }

    fn text(&self) -> String {
        let s = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.1} s"));
        format!(
            "mean {}, 95th percentile {}, max {} ({} answered, {} not)",
            s(self.mean_s),
            s(self.p95_s),
            s(self.max_s),
            self.count,
            self.unanswered
        )
    }
}

impl TrafficReport {
    /// The figures of `trips`; the handling capacity's mean is over `span_s` seconds.
    pub fn of(trips: Vec<TripReport>, span_s: f64) -> TrafficReport {
        let since = |from: f64, to: Option<f64>| to.map(|t| t - from);
        let hall: Vec<f64> = trips
            .iter()
            .filter_map(|t| since(t.hall_pressed_s, t.hall_answered_s))
            .collect();
        let cabin: Vec<f64> = trips
            .iter()
            .filter_map(|t| since(t.cabin_pressed_s?, t.delivered_s))
            .collect();
        let journey: Vec<f64> = trips
            .iter()
            .filter_map(|t| since(t.hall_pressed_s, t.delivered_s))
            .collect();
        let boarded = trips.iter().filter(|t| t.cabin_pressed_s.is_some()).count();
        let mut delivered: Vec<f64> = trips.iter().filter_map(|t| t.delivered_s).collect();
        delivered.sort_by(f64::total_cmp);
        let peak = delivered
            .iter()
            .enumerate()
            .map(|(i, &end)| i + 1 - delivered.partition_point(|&d| d <= end - 300.0))
            .max()
            .unwrap_or(0);
        TrafficReport {
            passengers: trips.len(),
            boarded,
            delivered: delivered.len(),
            waiting: CallKinds {
                hall: Times::of(&hall, trips.len() - hall.len()),
                cabin: Times::of(&cabin, boarded - cabin.len()),
            },
            journey: Times::of(&journey, trips.len() - journey.len()),
            handling_capacity: HandlingCapacity {
                mean_per_5min: if span_s > 0.0 {
                    round3(delivered.len() as f64 * 300.0 / span_s)
                } else {
                    0.0
                },
                peak_per_5min: peak,
                span_s: round3(span_s),
            },
            trips,
        }
    }

    /// The summary's lines.
    pub fn summary(&self) -> String {
        let mut s = String::new();
        let h = &self.handling_capacity;
        let _ = writeln!(
            s,
            "  traffic            {} passengers, {} boarded, {} delivered; handling capacity {:.1} per 5 min (mean over {:.0} s), peak {} in 5 min",
            self.passengers, self.boarded, self.delivered, h.mean_per_5min, h.span_s, h.peak_per_5min
        );
        let _ = writeln!(s, "  hall call waits    {}", self.waiting.hall.text());
        let _ = writeln!(s, "  cabin call waits   {}", self.waiting.cabin.text());
        let _ = writeln!(s, "  journeys           {}", self.journey.text());
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_nearest_rank_percentile_is_a_value_of_the_data() {
        // Twenty values 1..=20 shuffled: 95 % of 20 is 19, the 19th smallest is 19.
        let v: Vec<f64> = [
            7, 3, 20, 1, 14, 9, 18, 2, 11, 5, 16, 4, 13, 8, 19, 6, 12, 10, 17, 15,
        ]
        .iter()
        .map(|&x| f64::from(x))
        .collect();
        assert_eq!(nearest_rank(&v, 95.0), Some(19.0));
        assert_eq!(nearest_rank(&v, 50.0), Some(10.0));
        assert_eq!(nearest_rank(&v, 100.0), Some(20.0));
        // Five values: ⌈0.95 × 5⌉ = 5, the largest; ⌈0.5 × 5⌉ = 3.
        let v = [4.0, 1.5, 9.0, 2.0, 3.0];
        assert_eq!(nearest_rank(&v, 95.0), Some(9.0));
        assert_eq!(nearest_rank(&v, 50.0), Some(3.0));
        assert_eq!(nearest_rank(&v, 1.0), Some(1.5));
        assert_eq!(nearest_rank(&[], 95.0), None);
    }

    fn trip(hall: f64, answered: Option<f64>, cabin: Option<f64>, at: Option<f64>) -> TripReport {
        TripReport {
            origin: 1,
            destination: 2,
            hall_pressed_s: hall,
            hall_answered_s: answered,
            cabin_pressed_s: cabin,
            delivered_s: at,
        }
    }

    #[test]
    fn the_figures_by_hand() {
        let r = TrafficReport::of(
            vec![
                trip(10.0, Some(20.0), Some(21.0), Some(31.0)),
                trip(15.0, Some(20.0), Some(21.0), Some(41.0)),
                trip(100.0, Some(130.0), Some(131.0), None),
                trip(400.0, None, None, None),
            ],
            600.0,
        );
        assert_eq!((r.passengers, r.boarded, r.delivered), (4, 3, 2));
        // Hall waits 10, 5, 30: mean 15, ⌈0.95 × 3⌉ = 3rd = 30.
        assert_eq!(r.waiting.hall, Times::of(&[10.0, 5.0, 30.0], 1));
        assert_eq!(r.waiting.hall.mean_s, Some(15.0));
        assert_eq!(r.waiting.hall.p95_s, Some(30.0));
        // Cabin waits 10 and 20, one aboard not yet delivered.
        assert_eq!(r.waiting.cabin.mean_s, Some(15.0));
        assert_eq!(r.waiting.cabin.unanswered, 1);
        // Journeys 21 and 26.
        assert_eq!(r.journey.max_s, Some(26.0));
        assert_eq!(r.journey.unanswered, 2);
        // Two delivered in 600 s: 1 per 5 min; both within one window.
        assert_eq!(r.handling_capacity.mean_per_5min, 1.0);
        assert_eq!(r.handling_capacity.peak_per_5min, 2);
    }
}
