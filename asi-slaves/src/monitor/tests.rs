//! The Safety-at-Work monitor's tests.

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
    /// mostly every few transactions as on the bus. On the way, [`SafetyMonitor::releases`]
    /// tells what `released` and `has_drops` tell.
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
            // The one look at every channel is the look at each.
            let each = addresses
                .iter()
                .fold(0u32, |m, &a| m | u32::from(fast.released(a)) << a.get());
            proptest::prop_assert_eq!(fast.releases(), (each, fast.has_drops()));
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
        let mut fast = taught_or_not(taught);
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

/// The lab's monitor of addresses 11 and 12, with each address's table given (`taught`) or
/// still to be taught.
fn taught_or_not(taught: bool) -> SafetyMonitor {
    let addresses = [Address::new(11).expect("a"), Address::new(12).expect("a")];
    let timing = asi_phy::BusTiming::default();
    let mut m = SafetyMonitor::new(&timing, MonitorConfig::default(), &addresses);
    if taught {
        for a in addresses {
            m.set_table(a, CodeTable::from_serial(u64::from(a.get())));
        }
    }
    m
}

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

proptest::proptest! {
    #![proptest_config(proptest::test_runner::Config::with_cases(1_000))]

    /// A clean telegram handed over as the request or response itself
    /// ([`Heard::Request`], [`Heard::Response`]) leaves the
    /// monitor as the same telegram handed over as the valid [`Received`] a receiver makes of
    /// it ([`Heard::Received`]): any request (often a Data_Exchange to a monitored
    /// slave), answers with the codes in turn, wrong codes, no answer, at gaps around the
    /// tolerance, taught or teaching.
    #[test]
    fn clean_telegrams_are_judged_as_the_received_ones(
        steps in proptest::collection::vec(
            (
                proptest::prop_oneof![
                    2 => (0u16..1 << 11).prop_map(Some),
                    // Data_Exchange (CB 0, I4 0) to 11 or 12.
                    4 => (11u16..13, 0u16..16).prop_map(|(a, d)| Some(a << 5 | d)),
                    1 => proptest::strategy::Just(None),
                ],
                proptest::prop_oneof![
                    3 => proptest::strategy::Just(None),
                    1 => (0u8..16).prop_map(Some),
                ],
                proptest::prop_oneof![8 => 154_000..3_000_000u64, 1 => 3_000_000..100_000_000u64],
            ),
            1..300,
        ),
        taught in proptest::prelude::any::<bool>(),
    ) {
        let mut clean = taught_or_not(taught);
        let mut received = clean.clone();
        let tables = [CodeTable::from_serial(11).codes(), CodeTable::from_serial(12).codes()];
        let mut next = [0usize; 2];
        let mut now = 0u64;
        let valid = |kind, raw: u32, bit_count, t| Received {
            kind,
            start: t,
            end: t,
            pulses: 0,
            bit_count,
            raw,
            failed: asi_phy::Checks::NONE,
        };
        for (body, wrong, gap) in steps {
            now += gap;
            let t = at(now);
            let mut to = None;
            if let Some(body) = body {
                let a = Address::new((body >> 5 & 0x1F) as u8).expect("an address");
                let q = Request::from_fields(body & 0x400 != 0, a, (body & 0x1F) as u8)
                    .expect("a request");
                clean.hear(t, Heard::Request(q));
                received.hear(
                    t,
                    Heard::Received(&valid(TelegramKind::Request, u32::from(q.bits()), 14, t)),
                );
                to = usize::from(a.get()).checked_sub(11).filter(|&i| i < 2);
            }
            let code = match (wrong, to) {
                (Some(c), _) => c,
                (None, Some(i)) => {
                    next[i] = (next[i] + 1) % 8;
                    tables[i][next[i]]
                }
                (None, None) => 0b0110,
            };
            let r = Response::new(asi_phy::Nibble::from_low_bits(code));
            let t = at(now + 100_000);
            clean.hear(t, Heard::Response(r));
            received.hear(
                t,
                Heard::Received(&valid(TelegramKind::Response, u32::from(r.bits()), 7, t)),
            );
            clean.poll(t);
            received.poll(t);
            proptest::prop_assert!(clean == received, "{:?}\n{:?}", clean, received);
        }
    }
}

/// [`SafetyMonitor::releases`] as it was: one look at every channel.
fn releases_by_channels(m: &SafetyMonitor) -> (u32, bool) {
    m.channels.iter().fold((0, false), |(mask, drops), c| {
        (
            mask | u32::from(c.released) << c.address.get(),
            drops || !c.drops.is_empty(),
        )
    })
}

proptest::proptest! {
    #![proptest_config(proptest::test_runner::Config::with_cases(500))]

    /// The releases kept as the channels change are those one look at the channels finds,
    /// after every telegram, poll, taking of the drops, table given and reteaching: codes in
    /// turn (the channel released, or kept), wrong codes and 0000 (released dropped), silence
    /// beyond the tolerance, taught or teaching.
    #[test]
    fn the_kept_releases_are_the_channels_releases(
        steps in proptest::collection::vec(
            (
                0u8..3,
                proptest::prop_oneof![
                    12 => proptest::strategy::Just(None),
                    2 => (0u8..16).prop_map(Some),
                    1 => proptest::strategy::Just(Some(0)),
                ],
                proptest::prop_oneof![8 => 154_000..3_000_000u64, 1 => 3_000_000..100_000_000u64],
                0u8..40,
            ),
            1..400,
        ),
        taught in proptest::prelude::any::<bool>(),
    ) {
        let mut m = taught_or_not(taught);
        let tables = [CodeTable::from_serial(11).codes(), CodeTable::from_serial(12).codes()];
        let mut next = [0usize; 2];
        let mut now = 0u64;
        for (to, wrong, gap, other) in steps {
            now += gap;
            let t = at(now);
            // A Data_Exchange to 11 or 12, or to an address not monitored.
            let a = Address::new([11, 12, 3][usize::from(to)]).expect("an address");
            let q = Request::data_exchange(a, asi_phy::Nibble::ZERO).expect("a request");
            m.hear(t, Heard::Request(q));
            let code = match (wrong, usize::from(to)) {
                (Some(c), _) => c,
                (None, i) if i < 2 => {
                    next[i] = (next[i] + 1) % 8;
                    tables[i][next[i]]
                }
                _ => 0b0110,
            };
            let r = Response::new(asi_phy::Nibble::from_low_bits(code));
            m.hear(at(now + 100_000), Heard::Response(r));
            m.poll(at(now + 100_000));
            match other {
                0..=4 => {
                    m.take_drops();
                }
                5 => m.reteach(),
                6 => m.set_table(Address::new(11).expect("11"), CodeTable::from_serial(11)),
                _ => {}
            }
            let kept = m.looks;
            proptest::prop_assert_eq!(kept, releases_by_channels(&m));
            proptest::prop_assert_eq!(m.releases(), kept);
        }
    }
}
