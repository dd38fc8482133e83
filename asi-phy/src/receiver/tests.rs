use super::*;
use crate::manchester::HalfBits;
use crate::pulse::Polarity;
use crate::pulse::PulseTrain;
use crate::telegram::{Address, Nibble};
use crate::time::SimDuration;
use crate::timing::BusTiming;

fn timing() -> BusTiming {
    BusTiming::default()
}

fn rx(expect: Expect) -> Receiver {
    Receiver::new(timing().receiver(expect))
}

fn train(req: Request, at_us: u64) -> PulseTrain {
    PulseTrain::request(req, SimTime::from_micros(at_us), timing().half_bit())
}

fn dexg(a: u8, d: u8) -> Request {
    Request::data_exchange(Address::new(a).expect("addr"), Nibble::from_low_bits(d)).expect("valid")
}

fn pulses(spec: &str, start_us: u64) -> Vec<Pulse> {
    spec.split_whitespace()
        .map(|tok| {
            let (k, s) = tok.split_at(tok.len() - 1);
            let k: f64 = k.parse().expect("grid point");
            let pol = if s == "+" {
                Polarity::Positive
            } else {
                Polarity::Negative
            };
            Pulse::new(
                SimTime::from_nanos(start_us * 1000 + (3000.0 * k) as u64),
                pol,
            )
        })
        .collect()
}

#[test]
fn decodes_the_spec_vectors() {
    let mut r = rx(Expect::Requests);
    let got: Vec<Received> = r.decode(train(dexg(5, 0b1010), 0)).collect();
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].request(), Some(dexg(5, 0b1010)));
    let mut r = rx(Expect::Responses);
    let got: Vec<Received> = r
        .decode(pulses("0- 1+ 2- 3+ 5- 6+ 7- 9+ 10- 11+ 13- 14+", 0))
        .collect();
    assert_eq!(
        got[0].response().map(|r| r.data()),
        Some(Nibble::from_low_bits(0b0110))
    );
}

#[test]
fn a_telegram_completes_after_the_pause() {
    let mut r = rx(Expect::Requests);
    for p in train(dexg(3, 1), 0) {
        assert_eq!(r.push(p), None);
    }
    assert_eq!(r.poll_at(), Some(SimTime::from_micros(84 + 9)));
    assert_eq!(r.poll(SimTime::from_micros(92)), None);
    let got = r.poll(SimTime::from_micros(93)).expect("complete");
    assert_eq!(got.request(), Some(dexg(3, 1)));
    assert_eq!(
        (got.start, got.end),
        (SimTime::ZERO, SimTime::from_micros(84))
    );
    assert!(r.is_synchronised());
}

/// One hand-made broken telegram per check, the class it must get.
#[test]
fn each_check_has_its_class() {
    let cases = [
        // Response 0000 with the start pulse positive.
        (
            "0+ 1- 2+ 3- 4+ 5- 6+ 7- 8+ 9- 10+ 11- 13+ 14-",
            Check::StartBit,
        ),
        // 0110 with pulse 6+ flipped.
        (
            "0- 1+ 2- 3+ 5- 6- 7- 9+ 10- 11+ 13- 14+",
            Check::Alternation,
        ),
        // 0000 with pulse 10- half a grid step late.
        (
            "0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 10.5- 11+ 13- 14+",
            Check::Pause,
        ),
        // 0000 with the mid pulse of cell 5 moved to the free boundary after it.
        (
            "0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 10- 12+ 13- 14+",
            Check::Information,
        ),
        // 0000 with PB = 1: 0 0000 1 1.
        (
            "0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 11- 12+ 13- 14+",
            Check::Parity,
        ),
        // 0 0000 0 0 then idle: no end bit 1.
        (
            "0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 10- 11+ 12- 13+",
            Check::EndBit,
        ),
        // Six bits: 0 0000 1 (a response without its last bit).
        ("0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 11- 12+", Check::Length),
    ];
    for (spec, check) in cases {
        let mut r = rx(Expect::Responses);
        let got: Vec<Received> = r.decode(pulses(spec, 0)).collect();
        assert_eq!(got.len(), 1, "{spec}");
        assert_eq!(got[0].primary(), Some(check), "{spec}: {:?}", got[0]);
    }
}

