//! Inverse kinematics (being built).
