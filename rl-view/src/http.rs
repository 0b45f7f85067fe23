//! The HTTP side (std threads, never a real-time thread): the page's files embedded from
//! `web/dist/` at build time, `/api/scene` and `/api/state`, the model files of the fixed
//! table ([`crate::files`]) under `/files/`, and the WebSocket upgrade at `/ws`.
//!
//! A small HTTP/1.1 server over `std::net`: request heads are parsed with `httparse` (bounded
//! size and wait), only `GET` is served, every response closes its connection. Who gets a
//! connection, and what a slow or idle one loses, is [`crate::admission`]'s; which `Host` and
//! `Origin` are answered (DNS rebinding, cross-site pages) is [`crate::origin`]'s (refused with
//! 403). The WebSocket handshake answer is computed with tungstenite's key derivation and the
//! connection handed to [`crate::ws`].

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crate::Shared;
use crate::admission::{HEAD_TIMEOUT, Pool, Slot};
use crate::files::content_type;
use crate::ws::lock;

mod dist {
    include!(concat!(env!("OUT_DIR"), "/dist.rs"));
}

/// Largest request head accepted.
const MAX_HEAD: usize = 16 * 1024;
const HEAD_POLL: Duration = Duration::from_millis(50);
const ACCEPT_POLL: Duration = Duration::from_millis(2);
/// How long one write of a response may block (a client that does not read).
const WRITE_TIMEOUT: Duration = Duration::from_secs(5);
/// Stack of a thread that reads a request head: it holds the head and little else.
const HEAD_STACK: usize = 256 << 10;

/// The embedded file `name` (relative to `web/dist/`).
pub fn embedded(name: &str) -> Option<&'static [u8]> {
    dist::DIST.iter().find(|(n, _)| *n == name).map(|(_, b)| *b)
}

/// The names of the embedded files.
pub fn embedded_names() -> impl Iterator<Item = &'static str> {
    dist::DIST.iter().map(|(n, _)| *n)
}

pub(crate) fn bind(addr: SocketAddr) -> io::Result<TcpListener> {
    let l = TcpListener::bind(addr)?;
    l.set_nonblocking(true)?;
    Ok(l)
}

/// Accepts connections until the server stops: each goes to the pending pool (which may close
/// the oldest slow one to make room) and gets a small thread that reads its head.
pub(crate) fn accept_loop(listener: TcpListener, shared: Arc<Shared>) {
    let mut threads: Vec<std::thread::JoinHandle<()>> = Vec::new();
    while !shared.stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, peer)) => {
                threads.retain(|t| !t.is_finished());
                let Some(id) = shared.admission.admit(peer.ip(), &stream) else {
                    continue;
                };
                let s = shared.clone();
                match std::thread::Builder::new()
                    .name("rl-view-head".into())
                    .stack_size(HEAD_STACK)
                    .spawn(move || {
                        let head = read_and_check(stream, peer, &s);
                        s.admission.done(id);
                        if let Some((stream, request, slot)) = head {
                            spawn_worker(stream, request, slot, s);
                        }
                    }) {
                    Ok(t) => threads.push(t),
                    Err(_) => shared.admission.done(id),
                }
            }
            Err(_) => std::thread::sleep(ACCEPT_POLL),
        }
    }
    for t in threads {
        let _ = t.join();
    }
}

/// What the server needs of a request head.
#[derive(Debug)]
struct Request {
    path: String,
    upgrade: bool,
    key: Option<String>,
}

/// Reads and checks the head of a new connection: answers it with an error (and `None`) when
/// it is late, too large, malformed, not `GET`, from a `Host` or `Origin` not answered, or when
/// its pool is full; otherwise returns it with its slot.
fn read_and_check(
    mut stream: TcpStream,
    peer: SocketAddr,
    shared: &Shared,
) -> Option<(TcpStream, Request, Slot)> {
    if stream.set_nonblocking(false).is_err()
        || stream.set_read_timeout(Some(HEAD_POLL)).is_err()
        || stream.set_write_timeout(Some(WRITE_TIMEOUT)).is_err()
    {
        return None;
    }
    let head = match read_head(&mut stream, &shared.stop) {
        Ok(h) => h,
        Err(code) => {
            let _ = respond(&mut stream, code, "text/plain", b"bad request\n");
            return None;
        }
    };
    let mut headers = [httparse::EMPTY_HEADER; 64];
    let mut req = httparse::Request::new(&mut headers);
    if !matches!(req.parse(&head), Ok(httparse::Status::Complete(_))) {
        let _ = respond(&mut stream, 400, "text/plain", b"bad request\n");
        return None;
    }
    let header = |name: &str| {
        req.headers
            .iter()
            .find(|h| h.name.eq_ignore_ascii_case(name))
            .and_then(|h| std::str::from_utf8(h.value).ok())
    };
    if req.method != Some("GET") {
        let _ = respond(&mut stream, 405, "text/plain", b"only GET\n");
        return None;
    }
    let (host, origin) = (header("host"), header("origin"));
    let allowed = {
        let policy = lock(&shared.policy);
        policy.host_ok(host) && host.is_some_and(|h| policy.origin_ok(origin, h))
    };
    if !allowed {
        let _ = respond(
            &mut stream,
            403,
            "text/plain",
            b"refused: the Host or Origin of this request is not one this viewer answers \
              (a loopback name or an IP address with its port; a page from elsewhere may not \
              use it)\n",
        );
        return None;
    }
    let target = req.path.unwrap_or("/");
    let request = Request {
        path: target.split(['?', '#']).next().unwrap_or("/").to_string(),
        upgrade: header("upgrade").is_some_and(|u| u.eq_ignore_ascii_case("websocket")),
        key: header("sec-websocket-key").map(|k| k.trim().to_string()),
    };
    let pool = if request.path == "/ws" {
        Pool::Page
    } else {
        Pool::Request
    };
    let Some(slot) = shared.admission.slot(pool, peer.ip()) else {
        let _ = respond(&mut stream, 503, "text/plain", b"too many connections\n");
        return None;
    };
    Some((stream, request, slot))
}

