//! `rlrs.load` and `rlrs.Model`: a robot model with its kinematics and dynamics on numpy
//! arrays.
//!
//! Every algorithm takes one state (1-D arrays: `q` of `nq`, `v`/`a`/`tau` of `nv`) or a batch
//! (2-D arrays, one state per row) and returns arrays of the same batch; a batch runs in Rust
//! with the GIL released. Conventions are rl-core's, which are Pinocchio's where both have the
//! quantity: `q` of a free-flyer is `[x y z qx qy qz qw]` and its `v` is `[linear; angular]`
//! in the base frame; frame Jacobians are in the world frame at the frame's origin, rows
//! `[linear; angular]` (Pinocchio's `LOCAL_WORLD_ALIGNED`); a continuous joint's coordinate is
//! its angle (Pinocchio's is `(cos, sin)`: `q_from_pinocchio` converts).

use std::collections::HashMap;
use std::path::PathBuf;

use glam::{DMat3, DVec3};
use pyo3::exceptions::{PyKeyError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PySlice, PyTuple};
use rl_core::algo::ik::{IkGoal, IkMethod, IkOptions};
use rl_core::loader::{
    Format, InertiaCheck, JointOrder, LoadOptions, LoadedModel, MimicJoints, UrdfOptions,
};
use rl_core::spatial::PlueckerTransform;

use crate::array::{Input, Output, check_shape, shape_text, shared_slice};
use crate::dispatch::{self, Algo, Kin};
use crate::error;

/// Load a robot model: URDF (mimic joints, `package://` paths), RL's XML (rlmdl, rlkin).
///
/// Args:
///     path: the model file.
///     floating_base: URDF: add a free-flyer root joint `root_joint` (Pinocchio's
///         `JointModelFreeFlyer`): `q` starts with `x y z qx qy qz qw`.
///     joint_order: "file" numbers sibling joints in file order (RL's); "pinocchio" by name,
///         so that `q` lines up with Pinocchio's on branched robots.
///     mimic: "follow" (a mimic joint follows its leader and has no coordinate, Pinocchio's
///         `mimic=True`), "independent" (a joint of its own) or "reject".
///     inertia_check: "definite" (default: refuse inertias that are not positive
///         semi-definite), "strict" (also the triangle inequality) or "lenient" (warn only).
///     locked_joints: {joint: position} to freeze (Pinocchio's `buildReducedModel`).
///
/// Raises:
///     LoadError: the file was refused; the message names the file, the element and why.
#[pyfunction]
#[pyo3(signature = (path, floating_base=false, joint_order="file", mimic="follow", inertia_check="definite", locked_joints=None))]
pub fn load(
    py: Python<'_>,
    path: PathBuf,
    floating_base: bool,
    joint_order: &str,
    mimic: &str,
    inertia_check: &str,
    locked_joints: Option<HashMap<String, f64>>,
) -> PyResult<Model> {
    let joint_order = match joint_order {
        "file" => JointOrder::File,
        "pinocchio" => JointOrder::Pinocchio,
        other => {
            return Err(PyValueError::new_err(format!(
                "joint_order={other:?}: use \"file\" or \"pinocchio\""
            )));
        }
    };
    let mimic = match mimic {
        "follow" => MimicJoints::Follow,
        "independent" => MimicJoints::Independent,
        "reject" => MimicJoints::Reject,
        other => {
            return Err(PyValueError::new_err(format!(
                "mimic={other:?}: use \"follow\", \"independent\" or \"reject\""
            )));
        }
    };
    let inertia = match inertia_check {
        "definite" => InertiaCheck::Definite,
        "strict" => InertiaCheck::Strict,
        "lenient" => InertiaCheck::Lenient,
        other => {
            return Err(PyValueError::new_err(format!(
                "inertia_check={other:?}: use \"definite\", \"strict\" or \"lenient\""
            )));
        }
    };
    let mut locked: Vec<(String, f64)> = locked_joints.unwrap_or_default().into_iter().collect();
    locked.sort_by(|a, b| a.0.cmp(&b.0));
    let options = LoadOptions {
        urdf: UrdfOptions {
            floating_base,
            joint_order,
            mimic,
            locked_joints: locked,
            ..UrdfOptions::default()
        },
        inertia,
        ..LoadOptions::default()
    };
    let kin = py
        .detach(|| dispatch::load(&path, &options))
        .map_err(error::load)?;
    Ok(Model::new(kin, path))
}

