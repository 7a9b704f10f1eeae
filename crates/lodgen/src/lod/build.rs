//! The build driver: per mesh, flatten → simplify (QEM on wedges, or a
//! curvature-adaptive method) → select the levels → per level measure, fit
//! and extract → screen coverages. [`MeshBuild`] is what comes out.

use std::borrow::Cow;
use std::time::{Duration, Instant};

use lodgen_pm::metric::{ErrorReport, MeasureOptions, MeshRef, Reference};
use lodgen_pm::polish::Original;
use lodgen_pm::{
    levels, levels::LevelSpec, simplify_adaptive, Mesh, MeshError, Method, ProgressiveMesh,
    Simplified, SimplifyOptions, TopologyChange,
};

use crate::scene::{LodLevel, LodMesh, Primitive, Scene, SourceMesh, Warning};

use super::error::BuildError;
use super::extract::{deferred_primitives, extract_levels, Extracted};
use super::flat::{flatten, Flat};
use super::measure::Measurer;
use super::options::{BuildOptions, LevelHook, LevelRequest, Progress};
use super::reference::{inverse, measurer_in_input_order, Origins};
use super::select::select_splits;
use super::wedges::{prepare_wedged, simplify_wedged, simplify_wedged_beside};

/// What happened to one mesh, beside its [`LodMesh`].
#[derive(Clone, Debug)]
pub struct MeshBuild {
    pub lod: LodMesh,
    /// Triangles of the input mesh (all primitives, before welding).
    pub input_triangles: usize,
    /// The simplification (progressive mesh, stats, stop reason); its
    /// progressive mesh and maps are empty unless
    /// [`BuildOptions::keep_progressive`].
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

/// Build the LOD chain of every mesh of `scene` (a mesh the reader left
/// with no primitive has none); the first mesh that fails fails the call.
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
        .filter(|(_, m)| !m.primitives.is_empty())
        .map(|(i, m)| {
            progress(Progress::Simplifying { mesh: i, of: n });
            build_one(i, m, opts, progress)
        })
        .collect()
}

/// The builds of a scene with per-mesh fault isolation.
#[derive(Debug, Default)]
pub struct SceneBuild {
    /// The meshes that were simplified.
    pub builds: Vec<MeshBuild>,
    /// The meshes that could not be: one level, the input as it is.
    pub unsimplified: Vec<LodMesh>,
    /// Why each of `unsimplified` is there, naming the mesh.
    pub warnings: Vec<Warning>,
}

impl SceneBuild {
    /// Every chain to write, in source order.
    pub fn lods(&self) -> Vec<LodMesh> {
        let mut all: Vec<LodMesh> = self.builds.iter().map(|b| b.lod.clone()).collect();
        all.extend(self.unsimplified.iter().cloned());
        all.sort_by_key(|l| l.source);
        all
    }
}

