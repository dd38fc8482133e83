//! TwinSAFE connections: the safe telegram over an untrusted ("black") channel (§3.2 and §3.3 of
//! the KL6904 manual; docs/safety-logic.md §1.3, §1.4, §6.3, §9.2 "Group / connection").
//!
//! The logic is the TwinSAFE master of every connection to a safe I/O terminal. Each safety
//! scan it sends one request to the partner and checks the partner's reply:
//!
//! ```text
//!  logic (master) --request(seq N, outputs)--> [black channel] --> partner terminal
//!                 <--reply(seq N, inputs)----- [black channel] <--
//! ```
//!
//! **Decisions** (the KL-series TwinSAFE protocol is not public; it is close to PROFIsafe,
//! docs/safety-logic.md §1.4 INFER, §10 point 9 — the KL model is used, not FSoE):
//! - the telegram is 8 bytes: data, status/control, sequence number (u16 LE), sender address
//!   (u16 LE), CRC (u16 LE);
//! - the CRC is the FSoE CRC-16 (polynomial 0x39B7, MSB first, initial value 0, no final XOR;
//!   docs/safety-logic.md §6.3) over both addresses, the sequence number, data and status; the
//!   *receiver's* address enters the CRC without being sent, so a telegram meant for another
//!   connection fails the CRC;
//! - the master drives the sequence number (PROFIsafe consecutive number): it sends N until a
//!   valid reply echoing N arrives, then N+1; numbers run 1..=65535 and skip 0, so a valid
//!   telegram is never all zeros and an all-zero one is the "null telegram" of diag bit 0. A
//!   lost telegram thus only delays the exchange (the watchdog catches it); a replayed old one
//!   carries an old number (diag bit 4);
//! - the watchdog restarts on every valid reply and expires when none came for *longer* than
//!   the watchdog time; it counts from the connection's first scan;
//! - a reply from the wrong sender address is a CRC2 error (bit 3): the diag byte has no
//!   address bit; the event text names the address;
//! - any error latches in the diag byte, the logic then uses fail-safe values (all inputs 0,
//!   diag bit 7 "ActivateFV") and the group shows COM_ERR; restoring telegrams does not clear it,
//!   only the group's ERR_ACK, and only while valid telegrams arrive (docs/safety-logic.md §9.2);
//! - one telegram per direction per safety scan; the black channel delivers it within the scan
//!   unless a fault says otherwise; diag bit 1 (invalid K-bus state) is never raised.

use std::collections::VecDeque;

use asi_phy::{SimDuration, SimTime};
use core::fmt;

/// The connection diagnostic byte (§3.3 of the KL6904 manual; bit 0 is the rightmost).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ConnDiag(pub u8);

impl ConnDiag {
    /// Bit 0: an (unexpected) null telegram was received, e.g. K-bus or fieldbus interrupted.
    pub const NULL_TELEGRAM: ConnDiag = ConnDiag(1 << 0);
    /// Bit 1: invalid K-bus state (never raised by the simulation).
    pub const INVALID_KBUS: ConnDiag = ConnDiag(1 << 1);
    /// Bit 2: the watchdog expired.
    pub const WATCHDOG: ConnDiag = ConnDiag(1 << 2);
    /// Bit 3: CRC2 error.
    pub const CRC: ConnDiag = ConnDiag(1 << 3);
    /// Bit 4: sequence-number (SeqNo) error.
    pub const SEQUENCE: ConnDiag = ConnDiag(1 << 4);
    /// Bit 5: slave error: the partner set Comm_Fault or WD_Fault in its status.
    pub const SLAVE_ERROR: ConnDiag = ConnDiag(1 << 5);
    /// Bit 6: the F- and I-parameters have been sent (start-up, no valid reply yet).
    pub const PARAMETERS_SENT: ConnDiag = ConnDiag(1 << 6);
    /// Bit 7: ActivateFV set in F_Control: the logic uses fail-safe values.
    pub const FAIL_SAFE_VALUES: ConnDiag = ConnDiag(1 << 7);
    /// The bits that are communication errors (COM_ERR): 0 to 5.
    pub const ERRORS: ConnDiag = ConnDiag(0b0011_1111);

    const NAMES: [&'static str; 8] = [
        "null telegram",
        "invalid K-bus state",
        "watchdog expired",
        "CRC error",
        "sequence error",
        "slave error",
        "parameters sent",
        "fail-safe values",
    ];

