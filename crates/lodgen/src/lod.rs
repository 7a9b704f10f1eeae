//! The LOD builder: one simplification pass per [`SourceMesh`], every
//! requested level cut from its vertex-split log, each level measured
//! against the original and turned back into primitives.
//!
//! Owns the mapping between the scene's primitives and the core's single
//! welded mesh, the level selection (ratios, counts, measured error bounds)
//! and attribute transfer. No file I/O, no printing: progress goes through
//! a callback.
//!
//! Primitives of one mesh are simplified *jointly*: their positions are
//! welded together, so material borders are shared vertices and no crack
//! opens between primitives. Each output triangle keeps the primitive
//! (material) of the input triangle it descends from.
//!
//! Attributes live on corners (wedges). Flat vertices with the same
//! primitive, position and attribute bits are one wedge; the core welds
//! positions for topology and treats every edge across which wedges differ
//! — UV seams, hard normals, colour or skin discontinuities, material
//! borders — as a feature edge that collapses only along itself
//! (`lodgen_pm::simplify::features`); the cost adds attribute quadrics per wedge
//! (`AttributeWeights`). The log tracks each corner's wedge, and a level's
//! corner starts from the attributes of its wedge (a source vertex of the
//! same chart): JOINTS / WEIGHTS of every set stay those of that one vertex
//! (never interpolated, weights renormalised to sum 1 over all sets), while
//! normals, UVs, tangents and colours of every level below the input are
//! fitted to the input surface (`lodgen_pm::attrfit`: least squares, chart
//! by chart, seams keep their input values), then normals renormalised,
//! tangents re-orthogonalised against them, colours clamped to [0, 1].

use crate::scene::{LodLevel, LodMesh, Primitive, Scene, SourceMesh};
use lodgen_pm::attrfit::Channel;
use lodgen_pm::levels::{self, LevelSpec};
use lodgen_pm::metric::{
    self, Distance, ErrorReport, MeasureError, MeasureOptions, MeshRef, Reference,
};
use lodgen_pm::{
    simplify_adaptive, simplify_with_wedges, AdaptiveOptions, Mesh, MeshError, Method,
    ProgressiveMesh, Simplified, SimplifyOptions,
};
use std::collections::BTreeMap;
use std::time::Instant;
use thiserror::Error;

/// Which levels to build.
#[derive(Clone, Debug, PartialEq)]
pub enum LevelRequest {
    /// Ratios and/or triangle counts.
    Specs(Vec<LevelSpec>),
    /// Measured symmetric Hausdorff bounds, as fractions of the bounding-box
    /// diagonal: each level is the coarsest whose measured error stays
    /// within its bound.
    MaxErrors(Vec<f64>),
}

/// Options of [`build_lods`].
#[derive(Clone, Debug)]
pub struct BuildOptions {
    pub levels: LevelRequest,
    pub simplify: SimplifyOptions,
    /// QEM (default) or one of the curvature-adaptive methods of seed 001.
    pub method: Method,
    /// Options of the curvature-adaptive methods.
    pub adaptive: AdaptiveOptions,
    pub measure: MeasureOptions,
    /// Measure each level's error (default). When false, a level's error is
    /// the quadric's estimate (the largest recorded contraction error still
    /// in it; RMS unknown) and `MeshBuild::measured` says so.
    pub measured: bool,
    /// Weights of the attribute term of the cost (`lodgen_pm::simplify::features`).
    pub attribute_weights: AttributeWeights,
    /// Floor per mesh: no level has fewer triangles than this (nor fewer
    /// than 1), so a mesh with at most this many is written unsimplified.
    /// Default value: [`DEFAULT_MIN_TRIANGLES`].
    pub min_triangles: usize,
}

/// Default of [`BuildOptions::min_triangles`]: 8. Cards, quads, decals and
/// billboards (2–8 triangles) are kept as they are: any contraction of such a
/// part moves its outline by the part's own size, and a level of 1–7
/// triangles saves nothing a draw call would notice. A box (12) or more is
/// simplified down to 8 at most.
pub const DEFAULT_MIN_TRIANGLES: usize = 8;

/// Weights of each attribute in the cost (Hoppe 1999 attribute quadrics,
/// `lodgen_pm::simplify::features`): a difference of 1 in an attribute at weight 1
/// costs like a displacement by the bounding-box diagonal. 0 leaves an
/// attribute out (its seams are still kept).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttributeWeights {
    /// Unit normals (a difference of 2 is opposite). Default value: 0.05.
    pub normal: f32,
    /// Every `TEXCOORD_n` set. Default value: 0.5.
    pub uv: f32,
    /// Every `COLOR_n` set, RGBA. Default value: 0.5.
    pub color: f32,
}

impl AttributeWeights {
    /// What measured best on spot.obj (`cargo xtask attributes`, smooth
    /// normals, pass schedule): 0.05 / 0.5 is the pair that beats
    /// meshoptimizer's `simplify_with_attributes` on mean and RMS UV and
    /// normal error at 50 %, 10 % and 2 % (0.05 / 0.25, best under the
    /// greedy schedule, is 0.4° behind on the mean normal at 2 %), and keeps
    /// the geometric Hausdorff error below meshoptimizer's too. Colour is not
    /// measured (no test mesh has colours); it gets the UV weight, being
    /// in the same [0, 1] range.
    pub const DEFAULT: AttributeWeights = AttributeWeights {
        normal: 0.05,
        uv: 0.5,
        color: 0.5,
    };
}

