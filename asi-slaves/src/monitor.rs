//! AS-i Safety at Work: code tables and the passive safety monitor (docs/asi.md §7; docs/lab-bus.md,
//! docs/safety.md).
//!
//! A free safe slave sends, cycle after cycle, the 8 values of its own code table; tripped it
//! sends 0000. The [`SafetyMonitor`] listens on the bus with its own receiver (so it judges only
//! telegrams that pass the seven checks), pairs each Data_Exchange to a monitored address with
//! its response, learns each slave's table and reports released / not released.
//!
//! **What the sources say** (asi-slaves/README.md, "Safety at Work under line noise"): the
//! monitor listens passively and evaluates the safe slave's Data_Exchange answers (Leuze RS4/AS-i
//! manual; Siemens 3RK3 manual); the slave holds its code for 224 µs + 16 µs after a
//! Data_Exchange "so that an immediate master repeat does not desynchronise the monitor" (ZMD
//! SAP5 datasheet); the monitor's response delay is below 40 ms (Euchner/Bihl+Wiedemann AS-i
//! Safety Monitor data sheet) and an input must be off for at least 41 ms to be seen reliably
//! (Euchner Safety Basic Monitor manual); wrongly transferred code sequences cannot be
//! suppressed (Siemens FAQ). The exact acceptance rule is not public.
//!
//! **Decisions**:
//! - Tables have 8 distinct values in 0001..1110 (no 0000, which means tripped, and no 1111,
//!   which the coding rules forbid).
//! - Teaching: the monitor learns a table from 16 consecutive codes whose second 8 repeat the
//!   first 8; it then releases.
//! - Only valid telegrams are judged. The monitor counts the code steps the slave has taken
//!   since the last code it judged, from the valid Data_Exchange requests it heard: a request
//!   more than [`MonitorConfig::hold`] after the previous one to that address is a step (the
//!   slave's own rule); a request within it is the master's repeat and gets the same code.
//! - A valid code is correct if it is one of the next `steps` codes of the table (the slave
//!   answered the steps whose responses the line corrupted; 8 or more steps: any code of the
//!   table). The same code again without a step is the repeat of a code already judged and is
//!   ignored. Anything else is a wrong code (the same code after a step is a frozen code).
//! - 0000 drops the release at once (the demand). A wrong or frozen code drops it at once
//!   (`bad_codes_to_trip` = 1: noise never produces one, so one is a fault). No valid code for
//!   `max_silence` (default 40 ms, the monitors' response delay) drops it too (missing code).
//! - After a drop the monitor releases again after 8 consecutive correct codes (one rotation);
//!   restart interlocks (manual restart) belong to the safety logic (docs/safety.md, MON).

use asi_phy::{Address, Expect, Frame, Listener, Received, SimDuration, SimTime, TelegramKind};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// A code table that breaks the coding rules.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("code table: {why}")]
pub struct CodeTableError {
    /// What is wrong.
    pub why: String,
}

/// A safe slave's 8-value code table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CodeTable([u8; 8]);

impl CodeTable {
    /// A table from its values; each must be in 1..=14 and all distinct.
    pub fn new(codes: [u8; 8]) -> Result<CodeTable, CodeTableError> {
        for (i, &c) in codes.iter().enumerate() {
            if c == 0 || c >= 15 {
                return Err(CodeTableError {
                    why: format!("value {i} is {c:04b}: must be 0001..1110"),
                });
            }
            if codes[..i].contains(&c) {
                return Err(CodeTableError {
                    why: format!("value {i} ({c:04b}) repeats an earlier value"),
                });
            }
        }
        Ok(CodeTable(codes))
    }

    /// The table a device with serial number `serial` has: 8 distinct values drawn with a
    /// ChaCha RNG seeded by the serial (the manufacturer's unique table, reproducibly).
    pub fn from_serial(serial: u64) -> CodeTable {
        let mut values: Vec<u8> = (1..=14).collect();
        values.shuffle(&mut ChaCha8Rng::seed_from_u64(serial));
        let mut t = [0u8; 8];
        t.copy_from_slice(&values[..8]);
        CodeTable(t)
    }

    /// The values in sending order.
    pub fn codes(&self) -> [u8; 8] {
        self.0
    }

    fn position(&self, code: u8) -> Option<usize> {
        self.0.iter().position(|&c| c == code)
    }
}

/// Why a monitored slave is not released.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NotReleased {
    /// Not taught yet (or teaching was disturbed).
    Teaching,
    /// The slave sends 0000: tripped.
    Tripped,
    /// A code that is not the next of the table.
    WrongCode {
        /// The code expected.
        expected: u8,
        /// The code received.
        got: u8,
    },
    /// The same code twice in a row.
    Frozen {
        /// The code.
        code: u8,
    },
    /// No valid code for too long.
    Missing,
    /// Released again only after a full correct rotation.
    Recovering,
}

/// The monitor's settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MonitorConfig {
    /// Consecutive bad codes (wrong or frozen) that drop the release (default 1: the first).
    pub bad_codes_to_trip: u8,
    /// The tolerance time: the longest time without a valid code before the release drops
    /// (default 40 ms, the response delay of the AS-i safety monitors).
    pub max_silence: SimDuration,
    /// How long after a Data_Exchange the slave keeps its code, so that a request within it is
    /// the master's repeat, not a new step (default [`crate::devices::CODE_HOLD`], SAP5).
    pub hold: SimDuration,
}

impl Default for MonitorConfig {
    fn default() -> Self {
        MonitorConfig {
            bad_codes_to_trip: 1,
            max_silence: SimDuration::from_millis(40),
            hold: crate::devices::CODE_HOLD,
        }
    }
}

