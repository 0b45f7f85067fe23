//! A Coach server: the server side of RL's visualisation protocol. It keeps per-model joint
//! states and body/shape poses, answers `6 <i>` with the model's joint positions (`6 <i>` alone
//! for an unknown model, as rlCoachMdl does), and ignores a `2 <i>` line whose length differs
//! from the model's joints. Usable as the fake for tests (with options that split replies into
//! partial lines or batch several lines into one write) and as the endpoint a visualiser builds
//! on (read the state with [`CoachServer::status`]).

use std::collections::HashMap;
use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use crate::proto::coach::{LineBuffer, Message, Values};

const POLL: Duration = Duration::from_millis(20);

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

/// Server configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct CoachServerConfig {
    /// Listen address (RL's visualisers use port 11235).
    pub bind: SocketAddr,
    /// Models known from the start: index and number of joints (joints start at 0).
    pub models: Vec<(u32, usize)>,
    /// Learn a model from its first `2 <i> q…` line if it is not known.
    pub learn_models: bool,
    /// How replies are written.
    pub delivery: Delivery,
}

impl CoachServerConfig {
    /// 127.0.0.1 with a free port, no models known, models learnt from joint lines.
    pub fn loopback() -> Self {
        Self {
            bind: SocketAddr::from(([127, 0, 0, 1], 0)),
            models: Vec::new(),
            learn_models: true,
            delivery: Delivery::default(),
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
        for &(model, dof) in &config.models {
            status.joints.insert(model, vec![0.0; dof]);
        }
        let shared = Arc::new(Mutex::new(Shared { config, status }));
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
    let mut clients = Vec::new();
    while !stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, _)) => {
                lock(shared).status.clients += 1;
                let (s, st) = (shared.clone(), stop.clone());
                if let Ok(t) = std::thread::Builder::new()
                    .name("coach-client".into())
                    .spawn(move || serve_client(stream, &s, &st))
                {
                    clients.push(t);
                }
            }
            Err(_) => std::thread::sleep(POLL),
        }
    }
    for t in clients {
        let _ = t.join();
    }
}

fn serve_client(mut stream: TcpStream, shared: &Mutex<Shared>, stop: &AtomicBool) {
    if stream.set_nonblocking(false).is_err() || stream.set_read_timeout(Some(POLL)).is_err() {
        return;
    }
    let _ = stream.set_nodelay(true);
    let mut lines = LineBuffer::<65536>::new();
    let mut reply = Vec::new();
    while !stop.load(Ordering::Relaxed) {
        match stream.read(lines.spare()) {
            Ok(0) => return,
            Ok(n) => lines.commit(n),
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) =>
            {
                continue;
            }
            Err(_) => return,
        }
        let delivery = lock(shared).config.delivery;
        while let Some(line) = lines.next_line() {
            let mut s = lock(shared);
            s.status.lines += 1;
            match line.and_then(Message::parse) {
                Ok(m) => s.apply(m, &mut reply),
                Err(_) => s.status.bad_lines += 1,
            }
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

impl Shared {
    fn apply(&mut self, m: Message, reply: &mut Vec<u8>) {
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
            Message::JointPosition { model, values } => match st.joints.get_mut(&model) {
                Some(q) if q.len() == values.len() => q.copy_from_slice(&values),
                Some(_) => st.ignored_lines += 1,
                None if self.config.learn_models => {
                    st.joints.insert(model, values.to_vec());
                }
                None => st.ignored_lines += 1,
            },
            Message::JointVelocity { model, values } => {
                st.velocities.insert(model, values.to_vec());
            }
            Message::JointTorque { model, values } => {
                st.torques.insert(model, values.to_vec());
            }
            Message::Request { model } => {
                st.requests += 1;
                for i in 0..self.config.delivery.extra_lines {
                    // Lines a client must skip: empty lines (as rlSimulator sends) and an echo.
                    if i % 2 == 0 {
                        reply.push(b'\n');
                    } else {
                        reply.extend_from_slice(format!("2 {} 0\n", model + 1000).as_bytes());
                    }
                }
                let answer = match st.joints.get(&model) {
                    Some(q) => match Values::from_slice(q) {
                        Ok(values) => Message::Reply { model, values },
                        Err(_) => Message::Request { model },
                    },
                    None => Message::Request { model },
                };
                let mut buf = [0u8; 1024];
                if let Ok(n) = answer.encode(&mut buf) {
                    reply.extend_from_slice(&buf[..n]);
                }
            }
            Message::Reply { .. } | Message::Empty => {}
        }
    }
}
