use super::*;

fn a(v: u8) -> Address {
    Address::new(v).expect("test address")
}

fn n(v: u8) -> Nibble {
    Nibble::new(v).expect("test nibble")
}

/// The literal strings of SAP5 Table 6 (docs/asi.md §1.3) and docs/physical-layer.md's vectors.
#[test]
fn bit_strings_match_the_datasheet_literals() {
    assert_eq!(Request::broadcast_reset().bits(), 0b01111111010111);
    assert_eq!(
        Request::broadcast_reset().to_string(),
        "0 1 11111 10101 1 1"
    );
    let dexg = Request::data_exchange(a(5), n(0b1010)).expect("valid");
    assert_eq!(dexg.to_string(), "0 0 00101 01010 0 1");
    assert_eq!(Response::new(n(0b0110)).bits(), 0b0011001);
    assert_eq!(Response::new(n(0b0000)).bits(), 0b0000001);
}

/// The information-field codes of docs/asi.md §4 (hex view, standard mode).
#[test]
fn command_codes_match_the_call_table() {
    let cases: [(Result<Request, TelegramError>, u8); 6] = [
        (Request::read_io_configuration(a(7), Select::A), 0x10),
        (Request::read_id_code(a(7), Select::A), 0x11),
        (Request::read_id1(a(7), Select::A), 0x12),
        (Request::read_id2(a(7), Select::A), 0x13),
        (Request::reset_slave(a(7), Select::A), 0x1C),
        (Request::read_status(a(7), Select::A), 0x1E),
    ];
    for (req, info) in cases {
        let req = req.expect("valid");
        assert!(req.cb());
        assert_eq!(req.info(), info, "{:?}", req.call());
    }
    let dela = Request::delete_address(a(7), Select::A).expect("valid");
    assert_eq!((dela.cb(), dela.info()), (true, 0x00));
    // B slaves: reads carry Sel = 1 in I3, Reset and Status carry ~Sel = 0.
    assert_eq!(
        Request::read_id1(a(7), Select::B).expect("valid").info(),
        0x1A
    );
    assert_eq!(
        Request::read_status(a(7), Select::B).expect("valid").info(),
        0x16
    );
    assert_eq!(
        Request::reset_slave(a(7), Select::B).expect("valid").info(),
        0x14
    );
    assert_eq!(
        Request::delete_address(a(7), Select::B)
            .expect("valid")
            .info(),
        0x08
    );
}

#[test]
fn ab_data_exchange_carries_the_select_bit_in_i3() {
    let ra = Request::data_exchange_ab(a(9), Select::A, n(0b101)).expect("valid");
    let rb = Request::data_exchange_ab(a(9), Select::B, n(0b101)).expect("valid");
    assert_eq!(ra.info(), 0b01101);
    assert_eq!(rb.info(), 0b00101);
    assert_eq!(ra.ab_payload(), Some((Select::A, n(0b101))));
    assert_eq!(rb.ab_payload(), Some((Select::B, n(0b101))));
    assert_eq!(
        Request::data_exchange_ab(a(9), Select::A, n(0b1000)),
        Err(TelegramError::FieldOutOfRange {
            field: "A/B outputs D2..D0",
            value: 8,
            max: 7
        })
    );
}

#[test]
fn constructors_reject_what_no_telegram_can_say() {
    assert_eq!(
        Request::data_exchange(Address::ZERO, Nibble::ZERO),
        Err(TelegramError::AddressZero {
            call: "Data_Exchange"
        })
    );
    assert_eq!(
        Request::read_id_code(Address::ZERO, Select::B),
        Err(TelegramError::ZeroB)
    );
    assert!(Request::read_id_code(Address::ZERO, Select::A).is_ok());
    assert_eq!(Address::new(32), None);
    assert_eq!(Nibble::new(16), None);
}

