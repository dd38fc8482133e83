//! asi-lift's live view in a real headless browser (chromium through chromedriver): the page
//! loads and goes live; a click on cabin button 3 brings the cabin to floor 3 (read from the
//! page); a bad command is answered in the page; a click on STOP changes the ESTOP state shown;
//! a slave taken off line leaves LAS on the page; the page fits a phone's width.
//!
//! Needs chromedriver at `CHROMEDRIVER_URL` (default `http://127.0.0.1:9515`) and chromium at
//! `CHROMIUM` (default `/usr/bin/chromium`); `bash scripts/ci-browser.sh` provides both. With
//! `ASI_LIFT_SCREENSHOT=FILE` it writes a screenshot of the page during the trip to FILE
//! (`docs/live-view.png`, shown in the README and the book).

use fantoccini::{Client, ClientBuilder, Locator};
use gateway::live::LiveConfig;
use gateway::{Listen, Owner, Running, Speed};
use hyper_util::client::legacy::connect::HttpConnector;
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
    let make = move || Rig::new(sc.clone()).map_err(|e| e.to_string());
    let cfg = LiveConfig {
        speed: Speed::Factor(speed),
        owner: Owner::Builtin,
        watchdog: asi_phy::SimDuration::ZERO,
        step: asi_phy::SimDuration::from_millis(1),
    };
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
    assert!(r.arrivals.iter().any(|a| a.floor == 3), "{:?}", r.arrivals);
}
