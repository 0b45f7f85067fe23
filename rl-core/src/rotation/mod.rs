//! Rotations: unit-quaternion extensions (exp, log, pow, angular velocity and acceleration).
