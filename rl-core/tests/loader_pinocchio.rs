//! The URDF loader against Pinocchio: for every fixture in `tests/data/pinocchio/` (see its
//! README), loading the same example-robot-data URDF gives Pinocchio's joint order, joint
//! types and axes, placements, merged body inertias, limits and frame placements, and, end to
//! end, Pinocchio's joint placements and RNEA torques on the fixture's states.
//!
//! Needs example-robot-data: `$RL_ROBOT_DATA` or `scripts/robot-data`; skips with the reason
//! printed when neither is available.

mod support;

use std::path::{Path, PathBuf};

use rl_core::Data;
use rl_core::algo;
use rl_core::joint::JointKind;
use rl_core::loader::{self, JointOrder, LoadedModel, MimicJoints, UrdfOptions};
use rl_core::model::ROOT;
use rl_core::spatial::{MotionVector, PlueckerTransform};
use serde_json::Value;
use support::fixture::{f64s, mat3, pose, vec3};

// tiago_dual has 101 bodies.
const N: usize = 128;

fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn robot_data() -> Option<PathBuf> {
    match loader::example_robot_data_dir(&repo_root()) {
        Ok(d) => Some(d),
        Err(e) => {
            println!("SKIPPED: example-robot-data is not available: {e}");
            None
        }
    }
}

fn fixtures() -> Vec<(String, Value)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pinocchio");
    let mut out: Vec<(String, Value)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .map(|p| {
            let v = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
            (p.file_stem().unwrap().to_string_lossy().into_owned(), v)
        })
        .collect();
    out.sort_by(|a, b| a.0.cmp(&b.0));
    assert!(out.len() >= 4, "fixtures missing in {}", dir.display());
    out
}

fn close(what: &str, a: f64, b: f64, tol: f64) {
    assert!(
        (a - b).abs() <= tol * b.abs().max(1.0),
        "{what}: {a} vs {b}"
    );
}

fn close_pose(what: &str, a: &PlueckerTransform, b: &PlueckerTransform, tol: f64) {
    for k in 0..3 {
        close(
            &format!("{what} translation[{k}]"),
            a.translation[k],
            b.translation[k],
            tol,
        );
    }
    let (ra, rb) = (a.rotation.to_cols_array(), b.rotation.to_cols_array());
    for k in 0..9 {
        close(&format!("{what} rotation[{k}]"), ra[k], rb[k], tol);
    }
}

/// The options that reproduce the fixture's Pinocchio model.
fn options(fx: &Value) -> UrdfOptions {
    UrdfOptions {
        floating_base: fx["floating_base"].as_bool().unwrap(),
        // Pinocchio's default (mimic=False) loads mimic joints as independent joints.
        mimic: if fx["mimic"].as_bool() == Some(true) {
            MimicJoints::Follow
        } else {
            MimicJoints::Independent
        },
        joint_order: JointOrder::Pinocchio,
        locked_joints: fx["locked_joints"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| {
                (
                    l["name"].as_str().unwrap().to_string(),
                    l["value"].as_f64().unwrap(),
                )
            })
            .collect(),
        leaf_tools: false,
        extra_tools: fx["frames"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["name"].as_str().unwrap().to_string())
            .collect(),
    }
}

fn load(data: &Path, fx: &Value) -> LoadedModel<N> {
    let urdf = fx["urdf"].as_str().unwrap();
    // A URDF example-robot-data lacks (the iiwa) is in the repository.
    let path = if fx["urdf_source"].as_str() == Some("repository") {
        repo_root().join(urdf)
    } else {
        data.join(urdf)
    };
    let mut loaded =
        loader::load_file_with::<N>(&path, &options(fx)).unwrap_or_else(|e| panic!("{e}"));
    // URDF has no armature: the fixture's robot sets it as Pinocchio's model did.
    if let Some(a) = fx.get("armature") {
        loaded.model.set_armature(&f64s(a)).unwrap();
    }
    loaded
}

#[test]
fn joint_order_is_pinocchios() {
    let Some(data) = robot_data() else { return };
    for (robot, fx) in fixtures() {
        let m = load(&data, &fx);
        let ours: Vec<&str> = (0..m.model.body_count())
            .map(|i| m.model.joint_name(i))
            .collect();
        let theirs: Vec<&str> = fx["joint_names"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_str().unwrap())
            .collect();
        assert_eq!(ours, theirs, "{robot}: joint order");
        println!("{robot}: {} joints in Pinocchio's order", ours.len());
    }
}

