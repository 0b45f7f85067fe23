//! Queries on a scene: collision, distance with witness points, penetration depth, raycasts.
//!
//! Every query runs a broad phase first — bounding boxes of bodies and shapes, and a
//! bounding-volume tree over the shapes of the other model ([`crate::scene::ModelBvh`]) — so
//! a robot among hundreds of obstacles costs narrow-phase calls only for the few whose boxes
//! overlap (collision) or could beat the best distance found so far (distance). The narrow
//! phase is parry3d's: GJK/EPA for convex shapes, exact routines for sphere, box and capsule
//! pairs, and its own bounding-volume trees inside triangle meshes.
//!
//! Conventions (coal's): distances are signed — negative is the penetration depth, measured
//! between the two deepest points; witness points are in the world frame, `point_a` on the
//! first shape's surface, `point_b` on the second's.

mod broad;
mod collision;
mod distance;
mod mesh_distance;
mod raycast;

use glam::DVec3;
use parry3d_f64::math::Pose;
use parry3d_f64::query::{self, ClosestPoints};
use parry3d_f64::shape::SharedShape;

use crate::geometry::{Geometry, TriangleMesh};
use crate::scene::{ModelId, Shape, ShapeId};

/// Which pairs a collision query looks at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CollisionFilter {
    /// Every pair of bodies from different models (bodies with collision off excepted), and
    /// the self-collision pairs of every model that has self-collision on.
    All,
    /// The self-collision pairs of one model (its allowed set excepted).
    SelfCollision(ModelId),
    /// Bodies of one model against those of another.
    Between(ModelId, ModelId),
    /// Bodies of one model against those of every other model.
    Against(ModelId),
}

/// Two shapes in contact.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CollisionPair {
    /// One shape.
    pub a: ShapeId,
    /// The other.
    pub b: ShapeId,
}

/// The distance between two shapes (or the closest pair of two bodies or models).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Distance {
    /// The shape on the first side.
    pub a: ShapeId,
    /// The shape on the second side.
    pub b: ShapeId,
    /// Signed distance, m: negative is the penetration depth.
    pub distance: f64,
    /// Closest (deepest, when penetrating) point on `a`'s surface, world frame.
    pub point_a: DVec3,
    /// Closest (deepest) point on `b`'s surface, world frame.
    pub point_b: DVec3,
}

impl Distance {
    /// The same distance seen from the other side.
    pub fn swapped(self) -> Self {
        Self {
            a: self.b,
            b: self.a,
            distance: self.distance,
            point_a: self.point_b,
            point_b: self.point_a,
        }
    }
}

/// The first shape a ray hits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// The shape.
    pub shape: ShapeId,
    /// Distance along the ray to the hit, m (0 when the ray starts inside a solid shape).
    pub distance: f64,
    /// The hit point, world frame.
    pub point: DVec3,
    /// The surface normal there, world frame.
    pub normal: DVec3,
}

/// Whether two placed shapes overlap (touching counts). Pairs parry cannot test (two
/// half-spaces) count as not colliding.
#[inline]
pub(crate) fn shapes_intersect(a: &Shape, b: &Shape) -> bool {
    query::intersection_test(&a.world, &*a.parry, &b.world, &*b.parry)
        .map(|r| r.intersecting)
        .unwrap_or(false)
}

/// Signed distance between two placed shapes with witness points (`a`, `b` are only carried
/// into the result). `None` for pairs parry cannot measure (two half-spaces).
///
/// The distance comes first (parry's branch-and-bound over mesh trees), then the witness
/// points within just that distance: asking for closest points with an unbounded margin would
/// visit every triangle pair of two meshes.
pub(crate) fn shapes_distance(sa: &Shape, a: ShapeId, sb: &Shape, b: ShapeId) -> Option<Distance> {
    let make = |distance, point_a, point_b| Distance {
        a,
        b,
        distance,
        point_a,
        point_b,
    };
    match (sa.geometry(), sb.geometry()) {
        (Geometry::Mesh(ma), Geometry::Mesh(mb)) => {
            // Meshes are surfaces: intersecting ones are at distance 0, at a common point (coal
            // answers 0 too); there is no penetration depth between two triangle soups.
            let (d, p, q) = mesh_distance::trimesh_distance(ma, &sa.world, mb, &sb.world)?;
            return Some(make(d, p, q));
        }
        (Geometry::Mesh(m), g) | (g, Geometry::Mesh(m))
            if !matches!(g, Geometry::HalfSpace { .. }) =>
        {
            let mesh_first = matches!(sa.geometry(), Geometry::Mesh(_));
            let (sm, sc) = if mesh_first { (sa, sb) } else { (sb, sa) };
            if let Some((d, pm, pc)) = mesh_convex_distance(m, sm, sc) {
                return Some(if mesh_first {
                    make(d, pm, pc)
                } else {
                    make(d, pc, pm)
                });
            }
        }
        _ => {
            let d = query::distance(&sa.world, &*sa.parry, &sb.world, &*sb.parry)
                .ok()?
                .distance;
            if d > 0.0 {
                if let Some((p, q)) = shapes_closest_points(sa, sb, d) {
                    let (p, q) = polish(sa, sb, p, q);
                    return Some(make((q - p).length(), p, q));
                }
                // GJK saw them touch after all (within its last digits): the contact below.
            }
        }
    }
    // Touching or penetrating: the deepest points, from parry's contact query (EPA or exact);
    // a small prediction keeps pairs that merely touch.
    let c = query::contact(&sa.world, &*sa.parry, &sb.world, &*sb.parry, 1e-6).ok()??;
    Some(make(c.dist, c.point1, c.point2))
}

