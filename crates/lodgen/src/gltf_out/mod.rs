//! The glTF writer: serializes a [`Scene`] and its [`LodMesh`] chains as glTF
//! 2.0 (`.gltf` + one `.bin` per level, or `.glb`) with `MSFT_lod`.
//!
//! This module owns the output file format: the per-level vertex post-pass
//! (meshopt vertex cache and fetch order, normals when missing), the buffer
//! layout, optional `KHR_mesh_quantization` and `EXT_meshopt_compression`, and
//! the atomic write. It does not simplify, measure or print.
//!
//! # Structure
//! - Every level of every chain is its own glTF mesh on its own node. The
//!   finest level's node carries `extensions.MSFT_lod.ids` (finer → coarser node
//!   indices) and `extras.MSFT_screencoverage` (one value per level, the last
//!   being the cull threshold, see [`crate::coverage`]). Coarser nodes are in no
//!   scene and are no node's children: `MSFT_lod` clients load them in place of
//!   the finest node (Babylon.js parents them like it), others ignore them.
//!   Coarser nodes carry the finest node's local transform (`matrix` or TRS),
//!   no children.
//! - `Origin::Flat`: one scene with one root node per chain.
//! - `Origin::Gltf`: the input's JSON as written is the output's, so nodes,
//!   hierarchy, transforms, cameras, lights, materials, textures, samplers,
//!   images, names, extras and extensions are kept untouched (images stored
//!   in buffer views are copied, external image files are embedded); the node that
//!   referenced mesh `m` gets level 0 of `m`'s chain. Animations of node
//!   transforms are kept (keyframes copied into the non-LOD range; they drive
//!   the node they target, so in unquantized output the coarser LOD nodes do
//!   not follow them). Skins are kept with their inverse bind matrices, and
//!   every LOD node keeps the `skin` of the node it replaces (the levels
//!   carry JOINTS_n / WEIGHTS_n), except with `quantize`, whose
//!   dequantization lives in node transforms that skinning ignores: then
//!   skins are dropped, and the levels' JOINTS_n / WEIGHTS_n with them. `weights` channels and the nodes' morph `weights`
//!   are dropped since the new meshes have no morph targets.
//! - With `quantize`, positions are normalized `i16` in a cube around the
//!   chain's bounding box; the dequantization (translation + uniform scale) is
//!   the transform of the LOD nodes. For glTF input the LOD nodes are then new
//!   children of the node that referenced the mesh, so that node's own children
//!   do not inherit the dequantization. The other attributes keep compact
//!   formats (`KHR_mesh_quantization` and the core spec): NORMAL and TANGENT
//!   normalized `i8`, TEXCOORD_n normalized `u16` when within [0, 1] (float
//!   otherwise; for glTF input, TEXCOORD_0 of a textured material leaving
//!   [0, 1] normalized `u16` over its range, given back by
//!   `KHR_texture_transform` on the material's textures: `uvrange`), COLOR_n normalized `u8` when within [0, 1], WEIGHTS_n
//!   normalized `u8` with each vertex's sets summing to exactly 255, JOINTS_n
//!   `u8` when every joint index of the primitive is below 256 (`u16`
//!   otherwise). Without `quantize`: floats, `u16` joints.
//!
//! # Buffer layout
//! Each level's vertex and index data (all chains' level `k`) is one buffer
//! range: for `.gltf` the file `STEM.lodK.bin`, for `.glb` one contiguous range
//! of the BIN chunk. BIN chunk order: non-LOD data (images) first, then the
//! levels coarsest first (`lod(n-1)`, …, `lod0`), so a client that streams
//! coarse-first (Babylon.js `MSFT_lod` with range requests) reads a prefix.
//! Non-LOD data of `.gltf` output goes to `STEM.bin`. With meshopt compression
//! the ranges hold the compressed streams and each level also gets a
//! placeholder fallback buffer (no data, `fallback: true`).
//!
//! # Files
//! `prepare` (validation, meshopt post-pass, normals) → `builder` (buffers,
//! views, accessors, meshes; `codec` the quantized and compressed encodings)
//! → `document` (the root JSON; `input` what is carried over from a glTF
//! input, `msft_lod` the LOD nodes) → `files` (buffer layout, GLB, atomic
//! write).

mod builder;
mod codec;
mod document;
mod error;
mod files;
mod input;
mod msft_lod;
mod options;
mod order;
mod prepare;
mod uvrange;

use std::path::{Path, PathBuf};

use crate::scene::{LodMesh, Origin, Scene};

use builder::Builder;
use document::{flat_document, gltf_document, InputGltf};
pub use error::{LevelProblem, WriteError};
use files::{write_atomically, Format, OutFile};
pub use options::{Compression, MeshSummary, WriteOptions, WriteSummary};
pub use prepare::PreparedLevels;
use prepare::{material_count, prepare_chains};

/// Writes `scene` with every mesh replaced by its LOD chain to `path`
/// (`.glb` or `.gltf` by extension). `lods[i].levels[0]` is the finest level;
/// each level's `screen_coverage` is written as `MSFT_screencoverage`.
///
/// The output is written to temporary files in the target directory and
/// renamed at the end; on error no output (and no temporary file) remains.
/// The bytes are a pure function of the arguments.
pub fn write_lods(
    path: &Path,
    scene: &Scene,
    lods: &[LodMesh],
    opts: &WriteOptions,
) -> Result<WriteSummary, WriteError> {
    write_lods_with(path, scene, lods, opts, false)
}