    /// `true` if every bit of `other` is set.
    pub const fn contains(self, other: ConnDiag) -> bool {
        self.0 & other.0 == other.0
    }

    /// `true` if any communication-error bit (0–5) is set.
    pub const fn is_error(self) -> bool {
        self.0 & Self::ERRORS.0 != 0
    }

    /// The names of the set bits, lowest first.
    pub fn names(self) -> impl Iterator<Item = &'static str> {
        (0..8)
            .filter(move |b| self.0 & 1 << b != 0)
            .map(|b| Self::NAMES[b])
    }
}

impl core::ops::BitOr for ConnDiag {
    type Output = ConnDiag;
    fn bitor(self, rhs: ConnDiag) -> ConnDiag {
        ConnDiag(self.0 | rhs.0)
    }
}

impl fmt::Display for ConnDiag {
    /// `0x84 (watchdog expired, fail-safe values)`, or `0x00 (ok)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "0x{:02X} (", self.0)?;
        let mut names = self.names().peekable();
        if names.peek().is_none() {
            f.write_str("ok")?;
        }
        for (k, n) in names.enumerate() {
            if k > 0 {
                f.write_str(", ")?;
            }
            f.write_str(n)?;
        }
        f.write_str(")")
    }
}

/// CRC-16 with polynomial 0x39B7, MSB first, initial value 0, no final XOR (the FSoE CRC of
/// ETG.5100 §8.1.3.2; docs/safety-logic.md §6.3).
pub fn crc16(bytes: &[u8]) -> u16 {
    crc16_continue(0, bytes)
}

/// The CRC register after `bytes`, starting from the register `crc`: `crc16(a ++ b)` is
/// `crc16_continue(crc16(a), b)`, so a prefix that never changes is folded in once.
pub fn crc16_continue(crc: u16, bytes: &[u8]) -> u16 {
    bytes.iter().fold(crc, |crc, &b| {
        (crc << 8) ^ CRC16_TABLE[usize::from((crc >> 8) as u8 ^ b)]
    })
}

/// The CRC register after the two addresses of a telegram from `sender` to `receiver`: the
/// first four bytes of every telegram's CRC ([`Telegram::crc_for`]). A connection's two
/// directions each have one for good, so an exchange only runs the CRC over the four bytes
/// that change (seq, data, status).
pub fn address_crc(sender: u16, receiver: u16) -> u16 {
    let s = sender.to_le_bytes();
    let r = receiver.to_le_bytes();
    crc16(&[s[0], s[1], r[0], r[1]])
}

/// The CRC of every byte value as the high byte of the register: a byte at a time instead of
/// a bit at a time (four telegrams are checked every 1 ms scan).
const CRC16_TABLE: [u16; 256] = {
    let mut table = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        table[i] = crc16_bitwise_byte((i as u16) << 8);
        i += 1;
    }
    table
};

/// Eight shifts of the register `c` (the bitwise definition).
const fn crc16_bitwise_byte(mut c: u16) -> u16 {
    let mut k = 0;
    while k < 8 {
        c = if c & 0x8000 != 0 {
            (c << 1) ^ 0x39B7
        } else {
            c << 1
        };
        k += 1;
    }
    c
}

/// Status bits of a partner's reply (PROFIsafe F_Status style).
pub mod status {
    /// The partner received a faulty request (Comm_Fault).
    pub const COMM_FAULT: u8 = 1 << 0;
    /// The partner's own watchdog expired (WD_Fault).
    pub const WD_FAULT: u8 = 1 << 1;
}

/// Control bits of the logic's request (PROFIsafe F_Control style).
pub mod control {
    /// Operator acknowledge: the partner clears its fault bits.
    pub const ACK: u8 = 1 << 0;
    /// ActivateFV: the partner must drive fail-safe values (all outputs 0).
    pub const ACTIVATE_FV: u8 = 1 << 1;
}

/// One safe telegram as carried by the black channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Telegram {
    /// Safe data: 8 channels, bit `n-1` = channel `n`.
    pub data: u8,
    /// Status (partner → logic) or control (logic → partner) bits.
    pub status: u8,
    /// Sequence number, 1..=65535.
    pub seq: u16,
    /// TwinSAFE address of the sender.
    pub sender: u16,
    /// CRC over both addresses, seq, data and status.
    pub crc: u16,
}

