//! The batched pass walk: the next candidates planned in parallel on the
//! mesh as it is, then walked in order exactly as the serial walk would,
//! replanning the pairs a contraction since changed.

use super::{Plan, Rejected, Simplifier, StopReason};
use crate::mesh::adjacency::FanLookup;
use rayon::prelude::*;

/// On a batch index: the pair is planned in order only.
const LATER: u32 = 1 << 31;

/// At most this many pairs are planned at once (the batch is one pair per
/// 64 live triangles: enough to amortise the fork, few enough that a plan
/// is rarely invalidated).
const MAX_BATCH: usize = 1024;

/// A batch entry's plan: `None` when it was not planned ahead.
type Planned = Option<Result<Plan, Rejected>>;

impl Simplifier {
    /// The pass walk of [`Simplifier::step_pass`], a batch at a time, with
    /// the same result contraction for contraction: the next candidates
    /// (one per 64 live triangles, at most `MAX_BATCH`) are planned
    /// ([`Simplifier::plan`]: costing, placement and legality, most of a
    /// step's work) in parallel on the mesh as it is, then walked in order
    /// exactly as `step_pass` would, contracting from the plans. A
    /// contraction changes nothing outside the closed one-rings of its two
    /// vertices, and a plan reads nothing outside the closed one-rings of
    /// its pair; so each contraction marks its new one-ring (and the
    /// deleted triangles' corners), and a pair with a marked vertex is
    /// planned again, serially, when its turn comes. Pass boundaries and
    /// candidates beyond the sorted part go through `step_pass` itself.
    pub(super) fn walk_batch(&mut self, factor: f32) -> Result<(), StopReason> {
        if self.live_tris <= self.target {
            return Err(StopReason::Target);
        }
        let pass = &self.pass;
        let end = pass.queue.len().min(pass.buckets.sorted_end());
        if !pass.open || pass.cursor >= end {
            return self.step_pass(factor);
        }
        // about one planned pair per 64 live triangles: a contraction
        // marks ~10 vertices, so a pair's plan stays valid ~90 % of the time
        let want = (self.live_tris / 64).clamp(16, MAX_BATCH);
        let mut batch = std::mem::take(&mut self.scratch);
        let scan = self.claim_batch(&mut batch, end, want);
        let mut plans = std::mem::take(&mut self.plan_scratch);
        self.plan_batch(&batch, &mut plans);
        let r = self.apply_batch(&batch, &mut plans, scan);
        self.scratch = batch;
        self.plan_scratch = plans;
        r
    }

    /// Fill `batch` with the next (up to `want`) untouched candidates of
    /// the pass before `end`, as queue indices (`LATER` on those not to
    /// plan ahead); returns where the scan stopped.
    fn claim_batch(&mut self, batch: &mut Vec<u32>, end: usize, want: usize) -> usize {
        batch.clear();
        let n = self.pass.number;
        let mut scan = self.pass.cursor;
        // A pair sharing a vertex with an earlier pair of the batch is
        // nearly always skipped (that vertex is touched once the earlier
        // pair contracts): it is not planned ahead (`LATER` on its index),
        // only in order, in the rare case it is still wanted then.
        let claim = self.next_generation();
        let (pass, mark) = (&self.pass, &mut self.mark);
        let mut deferred = 0;
        while scan < end && batch.len() < want {
            let e = pass.queue[scan];
            let (a, b) = (e.a as usize, e.b as usize);
            if pass.touched[a] != n && pass.touched[b] != n {
                if pass.defers(&self.quadric, e, self.cost_unit) {
                    deferred += 1;
                    scan += 1;
                    continue;
                }
                let later = mark[a] == claim || mark[b] == claim;
                (mark[a], mark[b]) = (claim, claim);
                debug_assert!(scan < LATER as usize);
                batch.push(scan as u32 | if later { LATER } else { 0 });
            }
            scan += 1;
        }
        self.pass.deferred += deferred;
        scan
    }

