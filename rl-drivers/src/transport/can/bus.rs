//! An in-process CAN bus for unit tests: every frame one endpoint flushes reaches every other
//! endpoint, in order, as on a wire. Endpoints share a mutex: fine for tests and the fakes,
//! not for a real-time loop (use cannelloni on loopback for that).

use std::collections::VecDeque;
use std::io;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Instant;

use super::{CanTransport, Received, TransportCounters};
use crate::proto::can::Frame;

/// Frames one endpoint can hold unread before it drops (and counts) more.
pub const QUEUE_CAPACITY: usize = 4096;

#[derive(Debug)]
struct Slot {
    queue: VecDeque<Frame>,
    open: bool,
    overruns: u64,
}

#[derive(Debug, Default)]
struct Inner {
    slots: Mutex<Vec<Slot>>,
    ready: Condvar,
}

/// A bus; endpoints are made with [`Bus::endpoint`].
#[derive(Clone, Debug, Default)]
pub struct Bus {
    inner: Arc<Inner>,
}

fn lock(m: &Mutex<Vec<Slot>>) -> MutexGuard<'_, Vec<Slot>> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

impl Bus {
    /// An empty bus.
    pub fn new() -> Self {
        Self::default()
    }

    /// A new node on the bus.
    pub fn endpoint(&self) -> Endpoint {
        let mut slots = lock(&self.inner.slots);
        slots.push(Slot {
            queue: VecDeque::with_capacity(QUEUE_CAPACITY),
            open: true,
            overruns: 0,
        });
        Endpoint {
            inner: self.inner.clone(),
            index: slots.len() - 1,
            pending: Vec::with_capacity(256),
            counters: TransportCounters::default(),
        }
    }
}

/// One node's connection to a [`Bus`].
#[derive(Debug)]
pub struct Endpoint {
    inner: Arc<Inner>,
    index: usize,
    pending: Vec<Frame>,
    counters: TransportCounters,
}

impl Drop for Endpoint {
    fn drop(&mut self) {
        if let Some(slot) = lock(&self.inner.slots).get_mut(self.index) {
            slot.open = false;
            slot.queue.clear();
        }
    }
}

impl CanTransport for Endpoint {
    fn send(&mut self, frame: &Frame) -> io::Result<()> {
        if self.pending.len() == self.pending.capacity() {
            return Err(io::Error::new(io::ErrorKind::WouldBlock, "send queue full"));
        }
        self.pending.push(*frame);
        Ok(())
    }

    fn flush(&mut self, _deadline: Instant) -> io::Result<()> {
        if self.pending.is_empty() {
            return Ok(());
        }
        let mut slots = lock(&self.inner.slots);
        for (i, slot) in slots.iter_mut().enumerate() {
            if i == self.index || !slot.open {
                continue;
            }
            for f in &self.pending {
                if slot.queue.len() < QUEUE_CAPACITY {
                    slot.queue.push_back(*f);
                } else {
                    slot.overruns += 1;
                }
            }
        }
        self.counters.frames_sent += self.pending.len() as u64;
        self.pending.clear();
        drop(slots);
        self.inner.ready.notify_all();
        Ok(())
    }

    fn recv(&mut self, deadline: Instant) -> io::Result<Option<Received>> {
        let mut slots = lock(&self.inner.slots);
        loop {
            if let Some(frame) = slots[self.index].queue.pop_front() {
                self.counters.frames_received += 1;
                return Ok(Some(Received {
                    frame,
                    timestamp: None,
                }));
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(None);
            }
            slots = self
                .inner
                .ready
                .wait_timeout(slots, deadline - now)
                .unwrap_or_else(|p| p.into_inner())
                .0;
        }
    }

    fn counters(&self) -> TransportCounters {
        let mut c = self.counters;
        c.overruns = lock(&self.inner.slots)[self.index].overruns;
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn frames_reach_every_other_endpoint_in_order() {
        let bus = Bus::new();
        let (mut a, mut b, mut c) = (bus.endpoint(), bus.endpoint(), bus.endpoint());
        for k in 0..3u16 {
            a.send(&Frame::standard(0x100 + k, &[k as u8]).unwrap())
                .unwrap();
        }
        a.flush(Instant::now()).unwrap();
        let soon = Instant::now() + Duration::from_millis(100);
        for ep in [&mut b, &mut c] {
            for k in 0..3u16 {
                assert_eq!(
                    ep.recv(soon).unwrap().unwrap().frame.standard_id(),
                    Some(0x100 + k)
                );
            }
        }
        let t = Instant::now();
        assert_eq!(
            a.recv(t + Duration::from_millis(10)).unwrap(),
            None,
            "no echo"
        );
        assert!(t.elapsed() >= Duration::from_millis(10));
        assert_eq!(a.counters().frames_sent, 3);
    }
}
