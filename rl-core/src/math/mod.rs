//! Small dense linear algebra on fixed-size arrays.

mod small;

pub use small::invert_spd;
