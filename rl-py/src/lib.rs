//! `rlrs`: rl-rs from Python (PyO3, maturin, abi3).
//!
//! The compiled module `rlrs._rlrs`; the Python package `rlrs` (`python/rlrs`) re-exports it
//! with type stubs. One file per concept:
//!
//! - `src/array.rs`: numpy in and out (no copy for C-contiguous float64 input), all the `unsafe`;
//! - `src/dispatch.rs`: a model in the capacity that holds it, behind one trait;
//! - `src/model.rs`: `rlrs.load` and `rlrs.Model` (kinematics, dynamics, IK; batched);
//! - `src/traj.rs`: `rlrs.JerkLimited`, jerk-limited profiles on arrays of times;
//! - `src/otg.rs`: `rlrs.otg` and `rlrs.Otg`: the online trajectory generator, offline on arrays of
//!   times and one control cycle per call;
//! - `src/scene.rs`: `rlrs.Scene`: collision and distance queries (rl-sg);
//! - `src/plan.rs`: `rlrs.Planner`, `rlrs.plan`: rl-plan on MoveIt problems, certified paths;
//! - `src/control.rs`: `rlrs.ControlRun`: the supervised controller of `rl run` (the tool's device
//!   table, `src/cli.rs` its error type);
//! - `src/gil.rs`: waiting for a lock without holding the GIL;
//! - `src/error.rs`: the exceptions, with the Rust errors' what-and-where text.
//!
//! Python's docs are the doc comments here (PyO3 turns them into docstrings) and the stubs.

mod array;
mod control;
mod dispatch;
mod error;
mod gil;
mod model;
mod otg;
mod plan;
mod scene;
mod traj;

use pyo3::prelude::*;

/// How many threads a batched call may use: `n`, or 0 for one per CPU (the default). Batches
/// of fewer than 256 states per thread use fewer threads.
#[pyfunction]
fn set_threads(n: usize) {
    dispatch::set_threads(n);
}

/// How many threads a batched call may use.
#[pyfunction]
fn threads() -> usize {
    dispatch::threads()
}

/// rl-rs from Python: robot kinematics and dynamics, trajectories, collision and planning, and
/// real-time control, in Rust, on numpy arrays.
#[pymodule]
fn _rlrs(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("CAPACITIES", dispatch::CAPACITIES.to_vec())?;
    error::register(m)?;
    m.add_function(wrap_pyfunction!(model::load, m)?)?;
    m.add_function(wrap_pyfunction!(set_threads, m)?)?;
    m.add_function(wrap_pyfunction!(threads, m)?)?;
    m.add_class::<model::Model>()?;
    m.add_class::<traj::JerkLimited>()?;
    m.add_class::<otg::OtgTrajectoryPy>()?;
    m.add_class::<otg::OtgPy>()?;
    m.add_function(wrap_pyfunction!(otg::otg_calculate, m)?)?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<control::ControlRun>()?;
    m.add_class::<plan::Planner>()?;
    m.add_class::<plan::PlanOutcome>()?;
    m.add_function(wrap_pyfunction!(plan::plan_once, m)?)?;
    Ok(())
}
