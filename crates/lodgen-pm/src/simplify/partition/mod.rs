//! Partitioned simplification: the scheme of meshoptimizer's clusterlod
//! and of Nanite-style partitioned simplification, so that the first and
//! largest part of a run uses every core.
//!
//! The triangles are cut into clusters of consecutive triangles (`prepare`
//! numbers vertices along a z-order curve and triangles by their lowest
//! corner, so a run of triangles is a compact patch). The cut depends on
//! the mesh and [`crate::SimplifyOptions::partition`] only, never on the
//! thread count. A vertex all of whose triangles are in one cluster is
//! that cluster's *interior*; every other vertex is *held* while the
//! clusters are simplified: only pairs of two interior vertices contract.
//! Each cluster becomes a small [`Simplifier`] of its own (its triangles,
//! with the global quadrics and flags, held vertices locked).
//!
//! The clusters then make the passes of the whole-mesh schedule together,
//! in *rounds*: each costs its pairs (in parallel), the round's cost limit
//! is taken from all of them as one pass would take it (`factor ×` the
//! cost of the goal-th pair of the union, goal = half the triangles still
//! to remove), and each walks its own pairs cheapest first up to that
//! limit (in parallel). So the clusters remove what the whole-mesh walk
//! would remove first, wherever it is, and not a fixed share each. Rounds
//! stop at `KEEP` of the input, each cluster's share of that capped so
//! that none overshoots; then the states are written back.
//!
//! A contraction inside a cluster reads and changes only the fans of two
//! interior vertices, i.e. the cluster's own triangles, and the state of
//! its interior vertices (not even a held vertex's fan, which another
//! cluster's link test would read: two clusters pulling their sides of a
//! border edge onto the same held vertex could make a double face). So
//! the contractions of two clusters commute:
//! the logs are merged into one valid sequence in a fixed order (by round,
//! then by the running maximum of the errors of the cluster's round, then
//! cluster, then step, which keeps each cluster's order). A run to 2 %
//! or less of a mesh of at least `4 × 16` clusters then makes a coarse
//! stage (`coarse.rs`): groups of 16 consecutive clusters simplified the
//! same way from 15 % to 4 % of the input, holding only the groups'
//! borders. Then the whole mesh continues with the usual passes, the
//! borders now free.
//!
//! Runs with the pass schedule and without τ pairs, to at most `KEEP / 2`
//! of the input, on meshes of at least `MIN_CLUSTERS` clusters, take this
//! path: position-only runs, and runs with feature edges and wedges as
//! long as every vertex has one wedge (the CLI's and Python's path on a
//! scan: open borders are the feature lines, the wedge edits implied).
//! Each cluster takes the feature state of its vertices
//! (`Features::restricted`; an interior vertex's feature neighbours are
//! all in its cluster), and the merge replays `Features::contract` in the
//! merged order. Seams (wedges that differ at a vertex) and attribute
//! quadrics keep the whole-mesh walk.

mod coarse;
mod merge;

use super::{Meter, Pass, Simplifier, Stage, Stats};
use crate::mesh::adjacency::{FanLookup, Fans};
use crate::progressive::Log;
use crate::simplify::heap::{Buckets, QuadHeap};
use crate::simplify::quadric::Quadric;
use crate::simplify::schedule::{pass_bucket, pass_order};
use crate::simplify::stats::Rejections;
use crate::simplify::Schedule;
use rayon::prelude::*;

/// Meshes of fewer clusters than this keep the whole-mesh walk: on the
/// bunny (69,451 triangles, four clusters) partitioning raised the RMS
/// error of the 2 % level by 3.4 % (more of a small mesh is near a held
/// border) for a time gain of a few milliseconds.
const MIN_CLUSTERS: usize = 8;

