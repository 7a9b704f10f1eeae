//! Attribute values of a simplified level, fitted to the original surface
//! (the scalar-attribute fit of Hoppe 1996, "Progressive meshes", §4.2,
//! with the wedges of Hoppe 1999).
//!
//! A level keeps its topology and positions from the vertex-split log; each
//! of its corners names a *wedge* of the input (a source vertex of the same
//! chart). Taking that wedge's input values as they are is exact only where
//! nothing moved: a level vertex stands for a whole region of the input
//! surface, and its position is the quadric-optimal one, not its source
//! vertex's. So the values of every level wedge — a distinct (level vertex,
//! wedge) pair — are the least-squares fit of the input's attribute field
//! over the surface: with points `p` sampled on the input (area weights
//! `ω`), each mapped to its nearest point on the level (barycentrics `γ`
//! in level triangle `L`),
//!
//! ```text
//! minimise  Σ_p ω (a(p) − Σ_k γ_k x[L_k])²  +  λ Σ_i D_i (x_i − x⁰_i)²
//! ```
//!
//! which is the squared attribute error a viewer sees (the error
//! `cargo xtask attributes` measures), linear in the level values. `x⁰` is
//! the wedge's input value and `D` the diagonal of the normal matrix, so
//! the small `λ` term only decides values no sample constrains.
//!
//! Charts: a sample counts only when its input triangle and the level
//! triangle it lands on are in the same *chart* (wedge-connected component
//! of the input: seams, hard edges and material borders separate charts), so
//! no value is ever blended across a seam. Level vertices with more than one
//! wedge (they sit on a seam or a feature line, at an input position, since
//! feature vertices never move) keep their input values exactly: both sides
//! of a seam must keep matching texels. Values of a level equal to the
//! input are the input's (the caller skips the fit there).
//!
//! The solve is Jacobi-preconditioned conjugate gradients on the sparse
//! normal matrix (a sampled mass matrix), summed in a fixed order, so the
//! result is a pure function of the input. Post-processing by attribute
//! meaning (renormalising normals, …) is the caller's.

use crate::metric::bvh::TriangleBvh;
use crate::metric::triangle::{cross, dot, sub};
use crate::metric::MeshRef;
use rayon::prelude::*;
use std::ops::Range;

/// The input surface with per-wedge attribute values.
#[derive(Clone, Copy, Debug)]
pub struct Source<'a> {
    /// Position of each wedge.
    pub positions: &'a [[f32; 3]],
    /// Triangles as wedge triples.
    pub triangles: &'a [[u32; 3]],
    /// `dims` values per wedge.
    pub values: &'a [f32],
    /// Components per wedge.
    pub dims: usize,
}

/// A simplified level: positions per level vertex, triangles, and the
/// input wedge of each corner.
#[derive(Clone, Copy, Debug)]
pub struct Level<'a> {
    /// Positions per level vertex.
    pub positions: &'a [[f32; 3]],
    /// Triangles as level-vertex triples.
    pub triangles: &'a [[u32; 3]],
    /// The input wedge of each corner.
    pub wedges: &'a [[u32; 3]],
}

/// A group of components fitted as one unit.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// Which of the `dims` components.
    pub components: Range<usize>,
    /// Keep each fitted component within the input values it was fitted to
    /// (and its own input value): no extrapolation, so a UV stays within
    /// what its chart shows around it. Off for unit vectors (normals,
    /// tangents), which are renormalised instead.
    pub bounded: bool,
}

/// Fitted values: `keys` (level vertex, wedge), sorted, and `dims` values
/// for each.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Fitted {
    /// `(level vertex, wedge)`, sorted.
    pub keys: Vec<(u32, u32)>,
    /// `dims` values per key.
    pub values: Vec<f32>,
    /// Components per wedge.
    pub dims: usize,
}

impl Fitted {
    /// The fitted values of wedge `wedge` at level vertex `v`, if fitted.
    pub fn get(&self, v: u32, wedge: u32) -> Option<&[f32]> {
        let i = self.keys.binary_search(&(v, wedge)).ok()?;
        Some(&self.values[i * self.dims..(i + 1) * self.dims])
    }
}

