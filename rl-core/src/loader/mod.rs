//! Model loading (feature `std`): RL's XML model format (`rlmdl`), RL's older
//! Denavit–Hartenberg kinematics format (`rlkin`) and URDF, into a fixed-capacity [`Model`].
//!
//! All three formats describe a tree of frames joined by transforms. Loading walks it depth-first
//! from the root, adds one body per moving joint (so joints are numbered as RL and Pinocchio
//! number them) and merges everything reached through fixed transforms into its moving
//! ancestor: placements are composed, inertias added. Tools are the leaves of the frame tree
//! (RL's operational frames), in depth-first order, named after the leaf frame or link.
//!
//! ```no_run
//! // From the workspace root.
//! let loaded = rl_core::loader::load_file::<64>("tests/data/rlmdl/unimation-puma560.xml")?;
//! assert_eq!(loaded.model.dof(), 6);
//! # Ok::<(), rl_core::loader::LoadError>(())
//! ```
//!
//! Errors are a [`LoadError`]: the file, the element (tag, id or name, line:column) and what is
//! wrong with it. Nothing here panics on bad input.

mod error;
pub mod file;
mod physical;
mod rlkin;
mod rlmdl;
mod tree;
mod urdf;
mod xml;

use std::path::{Path, PathBuf};
use std::string::{String, ToString};
use std::vec::Vec;

pub use error::{ElementRef, LoadError, LoadErrorKind};
pub use file::{Clipped, FirstNames, ReadError, ReadErrorKind, read_bytes, read_text};

use crate::model::{Model, ROOT};
use crate::spatial::PlueckerTransform;

/// The format a model was read from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// RL's XML model format (`<rlmdl>` or `<rl><mdl>`).
    Rlmdl,
    /// RL's Denavit–Hartenberg kinematics format (`<rlkin>` or `<rl><kin>`): kinematics only,
    /// the bodies have no mass.
    Rlkin,
    /// URDF (`<robot>`).
    Urdf,
}

/// The order in which the joints below one URDF link are numbered.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum JointOrder {
    /// The order of the `<joint>` elements in the file (depth-first, siblings in file order),
    /// as RL numbers them.
    #[default]
    File,
    /// Pinocchio's: siblings in ascending byte order of their joint names (urdfdom keeps joints
    /// in a sorted map). This makes `q` line up with Pinocchio's on branched robots.
    Pinocchio,
}

/// What to do with a moving URDF joint that has a `<mimic>` tag.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MimicJoints {
    /// The joint follows its leader, `q = multiplier · q_leader + offset`, and adds no degree
    /// of freedom ([`crate::model::mimic`]; Pinocchio's `mimic=True`).
    #[default]
    Follow,
    /// Load the joint as an independent joint (what Pinocchio does by default), with a
    /// warning.
    Independent,
    /// Refuse the file.
    Reject,
}

/// Options for URDF (RL XML files carry all they need).
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfOptions {
    /// Add a six-DOF joint `root_joint` between the world and the root link, as Pinocchio's
    /// free-flyer: `q = [x y z qx qy qz qw]`, `v = [linear; angular]` in the root link's frame.
    pub floating_base: bool,
    /// The joint order.
    pub joint_order: JointOrder,
    /// Moving joints with `<mimic>`.
    pub mimic: MimicJoints,
    /// Joints to freeze at the given position (rad or m), treated as fixed: e.g. panda's
    /// fingers, as Pinocchio's `buildReducedModel`.
    pub locked_joints: Vec<(String, f64)>,
    /// Make the leaf links tools (on by default).
    pub leaf_tools: bool,
    /// More tools, by link name, after the leaves (e.g. `panda_hand`).
    pub extra_tools: Vec<String>,
}

impl Default for UrdfOptions {
    fn default() -> Self {
        Self {
            floating_base: false,
            joint_order: JointOrder::File,
            mimic: MimicJoints::Follow,
            locked_joints: Vec::new(),
            leaf_tools: true,
            extra_tools: Vec::new(),
        }
    }
}

/// How strictly body inertias are checked (see
/// [`crate::spatial::RigidBodyInertia::check_physical`] for the rules).
///
/// An inertia that is not positive semi-definite makes the spatial inertia indefinite (a
/// motion with negative kinetic energy): the mass matrix may lose its definiteness and the
/// dynamics their meaning. One that only breaks the triangle inequality `I₁ + I₂ ≥ I₃` is
/// impossible for a rigid body but numerically harmless (the mass matrix stays positive
/// definite), and common in published parameter sets: RL's own Puma 560 (Armstrong, Khatib and
/// Burdick's link 3, 0.0125 + 0.066 < 0.086 kg·m²) and a third of example-robot-data's robots
/// (ANYmal C's cameras, the Allegro hand's links, PR2's sensor mounts, …). Hence the default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum InertiaCheck {
    /// Refuse a body that is not positive semi-definite or breaks the triangle inequality,
    /// naming its link.
    Strict,
    /// Refuse a body that is not positive semi-definite, naming its link; warn about the
    /// triangle inequality.
    #[default]
    Definite,
    /// Warn about both and load.
    Lenient,
}