/// The rounds stop at this fraction of the input: the held borders are
/// still at full resolution there, so the clusters' interiors are a little
/// coarser than the whole-mesh walk would leave them, and the whole-mesh
/// passes that follow (with the borders free) must have room to even that
/// out before the target: runs to more than half of it keep the
/// whole-mesh walk. Measured on the CLI's path (`lodgen bunny-1m.obj
/// --levels 50%,10%,2%`; whole-mesh walk 2 % Hausdorff 0.1167 %, RMS
/// 0.0102 %): 0.1 made the 10 % level's Hausdorff distance 0.041 %
/// instead of 0.000007 %; 0.15 keeps every level (2 %: 0.1167 %, RMS
/// 0.0104 %); 0.2 0.1290 %, 0.25 0.1228 %, 0.3 0.1422 %. On subdivided
/// shared meshes (`cpu_simplify MESH 2|3 1 wedges RATIO 16384`) 0.15 gave
/// a geometric mean of 0.87 of the whole-mesh walk's Hausdorff distance
/// over seven cells (0.2: 0.94, with spot ×3 at 1 % +51 %), RMS within
/// 1.5 % everywhere (docs/performance.md).
const KEEP: f64 = 0.15;

/// At most this many rounds (the whole-mesh walk needs about ten passes
/// to 2 %; the rounds stop at `KEEP` well before).
const MAX_ROUNDS: usize = 16;

/// A vertex interior to no cluster (held, or in no triangle).
const HELD: u32 = u32::MAX;

/// Quadrics are handed to the clusters in blocks of this many vertices
/// (5.8 MB), each freed after the last cluster that reads it.
const BLOCK: usize = 1 << 16;

/// Clusters built at once (in parallel): the whole mesh's blocks are freed
/// between batches.
const BATCH: usize = 16;

/// The whole mesh's quadrics and positions in blocks of `BLOCK` vertices,
/// each `None` once its last cluster is built.
type Blocks<'a> = (&'a [Option<Vec<Quadric>>], &'a [Option<Vec<[f32; 3]>>]);

/// A cluster's triangles in the whole mesh's numbering.
enum Tris {
    /// A run of triangles: local triangle `t` is global `start + t` (the
    /// first stage's clusters).
    Run(u32),
    /// Local triangle `t` is global `ids[t]` (the coarse clusters': the
    /// live triangles of their run).
    List(Vec<u32>),
}

impl Tris {
    /// The global triangle of local triangle `t`.
    #[inline]
    fn global(&self, t: u32) -> u32 {
        match self {
            Tris::Run(start) => start + t,
            Tris::List(ids) => ids[t as usize],
        }
    }
}

/// A simplified cluster: its numbering and its simplifier after the run.
struct Local {
    /// Local vertex → global vertex (increasing, so ties between pairs of
    /// equal cost break as in the global numbering).
    verts: Vec<u32>,
    /// Its triangles' global numbers.
    tris: Tris,
    /// Local vertex → held (not interior): never contracted.
    held: Vec<bool>,
    /// The log's length at the end of each round.
    rounds: Vec<u32>,
    s: Simplifier,
}

/// A cluster's log and numbering, kept for the merge.
struct Done {
    verts: Vec<u32>,
    tris: Tris,
    rounds: Vec<u32>,
    log: Log,
}

impl Simplifier {
    /// Tells the meter, if any, what the run is doing.
    fn set_stage(&self, stage: Stage) {
        if let Some(m) = &self.meter {
            m.set_stage(stage);
        }
    }

    /// The cluster size when `run` should simplify in clusters first.
    pub(super) fn partition_size(&self) -> Option<usize> {
        let size = self.opts.partition.filter(|&s| s > 0)?;
        let nt = self.tris.len();
        let applies = matches!(self.opts.schedule, Schedule::Passes { .. })
            && self.features.as_ref().is_none_or(|f| {
                // (wedges only as one per vertex, whose edits the log
                // does not record: the clusters' logs carry no wedges)
                !f.tracked() || (f.vertex_wedge.is_some() && f.edits_implied)
            })
            && self.attributes.is_none()
            && self.partners.is_empty()
            && self.log.records.is_empty()
            && self.pass.number == 0
            && self.live_tris == nt
            && self.target as f64 <= KEEP / 2.0 * nt as f64
            && nt >= MIN_CLUSTERS.saturating_mul(size);
        // clusters of equal size, as close to `size` as divides evenly
        let count = (nt + size / 2) / size;
        applies.then(|| nt.div_ceil(count.max(1)))
    }

