//! The exchange as first written, a telegram's bytes at every step: the partner checks each
//! request's sender and CRC, and the logic each reply's, and the black channel keeps the bytes
//! of the last replies. The property test in the parent module checks the exchange against it.

use std::collections::VecDeque;

use asi_phy::{SimDuration, SimTime};

use super::{address_crc, control, next_seq, status, ChannelFault, ConnDiag, ConnEvent, Telegram};

/// The untrusted channel between the logic and one partner, with scheduled faults.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
struct BlackChannel {
    scheduled: Vec<(SimTime, ChannelFault)>,
    down_until: Option<SimTime>,
    next_reply_fault: VecDeque<ChannelFault>,
    history: VecDeque<[u8; Telegram::LEN]>,
}

impl BlackChannel {
    const HISTORY: usize = 16;

    fn schedule(&mut self, at: SimTime, fault: ChannelFault) {
        // Stable order: faults at the same instant act in the order they were given.
        let pos = self.scheduled.partition_point(|(t, _)| *t <= at);
        self.scheduled.insert(pos, (at, fault));
    }

    /// Start of an exchange at `now`: activate due faults; `true` if the link is down.
    fn begin(&mut self, now: SimTime) -> bool {
        // The schedule is in time order: nothing is due unless its first fault is (almost
        // every exchange has none scheduled at all).
        if self.scheduled.first().is_some_and(|(t, _)| *t <= now) {
            let due = self.scheduled.partition_point(|(t, _)| *t <= now);
            for (at, fault) in self.scheduled.drain(..due) {
                match fault {
                    ChannelFault::Drop { duration } => {
                        let until = at + duration;
                        self.down_until = Some(self.down_until.map_or(until, |u| u.max(until)));
                    }
                    other => self.next_reply_fault.push_back(other),
                }
            }
        }
        match self.down_until {
            Some(until) if now < until => true,
            _ => {
                self.down_until = None;
                false
            }
        }
    }

    /// Carry a reply: applies the next pending reply fault.
    fn carry_reply(&mut self, reply: [u8; Telegram::LEN]) -> Option<[u8; Telegram::LEN]> {
        let delivered = match self.next_reply_fault.pop_front() {
            None => Some(reply),
            Some(ChannelFault::CorruptCrc) => {
                let mut r = reply;
                r[Telegram::LEN - 1] ^= 0x01;
                Some(r)
            }
            Some(ChannelFault::Replay { age }) => self
                .history
                .len()
                .checked_sub(usize::from(age.max(1)))
                .map(|k| self.history[k]),
            Some(ChannelFault::WrongAddress { sender }) => {
                let mut t = Telegram::from_bytes(reply);
                t.sender = sender;
                Some(t.to_bytes())
            }
            Some(ChannelFault::NullTelegram) => Some([0; Telegram::LEN]),
            Some(ChannelFault::Drop { .. }) => None,
        };
        if self.history.len() == Self::HISTORY {
            self.history.pop_front();
        }
        self.history.push_back(reply);
        delivered
    }
}

/// The simulated partner terminal (TwinSAFE slave): it checks the logic's requests, drives its
/// safe outputs from them and answers with its safe inputs.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Partner {
    address: u16,
    master: u16,
    /// [`address_crc`] of requests (master to partner) and of replies (partner to master).
    request_crc: u16,
    reply_crc: u16,
    watchdog: SimDuration,
    inputs: u8,
    outputs: u8,
    last_seq: u16,
    last_valid: Option<SimTime>,
    faults: u8,
}