/// Weight of the pull towards the input value (module docs), relative to
/// the diagonal of the normal matrix.
const LAMBDA: f64 = 1e-3;
/// Conjugate-gradient iterations at most, and the relative residual that
/// ends them earlier.
const MAX_ITERATIONS: usize = 200;
const TOLERANCE: f64 = 1e-6;
/// Sample points per input triangle (barycentrics) and their shares of its
/// area: the centroid and three points towards the corners. Weights must
/// be positive (the normal matrix stays positive semi-definite).
const RULE: [([f64; 3], f64); 4] = [
    ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], 0.25),
    ([4.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0], 0.25),
    ([1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0], 0.25),
    ([1.0 / 6.0, 1.0 / 6.0, 4.0 / 6.0], 0.25),
];
/// Queries per unit of parallel work (fixed, so results do not depend on
/// the thread count), and units per batch (bounds the memory of results
/// waiting to be summed).
const CHUNK: usize = 4096;
const BATCH: usize = 64;

/// Fit the level's wedge values to the source surface (module docs).
/// Degenerate inputs (no triangles, indices out of range, non-finite
/// positions) give the input values unchanged.
/// `channels` are the component groups fitted as units (a normal's three
/// components, a UV pair): at a level vertex whose wedges disagree on a
/// channel (a seam of it), that channel keeps its input values.
pub fn fit(src: Source<'_>, level: Level<'_>, channels: &[Channel]) -> Fitted {
    let dims = src.dims;
    // Unknowns: distinct (level vertex, wedge) pairs.
    let mut keys: Vec<(u32, u32)> = level
        .triangles
        .iter()
        .zip(level.wedges)
        .flat_map(|(t, w)| (0..3).map(move |k| (t[k], w[k])))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    let wedge_count = src.positions.len();
    let valid = src.values.len() == dims * wedge_count
        && keys.iter().all(|&(_, w)| (w as usize) < wedge_count);
    if !valid || dims == 0 {
        return Fitted {
            keys: Vec::new(),
            values: Vec::new(),
            dims,
        };
    }
    let x0: Vec<f64> = keys
        .iter()
        .flat_map(|&(_, w)| {
            let w = w as usize;
            src.values[w * dims..(w + 1) * dims]
                .iter()
                .map(|&x| f64::from(x))
        })
        .collect();
    let input = |x: Vec<f64>| Fitted {
        keys: keys.clone(),
        values: x.iter().map(|&v| v as f32).collect(),
        dims,
    };
    if level.wedges.len() != level.triangles.len()
        || MeshRef::new(src.positions, src.triangles)
            .validate()
            .is_err()
    {
        return input(x0);
    }
    let Ok(bvh) = TriangleBvh::new(MeshRef::new(level.positions, level.triangles)) else {
        return input(x0);
    };
    let unknown = |v: u32, w: u32| keys.binary_search(&(v, w)).unwrap_or(0) as u32;
    let corner_keys: Vec<[u32; 3]> = level
        .triangles
        .iter()
        .zip(level.wedges)
        .map(|(t, w)| [0, 1, 2].map(|k| unknown(t[k], w[k])))
        .collect();
    let sums = Sums::of(src, level, &bvh);
    let problem = Problem {
        src,
        keys: &keys,
        corner_keys: &corner_keys,
        x0: &x0,
        sums: &sums,
    };
    let mut x = x0.clone();
    for channel in channels {
        problem.fit_channel(channel, &mut x);
    }
    input(x)
}

/// Every input sample's contribution, summed per level triangle: the 3×3
/// block `Σ ω γ_i γ_j`, the right-hand sides `Σ ω γ_i a_d(p)`, and the range
/// of the input values that landed on it.
struct Sums {
    block: Vec<f64>,
    rhs0: Vec<f64>,
    seen: Vec<[f64; 2]>,
}

