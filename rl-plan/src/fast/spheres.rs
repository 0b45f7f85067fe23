//! The robot as spheres: per link, spheres that contain its collision geometry.
//!
//! Two sources:
//!
//! - a `*_spherized.urdf` (VAMP's, from MotionBenchMaker and foam): every `<collision>` of a
//!   link that is a `<sphere>` at an `<origin>`; links are matched by name to the kinematic
//!   model's frames. How well those spheres cover the meshes is the file author's claim; the
//!   tests check planned paths against the meshes themselves.
//! - fitted from the model's own geometry ([`SphereSet::fit`]): rl-sg's
//!   [`rl_sg::fit`] puts every link into `k` spheres that contain its meshes and primitives
//!   (containment is proved there and tested by sampling surface points) — conservative by
//!   construction, coarser than hand-made ones.

use std::path::Path;

use glam::DVec3;
use rl_core::loader::LoadedModel;
use rl_core::spatial::PlueckerTransform;

use crate::error::PlanError;

/// The spheres of one link.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkSpheres {
    /// The link's name (URDF link, RL body).
    pub name: String,
    /// The rl-core body it moves with (or `rl_core::model::ROOT` for the world) and its pose
    /// in that body's frame; `None` for a link the kinematic model does not know (skipped).
    pub frame: Option<(usize, PlueckerTransform)>,
    /// Centres (in the link's frame) and radii, m.
    pub spheres: Vec<(DVec3, f64)>,
}

/// How deep below an uncovered surface sample [`SphereSet::cover`] puts a new sphere's
/// centre, m.
pub const COVER_DEPTH: f64 = 0.04;
/// How much more than the sampling margin a new sphere of [`SphereSet::cover`] may stick out
/// of a flat surface, m.
pub const COVER_EXCESS: f64 = 0.003;

/// What [`SphereSet::cover`] did to one link.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkCover {
    /// The link.
    pub name: String,
    /// How far the geometry stuck out of the link's spheres before (beyond the margin), m.
    pub largest_escape: f64,
    /// Spheres added.
    pub added: usize,
    /// Spheres of the link now.
    pub spheres: usize,
}

/// What [`SphereSet::cover`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CoverReport {
    /// Per covered link.
    pub links: Vec<LinkCover>,
    /// Bodies with geometry but no spheres (not covered: the checker ignores them).
    pub uncovered: Vec<String>,
    /// Surface samples tested.
    pub samples: usize,
}

/// Calls `f(p, r)` for balls (centre, radius) in the shape's frame such that every point of
/// the shape's surface is within `h` of one of them (see [`SphereSet::cover`]).
fn sample_surface(
    g: &rl_sg::Geometry,
    h: f64,
    f: &mut dyn FnMut(DVec3, f64),
) -> Result<(), PlanError> {
    use rl_sg::Geometry;
    let mut triangle = |a: DVec3, b: DVec3, c: DVec3| {
        let longest = (b - a).length().max((c - b).length()).max((a - c).length());
        let n = ((longest / h).ceil() as usize).max(1);
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                f(a + (b - a) * u + (c - a) * v, 0.0);
            }
        }
    };
    match g {
        Geometry::Mesh(m) | Geometry::Convex(m) => {
            for k in 0..m.triangles().len() {
                let [a, b, c] = m.triangle(k);
                triangle(a, b, c);
            }
        }
        Geometry::Box { size } => {
            let s = *size * 0.5;
            let p = |x: f64, y: f64, z: f64| DVec3::new(x * s.x, y * s.y, z * s.z);
            for axis in 0..3 {
                for side in [-1.0, 1.0] {
                    // The face normal to `axis` at `side`, as two triangles.
                    let corner = |u: f64, v: f64| match axis {
                        0 => p(side, u, v),
                        1 => p(u, side, v),
                        _ => p(u, v, side),
                    };
                    triangle(corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0));
                    triangle(corner(-1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0));
                }
            }
        }
        Geometry::HalfSpace { .. } => {
            return Err(PlanError::Unsupported(
                "covering a half-space with spheres".into(),
            ));
        }
        round => {
            // Sphere, cylinder, capsule, cone: balls along the segment between the (at most
            // two) balls whose hull contains the shape.
            let balls = round.bounding_balls().unwrap_or_default();
            match balls.as_slice() {
                [(p, r)] => f(*p, *r),
                [(p0, r0), (p1, r1)] => {
                    let n = (((*p1 - *p0).length() / h).ceil() as usize).max(1);
                    for i in 0..=n {
                        let t = i as f64 / n as f64;
                        f(*p0 + (*p1 - *p0) * t, r0 + (r1 - r0) * t);
                    }
                }
                _ => {
                    return Err(PlanError::Unsupported(format!(
                        "covering a {} with spheres",
                        round.kind()
                    )));
                }
            }
        }
    }
    Ok(())
}

