//! Shapes as described (dimensions in metres, in the shape's own frame) and their parry form.
//!
//! Axis conventions are URDF's and coal's: cylinders, capsules and cones lie along z, centred
//! on the origin, the cone's apex at `+length/2`. parry puts them along y; the rotation between
//! the two is applied inside the scene ([`Geometry::parry_offset`]), so users never see it.

mod mesh;
pub(crate) mod mesh_tree;

pub use mesh::{MeshStats, TriangleMesh};

use std::f64::consts::FRAC_PI_2;
use std::sync::Arc;

use glam::{DQuat, DVec3};
use parry3d_f64::math::Pose;
use parry3d_f64::shape::{SharedShape, TriMeshFlags};

use crate::error::{SgError, check_finite};

/// A shape's geometry.
#[derive(Clone, Debug, PartialEq)]
pub enum Geometry {
    /// A box with edge lengths `size` (x, y, z), centred.
    Box {
        /// Edge lengths, m.
        size: DVec3,
    },
    /// A sphere, centred.
    Sphere {
        /// Radius, m.
        radius: f64,
    },
    /// A cylinder along z, centred.
    Cylinder {
        /// Radius, m.
        radius: f64,
        /// Length along z, m.
        length: f64,
    },
    /// A capsule along z, centred: the points within `radius` of the segment from
    /// `-length/2` to `+length/2` on z (coal's `Capsule(radius, length)`).
    Capsule {
        /// Radius, m.
        radius: f64,
        /// Length of the axis segment, m (the capsule is `length + 2·radius` long).
        length: f64,
    },
    /// A cone along z, centred: base disc at `-length/2`, apex at `+length/2`.
    Cone {
        /// Base radius, m.
        radius: f64,
        /// Height, m.
        length: f64,
    },
    /// The convex hull of points, as its triangulated surface.
    Convex(Arc<TriangleMesh>),
    /// A triangle mesh (a surface: a mesh inside another shape without touching its surface
    /// does not collide with it, as in coal and FCL).
    Mesh(Arc<TriangleMesh>),
    /// The half-space `normal · x ≤ offset`.
    HalfSpace {
        /// Unit outward normal.
        normal: DVec3,
        /// Offset along it, m.
        offset: f64,
    },
}

fn positive(what: &str, v: f64) -> Result<(), SgError> {
    if !v.is_finite() {
        Err(SgError::invalid(what, v, "not finite"))
    } else if v <= 0.0 {
        Err(SgError::invalid(what, v, "must be positive"))
    } else {
        Ok(())
    }
}

impl Geometry {
    /// A box of edge lengths `size`.
    pub fn cuboid(size: DVec3) -> Result<Self, SgError> {
        for (a, v) in ["box size x", "box size y", "box size z"]
            .iter()
            .zip(size.to_array())
        {
            positive(a, v)?;
        }
        Ok(Self::Box { size })
    }

    /// A sphere.
    pub fn sphere(radius: f64) -> Result<Self, SgError> {
        positive("sphere radius", radius)?;
        Ok(Self::Sphere { radius })
    }

    /// A cylinder along z.
    pub fn cylinder(radius: f64, length: f64) -> Result<Self, SgError> {
        positive("cylinder radius", radius)?;
        positive("cylinder length", length)?;
        Ok(Self::Cylinder { radius, length })
    }

    /// A capsule along z (`length` of the axis segment, may be 0: a sphere).
    pub fn capsule(radius: f64, length: f64) -> Result<Self, SgError> {
        positive("capsule radius", radius)?;
        if !(length.is_finite() && length >= 0.0) {
            return Err(SgError::invalid("capsule length", length, "must be ≥ 0"));
        }
        Ok(Self::Capsule { radius, length })
    }

    /// A cone along z.
    pub fn cone(radius: f64, length: f64) -> Result<Self, SgError> {
        positive("cone radius", radius)?;
        positive("cone length", length)?;
        Ok(Self::Cone { radius, length })
    }

