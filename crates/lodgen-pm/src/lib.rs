#![warn(missing_docs)]
//! lodgen-pm: progressive meshes by Garland–Heckbert pair contraction, with
//! every contraction recorded as a Hoppe vertex split.
//!
//! ```
//! use lodgen_pm::{simplify, SimplifyOptions};
//! // a flat 3×3 grid of quads
//! let mut positions = Vec::new();
//! for y in 0..4 { for x in 0..4 { positions.push([x as f32, y as f32, 0.0]); } }
//! let mut indices = Vec::new();
//! for y in 0..3u32 { for x in 0..3u32 {
//!     let i = y * 4 + x;
//!     indices.extend_from_slice(&[i, i + 1, i + 5, i, i + 5, i + 4]);
//! } }
//! let out = simplify(&positions, &indices, &SimplifyOptions::DEFAULT.with_target_triangles(2)).unwrap();
//! assert_eq!(out.pm.base.triangles.len(), 2);
//! // the whole sequence M_n … M_g is there: refine back to the input
//! assert_eq!(out.pm.mesh_at(usize::MAX).triangles.len(), 18);
//! ```
//!
//! # Public areas
//!
//! | module | what |
//! |---|---|
//! | [`mesh`] | [`Mesh`], [`prepare`] (validate, weld, clean) and [`MeshError`] |
//! | [`simplify`](mod@simplify) | [`simplify()`], [`simplify_with_wedges`], the [`Simplifier`] and its [`SimplifyOptions`] |
//! | [`progressive`] | the result: [`ProgressiveMesh`], its [`Cursor`], the [`VertexSplit`] records, [`levels`], [`attrfit`], [`stream`] |
//! | [`adaptive`] | the curvature-adaptive methods ([`simplify_method`]) |
//! | [`metric`] | sampled Hausdorff / RMS distances between two meshes |
//! | [`polish`](mod@polish) | a level's vertices moved towards the original surface |
//! | [`shapes`] | small generated meshes for tests, examples and benchmarks |
//!
//! The crate does no I/O and never prints. See ARCHITECTURE.md for the data
//! flow: mesh → quadrics → pairs → heap → collapse → vertex-split log →
//! levels.

pub mod adaptive;
pub mod mesh;
#[allow(missing_docs)] // (documented by its owner, issue 15 metric work)
pub mod metric;
pub mod polish;
pub mod progressive;
pub mod shapes;
pub mod simplify;
mod util;

pub use adaptive::{
    simplify_adaptive, simplify_method, Adaptive, AdaptiveOptions, AdaptiveReport, AdaptiveStop,
    Method, Reclassify, Threshold,
};
pub use glam;
pub use mesh::{prepare, Mesh, MeshError, PrepareStats, Prepared};
pub use polish::{polish, polish_clusters, PolishOptions, PolishStats};
pub use progressive::{attrfit, levels, stream};
pub use progressive::{
    Corner, Corners, Cursor, ProgressiveMesh, SplitWedges, VertexSplit, WedgeLog,
};
pub use simplify::{
    Boundary, Meter, PhaseTimes, Placement, Rejected, Rejections, Schedule, Simplifier,
    SimplifyOptions, Snapshot, Stage, Stats, StopReason, Tau, TopologyChange,
    DEFAULT_BOUNDARY_WEIGHT, DEFAULT_CLUSTER_TRIANGLES, DEFAULT_PASS_FACTOR,
    DEFAULT_REACH_FACES_FACTOR, DEFAULT_REACH_FACTOR,
};

/// A simplification's result: the progressive mesh (numbered as in
/// [`progressive`]), what preparation removed, what the loop did, and why it
/// stopped.
#[derive(Clone, Debug)]
pub struct Simplified {
    /// The base mesh and the vertex splits back to the (welded) input.
    pub pm: ProgressiveMesh,
    /// Input vertex → welded vertex (`u32::MAX` if unused); the progressive
    /// mesh's `vertex_origin` maps into the welded numbering.
    pub vertex_map: Vec<u32>,
    /// Welded triangle → input triangle.
    pub triangle_map: Vec<u32>,
    /// What preparation welded and removed.
    pub prepare: PrepareStats,
    /// What the contraction loop did.
    pub stats: Stats,
    /// Why the loop stopped.
    pub stop: StopReason,
}

/// Prepare (validate, weld, clean) and simplify an indexed triangle list
/// (with [`TopologyChange::WhenShort`], twice when the topology stopped the
/// first run above its target).
pub fn simplify(
    positions: &[[f32; 3]],
    indices: &[u32],
    opts: &SimplifyOptions,
) -> Result<Simplified, MeshError> {
    simplify_metered(positions, indices, opts, None)
}

