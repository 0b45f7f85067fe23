//! Distance between two triangle meshes: a simultaneous best-first descent of both meshes'
//! bounding-volume trees ([`crate::geometry::mesh_tree`]; a bounding-volume test tree, as in PQP
//! and coal) pruned by the best distance found so far, with an exact triangle–triangle distance
//! at the leaves.
//!
//! parry measures a mesh against a mesh one triangle of the first against the whole second
//! mesh, bounded only by the second mesh's overall box, which for two links of an arm visits
//! hundreds of triangle–mesh queries (milliseconds); descending both trees together bounds
//! every node pair by its own bounds.
//!
//! Triangle–triangle distance (Ericson, *Real-Time Collision Detection*, §5.1.9 and §5.2.7):
//! two triangles that do not intersect are closest between an edge of one and an edge of the
//! other, or between a vertex of one and the inside of the other; they intersect exactly when
//! an edge of one crosses the other. All cases are closed form.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::{DMat3, DVec3};
use parry3d_f64::math::Pose;

use crate::capsule::segment_segment_parameters;
use crate::geometry::TriangleMesh;
use crate::geometry::mesh_tree::Node;

/// The closest points of two triangles and their distance (0 with a common point when they
/// intersect).
pub(crate) fn triangle_distance(a: &[DVec3; 3], b: &[DVec3; 3]) -> (f64, DVec3, DVec3) {
    triangle_distance_apart(a, b, false)
}

/// [`triangle_distance`]; with `apart` the caller knows they do not intersect (a positive lower
/// bound) and the crossing test is skipped.
fn triangle_distance_apart(a: &[DVec3; 3], b: &[DVec3; 3], apart: bool) -> (f64, DVec3, DVec3) {
    // An edge of one through the other: they intersect.
    for (t, u) in [(a, b), (b, a)].into_iter().filter(|_| !apart) {
        for k in 0..3 {
            if let Some(p) = segment_triangle(t[k], t[(k + 1) % 3], u) {
                return (0.0, p, p);
            }
        }
    }
    let mut best = (f64::INFINITY, DVec3::ZERO, DVec3::ZERO);
    let mut offer = |p: DVec3, q: DVec3| {
        let d = (p - q).length_squared();
        if d < best.0 {
            best = (d, p, q);
        }
    };
    for i in 0..3 {
        let (p1, d1) = (a[i], a[(i + 1) % 3] - a[i]);
        for j in 0..3 {
            let (p2, d2) = (b[j], b[(j + 1) % 3] - b[j]);
            let (s, t) = segment_segment_parameters(p1, d1, p2, d2);
            offer(p1 + d1 * s, p2 + d2 * t);
        }
    }
    for &v in a {
        if let Some(q) = project_inside(v, b) {
            offer(v, q);
        }
    }
    for &v in b {
        if let Some(q) = project_inside(v, a) {
            offer(q, v);
        }
    }
    (best.0.sqrt(), best.1, best.2)
}

/// The projection of `p` onto the plane of triangle `t` when it falls inside the triangle.
fn project_inside(p: DVec3, t: &[DVec3; 3]) -> Option<DVec3> {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let nn = n.length_squared();
    if nn <= 1e-300 {
        return None;
    }
    let q = p - n * ((p - t[0]).dot(n) / nn);
    let inside = (0..3).all(|k| (t[(k + 1) % 3] - t[k]).cross(q - t[k]).dot(n) >= 0.0);
    inside.then_some(q)
}

/// Where the segment `p`–`q` crosses triangle `t` (Möller–Trumbore), if it does.
fn segment_triangle(p: DVec3, q: DVec3, t: &[DVec3; 3]) -> Option<DVec3> {
    let d = q - p;
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let h = d.cross(e2);
    let det = e1.dot(h);
    let scale = e1.length() * e2.length() * d.length();
    if det.abs() <= 1e-14 * scale {
        return None; // parallel: no crossing point (touching edges are found as distance 0)
    }
    let f = 1.0 / det;
    let s = p - t[0];
    let u = f * s.dot(h);
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qv = s.cross(e1);
    let v = f * d.dot(qv);
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let r = f * e2.dot(qv);
    (0.0..=1.0).contains(&r).then(|| p + d * r)
}

