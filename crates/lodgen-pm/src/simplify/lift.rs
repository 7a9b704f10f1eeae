//! The lift in the log: where a contraction placed the merged vertex on its
//! pair's segment (the summed quadric nearly singular: a nearly flat pair,
//! `Quadric::placement`'s fallback), the vertex sits on the chord, inside a
//! convex patch and outside a concave one. The vertex-split log records it
//! lifted instead: one damped Newton step on its cluster's quadric
//! ([`Quadric::lifted`](super::quadric::Quadric::lifted)), along the
//! patch's normal nearly all the way, sideways barely.
//!
//! The simplifier keeps its own (unlifted) working position for every later
//! decision (lifting the working positions changed the contraction order:
//! 2 % Hausdorff −17..+111 %, docs/quality.md), but for one: a contraction
//! moving a face with a lifted corner must keep the legality test in the
//! logged positions too (`moved_faces_ok`'s `logged`), since the log's
//! levels show those — without it a face could turn past
//! [`FLIP_MIN_COS`] between two levels (a property test found one). So the
//! order is the unlifted run's but for the few contractions that test
//! refuses. What the log records is a pure function of the
//! vertex's quadric and working position, which do not change until the
//! vertex is contracted again: so the lifted point is computed once, when
//! the contraction into the vertex decides its bit, and kept with the bit
//! ([`Lifted`]; recomputed where a copied bit came without it), and read
//! where the log takes it ([`Simplifier::logged_position`]) —
//! as `v1`'s position before its next contraction (the record's `p1`), as a
//! removed vertex's last position (written over its working one when it
//! dies: nothing reads a dead vertex's position), and as a base vertex's
//! position (`finish`). One bit per vertex ([`Lifted`]) says whether its
//! position is lifted; the log, the progressive mesh, its stream, every
//! replayed or extracted level, the library, Python and the command all
//! see the same lifted positions.
//!
//! Which vertices: those made by a contraction of two free vertices
//! (neither locked, pinned nor fixed: no border corner, feature line or
//! attribute seam vertex — a vertex with two wedges is on a seam, so
//! pinned) with optimal placement, when [`SimplifyOptions::lift`] is on.
//! Their quadrics hold face and border planes only (feature planes are
//! added to feature vertices alone, and a free vertex's cluster holds no
//! feature vertex: a pinned vertex is never removed into a free one). A
//! lift that would turn a face of the vertex's fan by more than the
//! legality test allows (or collapse it) — from the working point, or from
//! the face's last logged state — is refused: the simplifier's point is
//! logged (counted in `Stats::lift_refused`).
//!
//! [`SimplifyOptions::lift`]: super::SimplifyOptions::lift

use super::legality::turn_ok;
#[cfg(doc)]
use super::legality::{DEGENERATE_AREA_RATIO_SQ, FLIP_MIN_COS};
use super::{dv, fv, Placement, Simplifier};
use crate::mesh::adjacency::FanLookup;
use glam::DVec3;
// (a map that is never iterated, with a fixed hasher: the order the
// disallowed-types rule guards against never reaches the output)
#[allow(clippy::disallowed_types)]
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// One bit per vertex: its position is logged lifted. Empty when the lift
/// is off. With it, the lifted point of each vertex whose bit
/// [`Lifted::set_at`] set, kept in a map (few vertices are lifted at a
/// time, so the map costs no memory per vertex): a vertex's lifted point is
/// computed once per contraction into it, not at every read (the legality
/// tests read the neighbours' ~10 times a contraction). [`Lifted::set`]
/// forgets the point (it is recomputed where read).
#[derive(Clone, Debug, Default)]
pub(super) struct Lifted(Vec<u64>, Points);

/// The lifted points by vertex (looked up, never iterated).
#[allow(clippy::disallowed_types)]
type Points = HashMap<u32, [f32; 3], BuildHasherDefault<VertexHash>>;

impl Lifted {
    /// `n` vertices, none lifted; no bit at all when `on` is false.
    pub fn new(n: usize, on: bool) -> Lifted {
        if on {
            Lifted(vec![0; n.div_ceil(64)], Points::default())
        } else {
            Lifted::default()
        }
    }

    /// The lift is on.
    #[inline]
    pub fn is_on(&self) -> bool {
        !self.0.is_empty()
    }

    #[inline]
    pub fn get(&self, v: u32) -> bool {
        bit(&self.0, v)
    }

    /// `v`'s lifted point, when its bit is set and the point known.
    #[inline]
    fn point(&self, v: u32) -> Option<[f32; 3]> {
        self.1.get(&v).copied()
    }

    #[inline]
    pub fn set(&mut self, v: u32, on: bool) {
        set_bit(&mut self.0, v, on);
        if !self.1.is_empty() {
            self.1.remove(&v);
        }
    }

