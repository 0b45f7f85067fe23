//! The module's exceptions. Their messages are the Rust errors' own text — the same what and
//! where the `rl` tool prints (file, element, line:column for a model file; argument and
//! lengths for a call) — so a message from Python can be searched for in the tool's docs.
//!
//! ```text
//! rlrs.Error                 every error rl-rs itself reports
//! ├── rlrs.LoadError         a model, scene or problem file was refused
//! ├── rlrs.ModelError        an algorithm refused its input (lengths, quaternions, a singular
//! │                          mass matrix, an unknown frame)
//! ├── rlrs.IkError           inverse kinematics found no solution (the best one is `.q`)
//! ├── rlrs.TrajectoryError   a trajectory cannot be built (limits, waypoints)
//! ├── rlrs.PlanError         planning refused its problem (an end point in collision, ...)
//! └── rlrs.RunError          a controller run did not start (nothing moved)
//! ```
//!
//! Arguments of the wrong shape or type are Python's own `ValueError` and `TypeError`.

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

create_exception!(
    rlrs,
    Error,
    PyException,
    "Every error rl-rs itself reports."
);
create_exception!(
    rlrs,
    LoadError,
    Error,
    "A model, scene or problem file was refused: the message names the file, the element \
     (line:column) and what is wrong with it."
);
create_exception!(
    rlrs,
    ModelError,
    Error,
    "An algorithm refused its input: a vector of the wrong length, a quaternion that is not a \
     unit quaternion, a singular mass matrix, an unknown frame."
);
create_exception!(
    rlrs,
    IkError,
    Error,
    "Inverse kinematics found no solution within its budget; `.q` holds the best configuration \
     found and `.residual` its error."
);
create_exception!(
    rlrs,
    TrajectoryError,
    Error,
    "A trajectory cannot be built: limits that are not finite and positive, waypoints that are \
     not finite, too many axes."
);
create_exception!(
    rlrs,
    PlanError,
    Error,
    "Planning refused its problem: a start or goal outside the limits or in collision, a \
     request that does not match the robot."
);
create_exception!(
    rlrs,
    RunError,
    Error,
    "A controller run did not start: a bad option, a device that failed to open, a plan the \
     model's limits refuse. Nothing moved."
);

/// A `ModelError` with this message.
pub fn model(message: impl std::fmt::Display) -> PyErr {
    ModelError::new_err(message.to_string())
}

/// A `LoadError` with this message.
pub fn load(message: impl std::fmt::Display) -> PyErr {
    LoadError::new_err(message.to_string())
}

/// Adds the exception types to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<Error>())?;
    m.add("LoadError", py.get_type::<LoadError>())?;
    m.add("ModelError", py.get_type::<ModelError>())?;
    m.add("IkError", py.get_type::<IkError>())?;
    m.add("TrajectoryError", py.get_type::<TrajectoryError>())?;
    m.add("PlanError", py.get_type::<PlanError>())?;
    m.add("RunError", py.get_type::<RunError>())?;
    Ok(())
}
