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
