//! The contraction loop (GH97 §3–4): per-vertex quadrics, candidate pairs
//! ordered by cost, legality checks, contraction, and one `Contraction`
//! record per step for the vertex-split log.
//!
//! [`Simplifier`] is the driver; each phase of its loop is one file:
//!
//! | file | phase |
//! |---|---|
//! | `setup` | classification (border, non-manifold, fans), quadrics, feature edges, τ pairs, the first heap |
//! | `cost` | a pair's target position and cost (quadric + attribute term, cost scale) |
//! | `schedule` | which pair next: the greedy heap, or the pass list (costing, bucketing, cost limit) |
//! | `plan` | the read-only half of a step: placement, `max_error` and `legality` |
//! | `walk` | the batched in-order pass walk (plans in parallel, contractions in order) |
//! | `partition` | clusters simplified in parallel first, their logs merged (large meshes) |
//! | `contract` | one contraction: fans, features, attributes, log, heap |
//! | `legality` | link condition, flips, slivers, duplicates ([`Rejected`]) |
//! | `stats` | what a run did ([`Stats`], [`Rejections`], [`StopReason`]) |
//!
//! The maths is in `quadric` and `attrquadric`, pair discovery in `pairs`,
//! the queues in `heap`, seams and hard edges in `features`, the log's final
//! form in [`crate::progressive`].
//!
//! ```
//! use lodgen_pm::{shapes, Simplifier, SimplifyOptions, StopReason};
//! let mesh = shapes::icosphere(2); // 320 triangles
//! let opts = SimplifyOptions::DEFAULT.with_target_triangles(100);
//! let mut s = Simplifier::new(&mesh, &opts).unwrap();
//! assert_eq!(s.run(), StopReason::Target);
//! let (pm, stats) = s.finish();
//! assert!(pm.base.triangles.len() <= 100);
//! assert_eq!(stats.collapses, pm.len()); // one vertex split per contraction
//! ```

pub(crate) mod attrquadric;
mod contract;
mod cost;
pub(crate) mod features;
pub(crate) mod heap;
pub(crate) mod legality;
mod lift;
mod meter;
mod options;
pub(crate) mod pairs;
mod partition;
mod plan;
pub(crate) mod quadric;
mod reach;
mod schedule;
mod setup;
pub(crate) mod stats;
mod walk;

pub use legality::{Rejected, DEGENERATE_AREA_RATIO_SQ, FLIP_MIN_COS};
pub use meter::{Meter, Stage};
pub use options::{
    Boundary, Placement, Schedule, SimplifyOptions, Tau, TopologyChange, DEFAULT_BOUNDARY_WEIGHT,
    DEFAULT_CLUSTER_TRIANGLES, DEFAULT_PASS_FACTOR, DEFAULT_REACH_FACES_FACTOR,
    DEFAULT_REACH_FACTOR,
};
pub use stats::{PhaseTimes, Rejections, Snapshot, Stats, StopReason};

use crate::mesh::adjacency::Fans;
use crate::mesh::{Mesh, MeshError};
use crate::progressive::{Log, ProgressiveMesh};
use crate::simplify::features::{AttributeCost, Features};
use crate::simplify::heap::{Buckets, QuadHeap};
use crate::simplify::quadric::Quadric;
use glam::DVec3;
use smallvec::SmallVec;
use std::cmp::Ordering;
use std::sync::Arc;
use std::time::Instant;

/// A heap entry: a pair's cost, stamped with both vertices' versions. It is
/// stale once either vertex has changed since. 16 bytes: the heap is the
/// loop's largest, most cache-missed structure (the cost is re-evaluated in
/// `f64` on pop; the `f32` key only orders). Versions are `u16`: a wrapped
/// version can only make an outdated entry look current, and such an entry
/// is still re-costed and checked before it is used.
#[derive(Clone, Copy, Debug)]
struct Entry {
    cost: f32,
    a: u32,
    b: u32,
    va: u16,
    vb: u16,
}