    /// The convex hull of `points` (an error if they are fewer than four or coplanar).
    pub fn convex_hull(points: &[DVec3]) -> Result<Self, SgError> {
        if let Some(p) = points.iter().find(|p| !p.is_finite()) {
            return Err(SgError::invalid(
                "convex hull point",
                format!("{p:?}"),
                "not finite",
            ));
        }
        let (v, t) = parry3d_f64::transformation::try_convex_hull(points).map_err(|e| {
            SgError::degenerate(format!(
                "no convex hull of {} points ({e:?}): fewer than four, or all in one plane",
                points.len()
            ))
        })?;
        let (hull, _) = TriangleMesh::new(v, t)?;
        // A hull of coplanar points comes back flat: no volume, no solid.
        let volume = signed_volume(&hull);
        if volume.abs() < 1e-18 {
            return Err(SgError::degenerate(format!(
                "the convex hull of {} points has no volume: they lie in one plane",
                points.len()
            )));
        }
        Ok(Self::Convex(Arc::new(hull)))
    }

    /// A triangle mesh.
    pub fn mesh(mesh: TriangleMesh) -> Self {
        Self::Mesh(Arc::new(mesh))
    }

    /// The half-space `normal · x ≤ offset` (`normal` is normalised; it must not be zero).
    pub fn half_space(normal: DVec3, offset: f64) -> Result<Self, SgError> {
        check_finite(
            "half-space normal and offset",
            &[normal.x, normal.y, normal.z, offset],
        )?;
        let n = normal.length();
        if n < 1e-12 {
            return Err(SgError::invalid(
                "half-space normal",
                format!("{normal:?}"),
                "zero",
            ));
        }
        Ok(Self::HalfSpace {
            normal: normal / n,
            offset,
        })
    }