/// Serves a checked request on a thread with the workers' stack (a page's thread may solve
/// IK on large kinematic models); the slot is given back when it ends.
fn spawn_worker(stream: TcpStream, request: Request, slot: Slot, shared: Arc<Shared>) {
    let _ = std::thread::Builder::new()
        .name("rl-view-http".into())
        .stack_size(crate::WORKER_STACK)
        .spawn(move || {
            serve(stream, &request, &shared);
            drop(slot);
        });
}

fn reason(code: u16) -> &'static str {
    match code {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        408 => "Request Timeout",
        431 => "Request Header Fields Too Large",
        503 => "Service Unavailable",
        _ => "Error",
    }
}

fn respond(stream: &mut TcpStream, code: u16, ctype: &str, body: &[u8]) -> io::Result<()> {
    let head = format!(
        "HTTP/1.1 {code} {}\r\nContent-Type: {ctype}\r\nContent-Length: {}\r\n\
         Cache-Control: no-cache\r\nX-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\n",
        reason(code),
        body.len()
    );
    stream.write_all(head.as_bytes())?;
    stream.write_all(body)?;
    stream.flush()
}

/// Reads a request head (up to the blank line), bounded in size and time; gives up early when
/// the server stops (browsers keep idle connections open).
fn read_head(stream: &mut TcpStream, stop: &AtomicBool) -> Result<Vec<u8>, u16> {
    let mut buf = Vec::with_capacity(1024);
    let mut chunk = [0u8; 1024];
    let start = Instant::now();
    // Where the search for the blank line resumes (a head dribbled byte by byte is scanned once).
    let mut scanned = 0;
    loop {
        if buf[scanned..].windows(4).any(|w| w == b"\r\n\r\n") {
            return Ok(buf);
        }
        scanned = buf.len().saturating_sub(3);
        if buf.len() > MAX_HEAD {
            return Err(431);
        }
        if stop.load(Ordering::Relaxed) || start.elapsed() > HEAD_TIMEOUT {
            return Err(408);
        }
        match stream.read(&mut chunk) {
            Ok(0) => return Err(400),
            Ok(n) => buf.extend_from_slice(&chunk[..n]),
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) => {}
            Err(_) => return Err(400),
        }
    }
}

fn serve(mut stream: TcpStream, request: &Request, shared: &Shared) {
    let path = request.path.as_str();
    if path == "/ws" {
        let Some(key) = request.key.as_deref().filter(|_| request.upgrade) else {
            let _ = respond(
                &mut stream,
                400,
                "text/plain",
                b"WebSocket upgrade expected\n",
            );
            return;
        };
        let accept = tungstenite::handshake::derive_accept_key(key.as_bytes());
        let answer = format!(
            "HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
             Sec-WebSocket-Accept: {accept}\r\n\r\n"
        );
        if stream.write_all(answer.as_bytes()).is_ok() {
            crate::ws::serve(stream, shared);
        }
        return;
    }
    let (code, ctype, body): (u16, &str, Vec<u8>) = match path {
        "/" | "/index.html" => match embedded("index.html") {
            Some(b) => (200, "text/html; charset=utf-8", b.to_vec()),
            None => (404, "text/plain", b"no page embedded\n".to_vec()),
        },
        "/api/scene" => {
            let s = lock(&shared.engine).scene().to_string();
            (200, "application/json", s.into_bytes())
        }
        "/api/state" => {
            let s = lock(&shared.engine).snapshot_json().to_string();
            (200, "application/json", s.into_bytes())
        }
        p => {
            if let Some(name) = p.strip_prefix("/dist/") {
                match embedded(name) {
                    Some(b) => (200, content_type(name), b.to_vec()),
                    None => (404, "text/plain", b"not found\n".to_vec()),
                }
            } else if let Some(key) = p.strip_prefix("/files/") {
                match shared.files.read(key) {
                    Some((b, t)) => (200, t, b),
                    None => (
                        404,
                        "text/plain",
                        b"not a file of the loaded models\n".to_vec(),
                    ),
                }
            } else {
                (404, "text/plain", b"not found\n".to_vec())
            }
        }
    };
    let _ = respond(&mut stream, code, ctype, &body);
}
