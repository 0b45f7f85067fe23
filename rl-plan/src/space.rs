//! Configuration spaces with the topology of each joint (RL's `Model::distance`,
//! `interpolate`, `generatePositionUniform`; OMPL's compound state spaces).
//!
//! A [`JointSpace`] is a list of [`Coordinate`]s over the position vector `q` of an rl-core
//! model (`nq` numbers):
//!
//! - [`Topology::Interval`]: a bounded joint (revolute with limits, prismatic): distance `|b−a|`,
//!   linear interpolation, uniform sampling within `[lower, upper]`.
//! - [`Topology::Circle`]: a continuous revolute joint (URDF `continuous`, RL without limits):
//!   distance `|wrap(b−a)|` with `wrap` into `[−π, π)`, interpolation along the shorter arc
//!   (results wrapped into `[−π, π)`), uniform sampling on the circle.
//! - [`Topology::Rotation`]: the unit quaternion `(x, y, z, w)` of a spherical joint or of the
//!   rotation of a free (six-DOF) joint, four coordinates: distance the rotation angle
//!   `2·acos|⟨a, b⟩|` (rad), interpolation by slerp along the shorter arc, uniform sampling of
//!   rotations (Shoemake).
//!
//! The metric is the weighted Euclidean norm of the per-coordinate distances,
//! `d(a, b) = sqrt(Σ (wᵢ dᵢ)²)` with weights 1 by default; interpolation follows geodesics of each
//! factor, so `d(a, interpolate(a, b, t)) = t · d(a, b)`. Limits come from the model and can be
//! overridden per coordinate ([`JointSpace::set_bounds`]).

use rl_core::Model;
use rl_core::joint::Joint;

use crate::error::PlanError;
use crate::rng::Rng;

const PI: f64 = std::f64::consts::PI;
const TWO_PI: f64 = 2.0 * PI;

/// `x` wrapped into `[−π, π)`.
#[inline]
pub fn wrap_angle(x: f64) -> f64 {
    if (-PI..PI).contains(&x) {
        return x;
    }
    let y = x - TWO_PI * ((x + PI) / TWO_PI).floor();
    // Rounding can land on +π; keep the half-open interval.
    if y >= PI { y - TWO_PI } else { y }
}

/// The topology of one coordinate (or, for rotations, of four).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Topology {
    /// A bounded interval, rad or m.
    Interval {
        /// Lowest value.
        lower: f64,
        /// Highest value.
        upper: f64,
    },
    /// An angle on the circle, rad; values are kept in `[−π, π)`.
    Circle,
    /// A unit quaternion `(x, y, z, w)` over four consecutive coordinates.
    Rotation,
}

impl Topology {
    /// Position coordinates it spans.
    pub fn width(&self) -> usize {
        match self {
            Topology::Rotation => 4,
            _ => 1,
        }
    }
}

/// One factor of a joint space.
#[derive(Clone, Debug, PartialEq)]
pub struct Coordinate {
    /// Its name: the joint's, with a suffix for joints of several coordinates (`/x`, `/rot`).
    pub name: String,
    /// Its topology.
    pub topology: Topology,
    /// Its weight in the metric.
    pub weight: f64,
    /// Index of its first number in `q`.
    pub offset: usize,
}

