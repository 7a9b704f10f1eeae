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
//! - `Origin::Gltf`: the input's nodes, hierarchy, transforms, cameras,
//!   materials, textures, samplers and images are kept (images stored in buffer
//!   views are copied, external image files are embedded); the node that
//!   referenced mesh `m` gets level 0 of `m`'s chain. Animations of node
//!   transforms are kept (keyframes copied into the non-LOD range; they drive
//!   the node they target, so in unquantized output the coarser LOD nodes do
//!   not follow them). Skins are kept with their inverse bind matrices, and
//!   every LOD node keeps the `skin` of the node it replaces (the levels
//!   carry JOINTS_n / WEIGHTS_n), except with `quantize`, whose
//!   dequantization lives in node transforms that skinning ignores: then
//!   skins are dropped. `weights` channels and the nodes' morph `weights`
//!   are dropped since the new meshes have no morph targets.
//! - With `quantize`, positions are normalized `i16` in a cube around the
//!   chain's bounding box; the dequantization (translation + uniform scale) is
//!   the transform of the LOD nodes. For glTF input the LOD nodes are then new
//!   children of the node that referenced the mesh, so that node's own children
//!   do not inherit the dequantization. The other attributes keep compact
//!   formats (`KHR_mesh_quantization` and the core spec): NORMAL and TANGENT
//!   normalized `i8`, TEXCOORD_n normalized `u16` when within [0, 1] (float
//!   otherwise), COLOR_n normalized `u8` when within [0, 1], WEIGHTS_n
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

use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};

use crate::scene::{LodMesh, Origin, Primitive, Scene};

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
    /// One entry per input [`LodMesh`], in input order.
    pub meshes: Vec<MeshSummary>,
    /// Every file written with its size in bytes; the main file first.
    pub files: Vec<(PathBuf, u64)>,
}

/// Bytes of one chain.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct MeshSummary {
    pub name: String,
    /// Bytes of vertex and index data of each level (compressed size when
    /// compressing), finest first.
    pub level_bytes: Vec<u64>,
}

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
}

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
    let format = match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("glb") => Format::Glb,
        Some(e) if e.eq_ignore_ascii_case("gltf") => Format::Gltf,
        _ => {
            return Err(WriteError::UnknownFormat {
                path: path.to_path_buf(),
            })
        }
    };
    let material_count = match &scene.origin {
        Origin::Flat => scene.materials.len(),
        Origin::Gltf { document, .. } => document.materials.len(),
    };
    let chains = prepare_chains(scene, lods, material_count)?;
    let level_count = chains.iter().map(|c| c.levels.len()).max().unwrap_or(0);

    let mut out = Builder::new(level_count, opts);
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
        Origin::Flat => flat_document(scene, &chains, &chain_meshes, &mut out),
        Origin::Gltf {
            path: input_path,
            document,
            buffers,
        } => gltf_document(
            input_path,
            document,
            buffers,
            lods,
            &chains,
            &chain_meshes,
            &mut out,
        )?,
    };

    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("lodgen")
        .to_string();
    let files = out.finish(&mut root, format, path, &stem)?;
    write_atomically(&files)?;
    summary.files = files
        .iter()
        .map(|(p, bytes)| (p.clone(), bytes.len() as u64))
        .collect();
    Ok(summary)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Glb,
    Gltf,
}

// ---------------------------------------------------------------------------
// Per-level preparation.

/// One primitive after validation and the meshopt post-pass.
struct Prepared {
    material: Option<usize>,
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    texcoords: Option<Vec<[f32; 2]>>,
    tangents: Option<Vec<[f32; 4]>>,
    extra_texcoords: Vec<Vec<[f32; 2]>>,
    colors: Option<Vec<[f32; 4]>>,
    joints: Option<Vec<[u16; 4]>>,
    weights: Option<Vec<[f32; 4]>>,
    extra_colors: Vec<Vec<[f32; 4]>>,
    extra_joints: Vec<Vec<[u16; 4]>>,
    extra_weights: Vec<Vec<[f32; 4]>>,
    indices: Vec<u32>,
}

struct PreparedChain {
    name: String,
    source: usize,
    /// Per level: its non-empty primitives.
    levels: Vec<Vec<Prepared>>,
    coverages: Vec<f64>,
    /// Dequantization (center, uniform half extent) over all levels.
    dequant: ([f64; 3], f64),
}

fn prepare_chains(
    scene: &Scene,
    lods: &[LodMesh],
    material_count: usize,
) -> Result<Vec<PreparedChain>, WriteError> {
    let mut seen = vec![false; scene.meshes.len()];
    let mut chains = Vec::with_capacity(lods.len());
    for lod in lods {
        let invalid = |reason: String| WriteError::InvalidChain {
            mesh: lod.name.clone(),
            reason,
        };
        match seen.get_mut(lod.source) {
            None => {
                return Err(invalid(format!(
                    "source mesh {} does not exist ({} meshes)",
                    lod.source,
                    scene.meshes.len()
                )))
            }
            Some(true) => {
                return Err(invalid(format!(
                    "source mesh {} has a second LOD chain",
                    lod.source
                )))
            }
            Some(s) => *s = true,
        }
        if lod.levels.is_empty() {
            return Err(invalid("no levels".into()));
        }
        let mut levels = Vec::with_capacity(lod.levels.len());
        let mut coverages = Vec::with_capacity(lod.levels.len());
        for (k, level) in lod.levels.iter().enumerate() {
            let bad = |primitive: usize, problem: LevelProblem| WriteError::InvalidLevel {
                mesh: lod.name.clone(),
                level: k,
                primitive,
                problem,
            };
            let value = level.screen_coverage;
            let previous = coverages.last().copied().unwrap_or(1.0);
            if !(0.0..=1.0).contains(&value) || value > previous {
                return Err(bad(0, LevelProblem::Coverage { value }));
            }
            coverages.push(value);
            let mut prims = Vec::with_capacity(level.primitives.len());
            for (i, p) in level.primitives.iter().enumerate() {
                if let Some(prepared) = prepare(p, material_count).map_err(|e| bad(i, e))? {
                    prims.push(prepared);
                }
            }
            if prims.is_empty() {
                return Err(bad(0, LevelProblem::Empty));
            }
            levels.push(prims);
        }
        let dequant = dequantization(&levels);
        chains.push(PreparedChain {
            name: lod.name.clone(),
            source: lod.source,
            levels,
            coverages,
            dequant,
        });
    }
    Ok(chains)
}