impl Default for AttributeWeights {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            levels: LevelRequest::Specs(vec![
                LevelSpec::Ratio(0.5),
                LevelSpec::Ratio(0.1),
                LevelSpec::Ratio(0.02),
            ]),
            simplify: SimplifyOptions::DEFAULT,
            method: Method::Qem,
            adaptive: AdaptiveOptions::DEFAULT,
            measure: MeasureOptions::DEFAULT,
            measured: true,
            attribute_weights: AttributeWeights::DEFAULT,
            min_triangles: DEFAULT_MIN_TRIANGLES,
        }
    }
}

/// Why a mesh could not be turned into LODs.
#[derive(Debug, Error)]
pub enum BuildError {
    #[error("mesh {index} ({name:?}): {source}")]
    Mesh {
        index: usize,
        name: String,
        source: MeshError,
    },
    #[error("mesh {index} ({name:?}): measuring a level failed: {source}")]
    Measure {
        index: usize,
        name: String,
        source: metric::MeasureError,
    },
    #[error("no levels requested")]
    NoLevels,
}

/// What happened to one mesh, beside its [`LodMesh`].
#[derive(Clone, Debug)]
pub struct MeshBuild {
    pub lod: LodMesh,
    /// The simplification (progressive mesh, stats, stop reason).
    pub simplified: Simplified,
    /// Split count of each level, finest first.
    pub level_splits: Vec<usize>,
    /// Measured error of each level against the welded input, finest first.
    pub errors: Vec<ErrorReport>,
    /// False when `errors` are the quadric's estimates (`--measure off`):
    /// their maxima are the recorded contraction errors, mean and RMS NaN.
    pub measured: bool,
    /// Wall time of the simplification (preparation included) and of the
    /// error measurement (the original's hierarchy included).
    pub times: BuildTimes,
    /// What the user should know about this chain, in words (levels raised
    /// to the triangle floor, requested levels that coincide); printed under
    /// the mesh's table and in the report.
    pub notes: Vec<String>,
}

/// Where a mesh's build time went (wall clock).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuildTimes {
    /// Weld, clean and simplify (the core's phases and its preparation).
    pub simplify: std::time::Duration,
    /// Measure every level against the original (and search levels by error).
    pub measure: std::time::Duration,
    /// The whole build of this mesh: the above plus flattening, level
    /// extraction and attribute fitting.
    pub total: std::time::Duration,
}

/// Progress events, for a progress bar (the builder never prints). In
/// order: `Reading`, then per mesh `Simplifying` and one `Measuring` per
/// level, then `Writing`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Parsing the input file (sent by [`crate::cli::build_file`]).
    Reading,
    /// Writing the output file (sent by [`crate::cli::build_file`]).
    Writing,
    Simplifying {
        mesh: usize,
        of: usize,
    },
    Measuring {
        mesh: usize,
        level: usize,
        of: usize,
    },
}

/// The input mesh flattened for the core: all primitives in one index list.
struct Flat {
    positions: Vec<[f32; 3]>,
    indices: Vec<u32>,
    /// Input triangle → primitive.
    prim_of_triangle: Vec<u32>,
    /// First flat vertex of each primitive.
    vertex_offset: Vec<u32>,
}

/// Bit pattern of every attribute of a flat vertex: equal keys, one wedge.
fn wedge_key(mesh: &SourceMesh, prim: usize, v: usize) -> Vec<u32> {
    let p = &mesh.primitives[prim];
    let mut k = vec![prim as u32];
    let mut put = |xs: &[f32]| k.extend(xs.iter().map(|x| if *x == 0.0 { 0 } else { x.to_bits() }));
    put(&p.positions[v]);
    if let Some(a) = &p.normals {
        put(&a[v]);
    }
    if let Some(a) = &p.texcoords {
        put(&a[v]);
    }
    if let Some(a) = &p.tangents {
        put(&a[v]);
    }
    for a in &p.extra_texcoords {
        put(&a[v]);
    }
    if let Some(a) = &p.colors {
        put(&a[v]);
    }
    if let Some(a) = &p.weights {
        put(&a[v]);
    }
    for a in &p.extra_colors {
        put(&a[v]);
    }
    for a in &p.extra_weights {
        put(&a[v]);
    }
    if let Some(a) = &p.joints {
        k.extend(a[v].map(u32::from));
    }
    for a in &p.extra_joints {
        k.extend(a[v].map(u32::from));
    }
    k
}

/// The weighted attribute vector of every flat vertex for the cost, and its
/// length: normal, every UV set, every colour set, each present when some
/// primitive has it and its weight is not 0 (vertices of primitives without
/// it get zeros, white for colours). Tangents follow the UV charts and are
/// not priced; joints and weights are never interpolated.
fn weighted_attributes(mesh: &SourceMesh, flat: &Flat, w: &AttributeWeights) -> (Vec<f32>, usize) {
    let any = |f: &dyn Fn(&Primitive) -> bool| mesh.primitives.iter().any(f);
    let most = |f: &dyn Fn(&Primitive) -> usize| mesh.primitives.iter().map(f).max().unwrap_or(0);
    let normal = w.normal != 0.0 && any(&|p| p.normals.is_some());
    // every UV set under the `uv` weight, every colour set under `color`
    let uv = w.uv != 0.0 && any(&|p| p.texcoords.is_some());
    let extra_uv = if w.uv != 0.0 {
        most(&|p| p.extra_texcoords.len())
    } else {
        0
    };
    let color = w.color != 0.0 && any(&|p| p.colors.is_some());
    let extra_color = if w.color != 0.0 {
        most(&|p| p.extra_colors.len())
    } else {
        0
    };
    let dims = 3 * usize::from(normal)
        + 2 * (usize::from(uv) + extra_uv)
        + 4 * (usize::from(color) + extra_color);
    let mut out = Vec::with_capacity(dims * flat.positions.len());
    if dims == 0 {
        return (out, 0);
    }
    for p in &mesh.primitives {
        for v in 0..p.positions.len() {
            if normal {
                let n = p.normals.as_ref().map_or([0.0; 3], |a| normalize3(a[v]));
                out.extend(n.map(|x| x * w.normal));
            }
            if uv {
                let t = p.texcoords.as_ref().map_or([0.0; 2], |a| a[v]);
                out.extend(t.map(|x| x * w.uv));
            }
            for k in 0..extra_uv {
                let t = p.extra_texcoords.get(k).map_or([0.0; 2], |a| a[v]);
                out.extend(t.map(|x| x * w.uv));
            }
            if color {
                let c = p.colors.as_ref().map_or([1.0; 4], |a| a[v]);
                out.extend(c.map(|x| x * w.color));
            }
            for k in 0..extra_color {
                let c = p.extra_colors.get(k).map_or([1.0; 4], |a| a[v]);
                out.extend(c.map(|x| x * w.color));
            }
        }
    }
    (out, dims)
}