impl Sums {
    /// Samples → (level triangle, barycentrics), in parallel batches, then
    /// summed in sample order: memory bounded by the level, not by the
    /// sample count. A sample counts only where the level triangle is in the
    /// input triangle's chart.
    fn of(src: Source<'_>, level: Level<'_>, bvh: &TriangleBvh) -> Sums {
        let dims = src.dims;
        let chart = charts(src.positions.len(), src.triangles);
        let level_chart: Vec<u32> = level.wedges.iter().map(|w| chart[w[0] as usize]).collect();
        let p3 = |ps: &[[f32; 3]], v: u32| ps[v as usize].map(f64::from);
        let (chart, level_chart) = (&chart, &level_chart);
        let nl = level.triangles.len();
        let mut block = vec![0.0f64; 9 * nl];
        let mut rhs0 = vec![0.0f64; 3 * dims * nl];
        // the range of the input values that landed on each level triangle
        let mut seen = vec![[f64::INFINITY, f64::NEG_INFINITY]; dims * nl];
        let total = src.triangles.len() * RULE.len();
        let mut start = 0;
        while start < total {
            let end = (start + BATCH * CHUNK).min(total);
            let hits: Vec<Option<(u32, [f64; 3])>> = (start..end)
                .collect::<Vec<usize>>()
                .par_chunks(CHUNK)
                .flat_map_iter(|chunk| {
                    // (consecutive samples lie on one input triangle or the next: each
                    // query starts from the previous answer; the answer is the same)
                    let mut hint = None;
                    chunk.iter().map(move |&i| {
                        let tri = src.triangles[i / RULE.len()];
                        let [a, b, c] = tri.map(|v| p3(src.positions, v));
                        let g = RULE[i % RULE.len()].0;
                        let p = [0, 1, 2].map(|k| g[0] * a[k] + g[1] * b[k] + g[2] * c[k]);
                        let (_, lt, q, h) = bvh.closest_point_from(p, hint)?;
                        hint = Some(h);
                        if level_chart[lt as usize] != chart[tri[0] as usize] {
                            return None;
                        }
                        let lp = level.triangles[lt as usize].map(|v| p3(level.positions, v));
                        Some((lt, barycentric(lp, q)))
                    })
                })
                .collect();
            for (i, hit) in (start..end).zip(hits) {
                let Some((lt, g)) = hit else { continue };
                let tri = src.triangles[i / RULE.len()];
                let [a, b, c] = tri.map(|v| p3(src.positions, v));
                let (beta, weight) = RULE[i % RULE.len()];
                let omega = 0.5 * norm(cross(sub(b, a), sub(c, a))) * weight;
                if omega == 0.0 || !omega.is_finite() {
                    continue;
                }
                let lt = lt as usize;
                for i in 0..3 {
                    for j in 0..3 {
                        block[9 * lt + 3 * i + j] += omega * g[i] * g[j];
                    }
                }
                for d in 0..dims {
                    let value: f64 = (0..3)
                        .map(|k| beta[k] * f64::from(src.values[tri[k] as usize * dims + d]))
                        .sum();
                    for i in 0..3 {
                        rhs0[(3 * lt + i) * dims + d] += omega * g[i] * value;
                    }
                    let r = &mut seen[lt * dims + d];
                    *r = [r[0].min(value), r[1].max(value)];
                }
            }
            start = end;
        }
        Sums { block, rhs0, seen }
    }
}

/// The sparse normal matrix of one channel's unknowns (CSR).
struct Normal {
    row_start: Vec<usize>,
    cols: Vec<u32>,
    vals: Vec<f64>,
}

/// The least-squares problem of a level: its keys, each level triangle's
/// corner keys, the input values `x0` and the summed samples.
struct Problem<'a> {
    src: Source<'a>,
    keys: &'a [(u32, u32)],
    corner_keys: &'a [[u32; 3]],
    x0: &'a [f64],
    sums: &'a Sums,
}