/// A lower bound of the distance between node `n1` of one tree and `n2` of the other: the
/// largest of the spheres' gap and the separations of the oriented boxes along the axes of
/// either (the distance from one box to the other's bounding box aligned with the first). `x`
/// maps `n2`'s mesh frame into `n1`'s, `r` is its rotation.
#[inline]
fn lower_bound(n1: &Node, n2: &Node, x: &Pose, r: &DMat3) -> f64 {
    let c2 = x.transform_point(n2.center);
    let d = c2 - n1.center;
    let spheres = d.length() - n1.radius - n2.radius;
    // n2's axes in n1's box frame, and the centres' offset there.
    let c = n1.axes.transpose() * (*r * n2.axes);
    let t = n1.axes.transpose() * d;
    let ac = DMat3::from_cols(c.x_axis.abs(), c.y_axis.abs(), c.z_axis.abs());
    // Along n1's axes: |t_i| − h1_i − Σ_j |c_ij| h2_j.
    let gap1 = (t.abs() - n1.half - ac * n2.half).max(DVec3::ZERO);
    // Along n2's axes: |cᵀ t|_j − Σ_i |c_ij| h1_i − h2_j.
    let gap2 = ((c.transpose() * t).abs() - ac.transpose() * n1.half - n2.half).max(DVec3::ZERO);
    spheres.max(gap1.length_squared().max(gap2.length_squared()).sqrt())
}

/// How close to a mesh's triangles a hull's witness point must be to count as on the mesh, m.
const ON_SURFACE: f64 = 1e-10;

/// The distance between two convex hulls and their closest points (world frame), if apart.
fn hull_distance(
    ha: &parry3d_f64::shape::SharedShape,
    pa: &Pose,
    hb: &parry3d_f64::shape::SharedShape,
    pb: &Pose,
) -> Option<(f64, DVec3, DVec3)> {
    use parry3d_f64::query::{self, ClosestPoints};
    let d = query::distance(pa, &**ha, pb, &**hb).ok()?.distance;
    if d <= 0.0 {
        return None;
    }
    match query::closest_points(pa, &**ha, pb, &**hb, d * 1.5 + 1e-9).ok()? {
        ClosestPoints::WithinMargin(p, q) => Some(((q - p).length(), p, q)),
        _ => None,
    }
}

/// The distance from `p` (mesh frame) to the mesh's triangles, searched only below `limit`
/// (returns a value ≥ `limit` when nothing is closer), and the closest triangle found.
pub(crate) fn point_mesh_distance(m: &TriangleMesh, p: DVec3, limit: f64) -> (f64, Option<usize>) {
    let t = m.tree();
    let mut best = (limit * 2.0 + 1.0, None);
    let mut stack = vec![0u32];
    let node_bound = |n: &Node| {
        let l = (n.axes.transpose() * (p - n.center)).abs() - n.half;
        l.max(DVec3::ZERO).length()
    };
    while let Some(k) = stack.pop() {
        let n = &t.nodes[k as usize];
        if node_bound(n) >= best.0 || node_bound(n) > limit {
            continue;
        }
        if n.leaf {
            for &tri in &t.order[n.a as usize..n.b as usize] {
                let c = m.triangle(tri as usize);
                let d = (closest_on_triangle(p, &c) - p).length();
                if d < best.0 {
                    best = (d, Some(tri as usize));
                }
            }
        } else {
            stack.push(n.a);
            stack.push(n.b);
        }
    }
    best
}

/// The point of triangle `t` closest to `p` (Ericson §5.1.5).
fn closest_on_triangle(p: DVec3, t: &[DVec3; 3]) -> DVec3 {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// A node pair to visit, by its lower bound (smallest first).
#[derive(PartialEq)]
struct Pair(f64, u32, u32);

impl Eq for Pair {}

impl PartialOrd for Pair {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Pair {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0)
    }
}

