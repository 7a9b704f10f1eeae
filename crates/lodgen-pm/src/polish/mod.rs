//! Polish: a level's vertices moved towards the original surface, after
//! simplification, to lower the squared distance between the two.
//!
//! The simplifier places every vertex where its quadric is smallest: the
//! quadric holds the planes of the input faces the vertex stands for, as they
//! were, so it cannot see that the level's own faces are chords (on a convex
//! patch they cut inside the surface). The polish looks at the level as it
//! is, against the original, in a few Jacobi iterations; each:
//!
//! * samples both surfaces: points spread by area over the original (A → B,
//!   fixed for the run) and three points on every level face (B → A); each
//!   is paired with its closest point on the other surface (the hierarchies
//!   of [`crate::metric`]);
//! * gives each pair a plane: through the pair's point on the original,
//!   across the way from the level point to it (the level face's normal
//!   when they coincide), added to the quadric of each corner of the level
//!   face with the sample's area times the corner's barycentric weight, at
//!   the offset that carries the corner by the pair's distance (so a vertex
//!   takes the weighted mean of the offsets of the surface around it: a
//!   uniform offset is corrected exactly, with no overshoot; and a level tip
//!   beyond the original's is pulled back along its axis, which a plane of
//!   the level's own normal could not do); a pair whose two faces differ by
//!   more than 60° (`PAIR_MIN_COS`: the far side of a thin part) is left out;
//! * solves each vertex's quadric, regularised towards where it stands
//!   ([`REGULARISATION`] of its weight: the quadric holds normals only, so
//!   a vertex on a flat patch would otherwise slide along it); a vertex on
//!   an open border also gets, per border edge, the plane through the edge
//!   perpendicular to its face, [`BORDER_WEIGHT`] times its weight, so the
//!   border keeps its line and a hole neither opens nor closes; a vertex on
//!   an edge of three or more faces does not move;
//! * shortens a move that would take the vertex farther from the original
//!   than it was and than [`GUARD_FACTOR`] × the RMS distance of its pairs
//!   (`guard`: the Hausdorff distance is a maximum, the fit a mean);
//! * moves the vertices, then backs off where a face would turn by more
//!   than [`MAX_TURN_COS`]'s angle or lose its area: such a face's corners
//!   go half way, up to [`BACK_OFFS`] times, then stay where they were.
//!
//! Two ways to pair: [`polish`] queries the hierarchies of both surfaces
//! (area samples of the original, the closest points exact; `xtask quality
//! --polish-exact`), [`polish_clusters`] walks from where the
//! simplification put each vertex (no hierarchy, about a third of the CPU
//! on the bunny: `clusters.rs`; what `lodgen --polish` and `xtask quality
//! --polish` run).
//!
//! Where it applies: the written levels only. The vertex-split log and the progressive stream keep
//! the simplifier's positions, so a replayed or streamed level is the
//! unpolished one.
//!
//! Deterministic: samples are made in a fixed order, the queries run in
//! parallel but are summed in sample order, so any thread count gives the
//! same bits. Topology is never changed, only positions.

mod clusters;
mod worst;

pub use clusters::{polish_clusters, Original};
pub use worst::{fix_worst, WorstFix, WorstOptions};

use rayon::prelude::*;

use crate::mesh::Mesh;
use crate::metric::triangle::{cross, dot, sub};
use crate::metric::{MeshRef, TriangleBvh};

/// How a level is polished.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PolishOptions {
    /// Jacobi iterations (each re-pairs the samples with the moved level).
    pub iterations: u32,
    /// Samples on the original per level triangle (A → B), at least
    /// [`MIN_SAMPLES`] and at most [`MAX_SAMPLES_PER_ORIGINAL`] per
    /// original triangle ([`polish`]; [`polish_clusters`] pairs every
    /// original vertex).
    pub samples_per_triangle: f64,
}

impl PolishOptions {
    /// Two iterations, eight original samples per level triangle.
    pub const DEFAULT: PolishOptions = PolishOptions {
        iterations: 2,
        samples_per_triangle: 8.0,
    };
    /// What `lodgen --polish` runs ([`polish_clusters`]): one iteration
    /// (a second lowers the quick table's RMS by 1.6 % and costs as much
    /// again: docs/quality.md).
    pub const CLUSTERS: PolishOptions = PolishOptions {
        iterations: 1,
        samples_per_triangle: 8.0,
    };
}