    /// `v` lifted to `p` (`Some`), or not lifted.
    #[inline]
    fn set_at(&mut self, v: u32, p: Option<[f32; 3]>) {
        set_bit(&mut self.0, v, p.is_some());
        match p {
            Some(p) => {
                self.1.insert(v, p);
            }
            None => {
                if !self.1.is_empty() {
                    self.1.remove(&v);
                }
            }
        }
    }
}

/// A vertex number's hash for [`Lifted`]'s map: one multiplication
/// (Fibonacci hashing), enough for distinct `u32` keys.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct VertexHash(u64);

impl Hasher for VertexHash {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ u64::from(b)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }

    #[inline]
    fn write_u32(&mut self, v: u32) {
        self.0 = u64::from(v).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }

    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
}

#[inline]
fn bit(words: &[u64], v: u32) -> bool {
    words
        .get(v as usize / 64)
        .is_some_and(|w| w >> (v % 64) & 1 != 0)
}

#[inline]
fn set_bit(words: &mut [u64], v: u32, on: bool) {
    if let Some(w) = words.get_mut(v as usize / 64) {
        let m = 1u64 << (v % 64);
        if on {
            *w |= m;
        } else {
            *w &= !m;
        }
    }
}

impl Simplifier {
    /// `v`'s position as the log records it: lifted if its bit says so,
    /// else its working position.
    #[inline]
    pub(super) fn logged_position(&self, v: u32) -> [f32; 3] {
        let p = self.pos[v as usize];
        if !self.lifted.get(v) {
            return p;
        }
        if let Some(l) = self.lifted.point(v) {
            return l;
        }
        self.lift_again(v)
    }

    /// A lifted `v` whose point is not kept (its bit copied by
    /// `Lifted::set`): the lift recomputed (rare; out of line so that
    /// `logged_position`'s two common answers inline in the hot loops).
    #[cold]
    #[inline(never)]
    fn lift_again(&self, v: u32) -> [f32; 3] {
        let p = self.pos[v as usize];
        self.quadric[v as usize].lifted(dv(p)).map_or(p, fv)
    }

    /// `v`'s logged position when it differs from its working one (a
    /// lifted vertex), for the legality test in the logged positions.
    #[inline]
    pub(super) fn lifted_at(&self, v: u32) -> Option<DVec3> {
        self.lifted.get(v).then(|| dv(self.logged_position(v)))
    }

    /// Whether contracting `v0` into `v1` (before it is made) gives a
    /// vertex that may be lifted: both free, optimal placement, lift on.
    #[inline]
    pub(super) fn liftable(&self, v0: u32, v1: u32) -> bool {
        self.lifted.is_on()
            && self.opts.placement == Placement::Optimal
            && self.free(v0)
            && self.free(v1)
    }

    /// After a contraction into `v1`: the removed `v0`'s last position
    /// becomes the logged one (`logged[0]`, taken before the contraction),
    /// and `v1`'s bit is decided (`liftable`: [`Simplifier::liftable`]
    /// before the contraction). `logged[1]` is `v1`'s logged position
    /// before the contraction, and the first `own` faces of `v1`'s fan were
    /// `v1`'s (the others came from `v0`).
    pub(super) fn settle_lift(
        &mut self,
        v0: u32,
        logged: [[f32; 3]; 2],
        v1: u32,
        liftable: bool,
        own: usize,
    ) {
        if !self.lifted.is_on() {
            return;
        }
        self.pos[v0 as usize] = logged[0];
        self.lifted.set(v0, false);
        let at = if liftable {
            self.lift_keeps_fan(v1, logged, own)
        } else {
            None
        };
        self.lifted.set_at(v1, at);
    }

    /// `v1`'s lifted point (`Some`) if it differs from its working one and turns no face
    /// of its fan by more than [`FLIP_MIN_COS`] nor collapses one
    /// ([`DEGENERATE_AREA_RATIO_SQ`]): neither from its working point
    /// (neighbours at their working positions) nor from the face's last
    /// logged state (its corner at `logged[1]` for `v1`'s first `own`
    /// faces, at `logged[0]` for those that came from `v0`; neighbours at
    /// their logged positions), which is what the log's levels show.
    fn lift_keeps_fan(&mut self, v1: u32, logged: [[f32; 3]; 2], own: usize) -> Option<[f32; 3]> {
        let p = self.pos[v1 as usize];
        let at = self.quadric[v1 as usize].lifted(dv(p)).map(fv)?;
        if at == p {
            return None;
        }
        let (pm, l) = (dv(p), dv(at));
        for (k, &t) in self.vtris.fan(v1).iter().enumerate() {
            if !self.tri_alive[t as usize] {
                continue;
            }
            let (b, c) = match self.tris[t as usize] {
                [x, b, c] | [c, x, b] | [b, c, x] if x == v1 => (b, c),
                _ => continue,
            };
            let before = dv(logged[usize::from(k < own)]);
            let (lb, lc) = (self.logged_position(b), self.logged_position(c));
            let (b, c) = (dv(self.pos[b as usize]), dv(self.pos[c as usize]));
            if turn_ok(pm, l, b, c).is_err() || turn_ok(before, l, dv(lb), dv(lc)).is_err() {
                self.stats.lift_refused += 1;
                return None;
            }
        }
        self.stats.lifted += 1;
        Some(at)
    }

