//! The live view without a browser: the page over HTTP, the snapshots and commands over the
//! WebSocket, and what the server does with bad paths, bad bytes and bad commands.

use futures_util::{SinkExt, StreamExt};
use gateway::live::LiveConfig;
use gateway::{Listen, Owner, Running, Speed};
use lift_model::Button;
use rig::report::{ClientLog, LogEvent};
use rig::scenario::Action;
use rig::Actor;
use rig::{Rig, Scenario};
use serde_json::{json, Value};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Message;

type Socket =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// The lab lift standing at floor 1, with the live view, at `speed`.
fn start(speed: Speed) -> Running {
    start_with(speed, gateway::Options::default())
}

/// As [`start`], with the servers' `options`.
fn start_with(speed: Speed, options: gateway::Options) -> Running {
    let toml = "name = \"web\"\nduration = \"10min\"\n[lift]\nstart_mm = 0.0\n";
    let sc = Scenario::from_toml("web.toml", toml).expect("a valid scenario");
    let make = move || Rig::new(sc.clone()).map_err(gateway::MakeRigError::from);
    let cfg = {
        let mut cfg = LiveConfig::default();
        cfg.speed = speed;
        cfg.owner = Owner::Builtin;
        cfg.watchdog = asi_phy::SimDuration::ZERO;
        cfg.step = asi_phy::SimDuration::from_millis(1);
        cfg
    };
    let loopback: SocketAddr = "127.0.0.1:0".parse().expect("an address");
    let listen = Listen {
        modbus: loopback,
        ttk: None,
        http: Some(loopback),
    };
    gateway::start_with(make, cfg, listen, options).expect("the gateway starts")
}

/// A plain HTTP/1.1 request; the status line and the body.
fn http(addr: SocketAddr, request: &str) -> (String, String) {
    let mut s = TcpStream::connect(addr).expect("a connection");
    s.set_read_timeout(Some(Duration::from_secs(5)))
        .expect("a timeout");
    s.write_all(request.as_bytes())
        .expect("the request goes out");
    let mut out = Vec::new();
    let _ = s.read_to_end(&mut out);
    let text = String::from_utf8_lossy(&out).into_owned();
    let status = text.lines().next().unwrap_or("").to_owned();
    let body = text
        .split_once("\r\n\r\n")
        .map(|(_, b)| b.to_owned())
        .unwrap_or_default();
    (status, body)
}

fn get(addr: SocketAddr, path: &str) -> (String, String) {
    http(
        addr,
        &format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"),
    )
}

