//! Spatial force vectors (wrenches): moments and forces, and momenta.

use core::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

use glam::DVec3;

/// A spatial force vector: moment n about a frame's origin and force f, both in the coordinates
/// of one frame (Featherstone's `[n; f]`).
#[doc(alias = "Force")]
#[doc(alias = "Wrench")]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ForceVector {
    /// Moment about the frame's origin, N·m.
    pub moment: DVec3,
    /// Force, N.
    pub force: DVec3,
}

impl ForceVector {
    /// The zero force.
    pub const ZERO: Self = Self {
        moment: DVec3::ZERO,
        force: DVec3::ZERO,
    };

    /// A force from its moment and force parts.
    #[inline]
    pub const fn new(moment: DVec3, force: DVec3) -> Self {
        Self { moment, force }
    }

    /// The six components in RL's order `[moment; force]`.
    #[inline]
    pub fn to_array(&self) -> [f64; 6] {
        let (n, f) = (self.moment, self.force);
        [n.x, n.y, n.z, f.x, f.y, f.z]
    }
}

impl Add for ForceVector {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self {
            moment: self.moment + o.moment,
            force: self.force + o.force,
        }
    }
}

impl AddAssign for ForceVector {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        self.moment += o.moment;
        self.force += o.force;
    }
}

impl Sub for ForceVector {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self {
            moment: self.moment - o.moment,
            force: self.force - o.force,
        }
    }
}

impl SubAssign for ForceVector {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        self.moment -= o.moment;
        self.force -= o.force;
    }
}

impl Neg for ForceVector {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self {
            moment: -self.moment,
            force: -self.force,
        }
    }
}

impl Mul<f64> for ForceVector {
    type Output = Self;
    #[inline]
    fn mul(self, s: f64) -> Self {
        Self {
            moment: self.moment * s,
            force: self.force * s,
        }
    }
}