#[test]
fn a_missing_return_to_idle_is_an_end_bit_error() {
    // Response 0000 without its final positive pulse: the line stays low.
    let mut r = rx(Expect::Responses);
    let got: Vec<Received> = r
        .decode(pulses("0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 10- 11+ 13-", 0))
        .collect();
    assert_eq!(got[0].failed, Checks::only(Check::EndBit));
}

#[test]
fn jitter_within_tolerance_is_accepted_and_beyond_is_a_pause_error() {
    let mut p: Vec<Pulse> = train(dexg(9, 6), 0).iter().collect();
    for (i, x) in p.iter_mut().enumerate() {
        x.at = if i % 2 == 0 {
            x.at + SimDuration::from_nanos(500)
        } else {
            x.at - SimDuration::from_nanos(0)
        };
    }
    p[0].at = SimTime::ZERO;
    let got: Vec<Received> = rx(Expect::Requests).decode(p.clone()).collect();
    assert_eq!(got[0].request(), Some(dexg(9, 6)));
    p[5].at += SimDuration::from_nanos(501);
    let got: Vec<Received> = rx(Expect::Requests).decode(p).collect();
    assert_eq!(got[0].failed, Checks::only(Check::Pause));
}

#[test]
fn after_an_error_the_next_request_needs_the_asynchronous_pause() {
    let mut r = rx(Expect::Requests);
    let mut bad: Vec<Pulse> = train(dexg(4, 0), 0).iter().collect();
    bad[4].polarity = bad[4].polarity.flipped();
    let good_soon = train(dexg(4, 0), 84 + 10);
    let good_later = train(dexg(4, 0), 84 + 10 + 84 + 18);
    let got: Vec<Received> = r
        .decode(bad.into_iter().chain(good_soon).chain(good_later))
        .collect();
    assert_eq!(got.len(), 3);
    assert!(got[0].failed.contains(Check::Alternation));
    assert_eq!(
        got[1].failed,
        Checks::only(Check::Pause),
        "10 µs after an error is too soon"
    );
    assert_eq!(
        got[2].request(),
        Some(dexg(4, 0)),
        "18 µs after an error is enough"
    );
}

#[test]
fn on_a_live_bus_the_reply_to_a_valid_request_is_a_response() {
    let t = timing();
    let req = train(dexg(4, 0), 0);
    let resp = PulseTrain::response(
        Response::new(Nibble::from_low_bits(5)),
        SimTime::from_micros(102),
        t.half_bit(),
    );
    let next = train(dexg(5, 0), 154);
    let mut r = rx(Expect::Both);
    let got: Vec<Received> = r.decode(req.into_iter().chain(resp).chain(next)).collect();
    let kinds: Vec<_> = got.iter().map(|g| (g.kind, g.is_valid())).collect();
    assert_eq!(
        kinds,
        [
            (TelegramKind::Request, true),
            (TelegramKind::Response, true),
            (TelegramKind::Request, true)
        ]
    );
    assert_eq!(got[1].response().map(|r| r.data().get()), Some(5));
}

