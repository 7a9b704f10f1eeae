//! A pair's contraction target and cost: where the merged vertex goes
//! (optimal placement, or an endpoint for locked, border, feature and seam
//! vertices), its quadric cost, the attribute term and the cost scale.

use super::{dv, Entry, PassEntry, Plan, Simplifier};
use crate::mesh::adjacency::FanLookup;
use crate::simplify::legality::closing_hole;
use crate::simplify::quadric::Quadric;
use crate::simplify::Placement;
use glam::DVec3;

impl Simplifier {
    /// The contraction target and cost of the pair `(a, b)`.
    #[inline]
    pub(super) fn target_of(&self, a: u32, b: u32) -> (DVec3, f64) {
        self.target_with(&(self.quadric[a as usize] + self.quadric[b as usize]), a, b)
    }

    /// [`Simplifier::target_of`] with the pair's summed quadric `q` given.
    #[inline]
    pub(super) fn target_with(&self, q: &Quadric, a: u32, b: u32) -> (DVec3, f64) {
        let (pa, pb) = (dv(self.pos[a as usize]), dv(self.pos[b as usize]));
        match (self.locked[a as usize], self.locked[b as usize]) {
            (true, _) => (pa, q.eval(pa)),
            (false, true) => (pb, q.eval(pb)),
            // Border corners never move to a new position: an interior or
            // border vertex is pulled onto a corner, and two corners merge
            // into the cheaper of the two (half-edge). With optimal
            // placement a corner slides a little along one border line, and
            // the next collapse along the other line cuts it off: borders
            // creep. Other border vertices take optimal placement, held to
            // the border by its constraint planes. Feature vertices follow
            // the corners' rule (`pinned`), and a seam junction is never the
            // one removed (`fixed`).
            (false, false) if self.pinned(a) && !self.pinned(b) || self.fixed(a) => {
                (pa, q.eval(pa))
            }
            (false, false) if self.pinned(b) && !self.pinned(a) || self.fixed(b) => {
                (pb, q.eval(pb))
            }
            (false, false) => match self.opts.placement {
                Placement::Optimal if !self.pinned(a) => q.placement(pa, pb),
                _ => {
                    let (ca, cb) = (q.eval(pa), q.eval(pb));
                    if cb < ca {
                        (pb, cb)
                    } else {
                        (pa, ca)
                    }
                }
            },
        }
    }

    /// `v`'s τ partners.
    #[inline]
    pub(super) fn partners(&self, v: u32) -> &[u32] {
        self.partners.get(v as usize).map_or(&[], |p| p)
    }

    /// A border corner or on a feature line: never moves to a new position.
    #[inline]
    pub(super) fn pinned(&self, v: u32) -> bool {
        self.corner[v as usize] || self.features.as_ref().is_some_and(|f| f.pinned(v))
    }

    /// A seam junction (three or more feature edges): never removed.
    #[inline]
    pub(super) fn fixed(&self, v: u32) -> bool {
        self.features.as_ref().is_some_and(|f| f.fixed(v))
    }

    pub(super) fn entry(&self, a: u32, b: u32) -> Entry {
        let (a, b) = (a.min(b), a.max(b));
        Entry {
            cost: self.key(a, b),
            a,
            b,
            va: self.version.get(a as usize).copied().unwrap_or(0),
            vb: self.version.get(b as usize).copied().unwrap_or(0),
        }
    }

    /// The order key of the pair `(a, b)`, `a < b`: its quadric cost, plus
    /// the attribute term, times the cost scale.
    #[inline]
    pub(super) fn key(&self, a: u32, b: u32) -> f32 {
        let (p, mut cost) = self.target_of(a, b);
        if let Some(at) = &self.attributes {
            // the farther endpoint is the one removed (as in `step`)
            let (pa, pb) = (dv(self.pos[a as usize]), dv(self.pos[b as usize]));
            let (v0, v1) = if (p - pa).length_squared() <= (p - pb).length_squared() {
                (b, a)
            } else {
                (a, b)
            };
            let w = self.features.as_ref().and_then(|f| f.wedges.as_deref());
            let fan0 = self.vtris.fan(v0);
            cost += at.cost(v0, v1, p, &self.tris, fan0, &self.tri_alive, w);
        }
        self.scaled(cost + self.hole_cost(a, b), a, b)
    }

    /// The heap key from the pair's cost: times the cost scale and the cost
    /// unit ([`super::cost_unit`]), as `f32`.
    #[inline]
    pub(super) fn scaled(&self, mut cost: f64, a: u32, b: u32) -> f32 {
        if let Some(s) = &self.cost_scale {
            cost *= f64::from(s[a as usize].max(s[b as usize]));
        }
        (cost * self.cost_unit) as f32
    }

