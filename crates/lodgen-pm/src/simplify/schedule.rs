//! Which pair is tried next. [`Schedule::Greedy`]: the cheapest pair of a
//! lazily invalidated heap. [`Schedule::Passes`]: passes over every live
//! pair, costed in parallel (a lane batch at a time), bucketed by cost and
//! sorted as far as the walk gets, each pass stopping at a cost limit.

use super::legality::Relax;
use super::{dv, Entry, Pass, PassEntry, Rejected, Simplifier, StopReason};
use crate::mesh::adjacency::FanLookup;
use crate::simplify::heap::{f32_order_key, Buckets, QuadHeap};
use crate::simplify::quadric::{CostLanes, Quadric, LANES};
use crate::simplify::{Placement, Schedule, TopologyChange};
use rayon::prelude::*;
use std::time::Instant;

/// The spread bound of a pass ([`Pass::defers`]): the
/// `SPREAD_QUANTILE`-th smallest cost per unit of quadric weight (a mean
/// squared distance to the pair's planes) among the pass's candidates up to
/// its goal, times `SPREAD_FACTOR`². A pair over it waits for a later
/// pass, by when the other contractions have caught up. The cost orders
/// pairs by area × squared distance, so a pair over a small area (the tip
/// of a thin part, a small bump) looks cheap however far it moves the
/// surface; this bound keeps such a pair from going long before its
/// distance is typical. Measured by `cargo xtask quality --quick` over
/// 0.5–0.99 and 1.25–3 (0.7 and 1.5 best): Hausdorff against the best peer
/// per cell 1.02 → 0.94 (geometric mean of 21 cells), RMS unchanged (0.88);
/// rocker-arm 10 % Hausdorff 0.50 → 0.34 % of the diagonal, 2 % 1.54 →
/// 0.96 %, bunny 10 % 0.21 → 0.17 %, spot 50/10/2 % 0.198/1.35/5.29 →
/// 0.157/1.05/4.36 %; worse: cow 10 % 1.93 → 2.15 %, teapot 10 % 0.67 →
/// 0.86 % (0.60 % with the border corners of `setup`), beetle 10 % 4.3 →
/// 5.6 %.
const SPREAD_QUANTILE: f64 = 0.7;
/// See [`SPREAD_QUANTILE`] (a factor on distances, so squared on the bound).
const SPREAD_FACTOR: f64 = 1.5;
/// The spread bound's quantile is taken over at most this many candidates,
/// evenly spaced in the pass's order (a bounded cost per pass).
const SPREAD_SAMPLES: usize = 1 << 12;

/// A pass that contracted nothing but deferred pairs (by the spread bound
/// or reach) is followed by one whose spread bound is at least the stuck
/// pass's times this factor squared (a factor on distances), after the
/// k-th such pass in a row the factor to the power 2^(k−1) (1.1, 1.21,
/// 1.46, 2.14, 4.6, 21, …), until that is over [`STUCK_UNBOUND`] × the
/// pass's own bound: then the pass has no bound. Before (session 20) every
/// stuck pass was followed by one without the bound, which contracted its
/// cheapest pairs unchecked (the cow's run to 2 % alternated so from 166
/// live triangles). `target/release/xtask quality --quick`, geometric mean
/// of lodgen / best peer 0.910 / 0.933 before; steps g^(2^(k−1)): g 1.1
/// **0.897 / 0.932** (cow 2 % H / RMS 5.898 / 0.931 → 4.444 / 0.921 %),
/// 1.2 0.906 / 0.931 (5.425 / 0.890 %), 1.5 0.906 / 0.931; steps g^k: 1.1
/// 0.896 / 0.931, 1.2 0.902 / 0.931; a constant step (session 19): 1.1
/// 0.896 / 0.929, 1.2 0.897 / 0.929 — every other cell the same bits in
/// each. The constant step costs most when no legal pair is left (beetle
/// with its normals: 21 → 81 passes at 1.2); the doubling exponent bounds
/// a stuck run to a few passes (44 at 1.1; callgrind, docs/quality.md
/// "Hausdorff (session 20)"). Jumping the bound to the cheapest pair it
/// deferred (g 1): 801 passes on the cow, dropped.
const STUCK_GROWTH: f64 = 1.1;
/// See [`STUCK_GROWTH`] (on squared distances).
const STUCK_UNBOUND: f64 = 1e6;
/// Stuck passes in a row after which the next pass has no bound whatever
/// the bounds (with [`STUCK_GROWTH`] the step is then over 10¹⁰ on squared
/// distances: unbounded already unless the bounds are degenerate).
const STUCK_MAX_PASSES: u32 = 8;

