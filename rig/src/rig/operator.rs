//! The operator's and the scenario's actions in the words of the run's log, and the
//! operator's overtravel rescue.

use crate::scenario::{needs_rescue, Action, Fault};
use lift_model::{Lift, SensorFault};
use safety::lift::K1Cause;

/// How long an operator holds the reset or acknowledge button.
pub(super) const OPERATOR_PULSE: asi_phy::SimDuration = asi_phy::SimDuration::from_millis(100);

/// A scenario action as the log tells it.
impl std::fmt::Display for Action {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&describe(self))
    }
}

fn describe(a: &Action) -> String {
    match a {
        Action::Press { button, hold } => format!("{button} pressed for {hold}"),
        Action::Load(l) => format!("load becomes {}", l.name()),
        Action::Door { closed } => format!("door {}", if *closed { "closed" } else { "opened" }),
        Action::Crank { mm } => format!("hand crank {mm:+.1} mm"),
        Action::Reset => "operator presses the safety reset".into(),
        Action::Rescue => "operator's overtravel rescue".into(),
        Action::Ack => "operator acknowledges the safety group error".into(),
        Action::Attend => "an attendant answers safety stops from now on".into(),
        Action::Fault(f) => match f {
            Fault::SlaveOffline { slave } => format!("fault: slave {slave} taken off the bus"),
            Fault::SlaveOnline { slave } => format!("fault cleared: slave {slave} back on the bus"),
            Fault::PowerFail { duration } => format!("fault: AS-i power fails for {duration}"),
            Fault::SafeLinkDrop { duration } => {
                format!("fault: the cabin STOP safe link is silent for {duration}")
            }
            Fault::Vane { sensor, fault } => match fault {
                SensorFault::None => format!("fault cleared: the {sensor} vane sensor works again"),
                SensorFault::StuckOn => format!("fault: the {sensor} vane sensor is stuck on"),
                SensorFault::StuckOff => format!("fault: the {sensor} vane sensor is stuck off"),
            },
            Fault::ConverterRunaway { up } => format!(
                "fault: the converter runs away {}, against its commands",
                if *up { "up" } else { "down" }
            ),
            Fault::ConverterRepaired => {
                "fault cleared: the converter follows its commands again".into()
            }
            Fault::EncoderFailed => "fault: the safe drive's encoder cannot be read".into(),
            Fault::EncoderRepaired => "fault cleared: the safe drive's encoder reads again".into(),
            Fault::LineNoise { rate, duration } => {
                format!("fault: a burst of line noise, pulse error rate {rate}, for {duration}")
            }
        },
    }
}

pub(super) use crate::report::Rescue;

/// The operator's overtravel rescue for a cabin that stands where initialisation cannot find
/// floor 1 by itself (on or beyond an overtravel sensor, below floor 1's vane): a crank to the
/// nearer end floor's level, only with K1 open.
pub(super) fn rescue(lift: &Lift, floors: u8) -> Rescue {
    let x = lift.position_mm();
    if !needs_rescue(floors, x) {
        return Rescue::NotNeeded;
    }
    let end_floor = if x < 0.0 { 1 } else { floors };
    let Some(to) = lift.config().floor_level_mm(end_floor) else {
        return Rescue::NotNeeded;
    };
    if lift.k1_closed() {
        return Rescue::K1Closed;
    }
    Rescue::Crank(to - x)
}

/// How long K1 stays open for a cause the attendant answers before a round begins.
pub(super) const ATTENDANT_NOTICE: asi_phy::SimDuration = asi_phy::SimDuration::from_secs(2);
/// From a round's rescue to its acknowledge: a cabin that halted on an overtravel sensor's trip
/// point (60 mm beyond the end floor, docs/lift-plant.md) is cranked back at 10 mm/s in 6 s; one
/// that stopped further out is not yet off the sensor, and the next round's rescue goes on.
pub(super) const ATTENDANT_ACK_AFTER: asi_phy::SimDuration = asi_phy::SimDuration::from_secs(6);
/// From a round's acknowledge to its safety reset.
pub(super) const ATTENDANT_RESET_AFTER: asi_phy::SimDuration = asi_phy::SimDuration::from_secs(1);