/// The monitor dropped the release of a slave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MonitorDrop {
    /// When.
    pub at: SimTime,
    /// The slave.
    pub address: Address,
    /// Why: [`NotReleased::Tripped`] (0000), [`NotReleased::WrongCode`],
    /// [`NotReleased::Frozen`] or [`NotReleased::Missing`] (tolerance time exceeded).
    pub why: NotReleased,
}

#[derive(Clone, Debug, PartialEq)]
struct Channel {
    address: Address,
    table: Option<CodeTable>,
    learn: Vec<u8>,
    pos: Option<usize>,
    last_code: Option<u8>,
    last_at: Option<SimTime>,
    /// The last valid Data_Exchange request heard for this slave.
    last_request: Option<SimTime>,
    /// Code steps the slave has taken since the last judged code, as the requests tell.
    steps: u32,
    bad: u8,
    good_run: u8,
    released: bool,
    reason: NotReleased,
    bad_codes: u64,
    drops: Vec<MonitorDrop>,
}

impl Channel {
    fn new(address: Address) -> Channel {
        Channel {
            address,
            table: None,
            learn: Vec::with_capacity(16),
            pos: None,
            last_code: None,
            last_at: None,
            last_request: None,
            steps: 0,
            bad: 0,
            good_run: 0,
            released: false,
            reason: NotReleased::Teaching,
            bad_codes: 0,
            drops: Vec::new(),
        }
    }

    fn drop_release(&mut self, now: SimTime, why: NotReleased) {
        if self.released {
            self.drops.push(MonitorDrop {
                at: now,
                address: self.address,
                why,
            });
        }
        self.reason = why;
        self.released = false;
        self.good_run = 0;
    }

    /// A valid Data_Exchange request to this slave at `now`.
    fn request(&mut self, now: SimTime, cfg: &MonitorConfig) {
        let step = self
            .last_request
            .is_none_or(|t| now.saturating_duration_since(t) > cfg.hold);
        self.last_request = Some(now);
        if step {
            self.steps = self.steps.saturating_add(1);
        }
    }

    /// Judges a valid code `code` heard at `now` if it is the next in turn; `false` (and
    /// nothing changed) for any other code, which the whole rule must judge.
    ///
    /// Nearly every code a taught slave sends is the next of its table after the position the
    /// monitor holds: that code is judged here with one comparison. For such a code the
    /// rule ([`Channel::judge_code`]) comes to the same: unless it is the repeat of the code
    /// just judged (no step, the same code), 0000 aside (no table holds it, but the test
    /// costs nothing), it is one code ahead of the position (the values are distinct, so it
    /// is found there and nowhere else), and one ahead is correct however many steps were
    /// counted; so the position moves on by one and the code counts as correct. Held to the
    /// whole rule by the property test
    /// `the_next_code_in_turn_is_judged_as_the_whole_rule_judges_it`.
    #[inline]
    fn next_in_turn(&mut self, now: SimTime, code: u8) -> bool {
        let (Some(table), Some(p)) = (self.table, self.pos) else {
            return false;
        };
        let next = (p + 1) % 8;
        if code != table.0[next] || code == 0 || (self.steps == 0 && self.last_code == Some(code)) {
            return false;
        }
        self.steps = 0;
        self.last_code = Some(code);
        self.last_at = Some(now);
        self.pos = Some(next);
        self.correct();
        true
    }

    /// A correct code: the bad run ends, the good run grows, and 8 in a row release again.
    #[inline]
    fn correct(&mut self) {
        self.bad = 0;
        self.good_run = self.good_run.saturating_add(1);
        if !self.released && self.good_run >= 8 {
            self.released = true;
        }
        if !self.released && self.reason != NotReleased::Recovering {
            self.reason = NotReleased::Recovering;
        }
    }

    /// A valid code `code` heard at `now` for this slave, judged by the whole rule (see the
    /// module documentation): the repeat of a code already judged, teaching, 0000, a correct
    /// code some steps ahead, a frozen or a wrong code.
    #[inline(never)]
    fn judge_code(&mut self, now: SimTime, code: u8, cfg: &MonitorConfig) {
        let steps = core::mem::take(&mut self.steps);
        if steps == 0 && self.last_code == Some(code) {
            // The master's repeat of a transaction whose first answer this receiver took:
            // the code already judged, not a new one.
            self.last_at = Some(now);
            return;
        }
        let previous = self.last_code.replace(code);
        self.last_at = Some(now);
        let Some(table) = self.table else {
            if steps > 1 {
                // A code was missed: the sequence heard is not consecutive.
                self.learn.clear();
            }
            self.teach(code);
            return;
        };
        if code == 0 {
            self.pos = None;
            self.bad = 0;
            self.drop_release(now, NotReleased::Tripped);
            return;
        }
        let bad = match self.pos {
            None => match table.position(code) {
                Some(p) => {
                    self.pos = Some(p);
                    None
                }
                None => Some(NotReleased::WrongCode {
                    expected: table.0[0],
                    got: code,
                }),
            },
            Some(p) => {
                let expected = table.0[(p + 1) % 8];
                let ahead = table.position(code).map(|q| (q + 8 - p) % 8);
                match ahead {
                    Some(d) if d >= 1 && (d as u32 <= steps.max(1) || steps >= 8) => {
                        self.pos = Some((p + d) % 8);
                        None
                    }
                    Some(0) if steps >= 8 => None,
                    _ if previous == Some(code) => Some(NotReleased::Frozen { code }),
                    _ => {
                        if let Some(q) = table.position(code) {
                            self.pos = Some(q);
                        }
                        Some(NotReleased::WrongCode {
                            expected,
                            got: code,
                        })
                    }
                }
            }
        };
        match bad {
            None => self.correct(),
            Some(why) => {
                self.bad_codes += 1;
                self.bad = self.bad.saturating_add(1);
                self.good_run = 0;
                if self.bad >= cfg.bad_codes_to_trip.max(1) || !self.released {
                    self.drop_release(now, why);
                }
            }
        }
    }

