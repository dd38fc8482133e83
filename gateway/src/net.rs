//! The servers' sockets: one accept loop for every listener (Modbus TCP, TTK4145, the live
//! view's HTTP), which survives failed accepts and bounds its connections, and the
//! connections themselves: Modbus TCP framing, the TTK4145 messages, HTTP/1.1 with a bounded
//! wait for a request's head.
//!
//! A failed `accept()` (out of file descriptors, `EMFILE`, among others) is logged once per
//! streak and retried after a wait that doubles from [`FIRST_BACKOFF`] to [`LAST_BACKOFF`], as
//! hyper 0.14's server did (it slept 1 s, for a process that "has hit the max open files";
//! axum 0.8's `serve` does the same); the loop never ends while the run goes on. A connection
//! beyond [`Options::max_connections`] of its listener is closed at once.

use crate::live::{Call, ToRig, TtkCall};
use crossbeam_channel::Sender;
use rig::report::{Actor, ClientLog};
use std::future::Future;
use std::io;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::sync::Semaphore;
use tokio_modbus::{ExceptionCode, Request, Response};

/// The first wait after a failed accept.
pub const FIRST_BACKOFF: Duration = Duration::from_millis(10);
/// The longest wait between tries while accepts fail.
pub const LAST_BACKOFF: Duration = Duration::from_secs(1);

/// What the servers allow their clients.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct Options {
    /// The most connections a listener serves at once; one more is closed at once.
    pub max_connections: usize,
    /// How long an HTTP client may take to send the head of a request (its request line and
    /// headers) before its connection is closed.
    pub header_timeout: Duration,
    /// Host names the live view answers to besides its own address and loopback
    /// (`asi-lift serve --allow-host`): `name` with the live view's port, or `name:port`.
    pub allow_hosts: Vec<String>,
}

impl Default for Options {
    /// 64 connections per listener (a class's controllers and browsers, far below the 1024
    /// descriptors of a default `ulimit -n`), 10 s for a request head, no other host names.
    fn default() -> Options {
        Options {
            max_connections: 64,
            header_timeout: Duration::from_secs(10),
            allow_hosts: Vec::new(),
        }
    }
}

/// A source of connections: a listener, or a test's stand-in for one.
pub(crate) trait Accept: Send {
    /// The connection's stream.
    type Stream: Send + 'static;
    /// The next connection, or why there is none.
    fn accept(&mut self) -> impl Future<Output = io::Result<(Self::Stream, SocketAddr)>> + Send;
}

impl Accept for tokio::net::TcpListener {
    type Stream = tokio::net::TcpStream;
    async fn accept(&mut self) -> io::Result<(Self::Stream, SocketAddr)> {
        tokio::net::TcpListener::accept(self).await
    }
}

/// An error of the connection being accepted (the client gave up before it was accepted):
/// nothing to wait for (the list of hyper 0.14 and axum 0.8).
fn connection_error(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::ConnectionRefused
            | io::ErrorKind::ConnectionAborted
            | io::ErrorKind::ConnectionReset
    )
}

/// How long to wait after failed accepts: `first`, doubling up to `last`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Backoff {
    pub(crate) first: Duration,
    pub(crate) last: Duration,
}

/// The servers' back-off: [`FIRST_BACKOFF`] to [`LAST_BACKOFF`].
pub(crate) const BACKOFF: Backoff = Backoff {
    first: FIRST_BACKOFF,
    last: LAST_BACKOFF,
};

