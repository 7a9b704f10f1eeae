//! What the writer is asked to do ([`WriteOptions`], [`Compression`]) and what it reports
//! ([`WriteSummary`]).

use std::path::PathBuf;

/// Geometry compression of the written file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Compression {
    /// Plain buffers.
    #[default]
    None,
    /// `EXT_meshopt_compression` (vertex codec version 0, triangle index codec).
    Meshopt,
}

/// How to write the file. Default value: no quantization, no compression.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct WriteOptions {
    /// Write `KHR_mesh_quantization` vertex data (positions `i16`, normals
    /// `i8`, texture coordinates `u16` when they lie in `[0, 1]`).
    pub quantize: bool,
    /// Geometry compression.
    pub compression: Compression,
}

/// What was written.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct WriteSummary {
    /// One entry per input [`LodMesh`](crate::scene::LodMesh), in input order.
    pub meshes: Vec<MeshSummary>,
    /// Every file written with its size in bytes; the main file first.
    pub files: Vec<(PathBuf, u64)>,
    /// What of a glTF input could not be carried into the output, each
    /// naming its place (nothing is dropped without one).
    pub warnings: Vec<crate::scene::Warning>,
}

/// Bytes of one chain.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct MeshSummary {
    pub name: String,
    /// Bytes of vertex and index data of each level (compressed size when
    /// compressing), finest first.
    pub level_bytes: Vec<u64>,
}