    fn teach(&mut self, code: u8) {
        if code == 0 || code == 15 {
            self.learn.clear();
            return;
        }
        self.learn.push(code);
        if self.learn.len() > 16 {
            self.learn.remove(0);
        }
        if self.learn.len() == 16 && self.learn[..8] == self.learn[8..] {
            let mut t = [0u8; 8];
            t.copy_from_slice(&self.learn[..8]);
            if let Ok(table) = CodeTable::new(t) {
                self.table = Some(table);
                self.pos = Some(7);
                self.released = true;
                self.good_run = 8;
                self.learn.clear();
            }
        }
    }

    fn check_silence(&mut self, now: SimTime, cfg: &MonitorConfig) {
        if let Some(t) = self.last_at {
            if self.released && now.saturating_duration_since(t) > cfg.max_silence {
                self.pos = None;
                self.drop_release(now, NotReleased::Missing);
            }
        }
    }
}

/// A passive Safety-at-Work monitor on the bus (docs/asi.md §7).
#[derive(Clone, Debug, PartialEq)]
pub struct SafetyMonitor {
    cfg: MonitorConfig,
    listener: Listener,
    asked: Option<Address>,
    channels: Vec<Channel>,
    /// The monitored addresses, as a mask.
    monitored: u32,
    /// The index in `channels` of each address's channel, [`SafetyMonitor::NO_CHANNEL`] for an
    /// address not monitored: the channel of a Data_Exchange and of its answer found with one
    /// look, not by a search of the channels.
    slots: [u16; 32],
    /// No released channel can have been silent too long at or before this time (a lower
    /// bound of every released channel's last code + `max_silence`): [`SafetyMonitor::poll`]
    /// up to it has nothing to check. Polled at every transaction, that check was a loop
    /// over the channels each time.
    quiet_until: SimTime,
}

impl SafetyMonitor {
    /// A monitor of the safe slaves at `addresses`, with `cfg`, listening with the receiver
    /// settings of `timing`. It starts teaching.
    pub fn new(
        timing: &asi_phy::BusTiming,
        cfg: MonitorConfig,
        addresses: &[Address],
    ) -> SafetyMonitor {
        SafetyMonitor {
            cfg,
            listener: Listener::new(&timing.receiver(Expect::Both)),
            asked: None,
            channels: addresses.iter().map(|&a| Channel::new(a)).collect(),
            monitored: addresses.iter().fold(0, |m, a| m | 1 << a.get()),
            slots: core::array::from_fn(|n| {
                // The first channel of the address, as a search of the channels finds it.
                addresses
                    .iter()
                    .position(|a| usize::from(a.get()) == n)
                    .and_then(|i| u16::try_from(i).ok())
                    .unwrap_or(SafetyMonitor::NO_CHANNEL)
            }),
            quiet_until: SimTime::ZERO,
        }
    }

    /// `slots` of an address that has no channel (no monitor has as many channels).
    const NO_CHANNEL: u16 = u16::MAX;

    /// Gives the monitor `table` for `address` instead of teaching it.
    pub fn set_table(&mut self, address: Address, table: CodeTable) {
        if let Some(c) = self.channel_mut(address) {
            c.table = Some(table);
            c.pos = None;
            c.released = false;
            c.reason = NotReleased::Recovering;
        }
    }

    /// Forgets every learned table and starts teaching again.
    pub fn reteach(&mut self) {
        for c in &mut self.channels {
            *c = Channel::new(c.address);
        }
    }

    /// The channel of the slave at `a`, `None` if it is not monitored.
    #[inline]
    fn channel_mut(&mut self, a: Address) -> Option<&mut Channel> {
        let slot = self.slots.get(usize::from(a.get()))?;
        self.channels.get_mut(usize::from(*slot))
    }

    /// A frame heard on the line at `now`.
    ///
    /// Every frame goes through the monitor's receiver, which must keep its synchronisation;
    /// but only a valid request whose address field names a monitored slave, and the response
    /// to one, leave anything to note. Those are told from the others by the receiver's verdict
    /// and the address bits alone, before any decoding; the work on them is out of line
    /// ([`SafetyMonitor::heard_request`], [`SafetyMonitor::heard_response`]), so that the
    /// common frame costs the receiver and a test. Inlined into the bus's per-frame loop.
    #[inline]
    pub fn on_frame(&mut self, now: SimTime, frame: &Frame) {
        let r = self.listener.accept(frame);
        self.judge(now, &r);
    }

    /// `true` if the monitor's receiver is in the state of `other`: it would take every frame
    /// as `other` does ([`SafetyMonitor::on_frame_as`]).
    pub fn listens_as(&self, other: &Listener) -> bool {
        self.listener == *other
    }

    /// [`SafetyMonitor::on_frame`] of a frame that a receiver in the state of the monitor's own
    /// ([`SafetyMonitor::listens_as`]) took as `r`, ending in state `after`: the monitor takes
    /// that telegram and state instead of checking the frame again (on the bus the slaves'
    /// receiver and the monitor's hear the same frames). Debug builds, and so every test
    /// that runs a bus, check that the monitor's own receiver would have done the same.
    #[inline]
    pub fn on_frame_as(&mut self, now: SimTime, frame: &Frame, r: &Received, after: &Listener) {
        debug_assert!(
            {
                let mut own = self.listener.clone();
                own.accept(frame) == *r && own == *after
            },
            "the monitor's receiver is not in the state of the one whose telegram it takes"
        );
        self.listener.clone_from(after);
        self.judge(now, r);
    }

