//! A boxed device is a device: the device and joint capability traits are implemented for
//! `Box<D>` by forwarding, so a program can choose its driver at run time (a device table)
//! and hand `Box<dyn …>` to code that is generic over the capabilities.

use core::time::Duration;

use crate::{
    CyclicDevice, Device, JointDevice, JointLimitSensor, JointPositionActuator,
    JointPositionSensor, JointTorqueActuator, JointTorqueFeedForward, JointTorqueSensor,
    JointVelocityActuator, JointVelocitySensor, LinkStatistics, LinkStatisticsSensor, State,
};

impl<D: Device + ?Sized> Device for Box<D> {
    type Error = D::Error;

    fn open(&mut self) -> Result<(), Self::Error> {
        (**self).open()
    }
    fn start(&mut self) -> Result<(), Self::Error> {
        (**self).start()
    }
    fn stop(&mut self) -> Result<(), Self::Error> {
        (**self).stop()
    }
    fn close(&mut self) -> Result<(), Self::Error> {
        (**self).close()
    }
    fn state(&self) -> State {
        (**self).state()
    }
    fn fault(&self) -> Option<Self::Error> {
        (**self).fault()
    }
    fn stop_description(&self) -> &'static str {
        (**self).stop_description()
    }
}

impl<D: CyclicDevice + ?Sized> CyclicDevice for Box<D> {
    fn step(&mut self) -> Result<(), Self::Error> {
        (**self).step()
    }
    fn step_within(&mut self, budget: Duration) -> Result<(), Self::Error> {
        (**self).step_within(budget)
    }
    fn update_period(&self) -> Duration {
        (**self).update_period()
    }
    fn runs_own_cycle(&self) -> bool {
        (**self).runs_own_cycle()
    }
}

impl<D: JointDevice + ?Sized> JointDevice for Box<D> {
    fn dof(&self) -> usize {
        (**self).dof()
    }
    fn torque_feed_forward(
        &mut self,
    ) -> Option<&mut dyn JointTorqueFeedForward<Error = Self::Error>> {
        (**self).torque_feed_forward()
    }
    fn joint_limit_sensor(&self) -> Option<&dyn JointLimitSensor<Error = Self::Error>> {
        (**self).joint_limit_sensor()
    }
    fn joint_velocity_actuator(
        &mut self,
    ) -> Option<&mut dyn JointVelocityActuator<Error = Self::Error>> {
        (**self).joint_velocity_actuator()
    }
    fn joint_torque_actuator(
        &mut self,
    ) -> Option<&mut dyn JointTorqueActuator<Error = Self::Error>> {
        (**self).joint_torque_actuator()
    }
    fn joint_velocity_sensor(&self) -> Option<&dyn JointVelocitySensor<Error = Self::Error>> {
        (**self).joint_velocity_sensor()
    }
    fn joint_torque_sensor(&self) -> Option<&dyn JointTorqueSensor<Error = Self::Error>> {
        (**self).joint_torque_sensor()
    }
}

impl<D: JointPositionSensor + ?Sized> JointPositionSensor for Box<D> {
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Self::Error> {
        (**self).joint_position(q)
    }
    fn joint_position_resolution(&self, q: f64) -> f64 {
        (**self).joint_position_resolution(q)
    }
    fn joint_position_sample(&self) -> Option<u64> {
        (**self).joint_position_sample()
    }
}

impl<D: JointPositionActuator + ?Sized> JointPositionActuator for Box<D> {
    fn set_joint_position(&mut self, q: &[f64]) -> Result<(), Self::Error> {
        (**self).set_joint_position(q)
    }
}

impl<D: JointVelocitySensor + ?Sized> JointVelocitySensor for Box<D> {
    fn joint_velocity(&self, qd: &mut [f64]) -> Result<(), Self::Error> {
        (**self).joint_velocity(qd)
    }
}

impl<D: JointVelocityActuator + ?Sized> JointVelocityActuator for Box<D> {
    fn set_joint_velocity(&mut self, qd: &[f64]) -> Result<(), Self::Error> {
        (**self).set_joint_velocity(qd)
    }
}

impl<D: JointTorqueSensor + ?Sized> JointTorqueSensor for Box<D> {
    fn joint_torque(&self, tau: &mut [f64]) -> Result<(), Self::Error> {
        (**self).joint_torque(tau)
    }
}

impl<D: JointTorqueActuator + ?Sized> JointTorqueActuator for Box<D> {
    fn set_joint_torque(&mut self, tau: &[f64]) -> Result<(), Self::Error> {
        (**self).set_joint_torque(tau)
    }
    fn adds_gravity(&self) -> bool {
        (**self).adds_gravity()
    }
    fn applied_joint_torque(&self, tau: &mut [f64]) -> bool {
        (**self).applied_joint_torque(tau)
    }
}

impl<D: LinkStatisticsSensor + ?Sized> LinkStatisticsSensor for Box<D> {
    fn link_statistics(&self) -> LinkStatistics {
        (**self).link_statistics()
    }
}