impl Telegram {
    /// Bytes on the wire.
    pub const LEN: usize = 8;

    /// A telegram from `sender` to `receiver` with its CRC.
    pub fn new(sender: u16, receiver: u16, seq: u16, data: u8, status: u8) -> Self {
        Telegram::with_address_crc(sender, address_crc(sender, receiver), seq, data, status)
    }

    /// A telegram from `sender` with its CRC, given the CRC of its addresses
    /// ([`address_crc`] of `sender` and the receiver).
    fn with_address_crc(sender: u16, addresses: u16, seq: u16, data: u8, status: u8) -> Self {
        let mut t = Telegram {
            data,
            status,
            seq,
            sender,
            crc: 0,
        };
        t.crc = t.crc_after(addresses);
        t
    }

    /// The CRC this telegram must carry if it is meant for `receiver`.
    pub fn crc_for(&self, receiver: u16) -> u16 {
        self.crc_after(address_crc(self.sender, receiver))
    }

    /// The CRC this telegram must carry, given the CRC of its addresses ([`address_crc`] of
    /// its sender and the receiver).
    fn crc_after(&self, addresses: u16) -> u16 {
        let q = self.seq.to_le_bytes();
        crc16_continue(addresses, &[q[0], q[1], self.data, self.status])
    }

    /// The wire bytes.
    pub fn to_bytes(self) -> [u8; Self::LEN] {
        let q = self.seq.to_le_bytes();
        let s = self.sender.to_le_bytes();
        let c = self.crc.to_le_bytes();
        [self.data, self.status, q[0], q[1], s[0], s[1], c[0], c[1]]
    }

    /// Read wire bytes (any 8 bytes are a telegram; the checks decide whether it is valid).
    pub fn from_bytes(b: [u8; Self::LEN]) -> Self {
        Telegram {
            data: b[0],
            status: b[1],
            seq: u16::from_le_bytes([b[2], b[3]]),
            sender: u16::from_le_bytes([b[4], b[5]]),
            crc: u16::from_le_bytes([b[6], b[7]]),
        }
    }
}

/// The sequence number after `n`: 1..=65535, skipping 0.
pub const fn next_seq(n: u16) -> u16 {
    if n == u16::MAX {
        1
    } else {
        n + 1
    }
}

/// A fault to inject into a connection's black channel. Faults act on the partner's replies,
/// except `Drop`, which silences both directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ChannelFault {
    /// Nothing is delivered, either way, for `duration` (the rig's "safe-link-drop").
    Drop {
        /// How long the link is down.
        duration: SimDuration,
    },
    /// The next reply arrives with one CRC bit flipped.
    CorruptCrc,
    /// The next reply is replaced by the reply delivered `age` exchanges earlier (1 = the
    /// previous one); with no such reply yet, it is lost.
    Replay {
        /// How many exchanges back.
        age: u8,
    },
    /// The next reply claims to come from `sender` (a telegram of another connection).
    WrongAddress {
        /// The address it carries.
        sender: u16,
    },
    /// The next reply is all zeros.
    NullTelegram,
}

impl fmt::Display for ChannelFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ChannelFault::Drop { duration } => write!(f, "link dropped for {duration}"),
            ChannelFault::CorruptCrc => f.write_str("corrupted CRC"),
            ChannelFault::Replay { age } => {
                write!(f, "telegram from {age} exchange(s) ago replayed")
            }
            ChannelFault::WrongAddress { sender } => write!(f, "telegram from address {sender}"),
            ChannelFault::NullTelegram => f.write_str("null telegram"),
        }
    }
}

/// The items of a telegram that change from one to the next: sequence number, data and
/// status (or control). The other two follow from the connection: the sender is the
/// sender's address and the CRC is [`Telegram::crc_after`] the connection's address CRC for
/// that direction, so the telegram's bytes are made only when a fault changes or replays them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Payload {
    seq: u16,
    data: u8,
    status: u8,
}

impl Payload {
    /// The wire bytes of the telegram from `sender`, given the CRC of its addresses.
    fn to_bytes(self, sender: u16, addresses: u16) -> [u8; Telegram::LEN] {
        Telegram::with_address_crc(sender, addresses, self.seq, self.data, self.status).to_bytes()
    }
}

/// What the black channel delivers of a reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Carried {
    /// Nothing arrives.
    Lost,
    /// The partner's reply as the partner made it.
    Intact(Payload),
    /// Bytes that a fault changed or put in the reply's place.
    Altered([u8; Telegram::LEN]),
}

