//! `rlrs.Scene`: a robot among obstacles (rl-sg) — collision and distance queries at joint
//! configurations, what `rl scene check` answers, from Python.
//!
//! The robot is a URDF (its collision geometry, `package://` meshes, an SRDF's allowed pairs)
//! or an RL scene (rlsg XML) whose first model is the robot, with its kinematics (rlmdl or
//! rlkin); the obstacles a MoveIt planning scene (YAML), an RL scene, VRML or a URDF. Batched
//! queries run with the GIL released.

use std::path::PathBuf;
use std::sync::Mutex;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rl_core::Data;
use rl_core::loader::{MimicJoints, UrdfOptions};
use rl_sg::load::{GeometryKind, MeshMode, RobotScene, RobotSetup, UrdfGeometryOptions};
use rl_sg::report::{self, NamedDistance};
use rl_sg::{CollisionFilter, ModelId};

use crate::array::{Input, Output, shape_text};

/// What a scene of some kinematic capacity does.
trait Placed: Send {
    fn nq(&self) -> usize;
    /// Places the robot at `q`.
    fn place(&mut self, q: &[f64]) -> Result<(), String>;
    fn scene(&self) -> &rl_sg::Scene;
    fn robot(&self) -> ModelId;
}

struct Robot<const N: usize> {
    loaded: Box<RobotScene<N>>,
    data: Box<Data<N>>,
}

impl<const N: usize> Placed for Robot<N> {
    fn nq(&self) -> usize {
        self.loaded.kinematics.model.nq()
    }

    fn place(&mut self, q: &[f64]) -> Result<(), String> {
        let r = &mut *self.loaded;
        r.scene
            .set_configuration(r.robot, &r.kinematics.model, &mut self.data, q)
            .map_err(|e| format!("q: {e}"))
    }

    fn scene(&self) -> &rl_sg::Scene {
        &self.loaded.scene
    }

    fn robot(&self) -> ModelId {
        self.loaded.robot
    }
}

/// A robot among obstacles, for collision and distance queries.
///
/// Args:
///     model: the robot: a URDF, or an RL scene (rlsg XML) whose first model is the robot.
///     env: obstacles: a MoveIt planning scene (.yaml), an RL scene (rlsg XML, .wrl) or a URDF.
///     srdf: the SRDF with the robot's allowed collision pairs (default: adjacent links and
///         links rigidly joined are not checked against each other).
///     kinematics: RL scenes: the robot's kinematic model (rlmdl or rlkin).
///     floating_base: URDF: a free-flyer root joint.
///     mimic_independent: URDF: load mimic joints as joints of their own.
///     package_dirs: where `package://` URIs are looked up.
///     convex_hulls: meshes as their convex hulls instead of triangle meshes.
#[pyclass(frozen, module = "rlrs")]
pub struct Scene {
    inner: Mutex<Box<dyn Placed>>,
    nq: usize,
}

fn named(d: &Option<NamedDistance>, py: Python<'_>) -> PyResult<Py<PyAny>> {
    Ok(match d {
        None => py.None(),
        Some(d) => {
            let o = PyDict::new(py);
            o.set_item("a", &d.a)?;
            o.set_item("b", &d.b)?;
            o.set_item("distance", d.distance)?;
            o.set_item("point_a", d.point_a.to_vec())?;
            o.set_item("point_b", d.point_b.to_vec())?;
            o.into_any().unbind()
        }
    })
}

/// What a query asks of the placed scene.
#[derive(Clone, Copy)]
enum Query {
    Colliding,
    Distance,
}

impl Scene {
    /// `q` as rows of nq values: the rows and whether it was a batch.
    fn rows(&self, q: &Input<'_>) -> PyResult<Option<usize>> {
        let nq = self.nq;
        match q.shape() {
            [n] if *n == nq => Ok(None),
            [b, n] if *n == nq => Ok(Some(*b)),
            s => Err(PyValueError::new_err(format!(
                "q: shape {}, expected ({nq},) or (batch, {nq})",
                shape_text(s)
            ))),
        }
    }

    fn query<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        query: Query,
        environment: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let input = Input::new(q, "q")?;
        let rows = self.rows(&input)?;
        let borrow = input.shared()?;
        let qs = crate::array::shared_slice(&borrow);
        let nq = self.nq.max(1);
        let n = rows.unwrap_or(1);
        let inner = &self.inner;
        let mut colliding = Output::<bool>::zeros(py, &[n]);
        let mut distance = Output::<f64>::zeros(py, &[n]);
        let (c, d) = (colliding.as_mut_slice(), distance.as_mut_slice());
        let failed = py.detach(|| -> Result<(), String> {
            let mut s = inner.lock().unwrap_or_else(|p| p.into_inner());
            for (k, q) in qs.chunks_exact(nq).enumerate().take(n) {
                s.place(q).map_err(|e| format!("state {k}: {e}"))?;
                let robot = s.robot();
                let filter = if environment {
                    CollisionFilter::Against(robot)
                } else {
                    CollisionFilter::SelfCollision(robot)
                };
                match query {
                    Query::Colliding => c[k] = s.scene().is_colliding(&filter),
                    Query::Distance => {
                        d[k] = s
                            .scene()
                            .min_distance(&filter)
                            .map_or(f64::INFINITY, |x| x.distance)
                    }
                }
            }
            Ok(())
        });
        failed.map_err(crate::error::model)?;
        let out = match query {
            Query::Colliding => colliding.into_any(),
            Query::Distance => distance.into_any(),
        };
        match rows {
            Some(_) => Ok(out),
            None => out.get_item(0),
        }
    }
}