/// Reads joint-limit overrides `NAME=MIN:MAX[,NAME=MIN:MAX…]` (rad or m; a negative bound is
/// written as is, `j1=-1.5:1.5`). Every entry must name a joint once and give a finite interval
/// with `MIN ≤ MAX`; the names are checked against a space by [`JointSpace::override_bounds`].
pub fn parse_bounds(text: &str) -> Result<Vec<(String, f64, f64)>, PlanError> {
    let bad = |entry: &str, why: &str| {
        PlanError::setting(
            "joint limits",
            format!("`{entry}`: {why} (expected NAME=MIN:MAX, e.g. joint1=-1.5:1.5)"),
        )
    };
    let mut out: Vec<(String, f64, f64)> = Vec::new();
    for entry in text.split(',').map(str::trim).filter(|e| !e.is_empty()) {
        let (name, range) = entry.split_once('=').ok_or_else(|| bad(entry, "no `=`"))?;
        let name = name.trim();
        if name.is_empty() {
            return Err(bad(entry, "no joint name"));
        }
        let (lo, hi) = range
            .split_once(':')
            .ok_or_else(|| bad(entry, "no `:` between MIN and MAX"))?;
        let number = |x: &str| {
            x.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(entry, &format!("`{}` is not a finite number", x.trim())))
        };
        let (lower, upper) = (number(lo)?, number(hi)?);
        if lower > upper {
            return Err(bad(entry, "MIN is above MAX"));
        }
        if out.iter().any(|(n, _, _)| n == name) {
            return Err(bad(entry, "the joint is given twice"));
        }
        out.push((name.to_owned(), lower, upper));
    }
    if out.is_empty() {
        return Err(bad(text, "no limits given"));
    }
    Ok(out)
}

/// The configuration space of a model: see the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct JointSpace {
    coordinates: Vec<Coordinate>,
    nq: usize,
    /// Intervals only, unit weights: the metric is the plain Euclidean one.
    plain: bool,
}

impl JointSpace {
    /// A space of the given coordinates, laid out one after the other.
    pub fn new(coordinates: Vec<(String, Topology)>) -> Result<Self, PlanError> {
        let mut offset = 0;
        let mut out = Vec::with_capacity(coordinates.len());
        for (name, topology) in coordinates {
            if let Topology::Interval { lower, upper } = topology {
                if !(lower.is_finite() && upper.is_finite()) {
                    return Err(PlanError::Unbounded { coordinate: name });
                }
                if lower > upper {
                    return Err(PlanError::setting(
                        format!("bounds of {name}"),
                        format!("lower {lower} is above upper {upper}"),
                    ));
                }
            }
            let width = topology.width();
            out.push(Coordinate {
                name,
                topology,
                weight: 1.0,
                offset,
            });
            offset += width;
        }
        let mut space = Self {
            coordinates: out,
            nq: offset,
            plain: false,
        };
        space.update_plain();
        Ok(space)
    }

    fn update_plain(&mut self) {
        self.plain = self
            .coordinates
            .iter()
            .all(|c| matches!(c.topology, Topology::Interval { .. }) && c.weight == 1.0);
    }

    /// The space of an rl-core model's joints: limits from the model (a revolute joint without
    /// limits or marked wrap-around is a circle; a prismatic joint or a free joint's translation
    /// without limits is an error, [`PlanError::Unbounded`] — give bounds with
    /// [`JointSpace::from_model_with_bounds`]).
    pub fn from_model<const N: usize>(model: &Model<N>) -> Result<Self, PlanError> {
        Self::from_model_with_bounds(model, &[])
    }

