//! The TCP plumbing the fakes share: an accept loop that serves each client on its own thread
//! until a stop flag is set, and client reads that time out, so a serving thread sees that flag.

use std::io::{self, Read};
use std::net::{TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Accepts clients on the non-blocking `listener` until `stop` is set, sleeping `idle` while
/// none is waiting; runs `accepted` for each new client (to count it) and serves it with `serve`
/// on a thread named `name`. Returns once every client thread has ended.
pub(crate) fn accept_clients<S: Send + Sync + 'static>(
    listener: &TcpListener,
    name: &str,
    idle: Duration,
    shared: &Arc<S>,
    stop: &Arc<AtomicBool>,
    accepted: impl Fn(&S),
    serve: fn(TcpStream, &S, &AtomicBool),
) {
    let mut clients = Vec::new();
    while !stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, _)) => {
                accepted(shared);
                let (s, st) = (shared.clone(), stop.clone());
                if let Ok(t) = std::thread::Builder::new()
                    .name(name.into())
                    .spawn(move || serve(stream, &s, &st))
                {
                    clients.push(t);
                }
            }
            Err(_) => std::thread::sleep(idle),
        }
    }
    for t in clients {
        let _ = t.join();
    }
}

/// Makes an accepted `stream` blocking, with reads that give up after `poll` (so the serving
/// thread can look at its stop flag) and no Nagle delay; `false` if the socket refused.
pub(crate) fn poll_reads(stream: &TcpStream, poll: Duration) -> bool {
    if stream.set_nonblocking(false).is_err() || stream.set_read_timeout(Some(poll)).is_err() {
        return false;
    }
    let _ = stream.set_nodelay(true);
    true
}

/// What one read of a client prepared by [`poll_reads`] brought.
pub(crate) enum Polled {
    /// This many bytes, at the start of the buffer.
    Bytes(usize),
    /// Nothing before the read timed out.
    Idle,
    /// The client closed the connection, or it failed.
    Closed,
}

/// Reads what the client sent into `buf`. A read interrupted by a signal (EINTR: a socket
/// read with a timeout is never restarted by the kernel) is no reason to drop the client: it
/// counts as an idle poll, and the next read goes on.
pub(crate) fn read_polled(stream: &mut TcpStream, buf: &mut [u8]) -> Polled {
    match stream.read(buf) {
        Ok(0) => Polled::Closed,
        Ok(n) => Polled::Bytes(n),
        Err(e)
            if matches!(
                e.kind(),
                io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut | io::ErrorKind::Interrupted
            ) =>
        {
            Polled::Idle
        }
        Err(_) => Polled::Closed,
    }
}
