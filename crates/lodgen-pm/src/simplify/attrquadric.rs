//! The attribute term of the cost: Hoppe 1999 attribute quadrics, one per
//! wedge ("New quadric metric for simplifying meshes with appearance
//! attributes"; the same quadric as Garland–Heckbert 1998 with the
//! attribute values optimised away).
//!
//! Each face carries, for every attribute component `j`, the linear
//! function `s_j(x) = g_j·x + d_j` that interpolates its corners' values in
//! the face's plane (the gradient `g_j` lies in the plane). A wedge's
//! quadric sums, over the faces around it, `A_f Σ_j (g_j·x + d_j − s_j)²`
//! (`A_f` the face area, like the geometric face quadrics). Placing the
//! vertex at `x` with the best values `s_j` (the area-weighted mean of the
//! faces' `s_j(x)`) leaves
//!
//! ```text
//! E(x) = Σ_f A_f Σ_j s_fj(x)² − Σ_j (Σ_f A_f s_fj(x))² / Σ_f A_f
//! ```
//!
//! the area-weighted variance of the faces' attribute fields at `x`: zero
//! while the merged faces interpolate one linear field, growing as a vertex
//! stands for a region over which the attributes bend (a normal over a
//! curved bump, a UV chart over a fold). Quadrics add on contraction, so a
//! vertex remembers the faces it replaced. Stored per quadric: the
//! quadratic part (6 + 3 + 1), `W = Σ A_f`, and `Σ A_f g_j`, `Σ A_f d_j` per
//! component.
//!
//! Wedges: a welded vertex on a seam has one quadric per wedge (per side):
//! adding a UV chart's faces to the other chart's would price the seam's
//! jump, which nothing moves. When `v0` goes into `v1`, each wedge of `v0`
//! joins the wedge of `v1` its corners take (`Features::wedge_edits`); the
//! cost of a pair evaluates the merged quadrics at the new position, with
//! the same mapping read from the triangles the pair shares.
//!
//! Values are the caller's, pre-multiplied by their weights; the sum is
//! scaled by the squared bounding-box diagonal so that a difference of 1 at
//! weight 1 weighs like a displacement by the whole mesh (meshoptimizer's
//! convention, which works in a unit cube).

use glam::DVec3;
use smallvec::SmallVec;

/// Per-wedge attribute quadrics (module docs).
#[derive(Clone, Debug)]
pub(crate) struct AttributeCost {
    dims: usize,
    /// `11 + 4·dims` coefficients per quadric.
    stride: usize,
    /// Squared bounding-box diagonal.
    scale: f64,
    /// Vertex → (wedge, quadric slot) of each of its wedges.
    slots: Vec<SmallVec<[(u32, u32); 1]>>,
    /// The quadrics, `stride` values each.
    q: Vec<f64>,
}

/// Offsets in a quadric: symmetric 3×3 (a00 a01 a02 a11 a12 a22), b, c, W,
/// then (G_j, D_j) per component.
const B: usize = 6;
const C: usize = 9;
const W: usize = 10;
const G: usize = 11;

/// Wedge of corner `k` of triangle `t` (the vertex itself without wedges).
#[inline]
fn wedge_at(wedges: Option<&[[u32; 3]]>, tris: &[[u32; 3]], t: u32, k: usize) -> u32 {
    wedges.map_or(tris[t as usize][k], |w| w[t as usize][k])
}

/// Wedge of vertex `v` in triangle `t`, if `t` has `v`.
#[inline]
fn wedge_of(wedges: Option<&[[u32; 3]]>, tris: &[[u32; 3]], t: u32, v: u32) -> Option<u32> {
    let k = tris[t as usize].iter().position(|&x| x == v)?;
    Some(wedge_at(wedges, tris, t, k))
}

