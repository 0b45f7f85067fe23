//! The fake robot's arm: the motion generators' checks (what the robot refuses in a command
//! stream: a first command away from where it stands, positions and velocities beyond the
//! limits, accelerations and jerks beyond them, torque jumps) and the arm itself — kinematic
//! (the joints are where the motion generator puts them) or, with a model, dynamic: the robot's
//! joint controller (computed torque, RNEA) or the client's torques plus gravity compensation
//! move the joints through rl-core's ABA, integrated at the robot's 1 ms.

use rl_core::model::{Data, Model};
use rl_core::spatial::PlueckerTransform;

use crate::franka::DOF;
use crate::franka::errors::{ErrorSet, RobotError};
use crate::franka::limits::{
    DELTA_T, JointLimits, MAX_JOINT_ACCELERATION, MAX_JOINT_JERK, MAX_TORQUE_RATE,
};

/// Model capacity of the fake's dynamics (an arm with a hand fits).
pub(crate) const CAPACITY: usize = 32;

/// How far a joint position generator's first command may be from where the robot stands.
pub(crate) const START_TOLERANCE: f64 = 1e-3;
/// Relative slack of the rate checks, for the rounding of differences of `f64` positions.
const RATE_SLACK: f64 = 1e-6;

/// Gains of the robot's internal joint controller (rad/s², per rad and per rad/s): a natural
/// frequency of 50 rad/s, critically damped.
const KP: f64 = 2500.0;
const KD: f64 = 100.0;

/// The arm's dynamics: an rl-core model of the arm and the frame of its flange.
pub(crate) struct Dynamics {
    pub(crate) model: Box<Model<CAPACITY>>,
    pub(crate) data: Box<Data<CAPACITY>>,
    /// The flange: a body and a placement on it.
    pub(crate) flange: (usize, PlueckerTransform),
}

impl core::fmt::Debug for Dynamics {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("Dynamics(..)")
    }
}

/// What the client's current motion commands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Generator {
    /// No motion: the robot holds its position.
    Hold,
    /// Joint positions.
    Position,
    /// Joint velocities.
    Velocity,
    /// Torques (no motion generator).
    Torque,
}

/// The commanded signal as the robot tracks it: position, velocity, acceleration.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Signal {
    q: [f64; DOF],
    v: [f64; DOF],
    a: [f64; DOF],
}

/// The simulated arm.
#[derive(Debug)]
pub(crate) struct Arm {
    pub(crate) limits: [JointLimits; DOF],
    pub(crate) dynamics: Option<Dynamics>,
    pub(crate) q: [f64; DOF],
    pub(crate) dq: [f64; DOF],
    /// Measured torques (gravity included).
    pub(crate) tau_j: [f64; DOF],
    /// Desired torques (without gravity).
    pub(crate) tau_j_d: [f64; DOF],
    /// Gravity at `q`.
    pub(crate) gravity: [f64; DOF],
    signal: Signal,
    /// Whether the motion's first command is still to come.
    first: bool,
    /// Torques clipped at the effort limits.
    pub(crate) torque_clips: u64,
}

impl Arm {
    pub(crate) fn new(
        limits: [JointLimits; DOF],
        q: [f64; DOF],
        dynamics: Option<Dynamics>,
    ) -> Self {
        let mut arm = Self {
            limits,
            dynamics,
            q,
            dq: [0.0; DOF],
            tau_j: [0.0; DOF],
            tau_j_d: [0.0; DOF],
            gravity: [0.0; DOF],
            signal: Signal {
                q,
                v: [0.0; DOF],
                a: [0.0; DOF],
            },
            first: true,
            torque_clips: 0,
        };
        arm.update_gravity();
        arm.tau_j = arm.gravity;
        arm
    }

    /// Desired position, velocity, acceleration.
    pub(crate) fn desired(&self) -> ([f64; DOF], [f64; DOF], [f64; DOF]) {
        (self.signal.q, self.signal.v, self.signal.a)
    }

    /// A motion starts: the commanded signal starts where the robot stands, at rest.
    pub(crate) fn begin(&mut self) {
        self.signal = Signal {
            q: self.signal.q,
            v: [0.0; DOF],
            a: [0.0; DOF],
        };
        self.tau_j_d = [0.0; DOF];
        self.first = true;
    }

