//! URDF geometry: one scene body per `<link>`, one shape per `<collision>` (or `<visual>`)
//! element, primitives and meshes; and [`load_robot`], which loads the kinematics with rl-core
//! and links the bodies to it by link name.
//!
//! Geometry kinds: `<box size>`, `<cylinder radius length>` (along z), `<sphere radius>`,
//! `<mesh filename scale>` (STL, OBJ, COLLADA; `package://`, `file://` and relative paths, see
//! [`super::resolve`]), and the non-standard `<capsule radius length>` some files use.
//! Negative mesh scales (mirrored meshes) are applied as given; the triangles' orientation
//! then flips, which does not matter to collision with surfaces.
//!
//! Self-collision: bodies joined directly by a joint (adjacent links) and links that rl-core
//! merges into one rigid body (chains of fixed joints) are not checked against each other;
//! an SRDF ([`super::srdf`]) replaces that default with its own list.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;
use rl_core::loader::{self as core_loader, LoadedModel};
use rl_core::spatial::PlueckerTransform;
use roxmltree::Node;

use super::limits::Budget;
use super::mesh_file::MeshCache;
use super::xml::{at, attr, child, children, number_attr, parse, robot_root, vec3_attr};
use super::{dir_of, read_text_within, resolve};
use crate::error::{SgError, SgErrorKind};
use crate::geometry::Geometry;
use crate::pose;
use crate::scene::{KinematicLink, Model, Shape};

/// Which geometry of a link to load.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GeometryKind {
    /// `<collision>` (what collision checking uses).
    #[default]
    Collision,
    /// `<visual>` (what a viewer shows).
    Visual,
}

impl GeometryKind {
    fn tag(self) -> &'static str {
        match self {
            Self::Collision => "collision",
            Self::Visual => "visual",
        }
    }
}

/// What a mesh becomes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MeshMode {
    /// The triangle mesh itself (as coal, FCL and MoveIt use it).
    #[default]
    Mesh,
    /// Its convex hull (faster; conservative).
    ConvexHull,
}

/// Options for URDF geometry.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UrdfGeometryOptions {
    /// Collision or visual geometry.
    pub kind: GeometryKind,
    /// Directories where `package://` URIs are looked up (see [`super::resolve`]).
    pub package_dirs: Vec<PathBuf>,
    /// Meshes as meshes or as convex hulls.
    pub mesh: MeshMode,
    /// Refuse meshes with triangles of no area or edges shared by more than two triangles
    /// ([`crate::SgErrorKind::NonManifoldMesh`]) instead of loading them with a note. Many
    /// published robot meshes have such edges (a third of example-robot-data's robots); they
    /// collide correctly as triangle surfaces, so the default is to note them.
    pub strict_meshes: bool,
}

/// `<origin xyz rpy>` of `n`, identity when absent.
fn origin(n: Node) -> Result<PlueckerTransform, SgError> {
    match child(n, "origin") {
        Some(o) => {
            let xyz = vec3_attr(o, "xyz", DVec3::ZERO)?;
            let rpy = vec3_attr(o, "rpy", DVec3::ZERO)?;
            Ok(PlueckerTransform::new(pose::rpy(rpy.x, rpy.y, rpy.z), xyz))
        }
        None => Ok(PlueckerTransform::IDENTITY),
    }
}

/// The loader's state for one file.
struct Reader<'c> {
    dir: PathBuf,
    options: UrdfGeometryOptions,
    cache: &'c mut MeshCache,
    /// Shapes, vertices and triangles so far: a mesh named by many links counts for each (each
    /// link's shape is its own collision structure).
    budget: Budget,
    warnings: Vec<String>,
}

