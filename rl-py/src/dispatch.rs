//! A model of whichever capacity holds it, behind one object-safe trait.
//!
//! `rl_core::Model<N>` fixes its capacity (bodies, degrees of freedom, tools) at compile time.
//! The module is built for [`CAPACITIES`] and puts every file into the smallest that holds it
//! (as the `rl` tool does, `src/cli/capacity.rs`): arms run in small, cache-friendly models and
//! robots of up to 256 bodies load at all. [`Kin`] is implemented once, generically, by
//! [`Loaded<N>`] and monomorphised per capacity; Python sees one `Model` class.
//!
//! Every algorithm runs through [`Kin::eval`]: `rows` states laid out row after row, the result
//! written into the caller's buffer. A single call (`rows == 1`, the GIL held) uses the model's
//! own workspace; a batched call (which releases the GIL) makes its own, so several Python
//! threads can run batches on one model at the same time.

use std::any::Any;
use std::path::Path;
use std::sync::Mutex;

use rl_core::algo::ik::{IkError, IkGoal, IkOptions, IkSolution, IkSolver, SplitMix64};
use rl_core::loader::{self, LoadError, LoadErrorKind, LoadOptions, LoadedModel};
use rl_core::model::ModelError;
use rl_core::model::{DerivativeData, MatrixView};
use rl_core::spatial::PlueckerTransform;
use rl_core::{Data, algo};

/// Defines [`CAPACITIES`] and [`load_into`], which tries them in order.
macro_rules! capacities {
    ($($n:literal),+) => {
        /// The capacities the module is built for, ascending (most bodies, degrees of freedom
        /// and tools of a model).
        pub const CAPACITIES: &[usize] = &[$($n),+];

        /// Loads `path` into the first capacity of at least `min` that holds it.
        #[allow(unused_assignments)] // each capacity's error is kept only for the last
        fn load_into(
            path: &Path,
            options: &LoadOptions,
            min: usize,
        ) -> Result<Box<dyn Kin>, LoadError> {
            let mut last = None;
            $(
                if $n >= min {
                    match loader::load_file_options::<$n>(path, options) {
                        Ok(m) => return Ok(Box::new(Loaded::new(m))),
                        Err(e) if over_capacity(&e) => last = Some(e),
                        Err(e) => return Err(e),
                    }
                }
            )+
            Err(last.unwrap_or(LoadError {
                path: Some(path.to_path_buf()),
                element: None,
                kind: LoadErrorKind::Model(ModelError::TooManyBodies { capacity: 0 }),
            }))
        }
    };
}

capacities!(16, 64, 256);

/// The largest capacity.
pub const LARGEST: usize = CAPACITIES[CAPACITIES.len() - 1];

/// Whether `e` says the model does not fit its capacity.
fn over_capacity(e: &LoadError) -> bool {
    matches!(
        e.kind,
        LoadErrorKind::Model(
            ModelError::TooManyBodies { .. }
                | ModelError::TooManyDofs { .. }
                | ModelError::TooManyTools { .. }
        )
    )
}

/// Loads a model file (URDF, rlmdl, rlkin) into the smallest capacity that holds it.
///
/// URDF: every link becomes a frame the kinematics can be asked about (a tool in rl-core's
/// terms: the leaf links first, then the others in the file's depth-first order), as
/// Pinocchio's frames are; if that does not fit the largest capacity, only the leaves are.
/// RL XML files keep their own tools (the leaf frames).
pub fn load(path: &Path, options: &LoadOptions) -> Result<Box<dyn Kin>, String> {
    let first = load_into(path, options, 0).map_err(over_capacity_message)?;
    if first.format() != loader::Format::Urdf {
        return Ok(first);
    }
    let tools = first.tool_names();
    let extra: Vec<String> = first
        .frame_names()
        .into_iter()
        .filter(|f| !tools.contains(f))
        .collect();
    if extra.is_empty() {
        return Ok(first);
    }
    let mut all = options.clone();
    all.urdf.extra_tools.extend(extra);
    match load_into(path, &all, first.capacity()) {
        Ok(m) => Ok(m),
        Err(e) if over_capacity(&e) => Ok(first),
        Err(e) => Err(e.to_string()),
    }
}

/// A load error as text, with the way out for a model over the largest capacity.
fn over_capacity_message(e: LoadError) -> String {
    if over_capacity(&e) {
        format!(
            "{e}. rlrs loads models into the capacities {CAPACITIES:?} (most bodies, degrees of \
             freedom and tools; rl-py/src/dispatch.rs) and this one needs more than {LARGEST}: \
             add a larger capacity there and rebuild the wheel"
        )
    } else {
        e.to_string()
    }
}