    /// Simplify the clusters of `size` triangles in rounds, write their
    /// states back, merge their logs, and leave the mesh ready for the
    /// whole-mesh passes.
    pub(super) fn run_partitioned(&mut self, size: usize) {
        let Schedule::Passes { factor } = self.opts.schedule else {
            return;
        };
        let nt = self.tris.len();
        self.set_stage(Stage::Clustering);
        let home = self.homes(size);
        // (the clusters build their own fans: the whole mesh's are not
        // read again before they are rebuilt at the end, and freeing them
        // first keeps them off the peak of the clusters' construction)
        self.vtris = Fans::default();
        // (nor are the whole mesh's pass marks and link-test marks, 8
        // bytes per vertex: zeroed again after the write-back)
        self.pass.touched = Vec::new();
        self.mark = Vec::new();
        // Memory: the clusters take the triangles and the interior
        // vertices' quadrics and positions; the whole mesh's are rebuilt
        // from theirs.
        let nv = self.pos.len();
        let held: Vec<(usize, Quadric, [f32; 3])> = (0..nv)
            .filter(|&v| home[v] == HELD)
            .map(|v| (v, self.quadric[v], self.pos[v]))
            .collect();
        let mut locals = self.clusters(size, &home);
        // (the write-back tells a cluster's interior by its `held` flags)
        drop(home);
        self.tri_alive = Vec::new();
        let stop = (KEEP * nt as f64) as usize;
        self.set_stage(Stage::Contracting);
        let meter = self.meter.as_deref();
        rounds(
            &mut locals,
            self.live_tris,
            self.target,
            stop,
            factor,
            meter,
        );
        // (zeroed pages, mapped as the write-back reaches them while it
        // frees the clusters' copies: the whole mesh's arrays and the
        // clusters' are never resident at once; the held vertices, spread
        // over every page, come last)
        self.quadric = zero_quadrics(nv);
        self.pos = vec![[0.0; 3]; nv];
        self.tris = vec![[0; 3]; nt];
        self.tri_alive = vec![false; nt];
        self.pass.touched = vec![0; nv];
        self.mark = vec![0; nv];
        let mut done = Vec::with_capacity(locals.len());
        for l in locals {
            done.push(self.write_back(l));
        }
        for (v, q, p) in held {
            self.quadric[v] = q;
            self.pos[v] = p;
        }
        self.merge_logs(done);
        let alive = &self.tri_alive;
        self.vtris = Fans::new(nv, &self.tris, |t| alive[t]);
        self.run_coarse(size, factor);
    }

    /// The clusters of `size` triangles, built a batch at a time from the
    /// whole mesh's triangles, quadrics and positions, which they consume:
    /// each cluster takes its own run of triangles (split off the whole
    /// mesh's array from its end, so the array shrinks as the pieces are
    /// made), and a block of quadrics and positions is freed once the last
    /// cluster with a corner in it is built. So the whole mesh's copies
    /// and the clusters' are never resident at once (bunny-4m: 196 MB of
    /// quadrics, 53 MB of triangles, 27 MB of positions).
    fn clusters(&mut self, size: usize, home: &[u32]) -> Vec<Local> {
        let own = into_pieces(std::mem::take(&mut self.tris), size);
        let nc = own.len();
        // the last cluster with a corner in each block of quadrics
        let mut last = vec![0usize; self.pos.len().div_ceil(BLOCK)];
        for (c, tris) in own.iter().enumerate() {
            for &v in tris.iter().flatten() {
                last[v as usize / BLOCK] = c;
            }
        }
        let mut quads: Vec<Option<Vec<Quadric>>> =
            into_pieces(std::mem::take(&mut self.quadric), BLOCK)
                .into_iter()
                .map(Some)
                .collect();
        let mut poss: Vec<Option<Vec<[f32; 3]>>> =
            into_pieces(std::mem::take(&mut self.pos), BLOCK)
                .into_iter()
                .map(Some)
                .collect();
        let mut own = own.into_iter();
        let mut locals: Vec<Local> = Vec::with_capacity(nc);
        while locals.len() < nc {
            let first = locals.len();
            let batch: Vec<Vec<[u32; 3]>> = own.by_ref().take(BATCH).collect();
            let (this, blocks) = (&*self, (&quads[..], &poss[..]));
            locals.par_extend(
                batch
                    .into_par_iter()
                    .enumerate()
                    .map(|(i, tris)| this.cluster((first + i) as u32, size, tris, home, blocks)),
            );
            for (b, (q, p)) in quads.iter_mut().zip(&mut poss).enumerate() {
                if last[b] < locals.len() {
                    *q = None;
                    *p = None;
                }
            }
        }
        locals
    }

