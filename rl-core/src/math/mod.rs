//! Small dense linear algebra on fixed-size arrays.

mod jacobi;
pub mod real;
mod small;
mod symmetric_eigen;

pub use jacobi::{MAX_SWEEPS, symmetric_eigen};
pub use small::invert_spd;
pub use symmetric_eigen::symmetric_eigenvalues;
