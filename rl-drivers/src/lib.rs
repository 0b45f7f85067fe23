//! Cyclic devices (open, start, step, stop, close), protocol codecs and loopback fake robots.
//!
//! Features:
//! - `std` (default): socket transports and the drivers ([`MitsubishiH7`], [`Coach`], CANopen,
//!   EtherCAT, Franka, UR, the gripper and the F/T sensor). Without it the crate is `no_std` and
//!   allocation-free: the device traits, the capability traits, the wire codecs in [`proto`] and
//!   the e-stop chain over `embedded-hal` pins in [`safety`] remain.
//! - `fake` (off by default; `std` with it): the loopback fakes in `fake`, a simulated device
//!   on the wire for every protocol, for tests, demos and `rl fake-robot`. A controller built
//!   for its robot leaves it off.
//!
//! The model follows the Robotics Library (RL): every device is opened, started, stepped once per
//! control cycle, stopped and closed. All communication happens inside
//! [`CyclicDevice::step`]; getters and setters only touch buffered values. No device ever starts
//! a thread: the application owns concurrency (the fakes do run their own thread, because they
//! imitate a remote controller).
//!
//! ```no_run
//! # #[cfg(feature = "fake")] fn main() -> Result<(), rl_drivers::Error> {
//! use rl_drivers::{CyclicDevice, Device, JointPositionActuator, JointPositionSensor};
//! use rl_drivers::fake::h7_controller::{FakeH7, FakeH7Config};
//! use rl_drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
//!
//! let fake = FakeH7::spawn(FakeH7Config::loopback(6)).expect("fake controller");
//! let mut robot = MitsubishiH7::new(MitsubishiH7Config::new(6, fake.udp_addr(), fake.r3_addr()))?;
//! robot.open()?;
//! robot.start()?;
//! let mut q = [0.0; 6];
//! for _ in 0..100 {
//!     robot.joint_position(&mut q)?;
//!     q[0] += 0.001;
//!     robot.set_joint_position(&q)?;
//!     robot.step()?; // sleep until the next 7.11 ms period between steps
//! }
//! robot.stop()?;
//! robot.close()?;
//! # Ok(()) }
//! # #[cfg(not(feature = "fake"))] fn main() {}
//! ```
#![cfg_attr(not(any(feature = "std", test)), no_std)]
#![deny(missing_docs)]

#[cfg(feature = "std")]
mod boxed;
pub mod capability;
pub mod cia402;
pub mod device;
pub mod franka;
pub mod proto;
pub mod safety;
pub mod typestate;

#[cfg(feature = "std")]
pub mod ati;
#[cfg(feature = "std")]
pub mod canopen;
#[cfg(feature = "std")]
pub mod coach;
#[cfg(feature = "std")]
pub mod ethercat;
#[cfg(feature = "fake")]
pub mod fake;
#[cfg(feature = "std")]
pub mod mitsubishi_h7;
#[cfg(feature = "std")]
pub mod robotiq;
#[cfg(feature = "std")]
pub mod transport;
#[cfg(feature = "std")]
pub mod ur;

#[cfg(feature = "std")]
pub use ati::AtiNetFt;
pub use capability::*;
#[cfg(feature = "std")]
pub use coach::Coach;
pub use device::{
    CyclicDevice, Description, Device, DeviceError, Error, ErrorKind, Lifecycle, Operation,
    ProtocolError, State,
};
#[cfg(feature = "std")]
pub use ethercat::EthercatDrives;
#[cfg(feature = "std")]
pub use franka::FrankaArm;
#[cfg(feature = "std")]
pub use mitsubishi_h7::MitsubishiH7;
#[cfg(feature = "std")]
pub use robotiq::RobotiqGripper;
#[cfg(feature = "std")]
pub use ur::UniversalRobot;
