//! The largest distance from the points of one surface to another, found by bounded
//! subdivision (branch and bound) instead of dense sampling, with a certified upper bound.
//!
//! Method (after M. Guthe, P. Borodin, R. Klein, "Fast and accurate Hausdorff distance
//! calculation between meshes", WSCG 2005, and M. Tang, M. Lee, Y. J. Kim, "Interactive
//! Hausdorff distance computation for general polygonal models", SIGGRAPH 2009): the distance
//! from a point x to the surface Y is at most its distance to any one triangle Y_k of Y, and
//! the distance to one triangle is a convex function of x. So over a triangle T = (p0, p1, p2)
//! of the sampled mesh,
//!
//! ```text
//! sup_{x in T} d(x, Y)  <=  U(T) = min_k max_j dist(p_j, Y_k)
//! ```
//!
//! for any set of candidate triangles Y_k (here: the nearest triangles of T's corners and of
//! its ancestors' corners). The running maximum L is the largest exact distance found at a
//! point of the surface (so it never exceeds the true maximum). T is settled when
//! `U(T) <= L (1 + relative) + absolute`; otherwise it is split into four at its edge
//! midpoints, whose exact distances are measured (raising L) and which are bounded in turn.
//! When nothing is left to split, the true maximum H satisfies
//! `L <= H <= max(L (1 + relative) + absolute, bound of any cell left at the depth limit)`.
//! Since `U(T) <= d(p_j) + diam(T) <= L + diam(T)`, a cell is settled once its diameter is
//! below the tolerance, so the subdivision always ends.
//!
//! Most triangles cost no search at all: a triangle whose three corners are all within the
//! tolerance of the previous triangle's nearest triangle (triangles come in Z-order, so that
//! one is usually adjacent) is settled by three point–triangle distances.
//!
//! Determinism: triangles are processed in fixed chunks (never derived from the thread
//! count), each starting from the same floor; the chunk maxima are combined by `max`. So the
//! result is bit-identical whatever the number of threads.

use rayon::prelude::*;

use super::bvh::{Hint, TriangleBvh};
use super::triangle::{cross, dot, sub, widen};
use super::MeshRef;

/// When a cell counts as settled: its upper bound is at most `L (1 + relative) + absolute`
/// for the running maximum `L` (`absolute` in the meshes' units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Tolerance {
    pub relative: f64,
    pub absolute: f64,
}

impl Tolerance {
    /// The squared distance a cell's bound may reach and be settled, for the running squared
    /// maximum `l2`.
    #[inline]
    fn settle2(&self, l2: f64) -> f64 {
        let t = l2.sqrt() * (1.0 + self.relative) + self.absolute;
        t * t
    }
}

/// The result of [`bounded_max`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BoundedMax {
    /// Largest squared distance found at a point of the surface (or the floor).
    pub max2: f64,
    /// Squared upper bound on the true maximum.
    pub bound2: f64,
    /// Exact closest-point queries made.
    pub queries: usize,
    /// Where a squared distance above the floor was found (`None`: nothing above it).
    pub at: Option<[f64; 3]>,
}

/// Triangles per unit of parallel work: fixed, so the result does not depend on the threads.
const CHUNK_TRIANGLES: usize = 1024;

/// Subdivision depth limit: a cell of depth 20 is a millionth of its triangle's size. Reached
/// only when the tolerance is far below the triangle size; the cell's own bound then enters
/// [`BoundedMax::bound2`], so the bound stays true.
const MAX_DEPTH: u8 = 20;

/// Candidate triangles kept per cell (its corners' nearest, then its ancestors').
const CANDIDATES: usize = 8;

/// A corner of a cell: its position, squared distance to the surface and nearest triangle's
/// slot in the hierarchy.
#[derive(Clone, Copy, Debug)]
struct Corner {
    p: [f64; 3],
    d2: f64,
    slot: u32,
    /// Where a search from this corner starts (`None`: from the root).
    hint: Option<Hint>,
}

/// A triangle (or part of one) of the sampled mesh waiting to be bounded.
#[derive(Clone, Copy, Debug)]
struct Cell {
    c: [Corner; 3],
    cand: [u32; CANDIDATES],
    n: u8,
    depth: u8,
}

