//! Why geometry could not be loaded or a scene refused a value, and where.

use std::fmt;
use std::path::{Path, PathBuf};

use rl_core::loader::{Clipped, ReadError, ReadErrorKind};

/// What went wrong.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum SgErrorKind {
    /// A file could not be read.
    Io(String),
    /// A file was not read: not a regular file (a FIFO, a device), above the size limit, not
    /// UTF-8 (rl-core's bounded reader said why).
    File(ReadErrorKind),
    /// A load would pass one of its limits ([`crate::load::SceneLimits`]).
    TooLarge {
        /// What would be too large.
        what: &'static str,
        /// The limit.
        limit: u64,
    },
    /// The text is not well-formed XML, YAML or VRML (the message says what was expected).
    Syntax(String),
    /// A file referred to (a mesh, an inlined VRML file, a scene) does not exist.
    MissingFile {
        /// The path as resolved.
        path: PathBuf,
    },
    /// A file whose format is not supported (by its extension or its content).
    UnsupportedFormat {
        /// What it is.
        format: String,
    },
    /// A feature of a format that is not supported.
    Unsupported {
        /// What it is.
        feature: String,
    },
    /// A mesh without volume or area where one is needed: no triangles, out-of-range indices,
    /// all triangles of zero area, a convex hull of coplanar points.
    DegenerateMesh {
        /// Why.
        reason: String,
    },
    /// A mesh whose edges are shared by more than two triangles.
    NonManifoldMesh {
        /// How many edges are.
        edges: usize,
        /// One of them, as its two vertex indices.
        example: (u32, u32),
    },
    /// A value that is not finite, or out of its domain (a negative radius, a NaN pose).
    InvalidValue {
        /// What the value is.
        what: String,
        /// The text or number found.
        value: String,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// A required element, attribute or field is missing.
    Missing {
        /// What.
        what: String,
    },
    /// A name that refers to nothing (a link, a body, a model, a DEF).
    UnknownName {
        /// What kind of thing was looked for.
        what: &'static str,
        /// The name.
        name: String,
    },
    /// Two things of one kind share a name.
    DuplicateName {
        /// The name.
        name: String,
    },
    /// The kinematic model could not be loaded (rl-core's loader said why).
    Model(String),
    /// An error in another file this one refers to (a mesh, an inlined VRML file).
    Nested(Box<SgError>),
}

impl fmt::Display for SgErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io(e) => write!(f, "cannot read: {e}"),
            Self::File(e) => write!(f, "{e}"),
            Self::TooLarge { what, limit } => {
                write!(f, "the {what} is above the loader's limit of {limit}")
            }
            Self::Syntax(e) => write!(f, "syntax error: {}", Clipped(e, 400)),
            Self::MissingFile { path } => write!(f, "file not found: {}", path.display()),
            Self::UnsupportedFormat { format } => {
                write!(f, "unsupported format: {}", Clipped(format, 400))
            }
            Self::Unsupported { feature } => write!(f, "unsupported: {}", Clipped(feature, 400)),
            Self::DegenerateMesh { reason } => write!(f, "degenerate mesh: {reason}"),
            Self::NonManifoldMesh { edges, example } => write!(
                f,
                "non-manifold mesh: {edges} edges are shared by more than two triangles \
                 (e.g. the edge between vertices {} and {})",
                example.0, example.1
            ),
            Self::InvalidValue {
                what,
                value,
                reason,
            } => write!(
                f,
                "invalid {} \"{}\": {reason}",
                Clipped(what, Clipped::NAME),
                Clipped(value, Clipped::NAME)
            ),
            Self::Missing { what } => write!(f, "missing {}", Clipped(what, 400)),
            Self::UnknownName { what, name } => {
                write!(f, "no {what} named \"{}\"", Clipped(name, Clipped::NAME))
            }
            Self::DuplicateName { name } => write!(
                f,
                "the name \"{}\" is used twice",
                Clipped(name, Clipped::NAME)
            ),
            Self::Model(e) => write!(f, "kinematic model: {e}"),
            Self::Nested(e) => write!(f, "{e}"),
        }
    }
}

/// An error with where it happened: the file, the element in it (a URDF link's `<collision>`,
/// a VRML node, a YAML collision object) and its line and column when known.
#[derive(Clone, Debug, PartialEq)]
pub struct SgError {
    /// The file.
    pub file: Option<PathBuf>,
    /// The element at fault, described for a person (e.g. `<collision> of link "panda_link1"`).
    pub element: Option<String>,
    /// Line and column (from 1) in the file, when known.
    pub position: Option<(u32, u32)>,
    /// What went wrong (boxed to keep `Result`s small).
    pub kind: Box<SgErrorKind>,
}