    /// As [`JointSpace::from_model`], with bounds `(coordinate name, lower, upper)` replacing
    /// the model's (and bounding what the model leaves unbounded).
    pub fn from_model_with_bounds<const N: usize>(
        model: &Model<N>,
        bounds: &[(String, f64, f64)],
    ) -> Result<Self, PlanError> {
        let mut coords: Vec<(String, Topology)> = Vec::new();
        for b in 0..model.body_count() {
            let name = model.joint_name(b).to_string();
            let sv = model.v_index(b);
            let limit = |k: usize| {
                let l = model.limits(sv + k);
                (l.lower, l.upper, l.wraparound)
            };
            let angle = |k: usize| {
                let (lo, hi, wrap) = limit(k);
                if wrap || !(lo.is_finite() && hi.is_finite()) {
                    Topology::Circle
                } else {
                    Topology::Interval {
                        lower: lo,
                        upper: hi,
                    }
                }
            };
            let length = |k: usize| {
                let (lo, hi, _) = limit(k);
                Topology::Interval {
                    lower: lo,
                    upper: hi,
                }
            };
            match model.joint(b) {
                Joint::Revolute(_) | Joint::Helical(_) => coords.push((name, angle(0))),
                Joint::Prismatic(_) => coords.push((name, length(0))),
                Joint::Cylindrical(_) => {
                    coords.push((format!("{name}/angle"), angle(0)));
                    coords.push((format!("{name}/z"), length(1)));
                }
                Joint::Planar(_) => {
                    coords.push((format!("{name}/x"), length(0)));
                    coords.push((format!("{name}/y"), length(1)));
                    coords.push((format!("{name}/angle"), angle(2)));
                }
                Joint::Spherical(_) => coords.push((format!("{name}/rot"), Topology::Rotation)),
                Joint::SixDof(_) => {
                    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
                        coords.push((format!("{name}/{axis}"), length(k)));
                    }
                    coords.push((format!("{name}/rot"), Topology::Rotation));
                }
            }
        }
        for (name, lower, upper) in bounds {
            let Some(c) = coords.iter_mut().find(|c| &c.0 == name) else {
                return Err(PlanError::UnknownName {
                    what: "coordinate",
                    name: name.clone(),
                });
            };
            if c.1 == Topology::Rotation {
                return Err(PlanError::setting(
                    format!("bounds of {name}"),
                    "a rotation has no interval bounds",
                ));
            }
            c.1 = Topology::Interval {
                lower: *lower,
                upper: *upper,
            };
        }
        let space = Self::new(coords)?;
        if space.nq != model.nq() {
            return Err(PlanError::Unsupported(format!(
                "a joint layout of {} coordinates where the model has {}",
                space.nq,
                model.nq()
            )));
        }
        Ok(space)
    }

    /// Its coordinates.
    pub fn coordinates(&self) -> &[Coordinate] {
        &self.coordinates
    }

    /// A name for each of the `nq` numbers of a configuration: the coordinate's name, and for a
    /// rotation its quaternion's components (`NAME/qx`, `/qy`, `/qz`, `/qw`).
    pub fn number_names(&self) -> Vec<String> {
        let mut out = Vec::with_capacity(self.nq);
        for c in &self.coordinates {
            match c.topology {
                Topology::Rotation => {
                    out.extend(["qx", "qy", "qz", "qw"].map(|k| format!("{}/{k}", c.name)))
                }
                _ => out.push(c.name.clone()),
            }
        }
        out
    }

    /// The number of position numbers (`q.len()`).
    #[inline]
    pub fn nq(&self) -> usize {
        self.nq
    }

    /// The index of the coordinate called `name`.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.coordinates.iter().position(|c| c.name == name)
    }

    /// Replaces the bounds of coordinate `index` (a circle becomes an interval).
    pub fn set_bounds(&mut self, index: usize, lower: f64, upper: f64) -> Result<(), PlanError> {
        let c = self
            .coordinates
            .get_mut(index)
            .ok_or_else(|| PlanError::UnknownName {
                what: "coordinate",
                name: index.to_string(),
            })?;
        if c.topology == Topology::Rotation {
            return Err(PlanError::setting(
                format!("bounds of {}", c.name),
                "a rotation has no interval bounds",
            ));
        }
        if !(lower.is_finite() && upper.is_finite() && lower <= upper) {
            return Err(PlanError::setting(
                format!("bounds of {}", c.name),
                format!("[{lower}, {upper}] is not a finite interval"),
            ));
        }
        c.topology = Topology::Interval { lower, upper };
        self.update_plain();
        Ok(())
    }

    /// Replaces the bounds of the coordinates named in `bounds` (`(name, lower, upper)`, as
    /// [`parse_bounds`] reads them): the joint-limit override. All or nothing: an unknown name
    /// ([`PlanError::UnknownName`], naming it) or a bad interval leaves the space as it was.
    pub fn override_bounds(&mut self, bounds: &[(String, f64, f64)]) -> Result<(), PlanError> {
        let mut out = self.clone();
        for (name, lower, upper) in bounds {
            let index = out.index_of(name).ok_or_else(|| PlanError::UnknownName {
                what: "joint",
                name: name.clone(),
            })?;
            out.set_bounds(index, *lower, *upper)?;
        }
        *self = out;
        Ok(())
    }

    /// Sets the metric weight of coordinate `index` (positive, finite).
    pub fn set_weight(&mut self, index: usize, weight: f64) -> Result<(), PlanError> {
        if !(weight.is_finite() && weight > 0.0) {
            return Err(PlanError::setting(
                "weight",
                format!("{weight} is not positive"),
            ));
        }
        if let Some(c) = self.coordinates.get_mut(index) {
            c.weight = weight;
        }
        self.update_plain();
        Ok(())
    }

    /// Whether the metric is the plain Euclidean one (intervals only, unit weights).
    #[inline]
    pub fn is_plain(&self) -> bool {
        self.plain
    }

    /// Whether every coordinate is one number (no rotations): then configurations form a
    /// vector space locally and `a + t·difference(a, b)` is the interpolation (up to wrapping
    /// of circles, which trigonometric functions do not see).
    pub fn is_vector(&self) -> bool {
        self.nq == self.coordinates.len()
    }

    /// Whether the space has circle coordinates.
    pub fn has_circles(&self) -> bool {
        self.coordinates
            .iter()
            .any(|c| c.topology == Topology::Circle)
    }

    /// The distance `d(a, b)` (see the module docs).
    #[inline]
    pub fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.distance_squared(a, b).sqrt()
    }

    /// `d(a, b)²` (cheaper; same order).
    #[inline]
    pub fn distance_squared(&self, a: &[f64], b: &[f64]) -> f64 {
        if self.plain {
            let mut s = 0.0;
            for (x, y) in a.iter().zip(b) {
                s += (y - x) * (y - x);
            }
            return s;
        }
        let mut s = 0.0;
        for c in &self.coordinates {
            let d = c.weight * component_distance(c, a, b);
            s += d * d;
        }
        s
    }

    /// The distance along coordinate `index` alone (unweighted).
    #[inline]
    pub fn coordinate_distance(&self, index: usize, a: &[f64], b: &[f64]) -> f64 {
        component_distance(&self.coordinates[index], a, b)
    }

    /// `b − a` per number, circles wrapped into `[−π, π)`; for rotations the quaternion
    /// difference is not meaningful and `b − a` is written (use [`JointSpace::interpolate`]).
    pub fn difference(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
        for c in &self.coordinates {
            let i = c.offset;
            match c.topology {
                Topology::Circle => out[i] = wrap_angle(b[i] - a[i]),
                Topology::Interval { .. } => out[i] = b[i] - a[i],
                Topology::Rotation => {
                    for k in i..i + 4 {
                        out[k] = b[k] - a[k];
                    }
                }
            }
        }
    }

    /// The configuration a fraction `t ∈ [0, 1]` of the way from `a` to `b` along the geodesic.
    pub fn interpolate(&self, a: &[f64], b: &[f64], t: f64, out: &mut [f64]) {
        for c in &self.coordinates {
            let i = c.offset;
            match c.topology {
                Topology::Interval { .. } => out[i] = a[i] + t * (b[i] - a[i]),
                Topology::Circle => out[i] = wrap_angle(a[i] + t * wrap_angle(b[i] - a[i])),
                Topology::Rotation => slerp(&a[i..i + 4], &b[i..i + 4], t, &mut out[i..i + 4]),
            }
        }
    }

    /// A configuration drawn uniformly: intervals and circles uniformly, rotations uniformly
    /// over SO(3).
    pub fn sample_uniform(&self, rng: &mut Rng, out: &mut [f64]) {
        for c in &self.coordinates {
            let i = c.offset;
            match c.topology {
                Topology::Interval { lower, upper } => out[i] = rng.uniform_in(lower, upper),
                Topology::Circle => out[i] = rng.uniform_in(-PI, PI),
                Topology::Rotation => random_rotation(rng, &mut out[i..i + 4]),
            }
        }
    }

    /// Maps a point of the unit cube (`u.len()` = number of coordinates, each in `[0, 1)`)
    /// onto the space (rotations take three cube coordinates). Used by low-discrepancy
    /// samplers. Returns `false` when `u` is too short.
    pub fn from_unit_cube(&self, u: &[f64], out: &mut [f64]) -> bool {
        let mut k = 0;
        for c in &self.coordinates {
            let i = c.offset;
            match c.topology {
                Topology::Interval { lower, upper } => {
                    let Some(&x) = u.get(k) else { return false };
                    out[i] = lower + (upper - lower) * x;
                    k += 1;
                }
                Topology::Circle => {
                    let Some(&x) = u.get(k) else { return false };
                    out[i] = -PI + TWO_PI * x;
                    k += 1;
                }
                Topology::Rotation => {
                    let Some(v) = u.get(k..k + 3) else {
                        return false;
                    };
                    shoemake(v[0], v[1], v[2], &mut out[i..i + 4]);
                    k += 3;
                }
            }
        }
        true
    }

    /// The number of unit-cube coordinates [`JointSpace::from_unit_cube`] needs.
    pub fn cube_dimension(&self) -> usize {
        self.coordinates
            .iter()
            .map(|c| {
                if c.topology == Topology::Rotation {
                    3
                } else {
                    1
                }
            })
            .sum()
    }

    /// A configuration near `mean`: each coordinate moved by a normal deviate of standard
    /// deviation `sigma[i]` (per coordinate; rotations turn about a random axis by a normal
    /// angle), intervals clamped into their bounds, circles wrapped (RL's
    /// `generatePositionGaussian`).
    pub fn sample_gaussian(&self, rng: &mut Rng, mean: &[f64], sigma: &[f64], out: &mut [f64]) {
        for (j, c) in self.coordinates.iter().enumerate() {
            let i = c.offset;
            let s = sigma.get(j).copied().unwrap_or(0.0);
            match c.topology {
                Topology::Interval { lower, upper } => {
                    out[i] = (mean[i] + s * rng.normal()).clamp(lower, upper);
                }
                Topology::Circle => out[i] = wrap_angle(mean[i] + s * rng.normal()),
                Topology::Rotation => {
                    let w = glam::DVec3::new(rng.normal(), rng.normal(), rng.normal()) * s;
                    let m = glam::DQuat::from_xyzw(mean[i], mean[i + 1], mean[i + 2], mean[i + 3]);
                    let q = (glam::DQuat::from_scaled_axis(w) * m).normalize();
                    out[i..i + 4].copy_from_slice(&[q.x, q.y, q.z, q.w]);
                }
            }
        }
    }

    /// Checks a configuration: length, finiteness, interval bounds, unit quaternions (within
    /// 1e-6). `what` names it in the error.
    pub fn check(&self, what: &str, q: &[f64]) -> Result<(), PlanError> {
        if q.len() != self.nq {
            return Err(PlanError::Length {
                what: what.to_string(),
                expected: self.nq,
                got: q.len(),
            });
        }
        for c in &self.coordinates {
            let i = c.offset;
            let bad = |value: f64, lower: f64, upper: f64| PlanError::OutsideBounds {
                what: what.to_string(),
                coordinate: c.name.clone(),
                value,
                lower,
                upper,
            };
            match c.topology {
                Topology::Interval { lower, upper } => {
                    if !(q[i] >= lower && q[i] <= upper) {
                        return Err(bad(q[i], lower, upper));
                    }
                }
                Topology::Circle => {
                    if !q[i].is_finite() {
                        return Err(bad(q[i], -PI, PI));
                    }
                }
                Topology::Rotation => {
                    let n2: f64 = q[i..i + 4].iter().map(|x| x * x).sum();
                    if n2.is_nan() || (n2 - 1.0).abs() >= 1e-6 {
                        return Err(bad(n2.sqrt(), 1.0, 1.0));
                    }
                }
            }
        }
        Ok(())
    }

    /// Whether `q` satisfies [`JointSpace::check`].
    pub fn contains(&self, q: &[f64]) -> bool {
        self.check("q", q).is_ok()
    }

    /// `q` brought into canonical form: circles wrapped into `[−π, π)`, quaternions normalised.
    pub fn normalize(&self, q: &mut [f64]) {
        for c in &self.coordinates {
            let i = c.offset;
            match c.topology {
                Topology::Circle => q[i] = wrap_angle(q[i]),
                Topology::Rotation => {
                    let n: f64 = q[i..i + 4].iter().map(|x| x * x).sum::<f64>().sqrt();
                    if n > 0.0 {
                        q[i..i + 4].iter_mut().for_each(|x| *x /= n);
                    }
                }
                Topology::Interval { .. } => {}
            }
        }
    }

    /// The length of a path (sum of distances between consecutive waypoints).
    pub fn path_length(&self, points: &[f64]) -> f64 {
        let n = self.nq;
        if n == 0 {
            return 0.0;
        }
        points
            .chunks_exact(n)
            .zip(points.chunks_exact(n).skip(1))
            .map(|(a, b)| self.distance(a, b))
            .sum()
    }
}