impl Cell {
    /// A cell with corners `c` whose candidates are its corners' nearest triangles, then
    /// `inherited`, without repeats, at most [`CANDIDATES`].
    fn new(c: [Corner; 3], inherited: &[u32], depth: u8) -> Cell {
        let mut cell = Cell {
            c,
            cand: [0; CANDIDATES],
            n: 0,
            depth,
        };
        for s in c.iter().map(|k| k.slot).chain(inherited.iter().copied()) {
            let n = usize::from(cell.n);
            if n < CANDIDATES && !cell.cand[..n].contains(&s) {
                cell.cand[n] = s;
                cell.n += 1;
            }
        }
        cell
    }
}

/// The largest distance from the surface of `from` (validated, non-empty) to the surface in
/// `to`, at least `floor2` (a squared distance already attained, e.g. by samples), with its
/// certified upper bound. `order` lists `from`'s triangles, best in Z-order.
pub(crate) fn bounded_max(
    from: MeshRef<'_>,
    order: &[u32],
    to: &TriangleBvh,
    floor2: f64,
    tol: Tolerance,
) -> BoundedMax {
    if to.is_empty() {
        return BoundedMax {
            max2: f64::INFINITY,
            bound2: f64::INFINITY,
            queries: 0,
            at: None,
        };
    }
    let partials: Vec<BoundedMax> = order
        .par_chunks(CHUNK_TRIANGLES)
        .map(|chunk| bound_chunk(from, chunk, to, floor2, tol))
        .collect();
    let mut out = BoundedMax {
        max2: floor2,
        bound2: 0.0,
        queries: 0,
        at: None,
    };
    for p in partials {
        if p.max2 > out.max2 {
            out.max2 = p.max2;
            out.at = p.at;
        }
        out.bound2 = out.bound2.max(p.bound2);
        out.queries += p.queries;
    }
    // every settled cell's bound is within the tolerance of its chunk's final maximum, which
    // is at most the overall one
    out.bound2 = out.bound2.max(tol.settle2(out.max2));
    out
}

/// [`bounded_max`] over one chunk of triangles; `bound2` holds only the cells left at the
/// depth limit.
fn bound_chunk(
    from: MeshRef<'_>,
    tris: &[u32],
    to: &TriangleBvh,
    floor2: f64,
    tol: Tolerance,
) -> BoundedMax {
    let mut out = BoundedMax {
        max2: floor2,
        bound2: 0.0,
        queries: 0,
        at: None,
    };
    let mut hint: Option<Hint> = None;
    let mut stack: Vec<Cell> = Vec::new();
    let mut recent = Recent::default();
    for &t in tris {
        let p = from.triangles[t as usize].map(|v| widen(from.positions[v as usize]));
        if recent.settles(p, to, tol.settle2(out.max2)) {
            continue;
        }
        let c = p.map(|q| exact(to, q, &mut hint, &mut out));
        for k in &c {
            recent.push(k.slot);
        }
        stack.push(Cell::new(c, &[], 0));
        while let Some(cell) = stack.pop() {
            refine(cell, to, tol, &mut out, &mut stack);
        }
    }
    out
}

/// The nearest triangles of the last corners measured exactly (most recent first), as
/// candidates that may bound the next triangles without any search.
#[derive(Clone, Copy, Debug, Default)]
struct Recent {
    slots: [u32; CANDIDATES],
    n: usize,
}

impl Recent {
    fn push(&mut self, slot: u32) {
        let at = self.slots[..self.n].iter().position(|&s| s == slot);
        let end = at.unwrap_or(self.n.min(CANDIDATES - 1));
        self.slots.copy_within(0..end, 1);
        self.slots[0] = slot;
        if at.is_none() && self.n < CANDIDATES {
            self.n += 1;
        }
    }

    /// True when the candidates bound the triangle `p` within `settle` (squared): one
    /// candidate near all three corners, or the pieces of [`piece_bound`].
    fn settles(&self, p: [[f64; 3]; 3], to: &TriangleBvh, settle: f64) -> bool {
        if self.n == 0 {
            return false;
        }
        let corner = |p| Corner {
            p,
            d2: f64::INFINITY,
            slot: u32::MAX,
            hint: None,
        };
        let mut cell = Cell::new(p.map(corner), &[], 0);
        cell.n = 0;
        cell.cand[..self.n].copy_from_slice(&self.slots[..self.n]);
        cell.n = self.n as u8;
        simple_bound(&cell, to, settle) <= settle || piece_bound(&cell, to, settle) <= settle
    }
}

/// The exact nearest triangle of `q`, searched from `hint`; raises the maximum.
#[inline]
fn exact(to: &TriangleBvh, q: [f64; 3], hint: &mut Option<Hint>, out: &mut BoundedMax) -> Corner {
    let (d2, h, _) = to
        .closest_slot(q, *hint)
        .expect("a non-empty hierarchy always has an answer");
    *hint = Some(h);
    out.queries += 1;
    if d2 > out.max2 {
        out.max2 = d2;
        out.at = Some(q);
    }
    Corner {
        p: q,
        d2,
        slot: h.slot,
        hint: Some(h),
    }
}

