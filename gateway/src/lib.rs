//! asi-lift's live mode (`asi-lift serve`): the rig on the wall clock on its own thread, and a
//! virtual AS-i gateway that speaks Modbus TCP, so that an outside controller (a soft PLC, a
//! SCADA package, a student's script) can drive the lab lift as the rig's PLC would, with the
//! simulated safety logic still guarding it.
//!
//! The deterministic core (the rig and everything below it) has no clock and no network; this
//! crate adds both: `live` paces the rig and serves requests between its moments, `map` is the
//! register map, and the Modbus server (`net`: tokio, with tokio-modbus's request decoder)
//! forwards each request to the rig thread over a crossbeam channel and waits for the answer. With `--http`, the live view
//! (`web`, `view`, `command`): a page in the browser that shows the rig as it runs and sends
//! it commands, over the same channel.

#![forbid(unsafe_code)]

pub mod command;
pub mod live;
pub mod map;
pub mod net;
pub mod speed;
pub mod ttk;
pub mod view;
pub mod web;

#[cfg(test)]
mod props;

use crossbeam_channel::{Receiver, Sender};
use live::{LiveConfig, Status, ToRig, ViewOut};
use rig::report::Actor;
use rig::{Report, Rig};
use std::net::SocketAddr;
use std::thread::JoinHandle;

pub use live::MakeRigError;
pub use map::Owner;
pub use net::Options;
pub use speed::Speed;

/// Why a live run cannot start.
#[derive(Debug, thiserror::Error)]
pub enum GatewayError {
    /// The listening address cannot be bound.
    #[error("cannot listen on {addr}: {source}")]
    Listen {
        /// The address.
        addr: SocketAddr,
        /// Why.
        source: std::io::Error,
    },
    /// The async runtime cannot start.
    #[error("cannot start the network runtime: {0}")]
    Runtime(std::io::Error),
    /// The speed factor is out of bounds ([`Speed::factor`]).
    #[error(transparent)]
    Speed(#[from] speed::SpeedError),
    /// The rig cannot be made (its configuration, or what the caller's maker needs).
    #[error("{0}")]
    Rig(MakeRigError),
    /// The rig's thread ended before the run began.
    #[error("the rig thread ended at its start")]
    RigThread,
}

/// A live run with its Modbus server, started by [`start`].
pub struct Running {
    addr: SocketAddr,
    ttk_addr: Option<SocketAddr>,
    http_addr: Option<SocketAddr>,
    tx: Sender<ToRig>,
    status: Receiver<Status>,
    rig: JoinHandle<Report>,
    runtime: tokio::runtime::Runtime,
}

impl Running {
    /// The address the Modbus server listens on (with the port the system chose for port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The address the TTK4145 server listens on, if there is one.
    pub fn ttk_addr(&self) -> Option<SocketAddr> {
        self.ttk_addr
    }

    /// The address the live view's web server listens on, if there is one.
    pub fn http_addr(&self) -> Option<SocketAddr> {
        self.http_addr
    }

    /// The status the rig thread sends about once per wall second, and at the end.
    pub fn status(&self) -> &Receiver<Status> {
        &self.status
    }

    /// Ends the run at the simulated time reached, as Ctrl-C does.
    pub fn stop(&self) {
        let _ = self.tx.send(ToRig::Stop);
    }

    /// Makes Ctrl-C end the run cleanly (the report is still written).
    pub fn stop_on_ctrl_c(&self) {
        let tx = self.tx.clone();
        self.runtime.spawn(async move {
            if tokio::signal::ctrl_c().await.is_ok() {
                let _ = tx.send(ToRig::Stop);
            }
        });
    }

