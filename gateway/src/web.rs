//! The live view's web server (the book, "Live view in the browser"): one page embedded in the
//! binary and a WebSocket at `/ws` on axum, on the gateway's tokio runtime.
//!
//! The rig thread publishes a snapshot every 40 ms of wall time ([`crate::live::ViewOut`]);
//! each socket forwards the latest one as it is able (a slow browser skips snapshots, it never
//! holds the others up), after the plot's history on connecting. What a browser sends is a
//! command: `{"id": 1, "command": {"press": "cabin:3"}}`, at most
//! [`MAX_COMMAND_BYTES`](crate::command::MAX_COMMAND_BYTES) of JSON text, handed to the rig
//! thread and answered with `{"type": "reply", "id": 1, "ok": true}` (and a `"note"` the page
//! shows, if the rig thread has one) or `"ok": false` and an `"error"` that names the key at
//! fault. Nothing else is served: other paths are 404, and
//! every path is 403 to a `Host` that is not this server ([`Hosts`]).

use crate::command::MAX_COMMAND_BYTES;
use crate::live::{History, ToRig, WebAnswer, WebCall};
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Request, State};
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use crossbeam_channel::Sender;
use serde_json::{json, Value};
use std::net::{IpAddr, SocketAddr};
use std::sync::Arc;
use tokio::sync::watch;

/// The page.
pub const INDEX_HTML: &str = include_str!("../web/index.html");
/// Its script.
pub const APP_JS: &str = include_str!("../web/app.js");
/// Its style sheet.
pub const STYLE_CSS: &str = include_str!("../web/style.css");

/// The largest WebSocket message or frame taken at all; a longer one closes the socket. Up to
/// this size a message too long for a command gets an answer that says so.
const MAX_FRAME_BYTES: usize = 64 * 1024;

/// The `Host` values the live view answers to; any other gets 403 on every route, so that a
/// page of another site cannot reach it through DNS rebinding (a name of the attacker's that
/// resolves to this machine: the browser then sends that name as `Host` and as the page's
/// `Origin`, which agree). Accepted: the bound address itself (`127.0.0.1:8080`), loopback
/// (`localhost`, `127.x.x.x`, `[::1]`) with the bound port, any IP literal with the bound port
/// when bound to all addresses (`0.0.0.0`, `[::]`: no name, nothing to rebind), and the
/// names of the allow-list (`name` with the bound port, or `name:port`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Hosts {
    bound: SocketAddr,
    allow: Vec<String>,
}

impl Hosts {
    /// The hosts of a live view bound to `bound`, with the extra names `allow`.
    pub fn new(bound: SocketAddr, allow: Vec<String>) -> Hosts {
        Hosts { bound, allow }
    }

    /// Whether `name` is well-formed for the allow-list: a host name or IP address, with or
    /// without `:port`.
    pub fn valid_name(name: &str) -> bool {
        authority(name).is_some()
    }

    /// Whether `host`, the value of a request's `Host` header, names this server.
    pub fn accepts(&self, host: &str) -> bool {
        let Some((name, port)) = authority(host) else {
            return false;
        };
        let allowed = self.allow.iter().any(|a| match authority(a) {
            Some((n, Some(p))) => n.eq_ignore_ascii_case(name) && port.unwrap_or(80) == p,
            Some((n, None)) => {
                n.eq_ignore_ascii_case(name) && port.unwrap_or(80) == self.bound.port()
            }
            None => false,
        });
        if allowed {
            return true;
        }
        if port.unwrap_or(80) != self.bound.port() {
            return false;
        }
        if name.eq_ignore_ascii_case("localhost") {
            return true;
        }
        let ip = name
            .strip_prefix('[')
            .and_then(|n| n.strip_suffix(']'))
            .unwrap_or(name)
            .parse::<IpAddr>();
        match ip {
            Ok(ip) => ip.is_loopback() || ip == self.bound.ip() || self.bound.ip().is_unspecified(),
            Err(_) => false,
        }
    }
}

/// A `Host` value's name (IPv6 literals in brackets) and port, if it is well-formed.
fn authority(host: &str) -> Option<(&str, Option<u16>)> {
    let (name, port) = if host.starts_with('[') {
        let end = host.find(']')? + 1;
        match &host[end..] {
            "" => (&host[..end], None),
            rest => (&host[..end], Some(rest.strip_prefix(':')?)),
        }
    } else {
        match host.split_once(':') {
            Some((n, p)) => (n, Some(p)),
            None => (host, None),
        }
    };
    let ok = |c: char| c.is_ascii_alphanumeric() || "-.[]:".contains(c);
    if name.is_empty() || !name.chars().all(ok) || (!name.starts_with('[') && name.contains(':')) {
        return None;
    }
    let port = port
        .map(|p| p.parse::<u16>().ok())
        .map_or(Some(None), |p| p.map(Some))?;
    Some((name, port))
}

