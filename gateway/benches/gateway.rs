//! The gateway under load, on loopback, with the lab rig: not a timed test, a
//! program that prints its figures.
//!
//! 1. **Throughput while keeping real time.** The built-in controller runs a quiet scenario at
//!    speed 1; eight client threads send typical reads (the input image 0..15, LAS, the
//!    simulated time) back to back for the whole run. Figures: requests per second served in
//!    total, the client's round trip, and how far the simulation fell behind the wall clock
//!    (the report's `live.max_lag_ms`, per simulated second). Target: ≥ 5,000 requests/s from
//!    8 clients with a lag below 1 ms per simulated second.
//! 2. **Write to the bus, in simulated time, exact.** An outside controller at speed `max`
//!    (lockstep: the simulation stands still between requests and each request advances it by
//!    exactly 1 ms) writes the converter's output nibble (holding register 1, slave 7 in bits
//!    0..3) 200 times, D0 alternating. The write is served at the simulated time the read of
//!    the time registers just before it gave plus one step, which the read just after checks;
//!    a transaction observer attached in `make_rig` records every Data_Exchange to slave 7.
//!    Figure: from the write to the start of the first Data_Exchange to slave 7 carrying the new
//!    nibble. Target: at most one AS-i cycle (2.0 ms on the lab bus) plus 1 ms.
//! 3. **The same at speed 1**, where the simulation follows the wall clock: the write's
//!    simulated time is only known between the reads just before and just after it (the time
//!    registers count whole ms), so the latency is given as the bounds; and the wall-clock round
//!    trip of the write request, client side.
//!
//! The clients are plain blocking sockets sending Modbus TCP frames (MBAP header, unit 1) and
//! checking every answer (transaction id, protocol, unit, function code, byte count); they cost
//! the two cores less than an async client would, so more of the machine is left to the
//! gateway.
//!
//! `cargo bench -p asi-lift-gateway --bench gateway` (arguments after `--`: the simulated seconds of
//! part 1, default 20). About 25 s.

use asi_phy::{Call, SimDuration, SimTime};
use gateway::live::{LiveConfig, Status};
use gateway::{Owner, Running, Speed};
use rig::{Report, Rig, Scenario};
use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The lab lift standing at floor 1, nobody pressing anything.
fn quiet(seconds: u64) -> Scenario {
    let toml = format!("name = \"quiet\"\nduration = \"{seconds}s\"\n[lift]\nstart_mm = 0.0\n");
    Scenario::from_toml("quiet.toml", &toml).expect("a valid scenario")
}

/// The Data_Exchanges to the converter (slave 7): start of the request, output nibble sent.
type Exchanges = Arc<Mutex<Vec<(SimTime, u8)>>>;

/// The converter's slave address on the lab bus; its nibble is holding register 1, bits 0..3.
const CONVERTER: u8 = 7;

fn start(seconds: u64, owner: Owner, speed: Speed, exchanges: Option<Exchanges>) -> Running {
    let sc = quiet(seconds);
    let make = move || {
        let mut rig = Rig::new(sc.clone()).map_err(gateway::MakeRigError::from)?;
        if let Some(seen) = exchanges.clone() {
            rig.on_transaction(Box::new(move |r| {
                if let Call::DataExchange { address, data } = r.request.call() {
                    if address.get() == CONVERTER {
                        seen.lock()
                            .expect("the observer's list")
                            .push((r.start, data.get()));
                    }
                }
            }));
        }
        Ok(match owner {
            Owner::External => rig.with_external_controller(),
            Owner::Builtin => rig,
        })
    };
    let mut cfg = LiveConfig::default();
    cfg.speed = speed;
    cfg.owner = owner;
    // The bench writes when it likes; the watchdog is not what is measured.
    cfg.watchdog = SimDuration::ZERO;
    cfg.step = SimDuration::from_millis(1);
    let loopback: SocketAddr = "127.0.0.1:0".parse().expect("an address");
    gateway::start(make, cfg, loopback, None).expect("the gateway starts")
}

/// Why a request got no answer to use.
#[derive(Debug)]
enum Fail {
    /// The connection failed or closed (the run has ended).
    Io,
    /// A Modbus exception (04 once the run has ended).
    Exception(u8),
}

