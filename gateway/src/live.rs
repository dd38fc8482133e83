//! The rig on the wall clock: its own thread, commands in and state out over
//! crossbeam-channel (the book, "Live mode and your own controller").
//!
//! The rig thread owns the rig and the gateway's state. Every request from a client reaches it
//! as a message and is served between two moments of the simulation, at the simulated time
//! reached; nothing else touches the rig. At a speed factor the simulation follows the wall
//! clock times the factor and counts how far it falls behind; at `max` with the built-in
//! controller it runs free, and with an outside controller it stands still between requests:
//! each request is served, then the simulation advances by the step (1 ms by default), so a
//! client's program and the simulation run in lockstep and the same requests give the same
//! run.

use crate::command;
use crate::map::{Gateway, Owner};
pub use crate::speed::{Speed, MAX_SPEED, MIN_SPEED};
use crate::ttk::Ttk;
use crate::view::{self, Telegrams};
use asi_phy::{SimDuration, SimTime};
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender, TryRecvError};
use rig::report::{LiveReport, LogLine};
use rig::{Report, Rig};
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio_modbus::{ExceptionCode, Request, Response};

/// How a live run goes.
#[derive(Clone, Copy, Debug)]
pub struct LiveConfig {
    /// How fast.
    pub speed: Speed,
    /// Who owns the output image.
    pub owner: Owner,
    /// The gateway's watchdog time (zero = off).
    pub watchdog: SimDuration,
    /// At `max` with an outside controller: how far each request advances the simulation.
    pub step: SimDuration,
}

/// A request from a client, with where its answer goes.
pub struct Call {
    /// The Modbus request.
    pub request: Request<'static>,
    /// Where the answer goes (a client that left drops it).
    pub reply: tokio::sync::oneshot::Sender<Result<Response, ExceptionCode>>,
}

/// A TTK4145 message, with where its answer goes (`None` for a write).
pub struct TtkCall {
    /// The 4-byte message.
    pub msg: [u8; 4],
    /// Where the answer goes.
    pub reply: tokio::sync::oneshot::Sender<Option<[u8; 4]>>,
}

/// A command from the live view's page ([`crate::command`]), with where its answer goes:
/// done, or why not.
pub struct WebCall {
    /// The command, a JSON object not yet checked.
    pub command: serde_json::Value,
    /// Where the answer goes.
    pub reply: tokio::sync::oneshot::Sender<Result<(), String>>,
}

/// The cabin's height and speed over the last [`HISTORY`] of simulated time, for the page's
/// plot: `[t_s, position_mm, velocity_mm_s]`, oldest first, one per snapshot.
pub type History = Arc<Mutex<VecDeque<[f64; 3]>>>;

/// How much of the cabin's past the plot shows.
pub const HISTORY: f64 = 30.0;
/// The most points the history holds (30 s at 25 snapshots per wall second is 750).
const HISTORY_POINTS: usize = 1200;

/// Where the rig thread publishes the live view's snapshots.
#[derive(Clone)]
pub struct ViewOut {
    /// The latest snapshot as JSON text (none before the first); every browser's socket
    /// watches it.
    pub snapshots: tokio::sync::watch::Sender<Option<Arc<str>>>,
    /// The plot's points so far, for a browser that connects.
    pub history: History,
}

/// How often the rig thread builds a snapshot for the live view, wall time: 25 a second, so
/// that a browser gets at least 20 whatever the pacing loop's granularity.
pub const VIEW_EVERY: Duration = Duration::from_millis(40);

