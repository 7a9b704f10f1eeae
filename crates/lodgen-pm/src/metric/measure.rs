//! The error metric: how far apart two triangle meshes are.
//!
//! This module owns surface sampling, the one-sided and symmetric distance statistics
//! (Hausdorff, mean, RMS) and their expression as a percentage of the original's bounding-box
//! diagonal. It takes meshes as plain slices ([`MeshRef`]) so it depends on nothing else in the
//! core; closest-point queries are [`TriangleBvh`]'s. To measure several meshes against one
//! original, [`Reference`] prepares the original once (its hierarchy, its samples' order).
//!
//! Method (after Metro: P. Cignoni, C. Rocchini, R. Scopigno, "Metro: measuring error on
//! simplified surfaces", Computer Graphics Forum 17(2), 1998): the one-sided distance from
//! mesh X to mesh Y is estimated from points of X — area-weighted samples of its surface plus
//! every vertex X's triangles use — each measured exactly against Y's surface
//! (Ericson's closest point on a triangle, over a BVH). The simplification literature often
//! reports one direction only (e.g. the distance of the original's points to the simplified
//! surface); both directions are reported here, and the symmetric value is the larger.
//!
//! Sampling is stratified along the cumulative-area axis: sample `i` of `n` sits at
//! `(i + u_i) / n` of the total area, `u_i` uniform in `[0, 1)`, so each triangle receives its
//! expected share of samples to within one, and within the triangle a uniform random
//! barycentric point. All randomness is SplitMix64 (G. Steele, D. Lea, C. Flood, "Fast
//! splittable pseudorandom number generators", OOPSLA 2014) indexed by sample number, so sample
//! `i` is a pure function of `(seed, i)`.
//!
//! Determinism: samples are processed in fixed chunks of 4,096 consecutive indices; each
//! chunk's sums are computed sequentially and the chunk results are folded in index order. The
//! result is therefore bit-identical whatever the number of rayon threads.

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;
use thiserror::Error;

use super::bounded::{bounded_max, Tolerance};
use super::bvh::TriangleBvh;
pub use super::options::{MeasureOptions, Method};
use super::sampling::{
    area_samples, max_above, measure_points, seek, Partial, SampleSet, Site, Top, MAX_CANDIDATES,
};
use super::triangle::widen;
use super::{prefetch, zorder, MeshError, MeshRef, AHEAD};

/// [`measure`]'s error: which mesh is invalid and why.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum MeasureError {
    #[error("mesh A (the original): {0}")]
    A(MeshError),
    #[error("mesh B: {0}")]
    B(MeshError),
}

/// One-sided distance from the points of one mesh to the surface of another.
///
/// `max` is over every sample (area samples and vertices); `mean` and `rms` are over the
/// area-weighted samples, so they estimate the surface integrals (1/area)∫d and
/// √((1/area)∫d²). When the sampled mesh has no area (only zero-area triangles), `mean` and
/// `rms` are over its vertices instead. From a mesh without triangles (nothing to sample) all
/// three are 0 and `samples` is 0; to a mesh without triangles they are infinite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Distance {
    pub max: f64,
    /// An upper bound on the true maximum over the whole surface: with [`Method::Bounded`]
    /// `max ≤ true maximum ≤ max_bound` (up to rounding); infinite when not known
    /// ([`Method::Sampled`], whose `max` is a lower estimate).
    pub max_bound: f64,
    pub mean: f64,
    pub rms: f64,
    /// Points measured: area samples plus vertices.
    pub samples: usize,
    /// The point of the sampled mesh where `max` was found (`None` when nothing was measured):
    /// where to look for the worst spot of a level.
    pub at: Option<[f64; 3]>,
    /// Other far places: where the max-seeking search's climbs ended ([`Method::Sampled`]).
    pub spots: Spots,
}

/// Where the max-seeking search's climbs ended, each with its distance, farthest first (equal
/// distances in the search's order), at most [`Spots::CAPACITY`]: the local maxima near the
/// farthest samples, which a level with several equal worst spots (a ring of them round a
/// symmetric rim) has several of. Places found twice are kept twice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spots {
    len: u8,
    spots: [([f64; 3], f64); Spots::CAPACITY],
}

impl Spots {
    /// The most kept.
    pub const CAPACITY: usize = 16;

    /// None.
    pub const NONE: Spots = Spots {
        len: 0,
        spots: [([0.0; 3], 0.0); Spots::CAPACITY],
    };

