//! Curvature-adaptive multiresolution: Ceballos, Hernández & Prieto,
//! "Multirresolución adaptativa de mallas triangulares basado en criterios
//! de curvatura" (Universidad Nacional de Colombia, Manizales). The mesh is
//! decimated only where its *average normal deviation* is low, with one of
//! the three collapse operators of the paper's §2.2, and every operation is
//! recorded in the core's vertex-split log so the result streams and exports
//! like a QEM one.
//!
//! The paper's Algorithm 1, as implemented here:
//! 1. **Borders** (Algorithm 2, [`boundary_vertices`]): a vertex whose
//!    umbrella is incomplete (some neighbour appears in only one of its
//!    triangles) is a border vertex and never moves. Vertices on a
//!    non-manifold edge or where several fans meet are fixed as well (the
//!    paper's meshes have none; moving them would tear the mesh).
//! 2. **Curvature** (Algorithm 3, [`normal_deviation`]): vertex normal = mean
//!    of the adjacent unit face normals; region normal = area-weighted mean
//!    of the face normals of the k-ring umbrella (Eq. 1, k = 3 in the paper);
//!    θ = acos(n_v · n_region) (Eq. 3). [`classify`] thresholds θ into
//!    low/high ([`Threshold`]: mean + 2σ, the median, or a fraction).
//! 3. **Decimation** (Algorithm 4): triangles are visited flattest first; a
//!    triangle whose vertices are all removable (interior, low θ) and not
//!    frozen is collapsed with the chosen [`Method`]: full edge collapse to
//!    the midpoint (§2.2.1), half-edge collapse onto an endpoint (§2.2.2), or
//!    triangle collapse of its three vertices to the centroid (§2.2.3).
//!    Every triangle sharing a vertex with a collapsed one is frozen until the
//!    next sweep (the paper's guard against Figure 4's collapse to a point).
//! 4. **Repeat** (Step 4): classify again on the decimated mesh and sweep
//!    again, until the triangle target is reached or a sweep removes nothing
//!    ([`AdaptiveStop`] says why).
//!
//! Algorithm 5's defects are *prevented* by the core's legality rules
//! (link condition, [`FLIP_MIN_COS`](crate::simplify::FLIP_MIN_COS) flip test, [`DEGENERATE_AREA_RATIO_SQ`](crate::simplify::DEGENERATE_AREA_RATIO_SQ),
//! duplicate-triangle test), counted in [`AdaptiveReport::prevented`]. What
//! still occurs after a legal operation (two triangles on the same three
//! vertices — the paper's "spikes"; a valence-3 "pyramid" whose one face turns
//! more than 90° from the other two; a face reversed against its umbrella) is
//! *repaired by rolling the operation back*, counted in
//! [`AdaptiveReport::repaired`]. The paper instead deletes and re-orients
//! triangles, which no vertex split can express; a rollback keeps the log a
//! plain sequence of splits.
//!
//! A triangle collapse is recorded as **two vertex splits**: `a` into `b` at
//! the centroid `d` (removing the triangle and its neighbour across `ab`),
//! then `c` into `b` at `d` (removing the two neighbours across `bc` and
//! `ca`). The intermediate mesh is a legal edge-collapse state, checked like
//! any other, so every prefix of the log is a valid mesh.
//!
//! [`Method::QemCurvature`] is the hybrid: the core GH97 [`Simplifier`] with
//! each pair's cost multiplied by `1 + w · θ / θ_max` (see
//! [`Simplifier::set_cost_scale`]), so curvature steers *which* pairs go
//! while QEM chooses *where* the new vertex goes.
//!
//! Deviations from the paper, with reasons: triangles are visited in order of
//! their largest θ (flattest first) instead of index order, so a sweep cut
//! short by the target has removed the flattest parts; with
//! [`Reclassify::FixedThreshold`] (the default) the threshold angle is taken
//! from the input's θ distribution once and θ is re-measured every sweep
//! against it, so the threshold is the level of detail to keep (the paper's
//! conclusion) and the method stops when everything left is curved;
//! [`Reclassify::EverySweep`] recomputes the threshold from each sweep's
//! distribution as the paper's Step 4 literally does.
//!
//! Owns [`Method`], [`AdaptiveOptions`], the classification and the sweep
//! engine. Does no I/O and never prints.

use crate::mesh::{prepare, Mesh, MeshError};
use crate::progressive::{Contraction, Corner, Log, ProgressiveMesh, Removed};
use crate::simplify::options::SimplifyOptions;
use crate::simplify::quadric::Quadric;
use crate::simplify::{
    fan_count, link, moved_faces_ok, Faces, Link, PhaseTimes, Rejected, Rejections, Simplifier,
    Stats, StopReason,
};
use crate::Simplified;
use glam::DVec3;
use rayon::prelude::*;
use smallvec::SmallVec;
use std::time::Instant;