#[test]
fn model_description_is_pinocchios() {
    let Some(data) = robot_data() else { return };
    let tol = 1e-12;
    for (robot, fx) in fixtures() {
        let m = load(&data, &fx);
        let model = &m.model;
        let joints = fx["joints"].as_array().unwrap();
        assert_eq!(model.body_count(), joints.len(), "{robot}");
        assert_eq!(
            model.dof(),
            fx["nv"].as_u64().unwrap() as usize,
            "{robot}: nv"
        );
        let continuous = joints
            .iter()
            .filter(|j| j["nq"] == 2 && j["nv"] == 1)
            .count();
        assert_eq!(
            model.nq() + continuous,
            fx["nq"].as_u64().unwrap() as usize,
            "{robot}: nq"
        );
        assert_eq!(model.gravity(), vec3(&fx["gravity"]), "{robot}: gravity");
        for (i, j) in joints.iter().enumerate() {
            let name = j["name"].as_str().unwrap();
            let what = format!("{robot} {name}");
            let parent = match j["parent"].as_str().unwrap() {
                "universe" => ROOT,
                p => model
                    .body_index(
                        model.body_name((0..i).find(|&k| model.joint_name(k) == p).unwrap()),
                    )
                    .unwrap(),
            };
            assert_eq!(model.parent(i), parent, "{what}: parent");
            close_pose(&what, model.placement(i), &pose(&j["placement"]), tol);
            // Motion subspace, rows [linear; angular] as the fixture has it.
            let joint = model.joint(i);
            let mut s = [MotionVector::ZERO; 6];
            joint.motion_subspace(&mut s);
            let rows = j["motion_subspace"].as_array().unwrap();
            for (c, col) in s.iter().enumerate().take(joint.nv()) {
                let ours = [col.linear.to_array(), col.angular.to_array()].concat();
                for r in 0..6 {
                    close(
                        &format!("{what}: S[{r}][{c}]"),
                        ours[r],
                        rows[r][c].as_f64().unwrap(),
                        tol,
                    );
                }
            }
            let body = &j["body"];
            let inertia = model.inertia(i);
            close(
                &format!("{what}: mass"),
                inertia.mass,
                body["mass"].as_f64().unwrap(),
                tol,
            );
            if inertia.mass > 0.0 {
                let com = vec3(&body["com"]);
                for k in 0..3 {
                    close(&format!("{what}: com"), inertia.com()[k], com[k], 1e-10);
                }
                let (a, b) = (
                    inertia.inertia_com().to_cols_array(),
                    mat3(&body["inertia_at_com"]),
                );
                for (k, x) in b.to_cols_array().iter().enumerate() {
                    close(&format!("{what}: inertia at com"), a[k], *x, 1e-10);
                }
            }
            // A mimic joint: the same leader, multiplier and offset; no limits of its own.
            match (&j["mimic"], model.mimic(i)) {
                (Value::Null, None) => {}
                (x, Some(mm)) if !x.is_null() => {
                    assert_eq!(
                        model.joint_name(mm.leader),
                        x["leader"].as_str().unwrap(),
                        "{what}: leader"
                    );
                    close(&what, mm.multiplier, x["multiplier"].as_f64().unwrap(), 0.0);
                    close(&what, mm.offset, x["offset"].as_f64().unwrap(), 0.0);
                    continue;
                }
                (x, ours) => panic!("{what}: mimic {x} in the fixture, {ours:?} here"),
            }
            if joint.kind() != JointKind::SixDof {
                let l = model.limits(model.v_index(i));
                // One ulp: urdfdom reads e.g. tiago_dual's upper="9.250245035569947" and
                // velocity="10.152284263959391" one ulp high (the correctly rounded doubles,
                // ours and Python's float(), are the written ones).
                let ulp = |ours: f64, theirs: f64, what: &str| {
                    if ours != theirs {
                        close(what, ours, theirs, 2.0 * f64::EPSILON);
                    }
                };
                if let (Some(lo), Some(hi)) = (j["lower"].as_f64(), j["upper"].as_f64()) {
                    ulp(l.lower, lo, &format!("{what}: lower limit"));
                    ulp(l.upper, hi, &format!("{what}: upper limit"));
                } else {
                    assert!(l.wraparound, "{what}: unbounded joint should wrap around");
                }
                // null: Pinocchio's "no limit" (a continuous joint without <limit>).
                let limit = |ours: f64, x: &Value, what: &str| {
                    ulp(ours, x[0].as_f64().unwrap_or(f64::INFINITY), what);
                };
                limit(
                    l.velocity,
                    &j["velocity_limit"],
                    &format!("{what}: velocity limit"),
                );
                limit(
                    l.effort,
                    &j["effort_limit"],
                    &format!("{what}: effort limit"),
                );
            }
        }
        for (k, f) in fx["frames"].as_array().unwrap().iter().enumerate() {
            let t = &model.tools()[k];
            assert_eq!(t.name.as_str(), f["name"].as_str().unwrap());
            assert_eq!(
                model.joint_name(t.body),
                f["parent_joint"].as_str().unwrap(),
                "{robot}"
            );
            close_pose(
                &format!("{robot} frame {}", t.name),
                &t.placement,
                &pose(&f["placement"]),
                tol,
            );
        }
    }
}

#[test]
fn loaded_models_reproduce_pinocchios_kinematics_and_torques() {
    let Some(data) = robot_data() else { return };
    for (robot, fx) in fixtures() {
        let m = load(&data, &fx);
        let mut d = Box::new(Data::<N>::new());
        for (k, s) in fx["states"].as_array().unwrap().iter().enumerate() {
            let what = format!("{robot} state {k}");
            let q = m.q_from_pinocchio(&f64s(&s["q"])).expect("q length");
            if let Some(qa) = s.get("q_angles") {
                for (a, b) in q.iter().zip(f64s(qa)) {
                    close(&format!("{what}: q from Pinocchio's"), *a, b, 1e-14);
                }
            }
            algo::forward_position(&m.model, &mut d, &q).unwrap();
            for (i, p) in s["joint_placements"].as_array().unwrap().iter().enumerate() {
                close_pose(
                    &format!("{what}: joint {i}"),
                    d.world_pose(i),
                    &pose(p),
                    1e-9,
                );
            }
            for (t, f) in m.model.tools().iter().zip(s["frames"].as_array().unwrap()) {
                let x = *d.world_pose(t.body) * t.placement;
                close_pose(
                    &format!("{what}: frame {}", t.name),
                    &x,
                    &pose(&f["placement"]),
                    1e-9,
                );
            }
            let tau = algo::rnea(&m.model, &mut d, &q, &f64s(&s["v"]), &f64s(&s["a"])).unwrap();
            for (a, b) in tau.iter().zip(f64s(&s["tau"])) {
                close(&format!("{what}: rnea"), *a, b, 1e-9);
            }
        }
    }
}