    /// The farthest [`Spots::CAPACITY`] of `ends` (point, distance), farthest first.
    fn farthest(mut ends: Vec<([f64; 3], f64)>) -> Spots {
        ends.sort_by(|x, y| y.1.total_cmp(&x.1));
        let mut out = Spots::NONE;
        for (slot, &e) in out.spots.iter_mut().zip(&ends) {
            *slot = e;
            out.len += 1;
        }
        out
    }

    /// The spots, farthest first.
    pub fn as_slice(&self) -> &[([f64; 3], f64)] {
        &self.spots[..usize::from(self.len)]
    }
}

impl Distance {
    /// No points measured.
    pub const NONE: Distance = Distance {
        max: 0.0,
        max_bound: 0.0,
        mean: 0.0,
        rms: 0.0,
        samples: 0,
        at: None,
        spots: Spots::NONE,
    };
}

/// Distances between an original mesh A and another mesh B (typically a simplification of A).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorReport {
    /// From points of A to the surface of B.
    pub a_to_b: Distance,
    /// From points of B to the surface of A.
    pub b_to_a: Distance,
    /// Bounding-box diagonal of A (the vertices its triangles use), the unit of the percentages.
    pub diagonal: f64,
}

impl ErrorReport {
    /// Symmetric Hausdorff distance: the larger one-sided maximum.
    pub fn hausdorff(&self) -> f64 {
        self.a_to_b.max.max(self.b_to_a.max)
    }

    /// Symmetric mean distance: the larger one-sided mean.
    pub fn mean(&self) -> f64 {
        self.a_to_b.mean.max(self.b_to_a.mean)
    }

    /// Symmetric RMS distance: the larger one-sided RMS.
    pub fn rms(&self) -> f64 {
        self.a_to_b.rms.max(self.b_to_a.rms)
    }

    /// [`Self::hausdorff`] in percent of A's bounding-box diagonal.
    pub fn hausdorff_percent(&self) -> f64 {
        self.percent(self.hausdorff())
    }

    /// [`Self::mean`] in percent of A's bounding-box diagonal.
    pub fn mean_percent(&self) -> f64 {
        self.percent(self.mean())
    }

    /// [`Self::rms`] in percent of A's bounding-box diagonal.
    pub fn rms_percent(&self) -> f64 {
        self.percent(self.rms())
    }

    /// `distance` in percent of A's bounding-box diagonal. With a zero diagonal (A empty or a
    /// single point) a zero distance is 0 % and any other is infinite.
    pub fn percent(&self, distance: f64) -> f64 {
        if self.diagonal > 0.0 {
            100.0 * distance / self.diagonal
        } else if distance == 0.0 {
            0.0
        } else {
            f64::INFINITY
        }
    }
}

/// Measures A (the original) against B both ways. Same as
/// `Reference::new(a)?.measure(b, opts)` (with the errors naming the mesh); use a [`Reference`]
/// to measure several meshes against one A.
///
/// # Errors
/// [`MeasureError`] naming the mesh when either has an out-of-range index or a non-finite
/// position. Meshes without triangles are not errors: see [`Distance`].
pub fn measure(
    a: MeshRef<'_>,
    b: MeshRef<'_>,
    opts: &MeasureOptions,
) -> Result<ErrorReport, MeasureError> {
    a.validate().map_err(MeasureError::A)?;
    b.validate().map_err(MeasureError::B)?;
    Ok(Reference::build_validated(a).measure_validated(b, opts))
}

/// An original mesh A prepared for measuring others against it: its hierarchy (for B→A) and
/// the Z-order of its triangles and vertices (for A→B), both built once. For the levels of one
/// LOD chain this saves a hierarchy build and a sort of A per level; the results are those of
/// [`measure`], bit for bit.
#[derive(Clone, Debug)]
pub struct Reference<'a> {
    mesh: MeshRef<'a>,
    bvh: TriangleBvh,
    samples: SampleSet,
    diagonal: f64,
}