/// Refuses a request whose `Host` (or absolute URI's authority) does not name this server.
async fn check_host(State(hosts): State<Arc<Hosts>>, req: Request, next: Next) -> Response {
    let host = req
        .headers()
        .get(header::HOST)
        .and_then(|h| h.to_str().ok());
    let uri_host = req.uri().authority().map(|a| a.as_str());
    let ok = match (host, uri_host) {
        (Some(h), Some(u)) => hosts.accepts(h) && hosts.accepts(u),
        (Some(h), None) | (None, Some(h)) => hosts.accepts(h),
        (None, None) => false,
    };
    if ok {
        return next.run(req).await;
    }
    (
        StatusCode::FORBIDDEN,
        [(header::CONTENT_TYPE, "text/plain; charset=utf-8")],
        "forbidden: the live view answers only to its own address and loopback names \
         (asi-lift serve --allow-host NAME adds a name)\n",
    )
        .into_response()
}

/// What every request of the live view shares.
#[derive(Clone)]
pub struct Web {
    /// The latest snapshot (none before the first).
    pub snapshots: watch::Receiver<Option<Arc<str>>>,
    /// The plot's history.
    pub history: History,
    /// The rig thread.
    pub tx: Sender<ToRig>,
    /// The `Host` values it answers to.
    pub hosts: Arc<Hosts>,
}

/// The live view's routes: the page, its script and style, the WebSocket; 404 for the rest,
/// and 403 for all of them when the `Host` is not this server ([`Hosts`]).
pub fn router(web: Web) -> Router {
    let hosts = web.hosts.clone();
    Router::new()
        .route("/", get(index))
        .route("/index.html", get(index))
        .route("/app.js", get(app_js))
        .route("/style.css", get(style_css))
        .route("/ws", get(socket))
        .fallback(not_found)
        .with_state(web)
        .layer(axum::middleware::from_fn_with_state(hosts, check_host))
}

/// The page's security policy: its own script, style and socket only.
const CSP: &str = "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; \
                   connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'";

fn asset(content_type: &'static str, body: &'static str) -> Response {
    (
        [
            (header::CONTENT_TYPE, HeaderValue::from_static(content_type)),
            (header::CACHE_CONTROL, HeaderValue::from_static("no-cache")),
            (
                header::X_CONTENT_TYPE_OPTIONS,
                HeaderValue::from_static("nosniff"),
            ),
            (
                header::CONTENT_SECURITY_POLICY,
                HeaderValue::from_static(CSP),
            ),
        ],
        body,
    )
        .into_response()
}

async fn index() -> Response {
    asset("text/html; charset=utf-8", INDEX_HTML)
}

async fn app_js() -> Response {
    asset("text/javascript; charset=utf-8", APP_JS)
}

async fn style_css() -> Response {
    asset("text/css; charset=utf-8", STYLE_CSS)
}

async fn not_found() -> Response {
    (
        StatusCode::NOT_FOUND,
        [(header::CONTENT_TYPE, "text/plain; charset=utf-8")],
        "not found: asi-lift's live view serves /, /app.js, /style.css and the WebSocket /ws\n",
    )
        .into_response()
}

/// Whether a browser's `Origin` is this server: a page from elsewhere may not drive the lift
/// through the visitor's browser. Clients that are no browser send no `Origin`.
fn same_origin(headers: &HeaderMap) -> bool {
    let Some(origin) = headers.get(header::ORIGIN) else {
        return true;
    };
    let host = headers.get(header::HOST).and_then(|h| h.to_str().ok());
    let origin_host = origin
        .to_str()
        .ok()
        .and_then(|o| o.split_once("://"))
        .map(|(_, rest)| rest);
    matches!((origin_host, host), (Some(o), Some(h)) if o.eq_ignore_ascii_case(h))
}

async fn socket(ws: WebSocketUpgrade, headers: HeaderMap, State(web): State<Web>) -> Response {
    if !same_origin(&headers) {
        return (
            StatusCode::FORBIDDEN,
            "forbidden: the live view's socket takes pages from this server only\n",
        )
            .into_response();
    }
    ws.max_message_size(MAX_FRAME_BYTES)
        .max_frame_size(MAX_FRAME_BYTES)
        .on_upgrade(move |s| serve_socket(s, web))
}

/// One browser: the history, then every snapshot as it can take them, and the answers to its
/// commands; until it leaves or the run ends.
async fn serve_socket(mut socket: WebSocket, web: Web) {
    let Web {
        mut snapshots,
        history,
        tx,
        hosts: _,
    } = web;
    let points: Vec<[f64; 3]> = history
        .lock()
        .map(|h| h.iter().copied().collect())
        .unwrap_or_default();
    let hello = json!({"type": "history", "points": points}).to_string();
    if socket.send(Message::Text(hello.into())).await.is_err() {
        return;
    }
    // The current snapshot at once: a reload shows the rig as it is.
    snapshots.mark_changed();
    loop {
        tokio::select! {
            changed = snapshots.changed() => {
                if changed.is_err() {
                    // The run has ended and its last snapshot went out.
                    let _ = socket.send(Message::Close(None)).await;
                    return;
                }
                let Some(text) = snapshots.borrow_and_update().clone() else {
                    continue;
                };
                if socket.send(Message::Text(text.as_ref().into())).await.is_err() {
                    return;
                }
            }
            msg = socket.recv() => {
                let answer = match msg {
                    Some(Ok(Message::Text(t))) => command(t.as_str(), &tx).await,
                    Some(Ok(Message::Binary(b))) => reply(
                        None,
                        Err(format!(
                            "a binary message of {} bytes: commands are JSON text",
                            b.len()
                        )),
                    ),
                    Some(Ok(Message::Ping(_) | Message::Pong(_))) => continue,
                    // Closed, or broken (a message over the size limit among others).
                    Some(Ok(Message::Close(_)) | Err(_)) | None => return,
                };
                if socket.send(Message::Text(answer.into())).await.is_err() {
                    return;
                }
            }
        }
    }
}

