//! `rlrs.Planner`, `rlrs.plan`: collision-free paths from rl-plan for a URDF robot among the
//! obstacles of a MoveIt planning scene (MotionBenchMaker's, VAMP's problem sets), the path as
//! a numpy array, and its certification on the exact geometry (conservative advancement:
//! nothing passes between samples) — what `rl plan` does, from Python.
//!
//! Planning runs with the GIL released. The defaults are the tool's (`rl plan`): RRT-Connect
//! with VAMP's settings (range 1 rad, balanced trees, dynamic domain), the Halton sampler, the
//! hybrid checker (spheres covering the meshes, then the exact meshes where they disagree),
//! shortcutting, a 1 s budget, edges checked at 1/32 rad.

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Duration;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rl_plan::optimizer::OptimizerKind;
use rl_plan::planner::{DynamicDomain, PlannerKind};
use rl_plan::problem::moveit::MotionRequest;
use rl_plan::problem::{COVER_SPACING, Robot};
use rl_plan::sampler::SamplerKind;
use rl_plan::scene::{CertifyOptions, SceneValidity};
use rl_plan::space::parse_bounds;
use rl_plan::verifier::Verifier;
use rl_plan::{Path as PlanPath, PlanOptions, PlanResult, Validity, plan};

use crate::array::{Input, Output, shape_text};
use crate::error::PlanError;

fn plan_error(e: impl std::fmt::Display) -> PyErr {
    PlanError::new_err(e.to_string())
}

/// A robot for planning: its kinematics, collision geometry (with the SRDF's allowed pairs)
/// and collision spheres (the `_spherized.urdf` beside the URDF, covered to the meshes, or
/// fitted).
///
/// Args:
///     urdf: the robot.
///     srdf: its SRDF (default: the .srdf beside the URDF, if any).
///     spheres: a spherized URDF (default: NAME_spherized.urdf beside the URDF, else spheres
///         fitted around the meshes).
///     raw_spheres: use the file's spheres as they are (VAMP's model: faster, not
///         conservative) instead of growing them to cover the meshes.
///     limits: {joint: (min, max)} to plan within instead of the model's limits.
#[pyclass(frozen, module = "rlrs")]
pub struct Planner {
    robot: Robot,
}

/// Checkers by name.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Checker {
    Hybrid,
    Spheres,
    Exact,
}

impl Checker {
    fn parse(s: &str) -> PyResult<Self> {
        match s {
            "hybrid" => Ok(Self::Hybrid),
            "spheres" => Ok(Self::Spheres),
            "exact" => Ok(Self::Exact),
            o => Err(PyValueError::new_err(format!(
                "checker={o:?}: use \"hybrid\", \"spheres\" or \"exact\""
            ))),
        }
    }
}

/// The result of `Planner.plan`.
#[pyclass(frozen, module = "rlrs", get_all)]
pub struct PlanOutcome {
    /// Whether a path was found.
    solved: bool,
    /// The optimised path (waypoints × nq), start to goal; None when not solved.
    path: Option<Py<PyAny>>,
    /// The planner's path before optimisation.
    raw_path: Option<Py<PyAny>>,
    /// The planner's name.
    planner: String,
    /// Seconds spent planning (the straight-motion try included).
    planning_time: f64,
    /// Seconds spent optimising.
    optimization_time: f64,
    /// Planner iterations (0 when the straight motion was valid).
    iterations: u64,
    /// Configurations checked while planning.
    collision_checks: u64,
    /// Length of the optimised path (nan when not solved).
    length: f64,
    /// Length of the planner's path.
    raw_length: f64,
    /// The certification on the exact geometry: {certified, edges, edges_certified, steps,
    /// min_distance, margin, failure}; None when not solved or not asked.
    certificate: Option<Py<PyAny>>,
    /// The joints, in the order of the path's columns.
    joint_names: Vec<String>,
}

#[pymethods]
impl PlanOutcome {
    fn __repr__(&self) -> String {
        format!(
            "<rlrs.PlanOutcome solved={} waypoints={} length={:.4} planning {:.1} µs>",
            if self.solved { "True" } else { "False" },
            Python::attach(|py| self
                .path
                .as_ref()
                .and_then(|p| p.bind(py).len().ok())
                .unwrap_or(0)),
            self.length,
            self.planning_time * 1e6
        )
    }
}

fn path_array<'py>(py: Python<'py>, p: &PlanPath) -> Bound<'py, PyAny> {
    let mut out = Output::<f64>::zeros(py, &[p.len(), p.nq()]);
    out.as_mut_slice().copy_from_slice(p.as_flat());
    out.into_any()
}