    /// [`SafetyMonitor::on_frame`] of telegram `r`, heard at `now` by a receiver in the state
    /// of the monitor's own, without bringing the monitor's receiver on: its caller knows the
    /// state the frames leave it in and sets it later ([`SafetyMonitor::listen_as`]), as the
    /// bus does at the end of a run of clean quick transactions. Held to `on_frame` by the
    /// bus's lockstep test against its pulse-exact path, which compares the monitors.
    #[inline]
    pub fn on_telegram(&mut self, now: SimTime, r: &Received) {
        self.judge(now, r);
    }

    /// Puts the monitor's receiver in the state of `other`.
    pub fn listen_as(&mut self, other: &Listener) {
        self.listener.clone_from(other);
    }

    /// What the monitor notes of telegram `r`, heard at `now`.
    #[inline]
    fn judge(&mut self, now: SimTime, r: &Received) {
        match r.kind {
            TelegramKind::Request => {
                // The address field of a request (A4..A0, bits 11..7): `Request::address` of
                // the request `r.request()` decodes, whenever it decodes one.
                let address = r.raw >> 7 & 0x1F;
                self.asked = None;
                if self.monitored >> address & 1 != 0 && r.is_valid() {
                    self.heard_request(now, r);
                }
            }
            TelegramKind::Response => {
                // Cleared only when set: most responses answer a slave the monitor does not
                // watch, and leave nothing to clear.
                if let Some(a) = self.asked {
                    self.asked = None;
                    self.heard_response(now, a, r);
                }
            }
        }
    }

    /// A request `r` to a monitored address (by its address bits): if it is a Data_Exchange,
    /// the slave it asks takes a step, and its answer is awaited.
    #[inline(never)]
    fn heard_request(&mut self, now: SimTime, r: &Received) {
        // A Data_Exchange told from its bits, without decoding the call
        // (`Request::as_data_exchange`, held to the call decoder for every request by asi-phy's
        // telegram tests).
        let Some((a, _)) = r.request().and_then(|q| q.as_data_exchange()) else {
            // `judge` cleared `asked` already.
            return;
        };
        self.asked = Some(a);
        let cfg = self.cfg;
        if let Some(c) = self.channel_mut(a) {
            c.request(now, &cfg);
        }
    }

    /// A telegram `r` taken for the response to the Data_Exchange that asked slave `a`.
    #[inline(never)]
    fn heard_response(&mut self, now: SimTime, a: Address, r: &Received) {
        let Some(resp) = r.response() else {
            return;
        };
        let code = resp.data().get();
        let Some(&slot) = self.slots.get(usize::from(a.get())) else {
            return;
        };
        let Some(c) = self.channels.get_mut(usize::from(slot)) else {
            return;
        };
        if c.next_in_turn(now, code) {
            // A channel released now (its last code now) may be the first to fall silent:
            // the bound comes down to it. A later code of a channel that was released
            // already only raises its own deadline, so the bound stays low enough.
            if c.released {
                self.quiet_until = self.quiet_until.min(now + self.cfg.max_silence);
            }
        } else {
            self.judge_in_full(now, usize::from(slot), code);
        }
    }

    /// [`SafetyMonitor::heard_response`] of a code that is not the next in turn: the whole
    /// rule, out of line, so that the code in turn is judged without saving registers.
    #[inline(never)]
    fn judge_in_full(&mut self, now: SimTime, slot: usize, code: u8) {
        let cfg = self.cfg;
        if let Some(c) = self.channels.get_mut(slot) {
            c.judge_code(now, code, &cfg);
            // As for the code in turn.
            if c.released {
                self.quiet_until = self.quiet_until.min(now + cfg.max_silence);
            }
        }
    }

    /// Advances the monitor's clock (missing-code timeouts). The bus polls at every
    /// transaction, and almost always before the earliest deadline: only that test is
    /// inlined.
    #[inline]
    pub fn poll(&mut self, now: SimTime) {
        if now > self.quiet_until {
            self.check_channels(now);
        }
    }

    /// [`SafetyMonitor::poll`] past the earliest deadline: every channel checked, and the next
    /// deadline found.
    #[inline(never)]
    fn check_channels(&mut self, now: SimTime) {
        let cfg = self.cfg;
        let mut quiet_until = SimTime::MAX;
        for c in &mut self.channels {
            c.check_silence(now, &cfg);
            if let (true, Some(t)) = (c.released, c.last_at) {
                quiet_until = quiet_until.min(t + cfg.max_silence);
            }
        }
        self.quiet_until = quiet_until;
    }

    /// `true` if the slave at `address` is monitored and released.
    pub fn released(&self, address: Address) -> bool {
        self.channels
            .iter()
            .any(|c| c.address == address && c.released)
    }

    /// `Ok(())` if released, else why not; `None` if `address` is not monitored.
    pub fn state(&self, address: Address) -> Option<Result<(), NotReleased>> {
        self.channels
            .iter()
            .find(|c| c.address == address)
            .map(|c| if c.released { Ok(()) } else { Err(c.reason) })
    }

    /// The learned table of `address`.
    pub fn table(&self, address: Address) -> Option<CodeTable> {
        self.channels
            .iter()
            .find(|c| c.address == address)
            .and_then(|c| c.table)
    }