impl<'a> Reference<'a> {
    /// Prepares `a`.
    ///
    /// # Errors
    /// [`MeshError`] when `a` has an out-of-range index or a non-finite position.
    pub fn new(a: MeshRef<'a>) -> Result<Reference<'a>, MeshError> {
        a.validate()?;
        Ok(Self::build_validated(a))
    }

    fn build_validated(a: MeshRef<'a>) -> Reference<'a> {
        // (the sample set after the hierarchy, along its order, not beside
        // it: at 4.4M triangles the two builds' buffers together were the
        // whole run's peak)
        let bvh = TriangleBvh::from_zorder(a, zorder::triangles(a));
        let samples = SampleSet::new(a, bvh.order());
        Reference {
            mesh: a,
            bvh,
            samples,
            diagonal: a.bbox_diagonal(),
        }
    }

    /// The reference of `a`, the same mesh as this one's with its vertices and triangles
    /// renumbered (`vertex_new[v]`, `triangle_new[t]`: the new numbers of this mesh's `v` and
    /// `t`; positions and each triangle's corner order unchanged), without building anything:
    /// what [`Self::new`]`(a)` gives, bit for bit. For a hierarchy built before the numbering
    /// was known (over the welded input, beside its simplification). `None` when `a` is not
    /// that renumbering, or when two triangles' centroids or two vertices share a Morton code
    /// (their order along the curve would follow the new numbering): then build anew.
    pub fn renumbered<'b>(
        self,
        a: MeshRef<'b>,
        vertex_new: &[u32],
        triangle_new: &[u32],
    ) -> Option<Reference<'b>> {
        if !is_renumbering(self.mesh, a, vertex_new, triangle_new) {
            return None;
        }
        Some(Reference {
            mesh: a,
            bvh: self.bvh.renumbered(triangle_new)?,
            samples: self.samples.renumbered(vertex_new)?,
            // (the same positions under the same triangles: the same box)
            diagonal: self.diagonal,
        })
    }

    /// The original's hierarchy.
    pub fn bvh(&self) -> &TriangleBvh {
        &self.bvh
    }

    /// Bounding-box diagonal of the original: the unit of the percentages.
    pub fn diagonal(&self) -> f64 {
        self.diagonal
    }

    /// Measures `b` against the original both ways.
    ///
    /// # Errors
    /// [`MeshError`] when `b` has an out-of-range index or a non-finite position.
    pub fn measure(&self, b: MeshRef<'_>, opts: &MeasureOptions) -> Result<ErrorReport, MeshError> {
        b.validate()?;
        Ok(self.measure_validated(b, opts))
    }

    /// [`Self::measure`] for a validated `b`: B's Z-order once, then A→B (over B's hierarchy,
    /// built from that order) and B→A (B's samples along it), side by side below
    /// [`ONE_AFTER_THE_OTHER`] triangles of B, else B→A first: B's sample set and order are
    /// freed before its hierarchy is built (at 4.4M triangles, the 50 % level's hierarchy
    /// built beside its B→A queries was the whole run's peak). B→A uses a different random
    /// stream than A→B, so that measuring a mesh against itself does not sample the same
    /// points twice. Either way the same reports, bit for bit.
    fn measure_validated(&self, b: MeshRef<'_>, opts: &MeasureOptions) -> ErrorReport {
        self.measure_ordered(b, opts, b.triangles.len() >= ONE_AFTER_THE_OTHER)
    }

    /// [`Self::measure_validated`], B→A before B's hierarchy when `one_after_the_other`.
    fn measure_ordered(
        &self,
        b: MeshRef<'_>,
        opts: &MeasureOptions,
        one_after_the_other: bool,
    ) -> ErrorReport {
        let a = self.mesh;
        let z = zorder::triangles(b);
        let a_to_b = |bvh_b: &TriangleBvh| {
            let plan = Plan::new(opts, a.triangles.len(), b.triangles.len(), self.diagonal);
            measure_from(a, self.bvh.order(), &self.samples, bvh_b, &plan)
        };
        let b_to_a = |order: &[u32], samples_b: &SampleSet| {
            let mut plan = Plan::new(opts, b.triangles.len(), a.triangles.len(), self.diagonal);
            plan.seed ^= 0xb5ad_4ece_da1c_e2a9;
            measure_from(b, order, samples_b, &self.bvh, &plan)
        };
        let (a_to_b, b_to_a) = if one_after_the_other {
            let b_to_a = b_to_a(&z.ids, &SampleSet::new(b, &z.ids));
            (a_to_b(&TriangleBvh::from_zorder(b, z)), b_to_a)
        } else {
            let order = z.ids.clone();
            // (B's sample set first: its sort's buffers beside B's hierarchy build were the
            // measurement's peak)
            let samples_b = SampleSet::new(b, &order);
            rayon::join(
                || a_to_b(&TriangleBvh::from_zorder(b, z)),
                || b_to_a(&order, &samples_b),
            )
        };
        ErrorReport {
            a_to_b,
            b_to_a,
            diagonal: self.diagonal,
        }
    }
}