/// Accepts connections from `listener` for ever and runs `handle` on each in a task of its
/// own, at most `max` at once. A failed accept is logged to the run (`who`, at the first of a
/// streak and when accepts work again) through `log`, and tried again after a wait that
/// doubles as `wait` says.
pub(crate) async fn accept_loop<A, H, F>(
    who: Actor,
    mut listener: A,
    max: usize,
    wait: Backoff,
    log: Sender<ToRig>,
    handle: H,
) where
    A: Accept,
    H: Fn(A::Stream) -> F + Send,
    F: Future<Output = ()> + Send + 'static,
{
    // A semaphore holds at most `MAX_PERMITS`; more would panic, and would bound nothing.
    let permits = Arc::new(Semaphore::new(max.min(Semaphore::MAX_PERMITS)));
    let mut backoff = wait.first;
    let mut failed = 0u64;
    loop {
        match listener.accept().await {
            Ok((stream, _)) => {
                if failed > 0 {
                    let _ = log.send(ToRig::Log(who, ClientLog::AcceptingAgain(failed)));
                    failed = 0;
                    backoff = wait.first;
                }
                // Beyond the bound the stream is dropped: the client sees its connection close.
                let Ok(permit) = permits.clone().try_acquire_owned() else {
                    continue;
                };
                let connection = handle(stream);
                tokio::spawn(async move {
                    connection.await;
                    drop(permit);
                });
            }
            Err(e) if connection_error(&e) => {}
            Err(e) => {
                if failed == 0 {
                    let cannot = ClientLog::CannotAccept {
                        error: e.to_string(),
                        retry_ms: wait.last.as_millis(),
                    };
                    let _ = log.send(ToRig::Log(who, cannot));
                }
                failed += 1;
                tokio::time::sleep(backoff).await;
                backoff = (backoff * 2).min(wait.last);
            }
        }
    }
}

/// The largest PDU of Modbus (application protocol v1.1b3 §4.1: 253 bytes), so the largest
/// MBAP length field is 254 (the PDU and the unit identifier).
const MAX_PDU: usize = 253;

/// One Modbus TCP connection: each request (MBAP header, PDU) is handed to the rig thread and
/// its answer, or exception, sent back with the request's transaction and unit identifiers.
/// A connection that sends what is not Modbus TCP (a protocol identifier other than 0, a
/// length outside 2..=254, a PDU that does not parse) is closed (Modbus messaging on TCP/IP
/// v1.0b §3.1.3).
pub(crate) async fn serve_modbus<S>(mut stream: S, tx: Sender<ToRig>)
where
    S: AsyncRead + AsyncWrite + Unpin,
{
    let _ = tx.send(ToRig::Connected);
    let mut head = [0u8; 7];
    loop {
        if stream.read_exact(&mut head).await.is_err() {
            return;
        }
        let protocol = u16::from_be_bytes([head[2], head[3]]);
        let len = usize::from(u16::from_be_bytes([head[4], head[5]]));
        if protocol != 0 || !(2..=MAX_PDU + 1).contains(&len) {
            return;
        }
        let mut pdu = vec![0u8; len - 1];
        if stream.read_exact(&mut pdu).await.is_err() {
            return;
        }
        let function = pdu[0];
        let Ok(request) = Request::try_from(tokio_modbus::bytes::Bytes::from(pdu)) else {
            return;
        };
        let answer = match call(&tx, request).await {
            Some(a) => a,
            None => Err(ExceptionCode::ServerDeviceFailure),
        };
        let body = encode_answer(function, &answer);
        let mut frame = Vec::with_capacity(7 + body.len());
        frame.extend_from_slice(&head[..4]);
        frame.extend_from_slice(&(body.len() as u16 + 1).to_be_bytes());
        frame.push(head[6]);
        frame.extend_from_slice(&body);
        if stream.write_all(&frame).await.is_err() {
            return;
        }
    }
}

/// Hands `request` to the rig thread; its answer, or `None` if the run has ended.
async fn call(
    tx: &Sender<ToRig>,
    request: Request<'static>,
) -> Option<Result<Response, ExceptionCode>> {
    let (reply, answer) = tokio::sync::oneshot::channel();
    tx.send(ToRig::Call(Call { request, reply })).ok()?;
    answer.await.ok()
}

