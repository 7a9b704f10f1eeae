//! The clusters' logs merged into the whole mesh's: one valid sequence in a
//! fixed order (clusters are disjoint, so their contractions commute).

use super::Done;
use crate::progressive::{Contraction, Removed};
use crate::simplify::heap::f32_order_key;
use crate::simplify::Simplifier;
use rayon::prelude::*;
use smallvec::SmallVec;

/// Clusters appended to the log at once (each batch's logs freed before
/// the next is copied: the copies do not raise the peak).
const APPEND_BATCH: usize = 16;

impl Simplifier {
    /// Append the clusters' records to the log in one fixed order: by
    /// round (as the whole-mesh walk's passes), then by the running maximum
    /// of the errors of the cluster's round (so a prefix of a round is
    /// about as even in error as a pass's), then by cluster and step (so
    /// each cluster keeps its own order). The log may hold records already
    /// (the first stage's, before the coarse clusters'): they stay first.
    ///
    /// Memory: the records are appended in cluster order, a batch of
    /// clusters at a time on every core, each batch's logs freed once
    /// copied; then gathered into the merged order (a second copy of the
    /// records, but not of the clusters' logs: those and the merged log
    /// both alive were bunny-4m's peak) and the corners rewritten in that
    /// order.
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
        let perm: Vec<u32> = order.par_iter().map(|o| o.3).collect();
        drop(order);
        self.log.records.reserve(total);
        self.log.reserve_corners(corners);
        let mut done = done.into_iter();
        loop {
            let batch: Vec<Done> = done.by_ref().take(APPEND_BATCH).collect();
            if batch.is_empty() {
                break;
            }
            self.append(&batch);
        }
        // the merged order gathered on every core (independent reads,
        // where following the permutation's cycles by swaps waited on each
        // one): beside the appended records, after the clusters' logs are
        // freed (bunny-4m: 84 MB under the rounds' peak); with the log's
        // capacity, so that the whole-mesh walk appends without a move
        let records = &self.log.records;
        let gather = |p: &u32| records[base + *p as usize].clone();
        if base == 0 {
            let mut merged = Vec::with_capacity(records.capacity());
            merged.par_extend(perm.par_iter().map(gather));
            self.log.records = merged;
        } else {
            // (the coarse stage's few, after the first stage's)
            let tail: Vec<Contraction> = perm.par_iter().map(gather).collect();
            self.log.records.truncate(base);
            self.log.records.extend(tail);
        }
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

impl Simplifier {
    /// Appends `batch`'s records and corners to the log in cluster order,
    /// in the whole mesh's numbering, on every core.
    fn append(&mut self, batch: &[Done]) {
        let logs: Vec<&crate::progressive::Log> = batch.iter().map(|d| &d.log).collect();
        let starts = self
            .log
            .append_corners(&logs, |i, t| batch[i].tris.global(t));
        let mut firsts = Vec::with_capacity(batch.len());
        let mut n = 0;
        for d in batch {
            firsts.push(n);
            n += d.log.records.len();
        }
        let at = self.log.records.len();
        self.log.records.par_extend((0..n).into_par_iter().map(|j| {
            let i = firsts.partition_point(|&f| f <= j) - 1;
            let (d, start) = (&batch[i], starts[i]);
            let r = &d.log.records[j - firsts[i]];
            let removed: SmallVec<[u32; 2]> =
                d.log.removed(r).iter().map(|&t| d.tris.global(t)).collect();
            Contraction {
                v0: d.verts[r.v0 as usize],
                v1: d.verts[r.v1 as usize],
                p1: r.p1,
                // (three or more: set below, in the log's own list)
                removed: Removed::inline(&removed).unwrap_or(Removed::NONE),
                moved: start + r.moved.start..start + r.moved.end,
                error: r.error,
            }
        }));
        for (i, d) in batch.iter().enumerate() {
            for (j, r) in d.log.records.iter().enumerate() {
                if r.removed.len() > 2 {
                    let removed: Vec<u32> =
                        d.log.removed(r).iter().map(|&t| d.tris.global(t)).collect();
                    self.log.records[at + firsts[i] + j].removed = self.log.removed_of(&removed);
                }
            }
        }
    }
}
