//! The fake controller's arm: joint targets from `servoj`, `speedj`, `movej` and `stopj`, the
//! measured joints following them, the joint speed limit a target may not exceed, and the tool
//! pose (a UR's Denavit–Hartenberg kinematics, or a model's).
//!
//! `servoj`'s lookahead smooths the commands: the target joints follow them as a first-order
//! lag of the lookahead time, so one late or doubled command is evened out and only a
//! sustained speed beyond a joint's limit stops the arm. The measured joints follow the targets
//! a few milliseconds behind ([`DRIVE_LAG`]).

use crate::fake::h7_controller::ForwardKinematics;

/// The controller's cycle, s.
pub(crate) const DT: f64 = 0.002;

/// The lag of the measured joints behind the targets, s.
pub(crate) const DRIVE_LAG: f64 = 0.004;

/// A UR arm's kinematics (standard Denavit–Hartenberg, Universal Robots' published values).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UrKinematics {
    /// The model's name (`UR5e`…), as the dashboard reports it.
    pub name: &'static str,
    /// `d`, m.
    pub d: [f64; 6],
    /// `a`, m.
    pub a: [f64; 6],
    /// `α`, rad.
    pub alpha: [f64; 6],
    /// Largest joint speeds, rad/s.
    pub max_speed: [f64; 6],
}

const HALF_PI: f64 = core::f64::consts::FRAC_PI_2;
const PI: f64 = core::f64::consts::PI;

impl UrKinematics {
    /// The UR5e.
    pub const UR5E: Self = Self {
        name: "UR5e",
        d: [0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996],
        a: [0.0, -0.425, -0.3922, 0.0, 0.0, 0.0],
        alpha: [HALF_PI, 0.0, 0.0, HALF_PI, -HALF_PI, 0.0],
        max_speed: [PI; 6],
    };

    /// The UR10e.
    pub const UR10E: Self = Self {
        name: "UR10e",
        d: [0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655],
        a: [0.0, -0.6127, -0.57155, 0.0, 0.0, 0.0],
        alpha: [HALF_PI, 0.0, 0.0, HALF_PI, -HALF_PI, 0.0],
        max_speed: [2.0 * PI / 3.0, 2.0 * PI / 3.0, PI, PI, PI, PI],
    };

    /// The tool pose at `q`: `[x, y, z, rx, ry, rz]` (m, rotation vector in rad), as RTDE's
    /// `actual_TCP_pose`.
    pub fn tcp_pose(&self, q: &[f64; 6]) -> [f64; 6] {
        #![allow(clippy::needless_range_loop)] // joints and matrices indexed alike
        // 4×4 homogeneous transforms, row-major.
        let mut t = [[0.0f64; 4]; 4];
        for (i, row) in t.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        for j in 0..6 {
            let (st, ct) = q[j].sin_cos();
            let (sa, ca) = self.alpha[j].sin_cos();
            let a = [
                [ct, -st * ca, st * sa, self.a[j] * ct],
                [st, ct * ca, -ct * sa, self.a[j] * st],
                [0.0, sa, ca, self.d[j]],
                [0.0, 0.0, 0.0, 1.0],
            ];
            let mut n = [[0.0; 4]; 4];
            for r in 0..4 {
                for c in 0..4 {
                    n[r][c] = (0..4).map(|k| t[r][k] * a[k][c]).sum();
                }
            }
            t = n;
        }
        let r = glam::DMat3::from_cols(
            glam::DVec3::new(t[0][0], t[1][0], t[2][0]),
            glam::DVec3::new(t[0][1], t[1][1], t[2][1]),
            glam::DVec3::new(t[0][2], t[1][2], t[2][2]),
        );
        let (axis, angle) = glam::DQuat::from_mat3(&r).to_axis_angle();
        let v = axis * angle;
        [t[0][3], t[1][3], t[2][3], v.x, v.y, v.z]
    }
}