async fn connect(addr: SocketAddr) -> Socket {
    let (ws, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/ws"))
        .await
        .expect("the socket opens");
    ws
}

/// The next text message, parsed.
async fn next(ws: &mut Socket) -> Value {
    loop {
        let msg = tokio::time::timeout(Duration::from_secs(5), ws.next())
            .await
            .expect("a message within 5 s")
            .expect("the socket is open")
            .expect("a good message");
        if let Message::Text(t) = msg {
            return serde_json::from_str(t.as_str()).expect("JSON");
        }
    }
}

/// The next message of `kind` (`view`, `reply`, `history`).
async fn next_of(ws: &mut Socket, kind: &str) -> Value {
    loop {
        let v = next(ws).await;
        if v["type"] == kind {
            return v;
        }
    }
}

async fn command(ws: &mut Socket, id: u64, cmd: Value) -> Value {
    let text = json!({"id": id, "command": cmd}).to_string();
    ws.send(Message::Text(text.into())).await.expect("sent");
    next_of(ws, "reply").await
}

#[test]
fn the_page_is_served_and_nothing_else() {
    let running = start(Speed::Factor(1.0));
    let addr = running.http_addr().expect("the live view's address");
    let (status, body) = get(addr, "/");
    assert!(status.contains("200"), "{status}");
    assert!(body.contains("<title>asi-lift live view</title>"), "{body}");
    for (path, needle) in [("/app.js", "new WebSocket"), ("/style.css", "@media")] {
        let (status, body) = get(addr, path);
        assert!(status.contains("200"), "{path}: {status}");
        assert!(body.contains(needle), "{path}");
    }
    for path in [
        "/etc/passwd",
        "/../Cargo.toml",
        "/index.htm",
        "/ws/x",
        "/%00",
    ] {
        let (status, _) = get(addr, path);
        assert!(status.contains("404"), "{path}: {status}");
    }
    // Bytes that are not HTTP end that connection, not the server.
    let mut s = TcpStream::connect(addr).expect("a connection");
    s.write_all(b"\x00\xff\x16\x03garbage\r\n\r\n\r\n")
        .expect("bytes go out");
    let _ = s.read(&mut [0u8; 256]);
    let (status, _) = http(
        addr,
        &format!(
            "POST / HTTP/1.1\r\nHost: {addr}\r\nContent-Length: 3\r\nConnection: close\r\n\r\nabc"
        ),
    );
    assert!(status.contains("405"), "{status}");
    // A WebSocket that sends a frame of no known kind is closed; the server goes on.
    let mut s = TcpStream::connect(addr).expect("a connection");
    s.set_read_timeout(Some(Duration::from_secs(5)))
        .expect("a timeout");
    let upgrade = format!(
        "GET /ws HTTP/1.1\r\nHost: {addr}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
    );
    s.write_all(upgrade.as_bytes())
        .expect("the upgrade goes out");
    let mut head = [0u8; 12];
    s.read_exact(&mut head).expect("an answer");
    assert_eq!(&head, b"HTTP/1.1 101");
    s.write_all(&[0x8b, 0x84, 1, 2, 3, 4, 0xde, 0xad, 0xbe, 0xef])
        .expect("a bad frame goes out");
    let mut rest = Vec::new();
    let _ = s.read_to_end(&mut rest);
    let (status, _) = get(addr, "/");
    assert!(status.contains("200"), "the server goes on: {status}");
    running.stop();
    running.wait();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 1)]
async fn the_socket_streams_at_least_20_snapshots_a_second_to_every_browser() {
    let running = start(Speed::Factor(1.0));
    let addr = running.http_addr().expect("the live view's address");
    let mut a = connect(addr).await;
    let mut b = connect(addr).await;
    // First the plot's history, then the current snapshot at once.
    assert_eq!(next(&mut a).await["type"], "history");
    assert_eq!(next(&mut a).await["type"], "view");
    let t0 = Instant::now();
    let mut views = 0;
    let mut first = None;
    let mut last = None;
    while t0.elapsed() < Duration::from_secs(2) {
        let v = next_of(&mut a, "view").await;
        views += 1;
        first.get_or_insert(v["t_s"].as_f64().expect("a time"));
        last = v["t_s"].as_f64();
    }
    let per_s = f64::from(views) / t0.elapsed().as_secs_f64();
    assert!(per_s >= 20.0, "{per_s:.1} snapshots per second");
    // At speed 1 the snapshots follow the wall clock.
    let span = last.expect("a time") - first.expect("a time");
    assert!((1.5..2.5).contains(&span), "{span} s simulated in 2 s");
    // The second browser got the same stream.
    assert_eq!(next(&mut b).await["type"], "history");
    let v = next_of(&mut b, "view").await;
    assert_eq!(v["shaft"]["floors"], 4);
    assert!(v["bus"]["slaves"].as_array().expect("slaves").len() >= 11);
    assert_eq!(v["bus"]["errors"].as_array().expect("errors").len(), 8);
    // The master's LEDs, PWR first, and a light with its counts per slave.
    let leds = v["bus"]["master_leds"].as_array().expect("master_leds");
    assert_eq!(leds.len(), 7);
    assert_eq!(leds[0], serde_json::json!(["pwr", "green"]));
    assert_eq!(leds[6][0], "prj");
    let slave = &v["bus"]["slaves"][0];
    // Early in the run: the counts may still be 0.
    assert!(slave["calls"].is_u64(), "{slave}");
    assert!(slave["repeats"].is_u64());
    assert!(
        slave["light"].is_null() || slave["light"].is_string(),
        "{slave}"
    );
    running.stop();
    tokio::task::spawn_blocking(move || running.wait())
        .await
        .expect("the run ends");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 1)]
