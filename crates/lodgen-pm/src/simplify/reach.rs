//! The reach test of [`super::SimplifyOptions::reach`]: whether a
//! contraction moves the surface farther than a distance. Part of
//! planning (reads the closed one-rings of the pair only).

use super::{dv, Simplifier};
use crate::mesh::adjacency::FanLookup;
use crate::metric::bvh::{closest_point_on_triangle, distance_squared};
use glam::DVec3;
use smallvec::SmallVec;

/// The reach test runs only on pairs whose error (the root mean squared
/// distance to their quadric's planes) squared is at least this share of
/// the limit: a pair that stays that close to its planes is rarely one
/// that moves the surface far. Measured by `cargo xtask quality --quick
/// --reach` (session 13): 0.1 skips ~13 % of the tests on the bunny and
/// moves the geometric means of lodgen / best peer from 1.024 / 1.032 to
/// 1.014 / 1.027 (cow 2 % Hausdorff 6.41 → 5.90 %, fandisk 2 % 0.338 →
/// 0.299 %; no cell worse); 0.2: 1.051 / 1.028, 0.3: 1.115 / 1.041.
pub(super) const REACH_GATE: f64 = 0.1;

/// The new faces' test ([`Simplifier::faces_over`]) runs while at least
/// this share of the input's triangles (of a cluster's, in a cluster
/// round) is alive: below it the new edges are long against the reach
/// distance, and deferring them changes which pairs the last passes
/// contract more than it keeps the surface. `target/release/xtask quality
/// --quick` (session 18; geometric mean of lodgen / best peer over 21
/// cells, without the test 0.910 / 0.933): in every pass 0.879 / 0.925
/// (spot 2 % Hausdorff 3.46 → 3.73 %), 0.04: 0.882 / 0.927 (spot 2 % the
/// same, fandisk 2 % 0.299 → 0.324 %), 0.07: 0.876 / 0.929, **0.1: 0.874
/// / 0.928** (spot 2 % 3.32 %, fandisk 2 % 0.304 %), 0.13: 0.897 / 0.929,
/// 0.2: 0.912 / 0.930 (rocker-arm 10 % 0.283 → 0.354 %).
pub(super) const REACH_FACES_MIN_LIVE: f64 = 0.1;

/// Whether the origin (the query point) lies over the triangle `a b c`
/// (given relative to it: its projection inside, by barycentric
/// coordinates) within `limit` (squared) of its plane: the cheap test,
/// which settles nearly every query (a sufficient condition for the
/// distance; never on a degenerate triangle). With `n` the triangle's
/// normal and `m = a × n`, the barycentric coordinates of `b` and `c`
/// times `|n|²` are `c·m` and `−b·m` (`n·(c × a)` and `n·(a × b)`).
#[inline]
fn over(a: DVec3, b: DVec3, c: DVec3, limit: f64) -> bool {
    let n = (b - a).cross(c - a);
    let nn = n.length_squared();
    let s = n.dot(a);
    if nn <= 0.0 || s * s > limit * nn {
        return false;
    }
    let m = a.cross(n);
    let (u, v) = (c.dot(m), -b.dot(m));
    u >= 0.0 && v >= 0.0 && u + v <= nn
}

/// The squared distance from `q` to the segment `[a, b]`.
#[inline]
fn segment_distance_squared(q: DVec3, a: DVec3, b: DVec3) -> f64 {
    let d = b - a;
    let len = d.length_squared();
    let t = if len > 0.0 {
        ((q - a).dot(d) / len).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + d * t - q).length_squared()
}

/// An old face of [`Simplifier::faces_over`]: its corners' ids and
/// positions, its normal `n` (`(b − a) × (c − a)`) and `n · n`.
struct Old {
    ids: [u32; 3],
    corners: [DVec3; 3],
    n: DVec3,
    nn: f64,
}

impl Old {
    /// [`over`] with the face's normal at hand: whether `q` lies over the
    /// face within `limit` (squared) of its plane.
    #[inline]
    fn over(&self, q: DVec3, limit: f64) -> bool {
        let [a, b, c] = self.corners.map(|x| x - q);
        let s = self.n.dot(a);
        if self.nn <= 0.0 || s * s > limit * self.nn {
            return false;
        }
        let m = a.cross(self.n);
        let (u, v) = (c.dot(m), -b.dot(m));
        u >= 0.0 && v >= 0.0 && u + v <= self.nn
    }
}

