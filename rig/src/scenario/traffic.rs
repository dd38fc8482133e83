//! Traffic templates: passengers generated from a seed instead of hand-written presses.
//!
//! The patterns are the lift planners' (the book, "Traffic templates"; "Lift Passenger Traffic
//! Patterns: Applications, Current Knowledge and Measurement", Peters, Mehta and Haddon;
//! Barney and Al-Sharif, "Elevator Traffic Handbook", balanced interfloor traffic):
//!
//! - **up-peak**: every passenger enters at floor 1, the main entrance, and goes up to a floor
//!   drawn uniformly from the others (the texts' pure up-peak);
//! - **down-peak**: every passenger leaves from a floor drawn uniformly from 2..=N to floor 1;
//! - **interfloor**: origin and destination uniform over all floors, origin ≠ destination.
//!
//! A mix (a morning with some interfloor traffic) is several templates at once. Arrivals are a
//! Poisson process: the gaps between passengers are exponential with mean 60 s / `per_minute`,
//! drawn from a ChaCha8 stream seeded with the template's seed (as the fault campaign draws its
//! cases), so that the same template gives the same passengers on every machine.

use asi_phy::{SimDuration, SimTime};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The most passengers per minute a template may bring: one a second is far beyond what a
/// single cabin carries, and bounds the passengers of a long run.
pub const MAX_PER_MINUTE: f64 = 60.0;

/// The spatial pattern of a traffic template.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pattern {
    /// From floor 1 up to a uniform other floor.
    UpPeak,
    /// From a uniform floor above 1 down to floor 1.
    DownPeak,
    /// Uniform origin and destination, origin ≠ destination.
    Interfloor,
}

impl Pattern {
    /// Its name in a scenario file.
    pub fn name(self) -> &'static str {
        match self {
            Pattern::UpPeak => "up-peak",
            Pattern::DownPeak => "down-peak",
            Pattern::Interfloor => "interfloor",
        }
    }

    /// The pattern named `s` in a scenario file.
    pub fn from_name(s: &str) -> Option<Pattern> {
        [Pattern::UpPeak, Pattern::DownPeak, Pattern::Interfloor]
            .into_iter()
            .find(|p| p.name() == s)
    }

    /// An origin and a destination on a lift of `floors` floors (≥ 2).
    fn trip(self, rng: &mut ChaCha8Rng, floors: u8) -> (u8, u8) {
        match self {
            Pattern::UpPeak => (1, rng.random_range(2..=floors)),
            Pattern::DownPeak => (rng.random_range(2..=floors), 1),
            Pattern::Interfloor => {
                let origin = rng.random_range(1..=floors);
                // Uniform over the other floors: draw among floors − 1 and skip the origin.
                let d = rng.random_range(1..floors);
                (origin, if d >= origin { d + 1 } else { d })
            }
        }
    }
}

/// A traffic template of a scenario (`[[traffic]]`).
#[derive(Clone, Debug, PartialEq)]
pub struct Traffic {
    /// Where passengers come from and go to.
    pub pattern: Pattern,
    /// Mean arrivals per minute, in (0, [`MAX_PER_MINUTE`]].
    pub per_minute: f64,
    /// The seed of its arrivals and floors; `None`: drawn from the scenario's ([`Traffic::seed`]),
    /// so that `run --seed` varies the traffic too.
    pub seed: Option<u64>,
    /// When its first passenger may come, from the start of the run.
    pub start: SimDuration,
    /// How long passengers come; `None`: until the end of the run.
    pub duration: Option<SimDuration>,
    /// The line of the `[[traffic]]` in the file (0 for built-in scenarios).
    pub line: usize,
}

/// One passenger of a template: when they come to the hall, where from and where to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Trip {
    /// When they arrive at the origin and press the hall button.
    pub at: SimTime,
    /// The origin floor.
    pub origin: u8,
    /// The destination floor.
    pub destination: u8,
}

impl Trip {
    /// `true` when the trip goes up.
    pub fn up(&self) -> bool {
        self.destination > self.origin
    }
}