/// Flat vertex → its wedge's representative (the lowest flat vertex with
/// the same primitive, position and attributes), so duplicated vertices
/// with identical attributes do not make false seams.
fn wedge_of_vertex(mesh: &SourceMesh, flat: &Flat) -> Vec<u32> {
    let n = flat.positions.len();
    let mut keys: Vec<(Vec<u32>, u32)> = (0..n as u32)
        .map(|v| {
            let (p, local) = locate(flat, v);
            (wedge_key(mesh, p, local), v)
        })
        .collect();
    keys.sort_unstable();
    let mut out = vec![0; n];
    for run in keys.chunk_by(|a, b| a.0 == b.0) {
        for k in run {
            out[k.1 as usize] = run[0].1;
        }
    }
    out
}

fn flatten(mesh: &SourceMesh) -> Flat {
    let mut f = Flat {
        positions: Vec::new(),
        indices: Vec::new(),
        prim_of_triangle: Vec::new(),
        vertex_offset: Vec::new(),
    };
    for (pi, p) in mesh.primitives.iter().enumerate() {
        let off = f.positions.len() as u32;
        f.vertex_offset.push(off);
        f.positions.extend_from_slice(&p.positions);
        f.indices.extend(p.indices.iter().map(|&i| i + off));
        f.prim_of_triangle
            .extend(std::iter::repeat_n(pi as u32, p.indices.len() / 3));
    }
    f
}

/// Every vertex attribute of `mesh` per flat vertex (primitives in order,
/// each its vertices in order: the numbering of the wedge ids in the log),
/// for the `LODGEN_progressive` stream: one channel per glTF attribute
/// some primitive has, named by its semantic (`NORMAL`, `TANGENT`,
/// `TEXCOORD_n`, `COLOR_n`, `JOINTS_n` as exact small integers,
/// `WEIGHTS_n`), values exactly the input's; a primitive without an
/// attribute gets zeros there (white for colours). Each wedge's group is
/// its primitive.
pub fn stream_attributes(mesh: &SourceMesh) -> lodgen_pm::stream::WedgeAttributes {
    use lodgen_pm::stream::{Channel, WedgeAttributes};
    let prims = &mesh.primitives;
    let sets = |f: &dyn Fn(&Primitive) -> usize| prims.iter().map(f).max().unwrap_or(0);
    // set indices as named (a primitive may have COLOR_1 without COLOR_0);
    // absent ones are filtered out below
    let (uvs, colors, joints) = (
        1 + sets(&|p| p.extra_texcoords.len()),
        1 + sets(&|p| p.extra_colors.len()),
        1 + sets(&|p| p.extra_joints.len()),
    );
    let candidates = [Attr::Normal, Attr::Tangent]
        .into_iter()
        .chain((0..uvs).map(Attr::Uv))
        .chain((0..colors).map(Attr::Color))
        .chain((0..joints).flat_map(|i| [Attr::Joints(i), Attr::Weights(i)]));
    let present: Vec<Attr> = candidates
        .filter(|&a| {
            prims
                .iter()
                .any(|p| a.fetch(p, 0, &mut Vec::new()).is_some())
        })
        .collect();
    let count: usize = prims.iter().map(|p| p.positions.len()).sum();
    let stride: usize = present.iter().map(|a| a.components()).sum();
    let mut values = Vec::with_capacity(count * stride);
    let mut groups = Vec::with_capacity(count);
    for (pi, p) in prims.iter().enumerate() {
        for v in 0..p.positions.len() {
            for a in &present {
                if a.fetch(p, v, &mut values).is_none() {
                    // white for a missing colour, zeros otherwise
                    let missing = if matches!(a, Attr::Color(_)) {
                        1.0
                    } else {
                        0.0
                    };
                    values.extend(std::iter::repeat_n(missing, a.components()));
                }
            }
            groups.push(pi as u32);
        }
    }
    WedgeAttributes {
        channels: present
            .iter()
            .map(|a| Channel {
                name: a.name(),
                components: a.components() as u8,
            })
            .collect(),
        values,
        groups,
        count,
    }
}

/// One glTF vertex attribute set of a [`Primitive`].
#[derive(Clone, Copy, Debug)]
enum Attr {
    Normal,
    Tangent,
    Uv(usize),
    Color(usize),
    Joints(usize),
    Weights(usize),
}

impl Attr {
    fn name(self) -> String {
        match self {
            Attr::Normal => "NORMAL".into(),
            Attr::Tangent => "TANGENT".into(),
            Attr::Uv(i) => format!("TEXCOORD_{i}"),
            Attr::Color(i) => format!("COLOR_{i}"),
            Attr::Joints(i) => format!("JOINTS_{i}"),
            Attr::Weights(i) => format!("WEIGHTS_{i}"),
        }
    }