#[pymethods]
impl Scene {
    #[new]
    #[pyo3(signature = (model, env=None, srdf=None, kinematics=None, floating_base=false, mimic_independent=false, package_dirs=Vec::new(), convex_hulls=false))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        model: PathBuf,
        env: Option<PathBuf>,
        srdf: Option<PathBuf>,
        kinematics: Option<PathBuf>,
        floating_base: bool,
        mimic_independent: bool,
        package_dirs: Vec<PathBuf>,
        convex_hulls: bool,
    ) -> PyResult<Self> {
        let setup = RobotSetup {
            model,
            kinematics,
            srdf,
            environment: env,
            urdf: UrdfOptions {
                floating_base,
                mimic: if mimic_independent {
                    MimicJoints::Independent
                } else {
                    MimicJoints::Reject
                },
                ..UrdfOptions::default()
            },
            geometry: UrdfGeometryOptions {
                kind: GeometryKind::Collision,
                package_dirs,
                mesh: if convex_hulls {
                    MeshMode::ConvexHull
                } else {
                    MeshMode::Mesh
                },
                strict_meshes: false,
            },
        };
        let placed = py.detach(|| -> Result<Box<dyn Placed>, String> {
            // The tool's capacity for scenes (rl scene), then the largest.
            match setup.load::<64>() {
                Ok(r) => Ok(Box::new(Robot {
                    loaded: Box::new(r),
                    data: Box::new(Data::new()),
                })),
                Err(e64) => match setup.load::<256>() {
                    Ok(r) => Ok(Box::new(Robot {
                        loaded: Box::new(r),
                        data: Box::new(Data::new()),
                    })),
                    Err(_) => Err(e64.to_string()),
                },
            }
        });
        let placed = placed.map_err(crate::error::load)?;
        let nq = placed.nq();
        Ok(Self {
            inner: Mutex::new(placed),
            nq,
        })
    }

    /// Size of the robot's configuration.
    #[getter]
    fn nq(&self) -> usize {
        self.nq
    }

    /// The models of the scene (the robot first, then the obstacles).
    #[getter]
    fn models(&self, py: Python<'_>) -> Vec<String> {
        let s = crate::gil::lock(py, &self.inner);
        s.scene()
            .models()
            .iter()
            .map(|m| m.name().to_owned())
            .collect()
    }

    /// What `rl scene check` prints, at `q`: {colliding, collisions, self_collisions,
    /// environment_collisions, min_distance, self_min_distance, environment_min_distance,
    /// self_pairs_checked, environment_bodies}; distances are {a, b, distance, point_a,
    /// point_b} in the world frame (negative: penetration depth) or None.
    fn check<'py>(&self, py: Python<'py>, q: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let input = Input::new(q, "q")?;
        if self.rows(&input)?.is_some() {
            return Err(PyValueError::new_err("check takes one configuration (nq,)"));
        }
        let mut s = crate::gil::lock(py, &self.inner);
        s.place(input.slice()).map_err(crate::error::model)?;
        let r = report::check(s.scene(), s.robot());
        let o = PyDict::new(py);
        o.set_item("colliding", r.colliding)?;
        o.set_item("collisions", r.collisions)?;
        o.set_item("self_collisions", r.self_collisions)?;
        o.set_item("environment_collisions", r.environment_collisions)?;
        o.set_item("min_distance", named(&r.min_distance, py)?)?;
        o.set_item("self_min_distance", named(&r.self_min_distance, py)?)?;
        o.set_item(
            "environment_min_distance",
            named(&r.environment_min_distance, py)?,
        )?;
        o.set_item("self_pairs_checked", r.self_pairs_checked)?;
        o.set_item("environment_bodies", r.environment_bodies)?;
        Ok(o.into_any())
    }

    /// Whether the robot at `q` collides with the obstacles (`environment=True`, default) or
    /// with itself: a bool, or a bool array for a batch (n, nq).
    #[pyo3(signature = (q, environment=true))]
    fn is_colliding<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        environment: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.query(py, q, Query::Colliding, environment)
    }

    /// The smallest signed distance (m; negative: penetration depth) between the robot at `q`
    /// and the obstacles (`environment=True`, default) or between its own checked pairs: a
    /// float (inf when nothing is checked), or an array for a batch (n, nq).
    #[pyo3(signature = (q, environment=true))]
    fn distance<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        environment: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.query(py, q, Query::Distance, environment)
    }
}
