//! What the fake takes from a robot's URDF: each arm joint's limits (`<limit>` and
//! `<position_based_velocity_limits>`, found by name as libfranka finds them: `joint1` …
//! `joint7`, exactly or as part of the name), and the dynamics (an rl-core model and the flange
//! frame, `link8` where there is one). Without a URDF the fake serves one it writes from the
//! FR3's limits: joints only, no inertias — enough for libfranka's velocity limits, not for
//! dynamics.

use std::fmt::Write as _;

use rl_core::loader::{UrdfOptions, load_str};

use super::arm::{CAPACITY, Dynamics};
use crate::franka::DOF;
use crate::franka::limits::{FR3, JointLimits};

/// The arm joints' limits in `urdf`; a joint without `<position_based_velocity_limits>` keeps
/// only its maximum speed. Errors name the joint and what is missing.
pub(crate) fn joint_limits(urdf: &str) -> Result<[JointLimits; DOF], String> {
    let doc = roxmltree::Document::parse(urdf).map_err(|e| format!("URDF: {e}"))?;
    let mut found: [Option<JointLimits>; DOF] = [None; DOF];
    for joint in doc.descendants().filter(|n| n.has_tag_name("joint")) {
        let Some(name) = joint.attribute("name") else {
            continue;
        };
        // `joint3`, `fr3_joint3`, `panda_joint3` (not `joint30`).
        let index = (1..=DOF).find(|k| name.ends_with(&format!("joint{k}")));
        let Some(k) = index else { continue };
        if found[k - 1].is_some() {
            continue;
        }
        let child = |tag: &str| joint.children().find(|c| c.has_tag_name(tag));
        let attr = |node: Option<roxmltree::Node<'_, '_>>, a: &str| -> Result<f64, String> {
            node.and_then(|n| n.attribute(a))
                .ok_or_else(|| format!("URDF joint {name}: no {a}"))?
                .parse::<f64>()
                .map_err(|e| format!("URDF joint {name}: {a}: {e}"))
        };
        let limit = child("limit");
        let pb = child("position_based_velocity_limits");
        found[k - 1] = Some(JointLimits {
            lower: attr(limit, "lower")?,
            upper: attr(limit, "upper")?,
            velocity: attr(limit, "velocity")?,
            effort: attr(limit, "effort")?,
            velocity_offset: if pb.is_some() {
                attr(pb, "velocity_offset")?
            } else {
                0.0
            },
            deceleration: if pb.is_some() {
                attr(pb, "deceleration_limit")?
            } else {
                f64::INFINITY
            },
        });
    }
    let mut out = FR3;
    for (k, f) in found.iter().enumerate() {
        out[k] = f.ok_or_else(|| format!("URDF: no joint{} (a Franka arm has 7)", k + 1))?;
    }
    Ok(out)
}

/// The arm's dynamics from `urdf` with the joints' `armature`: it must have 7 degrees of
/// freedom.
pub(crate) fn dynamics(urdf: &str, armature: &[f64; DOF]) -> Result<Dynamics, String> {
    let mut loaded =
        load_str::<CAPACITY>(urdf, &UrdfOptions::default()).map_err(|e| format!("URDF: {e}"))?;
    if loaded.model.dof() != DOF || loaded.model.nq() != DOF {
        return Err(format!(
            "URDF: {} degrees of freedom, a Franka arm has {DOF}",
            loaded.model.dof()
        ));
    }
    loaded
        .model
        .set_armature(armature)
        .map_err(|e| format!("armature: {e}"))?;
    let model = &loaded.model;
    let flange = loaded
        .frame_placement("link8")
        .or_else(|| {
            model
                .body_count()
                .checked_sub(1)
                .map(|b| (b, rl_core::spatial::PlueckerTransform::IDENTITY))
        })
        .ok_or("URDF: no bodies")?;
    Ok(Dynamics {
        data: Box::new(rl_core::model::Data::new()),
        model: Box::new(loaded.model),
        flange,
    })
}

/// A URDF of the FR3's joints and limits only (no geometry, no inertia), in the form libfranka
/// reads its velocity limits from.
pub(crate) fn limits_only_urdf(limits: &[JointLimits; DOF]) -> String {
    let mut s =
        String::from("<?xml version=\"1.0\" ?>\n<robot name=\"fr3\">\n  <link name=\"link0\"/>\n");
    for (k, l) in limits.iter().enumerate() {
        let _ = write!(
            s,
            "  <link name=\"link{n}\"/>\n  <joint name=\"joint{n}\" type=\"revolute\">\n    \
             <parent link=\"link{k}\"/>\n    <child link=\"link{n}\"/>\n    \
             <axis xyz=\"0 0 1\"/>\n    <limit effort=\"{}\" lower=\"{}\" upper=\"{}\" velocity=\"{}\"/>\n    \
             <position_based_velocity_limits deceleration_limit=\"{}\" velocity_offset=\"{}\"/>\n  \
             </joint>\n",
            l.effort,
            l.lower,
            l.upper,
            l.velocity,
            l.deceleration,
            l.velocity_offset,
            n = k + 1,
        );
    }
    s.push_str("</robot>\n");
    s
}