async fn a_press_from_the_page_brings_the_cabin_to_floor_3() {
    let running = start(Speed::Factor(10.0));
    let addr = running.http_addr().expect("the live view's address");
    let mut ws = connect(addr).await;
    // Wait for the controller's initialisation at floor 1.
    let t0 = Instant::now();
    loop {
        let v = next_of(&mut ws, "view").await;
        if v["controller"]["initialised"] == true && v["lift"]["velocity_mm_s"] == 0.0 {
            break;
        }
        assert!(t0.elapsed() < Duration::from_secs(20), "no initialisation");
    }
    let r = command(&mut ws, 1, json!({"press": "cabin:3"})).await;
    assert_eq!(r, json!({"type": "reply", "id": 1, "ok": true}));
    let t0 = Instant::now();
    loop {
        let v = next_of(&mut ws, "view").await;
        if v["lift"]["level_floor"] == 3 && v["lift"]["velocity_mm_s"] == 0.0 {
            assert_eq!(v["controller"]["floor"], 3);
            assert_eq!(v["violations"], 0);
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(20),
            "the cabin is at {}",
            v["lift"]["position_mm"]
        );
    }
    running.stop();
    let r = tokio::task::spawn_blocking(move || running.wait())
        .await
        .expect("the run ends");
    assert!(r.arrivals.iter().any(|a| a.floor == 3), "{:?}", r.arrivals);
    assert!(
        r.log.iter().any(|l| l.who == Actor::Web
            && matches!(&l.event, LogEvent::Action(Action::Press { button, .. })
                    if *button == Button::Cabin(3))),
        "the log names the page's press"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 1)]
async fn bad_commands_get_clear_errors_and_the_server_goes_on() {
    let running = start(Speed::Factor(1.0));
    let addr = running.http_addr().expect("the live view's address");
    let mut ws = connect(addr).await;
    let error = |r: &Value| {
        assert_eq!(r["ok"], false, "{r}");
        r["error"].as_str().expect("an error").to_owned()
    };
    let e = error(&command(&mut ws, 1, json!({"press": "cabin:9"})).await);
    assert_eq!(
        e,
        "press: floor `9` does not exist: the lift has floors 1..4"
    );
    let e = error(&command(&mut ws, 2, json!({"fault": {"kind": "meltdown"}})).await);
    assert!(e.starts_with("fault.kind: unknown fault `meltdown`"), "{e}");
    // Once K1 has closed, the hand crank is refused.
    let t0 = Instant::now();
    while next_of(&mut ws, "view").await["lift"]["k1"] != true {
        assert!(t0.elapsed() < Duration::from_secs(5), "K1 stays open");
    }
    let e = error(&command(&mut ws, 3, json!({"crank_mm": 10})).await);
    assert!(e.contains("K1 is closed"), "{e}");
    let e = error(&command(&mut ws, 4, json!({"line_noise": -1})).await);
    assert!(e.starts_with("line_noise:"), "{e}");
    // Not JSON, not an object, a binary message, too long.
    for (msg, needle) in [
        (Message::Text("{\"id\": 1,".into()), "not JSON"),
        (Message::Text("[1]".into()), "a JSON object"),
        (
            Message::Text("{\"id\": 5, \"cmd\": {}}".into()),
            "unknown key `cmd`",
        ),
        (Message::Binary(vec![0u8; 16].into()), "binary"),
        (
            Message::Text("x".repeat(10_000).into()),
            "a command has at most 4096",
        ),
    ] {
        ws.send(msg).await.expect("sent");
        let e = error(&next_of(&mut ws, "reply").await);
        assert!(e.contains(needle), "{e}");
    }
    // A page of another site may not open the socket.
    let mut req = format!("ws://{addr}/ws")
        .into_client_request()
        .expect("a request");
    req.headers_mut().insert(
        "origin",
        "http://attacker.example".parse().expect("a header"),
    );
    assert!(tokio_tungstenite::connect_async(req).await.is_err());
    // A message over the frame limit closes that socket only.
    let mut big = connect(addr).await;
    let _ = big.send(Message::Text("y".repeat(100_000).into())).await;
    // The first socket goes on, and a good command still works.
    let r = command(&mut ws, 6, json!({"door": "open"})).await;
    assert_eq!(r["ok"], true, "{r}");
    let t0 = Instant::now();
    loop {
        let v = next_of(&mut ws, "view").await;
        if v["lift"]["door_closed"] == false {
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(5),
            "the door stays closed"
        );
    }
    // A slave taken off line leaves LAS.
    let r = command(
        &mut ws,
        7,
        json!({"fault": {"kind": "slave-offline", "slave": 11}}),
    )
    .await;
    assert_eq!(r["ok"], true, "{r}");
    let t0 = Instant::now();
    loop {
        let v = next_of(&mut ws, "view").await;
        let slaves = v["bus"]["slaves"].as_array().expect("slaves").clone();
        let s11 = slaves
            .iter()
            .find(|s| s["number"] == 11)
            .expect("slave 11 is projected");
        if s11["las"] == false {
            assert_eq!(s11["lps"], true);
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(5),
            "slave 11 stays in LAS"
        );
    }
    running.stop();
    tokio::task::spawn_blocking(move || running.wait())
        .await
        .expect("the run ends");
}