    /// Every live vertex's working position replaced by its logged one,
    /// before the log is renumbered (`finish`: the base mesh's positions).
    pub(super) fn commit_lifts(&mut self) {
        if !self.lifted.is_on() {
            return;
        }
        for v in 0..self.pos.len() as u32 {
            if self.lifted.get(v) {
                self.pos[v as usize] = self.logged_position(v);
                self.lifted.set(v, false);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::metric::{MeasureOptions, MeshRef};
    use crate::{simplify, Mesh, SimplifyOptions};

    /// A UV sphere of radius 1.
    fn sphere(rings: u32, segments: u32) -> (Vec<[f32; 3]>, Vec<u32>) {
        let mut pos = vec![[0.0, 0.0, 1.0]];
        for r in 1..rings {
            let th = std::f64::consts::PI * f64::from(r) / f64::from(rings);
            for s in 0..segments {
                let ph = 2.0 * std::f64::consts::PI * f64::from(s) / f64::from(segments);
                pos.push([
                    (th.sin() * ph.cos()) as f32,
                    (th.sin() * ph.sin()) as f32,
                    th.cos() as f32,
                ]);
            }
        }
        pos.push([0.0, 0.0, -1.0]);
        let last = pos.len() as u32 - 1;
        let at = |r: u32, s: u32| 1 + (r - 1) * segments + s % segments;
        let mut idx = Vec::new();
        for s in 0..segments {
            idx.extend([0, at(1, s), at(1, s + 1)]);
            idx.extend([last, at(rings - 1, s + 1), at(rings - 1, s)]);
        }
        for r in 1..rings - 1 {
            for s in 0..segments {
                let (a, b, c, d) = (at(r, s), at(r, s + 1), at(r + 1, s), at(r + 1, s + 1));
                idx.extend([a, c, b, b, c, d]);
            }
        }
        (pos, idx)
    }

    /// The lifted log's levels are closer to the sphere than the unlifted
    /// one's at the same triangle counts, whole-mesh and partitioned, and
    /// the same bits on one thread. (The contractions differ only where
    /// the legality test in logged positions refused one: a handful.)
    #[test]
    fn a_sphere_is_logged_lifted_towards_the_sphere() {
        let (pos, idx) = sphere(120, 240);
        for partition in [None, Some(4096)] {
            let opts = SimplifyOptions::DEFAULT
                .with_target_ratio(0.02)
                .with_partition(partition);
            let on = simplify(&pos, &idx, &opts).expect("a sphere simplifies");
            let off = simplify(&pos, &idx, &opts.with_lift(false)).expect("simplifies");
            let (pm, plain) = (&on.pm, &off.pm);
            assert!(on.stats.lifted > 0, "nothing lifted");
            assert_eq!(off.stats.lifted, 0);
            // the finest level is the input, exactly
            let full = pm.full_in_input_order();
            assert_eq!(full, plain.full_in_input_order());
            let original = MeshRef::new(&full.positions, &full.triangles);
            let rms = |m: &Mesh| {
                crate::metric::measure(
                    original,
                    MeshRef::new(&m.positions, &m.triangles),
                    &MeasureOptions::DEFAULT,
                )
                .expect("measurable")
                .rms_percent()
            };
            for share in [2, 10] {
                let n = idx.len() / 3 / share;
                let lifted = pm.mesh_at_splits(pm.splits_for_triangles(n));
                let level = plain.mesh_at_splits(plain.splits_for_triangles(n));
                assert_eq!(lifted.triangles.len(), level.triangles.len());
                let (before, after) = (rms(&level), rms(&lifted));
                assert!(
                    after < before * 0.97,
                    "1/{share}, partition {partition:?}: RMS {before} -> {after} %"
                );
            }
            // the same bits on one thread
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .expect("a pool");
            let again = pool.install(|| simplify(&pos, &idx, &opts)).expect("again");
            assert_eq!(&again.pm, pm);
        }
    }
}