/// The constant-time path for encoded trains gives exactly what pulse-by-pulse decoding
/// gives, for every request and response, back to back and overlapping.
#[test]
fn push_train_equals_pushing_each_pulse() {
    let h = timing().half_bit();
    let mut trains = Vec::new();
    let mut t = 0u64;
    for body in 0u16..1 << 11 {
        let bits = (body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1;
        let req = Request::from_bits(bits).expect("valid");
        trains.push(PulseTrain::request(req, SimTime::from_micros(t), h));
        let resp = Response::new(Nibble::from_low_bits(body as u8));
        trains.push(PulseTrain::response(resp, SimTime::from_micros(t + 102), h));
        // Every 7th gap is too short, every 11th train overlaps its predecessor.
        t += match body % 77 {
            0 => 150,
            b if b % 11 == 0 => 60,
            b if b % 7 == 0 => 146,
            _ => 154,
        };
    }
    for expect in [Expect::Requests, Expect::Responses, Expect::Both] {
        let mut fast = rx(expect);
        let mut slow = rx(expect);
        let mut a = Vec::new();
        let mut b = Vec::new();
        for tr in &trains {
            a.extend(fast.push_train(tr));
            for p in tr.iter() {
                b.extend(slow.push(p));
            }
        }
        a.extend(fast.flush());
        b.extend(slow.flush());
        assert_eq!(a, b, "{expect:?}");
    }
}

#[test]
fn a_train_whose_first_pulse_is_not_at_its_start_is_decoded_from_its_first_pulse() {
    // 1 0 0 ... : the line is high in the first half-cell, so the first pulse is at point 1.
    let levels = HalfBits::encode(0b10_0000_0000_0001, 14);
    let train = PulseTrain::from_half_bits(levels, SimTime::from_micros(30), timing().half_bit());
    assert!(train.pulse_at(0).is_none());
    let mut fast = rx(Expect::Requests);
    let a: Vec<Received> = fast
        .push_train(&train)
        .into_iter()
        .chain(fast.flush())
        .collect();
    let b: Vec<Received> = rx(Expect::Requests).decode(train).collect();
    assert_eq!(a, b);
    assert!(!b[0].is_valid());
}

#[test]
fn odd_inputs_never_panic() {
    let mut r = rx(Expect::Both);
    let wild = [
        Pulse::new(SimTime::MAX, Polarity::Positive),
        Pulse::new(SimTime::ZERO, Polarity::Positive),
        Pulse::new(SimTime::ZERO, Polarity::Positive),
        Pulse::new(SimTime::from_nanos(1), Polarity::Negative),
        Pulse::new(SimTime::MAX, Polarity::Negative),
    ];
    let got: Vec<Received> = r.decode(wild).collect();
    assert!(got.iter().all(|g| !g.is_valid()));
    // A run far longer than any telegram.
    let long = (0..10_000u64).map(|k| {
        Pulse::new(
            SimTime::from_micros(3 * k),
            if k % 2 == 0 {
                Polarity::Negative
            } else {
                Polarity::Positive
            },
        )
    });
    let got: Vec<Received> = rx(Expect::Requests).decode(long).collect();
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].bit_count, 5000);
    assert!(got[0].failed.contains(Check::Length));
}

/// The equivalence of the fast line decoder with the one it replaced (`reference.rs`): random
/// pulse sequences, cut and fed in random ways, give the same frames, the same telegrams and
/// the same state (`poll_at`) after every step.
pub(super) mod equivalence {
    use super::super::reference::ReferenceLineDecoder;
    use super::*;
    use proptest::prelude::*;

    /// Settings: the bus's own, and odd ones (a tolerance at or past half the grid, a grid of
    /// 1 ns, a pause shorter than the grid).
    fn config() -> impl Strategy<Value = ReceiverConfig> {
        let odd = (
            1u64..8_000,
            0u64..5_000,
            1u64..40_000,
            0u64..40_000,
            0u64..100_000,
        )
            .prop_map(
                |(half_bit, tolerance, pause, async_pause, response_window)| ReceiverConfig {
                    half_bit,
                    tolerance,
                    pause,
                    async_pause,
                    response_window,
                    expect: Expect::Both,
                },
            );
        (
            prop_oneof![
                4 => Just(timing().receiver(Expect::Both)),
                1 => Just(ReceiverConfig { half_bit: 1, tolerance: 0, pause: 2, ..timing().receiver(Expect::Both) }),
                2 => odd,
            ],
            prop_oneof![
                Just(Expect::Requests),
                Just(Expect::Responses),
                Just(Expect::Both)
            ],
        )
            .prop_map(|(cfg, expect)| ReceiverConfig { expect, ..cfg })
    }

    /// One fault on an encoded pulse sequence.
    #[derive(Clone, Debug)]
    enum Fault {
        Drop(usize),
        Insert(usize, i64, bool),
        Shift(usize, i64),
        Flip(usize),
        Truncate(usize),
        Gap(usize, u64),
        BackInTime(usize, u64),
    }