/// The certificate of `path` on `checker`'s exact geometry, as a dict.
fn certify<'py>(
    py: Python<'py>,
    exact: &mut SceneValidity,
    path: &PlanPath,
    margin: f64,
) -> PyResult<Bound<'py, PyAny>> {
    if margin.is_nan() || margin < 0.0 {
        return Err(PyValueError::new_err(
            "certify_margin must be a distance >= 0 (m)",
        ));
    }
    let options = CertifyOptions {
        margin,
        ..Default::default()
    };
    let d = PyDict::new(py);
    d.set_item("margin", margin)?;
    match py.detach(|| exact.certify_path(path, &options)) {
        Ok(c) => {
            d.set_item("certified", c.is_certified())?;
            d.set_item("edges", c.edges)?;
            d.set_item("edges_certified", c.certified)?;
            d.set_item("steps", c.steps)?;
            d.set_item("min_distance", c.min_distance)?;
            d.set_item(
                "failure",
                c.failure.map(|(edge, why)| (edge, why.to_string())),
            )?;
        }
        // A model the motion bound does not cover: the plan stands, uncertified, and says why.
        Err(rl_plan::PlanError::Unsupported(why)) => {
            d.set_item("certified", false)?;
            d.set_item("unsupported", why)?;
        }
        Err(e) => return Err(plan_error(e)),
    }
    Ok(d.into_any())
}

#[pymethods]
impl Planner {
    #[new]
    #[pyo3(signature = (urdf, srdf=None, spheres=None, raw_spheres=false, limits=None))]
    fn new(
        py: Python<'_>,
        urdf: PathBuf,
        srdf: Option<PathBuf>,
        spheres: Option<PathBuf>,
        raw_spheres: bool,
        limits: Option<std::collections::HashMap<String, (f64, f64)>>,
    ) -> PyResult<Self> {
        let cover = (!raw_spheres).then_some(COVER_SPACING);
        let mut robot = py
            .detach(|| Robot::load_urdf_with(&urdf, srdf.as_deref(), spheres.as_deref(), cover))
            .map_err(|e| crate::error::LoadError::new_err(e.to_string()))?;
        if let Some(limits) = limits {
            let mut entries: Vec<_> = limits.into_iter().collect();
            entries.sort_by(|a, b| a.0.cmp(&b.0));
            let text = entries
                .iter()
                .map(|(j, (lo, hi))| format!("{j}={lo}:{hi}"))
                .collect::<Vec<_>>()
                .join(",");
            let bounds =
                parse_bounds(&text).map_err(|e| PyValueError::new_err(format!("limits: {e}")))?;
            robot
                .space
                .override_bounds(&bounds)
                .map_err(|e| PyValueError::new_err(format!("limits: {e}")))?;
        }
        Ok(Self { robot })
    }