/// The PDU of the answer to a request of function code `function` (application protocol
/// v1.1b3 §6: the functions the gateway serves; an exception is the function code + 0x80 and
/// the exception code, §7).
pub fn encode_answer(function: u8, answer: &Result<Response, ExceptionCode>) -> Vec<u8> {
    let mut pdu = Vec::new();
    let words = |pdu: &mut Vec<u8>, ws: &[u16]| {
        pdu.push((ws.len() * 2) as u8);
        for w in ws {
            pdu.extend_from_slice(&w.to_be_bytes());
        }
    };
    match answer {
        Ok(Response::ReadCoils(bits) | Response::ReadDiscreteInputs(bits))
            if bits.len() <= 8 * 250 =>
        {
            pdu.push(function);
            let mut packed = vec![0u8; bits.len().div_ceil(8)];
            for (i, &b) in bits.iter().enumerate() {
                packed[i / 8] |= u8::from(b) << (i % 8);
            }
            pdu.push(packed.len() as u8);
            pdu.extend_from_slice(&packed);
        }
        Ok(
            Response::ReadInputRegisters(ws)
            | Response::ReadHoldingRegisters(ws)
            | Response::ReadWriteMultipleRegisters(ws),
        ) if ws.len() <= 125 => {
            pdu.push(function);
            words(&mut pdu, ws);
        }
        Ok(Response::WriteSingleCoil(a, v)) => {
            pdu.push(function);
            pdu.extend_from_slice(&a.to_be_bytes());
            pdu.extend_from_slice(&(if *v { 0xFF00u16 } else { 0 }).to_be_bytes());
        }
        Ok(
            Response::WriteMultipleCoils(a, n)
            | Response::WriteMultipleRegisters(a, n)
            | Response::WriteSingleRegister(a, n),
        ) => {
            pdu.push(function);
            pdu.extend_from_slice(&a.to_be_bytes());
            pdu.extend_from_slice(&n.to_be_bytes());
        }
        // The map answers no other function; should it, the client gets an exception rather
        // than a frame it cannot read.
        Ok(_) => return encode_answer(function, &Err(ExceptionCode::ServerDeviceFailure)),
        Err(code) => {
            pdu.push(function | 0x80);
            pdu.push(u8::from(*code));
        }
    }
    pdu
}

/// One TTK4145 connection: fixed 4-byte messages, each handed to the rig thread; a read's
/// answer goes back, a write gets none.
pub(crate) async fn serve_ttk<S>(mut stream: S, tx: Sender<ToRig>)
where
    S: AsyncRead + AsyncWrite + Unpin,
{
    let _ = tx.send(ToRig::Connected);
    let mut msg = [0u8; 4];
    while stream.read_exact(&mut msg).await.is_ok() {
        let (reply, answer) = tokio::sync::oneshot::channel();
        if tx.send(ToRig::Ttk(TtkCall { msg, reply })).is_err() {
            return;
        }
        match answer.await {
            Ok(Some(a)) => {
                if stream.write_all(&a).await.is_err() {
                    return;
                }
            }
            Ok(None) => {}
            Err(_) => return,
        }
    }
}