    fn fault() -> impl Strategy<Value = Fault> {
        let shift = prop_oneof![
            3 => -600i64..=600,
            2 => -3_500i64..=3_500,
            1 => -40_000i64..=40_000,
        ];
        prop_oneof![
            (any::<usize>()).prop_map(Fault::Drop),
            (any::<usize>(), -6_000i64..6_000, any::<bool>())
                .prop_map(|(i, d, p)| Fault::Insert(i, d, p)),
            (any::<usize>(), shift).prop_map(|(i, d)| Fault::Shift(i, d)),
            (any::<usize>()).prop_map(Fault::Flip),
            (any::<usize>()).prop_map(Fault::Truncate),
            (
                any::<usize>(),
                prop_oneof![0u64..60_000, any::<u64>().prop_map(|g| g >> 8)]
            )
                .prop_map(|(i, g)| Fault::Gap(i, g)),
            (any::<usize>(), 0u64..200_000).prop_map(|(i, d)| Fault::BackInTime(i, d)),
        ]
    }

    fn polarity(positive: bool) -> Polarity {
        if positive {
            Polarity::Positive
        } else {
            Polarity::Negative
        }
    }

    /// Encoded requests and responses back to back with random gaps, then faults.
    fn faulty_line() -> impl Strategy<Value = Vec<Pulse>> {
        let telegram = (
            any::<bool>(),
            any::<u16>(),
            prop_oneof![
                4 => Just(18_000u64),
                4 => Just(10_000u64),
                2 => 0u64..30_000,
                1 => 0u64..2_000_000,
            ],
        );
        (
            prop::collection::vec(telegram, 0..12),
            prop::collection::vec(fault(), 0..8),
            prop_oneof![Just(0u64), Just(1u64 << 40), Just(u64::MAX - (1 << 30))],
        )
            .prop_map(|(telegrams, faults, origin)| {
                let h = timing().half_bit();
                let mut pulses: Vec<Pulse> = Vec::new();
                let mut t = origin;
                for (is_request, bits, gap) in telegrams {
                    let train = if is_request {
                        let body = bits & 0x7FF;
                        let bits = (body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1;
                        // Every request, and now and then one with a wrong bit.
                        let bits = if bits & 0x8000 != 0 {
                            bits ^ 0x10
                        } else {
                            bits
                        };
                        PulseTrain::request(
                            Request::from_bits(bits & 0x3FFF).unwrap_or(dexg(1, 0)),
                            SimTime::from_nanos(t),
                            h,
                        )
                    } else {
                        PulseTrain::response(
                            Response::new(Nibble::from_low_bits(bits as u8)),
                            SimTime::from_nanos(t),
                            h,
                        )
                    };
                    pulses.extend(train.iter());
                    t = train.end().as_nanos().saturating_add(gap);
                }
                for f in faults {
                    let n = pulses.len();
                    match f {
                        Fault::Drop(i) if n > 0 => {
                            pulses.remove(i % n);
                        }
                        Fault::Insert(i, d, p) => {
                            let i = if n == 0 { 0 } else { i % (n + 1) };
                            let base = pulses
                                .get(i.min(n.saturating_sub(1)))
                                .map_or(t, |p| p.at.as_nanos());
                            let at = SimTime::from_nanos(base.saturating_add_signed(d));
                            pulses.insert(i, Pulse::new(at, polarity(p)));
                        }
                        Fault::Shift(i, d) if n > 0 => {
                            let p = &mut pulses[i % n];
                            p.at = SimTime::from_nanos(p.at.as_nanos().saturating_add_signed(d));
                        }
                        Fault::Flip(i) if n > 0 => {
                            let p = &mut pulses[i % n];
                            p.polarity = p.polarity.flipped();
                        }
                        Fault::Truncate(i) if n > 0 => pulses.truncate(i % n),
                        Fault::Gap(i, g) if n > 0 => {
                            for p in &mut pulses[i % n..] {
                                p.at = SimTime::from_nanos(p.at.as_nanos().saturating_add(g));
                            }
                        }
                        Fault::BackInTime(i, d) if n > 0 => {
                            for p in &mut pulses[i % n..] {
                                p.at = SimTime::from_nanos(p.at.as_nanos().saturating_sub(d));
                            }
                        }
                        _ => {}
                    }
                }
                pulses
            })
    }

    /// Pulses at arbitrary times: near the grid, anywhere, back in time, at the clock's ends.
    fn wild_line() -> impl Strategy<Value = Vec<Pulse>> {
        let step = prop_oneof![
            3 => (2_500u64..3_500).prop_map(|d| d as i64),
            2 => (5_500u64..6_500).prop_map(|d| d as i64),
            1 => Just(3_000i64),
            1 => Just(6_000i64),
            1 => (0u64..40_000).prop_map(|d| d as i64),
            1 => -5_000i64..0,
            1 => any::<i64>(),
        ];
        (
            prop::collection::vec((step, any::<bool>()), 0..200),
            prop_oneof![
                Just(0u64),
                Just(1u64 << 40),
                Just(u64::MAX - 100_000),
                any::<u64>()
            ],
        )
            .prop_map(|(steps, origin)| {
                let mut t = origin;
                steps
                    .into_iter()
                    .map(|(d, p)| {
                        t = t.saturating_add_signed(d);
                        Pulse::new(SimTime::from_nanos(t), polarity(p))
                    })
                    .collect()
            })
    }

    /// Settings on the borders of the fast scan's conditions (see `Grid::recip` in `line.rs`):
    /// a tolerance at zero, just under, at and over half the grid; a pause just under, at and
    /// over two half-bits plus twice the tolerance; the largest grid the scan takes and the
    /// next one; and the bus's own.
    pub(in crate::receiver) fn border_config() -> impl Strategy<Value = ReceiverConfig> {
        let bordered = (
            prop_oneof![
                2 => Just(3_000u64),
                1 => 1u64..10,
                2 => 10u64..8_000,
                1 => Just(1u64 << 24),
                1 => Just((1u64 << 24) + 1),
            ],
            0u32..6,
            -2i64..=2,
            0u64..40_000,
            0u64..100_000,
        )
            .prop_map(|(h, t, dp, async_pause, response_window)| {
                let tolerance = match t {
                    0 => 0,
                    1 => (h / 2).saturating_sub(1),
                    2 => (h - 1) / 2,
                    3 => h / 2,
                    4 => h.div_ceil(2),
                    _ => h / 6,
                };
                ReceiverConfig {
                    half_bit: h,
                    tolerance,
                    pause: (2 * h + 2 * tolerance).saturating_add_signed(dp).max(1),
                    async_pause,
                    response_window,
                    expect: Expect::Both,
                }
            });
        (
            prop_oneof![
                1 => Just(timing().receiver(Expect::Both)),
                4 => bordered,
            ],
            prop_oneof![
                Just(Expect::Requests),
                Just(Expect::Responses),
                Just(Expect::Both)
            ],
        )
            .prop_map(|(cfg, expect)| ReceiverConfig { expect, ..cfg })
    }

    /// Runs of pulses on the grid anchored at each run's first pulse, as the receiver places
    /// them: mostly one or two grid points apart and alternating, each off its grid point by
    /// nothing, by exactly the tolerance, by one more, or at random; now and then a pulse on
    /// the same point, three or more points on, or with the last one's sign; runs longer than
    /// the masks; each next run just under, at or over the pause after the last pulse, or
    /// later. Times wrap past the clock's end where the origin is near it.
    pub(in crate::receiver) fn grid_line(cfg: ReceiverConfig) -> impl Strategy<Value = Vec<Pulse>> {
        let h = cfg.half_bit;
        let tol = cfg.tolerance as i64;
        let pause = cfg.pause;
        let pulse = (
            prop_oneof![
                12 => Just(1u64),
                6 => Just(2u64),
                1 => Just(0u64),
                1 => Just(3u64),
                1 => 4u64..40,
            ],
            prop_oneof![
                6 => Just(0i64),
                2 => Just(tol),
                2 => Just(-tol),
                1 => Just(tol + 1),
                1 => Just(-tol - 1),
                3 => -tol..=tol,
                1 => any::<i64>().prop_map(move |d| d % (2 * h as i64 + 1)),
            ],
            prop_oneof![24 => Just(false), 1 => Just(true)],
        );
        let run = (
            prop_oneof![
                4 => prop::collection::vec(pulse.clone(), 0..30),
                1 => prop::collection::vec(pulse, 30..90),
            ],
            prop_oneof![6 => Just(false), 1 => Just(true)],
            prop_oneof![
                1 => Just(-1i64),
                1 => Just(0i64),
                1 => Just(1i64),
                2 => 0i64..(3 * pause.min(1 << 40)) as i64,
            ],
        );
        (
            prop::collection::vec(run, 1..10),
            prop_oneof![
                Just(0u64),
                Just(1u64 << 40),
                Just(u64::MAX - 200_000),
                any::<u64>()
            ],
        )
            .prop_map(move |(runs, origin)| {
                let mut pulses = Vec::new();
                let mut start = origin;
                for (rest, first_positive, gap) in runs {
                    let mut positive = first_positive;
                    pulses.push(Pulse::new(SimTime::from_nanos(start), polarity(positive)));
                    let mut last = start;
                    let mut g = 0u64;
                    for (step, dev, same_sign) in rest {
                        g += step;
                        positive ^= !same_sign;
                        last = start
                            .wrapping_add(g.wrapping_mul(h))
                            .wrapping_add_signed(dev);
                        pulses.push(Pulse::new(SimTime::from_nanos(last), polarity(positive)));
                    }
                    start = last.wrapping_add(pause).wrapping_add_signed(gap);
                }
                pulses
            })
    }

    /// How the pulses reach the decoder.
    #[derive(Clone, Debug)]
    enum Feed {
        Slice(usize),
        One,
        Poll(u64),
        Flush,
        Reset,
    }

    fn feeds() -> impl Strategy<Value = Vec<Feed>> {
        prop::collection::vec(
            prop_oneof![
                6 => (1usize..64).prop_map(Feed::Slice),
                2 => (64usize..400).prop_map(Feed::Slice),
                3 => Just(Feed::One),
                1 => (0u64..40_000).prop_map(Feed::Poll),
                1 => Just(Feed::Flush),
                1 => Just(Feed::Reset),
            ],
            1..40,
        )
    }

    fn check_feeds(
        cfg: ReceiverConfig,
        pulses: &[Pulse],
        feeds: &[Feed],
    ) -> Result<(), TestCaseError> {
        let mut fast = LineDecoder::new(&cfg);
        let mut slow = ReferenceLineDecoder::new(&cfg);
        let mut rest = pulses;
        let mut step = 0;
        while !rest.is_empty() {
            let feed = &feeds[step % feeds.len()];
            step += 1;
            let (mut a, mut b) = (Vec::new(), Vec::new());
            match feed {
                Feed::Slice(n) => {
                    let (now, later) = rest.split_at((*n).min(rest.len()));
                    fast.push_slice(now, |f| a.push(f));
                    slow.push_slice(now, |f| b.push(f));
                    rest = later;
                }
                Feed::One => {
                    a.extend(fast.push(rest[0]));
                    b.extend(slow.push(rest[0]));
                    rest = &rest[1..];
                }
                Feed::Poll(d) => {
                    let now = rest[0]
                        .at
                        .checked_sub(SimDuration::from_nanos(*d))
                        .unwrap_or(rest[0].at);
                    a.extend(fast.poll(now));
                    b.extend(slow.poll(now));
                }
                Feed::Flush => {
                    a.extend(fast.flush());
                    b.extend(slow.flush());
                }
                Feed::Reset => {
                    fast.reset();
                    slow.reset();
                }
            }
            if matches!(feed, Feed::Poll(_) | Feed::Flush | Feed::Reset) {
                // Then one pulse, so that every step takes at least one.
                a.extend(fast.push(rest[0]));
                b.extend(slow.push(rest[0]));
                rest = &rest[1..];
            }
            prop_assert_eq!(&a, &b, "step {} {:?}", step, feed);
            prop_assert_eq!(fast.poll_at(), slow.poll_at(), "step {}", step);
        }
        prop_assert_eq!(fast.flush(), slow.flush());
        Ok(())
    }

    /// The whole receiver as the benchmark drives it: one slice, then a flush.
    fn check_receiver(cfg: ReceiverConfig, pulses: &[Pulse]) -> Result<(), TestCaseError> {
        let mut rx = Receiver::new(cfg);
        let mut a = Vec::new();
        rx.push_slice(pulses, |r| a.push(r));
        a.extend(rx.flush());
        let mut line = ReferenceLineDecoder::new(&cfg);
        let mut listener = Listener::new(&cfg);
        let mut b = Vec::new();
        line.push_slice(pulses, |f| b.push(listener.accept(&f)));
        b.extend(line.flush().map(|f| listener.accept(&f)));
        prop_assert_eq!(a, b);
        Ok(())
    }

    /// Encoded trains through `push_train` (its clean path and its pulse-by-pulse one), mixed
    /// with single pulses.
    fn check_trains(
        cfg: ReceiverConfig,
        trains: &[(bool, u16, u64, bool)],
    ) -> Result<(), TestCaseError> {
        let h = timing().half_bit();
        let mut fast = LineDecoder::new(&cfg);
        let mut slow = ReferenceLineDecoder::new(&cfg);
        let mut t = 1u64 << 30;
        for &(is_request, bits, gap, by_train) in trains {
            let train = if is_request {
                PulseTrain::request(
                    Request::from_bits(bits & 0x3FFF).unwrap_or(dexg(2, 1)),
                    SimTime::from_nanos(t),
                    h,
                )
            } else {
                PulseTrain::response(
                    Response::new(Nibble::from_low_bits(bits as u8)),
                    SimTime::from_nanos(t),
                    h,
                )
            };
            let (mut a, mut b) = (Vec::new(), Vec::new());
            if by_train {
                a.extend(fast.push_train(&train));
                b.extend(slow.push_train(&train));
            } else {
                let pulses: Vec<Pulse> = train.iter().collect();
                fast.push_slice(&pulses, |f| a.push(f));
                slow.push_slice(&pulses, |f| b.push(f));
            }
            prop_assert_eq!(a, b);
            prop_assert_eq!(fast.poll_at(), slow.poll_at());
            t = train.end().as_nanos() + gap;
        }
        prop_assert_eq!(fast.flush(), slow.flush());
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1_000))]

        #[test]
        fn the_line_decoder_equals_its_reference_on_faulty_lines(
            cfg in config(),
            pulses in faulty_line(),
            feeds in feeds(),
        ) {
            check_feeds(cfg, &pulses, &feeds)?;
            check_receiver(cfg, &pulses)?;
        }

        #[test]
        fn the_line_decoder_equals_its_reference_on_wild_pulses(
            cfg in config(),
            pulses in wild_line(),
            feeds in feeds(),
        ) {
            check_feeds(cfg, &pulses, &feeds)?;
            check_receiver(cfg, &pulses)?;
        }

        #[test]
        fn the_line_decoder_equals_its_reference_on_trains(
            cfg in config(),
            trains in prop::collection::vec(
                (any::<bool>(), any::<u16>(), prop_oneof![Just(18_000u64), Just(10_000u64), 0u64..30_000], any::<bool>()),
                0..24,
            ),
        ) {
            check_trains(cfg, &trains)?;
        }
    }

    proptest! {
        // The fast scan's borders are narrow: more cases.
        #![proptest_config(ProptestConfig::with_cases(4_000))]

        #[test]
        fn the_line_decoder_equals_its_reference_on_grid_borders(
            (cfg, pulses) in border_config().prop_flat_map(|cfg| (Just(cfg), grid_line(cfg))),
            feeds in feeds(),
        ) {
            check_feeds(cfg, &pulses, &feeds)?;
            check_receiver(cfg, &pulses)?;
        }
    }
}