/// Bounds on what a loader reads, so a huge or hostile file is refused early with a clear
/// error instead of taking the machine's memory or time ([`LoadErrorKind::TooLarge`]). rl-sg's
/// XML readers (URDF geometry, SRDF, rlsg) use the same bounds through [`check_xml`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InputLimits {
    /// Largest file (or text) in bytes; a file above it is not read ([`read_text`]).
    pub max_bytes: u64,
    /// Deepest element nesting (URDF and RL XML need about 6).
    pub max_depth: usize,
    /// Most XML nodes (elements, text and comments) the parser builds.
    pub max_nodes: u32,
    /// Most attributes on one element (URDF's `<inertia>` has six). The XML parser checks each
    /// new attribute against the element's earlier ones, so an element's cost grows with the
    /// square of its attribute count: 100 000 attributes on one element took 22 s.
    pub max_attributes: usize,
}

impl InputLimits {
    /// 64 MiB, depth 256, 8 million nodes, 256 attributes per element: about 300 times the
    /// largest URDF of example-robot-data and 700 000 URDF links; the parsed tree of such a file
    /// takes well under 1 GB, and the attribute checks at most 128 comparisons per byte.
    pub const DEFAULT: Self = Self {
        max_bytes: 64 << 20,
        max_depth: 256,
        max_nodes: 8_000_000,
        max_attributes: 256,
    };
}

/// Checks XML `text` against `limits` before a tree is built, in one linear pass without
/// allocating: its size, its nesting depth and the attributes of each element (the error names
/// the element's line and column). The loaders here and rl-sg's XML readers call it; the node
/// limit is the parser's ([`InputLimits::max_nodes`]).
pub fn check_xml(text: &str, limits: &InputLimits) -> Result<(), LoadError> {
    xml::check(text, limits)
}

impl Default for InputLimits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Every option of a load: the URDF options, the physical check, the input limits.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    /// URDF only (RL XML files carry all they need).
    pub urdf: UrdfOptions,
    /// Bodies whose inertia is not physical.
    pub inertia: InertiaCheck,
    /// Size and nesting bounds.
    pub input: InputLimits,
}

impl LoadOptions {
    /// The defaults with these URDF options.
    pub fn urdf(urdf: &UrdfOptions) -> Self {
        Self {
            urdf: urdf.clone(),
            ..Self::default()
        }
    }
}

/// Where a frame of the file (RL frame or body, URDF link) ended up.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameInfo {
    /// Its id or name in the file.
    pub name: String,
    /// The moving body it is part of, or [`ROOT`] for the world.
    pub body: usize,
    /// Its pose in that body's frame (in the world's for [`ROOT`]).
    pub placement: PlueckerTransform,
}

/// A transform of the file (RL transform, URDF joint), in depth-first order.
#[derive(Clone, Debug, PartialEq)]
pub struct TransformInfo {
    /// Its id or name.
    pub name: String,
    /// Its type as written (`revolute`, `continuous`, `fixed`, `sixDof`, `revolute (locked)`,
    /// `floating base` for the added free-flyer).
    pub source_type: String,
    /// The body it created (moving) or whose body its child was merged into ([`ROOT`] for the
    /// world).
    pub body: usize,
    /// Whether it became a joint of the model.
    pub moving: bool,
}

/// A loaded model and what the [`Model`] has no room for.
#[derive(Clone, Debug)]
pub struct LoadedModel<const N: usize> {
    /// The model.
    pub model: Model<N>,
    /// The file's format.
    pub format: Format,
    /// RL's home position (`home/q`, in rad), `nq` values.
    pub home: Option<Vec<f64>>,
    /// Every frame reached from the root, in depth-first order: where it sits in the model.
    pub frames: Vec<FrameInfo>,
    /// Every transform reached from the root, in depth-first order.
    pub transforms: Vec<TransformInfo>,
    /// Things that loaded but deserve a note (ignored elements, unconnected frames, mimic
    /// joints loaded as independent, inertias that are not physical, joints that move no
    /// mass).
    pub warnings: Vec<String>,
}

impl<const N: usize> LoadedModel<N> {
    /// The frame (RL frame or body, URDF link) called `name`.
    pub fn frame(&self, name: &str) -> Option<&FrameInfo> {
        self.frames.iter().find(|f| f.name == name)
    }

