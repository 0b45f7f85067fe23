//! `rlrs`: rl-rs from Python (PyO3, maturin, abi3).
//!
//! The compiled module `rlrs._rlrs`; the Python package `rlrs` (`python/rlrs`) re-exports it
//! with type stubs. One file per concept:
//!
//! - [`array`]: numpy in and out (no copy for C-contiguous float64 input), all the `unsafe`;
//! - [`dispatch`]: a model in the capacity that holds it, behind one trait;
//! - [`model`]: `rlrs.load` and `rlrs.Model` (kinematics, dynamics, IK; batched);
//! - [`error`]: the exceptions, with the Rust errors' what-and-where text.
//!
//! Python's docs are the doc comments here (PyO3 turns them into docstrings) and the stubs.

mod array;
mod dispatch;
mod error;
mod model;

use pyo3::prelude::*;

/// rl-rs from Python: robot kinematics and dynamics, trajectories, collision and planning, and
/// real-time control, in Rust, on numpy arrays.
#[pymodule]
fn _rlrs(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("CAPACITIES", dispatch::CAPACITIES.to_vec())?;
    error::register(m)?;
    m.add_function(wrap_pyfunction!(model::load, m)?)?;
    m.add_class::<model::Model>()?;
    Ok(())
}
