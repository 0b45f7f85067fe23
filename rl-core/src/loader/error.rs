//! Why a model file could not be loaded, and where.

use std::boxed::Box;
use std::fmt;
use std::path::PathBuf;
use std::string::String;

use super::file::{Clipped, FirstNames, ReadError, ReadErrorKind};
use crate::model::ModelError;
use crate::spatial::InertiaProblem;

/// An XML element named in an error: its tag, its `id`/`name` and where it starts.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ElementRef {
    /// The element's tag, e.g. `revolute` or `joint`.
    pub tag: String,
    /// Its `id` (RL) or `name` (URDF) attribute, if it has one.
    pub id: Option<String>,
    /// Line of the element's start, from 1.
    pub line: u32,
    /// Column of the element's start, from 1.
    pub column: u32,
}

impl fmt::Display for ElementRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}: <{}",
            self.line,
            self.column,
            Clipped(&self.tag, Clipped::NAME)
        )?;
        if let Some(id) = &self.id {
            write!(f, " \"{}\"", Clipped(id, Clipped::NAME))?;
        }
        f.write_str(">")
    }
}

/// What went wrong.
#[derive(Clone, Debug, PartialEq)]
pub enum LoadErrorKind {
    /// The file could not be read (an I/O error other than those of [`LoadErrorKind::File`]).
    Io(String),
    /// The file was not read: missing, not a regular file (a FIFO, a device), above the size
    /// limit, not UTF-8 ([`super::read_text`]).
    File(ReadErrorKind),
    /// The text is not well-formed XML (the message carries roxmltree's line:column).
    Xml(String),
    /// The root element is neither RL's `rlmdl`/`rlkin`/`rl` nor URDF's `robot`.
    UnknownFormat {
        /// The root element's tag.
        root: String,
    },
    /// A joint (transform) type this loader does not know.
    UnknownJointType {
        /// The type as written.
        joint_type: String,
    },
    /// A required attribute is missing.
    MissingAttribute {
        /// The attribute's name.
        attribute: &'static str,
    },
    /// A required child element is missing.
    MissingElement {
        /// The child's tag.
        child: &'static str,
    },
    /// A value that is not a finite number, or out of its domain.
    InvalidValue {
        /// What the value is (attribute or element name).
        what: String,
        /// The text found.
        value: String,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// An inertial description lacks its mass or inertia.
    MissingInertia {
        /// The missing part (`mass` or `inertia`).
        part: &'static str,
    },
    /// A reference to a frame, body or link that does not exist.
    UnresolvedReference {
        /// The name referred to.
        target: String,
    },
    /// Two frames, links or joints share one name.
    DuplicateName {
        /// The name.
        name: String,
    },
    /// The transforms form a cycle (the element is one transform on it).
    Cycle,
    /// A frame is the child of two transforms.
    TwoParents {
        /// The frame.
        frame: String,
        /// The other transform that already has it as its child.
        other: String,
    },
    /// The document has no root (world/root link) or more than one.
    NoSingleRoot {
        /// The first few candidate roots found (at most [`LoadErrorKind::ROOTS_KEPT`]).
        roots: std::vec::Vec<String>,
        /// How many there are.
        count: usize,
    },
    /// A body whose inertia no rigid body can have (see
    /// [`crate::spatial::RigidBodyInertia::check_physical`]).
    UnphysicalInertia {
        /// The body's link (URDF) or body (RL).
        link: String,
        /// How many links fixed to it are merged into the body's inertia.
        merged_links: usize,
        /// What is wrong.
        problem: InertiaProblem,
    },
    /// The input is larger or deeper than the loader reads ([`super::InputLimits`]).
    TooLarge {
        /// What is too large (`"file size"`, `"nesting depth"`, `"number of XML nodes"`).
        what: &'static str,
        /// The limit.
        limit: u64,
    },
    /// A mimic joint that cannot follow the joint it names.
    Mimic {
        /// The mimic joint.
        joint: String,
        /// Why (it names the joint it follows).
        reason: String,
    },
    /// The model does not fit in its capacity, or the builder refused a value.
    Model(ModelError),
    /// A feature of the format that this loader does not support.
    Unsupported {
        /// What it is and, where useful, what to do instead.
        feature: String,
    },
}

impl fmt::Display for LoadErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoadErrorKind::Io(e) => write!(f, "cannot read the file: {e}"),
            LoadErrorKind::File(e) => write!(f, "{e}"),
            LoadErrorKind::Xml(e) => write!(f, "XML syntax error: {e}"),
            LoadErrorKind::UnknownFormat { root } => write!(
                f,
                "unknown model format: the root element is <{}>, expected <rlmdl>, <rlkin>, \
                 <rl> (RL XML) or <robot> (URDF)",
                Clipped(root, Clipped::NAME)
            ),
            LoadErrorKind::UnknownJointType { joint_type } => {
                write!(
                    f,
                    "unknown joint type \"{}\"",
                    Clipped(joint_type, Clipped::NAME)
                )
            }
            LoadErrorKind::MissingAttribute { attribute } => {
                write!(f, "missing attribute \"{attribute}\"")
            }
            LoadErrorKind::MissingElement { child } => write!(f, "missing element <{child}>"),
            LoadErrorKind::InvalidValue {
                what,
                value,
                reason,
            } => {
                write!(
                    f,
                    "invalid {} \"{}\": {reason}",
                    Clipped(what, Clipped::NAME),
                    Clipped(value, Clipped::NAME)
                )
            }
            LoadErrorKind::MissingInertia { part } => {
                write!(f, "<inertial> without its <{part}>: missing inertia")
            }
            LoadErrorKind::UnresolvedReference { target } => {
                write!(
                    f,
                    "reference to \"{}\", which does not exist",
                    Clipped(target, Clipped::NAME)
                )
            }
            LoadErrorKind::DuplicateName { name } => {
                write!(f, "name \"{}\" is used twice", Clipped(name, Clipped::NAME))
            }
            LoadErrorKind::Cycle => f.write_str("the transforms form a cycle: not a tree"),
            LoadErrorKind::TwoParents { frame, other } => write!(
                f,
                "\"{}\" has two parents (it is also the child of \"{}\"): not a tree",
                Clipped(frame, Clipped::NAME),
                Clipped(other, Clipped::NAME)
            ),
            LoadErrorKind::NoSingleRoot { roots, count } => {
                if roots.is_empty() {
                    f.write_str("no root: every frame has a parent")
                } else {
                    write!(
                        f,
                        "several roots ({}); a model needs exactly one",
                        FirstNames {
                            names: roots,
                            total: *count
                        }
                    )
                }
            }
            LoadErrorKind::UnphysicalInertia {
                link,
                merged_links,
                problem,
            } => {
                write!(
                    f,
                    "the inertia of link \"{}\"",
                    Clipped(link, Clipped::NAME)
                )?;
                match merged_links {
                    0 => {}
                    1 => f.write_str(" (with the link fixed to it)")?,
                    n => write!(f, " (with the {n} links fixed to it)")?,
                }
                write!(f, " is not one a rigid body can have: {problem}")
            }
            LoadErrorKind::TooLarge { what, limit } => {
                write!(
                    f,
                    "the input's {what} is above the loader's limit of {limit}"
                )
            }
            LoadErrorKind::Mimic { joint, reason } => {
                write!(
                    f,
                    "mimic joint \"{}\": {reason}",
                    Clipped(joint, Clipped::NAME)
                )
            }
            LoadErrorKind::Model(e) => write!(f, "{e}"),
            LoadErrorKind::Unsupported { feature } => write!(f, "unsupported: {feature}"),
        }
    }
}