impl Partner {
    fn handle(
        &mut self,
        now: SimTime,
        request: Option<[u8; Telegram::LEN]>,
    ) -> Option<[u8; Telegram::LEN]> {
        let mut reply = None;
        if let Some(bytes) = request {
            let t = Telegram::from_bytes(bytes);
            let seq_ok =
                self.last_seq == 0 || t.seq == self.last_seq || t.seq == next_seq(self.last_seq);
            // The sender is checked first: `request_crc` is the CRC of the master's address.
            if t.sender == self.master
                && t.crc == t.crc_after(self.request_crc)
                && t.seq != 0
                && seq_ok
            {
                if t.status & control::ACK != 0 {
                    self.faults = 0;
                }
                self.last_seq = t.seq;
                self.last_valid = Some(now);
                self.outputs = if t.status & control::ACTIVATE_FV != 0 {
                    0
                } else {
                    t.data
                };
                let r = Telegram::with_address_crc(
                    self.address,
                    self.reply_crc,
                    t.seq,
                    self.inputs,
                    self.faults,
                );
                reply = Some(r.to_bytes());
            } else {
                self.faults |= status::COMM_FAULT;
            }
        }
        let since = self.last_valid.get_or_insert(now);
        if now.saturating_duration_since(*since) > self.watchdog {
            self.faults |= status::WD_FAULT;
            self.outputs = 0;
        }
        reply
    }
}

/// The logic's side of one TwinSAFE connection, with its partner and black channel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Connection {
    logic_address: u16,
    partner_address: u16,
    /// [`address_crc`] of requests (logic to partner) and of replies (partner to logic).
    request_crc: u16,
    reply_crc: u16,
    watchdog: SimDuration,
    pub(super) seq: u16,
    first_scan: Option<SimTime>,
    last_valid: Option<SimTime>,
    received: u8,
    latched: ConnDiag,
    cause_active: bool,
    ack_pending: bool,
    partner: Partner,
    channel: BlackChannel,
    events: Vec<ConnEvent>,
}

impl Connection {
    /// A connection from the logic at `logic_address` to the partner at `partner_address`.
    pub fn new(logic_address: u16, partner_address: u16, watchdog: SimDuration) -> Self {
        let request_crc = address_crc(logic_address, partner_address);
        let reply_crc = address_crc(partner_address, logic_address);
        Connection {
            logic_address,
            partner_address,
            request_crc,
            reply_crc,
            watchdog,
            seq: 1,
            first_scan: None,
            last_valid: None,
            received: 0,
            latched: ConnDiag::default(),
            cause_active: false,
            ack_pending: false,
            partner: Partner {
                address: partner_address,
                master: logic_address,
                request_crc,
                reply_crc,
                watchdog,
                inputs: 0,
                outputs: 0,
                last_seq: 0,
                last_valid: None,
                faults: 0,
            },
            channel: BlackChannel::default(),
            events: Vec::new(),
        }
    }

    /// Set the partner's safe inputs (bit `n-1` = channel `n`), e.g. the STOP contacts wired
    /// to a KL1904. They travel to the logic with the next exchange.
    pub fn set_partner_inputs(&mut self, bits: u8) {
        self.partner.inputs = bits;
    }

    /// The partner's safe outputs as it drives them (a KL2904's terminals).
    pub fn partner_outputs(&self) -> u8 {
        self.partner.outputs
    }

    /// Schedule a channel fault at `at` (acts at the first exchange at or after `at`).
    pub fn inject(&mut self, at: SimTime, fault: ChannelFault) {
        self.channel.schedule(at, fault);
    }

    /// One exchange at `now`: send `outputs` (the logic's TwinSAFE-Out channels) and check the
    /// reply. Returns what happened.
    pub fn exchange(&mut self, now: SimTime, outputs: u8) -> &[ConnEvent] {
        self.events.clear();
        let start = *self.first_scan.get_or_insert(now);
        let fail_safe = self.fail_safe();
        let mut ctrl = if fail_safe { control::ACTIVATE_FV } else { 0 };
        if core::mem::take(&mut self.ack_pending) {
            ctrl |= control::ACK;
        }
        let data = if fail_safe { 0 } else { outputs };
        let request =
            Telegram::with_address_crc(self.logic_address, self.request_crc, self.seq, data, ctrl);
        let down = self.channel.begin(now);
        let delivered = if down { None } else { Some(request.to_bytes()) };
        let reply = self.partner.handle(now, delivered);
        let reply = match reply {
            Some(r) if !down => self.channel.carry_reply(r),
            _ => None,
        };
        let valid = reply.is_some_and(|r| self.check(now, r));
        let since = self.last_valid.unwrap_or(start);
        let silent = now.saturating_duration_since(since);
        let expired = silent > self.watchdog;
        if expired {
            self.latch(
                ConnDiag::WATCHDOG,
                format!(
                    "no valid telegram for {silent} (watchdog {})",
                    self.watchdog
                ),
            );
        }
        self.cause_active = !valid || expired;
        &self.events
    }