/// Validates `p`, computes missing normals and applies meshopt's vertex cache
/// and vertex fetch optimizations. `None` for a primitive without triangles.
fn prepare(p: &Primitive, material_count: usize) -> Result<Option<Prepared>, LevelProblem> {
    let n = p.positions.len();
    if p.indices.len() % 3 != 0 {
        return Err(LevelProblem::IndexCount(p.indices.len()));
    }
    if u32::try_from(n).is_err() {
        return Err(LevelProblem::TooManyVertices);
    }
    if let Some(material) = p.material {
        if material >= material_count {
            return Err(LevelProblem::MaterialOutOfRange {
                material,
                count: material_count,
            });
        }
    }
    if let Some((i, &index)) = p.indices.iter().enumerate().find(|(_, &v)| v as usize >= n) {
        return Err(LevelProblem::IndexOutOfRange {
            triangle: i / 3,
            index,
            vertex_count: n,
        });
    }
    let check_len = |attribute: &'static str, len: usize| {
        if len == n {
            Ok(())
        } else {
            Err(LevelProblem::AttributeLength {
                attribute,
                len,
                vertex_count: n,
            })
        }
    };
    if let Some(normals) = &p.normals {
        check_len("NORMAL", normals.len())?;
    }
    if let Some(uv) = &p.texcoords {
        check_len("TEXCOORD_0", uv.len())?;
        if let Some(vertex) = uv.iter().position(|t| t.iter().any(|c| !c.is_finite())) {
            return Err(LevelProblem::NonFinite {
                attribute: "TEXCOORD_0",
                vertex,
            });
        }
    }
    fn finite<const N: usize>(
        v: &Option<Vec<[f32; N]>>,
        attribute: &'static str,
        check_len: &dyn Fn(&'static str, usize) -> Result<(), LevelProblem>,
    ) -> Result<(), LevelProblem> {
        if let Some(v) = v {
            check_len(attribute, v.len())?;
            if let Some(vertex) = v.iter().position(|t| t.iter().any(|c| !c.is_finite())) {
                return Err(LevelProblem::NonFinite { attribute, vertex });
            }
        }
        Ok(())
    }
    finite(&p.tangents, "TANGENT", &check_len)?;
    finite(&p.colors, "COLOR_0", &check_len)?;
    finite(&p.weights, "WEIGHTS_0", &check_len)?;
    for uv in &p.extra_texcoords {
        finite(&Some(uv.clone()), "TEXCOORD_n", &check_len)?;
    }
    if let Some(j) = &p.joints {
        check_len("JOINTS_0", j.len())?;
    }
    for c in &p.extra_colors {
        finite(&Some(c.clone()), "COLOR_n", &check_len)?;
    }
    for w in &p.extra_weights {
        finite(&Some(w.clone()), "WEIGHTS_n", &check_len)?;
    }
    for j in &p.extra_joints {
        check_len("JOINTS_n", j.len())?;
    }
    if let Some(vertex) = p
        .positions
        .iter()
        .position(|v| v.iter().any(|c| !c.is_finite()))
    {
        return Err(LevelProblem::NonFinite {
            attribute: "POSITION",
            vertex,
        });
    }
    if p.indices.is_empty() {
        return Ok(None);
    }

    let mut indices = meshopt::optimize_vertex_cache(&p.indices, n);
    // Vertex fetch order on an identity stream: `order[new] = old`, which then
    // reorders every attribute the same way (unused vertices are dropped).
    let identity: Vec<u32> = (0..n as u32).collect();
    let order = meshopt::optimize_vertex_fetch(&mut indices, &identity);
    let pick = |v: &[[f32; 3]]| -> Vec<[f32; 3]> { order.iter().map(|&o| v[o as usize]).collect() };
    let positions = pick(&p.positions);
    let computed = area_weighted_normals(&positions, &indices);
    let normals = match &p.normals {
        None => computed,
        Some(given) => pick(given)
            .iter()
            .zip(&computed)
            .map(|(g, c)| normalized(*g).unwrap_or(*c))
            .collect(),
    };
    fn reorder<T: Copy>(v: &[T], order: &[u32]) -> Vec<T> {
        order.iter().map(|&o| v[o as usize]).collect()
    }
    Ok(Some(Prepared {
        material: p.material,
        positions,
        normals,
        texcoords: p.texcoords.as_deref().map(|v| reorder(v, &order)),
        tangents: p.tangents.as_deref().map(|v| reorder(v, &order)),
        extra_texcoords: p
            .extra_texcoords
            .iter()
            .map(|v| reorder(v, &order))
            .collect(),
        colors: p.colors.as_deref().map(|v| reorder(v, &order)),
        joints: p.joints.as_deref().map(|v| reorder(v, &order)),
        weights: p.weights.as_deref().map(|v| reorder(v, &order)),
        extra_colors: p.extra_colors.iter().map(|v| reorder(v, &order)).collect(),
        extra_joints: p.extra_joints.iter().map(|v| reorder(v, &order)).collect(),
        extra_weights: p.extra_weights.iter().map(|v| reorder(v, &order)).collect(),
        indices,
    }))
}

/// One vertex attribute, encoded.
struct Encoded {
    name: String,
    bytes: Vec<u8>,
    stride: usize,
    component: u32,
    normalized: bool,
    kind: &'static str,
}

impl Encoded {
    fn new(
        name: &str,
        bytes: Vec<u8>,
        stride: usize,
        component: u32,
        normalized: bool,
        kind: &'static str,
    ) -> Encoded {
        Encoded {
            name: name.into(),
            bytes,
            stride,
            component,
            normalized,
            kind,
        }
    }
}

/// `x` in [-1, 1] as a signed normalized byte.
fn snorm8(x: f32) -> i8 {
    (f64::from(x) * 127.0).round().clamp(-127.0, 127.0) as i8
}

/// `x` in [0, 1] as an unsigned normalized byte.
fn unorm8(x: f32) -> u8 {
    (f64::from(x) * 255.0).round().clamp(0.0, 255.0) as u8
}

/// `x` in [0, 1] as an unsigned normalized short.
fn unorm16(x: f32) -> u16 {
    (f64::from(x) * 65535.0).round().clamp(0.0, 65535.0) as u16
}

/// One vertex's skin weights (all sets) as unsigned normalized bytes summing
/// to exactly 255, as glTF requires: rounded, the rounding error given to
/// the largest weight (all on the first when they sum to 0).
fn unorm8_weights(w: &[f32]) -> Vec<u8> {
    let clean: Vec<f64> = w
        .iter()
        .map(|&x| {
            if x.is_finite() {
                f64::from(x).max(0.0)
            } else {
                0.0
            }
        })
        .collect();
    let sum: f64 = clean.iter().sum();
    let mut q: Vec<i32> = if sum > 0.0 {
        clean
            .iter()
            .map(|x| (x / sum * 255.0).round() as i32)
            .collect()
    } else {
        (0..w.len()).map(|i| if i == 0 { 255 } else { 0 }).collect()
    };
    let total: i32 = q.iter().sum();
    let largest = (0..q.len()).max_by_key(|&i| (q[i], std::cmp::Reverse(i)));
    if let Some(i) = largest {
        q[i] = (q[i] + 255 - total).clamp(0, 255);
    }
    q.into_iter().map(|x| x as u8).collect()
}