impl SgError {
    /// An error of `kind`, not yet placed.
    pub fn new(kind: SgErrorKind) -> Self {
        Self {
            file: None,
            element: None,
            position: None,
            kind: Box::new(kind),
        }
    }

    /// An [`SgErrorKind::InvalidValue`].
    pub fn invalid(
        what: impl Into<String>,
        value: impl fmt::Display,
        reason: &'static str,
    ) -> Self {
        Self::new(SgErrorKind::InvalidValue {
            what: what.into(),
            value: value.to_string(),
            reason,
        })
    }

    /// An [`SgErrorKind::Missing`].
    pub fn missing(what: impl Into<String>) -> Self {
        Self::new(SgErrorKind::Missing { what: what.into() })
    }

    /// An [`SgErrorKind::Syntax`].
    pub fn syntax(message: impl Into<String>) -> Self {
        Self::new(SgErrorKind::Syntax(message.into()))
    }

    /// An [`SgErrorKind::Unsupported`].
    pub fn unsupported(feature: impl Into<String>) -> Self {
        Self::new(SgErrorKind::Unsupported {
            feature: feature.into(),
        })
    }

    /// An [`SgErrorKind::DegenerateMesh`].
    pub fn degenerate(reason: impl Into<String>) -> Self {
        Self::new(SgErrorKind::DegenerateMesh {
            reason: reason.into(),
        })
    }

    /// An error in a file referred to from another: `inner` keeps its own file and position,
    /// the new error gets those of the reference.
    pub fn nested(inner: SgError) -> Self {
        Self::new(SgErrorKind::Nested(Box::new(inner)))
    }

    /// The error at the end of a chain of [`SgErrorKind::Nested`] ones (the original cause).
    pub fn innermost(&self) -> &SgError {
        match &*self.kind {
            SgErrorKind::Nested(inner) => inner.innermost(),
            _ => self,
        }
    }

    /// An I/O error reading `path` ([`SgErrorKind::MissingFile`] when it does not exist).
    pub fn io(path: &Path, e: &std::io::Error) -> Self {
        let kind = if e.kind() == std::io::ErrorKind::NotFound {
            SgErrorKind::MissingFile {
                path: path.to_path_buf(),
            }
        } else {
            SgErrorKind::Io(e.to_string())
        };
        Self::new(kind).in_file(path)
    }

    /// The same error, in `file` (kept if a file is already named: the innermost wins).
    pub fn in_file(mut self, file: impl AsRef<Path>) -> Self {
        if self.file.is_none() {
            self.file = Some(file.as_ref().to_path_buf());
        }
        self
    }

    /// The same error, inside `element`: the first call names the innermost element, later
    /// ones prepend the outer ones (`<collision> #0 of link "arm" › <mesh>`).
    pub fn at(mut self, element: impl Into<String>) -> Self {
        let outer = element.into();
        self.element = Some(match self.element.take() {
            None => outer,
            Some(inner) if inner == outer || inner.starts_with(&format!("{outer} ›")) => inner,
            Some(inner) => format!("{outer} › {inner}"),
        });
        self
    }

    /// The same error, at line and column (kept if already placed).
    pub fn at_position(mut self, line: u32, column: u32) -> Self {
        if self.position.is_none() {
            self.position = Some((line, column));
        }
        self
    }
}

impl fmt::Display for SgError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(p) = &self.file {
            write!(f, "{}:", p.display())?;
            if let Some((l, c)) = self.position {
                write!(f, "{l}:{c}:")?;
            }
            f.write_str(" ")?;
        } else if let Some((l, c)) = self.position {
            write!(f, "{l}:{c}: ")?;
        }
        if let Some(e) = &self.element {
            write!(f, "{}: ", Clipped(e, 1000))?;
        }
        write!(f, "{}", self.kind)
    }
}

impl std::error::Error for SgError {}

impl From<ReadError> for SgError {
    /// A missing file is [`SgErrorKind::MissingFile`], anything else [`SgErrorKind::File`].
    fn from(e: ReadError) -> Self {
        let kind = match e.kind {
            ReadErrorKind::NotFound => SgErrorKind::MissingFile {
                path: e.path.clone(),
            },
            k => SgErrorKind::File(k),
        };
        Self::new(kind).in_file(e.path)
    }
}

/// Checks that every value is finite; `what` names them in the error.
pub(crate) fn check_finite(what: &str, values: &[f64]) -> Result<(), SgError> {
    match values.iter().find(|v| !v.is_finite()) {
        Some(v) => Err(SgError::invalid(what, v, "not finite")),
        None => Ok(()),
    }
}