/// The paper's umbrella depth: "se usan las tres capas de la vecindad".
pub const DEFAULT_K_RING: usize = 3;

/// The paper's statistical threshold: θ above mean + 2σ is high curvature.
pub const DEFAULT_SIGMA: f64 = 2.0;

/// Hybrid weight `w` in `1 + w · θ / θ_max`: the flattest pair keeps its QEM
/// cost, the most curved one costs 5× as much. Large enough to reorder pairs
/// whose QEM costs are close, small enough that a nearly free collapse on a
/// curved patch still beats an expensive one on a flat patch (a pure curvature
/// order — w → ∞ — throws away QEM's error ranking).
pub const DEFAULT_HYBRID_WEIGHT: f64 = 4.0;

/// A valence-3 vertex is a "pyramid" (Algorithm 5, step 2) when one of its
/// three faces turns more than 90° (cos < 0) from both others.
pub const PYRAMID_MAX_COS: f64 = 0.0;

/// A face whose normal makes more than 90° (cos < 0) with the area-weighted
/// normal of the umbrella it lies in is reversed (Algorithm 5, step 3). Only
/// low-curvature umbrellas are ever edited, where every face should agree.
pub const REVERSED_MAX_COS: f64 = 0.0;

/// Which simplification method to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Method {
    /// The core GH97 quadric pair contraction ([`crate::simplify()`]).
    Qem,
    /// Curvature-adaptive full edge collapse to the midpoint (§2.2.1).
    Edge,
    /// Curvature-adaptive half-edge collapse onto one endpoint (§2.2.2).
    HalfEdge,
    /// Curvature-adaptive triangle collapse to the centroid (§2.2.3).
    Triangle,
    /// QEM with pair costs scaled by the normal deviation.
    QemCurvature,
}

impl Method {
    /// Every method, in the order the comparison lists them.
    pub const ALL: [Method; 5] = [
        Method::Qem,
        Method::QemCurvature,
        Method::Edge,
        Method::HalfEdge,
        Method::Triangle,
    ];

    /// The CLI spelling (`--method`).
    pub fn name(self) -> &'static str {
        match self {
            Method::Qem => "qem",
            Method::Edge => "edge",
            Method::HalfEdge => "half-edge",
            Method::Triangle => "triangle",
            Method::QemCurvature => "qem-curvature",
        }
    }

    /// Whether this is one of the paper's sweep methods (as opposed to QEM).
    pub fn is_adaptive(self) -> bool {
        matches!(self, Method::Edge | Method::HalfEdge | Method::Triangle)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Method, String> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                format!("unknown method {s:?}; expected one of qem, edge, half-edge, triangle, qem-curvature")
            })
    }
}

/// How θ is split into low (removable) and high curvature. A vertex is high
/// when θ is strictly above the threshold angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Threshold {
    /// Threshold at mean + s·σ of θ (the paper's first strategy, s = 2).
    Sigma(f64),
    /// Threshold at the (lower) median: at least half the vertices are
    /// removable (the paper's second strategy). Same as `Fraction(0.5)`.
    Median,
    /// Threshold at the θ of rank `⌈f·n⌉` in increasing order (f in [0, 1]):
    /// at least that fraction is removable (exactly, when θ values differ).
    Fraction(f64),
}

/// When the threshold angle is recomputed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reclassify {
    /// The angle comes from the input's θ distribution; θ is re-measured
    /// every sweep and compared with it. Stops when all that is left is
    /// curved at that level of detail.
    FixedThreshold,
    /// The angle comes from each sweep's own θ distribution (the paper's
    /// Step 4 taken literally): some vertices are always removable.
    EverySweep,
}

/// Options of the curvature methods. `AdaptiveOptions::DEFAULT` documents
/// every default.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct AdaptiveOptions {
    /// Depth of the umbrella the region normal is averaged over (≥ 1).
    /// Default value: [`DEFAULT_K_RING`] = 3.
    pub k_ring: usize,
    /// Default value: `Sigma(DEFAULT_SIGMA)` (mean + 2σ).
    pub threshold: Threshold,
    /// Default value: `FixedThreshold`.
    pub reclassify: Reclassify,
    /// `w` of the hybrid's cost scale `1 + w · θ / θ_max` (≥ 0).
    /// Default value: [`DEFAULT_HYBRID_WEIGHT`].
    pub hybrid_weight: f64,
}

impl AdaptiveOptions {
    pub const DEFAULT: AdaptiveOptions = AdaptiveOptions {
        k_ring: DEFAULT_K_RING,
        threshold: Threshold::Sigma(DEFAULT_SIGMA),
        reclassify: Reclassify::FixedThreshold,
        hybrid_weight: DEFAULT_HYBRID_WEIGHT,
    };
    pub fn with_k_ring(mut self, k: usize) -> Self {
        self.k_ring = k;
        self
    }
    pub fn with_threshold(mut self, t: Threshold) -> Self {
        self.threshold = t;
        self
    }
    pub fn with_reclassify(mut self, r: Reclassify) -> Self {
        self.reclassify = r;
        self
    }
    pub fn with_hybrid_weight(mut self, w: f64) -> Self {
        self.hybrid_weight = w;
        self
    }
}

