//! Files held in memory: a program that carries a scene (its rlsg XML, the VRML it names and
//! the VRML that inlines) reads it from here instead of the file system, e.g. `rl`'s embedded
//! default robot with RL's visual meshes. Paths are names in a table, looked up after
//! removing `.` and resolving `..` lexically (an `Inline` of `link0.wrl` beside
//! `robot/robot.wrl` is `robot/link0.wrl`); nothing is read from disk while a table is in use.
//! Every byte counts against the load's [`super::SceneLimits`] as a file's would.

use std::borrow::Cow;
use std::path::{Component, Path, PathBuf};

/// A table of in-memory text files by path.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct EmbeddedFiles {
    files: Vec<(PathBuf, Cow<'static, str>)>,
}

/// `path` with `.` removed and `..` applied to what precedes it.
pub(crate) fn normal(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    out.push("..");
                }
            }
            other => out.push(other),
        }
    }
    out
}

impl EmbeddedFiles {
    /// An empty table.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds (or replaces) the file at `path` with `text`.
    pub fn add(&mut self, path: impl AsRef<Path>, text: impl Into<Cow<'static, str>>) {
        let key = normal(path.as_ref());
        let text = text.into();
        match self.files.iter_mut().find(|(p, _)| *p == key) {
            Some(slot) => slot.1 = text,
            None => self.files.push((key, text)),
        }
    }

    /// The text of the file at `path`, if the table holds it.
    pub fn get(&self, path: &Path) -> Option<&str> {
        let key = normal(path);
        self.files
            .iter()
            .find(|(p, _)| *p == key)
            .map(|(_, t)| t.as_ref())
    }

    /// Whether the table holds a file at `path`.
    pub fn contains(&self, path: &Path) -> bool {
        self.get(path).is_some()
    }

    /// The paths held, in the order added.
    pub fn paths(&self) -> impl Iterator<Item = &Path> {
        self.files.iter().map(|(p, _)| p.as_path())
    }

    /// Bytes held in all.
    pub fn bytes(&self) -> usize {
        self.files.iter().map(|(_, t)| t.len()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_are_looked_up_lexically_normalised() {
        let mut f = EmbeddedFiles::new();
        f.add("robot/./robot.wrl", "a");
        f.add("robot/link0.wrl", "b");
        assert_eq!(f.get(Path::new("robot/robot.wrl")), Some("a"));
        assert_eq!(f.get(Path::new("robot/sub/../link0.wrl")), Some("b"));
        assert_eq!(f.get(Path::new("link0.wrl")), None);
        f.add("robot/link0.wrl", "c");
        assert_eq!(f.get(Path::new("robot/link0.wrl")), Some("c"));
        assert_eq!(f.paths().count(), 2);
        assert_eq!(f.bytes(), 2);
    }
}