/// An algorithm [`Kin::eval`] runs on each state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Algo {
    /// Inverse dynamics `τ(q, v, a)`: inputs q, v, a; out nv.
    Rnea,
    /// Forward dynamics `q̈(q, v, τ)`: inputs q, v, τ; out nv.
    Aba,
    /// Mass matrix `M(q)`: input q; out nv × nv.
    Crba,
    /// Generalised gravity `g(q)`: input q; out nv.
    Gravity,
    /// Nonlinear effects `C(q, v) v + g(q)`: inputs q, v; out nv.
    Nle,
    /// Coriolis and centrifugal `C(q, v) v`: inputs q, v; out nv.
    Coriolis,
    /// Every frame's world pose: input q; out frames × 4 × 4.
    Frames,
    /// One frame's world pose: input q; out 4 × 4.
    FramePose(usize),
    /// One frame's world Jacobian `[linear; angular]` at its origin: input q; out 6 × nv.
    Jacobian(usize),
    /// `∂τ/∂q`, `∂τ/∂q̇` and `M` of RNEA (Pinocchio's `computeRNEADerivatives`): inputs q, v,
    /// a; out 3 × nv × nv.
    RneaDerivatives,
    /// `∂q̈/∂q`, `∂q̈/∂q̇` and `M⁻¹` of ABA (Pinocchio's `computeABADerivatives`): inputs q, v,
    /// τ; out 3 × nv × nv.
    AbaDerivatives,
    /// `∂g/∂q` of the generalised gravity (Pinocchio's
    /// `computeGeneralizedGravityDerivatives`): input q; out nv × nv.
    GravityDerivatives,
}

/// A failure of one state of a batch: its row and the algorithm's message.
#[derive(Debug)]
pub struct RowError {
    /// The state's index (0 for a single call).
    pub row: usize,
    /// What went wrong (rl-core's text).
    pub message: String,
}

/// A loaded model of some capacity: what Python's `Model` calls.
pub trait Kin: Send + Sync {
    /// The capacity it was loaded into.
    fn capacity(&self) -> usize;
    /// The file's format.
    fn format(&self) -> loader::Format;
    /// Configuration size.
    fn nq(&self) -> usize;
    /// Velocity size (degrees of freedom).
    fn nv(&self) -> usize;
    /// The output width of `algo` for one state.
    fn width(&self, algo: Algo) -> usize {
        let nv = self.nv();
        match algo {
            Algo::Rnea | Algo::Aba | Algo::Gravity | Algo::Nle | Algo::Coriolis => nv,
            Algo::Crba | Algo::GravityDerivatives => nv * nv,
            Algo::RneaDerivatives | Algo::AbaDerivatives => 3 * nv * nv,
            Algo::Frames => 16 * self.tool_names().len(),
            Algo::FramePose(_) => 16,
            Algo::Jacobian(_) => 6 * nv,
        }
    }
    /// The names of the tools (frames the kinematics answers for), in order.
    fn tool_names(&self) -> Vec<String>;
    /// Every frame of the file (links, RL frames), in depth-first order.
    fn frame_names(&self) -> Vec<String>;
    /// The loaded model, for code that needs its concrete capacity (downcast to
    /// `LoadedModel<N>` for one of [`CAPACITIES`]).
    fn loaded(&self) -> &dyn Any;
    /// Runs `algo` on `rows` states. `inputs[i]` holds `rows` rows of the algorithm's i-th
    /// input (q: nq values, v/a/τ: nv); `out` has `rows × width(algo)` values. `shared`: use
    /// the model's own workspace (single calls); else a new one.
    fn eval(
        &self,
        algo: Algo,
        inputs: &[&[f64]],
        out: &mut [f64],
        rows: usize,
        shared: bool,
    ) -> Result<(), RowError>;
    /// The neutral configuration into `q` (nq).
    fn neutral(&self, q: &mut [f64]);
    /// `rows` random configurations within the limits into `q`, from `seed`.
    fn random(&self, q: &mut [f64], rows: usize, seed: u64);
    /// Every quaternion of `q` divided by its norm.
    fn normalize(&self, q: &mut [f64]);
    /// `q ⊕ v·dt` into `out`.
    fn integrate(&self, q: &[f64], v: &[f64], dt: f64, out: &mut [f64]);
    /// A Pinocchio configuration of the same URDF as ours (continuous joints `(cos, sin)`).
    fn q_from_pinocchio(&self, q: &[f64]) -> Option<Vec<f64>>;
    /// Inverse kinematics from `q_init` into `q_out`.
    fn ik(
        &self,
        goals: &[IkGoal],
        options: IkOptions,
        q_init: &[f64],
        q_out: &mut [f64],
    ) -> Result<IkSolution, IkError>;
}