impl AttributeCost {
    /// Quadrics of every live face, per wedge. `values` holds `dims`
    /// weighted components per wedge id (per vertex without wedges);
    /// `None` when a wedge id has no values (a programming error the caller
    /// reports).
    pub fn new(
        values: &[f32],
        dims: usize,
        pos: &[[f32; 3]],
        tris: &[[u32; 3]],
        alive: &[bool],
        wedges: Option<&[[u32; 3]]>,
        scale: f64,
    ) -> Option<AttributeCost> {
        let stride = G + 4 * dims;
        let mut out = AttributeCost {
            dims,
            stride,
            scale,
            slots: vec![SmallVec::new(); pos.len()],
            q: Vec::new(),
        };
        let value = |w: u32, j: usize| -> Option<f64> {
            values.get(w as usize * dims + j).map(|&x| f64::from(x))
        };
        let mut face = vec![0.0; stride];
        for (t, tri) in tris.iter().enumerate() {
            if !alive[t] {
                continue;
            }
            let ws = [0, 1, 2].map(|k| wedge_at(wedges, tris, t as u32, k));
            if dims > 0 && ws.iter().any(|&w| value(w, dims - 1).is_none()) {
                return None;
            }
            let p = tri.map(|v| {
                let [x, y, z] = pos[v as usize].map(f64::from);
                DVec3::new(x, y, z)
            });
            let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
            let area = 0.5 * e1.cross(e2).length();
            // Gram matrix of the edges: the gradient g = α e1 + β e2 with
            // g·e1 = s1 − s0, g·e2 = s2 − s0.
            let (g11, g12, g22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
            let det = g11 * g22 - g12 * g12;
            if !(area > 0.0 && det > 1e-12 * g11 * g22 && det.is_finite()) {
                continue;
            }
            face.fill(0.0);
            face[W] = area;
            for j in 0..dims {
                let s = ws.map(|w| value(w, j).unwrap_or(0.0));
                let (r1, r2) = (s[1] - s[0], s[2] - s[0]);
                let alpha = (g22 * r1 - g12 * r2) / det;
                let beta = (g11 * r2 - g12 * r1) / det;
                let g = alpha * e1 + beta * e2;
                let d = s[0] - g.dot(p[0]);
                let q = &mut face;
                q[0] += area * g.x * g.x;
                q[1] += area * g.x * g.y;
                q[2] += area * g.x * g.z;
                q[3] += area * g.y * g.y;
                q[4] += area * g.y * g.z;
                q[5] += area * g.z * g.z;
                q[B] += area * g.x * d;
                q[B + 1] += area * g.y * d;
                q[B + 2] += area * g.z * d;
                q[C] += area * d * d;
                let o = G + 4 * j;
                q[o] = area * g.x;
                q[o + 1] = area * g.y;
                q[o + 2] = area * g.z;
                q[o + 3] = area * d;
            }
            for (k, &v) in tri.iter().enumerate() {
                let slot = out.slot(v, ws[k]);
                let dst = &mut out.q[slot * stride..(slot + 1) * stride];
                for (a, b) in dst.iter_mut().zip(&face) {
                    *a += b;
                }
            }
        }
        Some(out)
    }

    /// The slot of `v`'s quadric for `wedge`, created empty if missing.
    fn slot(&mut self, v: u32, wedge: u32) -> usize {
        if let Some(&(_, s)) = self.slots[v as usize].iter().find(|x| x.0 == wedge) {
            return s as usize;
        }
        let s = self.q.len() / self.stride;
        self.q.resize(self.q.len() + self.stride, 0.0);
        self.slots[v as usize].push((wedge, s as u32));
        s
    }

    /// Accumulate quadric `slot` at `x` into (quadratic part, Σ A s_j, W).
    #[inline]
    fn gather(&self, slot: u32, x: DVec3, acc: &mut Acc) {
        let q = &self.q[slot as usize * self.stride..(slot as usize + 1) * self.stride];
        let quad = q[0] * x.x * x.x
            + 2.0 * q[1] * x.x * x.y
            + 2.0 * q[2] * x.x * x.z
            + q[3] * x.y * x.y
            + 2.0 * q[4] * x.y * x.z
            + q[5] * x.z * x.z
            + 2.0 * (q[B] * x.x + q[B + 1] * x.y + q[B + 2] * x.z)
            + q[C];
        acc.quad += quad;
        acc.w += q[W];
        for j in 0..self.dims {
            let o = G + 4 * j;
            acc.lin[j] += q[o] * x.x + q[o + 1] * x.y + q[o + 2] * x.z + q[o + 3];
        }
    }

    /// The added cost of removing `v0` into `v1` placed at `x`: the merged
    /// wedge quadrics' error at `x` (module docs). `fan0` is `v0`'s
    /// triangle list; the pair's shared live triangles map `v0`'s wedges to
    /// `v1`'s.
    #[allow(clippy::too_many_arguments)]
    pub fn cost(
        &self,
        v0: u32,
        v1: u32,
        x: DVec3,
        tris: &[[u32; 3]],
        fan0: &[u32],
        alive: &[bool],
        wedges: Option<&[[u32; 3]]>,
    ) -> f64 {
        let s1 = &self.slots[v1 as usize];
        let mut groups: SmallVec<[(u32, Acc); 2]> = s1
            .iter()
            .map(|&(w, s)| {
                let mut a = Acc::new(self.dims);
                self.gather(s, x, &mut a);
                (w, a)
            })
            .collect();
        for &(w0, s0) in &self.slots[v0 as usize] {
            let target = fan0
                .iter()
                .filter(|&&t| alive[t as usize] && tris[t as usize].contains(&v1))
                .find(|&&t| wedge_of(wedges, tris, t, v0) == Some(w0))
                .and_then(|&t| wedge_of(wedges, tris, t, v1))
                .or_else(|| s1.first().map(|s| s.0));
            match groups.iter_mut().find(|g| Some(g.0) == target) {
                Some(g) => self.gather(s0, x, &mut g.1),
                None => {
                    let mut a = Acc::new(self.dims);
                    self.gather(s0, x, &mut a);
                    groups.push((w0, a));
                }
            }
        }
        let e: f64 = groups.iter().map(|g| g.1.error()).sum();
        self.scale * e
    }

    /// Merge `v0`'s quadrics into `v1`'s after `v0` went into `v1`: each
    /// wedge of `v0` into the wedge its corners took (`edits`, moved
    /// corners' `[before, after]`), or, for a wedge left only on removed
    /// triangles (which keep their corners), into `v1`'s wedge there.
    pub fn contract(
        &mut self,
        v0: u32,
        v1: u32,
        removed: &[u32],
        edits: &[(u32, [u32; 2])],
        tris: &[[u32; 3]],
        wedges: Option<&[[u32; 3]]>,
    ) {
        let from = std::mem::take(&mut self.slots[v0 as usize]);
        for (w0, s0) in from {
            let target = if wedges.is_none() {
                v1
            } else {
                edits
                    .iter()
                    .find(|e| e.1[0] == w0)
                    .map(|e| e.1[1])
                    .or_else(|| {
                        removed
                            .iter()
                            .find(|&&t| wedge_of(wedges, tris, t, v0) == Some(w0))
                            .and_then(|&t| wedge_of(wedges, tris, t, v1))
                    })
                    .or_else(|| self.slots[v1 as usize].first().map(|s| s.0))
                    .unwrap_or(w0)
            };
            let s1 = self.slot(v1, target);
            let (a, b) = (s0 as usize * self.stride, s1 * self.stride);
            for i in 0..self.stride {
                let x = self.q[a + i];
                self.q[b + i] += x;
            }
        }
    }
}

/// A merged quadric evaluated at one point.
struct Acc {
    quad: f64,
    w: f64,
    lin: SmallVec<[f64; 16]>,
}

impl Acc {
    fn new(dims: usize) -> Acc {
        Acc {
            quad: 0.0,
            w: 0.0,
            lin: SmallVec::from_elem(0.0, dims),
        }
    }

