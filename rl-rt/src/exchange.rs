//! Passing data to and from a real-time thread without ever blocking it.
//!
//! - [`queue`]: a wait-free single-producer/single-consumer FIFO (over `rtrb`) for commands in
//!   and telemetry out. A push into a full queue hands the value back and is counted as a drop.
//! - [`mailbox`]: a latest-value triple buffer (over `triple_buffer`) for setpoints and state:
//!   the reader always gets the newest complete value; values overwritten before anyone read
//!   them are counted.
//!
//! Both allocate once when made; sending, receiving, publishing and reading allocate nothing
//! and take no lock.

use core::fmt;
use core::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// A value that did not fit because the queue was full; it is handed back, and counted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Full<T>(pub T);

impl<T> fmt::Display for Full<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("queue full: value dropped (counted)")
    }
}

impl<T: fmt::Debug> std::error::Error for Full<T> {}

/// Makes a queue holding up to `capacity` values: the sending and the receiving end.
pub fn queue<T>(capacity: usize) -> (QueueSender<T>, QueueReceiver<T>) {
    let (tx, rx) = rtrb::RingBuffer::new(capacity);
    let dropped = Arc::new(AtomicU64::new(0));
    (
        QueueSender {
            inner: tx,
            dropped: Arc::clone(&dropped),
            sent: 0,
        },
        QueueReceiver { inner: rx, dropped },
    )
}

/// The sending end of a [`queue`]. Owned by one thread at a time.
#[derive(Debug)]
pub struct QueueSender<T> {
    inner: rtrb::Producer<T>,
    dropped: Arc<AtomicU64>,
    sent: u64,
}

impl<T> QueueSender<T> {
    /// Appends `value`, or hands it back in [`Full`] and counts a drop. Wait-free.
    #[inline]
    pub fn try_send(&mut self, value: T) -> Result<(), Full<T>> {
        match self.inner.push(value) {
            Ok(()) => {
                self.sent += 1;
                Ok(())
            }
            Err(rtrb::PushError::Full(value)) => {
                self.dropped.fetch_add(1, Ordering::Relaxed);
                Err(Full(value))
            }
        }
    }

    /// Values accepted so far.
    pub fn sent(&self) -> u64 {
        self.sent
    }

    /// Values refused because the queue was full.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    /// Free slots now.
    pub fn free(&self) -> usize {
        self.inner.slots()
    }
}

/// The receiving end of a [`queue`]. Owned by one thread at a time.
#[derive(Debug)]
pub struct QueueReceiver<T> {
    inner: rtrb::Consumer<T>,
    dropped: Arc<AtomicU64>,
}

impl<T> QueueReceiver<T> {
    /// The oldest value, if any. Wait-free.
    #[inline]
    pub fn try_recv(&mut self) -> Option<T> {
        self.inner.pop().ok()
    }

    /// Values waiting.
    pub fn len(&self) -> usize {
        self.inner.slots()
    }

    /// Whether no value is waiting.
    pub fn is_empty(&self) -> bool {
        self.inner.is_empty()
    }

    /// Values the sender could not enqueue because the queue was full.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    /// Whether the sender is gone (no more values will come after those waiting).
    pub fn is_abandoned(&self) -> bool {
        self.inner.is_abandoned()
    }
}

/// Makes a latest-value mailbox holding `initial`: the writing and the reading end.
pub fn mailbox<T: Clone + Send>(initial: T) -> (MailboxWriter<T>, MailboxReader<T>) {
    let (input, output) = triple_buffer::triple_buffer(&initial);
    let overwritten = Arc::new(AtomicU64::new(0));
    (
        MailboxWriter {
            input,
            overwritten: Arc::clone(&overwritten),
            published: 0,
        },
        MailboxReader {
            output,
            overwritten,
        },
    )
}

/// The writing end of a [`mailbox`].
pub struct MailboxWriter<T: Send> {
    input: triple_buffer::Input<T>,
    overwritten: Arc<AtomicU64>,
    published: u64,
}

impl<T: Send> MailboxWriter<T> {
    /// Publishes `value` as the newest. If the previous one was never read it is replaced and
    /// counted in [`overwritten`](Self::overwritten); returns whether that happened. Wait-free.
    #[inline]
    pub fn publish(&mut self, value: T) -> bool {
        *self.input.input_buffer_mut() = value;
        self.commit()
    }