impl LoadErrorKind {
    /// How many root names [`LoadErrorKind::NoSingleRoot`] keeps.
    pub const ROOTS_KEPT: usize = 5;

    /// [`LoadErrorKind::NoSingleRoot`] from every root's name (the first few kept).
    pub(crate) fn roots<'s>(names: impl ExactSizeIterator<Item = &'s str>) -> Self {
        let count = names.len();
        Self::NoSingleRoot {
            roots: names.take(Self::ROOTS_KEPT).map(String::from).collect(),
            count,
        }
    }
}

/// A model file that could not be loaded: what went wrong, in which file and at which element.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadError {
    /// The file, when loading from a file.
    pub path: Option<PathBuf>,
    /// The element at fault, when there is one (boxed to keep `Result`s small).
    pub element: Option<Box<ElementRef>>,
    /// What went wrong.
    pub kind: LoadErrorKind,
}

impl LoadError {
    /// An error at `element`.
    pub(crate) fn at(element: ElementRef, kind: LoadErrorKind) -> Self {
        Self {
            path: None,
            element: Some(Box::new(element)),
            kind,
        }
    }

    /// An error not tied to one element.
    pub(crate) fn new(kind: LoadErrorKind) -> Self {
        Self {
            path: None,
            element: None,
            kind,
        }
    }

    /// The same error, naming the file.
    pub(crate) fn in_file(mut self, path: PathBuf) -> Self {
        self.path = Some(path);
        self
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(p) = &self.path {
            write!(f, "{}:", p.display())?;
        }
        if let Some(e) = &self.element {
            write!(f, "{e}: ")?;
        } else if self.path.is_some() {
            f.write_str(" ")?;
        }
        write!(f, "{}", self.kind)
    }
}

impl std::error::Error for LoadError {}

impl From<ReadError> for LoadError {
    fn from(e: ReadError) -> Self {
        Self::new(LoadErrorKind::File(e.kind)).in_file(e.path)
    }
}