/// The lift attendant of [`Action::Attend`]: watches K1 and, once it has been open for
/// [`ATTENDANT_NOTICE`] for a cause an operator answers, begins a round (the rig does the
/// rescue now, the acknowledge and the reset later). The next round comes no earlier than
/// [`ATTENDANT_NOTICE`] after the last one's reset.
#[derive(Clone, Debug, Default)]
pub(super) struct Attendant {
    on: bool,
    /// Since when K1 has been open for a cause the attendant answers.
    open_since: Option<asi_phy::SimTime>,
    /// No round before this.
    next_round: asi_phy::SimTime,
}

impl Attendant {
    /// From `t` on, the attendant watches.
    /// Whether an attendant is at work (a scenario's `attend` has come).
    pub(super) fn started(&self) -> bool {
        self.on
    }

    pub(super) fn start(&mut self, t: asi_phy::SimTime) {
        if !self.on {
            self.on = true;
            self.open_since = None;
            self.next_round = t;
        }
    }

    /// After a safety scan at `t` whose K1 is open for `cause` (`None`: closed): `true` when
    /// a round begins now.
    #[cfg(test)]
    pub(super) fn watch_cause(&mut self, t: asi_phy::SimTime, cause: Option<&K1Cause>) -> bool {
        self.watch(t, cause.is_some_and(answers))
    }

    /// After a safety scan at `t`: `answered` = K1 is open for a cause a round answers (see
    /// [`answers`]; with the safe drive also its trip, acknowledged by the reset): `true` when
    /// a round begins now.
    pub(super) fn watch(&mut self, t: asi_phy::SimTime, answered: bool) -> bool {
        if !self.on {
            return false;
        }
        if !answered {
            self.open_since = None;
            return false;
        }
        let since = *self.open_since.get_or_insert(t);
        if t < since + ATTENDANT_NOTICE || t < self.next_round {
            return false;
        }
        self.next_round = t + ATTENDANT_ACK_AFTER + ATTENDANT_RESET_AFTER + ATTENDANT_NOTICE;
        true
    }
}

/// Whether an operator's round answers K1 open for `cause`: an overtravel (rescue and reset),
/// a group error (acknowledge), a monitor waiting for its reset. Not a STOP pressed, a STOP
/// waiting for the controller's restart, an overloaded cabin or a stopped logic: no round
/// helps those.
pub(super) fn answers(cause: &K1Cause) -> bool {
    matches!(
        cause,
        K1Cause::Overtravel { .. } | K1Cause::GroupError(_) | K1Cause::OvertravelResetPending
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use asi_phy::SimTime;

    fn at(ms: u64) -> SimTime {
        SimTime::from_millis(ms)
    }

    const TRIP: K1Cause = K1Cause::OvertravelResetPending;

    #[test]
    fn an_attendant_answers_a_trip_after_the_notice_and_again_while_k1_stays_open() {
        let mut a = Attendant::default();
        assert!(
            !a.watch_cause(at(0), Some(&TRIP)),
            "not on before it is told to attend"
        );
        a.start(at(1_000));
        assert!(!a.watch_cause(at(1_000), Some(&TRIP)));
        assert!(!a.watch_cause(at(2_999), Some(&TRIP)));
        assert!(a.watch_cause(at(3_000), Some(&TRIP)), "2 s of K1 open");
        // The round: ack at 9 s, reset at 10 s; the next one no earlier than 12 s.
        assert!(!a.watch_cause(at(11_999), Some(&TRIP)));
        assert!(a.watch_cause(at(12_000), Some(&TRIP)));
    }

    #[test]
    fn a_closed_k1_or_a_cause_no_round_helps_restarts_the_notice() {
        let mut a = Attendant::default();
        a.start(at(0));
        assert!(!a.watch_cause(at(0), Some(&TRIP)));
        assert!(!a.watch_cause(at(1_500), None));
        assert!(!a.watch_cause(at(2_500), Some(&TRIP)));
        assert!(!a.watch_cause(at(4_000), Some(&K1Cause::StopPressed)));
        assert!(!a.watch_cause(at(4_100), Some(&K1Cause::Overloaded)));
        assert!(!a.watch_cause(at(5_000), Some(&TRIP)));
        assert!(!a.watch_cause(at(6_999), Some(&TRIP)));
        assert!(a.watch_cause(at(7_000), Some(&TRIP)));
    }
}
