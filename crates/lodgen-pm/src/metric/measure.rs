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

use super::bvh::TriangleBvh;
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

/// Options of the metric.
///
/// Default sampling: 2 area samples per triangle of the larger mesh, in each direction, at
/// least 10,000. For the bunny (69,451 triangles) against any coarser level that is 138,902
/// area samples per direction plus the vertices (34,834 on the original side), about 310,000
/// distance queries in all. Why 2: the samples are then about half the finer mesh's mean edge
/// length apart (an equilateral triangle of edge e holding 2 samples gives a spacing of
/// √(0.433e²/2) ≈ 0.47e), so any feature the fine mesh can represent is hit by several samples.
/// Measured on the bunny against a 1,454-triangle clustering of it (example `measure_bunny`):
/// RMS is 0.4709 % of the diagonal at 2 per triangle and 0.4710 % at 32; the Hausdorff estimate
/// is 2.56 % at 2 and 2.62 % at 32 (a maximum over samples only creeps up with density), for
/// 16 times the cost.
///
/// Huge meshes: above [`Self::full_rate_triangles`] triangles the area samples grow with the
/// square root of the triangle count instead (see [`Self::area_sample_count`]): 1.08 M per
/// direction for the 1.1 M-triangle subdivided bunny instead of 2.2 M, 2.2 M for 4.4 M triangles
/// instead of 8.9 M. Every vertex is still measured. What this can miss: in the original → level
/// direction little, since the distance from a point of a fine flat triangle to the nearest
/// triangle of the level is convex along it and so peaks at a vertex, all of which are measured;
/// in the level → original direction, a spike or pit of the original narrower than the sample
/// spacing (√(area / samples), about 1.4 fine-triangle edges at 4.4 M) and away from the level's
/// vertices, so the Hausdorff figure of such a mesh is a slightly lower estimate. Set
/// `full_rate_triangles` to `usize::MAX` for the full rate at any size.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct MeasureOptions {
    /// Area samples per direction, per triangle of the mesh with more triangles. Negative or
    /// NaN counts as 0.
    ///
    /// Default value: 2.0.
    pub samples_per_triangle: f64,
    /// Lower bound on the area samples per direction, so that tiny meshes (a 12-triangle cube)
    /// are still sampled densely.
    ///
    /// Default value: 10,000.
    pub min_samples: usize,
    /// Cap on that lower bound, per triangle of the larger mesh: a 12-triangle card is sampled
    /// 768 times per direction, not 10,000 (plus every vertex). 64 samples per triangle put
    /// the spacing at an eighth of the triangle's size; without the cap a scene of many small
    /// meshes (a game level: 947 of 1,000 meshes under 157 triangles) spent ~60 % of its run
    /// measuring them. The cap changes nothing from 157 triangles up.
    /// [`MeasureOptions::with_min_samples`] removes it (an explicit bound is taken as given).
    ///
    /// Default value: 64.0.
    pub min_samples_per_triangle: f64,
    /// Triangle count (of the larger mesh) up to which area samples are
    /// `samples_per_triangle` per triangle; above it they grow with the square root of the
    /// count (see the type's documentation for what that can miss).
    ///
    /// Default value: 262,144 (2¹⁸).
    pub full_rate_triangles: usize,
    /// Also measure from every vertex the sampled mesh's triangles use (counted in the maximum
    /// only, see [`Distance`]). Vertices are where a fine mesh's extremes usually are.
    ///
    /// Default value: true.
    pub vertex_samples: bool,
    /// Seed of the sample positions. Results are a pure function of the meshes and the options.
    ///
    /// Default value: `0x6c6f_6467_656e` ("lodgen").
    pub seed: u64,
}

impl MeasureOptions {
    pub const DEFAULT: MeasureOptions = MeasureOptions {
        samples_per_triangle: 2.0,
        min_samples: 10_000,
        min_samples_per_triangle: 64.0,
        full_rate_triangles: 1 << 18,
        vertex_samples: true,
        seed: 0x6c6f_6467_656e,
    };

    pub fn with_samples_per_triangle(mut self, samples_per_triangle: f64) -> Self {
        self.samples_per_triangle = samples_per_triangle;
        self
    }

    /// At least `min_samples` area samples per direction, whatever the meshes' size (the
    /// per-triangle cap, [`MeasureOptions::min_samples_per_triangle`], is lifted).
    pub fn with_min_samples(mut self, min_samples: usize) -> Self {
        self.min_samples = min_samples;
        self.min_samples_per_triangle = f64::INFINITY;
        self
    }

    pub fn with_min_samples_per_triangle(mut self, min_samples_per_triangle: f64) -> Self {
        self.min_samples_per_triangle = min_samples_per_triangle;
        self
    }

    pub fn with_full_rate_triangles(mut self, full_rate_triangles: usize) -> Self {
        self.full_rate_triangles = full_rate_triangles;
        self
    }

