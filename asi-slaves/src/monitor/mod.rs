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

use asi_phy::{
    Address, Expect, Frame, Listener, Received, Request, Response, SimDuration, SimTime,
    TelegramKind,
};
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
#[non_exhaustive]
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

/// A telegram heard at a moment, as a receiver took it ([`SafetyMonitor::hear`]).
#[derive(Clone, Copy, Debug)]
pub enum Heard<'a> {
    /// What a receiver made of a frame, valid or not.
    Received(&'a Received),
    /// The valid request: what a receiver makes of a clean frame of it, taken as a request.
    Request(Request),
    /// The valid response: what a receiver makes of a clean frame of it, taken as a response.
    Response(Response),
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
    /// [`SafetyMonitor::releases`], kept as the channels change: the application asks it at
    /// every safety scan, and the channels' releases and drops change far more rarely.
    /// Worked out again after every change of a channel's release or drops
    /// ([`SafetyMonitor::look_again`]), except for the release of a channel with the code in
    /// turn, which only sets its bit.
    looks: (u32, bool),
}

impl SafetyMonitor {
    /// A monitor of the safe slaves at `addresses`, with `cfg`, listening with the receiver
    /// settings of `timing`. It starts teaching.
    pub fn new(
        timing: &asi_phy::BusTiming,
        cfg: MonitorConfig,
        addresses: &[Address],
    ) -> SafetyMonitor {
        let mut m = SafetyMonitor {
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
            looks: (0, false),
        };
        m.look_again();
        m
    }

    /// Works [`SafetyMonitor::looks`] out from the channels: the released addresses and
    /// whether a channel holds a dropped release.
    fn look_again(&mut self) {
        self.looks = self.channels.iter().fold((0, false), |(mask, drops), c| {
            (
                mask | u32::from(c.released) << c.address.get(),
                drops || !c.drops.is_empty(),
            )
        });
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
        self.look_again();
    }

    /// Forgets every learned table and starts teaching again.
    pub fn reteach(&mut self) {
        for c in &mut self.channels {
            *c = Channel::new(c.address);
        }
        self.look_again();
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
    /// ([`SafetyMonitor::heard_valid_request`], [`SafetyMonitor::heard_code`]), so that the
    /// common frame costs the receiver and a test. Inlined into the bus's per-frame loop.
    #[inline]
    pub fn on_frame(&mut self, now: SimTime, frame: &Frame) {
        let r = self.listener.accept(frame);
        self.judge(now, &r);
    }

    /// What the monitor notes of a telegram heard at `now` that a receiver in the state of
    /// the monitor's own took ([`Heard`]), without bringing the monitor's receiver on: for a
    /// caller that runs the receiver itself and keeps the monitor's
    /// ([`SafetyMonitor::receiver_mut`]) in the state the frames leave it in. The bus does:
    /// the monitor's receiver and the slaves' hear the same frames, so while the two are in
    /// the same state it checks each frame once; its lockstep test against its pulse-exact
    /// path compares the monitors.
    // Always inlined: the bus hears a known kind at each place, and the match folds away.
    #[inline(always)]
    pub fn hear(&mut self, now: SimTime, heard: Heard<'_>) {
        match heard {
            Heard::Received(r) => self.judge(now, r),
            // What `judge` does with a valid request, from the request itself.
            Heard::Request(q) => {
                self.asked = None;
                if self.monitored >> q.address().get() & 1 != 0 {
                    self.heard_valid_request(now, q);
                }
            }
            Heard::Response(a) => {
                if let Some(asked) = self.asked {
                    self.asked = None;
                    self.heard_code(now, asked, a.data().get());
                }
            }
        }
    }

    /// The monitor's receiver.
    pub fn receiver(&self) -> &Listener {
        &self.listener
    }

    /// The monitor's receiver, for a caller that takes frames through a receiver of its own
    /// in the same state ([`SafetyMonitor::hear`]).
    pub fn receiver_mut(&mut self) -> &mut Listener {
        &mut self.listener
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
    /// the slave it asks takes a step, and its answer is awaited (out of line:
    /// [`SafetyMonitor::heard_valid_request`]).
    #[inline]
    fn heard_request(&mut self, now: SimTime, r: &Received) {
        if let Some(q) = r.request() {
            self.heard_valid_request(now, q);
        }
    }

    /// [`SafetyMonitor::heard_request`] of the valid request `q`.
    #[inline(never)]
    fn heard_valid_request(&mut self, now: SimTime, q: Request) {
        // A Data_Exchange told from its bits, without decoding the call
        // (`Request::as_data_exchange`, held to the call decoder for every request by asi-phy's
        // telegram tests).
        let Some((a, _)) = q.as_data_exchange() else {
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
    #[inline]
    fn heard_response(&mut self, now: SimTime, a: Address, r: &Received) {
        if let Some(resp) = r.response() {
            self.heard_code(now, a, resp.data().get());
        }
    }

    /// Code `code` taken for the response to the Data_Exchange that asked slave `a`.
    #[inline(never)]
    fn heard_code(&mut self, now: SimTime, a: Address, code: u8) {
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
                // The code in turn releases a channel or leaves it as it was, and drops
                // nothing: its bit is all that can change in `looks`.
                self.looks.0 |= 1 << c.address.get();
            }
        } else {
            self.judge_in_full(now, usize::from(slot), code);
        }
    }

    /// [`SafetyMonitor::heard_code`] of a code that is not the next in turn: the whole
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
        self.look_again();
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
        self.look_again();
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

    /// The released addresses (bit `a` set for address `a`), and whether a release was
    /// dropped since the last [`SafetyMonitor::take_drops`]: [`SafetyMonitor::released`] of
    /// every address and [`SafetyMonitor::has_drops`] in one look at the channels.
    ///
    /// Kept as the channels change ([`SafetyMonitor::looks`]); debug builds, and so the
    /// tests, check it against the channels at every call.
    pub fn releases(&self) -> (u32, bool) {
        debug_assert_eq!(
            self.looks,
            self.channels.iter().fold((0, false), |(mask, drops), c| {
                (
                    mask | u32::from(c.released) << c.address.get(),
                    drops || !c.drops.is_empty(),
                )
            }),
            "the monitor's releases are out of step with its channels"
        );
        self.looks
    }

    /// `true` if a release was dropped since the last [`SafetyMonitor::take_drops`].
    pub fn has_drops(&self) -> bool {
        self.channels.iter().any(|c| !c.drops.is_empty())
    }

    /// The releases dropped since the last call, in order (for reports).
    pub fn take_drops(&mut self) -> Vec<MonitorDrop> {
        // Asked at every safety scan, and almost always with nothing to give.
        if !self.has_drops() {
            return Vec::new();
        }
        let mut all: Vec<MonitorDrop> = self
            .channels
            .iter_mut()
            .flat_map(|c| c.drops.drain(..))
            .collect();
        self.look_again();
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
mod tests;
