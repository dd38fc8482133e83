//! asi-lift's live view in a real headless browser (chromium through chromedriver): the page
//! loads and goes live; a click on cabin button 3 brings the cabin to floor 3 (read from the
//! page); a bad command is answered in the page; a click on STOP changes the ESTOP state shown;
//! a slave taken off line leaves LAS on the page; pause stands the time shown still and resume
//! lets it go on; a new speed is taken and a bad one answered; restart starts the time again;
//! the page fits a phone's width.
//!
//! Needs chromedriver at `CHROMEDRIVER_URL` (default `http://127.0.0.1:9515`) and chromium at
//! `CHROMIUM` (default `/usr/bin/chromium`); `bash scripts/ci-browser.sh` provides both. With
//! `ASI_LIFT_SCREENSHOT=FILE` it writes a screenshot of the page during the trip to FILE
//! (`docs/live-view.png`, shown in the README and the book).

use fantoccini::{Client, ClientBuilder, Locator};
use gateway::live::LiveConfig;
use gateway::{Listen, Owner, Running, Speed};
use hyper_util::client::legacy::connect::HttpConnector;
use rig::report::{ClientLog, LogEvent};
use rig::Actor;
use rig::{Rig, Scenario};
use serde_json::{json, Value};
use std::net::SocketAddr;
use std::time::{Duration, Instant};

/// How long any one step may take, wall time.
const STEP: Duration = Duration::from_secs(60);

/// The lab lift at floor 1 at speed `speed`, with the live view.
fn start(speed: f64) -> Running {
    let toml =
        "name = \"browser\"\nduration = \"30min\"\n[lift]\nstart_mm = 0.0\nload = \"loaded\"\n";
    let sc = Scenario::from_toml("browser.toml", toml).expect("a valid scenario");
    let make = move || Rig::new(sc.clone()).map_err(gateway::MakeRigError::from);
    let mut cfg = LiveConfig::default();
    cfg.speed = Speed::Factor(speed);
    cfg.owner = Owner::Builtin;
    cfg.watchdog = asi_phy::SimDuration::ZERO;
    cfg.step = asi_phy::SimDuration::from_millis(1);
    let loopback: SocketAddr = "127.0.0.1:0".parse().expect("an address");
    let listen = Listen {
        modbus: loopback,
        ttk: None,
        http: Some(loopback),
    };
    gateway::start_servers(make, cfg, listen).expect("the gateway starts")
}

async fn browser(profile: &std::path::Path) -> Client {
    let url = std::env::var("CHROMEDRIVER_URL").unwrap_or("http://127.0.0.1:9515".into());
    let chromium = std::env::var("CHROMIUM").unwrap_or("/usr/bin/chromium".into());
    let args = [
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--disable-dev-shm-usage",
        "--window-size=1280,1600",
        &format!("--user-data-dir={}", profile.display()),
    ];
    let mut caps = serde_json::Map::new();
    caps.insert(
        "goog:chromeOptions".into(),
        json!({"binary": chromium, "args": args}),
    );
    ClientBuilder::new(HttpConnector::new())
        .capabilities(caps)
        .connect(&url)
        .await
        .unwrap_or_else(|e| panic!("no WebDriver session at {url}: {e}"))
}

/// The text of the element `id`.
async fn text(c: &Client, id: &str) -> String {
    match c.find(Locator::Id(id)).await {
        Ok(e) => e.text().await.unwrap_or_default(),
        Err(_) => String::new(),
    }
}