    fn components(self) -> usize {
        match self {
            Attr::Normal => 3,
            Attr::Uv(_) => 2,
            _ => 4,
        }
    }

    /// Append vertex `v`'s values as `f32` (joints exactly); `None` when
    /// `p` lacks the set (or the vertex).
    fn fetch(self, p: &Primitive, v: usize, out: &mut Vec<f32>) -> Option<()> {
        fn put<const N: usize, T: Copy + Into<f64>>(
            set: Option<&Vec<[T; N]>>,
            v: usize,
            out: &mut Vec<f32>,
        ) -> Option<()> {
            out.extend(set?.get(v)?.iter().map(|&c| c.into() as f32));
            Some(())
        }
        fn nth<'a, X>(
            first: &'a Option<Vec<X>>,
            extra: &'a [Vec<X>],
            i: usize,
        ) -> Option<&'a Vec<X>> {
            if i == 0 {
                first.as_ref()
            } else {
                extra.get(i - 1)
            }
        }
        match self {
            Attr::Normal => put(p.normals.as_ref(), v, out),
            Attr::Tangent => put(p.tangents.as_ref(), v, out),
            Attr::Uv(i) => put(nth(&p.texcoords, &p.extra_texcoords, i), v, out),
            Attr::Color(i) => put(nth(&p.colors, &p.extra_colors, i), v, out),
            Attr::Joints(i) => put(nth(&p.joints, &p.extra_joints, i), v, out),
            Attr::Weights(i) => put(nth(&p.weights, &p.extra_weights, i), v, out),
        }
    }
}

/// QEM on `mesh`'s wedges: topology on welded positions, every primitive
/// and attribute seam kept, attribute quadrics weighted by `weights`. The
/// log's wedge ids are flat vertex ids (see [`stream_attributes`]).
pub fn simplify_mesh(
    mesh: &SourceMesh,
    opts: &SimplifyOptions,
    weights: &AttributeWeights,
) -> Result<Simplified, MeshError> {
    simplify_wedged(mesh, &flatten(mesh), opts, weights)
}

fn simplify_wedged(
    mesh: &SourceMesh,
    flat: &Flat,
    opts: &SimplifyOptions,
    weights: &AttributeWeights,
) -> Result<Simplified, MeshError> {
    let wedge = wedge_of_vertex(mesh, flat);
    let wedged: Vec<u32> = flat.indices.iter().map(|&i| wedge[i as usize]).collect();
    let (values, dims) = weighted_attributes(mesh, flat, weights);
    simplify_with_wedges(&flat.positions, &wedged, &values, dims, opts)
}