/// The untrusted channel between the logic and one partner, with scheduled faults.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
struct BlackChannel {
    scheduled: Vec<(SimTime, ChannelFault)>,
    down_until: Option<SimTime>,
    next_reply_fault: VecDeque<ChannelFault>,
    /// The last [`BlackChannel::HISTORY`] replies carried (for a replay), in a ring: the one
    /// `age` exchanges back (1 = the last) is at `(next + HISTORY - age) % HISTORY`, for
    /// `age` up to `carried`.
    history: [Payload; BlackChannel::HISTORY],
    next: usize,
    carried: usize,
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

    /// Carry a reply of the partner at `sender` (`addresses`: the CRC of the reply's
    /// addresses): applies the next pending reply fault.
    fn carry_reply(&mut self, reply: Payload, sender: u16, addresses: u16) -> Carried {
        let carried = match self.next_reply_fault.pop_front() {
            None => Carried::Intact(reply),
            Some(fault) => self.apply(fault, reply, sender, addresses),
        };
        self.history[self.next % Self::HISTORY] = reply;
        self.next = (self.next + 1) % Self::HISTORY;
        self.carried = (self.carried + 1).min(Self::HISTORY);
        carried
    }

    /// What a reply fault makes of `reply`.
    #[cold]
    fn apply(&self, fault: ChannelFault, reply: Payload, sender: u16, addresses: u16) -> Carried {
        match fault {
            ChannelFault::CorruptCrc => {
                let mut r = reply.to_bytes(sender, addresses);
                r[Telegram::LEN - 1] ^= 0x01;
                Carried::Altered(r)
            }
            ChannelFault::Replay { age } => {
                let age = usize::from(age.max(1));
                if age <= self.carried {
                    let old = self.history[(self.next + Self::HISTORY - age) % Self::HISTORY];
                    Carried::Altered(old.to_bytes(sender, addresses))
                } else {
                    Carried::Lost
                }
            }
            ChannelFault::WrongAddress { sender: claimed } => {
                let mut t = Telegram::from_bytes(reply.to_bytes(sender, addresses));
                t.sender = claimed;
                Carried::Altered(t.to_bytes())
            }
            ChannelFault::NullTelegram => Carried::Altered([0; Telegram::LEN]),
            ChannelFault::Drop { .. } => Carried::Lost,
        }
    }
}

/// The kind of TwinSAFE device at the other end of a connection, with its channel counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum PartnerKind {
    /// KL1904: safe input terminal, 4 safe inputs.
    #[serde(rename = "KL1904")]
    Kl1904,
    /// KL2904: safe output terminal, 4 safe outputs.
    #[serde(rename = "KL2904")]
    Kl2904,
    /// KL6904: another logic terminal, 8 channels each way (§5.3 of the KL6904 manual).
    #[serde(rename = "KL6904")]
    Kl6904,
}

impl PartnerKind {
    /// Safe channels the partner sends to the logic (TwinSAFE-In of the logic).
    pub const fn inputs(self) -> u8 {
        match self {
            PartnerKind::Kl1904 => 4,
            PartnerKind::Kl2904 => 0,
            PartnerKind::Kl6904 => 8,
        }
    }

    /// Safe channels the logic sends to the partner (TwinSAFE-Out of the logic).
    pub const fn outputs(self) -> u8 {
        match self {
            PartnerKind::Kl1904 => 0,
            PartnerKind::Kl2904 => 4,
            PartnerKind::Kl6904 => 8,
        }
    }

    /// The device name, e.g. `KL1904`.
    pub const fn name(self) -> &'static str {
        match self {
            PartnerKind::Kl1904 => "KL1904",
            PartnerKind::Kl2904 => "KL2904",
            PartnerKind::Kl6904 => "KL6904",
        }
    }
}

/// The simulated partner terminal (TwinSAFE slave): it checks the logic's requests, drives its
/// safe outputs from them and answers with its safe inputs.
///
/// The black channel delivers a request as the logic made it or not at all (its faults act
/// on replies), so a request that arrives always comes from the logic's address with the CRC
/// made from the connection's request address CRC: of the partner's checks only the sequence
/// number's can fail, and only it is run (the reference exchange in the tests runs all of
/// them on the bytes, and gives the same results).
#[derive(Clone, Debug, PartialEq, Eq)]
struct Partner {
    watchdog: SimDuration,
    inputs: u8,
    outputs: u8,
    last_seq: u16,
    last_valid: Option<SimTime>,
    faults: u8,
}

