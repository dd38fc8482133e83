//! What the application watches of the bus ([`Watch`]): where [`Bus::advance_before`] ends
//! early ([`Stop`]) — a watched slave's new output, or a change of what a periodic task
//! reads ([`Look`]) at one of the task's times.

use super::*;

/// What the application watches of the bus: the events at which [`Bus::advance_before`]
/// returns early, so that the application can hand them on at their moment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Watch {
    /// The addresses whose slaves drive something outside the bus (a plant): when one of
    /// them takes a Data_Exchange whose output nibble differs from its last one (or a call
    /// that writes to it, after which its next nibble counts as new), `advance_before`
    /// ends at that moment ([`Stop::Output`]).
    pub outputs: u32,
    /// Up to this time (inclusive), a watched slave's new nibble ends `advance_before`
    /// only if the drive count ([`Bus::drive_count`]) moved since the bus last looked: one
    /// that changed nothing a slave drives passes. For an application to which such a
    /// moment would do nothing (the rig while the plant has nothing for the slaves and its
    /// invariant watch nothing to check). `None`: every new nibble ends it.
    pub drives_only_through: Option<SimTime>,
    /// A periodic task's reads ([`LookWatch`]).
    pub look: Option<LookWatch>,
}

/// What a periodic task reads of the bus at its scan: the master's LAS in normal operation,
/// a safety monitor's releases, whether that monitor has dropped a release since the
/// application last took its drops ([`Bus::take_monitor_drops`]), and the drive count
/// ([`Bus::drive_count`]). The rig's 1 ms safety scan reads these.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct Look {
    /// The master's LAS (bit `a` for address `a`) while it is in normal operation; `None`
    /// outside it.
    pub las: Option<u32>,
    /// The addresses the monitor releases (bit `a` for address `a`; none without it).
    pub released: u32,
    /// `true` if the monitor has dropped a release since its drops were last taken.
    pub drops: bool,
    /// [`Bus::drive_count`].
    pub drives: Option<u64>,
}

/// A watch on what a periodic task reads ([`Look`]) at its times `first`, `first + period`,
/// …: [`Bus::advance_before`] ends at the first of them at which the look is not `seen`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LookWatch {
    /// The monitor whose releases the task reads.
    pub monitor: MonitorId,
    /// The task's next time.
    pub first: SimTime,
    /// The task's period.
    pub period: SimDuration,
    /// What the task read last.
    pub seen: Look,
}

/// Why [`Bus::advance_before`] ended before its end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// A watched slave ([`Watch::outputs`]) took a new output nibble at this time; the
    /// bus's time is this time.
    Output(SimTime),
    /// At this time of the look watch ([`Watch::look`]) the look is not the one seen, or
    /// a watched slave took a new output nibble exactly then (one that did not pass): the bus is as
    /// [`Bus::advance_to`] of this time leaves it.
    Look(SimTime),
}

impl Bus {
    /// What a periodic task that reads monitor `monitor` finds on the bus now ([`Look`]).
    #[inline]
    pub fn look(&self, monitor: MonitorId) -> Look {
        let m = &self.master;
        let las = (m.phase() == asi_master::Phase::NormalOperation).then(|| m.las().bits() as u32);
        let (released, drops) = self
            .monitors
            .get(monitor.0)
            .map_or((0, false), SafetyMonitor::releases);
        Look {
            las,
            released,
            drops,
            drives: self.drive_count(),
        }
    }

    /// Sets what the application watches ([`Watch`]).
    ///
    /// With a look watch, [`Bus::advance_before`] looks at the bus at each of the task's
    /// times before its end, as an application that stepped to each (`advance_before` and
    /// then [`Bus::advance_to`] of it) would, and ends at the first at which the look changed
    /// ([`Stop::Look`]). For a task that would find at each of its times what it found last
    /// and do nothing new (the rig's safety scan while the logic is at rest,
    /// `LiftSafety::poll_at`): the bus runs through them in one call, and the task's own
    /// deadline says how far.
    pub fn watch(&mut self, watch: Watch) {
        self.watch = watch;
    }

    /// What the application watches.
    pub fn watching(&self) -> Watch {
        self.watch
    }

    /// [`Bus::advance_before`] with the look watch `w`, the receivers left unsettled
    /// ([`Bus::settle`]): a run of clean quick transactions goes on across the task's
    /// times, where nothing but the bus hears a frame (the look is of what the master and
    /// the monitors hold, not of a receiver).
    #[inline]
    pub(super) fn run_watching(&mut self, w: LookWatch, until: SimTime) -> Option<Stop> {
        let mut g = w.first;
        while g < until {
            if let Some(at) = self.run_before(g) {
                return Some(Stop::Output(at));
            }
            if self.run_to(g) || self.look(w.monitor) != w.seen {
                return Some(Stop::Look(g));
            }
            match g.checked_add(w.period) {
                Some(next) => g = next,
                None => break,
            }
        }
        self.run_before(until).map(Stop::Output)
    }
}
