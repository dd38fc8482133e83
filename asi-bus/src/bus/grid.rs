//! A stretch of an application's grid points run in one call ([`Bus::advance_grid`]): the
//! bus stops at each as the application's own steps would stop it, and returns only where the
//! application has something to do there.

use super::*;

/// What [`Bus::advance_grid`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridRun {
    /// How many grid points, from the first, the bus passed: at each it was as
    /// [`Bus::advance_before`] and then [`Bus::advance_to`] of that point leave it, no watched
    /// slave took a new output in them, and the application's look found what it looks for.
    pub passed: u32,
    /// Where it stopped before the end, `None` if it passed every grid point before it.
    pub stop: Option<GridStop>,
}

/// Where [`Bus::advance_grid`] stopped before the end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridStop {
    /// A watched slave took a new output nibble at this time, before the next grid point:
    /// what [`Bus::advance_before`] of that point returns.
    Output(SimTime),
    /// At this grid point the bus is as [`Bus::advance_to`] of it leaves it, and either a
    /// watched slave took a new output nibble in that call (the application's to hand on
    /// now, as after `advance_to`) or the application's look did not find what it looks for.
    Point(SimTime),
}

impl Bus {
    /// Runs the bus through the grid points `first`, `first + period`, … before `until`, as an
    /// application that calls [`Bus::advance_before`] and then [`Bus::advance_to`] of each
    /// point would, and looks at the bus (`same`) after each: it goes on to the next point
    /// while no watched slave takes a new output and `same` is `true`, and stops where one
    /// does or it is not ([`GridRun`]).
    ///
    /// For an application with a periodic task that reads the bus (the rig's 1 ms safety
    /// scan): where the task would find at each point what it found last and do nothing
    /// new, the bus runs the whole stretch in one call, and the task's steps are taken
    /// after it, without moving the bus again.
    pub fn advance_grid(
        &mut self,
        first: SimTime,
        period: SimDuration,
        until: SimTime,
        same: impl FnMut(&Bus) -> bool,
    ) -> GridRun {
        let run = self.run_grid(first, period, until, same);
        self.settle();
        run
    }

    /// [`Bus::advance_grid`], the receivers left unsettled ([`Bus::settle`]): a run of clean
    /// quick transactions goes on across the grid points, where nothing but the bus hears a
    /// frame (`same` looks at what the master and the monitors hold, not at a receiver).
    #[inline]
    fn run_grid(
        &mut self,
        first: SimTime,
        period: SimDuration,
        until: SimTime,
        mut same: impl FnMut(&Bus) -> bool,
    ) -> GridRun {
        let mut passed = 0;
        let mut g = first;
        while g < until {
            if let Some(at) = self.run_before(g) {
                return GridRun {
                    passed,
                    stop: Some(GridStop::Output(at)),
                };
            }
            if self.run_to(g) || !same(self) {
                return GridRun {
                    passed,
                    stop: Some(GridStop::Point(g)),
                };
            }
            passed += 1;
            match g.checked_add(period) {
                Some(next) => g = next,
                None => break,
            }
        }
        GridRun { passed, stop: None }
    }
}