    /// Check a reply; `true` if it is valid. Latches the error bits of a bad one.
    fn check(&mut self, now: SimTime, bytes: [u8; Telegram::LEN]) -> bool {
        if bytes == [0; Telegram::LEN] {
            self.latch(ConnDiag::NULL_TELEGRAM, "null telegram received".into());
            return false;
        }
        let t = Telegram::from_bytes(bytes);
        if t.sender != self.partner_address {
            self.latch(
                ConnDiag::CRC,
                format!(
                    "telegram from TwinSAFE address {}, expected {} (CRC2)",
                    t.sender, self.partner_address
                ),
            );
            return false;
        }
        // The sender is the partner (checked above): `reply_crc` is the CRC of its address.
        if t.crc != t.crc_after(self.reply_crc) {
            self.latch(
                ConnDiag::CRC,
                format!(
                    "CRC error in telegram seq {} (got {:04X}, computed {:04X})",
                    t.seq,
                    t.crc,
                    t.crc_for(self.logic_address)
                ),
            );
            return false;
        }
        if t.seq != self.seq {
            self.latch(
                ConnDiag::SEQUENCE,
                format!(
                    "sequence error: got seq {}, expected {} (old or repeated telegram)",
                    t.seq, self.seq
                ),
            );
            return false;
        }
        if t.status & (status::COMM_FAULT | status::WD_FAULT) != 0 {
            let what = match t.status & (status::COMM_FAULT | status::WD_FAULT) {
                status::COMM_FAULT => "Comm_Fault",
                status::WD_FAULT => "WD_Fault",
                _ => "Comm_Fault and WD_Fault",
            };
            self.latch(ConnDiag::SLAVE_ERROR, format!("partner reports {what}"));
        }
        self.seq = next_seq(self.seq);
        self.received = t.data;
        if self.last_valid.is_none() {
            self.events.push(ConnEvent::Running);
        }
        self.last_valid = Some(now);
        true
    }

    fn latch(&mut self, bit: ConnDiag, detail: String) {
        if !self.latched.contains(bit) {
            self.latched = self.latched | bit;
            self.events.push(ConnEvent::Error { bit, detail });
        }
    }

    /// `true` while the logic uses fail-safe values: before the first valid reply, and while an
    /// error is latched.
    pub fn fail_safe(&self) -> bool {
        self.last_valid.is_none() || self.latched.is_error()
    }

    /// The partner's safe inputs as the logic sees them (0 while fail-safe).
    pub fn inputs(&self) -> u8 {
        if self.fail_safe() {
            0
        } else {
            self.received
        }
    }

    /// The diag byte: latched error bits plus the status bits 6 and 7.
    pub fn diag(&self) -> ConnDiag {
        let mut d = self.latched;
        if self.last_valid.is_none() {
            d = d | ConnDiag::PARAMETERS_SENT;
        }
        if self.fail_safe() {
            d = d | ConnDiag::FAIL_SAFE_VALUES;
        }
        d
    }

    /// `true` while an error is latched (COM_ERR).
    pub fn has_error(&self) -> bool {
        self.latched.is_error()
    }

    /// `true` if the last exchange did not deliver a valid telegram in time (then ERR_ACK is
    /// refused).
    pub fn error_cause_active(&self) -> bool {
        self.cause_active
    }

    /// The group's ERR_ACK: clear the latched errors; the next request tells the partner too
    /// (control bit ACK), so it clears its Comm_Fault/WD_Fault.
    pub fn acknowledge(&mut self) {
        if self.latched.is_error() {
            self.latched = ConnDiag::default();
            self.ack_pending = true;
        }
    }
}