    /// The arm stops where it is (a reflex: brakes; or the end of a motion).
    pub(crate) fn halt(&mut self) {
        self.dq = [0.0; DOF];
        self.signal = Signal {
            q: self.q,
            v: [0.0; DOF],
            a: [0.0; DOF],
        };
        self.tau_j_d = [0.0; DOF];
    }

    fn update_gravity(&mut self) {
        if let Some(d) = &mut self.dynamics
            && let Ok(g) = rl_core::algo::gravity(&d.model, &mut d.data, &self.q)
        {
            self.gravity.copy_from_slice(g);
        }
    }

    /// Checks a new commanded signal against the limits; returns the violations.
    fn check_signal(&self, next: &Signal) -> ErrorSet {
        let mut e = ErrorSet::EMPTY;
        for i in 0..DOF {
            let l = &self.limits[i];
            if next.q[i] < l.lower || next.q[i] > l.upper {
                e = e.with(RobotError::JointMotionGeneratorPositionLimitsViolation);
            }
            let slack = |limit: f64| limit.abs() * RATE_SLACK + 1e-9;
            if next.v[i] > l.upper_velocity(next.q[i]) + slack(l.velocity)
                || next.v[i] < l.lower_velocity(next.q[i]) - slack(l.velocity)
            {
                e = e.with(RobotError::JointMotionGeneratorVelocityLimitsViolation);
            }
            if next.a[i].abs() > MAX_JOINT_ACCELERATION * (1.0 + RATE_SLACK) {
                e = e.with(RobotError::JointMotionGeneratorVelocityDiscontinuity);
            }
            let jerk = (next.a[i] - self.signal.a[i]) / DELTA_T;
            if jerk.abs() > MAX_JOINT_JERK * (1.0 + RATE_SLACK) {
                e = e.with(RobotError::JointMotionGeneratorAccelerationDiscontinuity);
            }
        }
        e
    }

    /// One millisecond of `generator` with this cycle's command (`None`: the command was lost,
    /// and the robot extrapolates at constant acceleration, or holds the torque). Returns the
    /// violations the robot raises.
    pub(crate) fn tick(
        &mut self,
        generator: Generator,
        q_c: Option<&[f64; DOF]>,
        dq_c: Option<&[f64; DOF]>,
        tau_c: Option<&[f64; DOF]>,
    ) -> ErrorSet {
        let mut errors = ErrorSet::EMPTY;
        let s = self.signal;
        match generator {
            Generator::Hold | Generator::Torque => {}
            Generator::Position | Generator::Velocity => {
                let next = match (generator, q_c, dq_c) {
                    (Generator::Position, Some(q), _) => {
                        if self.first && (0..DOF).any(|i| (q[i] - s.q[i]).abs() > START_TOLERANCE) {
                            errors = errors
                                .with(RobotError::JointPositionMotionGeneratorStartPoseInvalid);
                        }
                        let v: [f64; DOF] = core::array::from_fn(|i| (q[i] - s.q[i]) / DELTA_T);
                        Signal {
                            q: *q,
                            v,
                            a: core::array::from_fn(|i| (v[i] - s.v[i]) / DELTA_T),
                        }
                    }
                    (Generator::Velocity, _, Some(v)) => Signal {
                        q: core::array::from_fn(|i| s.q[i] + v[i] * DELTA_T),
                        v: *v,
                        a: core::array::from_fn(|i| (v[i] - s.v[i]) / DELTA_T),
                    },
                    // Lost: constant acceleration.
                    _ => {
                        let v: [f64; DOF] = core::array::from_fn(|i| s.v[i] + s.a[i] * DELTA_T);
                        Signal {
                            q: core::array::from_fn(|i| s.q[i] + v[i] * DELTA_T),
                            v,
                            a: s.a,
                        }
                    }
                };
                if q_c.is_some() || dq_c.is_some() {
                    self.first = false;
                    errors = errors.union(self.check_signal(&next));
                }
                self.signal = next;
            }
        }
        if generator == Generator::Torque
            && let Some(tau) = tau_c
        {
            let rate_limit = MAX_TORQUE_RATE * (1.0 + RATE_SLACK);
            if tau
                .iter()
                .zip(&self.tau_j_d)
                .any(|(t, before)| ((t - before) / DELTA_T).abs() > rate_limit)
            {
                errors = errors.with(RobotError::ControllerTorqueDiscontinuity);
            }
            self.tau_j_d = *tau;
        }
        if !errors.is_empty() {
            return errors;
        }
        self.integrate(generator);
        for i in 0..DOF {
            let l = &self.limits[i];
            if self.q[i] < l.lower || self.q[i] > l.upper {
                errors = errors.with(RobotError::JointPositionLimitsViolation);
            }
            if self.dq[i].abs() > l.velocity {
                errors = errors.with(RobotError::JointVelocityViolation);
            }
        }
        errors
    }

