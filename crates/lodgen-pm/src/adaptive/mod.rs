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
//!
//! ```
//! use lodgen_pm::{shapes, simplify_method, AdaptiveOptions, Method, SimplifyOptions};
//! let m = shapes::torus(1.0, 0.3, 48, 24);
//! let opts = SimplifyOptions::DEFAULT.with_target_ratio(0.5);
//! let out = simplify_method(&m.positions, &m.indices(), Method::Edge, &opts, &AdaptiveOptions::DEFAULT)
//!     .unwrap();
//! assert!(out.report.sweeps > 0);
//! assert!(out.simplified.pm.base.triangles.len() < m.triangles.len());
//! ```

mod curvature;
mod options;
mod sweep;

pub use curvature::{boundary_vertices, classify, normal_deviation, threshold_value};
pub use options::{
    Adaptive, AdaptiveOptions, AdaptiveReport, AdaptiveStop, Method, Reclassify, Repairs,
    Threshold, DEFAULT_HYBRID_WEIGHT, DEFAULT_K_RING, DEFAULT_SIGMA, PYRAMID_MAX_COS,
    REVERSED_MAX_COS,
};

use crate::mesh::{prepare, MeshError};
use crate::simplify::SimplifyOptions;
use crate::simplify::{Simplifier, StopReason};
use crate::Simplified;
use sweep::Engine;

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