/// Set 0 (when present) and sets 1, 2, … with their set numbers.
fn sets<'a, T>(
    first: &'a Option<Vec<T>>,
    extra: &'a [Vec<T>],
) -> impl Iterator<Item = (usize, &'a Vec<T>)> {
    first
        .iter()
        .map(|v| (0, v))
        .chain(extra.iter().enumerate().map(|(i, v)| (i + 1, v)))
}

fn normalized(v: [f32; 3]) -> Option<[f32; 3]> {
    let len = (v[0] as f64).hypot(v[1] as f64).hypot(v[2] as f64);
    if len.is_finite() && len > 1e-20 {
        Some([
            (v[0] as f64 / len) as f32,
            (v[1] as f64 / len) as f32,
            (v[2] as f64 / len) as f32,
        ])
    } else {
        None
    }
}

/// Per-vertex normals as the sum of the incident triangles' unnormalized
/// normals (weights = twice the areas), normalized; `+Z` where that sum is 0.
fn area_weighted_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut acc = vec![[0.0f64; 3]; positions.len()];
    for t in indices.chunks_exact(3) {
        let p = |i: u32| positions[i as usize].map(f64::from);
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        for &i in t {
            for (s, d) in acc[i as usize].iter_mut().zip(n) {
                *s += d;
            }
        }
    }
    acc.iter()
        .map(|n| {
            let len = n[0].hypot(n[1]).hypot(n[2]);
            if len > 0.0 && len.is_finite() {
                [
                    (n[0] / len) as f32,
                    (n[1] / len) as f32,
                    (n[2] / len) as f32,
                ]
            } else {
                [0.0, 0.0, 1.0]
            }
        })
        .collect()
}

/// Center and uniform half extent of the chain's bounding box (half extent 1
/// for a degenerate box).
fn dequantization(levels: &[Vec<Prepared>]) -> ([f64; 3], f64) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in levels.iter().flatten().flat_map(|p| &p.positions) {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a] as f64);
            hi[a] = hi[a].max(p[a] as f64);
        }
    }
    let center = [0, 1, 2].map(|a| (lo[a] + hi[a]) * 0.5);
    let half = (0..3).map(|a| (hi[a] - lo[a]) * 0.5).fold(0.0, f64::max);
    (center, if half > 0.0 { half } else { 1.0 })
}

// ---------------------------------------------------------------------------
// Buffers, views and accessors.

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const BYTE: u32 = 5120;
const UNSIGNED_BYTE: u32 = 5121;
const SHORT: u32 = 5122;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;
const FLOAT: u32 = 5126;
/// Largest signed-normalized 16-bit value (`1.0`).
const I16_ONE: f64 = 32767.0;

/// Segment 0 holds non-LOD data; segment `1 + k` holds level `k`.
const SHARED: usize = 0;

struct View {
    segment: usize,
    offset: usize,
    length: usize,
    stride: Option<usize>,
    target: Option<u32>,
    meshopt: Option<MeshoptView>,
}

struct MeshoptView {
    /// Offset and length of the uncompressed data in the fallback buffer.
    fallback_offset: usize,
    uncompressed_length: usize,
    stride: usize,
    count: usize,
    mode: &'static str,
}

enum Payload<'a> {
    /// Vertex attribute elements of `stride` bytes each.
    Attribute { bytes: Vec<u8>, stride: usize },
    /// A triangle list.
    Indices { indices: &'a [u32], wide: bool },
    /// Opaque bytes (images).
    Raw(Vec<u8>),
}

struct Builder {
    opts: WriteOptions,
    segments: Vec<Vec<u8>>,
    fallback_len: Vec<usize>,
    views: Vec<View>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
}

fn align4(v: &mut Vec<u8>) {
    while v.len() % 4 != 0 {
        v.push(0);
    }
}

impl Builder {
    fn new(level_count: usize, opts: &WriteOptions) -> Self {
        Builder {
            opts: *opts,
            segments: vec![Vec::new(); 1 + level_count],
            fallback_len: vec![0; 1 + level_count],
            views: Vec::new(),
            accessors: Vec::new(),
            meshes: Vec::new(),
        }
    }

    fn compress(&self) -> bool {
        self.opts.compression == Compression::Meshopt
    }

    /// Appends a buffer view; returns its index and the bytes it occupies.
    fn view(&mut self, segment: usize, payload: Payload<'_>) -> Result<(usize, usize), WriteError> {
        let compress = self.compress() && segment != SHARED;
        let (bytes, stride, target, meshopt) = match payload {
            Payload::Raw(bytes) => (bytes, None, None, None),
            Payload::Attribute { bytes, stride } => {
                debug_assert!(stride % 4 == 0 && bytes.len() % stride == 0);
                let count = bytes.len() / stride;
                if compress {
                    let encoded = encode_attribute(&bytes, stride)?;
                    let m = MeshoptView {
                        fallback_offset: 0,
                        uncompressed_length: bytes.len(),
                        stride,
                        count,
                        mode: "ATTRIBUTES",
                    };
                    (encoded, Some(stride), Some(ARRAY_BUFFER), Some(m))
                } else {
                    (bytes, Some(stride), Some(ARRAY_BUFFER), None)
                }
            }
            Payload::Indices { indices, wide } => {
                let stride = if wide { 4 } else { 2 };
                if compress {
                    let vertex_count = indices.iter().max().map_or(0, |&m| m as usize + 1);
                    let encoded = meshopt::encode_index_buffer(indices, vertex_count)
                        .map_err(|e| WriteError::Compress(e.to_string()))?;
                    let m = MeshoptView {
                        fallback_offset: 0,
                        uncompressed_length: indices.len() * stride,
                        stride,
                        count: indices.len(),
                        mode: "TRIANGLES",
                    };
                    (encoded, None, Some(ELEMENT_ARRAY_BUFFER), Some(m))
                } else {
                    let mut bytes = Vec::with_capacity(indices.len() * stride);
                    for &i in indices {
                        if wide {
                            bytes.extend_from_slice(&i.to_le_bytes());
                        } else {
                            debug_assert!(i < 65535);
                            bytes.extend_from_slice(&(i as u16).to_le_bytes());
                        }
                    }
                    (bytes, None, Some(ELEMENT_ARRAY_BUFFER), None)
                }
            }
        };
        let data = &mut self.segments[segment];
        align4(data);
        let offset = data.len();
        data.extend_from_slice(&bytes);
        let meshopt = meshopt.map(|mut m| {
            let fallback = &mut self.fallback_len[segment];
            m.fallback_offset = *fallback;
            *fallback += m.uncompressed_length.div_ceil(4) * 4;
            m
        });
        self.views.push(View {
            segment,
            offset,
            length: bytes.len(),
            stride,
            target,
            meshopt,
        });
        Ok((self.views.len() - 1, bytes.len()))
    }