impl PartialEq for Entry {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Entry {
    /// Total order: cost, then vertex ids (the heap pops the smallest).
    /// Deterministic across runs and platforms.
    fn cmp(&self, o: &Self) -> Ordering {
        self.cost
            .total_cmp(&o.cost)
            .then(self.a.cmp(&o.a))
            .then(self.b.cmp(&o.b))
    }
}

/// The GH97 pair-contraction engine. `new`, then `step` until it returns
/// `Err(StopReason)` (or call `run`), then `finish`.
pub struct Simplifier {
    opts: SimplifyOptions,
    target: usize,
    pos: Vec<[f32; 3]>,
    quadric: Vec<Quadric>,
    tris: Vec<[u32; 3]>,
    tri_alive: Vec<bool>,
    /// Vertex → incident triangles; may hold dead triangles (skipped).
    vtris: Fans,
    /// Vertex → non-edge τ partners (empty when there are none).
    partners: Vec<Vec<u32>>,
    /// Vertex → version stamp ([`Schedule::Greedy`] only, else empty).
    version: Vec<u16>,
    alive: Vec<bool>,
    locked: Vec<bool>,
    boundary: Vec<bool>,
    /// Border corners (`setup::BORDER_CORNER_COS`): pinned like feature
    /// vertices.
    corner: Vec<bool>,
    /// [`Schedule::Greedy`]: every pair, lazily invalidated.
    heap: QuadHeap<Entry>,
    /// [`Schedule::Passes`]: the pass in progress.
    pass: Pass,
    live_tris: usize,
    log: Log,
    stats: Stats,
    /// Scratch: per-vertex marks with a generation counter.
    mark: Vec<u32>,
    generation: u32,
    scratch: Vec<u32>,
    fan_scratch: Vec<u32>,
    /// The batched walk's plans (reused from batch to batch).
    plan_scratch: Vec<Option<Result<Plan, Rejected>>>,
    /// Optional per-vertex multiplier of pair costs (curvature-weighted
    /// modes): a pair costs `cost × max(scale[a], scale[b])`.
    cost_scale: Option<Vec<f32>>,
    /// The power of two every key is multiplied by before it is an `f32`
    /// ([`cost_unit`]).
    cost_unit: f64,
    /// Feature edges and wedges, when set (`set_feature_edges`,
    /// `set_wedges`): feature vertices obey the border rule below.
    features: Option<Features>,
    /// Attribute term of the heap key, when set (`set_attributes`).
    attributes: Option<AttributeCost>,
    /// Where `run` reports its progress, when set (`set_meter`).
    meter: Option<Arc<Meter>>,
    /// Vertices whose position the log records lifted
    /// ([`SimplifyOptions::lift`], `lift.rs`).
    lifted: lift::Lifted,
}

/// A contraction that passed [`Simplifier::check`]: `v0` goes into `v1`,
/// which moves to `p`; `removed` are the triangles on both.
#[derive(Debug)]
struct Plan {
    v0: u32,
    v1: u32,
    p: DVec3,
    error: f32,
    removed: SmallVec<[u32; 2]>,
    /// Deferred to a later pass: it moves the surface too far
    /// ([`SimplifyOptions::reach`]).
    deferred: bool,
    /// [`Simplifier::hole_cost`] of the contraction (0: it closes no hole).
    hole: f64,
    /// The rule the contraction breaks, which the relaxation stage lets
    /// pass ([`SimplifyOptions::topology_change`]; `None`: none).
    broke: Option<Rejected>,
}

/// A candidate of a pass: 12 bytes (the pass list and its sort buffer are
/// the largest allocations of the first pass).
#[derive(Clone, Copy, Debug, Default)]
struct PassEntry {
    cost: f32,
    a: u32,
    b: u32,
}

/// The state of the pass in progress ([`Schedule::Passes`]).
#[derive(Debug, Default)]
struct Pass {
    /// Pass number (starts at 1; 0 = none yet).
    number: u32,
    /// Whether `queue` is a started pass (false after a rebuild).
    open: bool,
    /// The pass's candidates, bucketed by cost and sorted as far as
    /// `buckets` says; `cursor` is the next one.
    queue: Vec<PassEntry>,
    buckets: Buckets,
    cursor: usize,
    /// Vertex → the last pass that moved or removed it.
    touched: Vec<u32>,
    /// Triangles this pass should remove (to the target) and has removed.
    goal: usize,
    removed: usize,
    collapses: usize,
    error_rejections: usize,
    /// The pass stops at candidates costlier than this (once it has made
    /// a sixth of its goal, as meshoptimizer does, so that a pass whose
    /// cheap pairs were all blocked still makes progress).
    cost_limit: f32,
    /// The pass skips candidates whose cost per unit of quadric weight (a
    /// mean squared distance) exceeds this (`Simplifier::deferred`);
    /// infinite for a pass without the bound.
    spread_limit: f64,
    /// Candidates skipped by `spread_limit` in this pass.
    deferred: usize,
    /// Passes in a row that contracted nothing (each loosens the next
    /// pass's spread bound by a larger step, `schedule::STUCK_GROWTH`).
    stuck: u32,
    /// The rules this pass relaxes ([`SimplifyOptions::topology_change`]:
    /// raised a stage each time the run is stuck; back to none after a
    /// pass that made a contraction).
    relax: legality::Relax,
    /// Candidates of this pass the topology rules refused (or that broke
    /// one, relaxed): the next pass relaxes them when they outnumber its
    /// contractions by `RELAX_SHARE` ([`SimplifyOptions::topology_change`]).
    refused: usize,
}

#[inline]
fn dv(p: [f32; 3]) -> DVec3 {
    DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]))
}