impl Default for AdaptiveOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why an adaptive run stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdaptiveStop {
    /// The triangle target was reached.
    Target,
    /// No triangle (edge, for the edge operators) has all its vertices
    /// removable: what is left is border, non-manifold or high-curvature.
    Locked,
    /// Candidates remained, but every operation on them was illegal or had
    /// to be rolled back.
    Illegal,
    /// A QEM method stopped early with this core reason.
    Qem(StopReason),
}

impl AdaptiveStop {
    /// The core's reason for the same stop (`Exhausted` for both early
    /// adaptive stops).
    pub fn core(self) -> StopReason {
        match self {
            AdaptiveStop::Target => StopReason::Target,
            AdaptiveStop::Locked | AdaptiveStop::Illegal => StopReason::Exhausted,
            AdaptiveStop::Qem(r) => r,
        }
    }
}

/// Algorithm 5 defects found after a legal operation and repaired by rolling
/// the operation back.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Repairs {
    /// Two triangles on the same three vertices ("espigas").
    pub spikes: usize,
    /// A valence-3 vertex with one face folded over the other two.
    pub pyramids: usize,
    /// A face reversed against its umbrella.
    pub reversed: usize,
}

impl Repairs {
    pub fn total(&self) -> usize {
        self.spikes + self.pyramids + self.reversed
    }
}

/// What a curvature method did, beyond the core [`Stats`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveReport {
    pub method: Method,
    pub stop: AdaptiveStop,
    /// Classify → decimate sweeps run (0 for the QEM methods).
    pub sweeps: usize,
    /// Operator applications (a triangle collapse is one operation, two
    /// splits).
    pub operations: usize,
    /// The first sweep's threshold angle (radians); for the hybrid, θ_max.
    pub threshold: f64,
    /// Vertices classified high curvature in the input.
    pub high_curvature_vertices: usize,
    /// In the last sweep: interior vertices still alive, those of them
    /// above the threshold (high curvature, locked), and the candidate
    /// triangles the operator was tried on (0 for the QEM methods).
    pub last_interior: usize,
    pub last_high: usize,
    pub last_candidates: usize,
    /// Vertices that never move: border (Algorithm 2) and non-manifold.
    pub fixed_vertices: usize,
    /// Operations refused by the legality rules (Algorithm 5 prevented).
    pub prevented: Rejections,
    /// Operations rolled back because they produced an Algorithm 5 defect.
    pub repaired: Repairs,
}

/// A method's result: the core [`Simplified`] (same shape as
/// [`crate::simplify()`]'s) and the curvature report.
#[derive(Clone, Debug)]
pub struct Adaptive {
    pub simplified: Simplified,
    pub report: AdaptiveReport,
}

#[inline]
fn dv(p: [f32; 3]) -> DVec3 {
    DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]))
}

#[inline]
fn fv(p: DVec3) -> [f32; 3] {
    [p.x as f32, p.y as f32, p.z as f32]
}

/// Twice-area normal of a triangle.
#[inline]
fn cross_normal(pos: &[[f32; 3]], t: &[u32; 3]) -> DVec3 {
    let [a, b, c] = t.map(|v| dv(pos[v as usize]));
    (b - a).cross(c - a)
}

fn vertex_triangles(mesh: &Mesh) -> Vec<Vec<u32>> {
    let mut vt = vec![Vec::new(); mesh.positions.len()];
    for (i, t) in mesh.triangles.iter().enumerate() {
        for &v in t {
            vt[v as usize].push(i as u32);
        }
    }
    vt
}

/// Algorithm 2: a vertex is on the border when its umbrella is incomplete,
/// i.e. some neighbour appears in exactly one of its triangles (or it has no
/// triangle at all). Indices must be in range (a validated mesh).
pub fn boundary_vertices(mesh: &Mesh) -> Vec<bool> {
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(mesh.triangles.len() * 6);
    for t in &mesh.triangles {
        for k in 0..3 {
            pairs.push((t[k], t[(k + 1) % 3]));
            pairs.push((t[k], t[(k + 2) % 3]));
        }
    }
    pairs.sort_unstable();
    let mut border = vec![true; mesh.positions.len()];
    for v in pairs.iter().map(|p| p.0) {
        border[v as usize] = false;
    }
    for run in pairs.chunk_by(|a, b| a == b) {
        if run.len() == 1 {
            border[run[0].0 as usize] = true;
        }
    }
    border
}

