//! Bounds on the run's log for sources an outside party drives (a live run's clients): of
//! each bounded source the first lines and the last lines are kept, and a marker line says
//! how many between them were left out, so that a client that sends the same command
//! millions of times costs the run a bounded amount of memory.

use crate::report::{Actor, LogEvent, LogLine, RigNote};
use std::collections::VecDeque;

/// One bounded source.
#[derive(Clone, Debug)]
struct Bound {
    who: Actor,
    first: usize,
    last: usize,
    /// Lines of the source so far.
    seen: u64,
    /// The last lines after the first `first`, at most `last`.
    tail: VecDeque<LogLine>,
    /// Lines dropped from the tail, and the time of the first.
    left_out: u64,
    left_out_from: f64,
}

/// The bounded sources of a rig's log.
#[derive(Clone, Debug, Default)]
pub(super) struct LogBounds {
    bounds: Vec<Bound>,
}

impl LogBounds {
    /// Keeps the first `first` and the last `last` lines of `who`.
    pub(super) fn set(&mut self, who: Actor, first: usize, last: usize) {
        self.bounds.retain(|b| b.who != who);
        self.bounds.push(Bound {
            who,
            first,
            last,
            seen: 0,
            tail: VecDeque::new(),
            left_out: 0,
            left_out_from: 0.0,
        });
    }

    /// Takes `line` if its source is bounded and past its first lines; gives it back
    /// otherwise, for the log itself.
    pub(super) fn take(&mut self, line: LogLine) -> Option<LogLine> {
        let Some(b) = self.bounds.iter_mut().find(|b| b.who == line.who) else {
            return Some(line);
        };
        b.seen += 1;
        if b.seen <= b.first as u64 {
            return Some(line);
        }
        b.tail.push_back(line);
        if b.tail.len() > b.last {
            if let Some(gone) = b.tail.pop_front() {
                if b.left_out == 0 {
                    b.left_out_from = gone.at_s;
                }
                b.left_out += 1;
            }
        }
        None
    }

    /// The last `n` lines of each source's kept tail, oldest first per source (for a view of
    /// the latest lines).
    pub(super) fn tails(&self, n: usize) -> impl Iterator<Item = &LogLine> {
        self.bounds
            .iter()
            .flat_map(move |b| b.tail.iter().skip(b.tail.len().saturating_sub(n)))
    }

    /// The lines held back, each source's marker of what it left out before its tail.
    pub(super) fn drain(&mut self) -> Vec<LogLine> {
        let mut out = Vec::new();
        for b in &mut self.bounds {
            if b.left_out > 0 {
                out.push(LogLine::new(
                    b.left_out_from,
                    b.who,
                    LogEvent::Note(RigNote::LeftOut {
                        who: b.who,
                        left_out: b.left_out,
                        seen: b.seen,
                        first: b.first,
                        last: b.last,
                    }),
                ));
                b.left_out = 0;
            }
            out.extend(b.tail.drain(..));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(i: u32, who: Actor) -> LogLine {
        LogLine::new(f64::from(i), who, LogEvent::Text(format!("line {i}")))
    }

    #[test]
    fn a_bounded_source_keeps_its_first_and_last_lines_and_says_how_many_it_left_out() {
        let mut b = LogBounds::default();
        b.set(Actor::Client, 3, 2);
        let mut log = Vec::new();
        for i in 0..10 {
            log.extend(b.take(line(i, Actor::Client)));
            log.extend(b.take(line(i, Actor::Rig)));
        }
        assert_eq!(log.len(), 3 + 10);
        assert_eq!(b.tails(5).count(), 2);
        assert_eq!(b.tails(1).count(), 1);
        let rest = b.drain();
        let texts: Vec<String> = rest.iter().map(LogLine::text).collect();
        assert_eq!(
            texts,
            [
                "… 5 lines left out (of 10 `client` lines the first 3 and the last 2 are kept)",
                "line 8",
                "line 9"
            ]
        );
        assert_eq!(rest[0].at_s, 3.0);
        assert!(b.drain().is_empty());
    }
}
