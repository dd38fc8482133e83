//! The standard function blocks (IEC 61131-3, 3rd edition, §6.6.3.5): the bistables SR and
//! RS, the edge detectors R_TRIG and F_TRIG, the counters CTU, CTD and CTUD (on INT), and the
//! timers TP, TON and TOF on the PLC's clock, as the standard's timing diagrams draw them.
//!
//! Each block is its state and one call (`call`) with its inputs, which returns nothing and
//! leaves its outputs in its fields, as an instance's outputs are read after its call in
//! Structured Text. A timer measures time by the `now` of its calls (the scan's time on the
//! simulated clock, nanoseconds), so a run is the same whatever the wall clock does.

/// A duration or a time on the PLC's clock, nanoseconds (TIME).
pub type Time = i64;

/// SR: set-dominant bistable. `Q1 := S1 OR (NOT R AND Q1)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sr {
    /// The output.
    pub q1: bool,
}

impl Sr {
    /// One call with `s1` and `r`.
    pub fn call(&mut self, s1: bool, r: bool) {
        self.q1 = s1 || (!r && self.q1);
    }
}

/// RS: reset-dominant bistable. `Q1 := NOT R1 AND (S OR Q1)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Rs {
    /// The output.
    pub q1: bool,
}

impl Rs {
    /// One call with `s` and `r1`.
    pub fn call(&mut self, s: bool, r1: bool) {
        self.q1 = !r1 && (s || self.q1);
    }
}

/// R_TRIG: `Q` is TRUE for the one call in which `CLK` went from FALSE to TRUE.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RTrig {
    /// The output.
    pub q: bool,
    m: bool,
}

impl RTrig {
    /// One call with `clk`.
    pub fn call(&mut self, clk: bool) {
        self.q = clk && !self.m;
        self.m = clk;
    }
}

/// F_TRIG: `Q` is TRUE for the one call in which `CLK` went from TRUE to FALSE.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FTrig {
    /// The output.
    pub q: bool,
    m: bool,
}

impl FTrig {
    /// One call with `clk`. The memory of `CLK` starts FALSE, so a first call with `CLK`
    /// FALSE gives no edge (`Q := NOT CLK AND M; M := CLK`, as annex F of the 3rd edition
    /// gives the block).
    pub fn call(&mut self, clk: bool) {
        self.q = !clk && self.m;
        self.m = clk;
    }
}

/// CTU: counts rising edges of `CU` up to the type's greatest value; `R` resets.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Ctu {
    /// `CV >= PV`.
    pub q: bool,
    /// The count.
    pub cv: i16,
    edge: RTrig,
}

impl Ctu {
    /// One call with `cu`, `r` and `pv`.
    pub fn call(&mut self, cu: bool, r: bool, pv: i16) {
        self.edge.call(cu);
        if r {
            self.cv = 0;
        } else if self.edge.q && self.cv < i16::MAX {
            self.cv += 1;
        }
        self.q = self.cv >= pv;
    }
}

/// CTD: counts rising edges of `CD` down to the type's least value; `LD` loads `PV`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Ctd {
    /// `CV <= 0`.
    pub q: bool,
    /// The count.
    pub cv: i16,
    edge: RTrig,
}

impl Ctd {
    /// One call with `cd`, `ld` and `pv`.
    pub fn call(&mut self, cd: bool, ld: bool, pv: i16) {
        self.edge.call(cd);
        if ld {
            self.cv = pv;
        } else if self.edge.q && self.cv > i16::MIN {
            self.cv -= 1;
        }
        self.q = self.cv <= 0;
    }
}

/// CTUD: up on rising edges of `CU`, down on those of `CD` (neither when both rise), `R`
/// resets, `LD` loads `PV` (`R` first).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Ctud {
    /// `CV >= PV`.
    pub qu: bool,
    /// `CV <= 0`.
    pub qd: bool,
    /// The count.
    pub cv: i16,
    up: RTrig,
    down: RTrig,
}

impl Ctud {
    /// One call with `cu`, `cd`, `r`, `ld` and `pv`.
    pub fn call(&mut self, cu: bool, cd: bool, r: bool, ld: bool, pv: i16) {
        self.up.call(cu);
        self.down.call(cd);
        if r {
            self.cv = 0;
        } else if ld {
            self.cv = pv;
        } else if !(self.up.q && self.down.q) {
            if self.up.q && self.cv < i16::MAX {
                self.cv += 1;
            } else if self.down.q && self.cv > i16::MIN {
                self.cv -= 1;
            }
        }
        self.qu = self.cv >= pv;
        self.qd = self.cv <= 0;
    }
}