impl Default for PolishOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What a polish did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PolishStats {
    /// Samples on the original (A → B) per iteration.
    pub samples: usize,
    /// Vertex moves over all iterations (a vertex counts once per iteration
    /// in which it moved).
    pub moved: usize,
    /// Vertex moves shortened or undone because a face would have turned.
    pub backed_off: usize,
}

/// The fewest samples on the original (a small level still sees the whole
/// surface).
pub const MIN_SAMPLES: usize = 30_000;
/// At most this many samples per original triangle (a level near the
/// original's size gains nothing from more).
pub const MAX_SAMPLES_PER_ORIGINAL: f64 = 2.0;
/// Pull towards the current position, as a share of a vertex's sample
/// weight: keeps a vertex on a flat patch from sliding along it while
/// costing 1 % of each normal correction.
pub const REGULARISATION: f64 = 0.01;
/// Weight of a border edge's constraint plane, as a multiple of the vertex's
/// sample weight: the border stays on its line (a hundredth of the
/// correction would leak across it).
pub const BORDER_WEIGHT: f64 = 100.0;
/// A moved face's unit normal must keep at least this cosine with its old
/// one (60°): the polish corrects offsets of a fraction of an edge length;
/// a face that turns further is folding, not fitting.
pub const MAX_TURN_COS: f64 = 0.5;
/// A pair counts only when the original face and the level face keep at
/// least this cosine between their normals (60°): see `compatible`.
pub const PAIR_MIN_COS: f64 = 0.5;
/// How far from the original a moved vertex may end, as a multiple of the
/// RMS distance of the pairs around it (or where it stood, if farther): a
/// vertex fitting a convex patch in the mean stands outside it by about
/// half that; 1 and 1.5 gave up a quarter of the RMS gain, 2 keeps
/// tips from moving out (`xtask quality --quick --polish`: docs/quality.md).
pub const GUARD_FACTOR: f64 = 2.0;
/// Halvings of a move before it is undone.
pub const BACK_OFFS: u32 = 3;
/// Samples queried together (their pairs summed in order before the next
/// block: bounded memory whatever the mesh size).
const BLOCK: usize = 1 << 15;

/// A point on one surface paired with its closest point on the other.
#[derive(Clone, Copy)]
struct Pair {
    /// The level face the pair's plane belongs to.
    face: u32,
    /// Barycentric weights of the level point in `face`.
    bary: [f64; 3],
    /// The point on the original.
    target: [f64; 3],
    /// The sample's area.
    weight: f64,
}

/// Per-vertex sums: the quadric `Σ w n nᵀ` (upper triangle: xx xy xz yy yz
/// zz), `Σ w n (n·t)`, and `Σ w`.
#[derive(Clone, Copy, Default)]
struct Acc {
    a: [f64; 6],
    b: [f64; 3],
    w: f64,
    /// `Σ w dist²` of the pairs (the vertex's mean squared residual × `w`).
    e2: f64,
}

impl Acc {
    fn add_plane(&mut self, n: [f64; 3], d: f64, w: f64) {
        self.a[0] += w * n[0] * n[0];
        self.a[1] += w * n[0] * n[1];
        self.a[2] += w * n[0] * n[2];
        self.a[3] += w * n[1] * n[1];
        self.a[4] += w * n[1] * n[2];
        self.a[5] += w * n[2] * n[2];
        for (bk, nk) in self.b.iter_mut().zip(n) {
            *bk += w * d * nk;
        }
    }