/// From this many triangles of B on, [`Reference::measure`] measures B→A before it builds
/// B's hierarchy for A→B instead of beside it (peak memory: B's order and sample set, 14
/// bytes a triangle, are freed before B's hierarchy, ≈ 55 bytes a triangle, is built; the
/// queries of each direction run on every core anyway). Smaller levels keep the overlap of
/// the hierarchy's sequential steps with the queries.
const ONE_AFTER_THE_OTHER: usize = 1 << 20;

/// Whether `b` is `a` renumbered: `vertex_new` and `triangle_new` are one-to-one onto `b`'s
/// vertices and triangles, each vertex keeps its position bits and each triangle its corners
/// in order.
fn is_renumbering(
    a: MeshRef<'_>,
    b: MeshRef<'_>,
    vertex_new: &[u32],
    triangle_new: &[u32],
) -> bool {
    let (nv, nt) = (a.positions.len(), a.triangles.len());
    if b.positions.len() != nv
        || b.triangles.len() != nt
        || vertex_new.len() != nv
        || triangle_new.len() != nt
    {
        return false;
    }
    // (in parallel: the numberings scatter every read over both meshes; the
    // answer does not depend on the order the entries are checked in)
    let bits = |p: [f32; 3]| p.map(f32::to_bits);
    let seen: Vec<AtomicBool> = (0..nv).map(|_| AtomicBool::new(false)).collect();
    let vertices_ok = vertex_new.par_iter().enumerate().all(|(v, &n)| {
        let n = n as usize;
        n < nv
            && !seen[n].swap(true, Ordering::Relaxed)
            && bits(b.positions[n]) == bits(a.positions[v])
    });
    if !vertices_ok {
        return false;
    }
    let seen: Vec<AtomicBool> = (0..nt).map(|_| AtomicBool::new(false)).collect();
    triangle_new.par_iter().enumerate().all(|(t, &n)| {
        let n = n as usize;
        let corners = a.triangles[t].map(|v| vertex_new.get(v as usize).copied());
        n < nt && !seen[n].swap(true, Ordering::Relaxed) && corners == b.triangles[n].map(Some)
    })
}

/// One-sided distance from the points of `from` to the surface in `to`, with
/// `opts.area_sample_count(from.triangles.len(), to.len())` area samples.
///
/// # Errors
/// [`MeshError`] when `from` is invalid.
pub fn one_sided(
    from: MeshRef<'_>,
    to: &TriangleBvh,
    opts: &MeasureOptions,
) -> Result<Distance, MeshError> {
    from.validate()?;
    let plan = Plan::new(opts, from.triangles.len(), to.len(), from.bbox_diagonal());
    let order = zorder::triangles(from).ids;
    let set = SampleSet::new(from, &order);
    Ok(measure_from(from, &order, &set, to, &plan))
}

/// How one direction is measured: the options and what they come to for two meshes.
#[derive(Clone, Copy, Debug)]
struct Plan {
    method: Method,
    area_samples: usize,
    vertex_samples: bool,
    /// Candidates of the max-seeking search and points it may measure per candidate.
    seek: usize,
    seek_budget: usize,
    /// The sampled mesh has at most a quarter of the other's triangles: its triangles'
    /// centroids and its edges' midpoints are measured too (for the maximum).
    coarse: bool,
    seed: u64,
    tolerance: Tolerance,
}

impl Plan {
    /// The plan for measuring from a mesh of `tris_from` triangles to one of `tris_to`,
    /// `diagonal` being the original's.
    fn new(opts: &MeasureOptions, tris_from: usize, tris_to: usize, diagonal: f64) -> Plan {
        let nonneg = |x: f64| if x > 0.0 { x } else { 0.0 };
        Plan {
            method: opts.method,
            area_samples: opts.area_sample_count(tris_from, tris_to),
            vertex_samples: opts.vertex_samples,
            seek: opts.seek_candidates.min(MAX_CANDIDATES),
            seek_budget: opts.seek_budget,
            coarse: opts.seek_candidates > 0 && tris_from.saturating_mul(4) <= tris_to,
            seed: opts.seed,
            tolerance: Tolerance {
                relative: nonneg(opts.tolerance),
                absolute: nonneg(opts.absolute_tolerance) * diagonal,
            },
        }
    }
}

