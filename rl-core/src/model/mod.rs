//! Fixed-capacity tree models: an immutable description ([`Model`]) and a preallocated
//! workspace ([`Data`]) for the algorithms, as Pinocchio splits them.
//!
//! Capacity is a const generic `N`: the most moving bodies *and* the most degrees of freedom
//! (every moving body has at least one DOF, so `N` DOF bound the bodies too). Bodies are
//! stored in depth-first order from the root, so a parent always comes before its children
//! and every algorithm is a forward and/or backward sweep over arrays.

mod builder;
mod data;
mod error;
mod limits;
pub mod mimic;
#[allow(clippy::module_inception)]
mod model;
mod name;

pub use builder::ModelBuilder;
pub(crate) use data::DerivativeWorkspace;
pub use data::{Data, DerivativeData, MatrixView};
pub use error::ModelError;
pub use limits::JointLimits;
pub use mimic::Mimic;
pub use model::{Model, QuaternionNorm, ROOT, Tool, UNIT_QUATERNION_TOLERANCE};
pub use name::{NAME_CAPACITY, Name};
