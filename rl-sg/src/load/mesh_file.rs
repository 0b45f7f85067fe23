//! Mesh files: STL (binary and ASCII), Wavefront OBJ and COLLADA (`.dae`), through the
//! `mesh-loader` crate (one small parser for the three formats robot descriptions use).
//!
//! All parts of a file are merged into one [`TriangleMesh`]. COLLADA node transforms and the
//! `<unit meter>` scale are applied; `<up_axis>` is not (as ROS's viewers and Pinocchio's
//! loaders treat robot meshes). OBJ materials are not read.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;
use rl_core::loader::InputLimits;

use super::SceneLimits;
use crate::error::{SgError, SgErrorKind};
use crate::geometry::{MeshStats, TriangleMesh};

/// The mesh formats by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Stl,
    Obj,
    Collada,
}

fn format_of(path: &Path) -> Result<Format, SgError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "stl" => Ok(Format::Stl),
        "obj" => Ok(Format::Obj),
        "dae" => Ok(Format::Collada),
        _ => Err(SgError::new(SgErrorKind::UnsupportedFormat {
            format: format!(
                "mesh file \"{}\" (supported: .stl, .obj, .dae)",
                path.display()
            ),
        })
        .in_file(path)),
    }
}

/// Whether `bytes` have exactly the size of a binary STL with the triangle count in its header.
fn is_binary_stl(bytes: &[u8]) -> bool {
    match bytes.get(80..84) {
        Some(n) => {
            let n = u32::from_le_bytes([n[0], n[1], n[2], n[3]]) as usize;
            n.checked_mul(50).and_then(|b| b.checked_add(84)) == Some(bytes.len())
        }
        None => false,
    }
}

/// Reads the mesh in `bytes`, named `path` (for its format and for errors).
pub fn mesh_from_bytes(bytes: &[u8], path: &Path) -> Result<(TriangleMesh, MeshStats), SgError> {
    let format = format_of(path)?;
    let loader = mesh_loader::Loader::default();
    let scene = match format {
        Format::Stl if is_binary_stl(bytes) && bytes.starts_with(b"solid") => {
            // A binary STL whose free-text header begins with "solid" (exporters write that):
            // mesh-loader takes it for ASCII. The size settles it (84 + 50 bytes per triangle,
            // as assimp decides too); a copy with the header's first byte changed reads as binary.
            let mut copy = bytes.to_vec();
            copy[0] = b'_';
            loader.load_stl_from_slice(&copy, path)
        }
        Format::Stl => loader.load_stl_from_slice(bytes, path),
        Format::Collada => {
            // COLLADA is XML, read by roxmltree inside mesh-loader: the same attribute, depth
            // and size bounds as every XML file here, checked first.
            if let Ok(text) = std::str::from_utf8(bytes) {
                let limits = InputLimits {
                    max_bytes: u64::MAX,
                    ..InputLimits::DEFAULT
                };
                super::xml::check(text, &limits).map_err(|e| e.in_file(path))?;
            }
            loader.load_collada_from_slice(bytes, path)
        }
        // Materials are not needed: every `mtllib` reads as empty.
        Format::Obj => loader.load_obj_from_slice_with_reader(bytes, path, |_| Ok(Vec::new())),
    }
    .map_err(|e| SgError::syntax(e.to_string()).in_file(path))?;
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for m in &scene.meshes {
        let base = u32::try_from(vertices.len())
            .map_err(|_| SgError::degenerate("more than 2³² vertices").in_file(path))?;
        vertices.extend(
            m.vertices
                .iter()
                .map(|v| DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]))),
        );
        triangles.extend(m.faces.iter().map(|f| f.map(|i| i.saturating_add(base))));
    }
    TriangleMesh::new(vertices, triangles).map_err(|e| e.in_file(path))
}

/// Reads the mesh file at `path` (at most [`SceneLimits::DEFAULT`]'s file size).
pub fn load_mesh(path: &Path) -> Result<(TriangleMesh, MeshStats), SgError> {
    load_mesh_within(path, SceneLimits::DEFAULT.max_file_bytes)
}

/// Reads the mesh file at `path`, refused above `max_bytes` (and unread when it is not a
/// regular file: rl-core's bounded reader).
pub fn load_mesh_within(path: &Path, max_bytes: u64) -> Result<(TriangleMesh, MeshStats), SgError> {
    format_of(path)?;
    let bytes = rl_core::loader::read_bytes(path, max_bytes)?;
    mesh_from_bytes(&bytes, path)
}

/// Meshes already read, by path: robot descriptions use one file for several links, and
/// several descriptions of one robot share their files. It carries the [`SceneLimits`] of the
/// loads it serves ([`super::load_scene_file`], the URDF readers).
#[derive(Clone, Debug, Default)]
pub struct MeshCache {
    meshes: HashMap<PathBuf, (Arc<TriangleMesh>, MeshStats)>,
    limits: SceneLimits,
}

impl MeshCache {
    /// An empty cache, with the default limits.
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty cache whose loads keep within `limits`.
    pub fn with_limits(limits: SceneLimits) -> Self {
        Self {
            meshes: HashMap::new(),
            limits,
        }
    }

    /// The limits of the loads it serves.
    pub fn limits(&self) -> &SceneLimits {
        &self.limits
    }

    /// The mesh at `path`, read once.
    pub fn get(&mut self, path: &Path) -> Result<(Arc<TriangleMesh>, MeshStats), SgError> {
        if let Some(m) = self.meshes.get(path) {
            return Ok(m.clone());
        }
        let (m, stats) = load_mesh_within(path, self.limits.max_file_bytes)?;
        let entry = (Arc::new(m), stats);
        self.meshes.insert(path.to_path_buf(), entry.clone());
        Ok(entry)
    }

    /// How many meshes it holds.
    pub fn len(&self) -> usize {
        self.meshes.len()
    }

    /// Whether it holds none.
    pub fn is_empty(&self) -> bool {
        self.meshes.is_empty()
    }
}