/// Mean and RMS of the distances summed in `stats` (0 without points).
fn mean_rms(stats: &Partial) -> (f64, f64) {
    if stats.count > 0 {
        let n = stats.count as f64;
        (stats.sum / n, (stats.sum2 / n).sqrt())
    } else {
        (0.0, 0.0)
    }
}

/// The one-sided measurement from the validated mesh `from`, whose triangles' Z-order is
/// `order` and [`SampleSet`] `set`, to the surface in `to`.
fn measure_from(
    from: MeshRef<'_>,
    order: &[u32],
    set: &SampleSet,
    to: &TriangleBvh,
    plan: &Plan,
) -> Distance {
    if from.triangles.is_empty() {
        return Distance::NONE;
    }
    let area = area_samples(from, order, set, to, plan.area_samples, plan.seed);
    let vertex = |i: usize, _: &mut usize| {
        if let Some(&w) = set.vertices.get(i + AHEAD) {
            prefetch(from.positions, w as usize);
        }
        let v = set.vertices[i];
        (widen(from.positions[v as usize]), Site::Vertex(v))
    };
    if plan.method == Method::Bounded {
        // without area (only zero-area triangles) mean and RMS are over the vertices
        let stats = if area.count > 0 {
            area
        } else {
            measure_points(set.vertices.len(), to, vertex)
        };
        let max = bounded_max(from, order, to, stats.max2, plan.tolerance);
        let (mean, rms) = mean_rms(&stats);
        return Distance {
            max: max.max2.sqrt(),
            max_bound: max.bound2.sqrt(),
            mean,
            rms,
            samples: stats.count + max.queries,
            at: max.at.or(stats.at),
            spots: Spots::NONE,
        };
    }
    let vertices = if plan.vertex_samples {
        if area.count > 0 {
            // Vertices only count towards the maximum: those nearer than it need not be
            // measured exactly (see `max_above`).
            max_above(set.vertices.len(), to, area.max2, vertex)
        } else {
            measure_points(set.vertices.len(), to, vertex)
        }
    } else {
        Partial::ZERO
    };
    let (mean, rms) = mean_rms(if area.count > 0 { &area } else { &vertices });
    // max_above starts at the area maximum and records a place only above it
    let mut best = area;
    if vertices.at.is_some() && (vertices.max2 > area.max2 || area.at.is_none()) {
        best.max2 = vertices.max2;
        best.at = vertices.at;
    }
    let mut samples = area.count + vertices.count;
    let mut vertices = vertices;
    if plan.coarse && area.count > 0 {
        coarse_points(from, order, to, &mut best, &mut samples, &mut vertices.top);
    }
    let mut spots = Spots::NONE;
    if plan.seek > 0 && area.count > 0 && best.max2 > 0.0 {
        let top = area.top.merge_top(&vertices.top);
        let n = plan.seek.min(top.as_slice().len());
        let (found, ends) = seek(from, to, &top.as_slice()[..n], best.max2, plan.seek_budget);
        samples += found.count;
        raise(&mut best, &found);
        spots = Spots::farthest(ends);
    }
    Distance {
        max: best.max2.sqrt(),
        max_bound: f64::INFINITY,
        mean,
        rms,
        samples,
        at: best.at,
        spots,
    }
}