    /// The position minimising the quadric plus `reg · |x − p|²`, or `p`
    /// when the system is singular.
    fn solve(&self, p: [f64; 3], reg: f64) -> [f64; 3] {
        let a = [
            [self.a[0] + reg, self.a[1], self.a[2]],
            [self.a[1], self.a[3] + reg, self.a[4]],
            [self.a[2], self.a[4], self.a[5] + reg],
        ];
        let r = [0, 1, 2].map(|k| self.b[k] + reg * p[k]);
        let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        if det.abs().is_nan() || det.abs() <= 1e-300 {
            return p;
        }
        let col = |k: usize| -> f64 {
            let mut m = a;
            for (row, rk) in m.iter_mut().zip(r) {
                row[k] = rk;
            }
            m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
        };
        [col(0) / det, col(1) / det, col(2) / det]
    }
}

fn widen(p: [f32; 3]) -> [f64; 3] {
    p.map(f64::from)
}

/// Twice the area vector of a triangle.
fn area_vector(p: &[[f64; 3]], t: [u32; 3]) -> [f64; 3] {
    let [a, b, c] = t.map(|v| p[v as usize]);
    cross(sub(b, a), sub(c, a))
}

/// Barycentric weights of `q` (on the triangle's plane) in `a b c`; `None`
/// for a degenerate triangle.
fn barycentric(q: [f64; 3], [a, b, c]: [[f64; 3]; 3]) -> Option<[f64; 3]> {
    let n = cross(sub(b, a), sub(c, a));
    let nn = dot(n, n);
    if nn.is_nan() || nn <= 0.0 {
        return None;
    }
    let u = dot(cross(sub(c, b), sub(q, b)), n) / nn;
    let v = dot(cross(sub(a, c), sub(q, c)), n) / nn;
    let w = 1.0 - u - v;
    Some([u, v, w].map(|x| x.clamp(0.0, 1.0)))
}

/// What the level's topology allows each vertex: free, on a border (with
/// its border edges), or fixed.
struct Topology {
    /// Per vertex: moves at all.
    movable: Vec<bool>,
    /// Border edges `(a, b, face)`, in sorted order.
    border: Vec<(u32, u32, u32)>,
}

impl Topology {
    fn new(level: &Mesh) -> Topology {
        let mut edges: Vec<(u32, u32, u32)> = Vec::with_capacity(level.triangles.len() * 3);
        for (f, t) in level.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.push((a.min(b), a.max(b), f as u32));
            }
        }
        edges.sort_unstable();
        let mut movable = vec![false; level.positions.len()];
        for t in &level.triangles {
            for &v in t {
                movable[v as usize] = true;
            }
        }
        let mut border = Vec::new();
        let mut i = 0;
        while i < edges.len() {
            let mut j = i + 1;
            while j < edges.len() && edges[j].0 == edges[i].0 && edges[j].1 == edges[i].1 {
                j += 1;
            }
            match j - i {
                1 => border.push(edges[i]),
                2 => {}
                _ => {
                    movable[edges[i].0 as usize] = false;
                    movable[edges[i].1 as usize] = false;
                }
            }
            i = j;
        }
        Topology { movable, border }
    }
}

/// `count` points spread over `mesh` by area (stratified along its triangle
/// order, an R2 low-discrepancy point inside each), each with its share of
/// the area.
fn original_samples(mesh: MeshRef<'_>, count: usize) -> Vec<Sample> {
    let areas: Vec<f64> = mesh
        .triangles
        .iter()
        .map(|&t| 0.5 * unit_normal(mesh, t).1)
        .collect();
    let total: f64 = areas.iter().sum();
    if count == 0 || (total.is_nan() || total <= 0.0) {
        return Vec::new();
    }
    let step = total / count as f64;
    let (g1, g2) = (0.754_877_666_246_692_7_f64, 0.569_840_290_998_053_2_f64);
    let mut out = Vec::with_capacity(count);
    let mut next = 0.5 * step;
    let mut acc = 0.0;
    for (t, &area) in mesh.triangles.iter().zip(&areas) {
        let end = acc + area;
        while next < end && out.len() < count {
            let k = out.len() as f64;
            let (mut s, mut r) = ((0.5 + g1 * k).fract(), (0.5 + g2 * k).fract());
            if s + r > 1.0 {
                (s, r) = (1.0 - s, 1.0 - r);
            }
            let [a, b, c] = t.map(|v| widen(mesh.positions[v as usize]));
            let p = [0, 1, 2].map(|i| a[i] + s * (b[i] - a[i]) + r * (c[i] - a[i]));
            out.push(Sample {
                point: p,
                normal: unit_normal(mesh, *t).0,
                weight: step,
            });
            next += step;
        }
        acc = end;
    }
    out
}