/// Build the LOD chain of every mesh of `scene`.
pub fn build_lods(
    scene: &Scene,
    opts: &BuildOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<Vec<MeshBuild>, BuildError> {
    let n = scene.meshes.len();
    scene
        .meshes
        .iter()
        .enumerate()
        .map(|(i, m)| {
            progress(Progress::Simplifying { mesh: i, of: n });
            build_one(i, m, opts, progress)
        })
        .collect()
}

/// Build the LOD chain of one mesh.
pub fn build_one(
    index: usize,
    mesh: &SourceMesh,
    opts: &BuildOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<MeshBuild, BuildError> {
    let flat = flatten(mesh);
    let mesh_err = |source| BuildError::Mesh {
        index,
        name: mesh.name.clone(),
        source,
    };
    let measure_err = |source| BuildError::Measure {
        index,
        name: mesh.name.clone(),
        source,
    };
    let full_tris = flat.indices.len() / 3;
    let mut sopts = opts.simplify;
    match &opts.levels {
        LevelRequest::Specs(specs) => {
            if specs.is_empty() {
                return Err(BuildError::NoLevels);
            }
            // Ratios refer to the welded, cleaned mesh; a bound on the raw
            // count is only a lower bound of what is needed, so run to the
            // smallest requested ratio / count of the input.
            let target = levels::triangle_target(full_tris, specs).unwrap_or(0);
            sopts.target_triangles = Some(target.max(opts.min_triangles.max(1)));
            sopts.target_ratio = None;
        }
        LevelRequest::MaxErrors(bounds) => {
            if bounds.is_empty() {
                return Err(BuildError::NoLevels);
            }
            sopts.target_triangles = Some(opts.min_triangles.max(1));
            sopts.target_ratio = None;
        }
    }
    // QEM runs on wedges (seams and attributes kept); the curvature-adaptive
    // methods see positions only, and their levels take attributes from the
    // first input vertex of each position.
    let t_build = Instant::now();
    let simplified = if opts.method == Method::Qem {
        simplify_wedged(mesh, &flat, &sopts, &opts.attribute_weights)
    } else {
        simplify_adaptive(
            &flat.positions,
            &flat.indices,
            opts.method,
            &sopts,
            &opts.adaptive,
        )
    }
    .map_err(mesh_err)?;
    let simplify_time = t_build.elapsed();
    let pm = &simplified.pm;
    let full = pm.mesh_at_splits(pm.len());
    let diagonal = full.diagonal();
    // The original's hierarchy and sample order, built once for every level.
    // Without measurement (`measured == false`), a level's error is the
    // largest recorded contraction error still in it (the quadric's
    // estimate): the mesh after k splits still carries contractions k..
    let estimate = |k: usize| {
        let e = pm.splits[k.min(pm.splits.len())..]
            .iter()
            .map(|s| f64::from(s.error))
            .fold(0.0, f64::max);
        let d = Distance {
            max: e,
            mean: f64::NAN,
            rms: f64::NAN,
            samples: 0,
        };
        ErrorReport {
            a_to_b: d,
            b_to_a: d,
            diagonal,
        }
    };
    let t_measure = Instant::now();
    let reference = if opts.measured {
        Some(
            Reference::new(MeshRef::new(&full.positions, &full.triangles))
                .map_err(|e| measure_err(MeasureError::A(e)))?,
        )
    } else {
        None
    };
    let measure_time = std::cell::Cell::new(t_measure.elapsed());
    let measure_mesh = |m: &lodgen_pm::Mesh, k: usize, mopts: &MeasureOptions| {
        let Some(reference) = &reference else {
            return Ok(estimate(k));
        };
        let t = Instant::now();
        let r = reference
            .measure(MeshRef::new(&m.positions, &m.triangles), mopts)
            .map_err(|e| measure_err(MeasureError::B(e)));
        measure_time.set(measure_time.get() + t.elapsed());
        r
    };
    let measure_at = |k: usize, mopts: &MeasureOptions| -> Result<ErrorReport, BuildError> {
        measure_mesh(&pm.mesh_at_splits(k), k, mopts)
    };

    // Requested levels whose triangle count is below the floor.
    let floor = opts.min_triangles.max(1);
    let below_floor = match &opts.levels {
        LevelRequest::Specs(specs) => {
            let welded = pm.triangle_counts().last().copied().unwrap_or(0);
            specs
                .iter()
                .filter(|s| match **s {
                    LevelSpec::Ratio(r) => {
                        ((r.clamp(0.0, 1.0) * welded as f64).floor() as usize) < floor
                    }
                    LevelSpec::Triangles(t) => t < floor,
                    LevelSpec::MaxError(_) => false,
                })
                .count()
        }
        LevelRequest::MaxErrors(_) => 0,
    };
    // Split counts, finest first, without repeats.
    let mut splits: Vec<usize> = match &opts.levels {
        LevelRequest::Specs(specs) => {
            let welded = pm.triangle_counts().last().copied().unwrap_or(0);
            specs
                .iter()
                .map(|s| match *s {
                    // ratios of the welded mesh's triangles
                    LevelSpec::Ratio(r) => pm
                        .splits_for_triangles((r.clamp(0.0, 1.0) * welded as f64).floor() as usize),
                    other => levels::splits_for(pm, other),
                })
                .collect()
        }
        LevelRequest::MaxErrors(bounds) => {
            // Coarsest k whose measured error is within the bound: binary
            // search, with a lighter sampling while searching.
            let coarse = opts
                .measure
                .with_samples_per_triangle((opts.measure.samples_per_triangle / 4.0).max(0.25));
            let mut out = Vec::new();
            for (li, &b) in bounds.iter().enumerate() {
                progress(Progress::Measuring {
                    mesh: index,
                    level: li,
                    of: bounds.len(),
                });
                let bound = b * diagonal;
                if !opts.measured {
                    out.push(levels::splits_for(pm, LevelSpec::MaxError(bound)));
                    continue;
                }
                let (mut lo, mut hi) = (0usize, pm.len());
                while lo < hi {
                    let mid = lo + (hi - lo) / 2;
                    if measure_at(mid, &coarse)?.hausdorff() <= bound {
                        hi = mid;
                    } else {
                        lo = mid + 1;
                    }
                }
                out.push(lo);
            }
            out
        }
    };
    let notes = apply_floor(pm, opts.min_triangles, &mut splits, below_floor);

    let mut errors = Vec::with_capacity(splits.len());
    let mut lod_levels = Vec::with_capacity(splits.len());
    let mut cursor = pm.cursor();
    let fit_source = FitSource::new(mesh, &flat, &simplified);
    for (li, &k) in splits.iter().enumerate() {
        progress(Progress::Measuring {
            mesh: index,
            level: li,
            of: splits.len(),
        });
        cursor.seek(k);
        let m = cursor.mesh();
        let report = measure_mesh(m, k, &opts.measure)?;
        // a level below the input gets fitted values (module docs)
        let fitted = match (&fit_source, cursor.wedges()) {
            (Some(f), Some(w)) if k < pm.len() => Some(f.fit(m, w)),
            _ => None,
        };
        lod_levels.push(LodLevel {
            primitives: extract(
                mesh,
                &flat,
                &simplified,
                m,
                cursor.wedges(),
                fitted.as_ref(),
            ),
            hausdorff: report.hausdorff() / diagonal.max(f64::MIN_POSITIVE),
            rms: report.rms() / diagonal.max(f64::MIN_POSITIVE),
            screen_coverage: 0.0,
        });
        errors.push(report);
    }
    let coverages = crate::coverage::screen_coverages(
        &lod_levels.iter().map(|l| l.hausdorff).collect::<Vec<_>>(),
    );
    for (l, c) in lod_levels.iter_mut().zip(&coverages) {
        l.screen_coverage = *c;
    }
    Ok(MeshBuild {
        lod: LodMesh {
            source: index,
            name: mesh.name.clone(),
            levels: lod_levels,
        },
        simplified,
        level_splits: splits,
        errors,
        measured: opts.measured,
        times: BuildTimes {
            simplify: simplify_time,
            measure: measure_time.get(),
            total: t_build.elapsed(),
        },
        notes,
    })
}

/// Raise every level to the triangle floor (`min_triangles`, at least 1, at
/// most the whole mesh: a level is never empty), then order the split counts
/// finest first without repeats. `below` counts the requested levels known
/// to ask for fewer triangles than the floor. Returns the notes for the
/// table.
fn apply_floor(
    pm: &ProgressiveMesh,
    min_triangles: usize,
    splits: &mut Vec<usize>,
    below: usize,
) -> Vec<String> {
    let counts = pm.triangle_counts();
    let full = counts.last().copied().unwrap_or(0);
    let floor = min_triangles.max(1).min(full);
    // counts never decrease with k: the first k with enough triangles
    let k_floor = counts.partition_point(|&c| c < floor);
    let requested = splits.len();
    let mut raised = 0;
    for k in splits.iter_mut() {
        if *k < k_floor {
            *k = k_floor;
            raised += 1;
        }
    }
    splits.sort_unstable_by(|a, b| b.cmp(a));
    splits.dedup();
    let mut notes = Vec::new();
    let below = below.max(raised);
    if below > 0 {
        let kept = counts.get(k_floor).copied().unwrap_or(full);
        notes.push(format!(
            "{below} of {requested} requested levels ask for fewer than {} triangles \
             (--min-triangles) and keep {kept}{}; levels that coincide are written once: \
             {} of {requested} written",
            min_triangles.max(1),
            if kept == full { ", the whole mesh" } else { "" },
            splits.len()
        ));
    }
    notes
}

/// Which attributes are fitted per level (`lodgen_pm::attrfit`), and where
/// each sits in a wedge's value vector; present when some primitive has it.
#[derive(Clone, Debug, Default)]
struct Channels {
    normal: Option<usize>,
    uv: Option<usize>,
    /// Tangent xyz (w, the handedness, is the source's).
    tangent: Option<usize>,
    extra_uv: Vec<usize>,
    color: Option<usize>,
    /// `COLOR_1`, `COLOR_2`, …
    extra_color: Vec<usize>,
    dims: usize,
}

impl Channels {
    fn of(mesh: &SourceMesh) -> Channels {
        let any = |f: &dyn Fn(&Primitive) -> bool| mesh.primitives.iter().any(f);
        let mut c = Channels::default();
        let mut take = |present: bool, n: usize| {
            present.then(|| {
                c.dims += n;
                c.dims - n
            })
        };
        let normal = take(any(&|p| p.normals.is_some()), 3);
        let uv = take(any(&|p| p.texcoords.is_some()), 2);
        let tangent = take(any(&|p| p.tangents.is_some()), 3);
        let extra = mesh
            .primitives
            .iter()
            .map(|p| p.extra_texcoords.len())
            .max()
            .unwrap_or(0);
        let extra_uv: Vec<usize> = (0..extra).filter_map(|_| take(true, 2)).collect();
        let color = take(any(&|p| p.colors.is_some()), 4);
        let extra = mesh
            .primitives
            .iter()
            .map(|p| p.extra_colors.len())
            .max()
            .unwrap_or(0);
        let extra_color: Vec<usize> = (0..extra).filter_map(|_| take(true, 4)).collect();
        Channels {
            normal,
            uv,
            tangent,
            extra_uv,
            color,
            extra_color,
            dims: c.dims,
        }
    }

    /// The component range of every channel.
    fn ranges(&self) -> Vec<Channel> {
        let mut out = Vec::new();
        let mut put = |start: Option<usize>, n: usize, bounded: bool| {
            if let Some(i) = start {
                out.push(Channel {
                    components: i..i + n,
                    bounded,
                });
            }
        };
        // unit vectors are renormalised; UVs and colours never extrapolate
        put(self.normal, 3, false);
        put(self.uv, 2, true);
        put(self.tangent, 3, false);
        for &i in &self.extra_uv {
            put(Some(i), 2, true);
        }
        put(self.color, 4, true);
        for &i in &self.extra_color {
            put(Some(i), 4, true);
        }
        out
    }

    /// The channel values of vertex `v` of `p` (defaults where it lacks one).
    fn values(&self, p: &Primitive, v: usize, out: &mut Vec<f32>) {
        let start = out.len();
        out.resize(start + self.dims, 0.0);
        let o = &mut out[start..];
        if let Some(i) = self.normal {
            let n = p
                .normals
                .as_ref()
                .map_or([0.0, 0.0, 1.0], |a| normalize3(a[v]));
            o[i..i + 3].copy_from_slice(&n);
        }
        if let Some(i) = self.uv {
            o[i..i + 2].copy_from_slice(&p.texcoords.as_ref().map_or([0.0; 2], |a| a[v]));
        }
        if let Some(i) = self.tangent {
            let t = p.tangents.as_ref().map_or([1.0, 0.0, 0.0, 1.0], |a| a[v]);
            o[i..i + 3].copy_from_slice(&t[..3]);
        }
        for (k, &i) in self.extra_uv.iter().enumerate() {
            o[i..i + 2].copy_from_slice(&p.extra_texcoords.get(k).map_or([0.0; 2], |a| a[v]));
        }
        if let Some(i) = self.color {
            o[i..i + 4].copy_from_slice(&p.colors.as_ref().map_or([1.0; 4], |a| a[v]));
        }
        for (k, &i) in self.extra_color.iter().enumerate() {
            o[i..i + 4].copy_from_slice(&p.extra_colors.get(k).map_or([1.0; 4], |a| a[v]));
        }
        for x in o.iter_mut() {
            if !x.is_finite() {
                *x = 0.0;
            }
        }
    }

    /// Overwrite the last vertex pushed to `to` with fitted values `f`,
    /// made valid again: normals unit, tangents orthogonal to them, colours
    /// in [0, 1]. Only attributes the source primitive `from` has.
    fn apply(&self, to: &mut Primitive, from: &Primitive, f: &[f32]) {
        if let (Some(i), Some(n), true) = (self.normal, to.normals.as_mut(), from.normals.is_some())
        {
            if let Some(last) = n.last_mut() {
                *last = normalize3([f[i], f[i + 1], f[i + 2]]);
            }
        }
        if let (Some(i), Some(uv), true) =
            (self.uv, to.texcoords.as_mut(), from.texcoords.is_some())
        {
            if let Some(last) = uv.last_mut() {
                *last = [f[i], f[i + 1]];
            }
        }
        let normal = to.normals.as_ref().and_then(|n| n.last().copied());
        if let (Some(i), Some(t), true) =
            (self.tangent, to.tangents.as_mut(), from.tangents.is_some())
        {
            if let Some(last) = t.last_mut() {
                *last = orthogonal_tangent([f[i], f[i + 1], f[i + 2], last[3]], normal);
            }
        }
        for (k, &i) in self.extra_uv.iter().enumerate() {
            if from.extra_texcoords.get(k).is_some() {
                if let Some(last) = to.extra_texcoords.get_mut(k).and_then(|a| a.last_mut()) {
                    *last = [f[i], f[i + 1]];
                }
            }
        }
        let rgba = |i: usize| [f[i], f[i + 1], f[i + 2], f[i + 3]].map(|x| x.clamp(0.0, 1.0));
        if let (Some(i), Some(c), true) = (self.color, to.colors.as_mut(), from.colors.is_some()) {
            if let Some(last) = c.last_mut() {
                *last = rgba(i);
            }
        }
        for (k, &i) in self.extra_color.iter().enumerate() {
            if from.extra_colors.get(k).is_some() {
                if let Some(last) = to.extra_colors.get_mut(k).and_then(|a| a.last_mut()) {
                    *last = rgba(i);
                }
            }
        }
    }
}

/// The input surface for the per-level attribute fit: flat positions,
/// triangles as wedge (representative flat vertex) triples, and every
/// flat vertex's channel values.
struct FitSource {
    channels: Channels,
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    values: Vec<f32>,
}

impl FitSource {
    /// `None` when there is nothing to fit (no per-corner attributes
    /// besides joints and weights, which are never interpolated).
    fn new(mesh: &SourceMesh, flat: &Flat, s: &Simplified) -> Option<FitSource> {
        let channels = Channels::of(mesh);
        if channels.dims == 0 || s.pm.wedges.is_none() {
            return None;
        }
        let mut values = Vec::with_capacity(channels.dims * flat.positions.len());
        for p in &mesh.primitives {
            for v in 0..p.positions.len() {
                channels.values(p, v, &mut values);
            }
        }
        let wedge = wedge_of_vertex(mesh, flat);
        let triangles = flat
            .indices
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| wedge[t[k] as usize]))
            .collect();
        Some(FitSource {
            channels,
            positions: flat.positions.clone(),
            triangles,
            values,
        })
    }

    fn fit(&self, level: &Mesh, wedges: &[[u32; 3]]) -> Fitted {
        let values = lodgen_pm::attrfit::fit(
            lodgen_pm::attrfit::Source {
                positions: &self.positions,
                triangles: &self.triangles,
                values: &self.values,
                dims: self.channels.dims,
            },
            lodgen_pm::attrfit::Level {
                positions: &level.positions,
                triangles: &level.triangles,
                wedges,
            },
            &self.channels.ranges(),
        );
        Fitted {
            channels: self.channels.clone(),
            values,
        }
    }
}