    /// Bad codes seen at `address` (tolerated or not).
    pub fn bad_codes(&self, address: Address) -> u64 {
        self.channels
            .iter()
            .find(|c| c.address == address)
            .map_or(0, |c| c.bad_codes)
    }

    /// The releases dropped since the last call, in order (for reports).
    pub fn take_drops(&mut self) -> Vec<MonitorDrop> {
        // Asked at every safety scan, and almost always with nothing to give.
        if self.channels.iter().all(|c| c.drops.is_empty()) {
            return Vec::new();
        }
        let mut all: Vec<MonitorDrop> = self
            .channels
            .iter_mut()
            .flat_map(|c| c.drops.drain(..))
            .collect();
        all.sort_by_key(|d| d.at);
        all
    }

    /// The settings.
    pub fn config(&self) -> &MonitorConfig {
        &self.cfg
    }

    /// The monitored addresses.
    pub fn addresses(&self) -> impl Iterator<Item = Address> + '_ {
        self.channels.iter().map(|c| c.address)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use asi_phy::{Call, Request, Response};
    use proptest::strategy::Strategy as _;

    /// What the monitor does at a moment of the property test below.
    #[derive(Clone, Copy, Debug)]
    enum Step {
        /// A Data_Exchange to the slave, answered with the next code of its table.
        Good,
        /// Answered with a code off the table.
        Wrong,
        /// A request and no answer.
        Lost,
        /// Only a poll.
        Poll,
    }

    impl Channel {
        /// A valid code `code` heard at `now` for this slave, as the monitor judges it:
        /// [`Channel::next_in_turn`], else the whole rule ([`Channel::judge_code`]).
        fn code(&mut self, now: SimTime, code: u8, cfg: &MonitorConfig) {
            if !self.next_in_turn(now, code) {
                self.judge_code(now, code, cfg);
            }
        }
    }

    impl SafetyMonitor {
        /// [`SafetyMonitor::on_frame`] as it was: every request decoded, every response
        /// decoded before the monitor looked whether it had asked for one.
        fn on_frame_as_it_was(&mut self, now: SimTime, frame: &Frame) {
            let r = self.listener.accept(frame);
            match r.kind {
                TelegramKind::Request => {
                    // A request to a slave it does not monitor leaves nothing to note: no need to
                    // tell which call it is.
                    self.asked = match r.request() {
                        Some(q) if self.monitored >> q.address().get() & 1 == 0 => None,
                        Some(q) => match q.call() {
                            Call::DataExchange { address, .. } => Some(address),
                            _ => None,
                        },
                        None => None,
                    };
                    if let Some(a) = self.asked {
                        let cfg = self.cfg;
                        if let Some(c) = self.channel_mut(a) {
                            c.request(now, &cfg);
                        }
                    }
                }
                TelegramKind::Response => {
                    let (Some(a), Some(resp)) = (self.asked.take(), r.response()) else {
                        return;
                    };
                    let cfg = self.cfg;
                    if let Some(c) = self.channel_mut(a) {
                        c.code(now, resp.data().get(), &cfg);
                        // A channel released now (its last code now) may be the first to fall
                        // silent: the bound comes down to it. A later code of a channel that was
                        // released already only raises its own deadline, so the bound stays low
                        // enough.
                        if c.released {
                            self.quiet_until = self.quiet_until.min(now + cfg.max_silence);
                        }
                    }
                }
            }
        }

        /// [`SafetyMonitor::poll`] as it was: every channel checked at every poll.
        fn poll_every_channel(&mut self, now: SimTime) {
            let cfg = self.cfg;
            for c in &mut self.channels {
                c.check_silence(now, &cfg);
            }
        }
    }

    /// The frame of `bits` (`n` of them) sent at `start`, on a clean line.
    fn frame(start: u64, bits: u32, n: u32) -> Frame {
        Frame {
            start: at(start),
            end: at(start + u64::from(n) * 6_000),
            pulses: n,
            bit_count: n,
            raw: bits,
            line_failed: asi_phy::Checks::NONE,
        }
    }

    proptest::proptest! {
        /// Skipping the polls before the earliest deadline drops exactly what checking every
        /// channel at every poll drops, at the same times: codes, wrong codes, lost answers and
        /// silences of up to 100 ms (the tolerance is 40 ms) for two monitored slaves, polled
        /// mostly every few transactions as on the bus.
        #[test]
        fn a_poll_skipped_before_the_deadline_changes_nothing(
            steps in proptest::collection::vec(
                (0..2usize, proptest::prop_oneof![
                    6 => proptest::strategy::Just(Step::Good),
                    1 => proptest::strategy::Just(Step::Wrong),
                    1 => proptest::strategy::Just(Step::Lost),
                    2 => proptest::strategy::Just(Step::Poll),
                ], proptest::prop_oneof![8 => 154_000..3_000_000u64, 1 => 3_000_000..100_000_000u64]),
                1..400,
            ),
        ) {
            let addresses = [Address::new(11).expect("a"), Address::new(12).expect("a")];
            let timing = asi_phy::BusTiming::default();
            let cfg = MonitorConfig::default();
            let mut fast = SafetyMonitor::new(&timing, cfg, &addresses);
            let mut every = fast.clone();
            let tables = [CodeTable::from_serial(11).codes(), CodeTable::from_serial(12).codes()];
            let mut next = [0usize; 2];
            let mut now = 0u64;
            for (slave, step, gap) in steps {
                now += gap;
                let t = at(now);
                fast.poll(t);
                every.poll_every_channel(t);
                if matches!(step, Step::Poll) {
                    continue;
                }
                let q = Request::data_exchange(addresses[slave], asi_phy::Nibble::new(0).expect("n"))
                    .expect("a request");
                let req = frame(now, u32::from(q.bits()), Request::BITS);
                fast.on_frame(t, &req);
                every.on_frame(t, &req);
                let code = match step {
                    Step::Good => {
                        next[slave] = (next[slave] + 1) % 8;
                        tables[slave][next[slave]]
                    }
                    Step::Wrong => 15,
                    _ => continue,
                };
                let r = Response::new(asi_phy::Nibble::new(code).expect("n"));
                let start = now + 84_000 + 18_000;
                let resp = frame(start, u32::from(r.bits()), Response::BITS);
                fast.on_frame(at(start), &resp);
                every.on_frame(at(start), &resp);
            }
            let end = at(now + 200_000_000);
            fast.poll(end);
            every.poll_every_channel(end);
            proptest::prop_assert_eq!(fast.take_drops(), every.take_drops());
            for a in addresses {
                proptest::prop_assert_eq!(fast.state(a), every.state(a));
                proptest::prop_assert_eq!(fast.bad_codes(a), every.bad_codes(a));
            }
        }
    }