/// [`TopologyChange::Joins`] or [`TopologyChange::All`] with
/// [`Schedule::Passes`]: a pass after one whose candidates refused by
/// the topology rules (link, border pinch, duplicate; or contracted
/// breaking one) outnumbered this share of its contractions relaxes joins
/// and flattening (`Relax::Sheets`). Measured by `target/release/xtask
/// quality --quick` with the option on (throw-away switch): relaxing only
/// when stuck, beetle 10 % H / RMS 2.887 / 0.525 %, 2 % at 40 triangles
/// 16.80 / 5.19 %; share 1: 2.354 / 0.362, 9.27 / 2.05 %; 0.5: 2.344 /
/// 0.357, 15.85 / 2.85 %; 0.25: 2.344 / 0.341, 6.52 / 1.77 % (meshopt at
/// 201 triangles 2.14 / 0.58 %; asked for 41 it stops at 59, 8.72 /
/// 2.36 %); every other cell the same at every share but cow 2 % RMS
/// 0.974 → 0.912 / 0.965 / 0.951 %.
const RELAX_SHARE: f64 = 0.25;

/// One chunk of a pass's costing: its entries, and (compacting) its
/// vertices' live fans and their lengths.
type CostedChunk = (Vec<PassEntry>, Vec<u32>, Vec<u32>);

/// A pass entry's bucket: the top 11 bits of its cost's order key.
#[inline]
pub(super) fn pass_bucket(cost: f32) -> usize {
    (f32_order_key(cost) >> 21) as usize
}

/// The order of a pass: by cost (`total_cmp`), as a sort key. Sorted
/// stably from entries generated in (a, b) order, this is the total order
/// (cost, a, b).
#[inline]
pub(super) fn pass_order(x: &PassEntry) -> u32 {
    f32_order_key(x.cost)
}

impl Simplifier {
    /// The furthest stage of [`Relax`] the run's
    /// [`TopologyChange`] lets it reach (`Relax::None`: none;
    /// [`TopologyChange::WhenShort`]'s second run is `simplify`'s, with
    /// [`TopologyChange::Joins`]).
    fn relax_cap(&self) -> Relax {
        match self.opts.topology_change {
            TopologyChange::Never | TopologyChange::WhenShort => Relax::None,
            TopologyChange::Joins => Relax::Sheets,
            TopologyChange::All => Relax::Flips,
        }
    }

    /// Re-cost every queued pair (after the costs' inputs changed).
    pub(super) fn rebuild_heap(&mut self) {
        if self.opts.schedule != Schedule::Greedy {
            // the next step starts a fresh pass
            self.pass.queue.clear();
            self.pass.buckets = Buckets::default();
            self.pass.cursor = 0;
            self.pass.open = false;
            return;
        }
        let mut pairs: Vec<(u32, u32)> = self.heap.drain().map(|e| (e.a, e.b)).collect();
        pairs.retain(|&(a, b)| self.alive[a as usize] && self.alive[b as usize]);
        pairs.sort_unstable();
        pairs.dedup();
        let entries: Vec<Entry> = pairs.iter().map(|&(a, b)| self.entry(a, b)).collect();
        self.heap = QuadHeap::from_vec(entries);
    }

    pub(super) fn step_inner(&mut self) -> Result<(), StopReason> {
        if self.live_tris <= self.target {
            return Err(StopReason::Target);
        }
        match self.opts.schedule {
            Schedule::Greedy => self.step_greedy(),
            Schedule::Passes { factor } => self.step_pass(factor),
        }
    }

    pub(super) fn step_greedy(&mut self) -> Result<(), StopReason> {
        loop {
            while let Some(e) = self.heap.pop() {
                let (a, b) = (e.a as usize, e.b as usize);
                if !self.alive[a]
                    || !self.alive[b]
                    || self.version[a] != e.va
                    || self.version[b] != e.vb
                {
                    continue;
                }
                match self.try_contract(e.a, e.b) {
                    Ok(()) => return Ok(()),
                    Err(r) => self.stats.rejected.count(r),
                }
            }
            // stuck: every pair again, with the rules relaxed a stage
            // further (a greedy run keeps the stage from here on)
            match self.pass.relax.next() {
                Some(r) if r <= self.relax_cap() => {
                    self.pass.relax = r;
                    self.fill_heap(self.live_pairs(), &[]);
                }
                _ => {
                    return Err(if self.stats.rejected.error > 0 {
                        StopReason::MaxError
                    } else {
                        StopReason::Exhausted
                    })
                }
            }
        }
    }

