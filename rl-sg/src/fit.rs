//! Capsules (or spheres) that contain a body's geometry, for the control-rate path
//! ([`crate::capsule`]).
//!
//! # Why the capsules contain the geometry
//!
//! Every shape lies in the convex hull of a finite set of balls ([`Geometry::bounding_balls`]:
//! a triangle in the hull of its corners, a box in that of its eight corners, a cylinder in
//! that of the two balls on its end-disc centres, …). A capsule is convex, so a capsule that
//! contains each of those balls contains their hull and with it the shape. A ball `(p, r)` is
//! inside the capsule of axis segment `S` and radius `R` exactly when `dist(p, S) + r ≤ R`.
//!
//! For a chosen axis line through `c` with direction `u`, write each ball centre as its axial
//! coordinate `t = u·(p − c)` and its distance `ρ` from the line. The smallest radius that the
//! line allows is `R = max(ρ + r)`; the segment `[t₀, t₁]` must then reach every ball:
//! `t₁ ≥ t − h` and `t₀ ≤ t + h` with `h = √((R − r)² − ρ²)`, which the tightest segment meets
//! with equality. All of this is computed in closed form, so the containment holds up to
//! rounding (the test samples surface points and checks it).
//!
//! A body may get `k` capsules: its pieces (whole primitives, single mesh triangles) are
//! sorted along the body's principal axis and cut into `k` groups, one capsule per group;
//! each piece lies whole in its group's capsule, so the union contains the body.
//!
//! The axis of each capsule is the best (least volume) of the group's principal axis (power
//! iteration on the covariance of the ball centres) and the body frame's three axes; the line's
//! centre is the centre of the balls' 2-D bounding box across the axis.

use glam::DVec3;
use rl_core::model::ROOT;

use crate::capsule::{Capsule, CapsuleModel, LinkCapsule};
use crate::error::SgError;
use crate::geometry::Geometry;
use crate::scene::{Body, Model};

/// How to approximate each body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitOptions {
    /// Capsules per body (at least 1; bodies with fewer pieces get fewer).
    pub per_body: usize,
    /// Spheres instead of capsules (each "capsule" has zero length).
    pub spheres: bool,
    /// Added to every radius, m (a safety margin; 0 for the tightest fit).
    pub padding: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            per_body: 2,
            spheres: false,
            padding: 0.0,
        }
    }
}

/// A piece of a body: balls whose hull contains it, with a representative point.
struct Piece {
    balls: std::ops::Range<usize>,
    centre: DVec3,
}

/// Balls `(centre, radius)` and the pieces that own runs of them.
type Balls = (Vec<(DVec3, f64)>, Vec<Piece>);

/// The balls of a body's shapes in its frame, grouped by piece; `Err` for a half-space.
fn pieces(body: &Body) -> Result<Balls, SgError> {
    let mut balls = Vec::new();
    let mut pieces = Vec::new();
    for s in body.shapes() {
        let x = s.local_pose();
        let to_body = |p: DVec3| x.rotation * p + x.translation;
        match s.geometry() {
            Geometry::Mesh(m) => {
                for t in m.triangles() {
                    let start = balls.len();
                    let corners = t.map(|i| to_body(m.vertices()[i as usize]));
                    balls.extend(corners.iter().map(|&c| (c, 0.0)));
                    pieces.push(Piece {
                        balls: start..balls.len(),
                        centre: (corners[0] + corners[1] + corners[2]) / 3.0,
                    });
                }
            }
            g => {
                let Some(bs) = g.bounding_balls() else {
                    return Err(
                        SgError::unsupported("a capsule around a half-space (unbounded)")
                            .at(format!("body \"{}\"", body.name())),
                    );
                };
                let start = balls.len();
                balls.extend(bs.iter().map(|&(p, r)| (to_body(p), r)));
                let n = (balls.len() - start) as f64;
                let centre = balls[start..].iter().map(|b| b.0).sum::<DVec3>() / n;
                pieces.push(Piece {
                    balls: start..balls.len(),
                    centre,
                });
            }
        }
    }
    Ok((balls, pieces))
}