impl Reader<'_> {
    /// The geometry of a `<geometry>` element, and the mesh file it came from.
    fn geometry(&mut self, g: Node) -> Result<(Geometry, Option<(PathBuf, DVec3)>), SgError> {
        let Some(k) = g.children().find(|c| c.is_element()) else {
            return Err(at(
                g,
                SgError::missing("a shape element (box, cylinder, sphere, mesh)"),
            ));
        };
        let placed = |e: SgError| at(k, e);
        if k.tag_name().name() != "mesh" {
            self.budget.shape(0, 0).map_err(placed)?;
        }
        let geometry = match k.tag_name().name() {
            "box" => Geometry::cuboid(vec3_attr(k, "size", DVec3::NAN).and_then(|s| {
                if s.is_nan() {
                    Err(at(k, SgError::missing("attribute \"size\"")))
                } else {
                    Ok(s)
                }
            })?),
            "cylinder" => Geometry::cylinder(number_attr(k, "radius")?, number_attr(k, "length")?),
            "capsule" => Geometry::capsule(number_attr(k, "radius")?, number_attr(k, "length")?),
            "sphere" => Geometry::sphere(number_attr(k, "radius")?),
            "mesh" => {
                let uri = attr(k, "filename")?;
                let path = resolve(uri, &self.dir, &self.options.package_dirs).map_err(placed)?;
                let scale = vec3_attr(k, "scale", DVec3::ONE)?;
                let (mesh, stats) = self
                    .cache
                    .get(&path)
                    .map_err(|e| placed(SgError::nested(e)))?;
                self.budget
                    .shape(mesh.vertices().len(), mesh.triangles().len())
                    .map_err(placed)?;
                if self.options.strict_meshes {
                    stats
                        .strict()
                        .map_err(|e| placed(SgError::nested(e.in_file(&path))))?;
                }
                self.warnings
                    .extend(stats.notes(&path.display().to_string()));
                let g = if scale == DVec3::ONE {
                    Geometry::Mesh(Arc::clone(&mesh))
                } else {
                    if scale.x == 0.0 || scale.y == 0.0 || scale.z == 0.0 || !scale.is_finite() {
                        return Err(placed(SgError::invalid(
                            "scale",
                            format!("{} {} {}", scale.x, scale.y, scale.z),
                            "a zero or non-finite factor flattens the mesh",
                        )));
                    }
                    Geometry::mesh(mesh.map_vertices(|v| v * scale).map_err(placed)?.0)
                };
                let g = match (self.options.mesh, g) {
                    (MeshMode::ConvexHull, Geometry::Mesh(m)) => {
                        Geometry::convex_hull(m.vertices())
                            .map_err(|e| placed(SgError::nested(e.in_file(&path))))?
                    }
                    (_, g) => g,
                };
                return Ok((g, Some((path, scale))));
            }
            other => {
                return Err(placed(SgError::unsupported(format!(
                    "geometry <{other}> (supported: box, cylinder, sphere, mesh, capsule)"
                ))));
            }
        }
        .map_err(placed)?;
        Ok((geometry, None))
    }
}

/// Reads the geometry of every link of the URDF in `text` (from a file in `dir`, for relative
/// mesh paths) into a model named after the robot: one body per link, in file order; within
/// the limits of `cache` ([`MeshCache::limits`]: shapes, mesh vertices and triangles).
pub fn geometry_from_str(
    text: &str,
    dir: &Path,
    options: &UrdfGeometryOptions,
    cache: &mut MeshCache,
) -> Result<Model, SgError> {
    let doc = parse(text)?;
    let robot = robot_root(&doc, "a URDF")?;
    let budget = Budget::new(*cache.limits());
    let mut reader = Reader {
        dir: dir.to_path_buf(),
        options: options.clone(),
        cache,
        budget,
        warnings: Vec::new(),
    };
    let mut model = Model::new(robot.attribute("name").unwrap_or("robot"));
    let tag = options.kind.tag();
    for link in children(robot, "link") {
        let name = attr(link, "name")?;
        if model.body_index(name).is_some() {
            return Err(at(
                link,
                SgError::new(SgErrorKind::DuplicateName {
                    name: name.to_string(),
                }),
            ));
        }
        let mut shapes = Vec::new();
        for (k, e) in children(link, tag).enumerate() {
            let what = format!("<{tag}> #{k} of link \"{name}\"");
            let local = origin(e).map_err(|err| err.at(what.clone()))?;
            let g = child(e, "geometry")
                .ok_or_else(|| at(e, SgError::missing("<geometry>")).at(what.clone()))?;
            let (geometry, source) = reader.geometry(g).map_err(|err| err.at(what.clone()))?;
            let shape_name = e
                .attribute("name")
                .map_or_else(|| format!("{name}/{tag}/{k}"), str::to_string);
            let shape =
                Shape::new(shape_name, geometry, local).map_err(|err| at(e, err).at(what))?;
            shapes.push(match source {
                Some((path, scale)) => shape.with_source(path, scale),
                None => shape,
            });
        }
        let body = model.add_body(name);
        for s in shapes {
            body.push_shape(s);
        }
    }
    let mut seen = std::collections::HashSet::new();
    for w in reader.warnings {
        if seen.insert(w.clone()) {
            model.warn(w);
        }
    }
    // Adjacent links: parent and child of a joint.
    for j in children(robot, "joint") {
        let link_of = |tag: &str| child(j, tag).and_then(|c| c.attribute("link"));
        if let (Some(p), Some(c)) = (link_of("parent"), link_of("child")) {
            if let (Some(a), Some(b)) = (model.body_index(p), model.body_index(c)) {
                model.allowed_collisions_mut().allow(a, b);
            }
        }
    }
    model.set_self_collision(true);
    Ok(model)
}