    /// Count a refused candidate (by reason; in the pass, what decides
    /// its stop and its relaxation).
    pub(super) fn count_rejection(&mut self, r: Rejected) {
        if r == Rejected::Error {
            self.pass.error_rejections += 1;
        }
        if matches!(
            r,
            Rejected::Link | Rejected::BoundaryPinch | Rejected::Duplicate
        ) {
            self.pass.refused += 1;
        }
        self.stats.rejected.count(r);
    }

    /// Every live pair: the edges of the live triangles and the live τ
    /// partners, each once as `(a, b)`, `a < b`, sorted.
    fn live_pairs(&self) -> Vec<(u32, u32)> {
        let mut pairs = Vec::new();
        for v in 0..self.pos.len() as u32 {
            if !self.alive[v as usize] {
                continue;
            }
            for &t in self.vtris.fan(v) {
                if self.tri_alive[t as usize] && self.tris[t as usize].contains(&v) {
                    pairs.extend(
                        self.tris[t as usize]
                            .iter()
                            .filter(|&&x| x > v)
                            .map(|&x| (v, x)),
                    );
                }
            }
            pairs.extend(
                self.partners(v)
                    .iter()
                    .filter(|&&x| x > v && self.alive[x as usize])
                    .map(|&x| (v, x)),
            );
        }
        pairs.sort_unstable();
        pairs.dedup();
        pairs
    }

    pub(super) fn step_pass(&mut self, factor: f32) -> Result<(), StopReason> {
        let cap = self.relax_cap();
        loop {
            let pass = &mut self.pass;
            if pass.cursor >= pass.queue.len() {
                let stuck = pass.open && pass.collapses == 0;
                // (a stuck pass that deferred pairs: the next one loosens
                // the spread bound, `Simplifier::loosened`)
                let loosen = stuck && pass.deferred > 0;
                pass.stuck = if loosen { pass.stuck + 1 } else { 0 };
                // (after a pass that made a contraction, every rule is back)
                if !stuck {
                    // (the next pass relaxes joins and flattening too when
                    // they held this one: refused more than a share of
                    // what it contracted)
                    let held = pass.refused as f64 > RELAX_SHARE * pass.collapses as f64;
                    pass.relax = if held {
                        cap.min(Relax::Sheets)
                    } else {
                        Relax::None
                    };
                }
                if stuck && pass.deferred == 0 {
                    // nothing changed: the next pass would be the same,
                    // unless the rules relax a stage further
                    match pass.relax.next() {
                        Some(r) if r <= cap => pass.relax = r,
                        _ => {
                            return Err(if pass.error_rejections > 0 {
                                StopReason::MaxError
                            } else {
                                StopReason::Exhausted
                            })
                        }
                    }
                }
                // (a pass that contracted nothing and deferred nothing is
                // followed by one without the spread bound)
                self.start_pass(factor, !stuck || loosen);
                if self.pass.queue.is_empty() {
                    return Err(StopReason::Exhausted);
                }
                continue;
            }
            if pass.cursor >= pass.buckets.sorted_end() {
                pass.buckets
                    .sort_through(&mut pass.queue, pass.cursor, pass_order);
            }
            let e = pass.queue[pass.cursor];
            if e.cost > pass.cost_limit && pass.removed > pass.goal / 6 {
                pass.cursor = pass.queue.len();
                continue;
            }
            pass.cursor += 1;
            let n = pass.number;
            if pass.touched[e.a as usize] == n || pass.touched[e.b as usize] == n {
                continue;
            }
            if pass.defers(&self.quadric, e, self.cost_unit) {
                pass.deferred += 1;
                continue;
            }
            let before = self.live_tris;
            match self.plan(e.a, e.b) {
                Ok(plan) if plan.deferred || self.stale_hole(&plan, e) => self.pass.deferred += 1,
                Ok(plan) => {
                    self.contract(plan);
                    let pass = &mut self.pass;
                    pass.touched[e.a as usize] = n;
                    pass.touched[e.b as usize] = n;
                    pass.removed += before - self.live_tris;
                    pass.collapses += 1;
                    return Ok(());
                }
                Err(r) => self.count_rejection(r),
            }
        }
    }

