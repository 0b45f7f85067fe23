//! `rl view`: RL's rlCoachMdl visualiser as a local web page. The server side: it loads robots
//! (rl-core's URDF and RL XML loaders) and their geometry and obstacles (rl-sg), serves the
//! page embedded from `web/dist/`, the model files, the scene as JSON, a WebSocket that streams
//! the state (joint positions, body poses, collisions, distance, IK results) and takes the
//! page's commands, and a Coach listener (TCP 11235) speaking RL's protocol so controllers show
//! their motion live. The contract with the page: `brief/VIEW_PROTOCOL.md` (summarised in
//! [`ws`] and [`scene_json`]).
//!
//! Every listener binds 127.0.0.1 by default and runs on ordinary std threads; a real-time loop
//! hands joint positions through [`Viewer::publisher`] (rl-rt's lock-free mailbox), never
//! through a lock.
//!
//! ```no_run
//! use rl_view::{LoadOptions, ModelSource, Viewer, ViewerOptions};
//! let options = ViewerOptions {
//!     load: LoadOptions {
//!         models: vec![ModelSource::File("ur5.urdf".into())],
//!         ..LoadOptions::default()
//!     },
//!     ..ViewerOptions::default()
//! };
//! let viewer = Viewer::start(&options).unwrap();
//! println!("open {}", viewer.url());
//! ```

pub mod admission;
pub mod coach;
pub mod error;
pub mod files;
pub mod http;
pub mod load;
pub mod origin;
pub mod path;
pub mod publish;
pub mod scene_json;
pub mod state;
pub mod ws;

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

pub use error::ViewError;
pub use load::{LoadOptions, ModelSource, World};
pub use publish::{PublishError, Publisher};
pub use state::{Engine, IkReport, Source};

use admission::Admission;
use files::FileTable;
use origin::HostPolicy;
use publish::LiveReader;
use ws::{Hub, lock};

/// Default HTTP address.
pub const DEFAULT_HTTP: SocketAddr = SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), 8080);
/// Default Coach address (RL's port).
pub const DEFAULT_COACH: SocketAddr =
    SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), coach::DEFAULT_PORT);

/// What the viewer shows and where it listens.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewerOptions {
    /// Models, obstacles, SRDF, path.
    pub load: LoadOptions,
    /// HTTP and WebSocket address (port 0: any free port).
    pub http: SocketAddr,
    /// Coach address, or `None` for no Coach listener.
    pub coach: Option<SocketAddr>,
}

impl Default for ViewerOptions {
    fn default() -> Self {
        Self {
            load: LoadOptions::default(),
            http: DEFAULT_HTTP,
            coach: Some(DEFAULT_COACH),
        }
    }
}

/// What the server's threads share.
pub(crate) struct Shared {
    pub(crate) engine: Mutex<Engine>,
    pub(crate) files: FileTable,
    pub(crate) hub: Hub,
    pub(crate) stop: AtomicBool,
    /// Who gets a connection.
    pub(crate) admission: Admission,
    /// Which `Host` and `Origin` are answered.
    pub(crate) policy: Mutex<HostPolicy>,
    /// How long a page may stay silent, in milliseconds ([`ws::IDLE_LIMIT`] by default).
    pub(crate) page_idle_ms: AtomicU64,
    live: Mutex<Vec<LiveReader>>,
}

impl Shared {
    /// Applies the newest frame of every real-time publisher.
    pub(crate) fn take_live(&self) {
        let mut live = lock(&self.live);
        if live.is_empty() {
            return;
        }
        let mut e = lock(&self.engine);
        for l in live.iter_mut() {
            for (model, r) in l.readers.iter_mut().enumerate() {
                if r.has_update() {
                    let f = r.read();
                    // Lengths are checked by `publish`; a non-finite value is refused here.
                    let q_cmd = f.commanded.then(|| &f.q_cmd[..f.len]);
                    let _ = e.set_q_commanded(model, &f.q[..f.len], q_cmd, Source::Live);
                }
            }
        }
    }
}

/// Whether an address is a loopback one (anything else exposes the page, which has no
/// authentication).
pub fn is_loopback(addr: &SocketAddr) -> bool {
    addr.ip().is_loopback()
}

/// A running viewer: its listeners and the broadcast thread. Stops them when dropped.
pub struct Viewer {
    shared: Arc<Shared>,
    http: SocketAddr,
    coach: Option<SocketAddr>,
    threads: Vec<JoinHandle<()>>,
    warnings: Vec<String>,
}

impl std::fmt::Debug for Viewer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Viewer")
            .field("http", &self.http)
            .field("coach", &self.coach)
            .finish_non_exhaustive()
    }
}

/// Stack of the thread that loads the world: kinematic models and their scratch are large
/// values, copied more than once in unoptimised builds. It ends once the world is loaded.
const LOAD_STACK: usize = 64 << 20;

/// Stack of the viewer's long-lived threads (listeners, connections, broadcast). Small on
/// purpose: under `mlockall(MCL_FUTURE)` (a real-time process such as `rl run --view`) every
/// thread's whole stack is locked in RAM.
pub(crate) const WORKER_STACK: usize = 4 << 20;

fn spawn(name: &str, f: impl FnOnce() + Send + 'static) -> Result<JoinHandle<()>, ViewError> {
    std::thread::Builder::new()
        .name(name.into())
        .stack_size(WORKER_STACK)
        .spawn(f)
        .map_err(|e| ViewError::Invalid(format!("cannot start thread {name}: {e}")))
}