impl From<io::Error> for Fail {
    fn from(_: io::Error) -> Fail {
        Fail::Io
    }
}

/// A blocking Modbus TCP client on one connection.
struct Client {
    s: TcpStream,
    tid: u16,
    buf: [u8; 260],
}

impl Client {
    fn connect(addr: SocketAddr) -> Client {
        let s = TcpStream::connect(addr).expect("a connection");
        s.set_nodelay(true).expect("TCP_NODELAY");
        s.set_read_timeout(Some(Duration::from_secs(10)))
            .expect("a timeout");
        Client {
            s,
            tid: 0,
            buf: [0; 260],
        }
    }

    /// Sends `pdu` and returns the answer's PDU (function code first) in `self.buf`.
    fn call(&mut self, pdu: &[u8]) -> Result<&[u8], Fail> {
        self.tid = self.tid.wrapping_add(1);
        let mut frame = [0u8; 7 + 12];
        frame[..2].copy_from_slice(&self.tid.to_be_bytes());
        frame[4..6].copy_from_slice(&(pdu.len() as u16 + 1).to_be_bytes());
        frame[6] = 1;
        frame[7..7 + pdu.len()].copy_from_slice(pdu);
        self.s.write_all(&frame[..7 + pdu.len()])?;
        // The header, then as much of the body as the header announces.
        let mut got = 0;
        let mut want = 7;
        while got < want {
            let n = self.s.read(&mut self.buf[got..])?;
            if n == 0 {
                return Err(Fail::Io);
            }
            got += n;
            if want == 7 && got >= 7 {
                let len = usize::from(u16::from_be_bytes([self.buf[4], self.buf[5]]));
                assert!((2..=254).contains(&len), "a length of {len}");
                want = 6 + len;
            }
        }
        assert_eq!(got, want, "one answer per request");
        let b = &self.buf[..want];
        assert_eq!(u16::from_be_bytes([b[0], b[1]]), self.tid, "transaction id");
        assert_eq!(b[2..4], [0, 0], "protocol id");
        assert_eq!(b[6], 1, "unit id");
        if b[7] == pdu[0] | 0x80 {
            return Err(Fail::Exception(b[8]));
        }
        assert_eq!(b[7], pdu[0], "function code");
        Ok(&self.buf[7..want])
    }

    /// Function 04.
    fn read_input_registers(&mut self, a: u16, n: u16, out: &mut [u16]) -> Result<(), Fail> {
        let [a0, a1] = a.to_be_bytes();
        let [n0, n1] = n.to_be_bytes();
        let pdu = self.call(&[0x04, a0, a1, n0, n1])?;
        assert_eq!(usize::from(pdu[1]), 2 * usize::from(n), "byte count");
        for (w, c) in out.iter_mut().zip(pdu[2..].chunks_exact(2)) {
            *w = u16::from_be_bytes([c[0], c[1]]);
        }
        Ok(())
    }

    /// Function 06.
    fn write_single_register(&mut self, a: u16, v: u16) -> Result<(), Fail> {
        let [a0, a1] = a.to_be_bytes();
        let [v0, v1] = v.to_be_bytes();
        let req = [0x06, a0, a1, v0, v1];
        let pdu = self.call(&req)?;
        assert_eq!(pdu, req, "the echo of the write");
        Ok(())
    }

    /// Simulated time, ms (input registers 1050..1053).
    fn sim_ms(&mut self) -> Result<u64, Fail> {
        let mut w = [0u16; 4];
        self.read_input_registers(1050, 4, &mut w)?;
        Ok(w.iter().fold(0u64, |v, &x| v << 16 | u64::from(x)))
    }