/// What reaches the rig thread.
pub enum ToRig {
    /// A client's request.
    Call(Call),
    /// A TTK4145 client's message.
    Ttk(TtkCall),
    /// A command from the live view's page.
    Web(WebCall),
    /// A client connected.
    Connected,
    /// A line for the run's log from the servers (`who`, the text).
    Log(&'static str, String),
    /// End the run now (Ctrl-C).
    Stop,
}

/// What the rig thread tells the outside, about once per wall second and at the end.
#[derive(Clone, Debug, PartialEq)]
pub struct Status {
    /// Simulated time reached, s.
    pub simulated_s: f64,
    /// How far the simulation is behind the wall clock now, ms.
    pub lag_ms: f64,
    /// Requests served so far.
    pub requests: u64,
    /// Violations of the safety invariants so far.
    pub violations: usize,
    /// The gateway's watchdog has zeroed the outputs.
    pub watchdog_tripped: bool,
    /// The run has ended (this is the last status).
    pub ended: bool,
    /// The log lines since the last status that went out, the newest [`STATUS_LOG`] of them
    /// (for a terminal that shows the run as it happens; the report has them all).
    pub log: Vec<LogLine>,
    /// Lines since the last status that are not in `log`.
    pub log_left_out: usize,
}

/// The most log lines a status carries.
pub const STATUS_LOG: usize = 200;

/// Of each source of log lines that the clients drive, a live run keeps the first this many
/// lines and the last this many, and says how many it left out between them
/// ([`Rig::bound_log`]): a client may send the same command millions of times.
pub const LOG_KEEP: usize = 500;
/// The sources the clients drive: the TTK4145 front end, Modbus commands, the page's
/// commands, the gateway's watchdog and the servers' own lines.
const CLIENT_SOURCES: [&str; 6] = ["ttk4145", "client", "web", "gateway", "modbus", "http"];

/// Lag below this is the granularity of the pacing, not falling behind.
const LAG_REPORTED: Duration = Duration::from_millis(2);
/// At `max` with the built-in controller: simulated time between looks at the channel.
const FREE_RUN_SLICE: SimDuration = SimDuration::from_millis(10);
/// How often a status goes out, wall time.
const STATUS_EVERY: Duration = Duration::from_secs(1);

/// The rig thread's loop: runs `rig` until its end or a [`ToRig::Stop`], serving requests
/// from `rx` and sending a [`Status`] to `status` every wall second; returns the report.
pub fn run(rig: Rig, cfg: LiveConfig, rx: &Receiver<ToRig>, status: &Sender<Status>) -> Report {
    run_with_view(rig, cfg, rx, status, None)
}

/// The live view's side of the rig thread: the snapshots it publishes.
struct Viewer {
    out: ViewOut,
    telegrams: Telegrams,
    last: Option<Instant>,
    commands: u64,
}

impl Viewer {
    /// Whether the next snapshot is due.
    fn due(&self) -> bool {
        self.last.is_none_or(|l| l.elapsed() >= VIEW_EVERY)
    }

