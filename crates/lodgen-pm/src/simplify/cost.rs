//! A pair's contraction target and cost: where the merged vertex goes
//! (optimal placement, or an endpoint for locked, border, feature and seam
//! vertices), its quadric cost, the attribute term and the cost scale.

use super::{dv, Entry, Simplifier};
use crate::mesh::adjacency::FanLookup;
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
            // the corners' rule (`pinned`), and a seam corner is never the
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

    /// A seam corner or end: never removed.
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
        self.scaled(cost, a, b)
    }

    /// The heap key from the pair's cost: times the cost scale, as `f32`.
    #[inline]
    pub(super) fn scaled(&self, mut cost: f64, a: u32, b: u32) -> f32 {
        if let Some(s) = &self.cost_scale {
            cost *= f64::from(s[a as usize].max(s[b as usize]));
        }
        cost as f32
    }

    /// Neither locked, pinned nor fixed: a pair of two such vertices takes
    /// [`Quadric::placement`] in `target_with`.
    #[inline]
    pub(super) fn free(&self, v: u32) -> bool {
        !self.locked[v as usize] && !self.pinned(v) && !self.fixed(v)
    }
}