    /// A telegram of the property test below: a request (`true`) with the body (CB, address,
    /// information: 11 bits) and parity taken from `bits`, or a response with the data and
    /// parity taken from it; now and then a broken one (`flip` of a bit, a failed line check).
    fn telegram(request: bool, bits: u16, flip: u8, failed: u8) -> (u32, u32, asi_phy::Checks) {
        let (n, mut raw) = if request {
            let body = u32::from(bits & 0x7FF);
            (
                Request::BITS,
                (body << 2) | ((body.count_ones() & 1) << 1) | 1,
            )
        } else {
            let data = u32::from(bits & 0xF);
            (
                Response::BITS,
                (data << 2) | ((data.count_ones() & 1) << 1) | 1,
            )
        };
        if flip < 24 {
            raw ^= 1 << (flip % (n as u8 + 2));
        }
        let failed = if failed < 200 { 0 } else { failed };
        (raw, n, asi_phy::Checks::from_bits(failed))
    }

    proptest::proptest! {
        #![proptest_config(proptest::test_runner::Config::with_cases(2_000))]

        /// The monitor that looks only at what a monitored address needs does what the one
        /// that decoded every frame did: random requests (any call, now and then to a
        /// monitored address; some with a wrong bit, a failed line check or the wrong length)
        /// and responses at random gaps around the pause and the response window leave both in
        /// the same state (receiver, awaited answer, channels) after every frame.
        #[test]
        fn looking_only_at_monitored_addresses_changes_nothing(
            steps in proptest::collection::vec(
                (
                    proptest::prelude::any::<bool>(),
                    proptest::prop_oneof![
                        3 => proptest::prelude::any::<u16>(),
                        // Data_Exchange (CB 0, I4 0) to 11 or 12.
                        3 => (11u16..13, 0u16..16).prop_map(|(a, d)| a << 5 | d),
                    ],
                    proptest::prelude::any::<u8>(),
                    proptest::prelude::any::<u8>(),
                    proptest::prop_oneof![
                        2 => proptest::prelude::any::<bool>().prop_map(|_| 0u32),
                        1 => 0u32..=17,
                    ],
                    proptest::prop_oneof![
                        4 => 0u64..40_000,
                        2 => 150_000u64..250_000,
                        1 => 0u64..100_000_000,
                    ],
                ),
                1..300,
            ),
            taught in proptest::prelude::any::<bool>(),
        ) {
            let addresses = [Address::new(11).expect("a"), Address::new(12).expect("a")];
            let timing = asi_phy::BusTiming::default();
            let mut fast = SafetyMonitor::new(&timing, MonitorConfig::default(), &addresses);
            if taught {
                for a in addresses {
                    fast.set_table(a, CodeTable::from_serial(u64::from(a.get())));
                }
            }
            let mut old = fast.clone();
            let mut now = 0u64;
            for (request, bits, flip, failed, length, gap) in steps {
                let (raw, n, failed) = telegram(request, bits, flip, failed);
                let n = if length == 0 { n } else { length };
                now += gap;
                let f = Frame {
                    start: at(now),
                    end: at(now + u64::from(n) * 6_000),
                    pulses: 2 * n,
                    bit_count: n,
                    raw,
                    line_failed: failed,
                };
                now = f.end.as_nanos();
                fast.on_frame(f.start, &f);
                old.on_frame_as_it_was(f.start, &f);
                proptest::prop_assert_eq!(format!("{fast:?}"), format!("{old:?}"));
            }
        }
    }

    proptest::proptest! {
        /// The channel an address's slot names is the one a search of the channels finds
        /// (the first of that address), for any list of addresses: repeated ones, address 0,
        /// none at all.
        #[test]
        fn the_slot_of_an_address_names_the_channel_a_search_finds(
            numbers in proptest::collection::vec(0..32u8, 0..40),
        ) {
            let addresses: Vec<Address> =
                numbers.iter().map(|&n| Address::new(n).expect("a")).collect();
            let timing = asi_phy::BusTiming::default();
            let mut m = SafetyMonitor::new(&timing, MonitorConfig::default(), &addresses);
            for n in 0..32 {
                let a = Address::new(n).expect("a");
                let searched = m.channels.iter().position(|c| c.address == a);
                for c in &mut m.channels {
                    c.bad_codes = 0;
                }
                if let Some(c) = m.channel_mut(a) {
                    c.bad_codes = 1;
                }
                let found = m.channels.iter().position(|c| c.bad_codes == 1);
                proptest::prop_assert_eq!(found, searched, "address {}", n);
            }
        }
    }