    /// A short name of the kind (`box`, `sphere`, …, `mesh`, `halfspace`).
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Box { .. } => "box",
            Self::Sphere { .. } => "sphere",
            Self::Cylinder { .. } => "cylinder",
            Self::Capsule { .. } => "capsule",
            Self::Cone { .. } => "cone",
            Self::Convex(_) => "convex",
            Self::Mesh(_) => "mesh",
            Self::HalfSpace { .. } => "halfspace",
        }
    }

    /// Whether the shape is convex (everything but meshes).
    pub fn is_convex(&self) -> bool {
        !matches!(self, Self::Mesh(_))
    }

    /// The same geometry scaled by `s` along the shape's axes (meshes and hulls: any positive
    /// scale; boxes: any; spheres, cylinders, capsules, cones: where the scale keeps the kind,
    /// e.g. equal x and y for a cylinder).
    pub fn scaled(&self, s: DVec3) -> Result<Self, SgError> {
        if s == DVec3::ONE {
            return Ok(self.clone());
        }
        for v in s.to_array() {
            positive("scale", v)?;
        }
        let uniform_xy = (s.x - s.y).abs() <= 1e-9 * s.x.max(s.y);
        let refuse = || {
            SgError::unsupported(format!(
                "scaling a {} by ({}, {}, {}): the result is not a {}",
                self.kind(),
                s.x,
                s.y,
                s.z,
                self.kind()
            ))
        };
        match self {
            Self::Box { size } => Self::cuboid(*size * s),
            Self::Sphere { radius } => {
                if uniform_xy && (s.x - s.z).abs() <= 1e-9 * s.x.max(s.z) {
                    Self::sphere(radius * s.x)
                } else {
                    Err(refuse())
                }
            }
            Self::Cylinder { radius, length } if uniform_xy => {
                Self::cylinder(radius * s.x, length * s.z)
            }
            Self::Cone { radius, length } if uniform_xy => Self::cone(radius * s.x, length * s.z),
            Self::Capsule { radius, length } if uniform_xy && (s.x - s.z).abs() <= 1e-9 * s.x => {
                Self::capsule(radius * s.x, length * s.z)
            }
            Self::Mesh(m) => Ok(Self::Mesh(Arc::new(m.map_vertices(|v| v * s)?.0))),
            Self::Convex(m) => {
                Self::convex_hull(&m.vertices().iter().map(|&v| v * s).collect::<Vec<_>>())
            }
            _ => Err(refuse()),
        }
    }

    /// parry's shape.
    pub(crate) fn to_parry(&self) -> Result<SharedShape, SgError> {
        Ok(match self {
            Self::Box { size } => SharedShape::cuboid(size.x / 2.0, size.y / 2.0, size.z / 2.0),
            Self::Sphere { radius } => SharedShape::ball(*radius),
            Self::Cylinder { radius, length } => SharedShape::cylinder(length / 2.0, *radius),
            Self::Capsule { radius, length } => SharedShape::capsule(
                DVec3::new(0.0, 0.0, -length / 2.0),
                DVec3::new(0.0, 0.0, length / 2.0),
                *radius,
            ),
            Self::Cone { radius, length } => SharedShape::cone(length / 2.0, *radius),
            Self::Convex(m) => SharedShape::convex_mesh(m.vertices().to_vec(), m.triangles())
                .ok_or_else(|| SgError::degenerate("parry refused the convex hull"))?,
            Self::Mesh(m) => SharedShape::trimesh_with_flags(
                m.vertices().to_vec(),
                m.triangles().to_vec(),
                TriMeshFlags::empty(),
            )
            .map_err(|e| SgError::degenerate(format!("parry refused the mesh: {e:?}")))?,
            Self::HalfSpace { normal, .. } => SharedShape::halfspace(*normal),
        })
    }

    /// The pose of parry's shape in the shape's frame: a quarter turn about x for the shapes
    /// parry puts along y (its y onto our z), the offset of a half-space.
    pub(crate) fn parry_offset(&self) -> Pose {
        match self {
            Self::Cylinder { .. } | Self::Cone { .. } => {
                Pose::from_rotation(DQuat::from_rotation_x(FRAC_PI_2))
            }
            Self::HalfSpace { normal, offset } => Pose::from_translation(*normal * *offset),
            _ => Pose::IDENTITY,
        }
    }

    /// A finite set of balls whose convex hull contains the shape, in the shape's frame:
    /// corners for boxes and meshes (radius 0), centres with radii for the round shapes
    /// (a cylinder lies in the hull of the balls on its end-disc centres, a cone in that of its
    /// apex and its base ball). `None` for a half-space (unbounded).
    pub fn bounding_balls(&self) -> Option<Vec<(DVec3, f64)>> {
        let z = |h: f64| DVec3::new(0.0, 0.0, h);
        Some(match self {
            Self::Box { size } => {
                let h = *size / 2.0;
                (0..8)
                    .map(|i| {
                        let sx = if i & 1 == 0 { -h.x } else { h.x };
                        let sy = if i & 2 == 0 { -h.y } else { h.y };
                        let sz = if i & 4 == 0 { -h.z } else { h.z };
                        (DVec3::new(sx, sy, sz), 0.0)
                    })
                    .collect()
            }
            Self::Sphere { radius } => vec![(DVec3::ZERO, *radius)],
            Self::Cylinder { radius, length } | Self::Capsule { radius, length } => {
                vec![(z(-length / 2.0), *radius), (z(length / 2.0), *radius)]
            }
            Self::Cone { radius, length } => {
                vec![(z(-length / 2.0), *radius), (z(length / 2.0), 0.0)]
            }
            Self::Convex(m) | Self::Mesh(m) => m.vertices().iter().map(|&v| (v, 0.0)).collect(),
            Self::HalfSpace { .. } => return None,
        })
    }
}

/// The signed volume enclosed by a closed, outward-oriented mesh (divergence theorem).
pub(crate) fn signed_volume(m: &TriangleMesh) -> f64 {
    (0..m.triangles().len())
        .map(|k| {
            let [a, b, c] = m.triangle(k);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}