/// What the algorithms of one thread write: rl-core's `Data`, and the derivatives' workspace,
/// made on first use (3 × N² values and more: 1.5 MB at the largest capacity).
pub struct Workspace<const N: usize> {
    data: Box<Data<N>>,
    deriv: Option<Box<DerivativeData<N>>>,
}

impl<const N: usize> Workspace<N> {
    fn new() -> Self {
        Self {
            data: Box::new(Data::new()),
            deriv: None,
        }
    }
}

/// The leading `nv × nv` block of `m`, row after row, into `out`.
fn copy_matrix<const N: usize>(m: MatrixView<'_, N>, out: &mut [f64]) {
    let nv = m.dim();
    for (row, cells) in m.rows().zip(out.chunks_exact_mut(nv.max(1))) {
        cells.copy_from_slice(row);
    }
}

/// A model of capacity `N` with its workspace.
pub struct Loaded<const N: usize> {
    loaded: Box<LoadedModel<N>>,
    data: Mutex<Workspace<N>>,
    /// Whether `q` holds quaternions (spherical and free joints), checked for unit norm.
    quaternions: bool,
}

impl<const N: usize> Loaded<N> {
    fn new(loaded: LoadedModel<N>) -> Self {
        let m = &loaded.model;
        let quaternions =
            (0..m.body_count()).any(|b| m.mimic(b).is_none() && m.joint_nq(b) > m.joint_nv(b));
        Self {
            loaded: Box::new(loaded),
            data: Mutex::new(Workspace::new()),
            quaternions,
        }
    }

    /// One state of `algo`: `ins` its inputs, `out` its result.
    fn one(
        &self,
        algo: Algo,
        ws: &mut Workspace<N>,
        ins: [&[f64]; 3],
        out: &mut [f64],
    ) -> Result<(), rl_core::Error> {
        let m = &self.loaded.model;
        let [q, v, a] = ins;
        let Workspace { data, deriv } = ws;
        let data = &mut **data;
        match algo {
            Algo::Rnea => out.copy_from_slice(algo::rnea(m, data, q, v, a)?),
            Algo::Aba => out.copy_from_slice(algo::aba(m, data, q, v, a)?),
            Algo::Gravity => out.copy_from_slice(algo::gravity(m, data, q)?),
            Algo::Nle => out.copy_from_slice(algo::nonlinear_effects(m, data, q, v)?),
            Algo::Coriolis => out.copy_from_slice(algo::coriolis(m, data, q, v)?),
            Algo::Crba => {
                algo::crba(m, data, q)?;
                let nv = m.dof();
                for (r, row) in out.chunks_exact_mut(nv.max(1)).enumerate().take(nv) {
                    data.mass_matrix_row(r, row);
                }
            }
            Algo::Frames => {
                algo::forward_position(m, data, q)?;
                for (t, cell) in out.chunks_exact_mut(16).enumerate() {
                    homogeneous(&algo::tool_pose(m, data, t)?, cell);
                }
            }
            Algo::FramePose(t) => {
                algo::forward_position(m, data, q)?;
                homogeneous(&algo::tool_pose(m, data, t)?, out);
            }
            Algo::Jacobian(t) => {
                let mut jac = [[0.0; N]; 6];
                algo::jacobian(m, data, q, t, &mut jac)?;
                let nv = m.dof();
                for (row, cells) in jac.iter().zip(out.chunks_exact_mut(nv.max(1))) {
                    cells.copy_from_slice(&row[..nv]);
                }
            }
            Algo::RneaDerivatives => {
                let deriv = deriv.get_or_insert_with(|| Box::new(DerivativeData::new()));
                let r = algo::rnea_derivatives(m, data, deriv, q, v, a)?;
                let nn = m.dof() * m.dof();
                for (k, view) in [r.dtau_dq, r.dtau_dv, r.mass_matrix]
                    .into_iter()
                    .enumerate()
                {
                    copy_matrix(view, &mut out[k * nn..(k + 1) * nn]);
                }
            }
            Algo::AbaDerivatives => {
                let deriv = deriv.get_or_insert_with(|| Box::new(DerivativeData::new()));
                let r = algo::aba_derivatives(m, data, deriv, q, v, a)?;
                let nn = m.dof() * m.dof();
                for (k, view) in [r.ddq_dq, r.ddq_dv, r.minv].into_iter().enumerate() {
                    copy_matrix(view, &mut out[k * nn..(k + 1) * nn]);
                }
            }
            Algo::GravityDerivatives => {
                let deriv = deriv.get_or_insert_with(|| Box::new(DerivativeData::new()));
                copy_matrix(algo::static_torque_derivatives(m, data, deriv, q)?, out);
            }
        }
        Ok(())
    }

