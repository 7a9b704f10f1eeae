//! Where the metric's points come from and how they are measured: stratified area samples,
//! the vertices, and the max-seeking search around the farthest of them. Used by
//! [`measure`](mod@super::measure), which owns the options and the statistics' meaning.
//!
//! Determinism: points are processed in fixed chunks of [`CHUNK`] consecutive indices; each
//! chunk's sums are computed sequentially and the chunk results are folded in index order, so
//! a result is bit-identical whatever the number of rayon threads. The max-seeking search
//! starts from the candidates of that fold (ordered by distance, then by place) and each
//! candidate's search is sequential.

use rayon::prelude::*;

use super::bvh::TriangleBvh;
use super::triangle::widen;
use super::{zorder, MeshRef};

/// Sample indices per unit of parallel work. Fixed (never derived from the thread count), so
/// the summation order is fixed. 4096 queries take ~1 ms: coarse enough to amortise rayon's
/// overhead, fine enough to balance 2–16 threads on 10⁵ samples.
const CHUNK: usize = 4096;

/// Candidates kept for the max-seeking search, at most (see [`Top`]).
pub(super) const MAX_CANDIDATES: usize = 16;

/// Where a measured point lies on the sampled mesh: inside triangle `tri` at barycentric
/// `(u, v)` (the point is `a + u (b − a) + v (c − a)`), or at vertex `v`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Site {
    Area { tri: u32, u: f64, v: f64 },
    Vertex(u32),
}

impl Site {
    /// What two candidates in the same place share: one search per triangle or vertex.
    fn key(self) -> (u8, u32) {
        match self {
            Site::Area { tri, .. } => (0, tri),
            Site::Vertex(v) => (1, v),
        }
    }
}

/// A far point: its squared distance and where it lies.
#[derive(Clone, Copy, Debug)]
pub(super) struct Candidate {
    pub d2: f64,
    pub site: Site,
}

/// The farthest points seen, at most one per triangle or vertex, farthest first (ties by
/// place, so merging is independent of the order of arrival within equal distances).
#[derive(Clone, Copy, Debug)]
pub(super) struct Top {
    len: usize,
    items: [Candidate; MAX_CANDIDATES],
}

impl Top {
    const EMPTY: Top = Top {
        len: 0,
        items: [Candidate {
            d2: 0.0,
            site: Site::Vertex(0),
        }; MAX_CANDIDATES],
    };

    pub(super) fn as_slice(&self) -> &[Candidate] {
        &self.items[..self.len]
    }

    /// Squared distance a point must exceed to enter (−1 while not full).
    #[inline(always)]
    fn entry(&self) -> f64 {
        if self.len < MAX_CANDIDATES {
            -1.0
        } else {
            self.items[MAX_CANDIDATES - 1].d2
        }
    }

    #[inline]
    fn offer(&mut self, c: Candidate) {
        if c.d2 > self.entry() {
            self.insert(c);
        }
    }

    fn insert(&mut self, c: Candidate) {
        let before = |x: &Candidate, y: &Candidate| {
            x.d2 > y.d2 || (x.d2 == y.d2 && x.site.key() < y.site.key())
        };
        let key = c.site.key();
        if let Some(i) = self.as_slice().iter().position(|x| x.site.key() == key) {
            if !before(&c, &self.items[i]) {
                return;
            }
            self.items.copy_within(i + 1..self.len, i);
            self.len -= 1;
        }
        let mut i = self.len.min(MAX_CANDIDATES - 1);
        if self.len == MAX_CANDIDATES && !before(&c, &self.items[i]) {
            return;
        }
        while i > 0 && before(&c, &self.items[i - 1]) {
            self.items[i] = self.items[i - 1];
            i -= 1;
        }
        self.items[i] = c;
        self.len = (self.len + 1).min(MAX_CANDIDATES);
    }

    pub(super) fn merge_top(mut self, o: &Top) -> Top {
        for &c in o.as_slice() {
            self.insert(c);
        }
        self
    }
}