/// The answer to a command, as the page gets it: with a `note` when the rig thread has one
/// (a warning about the speed, a command that waits for the paused run to go on).
fn reply(id: Option<&Value>, result: WebAnswer) -> String {
    let id = id.cloned().unwrap_or(Value::Null);
    match result {
        Ok(None) => json!({"type": "reply", "id": id, "ok": true}),
        Ok(Some(note)) => json!({"type": "reply", "id": id, "ok": true, "note": note}),
        Err(e) => json!({"type": "reply", "id": id, "ok": false, "error": e}),
    }
    .to_string()
}

/// Checks a message's envelope and size, hands the command to the rig thread and waits for
/// its answer.
pub(crate) async fn command(text: &str, tx: &Sender<ToRig>) -> String {
    if text.len() > MAX_COMMAND_BYTES {
        return reply(
            None,
            Err(format!(
                "message of {} bytes: a command has at most {MAX_COMMAND_BYTES}",
                text.len()
            )),
        );
    }
    let value: Value = match serde_json::from_str(text) {
        Ok(v) => v,
        Err(e) => return reply(None, Err(format!("not JSON: {e}"))),
    };
    let Some(envelope) = value.as_object() else {
        return reply(
            None,
            Err("a message is a JSON object: {\"id\": 1, \"command\": {…}}".into()),
        );
    };
    let id = envelope.get("id");
    if let Some(k) = envelope.keys().find(|k| *k != "id" && *k != "command") {
        return reply(
            id,
            Err(format!(
                "unknown key `{k}` in the message: it holds `id` and `command`"
            )),
        );
    }
    let Some(cmd) = envelope.get("command") else {
        return reply(id, Err("the message has no `command`".into()));
    };
    let (reply_tx, answer) = tokio::sync::oneshot::channel();
    let call = WebCall {
        command: cmd.clone(),
        reply: reply_tx,
    };
    if tx.send(ToRig::Web(call)).is_err() {
        return reply(id, Err("the run has ended".into()));
    }
    let result = answer
        .await
        .unwrap_or_else(|_| Err("the run has ended".into()));
    reply(id, result)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_this_servers_own_names_are_hosts() {
        let bound: SocketAddr = "127.0.0.1:8099".parse().expect("an address");
        let hosts = Hosts::new(
            bound,
            vec!["lab-pc.local".into(), "proxy.example:443".into()],
        );
        for ok in [
            "127.0.0.1:8099",
            "localhost:8099",
            "LOCALHOST:8099",
            "127.1.2.3:8099",
            "[::1]:8099",
            "lab-pc.local:8099",
            "proxy.example:443",
        ] {
            assert!(hosts.accepts(ok), "{ok}");
        }
        for bad in [
            "evil.example:8099",
            "evil.example",
            "localhost:8080",
            "localhost",
            "127.0.0.1",
            "10.0.0.1:8099",
            "lab-pc.local:8100",
            "proxy.example:8099",
            "",
            ":8099",
            "127.0.0.1:8099:1",
            "127.0.0.1:99999",
            "[::1",
            "[::1]x",
            "::1:8099",
            "localhost:8099/x",
            "localhost.evil.example:8099",
        ] {
            assert!(!hosts.accepts(bad), "{bad}");
        }
        let any = Hosts::new("0.0.0.0:80".parse().expect("an address"), Vec::new());
        assert!(any.accepts("192.168.1.20") && any.accepts("192.168.1.20:80"));
        assert!(!any.accepts("evil.example") && !any.accepts("192.168.1.20:81"));
    }

    #[test]
    fn only_pages_of_this_server_may_open_the_socket() {
        let mut h = HeaderMap::new();
        h.insert(header::HOST, HeaderValue::from_static("127.0.0.1:8080"));
        assert!(same_origin(&h));
        h.insert(
            header::ORIGIN,
            HeaderValue::from_static("http://127.0.0.1:8080"),
        );
        assert!(same_origin(&h));
        h.insert(
            header::ORIGIN,
            HeaderValue::from_static("https://evil.example"),
        );
        assert!(!same_origin(&h));
        h.remove(header::HOST);
        h.insert(
            header::ORIGIN,
            HeaderValue::from_static("http://127.0.0.1:8080"),
        );
        assert!(!same_origin(&h));
    }
}