/// [`build_lods`], but a mesh that cannot be simplified (every triangle
/// degenerate, a simplification or measurement error) is kept unsimplified
/// as a one-level chain with a warning naming it, instead of failing the
/// scene. Errors that are not about one mesh (no levels requested) fail.
/// Without [`BuildOptions::keep_input`], a simplified mesh's input
/// positions and indices are freed in `scene` (its levels are extracted
/// and their measurement cannot fail then: a mesh kept unsimplified keeps
/// them).
pub fn build_lods_isolated(
    scene: &mut Scene,
    opts: &BuildOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<SceneBuild, BuildError> {
    let n = scene.meshes.len();
    let mut out = SceneBuild::default();
    for i in 0..n {
        if scene.meshes[i].primitives.is_empty() {
            continue;
        }
        progress(Progress::Simplifying { mesh: i, of: n });
        // owned while it is built, so that its input can be freed
        let mut mesh = Cow::Owned(std::mem::take(&mut scene.meshes[i]));
        let built = build_mesh(i, &mut mesh, opts, progress);
        scene.meshes[i] = mesh.into_owned();
        let m = &scene.meshes[i];
        match built {
            Ok(b) => out.builds.push(b),
            Err(e @ (BuildError::NoLevels | BuildError::Cancelled)) => return Err(e),
            Err(e) => {
                out.warnings.push(Warning::new(
                    format!("meshes[{i}] (mesh `{}`)", m.name),
                    format!("written unsimplified, one level: {e}"),
                ));
                let coverage = crate::coverage::screen_coverages(&[0.0]);
                out.unsimplified.push(LodMesh {
                    source: i,
                    name: m.name.clone(),
                    levels: vec![LodLevel {
                        primitives: m.primitives.clone(),
                        hausdorff: 0.0,
                        rms: 0.0,
                        screen_coverage: coverage.first().copied().unwrap_or(0.0),
                    }],
                });
            }
        }
    }
    Ok(out)
}

/// Build the LOD chain of one mesh.
pub fn build_one(
    index: usize,
    mesh: &SourceMesh,
    opts: &BuildOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<MeshBuild, BuildError> {
    build_mesh(index, &mut Cow::Borrowed(mesh), opts, progress)
}

/// The smallest mesh whose simplification may run partitioned (eight
/// clusters of [`lodgen_pm::DEFAULT_CLUSTER_TRIANGLES`]), the one that leaves
/// freed holes worth returning.
const TRIM_MIN_TRIANGLES: usize = 8 * lodgen_pm::DEFAULT_CLUSTER_TRIANGLES;

/// Give the pages the simplifier freed back to the system before the
/// measurement builds its trees: glibc returns only the top of each heap
/// by itself, and the partitioned simplification's clusters (small arrays
/// made on every pool thread, freed between arrays that live on) leave
/// holes that otherwise stay resident under the measurement's peak
/// (bunny-4m whole run 940 → 898 MB). Only after meshes of at least
/// [`TRIM_MIN_TRIANGLES`]: a scene of many small meshes would pay a walk
/// of the heaps per mesh for pages that do not matter.
fn return_freed_memory(input_triangles: usize) {
    if input_triangles < TRIM_MIN_TRIANGLES {
        return;
    }
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only releases free memory of glibc's heaps.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// Whether `mesh`'s input positions and indices can be freed once the
/// simplification is prepared, before it runs (peak memory: a scan's
/// parsed input, 18 bytes per triangle, beside the simplifier's state):
/// an `owned` mesh (its input is the caller's to free) of one primitive with
/// positions only (nothing after the
/// preparation reads its geometry: no attribute to transfer or fit),
/// simplified by QEM, unless [`BuildOptions::keep_input`] or
/// [`BuildOptions::keep_progressive`]. Such a mesh's levels are turned into
/// primitives only once measured ([`deferred_primitives`]), from their
/// meshes, so that the extracted primitives do not wait beside the
/// measurement (nor the preparation's maps beside the run). The later steps
/// cannot fail on the original (it passed the preparation's checks); if
/// a level fails its measurement the mesh is written as its welded input
/// ([`restore_input`]).
/// (The caller keeps a small mesh's input, under `SIDE_BY_SIDE_MAX_TRIANGLES`,
/// with `TopologyChange::WhenShort`: a freed input cannot be simplified
/// again, so a large mesh the topology stops runs once.)
fn frees_input_early(owned: bool, mesh: &SourceMesh, opts: &BuildOptions) -> bool {
    let [p] = mesh.primitives.as_slice() else {
        return false;
    };
    let positions_only = p.normals.is_none()
        && p.texcoords.is_none()
        && p.tangents.is_none()
        && p.extra_texcoords.is_empty()
        && p.colors.is_none()
        && p.joints.is_none()
        && p.weights.is_none()
        && p.extra_colors.is_empty()
        && p.extra_joints.is_empty()
        && p.extra_weights.is_empty()
        && p.targets.is_empty();
    owned
        && !opts.keep_input
        && !opts.keep_progressive
        && opts.method == Method::Qem
        && positions_only
}

/// Frees an owned mesh's input positions and indices.
fn free_input(mesh: &mut Cow<'_, SourceMesh>) {
    if let Cow::Owned(m) = mesh {
        for p in &mut m.primitives {
            p.positions = Vec::new();
            p.indices = Vec::new();
        }
    }
}

/// A mesh freed by [`frees_input_early`] given its welded input `full`
/// back as its geometry (what a mesh written unsimplified then shows: the
/// input's surface, welded and cleaned).
fn restore_input(mesh: &mut Cow<'_, SourceMesh>, full: &Mesh) {
    if let Cow::Owned(m) = mesh {
        if let [p] = m.primitives.as_mut_slice() {
            p.positions = full.positions.clone();
            p.indices = full.triangles.iter().flatten().copied().collect();
        }
    }
}

/// Below this many input triangles a mesh's original hierarchy is built
/// while its levels are extracted, and its levels are measured side by side
/// (both cores busy where one would wait: the bunny's measure phase). Larger
/// meshes keep the sequential order, in which the progressive mesh is freed
/// before the hierarchy is built and one level's hierarchy lives at a time
/// (at 4.4M triangles those were the run's peak).
const SIDE_BY_SIDE_MAX_TRIANGLES: usize = TRIM_MIN_TRIANGLES;

/// The value of a level step's `Result`, or (`freed`: a mesh whose input
/// was freed and whose levels then fail is written as its welded input) the
/// input rebuilt from `full` and the error returned.
macro_rules! or_restore {
    ($e:expr, $freed:expr, $mesh:expr, $full:expr) => {
        match $e {
            Ok(x) => x,
            Err(e) => {
                if $freed {
                    restore_input($mesh, $full);
                }
                return Err(e);
            }
        }
    };
}

/// `Err(Cancelled)` once the build's meter is cancelled (checked after the
/// simplification, which stops early then, and before the measurement).
fn go_on(opts: &BuildOptions) -> Result<(), BuildError> {
    match &opts.meter {
        Some(m) if m.is_cancelled() => Err(BuildError::Cancelled),
        _ => Ok(()),
    }
}

/// [`build_one`]; an owned `mesh` has its input positions and indices
/// freed once they are no longer read, unless [`BuildOptions::keep_input`].
fn build_mesh(
    index: usize,
    mesh: &mut Cow<'_, SourceMesh>,
    opts: &BuildOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<MeshBuild, BuildError> {
    let name = mesh.name.clone();
    let input_triangles = mesh.primitives.iter().map(Primitive::triangle_count).sum();
    let mesh_err = |source| BuildError::Mesh {
        index,
        name: name.clone(),
        source,
    };
    let sopts = simplify_options(opts, input_triangles)?;
    let side_by_side = input_triangles < SIDE_BY_SIDE_MAX_TRIANGLES;
    // (a level will be measured: the target is below the input)
    let early = side_by_side
        && opts.measured
        && opts.method == Method::Qem
        && sopts.target_for(input_triangles) < input_triangles;
    let t_build = Instant::now();
    let mut welded = None;
    let again = side_by_side && sopts.topology_change == TopologyChange::WhenShort;
    let freed = !early && !again && frees_input_early(matches!(mesh, Cow::Owned(_)), mesh, opts);
    let (mut simplified, early, flat) = if freed {
        let (simplified, flat) = simplify_freeing(mesh, opts, &sopts).map_err(mesh_err)?;
        (simplified, None, flat)
    } else {
        let flat = flatten(mesh);
        let (simplified, early) =
            simplify(mesh, &flat, opts, &sopts, early.then_some(&mut welded)).map_err(mesh_err)?;
        (simplified, early, flat)
    };
    let simplify_time = t_build.elapsed();
    go_on(opts)?;
    return_freed_memory(input_triangles);
    let pm = &simplified.pm;
    let mut full = pm.mesh_at_splits(pm.len());
    let measurer = Measurer::new(pm, &full, opts.measured, index, &name);
    if let Some((r, took)) = early.and_then(|e| e.renumbered(pm, &full)) {
        measurer.set_reference(r, took);
    }
    drop(welded);
    let mut measuring = |level: usize, of: usize| {
        progress(Progress::Measuring {
            mesh: index,
            level,
            of,
        })
    };
    let selected = select_splits(pm, opts, &measurer, &mut measuring);
    let (splits, notes) = or_restore!(selected, freed, mesh, &full);
    let what = (side_by_side, freed);
    let extracted = extract_all(mesh, &flat, &simplified, &splits, opts, &measurer, what);
    let extracted = or_restore!(extracted, freed, mesh, &full);
    drop(flat);
    if let (false, false, Cow::Owned(m)) = (freed, opts.keep_input, &mut *mesh) {
        if measurable(&full, &extracted) {
            for p in &mut m.primitives {
                p.positions = Vec::new();
                p.indices = Vec::new();
            }
        }
    }
    let coherent = measured_in_input_order(opts, side_by_side, &extracted);
    let (full, measurer) = match free_sequence(&mut simplified, opts.keep_progressive, coherent) {
        Some(origins) => {
            drop(measurer);
            // (the sequence's freed blocks, before the hierarchy's build)
            return_freed_memory(input_triangles);
            measurer_in_input_order(&mut full, origins, (index, &name))
        }
        None => (&full, measurer),
    };
    go_on(opts)?;
    let ready = opts.level_ready.as_ref().map(|h| (h, index));
    let measured = measure_levels(
        extracted,
        full,
        &splits,
        &opts.measure,
        &measurer,
        (side_by_side, ready),
        &mut measuring,
    );
    let (lod_levels, errors) = or_restore!(measured, freed, mesh, full);
    let measure_time = measurer.time();
    drop(measurer);
    Ok(MeshBuild {
        lod: LodMesh {
            source: index,
            name,
            levels: lod_levels,
        },
        input_triangles,
        simplified,
        level_splits: splits,
        errors,
        measured: opts.measured,
        times: BuildTimes {
            simplify: simplify_time,
            measure: measure_time,
            total: t_build.elapsed(),
        },
        notes,
    })
}

/// Whether the original's hierarchy is built over its welded input's
/// numbering ([`measurer_in_input_order`]): a large mesh (the small ones'
/// is built beside the simplification) whose levels are measured, by count
/// or ratio (nothing is measured before the levels are out), unpolished
/// (the polish builds its own) and unfixed (the fix measures each level as
/// it is extracted), with a level to measure.
fn measured_in_input_order(opts: &BuildOptions, side_by_side: bool, levels: &[Extracted]) -> bool {
    !side_by_side
        && opts.measured
        && opts.polish.is_none()
        && opts.fix_worst.is_none()
        && matches!(opts.levels, LevelRequest::Specs(_))
        && levels.iter().any(|e| e.mesh.is_some())
}

/// Frees the progressive mesh and the preparation's maps once the levels
/// are out (the sequence is not needed while the original's hierarchy is
/// built and the levels measured), unless `keep_progressive`; returns the
/// sequence's origin maps and length when `keep_origins`.
fn free_sequence(
    simplified: &mut Simplified,
    keep_progressive: bool,
    keep_origins: bool,
) -> Option<Origins> {
    let pm = &simplified.pm;
    let splits = pm.len();
    if keep_progressive {
        let maps = (pm.vertex_origin.clone(), pm.triangle_origin.clone());
        return keep_origins.then_some((maps.0, maps.1, splits));
    }
    let pm = std::mem::take(&mut simplified.pm);
    simplified.vertex_map = Vec::new();
    simplified.triangle_map = Vec::new();
    keep_origins.then_some((pm.vertex_origin, pm.triangle_origin, splits))
}

/// Every level extracted ([`extract_levels`]): polished first with
/// [`BuildOptions::polish`], its worst spot fixed with
/// [`BuildOptions::fix_worst`]; below [`SIDE_BY_SIDE_MAX_TRIANGLES`]
/// (`side_by_side`) while the original's hierarchy is built on the other
/// core (before, when the fix needs it); `freed`: the input was freed
/// ([`frees_input_early`]).
fn extract_all(
    mesh: &SourceMesh,
    flat: &Flat,
    simplified: &Simplified,
    splits: &[usize],
    opts: &BuildOptions,
    measurer: &Measurer<'_>,
    (side_by_side, freed): (bool, bool),
) -> Result<Vec<Extracted>, BuildError> {
    // (the polish walks from the simplification's clusters: no hierarchy)
    let full = measurer.full();
    let original = opts
        .polish
        .map(|_| Original::new(MeshRef::new(&full.positions, &full.triangles)));
    let polish = original.as_ref().zip(opts.polish.as_ref());
    let fix = opts
        .fix_worst
        .as_ref()
        .map(|w| (measurer, &opts.measure, w));
    let what = (opts.measured, freed);
    let extract = || extract_levels(mesh, flat, simplified, splits, what, polish, fix);
    if side_by_side && fix.is_none() {
        // (the original's hierarchy built on the other core meanwhile)
        let (extracted, prepared) = rayon::join(extract, || measurer.prepare());
        prepared?;
        extracted
    } else {
        extract()
    }
}

/// The simplification of a mesh whose input is freed once it is prepared
/// ([`frees_input_early`]), and its flattening without geometry.
fn simplify_freeing(
    mesh: &mut Cow<'_, SourceMesh>,
    opts: &BuildOptions,
    sopts: &SimplifyOptions,
) -> Result<(Simplified, Flat<'static>), MeshError> {
    let flat = flatten(mesh);
    let meter = opts.meter.clone();
    let ready = prepare_wedged(mesh, &flat, sopts, &opts.attribute_weights, meter)?;
    let flat = flat.without_geometry();
    free_input(mesh);
    // (nothing reads the maps: the levels' primitives come from their
    // meshes, `deferred_primitives`)
    let simplified = ready.without_maps().run();
    if let Some(m) = &opts.meter {
        m.set_stage(lodgen_pm::Stage::Idle);
    }
    Ok((simplified, flat))
}

/// `opts.simplify` with the triangle target the requested levels need.
fn simplify_options(opts: &BuildOptions, full_tris: usize) -> Result<SimplifyOptions, BuildError> {
    let mut sopts = opts.simplify;
    match &opts.levels {
        LevelRequest::Specs(specs) => {
            if specs.is_empty() {
                return Err(BuildError::NoLevels);
            }
            // Ratios refer to the welded, cleaned mesh (the simplifier's
            // input, which a ratio target of the core is taken of: with
            // duplicated or degenerate faces the raw count is larger, and
            // a target from it stopped the run above the coarsest level);
            // the floor is a triangle target beside it (the larger stops).
            let floor = opts.min_triangles.max(1);
            let smallest = |ratio: bool| {
                let of = |s: &LevelSpec| match (*s, ratio) {
                    (LevelSpec::Ratio(r), true) => Some(r.clamp(0.0, 1.0)),
                    (LevelSpec::Triangles(t), false) => Some(t as f64),
                    _ => None,
                };
                specs.iter().filter_map(of).reduce(f64::min)
            };
            let by_error = specs.iter().any(|s| matches!(s, LevelSpec::MaxError(_)));
            match (smallest(true), smallest(false), by_error) {
                (Some(r), None, false) => {
                    sopts.target_ratio = Some(r);
                    sopts.target_triangles = Some(floor);
                }
                // counts alone, or both (then the ratio of the raw count:
                // a count under it is what the run must reach anyway)
                _ => {
                    let target = levels::triangle_target(full_tris, specs).unwrap_or(0);
                    sopts.target_triangles = Some(target.max(floor));
                    sopts.target_ratio = None;
                }
            }
        }
        LevelRequest::MaxErrors(bounds) => {
            if bounds.is_empty() {
                return Err(BuildError::NoLevels);
            }
            sopts.target_triangles = Some(opts.min_triangles.max(1));
            sopts.target_ratio = None;
        }
    }
    Ok(sopts)
}

/// The original's hierarchy built beside the simplification, over the
/// welded input ([`simplify`] with a slot for it).
struct Early<'m> {
    reference: Result<Reference<'m>, lodgen_pm::metric::MeshError>,
    /// Wall time of the hierarchy's build.
    took: Duration,
}

impl Early<'_> {
    /// The hierarchy renumbered as `pm` numbers the original (`full`, `pm`
    /// fully refined): the one built over `full`, bit for bit, or `None`
    /// when that cannot be told from the welded input's (two triangles or
    /// vertices at one Morton code; a failed build): then it is built anew.
    fn renumbered<'f>(
        self,
        pm: &ProgressiveMesh,
        full: &'f Mesh,
    ) -> Option<(Reference<'f>, Duration)> {
        let r = self.reference.ok()?.renumbered(
            MeshRef::new(&full.positions, &full.triangles),
            &inverse(&pm.vertex_origin),
            &inverse(&pm.triangle_origin),
        )?;
        Some((r, self.took))
    }
}

/// QEM runs on wedges (seams and attributes kept); the curvature-adaptive
/// methods see positions only, and their levels take attributes from the
/// first input vertex of each position. With `welded` (QEM only), the
/// original's hierarchy is built on another thread meanwhile, over a copy of
/// the welded input put there: on a small mesh the simplification leaves
/// the other core idle most of the time (its walk is sequential), while
/// the hierarchy built after it was the measurement's first ~10 % of CPU
/// with one core idle.
fn simplify<'m>(
    mesh: &SourceMesh,
    flat: &Flat,
    opts: &BuildOptions,
    sopts: &SimplifyOptions,
    welded: Option<&'m mut Option<Mesh>>,
) -> Result<(Simplified, Option<Early<'m>>), MeshError> {
    if opts.method != Method::Qem {
        let s = simplify_adaptive(
            &flat.positions,
            &flat.indices,
            opts.method,
            sopts,
            &opts.adaptive,
        )?;
        return Ok((s, None));
    }
    let meter = opts.meter.clone();
    let weights = &opts.attribute_weights;
    let r = match welded {
        None => simplify_wedged(mesh, flat, sopts, weights, meter).map(|s| (s, None)),
        Some(slot) => {
            let build = |welded: &'m Mesh| {
                let t = Instant::now();
                let reference = Reference::new(MeshRef::new(&welded.positions, &welded.triangles));
                Early {
                    reference,
                    took: t.elapsed(),
                }
            };
            simplify_wedged_beside(mesh, flat, sopts, weights, meter, slot, build)
                .map(|(s, e)| (s, Some(e)))
        }
    };
    if let Some(m) = &opts.meter {
        m.set_stage(lodgen_pm::Stage::Idle);
    }
    r
}