    /// Each vertex's cluster if all its triangles are in one, else `HELD`.
    fn homes(&self, size: usize) -> Vec<u32> {
        (0..self.pos.len() as u32)
            .into_par_iter()
            .map(|v| {
                let mut cs = self.vtris.fan(v).iter().map(|&t| t as usize / size);
                match cs.next() {
                    Some(c) if cs.all(|d| d == c) => c as u32,
                    _ => HELD,
                }
            })
            .collect()
    }

    /// Cluster `c` (triangles `c·size..`, `own`) as a simplifier of its
    /// own, its quadrics and positions read from the blocks `blocks`.
    fn cluster(
        &self,
        c: u32,
        size: usize,
        own: Vec<[u32; 3]>,
        home: &[u32],
        (quads, poss): Blocks<'_>,
    ) -> Local {
        let start = c as usize * size;
        let fetch = |g: usize| {
            let quadric = quads[g / BLOCK].as_ref();
            let position = poss[g / BLOCK].as_ref();
            (
                quadric.expect("a block of quadrics outlives its last cluster")[g % BLOCK],
                position.expect("a block of positions outlives its last cluster")[g % BLOCK],
            )
        };
        self.numbered(c, Tris::Run(start as u32), own, home, fetch)
    }

    /// Cluster `c` of the triangles `own` (global ids, numbered `tris`) as
    /// a simplifier of its own, its vertices' quadrics and positions
    /// `fetch`ed by global id.
    fn numbered(
        &self,
        c: u32,
        tris: Tris,
        mut own: Vec<[u32; 3]>,
        home: &[u32],
        fetch: impl Fn(usize) -> (Quadric, [f32; 3]),
    ) -> Local {
        let mut verts: Vec<u32> = own.iter().flatten().copied().collect();
        verts.sort_unstable();
        verts.dedup();
        // (a sixth of the corners: the rest of the block, written, would
        // stay resident with every cluster, 44 MB at 4.4M triangles)
        verts.shrink_to_fit();
        let local = |g: u32| verts.binary_search(&g).map_or(u32::MAX, |i| i as u32);
        for t in &mut own {
            *t = t.map(local);
        }
        let held: Vec<bool> = verts.iter().map(|&g| home[g as usize] != c).collect();
        let s = self.local(&verts, own, &held, fetch);
        Local {
            verts,
            tris,
            held,
            rounds: Vec::new(),
            s,
        }
    }

    /// A simplifier over the vertices `verts` (global ids) and `tris`
    /// (local ids) with this one's flags and lift bits and the quadrics
    /// and positions `fetch` gives, the `held` ones locked.
    fn local(
        &self,
        verts: &[u32],
        tris: Vec<[u32; 3]>,
        held: &[bool],
        fetch: impl Fn(usize) -> (Quadric, [f32; 3]),
    ) -> Simplifier {
        let nv = verts.len();
        let nt = tris.len();
        let get = |g: &u32| *g as usize;
        let (quadric, pos) = verts.iter().map(|&g| fetch(g as usize)).unzip();
        let vtris = Fans::new(nv, &tris, |_| true);
        let mut lifted = super::lift::Lifted::new(nv, self.lifted.is_on());
        for (i, &g) in verts.iter().enumerate() {
            // (none before the first stage; the coarse clusters' vertices
            // made by the first may be)
            lifted.set(i as u32, self.lifted.get(g));
        }
        Simplifier {
            opts: self.opts,
            target: 0,
            pos,
            quadric,
            tris,
            tri_alive: vec![true; nt],
            vtris,
            partners: Vec::new(),
            version: Vec::new(),
            alive: vec![true; nv],
            locked: verts
                .iter()
                .zip(held)
                .map(|(g, &h)| self.locked[get(g)] || h)
                .collect(),
            boundary: verts.iter().map(|g| self.boundary[get(g)]).collect(),
            corner: verts.iter().map(|g| self.corner[get(g)]).collect(),
            heap: QuadHeap::from_vec(Vec::new()),
            pass: Pass {
                touched: vec![0; nv],
                ..Pass::default()
            },
            live_tris: nt,
            log: Log::with_capacity(nt / 2),
            stats: Stats::default(),
            mark: vec![0; nv],
            generation: 0,
            scratch: Vec::new(),
            fan_scratch: Vec::new(),
            plan_scratch: Vec::new(),
            cost_unit: self.cost_unit,
            cost_scale: self
                .cost_scale
                .as_ref()
                .map(|s| verts.iter().map(|g| s[get(g)]).collect()),
            features: self.features.as_ref().map(|f| f.restricted(verts)),
            attributes: None,
            meter: None,
            lifted,
        }
    }

