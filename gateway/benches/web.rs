//! The live view's stream under load: not a timed test, a program that prints its
//! figures.
//!
//! The built-in controller runs a quiet scenario at speed 1 three times, each for the same
//! wall time: (A) without the live view, (B) with it and no browser, (C) with it and eight
//! WebSocket clients that read every message, as eight browsers would. Figures: the CPU time
//! of the server's own threads (the rig thread and the runtime's, by their names in
//! `/proc/self/task/*/stat`; the clients run on threads of their own and are not counted) as
//! a share of one core; the snapshots each client got per wall second and their size; and
//! how far the simulation fell behind the wall clock (the report's `live.max_lag_ms`). The
//! stream's cost is C − A. Targets: at least 20 snapshots per second to every client, the
//! simulation keeping real time, and the stream below 5 % of one core.
//!
//! `cargo bench -p asi-lift-gateway --bench web` (argument after `--`: the wall seconds of each run,
//! default 10). About 35 s.

use futures_util::StreamExt;
use gateway::live::LiveConfig;
use gateway::{Listen, Owner, Running, Speed};
use rig::{Rig, Scenario};
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

const CLIENTS: usize = 8;

fn start(http: bool) -> Running {
    let toml = "name = \"quiet\"\nduration = \"1h\"\n[lift]\nstart_mm = 0.0\n";
    let sc = Scenario::from_toml("quiet.toml", toml).expect("a valid scenario");
    let make = move || Rig::new(sc.clone()).map_err(gateway::MakeRigError::from);
    let cfg = {
        let mut cfg = LiveConfig::default();
        cfg.speed = Speed::Factor(1.0);
        cfg.owner = Owner::Builtin;
        cfg.watchdog = asi_phy::SimDuration::ZERO;
        cfg.step = asi_phy::SimDuration::from_millis(1);
        cfg
    };
    let loopback: SocketAddr = "127.0.0.1:0".parse().expect("an address");
    let listen = Listen {
        modbus: loopback,
        ttk: None,
        http: http.then_some(loopback),
    };
    gateway::start_servers(make, cfg, listen).expect("the gateway starts")
}

/// CPU time (user + system) of this process's threads named `asi-lift-rig` or
/// `asi-lift-gateway` (15 characters of it), by thread id, in seconds.
fn server_cpu() -> Vec<(String, f64)> {
    let mut out = Vec::new();
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return out;
    };
    for t in tasks.flatten() {
        let Ok(stat) = std::fs::read_to_string(t.path().join("stat")) else {
            continue;
        };
        let (Some(open), Some(close)) = (stat.find('('), stat.rfind(')')) else {
            continue;
        };
        let name = &stat[open + 1..close];
        if !(name == "asi-lift-rig" || name.starts_with("asi-lift-gatewa")) {
            continue;
        }
        // After the name: state is field 3; utime and stime are fields 14 and 15, in clock
        // ticks of 1/100 s (USER_HZ).
        let fields: Vec<&str> = stat[close + 2..].split(' ').collect();
        let ticks = |i: usize| fields.get(i - 3).and_then(|f| f.parse::<f64>().ok());
        if let (Some(u), Some(s)) = (ticks(14), ticks(15)) {
            out.push((
                t.file_name().to_string_lossy().into_owned(),
                (u + s) / 100.0,
            ));
        }
    }
    out
}

/// CPU seconds the server's threads spent between two readings.
fn spent(before: &[(String, f64)], after: &[(String, f64)]) -> f64 {
    after
        .iter()
        .map(|(tid, a)| {
            a - before
                .iter()
                .find(|(t, _)| t == tid)
                .map_or(0.0, |(_, b)| *b)
        })
        .sum()
}

struct Figures {
    cpu_share: f64,
    max_lag_ms: f64,
    per_client_per_s: Vec<f64>,
    mean_bytes: f64,
}