#[test]
fn from_bits_names_the_broken_rule() {
    let good = Request::data_exchange(a(5), n(0b1010))
        .expect("valid")
        .bits();
    assert_eq!(
        Request::from_bits(good),
        Request::data_exchange(a(5), n(0b1010))
    );
    assert_eq!(
        Request::from_bits(good | 1 << 13),
        Err(TelegramError::StartBit)
    );
    assert_eq!(Request::from_bits(good & !1), Err(TelegramError::EndBit));
    assert_eq!(
        Request::from_bits(good ^ 0b10),
        Err(TelegramError::Parity {
            expected: 0,
            received: 1
        })
    );
    assert_eq!(
        Request::from_bits(good | 1 << 14),
        Err(TelegramError::TooLong {
            len: 14,
            received: good | 1 << 14
        })
    );
    assert_eq!(
        Response::from_bits(0b0011011),
        Err(TelegramError::Parity {
            expected: 0,
            received: 1
        })
    );
}

/// Every one of the 2^11 valid requests: classification and construction are inverse.
#[test]
fn every_request_classifies_and_rebuilds() {
    let mut unknown = 0;
    for body in 0u16..1 << 11 {
        let req = Request::from_fields(
            body & 0x400 != 0,
            a(((body >> 5) & 0x1F) as u8),
            (body & 0x1F) as u8,
        )
        .expect("in range");
        assert_eq!(Request::from_bits(req.bits()), Ok(req));
        let call = req.call();
        if matches!(call, Call::Unknown { .. }) {
            unknown += 1;
        }
        assert_eq!(call.request(), Some(req), "{call:?}");
        assert_eq!(
            req.is_broadcast_reset(),
            call == Call::BroadcastReset,
            "{call:?}"
        );
        let data_exchange = match call {
            Call::DataExchange { address, data } => Some((address, data)),
            _ => None,
        };
        assert_eq!(req.as_data_exchange(), data_exchange, "{call:?}");
    }
    // CB=1, I4=0, A≠0 with I2..I0 ≠ 0: 31·2·7 = 434; CB=1, I4=1: x111 at every address
    // (64), x101 except 31/I3=0 (63), Sel=B reads at address 0 (4), ~Sel=B at 0 (2).
    assert_eq!(unknown, 434 + 64 + 63 + 4 + 2);
}

#[test]
fn every_response_round_trips() {
    for v in 0..16 {
        let r = Response::new(n(v));
        assert_eq!(Response::from_bits(r.bits()), Ok(r));
        assert_eq!(r.data().get(), v);
        assert_eq!((r.bits() >> 1).count_ones() % 2, 0);
    }
}

/// The looked-up pulse counts are those of the encoder's train, for every request and every
/// response.
#[test]
fn every_telegram_has_the_pulses_of_its_train() {
    let h = crate::SimDuration::from_micros(3);
    for body in 0u16..1 << 11 {
        let bits = (body << 2) | ((body.count_ones() as u16 & 1) << 1) | 1;
        let q = Request::from_bits(bits).expect("a request");
        let tg = crate::Transmission::request(q, crate::SimTime::ZERO, h);
        assert_eq!(q.pulses(), tg.train().len(), "{q:?}");
        assert_eq!(q.pulses(), tg.pulses(), "{q:?}");
    }
    for v in 0..16 {
        let r = Response::new(n(v));
        let tg = crate::Transmission::response(r, crate::SimTime::ZERO, h);
        assert_eq!(r.pulses(), tg.train().len(), "{r:?}");
        assert_eq!(r.pulses(), tg.pulses(), "{r:?}");
    }
}

/// The responses built and counted by look-up are those worked out from the bits as before:
/// the parity bit counted over the data, and the pulses of the response with that data, for
/// every raw pattern a response can be made of.
#[test]
fn looked_up_responses_are_the_worked_out_ones() {
    let h = crate::SimDuration::from_micros(3);
    for v in 0..16u8 {
        let pb = (v.count_ones() & 1) as u8;
        assert_eq!(
            Response::new(n(v)).bits(),
            (v << 2) | (pb << 1) | 1,
            "data {v:04b}"
        );
    }
    let mut responses = 0;
    for bits in 0..=u8::MAX {
        let Ok(r) = Response::from_bits(bits) else {
            continue;
        };
        responses += 1;
        // The pulses of the response carrying the same data, from the encoder's train.
        let same_data = Response::new(r.data());
        let tg = crate::Transmission::response(same_data, crate::SimTime::ZERO, h);
        assert_eq!(r.pulses(), tg.pulses(), "{bits:07b}");
        assert_eq!(r.pulses(), tg.train().len(), "{bits:07b}");
    }
    assert_eq!(responses, 16);
}