/// TP: a pulse of `PT` on a rising edge of `IN`; an edge within the pulse is ignored. `ET`
/// counts the pulse's time up to `PT`, stays there while `IN` is TRUE after the pulse, and
/// returns to zero when `IN` is FALSE after it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tp {
    /// The pulse.
    pub q: bool,
    /// The elapsed time.
    pub et: Time,
    start: Option<Time>,
    last_in: bool,
}

impl Tp {
    /// One call at `now` with `input` and `pt`.
    pub fn call(&mut self, now: Time, input: bool, pt: Time) {
        let rising = input && !self.last_in;
        self.last_in = input;
        if self.start.is_none() && rising {
            self.start = Some(now);
        }
        match self.start {
            Some(s) => {
                let elapsed = now.saturating_sub(s);
                if elapsed >= pt {
                    self.q = false;
                    self.et = pt.max(0);
                    if !input {
                        self.start = None;
                        self.et = 0;
                    }
                } else {
                    self.q = true;
                    self.et = elapsed;
                }
            }
            None => {
                self.q = false;
                self.et = 0;
            }
        }
    }
}

/// TON: on delay. `Q` goes TRUE when `IN` has been TRUE for `PT`; `ET` counts up to `PT`
/// while `IN` is TRUE; both return at once when `IN` is FALSE.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Ton {
    /// The delayed input.
    pub q: bool,
    /// The elapsed time.
    pub et: Time,
    start: Option<Time>,
}

impl Ton {
    /// One call at `now` with `input` and `pt`.
    pub fn call(&mut self, now: Time, input: bool, pt: Time) {
        if !input {
            self.start = None;
            self.q = false;
            self.et = 0;
            return;
        }
        let start = *self.start.get_or_insert(now);
        let elapsed = now.saturating_sub(start);
        self.q = elapsed >= pt;
        self.et = elapsed.min(pt.max(0));
    }
}

/// TOF: off delay. `Q` is TRUE while `IN` is, and stays TRUE for `PT` after `IN` falls;
/// `ET` counts that time up to `PT`, and returns to zero when `IN` is TRUE again.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tof {
    /// The extended input.
    pub q: bool,
    /// The elapsed time.
    pub et: Time,
    fall: Option<Time>,
}

