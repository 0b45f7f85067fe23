//! Triangle meshes: checked on construction, so a scene never holds one that parry could
//! choke on.

use std::collections::HashMap;
use std::sync::OnceLock;

use glam::DVec3;

use super::mesh_tree::MeshTree;
use crate::error::{SgError, SgErrorKind};

/// Triangles of less than this area (m²) are degenerate: a slit or a point, no surface.
const MIN_AREA: f64 = 1e-14;

/// What a mesh check found and dropped (nothing is dropped silently: loaders report these).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MeshStats {
    /// Triangles in the input.
    pub triangles_in: usize,
    /// Triangles dropped because they have no area (repeated or collinear corners).
    pub degenerate_dropped: usize,
    /// Vertices not used by any triangle (kept; they do not affect queries on the triangles).
    pub unused_vertices: usize,
    /// Edges shared by more than two triangles ([`TriangleMesh::non_manifold_edges`]), and one
    /// of them: harmless to collision with surfaces (coal's and FCL's semantics, and ours), but
    /// such a mesh bounds no solid.
    pub non_manifold_edges: (usize, Option<(u32, u32)>),
}

impl MeshStats {
    /// Notes on what was dropped or is odd, for a model's warnings (empty when all is well).
    pub fn notes(&self, what: &str) -> Vec<String> {
        let mut out = Vec::new();
        if self.degenerate_dropped > 0 {
            out.push(format!(
                "{what}: {} of {} triangles have no area and were dropped",
                self.degenerate_dropped, self.triangles_in
            ));
        }
        if let (n, Some((a, b))) = self.non_manifold_edges {
            out.push(format!(
                "{what}: {n} edges are shared by more than two triangles (e.g. vertices {a}–{b}): \
                 not a closed surface, checked as triangles"
            ));
        }
        out
    }

    /// The strict check: an error for dropped triangles or non-manifold edges.
    pub fn strict(&self) -> Result<(), SgError> {
        if self.degenerate_dropped > 0 {
            return Err(SgError::degenerate(format!(
                "{} of {} triangles have no area",
                self.degenerate_dropped, self.triangles_in
            )));
        }
        if let (edges, Some(example)) = self.non_manifold_edges {
            return Err(SgError::new(SgErrorKind::NonManifoldMesh {
                edges,
                example,
            }));
        }
        Ok(())
    }
}

/// A triangle mesh: vertices (m, in the shape's frame) and triangles as vertex indices,
/// counter-clockwise seen from outside where the source says so.
#[derive(Clone, Debug)]
pub struct TriangleMesh {
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// The bounding-volume tree for mesh–mesh distance, built on first use.
    tree: OnceLock<MeshTree>,
    /// The convex hull (parry's), built on first use; `None` for a flat mesh.
    hull: OnceLock<Option<parry3d_f64::shape::SharedShape>>,
}

impl PartialEq for TriangleMesh {
    fn eq(&self, other: &Self) -> bool {
        self.vertices == other.vertices && self.triangles == other.triangles
    }
}

impl TriangleMesh {
    /// Checks and builds a mesh: every vertex finite, every index in range; triangles without
    /// area are dropped (counted in the returned [`MeshStats`]); no triangle left is an
    /// [`crate::SgErrorKind::DegenerateMesh`], as is an empty input.
    pub fn new(
        vertices: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<(Self, MeshStats), SgError> {
        let mut stats = MeshStats {
            triangles_in: triangles.len(),
            ..MeshStats::default()
        };
        if vertices.is_empty() || triangles.is_empty() {
            return Err(SgError::degenerate(format!(
                "{} vertices and {} triangles",
                vertices.len(),
                triangles.len()
            )));
        }
        if let Some((i, v)) = vertices.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(SgError::invalid(
                format!("vertex {i}"),
                format!("{} {} {}", v.x, v.y, v.z),
                "not finite",
            ));
        }
        let n = vertices.len();
        let mut used = vec![false; n];
        let mut kept = Vec::with_capacity(triangles.len());
        for (k, t) in triangles.iter().enumerate() {
            if let Some(&bad) = t.iter().find(|&&i| i as usize >= n) {
                return Err(SgError::degenerate(format!(
                    "triangle {k} refers to vertex {bad}, but there are only {n}"
                )));
            }
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            if (b - a).cross(c - a).length() * 0.5 < MIN_AREA {
                stats.degenerate_dropped += 1;
                continue;
            }
            for &i in t {
                used[i as usize] = true;
            }
            kept.push(*t);
        }
        if kept.is_empty() {
            return Err(SgError::degenerate(format!(
                "all {} triangles have zero area",
                triangles.len()
            )));
        }
        stats.unused_vertices = used.iter().filter(|u| !**u).count();
        let mesh = Self {
            vertices,
            triangles: kept,
            tree: OnceLock::new(),
            hull: OnceLock::new(),
        };
        stats.non_manifold_edges = mesh.non_manifold_edges();
        Ok((mesh, stats))
    }