    /// Publishes a snapshot now.
    fn publish(&mut self, rig: &Rig, run: view::Run) {
        self.last = Some(Instant::now());
        let v = view::build(rig, run, Some(&self.telegrams));
        let point = [v.t_s, v.lift.position_mm, v.lift.velocity_mm_s];
        if let Ok(mut h) = self.out.history.lock() {
            while h
                .front()
                .is_some_and(|p| p[0] < point[0] - HISTORY || h.len() >= HISTORY_POINTS)
            {
                h.pop_front();
            }
            h.push_back(point);
        }
        // The view holds only strings, numbers and booleans: it is always JSON.
        if let Ok(json) = serde_json::to_string(&v) {
            self.out.snapshots.send_replace(Some(json.into()));
        }
    }
}

/// As [`run`], and with `view` publishes a snapshot for the live view every [`VIEW_EVERY`] of
/// wall time and serves the page's commands ([`ToRig::Web`]). The live view adds a transaction
/// observer ([`Rig::on_transaction`]) for its list of the last telegrams.
pub fn run_with_view(
    rig: Rig,
    cfg: LiveConfig,
    rx: &Receiver<ToRig>,
    status: &Sender<Status>,
    view: Option<ViewOut>,
) -> Report {
    let mut t = RigThread::new(rig, cfg, view);
    let mut max_lag = Duration::ZERO;
    let mut lag_warned = false;
    let start = Instant::now();
    let sim0 = t.rig.now();
    let mut at = t.rig.now();
    let mut last_status = Instant::now();
    let mut log_sent = 0;
    let mut stopped = false;
    'run: while !stopped && at < t.rig.end() {
        match cfg.speed {
            Speed::Factor(x) => {
                let wall = start.elapsed();
                let target = sim0 + sim_of(wall.mul_f64(x));
                at = t.advance(at, target);
                let lag = behind(start, sim0, at, x);
                if lag > LAG_REPORTED {
                    max_lag = max_lag.max(lag);
                    if !lag_warned && lag > Duration::from_millis(100) {
                        lag_warned = true;
                        t.rig.log_now(
                            "live",
                            format!(
                                "the machine cannot keep up at speed {x}: {:.0} ms behind the wall clock",
                                lag.as_secs_f64() * 1e3
                            ),
                        );
                    }
                }
                // Wait for a request until the next millisecond of simulated time is due.
                let next = wall_secs(1e-3 / x).min(Duration::from_millis(1));
                match rx.recv_timeout(next) {
                    Ok(m) => stopped |= t.handle(m, at),
                    Err(RecvTimeoutError::Timeout) => {}
                    Err(RecvTimeoutError::Disconnected) => break 'run,
                }
            }
            Speed::Max if cfg.owner == Owner::Builtin => {
                at = t.advance(at, at + FREE_RUN_SLICE);
            }
            Speed::Max => {
                let wait = if t.viewer.is_some() {
                    VIEW_EVERY
                } else {
                    STATUS_EVERY
                };
                match rx.recv_timeout(wait) {
                    Ok(m) => {
                        let call = matches!(m, ToRig::Call(_) | ToRig::Ttk(_));
                        stopped |= t.handle(m, at);
                        if call {
                            at = t.advance(at, at + cfg.step);
                        }
                    }
                    Err(RecvTimeoutError::Timeout) => {}
                    Err(RecvTimeoutError::Disconnected) => break 'run,
                }
            }
        }
        // At a speed factor or running free, everything else waiting is served at the same
        // moment; in lockstep each request has its own step, and none is served at the end.
        let lockstep = cfg.speed == Speed::Max && cfg.owner == Owner::External;
        while !lockstep && at < t.rig.end() {
            match rx.try_recv() {
                Ok(m) => stopped |= t.handle(m, at),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => break 'run,
            }
        }
        if last_status.elapsed() >= STATUS_EVERY {
            last_status = Instant::now();
            let s = status_of(&t.rig, &t.gw, at, start, sim0, cfg.speed, false);
            send_with_log(status, s, &t.rig, &mut log_sent);
        }
        if let Some(v) = t.viewer.as_mut().filter(|v| v.due()) {
            let s = status_of(&t.rig, &t.gw, at, start, sim0, cfg.speed, false);
            v.publish(&t.rig, run_of(&s, cfg));
        }
    }
    let RigThread {
        mut rig,
        gw,
        ttk,
        connections,
        mut viewer,
    } = t;
    if stopped {
        rig.log_now(
            "live",
            "stopped by the operator (Ctrl-C or a termination signal)".into(),
        );
    }
    let last = status_of(&rig, &gw, at, start, sim0, cfg.speed, true);
    if let Some(v) = viewer.as_mut() {
        v.publish(&rig, run_of(&last, cfg));
    }
    send_with_log(status, last, &rig, &mut log_sent);
    // The moment at the end itself, as `asi-lift run` has it, then the report.
    rig.set_end(at);
    let mut report = rig.run(None);
    report.live = Some(LiveReport {
        controller: match cfg.owner {
            Owner::Builtin => "builtin".into(),
            Owner::External => "external".into(),
        },
        speed: cfg.speed.to_string(),
        requests: gw.requests,
        exceptions: gw.exceptions,
        connections,
        watchdog_trips: gw.watchdog_trips,
        max_lag_ms: (max_lag.as_secs_f64() * 1e4).round() / 10.0,
        lamps: ttk.lamps().clone(),
    });
    report
}

/// What the rig thread owns: the rig and everything that serves its clients.
struct RigThread {
    rig: Rig,
    gw: Gateway,
    ttk: Ttk,
    connections: u64,
    viewer: Option<Viewer>,
}

impl RigThread {
    fn new(mut rig: Rig, cfg: LiveConfig, view: Option<ViewOut>) -> RigThread {
        for who in CLIENT_SOURCES {
            rig.bound_log(who, LOG_KEEP, LOG_KEEP);
        }
        let viewer = view.map(|out| Viewer {
            telegrams: view::observe(&mut rig),
            out,
            last: None,
            commands: 0,
        });
        RigThread {
            rig,
            gw: Gateway::new(cfg.owner, cfg.watchdog),
            ttk: Ttk::default(),
            connections: 0,
            viewer,
        }
    }

    /// [`advance`] up to `target`, at most the run's end.
    fn advance(&mut self, at: SimTime, target: SimTime) -> SimTime {
        let target = target.min(self.rig.end());
        advance(&mut self.rig, &mut self.gw, &mut self.ttk, at, target)
    }