/// A coarse mesh's centroids and edge midpoints measured for the maximum, above `best` (which
/// they raise, adding their count to `samples` and their farthest points to `top`).
fn coarse_points(
    from: MeshRef<'_>,
    order: &[u32],
    to: &TriangleBvh,
    best: &mut Partial,
    samples: &mut usize,
    top: &mut Top,
) {
    // maxima of a coarse mesh's distance sit inside its large triangles: one point each
    let centroid = |i: usize, _: &mut usize| {
        from.prefetch_along(order, i);
        let tri = order[i];
        let [a, b, c] = from.triangles[tri as usize].map(|v| widen(from.positions[v as usize]));
        let p = std::array::from_fn(|j| (a[j] + b[j] + c[j]) / 3.0);
        let third = 1.0 / 3.0;
        (
            p,
            Site::Area {
                tri,
                u: third,
                v: third,
            },
        )
    };
    let found = max_above(order.len(), to, best.max2, centroid);
    *samples += found.count;
    raise(best, &found);
    *top = top.merge_top(&found.top);
    // and on its edges, where two of its faces meet at a crease that crosses the other
    // surface (bunny 10 %: the maximum halfway along an edge whose corners are 6× nearer,
    // between the area samples): each edge's midpoint, once (the triangle that has it in
    // ascending order; a border edge seen only descending is left out)
    let edges: Vec<u32> = (0..3 * order.len() as u32)
        .filter(|&e| {
            let t = from.triangles[order[e as usize / 3] as usize];
            t[e as usize % 3] < t[(e as usize + 1) % 3]
        })
        .collect();
    let midpoint = |i: usize, _: &mut usize| {
        let e = edges[i] as usize;
        let tri = order[e / 3];
        let t = from.triangles[tri as usize];
        let (k, next) = (e % 3, (e + 1) % 3);
        let (a, b) = (
            widen(from.positions[t[k] as usize]),
            widen(from.positions[t[next] as usize]),
        );
        let p = std::array::from_fn(|j| 0.5 * (a[j] + b[j]));
        let (u, v) = [(0.5, 0.0), (0.5, 0.5), (0.0, 0.5)][k];
        (p, Site::Area { tri, u, v })
    };
    let found = max_above(edges.len(), to, best.max2, midpoint);
    *samples += found.count;
    raise(best, &found);
    *top = top.merge_top(&found.top);
}

/// `best`'s maximum and its place raised to `found`'s when `found` measured a farther point.
fn raise(best: &mut Partial, found: &Partial) {
    if found.at.is_some() && found.max2 > best.max2 {
        best.max2 = found.max2;
        best.at = found.at;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    /// A coarse mesh's maximum that sits halfway along an edge, over a pit of the other mesh
    /// that no area sample, vertex or centroid comes near, is found: B is a unit square of
    /// two triangles, A the same square with a hole of half-width `r` around the middle of
    /// B's diagonal, so B → A is 0 but over the hole, where it peaks at `r` on the
    /// diagonal's midpoint (without the edge midpoints the measurement reports 0).
    #[test]
    fn a_coarse_mesh_is_measured_at_its_edges_midpoints() {
        let r = 0.005_f32;
        let (lo, hi) = (0.5 - r, 0.5 + r);
        let outer = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let inner = [[lo, lo, 0.0], [hi, lo, 0.0], [hi, hi, 0.0], [lo, hi, 0.0]];
        let a_pos: Vec<[f32; 3]> = outer.iter().chain(&inner).copied().collect();
        let a_tris: Vec<[u32; 3]> = (0..4u32)
            .flat_map(|i| {
                let j = (i + 1) % 4;
                [[i, j, 4 + j], [i, 4 + j, 4 + i]]
            })
            .collect();
        let b_tris = [[0, 1, 2], [0, 2, 3]];
        let e = measure(
            MeshRef::new(&a_pos, &a_tris),
            MeshRef::new(&outer, &b_tris),
            &MeasureOptions::DEFAULT,
        )
        .unwrap();
        assert!(e.a_to_b.max < 1e-12, "{e:?}");
        let at = e.b_to_a.at.unwrap();
        // (the hole's half-width as the f32 corners hold it)
        let half = 0.5 - f64::from(lo);
        assert!((e.b_to_a.max - half).abs() < 1e-12, "{e:?}");
        assert!(
            (at[0] - 0.5).abs() < 1e-9 && (at[1] - 0.5).abs() < 1e-9,
            "{at:?}"
        );
    }

    /// B→A measured before B's hierarchy is built gives the reports of the two measured side
    /// by side, bit for bit, with the default options and the bounded maximum (fails when the
    /// sequential order swaps the directions' random streams or their meshes).
    #[test]
    fn one_after_the_other_measures_as_side_by_side() {
        let a = shapes::torus_knot(2, 3, 180, 24, 0.01);
        let b = shapes::torus_knot(2, 3, 60, 10, 0.0);
        let r = Reference::new(MeshRef::new(&a.positions, &a.triangles)).unwrap();
        let mb = MeshRef::new(&b.positions, &b.triangles);
        for opts in [
            MeasureOptions::DEFAULT,
            MeasureOptions::DEFAULT.with_method(crate::metric::Method::Bounded),
        ] {
            let side = r.measure_ordered(mb, &opts, false);
            let after = r.measure_ordered(mb, &opts, true);
            assert_eq!(format!("{side:?}"), format!("{after:?}"));
            assert!(side.a_to_b.max > 0.0 && side.b_to_a.max > 0.0);
        }
    }
}