    fn accessor(&mut self, value: Value) -> usize {
        self.accessors.push(value);
        self.accessors.len() - 1
    }

    /// Adds one glTF mesh per level; returns their indices and each level's
    /// byte count.
    fn add_chain(&mut self, chain: &PreparedChain) -> Result<(Vec<usize>, Vec<u64>), WriteError> {
        let mut meshes = Vec::with_capacity(chain.levels.len());
        let mut level_bytes = Vec::with_capacity(chain.levels.len());
        for (k, level) in chain.levels.iter().enumerate() {
            let segment = 1 + k;
            let mut bytes = 0usize;
            let mut primitives = Vec::with_capacity(level.len());
            for p in level {
                let (value, b) = self.add_primitive(segment, p, chain.dequant)?;
                bytes += b;
                primitives.push(value);
            }
            self.meshes.push(json!({
                "name": format!("{}_LOD{k}", chain.name),
                "primitives": primitives,
            }));
            meshes.push(self.meshes.len() - 1);
            level_bytes.push(bytes as u64);
        }
        Ok((meshes, level_bytes))
    }

    /// Every attribute but POSITION, NORMAL and TEXCOORD_0, encoded.
    fn other_attributes(&self, p: &Prepared) -> Vec<Encoded> {
        let q = self.opts.quantize;
        let mut out = Vec::new();
        if let Some(t) = &p.tangents {
            out.push(if q {
                // signed normalized bytes; w = ±1 exactly
                let bytes = t.iter().flatten().map(|&c| snorm8(c) as u8).collect();
                Encoded::new("TANGENT", bytes, 4, BYTE, true, "VEC4")
            } else {
                Encoded::new(
                    "TANGENT",
                    f32_bytes(t.iter().flatten()),
                    16,
                    FLOAT,
                    false,
                    "VEC4",
                )
            });
        }
        for (i, uv) in p.extra_texcoords.iter().enumerate() {
            let name = format!("TEXCOORD_{}", i + 1);
            out.push(
                if q && uv.iter().flatten().all(|c| (0.0..=1.0).contains(c)) {
                    let bytes = uv
                        .iter()
                        .flatten()
                        .flat_map(|&c| unorm16(c).to_le_bytes())
                        .collect();
                    Encoded::new(&name, bytes, 4, UNSIGNED_SHORT, true, "VEC2")
                } else {
                    Encoded::new(
                        &name,
                        f32_bytes(uv.iter().flatten()),
                        8,
                        FLOAT,
                        false,
                        "VEC2",
                    )
                },
            );
        }
        for (i, c) in sets(&p.colors, &p.extra_colors) {
            let name = format!("COLOR_{i}");
            out.push(
                if q && c.iter().flatten().all(|x| (0.0..=1.0).contains(x)) {
                    let bytes = c.iter().flatten().map(|&x| unorm8(x)).collect();
                    Encoded::new(&name, bytes, 4, UNSIGNED_BYTE, true, "VEC4")
                } else {
                    Encoded::new(
                        &name,
                        f32_bytes(c.iter().flatten()),
                        16,
                        FLOAT,
                        false,
                        "VEC4",
                    )
                },
            );
        }
        let weights: Vec<(usize, &Vec<[f32; 4]>)> = sets(&p.weights, &p.extra_weights).collect();
        if q && !weights.is_empty() {
            // u8 per weight, each vertex's sets summing to exactly 255
            let mut bytes = vec![Vec::with_capacity(4 * p.positions.len()); weights.len()];
            for v in 0..p.positions.len() {
                let all: Vec<f32> = weights.iter().flat_map(|(_, w)| w[v]).collect();
                let quantized = unorm8_weights(&all);
                for (s, chunk) in quantized.chunks_exact(4).enumerate() {
                    bytes[s].extend_from_slice(chunk);
                }
            }
            for ((i, _), b) in weights.iter().zip(bytes) {
                let name = format!("WEIGHTS_{i}");
                out.push(Encoded::new(&name, b, 4, UNSIGNED_BYTE, true, "VEC4"));
            }
        } else {
            for (i, w) in weights {
                let name = format!("WEIGHTS_{i}");
                out.push(Encoded::new(
                    &name,
                    f32_bytes(w.iter().flatten()),
                    16,
                    FLOAT,
                    false,
                    "VEC4",
                ));
            }
        }
        let joints: Vec<(usize, &Vec<[u16; 4]>)> = sets(&p.joints, &p.extra_joints).collect();
        let small = joints
            .iter()
            .all(|(_, j)| j.iter().flatten().all(|&x| x < 256));
        for (i, j) in joints {
            let name = format!("JOINTS_{i}");
            out.push(if q && small {
                let bytes = j.iter().flatten().map(|&x| x as u8).collect();
                Encoded::new(&name, bytes, 4, UNSIGNED_BYTE, false, "VEC4")
            } else {
                let bytes = j.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
                Encoded::new(&name, bytes, 8, UNSIGNED_SHORT, false, "VEC4")
            });
        }
        out
    }