/// Whether the server closes `s` within `within` (a read gives 0 bytes or an error other than
/// a timeout).
fn closed_within(s: &mut TcpStream, within: Duration) -> bool {
    s.set_read_timeout(Some(within)).expect("a timeout");
    let mut b = [0u8; 256];
    loop {
        match s.read(&mut b) {
            Ok(0) => return true,
            // An answer (408, 400) before the close is fine.
            Ok(_) => {}
            Err(e) => {
                return !matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                )
            }
        }
    }
}

#[test]
fn a_client_that_never_finishes_its_request_head_is_closed_after_the_timeout() {
    let options = {
        let mut cfg = gateway::Options::default();
        cfg.header_timeout = Duration::from_millis(300);
        cfg
    };
    let running = start_with(Speed::Factor(1.0), options);
    let addr = running.http_addr().expect("the live view's address");
    let t0 = Instant::now();
    let mut slow = TcpStream::connect(addr).expect("a connection");
    slow.write_all(format!("GET / HTTP/1.1\r\nHost: {addr}\r\nX-Slow: ").as_bytes())
        .expect("half a head goes out");
    let mut silent = TcpStream::connect(addr).expect("a connection");
    assert!(
        closed_within(&mut slow, Duration::from_secs(5)),
        "the slow head stays open"
    );
    assert!(
        closed_within(&mut silent, Duration::from_secs(5)),
        "the silent client stays open"
    );
    let took = t0.elapsed();
    assert!(
        took >= Duration::from_millis(250),
        "closed before the timeout: {took:?}"
    );
    // A client that sends its request in time is served.
    let (status, _) = get(addr, "/");
    assert!(status.contains("200"), "{status}");
    running.stop();
    running.wait();
}

