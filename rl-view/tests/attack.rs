//! Hostile clients (issue 24): slow and idle connections must not lock the page out, idle
//! WebSocket clients lose their slot, one peer cannot take every page slot, and a page from
//! elsewhere (another origin, or a DNS-rebound name) cannot use the viewer.

mod support;

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use support::*;

/// A raw request with the given headers: the status code (0 when the connection gave none).
fn status(addr: SocketAddr, request: &str) -> u16 {
    let Ok(mut s) = TcpStream::connect(addr) else {
        return 0;
    };
    s.set_read_timeout(Some(WAIT)).unwrap();
    if s.write_all(request.as_bytes()).is_err() {
        return 0;
    }
    let mut head = [0u8; 12];
    let mut n = 0;
    while n < head.len() {
        match s.read(&mut head[n..]) {
            Ok(0) | Err(_) => break,
            Ok(k) => n += k,
        }
    }
    std::str::from_utf8(&head[..n])
        .ok()
        .and_then(|h| h.split_whitespace().nth(1))
        .and_then(|c| c.parse().ok())
        .unwrap_or(0)
}

fn get_with(addr: SocketAddr, path: &str, extra: &str) -> u16 {
    status(addr, &format!("GET {path} HTTP/1.1\r\n{extra}\r\n"))
}

fn upgrade(origin: Option<&str>, host: &str) -> String {
    let origin = origin.map_or_else(String::new, |o| format!("Origin: {o}\r\n"));
    format!(
        "Host: {host}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n{origin}"
    )
}

/// A connection to `addr` from the loopback address `from` (another peer than 127.0.0.1).
fn connect_from(from: &str, addr: SocketAddr) -> std::io::Result<TcpStream> {
    let s = socket2::Socket::new(socket2::Domain::IPV4, socket2::Type::STREAM, None)?;
    let local: SocketAddr = format!("{from}:0").parse().expect("an address");
    s.bind(&local.into())?;
    s.connect_timeout(&addr.into(), Duration::from_secs(5))?;
    Ok(s.into())
}

/// `n` slowloris clients from `from`: each sends the start of a request head and then one byte
/// every 300 ms, and opens a new connection whenever the server closes its own. Returns the
/// flag that stops them, the count of connections they opened, and their threads.
fn slowloris(
    addr: SocketAddr,
    from: &'static str,
    n: usize,
) -> (
    Arc<AtomicBool>,
    Arc<AtomicUsize>,
    Vec<std::thread::JoinHandle<()>>,
) {
    let stop = Arc::new(AtomicBool::new(false));
    let opened = Arc::new(AtomicUsize::new(0));
    let threads = (0..n)
        .map(|_| {
            let (stop, opened) = (stop.clone(), opened.clone());
            std::thread::spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    let Ok(mut s) = connect_from(from, addr) else {
                        std::thread::sleep(Duration::from_millis(20));
                        continue;
                    };
                    opened.fetch_add(1, Ordering::Relaxed);
                    let _ = s.set_write_timeout(Some(Duration::from_secs(1)));
                    if s.write_all(b"GET / HTTP/1.1\r\nX-a: ").is_err() {
                        continue;
                    }
                    while !stop.load(Ordering::Relaxed) {
                        std::thread::sleep(Duration::from_millis(300));
                        if s.write_all(b"a").is_err() {
                            break;
                        }
                    }
                }
            })
        })
        .collect();
    (stop, opened, threads)
}

#[test]
fn slow_and_idle_connections_do_not_lock_out_the_page() {
    let v = start(vec![ur5()]);
    let addr = v.http_addr();
    // 170 slowloris connections (70 from the probes' own address, 100 from another: together
    // more than the pending pool holds) and 40 WebSocket clients that never send or read.
    let (stop_a, opened_a, mut threads) = slowloris(addr, "127.0.0.1", 70);
    let (stop_b, opened_b, threads_b) = slowloris(addr, "127.0.0.2", 100);
    threads.extend(threads_b);
    let idle: Vec<TcpStream> = (0..40)
        .filter_map(|_| {
            let mut s = connect_from("127.0.0.2", addr).ok()?;
            let request = format!(
                "GET /ws HTTP/1.1\r\n{}\r\n",
                upgrade(None, &addr.to_string())
            );
            s.write_all(request.as_bytes()).ok()?;
            Some(s)
        })
        .collect();
    assert_eq!(idle.len(), 40);
    std::thread::sleep(Duration::from_millis(1500));
    let (pending, _, pages) = v.connections();
    println!("under attack: {pending} heads arriving, {pages} pages");
    assert!(pending >= 100, "the slow clients are connected ({pending})");
    // The idle clients hold at most their peer's share of the page slots.
    assert!(pages <= rl_view::admission::MAX_PAGES_PER_PEER, "{pages}");

    // Probes as a browser makes them, during the attack: the page, the API, and a page's
    // WebSocket that answers.
    let mut codes = Vec::new();
    let start_probes = Instant::now();
    for k in 0..12 {
        let path = ["/", "/api/state", "/api/scene"][k % 3];
        codes.push(get_with(addr, path, &format!("Host: {addr}\r\n")));
        std::thread::sleep(Duration::from_millis(200));
    }
    let (mut page, hello) = Page::connect(addr);
    assert_eq!(hello["type"], "hello");
    page.send(serde_json::json!({"type": "ping"}));
    page.wait_for(|m| m["type"] == "pong");
    let (evicted, refused) = v.turned_away();
    println!(
        "probes {codes:?} in {:?}; slow connections opened {} + {}; {evicted} closed to make \
         room, {refused} refused with 503",
        start_probes.elapsed(),
        opened_a.load(Ordering::Relaxed),
        opened_b.load(Ordering::Relaxed),
    );
    assert!(codes.iter().all(|&c| c == 200), "{codes:?}");
    assert!(evicted > 0, "the pending pool was full and made room");
    stop_a.store(true, Ordering::Relaxed);
    stop_b.store(true, Ordering::Relaxed);
    drop(idle);
    for t in threads {
        let _ = t.join();
    }
}

