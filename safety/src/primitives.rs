//! IEC 61131-3 standard function blocks and the TwinSAFE 0→1→0 pulse detector.
//!
//! docs/safety-logic.md §8.1 item 2: `R_TRIG`, `F_TRIG` and `TON` with IEC semantics, and the
//! "0→1→0" pulse that Restart and ERR_ACK use, acting on the falling edge (§10 point 2).
//! Time is passed in as [`SimTime`]; nothing here reads a clock.

use asi_phy::{SimDuration, SimTime};

/// Rising-edge detector `R_TRIG` (IEC 61131-3 table 35): `Q := CLK AND NOT M; M := CLK`.
///
/// The memory starts FALSE, so a CLK that is TRUE on the very first call is reported as an
/// edge — exactly as the standard's reference body does. The PLCopen blocks rely on that: a
/// Reset held TRUE from power-up is then seen as a *static* Reset one call later.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RTrig {
    m: bool,
}

impl RTrig {
    /// A detector that has seen CLK = FALSE.
    pub const fn new() -> Self {
        RTrig { m: false }
    }

    /// One call: `true` when CLK is TRUE now and was FALSE on the previous call.
    pub fn call(&mut self, clk: bool) -> bool {
        let q = clk && !self.m;
        self.m = clk;
        q
    }
}

/// Falling-edge detector `F_TRIG` (IEC 61131-3 table 35): `Q := NOT CLK AND NOT M; M := NOT CLK`.
///
/// The reference body with `M` starting FALSE reports a falling edge on the first call when CLK
/// is FALSE (a well-known quirk; some runtimes differ). This type keeps the standard's body
/// and that quirk; the safety logic never relies on it — Restart and ERR_ACK use
/// [`PulseDetector`], which cannot fire without a rising edge first.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FTrig {
    m: bool,
}

impl FTrig {
    /// A detector in the standard's initial state (`M = FALSE`).
    pub const fn new() -> Self {
        FTrig { m: false }
    }

    /// One call: `true` when CLK is FALSE now and was TRUE on the previous call (and on the
    /// first call if CLK is FALSE, see the type's doc).
    pub fn call(&mut self, clk: bool) -> bool {
        let q = !clk && !self.m;
        self.m = !clk;
        q
    }
}

/// On-delay timer `TON` (IEC 61131-3 table 36).
///
/// While IN is TRUE, the elapsed time ET counts from the call at which IN became TRUE, and
/// Q is TRUE once ET ≥ PT. IN = FALSE resets ET and Q at once. **Decision** (docs/safety-logic.md
/// §8.1): with PT = 0, Q is TRUE on the same call at which IN first is TRUE.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Ton {
    started: Option<SimTime>,
    q: bool,
    et: SimDuration,
}

impl Ton {
    /// A timer with IN = FALSE.
    pub const fn new() -> Self {
        Ton {
            started: None,
            q: false,
            et: SimDuration::ZERO,
        }
    }

    /// One call at `now` with input `input` and preset `pt`; returns Q.
    pub fn call(&mut self, now: SimTime, input: bool, pt: SimDuration) -> bool {
        if !input {
            self.reset();
            return false;
        }
        let start = *self.started.get_or_insert(now);
        let elapsed = now.saturating_duration_since(start);
        self.et = if elapsed > pt { pt } else { elapsed };
        self.q = elapsed >= pt;
        self.q
    }

    /// Q as of the last call.
    pub fn q(&self) -> bool {
        self.q
    }

    /// ET as of the last call (never more than PT).
    pub fn et(&self) -> SimDuration {
        self.et
    }

    /// Force IN = FALSE: stop and clear the timer.
    pub fn reset(&mut self) {
        *self = Ton::new();
    }
}