    /// An algorithm's error as the `rl` tool words it (`src/cli/model.rs`): a singular mass
    /// matrix names its joint.
    fn message(&self, e: rl_core::Error) -> String {
        let m = &self.loaded.model;
        match e {
            rl_core::Error::NotPositiveDefinite { dof } if dof < m.dof() => format!(
                "the mass matrix cannot be factorised: joint \"{}\" (DOF {dof}) moves no mass \
                 or inertia along its axis here (its subtree is massless), so forward dynamics \
                 are undefined; give the links it moves an inertia",
                m.joint_name(m.dof_body(dof))
            ),
            e => e.to_string(),
        }
    }

    fn rows(
        &self,
        algo: Algo,
        ws: &mut Workspace<N>,
        inputs: &[&[f64]],
        out: &mut [f64],
        rows: usize,
    ) -> Result<(), RowError> {
        let (nq, nv) = (self.nq(), self.nv());
        let width = self.width(algo);
        let mut ins: [&[f64]; 3] = [&[], &[], &[]];
        for row in 0..rows {
            for (i, input) in inputs.iter().enumerate().take(3) {
                let w = if i == 0 { nq } else { nv };
                ins[i] = &input[row * w..(row + 1) * w];
            }
            if self.quaternions {
                if let Some(bad) = self.loaded.model.unit_quaternion_errors(ins[0]).next() {
                    return Err(RowError {
                        row,
                        message: format!(
                            "q: elements {at}..{} (x, y, z, w of joint \"{}\"'s quaternion) \
                             have norm {}; a rotation needs a unit quaternion{}",
                            bad.q_index + 3,
                            self.loaded.model.joint_name(bad.body),
                            bad.norm,
                            if bad.norm > 0.0 {
                                " (Model.normalize divides it by its norm)"
                            } else {
                                ""
                            },
                            at = bad.q_index,
                        ),
                    });
                }
            }
            let cell = &mut out[row * width..(row + 1) * width];
            self.one(algo, ws, ins, cell).map_err(|e| RowError {
                row,
                message: self.message(e),
            })?;
        }
        Ok(())
    }
}