/// Sums over one chunk of samples.
#[derive(Clone, Copy, Debug)]
pub(super) struct Partial {
    pub max2: f64,
    /// Where `max2` was found.
    pub at: Option<[f64; 3]>,
    pub sum: f64,
    pub sum2: f64,
    pub count: usize,
    /// The farthest points, for the max-seeking search.
    pub top: Top,
}

impl Partial {
    pub(super) const ZERO: Partial = Partial {
        max2: 0.0,
        at: None,
        sum: 0.0,
        sum2: 0.0,
        count: 0,
        top: Top::EMPTY,
    };

    #[inline]
    fn add(&mut self, d2: f64, p: [f64; 3], site: Site) {
        if d2 > self.max2 || self.at.is_none() {
            self.max2 = d2;
            self.at = Some(p);
        }
        self.top.offer(Candidate { d2, site });
        self.sum += d2.sqrt();
        self.sum2 += d2;
        self.count += 1;
    }

    /// Folds `o` in; on equal maxima the earlier chunk's place stays (chunks fold in order).
    pub(super) fn merge(mut self, o: Partial) -> Partial {
        if o.max2 > self.max2 || (self.at.is_none() && o.max2 >= self.max2) {
            self.max2 = o.max2;
            self.at = o.at;
        }
        self.sum += o.sum;
        self.sum2 += o.sum2;
        self.count += o.count;
        self.top = self.top.merge_top(&o.top);
        self
    }
}

/// Measures `count` points given by `point(i, cursor)` against `to`, in fixed chunks folded in
/// order. `cursor` is per-chunk scratch for `point`, `usize::MAX` at the start of each chunk.
pub(super) fn measure_points(
    count: usize,
    to: &TriangleBvh,
    point: impl Fn(usize, &mut usize) -> ([f64; 3], Site) + Sync,
) -> Partial {
    let chunks = count.div_ceil(CHUNK);
    let partials: Vec<Partial> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut acc = Partial::ZERO;
            let mut hint = None;
            let mut cursor = usize::MAX;
            for i in c * CHUNK..((c + 1) * CHUNK).min(count) {
                let (p, site) = point(i, &mut cursor);
                let Some((d2, h, _)) = to.closest_slot(p, hint) else {
                    acc.add(f64::INFINITY, p, site);
                    continue;
                };
                hint = Some(h);
                acc.add(d2, p, site);
            }
            acc
        })
        .collect();
    partials.into_iter().fold(Partial::ZERO, Partial::merge)
}

/// Like [`measure_points`] when only the maximum of the squared distances matters and it is at
/// least `floor`: `max2` is the exact maximum of `floor` and every point's squared distance,
/// `count` the number of points; `sum` and `sum2` are left at 0, `top` holds the points that
/// raised a chunk's running maximum. A point whose distance to the previous answer's triangle
/// is already at most the running maximum is settled by that one triangle test. Chunks as in
/// [`measure_points`], so the result does not depend on the number of threads.
pub(super) fn max_above(
    count: usize,
    to: &TriangleBvh,
    floor: f64,
    point: impl Fn(usize, &mut usize) -> ([f64; 3], Site) + Sync,
) -> Partial {
    let start = Partial {
        max2: floor,
        ..Partial::ZERO
    };
    let chunks = count.div_ceil(CHUNK);
    let partials: Vec<Partial> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut acc = start;
            if to.is_empty() {
                acc.max2 = f64::INFINITY;
            }
            let mut hint = None;
            let mut cursor = usize::MAX;
            let range = c * CHUNK..((c + 1) * CHUNK).min(count);
            acc.count = range.len();
            for i in range {
                let (p, site) = point(i, &mut cursor);
                let (d2, h) = to.farther_than(p, acc.max2, hint);
                hint = h;
                if let Some(d2) = d2 {
                    acc.max2 = d2;
                    acc.at = Some(p);
                    acc.top.offer(Candidate { d2, site });
                }
            }
            acc
        })
        .collect();
    partials.into_iter().fold(start, Partial::merge)
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

