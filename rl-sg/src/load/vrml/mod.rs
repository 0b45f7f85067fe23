//! VRML97 (`.wrl`), the subset RL's scenes use: `Transform`, `Group` (and the other grouping
//! nodes), `Inline`, `Shape` with `Box`, `Sphere`, `Cylinder`, `Cone` or `IndexedFaceSet` with
//! its `Coordinate`, and `DEF`/`USE`. Other nodes (appearance, lights, viewpoints) are read and
//! ignored; a `Shape` with any other geometry is an error that names it. No Rust VRML crate
//! exists; the reader is `parse` (syntax) plus this module (meaning).
//!
//! Meaning, as RL (through Coin3D) gives it:
//! - `Transform` is `T · C · R · SR · S · −SR · −C` (VRML97 §6.52); scales are baked into
//!   meshes, and into primitives where the result is still that primitive.
//! - `Cylinder` and `Cone` are along y in VRML: the shape's pose turns them onto our z.
//! - An `IndexedFaceSet` is a triangle mesh (polygons triangulated: a fan when the file says
//!   its faces are convex, ear clipping otherwise), or its convex hull when it says `convex
//!   TRUE` explicitly — RL's FCL back end makes the same choice. `ccw FALSE` flips the faces.
//! - `Inline` reads the first of its `url`s that exists, relative to the file; its content is
//!   an unnamed group (so RL's empty body name selects an inlined file as a whole).
//!
//! Bounds ([`SceneLimits`]): each file is read once however often it is inlined, within the
//! file, total-bytes, file-count and node limits; searching and expanding the graph counts node
//! visits, shapes, vertices and triangles, so a `DEF`/`USE` or `Inline` "billion laughs" stops
//! at a limit with an error naming the file and the chain of nodes that led there.

mod lexer;
mod parse;

pub(crate) use parse::NodeIndex;

use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{DAffine3, DMat3, DQuat, DVec3};
use rl_core::spatial::PlueckerTransform;

use self::parse::{Document, Node, Value};
use super::dir_of;
use super::limits::{Budget, SceneLimits};
use crate::error::{SgError, SgErrorKind};
use crate::geometry::{Geometry, MeshStats, TriangleMesh};
use crate::scene::{Model, Shape};

/// How deep `Inline`s may nest (a file inlining itself is caught by this too).
const MAX_INLINE_DEPTH: usize = 16;
/// How deep the tree of groups may be, across inlines.
const MAX_TREE_DEPTH: usize = 1024;

/// A node of a loaded scene: the file and the node's index there.
pub type NodeRef = (usize, NodeIndex);

/// A VRML file and everything it inlines.
#[derive(Clone, Debug)]
pub struct VrmlScene {
    files: Vec<(PathBuf, Document)>,
    /// The file each `Inline` node loaded.
    inlines: HashMap<NodeRef, usize>,
    /// What `(file, ROOT)` stands for: the unnamed group around a file's top-level nodes (as
    /// Coin reads a file, and as an `Inline` holds it).
    group: Node,
    /// What the loading, the searches and the expansions have used of the limits.
    budget: RefCell<Budget>,
}

/// The node index of a file's root group.
const ROOT: NodeIndex = NodeIndex::MAX;