#[inline]
fn fv(p: DVec3) -> [f32; 3] {
    [p.x as f32, p.y as f32, p.z as f32]
}

impl Simplifier {
    /// Set up quadrics, classification, pairs and the heap. The mesh must be
    /// clean (see [`crate::mesh::prepare`]): no repeated corner in a triangle.
    pub fn new(mesh: &Mesh, opts: &SimplifyOptions) -> Result<Simplifier, MeshError> {
        Self::from_mesh(mesh.clone(), opts)
    }

    /// [`Simplifier::new`], taking the mesh over instead of copying it.
    pub fn from_mesh(mesh: Mesh, opts: &SimplifyOptions) -> Result<Simplifier, MeshError> {
        mesh.validate()?;
        if mesh.triangles.is_empty() {
            return Err(MeshError::Empty(""));
        }
        let t0 = Instant::now();
        let (mut s, edges, tau) = Simplifier::classified(mesh, opts);
        s.stats.time.setup = t0.elapsed();

        let t1 = Instant::now();
        let near = s.find_partners(&edges, tau);
        s.stats.time.pairs = t1.elapsed();

        let t2 = Instant::now();
        if opts.schedule == Schedule::Greedy {
            s.fill_heap(edges, &near);
        }
        s.stats.time.heap = t2.elapsed();
        Ok(s)
    }

    /// Multiply every pair's heap key by `max(scale[a], scale[b])` (one
    /// value per vertex, ≥ 0), and rebuild the heap. Errors recorded in the
    /// log stay unscaled quadric errors. Panics if the length is not the
    /// vertex count (a programming error, not input).
    pub fn set_cost_scale(&mut self, scale: Vec<f32>) {
        assert_eq!(scale.len(), self.pos.len(), "one scale per vertex");
        self.cost_scale = Some(scale);
        self.rebuild_heap();
    }

    /// Treat `edges` (pairs of vertices in the mesh's numbering; edges the
    /// mesh does not have are ignored) as feature edges: hard edges,
    /// material borders, seams. Feature vertices move like border vertices
    /// and only along their feature lines (see `features`); each feature
    /// edge adds a constraint plane per adjacent face, weighted like a
    /// border's. Turning features on also makes open borders feature
    /// edges. Call before the first `step`.
    pub fn set_feature_edges(&mut self, edges: &[(u32, u32)]) {
        self.add_features(edges);
        self.rebuild_heap();
    }

