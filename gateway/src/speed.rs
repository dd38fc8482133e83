//! How fast a live run's simulated time goes against the wall clock: the command line's
//! `--speed` and the live view's speed control, checked by the same bounds.

/// How fast simulated time runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Speed {
    /// Simulated seconds per wall second.
    Factor(f64),
    /// As fast as the machine can (builtin), or paced by the client's requests (external).
    Max,
}

/// The slowest speed factor: a simulated millisecond per wall second.
pub const MIN_SPEED: f64 = 0.001;
/// The fastest speed factor.
pub const MAX_SPEED: f64 = 1000.0;

/// A speed factor out of bounds ([`Speed::factor`]).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error(
    "speed factor {0:?}: expected {MIN_SPEED} to {MAX_SPEED} simulated seconds per wall second"
)]
pub struct SpeedError(pub f64);

impl Speed {
    /// The factor `x` if it is a number in [`MIN_SPEED`]..=[`MAX_SPEED`]. Outside it the
    /// pacing's wall times do not fit a `Duration`, or mean nothing.
    pub fn factor(x: f64) -> Result<Speed, SpeedError> {
        if x.is_finite() && (MIN_SPEED..=MAX_SPEED).contains(&x) {
            Ok(Speed::Factor(x))
        } else {
            Err(SpeedError(x))
        }
    }

    /// `self`, checked as [`Speed::factor`] checks a factor.
    pub fn checked(self) -> Result<Speed, SpeedError> {
        match self {
            Speed::Factor(x) => Speed::factor(x),
            Speed::Max => Ok(Speed::Max),
        }
    }

    /// What an outside controller should know of this speed, if anything: above 1 it runs
    /// on its own wall clock while the lift runs that many times faster, and its reactions
    /// come that many times later in simulated time (the Python example at speed 2 leaves
    /// calls unserved, the cabin stopped between floors). `asi-lift serve` prints it as a
    /// warning, the live view shows it when its page sets such a speed.
    pub fn outside_controller_warning(self) -> Option<String> {
        match self {
            Speed::Factor(x) if x > 1.0 => Some(format!(
                "speed {x} runs the lift {x} times faster than the outside controller's clock: a controller written for real time may react too late (stop past a floor, miss a call); speed 1 keeps real time, max paces the simulation by its requests (lockstep)"
            )),
            _ => None,
        }
    }
}

impl std::fmt::Display for Speed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Speed::Factor(x) => write!(f, "{x}"),
            Speed::Max => f.write_str("max"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_factors_outside_the_bounds_are_refused() {
        for x in [0.0, -1.0, 1e-30, 1e-4, 1000.5, f64::NAN, f64::INFINITY] {
            let err = Speed::factor(x).expect_err("refused");
            assert_eq!(err.0.to_bits(), x.to_bits());
            assert!(err.to_string().starts_with("speed factor"), "{err}");
        }
        assert_eq!(Speed::factor(MIN_SPEED), Ok(Speed::Factor(MIN_SPEED)));
        assert_eq!(Speed::factor(MAX_SPEED), Ok(Speed::Factor(MAX_SPEED)));
        assert_eq!(
            Speed::Factor(1e-30).checked().map(|_| ()),
            Speed::factor(1e-30).map(|_| ())
        );
    }

    #[test]
    fn an_outside_controller_is_warned_above_speed_1_only() {
        assert!(Speed::Factor(1.0).outside_controller_warning().is_none());
        assert!(Speed::Factor(0.5).outside_controller_warning().is_none());
        assert!(Speed::Max.outside_controller_warning().is_none());
        let w = Speed::Factor(2.0)
            .outside_controller_warning()
            .expect("a warning");
        assert!(w.starts_with("speed 2 runs the lift 2 times faster"), "{w}");
    }
}
