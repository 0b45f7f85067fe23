//! The real-time hook: a real-time loop hands joint positions to the viewer through rl-rt's
//! lock-free latest-value mailbox ([`rl_rt::exchange::mailbox`]). [`Publisher::publish`] copies
//! `q` into a preallocated frame and commits it: no lock, no allocation, no system call;
//! [`Publisher::publish_commanded`] hands the commanded position along with the measured one,
//! so the page can show the tracking error (`q_cmd` in the state). The
//! viewer's broadcast thread takes the newest frame of each model every period (older ones are
//! overwritten, as a display only needs the newest; the mailbox counts them).

use rl_rt::exchange::{MailboxReader, MailboxWriter, mailbox};

use crate::load::CAPACITY;

/// One model's joint positions (and, from a controller, the commanded ones), fixed size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Values used in `q` (and in `q_cmd` when `commanded`).
    pub len: usize,
    /// Joint positions (the first `len`): measured, for a controller.
    pub q: [f64; CAPACITY],
    /// Whether `q_cmd` holds the commanded positions.
    pub commanded: bool,
    /// Commanded joint positions (the first `len`, when `commanded`).
    pub q_cmd: [f64; CAPACITY],
}

impl Default for Frame {
    fn default() -> Self {
        Frame {
            len: 0,
            q: [0.0; CAPACITY],
            commanded: false,
            q_cmd: [0.0; CAPACITY],
        }
    }
}

/// Why a frame was not published.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PublishError {
    /// No such model.
    UnknownModel {
        /// The index given.
        model: usize,
    },
    /// `q` has the wrong length.
    Dimension {
        /// The model's joints.
        expected: usize,
        /// Values given.
        got: usize,
    },
}

impl core::fmt::Display for PublishError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PublishError::UnknownModel { model } => write!(f, "unknown model {model}"),
            PublishError::Dimension { expected, got } => {
                write!(f, "{got} joint values given, the model has {expected}")
            }
        }
    }
}

impl std::error::Error for PublishError {}

/// The real-time side: one mailbox writer per model. Move it into the real-time thread.
#[derive(Debug)]
pub struct Publisher {
    writers: Vec<(usize, MailboxWriter<Frame>)>,
}

/// The viewer's side of a [`Publisher`].
#[derive(Debug)]
pub(crate) struct LiveReader {
    pub(crate) readers: Vec<MailboxReader<Frame>>,
}

/// A publisher for models with `nq[i]` joints, and its reader.
pub(crate) fn channel(nq: &[usize]) -> (Publisher, LiveReader) {
    let mut writers = Vec::with_capacity(nq.len());
    let mut readers = Vec::with_capacity(nq.len());
    for &n in nq {
        let (w, r) = mailbox(Frame::default());
        writers.push((n, w));
        readers.push(r);
    }
    (Publisher { writers }, LiveReader { readers })
}

impl Publisher {
    /// Hands model `model`'s joint positions to the viewer (no commanded positions: the
    /// state's `q_cmd` is null). Wait-free, allocation-free.
    pub fn publish(&mut self, model: usize, q: &[f64]) -> Result<(), PublishError> {
        self.write(model, q, None)
    }

    /// Hands model `model`'s measured joint positions `q` and the commanded ones `q_cmd` (the
    /// position the controller asked for at the same time) to the viewer, which shows `q` and
    /// the tracking error `q_cmd − q`. Wait-free, allocation-free.
    pub fn publish_commanded(
        &mut self,
        model: usize,
        q: &[f64],
        q_cmd: &[f64],
    ) -> Result<(), PublishError> {
        self.write(model, q, Some(q_cmd))
    }

    fn write(
        &mut self,
        model: usize,
        q: &[f64],
        q_cmd: Option<&[f64]>,
    ) -> Result<(), PublishError> {
        let (n, w) = self
            .writers
            .get_mut(model)
            .ok_or(PublishError::UnknownModel { model })?;
        for got in [Some(q.len()), q_cmd.map(<[f64]>::len)]
            .into_iter()
            .flatten()
        {
            if got != *n {
                return Err(PublishError::Dimension { expected: *n, got });
            }
        }
        let f = w.buffer_mut();
        f.len = q.len();
        f.q[..q.len()].copy_from_slice(q);
        f.commanded = q_cmd.is_some();
        if let Some(c) = q_cmd {
            f.q_cmd[..c.len()].copy_from_slice(c);
        }
        w.commit();
        Ok(())
    }

    /// Joints of model `model` (the length `publish` expects), if there is such a model.
    pub fn joints(&self, model: usize) -> Option<usize> {
        self.writers.get(model).map(|(n, _)| *n)
    }

    /// Frames overwritten before the viewer took them, per model.
    pub fn overwritten(&self, model: usize) -> Option<u64> {
        self.writers.get(model).map(|(_, w)| w.overwritten())
    }
}