/// A level's fitted values and the channel layout they use.
struct Fitted {
    channels: Channels,
    values: lodgen_pm::attrfit::Fitted,
}

/// Turn a level of the progressive mesh back into the source's primitives,
/// transferring attributes corner by corner from each corner's wedge
/// (`wedges`, flat vertex ids; without them, from the level vertex's first
/// source vertex), then the fitted values where there are some.
fn extract(
    source: &SourceMesh,
    flat: &Flat,
    s: &Simplified,
    level: &Mesh,
    wedges: Option<&[[u32; 3]]>,
    fitted: Option<&Fitted>,
) -> Vec<Primitive> {
    let pm = &s.pm;
    // First input vertex of each welded vertex.
    let mut first_input = vec![u32::MAX; pm.vertex_origin.len()];
    for (iv, &w) in s.vertex_map.iter().enumerate() {
        if w != u32::MAX && first_input[w as usize] == u32::MAX {
            first_input[w as usize] = iv as u32;
        }
    }
    let mut prims: Vec<Primitive> = source
        .primitives
        .iter()
        .map(|p| Primitive {
            material: p.material,
            normals: p.normals.as_ref().map(|_| Vec::new()),
            texcoords: p.texcoords.as_ref().map(|_| Vec::new()),
            tangents: p.tangents.as_ref().map(|_| Vec::new()),
            extra_texcoords: vec![Vec::new(); p.extra_texcoords.len()],
            colors: p.colors.as_ref().map(|_| Vec::new()),
            joints: p.joints.as_ref().map(|_| Vec::new()),
            weights: p.weights.as_ref().map(|_| Vec::new()),
            extra_colors: vec![Vec::new(); p.extra_colors.len()],
            extra_joints: vec![Vec::new(); p.extra_joints.len()],
            extra_weights: vec![Vec::new(); p.extra_weights.len()],
            ..Primitive::default()
        })
        .collect();
    // (primitive, level vertex, wedge) → output vertex
    let mut remap: BTreeMap<(u32, u32, u32), u32> = BTreeMap::new();
    for (t, tri) in level.triangles.iter().enumerate() {
        let input_tri = s.triangle_map[pm.triangle_origin[t] as usize] as usize;
        let pi = flat.prim_of_triangle[input_tri];
        for (slot, &v) in tri.iter().enumerate() {
            let src = match wedges {
                Some(w) => w[t][slot],
                None => first_input[pm.vertex_origin[v as usize] as usize],
            };
            let next = prims[pi as usize].positions.len() as u32;
            let out = *remap.entry((pi, v, src)).or_insert_with(|| {
                let prim = &mut prims[pi as usize];
                prim.positions.push(level.positions[v as usize]);
                // the source vertex may belong to another primitive
                let (sp, local) = locate(flat, src);
                let from = &source.primitives[sp];
                push_attributes(prim, from, local);
                if let Some(f) = fitted {
                    if let Some(values) = f.values.get(v, src) {
                        f.channels.apply(prim, from, values);
                    }
                }
                next
            });
            prims[pi as usize].indices.push(out);
        }
    }
    // a material can vanish from a coarse level
    prims.retain(|p| !p.indices.is_empty());
    prims
}

