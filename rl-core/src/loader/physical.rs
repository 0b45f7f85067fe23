//! Physical checks of a loaded model: inertias a rigid body can have, and joints that move
//! some mass.
//!
//! Inertias are checked on the model's bodies, each link merged with the links fixed to it,
//! which is what the dynamics use: a body that is not physical is an error naming its link or
//! a warning, as [`super::InertiaCheck`] says (by default: an error when the inertia is not
//! positive semi-definite, a warning when it breaks the triangle inequality).
//! A single link that is not physical inside a body that is (a sensor link with a made-up
//! inertia fixed to a heavy base) changes nothing the library computes and gets a warning.
//! Mass fixed to the world is never simulated: warnings only. See
//! [`RigidBodyInertia::check_physical`] for the rules (and the exception for massless bodies).
//!
//! A joint that moves no mass or inertia along its axis makes `M` singular: forward dynamics
//! and the mass-matrix solve will fail on it. The model still serves kinematics, so this is a
//! warning at load (checked at the neutral configuration) and an error naming the joint from
//! the algorithms.

use std::collections::HashSet;
use std::format;
use std::string::String;
use std::vec;
use std::vec::Vec;

use super::InertiaCheck;
use super::error::{ElementRef, LoadError, LoadErrorKind};
use crate::model::{Model, ROOT};
use crate::spatial::{InertiaProblem, PlueckerTransform, RigidBodyInertia};

/// A body's inertia as assembled: its own link and the links merged into it.
pub(crate) struct BodyInertia<'a> {
    /// The first link with mass in the body (for messages).
    pub link: &'a str,
    pub elem: &'a ElementRef,
    /// Other links with mass merged into it.
    pub merged_links: usize,
    pub inertia: RigidBodyInertia,
}

/// Whether `check` refuses `problem`.
fn refused(check: InertiaCheck, problem: &InertiaProblem) -> bool {
    match problem {
        InertiaProblem::NotFinite | InertiaProblem::NegativeMass { .. } => true,
        InertiaProblem::NotPositiveSemiDefinite { .. } => check != InertiaCheck::Lenient,
        InertiaProblem::TriangleInequality { .. } => check == InertiaCheck::Strict,
    }
}

/// Checks the bodies' inertias (errors or warnings by `check`) and links' own inertias
/// (`links`: name and inertia of every link with one, warnings only when its body passed).
pub(crate) fn check_inertias(
    bodies: &[BodyInertia],
    links: &[(&str, RigidBodyInertia, bool)],
    check: InertiaCheck,
    warnings: &mut Vec<String>,
) -> Result<(), LoadError> {
    for b in bodies {
        if let Err(problem) = b.inertia.check_physical() {
            if refused(check, &problem) {
                return Err(LoadError::at(
                    b.elem.clone(),
                    LoadErrorKind::UnphysicalInertia {
                        link: b.link.into(),
                        merged_links: b.merged_links,
                        problem,
                    },
                ));
            }
            warnings.push(format!(
                "link \"{}\"{}: inertia not physical: {problem}",
                b.link,
                with_merged(b.merged_links)
            ));
        }
    }
    // A link that is a body by itself was reported with it.
    let alone: HashSet<&str> = bodies
        .iter()
        .filter(|b| b.merged_links == 0)
        .map(|b| b.link)
        .collect();
    for (name, inertia, on_world) in links {
        let Err(problem) = inertia.check_physical() else {
            continue;
        };
        if matches!(
            problem,
            InertiaProblem::NotFinite | InertiaProblem::NegativeMass { .. }
        ) {
            continue; // refused when it was read
        }
        if !alone.contains(name) {
            warnings.push(format!(
                "link \"{name}\": inertia not physical: {problem}{}",
                if *on_world {
                    " (fixed to the world: not simulated)"
                } else {
                    " (merged into a body that is)"
                }
            ));
        }
    }
    Ok(())
}

fn with_merged(n: usize) -> String {
    match n {
        0 => String::new(),
        1 => " (with the link fixed to it)".into(),
        n => format!(" (with the {n} links fixed to it)"),
    }
}

/// Public DOFs whose joint moves no mass or inertia along it at the neutral configuration
/// (mimic joints at their offset): `Σ s_k² S_kᵀ I_c S_k` over the internal coordinates `k` of
/// the DOF is zero (to `1e-12` of the model's largest), where `I_c` is the composite inertia of
/// the subtree the coordinate moves.
pub(crate) fn massless_dofs<const N: usize>(model: &Model<N>) -> Vec<usize> {
    let nb = model.nbodies;
    let mut composite: Vec<RigidBodyInertia> = model.inertias[..nb].to_vec();
    let mut pose = vec![PlueckerTransform::IDENTITY; nb];
    let mut q = [0.0; crate::joint::MAX_JOINT_NQ];
    for (i, p) in pose.iter_mut().enumerate() {
        let j = &model.joints[i];
        j.neutral(&mut q);
        if let Some(m) = &model.mimic[i] {
            q[0] = m.offset;
        }
        *p = j.placed_transform(&model.placements[i], &q[..j.nq()]);
    }
    for i in (0..nb).rev() {
        let p = model.parents[i];
        if p != ROOT {
            let moved = composite[i].transform_to_parent(&pose[i]);
            composite[p] += moved;
        }
    }
    let mut diag = vec![0.0; model.nv];
    for k in 0..model.nv_ext {
        let b = model.dof_body[k];
        let s = &model.subspace[k];
        let d = s.dot(&composite[b].mul_motion(s));
        diag[model.ext_v[k]] += model.ext_scale[k] * model.ext_scale[k] * d;
    }
    let largest = diag.iter().fold(0.0_f64, |a, &d| a.max(d));
    (0..model.nv)
        .filter(|&a| diag[a] <= 1e-12 * largest)
        .collect()
}