/// Vertices the adaptive methods never move: border ones (Algorithm 2), and
/// those on an edge with more than two triangles or where several fans meet.
fn fixed_vertices(mesh: &Mesh, vtris: &[Vec<u32>]) -> Vec<bool> {
    let mut fixed = boundary_vertices(mesh);
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(mesh.triangles.len() * 3);
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            pairs.push((a.min(b), a.max(b)));
        }
    }
    pairs.sort_unstable();
    for run in pairs.chunk_by(|a, b| a == b) {
        if run.len() > 2 {
            fixed[run[0].0 as usize] = true;
            fixed[run[0].1 as usize] = true;
        }
    }
    for (v, ts) in vtris.iter().enumerate() {
        if !fixed[v] && fan_count(&mesh.triangles, v as u32, ts) > 1 {
            fixed[v] = true;
        }
    }
    fixed
}

/// Algorithm 3: the average normal deviation θ (radians, in [0, π]) of every
/// vertex over its `k_ring`-deep umbrella (k = 0 is treated as 1). A vertex
/// with no triangle gets 0; one whose vertex or region normal vanishes (a
/// fan that folds back on itself) gets π, so it is never removable.
pub fn normal_deviation(mesh: &Mesh, k_ring: usize) -> Vec<f64> {
    let vtris = vertex_triangles(mesh);
    let alive = vec![true; mesh.triangles.len()];
    deviation(
        &mesh.positions,
        &mesh.triangles,
        &alive,
        &vtris,
        None,
        k_ring,
    )
}

/// θ over the live part of a mesh; `only` restricts which vertices are
/// measured (the others get 0).
fn deviation(
    pos: &[[f32; 3]],
    tris: &[[u32; 3]],
    tri_alive: &[bool],
    vtris: &[Vec<u32>],
    only: Option<&[bool]>,
    k_ring: usize,
) -> Vec<f64> {
    let k = k_ring.max(1);
    let normals: Vec<DVec3> = tris
        .par_iter()
        .zip(tri_alive.par_iter())
        .map(|(t, &a)| if a { cross_normal(pos, t) } else { DVec3::ZERO })
        .collect();
    (0..pos.len())
        .into_par_iter()
        .map_init(
            || (Vec::<u32>::new(), Vec::<u32>::new(), Vec::<u32>::new()),
            |(ring, frontier, faces), v| {
                if only.is_some_and(|m| !m[v]) {
                    return 0.0;
                }
                let own: DVec3 = vtris[v]
                    .iter()
                    .filter(|&&t| tri_alive[t as usize])
                    .map(|&t| normals[t as usize].normalize_or_zero())
                    .sum();
                if vtris[v].iter().all(|&t| !tri_alive[t as usize]) {
                    return 0.0;
                }
                ring.clear();
                ring.push(v as u32);
                frontier.clear();
                frontier.push(v as u32);
                faces.clear();
                for _ in 0..k {
                    let mut next: Vec<u32> = Vec::new();
                    for &u in frontier.iter() {
                        for &t in &vtris[u as usize] {
                            if tri_alive[t as usize] {
                                faces.push(t);
                                next.extend_from_slice(&tris[t as usize]);
                            }
                        }
                    }
                    next.sort_unstable();
                    next.dedup();
                    next.retain(|x| ring.binary_search(x).is_err());
                    ring.extend_from_slice(&next);
                    ring.sort_unstable();
                    *frontier = next;
                }
                faces.sort_unstable();
                faces.dedup();
                let region: DVec3 = faces.iter().map(|&t| normals[t as usize]).sum();
                let (a, b) = (own.normalize_or_zero(), region.normalize_or_zero());
                if a == DVec3::ZERO || b == DVec3::ZERO {
                    return std::f64::consts::PI;
                }
                a.dot(b).clamp(-1.0, 1.0).acos()
            },
        )
        .collect()
}

/// The threshold angle of `t` over the θ values `theta` (0 when empty).
/// Non-finite values are ignored.
pub fn threshold_value(theta: &[f64], t: Threshold) -> f64 {
    let vals: Vec<f64> = theta.iter().copied().filter(|x| x.is_finite()).collect();
    if vals.is_empty() {
        return 0.0;
    }
    let n = vals.len() as f64;
    let quantile = |f: f64| {
        let mut s = vals.clone();
        s.sort_unstable_by(f64::total_cmp);
        let f = if f.is_nan() { 0.5 } else { f.clamp(0.0, 1.0) };
        let rank = (f * n).ceil() as usize;
        if rank == 0 {
            // nothing is removable: below the smallest value
            s[0] - 1.0
        } else {
            s[rank - 1]
        }
    };
    match t {
        Threshold::Sigma(s) => {
            let mean = vals.iter().sum::<f64>() / n;
            let var = vals.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n;
            mean + s * var.sqrt()
        }
        Threshold::Median => quantile(0.5),
        Threshold::Fraction(f) => quantile(f),
    }
}