/// A robot model (rl-core's `Model` and its workspace) of the capacity that holds it.
///
/// Create it with `rlrs.load`. Every method accepts one state or a batch (2-D arrays, one
/// state per row; the loop runs in Rust with the GIL released) and returns new arrays.
#[pyclass(frozen, module = "rlrs")]
pub struct Model {
    pub(crate) kin: Box<dyn Kin>,
    path: PathBuf,
    name: String,
    joint_names: Vec<String>,
    frames: Vec<String>,
    frame_index: HashMap<String, usize>,
    limits: [Vec<f64>; 4],
    wraparound: Vec<bool>,
    gravity: [f64; 3],
    warnings: Vec<String>,
}

/// Facts read once from a loaded model of any capacity.
struct Facts {
    name: String,
    joint_names: Vec<String>,
    limits: [Vec<f64>; 4],
    wraparound: Vec<bool>,
    gravity: [f64; 3],
    warnings: Vec<String>,
}

fn facts<const N: usize>(l: &LoadedModel<N>) -> Facts {
    let m = &l.model;
    let joint_names = (0..m.body_count())
        .filter(|&b| m.joint_nv(b) > 0 && m.mimic(b).is_none())
        .map(|b| m.joint_name(b).to_owned())
        .collect();
    let nv = m.dof();
    let limits = [
        (0..nv).map(|k| m.limits(k).lower).collect(),
        (0..nv).map(|k| m.limits(k).upper).collect(),
        (0..nv).map(|k| m.limits(k).velocity).collect(),
        (0..nv).map(|k| m.limits(k).effort).collect(),
    ];
    Facts {
        name: m.name().to_owned(),
        joint_names,
        limits,
        wraparound: (0..nv).map(|k| m.limits(k).wraparound).collect(),
        gravity: m.gravity().to_array(),
        warnings: l.warnings.clone(),
    }
}

/// Calls `$f` on the `LoadedModel<N>` inside `$kin`, whichever capacity it has.
macro_rules! with_loaded {
    ($kin:expr, $f:ident) => {{
        let any = $kin.loaded();
        if let Some(l) = any.downcast_ref::<LoadedModel<16>>() {
            Some($f(l))
        } else if let Some(l) = any.downcast_ref::<LoadedModel<64>>() {
            Some($f(l))
        } else if let Some(l) = any.downcast_ref::<LoadedModel<256>>() {
            Some($f(l))
        } else {
            None
        }
    }};
}

impl Model {
    fn new(kin: Box<dyn Kin>, path: PathBuf) -> Self {
        let f = with_loaded!(kin, facts).unwrap_or(Facts {
            name: String::new(),
            joint_names: Vec::new(),
            limits: Default::default(),
            wraparound: Vec::new(),
            gravity: [0.0; 3],
            warnings: Vec::new(),
        });
        let frames = kin.tool_names();
        let frame_index = frames
            .iter()
            .enumerate()
            .map(|(i, n)| (n.clone(), i))
            .collect();
        Self {
            kin,
            path,
            name: f.name,
            joint_names: f.joint_names,
            frames,
            frame_index,
            limits: f.limits,
            wraparound: f.wraparound,
            gravity: f.gravity,
            warnings: f.warnings,
        }
    }

    /// How a report names the model: "name (path)" or the path.
    pub(crate) fn name_and_path(&self) -> String {
        if self.name.is_empty() {
            self.path.display().to_string()
        } else {
            format!("{} ({})", self.name, self.path.display())
        }
    }

    /// The index of frame `name`, or a `KeyError` listing the frames.
    fn frame(&self, name: &str) -> PyResult<usize> {
        self.frame_index.get(name).copied().ok_or_else(|| {
            PyKeyError::new_err(format!(
                "no frame \"{name}\" in {}; its frames: {}",
                self.path.display(),
                self.frames.join(", ")
            ))
        })
    }