    /// Serves one message at `at`; `true` if it ends the run.
    fn handle(&mut self, m: ToRig, at: SimTime) -> bool {
        let (rig, gw, ttk) = (&mut self.rig, &mut self.gw, &mut self.ttk);
        match m {
            ToRig::Web(c) => {
                let answer = match self.viewer.as_mut() {
                    Some(v) => {
                        v.commands += 1;
                        // Every change of the line noise draws from a seed of its own.
                        let seed = 0x6c69_6e65 ^ v.commands;
                        command::parse(&c.command, command::LiftShape::of(rig))
                            .and_then(|cmd| command::apply(rig, &cmd, seed))
                    }
                    None => Err("this run has no live view".into()),
                };
                let _ = c.reply.send(answer);
                false
            }
            ToRig::Ttk(c) => {
                let answer = ttk.serve(rig, gw, at, c.msg);
                let _ = c.reply.send(answer);
                false
            }
            ToRig::Call(c) => {
                let answer = gw.serve(rig, at, &c.request);
                // A client that has gone no longer waits for its answer.
                let _ = c.reply.send(answer);
                false
            }
            ToRig::Connected => {
                self.connections += 1;
                false
            }
            ToRig::Log(who, text) => {
                rig.log_now(who, text);
                false
            }
            ToRig::Stop => true,
        }
    }
}

/// Runs the rig's moments up to `target`, then the watchdog and the TTK4145 front end's
/// display handshakes; returns `target`.
pub(crate) fn advance(
    rig: &mut Rig,
    gw: &mut Gateway,
    ttk: &mut Ttk,
    at: SimTime,
    target: SimTime,
) -> SimTime {
    if target <= at {
        return at;
    }
    while rig.step_until(target).is_some() {}
    gw.watch(rig, target);
    ttk.scan(rig, target);
    target
}

/// The live view's line about the run.
/// Sends `s` with the log lines after the first `sent`; counts them as sent if it went out
/// (a status that finds the channel full waits for the next, and its lines with it).
fn send_with_log(status: &Sender<Status>, mut s: Status, rig: &Rig, sent: &mut usize) {
    let log = rig.log_lines();
    let new = log.get(*sent..).unwrap_or_default();
    let from = new.len().saturating_sub(STATUS_LOG);
    s.log = new[from..].to_vec();
    s.log_left_out = from;
    if status.try_send(s).is_ok() {
        *sent = log.len();
    }
}

fn run_of(s: &Status, cfg: LiveConfig) -> view::Run {
    view::Run {
        speed: cfg.speed.to_string(),
        lag_ms: (s.lag_ms * 10.0).round() / 10.0,
        controller: match cfg.owner {
            Owner::Builtin => "builtin",
            Owner::External => "external",
        },
        requests: s.requests,
        ended: s.ended,
    }
}

fn status_of(
    rig: &Rig,
    gw: &Gateway,
    at: SimTime,
    start: Instant,
    sim0: SimTime,
    speed: Speed,
    ended: bool,
) -> Status {
    let lag_ms = match speed {
        Speed::Factor(x) => behind(start, sim0, at, x).as_secs_f64() * 1e3,
        Speed::Max => 0.0,
    };
    Status {
        simulated_s: at.as_secs_f64(),
        lag_ms: if ended { 0.0 } else { lag_ms },
        requests: gw.requests,
        violations: rig.violations().len(),
        watchdog_tripped: gw.watchdog_tripped(),
        ended,
        log: Vec::new(),
        log_left_out: 0,
    }
}

/// How far simulated time `at` is behind the wall clock at speed `x`, in wall time.
fn behind(start: Instant, sim0: SimTime, at: SimTime, x: f64) -> Duration {
    let due = sim0 + sim_of(start.elapsed().mul_f64(x));
    wall_secs(due.saturating_duration_since(at).as_secs_f64() / x)
}

/// `s` seconds of wall time; a span too long for a `Duration` (or not a number) is the
/// longest one, never a panic.
fn wall_secs(s: f64) -> Duration {
    Duration::try_from_secs_f64(s).unwrap_or(Duration::MAX)
}

fn sim_of(d: Duration) -> SimDuration {
    SimDuration::from_nanos(u64::try_from(d.as_nanos()).unwrap_or(u64::MAX))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pacing_never_panics_at_any_factor() {
        assert_eq!(wall_secs(1e27), Duration::MAX);
        assert_eq!(wall_secs(f64::NAN), Duration::MAX);
        let start = Instant::now();
        assert!(behind(start, SimTime::ZERO, SimTime::ZERO, 1e-30) <= Duration::MAX);
    }
}
