//! asi-lift's live mode (`asi-lift serve`): the rig on the wall clock on its own thread, and a
//! virtual AS-i gateway that speaks Modbus TCP, so that an outside controller (a soft PLC, a
//! SCADA package, a student's script) can drive the lab lift as the rig's PLC would, with the
//! simulated safety logic still guarding it.
//!
//! The deterministic core (the rig and everything below it) has no clock and no network; this
//! crate adds both: `live` paces the rig and serves requests between its moments, `map` is the
//! register map, and the Modbus server (tokio-modbus on tokio) forwards each request to the rig
//! thread over a crossbeam channel and waits for the answer.

#![forbid(unsafe_code)]

pub mod live;
pub mod map;

use crossbeam_channel::{Receiver, Sender};
use live::{Call, LiveConfig, Status, ToRig};
use rig::{Report, Rig};
use std::future::Future;
use std::net::SocketAddr;
use std::pin::Pin;
use std::thread::JoinHandle;
use tokio_modbus::server::tcp::{accept_tcp_connection, Server};
use tokio_modbus::{ExceptionCode, Response, SlaveRequest};

pub use live::Speed;
pub use map::Owner;

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
    /// The rig cannot be built.
    #[error("{0}")]
    Rig(String),
}

/// A live run with its Modbus server, started by [`start`].
pub struct Running {
    addr: SocketAddr,
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

/// Starts a live run: builds the rig with `make_rig` on its own thread, listens on `listen`
/// and serves Modbus TCP until the run ends.
pub fn start<F>(make_rig: F, cfg: LiveConfig, listen: SocketAddr) -> Result<Running, GatewayError>
where
    F: FnOnce() -> Result<Rig, String> + Send + 'static,
{
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .thread_name("asi-lift-gateway")
        .enable_all()
        .build()
        .map_err(GatewayError::Runtime)?;
    let listener = std::net::TcpListener::bind(listen)
        .and_then(|l| l.set_nonblocking(true).map(|()| l))
        .map_err(|source| GatewayError::Listen {
            addr: listen,
            source,
        })?;
    let addr = listener
        .local_addr()
        .map_err(|source| GatewayError::Listen {
            addr: listen,
            source,
        })?;
    let listener = {
        let _guard = runtime.enter();
        tokio::net::TcpListener::from_std(listener)
            .map_err(|source| GatewayError::Listen { addr, source })?
    };

    let (tx, rx) = crossbeam_channel::unbounded();
    let (status_tx, status) = crossbeam_channel::bounded(64);
    let (ready_tx, ready) = crossbeam_channel::bounded(1);
    let rig = std::thread::Builder::new()
        .name("asi-lift-rig".into())
        .spawn(move || match make_rig() {
            Ok(rig) => {
                let _ = ready_tx.send(Ok(()));
                live::run(rig, cfg, &rx, &status_tx)
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
        Err(_) => {
            return Err(GatewayError::Rig(
                "the rig thread ended at its start".into(),
            ))
        }
    }

    let to_rig = tx.clone();
    runtime.spawn(async move {
        let server = Server::new(listener);
        let on_connected = |stream, socket_addr| {
            let tx = to_rig.clone();
            async move {
                let _ = tx.send(ToRig::Connected);
                accept_tcp_connection(stream, socket_addr, move |_| {
                    Ok(Some(ModbusService { tx: tx.clone() }))
                })
            }
        };
        // A connection that sends what is not Modbus TCP is closed; the others go on.
        let on_process_error = |_err: std::io::Error| {};
        let _ = server.serve(&on_connected, on_process_error).await;
    });
    Ok(Running {
        addr,
        tx,
        status,
        rig,
        runtime,
    })
}

/// One connection's service: hands each request to the rig thread and waits for its answer.
struct ModbusService {
    tx: Sender<ToRig>,
}

type Answer = Pin<Box<dyn Future<Output = Result<Response, ExceptionCode>> + Send>>;

impl tokio_modbus::server::Service for ModbusService {
    type Request = SlaveRequest<'static>;
    type Response = Response;
    type Exception = ExceptionCode;
    type Future = Answer;

    fn call(&self, req: Self::Request) -> Self::Future {
        let (reply, answer) = tokio::sync::oneshot::channel();
        let sent = self.tx.send(ToRig::Call(Call {
            request: req.request.into_owned(),
            reply,
        }));
        Box::pin(async move {
            if sent.is_err() {
                // The run has ended.
                return Err(ExceptionCode::ServerDeviceFailure);
            }
            answer
                .await
                .unwrap_or(Err(ExceptionCode::ServerDeviceFailure))
        })
    }
}
