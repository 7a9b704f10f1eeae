//! The read-only half of a step: where the pair goes, which end is
//! removed, whether the error is within `max_error`, and whether the
//! contraction is legal ([`super::legality`]). Reads nothing outside the
//! closed one-rings of the pair (what the batched walk relies on).

use super::legality::{link, moved_faces_ok, Faces, Link};
use super::{dv, Plan, Rejected, Simplifier};
use crate::mesh::adjacency::FanLookup;
use crate::metric::bvh::{closest_point_on_triangle, distance_squared};
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
        let removed = self.check(v0, v1, p)?;
        // (finite and positive only in a pass with the spread bound)
        let limit = self
            .opts
            .reach
            .map_or(f64::INFINITY, |f| self.pass.spread_limit * f * f);
        let deferred = limit.is_finite() && limit > 0.0 && self.reach_over(v0, v1, p, limit);
        Ok(Plan {
            v0,
            v1,
            p,
            error: error as f32,
            removed,
            deferred,
        })
    }

    /// Whether contracting `v0` and `v1` to `p` moves the surface farther
    /// than `limit` (squared; see `SimplifyOptions::reach`): the old position of
    /// `v0` or `v1` from every face it moves (with the two deleted ones
    /// left out), or `p` from every face of the two old fans. Reads the
    /// closed one-rings only.
    fn reach_over(&self, v0: u32, v1: u32, p: DVec3, limit: f64) -> bool {
        // the live faces of the two fans, as they are (`moved` false) or
        // with `v0` and `v1` at `p` (then without the two faces the
        // contraction deletes)
        let faces = |moved: bool| {
            [v0, v1].into_iter().flat_map(move |v| {
                self.vtris.fan(v).iter().filter_map(move |&t| {
                    let tri = self.tris[t as usize];
                    let deleted = tri.contains(&v0) && tri.contains(&v1);
                    (self.tri_alive[t as usize] && !(moved && deleted)).then(|| {
                        tri.map(|x| {
                            if moved && (x == v0 || x == v1) {
                                p
                            } else {
                                dv(self.pos[x as usize])
                            }
                        })
                    })
                })
            })
        };
        // whether `q` lies within the limit of one of the faces: first the
        // cheap test (over the face, its plane near enough: the usual
        // case), then the exact distance to the faces whose plane is near
        let near = |q: DVec3, moved: bool| {
            let over = |[a, b, c]: [DVec3; 3]| {
                let n = (b - a).cross(c - a);
                let s = n.dot(q - a);
                s * s <= limit * n.length_squared()
                    && (b - a).cross(q - a).dot(n) >= 0.0
                    && (c - b).cross(q - b).dot(n) >= 0.0
                    && (a - c).cross(q - c).dot(n) >= 0.0
            };
            faces(moved).any(over)
                || faces(moved).any(|[a, b, c]| {
                    let w = |v: DVec3| [v.x, v.y, v.z];
                    let (q, a, b, c) = (w(q), w(a), w(b), w(c));
                    distance_squared(q, closest_point_on_triangle(q, a, b, c)) <= limit
                })
        };
        let old_far = [v0, v1].iter().any(|&v| {
            let q = dv(self.pos[v as usize]);
            (q - p).length_squared() > limit && !near(q, true)
        });
        old_far || !near(p, false)
    }

    /// Legality of contracting `v0` into `v1` at `p`, cheapest test first.
    /// On success returns the triangles the contraction deletes.
    pub(super) fn check(&self, v0: u32, v1: u32, p: DVec3) -> Result<SmallVec<[u32; 2]>, Rejected> {
        let (i0, i1) = (v0 as usize, v1 as usize);
        if self.locked[i0] && self.locked[i1] {
            return Err(Rejected::Locked);
        }
        if let Some(f) = &self.features {
            f.allows(v0, v1)?;
        }
        let faces = Faces {
            tris: &self.tris,
            alive: &self.tri_alive,
            vtris: &self.vtris,
            pos: &self.pos,
        };
        let Link {
            shared,
            opposite,
            common,
        } = link(faces, v0, v1);
        if shared.len() == 2 && self.boundary[i0] && self.boundary[i1] {
            return Err(Rejected::BoundaryPinch);
        }
        if shared.len() > 2 {
            return Err(Rejected::Link);
        }
        if common != shared.len() || (opposite.len() == 2 && opposite[0] == opposite[1]) {
            return Err(Rejected::Link);
        }
        moved_faces_ok(faces, v0, v1, p, &opposite)?;
        Ok(shared)
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
