//! What the controller needs of a device, as capabilities: any driver that has them is a
//! [`JointRobot`]; the controller names no driver.

use rl_drivers::{
    CyclicDevice, Error, JointPositionActuator, JointPositionSensor, LinkStatisticsSensor,
};

/// A device the controller can drive: cyclic, joint positions in and out, and link statistics.
/// Optional capabilities (a feed-forward torque input, a limit report) are found at run time
/// through [`JointDevice`](rl_drivers::JointDevice)'s provided methods. `Box<dyn JointRobot +
/// Send>` is one too, so a program can pick its driver at run time.
pub trait JointRobot:
    CyclicDevice<Error = Error> + JointPositionActuator + JointPositionSensor + LinkStatisticsSensor
{
}

impl<T> JointRobot for T where
    T: CyclicDevice<Error = Error>
        + JointPositionActuator
        + JointPositionSensor
        + LinkStatisticsSensor
        + ?Sized
{
}