impl Problem<'_> {
    /// Fit `channel`'s components of `x`.
    fn fit_channel(&self, channel: &Channel, x: &mut [f64]) {
        let dims = self.src.dims;
        let range = &channel.components;
        let range = range.start.min(dims)..range.end.min(dims);
        if range.is_empty() {
            return;
        }
        let (unk, rep) = self.unknowns(&range);
        let m = rep.len();
        let width = range.len();
        let (normal, rhs) = self.normal_equations(&unk, m, &range);
        let Normal {
            row_start,
            cols,
            vals,
        } = &normal;
        let mut diag = vec![0.0; m];
        for i in 0..m {
            for e in row_start[i]..row_start[i + 1] {
                if cols[e] as usize == i {
                    diag[i] = vals[e];
                }
            }
        }
        // Regularisation: λ·D_i, and a unit pull where nothing constrains x_i.
        let scale = diag
            .iter()
            .copied()
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let reg: Vec<f64> = diag
            .iter()
            .map(|&d| if d > 0.0 { LAMBDA * d } else { scale })
            .collect();
        let apply = |y: &[f64], out: &mut [f64]| {
            for i in 0..m {
                let mut s = reg[i] * y[i];
                for e in row_start[i]..row_start[i + 1] {
                    s += vals[e] * y[cols[e] as usize];
                }
                out[i] = s;
            }
        };
        let precondition = diag_plus(&diag, &reg);
        let bounds = self.bounds(&unk, m, &range);
        let x0 = self.x0;
        for c in 0..width {
            let d = range.start + c;
            let start: Vec<f64> = rep.iter().map(|&i| x0[i * dims + d]).collect();
            let b: Vec<f64> = (0..m)
                .map(|i| rhs[i * width + c] + reg[i] * start[i])
                .collect();
            let mut y = start;
            conjugate_gradients(&apply, &b, &precondition, &mut y);
            for (i, &u) in unk.iter().enumerate() {
                if u != u32::MAX && y[u as usize].is_finite() {
                    x[i * dims + d] = if channel.bounded {
                        let [lo, hi] = bounds[u as usize * width + c];
                        let own = x0[i * dims + d];
                        y[u as usize].clamp(lo.min(own), hi.max(own))
                    } else {
                        y[u as usize]
                    };
                }
            }
        }
    }

    /// One unknown per level vertex where its wedges agree on the channel's
    /// components, none (`u32::MAX`: input values kept) where they differ:
    /// key → unknown, and each unknown's representative key (its start
    /// value).
    fn unknowns(&self, range: &Range<usize>) -> (Vec<u32>, Vec<usize>) {
        let (dims, values) = (self.src.dims, self.src.values);
        let mut unk = vec![u32::MAX; self.keys.len()];
        let mut count = 0u32;
        let mut first = 0;
        for run in self.keys.chunk_by(|a, b| a.0 == b.0) {
            let same = run.iter().all(|&(_, w)| {
                range.clone().all(|c| {
                    values[w as usize * dims + c].to_bits()
                        == values[run[0].1 as usize * dims + c].to_bits()
                })
            });
            if same {
                unk[first..first + run.len()].fill(count);
                count += 1;
            }
            first += run.len();
        }
        let mut rep = vec![0usize; count as usize];
        for (i, &u) in unk.iter().enumerate().rev() {
            if u != u32::MAX {
                rep[u as usize] = i;
            }
        }
        (unk, rep)
    }

    /// Normal matrix (CSR) and right-hand sides (`range.len()` per
    /// unknown) from the blocks, in level-triangle order; fixed corners go
    /// to the right-hand side.
    fn normal_equations(&self, unk: &[u32], m: usize, range: &Range<usize>) -> (Normal, Vec<f64>) {
        let (dims, width) = (self.src.dims, range.len());
        let (block, rhs0, x0) = (&self.sums.block, &self.sums.rhs0, self.x0);
        let mut triplets: Vec<(u32, u32, f64)> = Vec::with_capacity(9 * self.corner_keys.len());
        let mut rhs = vec![0.0; m * width];
        for (lt, ks) in self.corner_keys.iter().enumerate() {
            let bl = &block[9 * lt..9 * lt + 9];
            for i in 0..3 {
                let ui = unk[ks[i] as usize];
                if ui == u32::MAX {
                    continue;
                }
                for c in 0..width {
                    let d = range.start + c;
                    let mut r = rhs0[(3 * lt + i) * dims + d];
                    for k in 0..3 {
                        if unk[ks[k] as usize] == u32::MAX {
                            r -= bl[3 * i + k] * x0[ks[k] as usize * dims + d];
                        }
                    }
                    rhs[ui as usize * width + c] += r;
                }
                for j in 0..3 {
                    let uj = unk[ks[j] as usize];
                    if uj != u32::MAX && bl[3 * i + j] != 0.0 {
                        triplets.push((ui, uj, bl[3 * i + j]));
                    }
                }
            }
        }
        triplets.sort_by_key(|x| (x.0, x.1));
        let mut row_start = vec![0usize; m + 1];
        let (mut cols, mut vals): (Vec<u32>, Vec<f64>) = (Vec::new(), Vec::new());
        for run in triplets.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
            row_start[run[0].0 as usize + 1] += 1;
            cols.push(run[0].1);
            vals.push(run.iter().map(|x| x.2).sum());
        }
        for i in 0..m {
            row_start[i + 1] += row_start[i];
        }
        let normal = Normal {
            row_start,
            cols,
            vals,
        };
        (normal, rhs)
    }

    /// Each unknown's bounds per component: the range of the input values
    /// that landed on its level triangles.
    fn bounds(&self, unk: &[u32], m: usize, range: &Range<usize>) -> Vec<[f64; 2]> {
        let (dims, width) = (self.src.dims, range.len());
        let mut bounds = vec![[f64::INFINITY, f64::NEG_INFINITY]; m * width];
        for (lt, ks) in self.corner_keys.iter().enumerate() {
            for &k in ks {
                let u = unk[k as usize];
                if u == u32::MAX {
                    continue;
                }
                for c in 0..width {
                    let (r, b) = (
                        self.sums.seen[lt * dims + range.start + c],
                        &mut bounds[u as usize * width + c],
                    );
                    *b = [b[0].min(r[0]), b[1].max(r[1])];
                }
            }
        }
        bounds
    }
}