    /// Track a wedge (the caller's attribute id, e.g. its unwelded vertex
    /// index) at every triangle corner, `wedges[t][k]` for corner `k` of
    /// triangle `t` of the mesh given to `new`. Edges across which the
    /// wedges differ become feature edges (seams), and then open borders
    /// too; without a seam borders stay plain borders, as without wedges.
    /// The log records every corner's wedge (`ProgressiveMesh::wedges`).
    /// Call before the first `step`. Panics if the length is not the triangle count (a
    /// programming error, not input).
    pub fn set_wedges(&mut self, wedges: Vec<[u32; 3]>) {
        assert_eq!(
            wedges.len(),
            self.tris.len(),
            "one wedge triple per triangle"
        );
        let vertex_wedge = features::vertex_wedges(&self.tris, &wedges);
        match vertex_wedge {
            // no seam (positions only): wedges are tracked, but no feature
            // line is made, so open borders stay what they are without
            // wedges (constraint planes, optimal placement, corners
            // pinned), not feature lines their vertices may only slide
            // along (beetle at 41 triangles: Hausdorff 14.6 % instead of
            // `simplify`'s 6.1 %)
            Some(_) => {
                if self.features.is_none() {
                    self.features = Some(Features::with_borders(self.pos.len(), &[]));
                }
            }
            None => {
                let seams = self.seam_edges(&wedges);
                self.add_features(&seams);
            }
        }
        // one wedge per vertex and no attribute term (which reads corner
        // wedges): the corners' wedges follow from the vertices'
        let implied = vertex_wedge.is_some() && self.attributes.is_none();
        if let Some(f) = &mut self.features {
            f.wedges = (!implied).then_some(wedges);
            f.corners_implied = implied;
            f.edits_implied = vertex_wedge.is_some();
            f.vertex_wedge = vertex_wedge;
        }
        self.rebuild_heap();
    }

    /// Add an attribute term to every pair's heap key: Hoppe 1999
    /// attribute quadrics (`attrquadric`). `values` holds `dims` weighted
    /// components per wedge id when wedges are tracked (call `set_wedges`
    /// first), else per vertex. Errors recorded in the log stay geometric.
    /// Call before the first `step`. Panics if a wedge (vertex) has no
    /// values (a programming error, not input).
    pub fn set_attributes(&mut self, values: Vec<f32>, dims: usize) {
        if let Some(f) = &mut self.features {
            f.store_wedges(&self.tris);
        }
        let wedges = self.features.as_ref().and_then(|f| f.wedges.as_deref());
        let diagonal = Mesh {
            positions: self.pos.clone(),
            triangles: Vec::new(),
        }
        .diagonal();
        let cost = AttributeCost::new(
            &values,
            dims,
            &self.pos,
            &self.tris,
            &self.tri_alive,
            wedges,
            diagonal * diagonal,
        );
        self.attributes = Some(cost.expect("dims values per wedge"));
        self.rebuild_heap();
    }

    /// Report progress to `meter` (stage, share of the target reached)
    /// from `run` on, for an observer on another thread.
    pub fn set_meter(&mut self, meter: Arc<Meter>) {
        self.meter = Some(meter);
    }

    /// Live triangles now.
    pub fn triangle_count(&self) -> usize {
        self.live_tris
    }

    /// The triangle count `run` stops at.
    pub fn target(&self) -> usize {
        self.target
    }

    /// What the loop has done so far.
    pub fn stats(&self) -> &Stats {
        &self.stats
    }

    /// Perform the cheapest legal contraction. `Err` says why none was done.
    pub fn step(&mut self) -> Result<(), StopReason> {
        let t0 = Instant::now();
        let r = self.step_inner();
        self.stats.time.collapse += t0.elapsed();
        r
    }

