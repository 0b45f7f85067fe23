//! Spatial motion vectors (twists): velocities and accelerations of rigid bodies.

use core::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

use glam::DVec3;

use super::ForceVector;

/// A spatial motion vector: angular part ω and linear part v of a frame's origin, both in the
/// coordinates of one frame (Featherstone's `[ω; v]`).
#[doc(alias = "Motion")]
#[doc(alias = "Twist")]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MotionVector {
    /// Angular velocity (or acceleration), rad/s.
    pub angular: DVec3,
    /// Linear velocity (or acceleration) of the frame's origin, m/s.
    pub linear: DVec3,
}

impl MotionVector {
    /// The zero motion.
    pub const ZERO: Self = Self {
        angular: DVec3::ZERO,
        linear: DVec3::ZERO,
    };

    /// A motion from its angular and linear parts.
    #[inline]
    pub const fn new(angular: DVec3, linear: DVec3) -> Self {
        Self { angular, linear }
    }

    /// The motion cross product `self × m` (Featherstone's `crm`): how a motion vector fixed
    /// in a body changes when the body moves with `self`.
    #[inline]
    pub fn cross_motion(&self, m: &MotionVector) -> MotionVector {
        MotionVector {
            angular: self.angular.cross(m.angular),
            linear: self.angular.cross(m.linear) + self.linear.cross(m.angular),
        }
    }

    /// The force cross product `self ×* f` (Featherstone's `crf`).
    #[inline]
    pub fn cross_force(&self, f: &ForceVector) -> ForceVector {
        ForceVector {
            moment: self.angular.cross(f.moment) + self.linear.cross(f.force),
            force: self.angular.cross(f.force),
        }
    }

    /// The scalar product with a force: power (W) when `self` is a velocity.
    #[inline]
    pub fn dot(&self, f: &ForceVector) -> f64 {
        self.angular.dot(f.moment) + self.linear.dot(f.force)
    }

    /// The six components in RL's order `[angular; linear]`.
    #[inline]
    pub fn to_array(&self) -> [f64; 6] {
        let (a, l) = (self.angular, self.linear);
        [a.x, a.y, a.z, l.x, l.y, l.z]
    }
}

impl Add for MotionVector {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self {
            angular: self.angular + o.angular,
            linear: self.linear + o.linear,
        }
    }
}

impl AddAssign for MotionVector {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        self.angular += o.angular;
        self.linear += o.linear;
    }
}

impl Sub for MotionVector {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self {
            angular: self.angular - o.angular,
            linear: self.linear - o.linear,
        }
    }
}

impl SubAssign for MotionVector {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        self.angular -= o.angular;
        self.linear -= o.linear;
    }
}

impl Neg for MotionVector {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self {
            angular: -self.angular,
            linear: -self.linear,
        }
    }
}

impl Mul<f64> for MotionVector {
    type Output = Self;
    #[inline]
    fn mul(self, s: f64) -> Self {
        Self {
            angular: self.angular * s,
            linear: self.linear * s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cross_products_are_dual() {
        // (v × m) · f = -m · (v ×* f)
        let v = MotionVector::new(DVec3::new(0.1, -0.2, 0.3), DVec3::new(1.0, 2.0, -0.5));
        let m = MotionVector::new(DVec3::new(-0.7, 0.4, 0.2), DVec3::new(0.3, -1.0, 0.9));
        let f = ForceVector::new(DVec3::new(0.5, 0.6, -0.1), DVec3::new(-2.0, 0.25, 1.5));
        let lhs = v.cross_motion(&m).dot(&f);
        let rhs = -m.dot(&v.cross_force(&f));
        assert!((lhs - rhs).abs() < 1e-14, "{lhs} vs {rhs}");
        assert_eq!(v.cross_motion(&v), MotionVector::ZERO);
    }
}
