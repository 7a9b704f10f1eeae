//! Why writing fails: [`WriteError`], and [`LevelProblem`] for one primitive of one level.

use std::path::PathBuf;

/// What is wrong with one primitive of one level.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LevelProblem {
    #[error("index count {0} is not a multiple of 3")]
    IndexCount(usize),
    #[error("triangle {triangle} refers to vertex {index}, but there are {vertex_count} vertices")]
    IndexOutOfRange {
        triangle: usize,
        index: u32,
        vertex_count: usize,
    },
    #[error("{attribute} has {len} entries for {vertex_count} positions")]
    AttributeLength {
        attribute: &'static str,
        len: usize,
        vertex_count: usize,
    },
    #[error("{attribute} of vertex {vertex} is not finite")]
    NonFinite {
        attribute: &'static str,
        vertex: usize,
    },
    #[error("material {material} does not exist ({count} materials)")]
    MaterialOutOfRange { material: usize, count: usize },
    #[error("the level has no triangles")]
    Empty,
    #[error("screen coverage {value} is not in [0, 1] or exceeds the finer level's")]
    Coverage { value: f64 },
    #[error("more than 2^32 - 1 vertices")]
    TooManyVertices,
}

/// Why writing failed. Nothing is left on disk when this is returned.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error("{}: output file name must end in .glb or .gltf", .path.display())]
    UnknownFormat { path: PathBuf },
    #[error("LOD chain {mesh:?}: {reason}")]
    InvalidChain { mesh: String, reason: String },
    #[error("LOD chain {mesh:?}, level {level}, primitive {primitive}: {problem}")]
    InvalidLevel {
        mesh: String,
        level: usize,
        primitive: usize,
        problem: LevelProblem,
    },
    #[error("input glTF {path}: {reason}")]
    InputDocument { path: String, reason: String },
    #[error("{}: {source}", .path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("serializing the glTF JSON: {0}")]
    Json(#[from] serde_json::Error),
    #[error("meshopt compression failed: {0}")]
    Compress(String),
    #[error("the output exceeds the 4 GiB GLB limit")]
    TooLarge,
    /// What a caller adds to the file ([`super::Addition`]) failed.
    #[error("{0}")]
    Addition(String),
    /// `--strict`: something of the input would not be carried over.
    #[error("{0} (--strict)")]
    Strict(crate::scene::Warning),
}