fn measure(seconds: u64, http: bool, clients: usize) -> Figures {
    let running = start(http);
    let addr = running.http_addr();
    let stop = Arc::new(AtomicBool::new(false));
    let counts: Arc<Vec<AtomicU64>> = Arc::new((0..clients).map(|_| AtomicU64::new(0)).collect());
    let bytes = Arc::new(AtomicU64::new(0));
    let client_rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .thread_name("bench-client")
        .enable_all()
        .build()
        .expect("the clients' runtime");
    for i in 0..clients {
        let addr = addr.expect("the live view");
        let (stop, counts, bytes) = (stop.clone(), counts.clone(), bytes.clone());
        client_rt.spawn(async move {
            let (mut ws, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/ws"))
                .await
                .expect("the socket opens");
            while !stop.load(Ordering::Relaxed) {
                match tokio::time::timeout(Duration::from_millis(200), ws.next()).await {
                    Ok(Some(Ok(Message::Text(t)))) => {
                        if t.as_str().starts_with("{\"type\":\"view\"") {
                            counts[i].fetch_add(1, Ordering::Relaxed);
                            bytes.fetch_add(t.len() as u64, Ordering::Relaxed);
                        }
                    }
                    Ok(Some(Ok(_))) | Err(_) => {}
                    Ok(_) => return,
                }
            }
        });
    }
    // Let the start-up (the bus's detection, the sockets' handshakes) pass first.
    std::thread::sleep(Duration::from_secs(1));
    let c0: Vec<u64> = counts.iter().map(|c| c.load(Ordering::Relaxed)).collect();
    let b0 = bytes.load(Ordering::Relaxed);
    let cpu0 = server_cpu();
    let t0 = Instant::now();
    std::thread::sleep(Duration::from_secs(seconds));
    let cpu1 = server_cpu();
    let wall = t0.elapsed().as_secs_f64();
    let c1: Vec<u64> = counts.iter().map(|c| c.load(Ordering::Relaxed)).collect();
    let b1 = bytes.load(Ordering::Relaxed);
    stop.store(true, Ordering::Relaxed);
    running.stop();
    let report = running.wait();
    client_rt.shutdown_timeout(Duration::from_secs(1));
    let views: u64 = c1.iter().zip(&c0).map(|(a, b)| a - b).sum();
    Figures {
        cpu_share: spent(&cpu0, &cpu1) / wall,
        max_lag_ms: report.live.map_or(f64::NAN, |l| l.max_lag_ms),
        per_client_per_s: c1
            .iter()
            .zip(&c0)
            .map(|(a, b)| (a - b) as f64 / wall)
            .collect(),
        mean_bytes: if views > 0 {
            (b1 - b0) as f64 / views as f64
        } else {
            0.0
        },
    }
}

fn main() {
    let seconds: u64 = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .and_then(|a| a.parse().ok())
        .unwrap_or(10);
    if server_cpu().is_empty() && std::fs::metadata("/proc/self/task").is_err() {
        eprintln!("this benchmark reads /proc/self/task (Linux)");
    }
    println!("live view under load: quiet scenario at speed 1, {seconds} s of wall time per run");
    let a = measure(seconds, false, 0);
    println!(
        "(A) no live view:             server threads {:5.2} % of one core, max lag {:.1} ms",
        a.cpu_share * 100.0,
        a.max_lag_ms
    );
    let b = measure(seconds, true, 0);
    println!(
        "(B) live view, no browser:    server threads {:5.2} % of one core, max lag {:.1} ms",
        b.cpu_share * 100.0,
        b.max_lag_ms
    );
    let c = measure(seconds, true, CLIENTS);
    let min = c
        .per_client_per_s
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let max = c.per_client_per_s.iter().copied().fold(0.0, f64::max);
    println!(
        "(C) live view, {CLIENTS} clients:     server threads {:5.2} % of one core, max lag {:.1} ms",
        c.cpu_share * 100.0,
        c.max_lag_ms
    );
    println!(
        "    snapshots per client per second: {min:.1} .. {max:.1}, {:.0} bytes each",
        c.mean_bytes
    );
    let cost = (c.cpu_share - a.cpu_share) * 100.0;
    println!(
        "stream cost (C − A): {cost:.2} % of one core (snapshots alone, B − A: {:.2} %; forwarding to {CLIENTS} sockets, C − B: {:.2} %)",
        (b.cpu_share - a.cpu_share) * 100.0,
        (c.cpu_share - b.cpu_share) * 100.0
    );
    let ok = min >= 20.0 && cost < 5.0 && c.max_lag_ms < 100.0;
    println!(
        "targets (>= 20 snapshots/s to every client, cost < 5 %, lag < 100 ms): {}",
        if ok { "met" } else { "NOT met" }
    );
}
