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

use rayon::prelude::*;
use thiserror::Error;

use super::bounded::{bounded_max, Tolerance};
use super::bvh::TriangleBvh;
pub use super::options::{MeasureOptions, Method};
use super::triangle::widen;
use super::{MeshError, MeshRef};

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
    // A→B needs only B's hierarchy, so it runs while A's (usually the larger) is being built.
    let (reference, a_to_b) = rayon::join(
        || Reference::build_validated(a),
        || {
            let samples_a = SampleSet::new(a);
            let bvh_b = TriangleBvh::build_validated(b);
            let plan = Plan::new(
                opts,
                a.triangles.len(),
                b.triangles.len(),
                a.bbox_diagonal(),
            );
            measure_from(a, &samples_a, &bvh_b, &plan)
        },
    );
    let b_to_a = reference.b_to_a(b, opts);
    Ok(ErrorReport {
        a_to_b,
        b_to_a,
        diagonal: reference.diagonal,
    })
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
        let (bvh, samples) = rayon::join(|| TriangleBvh::build_validated(a), || SampleSet::new(a));
        Reference {
            mesh: a,
            bvh,
            samples,
            diagonal: a.bbox_diagonal(),
        }
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
        let a = self.mesh;
        let (a_to_b, b_to_a) = rayon::join(
            || {
                let bvh_b = TriangleBvh::build_validated(b);
                let plan = Plan::new(opts, a.triangles.len(), b.triangles.len(), self.diagonal);
                measure_from(a, &self.samples, &bvh_b, &plan)
            },
            || self.b_to_a(b, opts),
        );
        Ok(ErrorReport {
            a_to_b,
            b_to_a,
            diagonal: self.diagonal,
        })
    }

    /// B→A for a validated `b`. A different random stream than A→B, so that measuring a mesh
    /// against itself does not sample the same points twice.
    fn b_to_a(&self, b: MeshRef<'_>, opts: &MeasureOptions) -> Distance {
        let mut plan = Plan::new(
            opts,
            self.mesh.triangles.len(),
            b.triangles.len(),
            self.diagonal,
        );
        plan.seed ^= 0xb5ad_4ece_da1c_e2a9;
        measure_from(b, &SampleSet::new(b), &self.bvh, &plan)
    }
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
    Ok(measure_from(from, &SampleSet::new(from), to, &plan))
}

/// Sample indices per unit of parallel work. Fixed (never derived from the thread count), so
/// the summation order is fixed. 4096 queries take ~1 ms: coarse enough to amortise rayon's
/// overhead, fine enough to balance 2–16 threads on 10⁵ samples.
const CHUNK: usize = 4096;

/// Sums over one chunk of samples.
#[derive(Clone, Copy, Debug)]
struct Partial {
    max2: f64,
    /// Where `max2` was found.
    at: Option<[f64; 3]>,
    sum: f64,
    sum2: f64,
    count: usize,
}

impl Partial {
    const ZERO: Partial = Partial {
        max2: 0.0,
        at: None,
        sum: 0.0,
        sum2: 0.0,
        count: 0,
    };

    #[inline]
    fn add(&mut self, d2: f64, p: [f64; 3]) {
        if d2 > self.max2 || self.at.is_none() {
            self.max2 = d2;
            self.at = Some(p);
        }
        self.sum += d2.sqrt();
        self.sum2 += d2;
        self.count += 1;
    }

    /// Folds `o` in; on equal maxima the earlier chunk's place stays (chunks fold in order).
    fn merge(mut self, o: Partial) -> Partial {
        if o.max2 > self.max2 || (self.at.is_none() && o.max2 >= self.max2) {
            self.max2 = o.max2;
            self.at = o.at;
        }
        self.sum += o.sum;
        self.sum2 += o.sum2;
        self.count += o.count;
        self
    }
}

/// Measures `count` points given by `point(i, cursor)` against `to`, in fixed chunks folded in
/// order. `cursor` is per-chunk scratch for `point`, `usize::MAX` at the start of each chunk.
fn measure_points(
    count: usize,
    to: &TriangleBvh,
    point: impl Fn(usize, &mut usize) -> [f64; 3] + Sync,
) -> Partial {
    let chunks = count.div_ceil(CHUNK);
    let partials: Vec<Partial> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut acc = Partial::ZERO;
            let mut hint = None;
            let mut cursor = usize::MAX;
            for i in c * CHUNK..((c + 1) * CHUNK).min(count) {
                let p = point(i, &mut cursor);
                let Some((d2, slot, _)) = to.closest_slot(p, hint) else {
                    acc.add(f64::INFINITY, p);
                    continue;
                };
                hint = Some(slot);
                acc.add(d2, p);
            }
            acc
        })
        .collect();
    partials.into_iter().fold(Partial::ZERO, Partial::merge)
}