    /// Write a cluster's state back: its interior vertices and its own
    /// triangles as they are now.
    fn write_back(&mut self, l: Local) -> Done {
        let Local {
            verts,
            tris: ids,
            held,
            rounds,
            s,
        } = l;
        for (i, &g) in verts.iter().enumerate() {
            let g = g as usize;
            if !held[i] {
                self.pos[g] = s.pos[i];
                self.quadric[g] = s.quadric[i];
                self.alive[g] = s.alive[i];
                self.boundary[g] = s.boundary[i];
                self.corner[g] = s.corner[i];
                self.lifted.set(g as u32, s.lifted.get(i as u32));
            }
        }
        for (t, tri) in s.tris.iter().enumerate() {
            let g = ids.global(t as u32) as usize;
            self.tris[g] = tri.map(|x| verts[x as usize]);
            self.tri_alive[g] = s.tri_alive[t];
        }
        if let Some(f) = &mut self.features {
            // one wedge per vertex: each corner's wedge is its vertex's
            // (a dead triangle's as it died: its corners stay as they were)
            if let (Some(w), Some(vw)) = (&mut f.wedges, &f.vertex_wedge) {
                for t in 0..s.tris.len() as u32 {
                    let g = ids.global(t) as usize;
                    w[g] = self.tris[g].map(|v| vw[v as usize]);
                }
            }
        }
        self.live_tris -= s.tris.len() - s.live_tris;
        self.stats.collapses += s.stats.collapses;
        // (the clusters made the same rounds: count them once)
        self.stats.passes = self.stats.passes.max(s.stats.passes);
        add_rejections(&mut self.stats.rejected, &s.stats.rejected);
        Done {
            verts,
            tris: ids,
            rounds,
            log: s.log,
        }
    }
}

/// Rounds over the clusters (`live` triangles in all, the whole mesh's
/// target `target`) until `stop` triangles live, `MAX_ROUNDS` were made,
/// or a round removed less than 1 % (the held borders block the rest);
/// then frees what the write-back and the merge do not read. Each
/// cluster's walk counts its removed triangles off `meter`'s.
fn rounds(
    locals: &mut [Local],
    mut live: usize,
    target: usize,
    stop: usize,
    factor: f32,
    meter: Option<&Meter>,
) {
    for _ in 0..MAX_ROUNDS {
        if live <= stop || meter.is_some_and(Meter::is_cancelled) {
            break;
        }
        let removed = round(locals, live, live - target, live - stop, factor, meter);
        live -= removed;
        if removed < live / 100 {
            break; // the held borders block the rest
        }
    }
    for l in locals {
        l.s.vtris = Fans::default();
        l.s.pass = Pass::default();
        l.s.mark = Vec::new();
        l.s.locked = Vec::new();
    }
}

/// One round over every cluster (`live` triangles in all): each costs
/// its pairs, the limit is `factor ×` the cost of the union's
/// `goal / 2`-th pair (as a pass of the whole-mesh walk takes it), and each
/// cluster walks its pairs up to it, removing at most its share (by live
/// triangles) of `most`. Returns the triangles removed.
fn round(
    locals: &mut [Local],
    live: usize,
    goal: usize,
    most: usize,
    factor: f32,
    meter: Option<&Meter>,
) -> usize {
    locals.par_iter_mut().for_each(|l| {
        // (u128: live × most may not fit a usize)
        let share = (l.s.live_tris as u128 * most as u128 / live.max(1) as u128) as usize;
        l.s.target = l.s.live_tris - share;
        // (no spread bound: the round's walk takes pairs by cost only)
        l.s.start_pass(factor, false);
    });
    let limit = union_limit(locals, goal / 2, factor);
    locals
        .par_iter_mut()
        .map(|l| {
            let removed = walk(&mut l.s, &l.held, limit);
            // (the next round's pass makes its own list: the clusters
            // still walking then hold theirs beside the logs' growth)
            l.s.pass.queue = Vec::new();
            l.rounds.push(l.s.log.records.len() as u32);
            if let Some(m) = meter {
                m.remove(removed);
            }
            removed
        })
        .sum()
}

