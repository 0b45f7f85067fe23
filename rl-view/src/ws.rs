//! The WebSocket side: a hub that broadcasts the coalesced state to every page at most every
//! [`BROADCAST_PERIOD`], and one thread per page that sends `hello` on connect, forwards the
//! newest state (intermediate ones are skipped, not queued: a slow page never holds the others
//! back) and answers the page's messages (`set_q`, `ik`, `ping`). Malformed messages are
//! answered with `{"type":"error"}` and counted. A page silent for [`IDLE_LIMIT`] is closed.

use std::net::TcpStream;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use tungstenite::protocol::{Role, WebSocketConfig};
use tungstenite::{Message, WebSocket};

use crate::Shared;
use crate::state::Source;

/// Shortest time between two state broadcasts.
pub const BROADCAST_PERIOD: Duration = Duration::from_millis(15);

/// How long a page's thread waits for input before looking for a new state to send.
const POLL: Duration = Duration::from_millis(5);

/// Largest message a page may send.
const MAX_MESSAGE: usize = 1 << 20;

/// A page that sends nothing (no message, no pong) for this long is closed: the page pings every
/// 5 s, and the server sends a WebSocket ping every [`PING_PERIOD`], which browsers answer by
/// themselves. An idle client no longer holds a page slot forever ([`crate::admission`]).
pub const IDLE_LIMIT: Duration = Duration::from_secs(30);

/// How often the server pings a page that has been quiet.
pub const PING_PERIOD: Duration = Duration::from_secs(10);

/// Locks, ignoring poisoning (the data stays consistent: every update is one assignment).
pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// One page's mailbox: the newest state not yet sent.
#[derive(Debug, Default)]
struct Slot {
    latest: Mutex<Option<Arc<str>>>,
    closed: AtomicBool,
}

/// The connected pages.
#[derive(Debug, Default)]
pub(crate) struct Hub {
    slots: Mutex<Vec<Arc<Slot>>>,
}

impl Hub {
    /// Pages connected now.
    pub(crate) fn clients(&self) -> usize {
        lock(&self.slots).len()
    }

    fn join(&self) -> Arc<Slot> {
        let s = Arc::new(Slot::default());
        lock(&self.slots).push(s.clone());
        s
    }

    /// Hands `state` to every page (replacing one not yet sent) and forgets closed pages.
    pub(crate) fn broadcast(&self, state: &Arc<str>) {
        let mut slots = lock(&self.slots);
        slots.retain(|s| !s.closed.load(Ordering::Relaxed));
        for s in slots.iter() {
            *lock(&s.latest) = Some(state.clone());
        }
    }
}

/// The broadcast loop: every period, take real-time updates, and if anything changed render
/// the state once and hand it to every page.
pub(crate) fn broadcast_loop(shared: &Shared) {
    while !shared.stop.load(Ordering::Relaxed) {
        std::thread::sleep(BROADCAST_PERIOD);
        shared.take_live();
        let state = {
            let mut e = lock(&shared.engine);
            if !e.changed() {
                continue;
            }
            e.state_json()
        };
        let text: Arc<str> = Arc::from(state.to_string());
        shared.hub.broadcast(&text);
    }
}

fn error(message: impl Into<String>) -> Value {
    json!({"type": "error", "message": message.into()})
}

fn floats(v: &Value, what: &str) -> Result<Vec<f64>, String> {
    let a = v
        .as_array()
        .ok_or_else(|| format!("\"{what}\" is not an array"))?;
    a.iter()
        .enumerate()
        .map(|(k, x)| {
            x.as_f64()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("\"{what}\"[{k}] is not a finite number"))
        })
        .collect()
}