/// Like [`measure_points`] when only the maximum of the squared distances matters and it is at
/// least `floor`: `max2` is the exact maximum of `floor` and every point's squared distance,
/// `count` the number of points; `sum` and `sum2` are left at 0. A point whose distance to the
/// previous answer's triangle is already at most the running maximum is settled by that one
/// triangle test. Chunks as in [`measure_points`], so the result does not depend on the number
/// of threads (a maximum does not depend on the order anyway).
fn max_above(
    count: usize,
    to: &TriangleBvh,
    floor: f64,
    point: impl Fn(usize, &mut usize) -> [f64; 3] + Sync,
) -> Partial {
    let chunks = count.div_ceil(CHUNK);
    let partials: Vec<Partial> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut acc = Partial {
                max2: floor,
                ..Partial::ZERO
            };
            if to.is_empty() {
                acc.max2 = f64::INFINITY;
            }
            let mut hint = None;
            let mut cursor = usize::MAX;
            let range = c * CHUNK..((c + 1) * CHUNK).min(count);
            acc.count = range.len();
            for i in range {
                let p = point(i, &mut cursor);
                let (d2, h) = to.farther_than(p, acc.max2, hint);
                hint = h;
                if let Some(d2) = d2 {
                    acc.max2 = d2;
                    acc.at = Some(p);
                }
            }
            acc
        })
        .collect();
    partials.into_iter().fold(
        Partial {
            max2: floor,
            ..Partial::ZERO
        },
        Partial::merge,
    )
}

