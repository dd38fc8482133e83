//! Property tests of what the clients send, in bounded time in the normal test suite: random
//! byte streams to the TTK4145 front end, random Modbus requests through the register map,
//! random texts to the live view's socket. Nothing panics, and every answer is well-formed.

use crate::live::{ToRig, WebCall};
use crate::map::{Gateway, Owner, COMMAND_REGISTERS, PLC_SIGNALS_REGISTER};
use crate::ttk::Ttk;
use asi_phy::{SimDuration, SimTime};
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use rig::{Rig, Scenario};
use std::cell::RefCell;
use std::time::Duration;
use tokio_modbus::{ExceptionCode, Request, Response};

/// A rig with an outside controller at power-on, the cabin at floor 1, and its clock.
fn external_rig() -> Rig {
    let toml = "name = \"props\"\nduration = \"1h\"\n[lift]\nstart_mm = 0.0\n";
    let sc = Scenario::from_toml("props.toml", toml).expect("a scenario");
    Rig::new(sc).expect("a rig").with_external_controller()
}

/// A runner of `cases` cases whose failures are not saved to files.
fn runner(cases: u32) -> TestRunner {
    TestRunner::new(Config {
        cases: asi_phy::testing::fuzz_cases(cases),
        failure_persistence: None,
        ..Config::default()
    })
}

/// The rig, the gateway, the TTK4145 front end and the simulated time, shared by the cases
/// of one test (a new rig per case would cost most of the test's time).
struct World {
    rig: Rig,
    gw: Gateway,
    ttk: Ttk,
    at: SimTime,
}

impl World {
    fn new() -> World {
        World {
            rig: external_rig(),
            gw: Gateway::new(Owner::External, SimDuration::from_millis(1000)),
            ttk: Ttk::default(),
            at: SimTime::ZERO,
        }
    }

    /// A step of simulated time, as the lockstep loop takes after a request.
    fn step(&mut self) {
        let next = self.at + SimDuration::from_millis(1);
        self.at = crate::live::advance(&mut self.rig, &mut self.gw, &mut self.ttk, self.at, next);
    }
}

#[test]
fn any_bytes_to_the_ttk4145_front_end_get_well_formed_answers_or_none() {
    let world = RefCell::new(World::new());
    let floors = 4u8;
    runner(96)
        .run(&vec(any::<u8>(), 0..256), |bytes| {
            let mut w = world.borrow_mut();
            for msg in bytes.chunks_exact(4) {
                let msg = [msg[0], msg[1], msg[2], msg[3]];
                let World { rig, gw, ttk, at } = &mut *w;
                let answer = ttk.serve(rig, gw, *at, msg);
                match (msg[0], answer) {
                    (0..=5, a) => prop_assert_eq!(a, None),
                    (6 | 8 | 9, Some([op, v, 0, 0])) => {
                        prop_assert_eq!(op, msg[0]);
                        prop_assert!(v <= 1);
                    }
                    (7, Some([7, at_floor, f, 0])) => {
                        prop_assert!(at_floor <= 1);
                        prop_assert!(f < floors && (at_floor == 1 || f == 0));
                    }
                    // A button of a floor or kind that does not exist: no answer.
                    (6, None) => prop_assert!(msg[1] > 2 || msg[2] >= floors),
                    (10.., None) => {}
                    (_, a) => prop_assert!(false, "{:?} answered {:?}", msg, a),
                }
                w.step();
            }
            Ok(())
        })
        .expect("the front end takes any bytes");
}

