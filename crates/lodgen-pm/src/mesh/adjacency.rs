//! Vertex → triangle adjacency for the contraction loop.
//!
//! [`Fans`] keeps every vertex's triangles in one compressed array (CSR:
//! one allocation for the whole mesh, lists in vertex order) and writes a
//! vertex's list anew into an overflow arena when a contraction changes it.
//! The pass schedule compacts both back into one CSR (`replace`) once the
//! arena reaches half the CSR: the next pass's costing reads every live fan
//! anyway and writes out its live triangles. The greedy schedule
//! `rebuild`s from the live triangles whenever the arena outgrows the CSR.
//! So the arena stays bounded. (A `Vec` per vertex cost
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

/// The bit of a span's length that says the list is in the arena.
const ARENA: u32 = 1 << 31;

/// Vertex → triangles: a CSR array plus rewritten lists (module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct Fans {
    /// Vertex → `[start, len]` of its list: in `list`, or in `arena` when
    /// `len` has the [`ARENA`] bit. One load finds a list (a lookup is on
    /// the contraction walk's critical path of cache misses).
    span: Vec<[u32; 2]>,
    list: Vec<u32>,
    arena: Vec<u32>,
    /// Lists written to the arena (the schedule's compaction trigger counts
    /// one word per list on top of their triangles).
    rewritten: usize,
}

impl FanLookup for Fans {
    #[inline]
    fn fan(&self, v: u32) -> &[u32] {
        let [start, len] = self.span[v as usize];
        let s = start as usize;
        if len & ARENA == 0 {
            &self.list[s..s + len as usize]
        } else {
            &self.arena[s..s + (len & !ARENA) as usize]
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
        let span = &mut self.span;
        span.clear();
        span.resize(nv, [0, 0]);
        let mut runs = Vec::with_capacity(threads);
        let mut rest = &mut span[..];
        for w in cuts.windows(2) {
            let (head, tail) = rest.split_at_mut(w[1] - w[0]);
            runs.push((w[0], head));
            rest = tail;
        }
        // lengths
        runs.into_par_iter().for_each(|(lo, spans)| {
            for (t, tri) in tris.iter().enumerate() {
                if alive(t) {
                    for &v in tri {
                        if let Some(sp) =
                            (v as usize).checked_sub(lo).and_then(|i| spans.get_mut(i))
                        {
                            sp[1] += 1;
                        }
                    }
                }
            }
        });
        // starts
        let mut total = 0u32;
        for sp in span.iter_mut() {
            sp[0] = total;
            total += sp[1];
        }
        self.list.clear();
        self.list.resize(total as usize, 0);
        let span = &self.span;
        let mut runs = Vec::with_capacity(threads);
        let mut rest = &mut self.list[..];
        for w in cuts.windows(2) {
            let (lo, hi) = (w[0], w[1]);
            let len: u32 = span[lo..hi].iter().map(|sp| sp[1]).sum();
            let (head, tail) = rest.split_at_mut(len as usize);
            runs.push((lo, hi, head));
            rest = tail;
        }
        runs.into_par_iter().for_each(|(lo, hi, dst)| {
            // a moving cursor per vertex, relative to the run
            let base = span.get(lo).map_or(0, |sp| sp[0]);
            let mut next: Vec<u32> = span[lo..hi].iter().map(|sp| sp[0] - base).collect();
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
        self.arena.clear();
        self.rewritten = 0;
    }

    /// Compact into the CSR from the live triangles.
    pub fn rebuild(&mut self, tris: &[[u32; 3]], alive: &[bool]) {
        let nv = self.span.len();
        self.build(nv, tris, |t| alive[t]);
    }

    /// Replace every list at once, compacted: `lists` holds the lists of
    /// consecutive vertex ranges (one piece per range, in vertex order),
    /// `lens` each vertex's length in its piece; together they must cover
    /// every vertex.
    pub fn replace(&mut self, lists: &[Vec<u32>], lens: &[Vec<u32>]) {
        let total: usize = lists.iter().map(Vec::len).sum();
        self.list.clear();
        self.list.reserve_exact(total);
        self.span.clear();
        let mut start = 0u32;
        for (piece, ls) in lists.iter().zip(lens) {
            self.list.extend_from_slice(piece);
            for &len in ls {
                self.span.push([start, len]);
                start += len;
            }
        }
        self.arena.clear();
        self.rewritten = 0;
    }

    /// The arena's weight against the CSR: its triangles plus a word per
    /// list.
    fn arena_weight(&self) -> usize {
        self.arena.len() + self.rewritten
    }

    /// Whether the rewritten lists outweigh the CSR (time to `rebuild`).
    pub fn bloated(&self) -> bool {
        self.arena_weight() > self.list.len().max(1024)
    }

    /// Whether any list was rewritten since the CSR was built (the next
    /// pass's costing then compacts them).
    pub fn rewritten_any(&self) -> bool {
        self.rewritten > 0
    }

    /// Prefetch `v`'s span (where its list is).
    #[inline]
    pub fn prefetch_span(&self, v: u32) {
        crate::util::prefetch(&self.span[v as usize]);
    }

    /// Prefetch the start of `v`'s list (its span must be at hand).
    #[inline]
    pub fn prefetch_fan(&self, v: u32) {
        if let Some(t) = self.fan(v).first() {
            crate::util::prefetch(t);
        }
    }

    /// Replace `v`'s list.
    pub fn set(&mut self, v: u32, tris: &[u32]) {
        self.span[v as usize] = [self.arena.len() as u32, tris.len() as u32 | ARENA];
        self.arena.extend_from_slice(tris);
        self.rewritten += 1;
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
        let mut g = f.clone();
        g.replace(&[vec![1, 1], vec![2, 0]], &[vec![1, 1], vec![0, 2]]);
        assert_eq!(g.fan(0), &[1]);
        assert_eq!(g.fan(1), &[1]);
        assert_eq!(g.fan(2), &[] as &[u32]);
        assert_eq!(g.fan(3), &[2, 0]);
        assert!(f.rewritten_any() && !g.rewritten_any());
        f.rebuild(&tris, &[true, false, true]);
        assert_eq!(f.fan(0), &[0]);
        assert_eq!(f.fan(2), &[0, 2]);
        assert_eq!(f.fan(3), &[2]);
    }
}
