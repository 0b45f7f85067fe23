//! The algorithms, one file each. All write into a [`Data`](crate::model::Data), allocate
//! nothing, and check the lengths of their vector arguments.
//!
//! Conventions: bodies' velocities, accelerations and forces are in body coordinates
//! (Featherstone's local formulation); tool quantities are reported RL's way, in world
//! coordinates at the tool's origin, with Jacobian rows `[linear xyz; angular xyz]`.

mod aba;
mod aba_derivatives;
mod coriolis;
mod crba;
mod forward_acceleration;
mod forward_position;
mod forward_velocity;
mod gravity;
pub mod ik;
mod jacobian;
mod mass_solve;
mod mimic;
mod operational;
mod rnea;
mod rnea_derivatives;
mod static_torque_derivatives;

pub use aba::{aba, aba_with_external_forces};
pub use aba_derivatives::{AbaDerivatives, aba_derivatives, aba_derivatives_with_external_forces};
pub use coriolis::{coriolis, nonlinear_effects};
pub use crba::crba;
pub use forward_acceleration::{forward_acceleration, tool_acceleration};
pub use forward_position::{forward_position, tool_pose};
pub use forward_velocity::{forward_velocity, tool_velocity};
pub use gravity::gravity;
pub use jacobian::{Jacobian, jacobian, jacobian_derivative_times_qd, jacobians, point_jacobian};
pub use mass_solve::{factor_mass_matrix, solve_mass_matrix};
pub use operational::operational_inverse_inertia;
pub use rnea::{rnea, rnea_with_external_forces};
pub use rnea_derivatives::{
    RneaDerivatives, rnea_derivatives, rnea_derivatives_with_external_forces,
};
pub use static_torque_derivatives::{
    static_torque_derivatives, static_torque_derivatives_with_external_forces,
};
