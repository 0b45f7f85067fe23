//! A bounding-volume tree over a mesh's triangles for mesh–mesh distance: every node carries an
//! oriented box (along the principal axes of its vertices, as in RAPID/PQP and coal's OBB trees)
//! and a bounding sphere, in the mesh's frame. The traversal bounds a node pair by the larger
//! of the spheres' gap and the boxes' separations along either box's axes.
//!
//! Built top down: the triangles are split at the median of their centroids along the longest
//! axis of the centroids' box, down to leaves of at most [`LEAF`] triangles. O(n log n).

use glam::{DMat3, DVec3};

/// Triangles per leaf at most.
pub(crate) const LEAF: usize = 1;

/// A node: its bounds, and either two children or a run of triangles.
#[derive(Clone, Debug)]
pub(crate) struct Node {
    /// Centre of the oriented box (and of the sphere).
    pub center: DVec3,
    /// The box's axes (columns, orthonormal).
    pub axes: DMat3,
    /// The box's half extents along its axes.
    pub half: DVec3,
    /// The sphere's radius.
    pub radius: f64,
    /// Children `(left, right)` for an inner node; for a leaf, the range `start..end` of
    /// [`MeshTree::order`].
    pub a: u32,
    pub b: u32,
    pub leaf: bool,
}

/// The tree: nodes (root first) and the triangle order its leaves index.
#[derive(Clone, Debug, Default)]
pub(crate) struct MeshTree {
    pub nodes: Vec<Node>,
    pub order: Vec<u32>,
}

impl MeshTree {
    /// Builds the tree of `triangles` over `vertices`.
    pub(crate) fn build(vertices: &[DVec3], triangles: &[[u32; 3]]) -> Self {
        let corners = |t: u32| triangles[t as usize].map(|i| vertices[i as usize]);
        let centroid: Vec<DVec3> = (0..triangles.len() as u32)
            .map(|t| {
                let [a, b, c] = corners(t);
                (a + b + c) / 3.0
            })
            .collect();
        let mut tree = MeshTree {
            nodes: Vec::with_capacity(2 * triangles.len() / LEAF + 1),
            order: (0..triangles.len() as u32).collect(),
        };
        if triangles.is_empty() {
            return tree;
        }
        // (node index, start, end) still to split.
        tree.nodes
            .push(bounds(&tree.order, &corners, 0, triangles.len()));
        let mut stack = vec![(0usize, 0usize, triangles.len())];
        while let Some((n, start, end)) = stack.pop() {
            if end - start <= LEAF {
                continue;
            }
            let slice = &mut tree.order[start..end];
            let (clo, chi) = slice
                .iter()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), &t| {
                    (l.min(centroid[t as usize]), h.max(centroid[t as usize]))
                });
            let ext = chi - clo;
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = slice.len() / 2;
            slice.select_nth_unstable_by(mid, |&p, &q| {
                centroid[p as usize][axis].total_cmp(&centroid[q as usize][axis])
            });
            let split = start + mid;
            let left = tree.nodes.len();
            tree.nodes.push(bounds(&tree.order, &corners, start, split));
            tree.nodes.push(bounds(&tree.order, &corners, split, end));
            let node = &mut tree.nodes[n];
            node.leaf = false;
            node.a = left as u32;
            node.b = left as u32 + 1;
            stack.push((left, start, split));
            stack.push((left + 1, split, end));
        }
        tree
    }
}

/// Orthonormal principal axes of `points` (identity when degenerate).
fn principal_axes(points: &[DVec3]) -> DMat3 {
    let n = points.len().max(1) as f64;
    let mean = points.iter().sum::<DVec3>() / n;
    let mut c = DMat3::ZERO;
    for p in points {
        let d = *p - mean;
        c += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    let e = parry3d_f64::math::SymmetricEigen3::new(c * (1.0 / n)).eigenvectors;
    let Some(a) = e.x_axis.try_normalize() else {
        return DMat3::IDENTITY;
    };
    let Some(b) = (e.y_axis - a * a.dot(e.y_axis)).try_normalize() else {
        return DMat3::IDENTITY;
    };
    let m = DMat3::from_cols(a, b, a.cross(b));
    if m.is_finite() { m } else { DMat3::IDENTITY }
}

/// A leaf node over `order[start..end]`.
fn bounds(order: &[u32], corners: &impl Fn(u32) -> [DVec3; 3], start: usize, end: usize) -> Node {
    let points: Vec<DVec3> = order[start..end].iter().flat_map(|&t| corners(t)).collect();
    let axes = principal_axes(&points);
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in &points {
        let l = axes.transpose() * *p;
        lo = lo.min(l);
        hi = hi.max(l);
    }
    let center = axes * ((lo + hi) / 2.0);
    let half = (hi - lo) / 2.0;
    let radius = points
        .iter()
        .map(|p| (*p - center).length())
        .fold(0.0, f64::max);
    Node {
        center,
        axes,
        half,
        radius,
        a: start as u32,
        b: end as u32,
        leaf: true,
    }
}