    /// Moves the arm by one cycle.
    fn integrate(&mut self, generator: Generator) {
        let Some(d) = &mut self.dynamics else {
            // Kinematic: the joints are where the generator puts them; torques do not move them.
            if generator != Generator::Torque {
                self.q = self.signal.q;
                self.dq = if generator == Generator::Hold {
                    [0.0; DOF]
                } else {
                    self.signal.v
                };
            }
            self.tau_j = self.tau_j_d;
            return;
        };
        let mut tau = [0.0; DOF];
        if generator == Generator::Torque {
            let g = rl_core::algo::gravity(&d.model, &mut d.data, &self.q);
            if let Ok(g) = g {
                for i in 0..DOF {
                    tau[i] = self.tau_j_d[i] + g[i];
                }
            }
        } else {
            // The robot's joint controller: computed torque towards the desired signal.
            let (q_d, v_d, a_d) = (self.signal.q, self.signal.v, self.signal.a);
            let a_ref: [f64; DOF] = core::array::from_fn(|i| {
                a_d[i] + KP * (q_d[i] - self.q[i]) + KD * (v_d[i] - self.dq[i])
            });
            if let Ok(t) = rl_core::algo::rnea(&d.model, &mut d.data, &self.q, &self.dq, &a_ref) {
                tau.copy_from_slice(t);
            }
        }
        for (t, l) in tau.iter_mut().zip(&self.limits) {
            if t.abs() > l.effort {
                *t = t.clamp(-l.effort, l.effort);
                self.torque_clips += 1;
            }
        }
        if let Ok(qdd) = rl_core::algo::aba(&d.model, &mut d.data, &self.q, &self.dq, &tau) {
            // Semi-implicit Euler: the new velocity moves the joint.
            for ((q, dq), a) in self.q.iter_mut().zip(&mut self.dq).zip(qdd) {
                *dq += a * DELTA_T;
                *q += *dq * DELTA_T;
            }
        }
        self.tau_j = tau;
        self.update_gravity();
    }

    /// The flange's pose (column-major 4×4), with a model; the identity without.
    pub(crate) fn flange_pose(&mut self) -> [f64; 16] {
        let Some(d) = &mut self.dynamics else {
            return crate::franka::state::IDENTITY;
        };
        if rl_core::algo::forward_position(&d.model, &mut d.data, &self.q).is_err() {
            return crate::franka::state::IDENTITY;
        }
        let (body, placement) = d.flange;
        let p = *d.data.world_pose(body) * placement;
        to_matrix(&p)
    }
}

/// A transform as a column-major 4×4 matrix.
pub(crate) fn to_matrix(p: &PlueckerTransform) -> [f64; 16] {
    let r = p.rotation;
    let t = p.translation;
    [
        r.x_axis.x, r.x_axis.y, r.x_axis.z, 0.0, r.y_axis.x, r.y_axis.y, r.y_axis.z, 0.0,
        r.z_axis.x, r.z_axis.y, r.z_axis.z, 0.0, t.x, t.y, t.z, 1.0,
    ]
}

/// A column-major 4×4 matrix as a transform.
pub(crate) fn from_matrix(m: &[f64; 16]) -> PlueckerTransform {
    PlueckerTransform::new(
        glam::DMat3::from_cols_array(&[m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]]),
        glam::DVec3::new(m[12], m[13], m[14]),
    )
}