/// The distance between meshes `a` at `pa` and `b` at `pb` (world poses) and the closest
/// points (world frame); 0 with a common point when they intersect. Best first: the node pair
/// with the smallest lower bound is split next (the one with the larger sphere), and the
/// search stops when no pair left can beat the best triangle pair found.
pub(crate) fn trimesh_distance(
    a: &TriangleMesh,
    pa: &Pose,
    b: &TriangleMesh,
    pb: &Pose,
) -> Option<(f64, DVec3, DVec3)> {
    // The convex hulls' distance is a lower bound; when its witness points lie on both meshes
    // it is the meshes' distance (a certificate, checked, not assumed).
    let mut floor = 0.0;
    let mut seed = None;
    if let (Some(ha), Some(hb)) = (a.hull(), b.hull()) {
        if let Some((d, p, q)) = hull_distance(ha, pa, hb, pb) {
            let (pl, ql) = (pa.inverse_transform_point(p), pb.inverse_transform_point(q));
            let (da, ta) = point_mesh_distance(a, pl, f64::INFINITY);
            let (db, tb) = point_mesh_distance(b, ql, f64::INFINITY);
            if da <= ON_SURFACE && db <= ON_SURFACE {
                return Some((d, p, q));
            }
            floor = d;
            // The mesh triangles nearest to the hull's witnesses: a first upper bound.
            seed = ta.zip(tb);
        }
    }
    let (ta, tb) = (a.tree(), b.tree());
    if ta.nodes.is_empty() || tb.nodes.is_empty() {
        return None;
    }
    let x = pa.inv_mul(pb); // b's frame to a's
    let r = DMat3::from_quat(x.rotation);
    let mut best = (f64::INFINITY, DVec3::ZERO, DVec3::ZERO);
    let leaf_pair = |i: u32, j: u32, lb: f64, best: &mut (f64, DVec3, DVec3)| {
        let (n1, n2) = (&ta.nodes[i as usize], &tb.nodes[j as usize]);
        for &t1 in &ta.order[n1.a as usize..n1.b as usize] {
            let c1 = a.triangle(t1 as usize);
            for &t2 in &tb.order[n2.a as usize..n2.b as usize] {
                let c2 = b.triangle(t2 as usize).map(|p| x.transform_point(p));
                let (d, p, q) = triangle_distance_apart(&c1, &c2, lb > 0.0);
                if d < best.0 {
                    *best = (d, p, q);
                }
            }
        }
    };
    if let Some((t1, t2)) = seed {
        let c2 = b.triangle(t2).map(|p| x.transform_point(p));
        best = triangle_distance(&a.triangle(t1), &c2);
    }
    // A first upper bound: dive from the roots to a leaf pair, always into the closer children.
    // Best-first alone finds no leaf until every pair of near-equal bounds above it is split.
    let (mut i, mut j) = (0u32, 0u32);
    loop {
        let (n1, n2) = (&ta.nodes[i as usize], &tb.nodes[j as usize]);
        if n1.leaf && n2.leaf {
            leaf_pair(i, j, lower_bound(n1, n2, &x, &r), &mut best);
            break;
        }
        let split_first = !n1.leaf && (n2.leaf || n1.radius >= n2.radius);
        let c: [(u32, u32); 2] = if split_first {
            [(n1.a, j), (n1.b, j)]
        } else {
            [(i, n2.a), (i, n2.b)]
        };
        let lb =
            |(p, q): (u32, u32)| lower_bound(&ta.nodes[p as usize], &tb.nodes[q as usize], &x, &r);
        (i, j) = if lb(c[0]) <= lb(c[1]) { c[0] } else { c[1] };
    }
    let mut heap = BinaryHeap::new();
    heap.push(Pair(lower_bound(&ta.nodes[0], &tb.nodes[0], &x, &r), 0, 0));
    while let Some(Pair(lb, i, j)) = heap.pop() {
        if lb >= best.0 || best.0 <= floor {
            break;
        }
        let (n1, n2) = (&ta.nodes[i as usize], &tb.nodes[j as usize]);
        if n1.leaf && n2.leaf {
            leaf_pair(i, j, lb, &mut best);
            if best.0 == 0.0 {
                break;
            }
            continue;
        }
        // Split the node with the larger sphere (a leaf cannot be split).
        let split_first = !n1.leaf && (n2.leaf || n1.radius >= n2.radius);
        let children: [(u32, u32); 2] = if split_first {
            [(n1.a, j), (n1.b, j)]
        } else {
            [(i, n2.a), (i, n2.b)]
        };
        for (ci, cj) in children {
            let lb = lower_bound(&ta.nodes[ci as usize], &tb.nodes[cj as usize], &x, &r);
            if lb < best.0 {
                heap.push(Pair(lb, ci, cj));
            }
        }
    }
    best.0.is_finite().then(|| {
        (
            best.0,
            pa.transform_point(best.1),
            pa.transform_point(best.2),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(a: &[DVec3; 3], b: &[DVec3; 3]) -> f64 {
        let n = 25;
        let mut best = f64::INFINITY;
        let pts = |t: &[DVec3; 3]| {
            let mut v = Vec::new();
            for i in 0..=n {
                for j in 0..=n - i {
                    let (u, w) = (i as f64 / n as f64, j as f64 / n as f64);
                    v.push(t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * w);
                }
            }
            v
        };
        let (pa, pb) = (pts(a), pts(b));
        for p in &pa {
            for q in &pb {
                best = best.min((*p - *q).length());
            }
        }
        best
    }

    #[test]
    fn triangle_distance_against_sampling() {
        let mut rng = rl_core::algo::ik::SplitMix64::new(0x2545_f491_4f6c_dd1d);
        let mut r = || rng.next_f64() * 2.0 - 1.0;
        for _ in 0..60 {
            let mut p = [DVec3::ZERO; 7];
            for q in &mut p {
                *q = DVec3::new(r(), r(), r());
            }
            let off = p[6] * 0.8;
            let a = [p[0], p[1], p[2]];
            let b = [p[3] + off, p[4] + off, p[5] + off];
            let (d, p, q) = triangle_distance(&a, &b);
            assert!(((p - q).length() - d).abs() < 1e-12);
            let sampled = brute(&a, &b);
            assert!(d <= sampled + 1e-12, "{d} > {sampled}");
            assert!(sampled - d < 0.05, "{d} vs {sampled}");
        }
        // A triangle piercing another: distance 0.
        let a = [
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let b = [
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(0.1, 0.0, 1.0),
            DVec3::new(0.0, 0.2, 1.0),
        ];
        assert_eq!(triangle_distance(&a, &b).0, 0.0);
    }
}