    fn add_primitive(
        &mut self,
        segment: usize,
        p: &Prepared,
        (center, half): ([f64; 3], f64),
    ) -> Result<(Value, usize), WriteError> {
        let count = p.positions.len();
        let mut total = 0;
        let mut attributes = Map::new();

        // POSITION
        let position = if self.opts.quantize {
            let q: Vec<[i16; 3]> = p
                .positions
                .iter()
                .map(|v| {
                    [0, 1, 2].map(|a| {
                        ((v[a] as f64 - center[a]) / half * I16_ONE)
                            .round()
                            .clamp(-I16_ONE, I16_ONE) as i16
                    })
                })
                .collect();
            let (lo, hi) = min_max(q.iter().map(|v| v.map(f64::from)));
            let mut bytes = Vec::with_capacity(count * 8);
            for v in &q {
                for c in v.iter().chain(&[0i16]) {
                    bytes.extend_from_slice(&c.to_le_bytes());
                }
            }
            let (view, b) = self.view(segment, Payload::Attribute { bytes, stride: 8 })?;
            total += b;
            json!({"bufferView": view, "componentType": SHORT, "normalized": true,
                   "count": count, "type": "VEC3", "min": lo, "max": hi})
        } else {
            let (lo, hi) = min_max(p.positions.iter().map(|v| v.map(f64::from)));
            let (view, b) = self.view(
                segment,
                Payload::Attribute {
                    bytes: f32_bytes(p.positions.iter().flatten()),
                    stride: 12,
                },
            )?;
            total += b;
            json!({"bufferView": view, "componentType": FLOAT, "count": count,
                   "type": "VEC3", "min": lo, "max": hi})
        };
        attributes.insert("POSITION".into(), self.accessor(position).into());

        // NORMAL
        let normal = if self.opts.quantize {
            let mut bytes = Vec::with_capacity(count * 4);
            for n in &p.normals {
                for c in n {
                    bytes.push(((*c as f64 * 127.0).round().clamp(-127.0, 127.0) as i8) as u8);
                }
                bytes.push(0);
            }
            let (view, b) = self.view(segment, Payload::Attribute { bytes, stride: 4 })?;
            total += b;
            json!({"bufferView": view, "componentType": BYTE, "normalized": true,
                   "count": count, "type": "VEC3"})
        } else {
            let (view, b) = self.view(
                segment,
                Payload::Attribute {
                    bytes: f32_bytes(p.normals.iter().flatten()),
                    stride: 12,
                },
            )?;
            total += b;
            json!({"bufferView": view, "componentType": FLOAT, "count": count, "type": "VEC3"})
        };
        attributes.insert("NORMAL".into(), self.accessor(normal).into());

        // TEXCOORD_0
        if let Some(uv) = &p.texcoords {
            let unit = uv.iter().flatten().all(|c| (0.0..=1.0).contains(c));
            let accessor = if self.opts.quantize && unit {
                let mut bytes = Vec::with_capacity(count * 4);
                for c in uv.iter().flatten() {
                    let q = (*c as f64 * 65535.0).round().clamp(0.0, 65535.0) as u16;
                    bytes.extend_from_slice(&q.to_le_bytes());
                }
                let (view, b) = self.view(segment, Payload::Attribute { bytes, stride: 4 })?;
                total += b;
                json!({"bufferView": view, "componentType": UNSIGNED_SHORT, "normalized": true,
                       "count": count, "type": "VEC2"})
            } else {
                let (view, b) = self.view(
                    segment,
                    Payload::Attribute {
                        bytes: f32_bytes(uv.iter().flatten()),
                        stride: 8,
                    },
                )?;
                total += b;
                json!({"bufferView": view, "componentType": FLOAT, "count": count, "type": "VEC2"})
            };
            attributes.insert("TEXCOORD_0".into(), self.accessor(accessor).into());
        }

        // TANGENT, TEXCOORD_1.., COLOR_n, WEIGHTS_n, JOINTS_n: floats and
        // u16 joints, or with `quantize` the compact formats the core spec
        // and KHR_mesh_quantization allow (module docs).
        for a in self.other_attributes(p) {
            let (view, b) = self.view(
                segment,
                Payload::Attribute {
                    bytes: a.bytes,
                    stride: a.stride,
                },
            )?;
            total += b;
            let mut acc = json!({"bufferView": view, "componentType": a.component,
                                 "count": count, "type": a.kind});
            if a.normalized {
                acc["normalized"] = true.into();
            }
            attributes.insert(a.name, self.accessor(acc).into());
        }

        // Indices: u16 when every index fits below the primitive-restart value.
        let wide = count > 65535;
        let (view, b) = self.view(
            segment,
            Payload::Indices {
                indices: &p.indices,
                wide,
            },
        )?;
        total += b;
        let indices = self.accessor(json!({
            "bufferView": view,
            "componentType": if wide { UNSIGNED_INT } else { UNSIGNED_SHORT },
            "count": p.indices.len(),
            "type": "SCALAR",
        }));
        let mut prim = json!({"attributes": attributes, "indices": indices, "mode": 4});
        if let Some(m) = p.material {
            prim["material"] = m.into();
        }
        Ok((prim, total))
    }

    /// Lays out the segments, fills `accessors`, `bufferViews`, `buffers`,
    /// `meshes` and the extension lists of `root`, and returns the files to
    /// write (main file first).
    fn finish(
        self,
        root: &mut Map<String, Value>,
        format: Format,
        path: &Path,
        stem: &str,
    ) -> Result<Vec<(PathBuf, Vec<u8>)>, WriteError> {
        let compress = self.compress();
        let levels = self.segments.len() - 1;
        // Segment order: shared, then levels coarsest first.
        let order: Vec<usize> = std::iter::once(SHARED).chain((1..=levels).rev()).collect();
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut files: Vec<(PathBuf, Vec<u8>)> = Vec::new();
        let mut buffers: Vec<Value> = Vec::new();
        // Per segment: (buffer index, base offset in that buffer).
        let mut place = vec![(0usize, 0usize); self.segments.len()];
        let mut bin = Vec::new();
        match format {
            Format::Glb => {
                for &s in &order {
                    align4(&mut bin);
                    place[s] = (0, bin.len());
                    bin.extend_from_slice(&self.segments[s]);
                }
                align4(&mut bin);
                if !bin.is_empty() {
                    buffers.push(json!({"byteLength": bin.len()}));
                }
            }
            Format::Gltf => {
                for &s in &order {
                    let mut data = self.segments[s].clone();
                    if data.is_empty() {
                        continue;
                    }
                    align4(&mut data);
                    let name = if s == SHARED {
                        format!("{stem}.bin")
                    } else {
                        format!("{stem}.lod{}.bin", s - 1)
                    };
                    place[s] = (buffers.len(), 0);
                    buffers.push(json!({"byteLength": data.len(), "uri": uri_escape(&name)}));
                    files.push((dir.join(&name), data));
                }
            }
        }
        let mut fallback = vec![usize::MAX; self.segments.len()];
        if compress {
            for &s in &order {
                if self.fallback_len[s] > 0 {
                    fallback[s] = buffers.len();
                    buffers.push(json!({
                        "byteLength": self.fallback_len[s],
                        "extensions": {"EXT_meshopt_compression": {"fallback": true}},
                    }));
                }
            }
        }
        let views: Vec<Value> = self
            .views
            .iter()
            .map(|v| {
                let (buffer, base) = place[v.segment];
                let mut out = match &v.meshopt {
                    None => json!({"buffer": buffer, "byteOffset": base + v.offset,
                                   "byteLength": v.length}),
                    Some(m) => json!({
                        "buffer": fallback[v.segment],
                        "byteOffset": m.fallback_offset,
                        "byteLength": m.uncompressed_length,
                        "extensions": {"EXT_meshopt_compression": {
                            "buffer": buffer,
                            "byteOffset": base + v.offset,
                            "byteLength": v.length,
                            "byteStride": m.stride,
                            "count": m.count,
                            "mode": m.mode,
                        }},
                    }),
                };
                if let Some(stride) = v.stride {
                    out["byteStride"] = stride.into();
                }
                if let Some(target) = v.target {
                    out["target"] = target.into();
                }
                out
            })
            .collect();

        // Some node carries MSFT_lod exactly when some chain has 2+ levels.
        let mut used: Vec<String> = Vec::new();
        if levels > 1 {
            used.push("MSFT_lod".into());
        }
        let mut required: Vec<String> = Vec::new();
        if self.opts.quantize {
            used.push("KHR_mesh_quantization".into());
            required.push("KHR_mesh_quantization".into());
        }
        if compress {
            used.push("EXT_meshopt_compression".into());
            required.push("EXT_meshopt_compression".into());
        }
        merge_extension_list(root, "extensionsUsed", used);
        merge_extension_list(root, "extensionsRequired", required);
        root.insert("accessors".into(), self.accessors.into());
        root.insert("bufferViews".into(), views.into());
        root.insert("buffers".into(), buffers.into());
        root.insert("meshes".into(), self.meshes.into());
        for key in ["accessors", "bufferViews", "buffers", "meshes"] {
            if root[key].as_array().is_some_and(Vec::is_empty) {
                root.remove(key);
            }
        }
        let root = Value::Object(std::mem::take(root));
        let main = match format {
            Format::Gltf => {
                let mut json = serde_json::to_vec_pretty(&root)?;
                json.push(b'\n');
                json
            }
            Format::Glb => glb(&serde_json::to_vec(&root)?, &bin)?,
        };
        files.insert(0, (path.to_path_buf(), main));
        Ok(files)
    }
}