impl Viewer {
    /// Loads the world and starts the listeners.
    pub fn start(options: &ViewerOptions) -> Result<Viewer, ViewError> {
        // Kinematic models of capacity 64 are large values: load them on a thread with room
        // for them in unoptimised builds, whatever the caller's stack.
        let load = options.load.clone();
        let (http, coach) = (options.http, options.coach);
        std::thread::Builder::new()
            .name("rl-view-load".into())
            .stack_size(LOAD_STACK)
            .spawn(move || {
                let world = World::load(&load)?;
                Self::start_world(world, http, coach)
            })
            .map_err(|e| ViewError::Invalid(format!("cannot start the loading thread: {e}")))?
            .join()
            .map_err(|_| ViewError::Invalid("the loading thread panicked".into()))?
    }

    /// Starts the listeners for a loaded world.
    pub fn start_world(
        world: World,
        http: SocketAddr,
        coach: Option<SocketAddr>,
    ) -> Result<Viewer, ViewError> {
        let bind_err = |what: &'static str, addr: SocketAddr| {
            move |e: std::io::Error| ViewError::Bind {
                what,
                addr: addr.to_string(),
                reason: e.to_string(),
            }
        };
        let http_listener = http::bind(http).map_err(bind_err("HTTP", http))?;
        let http_addr = http_listener.local_addr().map_err(bind_err("HTTP", http))?;
        let coach_listener = match coach {
            Some(a) => Some(coach::bind(a).map_err(bind_err("Coach", a))?),
            None => None,
        };
        let coach_addr = match &coach_listener {
            Some(l) => Some(l.local_addr().map_err(bind_err("Coach", http))?),
            None => None,
        };
        let warnings = world
            .robots
            .iter()
            .flat_map(|r| r.warnings.iter().map(move |w| format!("{}: {w}", r.name)))
            .collect();
        let shared = Arc::new(Shared {
            files: world.files.clone(),
            engine: Mutex::new(Engine::new(world)),
            hub: Hub::default(),
            stop: AtomicBool::new(false),
            admission: Admission::default(),
            policy: Mutex::new(HostPolicy::new(http_addr)),
            page_idle_ms: AtomicU64::new(ws::IDLE_LIMIT.as_millis() as u64),
            live: Mutex::new(Vec::new()),
        });
        let mut threads = Vec::new();
        let s = shared.clone();
        threads.push(spawn("rl-view-accept", move || {
            http::accept_loop(http_listener, s)
        })?);
        if let Some(l) = coach_listener {
            let s = shared.clone();
            threads.push(spawn("rl-view-coach", move || coach::accept_loop(l, s))?);
        }
        let s = shared.clone();
        threads.push(spawn("rl-view-broadcast", move || ws::broadcast_loop(&s))?);
        Ok(Viewer {
            shared,
            http: http_addr,
            coach: coach_addr,
            threads,
            warnings,
        })
    }

    /// The HTTP address (with the actual port when 0 was asked for).
    pub fn http_addr(&self) -> SocketAddr {
        self.http
    }

    /// The Coach address, if listening.
    pub fn coach_addr(&self) -> Option<SocketAddr> {
        self.coach
    }

    /// The page's URL.
    pub fn url(&self) -> String {
        format!("http://{}/", self.http)
    }

    /// Notes made while loading (missing meshes, models without tools), one per line.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Pages connected now.
    pub fn pages(&self) -> usize {
        self.shared.hub.clients()
    }

    /// Answers requests that name the server `name` too (a host name of the machine, e.g.
    /// `robot.local`, when the viewer listens beyond loopback): by default only `localhost` and
    /// IP addresses are, so that a page from elsewhere cannot reach it through DNS rebinding
    /// ([`origin`]).
    pub fn allow_host(&self, name: &str) {
        lock(&self.shared.policy).allow(name);
    }

    /// Closes pages that send nothing for `limit` (default [`ws::IDLE_LIMIT`]; the page pings
    /// every 5 s and answers the server's pings).
    pub fn set_page_idle_limit(&self, limit: std::time::Duration) {
        let ms = u64::try_from(limit.as_millis()).unwrap_or(u64::MAX).max(1);
        self.shared.page_idle_ms.store(ms, Ordering::Relaxed);
    }

    /// Connections now: request heads arriving, requests being answered, pages
    /// ([`admission`]).
    pub fn connections(&self) -> (usize, usize, usize) {
        self.shared.admission.counts()
    }

    /// Connections turned away so far: slow ones closed to make room for newer ones, and
    /// requests or pages refused with 503 because their pool was full.
    pub fn turned_away(&self) -> (u64, u64) {
        self.shared.admission.turned_away()
    }

    /// The current state message (as a page would get it).
    pub fn state(&self) -> serde_json::Value {
        lock(&self.shared.engine).snapshot_json()
    }

    /// Runs `f` on the state (for embedding: set joints, solve IK from Rust).
    pub fn with_engine<R>(&self, f: impl FnOnce(&mut Engine) -> R) -> R {
        f(&mut lock(&self.shared.engine))
    }

    /// A handle for a real-time loop: `publish(model, &q)` goes through rl-rt's lock-free
    /// mailbox, allocates nothing and never blocks. The viewer takes the newest values every
    /// broadcast period. Each call makes a new, independent handle.
    pub fn publisher(&self) -> Publisher {
        let nq: Vec<usize> = {
            let e = lock(&self.shared.engine);
            (0..e.model_count())
                .map(|m| e.q(m).map_or(0, <[f64]>::len))
                .collect()
        };
        let (p, r) = publish::channel(&nq);
        lock(&self.shared.live).push(r);
        p
    }

    /// Stops the listeners and waits for their threads (also done on drop).
    pub fn shutdown(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        self.shutdown();
    }
}