/// SplitMix64 output number `k` of the stream that starts at `seed`.
#[inline]
fn splitmix64(seed: u64, k: u64) -> u64 {
    let mut z = seed.wrapping_add(k.wrapping_add(1).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Uniform in `[0, 1)` with 53 random bits.
#[inline]
fn unit(x: u64) -> f64 {
    (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Area of triangle `t` of a validated mesh.
fn triangle_area(mesh: MeshRef<'_>, t: [u32; 3]) -> f64 {
    let [a, b, c] = t.map(|v| widen(mesh.positions[v as usize]));
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

/// Spreads the low 21 bits of `x` to every third bit (Morton code helper).
fn spread3(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | x << 32) & 0x001f_0000_0000_ffff;
    x = (x | x << 16) & 0x001f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// Morton (Z-order) codes of points quantised on a 2²¹ grid over the box `lo..hi`.
fn morton(p: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> u64 {
    let q = |k: usize| {
        let extent = hi[k] - lo[k];
        if extent > 0.0 {
            (((p[k] - lo[k]) / extent) * 2_097_151.0) as u64
        } else {
            0
        }
    };
    spread3(q(0)) | spread3(q(1)) << 1 | spread3(q(2)) << 2
}

/// Sorts `items` (vertex or triangle ids) along the Z-order curve through `key(id)`, ties by id.
fn z_order(items: &mut [u32], key: impl Fn(u32) -> [f64; 3], lo: [f64; 3], hi: [f64; 3]) {
    let mut keyed: Vec<(u64, u32)> = items.iter().map(|&i| (morton(key(i), lo, hi), i)).collect();
    keyed.sort_unstable();
    for (dst, (_, i)) in items.iter_mut().zip(keyed) {
        *dst = i;
    }
}

/// Where the samples of a mesh come from: its triangles along a Z-order curve with their
/// cumulative areas, and the vertices its triangles use, in Z-order. Depends only on the mesh.
#[derive(Clone, Debug)]
struct SampleSet {
    /// Triangle ids along the curve.
    order: Vec<u32>,
    /// Cumulative area along `order`, summed sequentially (deterministic).
    cumulative: Vec<f64>,
    /// Used vertices along the curve.
    vertices: Vec<u32>,
}

impl SampleSet {
    /// Triangles and vertices of `mesh` (validated) are put along a Z-order curve, so
    /// consecutive samples are near each other: the previous answer is a tight first bound for
    /// the next query (and its BVH path is in cache), and stratifying along the curve spreads
    /// the samples evenly over the surface.
    fn new(mesh: MeshRef<'_>) -> SampleSet {
        let nt = mesh.triangles.len();
        let corners =
            |t: u32| mesh.triangles[t as usize].map(|v| widen(mesh.positions[v as usize]));
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let mut used = vec![false; mesh.positions.len()];
        for t in mesh.triangles {
            for &v in t {
                used[v as usize] = true;
                let p = widen(mesh.positions[v as usize]);
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        let mut order: Vec<u32> = (0..nt as u32).collect();
        z_order(
            &mut order,
            |t| {
                let [a, b, c] = corners(t);
                std::array::from_fn(|k| (a[k] + b[k] + c[k]) / 3.0)
            },
            lo,
            hi,
        );
        let mut cumulative = Vec::with_capacity(nt);
        let mut total = 0.0f64;
        for &t in &order {
            total += triangle_area(mesh, mesh.triangles[t as usize]);
            cumulative.push(total);
        }
        let mut vertices: Vec<u32> = (0..mesh.positions.len() as u32)
            .filter(|&v| used[v as usize])
            .collect();
        z_order(&mut vertices, |v| widen(mesh.positions[v as usize]), lo, hi);
        SampleSet {
            order,
            cumulative,
            vertices,
        }
    }
}

/// How one direction is measured: the options and what they come to for two meshes.
#[derive(Clone, Copy, Debug)]
struct Plan {
    method: Method,
    area_samples: usize,
    vertex_samples: bool,
    seed: u64,
    tolerance: Tolerance,
}

impl Plan {
    /// The plan for meshes of `tris_a` and `tris_b` triangles, `diagonal` being the original's.
    fn new(opts: &MeasureOptions, tris_a: usize, tris_b: usize, diagonal: f64) -> Plan {
        let nonneg = |x: f64| if x > 0.0 { x } else { 0.0 };
        Plan {
            method: opts.method,
            area_samples: opts.area_sample_count(tris_a, tris_b),
            vertex_samples: opts.vertex_samples,
            seed: opts.seed,
            tolerance: Tolerance {
                relative: nonneg(opts.tolerance),
                absolute: nonneg(opts.absolute_tolerance) * diagonal,
            },
        }
    }
}

/// The one-sided measurement from the validated mesh `from`, whose [`SampleSet`] is `set`, to
/// the surface in `to`.
fn measure_from(from: MeshRef<'_>, set: &SampleSet, to: &TriangleBvh, plan: &Plan) -> Distance {
    if from.triangles.is_empty() {
        return Distance::NONE;
    }
    let area = area_samples(from, set, to, plan.area_samples, plan.seed);
    let vertex = |i: usize, _: &mut usize| widen(from.positions[set.vertices[i] as usize]);
    let stats_of = |stats: &Partial| {
        if stats.count > 0 {
            let n = stats.count as f64;
            (stats.sum / n, (stats.sum2 / n).sqrt())
        } else {
            (0.0, 0.0)
        }
    };
    if plan.method == Method::Bounded {
        // without area (only zero-area triangles) mean and RMS are over the vertices
        let stats = if area.count > 0 {
            area
        } else {
            measure_points(set.vertices.len(), to, vertex)
        };
        let max = bounded_max(from, &set.order, to, stats.max2, plan.tolerance);
        let (mean, rms) = stats_of(&stats);
        return Distance {
            max: max.max2.sqrt(),
            max_bound: max.bound2.sqrt(),
            mean,
            rms,
            samples: stats.count + max.queries,
            at: max.at.or(stats.at),
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
    let (mean, rms) = stats_of(if area.count > 0 { &area } else { &vertices });
    // max_above starts at the area maximum and records a place only above it
    let at = match vertices.at {
        Some(p) if vertices.max2 > area.max2 || area.at.is_none() => Some(p),
        _ => area.at,
    };
    Distance {
        max: area.max2.max(vertices.max2).sqrt(),
        max_bound: f64::INFINITY,
        mean,
        rms,
        samples: area.count + vertices.count,
        at,
    }
}

/// `count` stratified area samples of the validated, non-empty mesh `from` (whose
/// [`SampleSet`] is `set`) measured against `to`; none when `from` has no area.
fn area_samples(
    from: MeshRef<'_>,
    set: &SampleSet,
    to: &TriangleBvh,
    count: usize,
    seed: u64,
) -> Partial {
    let nt = from.triangles.len();
    let corners = |t: u32| from.triangles[t as usize].map(|v| widen(from.positions[v as usize]));
    let (order, cumulative) = (&set.order, &set.cumulative);
    let total = cumulative.last().copied().unwrap_or(0.0);
    let count = if total > 0.0 { count } else { 0 };
    measure_points(count, to, |i, cursor| {
        let k = 3 * i as u64;
        let s = (i as f64 + unit(splitmix64(seed, k))) / count as f64 * total;
        // Position along the curve: the first triangle whose cumulative area exceeds s (so
        // zero-area triangles are never chosen). Positions rise within a chunk, so after one
        // binary search per chunk the cursor only walks forward.
        if *cursor == usize::MAX {
            *cursor = cumulative.partition_point(|&c| c <= s);
        }
        while *cursor < nt - 1 && cumulative[*cursor] <= s {
            *cursor += 1;
        }
        let at = (*cursor).min(nt - 1);
        let [a, b, c] = corners(order[at]);
        let mut r1 = unit(splitmix64(seed, k + 1));
        let mut r2 = unit(splitmix64(seed, k + 2));
        if r1 + r2 > 1.0 {
            // Fold the unit square's upper half onto the lower: uniform on the triangle.
            r1 = 1.0 - r1;
            r2 = 1.0 - r2;
        }
        std::array::from_fn(|j| a[j] + r1 * (b[j] - a[j]) + r2 * (c[j] - a[j]))
    })
}