/// [`simplify()`], reporting to `meter` as [`simplify_with_wedges_metered`]
/// does, and stopping with [`StopReason::Cancelled`] once it is
/// [cancelled](Meter::cancel).
pub fn simplify_metered(
    positions: &[[f32; 3]],
    indices: &[u32],
    opts: &SimplifyOptions,
    meter: Option<std::sync::Arc<Meter>>,
) -> Result<Simplified, MeshError> {
    let out = simplify_once(positions, indices, opts, meter.clone())?;
    if !short_on_topology(opts, &out) {
        return Ok(out);
    }
    drop(out);
    simplify_once(positions, indices, &again(opts), meter)
}

/// Whether [`TopologyChange::WhenShort`] runs again: the run stopped above
/// its target, and the topology rules that [`TopologyChange::Joins`]
/// relaxes refused candidates.
fn short_on_topology(opts: &SimplifyOptions, out: &Simplified) -> bool {
    let r = &out.stats.rejected;
    opts.topology_change == TopologyChange::WhenShort
        && out.stop == StopReason::Exhausted
        && r.link + r.boundary_pinch + r.duplicate > 0
}

/// The options of [`TopologyChange::WhenShort`]'s second run.
fn again(opts: &SimplifyOptions) -> SimplifyOptions {
    (*opts).with_topology_change(TopologyChange::Joins)
}

fn simplify_once(
    positions: &[[f32; 3]],
    indices: &[u32],
    opts: &SimplifyOptions,
    meter: Option<std::sync::Arc<Meter>>,
) -> Result<Simplified, MeshError> {
    let prepared = prepare(positions, indices)?;
    let mut s = Simplifier::from_mesh(prepared.mesh, opts)?;
    if let Some(m) = meter {
        s.set_meter(m);
    }
    let stop = s.run();
    let (pm, stats) = s.finish();
    Ok(Simplified {
        pm,
        vertex_map: prepared.vertex_map,
        triangle_map: prepared.triangle_map,
        prepare: prepared.stats,
        stats,
        stop,
    })
}

/// [`simplify()`], with attributes kept apart by wedges: `indices` refer to
/// unwelded vertices, and two corners share a wedge exactly when they share
/// an index. Positions are welded for topology; every edge across which the
/// indices differ (a UV seam, a hard edge, a material border when the
/// caller numbers primitives apart) is a feature edge that collapses only
/// along itself. The log carries every corner's wedge
/// (`pm.wedges`, input vertex indices), so replay restores them exactly.
///
/// `attributes` holds `dims` weighted values per input vertex, i.e. per
/// wedge (empty with `dims == 0`): they add Hoppe 1999 attribute quadrics,
/// one per wedge, to the costs (see ARCHITECTURE.md); non-finite values
/// count as 0.
/// Wrong lengths are a [`MeshError::AttributeCount`].
pub fn simplify_with_wedges(
    positions: &[[f32; 3]],
    indices: &[u32],
    attributes: &[f32],
    dims: usize,
    opts: &SimplifyOptions,
) -> Result<Simplified, MeshError> {
    simplify_with_wedges_metered(positions, indices, attributes, dims, opts, None)
}

/// [`simplify_with_wedges`], reporting its stage and the share of the
/// target reached to `meter` (read it from another thread for a progress
/// display; [`Meter`]; a second run of [`TopologyChange::WhenShort`]
/// reports from the start again).
pub fn simplify_with_wedges_metered(
    positions: &[[f32; 3]],
    indices: &[u32],
    attributes: &[f32],
    dims: usize,
    opts: &SimplifyOptions,
    meter: Option<std::sync::Arc<Meter>>,
) -> Result<Simplified, MeshError> {
    check_attributes(positions, attributes, dims, meter.as_deref())?;
    let prepared = prepare(positions, indices)?;
    run_again(prepared, positions, indices, attributes, dims, opts, meter)
}

/// [`simplify_with_wedges_metered`] in two steps: this one prepares (weld,
/// clean, the simplifier's set-up, the wedges and attribute values taken
/// over) and returns the simplification [`Ready`] to run, which no longer
/// reads `positions`, `indices` or `attributes`: a caller may free them
/// before [`Ready::run`] (peak memory: a scan's parsed input is 18 bytes
/// per triangle). So [`Ready::run`] runs once: with
/// [`TopologyChange::WhenShort`] a run the topology stops above its target
/// stays there (as with [`TopologyChange::Never`]); the caller may run
/// again with [`TopologyChange::Joins`] while it has the input.
pub fn prepare_with_wedges(
    positions: &[[f32; 3]],
    indices: &[u32],
    attributes: &[f32],
    dims: usize,
    opts: &SimplifyOptions,
    meter: Option<std::sync::Arc<Meter>>,
) -> Result<Ready, MeshError> {
    check_attributes(positions, attributes, dims, meter.as_deref())?;
    let prepared = prepare(positions, indices)?;
    ready(prepared, indices, attributes, dims, opts, meter)
}

