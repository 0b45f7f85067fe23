//! Reading the Pinocchio fixtures of `tests/data/pinocchio/` (see the README there).

use glam::{DMat3, DVec3};
use rl_core::joint::{Joint, Prismatic, Revolute, SixDof};
use rl_core::model::ROOT;
use rl_core::spatial::{PlueckerTransform, RigidBodyInertia};
use rl_core::{Model, ModelBuilder};
use serde_json::Value;

/// A JSON array of numbers.
pub fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// A JSON array of three numbers.
pub fn vec3(v: &Value) -> DVec3 {
    let a = f64s(v);
    DVec3::new(a[0], a[1], a[2])
}

/// A row-major 3×3 from JSON.
pub fn mat3(v: &Value) -> DMat3 {
    DMat3::from_cols_array(&<[f64; 9]>::try_from(f64s(v)).unwrap()).transpose()
}

/// A placement `{translation, rotation}`.
pub fn pose(v: &Value) -> PlueckerTransform {
    PlueckerTransform::new(mat3(&v["rotation"]), vec3(&v["translation"]))
}

/// The fixture `tests/data/pinocchio/{name}.json`.
pub fn fixture(name: &str) -> Value {
    let path = format!(
        "{}/tests/data/pinocchio/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    serde_json::from_str(&text).unwrap()
}

/// The model Pinocchio described, joint for joint (continuous joints as plain revolute ones;
/// their states use `q_angles`; mimic joints follow their leaders).
pub fn build<const N: usize>(fx: &Value) -> Model<N> {
    let mut b = ModelBuilder::<N>::new();
    b.gravity(vec3(&fx["gravity"]));
    let joints = fx["joints"].as_array().unwrap();
    let mut names: Vec<String> = Vec::new();
    for j in joints {
        let name = j["name"].as_str().unwrap();
        let parent = match j["parent"].as_str().unwrap() {
            "universe" => ROOT,
            p => names.iter().position(|n| n == p).unwrap(),
        };
        let ty = j["type"].as_str().unwrap();
        let s = j["motion_subspace"].as_array().unwrap();
        let joint = if ty.contains("FreeFlyer") {
            Joint::SixDof(SixDof)
        } else {
            let own_nv = if j["mimic"].is_null() { 1 } else { 0 };
            assert_eq!(j["nv"].as_u64(), Some(own_nv), "{ty}");
            let col: Vec<f64> = s.iter().map(|row| row[0].as_f64().unwrap()).collect();
            let lin = DVec3::new(col[0], col[1], col[2]);
            let ang = DVec3::new(col[3], col[4], col[5]);
            if ang.length() > 0.5 {
                Joint::Revolute(Revolute::new(ang))
            } else {
                Joint::Prismatic(Prismatic::new(lin))
            }
        };
        let body = &j["body"];
        let inertia = RigidBodyInertia::from_com(
            body["mass"].as_f64().unwrap(),
            vec3(&body["com"]),
            mat3(&body["inertia_at_com"]),
        );
        b.add_body(parent, name, joint, pose(&j["placement"]), name, inertia)
            .unwrap();
        names.push(name.to_string());
    }
    for (i, j) in joints.iter().enumerate() {
        let m = &j["mimic"];
        if !m.is_null() {
            let leader = names
                .iter()
                .position(|n| n == m["leader"].as_str().unwrap());
            b.set_mimic(
                i,
                leader.unwrap(),
                m["multiplier"].as_f64().unwrap(),
                m["offset"].as_f64().unwrap(),
            )
            .unwrap();
        }
    }
    for f in fx["frames"].as_array().unwrap() {
        let parent = names
            .iter()
            .position(|n| n == f["parent_joint"].as_str().unwrap())
            .unwrap();
        b.add_tool(f["name"].as_str().unwrap(), parent, pose(&f["placement"]))
            .unwrap();
    }
    let mut model = b.build();
    // The rotor inertia per DOF, where the fixture's robot sets one (Pinocchio's armature).
    if let Some(a) = fx.get("armature") {
        model.set_armature(&f64s(a)).unwrap();
    }
    model
}