    /// Waits until the master is in normal operation (input register 1016, bit 5) and every
    /// lab slave is in LAS, so that Data_Exchanges carry the output image.
    fn wait_for_the_bus(&mut self) {
        loop {
            let mut w = [0u16; 1];
            self.read_input_registers(1016, 1, &mut w)
                .expect("the flags");
            if w[0] & 1 << 5 != 0 {
                let mut las = [0u16; 1];
                self.read_input_registers(1000, 1, &mut las).expect("LAS");
                if las[0] & 1 << CONVERTER != 0 {
                    return;
                }
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

/// Sorted samples: min, mean, p50, p99, max.
struct Spread {
    min: f64,
    mean: f64,
    p50: f64,
    p99: f64,
    max: f64,
    n: usize,
}

fn spread(mut xs: Vec<f64>) -> Spread {
    assert!(!xs.is_empty(), "samples");
    xs.sort_by(f64::total_cmp);
    let q = |p: f64| xs[((xs.len() - 1) as f64 * p).round() as usize];
    Spread {
        min: xs[0],
        mean: xs.iter().sum::<f64>() / xs.len() as f64,
        p50: q(0.5),
        p99: q(0.99),
        max: xs[xs.len() - 1],
        n: xs.len(),
    }
}

/// Drains the status channel until the run's last status; returns the largest lag seen, ms.
fn follow(running: &Running) -> f64 {
    let mut max_lag: f64 = 0.0;
    while let Ok(Status { lag_ms, ended, .. }) = running.status().recv() {
        max_lag = max_lag.max(lag_ms);
        if ended {
            break;
        }
    }
    max_lag
}

struct Throughput {
    seconds: u64,
    requests: u64,
    wall: Duration,
    rtt_us: Spread,
    report: Report,
    status_lag_ms: f64,
}

/// Part 1: eight clients reading back to back while the built-in controller runs at speed 1.
fn throughput(seconds: u64) -> Throughput {
    const CLIENTS: usize = 8;
    let running = start(seconds, Owner::Builtin, Speed::Factor(1.0), None);
    let addr = running.local_addr();
    let go = Arc::new(AtomicBool::new(false));
    let clients: Vec<_> = (0..CLIENTS)
        .map(|k| {
            let go = Arc::clone(&go);
            std::thread::spawn(move || {
                let mut c = Client::connect(addr);
                while !go.load(Ordering::Acquire) {
                    std::thread::yield_now();
                }
                let mut rtt = Vec::with_capacity(1 << 18);
                let mut words = [0u16; 16];
                let mut last_ms = 0;
                let mut last_ok = Instant::now();
                for i in k.. {
                    let t0 = Instant::now();
                    let r = match i % 3 {
                        0 => c.read_input_registers(0, 16, &mut words),
                        1 => c.read_input_registers(1000, 4, &mut words[..4]),
                        _ => c.sim_ms().map(|ms| {
                            assert!(ms >= last_ms, "simulated time goes on");
                            last_ms = ms;
                        }),
                    };
                    match r {
                        Ok(()) => {
                            last_ok = Instant::now();
                            rtt.push((last_ok - t0).as_secs_f64() * 1e6);
                        }
                        // The run has ended: the gateway answers 04, then closes.
                        Err(Fail::Exception(4) | Fail::Io) => break,
                        Err(e) => panic!("client {k}: {e:?}"),
                    }
                }
                (rtt, last_ok)
            })
        })
        .collect();
    let t0 = Instant::now();
    go.store(true, Ordering::Release);
    let status_lag_ms = follow(&running);
    let report = running.wait();
    let mut all = Vec::new();
    let mut end = t0;
    for c in clients {
        let (rtt, last) = c.join().expect("a client thread");
        all.extend(rtt);
        end = end.max(last);
    }
    Throughput {
        seconds,
        requests: all.len() as u64,
        wall: end - t0,
        rtt_us: spread(all),
        report,
        status_lag_ms,
    }
}

/// For each write (simulated time it was served, nibble written), the first Data_Exchange to
/// the converter at or after `from` that carries the nibble; latency in ms from `at`.
fn first_exchange(seen: &[(SimTime, u8)], from: SimTime, nibble: u8) -> SimTime {
    seen.iter()
        .find(|(t, d)| *t >= from && *d == nibble)
        .map(|(t, _)| *t)
        .expect("a Data_Exchange carried the write")
}

fn ms_between(later: SimTime, earlier: SimTime) -> f64 {
    later.as_nanos() as f64 / 1e6 - earlier.as_nanos() as f64 / 1e6
}

const WRITES: usize = 200;

struct Lockstep {
    latency_ms: Spread,
    /// Data_Exchanges to the converter that started after a write and still carried the old
    /// nibble (a write the bus took late).
    stale: usize,
    rtt_us: Spread,
}

/// The nibble of write `i`: D0 alternating, D1..D3 zero (no direction, so the cabin stays).
fn nibble(i: usize) -> u8 {
    u8::from(i % 2 == 0)
}

/// Part 2: writes in lockstep, each at an exact simulated time.
fn lockstep() -> Lockstep {
    let seen: Exchanges = Arc::default();
    let running = start(60, Owner::External, Speed::Max, Some(Arc::clone(&seen)));
    let mut c = Client::connect(running.local_addr());
    c.wait_for_the_bus();
    let step = 1;
    let mut writes = Vec::new();
    let mut rtt = Vec::new();
    for i in 0..WRITES {
        let before = c.sim_ms().expect("the time");
        let t0 = Instant::now();
        c.write_single_register(1, u16::from(nibble(i)))
            .expect("the write");
        rtt.push(t0.elapsed().as_secs_f64() * 1e6);
        let after = c.sim_ms().expect("the time");
        assert_eq!(after, before + 2 * step, "one step per request");
        writes.push((SimTime::from_millis(before + step), nibble(i)));
        // Twenty more steps: several AS-i cycles and two PLC scans, at which the observer
        // gets the transactions.
        for _ in 0..20 {
            c.sim_ms().expect("the time");
        }
    }
    running.stop();
    let report = running.wait();
    assert!(report.violations.is_empty(), "{:?}", report.violations);
    let seen = seen.lock().expect("the observer's list");
    let mut latency = Vec::new();
    let mut stale = 0;
    for &(at, d) in &writes {
        let dx = first_exchange(&seen, at, d);
        stale += seen
            .iter()
            .filter(|(t, nib)| *t > at && *t < dx && *nib != d)
            .count();
        latency.push(ms_between(dx, at));
    }
    Lockstep {
        latency_ms: spread(latency),
        stale,
        rtt_us: spread(rtt),
    }
}

struct Paced {
    /// Latency measured from the read just after the write (a lower bound) and from the read
    /// just before it (an upper bound).
    low_ms: Spread,
    high_ms: Spread,
    /// From the read before to the read after (+ 1 ms, the registers' resolution), ms.
    bracket_ms: Spread,
    /// Data_Exchanges to the converter that started after the read after a write and still
    /// carried the old nibble.
    stale: usize,
    rtt_us: Spread,
    max_lag_ms: f64,
}

/// Part 3: the same writes at speed 1, a write every 10 ms of wall time.
fn paced() -> Paced {
    let seen: Exchanges = Arc::default();
    let running = start(
        60,
        Owner::External,
        Speed::Factor(1.0),
        Some(Arc::clone(&seen)),
    );
    let mut c = Client::connect(running.local_addr());
    c.wait_for_the_bus();
    let mut writes = Vec::new();
    let mut rtt = Vec::new();
    for i in 0..WRITES {
        let before = c.sim_ms().expect("the time");
        let t0 = Instant::now();
        c.write_single_register(1, u16::from(nibble(i)))
            .expect("the write");
        rtt.push(t0.elapsed().as_secs_f64() * 1e6);
        let after = c.sim_ms().expect("the time");
        writes.push((before, after, nibble(i)));
        std::thread::sleep(Duration::from_millis(10));
    }
    running.stop();
    let report = running.wait();
    let seen = seen.lock().expect("the observer's list");
    let (mut low, mut high, mut bracket) = (Vec::new(), Vec::new(), Vec::new());
    let mut stale = 0;
    for &(before, after, d) in &writes {
        let before = SimTime::from_millis(before);
        // The registers count whole ms: the read after was served before `after` + 1 ms.
        let after = SimTime::from_millis(after + 1);
        let dx = first_exchange(&seen, before, d);
        stale += seen
            .iter()
            .filter(|(t, nib)| *t >= after && *t < dx && *nib != d)
            .count();
        low.push(ms_between(dx, after));
        high.push(ms_between(dx, before));
        bracket.push(ms_between(after, before));
    }
    Paced {
        low_ms: spread(low),
        high_ms: spread(high),
        bracket_ms: spread(bracket),
        stale,
        rtt_us: spread(rtt),
        max_lag_ms: report.live.expect("a live report").max_lag_ms,
    }
}

fn main() {
    let seconds: u64 = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(20);
    println!("cargo bench -p asi-lift-gateway --bench gateway -- {seconds}");
    println!();

    let t = throughput(seconds);
    let live = t.report.live.as_ref().expect("a live report");
    let rate = t.requests as f64 / t.wall.as_secs_f64();
    let lag_per_s = live.max_lag_ms / t.seconds as f64;
    println!(
        "1. 8 clients reading for {seconds} simulated s, built-in controller, speed 1 \
         (target: >= 5000 requests/s, lag < 1 ms per simulated s)"
    );
    println!(
        "   requests served      {:>10} in {:.2} s wall = {rate:.0} requests/s {}",
        t.requests,
        t.wall.as_secs_f64(),
        verdict(rate >= 5000.0)
    );
    println!(
        "   gateway's count      {:>10} requests, {} exceptions, {} connections",
        live.requests, live.exceptions, live.connections
    );
    println!(
        "   round trip (client)  min {:.0} µs, mean {:.0} µs, p50 {:.0} µs, p99 {:.0} µs, max {:.0} µs",
        t.rtt_us.min, t.rtt_us.mean, t.rtt_us.p50, t.rtt_us.p99, t.rtt_us.max
    );
    println!(
        "   lag                  max {:.1} ms (report; below 2 ms counts as 0), {:.3} ms per simulated s {}; \
         largest in the once-a-second status {:.2} ms",
        live.max_lag_ms,
        lag_per_s,
        verdict(lag_per_s < 1.0),
        t.status_lag_ms
    );
    println!(
        "   simulation           {} violations, {} log lines",
        t.report.violations.len(),
        t.report.log.len()
    );
    println!();

    let l = lockstep();
    println!(
        "2. write of the converter's nibble to its next Data_Exchange, lockstep (speed max, \
         1 ms per request), {} writes (target: <= 3.0 ms simulated)",
        l.latency_ms.n
    );
    println!(
        "   latency (simulated)  min {:.3} ms, mean {:.3} ms, max {:.3} ms {}; \
         Data_Exchanges after a write with the old nibble: {}",
        l.latency_ms.min,
        l.latency_ms.mean,
        l.latency_ms.max,
        verdict(l.latency_ms.max <= 3.0),
        l.stale
    );
    println!(
        "   write round trip     min {:.0} µs, mean {:.0} µs, p99 {:.0} µs (wall, client side)",
        l.rtt_us.min, l.rtt_us.mean, l.rtt_us.p99
    );
    println!();

    let p = paced();
    println!(
        "3. the same at speed 1, a write every 10 ms of wall time, {} writes",
        p.rtt_us.n
    );
    println!(
        "   latency (simulated)  at most (from the read before): p50 {:.3} ms, mean {:.3} ms, p99 {:.3} ms, max {:.3} ms",
        p.high_ms.p50, p.high_ms.mean, p.high_ms.p99, p.high_ms.max
    );
    println!(
        "                        at least (from the read after): min {:.3} ms, mean {:.3} ms; \
         reads before and after {:.0} ms apart at p50, {:.0} ms at most",
        p.low_ms.min, p.low_ms.mean, p.bracket_ms.p50, p.bracket_ms.max
    );
    println!(
        "   write round trip     min {:.0} µs, mean {:.0} µs, p99 {:.0} µs, max {:.0} µs (wall, client side)",
        p.rtt_us.min, p.rtt_us.mean, p.rtt_us.p99, p.rtt_us.max
    );
    println!(
        "   lag                  max {:.1} ms; Data_Exchanges after the read after a write with the old nibble: {}",
        p.max_lag_ms, p.stale
    );
}

fn verdict(met: bool) -> &'static str {
    if met {
        "(target met)"
    } else {
        "(TARGET MISSED)"
    }
}
