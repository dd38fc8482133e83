//! The live view's run controls on the rig thread itself, without a network: pause and
//! resume, the speed, restart ([`gateway::command::RunControl`]); commands and Modbus requests
//! reach the rig thread as the servers send them.

use asi_phy::{SimDuration, SimTime};
use asi_trace::trace::TraceFormat;
use gateway::live::{self, LiveConfig, Status, ToRig, ViewOut, WebAnswer, WebCall};
use gateway::{Owner, Speed};
use rig::report::{ClientLog, LogEvent};
use rig::Actor;
use rig::{Report, Rig, Scenario};
use serde_json::{json, Value};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use tokio_modbus::{Request, Response};

/// A writer into memory that the test reads afterwards (a trace).
#[derive(Clone, Default)]
struct Shared(Arc<Mutex<Vec<u8>>>);

impl std::io::Write for Shared {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.lock().expect("the buffer").extend_from_slice(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Shared {
    fn bytes(&self) -> Vec<u8> {
        self.0.lock().expect("the buffer").clone()
    }
}

/// The lab lift at floor 1, with line noise (so that the seed matters) and a call at 1 s.
const NOISY: &str = "name = \"controls\"\nseed = 7\nduration = \"4s\"\n[lift]\nstart_mm = 0.0\n\
                     [bus]\npulse_error_rate = 0.0005\n[[event]]\nat = \"1s\"\npress = \"cabin:2\"\n";

/// The lab lift at floor 1 for ten minutes.
const LONG: &str = "name = \"controls\"\nduration = \"10min\"\n[lift]\nstart_mm = 0.0\n";

/// A live run on its own thread, as `gateway::start_with` runs it, with the channels in the
/// test's hands.
struct Live {
    tx: crossbeam_channel::Sender<ToRig>,
    snapshots: tokio::sync::watch::Receiver<Option<Arc<str>>>,
    /// The trace of the latest run (a restart starts a new one).
    trace: Arc<Mutex<Shared>>,
    thread: JoinHandle<Report>,
    // Kept so that the rig thread's statuses have somewhere to go.
    _status: crossbeam_channel::Receiver<Status>,
}

fn config(owner: Owner, speed: Speed) -> LiveConfig {
    {
        let mut cfg = LiveConfig::default();
        cfg.speed = speed;
        cfg.owner = owner;
        cfg.watchdog = SimDuration::from_secs(1);
        cfg.step = SimDuration::from_millis(1);
        cfg
    }
}

impl Live {
    fn start(toml: &str, cfg: LiveConfig) -> Live {
        let sc = Scenario::from_toml("controls.toml", toml).expect("a valid scenario");
        let (tx, rx) = crossbeam_channel::unbounded();
        let (status_tx, status) = crossbeam_channel::bounded(64);
        let (snapshots_tx, snapshots) = tokio::sync::watch::channel(None);
        let view = ViewOut {
            snapshots: snapshots_tx,
            history: live::History::default(),
        };
        let trace = Arc::new(Mutex::new(Shared::default()));
        let latest = Arc::clone(&trace);
        let thread = std::thread::spawn(move || {
            // Each run of the rig writes a trace of its own.
            let mut make = move || {
                let mut rig = Rig::new(sc.clone()).map_err(gateway::MakeRigError::from)?;
                if cfg.owner == Owner::External {
                    rig = rig.with_external_controller();
                }
                let out = Shared::default();
                *latest.lock().expect("the trace") = out.clone();
                rig.trace_to(Box::new(out), TraceFormat::Jsonl);
                Ok(rig)
            };
            let rig = make().expect("a rig");
            live::run_with_view(rig, cfg, &rx, &status_tx, Some(view), Some(&mut make))
        });
        Live {
            tx,
            snapshots,
            trace,
            thread,
            _status: status,
        }
    }

    /// Sends a command as the page does; the rig thread's answer.
    fn web(&self, command: Value) -> WebAnswer {
        let (reply, answer) = tokio::sync::oneshot::channel();
        self.tx
            .send(ToRig::Web(WebCall { command, reply }))
            .expect("the rig thread runs");
        answer.blocking_recv().expect("an answer")
    }

    /// A Modbus request as a client sends it; the answer.
    fn modbus(&self, request: Request<'static>) -> Response {
        let (reply, answer) = tokio::sync::oneshot::channel();
        self.tx
            .send(ToRig::Call(live::Call { request, reply }))
            .expect("the rig thread runs");
        answer
            .blocking_recv()
            .expect("an answer")
            .expect("no exception")
    }

    /// Simulated time as a Modbus client reads it (input registers 1050..1053).
    fn modbus_time(&self) -> SimTime {
        let Response::ReadInputRegisters(w) = self.modbus(Request::ReadInputRegisters(1050, 4))
        else {
            panic!("not an answer to a read");
        };
        SimTime::from_millis(w.iter().fold(0u64, |v, &x| v << 16 | u64::from(x)))
    }

    /// The latest snapshot the page would get, after `wait` (a snapshot goes out every 40 ms).
    fn view_after(&self, wait: Duration) -> Value {
        std::thread::sleep(wait);
        let t0 = Instant::now();
        loop {
            if let Some(text) = self.snapshots.borrow().clone() {
                return serde_json::from_str(&text).expect("JSON");
            }
            assert!(t0.elapsed() < Duration::from_secs(30), "no snapshot");
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// How many simulated seconds pass per wall second over `wall`, as a Modbus client reads
    /// the simulated time.
    fn rate_over(&self, wall: Duration) -> f64 {
        let (t0, w0) = (self.modbus_time(), Instant::now());
        std::thread::sleep(wall);
        let (t1, w1) = (self.modbus_time(), Instant::now());
        (t1 - t0).as_secs_f64() / (w1 - w0).as_secs_f64()
    }

    /// The simulated time the page shows after `wait`.
    fn t_after(&self, wait: Duration) -> f64 {
        self.view_after(wait)["t_s"].as_f64().expect("a time")
    }

    /// Ends the run (as Ctrl-C does, or at its end); the report and the last run's trace.
    fn end(self, stop: bool) -> (Report, Vec<u8>) {
        if stop {
            let _ = self.tx.send(ToRig::Stop);
        }
        let report = self.thread.join().expect("the rig thread ends");
        let trace = self.trace.lock().expect("the trace").bytes();
        (report, trace)
    }
}

/// The report without what the wall clock and the page's run controls add: the `live`
/// object, the page's log lines and the live loop's own (a machine that cannot keep up).
fn without_the_live_run(mut r: Report) -> Report {
    r.live = None;
    r.log
        .retain(|l| l.who != Actor::Web && l.who != Actor::Live);
    r
}

/// Waits until the snapshot's time passes `t_s`.
fn wait_past(live: &Live, t_s: f64) {
    let t0 = Instant::now();
    while live.t_after(Duration::from_millis(20)) <= t_s {
        assert!(
            t0.elapsed() < Duration::from_secs(30),
            "the run stands at {t_s} s"
        );
    }
}

#[test]
fn a_paused_run_stands_still_and_goes_on_from_where_it_stood_without_catching_up() {
    let live = Live::start(LONG, config(Owner::Builtin, Speed::Factor(1.0)));
    wait_past(&live, 0.2);
    assert_eq!(live.web(json!({"pause": true})), Ok(None));
    let v = live.view_after(Duration::from_millis(100));
    assert_eq!(v["run"]["paused"], true);
    assert_eq!(v["run"]["lag_ms"], 0.0);
    let paused_at = v["t_s"].as_f64().expect("a time");
    // A second of wall time: simulated time stands still, and a Modbus client reads it.
    let modbus = live.modbus_time();
    let v = live.view_after(Duration::from_secs(1));
    assert_eq!(
        v["t_s"].as_f64(),
        Some(paused_at),
        "time went on while paused"
    );
    assert_eq!(live.modbus_time(), modbus);
    assert!(
        (modbus.as_secs_f64() - paused_at).abs() < 0.002,
        "{modbus:?} against {paused_at}"
    );
    // Pausing again changes nothing; a press waits for the resume, lit on the page meanwhile.
    assert_eq!(live.web(json!({"pause": true})), Ok(None));
    let note = live
        .web(json!({"press": "cabin:3"}))
        .expect("the press is taken")
        .expect("a note");
    assert!(note.contains("takes effect when the run resumes"), "{note}");
    let v = live.view_after(Duration::from_millis(100));
    assert_eq!(v["t_s"].as_f64(), Some(paused_at));
    assert!(
        v["lift"]["pressed"]
            .as_array()
            .expect("the buttons")
            .contains(&json!("cabin:3")),
        "{}",
        v["lift"]["pressed"]
    );
    // Resumed, it goes on from where it stood: no jump for the second it stood still.
    assert_eq!(live.web(json!({"pause": false})), Ok(None));
    let v = live.view_after(Duration::from_millis(300));
    assert_eq!(v["run"]["paused"], false);
    let went = v["t_s"].as_f64().expect("a time") - paused_at;
    assert!(
        went > 0.05 && went < 0.8,
        "{went} s simulated in 0.3 s after the resume"
    );
    assert!(
        v["run"]["lag_ms"].as_f64().expect("a lag") < 100.0,
        "{}",
        v["run"]["lag_ms"]
    );
    let (report, _) = live.end(true);
    let web: Vec<String> = report
        .log
        .iter()
        .filter(|l| l.who == Actor::Web)
        .map(rig::report::LogLine::text)
        .collect();
    assert_eq!(web.len(), 3, "{web:?}");
    assert_eq!(web[0], "run paused by the page");
    assert!(web[1].contains("cabin button 3"), "{web:?}");
    assert_eq!(web[2], "run resumed by the page");
    let live_report = report.live.expect("the live figures");
    assert!(live_report.max_lag_ms < 100.0, "{}", live_report.max_lag_ms);
}

#[test]
fn a_run_paused_and_resumed_is_the_same_run_as_one_that_was_not() {
    // Speed 10: the 4 simulated seconds take 0.4 s of wall time.
    let cfg = config(Owner::Builtin, Speed::Factor(10.0));
    let (plain, plain_trace) = Live::start(NOISY, cfg).end(false);
    let live = Live::start(NOISY, cfg);
    wait_past(&live, 0.5);
    assert_eq!(live.web(json!({"pause": true})), Ok(None));
    std::thread::sleep(Duration::from_millis(150));
    assert_eq!(live.web(json!({"speed": 20})), Ok(None));
    assert_eq!(live.web(json!({"pause": false})), Ok(None));
    assert_eq!(live.web(json!({"pause": true})), Ok(None));
    std::thread::sleep(Duration::from_millis(20));
    assert_eq!(live.web(json!({"pause": false})), Ok(None));
    let (paused, paused_trace) = live.end(false);
    assert!(
        paused
            .log
            .iter()
            .any(|l| l.who == Actor::Web && l.event == LogEvent::Client(ClientLog::Paused(true))),
        "the pause came after the run's end: {:?}",
        paused.log
    );
    assert_eq!(paused.simulated_s, 4.0);
    assert!(!plain_trace.is_empty());
    assert!(
        plain_trace == paused_trace,
        "the traces differ ({} and {} bytes)",
        plain_trace.len(),
        paused_trace.len()
    );
    assert_eq!(without_the_live_run(plain), without_the_live_run(paused));
}

#[test]
fn a_restart_runs_the_scenario_again_from_0_with_the_same_seed() {
    let cfg = config(Owner::Builtin, Speed::Factor(5.0));
    let (fresh, fresh_trace) = Live::start(NOISY, cfg).end(false);
    let live = Live::start(NOISY, cfg);
    // The earlier run: past the scenario's call at 1 s, and a press of the page's own.
    wait_past(&live, 1.5);
    assert_eq!(live.web(json!({"press": "cabin:4"})), Ok(None));
    let before = live.t_after(Duration::ZERO);
    assert_eq!(live.web(json!({"pause": true})), Ok(None));
    assert_eq!(live.web(json!({"restart": true})), Ok(None));
    // A restart while paused stands at 0 until the resume.
    let v = live.view_after(Duration::from_millis(200));
    assert_eq!(v["t_s"], 0.0);
    assert_eq!(v["run"]["paused"], true);
    assert!(
        live.modbus_time() == SimTime::ZERO,
        "the gateway serves the fresh rig"
    );
    assert_eq!(live.web(json!({"pause": false})), Ok(None));
    let t = live.t_after(Duration::from_millis(100));
    assert!(
        t > 0.0 && t < before,
        "{t} s after the restart, {before} s before"
    );
    assert_eq!(live.web(json!({"speed": "max"})), Ok(None));
    let (restarted, restarted_trace) = live.end(false);
    // The report is of the last run: its log starts again, without the earlier press.
    let lines: Vec<String> = restarted.log.iter().map(ToString::to_string).collect();
    assert!(
        restarted.log.iter().any(|l| l.who == Actor::Web
            && matches!(l.event, LogEvent::Client(ClientLog::Restarted { .. }))),
        "{lines:?}"
    );
    assert!(
        !lines.iter().any(|l| l.contains("cabin button 4")),
        "{lines:?}"
    );
    assert_eq!(restarted.seed, 7);
    // The same seed, the same run, the same trace.
    assert!(
        fresh_trace == restarted_trace,
        "the traces differ ({} and {} bytes)",
        fresh_trace.len(),
        restarted_trace.len()
    );
    assert_eq!(without_the_live_run(fresh), without_the_live_run(restarted));
}

#[test]
fn a_new_speed_takes_effect_at_once_and_a_bad_one_is_refused() {
    let live = Live::start(LONG, config(Owner::Builtin, Speed::Factor(1.0)));
    wait_past(&live, 0.1);
    assert_eq!(live.web(json!({"speed": 10})), Ok(None));
    assert_eq!(
        live.view_after(Duration::from_millis(100))["run"]["speed"],
        "10"
    );
    // Never faster than the speed; slower only on a machine that cannot keep up.
    let rate = live.rate_over(Duration::from_millis(500));
    assert!(rate > 3.0 && rate < 10.5, "{rate} at speed 10");
    for bad in [json!(0), json!(2000), json!("fast"), json!(null)] {
        let e = live
            .web(json!({ "speed": bad.clone() }))
            .expect_err("refused");
        assert!(e.starts_with("speed: "), "{bad}: {e}");
    }
    assert_eq!(
        live.view_after(Duration::from_millis(50))["run"]["speed"],
        "10"
    );
    assert_eq!(live.web(json!({"speed": 0.5})), Ok(None));
    let rate = live.rate_over(Duration::from_millis(500));
    assert!(rate > 0.2 && rate < 0.55, "{rate} at speed 0.5");
    let (report, _) = live.end(true);
    assert_eq!(report.live.expect("the live figures").speed, "0.5");
    assert!(
        report.log.iter().any(|l| l.who == Actor::Web
            && l.event
                == LogEvent::Client(ClientLog::Speed {
                    speed: "10".into(),
                    was: "1".into(),
                })),
        "{:?}",
        report.log
    );
}

#[test]
fn an_outside_controller_is_warned_of_a_speed_above_1_and_max_is_lockstep() {
    let live = Live::start(LONG, config(Owner::External, Speed::Factor(1.0)));
    let note = live
        .web(json!({"speed": 2}))
        .expect("speed 2 is taken")
        .expect("a warning");
    assert!(
        note.contains("2 times faster than the outside controller's clock"),
        "{note}"
    );
    assert_eq!(live.web(json!({"speed": 1})), Ok(None));
    let note = live
        .web(json!({"speed": "max"}))
        .expect("max is taken")
        .expect("a note");
    assert!(note.contains("lockstep"), "{note}");
    // In lockstep each request advances the simulation by the step; paused, none does.
    let t0 = live.modbus_time();
    for _ in 0..9 {
        live.modbus(Request::ReadCoils(0, 8));
    }
    assert_eq!(live.modbus_time(), t0 + SimDuration::from_millis(10));
    assert_eq!(live.web(json!({"pause": true})), Ok(None));
    let t1 = live.modbus_time();
    for _ in 0..20 {
        live.modbus(Request::ReadCoils(0, 8));
    }
    assert_eq!(live.modbus_time(), t1);
    assert_eq!(live.web(json!({"pause": false})), Ok(None));
    live.modbus(Request::ReadCoils(0, 8));
    assert_eq!(live.modbus_time(), t1 + SimDuration::from_millis(1));
    live.end(true);
}

#[test]
fn a_pause_does_not_trip_the_watchdog_of_an_outside_controller() {
    // Speed 10 and a watchdog of 1 simulated second: 100 ms of wall time without a write.
    let live = Live::start(LONG, config(Owner::External, Speed::Factor(10.0)));
    let write = || live.modbus(Request::WriteSingleRegister(1, 0));
    let tripped = |live: &Live| {
        let Response::ReadDiscreteInputs(bits) = live.modbus(Request::ReadDiscreteInputs(1004, 1))
        else {
            panic!("not an answer to a read");
        };
        bits[0]
    };
    write();
    std::thread::sleep(Duration::from_millis(30));
    write();
    assert_eq!(live.web(json!({"pause": true})), Ok(None));
    // A wall second, 10 s of simulated time at speed 10: the watchdog counts simulated time,
    // which stands still; the client reads meanwhile and is answered.
    for _ in 0..10 {
        std::thread::sleep(Duration::from_millis(100));
        assert!(!tripped(&live), "the watchdog tripped during the pause");
    }
    assert_eq!(live.web(json!({"pause": false})), Ok(None));
    write();
    std::thread::sleep(Duration::from_millis(30));
    write();
    assert!(!tripped(&live), "the watchdog tripped after the pause");
    // The same silence without a pause trips it.
    std::thread::sleep(Duration::from_millis(400));
    assert!(tripped(&live), "the watchdog did not trip");
    let (report, _) = live.end(true);
    assert_eq!(report.live.expect("the live figures").watchdog_trips, 1);
}