fn encode_attribute(bytes: &[u8], stride: usize) -> Result<Vec<u8>, WriteError> {
    fn enc<const N: usize>(bytes: &[u8]) -> Result<Vec<u8>, WriteError> {
        let elements: Vec<[u8; N]> = bytes
            .chunks_exact(N)
            .map(|c| {
                let mut a = [0u8; N];
                a.copy_from_slice(c);
                a
            })
            .collect();
        // Version 0 (header 0xa0): the version EXT_meshopt_compression and
        // Babylon.js's decoder accept; meshoptimizer 1.x defaults to 1.
        meshopt::encode_vertex_buffer_level(&elements, 2, Some(0))
            .map_err(|e| WriteError::Compress(e.to_string()))
    }
    let encoded = match stride {
        4 => enc::<4>(bytes)?,
        8 => enc::<8>(bytes)?,
        12 => enc::<12>(bytes)?,
        16 => enc::<16>(bytes)?,
        _ => return Err(WriteError::Compress(format!("unsupported stride {stride}"))),
    };
    debug_assert_eq!(encoded.first(), Some(&0xa0));
    Ok(encoded)
}

fn f32_bytes<'a>(values: impl Iterator<Item = &'a f32>) -> Vec<u8> {
    values.flat_map(|v| v.to_le_bytes()).collect()
}

fn min_max(values: impl Iterator<Item = [f64; 3]>) -> (Vec<f64>, Vec<f64>) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in values {
        for a in 0..3 {
            lo[a] = lo[a].min(v[a]);
            hi[a] = hi[a].max(v[a]);
        }
    }
    (lo.to_vec(), hi.to_vec())
}

