//! The clusters' logs merged into the whole mesh's: one valid sequence in a
//! fixed order (clusters are disjoint, so their contractions commute).

use super::Done;
use crate::progressive::{Contraction, Corner};
use crate::simplify::heap::f32_order_key;
use crate::simplify::Simplifier;
use rayon::prelude::*;
use smallvec::SmallVec;

impl Simplifier {
    /// Append the clusters' records to the log in one fixed order: by
    /// round (as the whole-mesh walk's passes), then by the running maximum
    /// of the errors of the cluster's round (so a prefix of a round is
    /// about as even in error as a pass's), then by cluster and step (so
    /// each cluster keeps its own order). The log may hold records already
    /// (the first stage's, before the coarse clusters'): they stay first.
    ///
    /// Memory: the records are appended in cluster order, each cluster's
    /// log freed once copied, then permuted into the merged order in place
    /// and the corners rewritten in that order (the clusters' logs and the
    /// merged one were both alive: bunny-4m's run peaked here).
    pub(super) fn merge_logs(&mut self, done: Vec<Done>) {
        let base = self.log.records.len();
        let total: usize = done.iter().map(|d| d.log.records.len()).sum();
        let corners: usize = done.iter().map(|d| d.log.mark() as usize).sum();
        // each record's key (round, running maximum, cluster, place in
        // the clusters' concatenation), the clusters' parts on every core
        let mut order: Vec<(u32, u32, u32, u32)> = vec![(0, 0, 0, 0); total];
        let mut parts = Vec::with_capacity(done.len());
        let (mut rest, mut first) = (&mut order[..], 0u32);
        for d in &done {
            let (part, tail) = rest.split_at_mut(d.log.records.len());
            parts.push((part, first));
            first += d.log.records.len() as u32;
            rest = tail;
        }
        parts
            .into_par_iter()
            .zip(&done)
            .enumerate()
            .for_each(|(c, ((part, first), d))| {
                let mut from = 0;
                for (k, &to) in d.rounds.iter().enumerate() {
                    let mut run = 0;
                    for i in from..to {
                        run = f32_order_key(d.log.records[i as usize].error).max(run);
                        part[i as usize] = (k as u32, run, c as u32, first + i);
                    }
                    from = to;
                }
            });
        order.par_sort_unstable();
        // the merged order as positions in the clusters' concatenation
        let mut perm: Vec<u32> = order.iter().map(|o| o.3).collect();
        drop(order);
        self.log.records.reserve(total);
        self.log.reserve_corners(corners);
        for d in done {
            for r in &d.log.records {
                let mark = self.log.mark();
                for k in d.log.moved(r) {
                    self.log.push_corner(Corner {
                        triangle: d.tris.global(k.triangle),
                        slot: k.slot,
                    });
                }
                let removed: SmallVec<[u32; 2]> =
                    d.log.removed(r).iter().map(|&t| d.tris.global(t)).collect();
                let removed = self.log.removed_of(&removed);
                self.log.records.push(Contraction {
                    v0: d.verts[r.v0 as usize],
                    v1: d.verts[r.v1 as usize],
                    p1: r.p1,
                    removed,
                    moved: mark..self.log.mark(),
                    error: r.error,
                });
            }
        }
        permute(&mut self.log.records[base..], &mut perm);
        drop(perm);
        self.log.reorder_corners_from(base);
        if let Some(f) = &mut self.features {
            // the feature lines as the contractions in this order leave
            // them (the clusters' edits of a held vertex's neighbours,
            // e.g. along an open border, meet here)
            for r in &self.log.records[base..] {
                f.contract(r.v0, r.v1);
            }
        }
    }
}

/// Reorders `items` in place so that item `j` becomes the one at
/// `perm[j]` (a permutation of `0..items.len()`), one cycle at a time by
/// swaps; `perm` is consumed (entries set to `u32::MAX` once placed).
fn permute<T>(items: &mut [T], perm: &mut [u32]) {
    debug_assert_eq!(items.len(), perm.len());
    for j in 0..perm.len() {
        let mut k = j;
        // (the item due at `k` is `perm[k]`; `j`'s old item travels along)
        while perm[k] != u32::MAX && perm[k] as usize != j {
            let src = perm[k] as usize;
            items.swap(k, src);
            perm[k] = u32::MAX;
            k = src;
        }
        perm[k] = u32::MAX;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `permute` puts item `perm[j]` at `j` for permutations made of
    /// fixed points, one long cycle and many short ones; fails when a
    /// cycle is followed the wrong way (`items[perm[j]] = items[j]`) or
    /// left unfinished.
    #[test]
    fn permute_places_each_item_where_the_permutation_says() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        for n in [0usize, 1, 2, 7, 1000] {
            let mut perm: Vec<u32> = (0..n as u32).collect();
            // a shuffle, leaving some fixed points
            for i in (1..n).rev() {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                if x % 5 != 0 {
                    perm.swap(i, (x % (i as u64 + 1)) as usize);
                }
            }
            let items: Vec<String> = (0..n).map(|i| format!("item {i}")).collect();
            let want: Vec<String> = perm.iter().map(|&p| items[p as usize].clone()).collect();
            let mut got = items.clone();
            let mut p = perm.clone();
            permute(&mut got, &mut p);
            assert_eq!(got, want, "n = {n}");
        }
        // one cycle through every item
        let n = 10u32;
        let mut perm: Vec<u32> = (0..n).map(|j| (j + 3) % n).collect();
        let mut got: Vec<u32> = (0..n).collect();
        permute(&mut got, &mut perm);
        assert_eq!(got, (0..n).map(|j| (j + 3) % n).collect::<Vec<_>>());
    }
}
