//! The fixed table of model files the server may send: each URDF (rewritten so that its mesh
//! references point at `/files/...`) and every mesh it names, as resolved while loading. A
//! request for anything else is refused: the URL names an entry of the table, never a path on
//! disk, so there is no path traversal.
//!
//! URLs: `/files/<model>/robot.urdf` for the URDF of model `<model>`, and
//! `/files/<model>/<n>/<basename>` for its `n`-th mesh. A visual mesh that is missing on disk
//! (URDF packages often ship collision meshes only) is replaced by the link's first collision
//! mesh, with a warning, so the page still draws the link.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use rl_core::loader::{InputLimits, check_xml, read_bytes, read_text};
use rl_sg::load::SceneLimits;

use crate::error::ViewError;

/// What an entry serves.
#[derive(Clone, Debug)]
enum Content {
    /// Bytes made at load time (a rewritten URDF).
    Bytes(Vec<u8>),
    /// A file read from disk when asked for.
    File(PathBuf),
}

/// One file the server may send.
#[derive(Clone, Debug)]
struct Entry {
    content: Content,
    content_type: &'static str,
}

/// The files of every model, by URL (without the leading `/files/`).
#[derive(Clone, Debug, Default)]
pub struct FileTable {
    entries: HashMap<String, Entry>,
    /// Mesh file on disk → its URL, per model.
    by_path: HashMap<(usize, PathBuf), String>,
}

/// A served URDF: its URL and the notes made while rewriting it.
#[derive(Clone, Debug)]
pub struct ServedUrdf {
    /// `/files/<model>/robot.urdf`.
    pub url: String,
    /// Meshes that could not be found (and what replaced them).
    pub warnings: Vec<String>,
}

/// A file's content type by its extension.
pub fn content_type(name: &str) -> &'static str {
    let ext = name.rsplit('.').next().unwrap_or("").to_ascii_lowercase();
    match ext.as_str() {
        "html" | "htm" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "json" | "map" => "application/json",
        "svg" => "image/svg+xml",
        "png" => "image/png",
        "jpg" | "jpeg" => "image/jpeg",
        "txt" | "md" => "text/plain; charset=utf-8",
        "urdf" | "xml" | "dae" => "application/xml",
        "stl" => "model/stl",
        "obj" => "model/obj",
        "wasm" => "application/wasm",
        _ => "application/octet-stream",
    }
}

impl FileTable {
    /// An empty table.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the table is empty.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Adds mesh file `path` of model `model` (a file resolved while loading it) and returns
    /// its URL; the same file gets the same URL.
    pub fn add_mesh_file(&mut self, model: usize, path: &Path) -> String {
        if let Some(url) = self.by_path.get(&(model, path.to_path_buf())) {
            return url.clone();
        }
        let n = self.by_path.keys().filter(|(m, _)| *m == model).count();
        let base = path
            .file_name()
            .map(|b| b.to_string_lossy().into_owned())
            .unwrap_or_else(|| "mesh".into());
        // Only characters that need no escaping in a URL.
        let base: String = base
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || "._-".contains(c) {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        let key = format!("{model}/{n}/{base}");
        self.entries.insert(
            key.clone(),
            Entry {
                content: Content::File(path.to_path_buf()),
                content_type: content_type(&base),
            },
        );
        let url = format!("/files/{key}");
        self.by_path
            .insert((model, path.to_path_buf()), url.clone());
        url
    }

    /// The URL of mesh file `path` of model `model`, if the table holds it.
    pub fn url_of(&self, model: usize, path: &Path) -> Option<&str> {
        self.by_path
            .get(&(model, path.to_path_buf()))
            .map(String::as_str)
    }

    /// Adds the URDF at `path` as model `model`'s: every `<mesh filename>` is resolved (with
    /// rl-sg's `package://` rules) and rewritten to its `/files` URL.
    pub fn add_urdf(
        &mut self,
        model: usize,
        path: &Path,
        package_dirs: &[PathBuf],
    ) -> Result<ServedUrdf, ViewError> {
        let limits = InputLimits::DEFAULT;
        let text = read_text(path, limits.max_bytes).map_err(|e| ViewError::Io {
            path: path.to_path_buf(),
            reason: e.kind.to_string(),
        })?;
        check_xml(&text, &limits).map_err(|e| ViewError::Load {
            what: path.display().to_string(),
            reason: e.to_string(),
        })?;
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let doc = roxmltree::Document::parse(&text).map_err(|e| ViewError::Load {
            what: path.display().to_string(),
            reason: e.to_string(),
        })?;
        let resolve = |uri: &str| rl_sg::load::resolve(uri, &dir, package_dirs).ok();
        let mut edits: Vec<(std::ops::Range<usize>, String)> = Vec::new();
        let mut warnings = Vec::new();
        for link in doc
            .root_element()
            .children()
            .filter(|n| n.has_tag_name("link"))
        {
            let link_name = link.attribute("name").unwrap_or("?");
            // The link's first collision mesh: the stand-in for a missing visual one.
            let collision_mesh = link
                .children()
                .filter(|n| n.has_tag_name("collision"))
                .flat_map(|c| c.descendants())
                .filter(|n| n.has_tag_name("mesh"))
                .find_map(|m| m.attribute("filename").and_then(resolve));
            for mesh in link.descendants().filter(|n| n.has_tag_name("mesh")) {
                let Some(attr) = mesh.attributes().find(|a| a.name() == "filename") else {
                    continue;
                };
                let visual = mesh.ancestors().any(|a| a.has_tag_name("visual"));
                let resolved = match resolve(attr.value()) {
                    Some(p) => Some(p),
                    None if visual => {
                        let stand_in = collision_mesh.clone();
                        warnings.push(format!(
                            "link \"{link_name}\": visual mesh \"{}\" not found{}",
                            attr.value(),
                            if stand_in.is_some() {
                                ", drawn with its collision mesh"
                            } else {
                                ", not drawn"
                            }
                        ));
                        stand_in
                    }
                    None => {
                        warnings.push(format!(
                            "link \"{link_name}\": collision mesh \"{}\" not found",
                            attr.value()
                        ));
                        None
                    }
                };
                let url = match resolved {
                    Some(p) => self.add_mesh_file(model, &p),
                    // A URL the table does not hold: the page's loader gets a 404 and skips it.
                    None => format!("/files/{model}/missing"),
                };
                edits.push((attr.range_value(), url));
            }
        }
        edits.sort_by_key(|(r, _)| r.start);
        let mut out = String::with_capacity(text.len());
        let mut at = 0;
        for (r, url) in edits {
            out.push_str(&text[at..r.start]);
            out.push_str(&url);
            at = r.end;
        }
        out.push_str(&text[at..]);
        let key = format!("{model}/robot.urdf");
        self.entries.insert(
            key.clone(),
            Entry {
                content: Content::Bytes(out.into_bytes()),
                content_type: "application/xml",
            },
        );
        Ok(ServedUrdf {
            url: format!("/files/{key}"),
            warnings,
        })
    }

    /// The content of entry `key` (the URL without `/files/`) and its content type; `None` if
    /// the table has no such entry or its file cannot be read any more (or is no longer a
    /// regular file within rl-sg's file size limit).
    pub fn read(&self, key: &str) -> Option<(Vec<u8>, &'static str)> {
        let e = self.entries.get(key)?;
        let bytes = match &e.content {
            Content::Bytes(b) => b.clone(),
            Content::File(p) => read_bytes(p, SceneLimits::DEFAULT.max_file_bytes).ok()?,
        };
        Some((bytes, e.content_type))
    }
}
