//! Small dense linear algebra on fixed-size arrays.

pub mod real;
mod small;

pub use small::invert_spd;