/// Low/high classification: `true` where θ is above the threshold of `t`
/// (high curvature). Returns the flags and the threshold angle.
pub fn classify(theta: &[f64], t: Threshold) -> (Vec<bool>, f64) {
    let limit = threshold_value(theta, t);
    (
        theta.iter().map(|&x| x > limit || x.is_nan()).collect(),
        limit,
    )
}

/// Prepare (as [`crate::simplify()`] does) and run `method`. The triangle
/// target comes from `opts` (`target_triangles` / `target_ratio`); the QEM
/// methods use all of `opts`, the adaptive ones only the target (their
/// border rule is fixed: border vertices never move).
pub fn simplify_method(
    positions: &[[f32; 3]],
    indices: &[u32],
    method: Method,
    opts: &SimplifyOptions,
    adaptive: &AdaptiveOptions,
) -> Result<Adaptive, MeshError> {
    let prepared = prepare(positions, indices)?;
    let mesh = &prepared.mesh;
    let (pm, stats, report) = match method {
        Method::Qem | Method::QemCurvature => {
            let mut s = Simplifier::new(mesh, opts)?;
            let mut theta_max = 0.0;
            if method == Method::QemCurvature {
                let theta = normal_deviation(mesh, adaptive.k_ring);
                theta_max = theta.iter().copied().fold(0.0, f64::max);
                let w = if adaptive.hybrid_weight.is_finite() {
                    adaptive.hybrid_weight.max(0.0)
                } else {
                    DEFAULT_HYBRID_WEIGHT
                };
                let scale = theta
                    .iter()
                    .map(|&t| {
                        if theta_max > 0.0 {
                            (1.0 + w * t / theta_max) as f32
                        } else {
                            1.0
                        }
                    })
                    .collect();
                s.set_cost_scale(scale);
            }
            let stop = s.run();
            let (pm, stats) = s.finish();
            let report = AdaptiveReport {
                method,
                stop: match stop {
                    StopReason::Target => AdaptiveStop::Target,
                    r => AdaptiveStop::Qem(r),
                },
                sweeps: 0,
                operations: stats.collapses,
                threshold: theta_max,
                high_curvature_vertices: 0,
                last_interior: 0,
                last_high: 0,
                last_candidates: 0,
                fixed_vertices: stats.locked_vertices,
                prevented: stats.rejected,
                repaired: Repairs::default(),
            };
            (pm, stats, report)
        }
        Method::Edge | Method::HalfEdge | Method::Triangle => {
            let mut e = Engine::new(
                mesh,
                method,
                adaptive,
                opts.target_for(mesh.triangles.len()),
            );
            e.run();
            e.finish()
        }
    };
    let stop = report.stop.core();
    Ok(Adaptive {
        simplified: Simplified {
            pm,
            vertex_map: prepared.vertex_map,
            triangle_map: prepared.triangle_map,
            prepare: prepared.stats,
            stats,
            stop,
        },
        report,
    })
}

/// [`simplify_method`] without the report: the same [`Simplified`] as
/// [`crate::simplify()`], so levels, glTF and streaming work unchanged.
pub fn simplify_adaptive(
    positions: &[[f32; 3]],
    indices: &[u32],
    method: Method,
    opts: &SimplifyOptions,
    adaptive: &AdaptiveOptions,
) -> Result<Simplified, MeshError> {
    simplify_method(positions, indices, method, opts, adaptive).map(|a| a.simplified)
}

/// The sweep engine: the live mesh (tombstoned triangles, per-vertex
/// triangle lists that keep dead entries until the next sweep so an
/// operation can be rolled back), quadrics (only to record each split's error
/// in the core's units), and the contraction log.
struct Engine {
    method: Method,
    opts: AdaptiveOptions,
    target: usize,
    pos: Vec<[f32; 3]>,
    quadric: Vec<Quadric>,
    tris: Vec<[u32; 3]>,
    tri_alive: Vec<bool>,
    vtris: Vec<Vec<u32>>,
    alive: Vec<bool>,
    fixed: Vec<bool>,
    live_tris: usize,
    log: Log,
    /// `v1`'s quadric before each logged contraction (for rollback).
    saved_quadric: Vec<Quadric>,
    report: AdaptiveReport,
    stats: Stats,
}