    pub fn with_vertex_samples(mut self, vertex_samples: bool) -> Self {
        self.vertex_samples = vertex_samples;
        self
    }

    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Area samples per direction for meshes of `tris_a` and `tris_b` triangles: with
    /// `t = max(tris_a, tris_b)` and `k = full_rate_triangles`,
    /// `samples_per_triangle × (t if t ≤ k, else √(k·t))`, at least
    /// `min(min_samples, min_samples_per_triangle × t)`.
    pub fn area_sample_count(&self, tris_a: usize, tris_b: usize) -> usize {
        let per = if self.samples_per_triangle > 0.0 {
            self.samples_per_triangle
        } else {
            0.0
        };
        let t = tris_a.max(tris_b) as f64;
        let k = self.full_rate_triangles as f64;
        let effective = if t <= k { t } else { (k * t).sqrt() };
        // `as` saturates for huge values.
        let n = (per * effective).ceil() as usize;
        let floor = if self.min_samples_per_triangle >= 0.0 {
            // `as` saturates (infinity: no cap)
            (self.min_samples_per_triangle * t).ceil() as usize
        } else {
            0
        };
        n.max(self.min_samples.min(floor))
    }
}

impl Default for MeasureOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
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
    pub mean: f64,
    pub rms: f64,
    /// Points measured: area samples plus vertices.
    pub samples: usize,
}

impl Distance {
    /// No points measured.
    pub const NONE: Distance = Distance {
        max: 0.0,
        mean: 0.0,
        rms: 0.0,
        samples: 0,
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
            let n = opts.area_sample_count(a.triangles.len(), b.triangles.len());
            measure_from(a, &samples_a, &bvh_b, n, opts.vertex_samples, opts.seed)
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
                let n = opts.area_sample_count(a.triangles.len(), b.triangles.len());
                measure_from(a, &self.samples, &bvh_b, n, opts.vertex_samples, opts.seed)
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
        let n = opts.area_sample_count(self.mesh.triangles.len(), b.triangles.len());
        measure_from(
            b,
            &SampleSet::new(b),
            &self.bvh,
            n,
            opts.vertex_samples,
            opts.seed ^ 0xb5ad_4ece_da1c_e2a9,
        )
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
    let n = opts.area_sample_count(from.triangles.len(), to.len());
    Ok(measure_from(
        from,
        &SampleSet::new(from),
        to,
        n,
        opts.vertex_samples,
        opts.seed,
    ))
}

/// Sample indices per unit of parallel work. Fixed (never derived from the thread count), so
/// the summation order is fixed. 4096 queries take ~1 ms: coarse enough to amortise rayon's
/// overhead, fine enough to balance 2–16 threads on 10⁵ samples.
const CHUNK: usize = 4096;

/// Sums over one chunk of samples.
#[derive(Clone, Copy, Debug)]
struct Partial {
    max2: f64,
    sum: f64,
    sum2: f64,
    count: usize,
}

impl Partial {
    const ZERO: Partial = Partial {
        max2: 0.0,
        sum: 0.0,
        sum2: 0.0,
        count: 0,
    };

    #[inline]
    fn add(&mut self, d2: f64) {
        self.max2 = self.max2.max(d2);
        self.sum += d2.sqrt();
        self.sum2 += d2;
        self.count += 1;
    }

    fn merge(mut self, o: Partial) -> Partial {
        self.max2 = self.max2.max(o.max2);
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
                    acc.add(f64::INFINITY);
                    continue;
                };
                hint = Some(slot);
                acc.add(d2);
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
                let (d2, h) = to.farther_than(point(i, &mut cursor), acc.max2, hint);
                hint = h;
                if let Some(d2) = d2 {
                    acc.max2 = d2;
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

/// The one-sided measurement from the validated mesh `from`, whose [`SampleSet`] is `set`, to
/// the surface in `to`.
fn measure_from(
    from: MeshRef<'_>,
    set: &SampleSet,
    to: &TriangleBvh,
    area_samples: usize,
    vertex_samples: bool,
    seed: u64,
) -> Distance {
    if from.triangles.is_empty() {
        return Distance::NONE;
    }
    let nt = from.triangles.len();
    let corners = |t: u32| from.triangles[t as usize].map(|v| widen(from.positions[v as usize]));
    let (order, cumulative) = (&set.order, &set.cumulative);
    let total = cumulative.last().copied().unwrap_or(0.0);
    let area_samples = if total > 0.0 { area_samples } else { 0 };
    let area = measure_points(area_samples, to, |i, cursor| {
        let k = 3 * i as u64;
        let s = (i as f64 + unit(splitmix64(seed, k))) / area_samples as f64 * total;
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
    });
    let vertices = if vertex_samples {
        let list = &set.vertices;
        let vertex = |i: usize, _: &mut usize| widen(from.positions[list[i] as usize]);
        if area.count > 0 {
            // Vertices only count towards the maximum: those nearer than it need not be
            // measured exactly (see `max_above`).
            max_above(list.len(), to, area.max2, vertex)
        } else {
            measure_points(list.len(), to, vertex)
        }
    } else {
        Partial::ZERO
    };
    let stats = if area.count > 0 { area } else { vertices };
    let (mean, rms) = if stats.count > 0 {
        let n = stats.count as f64;
        (stats.sum / n, (stats.sum2 / n).sqrt())
    } else {
        (0.0, 0.0)
    };
    Distance {
        max: area.max2.max(vertices.max2).sqrt(),
        mean,
        rms,
        samples: area.count + vertices.count,
    }
}