/// Waits until `ok` holds for the text of `id`; returns that text.
async fn wait_text(c: &Client, id: &str, what: &str, ok: impl Fn(&str) -> bool) -> String {
    let t0 = Instant::now();
    loop {
        let t = text(c, id).await;
        if ok(&t) {
            return t;
        }
        assert!(t0.elapsed() < STEP, "{what}: #{id} shows {t:?}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// Whether the element `id` is displayed.
async fn is_shown(c: &Client, id: &str) -> bool {
    match c.find(Locator::Id(id)).await {
        Ok(e) => e.is_displayed().await.unwrap_or(false),
        Err(_) => false,
    }
}

/// Seconds as the page shows them (`12.34`).
fn seconds(t: &str) -> f64 {
    t.parse().unwrap_or_else(|_| panic!("not a time: {t:?}"))
}

async fn click(c: &Client, id: &str) {
    let e = c
        .wait()
        .at_most(STEP)
        .for_element(Locator::Id(id))
        .await
        .unwrap_or_else(|e| panic!("#{id}: {e}"));
    e.click()
        .await
        .unwrap_or_else(|e| panic!("click #{id}: {e}"));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_live_view_in_chromium() {
    let running = start(4.0);
    let addr = running.http_addr().expect("the live view's address");
    let profile = std::env::temp_dir().join(format!("asi-lift-chromium-{}", std::process::id()));
    let c = browser(&profile).await;
    c.goto(&format!("http://{addr}/"))
        .await
        .expect("the page loads");
    assert_eq!(c.title().await.expect("a title"), "asi-lift live view");
    wait_text(&c, "conn", "the socket goes live", |t| t == "live").await;
    // The controller initialises at floor 1 first.
    wait_text(&c, "ctl-init", "initialisation", |t| t == "yes").await;
    wait_text(&c, "velocity", "the cabin stands", |t| t == "0.0").await;
    assert_eq!(text(&c, "cabin-level").await, "1");

    click(&c, "btn-cabin-3").await;
    wait_text(&c, "cabin-level", "the cabin leaves floor 1", |t| t != "1").await;
    if let Ok(file) = std::env::var("ASI_LIFT_SCREENSHOT") {
        // Halfway up, with the plot showing the start of the trip.
        tokio::time::sleep(Duration::from_millis(1200)).await;
        let png = c.screenshot().await.expect("a screenshot");
        std::fs::write(&file, png).expect("the screenshot is written");
    }
    let t0 = Instant::now();
    loop {
        if text(&c, "cabin-level").await == "3" && text(&c, "velocity").await == "0.0" {
            break;
        }
        assert!(t0.elapsed() < STEP, "the cabin does not arrive at floor 3");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert_eq!(text(&c, "ctl-floor").await, "3");
    assert_eq!(text(&c, "violations").await, "0 violations");

    // A bad command is answered in the page.
    c.execute("send({press: 'cabin:9'}, 'press cabin:9');", vec![])
        .await
        .expect("the script runs");
    wait_text(&c, "message", "the error", |t| {
        t.contains("floor `9` does not exist")
    })
    .await;

    // STOP: the ESTOP module leaves RUN.
    let before = text(&c, "estop-state").await;
    assert_eq!(before, "RUN");
    click(&c, "btn-stop").await;
    wait_text(&c, "estop-state", "STOP changes ESTOP", |t| t != before).await;
    wait_text(&c, "estop-out", "EStopOut drops", |t| t.starts_with("off")).await;

    // A slave off line leaves LAS.
    let las = |t: &str| t.split(' ').map(str::to_owned).collect::<Vec<_>>();
    let t = wait_text(&c, "las", "slave 11 in LAS", |t| {
        las(t).contains(&"11A".into())
    })
    .await;
    assert!(las(&t).contains(&"8A".into()), "{t}");
    click(&c, "offline-11").await;
    wait_text(&c, "las", "slave 11 leaves LAS", |t| {
        !las(t).contains(&"11A".into()) && las(t).contains(&"8A".into())
    })
    .await;
    click(&c, "online-11").await;
    wait_text(&c, "las", "slave 11 back in LAS", |t| {
        las(t).contains(&"11A".into())
    })
    .await;

    // Pause: the time shown stands still; resume: it goes on.
    click(&c, "btn-pause").await;
    wait_text(&c, "btn-pause", "the button offers the resume", |t| {
        t.contains("resume")
    })
    .await;
    assert!(is_shown(&c, "paused").await, "no `paused` in the header");
    let t1 = text(&c, "sim-time").await;
    for _ in 0..10 {
        tokio::time::sleep(Duration::from_millis(100)).await;
        assert_eq!(
            text(&c, "sim-time").await,
            t1,
            "the time goes on while paused"
        );
    }
    click(&c, "btn-pause").await;
    wait_text(&c, "sim-time", "the time goes on after the resume", |t| {
        t != t1
    })
    .await;
    wait_text(&c, "btn-pause", "the button offers the pause", |t| {
        t.contains("pause")
    })
    .await;
    assert!(
        !is_shown(&c, "paused").await,
        "`paused` stays in the header"
    );

    // The speed: 10 from the list is taken and shown; a factor out of bounds is answered.
    c.find(Locator::Id("speed-select"))
        .await
        .expect("the speed's list")
        .select_by_value("10")
        .await
        .expect("speed 10 is chosen");
    wait_text(&c, "message", "speed 10 is taken", |t| {
        t == "speed 10: done"
    })
    .await;
    let t0: f64 = seconds(&text(&c, "sim-time").await);
    let w0 = Instant::now();
    tokio::time::sleep(Duration::from_millis(1000)).await;
    let rate = (seconds(&text(&c, "sim-time").await) - t0) / w0.elapsed().as_secs_f64();
    assert!(
        rate > 5.0,
        "{rate} simulated seconds per second at speed 10"
    );
    c.execute("send({speed: 0}, 'speed 0');", vec![])
        .await
        .expect("the script runs");
    wait_text(&c, "message", "the refused speed", |t| {
        t.contains("speed: 0: expected a factor from 0.001 to 1000")
    })
    .await;
    let shown: Value = c
        .execute(
            "return document.getElementById('speed-select').value;",
            vec![],
        )
        .await
        .expect("the script runs");
    assert_eq!(shown, json!("10"));

    // Restart: armed by the first click, done by the second; the time starts again.
    let before = seconds(&text(&c, "sim-time").await);
    click(&c, "btn-restart").await;
    wait_text(&c, "btn-restart", "restart asks for a second click", |t| {
        t.contains("click again")
    })
    .await;
    click(&c, "btn-restart").await;
    wait_text(&c, "sim-time", "the time starts again", |t| {
        seconds(t) < before / 2.0
    })
    .await;
    wait_text(&c, "message", "the restart is done", |t| {
        t == "restart: done"
    })
    .await;

    // On a phone-sized screen nothing is wider than the screen.
    c.set_window_size(390, 844).await.expect("a phone's window");
    tokio::time::sleep(Duration::from_millis(300)).await;
    let fits: Value = c
        .execute(
            "return document.documentElement.scrollWidth <= window.innerWidth + 1;",
            vec![],
        )
        .await
        .expect("the script runs");
    assert_eq!(fits, json!(true), "the page is wider than a phone");
    assert!(c
        .find(Locator::Id("btn-cabin-3"))
        .await
        .expect("the button")
        .is_displayed()
        .await
        .expect("displayed"));

    c.close().await.expect("the browser closes");
    let _ = std::fs::remove_dir_all(&profile);
    running.stop();
    let r = tokio::task::spawn_blocking(move || running.wait())
        .await
        .expect("the run ends");
    // The report is of the run since the restart.
    assert!(
        r.log.iter().any(|l| l.who == Actor::Web
            && matches!(l.event, LogEvent::Client(ClientLog::Restarted { .. }))),
        "{:?}",
        r.log
    );
}