    /// The type as written in the file of body `body`'s joint.
    pub fn joint_source_type(&self, body: usize) -> Option<&str> {
        self.transforms
            .iter()
            .find(|t| t.moving && t.body == body)
            .map(|t| t.source_type.as_str())
    }

    /// The configuration home (RL's `home/q`) or else the neutral one, `nq` values.
    pub fn home_or_neutral(&self) -> Vec<f64> {
        match &self.home {
            Some(h) => h.clone(),
            None => {
                let mut q = std::vec![0.0; self.model.nq()];
                self.model.neutral(&mut q);
                q
            }
        }
    }

    /// Converts a Pinocchio configuration of the same URDF to ours: Pinocchio stores a
    /// continuous joint as `(cos θ, sin θ)` (nq = 2), we store `θ`. Other joints are copied.
    /// Returns `None` if `q` has the wrong length.
    pub fn q_from_pinocchio(&self, q: &[f64]) -> Option<Vec<f64>> {
        let mut out = Vec::with_capacity(self.model.nq());
        let mut at = 0;
        for b in 0..self.model.body_count() {
            let nq = self.model.joint_nq(b);
            if nq == 0 {
                continue; // a mimic joint: no coordinates (nor in Pinocchio's q)
            }
            if self.joint_source_type(b) == Some("continuous") {
                let (c, s) = (*q.get(at)?, *q.get(at + 1)?);
                out.push(libm::atan2(s, c));
                at += 2;
            } else {
                out.extend_from_slice(q.get(at..at + nq)?);
                at += nq;
            }
        }
        (at == q.len()).then_some(out)
    }

    /// The pose of frame `name` in its body's frame and that body ([`ROOT`] for the world).
    pub fn frame_placement(&self, name: &str) -> Option<(usize, PlueckerTransform)> {
        self.frame(name).map(|f| (f.body, f.placement))
    }

    /// Whether frame `name` is fixed to the world.
    pub fn is_on_world(&self, name: &str) -> bool {
        self.frame(name).is_some_and(|f| f.body == ROOT)
    }
}

/// A speed or effort limit as read from a file: 0 means "not given" and becomes infinite,
/// decided here once for every format. URDF requires `velocity` and `effort` on every
/// `<limit>` (urdfdom refuses one without them), so files that do not know a joint's limits
/// write 0 (e.g. example-robot-data's double pendulums); a joint that could neither move nor
/// push would be a fixed joint. An infinite [`crate::model::JointLimits::velocity`] or
/// [`crate::model::JointLimits::effort`] means unknown, as when the file has no limit at all.
pub(crate) fn rate_limit(x: f64) -> f64 {
    if x == 0.0 { f64::INFINITY } else { x }
}

/// A model's display name cut to what [`crate::model::Name`] holds (at a character boundary):
/// unlike body and joint names it identifies nothing, so a long one is no error.
fn display_name(s: &str) -> &str {
    let mut end = s.len();
    while !(s.is_char_boundary(end) && crate::model::Name::try_new(&s[..end]).is_some()) {
        end -= 1;
    }
    &s[..end]
}

/// Loads RL XML (rlmdl, rlkin) or URDF from `text`, by its root element; URDF with `urdf` options.
pub fn load_str<const N: usize>(
    text: &str,
    urdf: &UrdfOptions,
) -> Result<LoadedModel<N>, LoadError> {
    load_str_options(text, &LoadOptions::urdf(urdf))
}

/// Loads RL XML (rlmdl, rlkin) or URDF from `text`, by its root element, with every option.
pub fn load_str_options<const N: usize>(
    text: &str,
    options: &LoadOptions,
) -> Result<LoadedModel<N>, LoadError> {
    load_as(text, options, None)
}

/// Parses `text` and loads it as `format` (or by its root element), then adds the warnings
/// about joints that move no mass.
///
/// The loaded value (a fixed-capacity [`Model`], about 0.8 KB per body of capacity) is written
/// once into this function's result and amended in place: matching on it or passing it through
/// `?` would copy it, and an unoptimised build keeps every such copy on the stack (over 1 MB
/// at a capacity of 128, enough to overflow a 2 MiB thread).
fn load_as<const N: usize>(
    text: &str,
    options: &LoadOptions,
    format: Option<Format>,
) -> Result<LoadedModel<N>, LoadError> {
    let doc = xml::parse(text, &options.input)?;
    let root = doc.root_element();
    let format = format.unwrap_or_else(|| {
        if root.tag_name().name() == "robot" {
            Format::Urdf
        } else if rlkin::is_rlkin(root) {
            Format::Rlkin
        } else {
            Format::Rlmdl
        }
    });
    let mut result = match format {
        Format::Urdf => urdf::from_document(root, options),
        Format::Rlkin => rlkin::from_document(root, options),
        Format::Rlmdl => rlmdl::from_document(root, options),
    };
    if let Ok(loaded) = &mut result {
        add_format_notes(loaded, format);
    }
    result
}