/// Whether measuring the levels cannot fail: the original and every level
/// to measure pass the check the measurement makes ([`MeshRef::validate`]).
/// Asked only of an input still to free (an input freed early has nothing
/// left to free: the check of every level was 0.6 s of bunny-4m's run).
fn measurable(full: &Mesh, extracted: &[Extracted]) -> bool {
    let ok = |m: &Mesh| MeshRef::new(&m.positions, &m.triangles).validate().is_ok();
    ok(full) && extracted.iter().filter_map(|e| e.mesh.as_ref()).all(ok)
}

/// Every extracted level measured (its mesh freed once it is; with
/// `side_by_side`, all levels at once, their meshes freed together), then
/// the screen coverages from the measured errors. `full` stands for a level
/// without a mesh (the original, or not measured: its error does not read
/// it). With `ready` (the hook of [`BuildOptions::level_ready`] and the
/// mesh's index), each level's primitives are given to the hook beside the
/// measurement: side by side every level during theirs, else the previous
/// level during the next one's (so one level's prepared buffers wait at a
/// time, not beside the finest level's measurement, the peak).
fn measure_levels(
    extracted: Vec<Extracted>,
    full: &Mesh,
    splits: &[usize],
    mopts: &MeasureOptions,
    measurer: &Measurer<'_>,
    (side_by_side, ready): (bool, Option<(&LevelHook, usize)>),
    measuring: &mut dyn FnMut(usize, usize),
) -> Result<(Vec<LodLevel>, Vec<ErrorReport>), BuildError> {
    let diagonal = measurer.diagonal();
    let mut errors = Vec::with_capacity(splits.len());
    let mut lod_levels: Vec<LodLevel> = Vec::with_capacity(splits.len());
    let mut reports = Vec::new();
    let hand = |level: usize, primitives: &[Primitive]| {
        if let Some((LevelHook(f), mesh)) = ready {
            f(mesh, level, primitives);
        }
    };
    // (levels whose worst spot was fixed were measured then)
    if side_by_side && extracted.iter().all(|l| l.report.is_none()) {
        measuring(0, splits.len());
        let levels: Vec<(&Mesh, usize)> = extracted
            .iter()
            .zip(splits)
            .map(|(l, &k)| (l.mesh.as_ref().unwrap_or(full), k))
            .collect();
        reports = match ready {
            None => measurer.measure_levels(&levels, mopts)?,
            // (side by side no level is deferred: its primitives are final)
            Some(_) => {
                let every = || {
                    for (li, l) in extracted.iter().enumerate() {
                        if l.deferred.is_none() {
                            hand(li, &l.primitives);
                        }
                    }
                };
                rayon::join(|| measurer.measure_levels(&levels, mopts), every).0?
            }
        };
    }
    let mut reports = reports.into_iter();
    for (li, (level, &k)) in extracted.into_iter().zip(splits).enumerate() {
        let report = match level.report.or_else(|| reports.next()) {
            Some(r) => r,
            None => {
                measuring(li, splits.len());
                let mesh = level.mesh.as_ref().unwrap_or(full);
                // (the previous level handed over meanwhile)
                match (ready, li.checked_sub(1).and_then(|p| lod_levels.get(p))) {
                    (Some(_), Some(previous)) => {
                        let previous = || hand(li - 1, &previous.primitives);
                        rayon::join(|| measurer.measure(mesh, k, mopts), previous).0?
                    }
                    _ => measurer.measure(mesh, k, mopts)?,
                }
            }
        };
        let primitives = match level.deferred {
            Some(material) => deferred_primitives(material, level.mesh.as_ref().unwrap_or(full)),
            None => level.primitives,
        };
        drop(level.mesh);
        lod_levels.push(LodLevel {
            primitives,
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
    Ok((lod_levels, errors))
}