impl Partner {
    /// One request at `now` (`None`: lost on the way); the reply, if the partner sends one.
    fn handle(&mut self, now: SimTime, request: Option<Payload>) -> Option<Payload> {
        let mut reply = None;
        if let Some(t) = request {
            let seq_ok =
                self.last_seq == 0 || t.seq == self.last_seq || t.seq == next_seq(self.last_seq);
            if t.seq != 0 && seq_ok {
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
                reply = Some(Payload {
                    seq: t.seq,
                    data: self.inputs,
                    status: self.faults,
                });
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

/// What a connection reported in a scan.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ConnEvent {
    /// A communication error latched; `bit` is the diag bit, `detail` says what was seen.
    Error {
        /// The newly latched bit.
        bit: ConnDiag,
        /// What happened, for the log.
        detail: String,
    },
    /// The first valid reply arrived: the connection runs.
    Running,
    /// The group acknowledged the connection's error (reported by the logic).
    Acknowledged,
}

/// The logic's side of one TwinSAFE connection, with its partner and black channel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Connection {
    logic_address: u16,
    partner_address: u16,
    /// [`address_crc`] of replies (partner to logic). A request needs none: its bytes are
    /// never made (see [`Partner`]).
    reply_crc: u16,
    watchdog: SimDuration,
    seq: u16,
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
        let reply_crc = address_crc(partner_address, logic_address);
        Connection {
            logic_address,
            partner_address,
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

    /// The partner's safe inputs as last set ([`Connection::set_partner_inputs`]).
    pub fn partner_inputs(&self) -> u8 {
        self.partner.inputs
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
        let request = Payload {
            seq: self.seq,
            data,
            status: ctrl,
        };
        let down = self.channel.begin(now);
        let reply = self.partner.handle(now, (!down).then_some(request));
        let reply = match reply {
            Some(r) if !down => self
                .channel
                .carry_reply(r, self.partner_address, self.reply_crc),
            _ => Carried::Lost,
        };
        let valid = match reply {
            Carried::Lost => false,
            // The partner's own reply to this request: not all zeros (its sequence number,
            // this request's, is never 0), from the partner's address, with the CRC made from
            // `reply_crc`, and echoing `self.seq`; every check of `check` passes up to the
            // partner's status, which `accept` looks at.
            Carried::Intact(r) => self.accept(now, r.data, r.status),
            Carried::Altered(bytes) => self.check(now, bytes),
        };
        let since = self.last_valid.unwrap_or(start);
        let silent = now.saturating_duration_since(since);
        let expired = silent > self.watchdog;
        if expired {
            self.watchdog_expired(silent);
        }
        self.cause_active = !valid || expired;
        &self.events
    }

    /// `true` if an exchange at `now` sending `outputs` would go as the last one did: the
    /// partner takes the request, its reply arrives intact and is accepted with nothing new
    /// (no event, no error, the same inputs), so only the sequence numbers, the black
    /// channel's reply history and the times of the last valid telegram move on
    /// ([`Connection::quiet_exchanges`]). That is [`Connection::rests`] and no fault falling
    /// due by `now`.
    pub(crate) fn is_quiet(&self, now: SimTime, outputs: u8) -> bool {
        self.rests(outputs) && self.next_fault_at().is_none_or(|at| at > now)
    }

    /// [`Connection::is_quiet`] apart from time: it checks every branch
    /// [`Connection::exchange`] could take otherwise but a scheduled fault falling due: a
    /// reply fault pending, the link down, an acknowledgement to send, a request the partner
    /// would refuse, the partner's outputs or inputs changing, a partner fault not yet
    /// latched, the first valid reply, a last exchange that failed. A quiet exchange keeps it
    /// true, so it holds until an input or fault changes.
    pub(crate) fn rests(&self, outputs: u8) -> bool {
        let p = &self.partner;
        let ch = &self.channel;
        let sent = if self.fail_safe() { 0 } else { outputs };
        let seq_ok = self.seq != 0
            && (p.last_seq == 0 || self.seq == p.last_seq || self.seq == next_seq(p.last_seq));
        let faults_seen = p.faults & (status::COMM_FAULT | status::WD_FAULT) == 0
            || self.latched.contains(ConnDiag::SLAVE_ERROR);
        self.events.is_empty()
            && self.first_scan.is_some()
            && self.last_valid.is_some()
            && !self.ack_pending
            && !self.cause_active
            && ch.down_until.is_none()
            && ch.next_reply_fault.is_empty()
            && seq_ok
            && p.outputs == sent
            && self.received == p.inputs
            && faults_seen
    }

    /// When the first scheduled fault falls due (it acts at the first exchange at or after
    /// it), if any.
    pub(crate) fn next_fault_at(&self) -> Option<SimTime> {
        self.channel.scheduled.first().map(|&(at, _)| at)
    }

    /// `n` (at least one) exchanges, the last at `last`, when [`Connection::is_quiet`] holds
    /// at each: what [`Connection::exchange`] changes in that case, and nothing else. Each
    /// carries the partner's reply with the next sequence number; the times are the last
    /// one's.
    pub(crate) fn quiet_exchanges(&mut self, last: SimTime, n: u32) {
        let p = &mut self.partner;
        let ch = &mut self.channel;
        let mut seq = self.seq;
        for _ in 0..n {
            p.last_seq = seq;
            let reply = Payload {
                seq,
                data: p.inputs,
                status: p.faults,
            };
            ch.history[ch.next % BlackChannel::HISTORY] = reply;
            ch.next = (ch.next + 1) % BlackChannel::HISTORY;
            ch.carried = (ch.carried + 1).min(BlackChannel::HISTORY);
            seq = next_seq(seq);
        }
        self.seq = seq;
        p.last_valid = Some(last);
        self.last_valid = Some(last);
    }

    /// No valid telegram for `silent`, longer than the watchdog time.
    #[cold]
    fn watchdog_expired(&mut self, silent: SimDuration) {
        self.latch(
            ConnDiag::WATCHDOG,
            format!(
                "no valid telegram for {silent} (watchdog {})",
                self.watchdog
            ),
        );
    }

    /// Check a reply's bytes; `true` if it is valid. Latches the error bits of a bad one.
    #[cold]
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
        self.accept(now, t.data, t.status)
    }

    /// A reply that passed the checks, with the partner's `data` and status bits `flags`:
    /// latch the partner's own faults, take the data and move to the next sequence number.
    /// `true`.
    #[inline]
    fn accept(&mut self, now: SimTime, data: u8, flags: u8) -> bool {
        if flags & (status::COMM_FAULT | status::WD_FAULT) != 0 {
            self.partner_faulted(flags);
        }
        self.seq = next_seq(self.seq);
        self.received = data;
        if self.last_valid.is_none() {
            self.events.push(ConnEvent::Running);
        }
        self.last_valid = Some(now);
        true
    }

    /// The partner reports Comm_Fault or WD_Fault in its status bits `flags`.
    #[cold]
    fn partner_faulted(&mut self, flags: u8) {
        let what = match flags & (status::COMM_FAULT | status::WD_FAULT) {
            status::COMM_FAULT => "Comm_Fault",
            status::WD_FAULT => "WD_Fault",
            _ => "Comm_Fault and WD_Fault",
        };
        self.latch(ConnDiag::SLAVE_ERROR, format!("partner reports {what}"));
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

#[cfg(test)]
mod reference;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_matches_the_fsoe_table_check_values() {
        // docs/safety-logic.md §6.3: t[1] = 0x39B7, t[2] = 0x736E, t[255] = 0x07C1; with a zero
        // initial value the CRC of the single byte b is the table entry t[b].
        assert_eq!(crc16(&[1]), 0x39B7);
        assert_eq!(crc16(&[2]), 0x736E);
        assert_eq!(crc16(&[255]), 0x07C1);
        assert_eq!(crc16(&[]), 0);
    }

    /// The bitwise definition, a bit at a time, as the table must reproduce it.
    fn crc16_bitwise(bytes: &[u8]) -> u16 {
        bytes.iter().fold(0u16, |crc, &b| {
            (0..8).fold(crc ^ (u16::from(b) << 8), |c, _| {
                if c & 0x8000 != 0 {
                    (c << 1) ^ 0x39B7
                } else {
                    c << 1
                }
            })
        })
    }

    #[test]
    fn the_crc_table_gives_the_bitwise_crc() {
        // Every pair of bytes (so every register value meets every byte), then longer
        // telegrams from a simple generator.
        for a in 0..=255u8 {
            for b in 0..=255u8 {
                assert_eq!(crc16(&[a, b]), crc16_bitwise(&[a, b]), "{a:#04x} {b:#04x}");
            }
        }
        let mut x = 0x1234_5678_9abc_def0u64;
        for len in 0..64 {
            let bytes: Vec<u8> = (0..len)
                .map(|_| {
                    x ^= x << 13;
                    x ^= x >> 7;
                    x ^= x << 17;
                    x as u8
                })
                .collect();
            assert_eq!(crc16(&bytes), crc16_bitwise(&bytes), "{bytes:?}");
        }
    }

    #[test]
    fn telegrams_round_trip_and_depend_on_the_receiver() {
        let t = Telegram::new(2, 1, 77, 0b0011, 0);
        assert_eq!(Telegram::from_bytes(t.to_bytes()), t);
        assert_eq!(t.crc, t.crc_for(1));
        assert_ne!(
            t.crc,
            t.crc_for(3),
            "a telegram for another receiver fails the CRC"
        );
    }

    proptest::proptest! {
        /// The CRC with the addresses folded in beforehand is the CRC over all eight bytes
        /// in their order (the definition), and differs from it only by where it starts.
        #[test]
        fn the_address_crc_gives_the_whole_telegram_crc(
            sender: u16, receiver: u16, seq: u16, data: u8, status: u8,
        ) {
            let s = sender.to_le_bytes();
            let r = receiver.to_le_bytes();
            let q = seq.to_le_bytes();
            let whole = crc16_bitwise(&[s[0], s[1], r[0], r[1], q[0], q[1], data, status]);
            let t = Telegram::new(sender, receiver, seq, data, status);
            proptest::prop_assert_eq!(t.crc, whole);
            proptest::prop_assert_eq!(t.crc_for(receiver), whole);
            proptest::prop_assert_eq!(t.crc_after(address_crc(sender, receiver)), whole);
            proptest::prop_assert_eq!(
                crc16_continue(crc16(&[s[0], s[1]]), &[r[0], r[1], q[0], q[1], data, status]),
                whole
            );
        }
    }

    /// `BlackChannel::begin` as written first: the due faults looked for at every exchange.
    fn begin_looking_every_time(c: &mut BlackChannel, now: SimTime) -> bool {
        let due = c.scheduled.partition_point(|(t, _)| *t <= now);
        for (at, fault) in c.scheduled.drain(..due) {
            match fault {
                ChannelFault::Drop { duration } => {
                    let until = at + duration;
                    c.down_until = Some(c.down_until.map_or(until, |u| u.max(until)));
                }
                other => c.next_reply_fault.push_back(other),
            }
        }
        match c.down_until {
            Some(until) if now < until => true,
            _ => {
                c.down_until = None;
                false
            }
        }
    }

    fn channel_fault() -> impl proptest::strategy::Strategy<Value = ChannelFault> {
        use proptest::prelude::*;
        prop_oneof![
            (0..20u64).prop_map(|ms| ChannelFault::Drop {
                duration: SimDuration::from_millis(ms)
            }),
            Just(ChannelFault::CorruptCrc),
            (0..4u8).prop_map(|age| ChannelFault::Replay { age }),
            Just(ChannelFault::NullTelegram),
        ]
    }

    proptest::proptest! {
        /// Looking at the first scheduled fault only (the schedule is in time order) takes
        /// the same faults at the same exchanges as searching the schedule every time.
        #[test]
        fn an_exchange_takes_the_faults_due_whether_or_not_it_searches(
            faults in proptest::collection::vec((0..60u64, channel_fault()), 0..8),
            steps in proptest::collection::vec(0..4u64, 0..60),
        ) {
            let mut fast = BlackChannel::default();
            for &(ms, fault) in &faults {
                fast.schedule(SimTime::from_millis(ms), fault);
            }
            let mut full = fast.clone();
            let mut ms = 0;
            for dt in steps {
                ms += dt;
                let now = SimTime::from_millis(ms);
                proptest::prop_assert_eq!(fast.begin(now), begin_looking_every_time(&mut full, now));
                proptest::prop_assert_eq!(&fast, &full);
            }
        }
    }

    #[test]
    fn a_connection_keeps_the_crc_of_its_replies_addresses() {
        let c = Connection::new(1, 2, SimDuration::from_millis(100));
        assert_eq!(c.reply_crc, address_crc(2, 1));
        assert_ne!(c.reply_crc, address_crc(1, 2), "the two directions differ");
    }

    /// One step of a connection's life in the property test below.
    #[derive(Clone, Debug)]
    enum Step {
        /// An exchange `dt_ms` after the previous one, with these partner inputs and outputs.
        Exchange { dt_ms: u64, inputs: u8, outputs: u8 },
        /// A fault on the black channel, `in_ms` from the last exchange.
        Fault { in_ms: u64, fault: ChannelFault },
        /// The group's ERR_ACK.
        Acknowledge,
    }

    fn step() -> impl proptest::strategy::Strategy<Value = Step> {
        use proptest::prelude::*;
        let fault = prop_oneof![
            (0..300u64).prop_map(|ms| ChannelFault::Drop {
                duration: SimDuration::from_millis(ms)
            }),
            Just(ChannelFault::CorruptCrc),
            (0..20u8).prop_map(|age| ChannelFault::Replay { age }),
            (1..5u16).prop_map(|sender| ChannelFault::WrongAddress { sender }),
            Just(ChannelFault::NullTelegram),
        ];
        prop_oneof![
            8 => (prop_oneof![3 => 0..3u64, 1 => 0..150u64], any::<u8>(), any::<u8>())
                .prop_map(|(dt_ms, inputs, outputs)| Step::Exchange { dt_ms, inputs, outputs }),
            2 => (0..20u64, fault).prop_map(|(in_ms, fault)| Step::Fault { in_ms, fault }),
            1 => Just(Step::Acknowledge),
        ]
    }

    proptest::proptest! {
        /// The exchange on payloads, which makes a telegram's bytes only for a fault, gives
        /// what the exchange on bytes gives (the reference, as first written): the same
        /// events, inputs, diag byte, error cause and partner outputs after every step, under
        /// every kind of channel fault, across the sequence number's wrap.
        #[test]
        fn the_exchange_on_payloads_is_the_exchange_on_bytes(
            first_seq in proptest::prop_oneof![proptest::strategy::Just(1u16), 65_500..=u16::MAX],
            steps in proptest::collection::vec(step(), 0..400),
        ) {
            let watchdog = SimDuration::from_millis(100);
            let mut fast = Connection::new(1, 3, watchdog);
            let mut bytes = reference::Connection::new(1, 3, watchdog);
            fast.seq = first_seq;
            bytes.seq = first_seq;
            let mut now = SimTime::from_millis(5);
            for step in steps {
                match step {
                    Step::Exchange { dt_ms, inputs, outputs } => {
                        now += SimDuration::from_millis(dt_ms);
                        fast.set_partner_inputs(inputs);
                        bytes.set_partner_inputs(inputs);
                        let a = fast.exchange(now, outputs).to_vec();
                        let b = bytes.exchange(now, outputs).to_vec();
                        proptest::prop_assert_eq!(a, b);
                    }
                    Step::Fault { in_ms, fault } => {
                        let at = now + SimDuration::from_millis(in_ms);
                        fast.inject(at, fault);
                        bytes.inject(at, fault);
                    }
                    Step::Acknowledge => {
                        fast.acknowledge();
                        bytes.acknowledge();
                    }
                }
                proptest::prop_assert_eq!(fast.inputs(), bytes.inputs());
                proptest::prop_assert_eq!(fast.diag(), bytes.diag());
                proptest::prop_assert_eq!(fast.has_error(), bytes.has_error());
                proptest::prop_assert_eq!(fast.error_cause_active(), bytes.error_cause_active());
                proptest::prop_assert_eq!(fast.partner_outputs(), bytes.partner_outputs());
                proptest::prop_assert_eq!(fast.seq, bytes.seq);
            }
        }
    }

    #[test]
    fn sequence_numbers_skip_zero() {
        assert_eq!(next_seq(1), 2);
        assert_eq!(next_seq(u16::MAX), 1);
    }

    #[test]
    fn diag_names_the_bits() {
        let d = ConnDiag::WATCHDOG | ConnDiag::FAIL_SAFE_VALUES;
        assert_eq!(d.to_string(), "0x84 (watchdog expired, fail-safe values)");
        assert!(d.is_error());
        assert!(!ConnDiag::FAIL_SAFE_VALUES.is_error());
    }
}