/// The TwinSAFE "0→1→0" pulse detector for Restart and ERR_ACK (§3.1, §4.4 of the KL6904 manual).
///
/// The rising edge *arms* it and the falling edge *fires* it, so a button held down does
/// nothing until it is let go (docs/safety-logic.md §6.1: the RESET state "waits for the negative
/// edge"; §10 point 2: act on the falling edge).
///
/// **Decisions** (docs/safety-logic.md §8.1 item 3, left open by the sources):
/// - the pulse counts only if the caller's condition holds at the rising edge *and* stays true
///   until the falling edge; a pulse begun while the condition was false is ignored and a fresh
///   pulse is needed;
/// - the first call only samples the input: a signal that is already TRUE when the logic starts
///   is not a rising edge, so a Restart or ERR_ACK stuck at TRUE since power-up can never
///   release anything.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PulseDetector {
    prev: Option<bool>,
    armed: bool,
}

impl PulseDetector {
    /// A detector that has not sampled its input yet.
    pub const fn new() -> Self {
        PulseDetector {
            prev: None,
            armed: false,
        }
    }

    /// One scan: `input` is the signal, `accept` the caller's condition for the pulse to count.
    /// Returns `true` on the scan of an accepted falling edge.
    pub fn call(&mut self, input: bool, accept: bool) -> bool {
        let prev = self.prev.replace(input).unwrap_or(input);
        if !accept {
            self.armed = false;
            return false;
        }
        if input && !prev {
            self.armed = true;
            false
        } else if !input && prev && self.armed {
            self.armed = false;
            true
        } else {
            false
        }
    }

    /// `true` between an accepted rising edge and the falling edge.
    pub fn is_armed(&self) -> bool {
        self.armed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(n: u64) -> SimTime {
        SimTime::from_millis(n)
    }

    #[test]
    fn r_trig_reports_each_rising_edge_once_including_the_first_call() {
        let mut t = RTrig::new();
        let seen: Vec<bool> = [true, true, false, true, false]
            .into_iter()
            .map(|c| t.call(c))
            .collect();
        assert_eq!(seen, [true, false, false, true, false]);
    }

    #[test]
    fn f_trig_follows_the_standard_body_with_its_first_call_quirk() {
        let mut t = FTrig::new();
        let seen: Vec<bool> = [false, true, false, false, true, false]
            .into_iter()
            .map(|c| t.call(c))
            .collect();
        assert_eq!(seen, [true, false, true, false, false, true]);
    }

    #[test]
    fn ton_counts_from_the_call_that_saw_in_rise() {
        let pt = SimDuration::from_millis(30);
        let mut t = Ton::new();
        assert!(!t.call(ms(0), false, pt));
        assert!(!t.call(ms(10), true, pt));
        assert!(!t.call(ms(39), true, pt));
        assert_eq!(t.et(), SimDuration::from_millis(29));
        assert!(t.call(ms(40), true, pt));
        assert!(t.call(ms(90), true, pt));
        assert_eq!(t.et(), pt, "ET stops at PT");
        assert!(!t.call(ms(91), false, pt));
        assert_eq!(t.et(), SimDuration::ZERO);
        assert!(!t.call(ms(92), true, pt), "a new IN restarts the count");
    }

    #[test]
    fn ton_with_zero_preset_is_q_on_the_first_true_call() {
        let mut t = Ton::new();
        assert!(t.call(ms(5), true, SimDuration::ZERO));
    }

    #[test]
    fn pulse_fires_on_the_falling_edge_only() {
        let mut p = PulseDetector::new();
        let seen: Vec<bool> = [false, true, true, false, false]
            .into_iter()
            .map(|i| p.call(i, true))
            .collect();
        assert_eq!(seen, [false, false, false, true, false]);
    }

    #[test]
    fn pulse_started_while_not_accepted_is_ignored() {
        let mut p = PulseDetector::new();
        p.call(false, false);
        p.call(true, false); // rises while the condition is false
        assert!(!p.call(false, true), "falling edge of an unaccepted pulse");
        p.call(true, true);
        assert!(p.is_armed());
        p.call(true, false); // condition lost while held
        assert!(!p.call(false, true));
    }

    #[test]
    fn pulse_stuck_true_since_start_never_fires() {
        let mut p = PulseDetector::new();
        assert!(!p.call(true, true));
        assert!(!p.call(true, true));
        assert!(!p.call(false, true), "no rising edge was ever seen");
        p.call(true, true);
        assert!(p.call(false, true));
    }
}