    /// The vertices.
    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    /// The triangles (indices into [`Self::vertices`]).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The bounding-volume tree over the triangles (built on first use).
    pub(crate) fn tree(&self) -> &MeshTree {
        self.tree
            .get_or_init(|| MeshTree::build(&self.vertices, &self.triangles))
    }

    /// The convex hull as a parry shape (built on first use), `None` when the mesh is flat.
    pub(crate) fn hull(&self) -> Option<&parry3d_f64::shape::SharedShape> {
        self.hull
            .get_or_init(|| parry3d_f64::shape::SharedShape::convex_hull(&self.vertices))
            .as_ref()
    }

    /// The three corners of triangle `k`.
    pub fn triangle(&self, k: usize) -> [DVec3; 3] {
        self.triangles[k].map(|i| self.vertices[i as usize])
    }

    /// The edges shared by more than two triangles, after merging vertices at identical
    /// positions (files such as STL repeat every vertex per triangle): the count and one of
    /// them. A closed surface has every edge in exactly two triangles; an open one has some in
    /// one; more than two means several sheets meet at the edge, and "inside" is undefined there.
    pub fn non_manifold_edges(&self) -> (usize, Option<(u32, u32)>) {
        let mut id: HashMap<[u64; 3], u32> = HashMap::with_capacity(self.vertices.len());
        let canon: Vec<u32> = self
            .vertices
            .iter()
            .enumerate()
            .map(|(i, v)| {
                // +0.0 and -0.0 are one position.
                let key = [v.x + 0.0, v.y + 0.0, v.z + 0.0].map(f64::to_bits);
                *id.entry(key).or_insert(i as u32)
            })
            .collect();
        let mut edges: HashMap<(u32, u32), u32> = HashMap::with_capacity(self.triangles.len() * 3);
        for t in &self.triangles {
            let t = t.map(|i| canon[i as usize]);
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                if a != b {
                    *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
                }
            }
        }
        let mut bad: Vec<(u32, u32)> = edges
            .into_iter()
            .filter(|(_, n)| *n > 2)
            .map(|(e, _)| e)
            .collect();
        bad.sort_unstable();
        (bad.len(), bad.first().copied())
    }

    /// The mesh with every vertex mapped by `f` (e.g. a scale, a transform); triangles whose
    /// area vanishes under `f` are dropped and counted again.
    pub fn map_vertices(&self, f: impl Fn(DVec3) -> DVec3) -> Result<(Self, MeshStats), SgError> {
        Self::new(
            self.vertices.iter().map(|&v| f(v)).collect(),
            self.triangles.clone(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        (
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
    }

    #[test]
    fn a_closed_tetrahedron_is_manifold() {
        let (v, t) = tetra();
        let (m, s) = TriangleMesh::new(v, t).unwrap();
        assert_eq!(s.degenerate_dropped, 0);
        assert_eq!(m.non_manifold_edges(), (0, None));
    }

    #[test]
    fn three_sheets_on_one_edge_are_non_manifold_even_with_repeated_vertices() {
        // Three triangles on the edge (0,0,0)–(1,0,0), each with its own copies (as in STL).
        let v = vec![
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            DVec3::ZERO,
            DVec3::X,
            DVec3::Z,
            DVec3::ZERO,
            DVec3::X,
            -DVec3::Y,
        ];
        let t = vec![[0, 1, 2], [3, 4, 5], [6, 7, 8]];
        let (m, _) = TriangleMesh::new(v, t).unwrap();
        assert_eq!(m.non_manifold_edges(), (1, Some((0, 1))));
    }

    #[test]
    fn bad_meshes_are_refused_and_slivers_dropped() {
        let (v, _) = tetra();
        assert!(TriangleMesh::new(v.clone(), vec![]).is_err());
        let e = TriangleMesh::new(v.clone(), vec![[0, 1, 7]]).unwrap_err();
        assert!(e.to_string().contains("vertex 7"), "{e}");
        let e = TriangleMesh::new(v.clone(), vec![[0, 0, 1], [0, 1, 1]]).unwrap_err();
        assert!(e.to_string().contains("zero area"), "{e}");
        let (m, s) = TriangleMesh::new(v.clone(), vec![[0, 0, 1], [0, 1, 2]]).unwrap();
        assert_eq!((s.degenerate_dropped, m.triangles().len()), (1, 1));
        assert_eq!(s.unused_vertices, 1);
        let mut nan = v;
        nan[2].y = f64::NAN;
        assert!(TriangleMesh::new(nan, vec![[0, 1, 2]]).is_err());
    }
}