fn diag_plus(diag: &[f64], reg: &[f64]) -> Vec<f64> {
    diag.iter().zip(reg).map(|(a, b)| a + b).collect()
}

/// Jacobi-preconditioned CG for `A y = b` from the start value in `y`.
fn conjugate_gradients(apply: &dyn Fn(&[f64], &mut [f64]), b: &[f64], diag: &[f64], y: &mut [f64]) {
    let n = b.len();
    let free = |i: usize| diag[i] > 0.0;
    let mut ay = vec![0.0; n];
    apply(y, &mut ay);
    let mut r: Vec<f64> = (0..n)
        .map(|i| if free(i) { b[i] - ay[i] } else { 0.0 })
        .collect();
    let precondition = |r: &[f64]| -> Vec<f64> {
        (0..n)
            .map(|i| if free(i) { r[i] / diag[i] } else { 0.0 })
            .collect()
    };
    let mut z = precondition(&r);
    let mut p = z.clone();
    let mut rz: f64 = dot_n(&r, &z);
    let b_norm = dot_n(b, b).sqrt().max(f64::MIN_POSITIVE);
    let mut ap = vec![0.0; n];
    for _ in 0..MAX_ITERATIONS {
        if dot_n(&r, &r).sqrt() <= TOLERANCE * b_norm {
            break;
        }
        apply(&p, &mut ap);
        let pap = dot_n(&p, &ap);
        if pap <= 0.0 || !pap.is_finite() {
            break;
        }
        let alpha = rz / pap;
        for i in 0..n {
            y[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
        }
        z = precondition(&r);
        let rz_next = dot_n(&r, &z);
        let beta = rz_next / rz.max(f64::MIN_POSITIVE);
        rz = rz_next;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
}

/// Wedge → chart (wedge-connected component of the triangles), as the
/// smallest wedge of the component.
pub fn charts(wedge_count: usize, triangles: &[[u32; 3]]) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..wedge_count as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    for t in triangles {
        if t.iter().any(|&v| v as usize >= wedge_count) {
            continue;
        }
        for k in 1..3 {
            let (a, b) = (find(&mut parent, t[0]), find(&mut parent, t[k]));
            parent[a.max(b) as usize] = a.min(b);
        }
    }
    (0..wedge_count as u32)
        .map(|v| find(&mut parent, v))
        .collect()
}

/// Barycentric coordinates of `q` (on the triangle's plane) in `t`; the
/// first corner's for a degenerate triangle.
/// Barycentric coordinates of `q` (projected onto the triangle's plane,
/// clamped into the triangle) in triangle `t`.
pub fn barycentric(t: [[f64; 3]; 3], q: [f64; 3]) -> [f64; 3] {
    let (v0, v1, v2) = (sub(t[1], t[0]), sub(t[2], t[0]), sub(q, t[0]));
    let (d00, d01, d11) = (dot(v0, v0), dot(v0, v1), dot(v1, v1));
    let (d20, d21) = (dot(v2, v0), dot(v2, v1));
    let den = d00 * d11 - d01 * d01;
    if den.abs() <= 1e-300 || !den.is_finite() {
        return [1.0, 0.0, 0.0];
    }
    let v = ((d11 * d20 - d01 * d21) / den).clamp(0.0, 1.0);
    let w = ((d00 * d21 - d01 * d20) / den).clamp(0.0, 1.0 - v);
    [1.0 - v - w, v, w]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
fn dot_n(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