/// A URDF of an arm with the FR3's kinematics (franka_description's joint origins) and limits
/// but made-up inertias: each link a 2 kg (links 1–4) or 1 kg (links 5–7) body at the next
/// joint's half-way point with the inertia of a 5 cm sphere. For tests and demos of the
/// dynamics without the FR3's URDF; its numbers are not the FR3's.
pub(crate) fn fr3_shaped_urdf() -> String {
    use core::f64::consts::FRAC_PI_2 as H;
    // (xyz, roll) of joints 1..7 and of the flange link8.
    let origins: [([f64; 3], f64); 8] = [
        ([0.0, 0.0, 0.333], 0.0),
        ([0.0, 0.0, 0.0], -H),
        ([0.0, -0.316, 0.0], H),
        ([0.0825, 0.0, 0.0], H),
        ([-0.0825, 0.384, 0.0], -H),
        ([0.0, 0.0, 0.0], H),
        ([0.088, 0.0, 0.0], H),
        ([0.0, 0.0, 0.107], 0.0),
    ];
    let mut s = String::from(
        "<?xml version=\"1.0\" ?>\n<robot name=\"fr3_shaped\">\n  <link name=\"link0\"/>\n",
    );
    for (k, l) in FR3.iter().enumerate() {
        let n = k + 1;
        let ([x, y, z], roll) = origins[k];
        let [cx, cy, cz] = origins[k + 1].0.map(|c| c / 2.0);
        let mass = if n <= 4 { 2.0 } else { 1.0 };
        let i = 0.4 * mass * 0.05 * 0.05;
        let _ = write!(
            s,
            "  <link name=\"link{n}\">\n    <inertial>\n      <origin xyz=\"{cx} {cy} {cz}\"/>\n      \
             <mass value=\"{mass}\"/>\n      <inertia ixx=\"{i}\" ixy=\"0\" ixz=\"0\" iyy=\"{i}\" iyz=\"0\" izz=\"{i}\"/>\n    \
             </inertial>\n  </link>\n  <joint name=\"joint{n}\" type=\"revolute\">\n    \
             <origin rpy=\"{roll} 0 0\" xyz=\"{x} {y} {z}\"/>\n    <parent link=\"link{k}\"/>\n    \
             <child link=\"link{n}\"/>\n    <axis xyz=\"0 0 1\"/>\n    \
             <limit effort=\"{}\" lower=\"{}\" upper=\"{}\" velocity=\"{}\"/>\n    \
             <position_based_velocity_limits deceleration_limit=\"{}\" velocity_offset=\"{}\"/>\n  \
             </joint>\n",
            l.effort, l.lower, l.upper, l.velocity, l.deceleration, l.velocity_offset,
        );
    }
    let [x, y, z] = origins[7].0;
    let _ = write!(
        s,
        "  <link name=\"link8\"/>\n  <joint name=\"joint8\" type=\"fixed\">\n    \
         <origin rpy=\"0 0 0\" xyz=\"{x} {y} {z}\"/>\n    <parent link=\"link7\"/>\n    \
         <child link=\"link8\"/>\n  </joint>\n</robot>\n"
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_written_urdf_gives_back_its_limits() {
        let urdf = limits_only_urdf(&FR3);
        assert_eq!(joint_limits(&urdf).unwrap(), FR3);
        let missing = urdf.replace("joint7", "wrist");
        assert_eq!(
            joint_limits(&missing).unwrap_err(),
            "URDF: no joint7 (a Franka arm has 7)"
        );
        let bad = urdf.replacen("lower=\"-2.9007\"", "lower=\"x\"", 1);
        assert!(joint_limits(&bad).unwrap_err().contains("joint1: lower"));
    }

    #[test]
    fn the_fr3_shaped_arm_loads_with_seven_joints_and_its_flange() {
        let urdf = fr3_shaped_urdf();
        assert_eq!(joint_limits(&urdf).unwrap(), FR3);
        let d = dynamics(&urdf, &[0.0; DOF]).unwrap();
        assert_eq!(d.model.dof(), 7);
        assert_eq!(d.flange.1.translation.z, 0.107);
        // The armature reaches the arm's model; a negative one is refused, by joint.
        let a = [0.195, 0.195, 0.195, 0.195, 0.074, 0.074, 0.074];
        assert_eq!(dynamics(&urdf, &a).unwrap().model.armature(), &a);
        let mut bad = a;
        bad[4] = -0.1;
        let Err(e) = dynamics(&urdf, &bad) else {
            panic!("a negative armature was taken")
        };
        assert!(e.starts_with("armature: `armature` element 4"), "{e}");
    }
}
