//! The HTTP side (std threads, never a real-time thread): the page's files embedded from
//! `web/dist/` at build time, `/api/scene` and `/api/state`, the model files of the fixed
//! table ([`crate::files`]) under `/files/`, and the WebSocket upgrade at `/ws`.
//!
//! A small HTTP/1.1 server over `std::net`: request heads are parsed with `httparse` (bounded
//! size and wait), only `GET` is served, every response closes its connection. The WebSocket
//! handshake answer is computed with tungstenite's key derivation and the connection handed to
//! [`crate::ws`].

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

use crate::Shared;
use crate::files::content_type;
use crate::ws::lock;

mod dist {
    include!(concat!(env!("OUT_DIR"), "/dist.rs"));
}

/// Largest request head accepted.
const MAX_HEAD: usize = 16 * 1024;
/// Most connections served at once (pages, their files, WebSockets); more get 503.
pub const MAX_CONNECTIONS: usize = 64;
const HEAD_TIMEOUT: Duration = Duration::from_secs(5);
const HEAD_POLL: Duration = Duration::from_millis(50);
const ACCEPT_POLL: Duration = Duration::from_millis(2);

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

/// Accepts connections until the server stops, one thread each.
pub(crate) fn accept_loop(listener: TcpListener, shared: Arc<Shared>) {
    let active = Arc::new(AtomicUsize::new(0));
    let mut threads: Vec<std::thread::JoinHandle<()>> = Vec::new();
    while !shared.stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((mut stream, _)) => {
                threads.retain(|t| !t.is_finished());
                if active.load(Ordering::Relaxed) >= MAX_CONNECTIONS {
                    let _ = stream.set_nonblocking(false);
                    let _ = stream.set_write_timeout(Some(ACCEPT_POLL));
                    let _ = respond(&mut stream, 503, "text/plain", b"too many connections\n");
                    continue;
                }
                active.fetch_add(1, Ordering::Relaxed);
                let (s, a) = (shared.clone(), active.clone());
                match std::thread::Builder::new()
                    .name("rl-view-http".into())
                    .stack_size(crate::WORKER_STACK)
                    .spawn(move || {
                        serve(stream, &s);
                        a.fetch_sub(1, Ordering::Relaxed);
                    }) {
                    Ok(t) => threads.push(t),
                    Err(_) => {
                        active.fetch_sub(1, Ordering::Relaxed);
                    }
                }
            }
            Err(_) => std::thread::sleep(ACCEPT_POLL),
        }
    }
    for t in threads {
        let _ = t.join();
    }
}

fn reason(code: u16) -> &'static str {
    match code {
        200 => "OK",
        400 => "Bad Request",
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
    let start = std::time::Instant::now();
    loop {
        if buf.windows(4).any(|w| w == b"\r\n\r\n") {
            return Ok(buf);
        }
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

fn serve(mut stream: TcpStream, shared: &Shared) {
    if stream.set_nonblocking(false).is_err()
        || stream.set_read_timeout(Some(HEAD_POLL)).is_err()
        || stream.set_write_timeout(Some(HEAD_TIMEOUT)).is_err()
    {
        return;
    }
    let head = match read_head(&mut stream, &shared.stop) {
        Ok(h) => h,
        Err(code) => {
            let _ = respond(&mut stream, code, "text/plain", b"bad request\n");
            return;
        }
    };
    let mut headers = [httparse::EMPTY_HEADER; 64];
    let mut req = httparse::Request::new(&mut headers);
    if !matches!(req.parse(&head), Ok(httparse::Status::Complete(_))) {
        let _ = respond(&mut stream, 400, "text/plain", b"bad request\n");
        return;
    }
    let method = req.method.unwrap_or("");
    let target = req.path.unwrap_or("/");
    let path = target.split(['?', '#']).next().unwrap_or("/");
    let header = |name: &str| {
        req.headers
            .iter()
            .find(|h| h.name.eq_ignore_ascii_case(name))
            .and_then(|h| std::str::from_utf8(h.value).ok())
    };
    if method != "GET" {
        let _ = respond(&mut stream, 405, "text/plain", b"only GET\n");
        return;
    }
    if path == "/ws" {
        let upgrade = header("upgrade").is_some_and(|u| u.eq_ignore_ascii_case("websocket"));
        let Some(key) = header("sec-websocket-key").filter(|_| upgrade) else {
            let _ = respond(
                &mut stream,
                400,
                "text/plain",
                b"WebSocket upgrade expected\n",
            );
            return;
        };
        let accept = tungstenite::handshake::derive_accept_key(key.trim().as_bytes());
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
