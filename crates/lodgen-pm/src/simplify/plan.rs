//! The read-only half of a step: where the pair goes, which end is
//! removed, whether the error is within `max_error`, and whether the
//! contraction is legal ([`super::legality`]). Reads nothing outside the
//! closed one-rings of the pair (what the batched walk relies on).

use super::legality::{fuses_odd_edges, lands_on_any, link, moved_faces_ok, Faces};
use super::reach::{REACH_FACES_MIN_LIVE, REACH_GATE};
use super::{dv, Plan, Rejected, Simplifier, TopologyChange};
use crate::mesh::adjacency::FanLookup;
use crate::util::prefetch;
use glam::DVec3;
use smallvec::SmallVec;

impl Simplifier {
    /// Re-cost the pair `(a, b)` (exact: its vertices are current) and
    /// contract it if it is within `max_error` and legal.
    pub(super) fn try_contract(&mut self, a: u32, b: u32) -> Result<(), Rejected> {
        let plan = self.plan(a, b)?;
        self.contract(plan);
        Ok(())
    }

    /// The read-only half of [`Simplifier::try_contract`]: where the pair
    /// `(a, b)` would go, which end is removed, and whether that is legal.
    /// It reads nothing outside the closed one-rings of `a` and `b` (what
    /// the batched walk's invalidation relies on, see `walk_batch`).
    pub(super) fn plan(&self, a: u32, b: u32) -> Result<Plan, Rejected> {
        let (ai, bi) = (a as usize, b as usize);
        let q = self.quadric[ai] + self.quadric[bi];
        let (p, cost) = self.target_with(&q, a, b);
        let error = q.distance(cost);
        if self.opts.max_error.is_some_and(|m| error > m) {
            return Err(Rejected::Error);
        }
        // v1 (kept) is the endpoint the new vertex is closer to.
        let (v0, v1) = if self.locked[ai]
            || (!self.locked[bi]
                && (p - dv(self.pos[ai])).length_squared()
                    <= (p - dv(self.pos[bi])).length_squared())
        {
            (b, a)
        } else {
            (a, b)
        };
        let (removed, broke) = self.check(v0, v1, p)?;
        // (finite and positive only in a pass with the spread bound)
        let limit = self
            .opts
            .reach
            .map_or(f64::INFINITY, |f| self.pass.spread_limit * f * f);
        let tested = limit.is_finite() && limit > 0.0 && error * error >= REACH_GATE * limit;
        // (the new faces' test while enough of the input lives)
        let faces = self
            .opts
            .reach_faces
            .filter(|_| self.live_tris as f64 >= REACH_FACES_MIN_LIVE * self.tris.len() as f64);
        let deferred = tested
            && (self.reach_over(v0, v1, p, !removed.is_empty(), limit)
                || faces.is_some_and(|f| self.faces_over(v0, v1, p, limit * f * f)));
        let hole = if removed.len() == 1 {
            self.hole_cost(v0, v1)
        } else {
            0.0
        };
        Ok(Plan {
            v0,
            v1,
            p,
            error: error as f32,
            removed,
            deferred,
            hole,
            broke,
        })
    }

    /// Legality of contracting `v0` into `v1` at `p`, cheapest test first.
    /// On success returns the triangles the contraction deletes, and the
    /// first rule it breaks that the run's relaxation stage (`Pass::relax`,
    /// [`crate::SimplifyOptions::topology_change`]) lets pass.
    pub(super) fn check(
        &self,
        v0: u32,
        v1: u32,
        p: DVec3,
    ) -> Result<(SmallVec<[u32; 2]>, Option<Rejected>), Rejected> {
        let (i0, i1) = (v0 as usize, v1 as usize);
        if self.locked[i0] && self.locked[i1] {
            return Err(Rejected::Locked);
        }
        let relax = self.pass.relax;
        let mut broke = None;
        // a refusal the stage lets pass: the first is recorded
        let mut refuse = |r: Rejected| {
            if relax.allows(r) {
                broke.get_or_insert(r);
                Ok(())
            } else {
                Err(r)
            }
        };
        if let Some(f) = &self.features {
            if let Err(r) = f.allows(v0, v1) {
                refuse(r)?;
            }
        }
        let faces = Faces {
            tris: &self.tris,
            alive: &self.tri_alive,
            vtris: &self.vtris,
            pos: &self.pos,
        };
        let l = link(faces, v0, v1);
        // an edge of two or more faces (inside a surface, or where three or
        // more sheets meet) is no border edge: with both ends on a border
        // the contraction would pinch
        if l.shared.len() >= 2 && self.boundary[i0] && self.boundary[i1] {
            refuse(Rejected::BoundaryPinch)?;
        }
        // (a vertex on an edge of three or more faces is a corner, and so
        // is whatever it is contracted into: only corner pairs can fuse)
        let joined = !l.holds()
            || (!l.shared.is_empty()
                && self.corner[i0]
                && self.corner[i1]
                && fuses_odd_edges(faces, v0, v1, &l.opposite));
        if joined {
            refuse(Rejected::Link)?;
        }
        if let Err(r) = moved_faces_ok(faces, v0, v1, p, &l.opposite, |v| self.lifted_at(v)) {
            refuse(r)?;
        }
        // a join lets any face land on another, not only the opposite
        // vertices' (which `moved_faces_ok` tests)
        if joined && lands_on_any(faces, v0, v1) {
            refuse(Rejected::Duplicate)?;
        }
        // (a flattened part's last two faces are on one edge: a run that
        // relaxes the rules keeps at least one face, even through a
        // contraction that breaks none)
        let relaxing = !matches!(
            self.opts.topology_change,
            TopologyChange::Never | TopologyChange::WhenShort
        );
        if (broke.is_some() || relaxing) && l.shared.len() >= self.live_tris {
            return Err(broke.unwrap_or(Rejected::Degenerate));
        }
        Ok((l.shared, broke))
    }

    /// Prefetch what planning the pair `(a, b)` reads first about its
    /// vertices: their fan spans, quadrics and positions.
    #[inline]
    pub(super) fn prefetch_vertices(&self, a: u32, b: u32) {
        for v in [a, b] {
            self.vtris.prefetch_span(v);
            // 88 bytes, 8-aligned: up to three cache lines, each holding
            // one of these fields
            let q = &self.quadric[v as usize];
            prefetch(&q.a2);
            prefetch(&q.bc);
            prefetch(&q.weight);
            prefetch(&self.pos[v as usize]);
        }
    }

    /// Prefetch the triangles of `v`'s fan (its list must be at hand).
    #[inline]
    pub(super) fn prefetch_triangles(&self, v: u32) {
        for &t in self.vtris.fan(v) {
            prefetch(&self.tris[t as usize]);
        }
    }
}
