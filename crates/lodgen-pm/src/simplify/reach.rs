//! The reach test of [`super::SimplifyOptions::reach`]: whether a
//! contraction moves the surface farther than a distance. Part of
//! planning (reads the closed one-rings of the pair only).

use super::{dv, Simplifier};
use crate::mesh::adjacency::FanLookup;
use crate::metric::bvh::{closest_point_on_triangle, distance_squared};
use glam::DVec3;

impl Simplifier {
    /// Whether contracting `v0` and `v1` to `p` moves the surface farther
    /// than `limit` (squared; see `SimplifyOptions::reach`): the old
    /// position of `v0` or `v1` from every face it moves (with the two
    /// deleted ones left out), or `p` from every face of the two old fans.
    /// Reads the closed one-rings only.
    pub(super) fn reach_over(&self, v0: u32, v1: u32, p: DVec3, limit: f64) -> bool {
        let (p0, p1) = (dv(self.pos[v0 as usize]), dv(self.pos[v1 as usize]));
        let far0 = (p0 - p).length_squared() > limit;
        let far1 = (p1 - p).length_squared() > limit;
        // (an old position within the limit of `p` is within it of the
        // moved faces through `p`; `p` within the limit of an old position
        // is within it of that vertex's old faces)
        (far0 && !self.near(p0, [v0, v1], Some(p), limit))
            || (far1 && !self.near(p1, [v1, v0], Some(p), limit))
            || (far0 && far1 && !self.near(p, [v1, v0], None, limit))
    }

    /// Whether `q` lies within `limit` (squared) of one of the live faces
    /// of the fans of `v` (the shared faces once): as they are (`moved`
    /// `None`), or with both vertices at `moved` (then without the faces
    /// the contraction deletes). First the cheap test (over the face, its
    /// plane near enough: the usual case), then the exact distance.
    #[inline]
    fn near(&self, q: DVec3, v: [u32; 2], moved: Option<DVec3>, limit: f64) -> bool {
        let over = |[a, b, c]: [DVec3; 3]| {
            let n = (b - a).cross(c - a);
            let s = n.dot(q - a);
            s * s <= limit * n.length_squared()
                && (b - a).cross(q - a).dot(n) >= 0.0
                && (c - b).cross(q - b).dot(n) >= 0.0
                && (a - c).cross(q - c).dot(n) >= 0.0
        };
        let exact = |[a, b, c]: [DVec3; 3]| {
            let w = |v: DVec3| [v.x, v.y, v.z];
            let (q, a, b, c) = (w(q), w(a), w(b), w(c));
            distance_squared(q, closest_point_on_triangle(q, a, b, c)) <= limit
        };
        self.any_face(v, moved, over) || self.any_face(v, moved, exact)
    }

    /// Whether `f` holds for one of the faces [`Simplifier::near`] tests.
    #[inline]
    fn any_face(
        &self,
        v: [u32; 2],
        moved: Option<DVec3>,
        mut f: impl FnMut([DVec3; 3]) -> bool,
    ) -> bool {
        for (i, &c) in v.iter().enumerate() {
            for &t in self.vtris.fan(c) {
                if !self.tri_alive[t as usize] {
                    continue;
                }
                let tri = self.tris[t as usize];
                let other = tri.contains(&v[1 - i]);
                // (a shared face is in both fans; deleted when moved)
                if other && (i == 1 || moved.is_some()) {
                    continue;
                }
                let corners = tri.map(|x| match moved {
                    Some(p) if x == v[0] || x == v[1] => p,
                    _ => dv(self.pos[x as usize]),
                });
                if f(corners) {
                    return true;
                }
            }
        }
        false
    }
}