    /// What a safe slave's exchange does in the property test below.
    #[derive(Clone, Copy, Debug)]
    enum Exchange {
        /// A request and the code `skip` + 1 places on in the slave's table (`skip` codes
        /// whose exchanges were lost), after `gap` ns.
        Step { gap: u64, skip: usize },
        /// A request whose answer is lost, after `gap` ns.
        Lost { gap: u64 },
        /// The master's repeat: a request within the hold and the code sent last.
        Repeat,
        /// A request answered with the code `code` (any value).
        Other { code: u8 },
        /// The tolerance time looked at, after `gap` ns.
        Poll { gap: u64 },
    }

    proptest::proptest! {
        #![proptest_config(proptest::test_runner::Config::with_cases(1_000))]

        /// The next code in turn judged with one comparison leaves the channel as the whole
        /// rule does: a slave's codes in turn, with lost exchanges, skipped codes, the
        /// master's repeats, codes off the table, 0000 and silences, to a channel that
        /// teaches itself or was given the table, compared after every exchange.
        #[test]
        fn the_next_code_in_turn_is_judged_as_the_whole_rule_judges_it(
            run in proptest::collection::vec(
                proptest::prop_oneof![
                    12 => (150_000..4_000_000u64, proptest::prop_oneof![
                        6 => proptest::strategy::Just(0usize),
                        1 => 1..10usize,
                    ]).prop_map(|(gap, skip)| Exchange::Step { gap, skip }),
                    1 => (0..4_000_000u64).prop_map(|gap| Exchange::Lost { gap }),
                    1 => proptest::strategy::Just(Exchange::Repeat),
                    1 => (0..16u8).prop_map(|code| Exchange::Other { code }),
                    1 => (0..60_000_000u64).prop_map(|gap| Exchange::Poll { gap }),
                ],
                1..300,
            ),
            given in proptest::prelude::any::<bool>(),
            serial in 0..1_000u64,
        ) {
            let cfg = MonitorConfig::default();
            let table = CodeTable::from_serial(serial);
            let mut fast = Channel::new(Address::new(11).expect("a"));
            if given {
                fast.table = Some(table);
                fast.reason = NotReleased::Recovering;
            }
            let mut rule = fast.clone();
            let (mut now, mut index, mut sent) = (0u64, 0usize, table.codes()[0]);
            for exchange in run {
                let code = match exchange {
                    Exchange::Step { gap, skip } => {
                        now += gap;
                        index = (index + 1 + skip) % 8;
                        Some(table.codes()[index])
                    }
                    Exchange::Lost { gap } => {
                        now += gap;
                        None
                    }
                    Exchange::Repeat => {
                        now += REPEAT;
                        Some(sent)
                    }
                    Exchange::Other { code } => {
                        now += CYCLE;
                        Some(code)
                    }
                    Exchange::Poll { gap } => {
                        now += gap;
                        fast.check_silence(at(now), &cfg);
                        rule.check_silence(at(now), &cfg);
                        proptest::prop_assert_eq!(format!("{fast:?}"), format!("{rule:?}"));
                        continue;
                    }
                };
                fast.request(at(now), &cfg);
                rule.request(at(now), &cfg);
                if let Some(code) = code {
                    sent = code;
                    fast.code(at(now + 100_000), code, &cfg);
                    rule.judge_code(at(now + 100_000), code, &cfg);
                }
                proptest::prop_assert_eq!(format!("{fast:?}"), format!("{rule:?}"));
            }
        }
    }

    /// One cycle of the lab bus.
    const CYCLE: u64 = 2_002_000;
    /// A master repeat comes this long after the first try.
    const REPEAT: u64 = 162_000;

    fn at(ns: u64) -> SimTime {
        SimTime::from_nanos(ns)
    }

    /// A channel that has learned `t` (two rotations, one exchange per cycle) at `now`.
    fn taught(t: &[u8; 8], now: &mut u64) -> Channel {
        let mut c = Channel::new(Address::new(11).expect("a"));
        feed(&mut c, t, now);
        feed(&mut c, t, now);
        assert!(c.released, "learned after two rotations");
        c
    }

    /// One exchange per cycle, each answered with the code.
    fn feed(c: &mut Channel, codes: &[u8], now: &mut u64) {
        let cfg = MonitorConfig::default();
        for &code in codes {
            *now += CYCLE;
            c.request(at(*now), &cfg);
            c.code(at(*now + 100_000), code, &cfg);
        }
    }

    /// One exchange whose answers (first try and repeat) were both rejected.
    fn lost(c: &mut Channel, now: &mut u64) {
        let cfg = MonitorConfig::default();
        *now += CYCLE;
        c.request(at(*now), &cfg);
        c.request(at(*now + REPEAT), &cfg);
    }

    #[test]
    fn tables_are_checked_and_unique_per_serial() {
        assert!(CodeTable::new([1, 2, 3, 4, 5, 6, 7, 15]).is_err());
        assert!(CodeTable::new([1, 2, 3, 4, 5, 6, 7, 0]).is_err());
        assert!(CodeTable::new([1, 2, 3, 4, 5, 6, 7, 1]).is_err());
        let a = CodeTable::from_serial(11);
        let b = CodeTable::from_serial(12);
        assert_ne!(a, b);
        assert!(CodeTable::new(a.codes()).is_ok());
        assert_eq!(a, CodeTable::from_serial(11));
    }