/// `factor ×` the cost of the `k`-th cheapest pair (from 0) of all the
/// clusters' passes, infinite when there are not that many.
fn union_limit(locals: &mut [Local], k: usize, factor: f32) -> f32 {
    let mut counts = vec![0usize; Buckets::COUNT];
    for l in locals.iter() {
        let mut prev = 0;
        for (b, &e) in l.s.pass.buckets.ends().iter().enumerate() {
            counts[b] += e - prev;
            prev = e;
        }
    }
    let mut before = 0;
    let Some(b) = counts.iter().position(|&n| {
        before += n;
        before > k
    }) else {
        return f32::INFINITY;
    };
    let rank = k - (before - counts[b]);
    let mut costs: Vec<f32> = Vec::new();
    for l in locals.iter() {
        let ends = l.s.pass.buckets.ends();
        if let Some(&e) = ends.get(b) {
            let s = if b == 0 { 0 } else { ends[b - 1] };
            costs.extend(l.s.pass.queue[s..e].iter().map(|x| x.cost));
        }
    }
    let (_, &mut cost, _) = costs.select_nth_unstable_by(rank, f32::total_cmp);
    cost * factor
}

/// The walk of one round in a cluster: the pass's pairs cheapest first, up
/// to `limit` or the cluster's target, skipping pairs whose vertices moved
/// in this pass, as `step_pass` does, and pairs with a `held` vertex.
/// Returns the triangles removed.
fn walk(s: &mut Simplifier, held: &[bool], limit: f32) -> usize {
    let before = s.live_tris;
    let n = s.pass.number;
    let pass = &mut s.pass;
    pass.buckets
        .sort_through_bucket(&mut pass.queue, pass_bucket(limit), pass_order);
    let end = pass.buckets.sorted_end().min(pass.queue.len());
    for i in 0..end {
        let e = s.pass.queue[i];
        if s.live_tris <= s.target || e.cost > limit {
            break;
        }
        let touched = &s.pass.touched;
        let (a, b) = (e.a as usize, e.b as usize);
        if touched[a] == n || touched[b] == n || held[a] || held[b] {
            continue;
        }
        match s.plan(e.a, e.b) {
            Ok(plan) => {
                s.contract(plan);
                s.pass.touched[e.a as usize] = n;
                s.pass.touched[e.b as usize] = n;
            }
            Err(r) => s.stats.rejected.count(r),
        }
    }
    before - s.live_tris
}

/// `v` cut into pieces of `size` elements (the last one shorter), with
/// at most one piece's worth of memory above `v`'s: the pieces are split
/// off the end and the rest shrunk in place each time (glibc reallocates
/// a large block smaller by unmapping its tail).
fn into_pieces<T>(mut v: Vec<T>, size: usize) -> Vec<Vec<T>> {
    let n = v.len().div_ceil(size);
    let mut pieces = Vec::with_capacity(n);
    for p in (0..n).rev() {
        pieces.push(v.split_off(p * size));
        v.shrink_to_fit();
    }
    pieces.reverse();
    pieces
}

/// `n` zero (default) quadrics in a zeroed allocation, whose pages the
/// system maps only when they are first written.
fn zero_quadrics(n: usize) -> Vec<Quadric> {
    if n == 0 {
        return Vec::new();
    }
    let layout = std::alloc::Layout::array::<Quadric>(n).expect("quadrics fit the address space");
    // SAFETY: `Quadric` is plain f64 fields, for which all-zero bits are
    // 0.0, i.e. `Quadric::default()` (test `zero_quadrics_are_default`);
    // the block is allocated by the global allocator with the layout of
    // `n` quadrics, as `Vec::from_raw_parts` requires for capacity `n`.
    unsafe {
        let p = std::alloc::alloc_zeroed(layout).cast::<Quadric>();
        if p.is_null() {
            std::alloc::handle_alloc_error(layout);
        }
        Vec::from_raw_parts(p, n, n)
    }
}