/// A point on the original, its face's unit normal, its share of the area.
#[derive(Clone, Copy)]
struct Sample {
    point: [f64; 3],
    normal: [f64; 3],
    weight: f64,
}

/// The unit normal of `t` in `mesh` (zero when degenerate) and twice its area.
fn unit_normal(mesh: MeshRef<'_>, t: [u32; 3]) -> ([f64; 3], f64) {
    let [a, b, c] = t.map(|v| widen(mesh.positions[v as usize]));
    let n = cross(sub(b, a), sub(c, a));
    let l = dot(n, n).sqrt();
    if l > 0.0 {
        (n.map(|x| x / l), l)
    } else {
        ([0.0; 3], 0.0)
    }
}

/// Whether an original face with unit normal `a` and a level face with
/// unit normal `b` may be paired: they face the same way within 60° (a
/// sample on the far side of a thin part, or on a sheet the level has
/// merged with another, would pull the level across).
fn compatible(a: [f64; 3], b: [f64; 3]) -> bool {
    dot(a, b) >= PAIR_MIN_COS
}

/// Barycentric points of the level's samples on each face (B → A), each a
/// third of the face's area.
const LEVEL_POINTS: [[f64; 3]; 3] = [
    [2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0],
    [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
    [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0],
];

/// Polishes `level` against `original` (whose hierarchy is `original_bvh`):
/// module docs. Vertices no triangle uses are left as they are.
pub fn polish(
    original: MeshRef<'_>,
    original_bvh: &TriangleBvh,
    level: &mut Mesh,
    opts: &PolishOptions,
) -> PolishStats {
    let mut stats = PolishStats::default();
    if level.triangles.is_empty() || original.triangles.is_empty() {
        return stats;
    }
    let topo = Topology::new(level);
    let wanted = (opts.samples_per_triangle * level.triangles.len() as f64) as usize;
    let cap = (MAX_SAMPLES_PER_ORIGINAL * original.triangles.len() as f64) as usize;
    let count = wanted.max(MIN_SAMPLES).min(cap.max(1));
    let samples = original_samples(original, count);
    stats.samples = samples.len();
    for _ in 0..opts.iterations {
        let pos: Vec<[f64; 3]> = level.positions.iter().map(|&p| widen(p)).collect();
        let acc = accumulate(&pos, level, original, &samples, original_bvh, &topo);
        let mut target = solve_all(&pos, &acc, &topo);
        guard(&pos, &mut target, &acc, |_, x| {
            original_bvh.closest_point(x).map_or(0.0, |r| r.0)
        });
        if !apply(&pos, &target, level, &mut stats) {
            break;
        }
    }
    stats
}

/// Every vertex's quadric from the two sample sets and the border planes.
fn accumulate(
    pos: &[[f64; 3]],
    level: &Mesh,
    original: MeshRef<'_>,
    samples: &[Sample],
    original_bvh: &TriangleBvh,
    topo: &Topology,
) -> Vec<Acc> {
    let level_bvh = TriangleBvh::new(MeshRef::new(&level.positions, &level.triangles))
        .expect("a level's indices and positions are valid");
    let normals = face_normals(pos, level);
    let mut acc = vec![Acc::default(); pos.len()];
    let mut add = |pairs: Vec<Option<Pair>>| add_pairs(&mut acc, pos, level, &normals, pairs);
    // A → B: each original sample and its closest level point
    for block in samples.chunks(BLOCK) {
        let pairs: Vec<Option<Pair>> = block
            .par_iter()
            .map(|s| {
                let (_, face, q) = level_bvh.closest_point(s.point)?;
                if !compatible(s.normal, normals[face as usize]?) {
                    return None;
                }
                let t = level.triangles[face as usize];
                let bary = barycentric(q, t.map(|v| pos[v as usize]))?;
                Some(Pair {
                    face,
                    bary,
                    target: s.point,
                    weight: s.weight,
                })
            })
            .collect();
        add(pairs);
    }
    // B → A: points on each level face and their closest original points
    let faces = level.triangles.len();
    for start in (0..faces).step_by(BLOCK / LEVEL_POINTS.len()) {
        let end = (start + BLOCK / LEVEL_POINTS.len()).min(faces);
        let pairs: Vec<Option<Pair>> = (start * LEVEL_POINTS.len()..end * LEVEL_POINTS.len())
            .into_par_iter()
            .map(|i| {
                let face = (i / LEVEL_POINTS.len()) as u32;
                let bary = LEVEL_POINTS[i % LEVEL_POINTS.len()];
                let t = level.triangles[face as usize];
                let [a, b, c] = t.map(|v| pos[v as usize]);
                let n = area_vector(pos, t);
                let area = 0.5 * dot(n, n).sqrt();
                let q = [0, 1, 2].map(|k| bary[0] * a[k] + bary[1] * b[k] + bary[2] * c[k]);
                let (_, tri, target) = original_bvh.closest_point(q)?;
                let m = unit_normal(original, original.triangles[tri as usize]).0;
                if !compatible(m, normals[face as usize]?) {
                    return None;
                }
                Some(Pair {
                    face,
                    bary,
                    target,
                    weight: area / LEVEL_POINTS.len() as f64,
                })
            })
            .collect();
        add(pairs);
    }
    add_border_planes(pos, topo, &normals, &mut acc);
    acc
}

/// Each level face's unit normal (`None`: degenerate).
fn face_normals(pos: &[[f64; 3]], level: &Mesh) -> Vec<Option<[f64; 3]>> {
    level
        .triangles
        .iter()
        .map(|&t| {
            let n = area_vector(pos, t);
            let l = dot(n, n).sqrt();
            (l > 0.0).then(|| n.map(|x| x / l))
        })
        .collect()
}

/// Adds each pair's plane to the quadrics of its level face's corners
/// (module docs), in the pairs' order.
fn add_pairs(
    acc: &mut [Acc],
    pos: &[[f64; 3]],
    level: &Mesh,
    normals: &[Option<[f64; 3]>],
    pairs: Vec<Option<Pair>>,
) {
    for p in pairs.into_iter().flatten() {
        let t = level.triangles[p.face as usize];
        let Some(n) = normals[p.face as usize] else {
            continue;
        };
        let q: [f64; 3] = [0, 1, 2].map(|k| {
            p.bary[0] * pos[t[0] as usize][k]
                + p.bary[1] * pos[t[1] as usize][k]
                + p.bary[2] * pos[t[2] as usize][k]
        });
        let e = sub(p.target, q);
        let dist = dot(e, e).sqrt();
        let u = if dist > 0.0 { e.map(|x| x / dist) } else { n };
        for (&v, &b) in t.iter().zip(&p.bary) {
            let d = dot(u, pos[v as usize]) + dot(u, e);
            acc[v as usize].add_plane(u, d, p.weight * b);
            acc[v as usize].w += p.weight * b;
            acc[v as usize].e2 += p.weight * b * dist * dist;
        }
    }
}

/// Per border edge, the plane through it perpendicular to its face, on both
/// its ends, [`BORDER_WEIGHT`] × the end's sample weight.
fn add_border_planes(
    pos: &[[f64; 3]],
    topo: &Topology,
    normals: &[Option<[f64; 3]>],
    acc: &mut [Acc],
) {
    let weights: Vec<f64> = acc.iter().map(|a| a.w).collect();
    for &(a, b, f) in &topo.border {
        let Some(n) = normals[f as usize] else {
            continue;
        };
        let m = cross(n, sub(pos[b as usize], pos[a as usize]));
        let l = dot(m, m).sqrt();
        if l.is_nan() || l <= 0.0 {
            continue;
        }
        let m = m.map(|x| x / l);
        let d = dot(m, pos[a as usize]);
        for v in [a, b] {
            let w = BORDER_WEIGHT * weights[v as usize];
            acc[v as usize].add_plane(m, d, w);
        }
    }
}

/// Each movable vertex's solved position (its current one otherwise).
fn solve_all(pos: &[[f64; 3]], acc: &[Acc], topo: &Topology) -> Vec<[f64; 3]> {
    pos.par_iter()
        .zip(acc)
        .zip(&topo.movable)
        .map(|((&p, a), &movable)| {
            if !movable || (a.w.is_nan() || a.w <= 0.0) {
                return p;
            }
            let x = a.solve(p, REGULARISATION * a.w);
            if x.iter().all(|c| c.is_finite()) {
                x
            } else {
                p
            }
        })
        .collect()
}

/// Shortens each move (halving, up to [`BACK_OFFS`] times, then none) until
/// the vertex is no farther from the original than it was or than
/// [`GUARD_FACTOR`] × the RMS residual of the pairs around it, whichever is
/// larger: a move that fits
/// the surface around a vertex in the mean but takes the vertex itself away
/// (the tip of a thin part, where the planes around it meet far out) would
/// raise the maximum.
/// `d2(v, x)`: the squared distance from `x` to the original, for vertex
/// `v` moved to `x`.
fn guard(
    pos: &[[f64; 3]],
    target: &mut [[f64; 3]],
    acc: &[Acc],
    d2: impl Fn(usize, [f64; 3]) -> f64 + Sync,
) {
    target
        .par_iter_mut()
        .zip(pos)
        .zip(acc)
        .enumerate()
        .for_each(|(v, ((t, &p), a))| {
            if *t == p {
                return;
            }
            let d2 = |x: [f64; 3]| d2(v, x);
            let allowed = d2(p).max(GUARD_FACTOR * GUARD_FACTOR * a.e2 / a.w);
            let mut s = 1.0;
            for _ in 0..=BACK_OFFS {
                let x = [0, 1, 2].map(|k| p[k] + s * (t[k] - p[k]));
                if d2(x) <= allowed {
                    *t = x;
                    return;
                }
                s *= 0.5;
            }
            *t = p;
        });
}

/// Whether face `t` at `new` keeps its orientation against `old`.
fn face_ok(old: &[[f64; 3]], new: &[[f64; 3]], t: [u32; 3]) -> bool {
    let n0 = area_vector(old, t);
    let n1 = area_vector(new, t);
    let (l0, l1) = (dot(n0, n0).sqrt(), dot(n1, n1).sqrt());
    if l0.is_nan() || l0 <= 0.0 {
        return true;
    }
    l1 > 0.0 && dot(n0, n1) >= MAX_TURN_COS * l0 * l1
}

/// Moves the level to `target`, backing off around faces that would turn,
/// and counts the vertices moved and the moves shortened or undone in
/// `stats`: false when no vertex moved (the iterations stop).
fn apply(pos: &[[f64; 3]], target: &[[f64; 3]], level: &mut Mesh, stats: &mut PolishStats) -> bool {
    let mut step: Vec<f64> = vec![1.0; pos.len()];
    let mut backed = vec![false; pos.len()];
    let place = |step: &[f64]| -> Vec<[f64; 3]> {
        pos.iter()
            .zip(target)
            .zip(step)
            .map(|((&p, &t), &s)| [0, 1, 2].map(|k| p[k] + s * (t[k] - p[k])))
            .collect()
    };
    let mut round = 0;
    loop {
        let new = place(&step);
        let bad: Vec<[u32; 3]> = level
            .triangles
            .iter()
            .copied()
            .filter(|&t| !face_ok(pos, &new, t))
            .collect();
        if bad.is_empty() {
            break;
        }
        for t in bad {
            for v in t {
                let v = v as usize;
                backed[v] = true;
                step[v] = if round < BACK_OFFS {
                    step[v] * 0.5
                } else {
                    0.0
                };
            }
        }
        round += 1;
    }
    let new = place(&step);
    let mut moved = 0;
    for (i, q) in new.iter().enumerate() {
        let q32 = q.map(|c| c as f32);
        if q32 != level.positions[i] {
            level.positions[i] = q32;
            moved += 1;
        }
    }
    stats.moved += moved;
    stats.backed_off += backed.iter().filter(|&&b| b).count();
    moved > 0
}