impl Traffic {
    /// The seed of the `n`-th template (0-based) of a scenario with seed `scenario`: its own,
    /// else the scenario's moved by `n`, so that two templates without a seed of their own do
    /// not bring their passengers at the same moments.
    pub fn seed(&self, scenario: u64, n: usize) -> u64 {
        self.seed.unwrap_or_else(|| scenario.wrapping_add(n as u64))
    }

    /// The template's passengers on a lift of `floors` floors, in time order, before `end`
    /// (the run's end; the template's own end if earlier), drawn from `seed`
    /// ([`Traffic::seed`]). Times are whole nanoseconds.
    pub fn trips(&self, seed: u64, floors: u8, end: SimTime) -> Vec<Trip> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let start = SimTime::ZERO + self.start;
        let end = match self.duration {
            Some(d) => end.min(start + d),
            None => end,
        };
        let mean_s = 60.0 / self.per_minute;
        let mut trips = Vec::new();
        let mut t = start.as_secs_f64();
        loop {
            // Inverse transform of a uniform draw in [0, 1): 1 − u lies in (0, 1], so the
            // logarithm is finite.
            let u: f64 = rng.random();
            t += -(1.0 - u).ln() * mean_s;
            let at = SimTime::ZERO + SimDuration::from_nanos((t * 1e9).round() as u64);
            if at >= end || floors < 2 {
                return trips;
            }
            let (origin, destination) = self.pattern.trip(&mut rng, floors);
            trips.push(Trip {
                at,
                origin,
                destination,
            });
        }
    }
}

/// Every passenger of `templates` of a scenario with seed `seed` on a lift of `floors` floors
/// before `end`, in time order (stable: at the same time, the earlier template's first).
pub fn trips(templates: &[Traffic], seed: u64, floors: u8, end: SimTime) -> Vec<Trip> {
    let mut all: Vec<Trip> = templates
        .iter()
        .enumerate()
        .flat_map(|(n, t)| t.trips(t.seed(seed, n), floors, end))
        .collect();
    all.sort_by_key(|t| t.at);
    all
}

#[cfg(test)]
mod tests {
    use super::*;

    fn template(pattern: Pattern, per_minute: f64, seed: u64) -> Traffic {
        Traffic {
            pattern,
            per_minute,
            seed: Some(seed),
            start: SimDuration::ZERO,
            duration: None,
            line: 0,
        }
    }

    /// The passengers of `t` (its own seed) before `end`.
    fn of(t: &Traffic, floors: u8, end: SimTime) -> Vec<Trip> {
        t.trips(t.seed(0, 0), floors, end)
    }

    fn hours(h: u64) -> SimTime {
        SimTime::ZERO + SimDuration::from_secs(3600 * h)
    }

    #[test]
    fn the_same_seed_gives_the_same_passengers() {
        let t = template(Pattern::Interfloor, 2.0, 7);
        let a = of(&t, 4, hours(1));
        assert_eq!(a, of(&t, 4, hours(1)));
        assert!(!a.is_empty());
        // Without seeds of their own, two templates of a scenario draw different passengers.
        let mut own = t.clone();
        own.seed = None;
        assert_ne!(
            own.trips(own.seed(7, 0), 4, hours(1)),
            own.trips(own.seed(7, 1), 4, hours(1))
        );
        assert_eq!(own.trips(own.seed(7, 0), 4, hours(1)), a);
        let other = of(&template(Pattern::Interfloor, 2.0, 8), 4, hours(1));
        assert_ne!(a, other, "another seed, other passengers");
    }

