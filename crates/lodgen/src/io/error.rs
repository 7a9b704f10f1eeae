//! The readers' error type: what went wrong ([`ErrorKind`]) and where
//! ([`Location`]), with the file's path ([`ReadError`]).

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in the input a [`ReadError`] happened.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Location {
    /// The file as a whole (I/O, unknown format, empty mesh).
    File,
    /// A 1-based line of a text format (OBJ, SMF, PLY header or ascii body).
    Line(usize),
    /// A 1-based line and byte column of a text format (the token an OBJ
    /// error is about).
    Column { line: usize, column: usize },
    /// A 0-based element instance of a binary PLY body, e.g. `face 12`.
    Element { element: String, index: usize },
    /// A place in a glTF document, as a JSON path such as
    /// `meshes[0].primitives[1].indices` (accessor indices are added by the
    /// message where they matter).
    Json(String),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::File => Ok(()),
            Location::Line(line) => write!(f, ":{line}"),
            Location::Column { line, column } => write!(f, ":{line}:{column}"),
            Location::Element { element, index } => write!(f, ": {element} {index}"),
            Location::Json(path) => write!(f, ": {path}"),
        }
    }
}

/// What was wrong with the input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ErrorKind {
    #[error("cannot read file")]
    Io,
    #[error("unknown format (expected .obj, .ply, .smf, .gltf or .glb)")]
    UnknownFormat,
    /// OBJ index 0; `target` is `vertex`, `texture coordinate` or `normal`.
    #[error("face refers to {target} 0 (OBJ indices start at 1)")]
    ObjIndexZero { target: &'static str },
    /// A face or index buffer refers past the end of its vertex array.
    /// `index` is as written in the file (1-based for OBJ/SMF, may be
    /// negative for OBJ relative indices).
    #[error("{what} refers to {target} {index}, but only {count} are defined")]
    IndexOutOfRange {
        what: &'static str,
        target: &'static str,
        index: i64,
        count: usize,
    },
    #[error("{what} is not finite ({value})")]
    NonFinite { what: String, value: f32 },
    #[error("expected {expected}, found `{found}`")]
    Syntax { expected: String, found: String },
    #[error("file ends early: {0}")]
    Truncated(String),
    #[error("no triangles in the file")]
    EmptyMesh,
    #[error("{0}")]
    Invalid(String),
    #[error("unsupported: {0}")]
    Unsupported(String),
}

/// A reader error: file, place and cause, displayed on one line such as
/// `bunny.obj:812: face refers to vertex 0 (OBJ indices start at 1)`.
///
/// Errors from lower layers (I/O, glTF JSON) are kept as [`std::error::Error::source`]
/// so a caller printing the cause chain shows them.
#[derive(Debug, thiserror::Error)]
#[error("{}{location}: {kind}", path.display())]
pub struct ReadError {
    /// The file as the caller named it.
    pub path: PathBuf,
    pub location: Location,
    /// Boxed to keep `Result<_, ReadError>` small.
    pub kind: Box<ErrorKind>,
    #[source]
    pub source: Option<Box<dyn std::error::Error + Send + Sync + 'static>>,
}

impl ReadError {
    pub fn new(path: &Path, location: Location, kind: ErrorKind) -> Self {
        ReadError {
            path: path.to_path_buf(),
            location,
            kind: Box::new(kind),
            source: None,
        }
    }

    pub(super) fn with_source(
        mut self,
        source: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        self.source = Some(Box::new(source));
        self
    }

    /// The 1-based line of the error, for text formats.
    pub fn line(&self) -> Option<usize> {
        match self.location {
            Location::Line(line) | Location::Column { line, .. } => Some(line),
            _ => None,
        }
    }
}