impl<const N: usize> Loaded<N> {
    /// A batch on up to [`threads`] threads, each with its own workspace, in contiguous
    /// chunks of rows; small batches on this thread. The error reported is that of the
    /// first failing row.
    fn rows_parallel(
        &self,
        algo: Algo,
        inputs: &[&[f64]],
        out: &mut [f64],
        rows: usize,
    ) -> Result<(), RowError> {
        let threads = threads().min(rows / MIN_ROWS_PER_THREAD).max(1);
        if threads == 1 {
            return self.rows(algo, &mut Workspace::new(), inputs, out, rows);
        }
        let (nq, nv, width) = (self.nq(), self.nv(), self.width(algo));
        let per = rows.div_ceil(threads);
        let results: Vec<Result<(), RowError>> = std::thread::scope(|scope| {
            let handles: Vec<_> = out
                .chunks_mut(per * width.max(1))
                .enumerate()
                .map(|(c, cells)| {
                    let first = c * per;
                    let count = per.min(rows - first);
                    let ins: Vec<&[f64]> = inputs
                        .iter()
                        .enumerate()
                        .map(|(i, x)| {
                            let w = if i == 0 { nq } else { nv };
                            &x[first * w..(first + count) * w]
                        })
                        .collect();
                    std::thread::Builder::new()
                        .stack_size(WORKER_STACK)
                        .spawn_scoped(scope, move || {
                            self.rows(algo, &mut Workspace::new(), &ins, cells, count)
                                .map_err(|e| RowError {
                                    row: e.row + first,
                                    message: e.message,
                                })
                        })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| match h {
                    Ok(h) => h.join().unwrap_or_else(|_| {
                        Err(RowError {
                            row: 0,
                            message: "a worker thread panicked".into(),
                        })
                    }),
                    Err(e) => Err(RowError {
                        row: 0,
                        message: format!("a worker thread could not start: {e}"),
                    }),
                })
                .collect()
        });
        // Chunks are in row order: the first error is the first failing row.
        results.into_iter().collect()
    }
}

/// A worker's stack: room for a workspace built on the stack before it is boxed (rl-core's
/// `DerivativeData` is 3.2 MB at the largest capacity; a thread's default is 2 MB).
const WORKER_STACK: usize = 16 << 20;

/// Fewer rows than this per thread are not worth a thread (spawning one costs about as much
/// as a few dozen states of RNEA on an arm).
const MIN_ROWS_PER_THREAD: usize = 256;

/// Threads for batches: 0 = one per CPU.
static THREADS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// How many threads a batch may use.
pub fn threads() -> usize {
    match THREADS.load(std::sync::atomic::Ordering::Relaxed) {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    }
}

/// Sets how many threads a batch may use (0: one per CPU).
pub fn set_threads(n: usize) {
    THREADS.store(n, std::sync::atomic::Ordering::Relaxed);
}

/// `x` as a row-major 4 × 4 homogeneous matrix into `out` (16 values).
fn homogeneous(x: &PlueckerTransform, out: &mut [f64]) {
    let r = &x.rotation;
    let t = x.translation;
    let rows = [
        [r.x_axis.x, r.y_axis.x, r.z_axis.x, t.x],
        [r.x_axis.y, r.y_axis.y, r.z_axis.y, t.y],
        [r.x_axis.z, r.y_axis.z, r.z_axis.z, t.z],
        [0.0, 0.0, 0.0, 1.0],
    ];
    out.copy_from_slice(rows.as_flattened());
}

impl<const N: usize> Kin for Loaded<N> {
    fn capacity(&self) -> usize {
        N
    }

    fn format(&self) -> loader::Format {
        self.loaded.format
    }

    fn nq(&self) -> usize {
        self.loaded.model.nq()
    }

    fn nv(&self) -> usize {
        self.loaded.model.dof()
    }

    fn tool_names(&self) -> Vec<String> {
        self.loaded
            .model
            .tools()
            .iter()
            .map(|t| t.name.as_str().to_owned())
            .collect()
    }

    fn frame_names(&self) -> Vec<String> {
        self.loaded.frames.iter().map(|f| f.name.clone()).collect()
    }

    fn loaded(&self) -> &dyn Any {
        &*self.loaded
    }

    fn eval(
        &self,
        algo: Algo,
        inputs: &[&[f64]],
        out: &mut [f64],
        rows: usize,
        shared: bool,
    ) -> Result<(), RowError> {
        if shared {
            // Only single calls with the GIL held take this lock, so it is never contended
            // for long; a panic elsewhere cannot leave the workspace inconsistent for the
            // next call (every algorithm overwrites what it reads).
            let mut data = self.data.lock().unwrap_or_else(|p| p.into_inner());
            self.rows(algo, &mut data, inputs, out, rows)
        } else {
            self.rows_parallel(algo, inputs, out, rows)
        }
    }

    fn neutral(&self, q: &mut [f64]) {
        self.loaded.model.neutral(q);
    }

    fn random(&self, q: &mut [f64], rows: usize, seed: u64) {
        let mut rng = SplitMix64::new(seed);
        let nq = self.nq();
        for row in q.chunks_exact_mut(nq.max(1)).take(rows) {
            self.loaded
                .model
                .random_configuration(row, || rng.next_f64());
        }
    }

    fn normalize(&self, q: &mut [f64]) {
        self.loaded.model.normalize(q);
    }

    fn integrate(&self, q: &[f64], v: &[f64], dt: f64, out: &mut [f64]) {
        self.loaded.model.integrate(q, v, dt, out);
    }

    fn q_from_pinocchio(&self, q: &[f64]) -> Option<Vec<f64>> {
        self.loaded.q_from_pinocchio(q)
    }

    fn ik(
        &self,
        goals: &[IkGoal],
        options: IkOptions,
        q_init: &[f64],
        q_out: &mut [f64],
    ) -> Result<IkSolution, IkError> {
        let mut solver = Box::new(IkSolver::<N>::new(options));
        let mut data = Box::new(Data::<N>::new());
        solver.solve(&self.loaded.model, &mut data, goals, q_init, q_out)
    }
}