/// Whether `m` is a homogeneous transform (orthonormal rotation, last row 0 0 0 1).
pub(crate) fn is_transform(m: &[f64; 16]) -> bool {
    if m.iter().any(|x| !x.is_finite()) {
        return false;
    }
    if (m[3].abs() + m[7].abs() + m[11].abs()) > 1e-6 || (m[15] - 1.0).abs() > 1e-6 {
        return false;
    }
    let r = from_matrix(m).rotation;
    let rtr = r.transpose() * r;
    (rtr - glam::DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .all(|x| x.abs() < 1e-3)
        && (r.determinant() - 1.0).abs() < 1e-3
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::franka::limits::FR3;

    const READY: [f64; DOF] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];

    #[test]
    fn a_smooth_position_stream_passes_and_jumps_are_refused() {
        let mut arm = Arm::new(FR3, READY, None);
        arm.begin();
        // Accelerate joint 0 at 5 rad/s² with a jerk-limited start.
        let mut q = READY;
        let (mut v, mut a) = (0.0, 0.0);
        for _ in 0..100 {
            a = f64::min(a + 4000.0 * DELTA_T, 5.0);
            v += a * DELTA_T;
            q[0] += v * DELTA_T;
            let e = arm.tick(Generator::Position, Some(&q), None, None);
            assert!(e.is_empty(), "{e}");
        }
        assert_eq!(arm.q, q, "kinematic: the joints are the command");
        // A step of 1 mrad at rest: 1 rad/s in a millisecond is a velocity discontinuity.
        let mut arm = Arm::new(FR3, READY, None);
        arm.begin();
        let mut q = READY;
        assert!(
            arm.tick(Generator::Position, Some(&q), None, None)
                .is_empty()
        );
        q[3] += 1e-3;
        let e = arm.tick(Generator::Position, Some(&q), None, None);
        assert!(
            e.contains(RobotError::JointMotionGeneratorVelocityDiscontinuity),
            "{e}"
        );
        assert!(
            e.contains(RobotError::JointMotionGeneratorAccelerationDiscontinuity),
            "{e}"
        );
    }

    #[test]
    fn the_first_command_must_be_where_the_robot_stands() {
        let mut arm = Arm::new(FR3, READY, None);
        arm.begin();
        let mut q = READY;
        q[1] += 0.01;
        let e = arm.tick(Generator::Position, Some(&q), None, None);
        assert!(
            e.contains(RobotError::JointPositionMotionGeneratorStartPoseInvalid),
            "{e}"
        );
    }

    #[test]
    fn torque_jumps_beyond_one_newton_metre_per_millisecond_are_refused() {
        let mut arm = Arm::new(FR3, READY, None);
        arm.begin();
        let mut tau = [0.0; DOF];
        tau[0] = 0.9;
        assert!(
            arm.tick(Generator::Torque, None, None, Some(&tau))
                .is_empty()
        );
        tau[0] = 2.0;
        let e = arm.tick(Generator::Torque, None, None, Some(&tau));
        assert!(e.contains(RobotError::ControllerTorqueDiscontinuity), "{e}");
    }

    #[test]
    fn matrices_and_transforms_agree() {
        let p = PlueckerTransform::new(
            glam::DMat3::from_rotation_z(0.3),
            glam::DVec3::new(0.1, 0.2, 0.3),
        );
        let m = to_matrix(&p);
        assert!(is_transform(&m));
        assert_eq!(from_matrix(&m).translation, p.translation);
        let mut bad = m;
        bad[0] = 2.0;
        assert!(!is_transform(&bad));
    }
}

#[cfg(test)]
mod lost_runs {
    use super::*;
    use crate::franka::limits::FR3;

    /// Lost commands are filled in at constant acceleration; where the path's acceleration
    /// changes, the gap leaves a position error that the first command after it turns into an
    /// acceleration jump. On `0.2 (1 − cos πt)` (jerk ≤ 6.2 rad/s³) runs of 8 lost commands
    /// pass and runs of 15 do not — as the FCI documentation warns, lost packets cause
    /// discontinuities.
    #[test]
    fn long_runs_of_lost_commands_on_a_curved_path_are_discontinuities() {
        let ready = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
        let path = |k: usize| {
            let mut q = ready;
            q[3] += 0.2 * (1.0 - (std::f64::consts::PI * k as f64 * 1e-3).cos());
            q
        };
        let run = |lost_len: usize| {
            let mut arm = Arm::new(FR3, ready, None);
            arm.begin();
            (0..1500)
                .map(|k| {
                    let lost = k % 100 >= 50 && k % 100 < 50 + lost_len;
                    let q = path(k);
                    arm.tick(Generator::Position, (!lost).then_some(&q), None, None)
                })
                .fold(ErrorSet::EMPTY, ErrorSet::union)
        };
        assert!(run(8).is_empty(), "{}", run(8));
        assert!(run(15).contains(RobotError::JointMotionGeneratorAccelerationDiscontinuity));
    }
}