    /// The joints planned for, in the order of a path's columns.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.robot
            .space
            .coordinates()
            .iter()
            .map(|c| c.name.clone())
            .collect()
    }

    /// Size of a configuration.
    #[getter]
    fn nq(&self) -> usize {
        self.robot.space.coordinates().len()
    }

    /// Start and goal of a MoveIt motion plan request (YAML) for this robot: two arrays (nq,).
    fn request<'py>(
        &self,
        py: Python<'py>,
        request: PathBuf,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let req = MotionRequest::load(&request).map_err(crate::error::load)?;
        let (start, goal) = req.configurations(&self.robot.space).map_err(plan_error)?;
        Ok((
            crate::array::vector(py, &start),
            crate::array::vector(py, &goal),
        ))
    }

    /// Plans a collision-free path among the obstacles of `scene` (a MoveIt planning scene,
    /// YAML), from the request's start to its goal (`request`, a MoveIt motion plan request)
    /// or from `start` to `goal`.
    ///
    /// Args:
    ///     planner: rrt-connect (default), rrt-con-con, rrt-ext-ext, rrt-dual, rrt-goal-bias,
    ///         rrt, prm.
    ///     seed: the same seed gives the same path.
    ///     time: seconds for planning (and again for optimising).
    ///     checker: "hybrid" (default), "spheres" (SIMD only) or "exact" (meshes).
    ///     sampler: halton (default), uniform, gaussian, bridge.
    ///     optimizer: simple (shortcutting, default), advanced (RL's), none.
    ///     resolution: edge check step, rad.
    ///     range: RRT step, rad (default 1).
    ///     dynamic_domain: dynamic-domain RRT extensions (rrt-connect).
    ///     certify: certify the returned path on the exact geometry (`certify_margin`, m).
    ///
    /// Raises PlanError for a start or goal outside the limits or in collision.
    #[pyo3(signature = (scene, request=None, start=None, goal=None, planner="rrt-connect", seed=0, time=1.0, checker="hybrid", sampler="halton", optimizer="simple", resolution=1.0/32.0, range=None, dynamic_domain=true, certify=true, certify_margin=CertifyOptions::default().margin))]
    #[allow(clippy::too_many_arguments)]
    fn plan<'py>(
        &self,
        py: Python<'py>,
        scene: PathBuf,
        request: Option<PathBuf>,
        start: Option<&Bound<'py, PyAny>>,
        goal: Option<&Bound<'py, PyAny>>,
        planner: &str,
        seed: u64,
        time: f64,
        checker: &str,
        sampler: &str,
        optimizer: &str,
        resolution: f64,
        range: Option<f64>,
        dynamic_domain: bool,
        certify: bool,
        certify_margin: f64,
    ) -> PyResult<PlanOutcome> {
        let checker = Checker::parse(checker)?;
        let (start, goal) = self.ends(request, start, goal)?;
        if !(time.is_finite() && time > 0.0) {
            return Err(PyValueError::new_err(
                "time must be a positive number of seconds",
            ));
        }
        let mut kind = PlannerKind::parse(planner)
            .map_err(|e| PyValueError::new_err(format!("planner={planner:?}: {e}")))?;
        if let Some(s) = kind.rrt_settings_mut() {
            s.delta = range.unwrap_or(1.0);
            s.balance = true;
            if dynamic_domain {
                s.dynamic_domain = Some(DynamicDomain::VAMP);
            }
        }
        let sampler = match sampler {
            "halton" => SamplerKind::Halton,
            "uniform" => SamplerKind::Uniform,
            "gaussian" => SamplerKind::Gaussian(None),
            "bridge" => SamplerKind::Bridge(None, 5.0 / 6.0),
            o => {
                return Err(PyValueError::new_err(format!(
                    "sampler={o:?}: use halton, uniform, gaussian or bridge"
                )));
            }
        };
        let optimizer = OptimizerKind::parse(optimizer).ok_or_else(|| {
            PyValueError::new_err(format!(
                "optimizer={optimizer:?}: use simple, advanced or none"
            ))
        })?;
        if !(resolution.is_finite() && resolution > 0.0) {
            return Err(PyValueError::new_err("resolution must be positive"));
        }
        let options = PlanOptions {
            planner: kind,
            sampler,
            verifier: Verifier::recursive(resolution),
            optimizer,
            optimizer_verifier: None,
            seed,
            time: Duration::from_secs_f64(time),
            optimize_time: Duration::from_secs_f64(time),
            try_direct: true,
        };
        let env = rl_sg::load::moveit::load_environment(&scene).map_err(crate::error::load)?;
        let robot = &self.robot;
        let space = &robot.space;
        // Plans with the checker asked for; the exact checker of the same scene certifies.
        let planned = py.detach(
            || -> Result<(PlanResult, Option<SceneValidity>), rl_plan::PlanError> {
                match checker {
                    Checker::Hybrid => {
                        let mut c = robot.hybrid_checker(&env)?;
                        let r = plan(space, &mut c, &start, &goal, &options)?;
                        let exact = c.exact_checker().map(|e| e.clone());
                        Ok((r, exact))
                    }
                    Checker::Spheres => {
                        let mut c = robot.sphere_checker(&env)?;
                        let r = plan(space, &mut c, &start, &goal, &options)?;
                        Ok((r, Some(robot.exact_checker(env.clone())?)))
                    }
                    Checker::Exact => {
                        let mut c = robot.exact_checker(env.clone())?;
                        let r = plan(space, &mut c, &start, &goal, &options)?;
                        Ok((r, Some(c)))
                    }
                }
            },
        );
        let (r, exact) = planned.map_err(plan_error)?;
        let certificate = match (&r.optimized, exact, certify) {
            (Some(path), Some(mut exact), true) => {
                Some(self::certify(py, &mut exact, path, certify_margin)?.unbind())
            }
            _ => None,
        };
        Ok(PlanOutcome {
            solved: r.solved,
            path: r.optimized.as_ref().map(|p| path_array(py, p).unbind()),
            raw_path: r.path.as_ref().map(|p| path_array(py, p).unbind()),
            planner: r.planner.to_owned(),
            planning_time: r.planning_time.as_secs_f64(),
            optimization_time: r.optimization_time.as_secs_f64(),
            iterations: r.iterations,
            collision_checks: r.planning_checks,
            length: r.length_after,
            raw_length: r.length_before,
            certificate,
            joint_names: self.joint_names(),
        })
    }

    /// Certifies `path` (waypoints × nq) among the obstacles of `scene` on the exact geometry:
    /// every edge by conservative advancement with clearance `margin` (m). Returns a dict
    /// {certified, edges, edges_certified, steps, min_distance, margin, failure}.
    #[pyo3(signature = (path, scene, margin=CertifyOptions::default().margin))]
    fn certify<'py>(
        &self,
        py: Python<'py>,
        path: &Bound<'py, PyAny>,
        scene: PathBuf,
        margin: f64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let p = self.path(path)?;
        let env = rl_sg::load::moveit::load_environment(&scene).map_err(crate::error::load)?;
        let mut exact = self.robot.exact_checker(env).map_err(plan_error)?;
        self::certify(py, &mut exact, &p, margin)
    }

    /// Whether configurations are free of collision (self-collision with the SRDF's pairs,
    /// and the obstacles of `scene`) on the exact geometry: a bool for one configuration
    /// (nq,), a bool array for a batch (n, nq), checked with the GIL released.
    fn is_valid<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        scene: PathBuf,
    ) -> PyResult<Bound<'py, PyAny>> {
        let env = rl_sg::load::moveit::load_environment(&scene).map_err(crate::error::load)?;
        let exact = Mutex::new(self.robot.exact_checker(env).map_err(plan_error)?);
        let nq = self.nq();
        let input = Input::new(q, "q")?;
        let shape = input.shape().to_vec();
        let rows = match shape.as_slice() {
            [n] if *n == nq => None,
            [b, n] if *n == nq => Some(*b),
            s => {
                return Err(PyValueError::new_err(format!(
                    "q: shape {}, expected ({nq},) or (batch, {nq})",
                    shape_text(s)
                )));
            }
        };
        let borrow = input.shared()?;
        let qs = crate::array::shared_slice(&borrow);
        let mut out = Output::<bool>::zeros(py, &[rows.unwrap_or(1)]);
        let cells = out.as_mut_slice();
        py.detach(|| {
            let mut c = exact.lock().unwrap_or_else(|p| p.into_inner());
            for (cell, q) in cells.iter_mut().zip(qs.chunks_exact(nq.max(1))) {
                *cell = c.is_valid(q);
            }
        });
        let out = out.into_any();
        match rows {
            Some(_) => Ok(out),
            None => out.get_item(0),
        }
    }
}