/// Distance between a mesh shape `sm` (`m`) and a convex one `sc` with the points (mesh's
/// first), `None` when they touch or overlap (then the caller asks for the contact). The mesh's
/// convex hull first: when the hull's witness point lies on the mesh, that is the answer
/// (polished like convex pairs); otherwise parry's descent of the mesh's tree.
fn mesh_convex_distance(m: &TriangleMesh, sm: &Shape, sc: &Shape) -> Option<(f64, DVec3, DVec3)> {
    if let Some(hull) = m.hull() {
        let d = query::distance(&sm.world, &**hull, &sc.world, &*sc.parry)
            .ok()?
            .distance;
        if d <= 0.0 {
            // The hull reaches the shape; the mesh may or may not: parry decides below.
        } else if let Ok(ClosestPoints::WithinMargin(p, q)) =
            query::closest_points(&sm.world, &**hull, &sc.world, &*sc.parry, d * 1.5 + 1e-9)
        {
            let (p, q) = polish_parry(hull, &sm.world, &sc.parry, &sc.world, p, q);
            let local = sm.world.inverse_transform_point(p);
            if mesh_distance::point_mesh_distance(m, local, 1e-10).0 <= 1e-10 {
                return Some(((q - p).length(), p, q));
            }
        }
    }
    let d = query::distance(&sm.world, &*sm.parry, &sc.world, &*sc.parry)
        .ok()?
        .distance;
    if d <= 0.0 {
        return None;
    }
    for margin in [d * (1.0 + 1e-6) + 1e-9, d * 1.5 + 1e-9] {
        if let Ok(ClosestPoints::WithinMargin(p, q)) =
            query::closest_points(&sm.world, &*sm.parry, &sc.world, &*sc.parry, margin)
        {
            return Some(((q - p).length(), p, q));
        }
    }
    None
}

/// Closest points refined by alternating exact projections (parry's closed-form point
/// projections onto boxes, spheres, capsules, cylinders and cones): each step projects the point
/// of one shape onto the other, which never increases the distance and converges to the
/// closest pair of two convex shapes. parry's GJK stops about 1e-6 m short on curved
/// surfaces (its simplex loses precision there); a few projections close that gap. Stops when
/// a step gains less than 1e-15 m, or after 64 steps.
fn polish(sa: &Shape, sb: &Shape, p: DVec3, q: DVec3) -> (DVec3, DVec3) {
    if !(sa.geometry().is_convex() && sb.geometry().is_convex()) {
        return (p, q);
    }
    polish_parry(&sa.parry, &sa.world, &sb.parry, &sb.world, p, q)
}

/// [`polish`] on parry shapes (convex) at their poses.
fn polish_parry(
    a: &SharedShape,
    pa: &Pose,
    b: &SharedShape,
    pb: &Pose,
    mut p: DVec3,
    mut q: DVec3,
) -> (DVec3, DVec3) {
    let mut d = (q - p).length();
    for _ in 0..64 {
        let q2 = b.project_point(pb, p, true).point;
        let p2 = a.project_point(pa, q2, true).point;
        let d2 = (q2 - p2).length();
        if !(d2 < d - 1e-15 && d2 > 0.0) {
            break;
        }
        (p, q, d) = (p2, q2, d2);
    }
    (p, q)
}

/// The closest points of two shapes known to be `d > 0` apart.
fn shapes_closest_points(sa: &Shape, sb: &Shape, d: f64) -> Option<(DVec3, DVec3)> {
    {
        let margin = d * 1.5 + 1e-9;
        match query::closest_points(&sa.world, &*sa.parry, &sb.world, &*sb.parry, margin).ok()? {
            ClosestPoints::WithinMargin(p, q) => Some((p, q)),
            // GJK's last digits: the pair is at `d`, seen as touching or just beyond the margin.
            ClosestPoints::Intersecting | ClosestPoints::Disjoint => None,
        }
    }
}
