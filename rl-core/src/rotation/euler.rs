//! Euler angles in the `Z-Y'-X''` convention of robot controllers: the angles `a, b, c` (rad)
//! with `R = Rz(c) · Ry(b) · Rx(a)` — MELFA's `A, B, C`, RL's Coach poses, KUKA's `C, B, A`.
//!
//! [`from_zyx`] builds the rotation matrix; [`to_zyx`] recovers angles with `b` in
//! `[-π/2, π/2]` and `a, c` in `(-π, π]`. At the singularity `|b| = π/2` only `c - a` (or
//! `c + a`) is defined; [`to_zyx`] then returns `a = 0`. Nothing here allocates or panics.

use glam::{DMat3, DVec3};
use libm::{atan2, sqrt};

use crate::math::real::sin_cos;

/// `cos b` below which the angles are treated as singular (`|b| = π/2`).
const SINGULAR: f64 = 1e-12;

/// The rotation `Rz(c) · Ry(b) · Rx(a)` of the angles `[a, b, c]` in rad.
pub fn from_zyx(abc: [f64; 3]) -> DMat3 {
    let (sa, ca) = sin_cos(abc[0]);
    let (sb, cb) = sin_cos(abc[1]);
    let (sc, cc) = sin_cos(abc[2]);
    DMat3::from_cols(
        DVec3::new(cb * cc, cb * sc, -sb),
        DVec3::new(sa * sb * cc - ca * sc, sa * sb * sc + ca * cc, sa * cb),
        DVec3::new(ca * sb * cc + sa * sc, ca * sb * sc - sa * cc, ca * cb),
    )
}

/// The angles `[a, b, c]` in rad with `R = Rz(c) · Ry(b) · Rx(a)`, for a rotation matrix `r`.
pub fn to_zyx(r: &DMat3) -> [f64; 3] {
    let (r00, r10, r20) = (r.x_axis.x, r.x_axis.y, r.x_axis.z);
    let cb = sqrt(r00 * r00 + r10 * r10);
    let b = atan2(-r20, cb);
    if cb > SINGULAR {
        [atan2(r.y_axis.z, r.z_axis.z), b, atan2(r10, r00)]
    } else {
        // a = 0: then r01 = -sin c and r11 = cos c.
        [0.0, b, atan2(-r.y_axis.x, r.y_axis.y)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &DMat3, b: &DMat3) -> bool {
        (0..3).all(|j| (a.col(j) - b.col(j)).abs().max_element() < 1e-12)
    }

    #[test]
    fn the_matrix_is_the_product_of_the_three_axis_rotations() {
        let abc = [0.3, -0.7, 2.1];
        let product = DMat3::from_rotation_z(abc[2])
            * DMat3::from_rotation_y(abc[1])
            * DMat3::from_rotation_x(abc[0]);
        assert!(close(&from_zyx(abc), &product));
    }

    #[test]
    fn angles_round_trip_away_from_and_at_the_singularity() {
        for abc in [
            [0.3, -0.7, 2.1],
            [-3.0, 1.5, -0.1],
            [3.1, 0.0, -3.1],
            [0.0, 0.0, 0.0],
        ] {
            let back = to_zyx(&from_zyx(abc));
            for k in 0..3 {
                assert!((back[k] - abc[k]).abs() < 1e-9, "{abc:?} -> {back:?}");
            }
        }
        // At b = ±π/2 the angles differ but the rotation is the same.
        for b in [core::f64::consts::FRAC_PI_2, -core::f64::consts::FRAC_PI_2] {
            let r = from_zyx([0.4, b, 1.0]);
            let back = to_zyx(&r);
            assert_eq!(back[0], 0.0);
            assert!(close(&from_zyx(back), &r), "{back:?}");
        }
    }
}
