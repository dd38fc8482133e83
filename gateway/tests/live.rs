//! The gateway end to end: a live run served over Modbus TCP on a loopback port, driven by
//! Rust clients (tokio-modbus) and by raw bytes; and the live view (`web`).

mod controls;
mod web;

use asi_master::ProcessImage;
use asi_phy::{SimDuration, SimTime};
use controller::plc::{FromSafety, Plc};
use controller::ControllerConfig;
use gateway::live::LiveConfig;
use gateway::{Owner, Running, Speed};
use rig::report::{CallSource, ClientLog, LogEvent, ViolationKind};
use rig::Actor;
use rig::{Report, Rig, Scenario};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::Duration;
use tokio_modbus::client::Context;
use tokio_modbus::prelude::*;

fn start(toml: &str, owner: Owner, speed: Speed) -> Running {
    start_with(toml, owner, speed, false)
}

fn start_with(toml: &str, owner: Owner, speed: Speed, ttk: bool) -> Running {
    let sc = Scenario::from_toml("test.toml", toml).expect("a valid scenario");
    let make = move || {
        let rig = Rig::new(sc.clone()).map_err(gateway::MakeRigError::from)?;
        Ok(match owner {
            Owner::External => rig.with_external_controller(),
            Owner::Builtin => rig,
        })
    };
    let cfg = {
        let mut cfg = LiveConfig::default();
        cfg.speed = speed;
        cfg.owner = owner;
        cfg.watchdog = SimDuration::from_millis(1000);
        cfg.step = SimDuration::from_millis(1);
        cfg
    };
    let loopback: SocketAddr = "127.0.0.1:0".parse().expect("an address");
    let ttk = ttk.then_some(loopback);
    gateway::start(make, cfg, loopback, ttk).expect("the gateway starts")
}

#[test]
fn a_speed_factor_out_of_bounds_is_refused_at_the_start_not_a_panic_later() {
    let sc = Scenario::from_toml("test.toml", QUIET).expect("a valid scenario");
    let cfg = {
        let mut cfg = LiveConfig::default();
        cfg.speed = Speed::Factor(1e-30);
        cfg.owner = Owner::Builtin;
        cfg.watchdog = SimDuration::from_millis(1000);
        cfg.step = SimDuration::from_millis(1);
        cfg
    };
    let loopback: SocketAddr = "127.0.0.1:0".parse().expect("an address");
    match gateway::start(
        move || Rig::new(sc.clone()).map_err(gateway::MakeRigError::from),
        cfg,
        loopback,
        None,
    ) {
        Err(e) => assert!(e.to_string().contains("speed factor 1e-30"), "{e}"),
        Ok(running) => {
            running.stop();
            let _ = running.wait();
            panic!("speed 1e-30 was accepted");
        }
    }
}

async fn connect(addr: SocketAddr) -> Context {
    tcp::connect(addr).await.expect("a connection")
}

/// Simulated time (input registers 1050..1053) and the safety bits (1054).
async fn time_and_safety(ctx: &mut Context) -> Option<(SimTime, u16)> {
    let w = ctx.read_input_registers(1050, 5).await.ok()?.ok()?;
    let ms = w[..4].iter().fold(0u64, |v, &x| v << 16 | u64::from(x));
    Some((SimTime::from_millis(ms), w[4]))
}

/// The built-in PLC program as an outside controller: it reads the input image over Modbus,
/// scans every 10 ms of simulated time, and writes the output image and its signals to the
/// safety logic back, until the run ends (the gateway answers with an exception then).
async fn plc_over_modbus(addr: SocketAddr) -> u64 {
    let mut ctx = connect(addr).await;
    let mut plc = Plc::new(ControllerConfig::default()).expect("a PLC");
    let mut image = ProcessImage::default();
    let mut next_scan = SimTime::ZERO;
    let mut scans = 0;
    loop {
        let Some((now, safety)) = time_and_safety(&mut ctx).await else {
            return scans;
        };
        if now < next_scan {
            continue;
        }
        let Ok(Ok(input)) = ctx.read_input_registers(0, 70).await else {
            return scans;
        };
        for (i, w) in input.iter().enumerate() {
            image.input.set_word(i, *w);
        }
        let to = plc.scan(
            now,
            &mut image,
            FromSafety {
                estop_out: safety & 1 != 0,
            },
        );
        let out: Vec<u16> = image.output.words()[..70].to_vec();
        if !matches!(ctx.write_multiple_registers(0, &out).await, Ok(Ok(()))) {
            return scans;
        }
        let signals = u16::from(to.restart) | u16::from(to.overloaded) << 1;
        if !matches!(ctx.write_single_register(1000, signals).await, Ok(Ok(()))) {
            return scans;
        }
        scans += 1;
        next_scan = now + SimDuration::from_millis(10);
    }
}