/// A Modbus request of the functions the gateway serves and some it does not, with addresses
/// near the map's tables and anywhere, counts within and beyond the protocol's limits.
fn request() -> impl Strategy<Value = Request<'static>> {
    let addr = prop_oneof![
        0u16..300,
        990u16..1070,
        PLC_SIGNALS_REGISTER..PLC_SIGNALS_REGISTER + 10,
        COMMAND_REGISTERS..COMMAND_REGISTERS + 12,
        2990u16..3250,
        any::<u16>(),
    ];
    let count = prop_oneof![0u16..8, 0u16..2100, any::<u16>()];
    let value = prop_oneof![0u16..8, 0x0100u16..0x0600, any::<u16>()];
    let addr2 = addr.clone();
    let count2 = count.clone();
    prop_oneof![
        (addr.clone(), count.clone()).prop_map(|(a, n)| Request::ReadCoils(a, n)),
        (addr.clone(), count.clone()).prop_map(|(a, n)| Request::ReadDiscreteInputs(a, n)),
        (addr.clone(), count.clone()).prop_map(|(a, n)| Request::ReadInputRegisters(a, n)),
        (addr.clone(), count.clone()).prop_map(|(a, n)| Request::ReadHoldingRegisters(a, n)),
        (addr.clone(), any::<bool>()).prop_map(|(a, v)| Request::WriteSingleCoil(a, v)),
        (addr.clone(), vec(any::<bool>(), 0..40))
            .prop_map(|(a, v)| Request::WriteMultipleCoils(a, v.into())),
        (addr.clone(), value.clone()).prop_map(|(a, v)| Request::WriteSingleRegister(a, v)),
        (addr.clone(), vec(value.clone(), 0..130))
            .prop_map(|(a, v)| Request::WriteMultipleRegisters(a, v.into())),
        (addr, count, addr2, vec(value, 0..125))
            .prop_map(|(ra, n, wa, v)| Request::ReadWriteMultipleRegisters(ra, n, wa, v.into())),
        (any::<u16>(), any::<u16>(), any::<u16>())
            .prop_map(|(a, m, o)| Request::MaskWriteRegister(a, m, o)),
        count2.prop_map(|n| Request::ReadCoils(n, 1)),
    ]
}

#[test]
fn any_modbus_request_through_the_map_is_served_whole_or_refused_and_changes_nothing() {
    let world = RefCell::new(World::new());
    runner(512)
        .run(&request(), |req| {
            let mut w = world.borrow_mut();
            let World { rig, gw, at, .. } = &mut *w;
            let outputs_before = *rig.lab().bus().image().output.words();
            let answer = gw.serve(rig, *at, &req);
            match (&req, &answer) {
                (Request::ReadCoils(_, n), Ok(Response::ReadCoils(v)))
                | (Request::ReadDiscreteInputs(_, n), Ok(Response::ReadDiscreteInputs(v))) => {
                    prop_assert_eq!(v.len(), usize::from(*n));
                    prop_assert!((1..=2000).contains(n));
                }
                (Request::ReadInputRegisters(_, n), Ok(Response::ReadInputRegisters(v)))
                | (Request::ReadHoldingRegisters(_, n), Ok(Response::ReadHoldingRegisters(v)))
                | (
                    Request::ReadWriteMultipleRegisters(_, n, _, _),
                    Ok(Response::ReadWriteMultipleRegisters(v)),
                ) => {
                    prop_assert_eq!(v.len(), usize::from(*n));
                    prop_assert!((1..=125).contains(n));
                }
                (Request::WriteSingleCoil(a, v), Ok(r)) => {
                    prop_assert_eq!(r, &Response::WriteSingleCoil(*a, *v));
                }
                (Request::WriteSingleRegister(a, v), Ok(r)) => {
                    prop_assert_eq!(r, &Response::WriteSingleRegister(*a, *v));
                }
                (Request::WriteMultipleCoils(a, v), Ok(r)) => {
                    prop_assert_eq!(r, &Response::WriteMultipleCoils(*a, v.len() as u16));
                }
                (Request::WriteMultipleRegisters(a, v), Ok(r)) => {
                    prop_assert_eq!(r, &Response::WriteMultipleRegisters(*a, v.len() as u16));
                }
                (_, Err(code)) => {
                    prop_assert!(
                        matches!(
                            code,
                            ExceptionCode::IllegalFunction
                                | ExceptionCode::IllegalDataAddress
                                | ExceptionCode::IllegalDataValue
                        ),
                        "{:?}",
                        code
                    );
                    // Refused: the output image is as it was.
                    prop_assert_eq!(&outputs_before, rig.lab().bus().image().output.words());
                }
                (q, a) => prop_assert!(false, "{:?} answered {:?}", q, a),
            }
            // The answer as it goes on the wire: the function code (or its exception), at most
            // the 253 bytes of a Modbus PDU.
            let function = req.function_code().value();
            let pdu = crate::net::encode_answer(function, &answer);
            prop_assert!(pdu.len() <= 253 && pdu.len() >= 2);
            prop_assert_eq!(
                pdu[0],
                if answer.is_ok() {
                    function
                } else {
                    function | 0x80
                }
            );
            w.step();
            Ok(())
        })
        .expect("the map takes any request");
}