/// Spheres for every link.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SphereSet {
    /// The links, in file order.
    pub links: Vec<LinkSpheres>,
}

impl SphereSet {
    /// Reads the spheres of the spherized URDF at `path`, links placed through `kinematics`
    /// (loaded from the ordinary URDF of the same robot).
    pub fn from_spherized_urdf<const N: usize>(
        path: &Path,
        kinematics: &LoadedModel<N>,
    ) -> Result<Self, PlanError> {
        let text =
            rl_core::loader::read_text(path, rl_core::loader::InputLimits::DEFAULT.max_bytes)
                .map_err(|e| PlanError::Load(e.to_string()))?;
        Self::from_spherized_urdf_str(&text, kinematics).map_err(|e| match e {
            PlanError::File {
                line,
                column,
                element,
                message,
                ..
            } => PlanError::File {
                path: path.to_path_buf(),
                line,
                column,
                element,
                message,
            },
            e => e,
        })
    }

    /// [`SphereSet::from_spherized_urdf`] from the file's text.
    pub fn from_spherized_urdf_str<const N: usize>(
        text: &str,
        kinematics: &LoadedModel<N>,
    ) -> Result<Self, PlanError> {
        rl_core::loader::check_xml(text, &rl_core::loader::InputLimits::DEFAULT)
            .map_err(|e| PlanError::file("", "XML", e.to_string()))?;
        let doc = roxmltree::Document::parse(text).map_err(|e| {
            let p = e.pos();
            PlanError::file("", "XML", e.to_string()).at_position(p.row, p.col)
        })?;
        let at = |n: roxmltree::Node, message: String| {
            let p = doc.text_pos_at(n.range().start);
            PlanError::file("", format!("<{}>", n.tag_name().name()), message)
                .at_position(p.row, p.col)
        };
        let mut links = Vec::new();
        for link in doc
            .root_element()
            .children()
            .filter(|n| n.has_tag_name("link"))
        {
            let name = link.attribute("name").unwrap_or("").to_string();
            let mut spheres = Vec::new();
            for c in link.children().filter(|n| n.has_tag_name("collision")) {
                let Some(s) = c.descendants().find(|n| n.has_tag_name("sphere")) else {
                    continue;
                };
                let r: f64 = s
                    .attribute("radius")
                    .and_then(|v| v.trim().parse().ok())
                    .filter(|r: &f64| r.is_finite() && *r > 0.0)
                    .ok_or_else(|| at(s, "radius missing or not a positive number".into()))?;
                let mut xyz = DVec3::ZERO;
                if let Some(o) = c.children().find(|n| n.has_tag_name("origin"))
                    && let Some(v) = o.attribute("xyz")
                {
                    let p: Vec<f64> = v
                        .split_whitespace()
                        .map(str::parse)
                        .collect::<Result<_, _>>()
                        .map_err(|_| at(o, format!("xyz \"{v}\" is not three numbers")))?;
                    if p.len() != 3 || !p.iter().all(|x| x.is_finite()) {
                        return Err(at(o, format!("xyz \"{v}\" is not three numbers")));
                    }
                    xyz = DVec3::new(p[0], p[1], p[2]);
                }
                spheres.push((xyz, r));
            }
            if spheres.is_empty() {
                continue;
            }
            let frame = kinematics.frame(&name).map(|f| (f.body, f.placement));
            links.push(LinkSpheres {
                name,
                frame,
                spheres,
            });
        }
        if links.is_empty() {
            return Err(PlanError::file(
                "",
                "<robot>",
                "no link has a <collision><sphere>: not a spherized URDF",
            ));
        }
        Ok(Self { links })
    }

    /// Fits `per_body` spheres around every body of `model` (a scene model linked to its
    /// kinematics), padded by `padding` m (see the module docs).
    pub fn fit(model: &rl_sg::Model, per_body: usize, padding: f64) -> Result<Self, PlanError> {
        let options = rl_sg::fit::FitOptions {
            per_body,
            spheres: true,
            padding,
        };
        let mut links = Vec::new();
        for (i, b) in model.bodies().iter().enumerate() {
            let caps = rl_sg::fit::fit_body(b, &options)?;
            if caps.is_empty() {
                continue;
            }
            let frame = model.kinematics().and_then(|k| k.frame(i));
            links.push(LinkSpheres {
                name: b.name().to_string(),
                frame,
                spheres: caps.iter().map(|c| (c.a, c.radius)).collect(),
            });
        }
        Ok(Self { links })
    }

