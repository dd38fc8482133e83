//! AS-i Safety at Work: code tables and the passive safety monitor (reference/asi.md §7; SPEC
//! §3, §6).
//!
//! A free safe slave sends, cycle after cycle, the 8 values of its own code table; tripped it
//! sends 0000. The [`SafetyMonitor`] listens on the bus with its own receiver (so it trusts
//! only telegrams that pass the seven checks), pairs each Data_Exchange to a monitored address
//! with its response, learns each slave's table and reports released / not released.
//!
//! **Decisions** (the public sources give the principle, not the rule; reference/asi.md §7):
//! - Tables have 8 distinct values in 0001..1110 (no 0000, which means tripped, and no 1111,
//!   which the coding rules forbid).
//! - Teaching: the monitor learns a table from 16 consecutive codes whose second 8 repeat the
//!   first 8; it then releases.
//! - 0000 drops the release at once (the demand). A wrong code (not the next of the table) or a
//!   frozen code (the same code twice: with the SAP5 hold rule a master repeat never shows a
//!   code twice, because the monitor sees only the valid response) is tolerated once; the
//!   second bad code in a row drops the release. No valid code for `max_silence` (default
//!   40 ms) drops it too (missing code).
//! - After a drop the monitor releases again after 8 consecutive correct codes (one rotation);
//!   restart interlocks (manual restart) belong to the safety logic (SPEC §6, MON).

use crate::config::ConfigError;
use asi_phy::{Address, Call, Expect, Frame, Listener, SimDuration, SimTime, TelegramKind};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// A safe slave's 8-value code table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CodeTable([u8; 8]);