/// Texts a page might send: JSON of the commands' keys and values, and anything at all.
fn command_text() -> impl Strategy<Value = String> {
    let key = prop_oneof![
        Just("press"),
        Just("load"),
        Just("door"),
        Just("fault"),
        Just("kind"),
        Just("slave"),
        Just("crank_mm"),
        Just("line_noise"),
        Just("reset"),
        Just("rescue"),
        Just("ack"),
        Just("attend"),
        Just("at"),
        Just("duration"),
        Just("x"),
    ]
    .prop_map(str::to_owned);
    let leaf = prop_oneof![
        Just(serde_json::Value::Null),
        any::<bool>().prop_map(serde_json::Value::from),
        any::<i64>().prop_map(serde_json::Value::from),
        (-1e6f64..1e6).prop_map(serde_json::Value::from),
        prop_oneof![
            Just("cabin:3".to_owned()),
            Just("hall-up:9".to_owned()),
            Just("stop".to_owned()),
            Just("full".to_owned()),
            Just("slave-offline".to_owned()),
            Just("power-fail".to_owned()),
            Just("1s".to_owned()),
            ".{0,12}",
        ]
        .prop_map(serde_json::Value::from),
    ];
    let value = leaf.prop_recursive(3, 24, 4, move |inner| {
        prop_oneof![
            vec(inner.clone(), 0..4).prop_map(serde_json::Value::from),
            vec((key.clone(), inner), 0..4)
                .prop_map(|kv| serde_json::Value::Object(kv.into_iter().collect())),
        ]
    });
    prop_oneof![
        (any::<Option<u32>>(), value.clone()).prop_map(|(id, cmd)| {
            let mut m = serde_json::Map::new();
            if let Some(id) = id {
                m.insert("id".into(), id.into());
            }
            m.insert("command".into(), cmd);
            serde_json::Value::Object(m).to_string()
        }),
        value.prop_map(|v| v.to_string()),
        ".{0,64}",
    ]
}

#[test]
fn any_text_on_the_socket_gets_a_well_formed_reply() {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .build()
        .expect("a runtime");
    // The rig thread's side of a command: checked for the lab lift, not done.
    let (tx, rx) = crossbeam_channel::unbounded::<ToRig>();
    let rig_thread = std::thread::spawn(move || {
        let shape = crate::command::LiftShape {
            floors: 4,
            safe_drive: false,
        };
        while let Ok(m) = rx.recv() {
            if let ToRig::Web(WebCall { command, reply }) = m {
                let _ = reply.send(crate::command::parse(&command, shape).map(|_| None));
            }
        }
    });
    runner(256)
        .run(&command_text(), |text| {
            let answer = runtime.block_on(async {
                tokio::time::timeout(Duration::from_secs(5), crate::web::command(&text, &tx)).await
            });
            let answer = answer.map_err(|_| TestCaseError::fail("no reply within 5 s"))?;
            let v: serde_json::Value = serde_json::from_str(&answer)
                .map_err(|e| TestCaseError::fail(format!("not JSON: {e}: {answer}")))?;
            prop_assert_eq!(&v["type"], "reply");
            match v["ok"].as_bool() {
                Some(true) => prop_assert!(v.get("error").is_none()),
                Some(false) => {
                    let e = v["error"].as_str().unwrap_or("");
                    prop_assert!(!e.is_empty(), "{}", answer);
                }
                None => prop_assert!(false, "no ok: {}", answer),
            }
            Ok(())
        })
        .expect("the socket takes any text");
    drop(tx);
    rig_thread.join().expect("the rig thread ends");
}