    /// Cost every live pair (edges and τ partners, both vertices not
    /// locked), sort, and set the pass's goal, cost limit and (when
    /// `bounded`) spread bound. Pairs are sorted by the total order (cost,
    /// a, b): the order depends on nothing but the mesh (not on the thread
    /// count).
    pub(super) fn start_pass(&mut self, factor: f32, bounded: bool) {
        let t0 = Instant::now();
        // The costing reads every live vertex's fan and skips its dead
        // triangles; once any list was rewritten it also writes the live
        // ones out, and they become the new CSR (compacted where they are
        // read anyway, not by a pass over all triangles). Every pass but
        // the first (the fans `new` builds are compact) so reads the fans
        // in vertex order, not the contractions' scattered rewrites: −3 %
        // CPU on the bunny to 2 % than compacting only once the rewrites
        // reached half the CSR (`RAYON_NUM_THREADS=1 cpu_simplify
        // bunny.obj 0 25 wedges 0.02`, alternating, median 93.5 → 90.3 ms).
        // (The fans `new` builds are compact: the first pass never does.)
        let compact = self.vtris.rewritten_any();
        // the last pass's list is not read again: freed before this pass's
        // parts are made (peak memory: the two were the second pass's
        // peak), `Buckets::scatter` allocates the new one at its size
        self.pass.queue = Vec::new();
        const CHUNK: usize = 2048;
        let nv = self.pos.len();
        let this = &*self;
        // pairs that take `placement` (most) are costed a lane batch at a
        // time, the others one by one by `key`
        let lanes_apply = self.attributes.is_none() && self.opts.placement == Placement::Optimal;
        let chunks: Vec<CostedChunk> = (0..nv.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| this.cost_chunk(c * CHUNK..((c + 1) * CHUNK).min(nv), compact, lanes_apply))
            .collect();
        let mut parts = Vec::with_capacity(chunks.len());
        if compact {
            let (mut lists, mut lens) = (Vec::new(), Vec::new());
            for (out, fans, len) in chunks {
                parts.push(out);
                lists.push(fans);
                lens.push(len);
            }
            self.vtris.replace(&lists, &lens);
        } else {
            parts.extend(chunks.into_iter().map(|c| c.0));
        }
        let mut queue: Vec<PassEntry> = std::mem::take(&mut self.pass.queue);
        let mut buckets = Buckets::scatter(parts, &mut queue, |e| pass_bucket(e.cost));
        let goal = self.live_tris.saturating_sub(self.target);
        // most contractions remove two triangles
        let (limit, spread) = if goal / 2 < queue.len() {
            buckets.sort_through(&mut queue, goal / 2, pass_order);
            let spread = if bounded {
                self.loosened(self.spread_limit(&queue[..goal / 2]))
            } else {
                f64::INFINITY
            };
            (queue[goal / 2].cost * factor, spread)
        } else {
            (f32::INFINITY, f64::INFINITY)
        };
        // the pass (nearly always) stops at the limit: sort up to it now,
        // in parallel, the rest only if the walk gets there
        buckets.sort_through_bucket(&mut queue, pass_bucket(limit), pass_order);
        let pass = &mut self.pass;
        pass.number += 1;
        pass.open = true;
        pass.queue = queue;
        pass.buckets = buckets;
        pass.cursor = 0;
        pass.goal = goal;
        pass.removed = 0;
        pass.collapses = 0;
        pass.error_rejections = 0;
        pass.cost_limit = limit;
        pass.spread_limit = spread;
        pass.deferred = 0;
        pass.refused = 0;
        self.stats.passes += 1;
        self.stats.time.heap += t0.elapsed();
    }

    /// The spread bound `own` of a pass (its quantile), loosened after
    /// passes that contracted nothing ([`STUCK_GROWTH`]): at least the
    /// stuck pass's bound times the step squared; infinite (no bound) once
    /// that is over [`STUCK_UNBOUND`] × `own`.
    fn loosened(&self, own: f64) -> f64 {
        let (k, prev) = (self.pass.stuck, self.pass.spread_limit);
        if k == 0 {
            return own;
        }
        // (a stuck pass with no positive finite bound to grow from — a
        // zero bound on a flat patch, say — or a run stuck that long: no
        // bound, as before the loosening; growing from zero would stall the
        // run forever)
        if !(prev > 0.0 && prev.is_finite() && own.is_finite()) || k > STUCK_MAX_PASSES {
            return f64::INFINITY;
        }
        // the k-th stuck pass in a row: a step of g^(2^(k−1)) in distance
        let g = STUCK_GROWTH.powi(1 << (k - 1).min(16));
        let loose = g * g * prev;
        if loose > STUCK_UNBOUND * own {
            f64::INFINITY
        } else {
            own.max(loose)
        }
    }

