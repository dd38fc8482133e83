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
//!
//! The live view's page may pause the run, change its speed or start it again
//! ([`crate::command::RunControl`]). They change only the pacing: a pause stops stepping the
//! rig (requests are still served, from the image of the moment reached), and a resume or a
//! new speed measures the wall clock afresh from the moment reached, so the run goes on from
//! where it stood and never catches up; the simulation is the same as without them. A
//! restart makes a fresh rig from the run's configuration ([`Remake`]).

use crate::command::{self, Command, RunControl};
use crate::map::{Gateway, Owner};
pub use crate::speed::{Speed, MAX_SPEED, MIN_SPEED};
use crate::ttk::Ttk;
use crate::view::{self, Telegrams};
use asi_phy::{SimDuration, SimTime};
use controller::structured::StProgram;
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender, TryRecvError};
use rig::report::{Actor, ClientLog, LiveReport, LogLine};
use rig::{Report, Rig};
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio_modbus::{ExceptionCode, Request, Response};

/// How a live run goes.
#[derive(Clone, Copy, Debug)]
#[non_exhaustive]
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

impl Default for LiveConfig {
    /// What `asi-lift serve` runs without options: real time, the built-in program, a 1 s
    /// watchdog, 1 ms per request at `max`.
    fn default() -> Self {
        LiveConfig {
            speed: Speed::Factor(1.0),
            owner: Owner::Builtin,
            watchdog: SimDuration::from_secs(1),
            step: SimDuration::from_millis(1),
        }
    }
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

/// The answer to a command from the page: done (with a note for the page, such as a warning
/// about the speed or that the run is paused), or why not.
pub type WebAnswer = Result<Option<String>, String>;

/// A command from the live view's page ([`crate::command`]), with where its answer goes.
pub struct WebCall {
    /// The command, a JSON object not yet checked.
    pub command: serde_json::Value,
    /// Where the answer goes.
    pub reply: tokio::sync::oneshot::Sender<WebAnswer>,
}

/// Makes the run's rig again, as at its start (the same scenario, seed, controller and
/// outputs), for a restart from the page.
pub type Remake<'a> = &'a mut dyn FnMut() -> Result<Rig, MakeRigError>;

/// Why a live run's rig could not be made: the rig's own [`rig::RigError`], or what the
/// caller's maker needs besides (a trace file to open, say).
pub type MakeRigError = Box<dyn std::error::Error + Send + Sync>;

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
    Log(Actor, ClientLog),
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
    /// The page has paused the run: simulated time stands still.
    pub paused: bool,
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
const CLIENT_SOURCES: [Actor; 6] = [
    Actor::Ttk4145,
    Actor::Client,
    Actor::Web,
    Actor::Gateway,
    Actor::ModbusServer,
    Actor::HttpServer,
];

/// Lag below this is the granularity of the pacing, not falling behind.
const LAG_REPORTED: Duration = Duration::from_millis(2);
/// At `max` with the built-in controller: simulated time between looks at the channel.
const FREE_RUN_SLICE: SimDuration = SimDuration::from_millis(10);
/// How often a status goes out, wall time.
const STATUS_EVERY: Duration = Duration::from_secs(1);

/// The rig thread's loop: runs `rig` until its end or a [`ToRig::Stop`], serving requests
/// from `rx` and sending a [`Status`] to `status` every wall second; returns the report.
pub fn run(rig: Rig, cfg: LiveConfig, rx: &Receiver<ToRig>, status: &Sender<Status>) -> Report {
    run_with_view(rig, cfg, rx, status, None, None)
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

    /// Starts again on `rig`, a fresh one: its own observer, an empty plot, the commands
    /// counted (for the line noise's seeds) from zero as in a fresh run.
    fn restart(&mut self, rig: &mut Rig) {
        self.telegrams = view::observe(rig);
        self.commands = 0;
        self.last = None;
        if let Ok(mut h) = self.out.history.lock() {
            h.clear();
        }
    }
}

/// As [`run`], and with `view` publishes a snapshot for the live view every [`VIEW_EVERY`] of
/// wall time and serves the page's commands ([`ToRig::Web`]). The live view adds a transaction
/// observer ([`Rig::on_transaction`]) for its list of the last telegrams. With `remake`, the
/// page may start the run again ([`crate::command::RunControl::Restart`]); without it a
/// restart is refused.
pub fn run_with_view(
    rig: Rig,
    cfg: LiveConfig,
    rx: &Receiver<ToRig>,
    status: &Sender<Status>,
    view: Option<ViewOut>,
    remake: Option<Remake<'_>>,
) -> Report {
    let mut t = RigThread::new(rig, cfg, view, remake);
    let mut last_status = Instant::now();
    let mut stopped = false;
    'run: while !stopped && t.at < t.rig.end() {
        match t.cfg.speed {
            _ if t.paused => {
                // Simulated time stands still; requests are served at the moment reached.
                match rx.recv_timeout(t.wait()) {
                    Ok(m) => stopped |= t.handle(m),
                    Err(RecvTimeoutError::Timeout) => {}
                    Err(RecvTimeoutError::Disconnected) => break 'run,
                }
            }
            Speed::Factor(x) => {
                let target = t.sim0 + sim_of(t.start.elapsed().mul_f64(x));
                t.advance(target);
                t.watch_lag(x);
                // Wait for a request until the next millisecond of simulated time is due.
                let next = wall_secs(1e-3 / x).min(Duration::from_millis(1));
                match rx.recv_timeout(next) {
                    Ok(m) => stopped |= t.handle(m),
                    Err(RecvTimeoutError::Timeout) => {}
                    Err(RecvTimeoutError::Disconnected) => break 'run,
                }
            }
            Speed::Max if t.cfg.owner == Owner::Builtin => {
                t.advance(t.at + FREE_RUN_SLICE);
            }
            Speed::Max => match rx.recv_timeout(t.wait()) {
                Ok(m) => {
                    let call = matches!(m, ToRig::Call(_) | ToRig::Ttk(_));
                    stopped |= t.handle(m);
                    if call {
                        t.advance(t.at + t.cfg.step);
                    }
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break 'run,
            },
        }
        // At a speed factor, running free or paused, everything else waiting is served at
        // the same moment; in lockstep each request has its own step, and none is served at
        // the end.
        while !t.lockstep() && t.at < t.rig.end() {
            match rx.try_recv() {
                Ok(m) => stopped |= t.handle(m),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => break 'run,
            }
        }
        if last_status.elapsed() >= STATUS_EVERY {
            last_status = Instant::now();
            t.send_status(status, false);
        }
        if t.viewer.as_ref().is_some_and(Viewer::due) {
            t.publish(false);
        }
    }
    if stopped {
        t.rig.log_now(Actor::Live, ClientLog::StoppedBySignal);
    }
    t.publish(true);
    t.send_status(status, true);
    let RigThread {
        mut rig,
        gw,
        ttk,
        cfg,
        connections,
        at,
        max_lag,
        ..
    } = t;
    // The moment at the end itself, as `asi-lift run` has it, then the report.
    rig.set_end(at);
    let controller = owner_name(&rig, cfg.owner).into();
    let mut report = rig.run(None);
    report.live = Some(LiveReport {
        controller,
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

/// Who runs the lift, for the page and the report: `builtin` (the built-in program),
/// `program` (a Structured Text program in the rig's PLC; the report names its file) or
/// `external` (a client).
fn owner_name(rig: &Rig, owner: Owner) -> &'static str {
    match owner {
        Owner::External => "external",
        Owner::Builtin if rig.controller::<StProgram>().is_some() => "program",
        Owner::Builtin => "builtin",
    }
}

/// What the rig thread owns: the rig, everything that serves its clients, and the pacing.
struct RigThread<'a> {
    rig: Rig,
    gw: Gateway,
    ttk: Ttk,
    /// The run's configuration; its speed is the one now (the page may change it).
    cfg: LiveConfig,
    connections: u64,
    viewer: Option<Viewer>,
    remake: Option<Remake<'a>>,
    /// The simulated time reached: the rig has run every moment up to it.
    at: SimTime,
    /// The page has paused the run.
    paused: bool,
    /// At a speed factor, simulated time follows the wall clock from `start`, where it was
    /// `sim0`: measured afresh at a resume and at a change of speed, so that the run never
    /// catches up on time it stood still.
    start: Instant,
    sim0: SimTime,
    /// The most the simulation fell behind, and whether the log has said so.
    max_lag: Duration,
    lag_warned: bool,
    /// How many of the rig's log lines went out with a status.
    log_sent: usize,
}

impl<'a> RigThread<'a> {
    fn new(
        mut rig: Rig,
        cfg: LiveConfig,
        view: Option<ViewOut>,
        remake: Option<Remake<'a>>,
    ) -> RigThread<'a> {
        for who in CLIENT_SOURCES {
            rig.bound_log(who, LOG_KEEP, LOG_KEEP);
        }
        let viewer = view.map(|out| Viewer {
            telegrams: view::observe(&mut rig),
            out,
            last: None,
            commands: 0,
        });
        let at = rig.now();
        RigThread {
            rig,
            gw: Gateway::new(cfg.owner, cfg.watchdog),
            ttk: Ttk::default(),
            cfg,
            connections: 0,
            viewer,
            remake,
            at,
            paused: false,
            start: Instant::now(),
            sim0: at,
            max_lag: Duration::ZERO,
            lag_warned: false,
            log_sent: 0,
        }
    }

    /// In lockstep: at `max` with an outside controller, and not paused.
    fn lockstep(&self) -> bool {
        !self.paused && self.cfg.speed == Speed::Max && self.cfg.owner == Owner::External
    }

    /// How long to wait for a message when the simulation does not advance by itself.
    fn wait(&self) -> Duration {
        if self.viewer.is_some() {
            VIEW_EVERY
        } else {
            STATUS_EVERY
        }
    }

    /// Measures the wall clock afresh from the moment reached: no lag from before.
    fn anchor(&mut self) {
        self.start = Instant::now();
        self.sim0 = self.at;
    }

    /// [`advance`] up to `target`, at most the run's end.
    fn advance(&mut self, target: SimTime) {
        let target = target.min(self.rig.end());
        self.at = advance(&mut self.rig, &mut self.gw, &mut self.ttk, self.at, target);
    }

    /// At speed `x`: keeps the largest lag, and says once in the log if the machine cannot
    /// keep up.
    fn watch_lag(&mut self, x: f64) {
        let lag = behind(self.start, self.sim0, self.at, x);
        if lag <= LAG_REPORTED {
            return;
        }
        self.max_lag = self.max_lag.max(lag);
        if !self.lag_warned && lag > Duration::from_millis(100) {
            self.lag_warned = true;
            let behind = ClientLog::Behind {
                speed: x.to_string(),
                lag_ms: lag.as_secs_f64() * 1e3,
            };
            self.rig.log_now(Actor::Live, behind);
        }
    }

    /// How far behind the wall clock the simulation is now, ms (0 at `max`, paused, ended).
    fn lag_ms(&self, ended: bool) -> f64 {
        match self.cfg.speed {
            Speed::Factor(x) if !self.paused && !ended => {
                behind(self.start, self.sim0, self.at, x).as_secs_f64() * 1e3
            }
            _ => 0.0,
        }
    }

    fn status(&self, ended: bool) -> Status {
        Status {
            simulated_s: self.at.as_secs_f64(),
            lag_ms: self.lag_ms(ended),
            requests: self.gw.requests,
            violations: self.rig.violations().len(),
            watchdog_tripped: self.gw.watchdog_tripped(),
            paused: self.paused,
            ended,
            log: Vec::new(),
            log_left_out: 0,
        }
    }

    /// Sends a status with the log lines since the last one that went out; counts them as
    /// sent if it went out (a status that finds the channel full waits for the next, and its
    /// lines with it).
    fn send_status(&mut self, status: &Sender<Status>, ended: bool) {
        let mut s = self.status(ended);
        let log = self.rig.log_lines();
        let new = log.get(self.log_sent..).unwrap_or_default();
        let from = new.len().saturating_sub(STATUS_LOG);
        s.log = new[from..].to_vec();
        s.log_left_out = from;
        if status.try_send(s).is_ok() {
            self.log_sent = log.len();
        }
    }

    /// Publishes a snapshot for the live view, if there is one.
    fn publish(&mut self, ended: bool) {
        let run = view::Run {
            speed: self.cfg.speed.to_string(),
            lag_ms: (self.lag_ms(ended) * 10.0).round() / 10.0,
            controller: owner_name(&self.rig, self.cfg.owner),
            requests: self.gw.requests,
            paused: self.paused,
            ended,
        };
        if let Some(v) = self.viewer.as_mut() {
            v.publish(&self.rig, run);
        }
    }

    /// Serves one message at the moment reached; `true` if it ends the run.
    fn handle(&mut self, m: ToRig) -> bool {
        let at = self.at;
        let (rig, gw, ttk) = (&mut self.rig, &mut self.gw, &mut self.ttk);
        match m {
            ToRig::Web(c) => {
                let answer = self.web(&c.command);
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

    /// Does a command from the page.
    fn web(&mut self, command: &serde_json::Value) -> WebAnswer {
        if self.viewer.is_none() {
            return Err("this run has no live view".into());
        }
        let cmd = command::parse(command, command::LiftShape::of(&self.rig));
        if let Ok(Command::Run(control)) = cmd {
            return self.control(control);
        }
        let commands = self.viewer.as_mut().map_or(0, |v| {
            v.commands += 1;
            v.commands
        });
        // Every change of the line noise draws from a seed of its own.
        let seed = 0x6c69_6e65 ^ commands;
        cmd.and_then(|cmd| command::apply(&mut self.rig, &cmd, seed))?;
        // While paused, the command happens at the moment the run stands at, the moment it
        // goes on from: it takes effect when the run resumes.
        Ok(self.paused.then(|| {
            format!(
                "paused at {:.3} s: it takes effect when the run resumes",
                self.at.as_secs_f64()
            )
        }))
    }

    /// Does one of the run's controls from the page (logged as `web`, as its other commands).
    fn control(&mut self, control: RunControl) -> WebAnswer {
        match control {
            RunControl::Pause(pause) => {
                if pause != self.paused {
                    self.paused = pause;
                    self.anchor();
                    self.rig.log_now(Actor::Web, ClientLog::Paused(pause));
                }
                Ok(None)
            }
            RunControl::Speed(speed) => {
                let speed = speed.checked().map_err(|e| e.to_string())?;
                if speed != self.cfg.speed {
                    let was = self.cfg.speed;
                    self.cfg.speed = speed;
                    self.anchor();
                    self.lag_warned = false;
                    let set = ClientLog::Speed {
                        speed: speed.to_string(),
                        was: was.to_string(),
                    };
                    self.rig.log_now(Actor::Web, set);
                }
                Ok(match (self.cfg.owner, speed) {
                    (Owner::Builtin, _) => None,
                    (Owner::External, Speed::Max) => Some(format!(
                        "at max the simulation advances only with the outside controller's requests, {} ms each (lockstep)",
                        self.cfg.step.as_nanos() as f64 / 1e6
                    )),
                    (Owner::External, Speed::Factor(_)) => speed.outside_controller_warning(),
                })
            }
            RunControl::Restart => self.restart().map(|()| None),
        }
    }

    /// Starts the run again from its beginning on a fresh rig from the run's configuration
    /// (its scenario and seed; its trace, if any, starts again too). The gateway and the
    /// TTK4145 front end start afresh as at the command's start (counters, watchdog time,
    /// lamps); the clients' connections, the pause and the speed stay.
    fn restart(&mut self) -> Result<(), String> {
        let remake = self
            .remake
            .as_mut()
            .ok_or("restart: this run cannot make its rig again")?;
        let mut rig = remake().map_err(|e| format!("restart: {e}"))?;
        for who in CLIENT_SOURCES {
            rig.bound_log(who, LOG_KEEP, LOG_KEEP);
        }
        if let Some(v) = self.viewer.as_mut() {
            v.restart(&mut rig);
        }
        let restarted = ClientLog::Restarted {
            reached_s: self.at.as_secs_f64(),
        };
        rig.log_now(Actor::Web, restarted);
        // The earlier rig goes here, with its outputs.
        self.rig = rig;
        self.gw = Gateway::new(self.cfg.owner, self.cfg.watchdog);
        self.ttk = Ttk::default();
        self.at = self.rig.now();
        self.anchor();
        self.max_lag = Duration::ZERO;
        self.lag_warned = false;
        self.log_sent = 0;
        Ok(())
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