/// Append vertex `v` of `from`'s attributes to `to` (defaults where `from`
/// lacks one `to` has), normalised as the module docs say.
fn push_attributes(to: &mut Primitive, from: &Primitive, v: usize) {
    let normal = from.normals.as_ref().map(|a| normalize3(a[v]));
    if let Some(n) = to.normals.as_mut() {
        n.push(normal.unwrap_or([0.0, 0.0, 1.0]));
    }
    if let Some(uv) = to.texcoords.as_mut() {
        uv.push(from.texcoords.as_ref().map_or([0.0; 2], |a| a[v]));
    }
    if let Some(t) = to.tangents.as_mut() {
        let raw = from
            .tangents
            .as_ref()
            .map_or([1.0, 0.0, 0.0, 1.0], |a| a[v]);
        t.push(orthogonal_tangent(raw, normal));
    }
    for (i, uv) in to.extra_texcoords.iter_mut().enumerate() {
        uv.push(from.extra_texcoords.get(i).map_or([0.0; 2], |a| a[v]));
    }
    if let Some(c) = to.colors.as_mut() {
        c.push(from.colors.as_ref().map_or([1.0; 4], |a| a[v]));
    }
    for (i, c) in to.extra_colors.iter_mut().enumerate() {
        c.push(from.extra_colors.get(i).map_or([1.0; 4], |a| a[v]));
    }
    // JOINTS_n and WEIGHTS_n: all sets from the same source vertex, the
    // weights of all sets together renormalised to sum 1
    if let Some(j) = to.joints.as_mut() {
        j.push(from.joints.as_ref().map_or([0; 4], |a| a[v]));
    }
    for (i, j) in to.extra_joints.iter_mut().enumerate() {
        j.push(from.extra_joints.get(i).map_or([0; 4], |a| a[v]));
    }
    let mut sets: Vec<[f32; 4]> = Vec::with_capacity(1 + to.extra_weights.len());
    if to.weights.is_some() {
        sets.push(from.weights.as_ref().map_or([1.0, 0.0, 0.0, 0.0], |a| a[v]));
    }
    for i in 0..to.extra_weights.len() {
        sets.push(from.extra_weights.get(i).map_or([0.0; 4], |a| a[v]));
    }
    normalize_weights(&mut sets);
    let mut sets = sets.into_iter();
    if let Some(w) = to.weights.as_mut() {
        w.extend(sets.next());
    }
    for w in to.extra_weights.iter_mut() {
        w.extend(sets.next());
    }
}

