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
    pub fn new(vertex_count: usize, tris: &[[u32; 3]], alive: impl Fn(usize) -> bool) -> Fans {
        let mut f = Fans::default();
        f.build(vertex_count, tris, alive);
        f
    }

    fn build(&mut self, nv: usize, tris: &[[u32; 3]], alive: impl Fn(usize) -> bool) {
        let offsets = &mut self.offsets;
        offsets.clear();
        offsets.resize(nv + 1, 0);
        for (t, tri) in tris.iter().enumerate() {
            if alive(t) {
                for &v in tri {
                    offsets[v as usize + 1] += 1;
                }
            }
        }
        for v in 0..nv {
            offsets[v + 1] += offsets[v];
        }
        let total = offsets[nv] as usize;
        self.list.clear();
        self.list.resize(total, 0);
        // fill with a moving cursor per vertex (offsets[v] advances, then is
        // restored by shifting)
        let mut next: Vec<u32> = offsets[..nv].to_vec();
        for (t, tri) in tris.iter().enumerate() {
            if alive(t) {
                for &v in tri {
                    let slot = &mut next[v as usize];
                    self.list[*slot as usize] = t as u32;
                    *slot += 1;
                }
            }
        }
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