    /// Lets the value be built in place (no copy of a large `T`); call
    /// [`commit`](Self::commit) after. The buffer holds an older value, not the last one sent.
    pub fn buffer_mut(&mut self) -> &mut T {
        self.input.input_buffer_mut()
    }

    /// Publishes what was written through [`buffer_mut`](Self::buffer_mut); same counting as
    /// [`publish`](Self::publish).
    #[inline]
    pub fn commit(&mut self) -> bool {
        self.published += 1;
        let lost = self.input.publish();
        if lost {
            self.overwritten.fetch_add(1, Ordering::Relaxed);
        }
        lost
    }

    /// Values published so far.
    pub fn published(&self) -> u64 {
        self.published
    }

    /// Values replaced before the reader saw them.
    pub fn overwritten(&self) -> u64 {
        self.overwritten.load(Ordering::Relaxed)
    }
}

impl<T: Send> fmt::Debug for MailboxWriter<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MailboxWriter")
            .field("published", &self.published)
            .field("overwritten", &self.overwritten())
            .finish()
    }
}

/// The reading end of a [`mailbox`].
pub struct MailboxReader<T: Send> {
    output: triple_buffer::Output<T>,
    overwritten: Arc<AtomicU64>,
}

impl<T: Send> MailboxReader<T> {
    /// The newest published value (or the initial one). Wait-free.
    #[inline]
    pub fn read(&mut self) -> &T {
        self.output.read()
    }

    /// Whether a value newer than the last [`read`](Self::read) is waiting.
    pub fn has_update(&self) -> bool {
        self.output.updated()
    }

    /// Values the writer replaced before they were read.
    pub fn overwritten(&self) -> u64 {
        self.overwritten.load(Ordering::Relaxed)
    }
}

impl<T: Send> fmt::Debug for MailboxReader<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MailboxReader")
            .field("overwritten", &self.overwritten())
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_queue_hands_back_and_counts() {
        let (mut tx, mut rx) = queue::<u32>(2);
        assert_eq!(tx.try_send(1), Ok(()));
        assert_eq!(tx.try_send(2), Ok(()));
        assert_eq!(tx.try_send(3), Err(Full(3)));
        assert_eq!((tx.sent(), tx.dropped(), rx.dropped()), (2, 1, 1));
        assert_eq!(rx.len(), 2);
        assert_eq!(rx.try_recv(), Some(1));
        assert_eq!(rx.try_recv(), Some(2));
        assert_eq!(rx.try_recv(), None);
        drop(tx);
        assert!(rx.is_abandoned());
    }

    #[test]
    fn mailbox_keeps_the_latest_and_counts_overwrites() {
        let (mut w, mut r) = mailbox([0.0f64; 3]);
        assert_eq!(*r.read(), [0.0; 3]);
        assert!(!w.publish([1.0; 3]));
        assert!(w.publish([2.0; 3]), "1.0 was never read");
        assert!(r.has_update());
        assert_eq!(*r.read(), [2.0; 3]);
        assert!(!r.has_update());
        *w.buffer_mut() = [3.0; 3];
        assert!(!w.commit());
        assert_eq!(*r.read(), [3.0; 3]);
        assert_eq!((w.published(), w.overwritten(), r.overwritten()), (3, 1, 1));
    }

    #[test]
    fn queue_across_threads_loses_nothing_it_does_not_count() {
        let (mut tx, mut rx) = queue::<u64>(16);
        let producer = std::thread::spawn(move || {
            for i in 0..10_000u64 {
                let _ = tx.try_send(i);
            }
            (tx.sent(), tx.dropped())
        });
        let mut received = Vec::new();
        let mut last = None;
        loop {
            match rx.try_recv() {
                Some(v) => {
                    assert!(last.is_none_or(|l| v > l), "FIFO order kept");
                    last = Some(v);
                    received.push(v);
                }
                None if rx.is_abandoned() && rx.is_empty() => break,
                None => std::thread::yield_now(),
            }
        }
        let (sent, dropped) = producer.join().expect("producer");
        assert_eq!(received.len() as u64, sent);
        assert_eq!(sent + dropped, 10_000);
    }
}