/// The principal axis of `points` (unit), by power iteration on their covariance.
fn principal_axis(points: impl Iterator<Item = DVec3> + Clone) -> DVec3 {
    let n = points.clone().count().max(1) as f64;
    let mean = points.clone().sum::<DVec3>() / n;
    let mut c = glam::DMat3::ZERO;
    for p in points {
        let d = p - mean;
        c += glam::DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    let mut v = DVec3::new(0.577, 0.578, 0.579);
    for _ in 0..64 {
        let w = c * v;
        let len = w.length();
        if len.is_nan() || len <= 1e-300 {
            return DVec3::Z;
        }
        v = w / len;
    }
    v
}

/// Two unit vectors completing `u` to an orthonormal frame.
fn orthonormal(u: DVec3) -> (DVec3, DVec3) {
    let a = if u.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let v = u.cross(a).normalize();
    (v, u.cross(v))
}

/// The tightest capsule with axis direction `u` containing `balls` (see the module docs).
fn capsule_along(u: DVec3, balls: &[(DVec3, f64)], sphere: bool) -> Capsule {
    let (v, w) = orthonormal(u);
    if sphere {
        let (lo, hi) = bounds(balls, |p| p);
        let c = (lo + hi) / 2.0;
        let r = balls
            .iter()
            .map(|&(p, r)| (p - c).length() + r)
            .fold(0.0, f64::max);
        return Capsule::sphere(c, r);
    }
    // Centre of the line: middle of the 2-D box across the axis.
    let (lo, hi) = bounds(balls, |p| DVec3::new(p.dot(v), p.dot(w), 0.0));
    let c2 = (lo + hi) / 2.0;
    let c = v * c2.x + w * c2.y;
    let rho = |p: DVec3| {
        let d = p - c;
        (d - u * d.dot(u)).length()
    };
    let radius = balls.iter().map(|&(p, r)| rho(p) + r).fold(0.0, f64::max);
    let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
    for &(p, r) in balls {
        let t = (p - c).dot(u);
        let h = ((radius - r).powi(2) - rho(p).powi(2)).max(0.0).sqrt();
        t0 = t0.min(t + h);
        t1 = t1.max(t - h);
    }
    if t0 > t1 {
        // Every ball fits around one point of the line.
        let m = (t0 + t1) / 2.0;
        (t0, t1) = (m, m);
    }
    Capsule::new(c + u * t0, c + u * t1, radius)
}

fn bounds(balls: &[(DVec3, f64)], f: impl Fn(DVec3) -> DVec3) -> (DVec3, DVec3) {
    balls.iter().fold(
        (DVec3::INFINITY, DVec3::NEG_INFINITY),
        |(lo, hi), &(p, _)| (lo.min(f(p)), hi.max(f(p))),
    )
}

fn volume(c: &Capsule) -> f64 {
    let r = c.radius;
    std::f64::consts::PI * r * r * ((c.b - c.a).length() + 4.0 / 3.0 * r)
}

/// The best capsule for `balls` among the principal axis and the three frame axes.
fn fit_group(balls: &[(DVec3, f64)], sphere: bool) -> Capsule {
    let axis = principal_axis(balls.iter().map(|b| b.0));
    [axis, DVec3::X, DVec3::Y, DVec3::Z]
        .into_iter()
        .map(|u| capsule_along(u, balls, sphere))
        .min_by(|a, b| volume(a).total_cmp(&volume(b)))
        .expect("four candidates")
}

/// Capsules (in the body's frame) whose union contains every shape of `body`; none for a body
/// without shapes. A half-space is an error (it has no bounded hull).
pub fn fit_body(body: &Body, options: &FitOptions) -> Result<Vec<Capsule>, SgError> {
    let (balls, mut pieces) = pieces(body)?;
    if pieces.is_empty() {
        return Ok(Vec::new());
    }
    let k = options.per_body.max(1).min(pieces.len());
    let axis = principal_axis(pieces.iter().map(|p| p.centre));
    pieces.sort_by(|a, b| a.centre.dot(axis).total_cmp(&b.centre.dot(axis)));
    let mut out = Vec::with_capacity(k);
    for g in 0..k {
        let group = &pieces[g * pieces.len() / k..(g + 1) * pieces.len() / k];
        let gb: Vec<(DVec3, f64)> = group
            .iter()
            .flat_map(|p| balls[p.balls.clone()].iter().copied())
            .collect();
        let mut c = fit_group(&gb, options.spheres);
        c.radius += options.padding;
        out.push(c);
    }
    Ok(out)
}

/// The capsules of a whole model: `(body index, capsule in the body's frame)`.
pub fn fit_model(model: &Model, options: &FitOptions) -> Result<Vec<(usize, Capsule)>, SgError> {
    let mut out = Vec::new();
    for (i, b) in model.bodies().iter().enumerate() {
        for c in fit_body(b, options)? {
            out.push((i, c));
        }
    }
    Ok(out)
}

/// A model's capsules for the real-time kernel, and what goes with them.
#[derive(Clone, Debug)]
pub struct FittedModel<const N: usize> {
    /// The kernel's model: capsules in rl-core body frames (through the scene model's
    /// [`crate::KinematicLink`]; bodies without a kinematic frame are fixed to the world where
    /// they are now). [`crate::capsule::LinkCapsule::link`] is the scene body's index.
    pub capsules: CapsuleModel<N>,
    /// The scene body names, indexed by [`crate::capsule::LinkCapsule::link`].
    pub body_names: Vec<String>,
    /// Capsule index pairs for self-distance: those of the model's self-collision body pairs.
    pub self_pairs: Vec<(u16, u16)>,
}

/// Fits a model and fills a kernel model of capacity `N` (an error if the capsules do not fit,
/// or there are more than 65 536 bodies).
pub fn fit_capsule_model<const N: usize>(
    model: &Model,
    options: &FitOptions,
) -> Result<FittedModel<N>, SgError> {
    let fitted = fit_model(model, options)?;
    let mut capsules = CapsuleModel::<N>::new();
    let mut of_body: Vec<Vec<u16>> = vec![Vec::new(); model.bodies().len()];
    for (i, c) in &fitted {
        let link = u16::try_from(*i)
            .map_err(|_| SgError::invalid("body index", i, "more than 65536 bodies"))?;
        let (body, x) = match model.kinematics().and_then(|k| k.frame(*i)) {
            Some(f) => f,
            None => (ROOT, *model.bodies()[*i].pose()),
        };
        let local = c.transformed(&x);
        of_body[*i].push(capsules.len() as u16);
        capsules
            .push(LinkCapsule::new(body, link, local))
            .map_err(|e| {
                SgError::invalid(
                    "capsule count",
                    fitted.len(),
                    "more than the model's capacity",
                )
                .at(e.to_string())
            })?;
    }
    let mut self_pairs = Vec::new();
    for &(a, b) in model.self_collision_pairs() {
        for &i in &of_body[a as usize] {
            for &j in &of_body[b as usize] {
                self_pairs.push((i, j));
            }
        }
    }
    Ok(FittedModel {
        capsules,
        body_names: model
            .bodies()
            .iter()
            .map(|b| b.name().to_string())
            .collect(),
        self_pairs,
    })
}