    /// `Σ A s² − Σ_j (Σ A s_j)² / W`, never below 0.
    fn error(&self) -> f64 {
        if self.w <= 0.0 {
            return 0.0;
        }
        let mean: f64 = self.lin.iter().map(|l| l * l).sum::<f64>() / self.w;
        (self.quad - mean).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Positions, triangles, and each vertex's triangles.
    type Grid = (Vec<[f32; 3]>, Vec<[u32; 3]>, Vec<Vec<u32>>);

    /// An `n × n` grid on `[0, 1]²`, z = 0.
    fn grid(n: u32) -> Grid {
        let m = crate::shapes::grid(n, n, |_, _| 0.0);
        let mut fans = vec![Vec::new(); m.positions.len()];
        for (t, tri) in m.triangles.iter().enumerate() {
            for &v in tri {
                fans[v as usize].push(t as u32);
            }
        }
        (m.positions, m.triangles, fans)
    }

    fn at(pos: &[[f32; 3]], v: u32) -> DVec3 {
        let [x, y, z] = pos[v as usize].map(f64::from);
        DVec3::new(x, y, z)
    }

    /// Interior vertex (3, 4) of an 8×8 grid and its right neighbour.
    const V0: u32 = 4 * 9 + 3;
    const V1: u32 = 4 * 9 + 4;

    #[test]
    fn a_linear_field_costs_nothing_and_a_curved_one_does() {
        let (pos, tris, fans) = grid(8);
        let alive = vec![true; tris.len()];
        let linear: Vec<f32> = pos.iter().map(|p| 2.0 * p[0] + 3.0 * p[1]).collect();
        let curved: Vec<f32> = pos.iter().map(|p| 4.0 * p[0] * p[0]).collect();
        let cost = |values: &[f32]| {
            let at_cost = AttributeCost::new(values, 1, &pos, &tris, &alive, None, 1.0).unwrap();
            let x = at(&pos, V1);
            at_cost.cost(V0, V1, x, &tris, &fans[V0 as usize], &alive, None)
        };
        assert!(cost(&linear).abs() < 1e-12, "{}", cost(&linear));
        assert!(cost(&curved) > 1e-4, "{}", cost(&curved));
        // moving off the vertex does not matter for a linear field either
        let at_cost = AttributeCost::new(&linear, 1, &pos, &tris, &alive, None, 1.0).unwrap();
        let mid = (at(&pos, V0) + at(&pos, V1)) / 2.0;
        let c = at_cost.cost(V0, V1, mid, &tris, &fans[V0 as usize], &alive, None);
        assert!(c.abs() < 1e-12, "{c}");
    }

    #[test]
    fn a_seam_jump_is_not_priced() {
        // left and right of x = 0.5 are two charts, the right one's values
        // offset by 10; each chart's field is linear. One quadric per
        // welded vertex would mix both charts' fields and price the jump
        // (variance 25 at every seam vertex).
        let (pos, tris, fans) = grid(8);
        let alive = vec![true; tris.len()];
        let nv = pos.len() as u32;
        let right = |t: &[u32; 3]| t.iter().map(|&v| pos[v as usize][0]).sum::<f32>() > 1.5;
        let wedges: Vec<[u32; 3]> = tris
            .iter()
            .map(|t| t.map(|v| if right(t) { v + nv } else { v }))
            .collect();
        let values: Vec<f32> = (0..2 * nv)
            .map(|w| {
                let p = pos[(w % nv) as usize];
                2.0 * p[0] + 3.0 * p[1] + if w >= nv { 10.0 } else { 0.0 }
            })
            .collect();
        // seam vertices (4, 3) → (4, 4): along the seam
        let (s0, s1) = (3 * 9 + 4, 4 * 9 + 4);
        let x = at(&pos, s1);
        let w = Some(&wedges[..]);
        let with = AttributeCost::new(&values, 1, &pos, &tris, &alive, w, 1.0).unwrap();
        let c = with.cost(s0, s1, x, &tris, &fans[s0 as usize], &alive, w);
        assert!(c.abs() < 1e-9, "{c}");
    }

    #[test]
    fn merged_quadrics_remember_the_faces_they_replaced() {
        // a curved field: after v0 went into v1, moving v1 away costs more
        // than it did before (the faces of v0 came along)
        let (pos, tris, fans) = grid(8);
        let alive = vec![true; tris.len()];
        let curved: Vec<f32> = pos.iter().map(|p| 4.0 * p[0] * p[0]).collect();
        let mut q = AttributeCost::new(&curved, 1, &pos, &tris, &alive, None, 1.0).unwrap();
        let v2 = V1 + 1;
        let x = at(&pos, v2);
        let before = q.cost(V1, v2, x, &tris, &fans[V1 as usize], &alive, None);
        q.contract(V0, V1, &[], &[], &tris, None);
        let after = q.cost(V1, v2, x, &tris, &fans[V1 as usize], &alive, None);
        assert!(after > 1.5 * before, "{before} → {after}");
    }
}