impl Planner {
    /// Start and goal from a request or given.
    fn ends(
        &self,
        request: Option<PathBuf>,
        start: Option<&Bound<'_, PyAny>>,
        goal: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<(Vec<f64>, Vec<f64>)> {
        let nq = self.nq();
        let one = |x: &Bound<'_, PyAny>, name: &str| -> PyResult<Vec<f64>> {
            let i = Input::new(x, name)?;
            if i.shape() != [nq] {
                return Err(PyValueError::new_err(format!(
                    "{name}: shape {}, expected ({nq},)",
                    shape_text(i.shape())
                )));
            }
            Ok(i.slice().to_vec())
        };
        match (request, start, goal) {
            (Some(r), None, None) => {
                let req = MotionRequest::load(&r).map_err(crate::error::load)?;
                req.configurations(&self.robot.space).map_err(plan_error)
            }
            (None, Some(s), Some(g)) => Ok((one(s, "start")?, one(g, "goal")?)),
            _ => Err(PyValueError::new_err(
                "give a request (MoveIt YAML) or both start and goal",
            )),
        }
    }

    /// A path argument (waypoints × nq).
    fn path(&self, path: &Bound<'_, PyAny>) -> PyResult<PlanPath> {
        let nq = self.nq();
        let input = Input::new(path, "path")?;
        match input.shape() {
            [_, n] if *n == nq => {}
            s => {
                return Err(PyValueError::new_err(format!(
                    "path: shape {}, expected (waypoints, {nq})",
                    shape_text(s)
                )));
            }
        }
        let mut p = PlanPath::new(nq);
        for q in input.slice().chunks_exact(nq.max(1)) {
            p.push(q);
        }
        Ok(p)
    }
}

/// Plans once: `Planner(urdf, srdf, spheres).plan(scene, request, **options)`.
#[pyfunction]
#[pyo3(name = "plan", signature = (urdf, scene, request=None, srdf=None, spheres=None, **options))]
pub fn plan_once<'py>(
    py: Python<'py>,
    urdf: PathBuf,
    scene: PathBuf,
    request: Option<PathBuf>,
    srdf: Option<PathBuf>,
    spheres: Option<PathBuf>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let planner = Bound::new(py, Planner::new(py, urdf, srdf, spheres, false, None)?)?;
    let kwargs = PyDict::new(py);
    if let Some(o) = options {
        kwargs.update(o.as_mapping())?;
    }
    kwargs.set_item("request", request)?;
    planner.call_method("plan", (scene,), Some(&kwargs))
}