/// Bytes a Modbus TCP client might send: frames with good headers around random PDUs, frames
/// with bad headers, and anything at all.
fn modbus_bytes() -> impl Strategy<Value = Vec<u8>> {
    let frame = (
        any::<u16>(),
        prop_oneof![Just(0u16), any::<u16>()],
        any::<u8>(),
        prop_oneof![
            vec(any::<u8>(), 0..12),
            (1u8..=6, any::<u16>(), 0u16..130).prop_map(|(f, a, n)| [
                [f].as_slice(),
                &a.to_be_bytes(),
                &n.to_be_bytes()
            ]
            .concat()),
        ],
        any::<bool>(),
    )
        .prop_map(|(tid, protocol, unit, pdu, honest)| {
            let len = if honest {
                pdu.len() as u16 + 1
            } else {
                tid % 300
            };
            [
                tid.to_be_bytes().as_slice(),
                &protocol.to_be_bytes(),
                &len.to_be_bytes(),
                &[unit],
                &pdu,
            ]
            .concat()
        });
    prop_oneof![
        vec(frame, 0..6).prop_map(|fs| fs.concat()),
        vec(any::<u8>(), 0..64),
    ]
}

#[test]
fn any_bytes_on_a_modbus_connection_get_well_formed_frames_and_the_connection_ends() {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("a runtime");
    // The rig thread: the map itself serves the requests.
    let (tx, rx) = crossbeam_channel::unbounded::<ToRig>();
    let rig_thread = std::thread::spawn(move || {
        let mut w = World::new();
        while let Ok(m) = rx.recv() {
            if let ToRig::Call(c) = m {
                let World { rig, gw, at, .. } = &mut w;
                let _ = c.reply.send(gw.serve(rig, *at, &c.request));
                w.step();
            }
        }
    });
    runner(128)
        .run(&modbus_bytes(), |bytes| {
            let out = runtime.block_on(async {
                let (mut client, server) = tokio::io::duplex(4096);
                let conn = tokio::spawn(crate::net::serve_modbus(server, tx.clone()));
                let _ = client.write_all(&bytes).await;
                let _ = client.shutdown().await;
                let mut out = Vec::new();
                let read =
                    tokio::time::timeout(Duration::from_secs(5), client.read_to_end(&mut out));
                let ended = matches!(read.await, Ok(Ok(_)));
                let _ = tokio::time::timeout(Duration::from_secs(5), conn).await;
                (ended, out)
            });
            let (ended, out) = out;
            prop_assert!(ended, "the connection did not end");
            // The answers: whole frames, protocol 0, each length the rest of its frame.
            let mut rest = out.as_slice();
            while !rest.is_empty() {
                prop_assert!(rest.len() >= 9, "a cut frame: {:?}", rest);
                prop_assert_eq!(&rest[2..4], &[0u8, 0]);
                let len = usize::from(u16::from_be_bytes([rest[4], rest[5]]));
                prop_assert!((3..=254).contains(&len) && rest.len() >= 6 + len);
                rest = &rest[6 + len..];
            }
            Ok(())
        })
        .expect("a connection takes any bytes");
    drop(tx);
    rig_thread.join().expect("the rig thread ends");
}
