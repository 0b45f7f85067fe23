//! Loading geometry: URDF and SRDF, mesh files, RL's rlsg scenes with VRML, MoveIt planning
//! scenes.
//!
//! Every loader reports bad input as an [`SgError`] with the file, the element and, where the
//! format has lines, the line and column. Every file is read through rl-core's bounded reader
//! and every load is bounded by [`SceneLimits`] (see [`limits`]).

pub mod limits;
pub mod mesh_file;
pub mod moveit;
pub mod rlsg;
mod setup;
pub mod srdf;
pub mod urdf;
pub mod vrml;
mod xml;

pub use limits::SceneLimits;
pub use mesh_file::{MeshCache, load_mesh};
pub use setup::{RobotScene, RobotSetup, is_urdf};
pub use urdf::{GeometryKind, MeshMode, Robot, UrdfGeometryOptions, load_robot};

use std::path::{Path, PathBuf};

use crate::error::{SgError, SgErrorKind};
use crate::scene::Scene;

/// Reads any scene file, by its extension and root element: URDF (`.urdf`, or `.xml` with a
/// `<robot>` root: its geometry as one static model), RL's rlsg XML, VRML (`.wrl`), MoveIt
/// planning-scene YAML (`.yaml`, `.yml`); within the limits of `cache`
/// ([`MeshCache::limits`]).
pub fn load_scene_file(
    path: &Path,
    urdf: &UrdfGeometryOptions,
    cache: &mut MeshCache,
) -> Result<Scene, SgError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let urdf_scene = |cache: &mut MeshCache| -> Result<Scene, SgError> {
        let mut model = urdf::load_geometry(path, urdf, cache)?;
        model.set_self_collision(false);
        let mut s = Scene::new();
        s.add_model(model)?;
        Ok(s)
    };
    let limits = *cache.limits();
    match ext.as_str() {
        "yaml" | "yml" => {
            let mut s = Scene::new();
            s.add_model(moveit::load_environment_with(path, &limits)?)?;
            Ok(s)
        }
        "wrl" => rlsg::load_vrml_with(path, &limits),
        "urdf" => urdf_scene(cache),
        "xml" => {
            let text = read_text_within(path, limits.max_file_bytes)?;
            let root = xml::parse(&text)
                .map_err(|e| e.in_file(path))?
                .root_element()
                .tag_name()
                .name()
                .to_string();
            if root == "robot" {
                urdf_scene(cache)
            } else {
                rlsg::load_scene_with(path, &limits)
            }
        }
        _ => Err(SgError::new(SgErrorKind::UnsupportedFormat {
            format: format!(
                "scene file \"{}\" (supported: .urdf, .xml (URDF or rlsg), .wrl, .yaml)",
                path.display()
            ),
        })
        .in_file(path)),
    }
}

/// Where a resource named in a file is: `package://NAME/path` is looked up in `package_dirs`
/// (each a directory that holds packages, or a package itself when its name is NAME), then in
/// `$ROS_PACKAGE_PATH`, then in the ancestors of `base_dir` (so an unpacked package tree works
/// without configuration); `file://` paths are taken as they are; other paths are relative to
/// `base_dir` (the directory of the file that names them).
pub fn resolve(uri: &str, base_dir: &Path, package_dirs: &[PathBuf]) -> Result<PathBuf, SgError> {
    if let Some(rest) = uri.strip_prefix("package://") {
        let rest = rest.trim_start_matches('/');
        let (name, inner) = rest.split_once('/').unwrap_or((rest, ""));
        let env: Vec<PathBuf> = std::env::var_os("ROS_PACKAGE_PATH")
            .map(|v| std::env::split_paths(&v).collect())
            .unwrap_or_default();
        let ancestors = base_dir.ancestors().map(Path::to_path_buf);
        let mut tried = Vec::new();
        for dir in package_dirs.iter().cloned().chain(env).chain(ancestors) {
            let candidates = [
                dir.join(rest),
                if dir.file_name().is_some_and(|n| n == name) {
                    dir.join(inner)
                } else {
                    PathBuf::new()
                },
            ];
            for c in candidates {
                if !c.as_os_str().is_empty() && c.exists() {
                    return Ok(c);
                }
            }
            tried.push(dir.display().to_string());
        }
        return Err(SgError::new(SgErrorKind::MissingFile {
            path: PathBuf::from(uri),
        })
        .at(format!(
            "package \"{name}\" not found (looked in {})",
            shorten(&tried)
        )));
    }
    let path = match uri.strip_prefix("file://") {
        Some(p) => PathBuf::from(p),
        None => base_dir.join(uri),
    };
    if path.exists() {
        Ok(path)
    } else {
        Err(SgError::new(SgErrorKind::MissingFile { path }))
    }
}

fn shorten(dirs: &[String]) -> String {
    if dirs.len() <= 4 {
        dirs.join(", ")
    } else {
        format!("{}, … and {} more", dirs[..3].join(", "), dirs.len() - 3)
    }
}

/// Reads a text file within the default file limit ([`SceneLimits::DEFAULT`]).
pub(crate) fn read_text(path: &Path) -> Result<String, SgError> {
    read_text_within(path, SceneLimits::DEFAULT.max_file_bytes)
}

/// Reads a text file of at most `max_bytes` through rl-core's bounded reader (a FIFO or a
/// device is refused unread).
pub(crate) fn read_text_within(path: &Path, max_bytes: u64) -> Result<String, SgError> {
    rl_core::loader::read_text(path, max_bytes).map_err(SgError::from)
}

/// The directory of `path` (`.` for a bare file name).
pub(crate) fn dir_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}
