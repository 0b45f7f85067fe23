//! The canary's computation, shared by the bare-metal binary (`main.rs`) and a host test that
//! checks it: a 6-axis arm from compile-time constants, a rest-to-rest quintic, and per control
//! step forward kinematics, RNEA and ABA. `no_std` except when compiled for the host's tests.
#![cfg_attr(not(test), no_std)]

use core::f64::consts::{FRAC_PI_2, PI, TAU};
use glam::{DMat3, DQuat, DVec3};
use rl_core::joint::{Joint, Revolute};
use rl_core::model::{JointLimits, ROOT};
use rl_core::spatial::{PlueckerTransform, RigidBodyInertia};
use rl_core::traj::{Limits, Polynomial, Trajectory};
use rl_core::{Data, Model, ModelBuilder};

/// Number of axes of the baked-in arm.
pub const DOF: usize = 6;

/// One link in modified Denavit–Hartenberg form (Craig): the joint frame sits at
/// `Rot_x(alpha) · Trans_x(a) · Trans_z(d)` in the previous link's frame and turns about z.
pub struct Link {
    /// Link twist α (rad).
    pub alpha: f64,
    /// Link length a (m).
    pub a: f64,
    /// Link offset d (m).
    pub d: f64,
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass in the link frame (m).
    pub com: [f64; 3],
    /// Principal moments of inertia about the centre of mass (kg m²).
    pub inertia: [f64; 3],
    /// Position limit ± (rad), velocity limit (rad/s), effort limit (N m).
    pub limits: [f64; 3],
}

/// A UR5-class arm (DH lengths and masses of the UR5), fixed at compile time.
#[rustfmt::skip]
pub const ARM: [Link; DOF] = [
    Link { alpha: 0.0, a: 0.0, d: 0.089159, mass: 3.7, com: [0.0, -0.02561, 0.00193], inertia: [0.0084, 0.0064, 0.0084], limits: [TAU, 3.15, 150.0] },
    Link { alpha: FRAC_PI_2, a: 0.0, d: 0.0, mass: 8.393, com: [0.2125, 0.0, 0.11336], inertia: [0.0078, 0.2100, 0.2100], limits: [TAU, 3.15, 150.0] },
    Link { alpha: 0.0, a: -0.425, d: 0.0, mass: 2.275, com: [0.15, 0.0, 0.0265], inertia: [0.0016, 0.0462, 0.0462], limits: [PI, 3.15, 150.0] },
    Link { alpha: 0.0, a: -0.39225, d: 0.10915, mass: 1.219, com: [0.0, -0.0018, 0.01634], inertia: [0.0016, 0.0016, 0.0009], limits: [TAU, 3.2, 28.0] },
    Link { alpha: FRAC_PI_2, a: 0.0, d: 0.09465, mass: 1.219, com: [0.0, 0.0018, 0.01634], inertia: [0.0016, 0.0016, 0.0009], limits: [TAU, 3.2, 28.0] },
    Link { alpha: -FRAC_PI_2, a: 0.0, d: 0.0823, mass: 0.1879, com: [0.0, 0.0, -0.001159], inertia: [0.0001, 0.0001, 0.0001], limits: [TAU, 3.2, 28.0] },
];

/// Start and goal of the trajectory (rad).
pub const Q_START: [f64; DOF] = [0.0, -1.2, 1.0, -0.4, 1.5, 0.0];
/// Goal of the trajectory (rad).
pub const Q_GOAL: [f64; DOF] = [1.0, -0.6, 0.4, 0.3, 0.9, 0.8];
/// Joint-space velocity, acceleration and jerk limits for the at-rest quintic.
pub const TRAJ_LIMITS: Limits<DOF> = Limits::uniform(1.0, 3.0, 30.0);

/// Results of one control step, kept in a static so the optimiser must compute them.
#[derive(Clone, Copy)]
pub struct Outputs {
    /// Tool flange position in the world (m).
    pub flange: [f64; 3],
    /// Feed-forward joint torques from RNEA (N m).
    pub tau: [f64; DOF],
    /// Joint accelerations from ABA under those torques (rad/s²).
    pub qdd: [f64; DOF],
    /// Error code: 0 = all calls succeeded.
    pub error: u32,
}

