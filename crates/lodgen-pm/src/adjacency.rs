//! Vertex → triangle adjacency for the contraction loop.
//!
//! [`Fans`] keeps every vertex's triangles in one compressed array (CSR:
//! one allocation for the whole mesh, lists in vertex order) and writes a
//! vertex's list anew into an overflow arena when a contraction changes it.
//! `rebuild` compacts both back into the CSR from the live triangles; the
//! pass schedule does so between passes once the arena reaches half the
//! CSR, the greedy one whenever it outgrows the CSR, so it stays bounded. (A `Vec` per vertex cost
//! one allocation per vertex to build and drop and one reallocation per
//! contraction: 15 % of the bunny's instructions went to `malloc`/`free`.)
//!
//! Owns [`Fans`] and the [`FanLookup`] trait the legality tests read
//! adjacency through (also implemented by the curvature engine's
//! `[Vec<u32>]`).

/// Read access to "the triangles around `v`" (may include dead ones).
pub(crate) trait FanLookup {
    fn fan(&self, v: u32) -> &[u32];
}

impl FanLookup for [Vec<u32>] {
    #[inline]
    fn fan(&self, v: u32) -> &[u32] {
        &self[v as usize]
    }
}

const CSR: u32 = u32::MAX;

/// Vertex → triangles: a CSR array plus rewritten lists (module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct Fans {
    offsets: Vec<u32>,
    list: Vec<u32>,
    /// Vertex → start of its rewritten list in `arena` (`[len, t…]`), or
    /// `CSR`.
    over: Vec<u32>,
    arena: Vec<u32>,
}

impl FanLookup for Fans {
    #[inline]
    fn fan(&self, v: u32) -> &[u32] {
        let o = self.over[v as usize];
        if o == CSR {
            let v = v as usize;
            &self.list[self.offsets[v] as usize..self.offsets[v + 1] as usize]
        } else {
            let s = o as usize + 1;
            &self.arena[s..s + self.arena[o as usize] as usize]
        }
    }
}

impl Fans {
    /// The fans of `vertex_count` vertices over the triangles for which
    /// `alive(t)` holds.
    pub fn new(
        vertex_count: usize,
        tris: &[[u32; 3]],
        alive: impl Fn(usize) -> bool + Sync,
    ) -> Fans {
        let mut f = Fans::default();
        f.build(vertex_count, tris, alive);
        f
    }

    /// In parallel: the vertices are split into one range per thread, and
    /// each thread reads every triangle and fills its range's lists (each
    /// list in triangle order: the result does not depend on the split).
    fn build(&mut self, nv: usize, tris: &[[u32; 3]], alive: impl Fn(usize) -> bool + Sync) {
        use rayon::prelude::*;
        let threads = rayon::current_num_threads().clamp(1, 64);
        let cuts: Vec<usize> = (0..=threads).map(|k| nv * k / threads).collect();
        let offsets = &mut self.offsets;
        offsets.clear();
        offsets.resize(nv + 1, 0);
        let mut runs = Vec::with_capacity(threads);
        let mut rest = &mut offsets[1..];
        for w in cuts.windows(2) {
            let (head, tail) = rest.split_at_mut(w[1] - w[0]);
            runs.push((w[0], head));
            rest = tail;
        }
        runs.into_par_iter().for_each(|(lo, counts)| {
            for (t, tri) in tris.iter().enumerate() {
                if alive(t) {
                    for &v in tri {
                        if let Some(c) =
                            (v as usize).checked_sub(lo).and_then(|i| counts.get_mut(i))
                        {
                            *c += 1;
                        }
                    }
                }
            }
        });
        for v in 0..nv {
            offsets[v + 1] += offsets[v];
        }
        let total = offsets[nv] as usize;
        self.list.clear();
        self.list.resize(total, 0);
        let offsets = &self.offsets;
        let mut runs = Vec::with_capacity(threads);
        let mut rest = &mut self.list[..];
        for w in cuts.windows(2) {
            let (lo, hi) = (w[0], w[1]);
            let (head, tail) = rest.split_at_mut((offsets[hi] - offsets[lo]) as usize);
            runs.push((lo, hi, head));
            rest = tail;
        }
        runs.into_par_iter().for_each(|(lo, hi, dst)| {
            // a moving cursor per vertex, relative to the run
            let base = offsets[lo];
            let mut next: Vec<u32> = offsets[lo..hi].iter().map(|&o| o - base).collect();
            for (t, tri) in tris.iter().enumerate() {
                if alive(t) {
                    for &v in tri {
                        if let Some(slot) =
                            (v as usize).checked_sub(lo).and_then(|i| next.get_mut(i))
                        {
                            dst[*slot as usize] = t as u32;
                            *slot += 1;
                        }
                    }
                }
            }
        });
        self.over.clear();
        self.over.resize(nv, CSR);
        self.arena.clear();
    }

    /// Compact into the CSR from the live triangles.
    pub fn rebuild(&mut self, tris: &[[u32; 3]], alive: &[bool]) {
        let nv = self.over.len();
        self.build(nv, tris, |t| alive[t]);
    }

    /// Whether the rewritten lists outweigh the CSR (time to `rebuild`).
    pub fn bloated(&self) -> bool {
        self.arena.len() > self.list.len().max(1024)
    }

    /// Whether the rewritten lists reach half the CSR: with the dead
    /// triangles the lists carry, worth a `rebuild` between passes.
    pub fn half_dead(&self) -> bool {
        2 * self.arena.len() > self.list.len()
    }

    /// Replace `v`'s list.
    pub fn set(&mut self, v: u32, tris: &[u32]) {
        self.over[v as usize] = self.arena.len() as u32;
        self.arena.push(tris.len() as u32);
        self.arena.extend_from_slice(tris);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_follow_rewrites_and_rebuilds() {
        let tris = [[0, 1, 2], [0, 2, 3], [1, 3, 2]];
        let mut f = Fans::new(4, &tris, |_| true);
        assert_eq!(f.fan(0), &[0, 1]);
        assert_eq!(f.fan(2), &[0, 1, 2]);
        f.set(0, &[1]);
        assert_eq!(f.fan(0), &[1]);
        assert_eq!(f.fan(1), &[0, 2]);
        f.rebuild(&tris, &[true, false, true]);
        assert_eq!(f.fan(0), &[0]);
        assert_eq!(f.fan(2), &[0, 2]);
        assert_eq!(f.fan(3), &[2]);
    }
}