impl CodeTable {
    /// A table from its values; each must be in 1..=14 and all distinct.
    pub fn new(codes: [u8; 8]) -> Result<CodeTable, ConfigError> {
        for (i, &c) in codes.iter().enumerate() {
            if c == 0 || c >= 15 {
                return Err(ConfigError::Slave {
                    name: "code table".into(),
                    why: format!("value {i} is {c:04b}: must be 0001..1110"),
                });
            }
            if codes[..i].contains(&c) {
                return Err(ConfigError::Slave {
                    name: "code table".into(),
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
    /// Consecutive bad codes (wrong or frozen) that drop the release (default 2).
    pub bad_codes_to_trip: u8,
    /// Longest time without a valid code before the release drops (default 40 ms).
    pub max_silence: SimDuration,
}

impl Default for MonitorConfig {
    fn default() -> Self {
        MonitorConfig {
            bad_codes_to_trip: 2,
            max_silence: SimDuration::from_millis(40),
        }
    }
}

#[derive(Clone, Debug)]
struct Channel {
    address: Address,
    table: Option<CodeTable>,
    learn: Vec<u8>,
    pos: Option<usize>,
    last_code: Option<u8>,
    last_at: Option<SimTime>,
    bad: u8,
    good_run: u8,
    released: bool,
    reason: NotReleased,
    bad_codes: u64,
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
            bad: 0,
            good_run: 0,
            released: false,
            reason: NotReleased::Teaching,
            bad_codes: 0,
        }
    }

    fn drop_release(&mut self, why: NotReleased) {
        self.reason = why;
        self.released = false;
        self.good_run = 0;
    }

    fn code(&mut self, now: SimTime, code: u8, cfg: &MonitorConfig) {
        let previous = self.last_code.replace(code);
        self.last_at = Some(now);
        let Some(table) = self.table else {
            self.teach(code);
            return;
        };
        if code == 0 {
            self.pos = None;
            self.bad = 0;
            self.drop_release(NotReleased::Tripped);
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
                if code == expected {
                    self.pos = Some((p + 1) % 8);
                    None
                } else if previous == Some(code) {
                    Some(NotReleased::Frozen { code })
                } else {
                    if let Some(q) = table.position(code) {
                        self.pos = Some(q);
                    }
                    Some(NotReleased::WrongCode {
                        expected,
                        got: code,
                    })
                }
            }
        };
        match bad {
            None => {
                self.bad = 0;
                self.good_run = self.good_run.saturating_add(1);
                if !self.released && self.good_run >= 8 {
                    self.released = true;
                }
                if !self.released && self.reason != NotReleased::Recovering {
                    self.reason = NotReleased::Recovering;
                }
            }
            Some(why) => {
                self.bad_codes += 1;
                self.bad = self.bad.saturating_add(1);
                self.good_run = 0;
                if self.bad >= cfg.bad_codes_to_trip || !self.released {
                    self.drop_release(why);
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
                self.drop_release(NotReleased::Missing);
            }
        }
    }
}

/// A passive Safety-at-Work monitor on the bus (reference/asi.md §7).
#[derive(Clone, Debug)]
pub struct SafetyMonitor {
    cfg: MonitorConfig,
    listener: Listener,
    asked: Option<Address>,
    channels: Vec<Channel>,
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
        }
    }

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

    fn channel_mut(&mut self, a: Address) -> Option<&mut Channel> {
        self.channels.iter_mut().find(|c| c.address == a)
    }

    /// A frame heard on the line at `now`.
    pub fn on_frame(&mut self, now: SimTime, frame: &Frame) {
        let r = self.listener.accept(frame);
        match r.kind {
            TelegramKind::Request => {
                self.asked = match r.request().map(|q| q.call()) {
                    Some(Call::DataExchange { address, .. }) => Some(address),
                    _ => None,
                };
            }
            TelegramKind::Response => {
                let (Some(a), Some(resp)) = (self.asked.take(), r.response()) else {
                    return;
                };
                let cfg = self.cfg;
                if let Some(c) = self.channel_mut(a) {
                    c.code(now, resp.data().get(), &cfg);
                }
            }
        }
    }

    /// Advances the monitor's clock (missing-code timeouts).
    pub fn poll(&mut self, now: SimTime) {
        let cfg = self.cfg;
        for c in &mut self.channels {
            c.check_silence(now, &cfg);
        }
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

    /// The monitored addresses.
    pub fn addresses(&self) -> impl Iterator<Item = Address> + '_ {
        self.channels.iter().map(|c| c.address)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn feed(c: &mut Channel, codes: &[u8], t0: &mut u64) {
        let cfg = MonitorConfig::default();
        for &code in codes {
            *t0 += 2_000_000;
            c.code(SimTime::from_nanos(*t0), code, &cfg);
        }
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
    fn teach_then_release_then_trip_on_0000_and_recover_after_a_rotation() {
        let t = CodeTable::from_serial(5).codes();
        let mut c = Channel::new(Address::new(11).expect("a"));
        let mut now = 0;
        feed(&mut c, &t, &mut now);
        assert!(!c.released);
        feed(&mut c, &t, &mut now);
        assert!(c.released, "learned after two rotations");
        feed(&mut c, &[0], &mut now);
        assert_eq!((c.released, c.reason), (false, NotReleased::Tripped));
        feed(&mut c, &t[..7], &mut now);
        assert!(!c.released);
        feed(&mut c, &t[7..], &mut now);
        assert!(c.released, "8 correct codes release again");
    }

    #[test]
    fn one_bad_code_is_tolerated_the_second_drops_the_release() {
        let t = CodeTable::from_serial(5).codes();
        let mut c = Channel::new(Address::new(11).expect("a"));
        let mut now = 0;
        feed(&mut c, &t, &mut now);
        feed(&mut c, &t, &mut now);
        feed(&mut c, &t[..3], &mut now);
        feed(&mut c, &[t[2]], &mut now); // frozen once
        assert!(c.released);
        feed(&mut c, &[t[2]], &mut now); // frozen twice
        assert_eq!(
            (c.released, c.reason),
            (false, NotReleased::Frozen { code: t[2] })
        );
    }

    #[test]
    fn silence_drops_the_release() {
        let t = CodeTable::from_serial(9).codes();
        let mut c = Channel::new(Address::new(12).expect("a"));
        let mut now = 0;
        feed(&mut c, &t, &mut now);
        feed(&mut c, &t, &mut now);
        let cfg = MonitorConfig::default();
        c.check_silence(SimTime::from_nanos(now + 39_000_000), &cfg);
        assert!(c.released);
        c.check_silence(SimTime::from_nanos(now + 41_000_000), &cfg);
        assert_eq!((c.released, c.reason), (false, NotReleased::Missing));
    }
}