/// Reads the geometry of the URDF file at `path` (see [`geometry_from_str`]).
pub fn load_geometry(
    path: &Path,
    options: &UrdfGeometryOptions,
    cache: &mut MeshCache,
) -> Result<Model, SgError> {
    let text = read_text_within(path, cache.limits().max_file_bytes)?;
    geometry_from_str(&text, &dir_of(path), options, cache).map_err(|e| e.in_file(path))
}

/// A robot: its scene model (geometry, bodies following the kinematics) and its kinematic
/// model from rl-core.
#[derive(Clone, Debug)]
pub struct Robot<const N: usize> {
    /// The scene model: one body per link.
    pub model: Model,
    /// The kinematic model (rl-core's loader).
    pub kinematics: LoadedModel<N>,
}

/// Loads a URDF robot: kinematics through rl-core's loader (with `urdf` options), then
/// [`robot_from_kinematics`].
pub fn load_robot<const N: usize>(
    path: &Path,
    geometry: &UrdfGeometryOptions,
    urdf: &core_loader::UrdfOptions,
    cache: &mut MeshCache,
) -> Result<Robot<N>, SgError> {
    let kinematics = core_loader::load_file_with::<N>(path, urdf)
        .map_err(|e| SgError::new(SgErrorKind::Model(e.to_string())).in_file(path))?;
    robot_from_kinematics(path, kinematics, geometry, cache)
}

/// The geometry of the URDF at `path` ([`load_geometry`]) with every link's body linked to the
/// rl-core body of `kinematics` (loaded from the same file) it belongs to. Links that rl-core
/// merges into one rigid body are added to the allowed set (they cannot move against each
/// other); links not connected to the root stay where they are, with a warning.
pub fn robot_from_kinematics<const N: usize>(
    path: &Path,
    kinematics: LoadedModel<N>,
    geometry: &UrdfGeometryOptions,
    cache: &mut MeshCache,
) -> Result<Robot<N>, SgError> {
    let mut model = load_geometry(path, geometry, cache)?;
    let mut frames = Vec::with_capacity(model.bodies().len());
    let mut missing = Vec::new();
    for b in model.bodies() {
        match kinematics.frame(b.name()) {
            Some(f) => frames.push(Some((f.body, f.placement))),
            None => {
                missing.push(b.name().to_string());
                frames.push(None);
            }
        }
    }
    for m in missing {
        model.warn(format!(
            "link \"{m}\" is not connected to the root: it stays in place"
        ));
    }
    let link =
        KinematicLink::new(frames, kinematics.model.body_count()).map_err(|e| e.in_file(path))?;
    model.set_kinematics(link);
    // Links merged into one rl-core body are rigidly attached.
    model.allow_rigidly_joined();
    Ok(Robot { model, kinematics })
}