/// Adds `names` to the root's extension list `key`, sorted, without duplicates.
fn merge_extension_list(root: &mut Map<String, Value>, key: &str, names: Vec<String>) {
    let mut list: Vec<String> = root
        .get(key)
        .and_then(Value::as_array)
        .map(|a| {
            a.iter()
                .filter_map(|v| v.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    list.extend(names);
    list.sort();
    list.dedup();
    if list.is_empty() {
        root.remove(key);
    } else {
        root.insert(key.into(), list.into());
    }
}

/// Percent-escapes the characters a URI reference cannot hold verbatim.
fn uri_escape(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for b in name.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

fn glb(json: &[u8], bin: &[u8]) -> Result<Vec<u8>, WriteError> {
    let mut json = json.to_vec();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = u32::try_from(total).map_err(|_| WriteError::TooLarge)?;
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total.to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(bin);
    }
    Ok(out)
}

// ---------------------------------------------------------------------------
// Documents.

/// The `MSFT_lod` node of level 0 plus its coarser siblings: sets
/// `ids`/`MSFT_screencoverage` on `nodes[first]` and appends the coarser
/// nodes (`template` gives their transform keys). Returns nothing: the coarser
/// nodes are appended to `nodes`.
fn add_lod_nodes(
    nodes: &mut Vec<Value>,
    first: usize,
    name: &str,
    meshes: &[usize],
    coverages: &[f64],
    template: &Map<String, Value>,
) {
    let mut ids = Vec::with_capacity(meshes.len().saturating_sub(1));
    for (k, &mesh) in meshes.iter().enumerate().skip(1) {
        let mut node = Map::new();
        for key in ["matrix", "translation", "rotation", "scale", "skin"] {
            if let Some(v) = template.get(key) {
                node.insert(key.into(), v.clone());
            }
        }
        node.insert("name".into(), format!("{name}_LOD{k}").into());
        node.insert("mesh".into(), mesh.into());
        nodes.push(Value::Object(node));
        ids.push(nodes.len() - 1);
    }
    let node = &mut nodes[first];
    node["mesh"] = meshes[0].into();
    if ids.is_empty() {
        return;
    }
    let extensions = node
        .as_object_mut()
        .map(|o| o.entry("extensions").or_insert_with(|| json!({})));
    if let Some(ext) = extensions {
        if !ext.is_object() {
            *ext = json!({});
        }
        ext["MSFT_lod"] = json!({ "ids": ids });
    }
    let coverage = Value::from(coverages.to_vec());
    match node.get_mut("extras") {
        Some(Value::Object(extras)) => {
            extras.insert("MSFT_screencoverage".into(), coverage);
        }
        _ => node["extras"] = json!({ "MSFT_screencoverage": coverage }),
    }
}

fn dequant_transform(chain: &PreparedChain, quantize: bool) -> Map<String, Value> {
    let mut m = Map::new();
    if quantize {
        let (c, s) = chain.dequant;
        m.insert("translation".into(), json!(c));
        m.insert("scale".into(), json!([s, s, s]));
    }
    m
}

fn flat_document(
    scene: &Scene,
    chains: &[PreparedChain],
    chain_meshes: &[Vec<usize>],
    out: &mut Builder,
) -> Map<String, Value> {
    let materials: Vec<Value> = scene
        .materials
        .iter()
        .map(|m| {
            let mut pbr = json!({"metallicFactor": 0.0});
            if let Some(c) = m.base_color {
                pbr["baseColorFactor"] = json!(c);
            }
            json!({"name": m.name, "pbrMetallicRoughness": pbr})
        })
        .collect();
    let mut nodes = Vec::new();
    let mut roots = Vec::new();
    for (chain, meshes) in chains.iter().zip(chain_meshes) {
        let transform = dequant_transform(chain, out.opts.quantize);
        let mut node = transform.clone();
        node.insert("name".into(), chain.name.clone().into());
        nodes.push(Value::Object(node));
        let first = nodes.len() - 1;
        roots.push(first);
        add_lod_nodes(
            &mut nodes,
            first,
            &chain.name,
            meshes,
            &chain.coverages,
            &transform,
        );
    }
    let mut root = Map::new();
    root.insert(
        "asset".into(),
        json!({"version": "2.0", "generator": "lodgen"}),
    );
    if !materials.is_empty() {
        root.insert("materials".into(), materials.into());
    }
    root.insert("nodes".into(), nodes.into());
    root.insert("scene".into(), 0.into());
    root.insert("scenes".into(), json!([{ "nodes": roots }]));
    root
}

/// Mesh-data extensions of the input that no longer apply to the output.
const DROPPED_EXTENSIONS: &[&str] = &[
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_mesh_quantization",
    "MSFT_lod",
    "EXT_mesh_gpu_instancing",
];

fn gltf_document(
    input_path: &Path,
    document: &gltf_json::Root,
    buffers: &[Vec<u8>],
    lods: &[LodMesh],
    chains: &[PreparedChain],
    chain_meshes: &[Vec<usize>],
    out: &mut Builder,
) -> Result<Map<String, Value>, WriteError> {
    let input_err = |path: String, reason: String| WriteError::InputDocument { path, reason };
    let mut root = match serde_json::to_value(document)? {
        Value::Object(m) => m,
        _ => return Err(input_err("/".into(), "not a JSON object".into())),
    };
    let in_accessors = take_array(&mut root, "accessors");
    let in_buffer_views = take_array(&mut root, "bufferViews");
    for key in ["buffers", "meshes"] {
        root.remove(key);
    }
    // Skins are kept (their inverse bind matrices copied into the non-LOD
    // range) without quantization: every level carries JOINTS / WEIGHTS.
    // Quantized positions put the dequantization into node transforms,
    // which skinning ignores, so quantized output drops skins.
    let mut skins = take_array(&mut root, "skins");
    if out.opts.quantize {
        skins.clear();
    }
    for (k, skin) in skins.iter_mut().enumerate() {
        if let Some(a) = skin.get("inverseBindMatrices").and_then(Value::as_u64) {
            let copied = copy_accessor(a as usize, &in_accessors, &in_buffer_views, buffers, out)
                .ok_or_else(|| {
                input_err(
                    format!("/skins/{k}/inverseBindMatrices"),
                    format!("accessor {a} cannot be copied (missing or sparse)"),
                )
            })?;
            skin["inverseBindMatrices"] = copied.into();
        }
    }
    if !skins.is_empty() {
        root.insert("skins".into(), skins.into());
    }
    // Animations of node transforms are kept with their keyframe data copied
    // into the non-LOD range; `weights` channels (the new meshes have no
    // morph targets) and animations whose data cannot be copied as a plain
    // dense accessor (sparse, missing) are dropped.
    let mut animations = take_array(&mut root, "animations");
    animations.retain_mut(|animation| {
        if let Some(Value::Array(channels)) = animation.get_mut("channels") {
            channels.retain(|c| {
                c.pointer("/target/path").and_then(Value::as_str) != Some("weights")
                    && c.pointer("/target/node").is_some()
            });
        }
        let has_channels = animation
            .get("channels")
            .and_then(Value::as_array)
            .is_some_and(|c| !c.is_empty());
        let Some(Value::Array(samplers)) = animation.get_mut("samplers") else {
            return false;
        };
        has_channels
            && samplers.iter_mut().all(|sampler| {
                ["input", "output"].iter().all(|key| {
                    let copied = sampler.get(*key).and_then(Value::as_u64).and_then(|a| {
                        copy_accessor(a as usize, &in_accessors, &in_buffer_views, buffers, out)
                    });
                    match copied {
                        Some(new) => {
                            sampler[*key] = new.into();
                            true
                        }
                        None => false,
                    }
                })
            })
    });
    if !animations.is_empty() {
        root.insert("animations".into(), animations.into());
    }
    for key in ["extensionsUsed", "extensionsRequired"] {
        if let Some(Value::Array(list)) = root.get_mut(key) {
            list.retain(|v| v.as_str().is_some_and(|s| !DROPPED_EXTENSIONS.contains(&s)));
        }
    }
    if let Some(asset) = root.get_mut("asset").and_then(Value::as_object_mut) {
        asset.insert("generator".into(), "lodgen".into());
    }

    // Images: copy buffer-view images and embed external files into the
    // non-LOD range; data URIs stay as they are.
    let in_views = &document.buffer_views;
    if let Some(Value::Array(images)) = root.get_mut("images") {
        for (i, image) in images.iter_mut().enumerate() {
            let Some(obj) = image.as_object_mut() else {
                continue;
            };
            let at = format!("/images/{i}");
            let bytes = if let Some(v) = obj.get("bufferView").and_then(Value::as_u64) {
                let view = in_views.get(v as usize).ok_or_else(|| {
                    input_err(at.clone(), format!("bufferView {v} does not exist"))
                })?;
                let data = buffers.get(view.buffer.value()).ok_or_else(|| {
                    input_err(
                        at.clone(),
                        format!("buffer {} has no data", view.buffer.value()),
                    )
                })?;
                let start = view.byte_offset.map_or(0, |o| o.0);
                let end = start.saturating_add(view.byte_length.0);
                usize::try_from(start)
                    .ok()
                    .zip(usize::try_from(end).ok())
                    .and_then(|(start, end)| data.get(start..end))
                    .ok_or_else(|| input_err(at.clone(), "bufferView exceeds its buffer".into()))?
                    .to_vec()
            } else if let Some(uri) = obj.get("uri").and_then(Value::as_str) {
                if uri.starts_with("data:") {
                    continue;
                }
                let file = input_path
                    .parent()
                    .unwrap_or(Path::new(""))
                    .join(percent_decode(uri));
                std::fs::read(&file).map_err(|e| {
                    input_err(at.clone(), format!("reading image {}: {e}", file.display()))
                })?
            } else {
                return Err(input_err(at, "image has neither uri nor bufferView".into()));
            };
            if !obj.contains_key("mimeType") {
                let mime = sniff_mime(&bytes).ok_or_else(|| {
                    input_err(
                        at.clone(),
                        "unknown image format (not PNG, JPEG, WebP or KTX2)".into(),
                    )
                })?;
                obj.insert("mimeType".into(), mime.into());
            }
            let (view, _) = out.view(SHARED, Payload::Raw(bytes))?;
            obj.remove("uri");
            obj.insert("bufferView".into(), view.into());
        }
    }

    // Nodes: each node with a mesh gets that mesh's chain.
    let mut chain_of = vec![usize::MAX; document.meshes.len()];
    for (c, lod) in lods.iter().enumerate() {
        if let Some(slot) = chain_of.get_mut(lod.source) {
            *slot = c;
        }
    }
    let quantize = out.opts.quantize;
    let mut nodes = match root.remove("nodes") {
        Some(Value::Array(n)) => n,
        _ => Vec::new(),
    };
    for node in &mut nodes {
        // Node extensions that point at mesh data (instancing accessors) or
        // at the input's own LOD chains no longer apply.
        if let Some(Value::Object(ext)) = node.get_mut("extensions") {
            ext.retain(|k, _| !DROPPED_EXTENSIONS.contains(&k.as_str()));
            if ext.is_empty() {
                if let Some(obj) = node.as_object_mut() {
                    obj.remove("extensions");
                }
            }
        }
    }
    let original_count = nodes.len();
    for i in 0..original_count {
        let Some(mesh) = nodes[i].get("mesh").and_then(Value::as_u64) else {
            continue;
        };
        let at = format!("/nodes/{i}");
        let c = *chain_of
            .get(mesh as usize)
            .filter(|&&c| c != usize::MAX)
            .ok_or_else(|| input_err(at.clone(), format!("mesh {mesh} has no LOD chain")))?;
        let chain = &chains[c];
        debug_assert_eq!(chain.source, mesh as usize);
        let name = nodes[i]
            .get("name")
            .and_then(Value::as_str)
            .map_or_else(|| chain.name.clone(), String::from);
        if let Some(obj) = nodes[i].as_object_mut() {
            if quantize {
                obj.remove("skin");
            }
            obj.remove("weights");
        }
        if quantize {
            // The dequantization lives on new child nodes.
            if let Some(obj) = nodes[i].as_object_mut() {
                obj.remove("mesh");
            }
            let transform = dequant_transform(chain, true);
            let mut node = transform.clone();
            node.insert("name".into(), format!("{name}_LOD0").into());
            nodes.push(Value::Object(node));
            let first = nodes.len() - 1;
            match nodes[i].get_mut("children") {
                Some(Value::Array(children)) => children.push(first.into()),
                _ => nodes[i]["children"] = json!([first]),
            }
            add_lod_nodes(
                &mut nodes,
                first,
                &name,
                &chain_meshes[c],
                &chain.coverages,
                &transform,
            );
        } else {
            let template = nodes[i].as_object().cloned().unwrap_or_default();
            add_lod_nodes(
                &mut nodes,
                i,
                &name,
                &chain_meshes[c],
                &chain.coverages,
                &template,
            );
        }
    }
    if !nodes.is_empty() {
        root.insert("nodes".into(), nodes.into());
    }
    Ok(root)
}

fn take_array(root: &mut Map<String, Value>, key: &str) -> Vec<Value> {
    match root.remove(key) {
        Some(Value::Array(a)) => a,
        _ => Vec::new(),
    }
}

/// Copies input accessor `a` (dense, with a buffer view) tightly packed into
/// the non-LOD range; returns the new accessor index, `None` when it cannot be
/// copied that way.
fn copy_accessor(
    a: usize,
    accessors: &[Value],
    views: &[Value],
    buffers: &[Vec<u8>],
    out: &mut Builder,
) -> Option<usize> {
    let acc = accessors.get(a)?;
    if acc.get("sparse").is_some() {
        return None;
    }
    let size = match acc.get("componentType")?.as_u64()? {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        5125 | 5126 => 4,
        _ => return None,
    };
    let comps = match acc.get("type")?.as_str()? {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" => 4,
        // Matrices of 1- and 2-byte components have padded columns.
        "MAT4" if size == 4 => 16,
        _ => return None,
    };
    let elem = size * comps;
    let view = views.get(acc.get("bufferView")?.as_u64()? as usize)?;
    let data = buffers.get(view.get("buffer")?.as_u64()? as usize)?;
    let stride = view
        .get("byteStride")
        .and_then(Value::as_u64)
        .map_or(elem, |s| s as usize);
    let start = view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
    let start =
        start.checked_add(acc.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize)?;
    let count = acc.get("count")?.as_u64()? as usize;
    let mut bytes = Vec::with_capacity(count.checked_mul(elem)?);
    for i in 0..count {
        let at = start.checked_add(i.checked_mul(stride)?)?;
        bytes.extend_from_slice(data.get(at..at.checked_add(elem)?)?);
    }
    let (new_view, _) = out.view(SHARED, Payload::Raw(bytes)).ok()?;
    let mut copy = acc.clone();
    let obj = copy.as_object_mut()?;
    obj.remove("byteOffset");
    obj.insert("bufferView".into(), new_view.into());
    Some(out.accessor(copy))
}

fn sniff_mime(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some("image/png")
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        Some("image/jpeg")
    } else if bytes.len() >= 12 && &bytes[0..4] == b"RIFF" && &bytes[8..12] == b"WEBP" {
        Some("image/webp")
    } else if bytes.starts_with(b"\xabKTX 20\xbb\r\n\x1a\n") {
        Some("image/ktx2")
    } else {
        None
    }
}

fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

// ---------------------------------------------------------------------------
// Atomic output.

/// Writes every file to a temporary name in its directory, then renames them
/// (the main file, first in `files`, last). On error, removes whatever it
/// created.
fn write_atomically(files: &[(PathBuf, Vec<u8>)]) -> Result<(), WriteError> {
    let temp_of = |p: &Path| {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        p.with_file_name(format!(".{name}.{}.lodgen-tmp", std::process::id()))
    };
    let mut temps: Vec<PathBuf> = Vec::with_capacity(files.len());
    let cleanup = |temps: &[PathBuf], done: &[PathBuf]| {
        for p in temps.iter().chain(done) {
            let _ = std::fs::remove_file(p);
        }
    };
    for (path, bytes) in files {
        let temp = temp_of(path);
        if let Err(source) = std::fs::write(&temp, bytes) {
            let _ = std::fs::remove_file(&temp);
            cleanup(&temps, &[]);
            return Err(WriteError::Io {
                path: path.clone(),
                source,
            });
        }
        temps.push(temp);
    }
    let mut done: Vec<PathBuf> = Vec::with_capacity(files.len());
    // Side files first, the main file last.
    let order = (1..files.len()).chain(std::iter::once(0));
    for i in order {
        let (path, _) = &files[i];
        if let Err(source) = std::fs::rename(&temps[i], path) {
            let pending: Vec<PathBuf> = temps
                .iter()
                .enumerate()
                .filter(|(j, _)| !done.contains(&files[*j].0))
                .map(|(_, t)| t.clone())
                .collect();
            cleanup(&pending, &done);
            return Err(WriteError::Io {
                path: path.clone(),
                source,
            });
        }
        done.push(path.clone());
    }
    Ok(())
}