fn add_rejections(to: &mut Rejections, r: &Rejections) {
    to.locked += r.locked;
    to.link += r.link;
    to.boundary_pinch += r.boundary_pinch;
    to.flip += r.flip;
    to.degenerate += r.degenerate;
    to.duplicate += r.duplicate;
    to.error += r.error;
    to.feature += r.feature;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simplify::features::Features;
    use crate::{shapes, SimplifyOptions};

    /// With wedges (one per vertex) and features on the clusters' rounds keep the feature
    /// lines right: after the write-back and the merge, every live
    /// vertex's feature neighbours are its open-border neighbours in the
    /// current mesh, as the serial walk keeps them, and every corner's
    /// wedge is its vertex's; so too after the coarse stage (a grid of
    /// 72 clusters: 5 coarse ones, which take the run below the first
    /// stage's stop). (Fails when the merge does not replay
    /// `Features::contract`: a held vertex on the open border keeps a
    /// removed neighbour.)
    #[test]
    fn clusters_keep_the_feature_lines_and_wedges() {
        for (n, coarse) in [(60, false), (120, true)] {
            clusters_keep_features(n, coarse);
        }
    }

    fn clusters_keep_features(n: u32, coarse: bool) {
        let m = shapes::grid(n, n, |x, y| 0.1 * (7.0 * x).sin() * (5.0 * y).cos());
        let opts = SimplifyOptions::DEFAULT
            .with_target_ratio(0.015)
            .with_partition(Some(400));
        let mut s = Simplifier::new(&m, &opts).unwrap();
        // features on (no edge of their own): the open border is a feature
        // line, which wedges without a seam alone no longer make
        s.set_feature_edges(&[]);
        let ids: Vec<[u32; 3]> = m.triangles.clone();
        s.set_wedges(ids);
        let size = s.partition_size().expect("a partitioned run");
        s.run_partitioned(size);
        assert!(s.log.records.len() > m.triangles.len() / 4);
        // the coarse stage ran (or not): below the first stage's stop
        let nt = m.triangles.len() as f64;
        assert_eq!((s.live_tris as f64) < 0.75 * KEEP * nt, coarse, "{n}");
        let live: Vec<[u32; 3]> = (0..s.tris.len())
            .filter(|&t| s.tri_alive[t])
            .map(|t| s.tris[t])
            .collect();
        let fresh = Features::new(s.pos.len(), &live);
        let f = s.features.as_ref().unwrap();
        // the clusters did contract along the open border
        let border = Features::new(s.pos.len(), &m.triangles);
        assert!(s.log.records.iter().any(|r| !border.nbrs[r.v0].is_empty()));
        for v in 0..s.pos.len() as u32 {
            if !s.alive[v as usize] {
                continue;
            }
            let mut a = f.nbrs[v].to_vec();
            let mut b = fresh.nbrs[v].to_vec();
            a.sort_unstable();
            b.sort_unstable();
            assert_eq!(a, b, "feature neighbours of {v}");
            assert_eq!(f.kind[v as usize], fresh.kind[v as usize]);
        }
        // (stored per corner, or implied by each vertex's wedge)
        let vw = f.vertex_wedge.as_ref().unwrap();
        match &f.wedges {
            Some(w) => {
                for (t, tri) in s.tris.iter().enumerate() {
                    assert_eq!(w[t], tri.map(|v| vw[v as usize]), "triangle {t}");
                }
            }
            None => assert!(f.corners_implied),
        }
    }

    /// Fails if `Quadric` gains a field whose default is not all-zero bits.
    #[test]
    fn zero_quadrics_are_default() {
        assert!(zero_quadrics(0).is_empty());
        let q = zero_quadrics(1000);
        assert_eq!(q, vec![Quadric::default(); 1000]);
        let bits: Vec<u64> = [Quadric::default()]
            .iter()
            .flat_map(|q| {
                [
                    q.a2, q.ab, q.ac, q.ad, q.b2, q.bc, q.bd, q.c2, q.cd, q.d2, q.weight,
                ]
            })
            .map(f64::to_bits)
            .collect();
        assert!(bits.iter().all(|&b| b == 0));
    }
}