impl Engine {
    fn new(mesh: &Mesh, method: Method, opts: &AdaptiveOptions, target: usize) -> Engine {
        let t0 = Instant::now();
        let nv = mesh.positions.len();
        let vtris = vertex_triangles(mesh);
        let fixed = fixed_vertices(mesh, &vtris);
        let mut quadric = vec![Quadric::default(); nv];
        for t in &mesh.triangles {
            let n = cross_normal(&mesh.positions, t);
            let len = n.length();
            if len > 0.0 {
                let unit = n / len;
                let q = Quadric::from_plane(
                    unit,
                    -unit.dot(dv(mesh.positions[t[0] as usize])),
                    0.5 * len,
                );
                for &v in t {
                    quadric[v as usize] += q;
                }
            }
        }
        let fixed_count = fixed.iter().filter(|&&f| f).count();
        let stats = Stats {
            input_vertices: nv,
            input_triangles: mesh.triangles.len(),
            boundary_vertices: boundary_vertices(mesh).iter().filter(|&&b| b).count(),
            locked_vertices: fixed_count,
            time: PhaseTimes {
                setup: t0.elapsed(),
                ..PhaseTimes::default()
            },
            ..Stats::default()
        };
        Engine {
            method,
            opts: *opts,
            target,
            pos: mesh.positions.clone(),
            quadric,
            tris: mesh.triangles.clone(),
            tri_alive: vec![true; mesh.triangles.len()],
            vtris,
            alive: vec![true; nv],
            fixed,
            live_tris: mesh.triangles.len(),
            log: Log::default(),
            saved_quadric: Vec::new(),
            report: AdaptiveReport {
                method,
                stop: AdaptiveStop::Target,
                sweeps: 0,
                operations: 0,
                threshold: 0.0,
                high_curvature_vertices: 0,
                last_interior: 0,
                last_high: 0,
                last_candidates: 0,
                fixed_vertices: fixed_count,
                prevented: Rejections::default(),
                repaired: Repairs::default(),
            },
            stats,
        }
    }

    fn reject(&mut self, r: Rejected) {
        let c = &mut self.report.prevented;
        *match r {
            Rejected::Locked => &mut c.locked,
            Rejected::Link => &mut c.link,
            Rejected::BoundaryPinch => &mut c.boundary_pinch,
            Rejected::Flip => &mut c.flip,
            Rejected::Degenerate => &mut c.degenerate,
            Rejected::Duplicate => &mut c.duplicate,
            Rejected::Error => &mut c.error,
            Rejected::Feature => &mut c.feature,
        } += 1;
    }

    /// Algorithm 1, steps 2–4: classify, decimate, repeat.
    fn run(&mut self) {
        let t0 = Instant::now();
        let mut limit = None;
        loop {
            if self.live_tris <= self.target {
                self.report.stop = AdaptiveStop::Target;
                break;
            }
            for ts in &mut self.vtris {
                ts.retain(|&t| self.tri_alive[t as usize]);
            }
            let movable: Vec<bool> = (0..self.pos.len())
                .map(|v| self.alive[v] && !self.fixed[v] && !self.vtris[v].is_empty())
                .collect();
            let theta = deviation(
                &self.pos,
                &self.tris,
                &self.tri_alive,
                &self.vtris,
                Some(&movable),
                self.opts.k_ring,
            );
            let thr = match (limit, self.opts.reclassify) {
                (Some(l), Reclassify::FixedThreshold) => l,
                _ => {
                    let vals: Vec<f64> = (0..theta.len())
                        .filter(|&v| movable[v])
                        .map(|v| theta[v])
                        .collect();
                    let l = threshold_value(&vals, self.opts.threshold);
                    if limit.is_none() {
                        self.report.threshold = l;
                        self.report.high_curvature_vertices =
                            vals.iter().filter(|&&x| x > l).count();
                    }
                    l
                }
            };
            limit = Some(thr);
            let removable: Vec<bool> = (0..theta.len())
                .map(|v| movable[v] && theta[v] <= thr)
                .collect();
            self.report.last_interior = movable.iter().filter(|&&m| m).count();
            self.report.last_high =
                self.report.last_interior - removable.iter().filter(|&&r| r).count();
            let key = |t: &[u32; 3]| t.iter().map(|&v| theta[v as usize]).fold(0.0, f64::max);
            let mut order: Vec<(f64, u32)> = (0..self.tris.len())
                .filter(|&t| self.tri_alive[t])
                .filter(|&t| {
                    let r = self.tris[t].map(|v| removable[v as usize]);
                    match self.method {
                        Method::Triangle => r.iter().all(|&x| x),
                        // two removable corners make a removable edge
                        _ => r.iter().filter(|&&x| x).count() >= 2,
                    }
                })
                .map(|t| (key(&self.tris[t]), t as u32))
                .collect();
            self.report.last_candidates = order.len();
            if order.is_empty() {
                self.report.stop = AdaptiveStop::Locked;
                break;
            }
            order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            self.report.sweeps += 1;
            let mut touched = vec![false; self.pos.len()];
            let mut done = 0;
            for &(_, t) in &order {
                if self.live_tris <= self.target {
                    break;
                }
                let t = t as usize;
                if !self.tri_alive[t] || self.tris[t].iter().any(|&v| touched[v as usize]) {
                    continue; // deleted, or frozen until the next sweep
                }
                if let Some(s) = self.operate(t, &removable, &theta) {
                    touched[s as usize] = true;
                    done += 1;
                }
            }
            self.report.operations += done;
            if done == 0 {
                self.report.stop = AdaptiveStop::Illegal;
                break;
            }
        }
        self.stats.time.collapse = t0.elapsed();
    }

