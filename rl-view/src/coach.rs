//! The Coach listener: the server side of RL's visualisation protocol (rlCoachMdl's), on
//! 127.0.0.1:11235 by default, so RL's controllers and ours (rl-drivers' Coach device, `rl run
//! --device coach://…`) show their motion in the page. Lines are read with rl-drivers' codec
//! ([`LineBuffer`], [`Message`]).
//!
//! As rlCoachMdl: `2 <i> q…` sets model i's joints (ignored unless the count matches),
//! `6 <i>` is answered with `6 <i> q…` (`6 <i>` alone for an unknown model), `0`/`1` set body
//! and shape poses, `3` velocities are shown, `5` torques are accepted and not used. Unlike
//! rlCoachMdl nothing is ignored silently: a line with a wrong count, an unknown model, a
//! value that is not finite, an unknown command or more than [`MAX_LINE`] bytes is counted
//! and reported (`coach.rejected`, `coach.last_error` in the state). Nothing here panics on
//! input.

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::Duration;

use rl_drivers::proto::coach::{LineBuffer, Message, write_g6};

use crate::Shared;
use crate::state::{Engine, Source};
use crate::ws::lock;

/// RL's Coach port.
pub const DEFAULT_PORT: u16 = 11235;

/// Longest line accepted, newline included; a longer one is dropped up to its newline and
/// counted.
pub const MAX_LINE: usize = 16 * 1024;

/// Most Coach clients served at once; more are refused (and counted).
pub const MAX_CLIENTS: usize = 32;

const POLL: Duration = Duration::from_millis(20);
const ACCEPT_POLL: Duration = Duration::from_millis(2);

/// Applies one line to `engine`; appends a reply to `reply` for requests. Returns the reason a
/// line is rejected.
pub fn apply_line(engine: &mut Engine, line: &[u8], reply: &mut Vec<u8>) -> Result<(), String> {
    let msg = Message::parse(line).map_err(|e| e.to_string())?;
    let finite = |v: &[f64]| match v.iter().position(|x| !x.is_finite()) {
        Some(k) => Err(format!("value {} is not a finite number", k + 1)),
        None => Ok(()),
    };
    match msg {
        Message::JointPosition { model, values } => {
            finite(&values)?;
            engine.set_q(model as usize, &values, Source::Coach)
        }
        Message::JointVelocity { model, values } => {
            finite(&values)?;
            engine.set_qd(model as usize, &values)
        }
        // Only rlSimulator uses torques; a viewer has nothing to do with them.
        Message::JointTorque { .. } => Ok(()),
        Message::BodyPose { model, body, pose } => {
            engine.set_body_pose(model as usize, body as usize, &pose)
        }
        Message::ShapePose {
            model,
            body,
            shape,
            pose,
        } => engine.set_shape_pose(model as usize, body as usize, shape as usize, &pose),
        Message::Request { model } => {
            // `6 <i> q…` as rl-drivers' codec writes numbers (%g, 6 significant digits), with
            // no bound on the number of values.
            let mut line = format!("6 {model}");
            for &v in engine.q(model as usize).unwrap_or(&[]) {
                line.push(' ');
                write_g6(&mut line, v).map_err(|e| e.to_string())?;
            }
            line.push('\n');
            reply.extend_from_slice(line.as_bytes());
            Ok(())
        }
        // A reply sent to us, or an empty line (rlSimulator's acknowledgement): nothing to do.
        Message::Reply { .. } | Message::Empty => Ok(()),
    }
}

/// Binds the listener.
pub(crate) fn bind(addr: SocketAddr) -> io::Result<TcpListener> {
    let l = TcpListener::bind(addr)?;
    l.set_nonblocking(true)?;
    Ok(l)
}

/// Accepts clients until the server stops.
pub(crate) fn accept_loop(listener: TcpListener, shared: Arc<Shared>) {
    let mut threads: Vec<std::thread::JoinHandle<()>> = Vec::new();
    while !shared.stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, peer)) => {
                threads.retain(|t| !t.is_finished());
                if threads.len() >= MAX_CLIENTS {
                    let mut e = lock(&shared.engine);
                    e.coach_line(Some(format!(
                        "client {peer} refused: {MAX_CLIENTS} clients already connected"
                    )));
                    continue;
                }
                let s = shared.clone();
                if let Ok(t) = std::thread::Builder::new()
                    .name("rl-view-coach".into())
                    .stack_size(crate::WORKER_STACK)
                    .spawn(move || serve(stream, &s))
                {
                    threads.push(t);
                }
            }
            Err(_) => std::thread::sleep(ACCEPT_POLL),
        }
    }
    for t in threads {
        let _ = t.join();
    }
}

fn serve(mut stream: TcpStream, shared: &Shared) {
    if stream.set_nonblocking(false).is_err() || stream.set_read_timeout(Some(POLL)).is_err() {
        return;
    }
    let _ = stream.set_write_timeout(Some(Duration::from_secs(2)));
    let _ = stream.set_nodelay(true);
    lock(&shared.engine).coach_clients(1);
    let mut lines = Box::new(LineBuffer::<MAX_LINE>::new());
    let mut reply = Vec::new();
    while !shared.stop.load(Ordering::Relaxed) {
        let n = match stream.read(lines.spare()) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) =>
            {
                continue;
            }
            Err(_) => break,
        };
        lines.commit(n);
        {
            let mut e = lock(&shared.engine);
            while let Some(line) = lines.next_line() {
                let rejected = match line {
                    Ok(l) => apply_line(&mut e, l, &mut reply).err().map(|why| {
                        let shown: String = String::from_utf8_lossy(&l[..l.len().min(60)]).into();
                        format!("\"{shown}\": {why}")
                    }),
                    Err(err) => Some(err.to_string()),
                };
                e.coach_line(rejected);
            }
        }
        if !reply.is_empty() {
            if stream.write_all(&reply).is_err() {
                break;
            }
            reply.clear();
        }
    }
    lock(&shared.engine).coach_clients(-1);
}
