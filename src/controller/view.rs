//! Showing a run in the robot viewer (`rl run --view`, feature `view`): a [`ViewHook`] in
//! [`RunOptions::view`](super::RunOptions::view) makes the real-time loop hand every cycle's
//! measured and commanded joint positions to an [`rl_view::Viewer`] in the same process,
//! through the viewer's [`Publisher`] (rl-rt's lock-free latest-value mailbox): no lock, no
//! allocation, no system call in the loop. The viewer's own threads (HTTP, WebSocket,
//! broadcast) are ordinary threads; they take the newest frame every broadcast period, and the
//! page shows the motion and the tracking error `q_cmd − q` (the same difference the run's
//! tracking statistics are made of).
//!
//! ```no_run
//! use std::time::Duration;
//! use rl::controller::{RunOptions, ViewHook, RV6SL_XML};
//! use rl_view::ModelSource;
//!
//! let source = ModelSource::Text { name: "RV-6SL".into(), text: RV6SL_XML.into() };
//! let view = ViewHook::start(source, "127.0.0.1:0".parse()?)?;
//! println!("open {}", view.viewer().url());
//! let options = RunOptions { view: Some(view.clone()), ..RunOptions::default() };
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::fmt;
use std::net::SocketAddr;
use std::sync::Arc;

use rl_view::{LoadOptions, ModelSource, Publisher, ViewError, Viewer, ViewerOptions};

use super::runtime::RunError;
use super::telemetry::CycleRecord;

/// A viewer a run shows its motion in, and which of its models is the robot. Clones share the
/// viewer; each run started with it gets its own [`ViewPublisher`].
#[derive(Clone)]
pub struct ViewHook {
    viewer: Arc<Viewer>,
    model: usize,
}

impl fmt::Debug for ViewHook {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ViewHook")
            .field("url", &self.viewer.url())
            .field("model", &self.model)
            .finish()
    }
}

impl ViewHook {
    /// Shows runs in `viewer`'s model `model` (its joints must be the run's, in order).
    pub fn new(viewer: Arc<Viewer>, model: usize) -> Self {
        Self { viewer, model }
    }

    /// Starts a viewer for one robot on `http` (port 0: any free port), without a Coach
    /// listener, on ordinary threads, and shows runs in it.
    pub fn start(robot: ModelSource, http: SocketAddr) -> Result<Self, ViewError> {
        let load = LoadOptions {
            models: vec![robot],
            ..LoadOptions::default()
        };
        Self::start_with(load, http)
    }

    /// [`ViewHook::start`] for what `load` names (the robot is its first model; obstacles,
    /// SRDF and path as `rl view` takes them).
    pub fn start_with(load: LoadOptions, http: SocketAddr) -> Result<Self, ViewError> {
        let options = ViewerOptions {
            load,
            http,
            coach: None,
        };
        Ok(Self::new(Arc::new(Viewer::start(&options)?), 0))
    }

    /// The viewer.
    pub fn viewer(&self) -> &Viewer {
        &self.viewer
    }

    /// A shared handle on the viewer (to keep it serving after the run).
    pub fn viewer_arc(&self) -> Arc<Viewer> {
        self.viewer.clone()
    }

    /// The handle a real-time loop of a model with `dof` joints publishes through; refused
    /// (before anything moves) when the viewer's model has other joints.
    pub fn attach(&self, dof: usize) -> Result<ViewPublisher, RunError> {
        let publisher = self.viewer.publisher();
        match publisher.joints(self.model) {
            Some(n) if n == dof => Ok(ViewPublisher {
                publisher,
                model: self.model,
                dof,
                published: 0,
                refused: 0,
            }),
            Some(n) => Err(RunError::Options(format!(
                "view: the viewer's model {} has {n} joints, the run's model {dof}",
                self.model
            ))),
            None => Err(RunError::Options(format!(
                "view: the viewer has no model {}",
                self.model
            ))),
        }
    }
}

/// The real-time side of a [`ViewHook`]: lives in the control thread.
#[derive(Debug)]
pub struct ViewPublisher {
    publisher: Publisher,
    model: usize,
    dof: usize,
    published: u64,
    refused: u64,
}

impl ViewPublisher {
    /// Hands one cycle's measured and commanded positions to the viewer. Wait-free,
    /// allocation-free; never blocks the loop. A cycle the run's tracking statistics do not
    /// count (its measurement held from an earlier reply after a lost one, or a cycle after
    /// the first fault) shows the arm without a command: `q_cmd − q` of a stale measurement is
    /// not a tracking error, and the page would show one the report does not have.
    #[inline]
    pub fn show<const J: usize>(&mut self, record: &CycleRecord<J>) {
        let dof = self.dof.min(J);
        let measured = &record.measured[..dof];
        let shown = if record.counted {
            self.publisher
                .publish_commanded(self.model, measured, &record.commanded[..dof])
        } else {
            self.publisher.publish(self.model, measured)
        };
        match shown {
            Ok(()) => self.published += 1,
            Err(_) => self.refused += 1,
        }
    }

    /// Frames handed to the viewer.
    pub fn published(&self) -> u64 {
        self.published
    }

    /// Frames the viewer's publisher refused (none once [`ViewHook::attach`] has checked the
    /// model; counted rather than dropped silently).
    pub fn refused(&self) -> u64 {
        self.refused
    }

    /// Frames the viewer replaced by newer ones before taking them (a display needs only the
    /// newest).
    pub fn overwritten(&self) -> u64 {
        self.publisher.overwritten(self.model).unwrap_or(0)
    }
}