    /// Apply the method's operator to triangle `t`; returns the surviving
    /// vertex on success.
    fn operate(&mut self, t: usize, removable: &[bool], theta: &[f64]) -> Option<u32> {
        let tri = self.tris[t];
        if self.method == Method::Triangle {
            let [a, b, c] = tri;
            let d =
                (dv(self.pos[a as usize]) + dv(self.pos[b as usize]) + dv(self.pos[c as usize]))
                    / 3.0;
            let mark = self.log.records.len();
            if self.try_contract(a, b, d) && self.try_contract(c, b, d) {
                if self.defects_ok(b, mark) {
                    return Some(b);
                }
            } else {
                self.rollback(mark);
            }
            return None;
        }
        // Edges of the triangle, shortest first (least displacement).
        let mut edges: SmallVec<[(f64, u32, u32); 3]> = (0..3)
            .map(|k| (tri[k], tri[(k + 1) % 3]))
            .filter(|&(x, y)| removable[x as usize] && removable[y as usize])
            .map(|(x, y)| {
                let l = (dv(self.pos[x as usize]) - dv(self.pos[y as usize])).length_squared();
                (l, x, y)
            })
            .collect();
        edges.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then((a.1, a.2).cmp(&(b.1, b.2))));
        for &(_, x, y) in &edges {
            let tries: SmallVec<[(u32, u32, DVec3); 2]> = match self.method {
                Method::Edge => {
                    let mid = (dv(self.pos[x as usize]) + dv(self.pos[y as usize])) * 0.5;
                    smallvec::smallvec![(y, x, mid)]
                }
                // remove the flatter endpoint first (it carries less shape),
                // the other one if that is illegal
                _ => {
                    let (keep, gone) = if theta[x as usize] < theta[y as usize] {
                        (y, x)
                    } else {
                        (x, y)
                    };
                    smallvec::smallvec![
                        (gone, keep, dv(self.pos[keep as usize])),
                        (keep, gone, dv(self.pos[gone as usize]))
                    ]
                }
            };
            for (v0, v1, p) in tries {
                let mark = self.log.records.len();
                if self.try_contract(v0, v1, p) && self.defects_ok(v1, mark) {
                    return Some(v1);
                }
            }
        }
        None
    }

    /// Check and, when legal, contract `v0` into `v1` at `p`.
    fn try_contract(&mut self, v0: u32, v1: u32, p: DVec3) -> bool {
        match self.check(v0, v1, p) {
            Ok(removed) => {
                self.contract(v0, v1, p, removed);
                true
            }
            Err(r) => {
                self.reject(r);
                false
            }
        }
    }

    /// The core's legality rules, in its order: the edge must be interior
    /// with two triangles, link condition, flip ([`FLIP_MIN_COS`](crate::simplify::FLIP_MIN_COS)) and
    /// degeneracy ([`DEGENERATE_AREA_RATIO_SQ`](crate::simplify::DEGENERATE_AREA_RATIO_SQ)) of every moved triangle, no
    /// moved triangle landing on an existing one.
    fn check(&mut self, v0: u32, v1: u32, p: DVec3) -> Result<SmallVec<[u32; 2]>, Rejected> {
        let (i0, i1) = (v0 as usize, v1 as usize);
        if self.fixed[i0] || self.fixed[i1] {
            return Err(Rejected::Locked);
        }
        let faces = Faces {
            tris: &self.tris,
            alive: &self.tri_alive,
            vtris: self.vtris.as_slice(),
            pos: &self.pos,
        };
        let Link {
            shared,
            opposite,
            common,
        } = link(faces, v0, v1);
        if shared.len() != 2 || common != 2 || opposite[0] == opposite[1] {
            return Err(Rejected::Link);
        }
        moved_faces_ok(faces, v0, v1, p, &opposite)?;
        Ok(shared)
    }

    /// Contract `v0` into `v1` at `p` and log it. `v0`'s triangle list is
    /// kept (for rollback); moved triangles are appended to `v1`'s.
    fn contract(&mut self, v0: u32, v1: u32, p: DVec3, removed: SmallVec<[u32; 2]>) {
        let (i0, i1) = (v0 as usize, v1 as usize);
        let q = self.quadric[i0] + self.quadric[i1];
        let cost = q.eval(p);
        let error = if q.weight > 0.0 {
            (cost / q.weight).sqrt()
        } else {
            cost.sqrt()
        };
        let mut record = Contraction {
            v0,
            v1,
            p1: self.pos[i1],
            removed: Removed::new(&removed),
            moved: self.log.mark()..self.log.mark(),
            error: error as f32,
        };
        for &t in &record.removed {
            self.tri_alive[t as usize] = false;
        }
        self.live_tris -= record.removed.len();
        for k in 0..self.vtris[i0].len() {
            let t = self.vtris[i0][k];
            if !self.tri_alive[t as usize] {
                continue;
            }
            let tri = &mut self.tris[t as usize];
            if let Some(slot) = tri.iter().position(|&x| x == v0) {
                tri[slot] = v1;
                self.log.push_corner(Corner {
                    triangle: t,
                    slot: slot as u8,
                });
                self.vtris[i1].push(t);
            }
        }
        self.pos[i1] = fv(p);
        self.saved_quadric.push(self.quadric[i1]);
        self.quadric[i1] = q;
        self.alive[i0] = false;
        record.moved.end = self.log.mark();
        self.log.records.push(record);
    }

    /// Undo the contractions logged after `mark`, newest first.
    fn rollback(&mut self, mark: usize) {
        while self.log.records.len() > mark {
            let Some(c) = self.log.records.last().cloned() else {
                break;
            };
            let (i0, i1) = (c.v0 as usize, c.v1 as usize);
            for k in self.log.moved(&c) {
                self.tris[k.triangle as usize][k.slot as usize] = c.v0;
            }
            self.log.pop();
            let keep = self.vtris[i1].len() - c.moved.len();
            self.vtris[i1].truncate(keep);
            for &t in &c.removed {
                self.tri_alive[t as usize] = true;
            }
            self.live_tris += c.removed.len();
            self.pos[i1] = c.p1;
            self.alive[i0] = true;
            if let Some(q) = self.saved_quadric.pop() {
                self.quadric[i1] = q;
            }
        }
    }

    /// Algorithm 5 after an operation with survivor `s`: look for spikes,
    /// pyramids and reversed faces around it; if any, roll back to `mark`,
    /// count the repair and return false.
    fn defects_ok(&mut self, s: u32, mark: usize) -> bool {
        let live: SmallVec<[u32; 16]> = self.vtris[s as usize]
            .iter()
            .copied()
            .filter(|&t| self.tri_alive[t as usize])
            .collect();
        // spikes: two triangles on the same three vertices
        let mut keys: SmallVec<[[u32; 3]; 16]> = live
            .iter()
            .map(|&t| {
                let mut k = self.tris[t as usize];
                k.sort_unstable();
                k
            })
            .collect();
        keys.sort_unstable();
        if keys.windows(2).any(|w| w[0] == w[1]) {
            self.rollback(mark);
            self.report.repaired.spikes += 1;
            return false;
        }
        // reversed: a face against its umbrella's area-weighted normal
        let normals: SmallVec<[DVec3; 16]> = live
            .iter()
            .map(|&t| cross_normal(&self.pos, &self.tris[t as usize]))
            .collect();
        let umbrella: DVec3 = normals.iter().copied().sum();
        if normals
            .iter()
            .any(|n| n.dot(umbrella) < REVERSED_MAX_COS * n.length() * umbrella.length())
        {
            self.rollback(mark);
            self.report.repaired.reversed += 1;
            return false;
        }
        // pyramids: the survivor or a neighbour left with three faces, one
        // folded over the other two
        let mut ring: SmallVec<[u32; 16]> =
            live.iter().flat_map(|&t| self.tris[t as usize]).collect();
        ring.sort_unstable();
        ring.dedup();
        for &v in &ring {
            if self.fixed[v as usize] {
                continue;
            }
            let fan: SmallVec<[DVec3; 4]> = self.vtris[v as usize]
                .iter()
                .filter(|&&t| self.tri_alive[t as usize])
                .take(4)
                .map(|&t| cross_normal(&self.pos, &self.tris[t as usize]).normalize_or_zero())
                .collect();
            if fan.len() == 3
                && (0..3).any(|i| {
                    let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                    fan[i].dot(fan[j]) < PYRAMID_MAX_COS && fan[i].dot(fan[k]) < PYRAMID_MAX_COS
                })
            {
                self.rollback(mark);
                self.report.repaired.pyramids += 1;
                return false;
            }
        }
        true
    }

    fn finish(mut self) -> (ProgressiveMesh, Stats, AdaptiveReport) {
        let t0 = Instant::now();
        let pm = ProgressiveMesh::from_log(
            &self.pos,
            &self.tris,
            &self.alive,
            &self.tri_alive,
            &self.log,
            None,
        );
        self.stats.collapses = self.log.records.len();
        self.stats.output_triangles = self.live_tris;
        self.stats.output_vertices = pm.base.positions.len();
        self.stats.rejected = self.report.prevented;
        self.stats.time.log = t0.elapsed();
        (pm, self.stats, self.report)
    }
}
