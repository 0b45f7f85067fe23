//! What one load may read and build, so that a small hostile file cannot take the machine's
//! memory or time: a VRML "billion laughs" (a `DEF` used ten times by a node `DEF`'d and used
//! ten times, eight levels deep: 650 bytes, 10⁸ shapes), the same fan-out through `Inline`
//! files, a URDF whose 100 000 links all name one large mesh, `/dev/zero` named as a file.
//!
//! [`SceneLimits`] bounds the bytes read (every file through rl-core's bounded reader,
//! [`rl_core::loader::read_text`]: a FIFO or a device is refused unread) and what the scene
//! expands into: node visits, shapes, vertices and triangles, counted after `DEF`/`USE` and
//! `Inline` expansion (a mesh used twice counts twice: each use becomes its own collision
//! shape). A load that would pass a limit stops there with [`SgErrorKind::TooLarge`], naming
//! the file and the chain of nodes that led to it. Every loader takes its limits from the
//! [`super::MeshCache`] it is given ([`super::MeshCache::with_limits`]) or from a `_with`
//! variant; the default is [`SceneLimits::DEFAULT`].

use std::path::Path;

use crate::error::{SgError, SgErrorKind};

/// Bounds on one load (a scene file and everything it names).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneLimits {
    /// Largest file read, in bytes (a scene, a VRML file, an inlined file, a mesh, a YAML
    /// planning scene, a URDF or SRDF).
    pub max_file_bytes: u64,
    /// Most bytes read by one VRML scene with all its inlined files.
    pub max_total_bytes: u64,
    /// Most distinct files one VRML scene inlines (each is read once, however often it is
    /// inlined).
    pub max_files: usize,
    /// Most VRML nodes parsed, over all files of one scene.
    pub max_nodes: usize,
    /// Most node visits while searching and expanding the scene graph (`DEF`/`USE` and
    /// `Inline` make a small file a large tree; a search for a name that is not there walks
    /// all of it).
    pub max_visits: u64,
    /// Most shapes after expansion.
    pub max_shapes: usize,
    /// Most mesh vertices after expansion (the sum over every shape).
    pub max_vertices: usize,
    /// Most mesh triangles after expansion (the sum over every shape).
    pub max_triangles: usize,
}

impl SceneLimits {
    /// 64 MiB per file (rl-core's model limit), 128 MiB and 1024 files per VRML scene, 2 million
    /// VRML nodes, 20 million node visits, 200 000 shapes, 4 million vertices, 4 million
    /// triangles. RL's example scenes are far below (the largest file is 1.4 MB, the largest
    /// scene 60 shapes and 32 000 triangles); a scene at the triangle limit takes about 0.8 GB
    /// to load, one at the shape limit 130 MB (see rl-sg/NOTES.md for the measurement).
    pub const DEFAULT: Self = Self {
        max_file_bytes: 64 << 20,
        max_total_bytes: 128 << 20,
        max_files: 1024,
        max_nodes: 2_000_000,
        max_visits: 20_000_000,
        max_shapes: 200_000,
        max_vertices: 4_000_000,
        max_triangles: 4_000_000,
    };
}

impl Default for SceneLimits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What one load has used so far, against its limits.
#[derive(Clone, Debug)]
pub(crate) struct Budget {
    pub(crate) limits: SceneLimits,
    bytes: u64,
    nodes: usize,
    visits: u64,
    shapes: usize,
    vertices: usize,
    triangles: usize,
}

impl Budget {
    pub(crate) fn new(limits: SceneLimits) -> Self {
        Self {
            limits,
            bytes: 0,
            nodes: 0,
            visits: 0,
            shapes: 0,
            vertices: 0,
            triangles: 0,
        }
    }

    fn too_large(what: &'static str, limit: u64) -> SgError {
        SgError::new(SgErrorKind::TooLarge { what, limit })
    }

    /// Reads the text of `path` within the file limit and counts it against the total.
    pub(crate) fn read_text(&mut self, path: &Path) -> Result<String, SgError> {
        let text = super::read_text_within(path, self.limits.max_file_bytes)?;
        self.bytes = self.bytes.saturating_add(text.len() as u64);
        if self.bytes > self.limits.max_total_bytes {
            return Err(
                Self::too_large("bytes read for one scene", self.limits.max_total_bytes)
                    .in_file(path),
            );
        }
        Ok(text)
    }

    /// The node budget left for the next file's parser.
    pub(crate) fn nodes_left(&self) -> usize {
        self.limits.max_nodes.saturating_sub(self.nodes)
    }

    /// Counts `n` more parsed nodes (within [`Budget::nodes_left`] by the parser).
    pub(crate) fn add_nodes(&mut self, n: usize) {
        self.nodes = self.nodes.saturating_add(n);
    }

    /// One more node visited.
    pub(crate) fn visit(&mut self) -> Result<(), SgError> {
        self.visits += 1;
        if self.visits > self.limits.max_visits {
            return Err(Self::too_large(
                "number of node visits (DEF/USE and Inline expansion)",
                self.limits.max_visits,
            ));
        }
        Ok(())
    }

    /// One more shape of `vertices` vertices and `triangles` triangles, checked before it is
    /// built.
    pub(crate) fn shape(&mut self, vertices: usize, triangles: usize) -> Result<(), SgError> {
        self.shapes += 1;
        self.vertices = self.vertices.saturating_add(vertices);
        self.triangles = self.triangles.saturating_add(triangles);
        let l = &self.limits;
        if self.shapes > l.max_shapes {
            return Err(Self::too_large(
                "number of shapes (after DEF/USE and Inline expansion)",
                l.max_shapes as u64,
            ));
        }
        if self.vertices > l.max_vertices {
            return Err(Self::too_large(
                "number of mesh vertices (after DEF/USE and Inline expansion)",
                l.max_vertices as u64,
            ));
        }
        if self.triangles > l.max_triangles {
            return Err(Self::too_large(
                "number of mesh triangles (after DEF/USE and Inline expansion)",
                l.max_triangles as u64,
            ));
        }
        Ok(())
    }
}
