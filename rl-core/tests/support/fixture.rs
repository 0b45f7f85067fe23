//! Reading the Pinocchio fixtures of `tests/data/pinocchio/` (see the README there).

use glam::{DMat3, DVec3};
use rl_core::spatial::PlueckerTransform;
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