    /// Runs `algo` on one state or a batch: `args` are the inputs with their names and widths;
    /// `shape` the result's shape for one state.
    fn run<'py>(
        &self,
        py: Python<'py>,
        algo: Algo,
        args: &[(&Bound<'py, PyAny>, &str)],
        shape: &[usize],
    ) -> PyResult<Bound<'py, PyAny>> {
        let (nq, nv) = (self.kin.nq(), self.kin.nv());
        let mut inputs = Vec::with_capacity(args.len());
        let mut batch = None;
        for (i, (ob, name)) in args.iter().enumerate() {
            let input = Input::new(ob, name)?;
            check_shape(name, &input, if i == 0 { nq } else { nv }, &mut batch)?;
            inputs.push(input);
        }
        match batch.flatten() {
            None => {
                let mut out = Output::<f64>::zeros(py, shape);
                let slices: Vec<&[f64]> = inputs.iter().map(Input::slice).collect();
                self.kin
                    .eval(algo, &slices, out.as_mut_slice(), 1, true)
                    .map_err(|e| error::model(e.message))?;
                Ok(out.into_any())
            }
            Some(rows) => {
                let mut full = vec![rows];
                full.extend_from_slice(shape);
                let mut out = Output::<f64>::zeros(py, &full);
                let borrows = inputs
                    .iter()
                    .map(Input::shared)
                    .collect::<PyResult<Vec<_>>>()?;
                let slices: Vec<&[f64]> = borrows.iter().map(shared_slice).collect();
                let kin = &*self.kin;
                let cells = out.as_mut_slice();
                py.detach(|| kin.eval(algo, &slices, cells, rows, false))
                    .map_err(|e| error::model(format!("state {}: {}", e.row, e.message)))?;
                Ok(out.into_any())
            }
        }
    }

    /// `q` as one configuration of `nq` values.
    fn one_q(&self, q: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
        let input = Input::new(q, name)?;
        if input.shape() != [self.kin.nq()] {
            return Err(PyValueError::new_err(format!(
                "{name}: shape {}, expected ({},)",
                shape_text(input.shape()),
                self.kin.nq()
            )));
        }
        Ok(input.slice().to_vec())
    }
}

/// The three matrices of a derivative call, `(x[0], x[1], x[2])` or `(x[:, 0], …)` for a
/// batch: views into one array.
fn three<'py>(x: &Bound<'py, PyAny>, batched: bool) -> PyResult<Bound<'py, PyTuple>> {
    let parts = (0..3)
        .map(|i| take(x, i, batched))
        .collect::<PyResult<Vec<_>>>()?;
    PyTuple::new(x.py(), parts)
}

/// `x[..., i]` along the first axis after the batch: `x[i]` or `x[:, i]`.
fn take<'py>(x: &Bound<'py, PyAny>, i: usize, batched: bool) -> PyResult<Bound<'py, PyAny>> {
    if batched {
        let py = x.py();
        let all = PySlice::full(py);
        x.get_item(PyTuple::new(
            py,
            [all.into_any(), i.into_pyobject(py)?.into_any()],
        )?)
    } else {
        x.get_item(i)
    }
}

/// A pose target from a 4 × 4 homogeneous matrix.
fn pose_from(t: &[f64]) -> PlueckerTransform {
    let col = |c: usize| DVec3::new(t[c], t[4 + c], t[8 + c]);
    PlueckerTransform::new(
        DMat3::from_cols(col(0), col(1), col(2)),
        DVec3::new(t[3], t[7], t[11]),
    )
}