    /// Run until a stop; returns the reason.
    pub fn run(&mut self) -> StopReason {
        // timed once, not per step (two clock reads per contraction were
        // 2 % of a bunny run)
        let t0 = Instant::now();
        let meter = self.meter.clone();
        if let Some(m) = &meter {
            m.begin(self.live_tris, self.target);
        }
        if let Some(size) = self.partition_size() {
            self.run_partitioned(size);
            if let Some(m) = &meter {
                m.set_live(self.live_tris);
            }
        }
        if meter.as_ref().is_some_and(|m| m.is_cancelled()) {
            self.stats.time.collapse += t0.elapsed();
            return StopReason::Cancelled;
        }
        // (batched on one thread too: the walk then plans a batch ahead
        // with its prefetches, 10 % less CPU time than step by step)
        let batched = matches!(self.opts.schedule, Schedule::Passes { .. });
        let mut walk = || loop {
            let step = match self.opts.schedule {
                Schedule::Passes { factor } if batched => self.walk_batch(factor),
                _ => self.step_inner(),
            };
            if let Some(m) = &meter {
                m.set_live(self.live_tris);
                if step.is_ok() && m.is_cancelled() {
                    break StopReason::Cancelled;
                }
            }
            if let Err(r) = step {
                break r;
            }
        };
        // batched, the walk runs on a pool thread: its batches then fork
        // to a sibling that is often still awake, instead of waking two
        let r = if batched {
            rayon::scope(|_| walk())
        } else {
            walk()
        };
        self.stats.time.collapse += t0.elapsed();
        r
    }

    /// The current mesh in the input's numbering.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            // (as the log records them: lifted where `lift.rs` lifts)
            positions: (0..self.pos.len() as u32)
                .map(|v| self.logged_position(v))
                .collect(),
            triangles: (0..self.tris.len())
                .filter(|&t| self.tri_alive[t])
                .map(|t| (t as u32, self.tris[t]))
                .collect(),
        }
    }

    /// Turn the log into the progressive mesh.
    pub fn finish(mut self) -> (ProgressiveMesh, Stats) {
        let t0 = Instant::now();
        if let Some(m) = &self.meter {
            m.set_stage(Stage::Finishing);
        }
        // the live vertices' positions as the log records them (before
        // their quadrics are freed)
        self.commit_lifts();
        // free what the log's renumbering does not read before it
        // allocates the progressive mesh (peak memory)
        self.pass = Pass::default();
        self.heap = QuadHeap::from_vec(Vec::new());
        self.vtris = Fans::default();
        self.quadric = Vec::new();
        self.partners = Vec::new();
        self.mark = Vec::new();
        self.version = Vec::new();
        self.attributes = None;
        self.cost_scale = None;
        // implied corners stay implied for the log's renumbering when the
        // edits are (from_log reads each corner's wedge from its vertex)
        if let Some(f) = self.features.as_mut().filter(|f| !f.edits_implied) {
            f.store_wedges(&self.tris);
        }
        let pm = ProgressiveMesh::from_log(
            &self.pos,
            &self.tris,
            &self.alive,
            &self.tri_alive,
            &mut self.log,
            self.features.as_ref().and_then(|f| f.wedges.as_deref()),
            self.features
                .as_ref()
                .filter(|f| f.edits_implied)
                .and_then(|f| f.vertex_wedge.as_deref()),
        );
        self.stats.output_triangles = self.live_tris;
        self.stats.output_vertices = pm.base.positions.len();
        self.stats.time.log = t0.elapsed();
        if let Some(m) = &self.meter {
            m.set_stage(Stage::Idle);
        }
        (pm, self.stats)
    }
}

/// The unit of a mesh's keys: `2^(−4k)`, `2^k` the power of two nearest
/// its bounding-box diagonal `d`. Keys are area × squared distance
/// (length⁴) in `f32`: taken as they came, at `d` ≈ 10⁻⁹ they underflowed to
/// zero and the contractions came in another order, at 10¹⁰ they
/// overflowed. In this unit they are those of the mesh scaled to a
/// diagonal near 1, and a power of two changes no comparison: a mesh
/// scaled by a power of two simplifies to the same triangles, its positions
/// scaled by exactly that power (the spread bound, a squared distance, is
/// taken in mesh units: `Pass::defers`).
pub(crate) fn cost_unit(positions: &[[f32; 3]]) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in positions {
        for k in 0..3 {
            lo[k] = lo[k].min(f64::from(p[k]));
            hi[k] = hi[k].max(f64::from(p[k]));
        }
    }
    let d = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    if !(d > 0.0 && d.is_finite()) {
        return 1.0;
    }
    let k = d.log2().round() as i32;
    2f64.powi(-4 * k)
}