#[test]
fn connections_beyond_the_bound_are_closed_and_the_others_are_served() {
    let options = {
        let mut cfg = gateway::Options::default();
        cfg.max_connections = 3;
        cfg
    };
    let running = start_with(Speed::Factor(1.0), options);
    let addr = running.http_addr().expect("the live view's address");
    let held: Vec<TcpStream> = (0..3)
        .map(|_| TcpStream::connect(addr).expect("a connection"))
        .collect();
    let mut beyond = TcpStream::connect(addr).expect("a connection");
    assert!(
        closed_within(&mut beyond, Duration::from_secs(5)),
        "a fourth is served"
    );
    drop(held);
    // The places are free again (the server sees the closes a moment later).
    let t0 = Instant::now();
    loop {
        let (status, _) = get(addr, "/");
        if status.contains("200") {
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(5),
            "no place frees: {status}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    running.stop();
    running.wait();
}

#[test]
fn a_foreign_host_name_is_refused_on_every_route_and_the_own_names_are_served() {
    let options = {
        let mut cfg = gateway::Options::default();
        cfg.allow_hosts = vec!["lab-pc.local".into()];
        cfg
    };
    let running = start_with(Speed::Factor(1.0), options);
    let addr = running.http_addr().expect("the live view's address");
    let port = addr.port();
    let request = |host: &str, path: &str, extra: &str| {
        http(
            addr,
            &format!("GET {path} HTTP/1.1\r\nHost: {host}\r\n{extra}Connection: close\r\n\r\n"),
        )
    };
    let upgrade = "Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: \
                   dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n";
    // DNS rebinding: the attacker's name resolves to this machine; Origin and Host agree.
    let evil = format!("evil.example:{port}");
    let evil_origin = format!("Origin: http://{evil}\r\n{upgrade}");
    for path in ["/", "/index.html", "/app.js", "/style.css", "/nothing"] {
        let (status, body) = request(&evil, path, "");
        assert!(status.contains("403"), "{path}: {status}");
        assert!(body.contains("--allow-host"), "{body}");
    }
    let (status, _) = request(&evil, "/ws", &evil_origin);
    assert!(status.contains("403"), "the socket: {status}");
    // No Host at all (HTTP/1.0) is refused too.
    let (status, _) = http(addr, "GET / HTTP/1.0\r\n\r\n");
    assert!(status.contains("403"), "{status}");
    // The own names are served; the allow-list's name with the bound port too.
    for host in [
        addr.to_string(),
        format!("localhost:{port}"),
        format!("127.0.0.2:{port}"),
        format!("lab-pc.local:{port}"),
    ] {
        let (status, _) = request(&host, "/", "");
        assert!(status.contains("200"), "{host}: {status}");
    }
    let (status, _) = request(&format!("lab-pc.local:{}", port.wrapping_add(1)), "/", "");
    assert!(status.contains("403"), "{status}");
    // The socket still wants its Origin to be the Host.
    let own = format!("localhost:{port}");
    let (status, _) = request(
        &own,
        "/ws",
        &format!("Origin: http://evil.example:{port}\r\n{upgrade}"),
    );
    assert!(status.contains("403"), "{status}");
    let mut s = TcpStream::connect(addr).expect("a connection");
    s.set_read_timeout(Some(Duration::from_secs(5)))
        .expect("a timeout");
    let req = format!("GET /ws HTTP/1.1\r\nHost: {own}\r\nOrigin: http://{own}\r\n{upgrade}\r\n");
    s.write_all(req.as_bytes()).expect("the upgrade goes out");
    let mut head = [0u8; 12];
    s.read_exact(&mut head).expect("an answer");
    assert_eq!(&head, b"HTTP/1.1 101");
    drop(s);
    running.stop();
    running.wait();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 1)]
async fn the_run_controls_work_over_the_socket() {
    let running = start(Speed::Factor(1.0));
    let addr = running.http_addr().expect("the live view's address");
    let (_, page) = tokio::task::spawn_blocking(move || get(addr, "/"))
        .await
        .expect("the page");
    for id in ["btn-pause", "speed-select", "btn-restart", "paused"] {
        assert!(
            page.contains(&format!("id=\"{id}\"")),
            "no #{id} on the page"
        );
    }
    let mut ws = connect(addr).await;
    while next_of(&mut ws, "view").await["t_s"].as_f64() < Some(0.2) {}
    let r = command(&mut ws, 1, json!({"pause": true})).await;
    assert_eq!(r, json!({"type": "reply", "id": 1, "ok": true}));
    let mut v = next_of(&mut ws, "view").await;
    while v["run"]["paused"] != true {
        v = next_of(&mut ws, "view").await;
    }
    let paused_at = v["t_s"].clone();
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_millis(400) {
        assert_eq!(next_of(&mut ws, "view").await["t_s"], paused_at);
    }
    // A press while paused is taken, with a note that it waits for the resume.
    let r = command(&mut ws, 2, json!({"press": "cabin:2"})).await;
    assert_eq!(r["ok"], true, "{r}");
    let note = r["note"].as_str().expect("a note");
    assert!(note.contains("when the run resumes"), "{note}");
    let r = command(&mut ws, 3, json!({"speed": 0})).await;
    assert_eq!(r["ok"], false, "{r}");
    assert!(r["error"]
        .as_str()
        .expect("an error")
        .starts_with("speed: 0: expected a factor"));
    assert!(r.get("note").is_none(), "{r}");
    let r = command(&mut ws, 4, json!({"restart": true})).await;
    assert_eq!(r, json!({"type": "reply", "id": 4, "ok": true}));
    while next_of(&mut ws, "view").await["t_s"] != 0.0 {}
    let r = command(&mut ws, 5, json!({"speed": 10})).await;
    assert_eq!(r, json!({"type": "reply", "id": 5, "ok": true}));
    let r = command(&mut ws, 6, json!({"pause": false})).await;
    assert_eq!(r["ok"], true, "{r}");
    let t0 = Instant::now();
    loop {
        let v = next_of(&mut ws, "view").await;
        assert_eq!(v["run"]["speed"], "10");
        if v["t_s"].as_f64() > Some(1.0) {
            assert_eq!(v["run"]["paused"], false);
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(5),
            "the run stands still"
        );
    }
    running.stop();
    let r = tokio::task::spawn_blocking(move || running.wait())
        .await
        .expect("the run ends");
    assert!(r
        .log
        .iter()
        .any(|l| l.who == Actor::Web
            && matches!(l.event, LogEvent::Client(ClientLog::Restarted { .. }))));
}

/// A Structured Text program in the PLC: the view names it, lists its variables with their
/// values as literals (a PLC's online watch list) and, once it faults, says where the PLC
/// went to STOP.
#[tokio::test(flavor = "multi_thread", worker_threads = 1)]
async fn the_view_watches_a_structured_text_programs_variables() {
    let program = "PROGRAM count
VAR
  n : INT;
  zero : INT;
  q : INT;
  elapsed : TIME;
END_VAR
  n := n + 1;
  elapsed := elapsed + T#10ms;
  IF n >= 30 THEN
    q := n / zero;
  END_IF;
END_PROGRAM
";
    let toml = "name = \"web\"\nduration = \"10min\"\n[lift]\nstart_mm = 0.0\n";
    let mut sc = Scenario::from_toml("web.toml", toml).expect("a valid scenario");
    sc.program = Some(
        rig::scenario::program::ProgramFile::from_text(std::path::Path::new("count.st"), program)
            .expect("the program compiles"),
    );
    let make = move || Rig::new(sc.clone()).map_err(gateway::MakeRigError::from);
    let cfg = {
        let mut cfg = LiveConfig::default();
        cfg.speed = Speed::Factor(1.0);
        cfg.owner = Owner::Builtin;
        cfg
    };
    let loopback: SocketAddr = "127.0.0.1:0".parse().expect("an address");
    let listen = Listen {
        modbus: loopback,
        ttk: None,
        http: Some(loopback),
    };
    let running = gateway::start_with(make, cfg, listen, gateway::Options::default())
        .expect("the gateway starts");
    let mut ws = connect(running.http_addr().expect("the live view's address")).await;
    let value = |v: &Value, name: &str| -> String {
        v["controller"]["watch"]
            .as_array()
            .and_then(|w| w.iter().find(|e| e[0] == name))
            .map(|e| e[1].as_str().unwrap_or_default().to_owned())
            .unwrap_or_else(|| panic!("{name} in the watch list: {v}"))
    };
    let first = next_of(&mut ws, "view").await;
    assert_eq!(first["run"]["controller"], "program");
    assert_eq!(first["controller"]["program"], "count.st");
    assert_eq!(first["controller"]["external"], false);
    assert_eq!(first["controller"]["watch_left_out"], 0);
    let t0 = Instant::now();
    let stopped = loop {
        let v = next_of(&mut ws, "view").await;
        // Each scan counts once and adds 10 ms: the two move together.
        let n: i64 = value(&v, "n").parse().expect("an INT literal");
        let elapsed = value(&v, "elapsed");
        if n < 30 {
            assert_eq!(elapsed, format!("T#{}ms", n * 10).replace("T#0ms", "T#0s"));
            assert!(v["controller"]["stopped"].is_null(), "{v}");
        }
        if let Some(s) = v["controller"]["stopped"].as_str() {
            break s.to_owned();
        }
        assert!(t0.elapsed() < Duration::from_secs(20), "no STOP: {v}");
    };
    assert_eq!(stopped, "count.st:11:10: division by zero");
    running.stop();
    let r = tokio::task::spawn_blocking(move || running.wait())
        .await
        .expect("the run ends");
    assert_eq!(r.controller.as_deref(), Some("count.st"));
    assert!(r.violations.is_empty(), "{:?}", r.violations);
}