#[pymethods]
impl Model {
    /// The model's name (URDF `<robot name>`, RL's `<model><name>`).
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// The file it was loaded from.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    /// "urdf", "rlmdl" or "rlkin".
    #[getter]
    fn format(&self) -> &'static str {
        match self.kin.format() {
            Format::Urdf => "urdf",
            Format::Rlmdl => "rlmdl",
            Format::Rlkin => "rlkin",
        }
    }

    /// Size of a configuration `q`.
    #[getter]
    fn nq(&self) -> usize {
        self.kin.nq()
    }

    /// Size of a velocity `v` (degrees of freedom), of `a` and of `tau`.
    #[getter]
    fn nv(&self) -> usize {
        self.kin.nv()
    }

    /// The capacity the model was loaded into (16, 64 or 256 bodies, DOFs and frames).
    #[getter]
    fn capacity(&self) -> usize {
        self.kin.capacity()
    }

    /// The joints with coordinates, in the order of `q` (mimic joints, which follow their
    /// leaders, have none).
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.joint_names.clone()
    }

    /// The frames `fk` and `jacobian` answer for: URDF links (leaves first, then the others),
    /// RL's leaf frames.
    #[getter]
    fn frames(&self) -> Vec<String> {
        self.frames.clone()
    }

    /// Lower position limits per degree of freedom (nv; -inf where unlimited).
    #[getter]
    fn lower_limits<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        crate::array::vector(py, &self.limits[0])
    }

    /// Upper position limits per degree of freedom (nv; inf where unlimited).
    #[getter]
    fn upper_limits<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        crate::array::vector(py, &self.limits[1])
    }

    /// Speed limits per degree of freedom (nv; inf where the file gives none).
    #[getter]
    fn velocity_limits<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        crate::array::vector(py, &self.limits[2])
    }

    /// Effort limits per degree of freedom (nv; inf where the file gives none).
    #[getter]
    fn effort_limits<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        crate::array::vector(py, &self.limits[3])
    }

    /// Per degree of freedom: whether it is an angle that wraps around (a continuous joint,
    /// whose position limits do not apply; Pinocchio stores it as `(cos, sin)`).
    #[getter]
    fn wraparound(&self) -> Vec<bool> {
        self.wraparound.clone()
    }

    /// The gravity vector, m/s² (world frame).
    #[getter]
    fn gravity_vector<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        crate::array::vector(py, &self.gravity)
    }

    /// What the loader noted (ignored elements, unphysical inertias, massless joints).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "<rlrs.Model {:?} from {}: nq={} nv={} frames={} capacity={}>",
            self.name,
            self.path.display(),
            self.kin.nq(),
            self.kin.nv(),
            self.frames.len(),
            self.kin.capacity()
        )
    }

    /// The neutral configuration (zeros, identity quaternions), nq values.
    fn neutral<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let mut out = Output::<f64>::zeros(py, &[self.kin.nq()]);
        self.kin.neutral(out.as_mut_slice());
        out.into_any()
    }

    /// Random configurations within the limits (uniform; `[-pi, pi]` or `[-1, 1]` m where
    /// unlimited; uniform unit quaternions), reproducible from `seed`.
    ///
    /// Returns nq values, or an array (n, nq) when `n` is given.
    #[pyo3(signature = (n=None, seed=0))]
    fn random_configuration<'py>(
        &self,
        py: Python<'py>,
        n: Option<usize>,
        seed: u64,
    ) -> Bound<'py, PyAny> {
        let nq = self.kin.nq();
        let rows = n.unwrap_or(1);
        let shape: Vec<usize> = match n {
            Some(n) => vec![n, nq],
            None => vec![nq],
        };
        let mut out = Output::<f64>::zeros(py, &shape);
        self.kin.random(out.as_mut_slice(), rows, seed);
        out.into_any()
    }

    /// `q` with every quaternion (spherical joints, a free-flyer) divided by its norm.
    fn normalize<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let mut q = self.one_q(q, "q")?;
        self.kin.normalize(&mut q);
        Ok(crate::array::vector(py, &q))
    }

    /// `q ⊕ v·dt`: the configuration reached from `q` moving at `v` for `dt` seconds (on the
    /// unit quaternion for spherical and free joints).
    #[pyo3(signature = (q, v, dt=1.0))]
    fn integrate<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        v: &Bound<'py, PyAny>,
        dt: f64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let q = self.one_q(q, "q")?;
        let v = Input::new(v, "v")?;
        if v.shape() != [self.kin.nv()] {
            return Err(PyValueError::new_err(format!(
                "v: shape {}, expected ({},)",
                shape_text(v.shape()),
                self.kin.nv()
            )));
        }
        let mut out = Output::<f64>::zeros(py, &[self.kin.nq()]);
        self.kin.integrate(&q, v.slice(), dt, out.as_mut_slice());
        Ok(out.into_any())
    }

    /// A configuration of Pinocchio's for the same URDF, in ours: Pinocchio stores a
    /// continuous joint as `(cos, sin)`, we store its angle. Load with
    /// `joint_order="pinocchio"` so that the joints line up.
    fn q_from_pinocchio<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let q = Input::new(q, "q")?;
        let ours = self.kin.q_from_pinocchio(q.slice()).ok_or_else(|| {
            PyValueError::new_err(format!(
                "q: {} values do not make a Pinocchio configuration of this model",
                q.slice().len()
            ))
        })?;
        Ok(crate::array::vector(py, &ours))
    }

    /// Forward kinematics: world poses as 4 × 4 homogeneous matrices.
    ///
    /// Returns {frame: (4, 4)} for every frame, or the (4, 4) of `frame` when given; with a
    /// batch of configurations (n, nq): {frame: (n, 4, 4)} or (n, 4, 4). The dict's arrays are
    /// views into one array (n, frames, 4, 4).
    #[pyo3(signature = (q, frame=None))]
    fn fk<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        frame: Option<&str>,
    ) -> PyResult<Bound<'py, PyAny>> {
        if let Some(name) = frame {
            let t = self.frame(name)?;
            return self.run(py, Algo::FramePose(t), &[(q, "q")], &[4, 4]);
        }
        let all = self.run(py, Algo::Frames, &[(q, "q")], &[self.frames.len(), 4, 4])?;
        let batched = all.getattr("ndim")?.extract::<usize>()? == 4;
        let dict = PyDict::new(py);
        for (i, name) in self.frames.iter().enumerate() {
            dict.set_item(name, take(&all, i, batched)?)?;
        }
        Ok(dict.into_any())
    }

    /// The world Jacobian of `frame` at its origin, rows `[linear xyz; angular xyz]`
    /// (Pinocchio's `LOCAL_WORLD_ALIGNED`): (6, nv), or (n, 6, nv) for a batch.
    fn jacobian<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        frame: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        let t = self.frame(frame)?;
        self.run(py, Algo::Jacobian(t), &[(q, "q")], &[6, self.kin.nv()])
    }

    /// Inverse dynamics (recursive Newton-Euler): `tau = M(q) a + C(q, v) v + g(q)`.
    fn rnea<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        v: &Bound<'py, PyAny>,
        a: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.run(
            py,
            Algo::Rnea,
            &[(q, "q"), (v, "v"), (a, "a")],
            &[self.kin.nv()],
        )
    }

    /// Forward dynamics (articulated-body algorithm): `a = M(q)⁻¹ (tau - C(q, v) v - g(q))`.
    fn aba<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        v: &Bound<'py, PyAny>,
        tau: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.run(
            py,
            Algo::Aba,
            &[(q, "q"), (v, "v"), (tau, "tau")],
            &[self.kin.nv()],
        )
    }

    /// The joint-space mass matrix `M(q)` (composite rigid-body algorithm), full and
    /// symmetric: (nv, nv), or (n, nv, nv) for a batch.
    fn crba<'py>(&self, py: Python<'py>, q: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let nv = self.kin.nv();
        self.run(py, Algo::Crba, &[(q, "q")], &[nv, nv])
    }

    /// Generalised gravity `g(q)`.
    fn gravity<'py>(&self, py: Python<'py>, q: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        self.run(py, Algo::Gravity, &[(q, "q")], &[self.kin.nv()])
    }

    /// Nonlinear effects `C(q, v) v + g(q)` (Pinocchio's `nonLinearEffects`).
    fn nle<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        v: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.run(py, Algo::Nle, &[(q, "q"), (v, "v")], &[self.kin.nv()])
    }

    /// The same as `nle`.
    fn nonlinear_effects<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        v: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.nle(py, q, v)
    }

    /// The analytical derivatives of inverse dynamics (Pinocchio's
    /// `computeRNEADerivatives`): `(dtau_dq, dtau_dv, M)`, each (nv, nv), or (n, nv, nv) for a
    /// batch; `M` with both triangles. `dtau_dq` is in the tangent space (Pinocchio's
    /// convention for free-flyer and spherical joints: a variation `q ⊕ δ` of the
    /// configuration).
    fn rnea_derivatives<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        v: &Bound<'py, PyAny>,
        a: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let nv = self.kin.nv();
        let all = self.run(
            py,
            Algo::RneaDerivatives,
            &[(q, "q"), (v, "v"), (a, "a")],
            &[3, nv, nv],
        )?;
        three(&all, all.getattr("ndim")?.extract::<usize>()? == 4)
    }

    /// The analytical derivatives of forward dynamics (Pinocchio's `computeABADerivatives`):
    /// `(ddq_dq, ddq_dv, Minv)`, each (nv, nv), or (n, nv, nv) for a batch; `Minv = M⁻¹`
    /// (`∂q̈/∂τ`) with both triangles; `ddq_dq` in the tangent space (see
    /// `rnea_derivatives`). Raises ModelError where the mass matrix is singular.
    fn aba_derivatives<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        v: &Bound<'py, PyAny>,
        tau: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let nv = self.kin.nv();
        let all = self.run(
            py,
            Algo::AbaDerivatives,
            &[(q, "q"), (v, "v"), (tau, "tau")],
            &[3, nv, nv],
        )?;
        three(&all, all.getattr("ndim")?.extract::<usize>()? == 4)
    }

    /// `∂g/∂q` of the generalised gravity (Pinocchio's
    /// `computeGeneralizedGravityDerivatives`, the static torque without external forces):
    /// (nv, nv), or (n, nv, nv) for a batch; in the tangent space.
    fn gravity_derivatives<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let nv = self.kin.nv();
        self.run(py, Algo::GravityDerivatives, &[(q, "q")], &[nv, nv])
    }

    /// Coriolis and centrifugal torques `C(q, v) v`.
    fn coriolis<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        v: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.run(py, Algo::Coriolis, &[(q, "q"), (v, "v")], &[self.kin.nv()])
    }

    /// Inverse kinematics: a configuration that puts `frame` at `target`.
    ///
    /// Args:
    ///     frame: the frame to place.
    ///     target: a 4 × 4 pose, or a 3-vector (position only).
    ///     q0: where to start (default: the neutral configuration).
    ///     method: "dls" (damped least squares, `damping`), "svd" (damped pseudo-inverse)
    ///         or "transpose".
    ///     epsilon: success below this error (m and rad stacked).
    ///     max_iterations: over all random restarts.
    ///     seed: of the restarts (the same seed gives the same answer).
    ///
    /// Returns the configuration (nq). Raises IkError (with `.q`, the best configuration
    /// found, and `.residual`) when none is found.
    #[pyo3(signature = (frame, target, q0=None, method="dls", damping=1e-3, epsilon=1e-6, max_iterations=10_000, seed=None))]
    #[allow(clippy::too_many_arguments)]
    fn ik<'py>(
        &self,
        py: Python<'py>,
        frame: &str,
        target: &Bound<'py, PyAny>,
        q0: Option<&Bound<'py, PyAny>>,
        method: &str,
        damping: f64,
        epsilon: f64,
        max_iterations: usize,
        seed: Option<u64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let tool = self.frame(frame)?;
        let target = Input::new(target, "target")?;
        let goal = match target.shape() {
            [4, 4] => IkGoal::pose(tool, pose_from(target.slice())),
            [3] => IkGoal::position(tool, DVec3::from_slice(target.slice())),
            s => {
                return Err(PyValueError::new_err(format!(
                    "target: shape {}, expected (4, 4) (a pose) or (3,) (a position)",
                    shape_text(s)
                )));
            }
        };
        let q_init = match q0 {
            Some(q) => self.one_q(q, "q0")?,
            None => {
                let mut q = vec![0.0; self.kin.nq()];
                self.kin.neutral(&mut q);
                q
            }
        };
        let mut options = IkOptions {
            method: match method {
                "dls" => IkMethod::Dls { lambda: damping },
                "svd" => IkMethod::PseudoInverse { threshold: damping },
                "transpose" => IkMethod::Transpose,
                other => {
                    return Err(PyValueError::new_err(format!(
                        "method={other:?}: use \"dls\", \"svd\" or \"transpose\""
                    )));
                }
            },
            epsilon,
            max_iterations,
            ..IkOptions::default()
        };
        if let Some(s) = seed {
            options.seed = s;
        }
        let mut q = vec![0.0; self.kin.nq()];
        let kin = &*self.kin;
        let result = py.detach(|| kin.ik(&[goal], options, &q_init, &mut q));
        match result {
            Ok(_) => Ok(crate::array::vector(py, &q)),
            Err(e) => {
                let err = error::IkError::new_err(e.to_string());
                let value = err.value(py);
                value.setattr("q", crate::array::vector(py, &q))?;
                let residual = match e {
                    rl_core::algo::ik::IkError::NotConverged { residual, .. }
                    | rl_core::algo::ik::IkError::TimeBudget { residual, .. } => residual,
                    _ => f64::NAN,
                };
                value.setattr("residual", residual)?;
                Err(err)
            }
        }
    }
}
