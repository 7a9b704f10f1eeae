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

mod common;
mod error;
mod gltf_accessor;
mod gltf_data;
mod gltf_in;
mod meshopt_in;
mod obj;
mod obj_parse;
mod obj_plain;
mod ply;
mod ply_binary;
mod ply_header;
mod smf;

pub use common::{
    far_offset, ReadOptions, DECODED_BYTES_FLOOR, DECODED_BYTES_PER_INPUT_BYTE, FAR_COORDINATE,
};
pub use error::{ErrorKind, Location, ReadError};
pub(crate) use gltf_data::decode_base64;
pub use gltf_data::encode_base64;
pub use gltf_in::{read_gltf, read_gltf_with};
pub use obj::{read_obj, read_obj_with_materials};
pub use ply::read_ply;
pub use smf::read_smf;

use std::path::Path;

use crate::scene::Scene;

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

/// Reads any supported mesh file. See the module documentation.
pub fn read_scene(path: &Path) -> Result<Scene, ReadError> {
    read_scene_with(path, &ReadOptions::default())
}

/// [`read_scene`] with options. An OBJ file is read and parsed a batch of
/// lines at a time, never held whole; other formats are read whole first.
pub fn read_scene_with(path: &Path, opts: &ReadOptions) -> Result<Scene, ReadError> {
    use std::io::Read;
    /// Enough of the file to tell its format.
    const HEAD_BYTES: u64 = 64 << 10;
    let io_err = |e| ReadError::new(path, Location::File, ErrorKind::Io).with_source(e);
    let mut file = std::fs::File::open(path).map_err(io_err)?;
    let mut bytes = Vec::new();
    (&mut file)
        .take(HEAD_BYTES)
        .read_to_end(&mut bytes)
        .map_err(io_err)?;
    // (a text file saved with a byte order mark, as Windows tools do)
    if bytes.starts_with(b"\xEF\xBB\xBF") {
        bytes.drain(..3);
    }
    let format = detect_format(path, &bytes);
    let scene = if format == Some(Format::Obj) {
        obj::read_obj_file(bytes, file, path)?
    } else {
        file.read_to_end(&mut bytes).map_err(io_err)?;
        match detect_format(path, &bytes) {
            Some(Format::Obj) => read_obj(&bytes, path)?,
            Some(Format::Ply) => read_ply(&bytes, path)?,
            Some(Format::Smf) => read_smf(&bytes, path)?,
            // (`--strict` is the glTF reader's own: it names the place in the document)
            Some(Format::Gltf) => return read_gltf_with(&bytes, path, opts),
            None => {
                return Err(ReadError::new(
                    path,
                    Location::File,
                    ErrorKind::UnknownFormat,
                ))
            }
        }
    };
    if let (true, Some(w)) = (opts.strict, scene.warnings.first()) {
        return Err(ReadError::new(
            path,
            Location::File,
            ErrorKind::Invalid(format!("{w} (--strict)")),
        ));
    }
    Ok(scene)
}