/// What identifies a file for reading it once and for finding cycles: its canonical path
/// (links resolved, `..` removed), or the path as given when it has none.
fn file_key(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

/// A shape found under a node: its geometry, its pose relative to the node, its name.
#[derive(Clone, Debug)]
pub struct FoundShape {
    /// The `Shape`'s DEF name (may be empty).
    pub name: String,
    /// Its geometry.
    pub geometry: Geometry,
    /// Its pose in the frame of the node searched from.
    pub pose: PlueckerTransform,
    /// What the mesh check reported (dropped degenerate triangles, non-manifold edges), for
    /// the model's warnings; empty when all is well.
    pub notes: Vec<String>,
}

impl VrmlScene {
    /// Reads the file at `path` and the files it inlines, within [`SceneLimits::DEFAULT`].
    pub fn load(path: &Path) -> Result<Self, SgError> {
        Self::load_with(path, &SceneLimits::DEFAULT)
    }

    /// Reads the file at `path` and the files it inlines, within `limits` (which also bound the
    /// searches and expansions of the scene).
    pub fn load_with(path: &Path, limits: &SceneLimits) -> Result<Self, SgError> {
        let mut budget = Budget::new(*limits);
        let text = budget.read_text(path)?;
        Self::from_text(&text, path, budget)
    }

    /// Reads `text` as if it were the file `path` (for its inlines and errors).
    pub fn from_str(text: &str, path: &Path) -> Result<Self, SgError> {
        Self::from_str_with(text, path, &SceneLimits::DEFAULT)
    }

    /// [`VrmlScene::from_str`] within `limits`.
    pub fn from_str_with(text: &str, path: &Path, limits: &SceneLimits) -> Result<Self, SgError> {
        Self::from_text(text, path, Budget::new(*limits))
    }

    fn from_text(text: &str, path: &Path, mut budget: Budget) -> Result<Self, SgError> {
        let doc = parse::parse(text, budget.nodes_left()).map_err(|e| e.in_file(path))?;
        budget.add_nodes(doc.nodes.len());
        let mut s = Self {
            files: vec![(path.to_path_buf(), doc)],
            inlines: HashMap::new(),
            group: Node {
                type_name: "Group".into(),
                def: None,
                fields: Vec::new(),
                line: 1,
                column: 1,
            },
            budget: RefCell::new(budget),
        };
        let key = file_key(path);
        let mut known = HashMap::from([(key.clone(), 0)]);
        s.load_inlines(0, &mut vec![key], &mut known)?;
        Ok(s)
    }

    fn node(&self, r: NodeRef) -> &Node {
        if r.1 == ROOT {
            &self.group
        } else {
            &self.files[r.0].1.nodes[r.1]
        }
    }

    fn error_at(&self, r: NodeRef, e: SgError) -> SgError {
        let n = self.node(r);
        e.at(n.describe())
            .at_position(n.line, n.column)
            .in_file(&self.files[r.0].0)
    }

    /// `e` (a limit reached) at the last node of `chain`, naming every node of it from the
    /// scene's root (and the files entered on the way).
    fn chain_error(&self, chain: &[NodeRef], e: SgError) -> SgError {
        let mut names = Vec::with_capacity(chain.len());
        for &r in chain {
            if r.1 == ROOT {
                let file = self.files[r.0].0.file_name().unwrap_or_default();
                names.push(format!("file \"{}\"", file.to_string_lossy()));
            } else {
                names.push(self.node(r).describe());
            }
        }
        let e = e.at(names.join(" › "));
        match chain.last() {
            Some(&r) => {
                let n = self.node(r);
                e.at_position(n.line, n.column).in_file(&self.files[r.0].0)
            }
            None => e.in_file(&self.files[0].0),
        }
    }

    /// Reads the files that the `Inline`s of file `file` name, each file once (`known`: the
    /// files read, by [`file_key`]), refusing cycles (`stack`: the files being read).
    fn load_inlines(
        &mut self,
        file: usize,
        stack: &mut Vec<PathBuf>,
        known: &mut HashMap<PathBuf, usize>,
    ) -> Result<(), SgError> {
        let dir = dir_of(&self.files[file].0);
        let inline_nodes: Vec<NodeIndex> = (0..self.files[file].1.nodes.len())
            .filter(|&i| self.files[file].1.nodes[i].type_name == "Inline")
            .collect();
        for i in inline_nodes {
            let r = (file, i);
            let urls = match self.node(r).field("url") {
                Some(Value::Strings(u)) => u.clone(),
                _ => return Err(self.error_at(r, SgError::missing("field \"url\""))),
            };
            let found = urls.iter().map(|u| dir.join(u)).find(|p| p.exists());
            let Some(path) = found else {
                let first = urls.first().map_or_else(PathBuf::new, |u| dir.join(u));
                return Err(
                    self.error_at(r, SgError::new(SgErrorKind::MissingFile { path: first }))
                );
            };
            let key = file_key(&path);
            if stack.len() >= MAX_INLINE_DEPTH || stack.contains(&key) {
                return Err(self.error_at(
                    r,
                    SgError::unsupported(format!(
                        "Inline of \"{}\": inlines nested deeper than {MAX_INLINE_DEPTH} or in a cycle",
                        path.display()
                    )),
                ));
            }
            if let Some(&idx) = known.get(&key) {
                self.inlines.insert(r, idx);
                continue;
            }
            let max_files = self.budget.get_mut().limits.max_files;
            if self.files.len() >= max_files {
                return Err(self.error_at(
                    r,
                    SgError::new(SgErrorKind::TooLarge {
                        what: "number of files one VRML scene reads (itself and its inlines)",
                        limit: max_files as u64,
                    }),
                ));
            }
            let budget = self.budget.get_mut();
            let doc = budget
                .read_text(&path)
                .and_then(|text| {
                    parse::parse(&text, budget.nodes_left()).map_err(|e| e.in_file(&path))
                })
                .map_err(|e| self.error_at(r, SgError::nested(e)))?;
            self.budget.get_mut().add_nodes(doc.nodes.len());
            self.files.push((path, doc));
            let idx = self.files.len() - 1;
            self.inlines.insert(r, idx);
            known.insert(key.clone(), idx);
            stack.push(key);
            self.load_inlines(idx, stack, known)?;
            stack.pop();
        }
        Ok(())
    }

    /// The children of a grouping node, an `Inline`'s file content, nothing for other nodes.
    fn children(&self, r: NodeRef) -> Vec<NodeRef> {
        if r.1 == ROOT {
            return self.files[r.0].1.roots.iter().map(|&i| (r.0, i)).collect();
        }
        let n = self.node(r);
        let nodes = |field: &str| match n.field(field) {
            Some(Value::Nodes(v)) => v.iter().map(|&i| (r.0, i)).collect(),
            _ => Vec::new(),
        };
        match n.type_name.as_str() {
            "Transform" | "Group" | "Anchor" | "Billboard" | "Collision" => nodes("children"),
            "Switch" => {
                let which = match n.field("whichChoice") {
                    Some(Value::Numbers(v)) => v.first().copied().unwrap_or(-1.0),
                    _ => -1.0,
                };
                let choices = nodes("choice");
                if which >= 0.0 {
                    choices.get(which as usize).copied().into_iter().collect()
                } else {
                    Vec::new()
                }
            }
            "LOD" => nodes("level").into_iter().take(1).collect(),
            "Inline" => match self.inlines.get(&r) {
                Some(&f) => vec![(f, ROOT)],
                None => Vec::new(),
            },
            _ => Vec::new(),
        }
    }

    /// The node's own transform (a `Transform`'s; identity for others).
    fn local(&self, r: NodeRef) -> Result<DAffine3, SgError> {
        let n = self.node(r);
        if n.type_name != "Transform" {
            return Ok(DAffine3::IDENTITY);
        }
        let v3 = |name: &str, d: DVec3| -> Result<DVec3, SgError> {
            match n.field(name) {
                None => Ok(d),
                Some(Value::Numbers(v)) if v.len() == 3 => Ok(DVec3::new(v[0], v[1], v[2])),
                Some(_) => {
                    Err(self.error_at(r, SgError::invalid(name, "", "expected three numbers")))
                }
            }
        };
        let rot = |name: &str| -> Result<DMat3, SgError> {
            match n.field(name) {
                None => Ok(DMat3::IDENTITY),
                Some(Value::Numbers(v)) if v.len() == 4 => {
                    Ok(crate::pose::axis_angle(DVec3::new(v[0], v[1], v[2]), v[3]))
                }
                Some(_) => {
                    Err(self.error_at(r, SgError::invalid(name, "", "expected four numbers")))
                }
            }
        };
        let t = v3("translation", DVec3::ZERO)?;
        let c = v3("center", DVec3::ZERO)?;
        let s = v3("scale", DVec3::ONE)?;
        let rm = rot("rotation")?;
        let sr = rot("scaleOrientation")?;
        Ok(DAffine3::from_translation(t + c)
            * DAffine3::from_mat3(rm * sr * DMat3::from_diagonal(s) * sr.transpose())
            * DAffine3::from_translation(-c))
    }

    /// Depth-first pre-order search for the first node `DEF`'d as `name` (the empty name
    /// matches the first node without one: a file's or an `Inline`'s root group, an unnamed
    /// `Transform`…), from `start` (itself included) or from the main file's root group.
    /// Returns the path from `start` to the node. Every node visited counts against the scene's
    /// [`SceneLimits::max_visits`]: a search that would pass it is an error.
    pub fn find(
        &self,
        name: &str,
        start: Option<NodeRef>,
    ) -> Result<Option<Vec<NodeRef>>, SgError> {
        let mut path = Vec::new();
        let found = self.search(name, start.unwrap_or((0, ROOT)), &mut path, 0)?;
        Ok(found.then_some(path))
    }

    fn search(
        &self,
        name: &str,
        r: NodeRef,
        path: &mut Vec<NodeRef>,
        depth: usize,
    ) -> Result<bool, SgError> {
        if depth > MAX_TREE_DEPTH {
            return Ok(false);
        }
        path.push(r);
        if let Err(e) = self.budget.borrow_mut().visit() {
            return Err(self.chain_error(path, e));
        }
        if self.node(r).def.as_deref().unwrap_or("") == name {
            return Ok(true);
        }
        for c in self.children(r) {
            if self.search(name, c, path, depth + 1)? {
                return Ok(true);
            }
        }
        path.pop();
        Ok(false)
    }

    /// The product of the transforms along `path`, the last node's own included.
    pub fn path_transform(&self, path: &[NodeRef]) -> Result<DAffine3, SgError> {
        path.iter()
            .try_fold(DAffine3::IDENTITY, |acc, &r| Ok(acc * self.local(r)?))
    }

    /// Every `Shape` below `r` (not `r`'s own transform: poses are in `r`'s frame after it),
    /// in depth-first order. Nodes visited, shapes, vertices and triangles count against the
    /// scene's [`SceneLimits`] (over every call on this scene): passing one is an error naming
    /// the chain of nodes from `r`.
    pub fn shapes_under(&self, r: NodeRef) -> Result<Vec<FoundShape>, SgError> {
        let mut out = Vec::new();
        let mut chain = vec![r];
        if self.node(r).type_name == "Shape" {
            self.shape(r, DAffine3::IDENTITY, &mut out, &chain)?;
            return Ok(out);
        }
        for c in self.children(r) {
            self.collect(c, DAffine3::IDENTITY, &mut out, &mut chain)?;
        }
        Ok(out)
    }

    fn collect(
        &self,
        r: NodeRef,
        parent: DAffine3,
        out: &mut Vec<FoundShape>,
        chain: &mut Vec<NodeRef>,
    ) -> Result<(), SgError> {
        chain.push(r);
        if let Err(e) = self.budget.borrow_mut().visit() {
            return Err(self.chain_error(chain, e));
        }
        if chain.len() > MAX_TREE_DEPTH {
            return Err(self.error_at(r, SgError::unsupported("groups nested too deep")));
        }
        if self.node(r).type_name == "Shape" {
            self.shape(r, parent, out, chain)?;
            chain.pop();
            return Ok(());
        }
        let x = parent * self.local(r)?;
        let inline = self.node(r).type_name == "Inline";
        for c in self.children(r) {
            self.collect(c, x, out, chain).map_err(|e| {
                // Name the Inline in this file as well as the place in the inlined one (a
                // limit's error names the whole chain already).
                if inline && !matches!(*e.kind, SgErrorKind::TooLarge { .. }) {
                    self.error_at(r, SgError::nested(e))
                } else {
                    e
                }
            })?;
        }
        chain.pop();
        Ok(())
    }

    /// The vertices and triangles geometry node `g` will have (an upper bound for a convex
    /// hull), from its fields, before anything is built.
    fn cost(&self, g: NodeRef) -> (usize, usize) {
        let n = self.node(g);
        if n.type_name != "IndexedFaceSet" {
            return (0, 0);
        }
        let points = match n.field("coord") {
            Some(Value::Nodes(v)) if !v.is_empty() => match self.node((g.0, v[0])).field("point") {
                Some(Value::Numbers(p)) => p.len() / 3,
                _ => 0,
            },
            _ => 0,
        };
        let mut triangles = 0usize;
        let mut run = 0usize;
        if let Some(Value::Numbers(index)) = n.field("coordIndex") {
            for &i in index.iter().chain(std::iter::once(&-1.0)) {
                if i == -1.0 {
                    triangles += run.saturating_sub(2);
                    run = 0;
                } else {
                    run += 1;
                }
            }
        }
        (points, triangles)
    }

    fn shape(
        &self,
        r: NodeRef,
        x: DAffine3,
        out: &mut Vec<FoundShape>,
        chain: &[NodeRef],
    ) -> Result<(), SgError> {
        let n = self.node(r);
        let name = n.def.clone().unwrap_or_default();
        let g = match n.field("geometry") {
            Some(Value::Nodes(v)) if !v.is_empty() => (r.0, v[0]),
            // A Shape without geometry draws nothing and collides with nothing.
            _ => return Ok(()),
        };
        let (vertices, triangles) = self.cost(g);
        if let Err(e) = self.budget.borrow_mut().shape(vertices, triangles) {
            return Err(self.chain_error(chain, e));
        }
        let (geometry, pose, stats) = self.geometry(g, x).map_err(|e| self.error_at(g, e))?;
        let notes = stats.map_or_else(Vec::new, |s| {
            let n = self.node(g);
            let what = format!(
                "{} line {}: {}",
                self.files[g.0].0.display(),
                n.line,
                n.describe()
            );
            s.notes(&what)
        });
        out.push(FoundShape {
            name,
            geometry,
            pose,
            notes,
        });
        Ok(())
    }

    fn number(&self, r: NodeRef, field: &str, default: f64) -> Result<f64, SgError> {
        match self.node(r).field(field) {
            None => Ok(default),
            Some(Value::Numbers(v)) if v.len() == 1 => Ok(v[0]),
            Some(_) => Err(SgError::invalid(field, "", "expected one number")),
        }
    }

    fn flag(&self, r: NodeRef, field: &str) -> Option<bool> {
        match self.node(r).field(field) {
            Some(Value::Bools(v)) => v.first().copied(),
            _ => None,
        }
    }

    /// The geometry node `g` under the affine map `x`: the geometry, its rigid pose, and for a
    /// mesh what its check reported.
    fn geometry(
        &self,
        g: NodeRef,
        x: DAffine3,
    ) -> Result<(Geometry, PlueckerTransform, Option<MeshStats>), SgError> {
        let n = self.node(g);
        // VRML's y axis onto our z for cylinders and cones.
        let y_up = DMat3::from_rotation_x(-std::f64::consts::FRAC_PI_2);
        let (geometry, frame) = match n.type_name.as_str() {
            "Box" => {
                let s = match n.field("size") {
                    None => DVec3::splat(2.0),
                    Some(Value::Numbers(v)) if v.len() == 3 => DVec3::new(v[0], v[1], v[2]),
                    Some(_) => return Err(SgError::invalid("size", "", "expected three numbers")),
                };
                (Geometry::cuboid(s)?, DMat3::IDENTITY)
            }
            "Sphere" => (
                Geometry::sphere(self.number(g, "radius", 1.0)?)?,
                DMat3::IDENTITY,
            ),
            "Cylinder" => (
                Geometry::cylinder(
                    self.number(g, "radius", 1.0)?,
                    self.number(g, "height", 2.0)?,
                )?,
                y_up,
            ),
            "Cone" => (
                Geometry::cone(
                    self.number(g, "bottomRadius", 1.0)?,
                    self.number(g, "height", 2.0)?,
                )?,
                y_up,
            ),
            "IndexedFaceSet" => return self.face_set(g, x),
            other => {
                return Err(SgError::unsupported(format!(
                    "geometry {other} (supported: Box, Sphere, Cylinder, Cone, IndexedFaceSet)"
                )));
            }
        };
        // x · frame = R · diag(s) with R a rotation: the primitive scaled by s at R.
        let m = x.matrix3 * frame;
        let s = DVec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length());
        let r = DMat3::from_cols(m.x_axis / s.x, m.y_axis / s.y, m.z_axis / s.z);
        let orthonormal = (r.transpose() * r - DMat3::IDENTITY)
            .abs()
            .to_cols_array()
            .iter()
            .all(|e| *e < 1e-6)
            && r.determinant() > 0.0;
        if !orthonormal {
            return Err(SgError::unsupported(format!(
                "{} under a shearing or mirroring transform",
                n.type_name
            )));
        }
        let geometry = geometry.scaled(s)?;
        Ok((geometry, PlueckerTransform::new(r, x.translation), None))
    }

    /// An `IndexedFaceSet` under `x` (baked into the vertices when not rigid).
    fn face_set(
        &self,
        g: NodeRef,
        x: DAffine3,
    ) -> Result<(Geometry, PlueckerTransform, Option<MeshStats>), SgError> {
        let n = self.node(g);
        let coord = match n.field("coord") {
            Some(Value::Nodes(v)) if !v.is_empty() => (g.0, v[0]),
            _ => return Err(SgError::missing("field \"coord\" (a Coordinate node)")),
        };
        let points = match self.node(coord).field("point") {
            Some(Value::Numbers(v)) if v.len() % 3 == 0 => v.clone(),
            None => Vec::new(),
            Some(_) => {
                return Err(SgError::invalid(
                    "Coordinate point",
                    "",
                    "not a list of 3-D points",
                ));
            }
        };
        let mut vertices: Vec<DVec3> = points
            .chunks_exact(3)
            .map(|p| DVec3::new(p[0], p[1], p[2]))
            .collect();
        let index = match n.field("coordIndex") {
            Some(Value::Numbers(v)) => v.clone(),
            None => Vec::new(),
            Some(_) => return Err(SgError::invalid("coordIndex", "", "not a list of integers")),
        };
        let ccw = self.flag(g, "ccw").unwrap_or(true);
        let convex_field = self.flag(g, "convex");
        let mut triangles = Vec::new();
        let mut polygon: Vec<u32> = Vec::new();
        for (k, &i) in index.iter().chain(std::iter::once(&-1.0)).enumerate() {
            if i == -1.0 {
                triangulate(
                    &polygon,
                    &vertices,
                    convex_field.unwrap_or(true),
                    &mut triangles,
                );
                polygon.clear();
            } else if i >= 0.0 && i.fract() == 0.0 && (i as usize) < vertices.len() {
                polygon.push(i as u32);
            } else {
                return Err(SgError::invalid(
                    format!("coordIndex[{k}]"),
                    i,
                    "not -1 or the index of a point",
                ));
            }
        }
        if !ccw {
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        // Rigid part as the pose, anything else baked into the points.
        let m = x.matrix3;
        let rigid = (m.transpose() * m - DMat3::IDENTITY)
            .abs()
            .to_cols_array()
            .iter()
            .all(|e| *e < 1e-6)
            && m.determinant() > 0.0;
        let pose = if rigid {
            PlueckerTransform::new(m, x.translation)
        } else {
            for v in &mut vertices {
                *v = m * *v;
            }
            if m.determinant() < 0.0 {
                for t in &mut triangles {
                    t.swap(1, 2);
                }
            }
            PlueckerTransform::from_translation(x.translation)
        };
        // RL builds a convex shape only when the file says `convex TRUE` itself.
        if convex_field == Some(true) {
            let used: Vec<DVec3> = triangles
                .iter()
                .flatten()
                .map(|&i| vertices[i as usize])
                .collect();
            Ok((Geometry::convex_hull(&used)?, pose, None))
        } else {
            let (mesh, stats) = TriangleMesh::new(vertices, triangles)?;
            Ok((Geometry::mesh(mesh), pose, Some(stats)))
        }
    }

    /// A scene of one model named `name` with one body (named `""`) holding every shape of the
    /// file, in the world frame: for looking at a bare `.wrl`.
    pub fn to_model(&self, name: &str) -> Result<Model, SgError> {
        let mut model = Model::new(name);
        let body = model.add_body("");
        let mut notes = Vec::new();
        for s in self.shapes_under((0, ROOT))? {
            notes.extend(s.notes);
            body.push_shape(Shape::new(s.name, s.geometry, s.pose)?);
        }
        for n in notes {
            model.warn(n);
        }
        Ok(model)
    }

    /// The path of the file (0: the main one).
    pub fn file(&self, i: usize) -> Option<&Path> {
        self.files.get(i).map(|f| f.0.as_path())
    }

    /// How many files were read (the main one and its inlines).
    pub fn file_count(&self) -> usize {
        self.files.len()
    }
}

/// A rigid transform from an affine one that should be rigid (body frames).
pub(crate) fn rigid(x: &DAffine3) -> Option<PlueckerTransform> {
    let m = x.matrix3;
    let ok = (m.transpose() * m - DMat3::IDENTITY)
        .abs()
        .to_cols_array()
        .iter()
        .all(|e| *e < 1e-6)
        && m.determinant() > 0.0;
    // Re-orthonormalise through the quaternion (files carry 6–7 digits).
    ok.then(|| {
        PlueckerTransform::from_quat_translation(DQuat::from_mat3(&m).normalize(), x.translation)
    })
}

/// Appends the triangles of polygon `p` (vertex indices): a fan if `convex`, else ear clipping
/// in the polygon's best-fit plane (falling back to a fan if the polygon is too irregular).
fn triangulate(p: &[u32], v: &[DVec3], convex: bool, out: &mut Vec<[u32; 3]>) {
    if p.len() < 3 {
        return;
    }
    if convex || p.len() == 3 {
        for k in 1..p.len() - 1 {
            out.push([p[0], p[k], p[k + 1]]);
        }
        return;
    }
    // Newell's normal, then 2-D coordinates in the plane.
    let mut n = DVec3::ZERO;
    for k in 0..p.len() {
        let (a, b) = (v[p[k] as usize], v[p[(k + 1) % p.len()] as usize]);
        n += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let Some(n) = n.try_normalize() else {
        for k in 1..p.len() - 1 {
            out.push([p[0], p[k], p[k + 1]]);
        }
        return;
    };
    let u = n.any_orthonormal_vector();
    let w = n.cross(u);
    let pts: Vec<(f64, f64)> = p
        .iter()
        .map(|&i| (v[i as usize].dot(u), v[i as usize].dot(w)))
        .collect();
    let mut idx: Vec<usize> = (0..p.len()).collect();
    let cross = |a: (f64, f64), b: (f64, f64), c: (f64, f64)| {
        (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
    };
    let mut guard = 0;
    while idx.len() > 3 && guard < 10 * p.len() * p.len() {
        guard += 1;
        let m = idx.len();
        let mut clipped = false;
        for k in 0..m {
            let (ia, ib, ic) = (idx[(k + m - 1) % m], idx[k], idx[(k + 1) % m]);
            let (a, b, c) = (pts[ia], pts[ib], pts[ic]);
            if cross(a, b, c) <= 0.0 {
                continue; // reflex corner
            }
            let inside = idx.iter().any(|&j| {
                j != ia && j != ib && j != ic && {
                    let q = pts[j];
                    cross(a, b, q) >= 0.0 && cross(b, c, q) >= 0.0 && cross(c, a, q) >= 0.0
                }
            });
            if !inside {
                out.push([p[ia], p[ib], p[ic]]);
                idx.remove(k);
                clipped = true;
                break;
            }
        }
        if !clipped {
            break;
        }
    }
    for k in 1..idx.len().saturating_sub(1) {
        out.push([p[idx[0]], p[idx[k]], p[idx[k + 1]]]);
    }
}