/// Handles one message from a page; returns the reply to send, if any.
pub(crate) fn handle(shared: &Shared, text: &str) -> Option<Value> {
    let reply = (|| -> Result<Option<Value>, String> {
        let v: Value = serde_json::from_str(text).map_err(|e| format!("not JSON: {e}"))?;
        let kind = v.get("type").and_then(Value::as_str).ok_or("no \"type\"")?;
        let model = || -> Result<usize, String> {
            v.get("model")
                .and_then(Value::as_u64)
                .map(|m| m as usize)
                .ok_or_else(|| "no \"model\" index".to_string())
        };
        match kind {
            "ping" => Ok(Some(json!({"type": "pong"}))),
            "set_q" => {
                let m = model()?;
                let q = floats(v.get("q").ok_or("no \"q\"")?, "q")?;
                let source = match v.get("source").and_then(Value::as_str) {
                    Some("path") => Source::Path,
                    _ => Source::Ui,
                };
                lock(&shared.engine).set_q(m, &q, source)?;
                Ok(None)
            }
            "ik" => {
                let m = model()?;
                let t = floats(v.get("target").ok_or("no \"target\"")?, "target")?;
                let t: [f64; 7] = t
                    .try_into()
                    .map_err(|t: Vec<f64>| format!("\"target\" has {} values, not 7", t.len()))?;
                // The result goes out with the next state (its "ik" field).
                lock(&shared.engine).ik(m, &t);
                Ok(None)
            }
            other => Err(format!("unknown message type \"{other}\"")),
        }
    })();
    match reply {
        Ok(r) => r,
        Err(e) => {
            lock(&shared.engine).page_error();
            Some(error(e))
        }
    }
}

fn is_timeout(e: &tungstenite::Error) -> bool {
    matches!(e, tungstenite::Error::Io(io) if matches!(io.kind(),
        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut))
}

/// Serves one page on `stream` (the handshake is done): `hello`, then states and replies
/// until the page or the server goes.
pub(crate) fn serve(stream: TcpStream, shared: &Shared) {
    if stream.set_read_timeout(Some(POLL)).is_err()
        || stream
            .set_write_timeout(Some(Duration::from_secs(5)))
            .is_err()
    {
        return;
    }
    let _ = stream.set_nodelay(true);
    let config = WebSocketConfig::default()
        .max_message_size(Some(MAX_MESSAGE))
        .max_frame_size(Some(MAX_MESSAGE));
    let mut ws = WebSocket::from_raw_socket(stream, Role::Server, Some(config));
    let slot = shared.hub.join();
    let hello = {
        let mut e = lock(&shared.engine);
        json!({"type": "hello", "scene": e.scene().clone(), "state": e.snapshot_json()})
    };
    let mut ok = ws.send(Message::text(hello.to_string())).is_ok();
    let mut heard = Instant::now();
    let mut pinged = Instant::now();
    while ok && !shared.stop.load(Ordering::Relaxed) {
        let read = ws.read();
        if read.is_ok() {
            heard = Instant::now();
        }
        match read {
            Ok(Message::Text(t)) => {
                if let Some(r) = handle(shared, t.as_str()) {
                    ok = ws.send(Message::text(r.to_string())).is_ok();
                }
            }
            Ok(Message::Binary(_)) => {
                lock(&shared.engine).page_error();
                ok = ws
                    .send(Message::text(
                        error("binary messages are not understood").to_string(),
                    ))
                    .is_ok();
            }
            Ok(Message::Close(_)) => break,
            Ok(_) => {}
            Err(e) if is_timeout(&e) => {}
            Err(_) => break,
        }
        let next = lock(&slot.latest).take();
        if let Some(s) = next {
            ok = ok && ws.send(Message::text(s.to_string())).is_ok();
        }
        let idle = Duration::from_millis(shared.page_idle_ms.load(Ordering::Relaxed));
        let ping = PING_PERIOD.min(idle / 3);
        let quiet = heard.elapsed();
        if quiet > idle {
            break;
        }
        if quiet > ping && pinged.elapsed() > ping {
            pinged = Instant::now();
            ok = ok && ws.send(Message::Ping(Vec::new().into())).is_ok();
        }
    }
    slot.closed.store(true, Ordering::Relaxed);
    let _ = ws.close(None);
    let _ = ws.flush();
}