#[test]
fn idle_pages_are_closed_and_one_peer_holds_at_most_its_share() {
    let v = start(vec![ur5()]);
    let addr = v.http_addr();
    v.set_page_idle_limit(Duration::from_millis(1500));
    // A page that answers (it reads, so its WebSocket answers the server's pings) stays; a
    // client that never reads or sends is closed after the idle limit.
    let (mut live, _) = Page::connect(addr);
    let (silent, _) = tungstenite::connect(format!("ws://{addr}/ws")).expect("connects");
    let t0 = Instant::now();
    while v.connections().2 != 2 && t0.elapsed() < WAIT {
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(v.connections().2, 2);
    let t0 = Instant::now();
    while v.connections().2 > 1 && t0.elapsed() < WAIT {
        // The live page keeps reading (and so answers pings) without sending anything.
        let _ = live.ws.read();
    }
    let closed_after = t0.elapsed();
    println!("the silent client was closed after {closed_after:?}");
    assert_eq!(
        v.connections().2,
        1,
        "the silent client still holds its slot"
    );
    assert!(
        closed_after >= Duration::from_millis(1000),
        "{closed_after:?}"
    );
    live.send(serde_json::json!({"type": "ping"}));
    live.wait_for(|m| m["type"] == "pong");
    drop(silent);

    // One peer holds at most MAX_PAGES_PER_PEER pages; the next gets 503.
    let max = rl_view::admission::MAX_PAGES_PER_PEER;
    let mut held = Vec::new();
    while held.len() + 1 < max {
        let (ws, _) = tungstenite::connect(format!("ws://{addr}/ws")).expect("connects");
        held.push(ws);
    }
    assert_eq!(
        get_with(addr, "/ws", &upgrade(None, &addr.to_string())),
        503
    );
    // Plain requests are another pool: still answered.
    assert_eq!(
        get_with(addr, "/api/state", &format!("Host: {addr}\r\n")),
        200
    );
}

#[test]
fn requests_from_another_origin_or_host_are_refused() {
    let v = start(vec![ur5()]);
    let addr = v.http_addr();
    let port = addr.port();
    let own = format!("http://{addr}");
    // DNS rebinding: the attacker's name resolved to 127.0.0.1; the browser sends its Host.
    for path in ["/api/state", "/api/scene", "/files/0/robot.urdf", "/"] {
        assert_eq!(
            get_with(addr, path, &format!("Host: evil.example:{port}\r\n")),
            403,
            "{path}"
        );
        assert_eq!(
            get_with(addr, path, &format!("Host: {addr}\r\n")),
            200,
            "{path}"
        );
    }
    assert_eq!(
        get_with(addr, "/ws", &upgrade(None, &format!("evil.example:{port}"))),
        403
    );
    // No Host at all (HTTP/1.1 requires one), another port, a rebound name with our origin.
    assert_eq!(get_with(addr, "/api/state", ""), 403);
    assert_eq!(
        get_with(
            addr,
            "/api/state",
            &format!("Host: 127.0.0.1:{}\r\n", port + 1)
        ),
        403
    );
    // Loopback names of this server are answered.
    assert_eq!(
        get_with(addr, "/api/state", &format!("Host: localhost:{port}\r\n")),
        200
    );
    // A page from elsewhere opening the WebSocket (to send set_q) or fetching files.
    for origin in [
        "http://evil.example",
        "http://evil.example:8080",
        "null",
        &format!("http://localhost:{}", port + 1),
    ] {
        assert_eq!(
            get_with(addr, "/ws", &upgrade(Some(origin), &addr.to_string())),
            403,
            "{origin}"
        );
        assert_eq!(
            get_with(
                addr,
                "/files/0/robot.urdf",
                &format!("Host: {addr}\r\nOrigin: {origin}\r\n")
            ),
            403,
            "{origin}"
        );
    }
    // The server's own origin, and a loopback name of it, open the WebSocket.
    for origin in [own.as_str(), &format!("http://localhost:{port}")] {
        assert_eq!(
            get_with(addr, "/ws", &upgrade(Some(origin), &addr.to_string())),
            101,
            "{origin}"
        );
    }
    // A set_q refused at the handshake never reaches the model.
    let before = get_json(addr, "/api/state")["models"][0]["q"].clone();
    let mut s = TcpStream::connect(addr).unwrap();
    s.write_all(
        format!(
            "GET /ws HTTP/1.1\r\n{}\r\n",
            upgrade(Some("http://evil.example"), &addr.to_string())
        )
        .as_bytes(),
    )
    .unwrap();
    let _ = s.write_all(b"\x81\x05hello");
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(get_json(addr, "/api/state")["models"][0]["q"], before);
    // A host name the application adds is answered.
    assert_eq!(
        get_with(addr, "/api/state", &format!("Host: robot.local:{port}\r\n")),
        403
    );
    v.allow_host("robot.local");
    assert_eq!(
        get_with(addr, "/api/state", &format!("Host: robot.local:{port}\r\n")),
        200
    );
}