/// [`simplify_with_wedges_metered`], with `beside` run on another thread
/// while the mesh is simplified: it gets a copy of the prepared (welded,
/// cleaned) mesh, put in `welded`, which the progressive mesh refines back
/// to (numbered as [`prepare`] numbers it, not as the progressive mesh does:
/// `pm.vertex_origin` and `pm.triangle_origin` map one to the other).
/// For work that needs only the input, such as the hierarchy its levels
/// will be measured against, on a core the simplification leaves idle most
/// of the time. `beside` is not run when the input is rejected.
#[allow(clippy::too_many_arguments)]
pub fn simplify_with_wedges_beside<'m, R: Send>(
    positions: &[[f32; 3]],
    indices: &[u32],
    attributes: &[f32],
    dims: usize,
    opts: &SimplifyOptions,
    meter: Option<std::sync::Arc<Meter>>,
    welded: &'m mut Option<Mesh>,
    beside: impl FnOnce(&'m Mesh) -> R + Send,
) -> Result<(Simplified, R), MeshError> {
    check_attributes(positions, attributes, dims, meter.as_deref())?;
    let prepared = prepare(positions, indices)?;
    let copy: &'m Mesh = welded.insert(prepared.mesh.clone());
    let (simplified, r) = rayon::join(
        || run_again(prepared, positions, indices, attributes, dims, opts, meter),
        || beside(copy),
    );
    Ok((simplified?, r))
}

/// The attribute values' length against the vertex count (the first check
/// of the wedged entry points, before preparation).
fn check_attributes(
    positions: &[[f32; 3]],
    attributes: &[f32],
    dims: usize,
    meter: Option<&Meter>,
) -> Result<(), MeshError> {
    if let Some(m) = meter {
        m.set_stage(Stage::Preparing);
    }
    if attributes.len() != dims * positions.len() {
        return Err(MeshError::AttributeCount {
            len: attributes.len(),
            dims,
            vertex_count: positions.len(),
        });
    }
    Ok(())
}

/// [`ready`] and run, and with [`TopologyChange::WhenShort`] again from
/// the input (prepared again) when the topology stopped it above its
/// target.
fn run_again(
    prepared: Prepared,
    positions: &[[f32; 3]],
    indices: &[u32],
    attributes: &[f32],
    dims: usize,
    opts: &SimplifyOptions,
    meter: Option<std::sync::Arc<Meter>>,
) -> Result<Simplified, MeshError> {
    let out = ready(prepared, indices, attributes, dims, opts, meter.clone())?.run();
    if !short_on_topology(opts, &out) {
        return Ok(out);
    }
    drop(out);
    let prepared = prepare(positions, indices)?;
    Ok(ready(prepared, indices, attributes, dims, &again(opts), meter)?.run())
}

/// The simplification of the wedged entry points, from the prepared mesh,
/// ready to run.
fn ready(
    prepared: Prepared,
    indices: &[u32],
    attributes: &[f32],
    dims: usize,
    opts: &SimplifyOptions,
    meter: Option<std::sync::Arc<Meter>>,
) -> Result<Ready, MeshError> {
    let mut s = Simplifier::from_mesh(prepared.mesh, opts)?;
    let wedges = prepared
        .triangle_map
        .iter()
        .map(|&t| {
            let t = 3 * t as usize;
            [indices[t], indices[t + 1], indices[t + 2]]
        })
        .collect();
    s.set_wedges(wedges);
    if dims > 0 {
        // per wedge (the caller's vertex ids), non-finite values as 0
        let values = attributes
            .iter()
            .map(|&x| if x.is_finite() { x } else { 0.0 })
            .collect();
        s.set_attributes(values, dims);
    }
    if let Some(m) = meter {
        s.set_meter(m);
    }
    Ok(Ready {
        s,
        vertex_map: prepared.vertex_map,
        triangle_map: prepared.triangle_map,
        prepare: prepared.stats,
    })
}

/// A simplification prepared by [`prepare_with_wedges`], holding
/// everything it reads: [`Ready::run`] gives the [`Simplified`] result.
pub struct Ready {
    s: Simplifier,
    vertex_map: Vec<u32>,
    triangle_map: Vec<u32>,
    prepare: PrepareStats,
}

impl Ready {
    /// Frees the preparation's maps now: the result's
    /// [`Simplified::vertex_map`] and [`Simplified::triangle_map`] will be
    /// empty (a caller that does not read them saves 12 bytes per input
    /// triangle during the run).
    pub fn without_maps(mut self) -> Ready {
        self.vertex_map = Vec::new();
        self.triangle_map = Vec::new();
        self
    }

    /// Run the contractions to the target and build the progressive mesh.
    pub fn run(self) -> Simplified {
        let Ready {
            mut s,
            vertex_map,
            triangle_map,
            prepare,
        } = self;
        let stop = s.run();
        let (pm, stats) = s.finish();
        Simplified {
            pm,
            vertex_map,
            triangle_map,
            prepare,
            stats,
            stop,
        }
    }
}