impl Simplifier {
    /// Whether contracting `v0` and `v1` to `p` moves the surface farther
    /// than `limit` (squared; see `SimplifyOptions::reach`): the old
    /// position of `v0` or `v1` from every face it moves (with the two
    /// deleted ones left out), or `p` from every face of the two old fans.
    /// `edge`: the pair shares a live face (then the old surface holds the
    /// segment between the two old positions). Reads the closed one-rings
    /// only.
    ///
    /// The three queries share one walk over the two fans with the cheap
    /// test ([`over`]); a query it leaves open takes the exact distance.
    pub(super) fn reach_over(&self, v0: u32, v1: u32, p: DVec3, edge: bool, limit: f64) -> bool {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (just checked)
            return unsafe { self.reach_over_avx2(v0, v1, p, edge, limit) };
        }
        self.reach_over_portable(v0, v1, p, edge, limit)
    }

    /// [`Simplifier::reach_over`] compiled for AVX2 (the same operations,
    /// unfused: the same bits).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn reach_over_avx2(&self, v0: u32, v1: u32, p: DVec3, edge: bool, limit: f64) -> bool {
        self.reach_over_portable(v0, v1, p, edge, limit)
    }

    #[inline(always)]
    fn reach_over_portable(&self, v0: u32, v1: u32, p: DVec3, edge: bool, limit: f64) -> bool {
        let (p0, p1) = (dv(self.pos[v0 as usize]), dv(self.pos[v1 as usize]));
        let far0 = (p0 - p).length_squared() > limit;
        let far1 = (p1 - p).length_squared() > limit;
        // (an old position within the limit of `p` is within it of the
        // moved faces through `p`; `p` within the limit of an old position,
        // or of the old edge between them, is within it of the old faces)
        let far = far0 && far1 && !(edge && segment_distance_squared(p, p0, p1) <= limit);
        // open queries: p0 from the moved faces, p1 from them, p from the old
        let mut open = [far0, far1, far];
        if open == [false; 3] {
            return false;
        }
        // Each old position lies over one of its own moved faces nearly
        // always: first `v0`'s fan for `p0` (and `p`), then `v1`'s for
        // `p1` (and `p`), each walk stopping once its queries are settled;
        // then the other fans for what is still open (rare).
        let (q, v) = ([p0, p1, p], [v0, v1]);
        let ask = |k: usize, open: bool| open.then_some(k);
        (open[0], open[2]) = self.settle(v, 0, q, (ask(0, open[0]), open[2]), limit);
        (open[1], open[2]) = self.settle(v, 1, q, (ask(1, open[1]), open[2]), limit);
        if open[0] {
            open[0] = self.settle(v, 1, q, (Some(0), false), limit).0;
        }
        if open[1] {
            open[1] = self.settle(v, 0, q, (Some(1), false), limit).0;
        }
        let exact = |q: DVec3, moved: Option<DVec3>| {
            self.any_face([v0, v1], moved, |[a, b, c]| {
                let w = |v: DVec3| [v.x, v.y, v.z];
                let (q, a, b, c) = (w(q), w(a), w(b), w(c));
                distance_squared(q, closest_point_on_triangle(q, a, b, c)) <= limit
            })
        };
        (open[0] && !exact(p0, Some(p)))
            || (open[1] && !exact(p1, Some(p)))
            || (open[2] && !exact(p, None))
    }

    /// Whether contracting `v0` and `v1` to `p` makes a face that leaves
    /// the old surface farther than `limit` (squared; see
    /// `SimplifyOptions::reach_faces`): the midpoint of each new edge from
    /// `p` (the moved faces' edges; the deleted faces left out) against
    /// every face of the two old fans. A fan whose centre moves less than
    /// twice the limit's distance is left out (each midpoint is then within
    /// the limit of the old edge's). Reads the closed one-rings only.
    ///
    /// The old fans are read once (with their normals); each midpoint is
    /// tested once (two moved faces share it); one within the limit of its
    /// old edge (from the fan's centre to the same corner, on the old
    /// surface) is near without a search; the others are tried first
    /// against the old faces on that edge, where they nearly always lie,
    /// with the cheap test ([`over`]), then the other faces, then the exact
    /// distance. The answer is that of every midpoint against every face.
    pub(super) fn faces_over(&self, v0: u32, v1: u32, p: DVec3, limit: f64) -> bool {
        let v = [v0, v1];
        let moves = v.map(|c| 0.25 * (p - dv(self.pos[c as usize])).length_squared() > limit);
        if moves == [false; 2] {
            return false;
        }
        // the two old fans' live faces (the shared ones once) with their
        // normals, and the new edges of the fans tested: their old edge (the
        // fan's centre, the other corner) and an old face on it
        let mut old: SmallVec<[Old; 32]> = SmallVec::new();
        let mut edges: SmallVec<[(u32, u32, usize); 32]> = SmallVec::new();
        self.fan_faces(v, |i, tri, shared| {
            let c = v[i];
            if moves[i] && !shared {
                for x in tri {
                    // (a corner both fans share gives one new edge)
                    if x != c && !edges.iter().any(|e| e.1 == x) {
                        edges.push((c, x, old.len()));
                    }
                }
            }
            let [a, b, e] = tri.map(|x| dv(self.pos[x as usize]));
            let n = (b - a).cross(e - a);
            old.push(Old {
                ids: tri,
                corners: [a, b, e],
                n,
                nn: n.length_squared(),
            });
            false
        });
        edges.iter().any(|&(c, x, k)| {
            let (pc, px) = (dv(self.pos[c as usize]), dv(self.pos[x as usize]));
            let m = (p + px) * 0.5;
            // (the old edge c–x lies on the old surface)
            if segment_distance_squared(m, pc, px) <= limit || old[k].over(m, limit) {
                return false;
            }
            // the other old face on the edge, then the rest with the cheap
            // test, then the exact distance
            let on_edge = |f: &Old| f.ids.contains(&x) && f.ids.contains(&c);
            let near = old
                .iter()
                .enumerate()
                .any(|(j, f)| j != k && on_edge(f) && f.over(m, limit))
                || old.iter().any(|f| !on_edge(f) && f.over(m, limit))
                || old.iter().any(|f| {
                    let w = |v: DVec3| [v.x, v.y, v.z];
                    let [a, b, e] = f.corners.map(w);
                    distance_squared(w(m), closest_point_on_triangle(w(m), a, b, e)) <= limit
                });
            !near
        })
    }

    /// Walk the fan of `v[i]` with the cheap test ([`over`]) for the open
    /// queries among `old` (`q[old]`, an old position, against the moved
    /// faces) and `new` (`q[2]`, the new position, against the old
    /// faces); each shared face is walked in `v[0]`'s fan only. Stops once
    /// those queries are settled; returns which are still open.
    #[inline(always)]
    fn settle(
        &self,
        v: [u32; 2],
        i: usize,
        q: [DVec3; 3],
        (mut old, mut new): (Option<usize>, bool),
        limit: f64,
    ) -> (bool, bool) {
        // (`q[i]` is the old position of the fan's centre)
        let (c, other, apex, p) = (v[i], v[1 - i], q[i], q[2]);
        let x = q[old.unwrap_or(0)];
        for &t in self.vtris.fan(c) {
            if old.is_none() && !new {
                break;
            }
            if !self.tri_alive[t as usize] {
                continue;
            }
            // the face's two other corners, in its order
            let [a, b, e] = self.tris[t as usize];
            let (y, z) = if a == c {
                (b, e)
            } else if b == c {
                (e, a)
            } else {
                (a, b)
            };
            // (a shared face is in both fans, and deleted when moved)
            let shared = y == other || z == other;
            if shared && i == 1 {
                continue;
            }
            let (b, e) = (dv(self.pos[y as usize]), dv(self.pos[z as usize]));
            if new && over(apex - p, b - p, e - p, limit) {
                new = false;
            }
            if old.is_some() && !shared && over(p - x, b - x, e - x, limit) {
                old = None;
            }
        }
        (old.is_some(), new)
    }

    /// Whether `f` holds for one of the live faces of the fans of `v` (the
    /// shared faces once): as they are (`moved` `None`), or with both
    /// vertices at `moved` (then without the faces the contraction
    /// deletes).
    fn any_face(
        &self,
        v: [u32; 2],
        moved: Option<DVec3>,
        mut f: impl FnMut([DVec3; 3]) -> bool,
    ) -> bool {
        self.fan_faces(v, |_, tri, shared| {
            // (a shared face is deleted when moved)
            if shared && moved.is_some() {
                return false;
            }
            let corners = tri.map(|x| match moved {
                Some(p) if x == v[0] || x == v[1] => p,
                _ => dv(self.pos[x as usize]),
            });
            f(corners)
        })
    }

    /// Calls `f(i, face, shared)` for each live face of the fan of `v[i]`,
    /// `i` = 0 then 1, a face of both fans (`shared`) once, from fan 0;
    /// stops at the first `true` and returns whether `f` stopped it.
    #[inline]
    fn fan_faces(&self, v: [u32; 2], mut f: impl FnMut(usize, [u32; 3], bool) -> bool) -> bool {
        for (i, &c) in v.iter().enumerate() {
            for &t in self.vtris.fan(c) {
                if !self.tri_alive[t as usize] {
                    continue;
                }
                let tri = self.tris[t as usize];
                let shared = tri.contains(&v[1 - i]);
                if shared && i == 1 {
                    continue;
                }
                if f(i, tri, shared) {
                    return true;
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{shapes, SimplifyOptions};

    /// The reach test by definition: the exact distance of each query point
    /// to every face it is tested against, no shortcut.
    fn reference(s: &Simplifier, v0: u32, v1: u32, p: DVec3, limit: f64) -> bool {
        let (p0, p1) = (dv(s.pos[v0 as usize]), dv(s.pos[v1 as usize]));
        let mut faces: Vec<u32> = [v0, v1]
            .iter()
            .flat_map(|&v| s.vtris.fan(v).iter().copied())
            .filter(|&t| s.tri_alive[t as usize])
            .collect();
        faces.sort_unstable();
        faces.dedup();
        let w = |v: DVec3| [v.x, v.y, v.z];
        let nearest = |q: DVec3, moved: bool| {
            faces
                .iter()
                .map(|&t| s.tris[t as usize])
                .filter(|tri| !(moved && tri.contains(&v0) && tri.contains(&v1)))
                .map(|tri| {
                    let [a, b, c] = tri.map(|x| {
                        if moved && (x == v0 || x == v1) {
                            w(p)
                        } else {
                            w(dv(s.pos[x as usize]))
                        }
                    });
                    distance_squared(w(q), closest_point_on_triangle(w(q), a, b, c))
                })
                .fold(f64::INFINITY, f64::min)
        };
        let far0 = (p0 - p).length_squared() > limit;
        let far1 = (p1 - p).length_squared() > limit;
        (far0 && nearest(p0, true) > limit)
            || (far1 && nearest(p1, true) > limit)
            || (far0 && far1 && nearest(p, false) > limit)
    }

    /// `faces_over` by definition: the exact distance of each moved face's
    /// edge midpoints (from the merged vertex) to every face of the two old
    /// fans, no shortcut.
    fn faces_reference(s: &Simplifier, v0: u32, v1: u32, p: DVec3, limit: f64) -> bool {
        let w = |v: DVec3| [v.x, v.y, v.z];
        let fans = |moved: bool| -> Vec<[DVec3; 3]> {
            let mut faces: Vec<u32> = [v0, v1]
                .iter()
                .flat_map(|&v| s.vtris.fan(v).iter().copied())
                .filter(|&t| s.tri_alive[t as usize])
                .collect();
            faces.sort_unstable();
            faces.dedup();
            faces
                .iter()
                .map(|&t| s.tris[t as usize])
                .filter(|tri| !(moved && tri.contains(&v0) && tri.contains(&v1)))
                .map(|tri| {
                    tri.map(|x| match moved && (x == v0 || x == v1) {
                        true => p,
                        false => dv(s.pos[x as usize]),
                    })
                })
                .collect()
        };
        let old = fans(false);
        fans(true).into_iter().any(|f| {
            // the moved face's corner at `p` and its two others
            let k = f.iter().position(|&c| c == p).unwrap();
            let (y, z) = (f[(k + 1) % 3], f[(k + 2) % 3]);
            [(p + y) * 0.5, (p + z) * 0.5].into_iter().any(|q| {
                old.iter().all(|&[a, b, c]| {
                    distance_squared(w(q), closest_point_on_triangle(w(q), w(a), w(b), w(c)))
                        > limit
                })
            })
        })
    }

    /// Runs `check(s, v0, v1, p, edge, limit)` (which asserts and returns
    /// the expected answer) on every legal pair of a half-simplified noisy
    /// torus knot, at limits from far below to far above the pair's move,
    /// and asserts that both answers occur often. `half_edge_moves: false`
    /// leaves out the pairs whose `p` is an old corner.
    fn check_every_pair_of_a_knot(
        half_edge_moves: bool,
        mut check: impl FnMut(&Simplifier, u32, u32, DVec3, bool, f64) -> bool,
    ) {
        let m = shapes::torus_knot(2, 3, 160, 12, 0.02);
        let opts = SimplifyOptions::DEFAULT.with_target_ratio(0.1);
        let mut s = Simplifier::new(&m, &opts).unwrap();
        while s.triangle_count() > m.triangles.len() / 2 {
            s.step().unwrap();
        }
        let (mut over, mut within) = (0, 0);
        for a in 0..s.pos.len() as u32 {
            if !s.alive[a as usize] {
                continue;
            }
            let mut nb: Vec<u32> = s
                .vtris
                .fan(a)
                .iter()
                .filter(|&&t| s.tri_alive[t as usize])
                .flat_map(|&t| s.tris[t as usize])
                .filter(|&b| b > a)
                .collect();
            nb.sort_unstable();
            nb.dedup();
            for b in nb {
                let Ok(plan) = s.plan(a, b) else { continue };
                let (v0, v1, p) = (plan.v0, plan.v1, plan.p);
                if !half_edge_moves && (p == dv(s.pos[v0 as usize]) || p == dv(s.pos[v1 as usize]))
                {
                    continue;
                }
                let edge = !plan.removed.is_empty();
                let d = (dv(s.pos[v0 as usize]) - p).length();
                for f in [0.01, 0.1, 0.3, 0.6, 1.2] {
                    let limit = (f * d) * (f * d);
                    if check(&s, v0, v1, p, edge, limit) {
                        over += 1;
                    } else {
                        within += 1;
                    }
                }
            }
        }
        assert!(over > 100 && within > 100, "{over} over, {within} within");
    }

    /// `faces_over` (the fans of centres that move little left out, the
    /// old-edge shortcut, the cheap test, the exact fallback) agrees with
    /// the definition on every legal pair of a half-simplified noisy torus
    /// knot (half-edge moves left out: `p` is an old corner there), at
    /// limits from far below to far above the pairs' moves, with both
    /// answers occurring. (Fails when a midpoint is misplaced, when the
    /// cheap test accepts a point beside the face, when a deleted face
    /// counts, or when the shortcut takes a segment off the old surface.)
    #[test]
    fn faces_over_matches_the_exact_distances() {
        check_every_pair_of_a_knot(false, |s, v0, v1, p, _, limit| {
            let want = faces_reference(s, v0, v1, p, limit);
            assert_eq!(
                s.faces_over(v0, v1, p, limit),
                want,
                "pair {v0} {v1} at limit {limit}"
            );
            want
        });
    }

    /// `reach_over` (one walk, the cheap test, the old-edge shortcut, the
    /// exact fallback) agrees with the definition on every legal pair of a
    /// half-simplified noisy torus knot, at limits from far below to far
    /// above the pairs' moves, with both answers occurring. (Fails when
    /// the cheap test accepts a point beside the face, when a shared face
    /// counts as moved, or when the shortcut takes a segment off the old
    /// surface.)
    #[test]
    fn reach_over_matches_the_exact_distances() {
        check_every_pair_of_a_knot(true, |s, v0, v1, p, edge, limit| {
            let want = reference(s, v0, v1, p, limit);
            assert_eq!(
                s.reach_over(v0, v1, p, edge, limit),
                want,
                "pair {v0} {v1} at limit {limit}"
            );
            want
        });
    }
}