/// What moves the targets.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Motion {
    Hold,
    /// `servoj`: reach `q` within the call's time.
    Servo {
        q: [f64; 6],
        lookahead: f64,
    },
    /// `speedj`: reach `qd` at acceleration `a`.
    Speed {
        qd: [f64; 6],
        a: f64,
    },
    /// `movej`: a synchronised linear move at `v` (rad/s of the leading joint).
    Move {
        q: [f64; 6],
        v: f64,
    },
    /// `stopj`: decelerate at `a`.
    Stop {
        a: f64,
    },
}

/// The arm.
#[derive(Clone, Debug)]
pub(crate) struct Arm {
    pub kin: UrKinematics,
    pub model: Option<ForwardKinematics>,
    /// Measured joints and speeds.
    pub q: [f64; 6],
    pub qd: [f64; 6],
    /// Target joints, speeds, accelerations.
    pub target_q: [f64; 6],
    pub target_qd: [f64; 6],
    pub target_qdd: [f64; 6],
    motion: Motion,
}

impl Arm {
    pub(crate) fn new(kin: UrKinematics, model: Option<ForwardKinematics>, q: [f64; 6]) -> Self {
        Self {
            kin,
            model,
            q,
            qd: [0.0; 6],
            target_q: q,
            target_qd: [0.0; 6],
            target_qdd: [0.0; 6],
            motion: Motion::Hold,
        }
    }

    pub(crate) fn servo(&mut self, q: [f64; 6], lookahead: f64) {
        self.motion = Motion::Servo {
            q,
            lookahead: lookahead.clamp(0.03, 0.2),
        };
    }

    pub(crate) fn speed(&mut self, qd: [f64; 6], a: f64) {
        self.motion = Motion::Speed { qd, a: a.max(1e-3) };
    }

    pub(crate) fn move_to(&mut self, q: [f64; 6], v: f64) {
        self.motion = Motion::Move { q, v: v.max(1e-3) };
    }

    pub(crate) fn stop(&mut self, a: f64) {
        self.motion = Motion::Stop { a: a.max(1e-3) };
    }

    /// Stops the targets at once (a protective stop, the end of a program).
    pub(crate) fn halt(&mut self) {
        self.motion = Motion::Hold;
        self.target_qd = [0.0; 6];
        self.target_qdd = [0.0; 6];
    }

    /// Whether a `movej` or `stopj` is done.
    pub(crate) fn motion_done(&self) -> bool {
        match self.motion {
            Motion::Move { q, .. } => q == self.target_q,
            Motion::Stop { .. } => self.target_qd.iter().all(|v| *v == 0.0),
            _ => true,
        }
    }

    /// One cycle. `Err(joint)` if a target would exceed the joint's speed limit (the
    /// controller then stops: a protective stop).
    pub(crate) fn advance(&mut self, speed_fraction: f64) -> Result<(), usize> {
        #![allow(clippy::needless_range_loop)] // six arrays indexed alike
        let before = self.target_q;
        let old_qd = self.target_qd;
        match self.motion {
            Motion::Hold => self.target_qd = [0.0; 6],
            Motion::Servo { q, lookahead } => {
                let k = DT / (lookahead + DT);
                for j in 0..6 {
                    self.target_q[j] += (q[j] - self.target_q[j]) * k;
                }
            }
            Motion::Speed { qd, a } => {
                for j in 0..6 {
                    let want = qd[j] * speed_fraction;
                    let dv = (want - self.target_qd[j]).clamp(-a * DT, a * DT);
                    self.target_qd[j] += dv;
                    self.target_q[j] += self.target_qd[j] * DT;
                }
            }
            Motion::Move { q, v } => {
                let v = v * speed_fraction;
                let lead = (0..6)
                    .map(|j| (q[j] - self.target_q[j]).abs())
                    .fold(0.0, f64::max);
                if lead <= v * DT {
                    self.target_q = q;
                } else {
                    let s = v * DT / lead;
                    for j in 0..6 {
                        self.target_q[j] += (q[j] - self.target_q[j]) * s;
                    }
                }
            }
            Motion::Stop { a } => {
                for j in 0..6 {
                    let v = self.target_qd[j];
                    let dv = v.abs().min(a * DT);
                    self.target_qd[j] = v - dv.copysign(v);
                    self.target_q[j] += self.target_qd[j] * DT;
                }
            }
        }
        if !matches!(self.motion, Motion::Speed { .. } | Motion::Stop { .. }) {
            for j in 0..6 {
                self.target_qd[j] = (self.target_q[j] - before[j]) / DT;
            }
        }
        for j in 0..6 {
            self.target_qdd[j] = (self.target_qd[j] - old_qd[j]) / DT;
            if self.target_qd[j].abs() > self.kin.max_speed[j] * (1.0 + 1e-9) {
                self.target_q = before;
                return Err(j);
            }
        }
        // The measured joints follow with a first-order lag.
        let k = DT / (DRIVE_LAG + DT);
        for j in 0..6 {
            let q = self.q[j] + (self.target_q[j] - self.q[j]) * k;
            self.qd[j] = (q - self.q[j]) / DT;
            self.q[j] = q;
        }
        Ok(())
    }