    /// Neither locked, pinned nor fixed: a pair of two such vertices takes
    /// [`Quadric::placement`] in `target_with`.
    #[inline]
    pub(super) fn free(&self, v: u32) -> bool {
        !self.locked[v as usize] && !self.pinned(v) && !self.fixed(v)
    }

    /// What closing a triangular hole costs beside the quadric: the pair
    /// `(a, b)` is a border edge of a hole `a b o` (`legality::closing_hole`)
    /// whose contraction covers it; the new surface lies up to about the
    /// hole's inradius `r` from the rim, over its area `A`: `A · r²`, in the
    /// units of the area-weighted plane quadrics. 0 for any other pair.
    pub(super) fn hole_cost(&self, a: u32, b: u32) -> f64 {
        if !(self.boundary[a as usize] && self.boundary[b as usize]) {
            return 0.0;
        }
        let Some(o) = closing_hole(self.faces(), a, b) else {
            return 0.0;
        };
        // (the same bits for (a, b) and (b, a))
        let [pa, pb, po] = [a.min(b), a.max(b), o].map(|v| dv(self.pos[v as usize]));
        let area = 0.5 * (pb - pa).cross(po - pa).length();
        let perimeter = pa.distance(pb) + pb.distance(po) + po.distance(pa);
        if perimeter <= 0.0 {
            return 0.0;
        }
        let r = 2.0 * area / perimeter;
        HOLE_WEIGHT * area * r * r
    }
}

impl Simplifier {
    /// Whether the pass candidate `e`, planned as `plan`, closes a hole that
    /// became triangular during this pass (so its pass cost lacks
    /// [`Simplifier::hole_cost`]) and, with it, costs more than the pass's
    /// limit: then it waits for the next pass, which costs it with the
    /// hole. (Its own vertices are untouched in the pass, so the pass cost
    /// differs from the current key by the hole's cost alone.)
    pub(super) fn stale_hole(&self, plan: &Plan, e: PassEntry) -> bool {
        if plan.hole <= 0.0 || !self.pass.cost_limit.is_finite() {
            return false;
        }
        let key = self.key(e.a, e.b);
        let hole = self.scaled(plan.hole, e.a, e.b);
        e.cost < key - 0.5 * hole && key > self.pass.cost_limit
    }
}

/// The weight of [`Simplifier::hole_cost`] against the area-weighted plane
/// quadrics (whose border constraint planes weigh `DEFAULT_BOUNDARY_WEIGHT`
/// = 10 times their edge's length²). Measured on the CLI (features on) at
/// 50/10/2 % (`lodgen MESH.obj --levels 50%,10%,2% --report r.json`): at 1,
/// 10 or 100 the teapot's spout opening closes and its 2 % level's
/// Hausdorff goes 3.475 → 4.232 % of the diagonal; from 200 on it stays open
/// (3.475 %); beetle's 10 % level is 12.05 % before hole closing, 9.13 % at
/// 200–300, 10.74 % at 500–3000; `xtask quality --quick` (positions only):
/// beetle 10 % 4.24 → 3.78 % at 300 and 1000, its floor 166 → 120
/// triangles, every other cell unchanged.
const HOLE_WEIGHT: f64 = 1000.0;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;
    use crate::SimplifyOptions;

    /// A border edge of a triangular hole costs `HOLE_WEIGHT · A · r²`
    /// (area and inradius of the hole), any other pair nothing: fails if the
    /// hole is not found or priced otherwise.
    #[test]
    fn closing_a_triangular_hole_costs_its_area_times_its_inradius_squared() {
        let mut m = shapes::icosphere(2);
        let [a, b, c] = m.triangles.remove(7);
        let s = Simplifier::new(&m, &SimplifyOptions::DEFAULT).unwrap();
        let [pa, pb, pc] = [a, b, c].map(|v| dv(m.positions[v as usize]));
        let area = 0.5 * (pb - pa).cross(pc - pa).length();
        let r = 2.0 * area / (pa.distance(pb) + pb.distance(pc) + pc.distance(pa));
        for (x, y) in [(a, b), (b, c), (c, a)] {
            let h = s.hole_cost(x, y);
            assert!((h - HOLE_WEIGHT * area * r * r).abs() <= 1e-9 * h, "{h}");
            assert_eq!(h, s.hole_cost(y, x));
        }
        // an interior edge, and a grid's border edge (no hole)
        let t = m.triangles[0];
        assert_eq!(s.hole_cost(t[0], t[1]), 0.0);
        let grid =
            Simplifier::new(&shapes::grid(4, 4, |_, _| 0.0), &SimplifyOptions::DEFAULT).unwrap();
        assert_eq!(grid.hole_cost(0, 1), 0.0);
    }
}