/// Where the samples of a mesh come from, besides its triangles' Z-order (the hierarchy's
/// leaf order, [`TriangleBvh::order`], or [`zorder::triangles`]): the cumulative areas along
/// that order, and the vertices its triangles use, in Z-order. Depends only on the mesh.
///
/// Along the curve consecutive samples are near each other: the previous answer is a tight
/// first bound for the next query (and its hierarchy path is in cache), and stratifying along
/// the curve spreads the samples evenly over the surface.
#[derive(Clone, Debug)]
pub(super) struct SampleSet {
    /// Cumulative area along the triangles' Z-order, summed sequentially (deterministic).
    pub cumulative: Vec<f64>,
    /// Used vertices along the curve.
    pub vertices: Vec<u32>,
    /// Two used vertices share a Morton code: their order is their numbering's.
    pub tied: bool,
}

impl SampleSet {
    /// The sample set of the validated `mesh` whose triangles' Z-order is `order`.
    pub(super) fn new(mesh: MeshRef<'_>, order: &[u32]) -> SampleSet {
        let mut total = 0.0f64;
        let cumulative = order
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                mesh.prefetch_along(order, i);
                total += triangle_area(mesh, mesh.triangles[t as usize]);
                total
            })
            .collect();
        let (vertices, tied) = zorder::vertices(mesh);
        SampleSet {
            cumulative,
            vertices,
            tied,
        }
    }

    /// The set of the same mesh with its vertices renumbered (`vertex_new[v]` the new number
    /// of `v`) and its triangles along the same order: the set built anew, bit for bit, unless
    /// two vertices share a code (`None`: their order would follow the new numbering).
    pub(super) fn renumbered(mut self, vertex_new: &[u32]) -> Option<SampleSet> {
        if self.tied {
            return None;
        }
        for v in &mut self.vertices {
            *v = *vertex_new.get(*v as usize)?;
        }
        Some(self)
    }
}

/// `count` stratified area samples of the validated, non-empty mesh `from` (whose triangles'
/// Z-order is `order` and [`SampleSet`] `set`) measured against `to`; none when `from` has no area.
pub(super) fn area_samples(
    from: MeshRef<'_>,
    order: &[u32],
    set: &SampleSet,
    to: &TriangleBvh,
    count: usize,
    seed: u64,
) -> Partial {
    let nt = from.triangles.len();
    let corners = |t: u32| from.triangles[t as usize].map(|v| widen(from.positions[v as usize]));
    let cumulative = &set.cumulative;
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
        from.prefetch_along(order, at);
        let [a, b, c] = corners(order[at]);
        let mut r1 = unit(splitmix64(seed, k + 1));
        let mut r2 = unit(splitmix64(seed, k + 2));
        if r1 + r2 > 1.0 {
            // Fold the unit square's upper half onto the lower: uniform on the triangle.
            r1 = 1.0 - r1;
            r2 = 1.0 - r2;
        }
        let p = std::array::from_fn(|j| a[j] + r1 * (b[j] - a[j]) + r2 * (c[j] - a[j]));
        (
            p,
            Site::Area {
                tri: order[at],
                u: r1,
                v: r2,
            },
        )
    })
}

/// The six neighbours of a point on the triangular lattice, in barycentric steps `(du, dv)`.
const STEPS: [(f64, f64); 6] = [
    (1.0, 0.0),
    (-1.0, 0.0),
    (0.0, 1.0),
    (0.0, -1.0),
    (1.0, -1.0),
    (-1.0, 1.0),
];

/// Where a climb of [`seek`] ended, and its distance.
type End = ([f64; 3], f64);

/// First step of the max-seeking search, in barycentric units (a quarter of the triangle).
const FIRST_STEP: f64 = 0.25;

/// The search stops when its step falls below this (1/1024 of the triangle).
const LAST_STEP: f64 = 1.0 / 1024.0;