    #[test]
    fn a_correct_rotation_stays_released() {
        let t = CodeTable::from_serial(5).codes();
        let mut now = 0;
        let mut c = taught(&t, &mut now);
        for _ in 0..50 {
            feed(&mut c, &t, &mut now);
            assert!(c.released);
        }
        assert_eq!(c.bad_codes, 0);
        assert!(c.drops.is_empty());
    }

    #[test]
    fn a_rejected_telegram_and_its_repeat_are_not_a_wrong_code() {
        let t = CodeTable::from_serial(5).codes();
        let mut now = 0;
        let mut c = taught(&t, &mut now);
        let cfg = MonitorConfig::default();
        feed(&mut c, &t[..3], &mut now);
        // The response to the first try fails the checks; the repeat gets the same code.
        now += CYCLE;
        c.request(at(now), &cfg);
        c.request(at(now + REPEAT), &cfg);
        c.code(at(now + REPEAT + 100_000), t[3], &cfg);
        assert!(c.released);
        // This receiver took the first answer, the master did not: the repeat's code is the
        // same code, not a frozen one.
        now += CYCLE;
        c.request(at(now), &cfg);
        c.code(at(now + 100_000), t[4], &cfg);
        c.request(at(now + REPEAT), &cfg);
        c.code(at(now + REPEAT + 100_000), t[4], &cfg);
        assert!(c.released);
        // Both tries of an exchange lost: the slave stepped unheard, the next code skips one.
        lost(&mut c, &mut now);
        feed(&mut c, &[t[6], t[7]], &mut now);
        // Three exchanges lost in a row.
        for _ in 0..3 {
            lost(&mut c, &mut now);
        }
        feed(&mut c, &[t[3], t[4]], &mut now);
        assert!(c.released);
        assert_eq!(c.bad_codes, 0);
    }

    #[test]
    fn code_0000_drops_the_release_at_once_and_a_rotation_releases_again() {
        let t = CodeTable::from_serial(5).codes();
        let mut now = 0;
        let mut c = taught(&t, &mut now);
        feed(&mut c, &[0], &mut now);
        assert_eq!((c.released, c.reason), (false, NotReleased::Tripped));
        feed(&mut c, &[0, 0, 0], &mut now);
        feed(&mut c, &t[..7], &mut now);
        assert!(!c.released);
        feed(&mut c, &t[7..], &mut now);
        assert!(c.released, "8 correct codes release again");
        assert_eq!(c.drops.len(), 1);
        assert_eq!(c.drops[0].why, NotReleased::Tripped);
    }

    #[test]
    fn a_wrong_code_drops_the_release_at_once() {
        let t = CodeTable::from_serial(5).codes();
        let mut now = 0;
        let mut c = taught(&t, &mut now);
        feed(&mut c, &t[..3], &mut now);
        // One step, but the code two ahead.
        feed(&mut c, &[t[4]], &mut now);
        assert_eq!(
            (c.released, c.reason),
            (
                false,
                NotReleased::WrongCode {
                    expected: t[3],
                    got: t[4]
                }
            )
        );
        // A code outside the table after recovery.
        feed(&mut c, &t[5..], &mut now);
        feed(&mut c, &t[..5], &mut now);
        assert!(c.released);
        let outside = (1..15).find(|v| !t.contains(v)).expect("a value outside");
        feed(&mut c, &[outside], &mut now);
        assert!(!c.released);
        assert!(matches!(c.reason, NotReleased::WrongCode { .. }));
    }

    #[test]
    fn a_frozen_code_drops_the_release() {
        let t = CodeTable::from_serial(5).codes();
        let mut now = 0;
        let mut c = taught(&t, &mut now);
        feed(&mut c, &t[..3], &mut now);
        feed(&mut c, &[t[2]], &mut now);
        assert_eq!(
            (c.released, c.reason),
            (false, NotReleased::Frozen { code: t[2] })
        );
    }

    #[test]
    fn silence_beyond_the_tolerance_time_drops_the_release() {
        let t = CodeTable::from_serial(9).codes();
        let mut now = 0;
        let mut c = taught(&t, &mut now);
        let cfg = MonitorConfig::default();
        let last = now + 100_000;
        c.check_silence(at(last + 40_000_000), &cfg);
        assert!(c.released, "exactly the tolerance time");
        c.check_silence(at(last + 40_000_001), &cfg);
        assert_eq!((c.released, c.reason), (false, NotReleased::Missing));
        // Codes return: one rotation releases again.
        now = last + 50_000_000;
        feed(&mut c, &t[3..], &mut now);
        feed(&mut c, &t[..2], &mut now);
        assert!(!c.released);
        feed(&mut c, &t[2..3], &mut now);
        assert!(c.released);
        // A longer tolerance time is a setting.
        let long = MonitorConfig {
            max_silence: SimDuration::from_millis(100),
            ..cfg
        };
        c.check_silence(at(now + 60_000_000), &long);
        assert!(c.released);
    }

    #[test]
    fn teaching_needs_two_consecutive_rotations_heard_without_a_gap() {
        let t = CodeTable::from_serial(3).codes();
        let mut c = Channel::new(Address::new(12).expect("a"));
        let mut now = 0;
        feed(&mut c, &t[..5], &mut now);
        lost(&mut c, &mut now);
        feed(&mut c, &t[6..], &mut now);
        feed(&mut c, &t, &mut now);
        assert!(!c.released, "a gap restarts teaching");
        feed(&mut c, &t, &mut now);
        assert!(c.released);
        // Learned from t[6] on: the same cycle, started where the hearing started.
        let mut rotated = t;
        rotated.rotate_left(6);
        assert_eq!(c.table.map(|x| x.codes()), Some(rotated));
    }
}