#[inline]
fn component_distance(c: &Coordinate, a: &[f64], b: &[f64]) -> f64 {
    let i = c.offset;
    match c.topology {
        Topology::Interval { .. } => (b[i] - a[i]).abs(),
        Topology::Circle => wrap_angle(b[i] - a[i]).abs(),
        Topology::Rotation => {
            let dot: f64 = (0..4).map(|k| a[i + k] * b[i + k]).sum();
            2.0 * dot.abs().min(1.0).acos()
        }
    }
}

/// Slerp between unit quaternions along the shorter arc.
fn slerp(a: &[f64], b: &[f64], t: f64, out: &mut [f64]) {
    let mut dot: f64 = (0..4).map(|k| a[k] * b[k]).sum();
    let sign = if dot < 0.0 { -1.0 } else { 1.0 };
    dot = dot.abs().min(1.0);
    let (wa, wb) = if dot > 1.0 - 1e-12 {
        (1.0 - t, t)
    } else {
        let theta = dot.acos();
        let s = theta.sin();
        (((1.0 - t) * theta).sin() / s, (t * theta).sin() / s)
    };
    let mut n = 0.0;
    for k in 0..4 {
        out[k] = wa * a[k] + wb * sign * b[k];
        n += out[k] * out[k];
    }
    let n = n.sqrt();
    for x in out.iter_mut().take(4) {
        *x /= n;
    }
}

