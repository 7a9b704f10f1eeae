//! Mesh readers: OBJ, PLY, SMF and glTF/GLB into a [`Scene`].
//!
//! This module owns turning bytes into the neutral [`Scene`] form and
//! reporting bad input as a [`ReadError`] that names the file and the exact
//! place (line, element index, JSON path). It never writes files, never
//! prints and never panics on user input.
//!
//! Conventions shared by every reader:
//! - Polygons are fan-triangulated `(c0, ci, ci+1)`; degenerate triangles
//!   are kept (the core drops them).
//! - Only vertices referenced by a triangle are kept, numbered in order of
//!   first use, so the output is a pure function of the input bytes.
//! - Non-finite coordinates, out-of-range indices, truncated data and a
//!   scene without a single triangle are errors.
//! - Texture coordinates use glTF's convention (origin at the top left):
//!   OBJ and PLY `v` is flipped to `1 - v`, glTF input is kept as is.
//!
//! [`read_scene`] picks the reader from the content (GLB magic `glTF`, a
//! `ply` header line, a JSON object) and else from the extension
//! (case-insensitive `.obj`, `.ply`, `.smf`, `.gltf`, `.glb`).

mod gltf_accessor;
mod gltf_data;
mod gltf_in;
mod meshopt_in;
mod obj;
mod ply;
mod smf;

pub use gltf_in::{read_gltf, read_gltf_with};
pub use obj::{read_obj, read_obj_with_materials};
pub use ply::read_ply;
pub use smf::read_smf;

use std::fmt;
use std::path::{Path, PathBuf};

use crate::scene::{Primitive, Scene};

/// The memory cap of the readers: decoded data allocated from counts a
/// file declares (glTF accessors, `EXT_meshopt_compression` views) may take
/// at most this many bytes per byte of input (the file and its buffers),
/// plus [`DECODED_BYTES_FLOOR`]. Every count is checked against the bytes
/// that hold its data and against this cap *before* anything is allocated,
/// so a lying count fails at once with an error naming it. The PLY reader
/// sizes its arrays by the file's length. OBJ and SMF declare no counts:
/// their arrays grow with the lines read, at most 14 bytes per input byte
/// (a huge polygon's fan) plus one [`Primitive`] and a few hundred bytes
/// per OBJ object (`tests/read_limits_text.rs` checks the worst cases).
pub const DECODED_BYTES_PER_INPUT_BYTE: u64 = 64;

/// The part of the memory cap every file gets whatever its size (64 MiB).
pub const DECODED_BYTES_FLOOR: u64 = 64 << 20;

/// Where in the input a [`ReadError`] happened.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Location {
    /// The file as a whole (I/O, unknown format, empty mesh).
    File,
    /// A 1-based line of a text format (OBJ, SMF, PLY header or ascii body).
    Line(usize),
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

    fn with_source(mut self, source: impl std::error::Error + Send + Sync + 'static) -> Self {
        self.source = Some(Box::new(source));
        self
    }

    /// The 1-based line of the error, for text formats.
    pub fn line(&self) -> Option<usize> {
        match self.location {
            Location::Line(line) => Some(line),
            _ => None,
        }
    }
}

/// The input formats [`read_scene`] knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Obj,
    Ply,
    Smf,
    Gltf,
}

/// Picks the format of `path`/`bytes`: content first (GLB magic, a `ply`
/// first line, a JSON object), then the case-insensitive extension.
pub fn detect_format(path: &Path, bytes: &[u8]) -> Option<Format> {
    if bytes.starts_with(b"glTF") {
        return Some(Format::Gltf);
    }
    if bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n") {
        return Some(Format::Ply);
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("obj") => Some(Format::Obj),
        Some("ply") => Some(Format::Ply),
        Some("smf") => Some(Format::Smf),
        Some("gltf") | Some("glb") => Some(Format::Gltf),
        _ if bytes.trim_ascii_start().starts_with(b"{") => Some(Format::Gltf),
        _ => None,
    }
}

/// How to read.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// A part of the file that would be left out with a warning (a glTF
    /// primitive that cannot be read, points and lines, a mesh with no
    /// triangle) is an error instead (`--strict`).
    pub strict: bool,
}

/// Reads any supported mesh file. See the module documentation.
pub fn read_scene(path: &Path) -> Result<Scene, ReadError> {
    read_scene_with(path, &ReadOptions::default())
}

