//! Shared helpers of the rl-view tests: the data files, a viewer on free ports, a raw HTTP GET,
//! a WebSocket client that waits for a message matching a test, a Coach client on a raw socket.

#![allow(dead_code)]

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use rl_view::{LoadOptions, ModelSource, Viewer, ViewerOptions};
use serde_json::Value;
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

/// How long a test waits for something that should happen within a few frames.
pub const WAIT: Duration = Duration::from_secs(10);

pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

pub fn ur5() -> PathBuf {
    repo().join("tests/data/mbm/ur5/ur5.urdf")
}

pub fn puma() -> PathBuf {
    repo().join("tests/data/rlmdl/unimation-puma560.xml")
}

pub fn options(models: Vec<PathBuf>) -> ViewerOptions {
    ViewerOptions {
        load: LoadOptions {
            models: models.into_iter().map(ModelSource::File).collect(),
            ..LoadOptions::default()
        },
        http: "127.0.0.1:0".parse().unwrap(),
        coach: Some("127.0.0.1:0".parse().unwrap()),
    }
}

pub fn start(models: Vec<PathBuf>) -> Viewer {
    Viewer::start(&options(models)).expect("viewer starts")
}

/// A GET: status and body.
pub fn get(addr: SocketAddr, path: &str) -> (u16, Vec<u8>) {
    let mut s = TcpStream::connect(addr).expect("connect");
    s.set_read_timeout(Some(WAIT)).unwrap();
    write!(s, "GET {path} HTTP/1.1\r\nHost: {addr}\r\n\r\n").unwrap();
    let mut out = Vec::new();
    s.read_to_end(&mut out).expect("read response");
    let end = out
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("a response head");
    let head = String::from_utf8_lossy(&out[..end]).to_string();
    let status: u16 = head
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .expect("a status code");
    (status, out[end + 4..].to_vec())
}

pub fn get_json(addr: SocketAddr, path: &str) -> Value {
    let (status, body) = get(addr, path);
    assert_eq!(status, 200, "GET {path}");
    serde_json::from_slice(&body).expect("JSON")
}

pub struct Page {
    pub ws: WebSocket<MaybeTlsStream<TcpStream>>,
    pub last_state: Option<Value>,
}

impl Page {
    /// Connects to `/ws` and returns the page with its `hello`.
    pub fn connect(addr: SocketAddr) -> (Page, Value) {
        let (ws, _) = tungstenite::connect(format!("ws://{addr}/ws")).expect("WebSocket connects");
        if let MaybeTlsStream::Plain(s) = ws.get_ref() {
            s.set_read_timeout(Some(Duration::from_millis(50))).unwrap();
        }
        let mut page = Page {
            ws,
            last_state: None,
        };
        let hello = page.wait_for(|m| m["type"] == "hello");
        (page, hello)
    }

    pub fn send(&mut self, v: Value) {
        self.ws.send(Message::text(v.to_string())).expect("send");
    }

    /// The next message for which `f` holds (others are skipped), within [`WAIT`].
    pub fn wait_for(&mut self, mut f: impl FnMut(&Value) -> bool) -> Value {
        let end = Instant::now() + WAIT;
        while Instant::now() < end {
            match self.ws.read() {
                Ok(Message::Text(t)) => {
                    let v: Value = serde_json::from_str(t.as_str()).expect("JSON message");
                    if v["type"] == "state" {
                        self.last_state = Some(v.clone());
                    }
                    if f(&v) {
                        return v;
                    }
                }
                Ok(_) => {}
                Err(tungstenite::Error::Io(e))
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) => {}
                Err(e) => panic!("WebSocket: {e}"),
            }
        }
        panic!(
            "no matching message within {WAIT:?}; last state: {}",
            self.last_state
                .as_ref()
                .map(Value::to_string)
                .unwrap_or_default()
        );
    }

    /// The next state for which `f` holds.
    pub fn wait_state(&mut self, mut f: impl FnMut(&Value) -> bool) -> Value {
        self.wait_for(|m| m["type"] == "state" && f(m))
    }
}

/// A Coach client on a raw socket, writing RL's lines.
pub struct Coach {
    pub s: TcpStream,
}

impl Coach {
    pub fn connect(addr: SocketAddr) -> Coach {
        let s = TcpStream::connect(addr).expect("Coach connects");
        s.set_read_timeout(Some(WAIT)).unwrap();
        Coach { s }
    }

    pub fn send(&mut self, text: &str) {
        self.s.write_all(text.as_bytes()).expect("Coach write");
    }

    /// Reads one reply line.
    pub fn read_line(&mut self) -> String {
        let mut line = Vec::new();
        let mut b = [0u8; 1];
        while self.s.read(&mut b).expect("Coach reply") == 1 {
            if b[0] == b'\n' {
                break;
            }
            line.push(b[0]);
        }
        String::from_utf8(line).expect("ASCII reply")
    }
}

pub fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// The body poses of model `m` in a state.
pub fn bodies(state: &Value, m: usize) -> Vec<Vec<f64>> {
    state["models"][m]["bodies"]
        .as_array()
        .expect("bodies")
        .iter()
        .map(floats)
        .collect()
}

pub fn max_diff(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs()))
        .fold(0.0, f64::max)
}

/// Writes `text` to `name` in a directory of this test process and returns its path.
pub fn temp_file(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rl-view-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}