/// Builds the arm from [`ARM`]. Returns `None` if the builder rejects it (it does not: the
/// table is valid, and a host test of the same table would say so).
pub fn build_arm() -> Option<Model<DOF>> {
    let mut b = ModelBuilder::<DOF>::new();
    b.name("canary-arm").ok()?;
    b.gravity(DVec3::new(0.0, 0.0, -9.81));
    let mut parent = ROOT;
    for (i, l) in ARM.iter().enumerate() {
        let placement = PlueckerTransform::from_quat_translation(
            DQuat::from_rotation_x(l.alpha),
            DQuat::from_rotation_x(l.alpha) * DVec3::new(l.a, 0.0, l.d),
        );
        let inertia = RigidBodyInertia::from_com(
            l.mass,
            DVec3::from_array(l.com),
            DMat3::from_diagonal(DVec3::from_array(l.inertia)),
        );
        const JOINTS: [&str; DOF] = ["j1", "j2", "j3", "j4", "j5", "j6"];
        const LINKS: [&str; DOF] = ["l1", "l2", "l3", "l4", "l5", "l6"];
        let joint = Joint::Revolute(Revolute::new(DVec3::Z));
        parent = b
            .add_body(parent, JOINTS[i], joint, placement, LINKS[i], inertia)
            .ok()?;
        let [pos, vel, eff] = l.limits;
        b.set_limits(
            parent,
            0,
            JointLimits {
                lower: -pos,
                upper: pos,
                velocity: vel,
                effort: eff,
                wraparound: false,
            },
        )
        .ok()?;
    }
    b.add_tool("flange", parent, PlueckerTransform::IDENTITY)
        .ok()?;
    Some(b.build())
}

/// One control step at time `t`: trajectory sample, forward kinematics of the flange,
/// inverse dynamics feed-forward (RNEA) and the forward dynamics check (ABA).
pub fn control_step(
    model: &Model<DOF>,
    data: &mut Data<DOF>,
    traj: &Polynomial<DOF, 6>,
    t: f64,
) -> Result<Outputs, rl_core::Error> {
    let s = traj.sample(t);
    rl_core::algo::forward_position(model, data, &s.position)?;
    let flange = rl_core::algo::tool_pose(model, data, 0)?
        .translation
        .to_array();
    let mut tau = [0.0; DOF];
    tau.copy_from_slice(rl_core::algo::rnea(
        model,
        data,
        &s.position,
        &s.velocity,
        &s.acceleration,
    )?);
    let mut qdd = [0.0; DOF];
    qdd.copy_from_slice(rl_core::algo::aba(
        model,
        data,
        &s.position,
        &s.velocity,
        &tau,
    )?);
    Ok(Outputs {
        flange,
        tau,
        qdd,
        error: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_baked_in_arm_builds() {
        let model = build_arm().expect("the ARM table is a valid model");
        assert_eq!((model.body_count(), model.dof()), (DOF, DOF));
    }

    #[test]
    fn aba_inverts_rnea_along_the_trajectory() {
        // The bare-metal binary is linked, not run; this runs the same computation on the host
        // and checks it: ABA of RNEA's torques gives back the planned acceleration.
        let model = build_arm().expect("valid model");
        let mut data = Data::<DOF>::new();
        let traj = Polynomial::quintic_at_rest(Q_START, Q_GOAL, &TRAJ_LIMITS).expect("trajectory");
        let steps = 50;
        for k in 0..=steps {
            let t = traj.duration() * k as f64 / steps as f64;
            let out = control_step(&model, &mut data, &traj, t).expect("control step");
            let planned = traj.sample(t).acceleration;
            assert_eq!(out.error, 0);
            assert!(out.flange.iter().all(|x| x.is_finite()), "flange at t={t}");
            assert!(
                out.tau.iter().any(|x| x.abs() > 0.1),
                "gravity load at t={t}"
            );
            for (j, (a, b)) in out.qdd.iter().zip(planned).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-9 * (1.0 + b.abs()),
                    "axis {j} at t={t}: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn the_flange_moves_from_start_to_goal() {
        let model = build_arm().expect("valid model");
        let mut data = Data::<DOF>::new();
        let traj = Polynomial::quintic_at_rest(Q_START, Q_GOAL, &TRAJ_LIMITS).expect("trajectory");
        let a = control_step(&model, &mut data, &traj, 0.0)
            .expect("start")
            .flange;
        let b = control_step(&model, &mut data, &traj, traj.duration())
            .expect("goal")
            .flange;
        let dist = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
        // A UR5-sized arm (reach ~0.85 m) moved by up to 1 rad per joint: decimetres.
        assert!(dist > 0.05 && dist < 2.0, "flange moved {dist} m");
    }
}