/// [`read_scene`] with options.
pub fn read_scene_with(path: &Path, opts: &ReadOptions) -> Result<Scene, ReadError> {
    let bytes = std::fs::read(path)
        .map_err(|e| ReadError::new(path, Location::File, ErrorKind::Io).with_source(e))?;
    match detect_format(path, &bytes) {
        Some(Format::Obj) => read_obj(&bytes, path),
        Some(Format::Ply) => read_ply(&bytes, path),
        Some(Format::Smf) => read_smf(&bytes, path),
        Some(Format::Gltf) => read_gltf_with(&bytes, path, opts),
        None => Err(ReadError::new(
            path,
            Location::File,
            ErrorKind::UnknownFormat,
        )),
    }
}

/// Name of a mesh read from a single-mesh file: the file stem.
fn file_stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "mesh".to_owned())
}

/// Parses one number token of a text format.
fn parse_f32(token: &str, path: &Path, line: usize, what: &str) -> Result<f32, ReadError> {
    let value: f32 = token.parse().map_err(|_| {
        ReadError::new(
            path,
            Location::Line(line),
            ErrorKind::Syntax {
                expected: format!("a number for {what}"),
                found: token.to_owned(),
            },
        )
    })?;
    if !value.is_finite() {
        return Err(ReadError::new(
            path,
            Location::Line(line),
            ErrorKind::NonFinite {
                what: what.to_owned(),
                value,
            },
        ));
    }
    Ok(value)
}

/// Parses the next `N` coordinates of a text line; missing ones are a
/// syntax error, extra ones are ignored by the caller.
fn parse_coords<'a, const N: usize>(
    tokens: &mut impl Iterator<Item = &'a str>,
    path: &Path,
    line: usize,
    what: &str,
) -> Result<[f32; N], ReadError> {
    let mut out = [0.0f32; N];
    for slot in &mut out {
        let token = tokens.next().ok_or_else(|| {
            ReadError::new(
                path,
                Location::Line(line),
                ErrorKind::Syntax {
                    expected: format!("{N} coordinates for {what}"),
                    found: "end of line".to_owned(),
                },
            )
        })?;
        *slot = parse_f32(token, path, line, what)?;
    }
    Ok(out)
}

/// Fails with [`ErrorKind::EmptyMesh`] when no mesh has a triangle.
fn check_not_empty(scene: &Scene, path: &Path) -> Result<(), ReadError> {
    let triangles: usize = scene
        .meshes
        .iter()
        .flat_map(|m| &m.primitives)
        .map(|p| p.triangle_count())
        .sum();
    if triangles == 0 {
        return Err(ReadError::new(path, Location::File, ErrorKind::EmptyMesh));
    }
    Ok(())
}

/// Splits text into `(1-based line number, line without "\r\n")`.
fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.split('\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l)))
}

/// Drops vertices no triangle refers to and renumbers the rest in order of
/// first use. Every index must already be `< positions.len()`.
fn compact(p: Primitive) -> Primitive {
    const UNSEEN: u32 = u32::MAX;
    let mut remap = vec![UNSEEN; p.positions.len()];
    let mut order: Vec<u32> = Vec::new();
    let indices = p
        .indices
        .iter()
        .map(|&i| {
            debug_assert!((i as usize) < remap.len());
            let r = &mut remap[i as usize];
            if *r == UNSEEN {
                *r = order.len() as u32;
                order.push(i);
            }
            *r
        })
        .collect();
    fn pick<T: Copy>(values: &[T], order: &[u32]) -> Vec<T> {
        order.iter().map(|&i| values[i as usize]).collect()
    }
    Primitive {
        material: p.material,
        positions: pick(&p.positions, &order),
        normals: p.normals.as_deref().map(|n| pick(n, &order)),
        texcoords: p.texcoords.as_deref().map(|t| pick(t, &order)),
        tangents: p.tangents.as_deref().map(|t| pick(t, &order)),
        extra_texcoords: p.extra_texcoords.iter().map(|t| pick(t, &order)).collect(),
        colors: p.colors.as_deref().map(|c| pick(c, &order)),
        joints: p.joints.as_deref().map(|j| pick(j, &order)),
        weights: p.weights.as_deref().map(|w| pick(w, &order)),
        extra_colors: p.extra_colors.iter().map(|c| pick(c, &order)).collect(),
        extra_joints: p.extra_joints.iter().map(|j| pick(j, &order)).collect(),
        extra_weights: p.extra_weights.iter().map(|w| pick(w, &order)).collect(),
        targets: p
            .targets
            .iter()
            .map(|t| crate::scene::MorphTarget {
                positions: t.positions.as_deref().map(|v| pick(v, &order)),
                normals: t.normals.as_deref().map(|v| pick(v, &order)),
                tangents: t.tangents.as_deref().map(|v| pick(v, &order)),
            })
            .collect(),
        indices,
    }
}