/// Bounds `cell`: settled when its upper bound (the better of [`simple_bound`] and
/// [`piece_bound`]) is within the tolerance, else split into four (pushed on `stack`) or, at
/// the depth limit, its bound kept.
fn refine(
    cell: Cell,
    to: &TriangleBvh,
    tol: Tolerance,
    out: &mut BoundedMax,
    stack: &mut Vec<Cell>,
) {
    let settle = tol.settle2(out.max2);
    let mut upper = simple_bound(&cell, to, settle);
    if upper <= settle {
        return;
    }
    upper = upper.min(piece_bound(&cell, to, settle));
    if upper <= settle {
        return;
    }
    if cell.depth >= MAX_DEPTH {
        out.bound2 = out.bound2.max(upper);
        return;
    }
    let [a, b, c] = cell.c;
    let mid = |x: &Corner, y: &Corner, out: &mut BoundedMax| {
        let q = std::array::from_fn(|k| 0.5 * (x.p[k] + y.p[k]));
        exact(to, q, &mut { x.hint }, out)
    };
    let ab = mid(&a, &b, out);
    let bc = mid(&b, &c, out);
    let ca = mid(&c, &a, out);
    let inherited = &cell.cand[..usize::from(cell.n)];
    let depth = cell.depth + 1;
    stack.push(Cell::new([ab, bc, ca], inherited, depth));
    stack.push(Cell::new([ca, bc, c], inherited, depth));
    stack.push(Cell::new([ab, b, bc], inherited, depth));
    stack.push(Cell::new([a, ab, ca], inherited, depth));
}

/// `min_k max_j dist²(p_j, Y_k)` over the cell's candidates Y_k (the distance to one triangle
/// is convex, so its maximum over the cell is at a corner); stops at the first candidate whose
/// value is at most `settle`.
fn simple_bound(cell: &Cell, to: &TriangleBvh, settle: f64) -> f64 {
    let mut upper = f64::INFINITY;
    for &k in &cell.cand[..usize::from(cell.n)] {
        let mut m = 0.0f64;
        for c in &cell.c {
            let d2 = if c.slot == k {
                c.d2
            } else {
                to.slot_distance_squared(c.p, k)
            };
            m = m.max(d2);
            if m >= upper {
                break;
            }
        }
        upper = upper.min(m);
        if upper <= settle {
            break;
        }
    }
    upper
}

const PIECES: usize = CANDIDATES;

/// Vertices of a cell clipped by at most [`CANDIDATES`] − 1 planes.
const POLY: usize = 3 + CANDIDATES;

/// A bound for cells over several triangles of the target (a crease, a vertex's fan), where
/// no single candidate is near all three corners. Each candidate Y_k gets the affine function
/// `h_k(x) = |x − c_k|² − R_k² − |x|²` (the power of x with respect to Y_k's circumsphere,
/// centre c_k, radius R_k, less |x|²); the cell is cut into the convex pieces
/// `P_k = {x : h_k(x) ≤ h_j(x) for all j}`, which cover it (every point has a smallest `h`).
/// On `P_k` the distance to the surface is at most the distance to Y_k, a convex function, so
/// its maximum over `P_k` is at one of `P_k`'s vertices:
/// `sup_cell d ≤ max_k max_{v ∈ P_k} dist²(v, Y_k)`. Any affine functions give a true bound;
/// these make it tight near the surface, since the power diagram of the circumspheres of
/// adjacent triangles is cut along their shared edges (the radical plane of two triangles'
/// circumspheres contains the edge they share). Returns early, with a value above `settle`,
/// as soon as the bound exceeds it.
fn piece_bound(cell: &Cell, to: &TriangleBvh, settle: f64) -> f64 {
    // (slot, a, b): h(x) = a·x + b, the power of x with respect to the candidate's
    // circumsphere minus |x|²
    let mut planes = [(0u32, [0.0f64; 3], 0.0f64); CANDIDATES];
    let mut count = 0;
    for &k in &cell.cand[..usize::from(cell.n).min(PIECES)] {
        let Some((c, r2)) = circumsphere(to.slot_triangle(k)) else {
            continue; // no circumsphere: the other candidates' pieces still cover the cell
        };
        planes[count] = (k, c.map(|x| -2.0 * x), dot(c, c) - r2);
        count += 1;
    }
    if count == 0 {
        return f64::INFINITY;
    }
    let mut bound = 0.0f64;
    for i in 0..count {
        let mut poly = [[0.0f64; 3]; POLY];
        poly[..3].copy_from_slice(&cell.c.map(|c| c.p));
        let mut len = 3;
        for j in 0..count {
            if j == i || len == 0 {
                continue;
            }
            // keep h_i − h_j ≤ 0
            let w = sub(planes[i].1, planes[j].1);
            let o = planes[j].2 - planes[i].2;
            len = clip(&mut poly, len, w, o);
        }
        let slot = planes[i].0;
        for v in &poly[..len] {
            bound = bound.max(to.slot_distance_squared(*v, slot));
            if bound > settle {
                return bound;
            }
        }
    }
    bound
}