    /// Plan the batch's pairs (but those marked `LATER`) in parallel on the
    /// mesh as it is, into `plans` (one per batch entry).
    fn plan_batch(&self, batch: &[u32], plans: &mut Vec<Planned>) {
        // Plans wait on memory: the pairs are in cost order, so each one's
        // neighbourhood is cold, and its fan → triangle → vertex loads
        // depend on each other. Each thread plans a run of pairs and
        // prefetches ahead: the vertex data of the pair four on, the fan
        // lists of the pair two on, the triangles of the next pair.
        let pair = |k: usize| {
            let e = self.pass.queue[(batch[k] & !LATER) as usize];
            (e.a, e.b)
        };
        let ahead = |k: usize| batch[k] & LATER == 0;
        // (each thread takes runs of at least 32 pairs, in order; the plans
        // are written in place into the vector of the last batch)
        let len = batch.len();
        (0..len)
            .into_par_iter()
            .with_min_len(32)
            .map(|k| {
                if k + 4 < len && ahead(k + 4) {
                    let (a, b) = pair(k + 4);
                    self.prefetch_vertices(a, b);
                }
                if k + 2 < len && ahead(k + 2) {
                    let (a, b) = pair(k + 2);
                    self.vtris.prefetch_fan(a);
                    self.vtris.prefetch_fan(b);
                }
                if k + 1 < len && ahead(k + 1) {
                    let (a, b) = pair(k + 1);
                    self.prefetch_triangles(a);
                    self.prefetch_triangles(b);
                }
                ahead(k).then(|| {
                    let (a, b) = pair(k);
                    self.plan(a, b)
                })
            })
            .collect_into_vec(plans);
    }

    /// Walk the batch in order as `step_pass` would, contracting from the
    /// plans still valid and planning the others again.
    fn apply_batch(
        &mut self,
        batch: &[u32],
        plans: &mut [Planned],
        scan: usize,
    ) -> Result<(), StopReason> {
        let n = self.pass.number;
        let g = self.next_generation();
        for (k, i) in batch.iter().map(|&i| i & !LATER).enumerate() {
            // (prefetching for the contractions ahead, as for the plans:
            // what `contract` reads of the pair three on, and the fans and
            // triangles of the next)
            if let Some(Some(Ok(p))) = plans.get(k + 3) {
                self.prefetch_vertices(p.v0, p.v1);
            }
            if let Some(Some(Ok(p))) = plans.get(k + 1) {
                self.prefetch_triangles(p.v0);
                self.vtris.prefetch_fan(p.v1);
            }
            // what `step_inner` and `step_pass` check before a candidate
            if self.live_tris <= self.target {
                self.pass.cursor = i as usize;
                return Err(StopReason::Target);
            }
            let pass = &mut self.pass;
            let e = pass.queue[i as usize];
            if e.cost > pass.cost_limit && pass.removed > pass.goal / 6 {
                pass.cursor = pass.queue.len();
                return Ok(());
            }
            pass.cursor = i as usize + 1;
            if pass.touched[e.a as usize] == n || pass.touched[e.b as usize] == n {
                continue;
            }
            let plan = match plans[k].take() {
                Some(plan) if self.mark[e.a as usize] != g && self.mark[e.b as usize] != g => plan,
                // changed since it was planned, or not planned ahead
                _ => self.plan(e.a, e.b),
            };
            match plan {
                Ok(plan) if plan.deferred || self.stale_hole(&plan, e) => self.pass.deferred += 1,
                Ok(plan) => {
                    let before = self.live_tris;
                    let (v1, removed) = (plan.v1, plan.removed.clone());
                    self.contract(plan);
                    self.mark_changed(v1, &removed, g);
                    let pass = &mut self.pass;
                    pass.touched[e.a as usize] = n;
                    pass.touched[e.b as usize] = n;
                    pass.removed += before - self.live_tris;
                    pass.collapses += 1;
                }
                Err(r) => self.count_rejection(r),
            }
        }
        // the rest of the scanned range was touched: skipped, as step_pass would
        self.pass.cursor = self.pass.cursor.max(scan);
        Ok(())
    }

    /// Mark with `g` every vertex whose plan a contraction into `v1` may
    /// have changed: `v1`'s new one-ring (which holds the removed vertex's
    /// old one), the corners of the deleted triangles, and `v1`'s feature
    /// neighbours (whose feature kind `Features::contract` recounted).
    pub(super) fn mark_changed(&mut self, v1: u32, removed: &[u32], g: u32) {
        self.mark[v1 as usize] = g;
        for &t in self.vtris.fan(v1).iter().chain(removed) {
            for &x in &self.tris[t as usize] {
                self.mark[x as usize] = g;
            }
        }
        if let Some(f) = &self.features {
            for &x in &f.nbrs[v1] {
                self.mark[x as usize] = g;
            }
        }
    }

    pub(super) fn next_generation(&mut self) -> u32 {
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.mark.fill(0);
            self.generation = 1;
        }
        self.generation
    }
}