const CALLS: &str = r#"
name = "calls over the gateway"
duration = "45s"
[lift]
start_mm = 0.0
[[event]]
at = "15s"
press = "cabin:3"
[[event]]
at = "30s"
press = "hall-down:2"
"#;

#[tokio::test(flavor = "multi_thread", worker_threads = 1)]
async fn an_outside_plc_serves_the_calls_through_the_gateway_without_violations() {
    let running = start(CALLS, Owner::External, Speed::Max);
    let scans = plc_over_modbus(running.local_addr()).await;
    let r: Report = tokio::task::spawn_blocking(move || running.wait())
        .await
        .expect("the run ends");
    assert!(r.violations.is_empty(), "{:?}", r.violations);
    // The outside program's initialisation brought the cabin to floor 1 first.
    assert_eq!(r.arrivals.first().map(|a| a.floor), Some(1));
    let served: Vec<(u8, CallSource)> = r.served.iter().map(|s| (s.floor, s.source)).collect();
    assert!(served.contains(&(3, CallSource::Cabin)), "{served:?}");
    assert!(served.contains(&(2, CallSource::Hall)), "{served:?}");
    assert!(r.passengers.iter().all(|p| p.served_at_s.is_some()));
    let live = r.live.expect("a live report");
    assert_eq!(live.controller, "external");
    assert_eq!(live.watchdog_trips, 0);
    assert_eq!(live.exceptions, 0);
    // In lockstep the run is exact: a scan every 10 ms of simulated time, the first at 0 and
    // the last at 44.99 s (the request at 45 s is not served: the run has ended).
    assert_eq!(scans, 4_500);
    assert_eq!(r.final_state.state, None, "no built-in program ran");
}

const DOOR_OPEN: &str = r#"
name = "run with the door open"
duration = "30s"
[lift]
start_mm = 0.0
door = "open"
"#;