    /// The tool pose at `q`.
    pub(crate) fn tcp_pose(&self, q: &[f64; 6]) -> [f64; 6] {
        if let Some(m) = &self.model
            && let Some(p) = m.pose(q)
        {
            let (axis, angle) = glam::DQuat::from_mat3(&p.rotation).to_axis_angle();
            let v = axis * angle;
            return [
                p.translation.x,
                p.translation.y,
                p.translation.z,
                v.x,
                v.y,
                v.z,
            ];
        }
        self.kin.tcp_pose(q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ur5e_at_zero_reaches_out_along_minus_x() {
        // At q = 0 the UR5e's tool is at x = a2 + a3 = -0.8172, y = -(d4 + d6) = -0.2329,
        // z = d1 - d5 = 0.0628 (Universal Robots' DH frame conventions).
        let p = UrKinematics::UR5E.tcp_pose(&[0.0; 6]);
        assert!((p[0] + 0.8172).abs() < 1e-9, "{p:?}");
        assert!((p[1] + 0.2329).abs() < 1e-9, "{p:?}");
        assert!((p[2] - 0.0628).abs() < 1e-9, "{p:?}");
    }

    #[test]
    fn servo_targets_are_smoothed_followed_and_speed_limited() {
        let mut arm = Arm::new(UrKinematics::UR5E, None, [0.0; 6]);
        arm.servo([0.004, 0.0, 0.0, 0.0, 0.0, 0.0], 0.05);
        arm.advance(1.0).unwrap();
        // One cycle of the lookahead's smoothing: 2/52 of the way.
        let first = 0.004 * DT / (0.05 + DT);
        assert!(
            (arm.target_q[0] - first).abs() < 1e-15,
            "{}",
            arm.target_q[0]
        );
        assert!((arm.target_qd[0] - first / DT).abs() < 1e-9);
        assert!(arm.q[0] > 0.0 && arm.q[0] < arm.target_q[0]);
        // One second on, the target and the measured joint are there.
        for _ in 0..500 {
            arm.advance(1.0).unwrap();
        }
        assert!((arm.target_q[0] - 0.004).abs() < 1e-9);
        assert!((arm.q[0] - 0.004).abs() < 1e-9);
        // A jump of 0.5 rad: the smoothed target would move 9.6 rad/s, beyond the UR5e's π.
        arm.servo([0.504, 0.0, 0.0, 0.0, 0.0, 0.0], 0.05);
        let before = arm.target_q;
        assert_eq!(arm.advance(1.0), Err(0));
        assert_eq!(arm.target_q, before, "the target did not move");
    }

    #[test]
    fn one_doubled_servo_step_is_smoothed_out() {
        // A client late by one cycle sends two cycles' motion at once: 2 rad/s for one cycle of
        // a 1 rad/s ramp. The lookahead evens it out; the limit is not reached.
        let mut arm = Arm::new(UrKinematics::UR5E, None, [0.0; 6]);
        let mut q = 0.0;
        for i in 0..200 {
            q += if i == 100 { 2.0 * DT } else { DT };
            arm.servo([q, 0.0, 0.0, 0.0, 0.0, 0.0], 0.1);
            arm.advance(1.0).unwrap();
            assert!(arm.target_qd[0] < 1.1, "{}", arm.target_qd[0]);
        }
    }
}