/// Shoemake's uniform rotation from three uniform numbers.
fn shoemake(u1: f64, u2: f64, u3: f64, out: &mut [f64]) {
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    out[0] = a * (TWO_PI * u2).sin();
    out[1] = a * (TWO_PI * u2).cos();
    out[2] = b * (TWO_PI * u3).sin();
    out[3] = b * (TWO_PI * u3).cos();
}

fn random_rotation(rng: &mut Rng, out: &mut [f64]) {
    let (u1, u2, u3) = (rng.uniform(), rng.uniform(), rng.uniform());
    shoemake(u1, u2, u3, out);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mixed() -> JointSpace {
        JointSpace::new(vec![
            (
                "a".into(),
                Topology::Interval {
                    lower: -1.0,
                    upper: 2.0,
                },
            ),
            ("b".into(), Topology::Circle),
            ("c".into(), Topology::Rotation),
        ])
        .unwrap()
    }

    #[test]
    fn limit_overrides_parse_and_apply_all_or_nothing() {
        let b = parse_bounds("a=-0.5:1.5, b = -1:1").unwrap();
        assert_eq!(
            b,
            vec![("a".to_string(), -0.5, 1.5), ("b".to_string(), -1.0, 1.0)]
        );
        let mut s = mixed();
        s.override_bounds(&b).unwrap();
        assert_eq!(
            s.coordinates()[0].topology,
            Topology::Interval {
                lower: -0.5,
                upper: 1.5
            }
        );
        // The circle became an interval.
        assert_eq!(
            s.coordinates()[1].topology,
            Topology::Interval {
                lower: -1.0,
                upper: 1.0
            }
        );
        // An unknown joint is named, and nothing changes.
        let before = mixed();
        let mut s = before.clone();
        let e = s
            .override_bounds(&parse_bounds("a=0:1,elbow=0:1").unwrap())
            .unwrap_err();
        assert_eq!(
            e,
            PlanError::UnknownName {
                what: "joint",
                name: "elbow".into()
            }
        );
        assert_eq!(s, before);
        assert!(s.override_bounds(&[("c".into(), 0.0, 1.0)]).is_err());
        for bad in [
            "",
            "a",
            "a=1",
            "a=x:1",
            "a=2:1",
            "=0:1",
            "a=0:1,a=0:2",
            "a=0:inf",
        ] {
            let e = parse_bounds(bad).unwrap_err();
            assert!(e.to_string().contains("NAME=MIN:MAX"), "{bad}: {e}");
        }
    }

    #[test]
    fn wrap_is_half_open() {
        assert_eq!(wrap_angle(PI), -PI);
        assert_eq!(wrap_angle(-PI), -PI);
        assert!((wrap_angle(3.0 * PI + 0.1) - (-PI + 0.1)).abs() < 1e-12);
        assert!((wrap_angle(-0.5) + 0.5).abs() < 1e-15);
    }

    #[test]
    fn circle_distance_and_interpolation_go_the_short_way() {
        let s = mixed();
        let a = [0.0, 3.0, 0.0, 0.0, 0.0, 1.0];
        let b = [0.0, -3.0, 0.0, 0.0, 0.0, 1.0];
        let d = s.distance(&a, &b);
        assert!((d - (TWO_PI - 6.0)).abs() < 1e-12, "{d}");
        let mut m = [0.0; 6];
        s.interpolate(&a, &b, 0.5, &mut m);
        // Halfway across +π.
        assert!((m[1].abs() - PI).abs() < 1e-12);
        // d(a, interp(t)) = t d(a, b) for every factor.
        let q1 = glam::DQuat::from_rotation_z(0.3);
        let q2 = glam::DQuat::from_rotation_x(1.2) * q1;
        let a = [-1.0, 2.0, q1.x, q1.y, q1.z, q1.w];
        let b = [1.5, -2.5, q2.x, q2.y, q2.z, q2.w];
        for t in [0.1, 0.37, 0.8] {
            s.interpolate(&a, &b, t, &mut m);
            assert!((s.distance(&a, &m) - t * s.distance(&a, &b)).abs() < 1e-9);
        }
    }

    #[test]
    fn sampling_stays_in_the_space_and_checks_catch_bad_input() {
        let s = mixed();
        let mut r = Rng::seed_from(3);
        let mut q = [0.0; 6];
        for _ in 0..1000 {
            s.sample_uniform(&mut r, &mut q);
            s.check("sample", &q).unwrap();
            let mean = q;
            s.sample_gaussian(&mut r, &mean, &[5.0, 1.0, 0.3], &mut q);
            s.check("gaussian", &q).unwrap();
        }
        assert!(matches!(
            s.check("x", &[3.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
            Err(PlanError::OutsideBounds { .. })
        ));
        assert!(matches!(
            s.check("x", &[0.0; 5]),
            Err(PlanError::Length { .. })
        ));
        assert!(
            JointSpace::new(vec![(
                "p".into(),
                Topology::Interval {
                    lower: 0.0,
                    upper: f64::INFINITY
                }
            )])
            .is_err()
        );
    }

    #[test]
    fn space_of_a_model_follows_its_joints() {
        let loaded = rl_core::loader::load_file::<8>(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../tests/data/rlmdl/box-6d-300505.sixDof.xml"
        ))
        .unwrap();
        let s = JointSpace::from_model(&loaded.model).unwrap();
        assert_eq!(s.nq(), 7);
        assert_eq!(s.coordinates().len(), 4);
        assert_eq!(
            s.coordinates()[0].topology,
            Topology::Interval {
                lower: 0.0,
                upper: 30.0
            }
        );
        assert_eq!(s.coordinates()[3].topology, Topology::Rotation);
        assert!(!s.is_vector());
    }
}