    /// Waits for the end of the run (its `until`, or [`Running::stop`]) and returns the
    /// report; the server stops with it.
    pub fn wait(self) -> Report {
        let report = match self.rig.join() {
            Ok(r) => r,
            Err(panic) => std::panic::resume_unwind(panic),
        };
        self.runtime.shutdown_background();
        report
    }
}

/// Binds `addr` for the runtime, or says which address could not be bound.
fn bind(
    runtime: &tokio::runtime::Runtime,
    addr: SocketAddr,
) -> Result<(tokio::net::TcpListener, SocketAddr), GatewayError> {
    let listen_error = |source| GatewayError::Listen { addr, source };
    let listener = std::net::TcpListener::bind(addr)
        .and_then(|l| l.set_nonblocking(true).map(|()| l))
        .map_err(listen_error)?;
    let bound = listener.local_addr().map_err(listen_error)?;
    let _guard = runtime.enter();
    let listener = tokio::net::TcpListener::from_std(listener).map_err(listen_error)?;
    Ok((listener, bound))
}

/// Where a live run's servers listen.
#[derive(Clone, Copy, Debug)]
pub struct Listen {
    /// Modbus TCP.
    pub modbus: SocketAddr,
    /// The TTK4145 protocol, if wanted.
    pub ttk: Option<SocketAddr>,
    /// The live view in the browser (HTTP and WebSocket), if wanted.
    pub http: Option<SocketAddr>,
}

/// Starts a live run: builds the rig with `make_rig` on its own thread (and again for each
/// restart from the live view's page), listens on `listen` and serves Modbus TCP until the
/// run ends; with `ttk`, serves the TTK4145 protocol there too.
pub fn start<F>(
    make_rig: F,
    cfg: LiveConfig,
    listen: SocketAddr,
    ttk: Option<SocketAddr>,
) -> Result<Running, GatewayError>
where
    F: FnMut() -> Result<Rig, MakeRigError> + Send + 'static,
{
    start_servers(
        make_rig,
        cfg,
        Listen {
            modbus: listen,
            ttk,
            http: None,
        },
    )
}

/// As [`start`], with every server of [`Listen`]: with `http`, the live view too.
pub fn start_servers<F>(
    make_rig: F,
    cfg: LiveConfig,
    listen: Listen,
) -> Result<Running, GatewayError>
where
    F: FnMut() -> Result<Rig, MakeRigError> + Send + 'static,
{
    start_with(make_rig, cfg, listen, Options::default())
}

/// As [`start_servers`], with the servers' [`Options`].
pub fn start_with<F>(
    mut make_rig: F,
    cfg: LiveConfig,
    listen: Listen,
    options: Options,
) -> Result<Running, GatewayError>
where
    F: FnMut() -> Result<Rig, MakeRigError> + Send + 'static,
{
    let Listen {
        modbus: listen,
        ttk,
        http,
    } = listen;
    cfg.speed.checked().map_err(GatewayError::Speed)?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .thread_name("asi-lift-gateway")
        .enable_all()
        .build()
        .map_err(GatewayError::Runtime)?;
    let (listener, addr) = bind(&runtime, listen)?;
    let ttk = ttk.map(|a| bind(&runtime, a)).transpose()?;
    let ttk_addr = ttk.as_ref().map(|(_, a)| *a);
    let http = http.map(|a| bind(&runtime, a)).transpose()?;
    let http_addr = http.as_ref().map(|(_, a)| *a);
    let (snapshots_tx, snapshots) = tokio::sync::watch::channel(None);
    let history = live::History::default();
    let view = http.is_some().then(|| ViewOut {
        snapshots: snapshots_tx,
        history: history.clone(),
    });
    let (tx, rx) = crossbeam_channel::unbounded();
    let (status_tx, status) = crossbeam_channel::bounded(64);
    let (ready_tx, ready) = crossbeam_channel::bounded(1);
    let rig = std::thread::Builder::new()
        .name("asi-lift-rig".into())
        .spawn(move || match make_rig() {
            Ok(rig) => {
                let _ = ready_tx.send(Ok(()));
                live::run_with_view(rig, cfg, &rx, &status_tx, view, Some(&mut make_rig))
            }
            Err(e) => {
                let _ = ready_tx.send(Err(e));
                Report::at_power_on("", 0, 0.0)
            }
        })
        .map_err(GatewayError::Runtime)?;
    match ready.recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(GatewayError::Rig(e)),
        Err(_) => return Err(GatewayError::RigThread),
    }

    let max = options.max_connections;
    let to_rig = tx.clone();
    runtime.spawn(net::accept_loop(
        Actor::ModbusServer,
        listener,
        max,
        net::BACKOFF,
        tx.clone(),
        move |s| net::serve_modbus(s, to_rig.clone()),
    ));
    if let Some((listener, _)) = ttk {
        let to_rig = tx.clone();
        runtime.spawn(net::accept_loop(
            Actor::Ttk4145,
            listener,
            max,
            net::BACKOFF,
            tx.clone(),
            move |s| net::serve_ttk(s, to_rig.clone()),
        ));
    }
    if let Some((listener, bound)) = http {
        let app = web::router(web::Web {
            snapshots,
            history,
            tx: tx.clone(),
            hosts: std::sync::Arc::new(web::Hosts::new(bound, options.allow_hosts.clone())),
        });
        let timeout = options.header_timeout;
        runtime.spawn(net::accept_loop(
            Actor::HttpServer,
            listener,
            max,
            net::BACKOFF,
            tx.clone(),
            move |s| net::serve_http(s, app.clone(), timeout),
        ));
    }
    Ok(Running {
        addr,
        ttk_addr,
        http_addr,
        tx,
        status,
        rig,
        runtime,
    })
}