/// `n` made unit; already unit vectors keep their bits (so full refinement
/// gives back the input exactly).
fn normalize3(n: [f32; 3]) -> [f32; 3] {
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if (l - 1.0).abs() <= UNIT_EPS {
        n
    } else if l > 0.0 && l.is_finite() {
        n.map(|x| x / l)
    } else {
        [0.0, 0.0, 1.0]
    }
}

/// Tolerance below which a length, a dot product or a weight sum counts as
/// already normalised (and the input's bits are kept).
const UNIT_EPS: f32 = 4.0 * f32::EPSILON;

/// Gram–Schmidt: the tangent's xyz made unit and orthogonal to the normal,
/// its handedness `w` kept as ±1.
fn orthogonal_tangent(t: [f32; 4], normal: Option<[f32; 3]>) -> [f32; 4] {
    let mut x = [t[0], t[1], t[2]];
    let d = normal.map_or(0.0, |n| x[0] * n[0] + x[1] * n[1] + x[2] * n[2]);
    let l = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
    if d.abs() <= UNIT_EPS && (l - 1.0).abs() <= UNIT_EPS && t[3].abs() == 1.0 {
        return t;
    }
    if let Some(n) = normal {
        x = [x[0] - d * n[0], x[1] - d * n[1], x[2] - d * n[2]];
    }
    let l = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
    let x = if l > 1e-12 {
        x.map(|c| c / l)
    } else {
        [1.0, 0.0, 0.0]
    };
    [x[0], x[1], x[2], if t[3] < 0.0 { -1.0 } else { 1.0 }]
}

/// Skin weights of one vertex (every WEIGHTS_n set) made non-negative and
/// summing to 1 over all sets (all on the first joint when they sum to 0).
fn normalize_weights(sets: &mut [[f32; 4]]) {
    for w in sets.iter_mut() {
        *w = w.map(|x| if x.is_finite() { x.max(0.0) } else { 0.0 });
    }
    let s: f32 = sets.iter().flatten().sum();
    if (s - 1.0).abs() <= UNIT_EPS {
        return;
    }
    for (i, w) in sets.iter_mut().enumerate() {
        *w = if s > 0.0 {
            w.map(|x| x / s)
        } else if i == 0 {
            [1.0, 0.0, 0.0, 0.0]
        } else {
            [0.0; 4]
        };
    }
}

/// Flat vertex → (primitive, local vertex).
fn locate(flat: &Flat, v: u32) -> (usize, usize) {
    let p = flat.vertex_offset.partition_point(|&o| o <= v) - 1;
    (p, (v - flat.vertex_offset[p]) as usize)
}