/// The max-seeking search: from each candidate (a far point found by the sampling), a pattern
/// search over the triangle of `from` it lies in (a vertex: the first triangle using it) for a
/// local maximum of the distance to `to`: the six lattice neighbours at the current step are
/// measured exactly, the search moves to the farthest when it is farther, else halves the step,
/// until the step is below [`LAST_STEP`] or `budget` points were measured. The maxima of a
/// level's distance sit on narrow features (a crease cut across, a tip) that random samples
/// brush past: the search climbs from the sample that brushed them. `max2` is the largest
/// distance found (at least `floor`), `count` the points measured; with it, where each climb
/// ended and its distance (in candidate order; none for a vertex in no triangle).
pub(super) fn seek(
    from: MeshRef<'_>,
    to: &TriangleBvh,
    candidates: &[Candidate],
    floor: f64,
    budget: usize,
) -> (Partial, Vec<End>) {
    let start = Partial {
        max2: floor,
        ..Partial::ZERO
    };
    if to.is_empty() || candidates.is_empty() {
        return (start, Vec::new());
    }
    let vertex_triangles = triangles_of(from, candidates);
    let results: Vec<(Partial, Option<End>)> = candidates
        .par_iter()
        .zip(&vertex_triangles)
        .map(|(c, &found)| {
            let mut acc = start;
            let (tri, u, v) = match (c.site, found) {
                (Site::Area { tri, u, v }, _) => (tri, u, v),
                (Site::Vertex(_), Some((tri, corner))) => match corner {
                    0 => (tri, 0.0, 0.0),
                    1 => (tri, 1.0, 0.0),
                    _ => (tri, 0.0, 1.0),
                },
                (Site::Vertex(_), None) => return (acc, None),
            };
            let [a, b, cc] =
                from.triangles[tri as usize].map(|i| widen(from.positions[i as usize]));
            let at = |u: f64, v: f64| -> [f64; 3] {
                std::array::from_fn(|j| a[j] + u * (b[j] - a[j]) + v * (cc[j] - a[j]))
            };
            let (mut u, mut v, mut d2) = (u, v, c.d2);
            let mut step = FIRST_STEP;
            let mut hint = None;
            while step >= LAST_STEP && acc.count + STEPS.len() <= budget {
                let mut best = (d2, u, v);
                for (du, dv) in STEPS {
                    let (u2, v2) = (u + step * du, v + step * dv);
                    if u2 < 0.0 || v2 < 0.0 || u2 + v2 > 1.0 {
                        continue;
                    }
                    let Some((e2, h, _)) = to.closest_slot(at(u2, v2), hint) else {
                        break;
                    };
                    hint = Some(h);
                    acc.count += 1;
                    if e2 > best.0 {
                        best = (e2, u2, v2);
                    }
                }
                if best.0 > d2 {
                    (d2, u, v) = best;
                } else {
                    step *= 0.5;
                }
            }
            if d2 > acc.max2 {
                acc.max2 = d2;
                acc.at = Some(at(u, v));
            }
            (acc, Some((at(u, v), d2.sqrt())))
        })
        .collect();
    let ends = results.iter().filter_map(|r| r.1).collect();
    let found = results.into_iter().map(|r| r.0).fold(start, Partial::merge);
    (found, ends)
}

/// For each vertex candidate, the first triangle of `mesh` using that vertex and the corner it
/// is at (`None` for area candidates): one pass over the triangles.
fn triangles_of(mesh: MeshRef<'_>, candidates: &[Candidate]) -> Vec<Option<(u32, u8)>> {
    let mut out = vec![None; candidates.len()];
    let mut missing = candidates
        .iter()
        .filter(|c| matches!(c.site, Site::Vertex(_)))
        .count();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if missing == 0 {
            break;
        }
        for (c, slot) in candidates.iter().zip(out.iter_mut()) {
            if let (Site::Vertex(v), None) = (c.site, *slot) {
                if let Some(k) = tri.iter().position(|&w| w == v) {
                    *slot = Some((t as u32, k as u8));
                    missing -= 1;
                }
            }
        }
    }
    out
}