/// Clips the convex polygon `poly[..len]` to the half-space `w·x − o ≤ 0` (Sutherland–Hodgman);
/// returns the new length (at most one more).
fn clip(poly: &mut [[f64; 3]; POLY], len: usize, w: [f64; 3], o: f64) -> usize {
    let side = |p: [f64; 3]| dot(w, p) - o;
    let mut out = [[0.0f64; 3]; POLY];
    let mut n = 0;
    for i in 0..len {
        let p = poly[i];
        let q = poly[(i + 1) % len];
        let (sp, sq) = (side(p), side(q));
        if sp <= 0.0 {
            out[n] = p;
            n += 1;
        }
        if (sp <= 0.0) != (sq <= 0.0) && n < POLY {
            let t = sp / (sp - sq);
            out[n] = std::array::from_fn(|k| p[k] + t * (q[k] - p[k]));
            n += 1;
        }
    }
    *poly = out;
    n
}

/// Centre and squared radius of the smallest sphere through the corners of a triangle (its
/// centre lies in the triangle's plane); `None` for a degenerate triangle.
fn circumsphere([a, b, c]: [[f64; 3]; 3]) -> Option<([f64; 3], f64)> {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let n = cross(ab, ac);
    let n2 = dot(n, n);
    if n2.is_nan() || n2 <= 0.0 || !n2.is_finite() {
        return None;
    }
    let t1 = cross(n, ab).map(|x| x * dot(ac, ac));
    let t2 = cross(ac, n).map(|x| x * dot(ab, ab));
    let off: [f64; 3] = std::array::from_fn(|k| (t1[k] + t2[k]) / (2.0 * n2));
    let centre = std::array::from_fn(|k| a[k] + off[k]);
    Some((centre, dot(off, off)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn piece_bound_is_tight_over_a_crease() {
        // a roof: two triangles meeting along x = 0, a 10° dihedral crease
        let h = 0.1f32;
        let p = [
            [-1.1, -0.9, -h],
            [0.0, -1.0, 0.0],
            [0.0, 1.0, 0.0],
            [-0.9, 1.2, -h],
            [1.2, -1.1, -h],
            [0.9, 0.8, -h],
        ];
        let t = [[0u32, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]];
        let bvh = TriangleBvh::build_validated(MeshRef::new(&p, &t));
        let z = 0.01;
        let q = [[-0.5, -0.2, z], [0.5, -0.2, z], [0.0, 0.5, z]];
        let c = q.map(|p| {
            let (d2, h, _) = bvh.closest_slot(p, None).unwrap();
            Corner {
                p,
                d2,
                slot: h.slot,
                hint: Some(h),
            }
        });
        let cell = Cell::new(c, &[0, 1, 2, 3], 0);
        let simple = simple_bound(&cell, &bvh, 0.0).sqrt();
        let piece = piece_bound(&cell, &bvh, f64::INFINITY).sqrt();
        let truth = (0..=100)
            .flat_map(|i| (0..=100 - i).map(move |j| (i, j)))
            .map(|(i, j)| {
                let (u, v) = (f64::from(i) / 100.0, f64::from(j) / 100.0);
                let x: [f64; 3] = std::array::from_fn(|k| {
                    q[0][k] + u * (q[1][k] - q[0][k]) + v * (q[2][k] - q[0][k])
                });
                bvh.closest_slot(x, None).unwrap().0.sqrt()
            })
            .fold(0.0, f64::max);
        eprintln!(
            "simple {simple} piece {piece} truth {truth} cands {:?}",
            &cell.cand[..cell.n as usize]
        );
        assert!(piece >= truth * (1.0 - 1e-12));
        assert!(piece <= truth * 1.01);
    }
}
