//! Who gets a connection: the server's defence against connections that hold it without using
//! it. Before, 64 connections of any kind shared one pool: 70 clients that open a connection,
//! send a byte every few seconds and reconnect when dropped ("slowloris") turned 5 of 6 probes
//! away with 503, and a WebSocket client holding its slot without traffic kept it forever.
//!
//! Three pools, each bounded, with a different rule when full:
//! - **Heads arriving** ([`MAX_PENDING`], [`MAX_PENDING_PER_PEER`]): every new connection is
//!   admitted; when the pool (or the peer's share of it) is full the *oldest* connection whose
//!   head is still arriving is closed to make room. A client that sends its request at once is
//!   answered within milliseconds and never the oldest; one that dribbles its head is. A head
//!   must also be complete within [`HEAD_TIMEOUT`].
//! - **Requests being answered** ([`MAX_REQUESTS`]): short (every response closes its
//!   connection, writes time out); when full, `503`.
//! - **Pages** (WebSockets, [`MAX_PAGES`], [`MAX_PAGES_PER_PEER`]): when full, `503`; a page that
//!   sends nothing for [`crate::ws::IDLE_LIMIT`] (the page pings every 5 s, and the server
//!   pings it too) is closed.
//!
//! The threads that read heads have small stacks (they hold nothing but the head): a flood of
//! connections costs little memory even when the process locks its memory (`rl run --view`).

use std::collections::VecDeque;
use std::net::{IpAddr, Shutdown, TcpStream};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::ws::lock;

/// Most connections whose request head is still arriving.
pub const MAX_PENDING: usize = 128;
/// Most such connections of one peer (IP address).
pub const MAX_PENDING_PER_PEER: usize = 64;
/// Most requests being answered at once (pages' files, the API).
pub const MAX_REQUESTS: usize = 32;
/// Most pages (WebSocket connections).
pub const MAX_PAGES: usize = 32;
/// Most pages of one peer.
pub const MAX_PAGES_PER_PEER: usize = 16;
/// How long a request head may take to arrive.
pub const HEAD_TIMEOUT: Duration = Duration::from_secs(5);

/// A connection whose head is arriving: who, and a handle to close it from outside.
#[derive(Debug)]
struct Pending {
    id: u64,
    peer: IpAddr,
    stream: TcpStream,
}

/// The three pools.
#[derive(Debug, Default)]
pub(crate) struct Admission {
    pending: Mutex<VecDeque<Pending>>,
    next_id: AtomicU64,
    requests: Arc<Mutex<Vec<IpAddr>>>,
    pages: Arc<Mutex<Vec<IpAddr>>>,
    /// Connections closed to make room for newer ones.
    evicted: AtomicU64,
    /// Requests and pages refused with 503.
    refused: AtomicU64,
}

/// A slot in the request or page pool, given back when dropped.
#[derive(Debug)]
pub(crate) struct Slot {
    pool: Arc<Mutex<Vec<IpAddr>>>,
    peer: IpAddr,
}

impl Drop for Slot {
    fn drop(&mut self) {
        let mut v = lock(&self.pool);
        if let Some(i) = v.iter().position(|p| *p == self.peer) {
            v.swap_remove(i);
        }
    }
}

/// Which pool a complete request goes to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Pool {
    /// A request answered and closed.
    Request,
    /// A WebSocket page.
    Page,
}

impl Admission {
    /// Admits a new connection from `peer` to the pending pool, closing the oldest pending
    /// connection (of the peer, if it has its share; else of anyone) when full. Returns its id
    /// (for [`Admission::done`]).
    pub(crate) fn admit(&self, peer: IpAddr, stream: &TcpStream) -> Option<u64> {
        let handle = stream.try_clone().ok()?;
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        let mut q = lock(&self.pending);
        let evict = |q: &mut VecDeque<Pending>, i: usize| {
            if let Some(old) = q.remove(i) {
                let _ = old.stream.shutdown(Shutdown::Both);
                self.evicted.fetch_add(1, Ordering::Relaxed);
            }
        };
        if q.iter().filter(|p| p.peer == peer).count() >= MAX_PENDING_PER_PEER {
            if let Some(i) = q.iter().position(|p| p.peer == peer) {
                evict(&mut q, i);
            }
        }
        while q.len() >= MAX_PENDING {
            evict(&mut q, 0);
        }
        q.push_back(Pending {
            id,
            peer,
            stream: handle,
        });
        Some(id)
    }

    /// The head of connection `id` has arrived (or it failed): it leaves the pending pool.
    pub(crate) fn done(&self, id: u64) {
        let mut q = lock(&self.pending);
        if let Some(i) = q.iter().position(|p| p.id == id) {
            q.remove(i);
        }
    }

    /// A slot in `pool` for `peer`, or `None` (answer 503) when the pool or the peer's share of
    /// it is full.
    pub(crate) fn slot(&self, pool: Pool, peer: IpAddr) -> Option<Slot> {
        let (m, max, per_peer) = match pool {
            Pool::Request => (&self.requests, MAX_REQUESTS, MAX_REQUESTS),
            Pool::Page => (&self.pages, MAX_PAGES, MAX_PAGES_PER_PEER),
        };
        let mut v = lock(m);
        if v.len() >= max || v.iter().filter(|p| **p == peer).count() >= per_peer {
            self.refused.fetch_add(1, Ordering::Relaxed);
            return None;
        }
        v.push(peer);
        Some(Slot {
            pool: m.clone(),
            peer,
        })
    }

    /// Connections whose head is arriving, requests being answered, pages.
    pub(crate) fn counts(&self) -> (usize, usize, usize) {
        (
            lock(&self.pending).len(),
            lock(&self.requests).len(),
            lock(&self.pages).len(),
        )
    }

    /// Connections closed to make room, and requests or pages refused with 503, so far.
    pub(crate) fn turned_away(&self) -> (u64, u64) {
        (
            self.evicted.load(Ordering::Relaxed),
            self.refused.load(Ordering::Relaxed),
        )
    }
}