/// The warnings every load of `format` gets: rlkin's missing masses, or else the joints that
/// move no mass.
fn add_format_notes<const N: usize>(loaded: &mut LoadedModel<N>, format: Format) {
    if format == Format::Rlkin {
        // The format has no masses at all: one note instead of one per joint.
        loaded.warnings.push(
            "rlkin describes kinematics only: the bodies have no mass, so the dynamics \
             (mass matrix, forward dynamics) are not defined for this model"
                .into(),
        );
        return;
    }
    for k in physical::massless_dofs(&loaded.model) {
        let b = loaded.model.dof_body(k);
        loaded.warnings.push(std::format!(
            "joint \"{}\" (DOF {k}) moves no mass or inertia along it at the neutral \
             configuration: the mass matrix is singular there, so forward dynamics and the \
             mass-matrix solve fail; give the links it moves an inertia",
            loaded.model.joint_name(b)
        ));
    }
}

/// Loads RL's XML model format from `text`.
pub fn load_rlmdl_str<const N: usize>(text: &str) -> Result<LoadedModel<N>, LoadError> {
    load_as(text, &LoadOptions::default(), Some(Format::Rlmdl))
}

/// Loads RL's Denavit–Hartenberg kinematics format (`rlkin`) from `text`.
pub fn load_rlkin_str<const N: usize>(text: &str) -> Result<LoadedModel<N>, LoadError> {
    load_as(text, &LoadOptions::default(), Some(Format::Rlkin))
}

/// Loads URDF from `text`.
pub fn load_urdf_str<const N: usize>(
    text: &str,
    options: &UrdfOptions,
) -> Result<LoadedModel<N>, LoadError> {
    load_as(text, &LoadOptions::urdf(options), Some(Format::Urdf))
}

/// Loads a model file (RL XML rlmdl or rlkin, or URDF, by its root element) with default URDF
/// options.
pub fn load_file<const N: usize>(path: impl AsRef<Path>) -> Result<LoadedModel<N>, LoadError> {
    load_file_with(path, &UrdfOptions::default())
}

/// Loads a model file (RL XML rlmdl or rlkin, or URDF, by its root element).
pub fn load_file_with<const N: usize>(
    path: impl AsRef<Path>,
    urdf: &UrdfOptions,
) -> Result<LoadedModel<N>, LoadError> {
    load_file_options(path, &LoadOptions::urdf(urdf))
}

/// Loads a model file (RL XML rlmdl or rlkin, or URDF, by its root element) with every option.
/// A file larger than [`InputLimits::max_bytes`] is refused before it is read.
pub fn load_file_options<const N: usize>(
    path: impl AsRef<Path>,
    options: &LoadOptions,
) -> Result<LoadedModel<N>, LoadError> {
    let path = path.as_ref();
    let text = read_text(path, options.input.max_bytes).map_err(LoadError::from)?;
    load_str_options(&text, options).map_err(|e| e.in_file(path.to_path_buf()))
}

/// The directory holding example-robot-data's `robots/` (for tests and tools): `$RL_ROBOT_DATA`
/// if set, else the line printed by `<repo_root>/scripts/robot-data` (which may download the
/// package once). The error says why neither worked, for a test to print when it skips.
pub fn example_robot_data_dir(repo_root: &Path) -> Result<PathBuf, String> {
    if let Some(d) = std::env::var_os("RL_ROBOT_DATA") {
        let d = PathBuf::from(d);
        return if d.join("robots").is_dir() {
            Ok(d)
        } else {
            Err(std::format!(
                "RL_ROBOT_DATA={} has no robots/ folder",
                d.display()
            ))
        };
    }
    let script = repo_root.join("scripts/robot-data");
    let out = std::process::Command::new(&script)
        .stderr(std::process::Stdio::inherit())
        .output()
        .map_err(|e| std::format!("cannot run {}: {e}", script.display()))?;
    if !out.status.success() {
        return Err(std::format!("{} failed ({})", script.display(), out.status));
    }
    let line = String::from_utf8_lossy(&out.stdout).trim().to_string();
    let d = PathBuf::from(line);
    if d.join("robots").is_dir() {
        Ok(d)
    } else {
        Err(std::format!(
            "{} printed {}, which has no robots/",
            script.display(),
            d.display()
        ))
    }
}