    #[test]
    fn arrivals_come_at_the_rate_asked() {
        // 100 hours at 2 a minute: 12,000 expected. A Poisson count's standard deviation is
        // √12000 ≈ 110, so 3 % (about 3.3 σ) holds for any seed; the gaps' mean likewise.
        let t = template(Pattern::Interfloor, 2.0, 11);
        let trips = of(&t, 4, hours(100));
        let n = trips.len() as f64;
        assert!((n - 12_000.0).abs() < 360.0, "{n} arrivals in 100 h");
        let mean_gap = trips.last().expect("arrivals").at.as_secs_f64() / n;
        assert!((mean_gap - 30.0).abs() < 0.9, "mean gap {mean_gap} s");
        // Exponential gaps: about e^-1 ≈ 36.8 % of them are longer than the mean.
        let mut prev = 0.0;
        let long = trips
            .iter()
            .filter(|tr| {
                let t = tr.at.as_secs_f64();
                let long = t - prev > 30.0;
                prev = t;
                long
            })
            .count() as f64;
        assert!(
            (long / n - (-1f64).exp()).abs() < 0.02,
            "{long} gaps above the mean"
        );
    }

    #[test]
    fn the_start_and_the_duration_bound_the_arrivals() {
        let mut t = template(Pattern::UpPeak, 6.0, 3);
        t.start = SimDuration::from_secs(60);
        t.duration = Some(SimDuration::from_secs(120));
        let trips = of(&t, 4, hours(1));
        assert!(!trips.is_empty());
        assert!(trips.iter().all(|tr| {
            let s = tr.at.as_secs_f64();
            (60.0..180.0).contains(&s)
        }));
        assert!(of(&t, 4, SimTime::ZERO + SimDuration::from_secs(100))
            .iter()
            .all(|tr| tr.at.as_secs_f64() < 100.0));
    }

    /// Counts of each (origin, destination) over `trips`, floors 1..=4.
    fn od(trips: &[Trip]) -> [[usize; 5]; 5] {
        let mut c = [[0; 5]; 5];
        for t in trips {
            c[t.origin as usize][t.destination as usize] += 1;
        }
        c
    }

    #[test]
    fn up_peak_goes_from_floor_1_to_every_other_floor_alike() {
        let trips = of(&template(Pattern::UpPeak, 10.0, 5), 4, hours(10));
        let c = od(&trips);
        let n = trips.len() as f64;
        assert!(trips.iter().all(|t| t.origin == 1 && t.destination > 1));
        for (d, &k) in c[1].iter().enumerate().skip(2) {
            let share = k as f64 / n;
            assert!((share - 1.0 / 3.0).abs() < 0.02, "floor {d}: {share}");
        }
    }

    #[test]
    fn down_peak_goes_to_floor_1_from_every_other_floor_alike() {
        let trips = of(&template(Pattern::DownPeak, 10.0, 5), 4, hours(10));
        let c = od(&trips);
        let n = trips.len() as f64;
        assert!(trips.iter().all(|t| t.destination == 1 && t.origin > 1));
        for (o, row) in c.iter().enumerate().skip(2) {
            let share = row[1] as f64 / n;
            assert!((share - 1.0 / 3.0).abs() < 0.02, "floor {o}: {share}");
        }
    }

    #[test]
    fn interfloor_is_uniform_over_pairs_of_different_floors() {
        let trips = of(&template(Pattern::Interfloor, 10.0, 5), 4, hours(20));
        let c = od(&trips);
        let n = trips.len() as f64;
        for (o, row) in c.iter().enumerate().skip(1) {
            assert_eq!(row[o], 0, "floor {o} to itself");
            for (d, &k) in row.iter().enumerate().skip(1).filter(|(d, _)| *d != o) {
                let share = k as f64 / n;
                assert!((share - 1.0 / 12.0).abs() < 0.01, "{o}→{d}: {share}");
            }
        }
    }

    #[test]
    fn templates_merge_in_time_order() {
        let a = template(Pattern::UpPeak, 2.0, 1);
        let b = template(Pattern::DownPeak, 2.0, 2);
        let all = trips(&[a.clone(), b.clone()], 0, 4, hours(1));
        assert_eq!(
            all.len(),
            of(&a, 4, hours(1)).len() + of(&b, 4, hours(1)).len()
        );
        assert!(all.windows(2).all(|w| w[0].at <= w[1].at));
    }
}