    /// The spread bound ([`SPREAD_QUANTILE`]) over the pass's first
    /// candidates `sorted`, in cost order.
    fn spread_limit(&self, sorted: &[PassEntry]) -> f64 {
        let step = sorted.len().div_ceil(SPREAD_SAMPLES).max(1);
        let mut spread: Vec<f64> = sorted
            .iter()
            .step_by(step)
            .filter_map(|e| {
                let w = self.quadric[e.a as usize].weight + self.quadric[e.b as usize].weight;
                // (in mesh units: the key without its unit, a power of two)
                (w > 0.0).then(|| f64::from(e.cost) / self.cost_unit / w)
            })
            .collect();
        if spread.is_empty() {
            return f64::INFINITY;
        }
        let k = ((SPREAD_QUANTILE * spread.len() as f64) as usize).min(spread.len() - 1);
        let (_, q, _) = spread.select_nth_unstable_by(k, f64::total_cmp);
        *q * SPREAD_FACTOR * SPREAD_FACTOR
    }

    /// Cost the live pairs `(v, x)`, `v < x`, of the vertices `range`, in
    /// `(v, x)` order, skipping pairs of two locked vertices; pairs of two
    /// free vertices a lane batch at a time when `lanes_apply`. With
    /// `compact`, also each vertex's live fan and its length.
    fn cost_chunk(
        &self,
        range: std::ops::Range<usize>,
        compact: bool,
        lanes_apply: bool,
    ) -> CostedChunk {
        let mut out = Vec::with_capacity(3 * range.len());
        // compacted fans: the lists, and each vertex's length
        let (mut fans, mut lens) = (Vec::new(), Vec::new());
        let mut lanes = CostLanes::default();
        // where each lane's entry is in `out`
        let mut slots = [0usize; LANES];
        let flush = |lanes: &mut CostLanes, out: &mut Vec<PassEntry>, slots: &[usize]| {
            let n = lanes.len();
            let costs = lanes.costs();
            for (&i, &cost) in slots[..n].iter().zip(&costs[..n]) {
                let (a, b) = (out[i].a, out[i].b);
                out[i].cost = self.scaled(cost + self.hole_cost(a, b), a, b);
            }
        };
        let mut nb: Vec<u32> = Vec::with_capacity(32);
        for v in range.start as u32..range.end as u32 {
            let vi = v as usize;
            if !self.alive[vi] {
                if compact {
                    lens.push(0);
                }
                continue;
            }
            // neighbours above v, each once, in fan order
            nb.clear();
            let mut add = |x: u32| {
                if x > v && !nb.contains(&x) {
                    nb.push(x);
                }
            };
            let before = fans.len();
            for &t in self.vtris.fan(v) {
                if self.tri_alive[t as usize] {
                    let [x, y, z] = self.tris[t as usize];
                    add(x);
                    add(y);
                    add(z);
                    if compact {
                        fans.push(t);
                    }
                }
            }
            if compact {
                lens.push((fans.len() - before) as u32);
            }
            for &x in self.partners(v) {
                if self.alive[x as usize] {
                    add(x);
                }
            }
            // in (a, b) order: the buckets keep it, and a stable
            // sort by cost then gives the total order
            nb.sort_unstable();
            // (what is v's, once)
            let v_locked = self.locked[vi];
            let v_lanes = lanes_apply && self.free(v);
            let (qv, pv) = (&self.quadric[vi], dv(self.pos[vi]));
            for &x in &nb {
                let xi = x as usize;
                if v_locked && self.locked[xi] {
                    continue;
                }
                if v_lanes && self.free(x) {
                    slots[lanes.len()] = out.len();
                    out.push(PassEntry {
                        cost: 0.0,
                        a: v,
                        b: x,
                    });
                    let q = *qv + self.quadric[xi];
                    lanes.push(&q, pv, dv(self.pos[xi]));
                    if lanes.is_full() {
                        flush(&mut lanes, &mut out, &slots);
                    }
                } else {
                    out.push(PassEntry {
                        cost: self.key(v, x),
                        a: v,
                        b: x,
                    });
                }
            }
        }
        if !lanes.is_empty() {
            flush(&mut lanes, &mut out, &slots);
        }
        (out, fans, lens)
    }
}

impl Pass {
    /// Whether the candidate `e` waits for a later pass: its cost per unit
    /// of its quadrics' weight is over the pass's spread bound.
    #[inline]
    pub(super) fn defers(&self, quadric: &[Quadric], e: PassEntry, unit: f64) -> bool {
        if self.spread_limit == f64::INFINITY {
            return false;
        }
        let w = quadric[e.a as usize].weight + quadric[e.b as usize].weight;
        f64::from(e.cost) / unit > self.spread_limit * w && w > 0.0
    }
}