    /// Adds spheres until the set covers `model`'s geometry (matched to links by body name):
    /// every surface is sampled on a grid of spacing at most `spacing` (triangles of meshes,
    /// convex hulls and boxes subdivided; round primitives as balls along their axis), so every
    /// surface point is within `spacing` of a sample, and every sample must lie inside some
    /// sphere with that margin. While one does not, the sample farthest outside gets a new
    /// sphere: its centre `COVER_DEPTH` from the sample towards the nearest original centre
    /// (inwards; no farther than that centre), its radius that distance plus the margin plus
    /// `COVER_EXCESS`, so it sticks out of a flat surface by at most margin + excess around
    /// that sample. Samples are taken worst first, and one covered by a sphere added before is
    /// skipped. Existing spheres are kept as they are; a link without spheres gets its first
    /// from the same rule (towards the link's sample centroid). Afterwards the spheres contain
    /// the geometry.
    pub fn cover(&mut self, model: &rl_sg::Model, spacing: f64) -> Result<CoverReport, PlanError> {
        let (depth, excess) = (COVER_DEPTH, COVER_EXCESS);
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(PlanError::setting(
                "sphere cover spacing",
                "must be positive",
            ));
        }
        let mut report = CoverReport::default();
        for (bi, body) in model.bodies().iter().enumerate() {
            if body.shapes().is_empty() {
                continue;
            }
            // Samples (point, ball radius) in the body (= link) frame.
            let mut samples: Vec<(DVec3, f64)> = Vec::new();
            for shape in body.shapes() {
                let x = shape.local_pose();
                sample_surface(shape.geometry(), spacing, &mut |p, r| {
                    samples.push((x.rotation * p + x.translation, r));
                })
                .map_err(|e| match e {
                    PlanError::Unsupported(w) => {
                        PlanError::Unsupported(format!("{w} (link \"{}\")", body.name()))
                    }
                    e => e,
                })?;
            }
            report.samples += samples.len();
            let index = match self.links.iter().position(|l| l.name == body.name()) {
                Some(i) => i,
                None => {
                    self.links.push(LinkSpheres {
                        name: body.name().to_string(),
                        frame: model.kinematics().and_then(|k| k.frame(bi)),
                        spheres: Vec::new(),
                    });
                    self.links.len() - 1
                }
            };
            let link = &mut self.links[index];
            let original = link.spheres.len();
            let centroid = samples.iter().map(|s| s.0).sum::<DVec3>() / samples.len().max(1) as f64;
            // How far each sample is from being covered (≤ 0: covered).
            let need = |spheres: &[(DVec3, f64)], (p, r): (DVec3, f64)| {
                spheres
                    .iter()
                    .map(|(c, rad)| (p - *c).length() + r + spacing - rad)
                    .fold(f64::INFINITY, f64::min)
            };
            // Samples by how far they stick out, worst first; a sample covered by a sphere
            // added meanwhile is skipped (only the new spheres need testing).
            let mut open: Vec<(f64, DVec3, f64)> = samples
                .iter()
                .map(|&s| (need(&link.spheres, s), s.0, s.1))
                .filter(|x| x.0 > 0.0)
                .collect();
            open.sort_by(|a, b| b.0.total_cmp(&a.0));
            let worst = open.first().map_or(0.0, |x| x.0);
            for &(_, p, r) in &open {
                if need(&link.spheres[original..], (p, r)) <= 0.0 {
                    continue;
                }
                let inward = link
                    .spheres
                    .iter()
                    .take(original.max(1))
                    .min_by(|a, b| {
                        ((p - a.0).length() - a.1).total_cmp(&((p - b.0).length() - b.1))
                    })
                    .map_or(centroid, |s| s.0);
                let dir = (inward - p).normalize_or_zero();
                let c = p + dir * depth.min((inward - p).length());
                let rad = (c - p).length() + r + spacing + excess;
                link.spheres.push((c, rad));
            }
            report.links.push(LinkCover {
                name: link.name.clone(),
                largest_escape: worst,
                added: link.spheres.len() - original,
                spheres: link.spheres.len(),
            });
        }
        Ok(report)
    }

    /// The same spheres with every radius grown by `padding` m.
    pub fn padded(mut self, padding: f64) -> Self {
        for l in &mut self.links {
            for s in &mut l.spheres {
                s.1 += padding;
            }
        }
        self
    }

    /// The number of spheres.
    pub fn len(&self) -> usize {
        self.links.iter().map(|l| l.spheres.len()).sum()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}
