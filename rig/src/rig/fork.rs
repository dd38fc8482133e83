//! What the fault explorer ([`crate::explore`]) asks of a rig it has forked: a run that it
//! can stop at any PLC scan, and whether a person may still act on the lift.

use super::*;
use std::ops::ControlFlow;

impl Rig {
    /// Runs on the fast path (as [`Rig::run`] does, with the same moments) to the end of the
    /// run, or until `check`, asked after every PLC scan, breaks; returns the moment reached.
    /// The rig stays as it is there: it may be looked at, run on or [`Rig::finish`]ed.
    pub fn run_while(&mut self, check: &mut dyn FnMut(&Rig) -> ControlFlow<()>) -> SimTime {
        let mut scans = self.agenda.next_plc;
        while let Some(t) = self.advance_to_step(self.agenda.end) {
            if self.agenda.next_plc != scans {
                scans = self.agenda.next_plc;
                if check(self).is_break() {
                    break;
                }
            }
            if t == self.agenda.end {
                break;
            }
        }
        self.agenda.now
    }

    /// The scenario the rig runs, with the events scheduled on it since.
    pub fn scenario(&self) -> &Scenario {
        &self.sc
    }

    /// Whether a person may still act on the lift before `until`: an operator's reset,
    /// acknowledge, rescue or hand crank among the scenario's events still to come, one of the
    /// operator's buttons pressed or about to be (the power-on reset), or an attendant at work.
    /// Without any of these, nothing but the controller and the safety logic moves the lift.
    pub fn person_may_act_before(&self, until: SimTime) -> bool {
        if self.people.attendant.started() || self.safety.operator_reset || self.safety.err_ack {
            return true;
        }
        let timers = self.agenda.timers.iter().any(|(at, timer)| {
            *at < until
                && matches!(
                    timer,
                    Timer::OperatorReset(true) | Timer::ErrAck(true) | Timer::Attendant(_)
                )
        });
        let events = self.sc.events[self.agenda.next_event..]
            .iter()
            .take_while(|e| e.at < until)
            .any(|e| {
                matches!(
                    e.action,
                    Action::Reset
                        | Action::Ack
                        | Action::Rescue
                        | Action::Attend
                        | Action::Crank { .. }
                )
            });
        timers || events
    }
}