/// Writes "run up at travel speed" every 10 ms of simulated time, whatever the plant does.
async fn run_up_regardless(addr: SocketAddr, for_ms: u64) {
    let mut ctx = connect(addr).await;
    let mut next = SimTime::ZERO;
    loop {
        let Some((now, _)) = time_and_safety(&mut ctx).await else {
            return;
        };
        if now >= SimTime::from_millis(for_ms) {
            return;
        }
        if now >= next {
            // Converter (slave 7, word 1 bits 0..3): D0 run, D1 up; set-point word 68; the
            // STOP circuit's restart (holding register 1000, bit 0) in the first 100 ms.
            let restart = u16::from(now < SimTime::from_millis(100));
            let ok = ctx.write_single_register(1, 0b0011).await;
            let ok2 = ctx.write_single_register(68, 10_000).await;
            let ok3 = ctx.write_single_register(1000, restart).await;
            if !matches!((ok, ok2, ok3), (Ok(Ok(())), Ok(Ok(())), Ok(Ok(())))) {
                return;
            }
            next = now + SimDuration::from_millis(10);
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 1)]
async fn a_controller_that_runs_with_the_door_open_is_stopped_by_the_safety_logic() {
    let running = start(DOOR_OPEN, Owner::External, Speed::Max);
    run_up_regardless(running.local_addr(), 29_000).await;
    // The rest of the minute passes with reads only.
    let mut ctx = connect(running.local_addr()).await;
    while time_and_safety(&mut ctx).await.is_some() {}
    let r = tokio::task::spawn_blocking(move || running.wait())
        .await
        .expect("the run ends");
    let kinds: Vec<ViolationKind> = r.violations.iter().map(|v| v.kind).collect();
    assert_eq!(
        kinds.first(),
        Some(&ViolationKind::DoorOpenMoving),
        "{kinds:?}"
    );
    assert!(
        !kinds.contains(&ViolationKind::MechanicalEnd),
        "the safety logic stops the cabin before the end: {kinds:?}"
    );
    // The top overtravel sensor took K1 away; the cabin stands.
    assert!(!r.final_state.contactor_closed);
    assert!(!r.final_state.moving);
    let cause = r.final_state.k1_open_cause.expect("a cause");
    assert!(cause.contains("overtravel"), "{cause}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 1)]
async fn the_watchdog_zeroes_the_outputs_of_a_controller_that_went_quiet() {
    let running = start(DOOR_OPEN, Owner::External, Speed::Max);
    let addr = running.local_addr();
    let mut ctx = connect(addr).await;
    // Function 23 writes the watchdog time (1 s, as it is) and reads it back in one request.
    let rw = ctx
        .read_write_multiple_registers(1008, 1, 1008, &[1000])
        .await;
    assert_eq!(rw.expect("io").expect("no exception"), vec![1000]);
    // The load (a simulator command) reaches the load sensor's register over the bus.
    assert!(matches!(
        ctx.write_single_register(2003, 2).await,
        Ok(Ok(()))
    ));
    for _ in 0..20 {
        let _ = time_and_safety(&mut ctx).await;
    }
    let load = ctx.read_input_registers(1055, 1).await;
    assert_eq!(load.expect("io").expect("no exception"), vec![2]);
    assert!(matches!(
        ctx.write_single_register(2003, 0).await,
        Ok(Ok(()))
    ));
    // Close the door by a simulator command, then run up for 2 s and go quiet.
    assert!(matches!(
        ctx.write_single_register(2004, 1).await,
        Ok(Ok(()))
    ));
    run_up_regardless(addr, 2_000).await;
    let mut tripped_at = None;
    while let Some((now, safety)) = time_and_safety(&mut ctx).await {
        if safety & 1 << 4 != 0 && tripped_at.is_none() {
            tripped_at = Some(now);
            let out = ctx.read_holding_registers(0, 70).await;
            assert_eq!(out.expect("io").expect("no exception"), vec![0; 70]);
        }
        if now >= SimTime::from_millis(10_000) {
            running.stop();
        }
    }
    let t = tripped_at.expect("the watchdog tripped");
    // The last write came just before 2 s; the watchdog is 1 s.
    assert!(
        (SimTime::from_millis(2_990)..=SimTime::from_millis(3_010)).contains(&t),
        "{t:?}"
    );
    let r = tokio::task::spawn_blocking(move || running.wait())
        .await
        .expect("the run ends");
    assert_eq!(r.live.expect("live").watchdog_trips, 1);
    assert!(!r.final_state.moving);
    assert!(r.log.iter().any(|l| l.who == Actor::Gateway
        && matches!(l.event, LogEvent::Client(ClientLog::WatchdogExpired { .. }))));
}

/// One Modbus TCP request as bytes (MBAP header, unit 1).
fn frame(tid: u16, pdu: &[u8]) -> Vec<u8> {
    let mut f = Vec::new();
    f.extend_from_slice(&tid.to_be_bytes());
    f.extend_from_slice(&0u16.to_be_bytes());
    f.extend_from_slice(&(pdu.len() as u16 + 1).to_be_bytes());
    f.push(1);
    f.extend_from_slice(pdu);
    f
}

/// Sends `pdu` and returns the answer's PDU.
fn ask(s: &mut TcpStream, tid: u16, pdu: &[u8]) -> Vec<u8> {
    s.write_all(&frame(tid, pdu)).expect("sent");
    let mut head = [0u8; 7];
    s.read_exact(&mut head).expect("an answer");
    assert_eq!(u16::from_be_bytes([head[0], head[1]]), tid);
    let len = usize::from(u16::from_be_bytes([head[4], head[5]])) - 1;
    let mut body = vec![0; len];
    s.read_exact(&mut body).expect("its body");
    body
}

fn raw(addr: SocketAddr) -> TcpStream {
    let s = TcpStream::connect(addr).expect("a connection");
    s.set_read_timeout(Some(Duration::from_secs(10)))
        .expect("a timeout");
    s
}

/// Whether the server closed `s` (read gives 0 bytes or an error).
fn closed(s: &mut TcpStream) -> bool {
    let mut b = [0u8; 64];
    !matches!(s.read(&mut b), Ok(n) if n > 0)
}

const QUIET: &str = r#"
name = "quiet"
duration = "1h"
[lift]
start_mm = 0.0
"#;

#[test]
fn bad_requests_get_the_standard_exceptions_and_the_server_goes_on() {
    let running = start(QUIET, Owner::Builtin, Speed::Factor(1.0));
    let addr = running.local_addr();
    let mut s = raw(addr);
    // Function 0x08 (diagnostics) and 0x41 are not offered: exception 01.
    assert_eq!(ask(&mut s, 1, &[0x08, 0, 0, 0x12, 0x34]), [0x88, 0x01]);
    assert_eq!(ask(&mut s, 2, &[0x41, 1, 2, 3]), [0xC1, 0x01]);
    // Past the map: exception 02 (input image ends at 243; 244..999 are not mapped).
    assert_eq!(ask(&mut s, 3, &[0x04, 0, 240, 0, 8]), [0x84, 0x02]);
    assert_eq!(ask(&mut s, 4, &[0x01, 0x27, 0x10, 0, 1]), [0x81, 0x02]);
    // Counts outside Modbus's limits: exception 03.
    assert_eq!(ask(&mut s, 5, &[0x03, 0, 0, 0, 126]), [0x83, 0x03]);
    assert_eq!(ask(&mut s, 6, &[0x02, 0, 0, 0, 0]), [0x82, 0x03]);
    // The built-in program owns the outputs: a write is refused, the image unchanged.
    assert_eq!(ask(&mut s, 7, &[0x06, 0, 1, 0, 3]), [0x86, 0x02]);
    assert_eq!(ask(&mut s, 8, &[0x05, 0, 28, 0xFF, 0]), [0x85, 0x02]);
    // An input area is never written: the input image mirror of holding registers 3000...
    assert_eq!(ask(&mut s, 9, &[0x06, 0x0B, 0xB8, 0, 1]), [0x86, 0x02]);
    // ... and illegal values of a simulator command: exception 03.
    assert_eq!(
        ask(&mut s, 10, &[0x06, 0x07, 0xD0, 0x01, 0x09]),
        [0x86, 0x03]
    );
    assert_eq!(ask(&mut s, 11, &[0x06, 0x07, 0xD3, 0, 9]), [0x86, 0x03]);
    // A good request on the same connection is still served: the flags and slaves 1..3.
    let ok = ask(&mut s, 12, &[0x04, 0, 0, 0, 1]);
    assert_eq!(ok[..2], [0x04, 2]);

    // A malformed MBAP header (protocol 7) or a length of 0 closes that connection.
    let mut bad = raw(addr);
    bad.write_all(&[0, 1, 0, 7, 0, 6, 1, 4, 0, 0, 0, 1])
        .expect("sent");
    assert!(closed(&mut bad));
    let mut bad = raw(addr);
    bad.write_all(&[0, 1, 0, 0, 0, 0, 1]).expect("sent");
    assert!(closed(&mut bad));
    // Random bytes (a fixed seed), a request cut off by a disconnect.
    let mut x = 0x2545_F491_4F6C_DD1Du64;
    for _ in 0..20 {
        let mut junk = raw(addr);
        let bytes: Vec<u8> = (0..97)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                x as u8
            })
            .collect();
        let _ = junk.write_all(&bytes);
    }
    let mut cut = raw(addr);
    cut.write_all(&frame(13, &[0x04, 0, 0, 0, 16])[..9])
        .expect("sent");
    drop(cut);
    // 32 clients at once, each served.
    let clients: Vec<_> = (0..32)
        .map(|k| {
            std::thread::spawn(move || {
                let mut c = raw(addr);
                for i in 0..20u16 {
                    let a = ask(&mut c, i, &[0x02, 0x01, 0x00, 0, 64]);
                    assert_eq!(a[..2], [0x02, 8], "client {k}");
                }
            })
        })
        .collect();
    for c in clients {
        c.join().expect("a client thread");
    }
    // The first connection and the simulation go on.
    let t1 = ask(&mut s, 14, &[0x04, 0x04, 0x1A, 0, 4]);
    std::thread::sleep(Duration::from_millis(50));
    let t2 = ask(&mut s, 15, &[0x04, 0x04, 0x1A, 0, 4]);
    assert!(t2[2..] > t1[2..], "simulated time goes on: {t1:?} {t2:?}");
    running.stop();
    let r = running.wait();
    let live = r.live.expect("live");
    assert_eq!(live.controller, "builtin");
    assert!(live.connections >= 56, "{}", live.connections);
    assert!(r.violations.is_empty());
}

#[test]
fn in_lockstep_every_request_advances_the_simulation_by_one_step() {
    // Requests that reach the rig thread while it is still busy with the one before (here:
    // 200 sent in one write) must not be served at the same moment: simulated time (input
    // registers 1050..1053) goes up by exactly 1 ms per request, from 0.
    let running = start(QUIET, Owner::External, Speed::Max);
    let mut s = raw(running.local_addr());
    let burst: Vec<u8> = (0..200u16)
        .flat_map(|tid| frame(tid, &[0x04, 0x04, 0x1A, 0, 4]))
        .collect();
    s.write_all(&burst).expect("sent");
    let times: Vec<u64> = (0..200u16)
        .map(|tid| {
            let mut a = [0u8; 7 + 2 + 8];
            s.read_exact(&mut a).expect("an answer");
            assert_eq!(u16::from_be_bytes([a[0], a[1]]), tid);
            a[9..].chunks(2).fold(0, |v, c| {
                v << 16 | u64::from(u16::from_be_bytes([c[0], c[1]]))
            })
        })
        .collect();
    assert_eq!(times, (0..200).collect::<Vec<u64>>());
    running.stop();
    let r = running.wait();
    assert_eq!(r.live.expect("live").requests, 200);
}

#[test]
fn a_watching_client_sees_the_lists_and_the_image_of_the_lab_bus() {
    let running = start(QUIET, Owner::Builtin, Speed::Factor(4.0));
    let addr = running.local_addr();
    let mut s = raw(addr);
    // Let the master start the bus: a few simulated seconds.
    std::thread::sleep(Duration::from_millis(1_000));
    // LAS as bits (discrete inputs 256..319) and as registers (input registers 1000..1003).
    let bits = ask(&mut s, 1, &[0x02, 0x01, 0x00, 0, 64]);
    let regs = ask(&mut s, 2, &[0x04, 0x03, 0xE8, 0, 4]);
    let las: u64 = u64::from_le_bytes(bits[2..10].try_into().expect("8 bytes"));
    let mut expected = 0u64;
    for a in lab::address::ALL {
        expected |= 1 << a;
    }
    assert_eq!(las, expected, "LAS {las:#x}");
    let words: Vec<u16> = regs[2..]
        .chunks(2)
        .map(|c| u16::from_be_bytes([c[0], c[1]]))
        .collect();
    assert_eq!(words, [expected as u16, (expected >> 16) as u16, 0, 0]);
    // Config_OK and Normal_Operation_Active (discrete inputs 512, 517).
    let flags = ask(&mut s, 3, &[0x02, 0x02, 0x00, 0, 9]);
    assert_eq!(flags[2] & 1, 1, "Config_OK");
    assert_eq!(flags[2] >> 5 & 1, 1, "Normal_Operation_Active");
    // The converter's "ready" input (slave 7, D0: discrete input 28) matches the image word.
    let word1 = ask(&mut s, 4, &[0x04, 0, 1, 0, 1]);
    let ready = ask(&mut s, 5, &[0x02, 0, 28, 0, 1]);
    assert_eq!(word1[3] & 1, ready[2] & 1);
    // The master's LEDs (input registers 1060..1066) and their changes (1070..1076): all
    // green but prj after the start-up, which changed AS-i and AS-i active once.
    let words = |r: Vec<u8>| -> Vec<u16> {
        r[2..]
            .chunks(2)
            .map(|c| u16::from_be_bytes([c[0], c[1]]))
            .collect()
    };
    let leds = words(ask(&mut s, 6, &[0x04, 0x04, 0x24, 0, 7]));
    assert_eq!(leds, [1, 1, 1, 1, 1, 1, 0], "LEDs");
    let changes = words(ask(&mut s, 11, &[0x04, 0x04, 0x2E, 0, 7]));
    assert_eq!(changes, [0, 0, 0, 1, 1, 0, 0], "changes");
    // Slave 1's light (1101), calls (1202..1203) and repeats (1402..1403); an empty place
    // reads no light and no calls.
    let light = ask(&mut s, 7, &[0x04, 0x04, 0x4D, 0, 2]);
    assert_eq!((light[3], light[4]), (1, 0), "slave 1 green");
    let calls = ask(&mut s, 8, &[0x04, 0x04, 0xB2, 0, 2]);
    let calls = u32::from_be_bytes(calls[2..6].try_into().expect("4 bytes"));
    assert!(calls > 1_000, "{calls} calls");
    let empty = ask(&mut s, 9, &[0x04, 0x04, 0x4C + 30, 0, 1]);
    assert_eq!(&empty[2..], [0, 0], "place 30 has no slave");
    // Past the last per-slave register: an exception.
    let past = ask(&mut s, 10, &[0x04, 0x07, 0x48, 0, 1]);
    assert_eq!(past[0], 0x84, "input register 1864 does not exist");
    running.stop();
    let _ = running.wait();
}

/// A TTK4145 message; the answer of a read.
fn ttk(s: &mut TcpStream, msg: [u8; 4]) -> Option<[u8; 4]> {
    s.write_all(&msg).ok()?;
    if !(6..=9).contains(&msg[0]) {
        return None;
    }
    let mut a = [0u8; 4];
    s.read_exact(&mut a).ok()?;
    Some(a)
}

const TTK: &str = r#"
name = "a TTK4145 controller"
duration = "60s"
[lift]
start_mm = 650.0
[[event]]
at = "15s"
press = "cabin:4"
[[event]]
at = "30s"
press = "hall-up:1"
"#;

/// A TTK4145 course controller in its simplest form: find a floor going down, then serve the
/// calls in the order seen, stopping at the floor sensor, with the lamps a student sets.
/// Every message advances the lockstep simulation by 1 ms; it stops after `messages`.
fn ttk_controller(addr: SocketAddr, messages: u32) -> Vec<u8> {
    let mut s = raw(addr);
    let mut sent = 0u32;
    let mut calls: Vec<u8> = Vec::new();
    let mut floor: Option<u8> = None;
    let mut dir: i8 = -1;
    let mut stops = Vec::new();
    ttk(&mut s, [1, dir as u8, 0, 0]);
    while sent < messages {
        // Poll the buttons: hall up/down and cabin, floors 0..3.
        for kind in 0..3u8 {
            for f in 0..4u8 {
                sent += 1;
                if ttk(&mut s, [6, kind, f, 0]) == Some([6, 1, 0, 0]) && !calls.contains(&f) {
                    calls.push(f);
                    ttk(&mut s, [2, kind, f, 1]);
                }
            }
        }
        sent += 1;
        let sensor = ttk(&mut s, [7, 0, 0, 0]).expect("a floor sensor answer");
        if sensor[1] == 1 && floor != Some(sensor[2]) {
            floor = Some(sensor[2]);
            ttk(&mut s, [3, sensor[2], 0, 0]);
        }
        let here = if sensor[1] == 1 {
            Some(sensor[2])
        } else {
            None
        };
        let target = calls.first().copied();
        let want: i8 = match (here, target, floor) {
            // Not yet at any floor: keep going down.
            (None, _, None) => -1,
            (Some(f), Some(t), _) if f == t => 0,
            (_, Some(t), Some(f)) if t > f => 1,
            (_, Some(t), Some(f)) if t < f => -1,
            (Some(_), None, _) => 0,
            _ => dir,
        };
        if want != dir {
            dir = want;
            ttk(&mut s, [1, dir as u8, 0, 0]);
            if dir == 0 {
                if let Some(f) = here {
                    stops.push(f);
                    calls.retain(|&c| c != f);
                    for kind in 0..3u8 {
                        ttk(&mut s, [2, kind, f, 0]);
                    }
                }
            }
        }
    }
    stops
}

#[test]
fn a_ttk4145_controller_drives_the_lab_lift_and_its_lamps_are_recorded() {
    let running = start_with(TTK, Owner::External, Speed::Max, true);
    let addr = running.ttk_addr().expect("a TTK4145 address");
    let stops = ttk_controller(addr, 59_000);
    running.stop();
    let r = running.wait();
    // Down to floor 2 from between 2 and 3, up to 4 for the cabin call, down to 1 for the hall
    // call (TTK floors count from 0).
    assert_eq!(stops, [1, 3, 0]);
    assert!(r.violations.is_empty(), "{:?}", r.violations);
    let arrived: Vec<u8> = r.arrivals.iter().map(|a| a.floor).collect();
    assert_eq!(arrived, [2, 4, 1]);
    assert!(r.passengers.iter().all(|p| p.served_at_s.is_some()));
    let live = r.live.expect("live");
    assert_eq!(live.lamps.get("floor indicator"), Some(&1));
    assert_eq!(live.lamps.get("cabin lamp 4"), Some(&0));
    assert_eq!(live.exceptions, 0);
    assert!(r
        .log
        .iter()
        .any(|l| l.who == Actor::Ttk4145 && l.event == LogEvent::Client(ClientLog::Motor(1))));
}

#[test]
fn a_ttk4145_client_that_sends_nonsense_gets_no_answer_and_the_next_read_works() {
    let running = start_with(QUIET, Owner::External, Speed::Factor(1.0), true);
    let addr = running.ttk_addr().expect("a TTK4145 address");
    let mut s = raw(addr);
    // Unknown opcodes, a button of a fifth floor, an unknown button kind: no answer.
    s.write_all(&[0xEE, 1, 2, 3, 10, 0, 0, 0, 6, 0, 4, 0, 6, 7, 0, 0])
        .expect("sent");
    // The next read is answered: the cabin starts at floor 1, level.
    assert_eq!(ttk(&mut s, [7, 0, 0, 0]), Some([7, 1, 0, 0]));
    assert_eq!(
        ttk(&mut s, [9, 0, 0, 0]),
        Some([9, 0, 0, 0]),
        "the door is closed"
    );
    // A message cut short by a disconnect.
    let mut cut = raw(addr);
    cut.write_all(&[6, 2]).expect("sent");
    drop(cut);
    assert_eq!(ttk(&mut s, [8, 0, 0, 0]), Some([8, 0, 0, 0]));
    running.stop();
    let live = running.wait().live.expect("live");
    assert_eq!(live.exceptions, 4);
    assert_eq!(live.requests, 7);
}

#[test]
fn a_ttk4145_controller_that_runs_with_the_door_open_is_stopped_by_the_safety_logic() {
    let running = start_with(DOOR_OPEN, Owner::External, Speed::Max, true);
    let addr = running.ttk_addr().expect("a TTK4145 address");
    let mut s = raw(addr);
    // The obstruction switch says the door is open; the client drives up all the same.
    assert_eq!(ttk(&mut s, [9, 0, 0, 0]), Some([9, 1, 0, 0]));
    ttk(&mut s, [1, 1, 0, 0]);
    for _ in 0..29_000 {
        ttk(&mut s, [8, 0, 0, 0]).expect("an answer");
    }
    running.stop();
    let r = running.wait();
    let kinds: Vec<ViolationKind> = r.violations.iter().map(|v| v.kind).collect();
    assert_eq!(
        kinds.first(),
        Some(&ViolationKind::DoorOpenMoving),
        "{kinds:?}"
    );
    assert!(!kinds.contains(&ViolationKind::MechanicalEnd), "{kinds:?}");
    assert!(!r.final_state.contactor_closed);
    assert!(!r.final_state.moving);
    let cause = r.final_state.k1_open_cause.expect("a cause");
    assert!(cause.contains("overtravel"), "{cause}");
}

#[test]
fn clients_that_repeat_themselves_for_ever_leave_a_bounded_log() {
    let running = start_with(QUIET, Owner::External, Speed::Max, true);
    // A TTK4145 client that toggles a lamp 20 000 times (each change is a log line).
    let mut s = raw(running.ttk_addr().expect("a TTK4145 address"));
    let mut batch = Vec::new();
    for i in 0..20_000u32 {
        batch.extend_from_slice(&[2, 2, 0, (i % 2) as u8]);
    }
    s.write_all(&batch).expect("sent");
    assert_eq!(ttk(&mut s, [7, 0, 0, 0]), Some([7, 1, 0, 0]));
    // A Modbus client that acknowledges 3000 times (each command is a log line).
    let mut m = raw(running.local_addr());
    for tid in 0..3000u16 {
        let answer = ask(&mut m, tid, &[6, 0x07, 0xD6, 0, 1]);
        assert_eq!(answer, [6, 0x07, 0xD6, 0, 1]);
    }
    running.stop();
    let r = running.wait();
    let keep = gateway::live::LOG_KEEP;
    for (who, sent) in [(Actor::Ttk4145, 20_000), (Actor::Client, 3000)] {
        let lines: Vec<String> = r
            .log
            .iter()
            .filter(|l| l.who == who)
            .map(rig::report::LogLine::text)
            .collect();
        assert_eq!(lines.len(), 2 * keep + 1, "{who}");
        let marker = format!("… {} lines left out", sent - 2 * keep);
        assert!(lines[keep].starts_with(&marker), "{who}: {}", lines[keep]);
    }
    let live = r.live.expect("live");
    assert_eq!(live.lamps.get("cabin lamp 1"), Some(&1));
}