impl Tof {
    /// One call at `now` with `input` and `pt`.
    pub fn call(&mut self, now: Time, input: bool, pt: Time) {
        if input {
            self.fall = None;
            self.q = true;
            self.et = 0;
            return;
        }
        if !self.q && self.fall.is_none() {
            // FALSE since the start, or run out: nothing to extend.
            return;
        }
        let fall = *self.fall.get_or_insert(now);
        let elapsed = now.saturating_sub(fall);
        self.q = elapsed < pt;
        self.et = elapsed.min(pt.max(0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Time = 1_000_000;

    /// A block called every 10 ms (a PLC's scan) with `input` as a function of the time, ms;
    /// the samples `(t, Q, ET)` at each call.
    fn run(
        mut call: impl FnMut(Time, bool) -> (bool, Time),
        input: impl Fn(i64) -> bool,
        until_ms: i64,
    ) -> Vec<(i64, bool, i64)> {
        (0..=until_ms / 10)
            .map(|k| {
                let t = k * 10;
                let (q, et) = call(t * MS, input(t));
                (t, q, et / MS)
            })
            .collect()
    }

    fn at(samples: &[(i64, bool, i64)], t: i64) -> (bool, i64) {
        samples
            .iter()
            .find(|s| s.0 == t)
            .map(|s| (s.1, s.2))
            .expect("a sample")
    }

    /// TON's diagram: IN high 100–500 ms (longer than PT = 200 ms), then 600–700 ms (shorter):
    /// Q from 300 ms to 500 ms only; ET ramps and holds at PT, back to 0 with IN.
    #[test]
    fn ton_as_the_standard_draws_it() {
        let mut ton = Ton::default();
        let s = run(
            |now, i| {
                ton.call(now, i, 200 * MS);
                (ton.q, ton.et)
            },
            |t| (100..500).contains(&t) || (600..700).contains(&t),
            900,
        );
        assert_eq!(at(&s, 90), (false, 0));
        assert_eq!(at(&s, 100), (false, 0));
        assert_eq!(at(&s, 250), (false, 150));
        assert_eq!(at(&s, 300), (true, 200));
        assert_eq!(at(&s, 490), (true, 200));
        assert_eq!(at(&s, 500), (false, 0));
        assert_eq!(at(&s, 690), (false, 90));
        assert_eq!(at(&s, 700), (false, 0));
    }

    /// TOF's diagram: IN high 100–300 ms, then 400–420 ms; PT = 150 ms: Q from 100 to 450
    /// (the short gap 300–400 is bridged), then to 570; ET counts after each fall.
    #[test]
    fn tof_as_the_standard_draws_it() {
        let mut tof = Tof::default();
        let s = run(
            |now, i| {
                tof.call(now, i, 150 * MS);
                (tof.q, tof.et)
            },
            |t| (100..300).contains(&t) || (400..420).contains(&t),
            700,
        );
        assert_eq!(at(&s, 0), (false, 0));
        assert_eq!(at(&s, 100), (true, 0));
        assert_eq!(at(&s, 300), (true, 0));
        assert_eq!(at(&s, 390), (true, 90));
        assert_eq!(at(&s, 400), (true, 0));
        assert_eq!(at(&s, 420), (true, 0));
        assert_eq!(at(&s, 560), (true, 140));
        assert_eq!(at(&s, 570), (false, 150));
        assert_eq!(at(&s, 700), (false, 150));
    }

    /// TP's diagram, PT = 150 ms: IN held 100–400 ms gives a pulse 100–250 ms, ET holding
    /// at PT until IN falls; a short IN at 500–520 ms gives a full pulse to 650 ms; an edge
    /// within that pulse (at 560 ms) is ignored.
    #[test]
    fn tp_as_the_standard_draws_it() {
        let mut tp = Tp::default();
        let s = run(
            |now, i| {
                tp.call(now, i, 150 * MS);
                (tp.q, tp.et)
            },
            |t| (100..400).contains(&t) || (500..520).contains(&t) || (560..570).contains(&t),
            800,
        );
        assert_eq!(at(&s, 100), (true, 0));
        assert_eq!(at(&s, 240), (true, 140));
        assert_eq!(at(&s, 250), (false, 150));
        assert_eq!(at(&s, 390), (false, 150));
        assert_eq!(at(&s, 400), (false, 0));
        assert_eq!(at(&s, 500), (true, 0));
        assert_eq!(at(&s, 530), (true, 30));
        assert_eq!(at(&s, 560), (true, 60));
        assert_eq!(at(&s, 640), (true, 140));
        assert_eq!(at(&s, 650), (false, 0));
    }

    #[test]
    fn edges_and_bistables() {
        let mut r = RTrig::default();
        let mut f = FTrig::default();
        let clk = [false, true, true, false, false, true];
        let rising: Vec<bool> = clk
            .iter()
            .map(|&c| {
                r.call(c);
                r.q
            })
            .collect();
        let falling: Vec<bool> = clk
            .iter()
            .map(|&c| {
                f.call(c);
                f.q
            })
            .collect();
        assert_eq!(rising, [false, true, false, false, false, true]);
        assert_eq!(falling, [false, false, false, true, false, false]);
        let (mut sr, mut rs) = (Sr::default(), Rs::default());
        sr.call(true, true);
        rs.call(true, true);
        assert!(sr.q1 && !rs.q1, "set dominates in SR, reset in RS");
        sr.call(false, false);
        assert!(sr.q1, "SR holds");
        sr.call(false, true);
        assert!(!sr.q1);
    }

    #[test]
    fn counters_count_edges_and_saturate() {
        let mut ctu = Ctu::default();
        for cu in [true, true, false, true, false, true] {
            ctu.call(cu, false, 3);
        }
        assert_eq!((ctu.cv, ctu.q), (3, true));
        ctu.call(false, true, 3);
        assert_eq!((ctu.cv, ctu.q), (0, false));
        ctu.cv = i16::MAX;
        ctu.call(true, false, 3);
        ctu.call(false, false, 3);
        ctu.call(true, false, 3);
        assert_eq!(ctu.cv, i16::MAX, "CTU stops at the type's greatest value");

        let mut ctd = Ctd::default();
        ctd.call(false, true, 2);
        assert_eq!((ctd.cv, ctd.q), (2, false));
        for cd in [true, false, true, false, true] {
            ctd.call(cd, false, 2);
        }
        assert_eq!((ctd.cv, ctd.q), (-1, true));

        let mut ctud = Ctud::default();
        ctud.call(true, false, false, false, 2);
        ctud.call(false, false, false, false, 2);
        ctud.call(true, true, false, false, 2);
        assert_eq!(ctud.cv, 1, "both edges at once: no count");
        ctud.call(false, false, false, false, 2);
        ctud.call(true, false, false, false, 2);
        assert_eq!((ctud.cv, ctud.qu, ctud.qd), (2, true, false));
        ctud.call(false, false, true, true, 2);
        assert_eq!(ctud.cv, 0, "R before LD");
    }
}
