//! A Coach server: the server side of RL's visualisation protocol. It keeps per-model joint
//! states and body/shape poses, answers `6 <i>` with the model's joint positions (`6 <i>` alone
//! for an unknown model, as rlCoachMdl does), and ignores a `2 <i>` line whose length differs
//! from the model's joints. Usable as the fake for tests (with options that split replies into
//! partial lines or batch several lines into one write, and [`Behaviour`]s that pause, stay
//! silent, garble or hang up) and as the endpoint a visualiser builds on (read the state with
//! [`CoachServer::status`]).
//!
//! Like RL's servers it has no limit on the number of values in a line (values are kept in
//! growable storage; this server is not on a real-time path). A line is bounded by
//! [`CoachServerConfig::max_line_bytes`] instead: a longer one is dropped up to its newline,
//! counted and described in [`CoachServerStatus::last_error`] — nothing is dropped silently.

use std::collections::HashMap;
use std::io::{self, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use super::tcp_server::{self, Polled};
use crate::proto::coach::Message;

const POLL: Duration = Duration::from_millis(20);
const ACCEPT_POLL: Duration = Duration::from_millis(1);

/// How the server writes its replies (to exercise a client's line reassembly).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Delivery {
    /// Write each reply in pieces of this many bytes, pausing `chunk_pause` between them.
    pub chunk_bytes: Option<usize>,
    /// Pause between pieces.
    pub chunk_pause: Duration,
    /// Put this many extra lines (empty lines and a `2 <i>` echo) in the same write before
    /// each reply, so a client reads several lines at once.
    pub extra_lines: usize,
}

/// How the server treats its clients (hostile behaviours for tests).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Behaviour {
    /// Reads every line and answers requests.
    #[default]
    Normal,
    /// Stops reading (the client's lines queue up in the kernel, as behind a stopped process);
    /// on [`Normal`](Behaviour::Normal) again it reads and answers all of them.
    Paused,
    /// Reads lines but never answers.
    Silent,
    /// Answers every request with a line that is not Coach.
    Garbage,
}

/// Server configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct CoachServerConfig {
    /// Listen address (RL's visualisers use port 11235).
    pub bind: SocketAddr,
    /// Models known from the start (as RL's viewers know the models they loaded): index and
    /// joint positions, where the robot stands.
    pub models: Vec<(u32, Vec<f64>)>,
    /// Learn a model from its first `2 <i> q…` line if it is not known.
    pub learn_models: bool,
    /// How replies are written.
    pub delivery: Delivery,
    /// Longest line accepted, newline excluded; longer ones are dropped and counted.
    pub max_line_bytes: usize,
    /// How clients are treated.
    pub behaviour: Behaviour,
}

impl CoachServerConfig {
    /// 127.0.0.1 with a free port, no models known, models learnt from joint lines.
    pub fn loopback() -> Self {
        Self {
            bind: SocketAddr::from(([127, 0, 0, 1], 0)),
            models: Vec::new(),
            learn_models: true,
            delivery: Delivery::default(),
            max_line_bytes: 1 << 20,
            behaviour: Behaviour::Normal,
        }
    }
}

/// The server's state (a snapshot).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CoachServerStatus {
    /// Clients accepted.
    pub clients: u64,
    /// Lines received.
    pub lines: u64,
    /// Lines that did not parse.
    pub bad_lines: u64,
    /// Joint lines ignored because their length differs from the model's joints.
    pub ignored_lines: u64,
    /// Lines longer than `max_line_bytes`, dropped up to their newline.
    pub overlong_lines: u64,
    /// What was wrong with the last bad or overlong line (line number and reason).
    pub last_error: Option<String>,
    /// `6 <i>` requests answered.
    pub requests: u64,
    /// Joint positions per model.
    pub joints: HashMap<u32, Vec<f64>>,
    /// Last joint velocities per model.
    pub velocities: HashMap<u32, Vec<f64>>,
    /// Last joint torques per model.
    pub torques: HashMap<u32, Vec<f64>>,
    /// Body frames by (model, body): `x y z a b c`.
    pub bodies: HashMap<(u32, u32), [f64; 6]>,
    /// Shape transforms by (model, body, shape).
    pub shapes: HashMap<(u32, u32, u32), [f64; 6]>,
}

#[derive(Debug)]
struct Shared {
    config: CoachServerConfig,
    status: CoachServerStatus,
    /// Bumped by `disconnect_clients`: clients of an older generation hang up.
    generation: u64,
}

fn lock(shared: &Mutex<Shared>) -> MutexGuard<'_, Shared> {
    shared.lock().unwrap_or_else(|p| p.into_inner())
}