/// [`write_lods`]; with `strict`, a part of the input that would not be
/// carried over (a [`WriteSummary::warnings`] entry) is an error instead,
/// and nothing is written.
pub fn write_lods_with(
    path: &Path,
    scene: &Scene,
    lods: &[LodMesh],
    opts: &WriteOptions,
    strict: bool,
) -> Result<WriteSummary, WriteError> {
    write_lods_prepared(path, scene, lods, opts, strict, None)
}

/// Whether `path` names an output lodgen writes: `.glb` or `.gltf` (any
/// case), else [`WriteError::UnknownFormat`] (the command checks it before
/// any work).
pub fn check_output_path(path: &Path) -> Result<(), WriteError> {
    output_format(path).map(|_| ())
}

fn output_format(path: &Path) -> Result<Format, WriteError> {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("glb") => Ok(Format::Glb),
        Some(e) if e.eq_ignore_ascii_case("gltf") => Ok(Format::Gltf),
        _ => Err(WriteError::UnknownFormat {
            path: path.to_path_buf(),
        }),
    }
}

/// What a caller adds to the file before it is written ([`write_lods_added`]):
/// given the output's path and the main file's bytes, the new bytes and the
/// side files to write with them, or why it failed.
pub type Addition<'a> = &'a dyn Fn(&Path, Vec<u8>) -> Result<Added, String>;

/// A main file's new bytes and the side files (path, bytes) to write with it.
pub type Added = (Vec<u8>, Vec<(PathBuf, Vec<u8>)>);

/// [`write_lods_with`], taking the levels `ready` holds (prepared while the
/// build went on, [`PreparedLevels`]) instead of preparing them again: the
/// same bytes.
pub fn write_lods_prepared(
    path: &Path,
    scene: &Scene,
    lods: &[LodMesh],
    opts: &WriteOptions,
    strict: bool,
    ready: Option<&PreparedLevels>,
) -> Result<WriteSummary, WriteError> {
    write_lods_added(path, scene, lods, opts, strict, ready, None)
}

/// [`write_lods_prepared`], the main file's bytes passed through `add`
/// (`lodgen --progressive` adds its stream there) before anything is
/// written: on error nothing is, and an existing output stays as it was.
pub fn write_lods_added(
    path: &Path,
    scene: &Scene,
    lods: &[LodMesh],
    opts: &WriteOptions,
    strict: bool,
    ready: Option<&PreparedLevels>,
    add: Option<Addition<'_>>,
) -> Result<WriteSummary, WriteError> {
    let format = output_format(path)?;
    let mut chains = prepare_chains(scene, lods, material_count(scene), ready)?;
    let mut warnings = Vec::new();
    if let Origin::Gltf { json, .. } = &scene.origin {
        input::carry_mesh_properties(json, &mut chains, &mut warnings);
    }
    let level_count = chains.iter().map(|c| c.levels.len()).max().unwrap_or(0);

    let mut out = Builder::new(level_count, opts);
    out.warnings = warnings;
    if let Origin::Gltf { json, .. } = &scene.origin {
        let skins = json.get("skins").and_then(|s| s.as_array());
        out.drop_skinning = opts.quantize && skins.is_some_and(|s| !s.is_empty());
    }
    if let Origin::Gltf { json, .. } = &scene.origin {
        let materials = json.get("materials").and_then(|m| m.as_array());
        let materials = materials.map_or(&[][..], Vec::as_slice);
        out.uv_ranges = uvrange::material_ranges(materials, &chains, opts.quantize);
    }
    let mut summary = WriteSummary::default();
    let mut chain_meshes = Vec::with_capacity(chains.len());
    for chain in &chains {
        let (meshes, bytes) = out.add_chain(chain)?;
        chain_meshes.push(meshes);
        summary.meshes.push(MeshSummary {
            name: chain.name.clone(),
            level_bytes: bytes,
        });
    }

    let mut root = match &scene.origin {
        Origin::Flat => flat_document(scene, &chains, &chain_meshes, [0.0; 3], &mut out),
        Origin::Moved { offset } => flat_document(scene, &chains, &chain_meshes, *offset, &mut out),
        Origin::Gltf {
            path,
            document,
            json,
            buffers,
        } => gltf_document(
            &InputGltf {
                path,
                document,
                json,
                buffers,
            },
            lods,
            &chains,
            &chain_meshes,
            &mut out,
        )?,
    };

    out.texture_transform = uvrange::add_transforms(&mut root, &out.uv_ranges);

    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("lodgen")
        .to_string();
    summary.warnings = std::mem::take(&mut out.warnings);
    if let (true, Some(w)) = (strict, summary.warnings.first()) {
        return Err(WriteError::Strict(w.clone()));
    }
    let mut files = out.finish(&mut root, format, path, &stem)?;
    if let Some(add) = add {
        let main = std::mem::take(&mut files[0].parts).concat();
        let (main, side) = add(path, main).map_err(WriteError::Addition)?;
        files[0].parts = vec![main];
        files.extend(side.into_iter().map(|(path, bytes)| OutFile {
            path,
            parts: vec![bytes],
        }));
    }
    write_atomically(&files)?;
    summary.files = files
        .iter()
        .map(|f| (f.path.clone(), f.len() as u64))
        .collect();
    Ok(summary)
}