/// One HTTP/1.1 connection of the live view, upgrades (the WebSocket) included; closed when
/// a request's head has not arrived whole within `header_timeout` (hyper's
/// `http1::Builder::header_read_timeout`, which needs a timer).
pub(crate) async fn serve_http(
    stream: tokio::net::TcpStream,
    app: axum::Router,
    header_timeout: Duration,
) {
    let io = hyper_util::rt::TokioIo::new(stream);
    let service = hyper_util::service::TowerToHyperService::new(app);
    let mut builder = hyper::server::conn::http1::Builder::new();
    builder
        .timer(hyper_util::rt::TokioTimer::new())
        .header_read_timeout(header_timeout);
    // A connection that breaks or sends what is not HTTP ends alone; the server goes on.
    let _ = builder.serve_connection(io, service).with_upgrades().await;
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::VecDeque;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// A listener that gives the results in its list, then waits for ever.
    struct Scripted(VecDeque<io::Result<u32>>);

    impl Accept for Scripted {
        type Stream = u32;
        async fn accept(&mut self) -> io::Result<(u32, SocketAddr)> {
            let peer = SocketAddr::from(([127, 0, 0, 1], 1));
            match self.0.pop_front() {
                Some(r) => r.map(|s| (s, peer)),
                None => std::future::pending().await,
            }
        }
    }

    fn emfile() -> io::Error {
        io::Error::from_raw_os_error(24)
    }

    #[tokio::test(flavor = "current_thread")]
    async fn the_accept_loop_outlives_failed_accepts_and_waits_between_them() {
        let mut script: VecDeque<io::Result<u32>> = VecDeque::new();
        script.push_back(Ok(1));
        for _ in 0..12 {
            script.push_back(Err(emfile()));
        }
        script.push_back(Err(io::ErrorKind::ConnectionAborted.into()));
        script.push_back(Ok(2));
        script.push_back(Err(emfile()));
        script.push_back(Ok(3));
        let served = Arc::new(AtomicUsize::new(0));
        let (tx, rx) = crossbeam_channel::unbounded();
        let counter = served.clone();
        let start = tokio::time::Instant::now();
        let wait = Backoff {
            first: Duration::from_millis(1),
            last: Duration::from_millis(16),
        };
        let task = tokio::spawn(accept_loop(
            Actor::Gateway,
            Scripted(script),
            8,
            wait,
            tx,
            move |_| {
                let counter = counter.clone();
                async move {
                    counter.fetch_add(1, Ordering::SeqCst);
                }
            },
        ));
        for _ in 0..1000 {
            if served.load(Ordering::SeqCst) == 3 {
                break;
            }
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
        assert_eq!(served.load(Ordering::SeqCst), 3);
        // 1, 2, 4, 8 ms, then 16 ms eight times, then 1 ms again after a success.
        let waited = start.elapsed();
        assert!(waited >= Duration::from_millis(143), "{waited:?}");
        assert!(!task.is_finished());
        task.abort();
        let notes: Vec<String> = rx
            .try_iter()
            .filter_map(|m| match m {
                ToRig::Log(who, text) => Some(format!("{who}: {text}")),
                _ => None,
            })
            .collect();
        assert_eq!(notes.len(), 4, "{notes:?}");
        assert!(
            notes[0].starts_with("gateway: cannot accept a connection"),
            "{notes:?}"
        );
        assert!(notes[1].contains("after 12 failed tries"), "{notes:?}");
    }

    #[tokio::test(flavor = "current_thread")]
    async fn a_bound_past_what_a_semaphore_holds_is_no_panic() {
        let (tx, _rx) = crossbeam_channel::unbounded();
        let script = Scripted(VecDeque::from([Ok(1)]));
        let (done_tx, done) = tokio::sync::oneshot::channel();
        let done_tx = std::sync::Mutex::new(Some(done_tx));
        let task = tokio::spawn(accept_loop(
            Actor::Gateway,
            script,
            usize::MAX,
            BACKOFF,
            tx,
            move |_| {
                let done_tx = done_tx.lock().ok().and_then(|mut d| d.take());
                async move {
                    if let Some(d) = done_tx {
                        let _ = d.send(());
                    }
                }
            },
        ));
        let served = tokio::time::timeout(Duration::from_secs(5), done).await;
        assert!(matches!(served, Ok(Ok(()))), "{served:?}");
        task.abort();
    }

    #[tokio::test(flavor = "current_thread")]
    async fn connections_beyond_the_bound_are_closed_and_a_freed_place_is_taken_again() {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0")
            .await
            .expect("a port");
        let addr = listener.local_addr().expect("its address");
        let (tx, _rx) = crossbeam_channel::unbounded();
        // Each connection echoes one byte and ends.
        let task = tokio::spawn(accept_loop(
            Actor::Gateway,
            listener,
            2,
            BACKOFF,
            tx,
            |mut s: tokio::net::TcpStream| async move {
                let mut b = [0u8; 1];
                if s.read_exact(&mut b).await.is_ok() {
                    let _ = s.write_all(&b).await;
                }
            },
        ));
        let mut held = Vec::new();
        for _ in 0..2 {
            held.push(
                tokio::net::TcpStream::connect(addr)
                    .await
                    .expect("a connection"),
            );
        }
        let mut third = tokio::net::TcpStream::connect(addr)
            .await
            .expect("a connection");
        let mut b = [0u8; 1];
        let read = tokio::time::timeout(Duration::from_secs(5), third.read(&mut b))
            .await
            .expect("closed within 5 s");
        assert!(matches!(read, Ok(0) | Err(_)), "{read:?}");
        // One of the first two ends: its place is free for the next client.
        held[0].write_all(&[7]).await.expect("sent");
        held[0].read_exact(&mut b).await.expect("echoed");
        assert_eq!(b, [7]);
        drop(held.remove(0));
        let mut next = None;
        for _ in 0..100 {
            let mut s = tokio::net::TcpStream::connect(addr)
                .await
                .expect("a connection");
            let _ = s.write_all(&[9]).await;
            let r = tokio::time::timeout(Duration::from_secs(5), s.read(&mut b)).await;
            if matches!(r, Ok(Ok(1))) {
                next = Some(b[0]);
                break;
            }
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
        assert_eq!(next, Some(9));
        task.abort();
    }
}
