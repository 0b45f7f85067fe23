//! Loopback fakes that speak the real wire formats from the other side, so every driver can be
//! tested (and tried by a user) without hardware. A fake imitates a remote controller, so unlike
//! a device it runs its own server threads; it is not meant for the real-time path.

pub mod cia402_drive;
pub mod coach_server;
pub mod ecat_segment;
pub mod franka_controller;
pub mod h7_controller;
pub mod netft_sensor;
pub mod robotiq_gripper;
mod tcp_server;
pub mod ur_controller;