/// A running Coach server; stops its threads when dropped.
#[derive(Debug)]
pub struct CoachServer {
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    addr: SocketAddr,
    accept: Option<JoinHandle<()>>,
}

impl CoachServer {
    /// Binds and starts accepting clients (one thread per client).
    pub fn spawn(config: CoachServerConfig) -> io::Result<CoachServer> {
        let listener = TcpListener::bind(config.bind)?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let mut status = CoachServerStatus::default();
        for (model, q) in &config.models {
            status.joints.insert(*model, q.clone());
        }
        let shared = Arc::new(Mutex::new(Shared {
            config,
            status,
            generation: 0,
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let (s, st) = (shared.clone(), stop.clone());
        let accept = std::thread::Builder::new()
            .name("coach-accept".into())
            .spawn(move || accept_loop(&listener, &s, &st))?;
        Ok(CoachServer {
            shared,
            stop,
            addr,
            accept: Some(accept),
        })
    }

    /// The listening address.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// A snapshot of the state.
    pub fn status(&self) -> CoachServerStatus {
        lock(&self.shared).status.clone()
    }

    /// Sets a model's joint positions (as a simulator moving the model would).
    pub fn set_joints(&self, model: u32, q: &[f64]) {
        lock(&self.shared).status.joints.insert(model, q.to_vec());
    }

    /// Changes how replies are written.
    pub fn set_delivery(&self, delivery: Delivery) {
        lock(&self.shared).config.delivery = delivery;
    }

    /// Changes how clients are treated.
    pub fn set_behaviour(&self, behaviour: Behaviour) {
        lock(&self.shared).config.behaviour = behaviour;
    }

    /// Closes every client connection (as a server that is killed would), keeps listening.
    pub fn disconnect_clients(&self) {
        lock(&self.shared).generation += 1;
    }

    /// Stops accepting and serving (also done on drop).
    pub fn shutdown(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.accept.take() {
            let _ = t.join();
        }
    }
}

impl Drop for CoachServer {
    fn drop(&mut self) {
        self.shutdown();
    }
}

fn accept_loop(listener: &TcpListener, shared: &Arc<Mutex<Shared>>, stop: &Arc<AtomicBool>) {
    // A new client waits at most `ACCEPT_POLL` to be served.
    tcp_server::accept_clients(
        listener,
        "coach-client",
        ACCEPT_POLL,
        shared,
        stop,
        |s| lock(s).status.clients += 1,
        serve_client,
    );
}

fn serve_client(mut stream: TcpStream, shared: &Mutex<Shared>, stop: &AtomicBool) {
    if !tcp_server::poll_reads(&stream, POLL) {
        return;
    }
    let generation = lock(shared).generation;
    let mut line: Vec<u8> = Vec::new();
    let mut overlong = false;
    let mut reply = Vec::new();
    let mut buf = [0u8; 4096];
    while !stop.load(Ordering::Relaxed) {
        let (behaviour, max_line, gen_now) = {
            let s = lock(shared);
            (s.config.behaviour, s.config.max_line_bytes, s.generation)
        };
        if gen_now != generation {
            let _ = stream.shutdown(std::net::Shutdown::Both);
            return;
        }
        if behaviour == Behaviour::Paused {
            std::thread::sleep(Duration::from_millis(5));
            continue;
        }
        let n = match tcp_server::read_polled(&mut stream, &mut buf) {
            Polled::Bytes(n) => n,
            Polled::Idle => continue,
            Polled::Closed => return,
        };
        let delivery = lock(shared).config.delivery;
        for &b in &buf[..n] {
            if b != b'\n' {
                if line.len() < max_line {
                    line.push(b);
                } else if !overlong {
                    overlong = true;
                }
                continue;
            }
            let mut s = lock(shared);
            s.status.lines += 1;
            if std::mem::take(&mut overlong) {
                s.status.overlong_lines += 1;
                s.status.last_error = Some(format!(
                    "line {}: longer than {max_line} bytes, dropped",
                    s.status.lines
                ));
            } else {
                // The behaviour as it is now, not as it was when the read began.
                let behaviour = s.config.behaviour;
                s.apply_line(&line, behaviour, &mut reply);
            }
            line.clear();
        }
        if !reply.is_empty() && send(&mut stream, &reply, delivery).is_err() {
            return;
        }
        reply.clear();
    }
}

fn send(stream: &mut TcpStream, bytes: &[u8], delivery: Delivery) -> io::Result<()> {
    match delivery.chunk_bytes {
        Some(k) if k > 0 => {
            for piece in bytes.chunks(k) {
                stream.write_all(piece)?;
                std::thread::sleep(delivery.chunk_pause);
            }
            Ok(())
        }
        _ => stream.write_all(bytes),
    }
}

/// A joint line: its code, model and values.
type JointLine = (u8, u32, Vec<f64>);

/// A joint line (`2`, `3`, `5`, `6`) with any number of values, or `None` for other lines.
fn joint_line(line: &[u8]) -> Option<Result<JointLine, String>> {
    let text = core::str::from_utf8(line).ok()?;
    let mut tokens = text.split_ascii_whitespace();
    let code = match tokens.next()? {
        "2" => 2,
        "3" => 3,
        "5" => 5,
        "6" => 6,
        _ => return None,
    };
    let Some(model) = tokens.next() else {
        return Some(Err("field 1 (model) is missing".into()));
    };
    let Ok(model) = model.parse::<u32>() else {
        return Some(Err("field 1 (model) is not a model index".into()));
    };
    let mut values = Vec::new();
    for (k, t) in tokens.enumerate() {
        match t.parse::<f64>() {
            Ok(v) => values.push(v),
            Err(_) => return Some(Err(format!("field {} is not a number", k + 2))),
        }
    }
    Some(Ok((code, model, values)))
}

impl Shared {
    fn apply_line(&mut self, line: &[u8], behaviour: Behaviour, reply: &mut Vec<u8>) {
        let parsed = match joint_line(line) {
            Some(Ok((code, model, values))) => Ok(self.apply_joints(code, model, values)),
            Some(Err(e)) => Err(e),
            None => Message::parse(line)
                .map(|m| self.apply(m))
                .map_err(|e| e.to_string()),
        };
        match parsed {
            Ok(Some(model)) => {
                self.status.requests += 1;
                self.answer(model, behaviour, reply);
            }
            Ok(None) => {}
            Err(e) => {
                self.status.bad_lines += 1;
                self.status.last_error = Some(format!("line {}: {e}", self.status.lines));
            }
        }
    }

    /// Applies a joint line; returns the model of a request to answer.
    fn apply_joints(&mut self, code: u8, model: u32, values: Vec<f64>) -> Option<u32> {
        let st = &mut self.status;
        match code {
            2 => match st.joints.get_mut(&model) {
                Some(q) if q.len() == values.len() => q.copy_from_slice(&values),
                Some(_) => st.ignored_lines += 1,
                None if self.config.learn_models => {
                    st.joints.insert(model, values);
                }
                None => st.ignored_lines += 1,
            },
            3 => {
                st.velocities.insert(model, values);
            }
            5 => {
                st.torques.insert(model, values);
            }
            // A `6 <i> q…` line from a client is a reply: nothing to do.
            _ if !values.is_empty() => {}
            _ => return Some(model),
        }
        None
    }

    /// Writes the answer to a `6 <model>` request (or garbage, or nothing).
    fn answer(&mut self, model: u32, behaviour: Behaviour, reply: &mut Vec<u8>) {
        match behaviour {
            // A pause only stops reading: a line read before it is answered.
            Behaviour::Paused | Behaviour::Normal => {}
            Behaviour::Silent => return,
            Behaviour::Garbage => {
                reply.extend_from_slice(b"\x01garbage reply\n");
                return;
            }
        }
        for i in 0..self.config.delivery.extra_lines {
            // Lines a client must skip: empty lines (as rlSimulator sends) and an echo.
            if i % 2 == 0 {
                reply.push(b'\n');
            } else {
                reply.extend_from_slice(format!("2 {} 0\n", model + 1000).as_bytes());
            }
        }
        let mut line = format!("6 {model}");
        if let Some(q) = self.status.joints.get(&model) {
            for v in q {
                line.push(' ');
                let mut g = heapless::String::<32>::new();
                let _ = crate::proto::coach::write_g6(&mut g, *v);
                line.push_str(&g);
            }
        }
        line.push('\n');
        reply.extend_from_slice(line.as_bytes());
    }

    /// Applies a pose line (joint lines go through `apply_joints`).
    fn apply(&mut self, m: Message) -> Option<u32> {
        let st = &mut self.status;
        match m {
            Message::BodyPose { model, body, pose } => {
                st.bodies.insert((model, body), pose);
            }
            Message::ShapePose {
                model,
                body,
                shape,
                pose,
            } => {
                st.shapes.insert((model, body, shape), pose);
            }
            // Joint lines are read with growable storage by `joint_line`.
            Message::JointPosition { .. }
            | Message::JointVelocity { .. }
            | Message::JointTorque { .. }
            | Message::Reply { .. } => {}
            Message::Request { model } => return Some(model),
            Message::Empty => {}
        }
        None
    }
}
