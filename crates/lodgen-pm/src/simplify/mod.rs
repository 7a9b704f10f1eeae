//! The contraction loop (GH97 §3–4): per-vertex quadrics, candidate pairs in
//! a heap keyed on cost, legality checks, contraction, and one
//! `Contraction` record per step for the vertex-split log.
//!
//! Owns [`Simplifier`], [`Stats`], [`Rejections`], [`StopReason`]. Pair
//! discovery is in `pairs`, the quadric maths in `quadric`, the log's final
//! form in `vsplit`.

pub mod attrquadric;
pub mod features;
pub mod heap;
pub mod options;
pub mod pairs;
pub mod quadric;

use crate::mesh::adjacency::{FanLookup, Fans};
use crate::mesh::{Mesh, MeshError};
use crate::progressive::{Contraction, Corner, Log, ProgressiveMesh, Removed};
use crate::simplify::features::{AttributeCost, Features};
use crate::simplify::heap::{f32_order_key, Buckets, QuadHeap};
use crate::simplify::options::{Boundary, Placement, Schedule, SimplifyOptions};
use crate::simplify::quadric::{CostLanes, Quadric, LANES};
use crate::util::{prefetch, with_marks};
use glam::DVec3;
use rayon::prelude::*;
use smallvec::SmallVec;
use std::cmp::Ordering;
use std::time::{Duration, Instant};

/// A moved triangle whose new normal is turned more than ≈75.5° from its old
/// one (cos < 0.25) counts as flipped. A pure 90° test (cos < 0) lets chains
/// of collapses that each turn a face by 80–89° fold the surface over.
pub const FLIP_MIN_COS: f64 = 0.25;

/// A moved triangle whose area shrinks below this fraction of its old area
/// (squared-normal ratio 1e-12 ≈ area ratio 1e-6) becomes a sliver that
/// breaks normals and later flip tests.
pub const DEGENERATE_AREA_RATIO_SQ: f64 = 1e-12;

/// Why a candidate contraction was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rejected {
    /// Both vertices are locked (boundary lock, non-manifold).
    Locked,
    /// The link condition fails: the one-rings share a vertex that is not
    /// opposite the edge (the result would be non-manifold).
    Link,
    /// Two border vertices joined by an interior edge (would pinch).
    BoundaryPinch,
    /// A moved triangle's normal turns by more than the flip threshold.
    Flip,
    /// A moved triangle would lose (nearly) all its area.
    Degenerate,
    /// A moved triangle would land on an existing one: a tetrahedron or a
    /// small closed component flattening into a double-sided sheet.
    Duplicate,
    /// The contraction's error exceeds `max_error`.
    Error,
    /// A feature vertex (seam, material border, hard edge) would leave its
    /// feature line, or a seam corner would be removed (see `features`).
    Feature,
}

/// Rejections counted by reason.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Rejections {
    pub locked: usize,
    pub link: usize,
    pub boundary_pinch: usize,
    pub flip: usize,
    pub degenerate: usize,
    pub duplicate: usize,
    pub error: usize,
    pub feature: usize,
}

impl Rejections {
    fn count(&mut self, r: Rejected) {
        *match r {
            Rejected::Locked => &mut self.locked,
            Rejected::Link => &mut self.link,
            Rejected::BoundaryPinch => &mut self.boundary_pinch,
            Rejected::Flip => &mut self.flip,
            Rejected::Degenerate => &mut self.degenerate,
            Rejected::Duplicate => &mut self.duplicate,
            Rejected::Error => &mut self.error,
            Rejected::Feature => &mut self.feature,
        } += 1;
    }

    pub fn total(&self) -> usize {
        self.locked
            + self.link
            + self.boundary_pinch
            + self.flip
            + self.degenerate
            + self.duplicate
            + self.error
            + self.feature
    }
}

/// Wall time per phase.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseTimes {
    /// Adjacency, boundary and non-manifold classification, quadrics.
    pub setup: Duration,
    /// Edge and τ-pair discovery.
    pub pairs: Duration,
    /// Costing and ordering candidates: the initial heap
    /// ([`Schedule::Greedy`]), or every pass's sorted list
    /// ([`Schedule::Passes`]).
    pub heap: Duration,
    /// The contraction loop (without `heap`).
    pub collapse: Duration,
    /// Renumbering the log into the progressive mesh.
    pub log: Duration,
}

/// What a simplification did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    pub input_vertices: usize,
    pub input_triangles: usize,
    pub output_vertices: usize,
    pub output_triangles: usize,
    pub collapses: usize,
    /// Passes made ([`Schedule::Passes`]; 0 when greedy).
    pub passes: usize,
    /// Non-edge pairs within τ at the start.
    pub near_pairs: usize,
    pub boundary_vertices: usize,
    /// Vertices that never move (non-manifold, or boundary with
    /// `Boundary::Locked`).
    pub locked_vertices: usize,
    pub rejected: Rejections,
    pub time: PhaseTimes,
}

/// Why the loop stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// The triangle target was reached.
    Target,
    /// Every remaining candidate's error exceeds `max_error`.
    MaxError,
    /// No legal candidate is left (all locked or every contraction
    /// illegal) before the target: the stats say why.
    Exhausted,
}

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

/// A read-only view of the simplifier's current mesh, in the welded input's
/// numbering (for tests and debugging).
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    /// All vertices' current positions (removed ones keep their last).
    pub positions: Vec<[f32; 3]>,
    /// `(input triangle id, corners)` of every live triangle, by id.
    pub triangles: Vec<(u32, [u32; 3])>,
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
    /// Feature edges and wedges, when set (`set_feature_edges`,
    /// `set_wedges`): feature vertices obey the border rule below.
    features: Option<Features>,
    /// Attribute term of the heap key, when set (`set_attributes`).
    attributes: Option<AttributeCost>,
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
}

/// A pass entry's bucket: the top 11 bits of its cost's order key.
#[inline]
fn pass_bucket(cost: f32) -> usize {
    (f32_order_key(cost) >> 21) as usize
}

/// The order of a pass: by cost (`total_cmp`), as a sort key. Sorted
/// stably from entries generated in (a, b) order, this is the total order
/// (cost, a, b).
#[inline]
fn pass_order(x: &PassEntry) -> u32 {
    f32_order_key(x.cost)
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
        let nv = mesh.positions.len();
        let nt = mesh.triangles.len();
        let mut stats = Stats {
            input_vertices: nv,
            input_triangles: nt,
            ..Stats::default()
        };
        let vtris = Fans::new(nv, &mesh.triangles, |_| true);

        // Classify every vertex from its own fan (in parallel): border
        // and non-manifold edges, fans, and its quadric.
        let boundary_weight = match opts.boundary {
            Boundary::Weighted(w) => w,
            Boundary::Locked => 0.0,
        };
        // Each face's plane once, not once per corner (the same sums, a
        // third of the square roots and divisions).
        let planes: Vec<Plane> = mesh
            .triangles
            .par_iter()
            .map(|t| face_plane(&mesh.positions, t, opts.area_weighted))
            .collect();
        let (quadric, (boundary, locked)): (Vec<Quadric>, (Vec<bool>, Vec<bool>)) = (0..nv as u32)
            .into_par_iter()
            .map(|v| {
                let i = classify_vertex(&mesh, &planes, vtris.fan(v), v, opts, boundary_weight);
                (i.quadric, (i.boundary, i.locked))
            })
            .unzip();
        drop(planes);
        let tau = opts.tau_for(mesh.diagonal());
        // Sorted edges (only the greedy heap and τ pairs need the list).
        let mut edges: Vec<(u32, u32)> = if opts.schedule == Schedule::Greedy || tau > 0.0 {
            (0..nv as u32)
                .into_par_iter()
                .flat_map_iter(|v| {
                    let mut nb: SmallVec<[u32; 32]> = SmallVec::new();
                    for &t in vtris.fan(v) {
                        nb.extend(
                            mesh.triangles[t as usize]
                                .iter()
                                .copied()
                                .filter(|&x| x > v),
                        );
                    }
                    nb.sort_unstable();
                    nb.dedup();
                    nb.into_iter().map(move |x| (v, x))
                })
                .collect()
        } else {
            Vec::new()
        };

        let mut s = Simplifier {
            opts: *opts,
            target: opts.target_for(nt),
            pos: mesh.positions,
            quadric,
            tris: mesh.triangles,
            tri_alive: vec![true; nt],
            vtris,
            partners: Vec::new(),
            version: if opts.schedule == Schedule::Greedy {
                vec![0; nv]
            } else {
                Vec::new()
            },
            alive: vec![true; nv],
            locked,
            boundary,
            heap: QuadHeap::from_vec(Vec::new()),
            pass: Pass {
                touched: vec![0; nv],
                ..Pass::default()
            },
            live_tris: nt,
            log: Log::with_capacity(nt / 2),
            stats,
            mark: vec![0; nv],
            generation: 0,
            scratch: Vec::new(),
            fan_scratch: Vec::new(),
            plan_scratch: Vec::new(),
            cost_scale: None,
            features: None,
            attributes: None,
        };
        if opts.boundary == Boundary::Locked {
            for v in 0..nv {
                s.locked[v] |= s.boundary[v];
            }
        }
        stats = s.stats;
        stats.boundary_vertices = s.boundary.iter().filter(|&&b| b).count();
        stats.locked_vertices = s.locked.iter().filter(|&&b| b).count();
        stats.time.setup = t0.elapsed();

        let t1 = Instant::now();
        let near = pairs::near_pairs(&s.pos, &edges, tau);
        stats.near_pairs = near.len();
        if !near.is_empty() {
            s.partners = vec![Vec::new(); nv];
        }
        for &(a, b) in &near {
            s.partners[a as usize].push(b);
            s.partners[b as usize].push(a);
        }
        stats.time.pairs = t1.elapsed();

        let t2 = Instant::now();
        if opts.schedule == Schedule::Greedy {
            edges.extend_from_slice(&near);
            let entries: Vec<Entry> = edges
                .par_iter()
                .filter(|&&(a, b)| !(s.locked[a as usize] && s.locked[b as usize]))
                .map(|&(a, b)| s.entry(a, b))
                .collect();
            s.heap = QuadHeap::from_vec(entries);
        }
        stats.time.heap = t2.elapsed();
        s.stats = stats;
        Ok(s)
    }

    /// The contraction target and cost of the pair `(a, b)`.
    #[inline]
    fn target_of(&self, a: u32, b: u32) -> (DVec3, f64) {
        self.target_with(&(self.quadric[a as usize] + self.quadric[b as usize]), a, b)
    }

    /// [`Simplifier::target_of`] with the pair's summed quadric `q` given.
    #[inline]
    fn target_with(&self, q: &Quadric, a: u32, b: u32) -> (DVec3, f64) {
        let (pa, pb) = (dv(self.pos[a as usize]), dv(self.pos[b as usize]));
        match (self.locked[a as usize], self.locked[b as usize]) {
            (true, _) => (pa, q.eval(pa)),
            (false, true) => (pb, q.eval(pb)),
            // Border vertices never move to a new position: an interior
            // vertex is pulled onto a border one, and two border vertices
            // merge into the cheaper of the two (half-edge). With optimal
            // placement a corner slides a little along one border line, and
            // the next collapse along the other line cuts it off: borders
            // creep. The constraint planes still price which one goes.
            // Feature vertices follow the same rule (`pinned`), and a seam
            // corner is never the one removed (`fixed`).
            (false, false) if self.pinned(a) && !self.pinned(b) || self.fixed(a) => {
                (pa, q.eval(pa))
            }
            (false, false) if self.pinned(b) && !self.pinned(a) || self.fixed(b) => {
                (pb, q.eval(pb))
            }
            (false, false) => match self.opts.placement {
                Placement::Optimal if !self.pinned(a) => q.placement(pa, pb),
                _ => {
                    let (ca, cb) = (q.eval(pa), q.eval(pb));
                    if cb < ca {
                        (pb, cb)
                    } else {
                        (pa, ca)
                    }
                }
            },
        }
    }

    /// `v`'s τ partners.
    #[inline]
    fn partners(&self, v: u32) -> &[u32] {
        self.partners.get(v as usize).map_or(&[], |p| p)
    }

    /// On a border or a feature line: never moves to a new position.
    #[inline]
    fn pinned(&self, v: u32) -> bool {
        self.boundary[v as usize] || self.features.as_ref().is_some_and(|f| f.pinned(v))
    }

    /// A seam corner or end: never removed.
    #[inline]
    fn fixed(&self, v: u32) -> bool {
        self.features.as_ref().is_some_and(|f| f.fixed(v))
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
    /// wedges differ become feature edges (seams); the log records every
    /// corner's wedge (`ProgressiveMesh::wedges`). Call before the first
    /// `step`. Panics if the length is not the triangle count (a
    /// programming error, not input).
    pub fn set_wedges(&mut self, wedges: Vec<[u32; 3]>) {
        assert_eq!(
            wedges.len(),
            self.tris.len(),
            "one wedge triple per triangle"
        );
        let seams = Features::seams(&self.tris, &wedges);
        self.add_features(&seams);
        if let Some(f) = &mut self.features {
            f.wedges = Some(wedges);
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

    fn add_features(&mut self, edges: &[(u32, u32)]) {
        let nv = self.pos.len();
        let mut f = self
            .features
            .take()
            .unwrap_or_else(|| Features::new(nv, &self.tris));
        let weight = match self.opts.boundary {
            Boundary::Weighted(w) => w,
            Boundary::Locked => crate::simplify::options::DEFAULT_BOUNDARY_WEIGHT,
        };
        for &(a, b) in edges {
            if a as usize >= nv || b as usize >= nv {
                continue;
            }
            let faces: SmallVec<[u32; 2]> = self
                .vtris
                .fan(a)
                .iter()
                .copied()
                .filter(|&t| self.tri_alive[t as usize] && self.tris[t as usize].contains(&b))
                .collect();
            if faces.is_empty() || !f.add(a, b) {
                continue;
            }
            let (pa, pb) = (dv(self.pos[a as usize]), dv(self.pos[b as usize]));
            let e = pb - pa;
            let w = weight
                * if self.opts.area_weighted {
                    e.length_squared()
                } else {
                    1.0
                };
            for t in faces {
                let c = e.cross(face_normal(&self.pos, &self.tris[t as usize]));
                let len = c.length();
                if len > 0.0 && w > 0.0 {
                    let c = c / len;
                    let q = Quadric::from_plane(c, -c.dot(pa), w);
                    let q = Quadric { weight: 0.0, ..q };
                    self.quadric[a as usize] += q;
                    self.quadric[b as usize] += q;
                }
            }
        }
        self.features = Some(f);
    }

    /// Re-cost every queued pair (after the costs' inputs changed).
    fn rebuild_heap(&mut self) {
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

    fn entry(&self, a: u32, b: u32) -> Entry {
        let (a, b) = (a.min(b), a.max(b));
        Entry {
            cost: self.key(a, b),
            a,
            b,
            va: self.version.get(a as usize).copied().unwrap_or(0),
            vb: self.version.get(b as usize).copied().unwrap_or(0),
        }
    }

    /// The order key of the pair `(a, b)`, `a < b`: its quadric cost, plus
    /// the attribute term, times the cost scale.
    #[inline]
    fn key(&self, a: u32, b: u32) -> f32 {
        let (p, mut cost) = self.target_of(a, b);
        if let Some(at) = &self.attributes {
            // the farther endpoint is the one removed (as in `step`)
            let (pa, pb) = (dv(self.pos[a as usize]), dv(self.pos[b as usize]));
            let (v0, v1) = if (p - pa).length_squared() <= (p - pb).length_squared() {
                (b, a)
            } else {
                (a, b)
            };
            let w = self.features.as_ref().and_then(|f| f.wedges.as_deref());
            let fan0 = self.vtris.fan(v0);
            cost += at.cost(v0, v1, p, &self.tris, fan0, &self.tri_alive, w);
        }
        self.scaled(cost, a, b)
    }

    /// The heap key from the pair's cost: times the cost scale, as `f32`.
    #[inline]
    fn scaled(&self, mut cost: f64, a: u32, b: u32) -> f32 {
        if let Some(s) = &self.cost_scale {
            cost *= f64::from(s[a as usize].max(s[b as usize]));
        }
        cost as f32
    }

    /// Prefetch what planning the pair `(a, b)` reads first about its
    /// vertices: their fan spans, quadrics and positions.
    #[inline]
    fn prefetch_vertices(&self, a: u32, b: u32) {
        for v in [a, b] {
            self.vtris.prefetch_span(v);
            // 88 bytes, 8-aligned: up to three cache lines, each holding
            // one of these fields
            let q = &self.quadric[v as usize];
            prefetch(&q.a2);
            prefetch(&q.bc);
            prefetch(&q.weight);
            prefetch(&self.pos[v as usize]);
        }
    }

    /// Prefetch the triangles of `v`'s fan (its list must be at hand).
    #[inline]
    fn prefetch_triangles(&self, v: u32) {
        for &t in self.vtris.fan(v) {
            prefetch(&self.tris[t as usize]);
        }
    }

    /// Neither locked, pinned nor fixed: a pair of two such vertices takes
    /// [`Quadric::placement`] in `target_with`.
    #[inline]
    fn free(&self, v: u32) -> bool {
        !self.locked[v as usize] && !self.pinned(v) && !self.fixed(v)
    }

    /// Live triangles now.
    pub fn triangle_count(&self) -> usize {
        self.live_tris
    }

    /// The triangle count `run` stops at.
    pub fn target(&self) -> usize {
        self.target
    }

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

    fn step_inner(&mut self) -> Result<(), StopReason> {
        if self.live_tris <= self.target {
            return Err(StopReason::Target);
        }
        match self.opts.schedule {
            Schedule::Greedy => self.step_greedy(),
            Schedule::Passes { factor } => self.step_pass(factor),
        }
    }

    fn step_greedy(&mut self) -> Result<(), StopReason> {
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
        Err(if self.stats.rejected.error > 0 {
            StopReason::MaxError
        } else {
            StopReason::Exhausted
        })
    }

    fn step_pass(&mut self, factor: f32) -> Result<(), StopReason> {
        loop {
            let pass = &mut self.pass;
            if pass.cursor >= pass.queue.len() {
                if pass.open && pass.collapses == 0 {
                    // nothing changed: the next pass would be the same
                    return Err(if pass.error_rejections > 0 {
                        StopReason::MaxError
                    } else {
                        StopReason::Exhausted
                    });
                }
                self.start_pass(factor);
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
            let before = self.live_tris;
            match self.try_contract(e.a, e.b) {
                Ok(()) => {
                    let pass = &mut self.pass;
                    pass.touched[e.a as usize] = n;
                    pass.touched[e.b as usize] = n;
                    pass.removed += before - self.live_tris;
                    pass.collapses += 1;
                    return Ok(());
                }
                Err(r) => {
                    if r == Rejected::Error {
                        self.pass.error_rejections += 1;
                    }
                    self.stats.rejected.count(r);
                }
            }
        }
    }

    /// Cost every live pair (edges and τ partners, both vertices not
    /// locked), sort, and set the pass's goal and cost limit. Pairs are
    /// sorted by the total order (cost, a, b): the order depends on nothing
    /// but the mesh (not on the thread count).
    fn start_pass(&mut self, factor: f32) {
        let t0 = Instant::now();
        // The costing reads every live vertex's fan and skips its dead
        // triangles; once the rewritten lists reach half the CSR it also
        // writes the live ones out, and they become the new CSR (compacted
        // where they are read anyway, not by a pass over all triangles).
        // (The fans `new` builds are compact: the first pass never does.)
        let compact = self.vtris.half_dead();
        const CHUNK: usize = 2048;
        let nv = self.pos.len();
        let this = &*self;
        // pairs that take `placement` (most) are costed a lane batch at a
        // time, the others one by one by `key`
        let lanes_apply = self.attributes.is_none() && self.opts.placement == Placement::Optimal;
        let chunks: Vec<(Vec<PassEntry>, Vec<u32>, Vec<u32>)> = (0..nv.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut out = Vec::with_capacity(3 * CHUNK);
                // compacted fans: the lists, and each vertex's length
                let (mut fans, mut lens) = (Vec::new(), Vec::new());
                let mut lanes = CostLanes::default();
                // where each lane's entry is in `out`
                let mut slots = [0usize; LANES];
                let flush = |lanes: &mut CostLanes, out: &mut Vec<PassEntry>, slots: &[usize]| {
                    let n = lanes.len();
                    let costs = lanes.costs();
                    for (&i, &cost) in slots[..n].iter().zip(&costs[..n]) {
                        out[i].cost = this.scaled(cost, out[i].a, out[i].b);
                    }
                };
                let mut nb: Vec<u32> = Vec::with_capacity(32);
                for v in (c * CHUNK) as u32..((c + 1) * CHUNK).min(nv) as u32 {
                    let vi = v as usize;
                    if !this.alive[vi] {
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
                    for &t in this.vtris.fan(v) {
                        if this.tri_alive[t as usize] {
                            let [x, y, z] = this.tris[t as usize];
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
                    for &x in this.partners(v) {
                        if this.alive[x as usize] {
                            add(x);
                        }
                    }
                    // in (a, b) order: the buckets keep it, and a stable
                    // sort by cost then gives the total order
                    nb.sort_unstable();
                    for &x in &nb {
                        if this.locked[vi] && this.locked[x as usize] {
                            continue;
                        }
                        if lanes_apply && this.free(v) && this.free(x) {
                            slots[lanes.len()] = out.len();
                            out.push(PassEntry {
                                cost: 0.0,
                                a: v,
                                b: x,
                            });
                            let q = this.quadric[vi] + this.quadric[x as usize];
                            lanes.push(&q, dv(this.pos[vi]), dv(this.pos[x as usize]));
                            if lanes.is_full() {
                                flush(&mut lanes, &mut out, &slots);
                            }
                        } else {
                            out.push(PassEntry {
                                cost: this.key(v, x),
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
            })
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
        let limit = if goal / 2 < queue.len() {
            buckets.sort_through(&mut queue, goal / 2, pass_order);
            queue[goal / 2].cost * factor
        } else {
            f32::INFINITY
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
        self.stats.passes += 1;
        self.stats.time.heap += t0.elapsed();
    }

    /// Re-cost the pair `(a, b)` (exact: its vertices are current) and
    /// contract it if it is within `max_error` and legal.
    fn try_contract(&mut self, a: u32, b: u32) -> Result<(), Rejected> {
        let plan = self.plan(a, b)?;
        self.contract(plan);
        Ok(())
    }

    /// The read-only half of [`Simplifier::try_contract`]: where the pair
    /// `(a, b)` would go, which end is removed, and whether that is legal.
    /// It reads nothing outside the closed one-rings of `a` and `b` (what
    /// the batched walk's invalidation relies on, see `walk_batch`).
    fn plan(&self, a: u32, b: u32) -> Result<Plan, Rejected> {
        let (ai, bi) = (a as usize, b as usize);
        let q = self.quadric[ai] + self.quadric[bi];
        let (p, cost) = self.target_with(&q, a, b);
        let error = if q.weight > 0.0 {
            (cost / q.weight).sqrt()
        } else {
            cost.sqrt()
        };
        if self.opts.max_error.is_some_and(|m| error > m) {
            return Err(Rejected::Error);
        }
        // v1 (kept) is the endpoint the new vertex is closer to.
        let (v0, v1) = if self.locked[ai]
            || (!self.locked[bi]
                && (p - dv(self.pos[ai])).length_squared()
                    <= (p - dv(self.pos[bi])).length_squared())
        {
            (b, a)
        } else {
            (a, b)
        };
        let removed = self.check(v0, v1, p)?;
        Ok(Plan {
            v0,
            v1,
            p,
            error: error as f32,
            removed,
        })
    }

    /// Run until a stop; returns the reason.
    pub fn run(&mut self) -> StopReason {
        // timed once, not per step (two clock reads per contraction were
        // 2 % of a bunny run)
        let t0 = Instant::now();
        let batched = matches!(self.opts.schedule, Schedule::Passes { .. })
            && rayon::current_num_threads() > 1;
        let mut walk = || loop {
            let step = match self.opts.schedule {
                Schedule::Passes { factor } if batched => self.walk_batch(factor),
                _ => self.step_inner(),
            };
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

    /// The pass walk of [`Simplifier::step_pass`], a batch at a time, with
    /// the same result contraction for contraction: the next candidates
    /// (one per 64 live triangles, at most `MAX_BATCH`) are planned ([`Simplifier::plan`]: costing, placement and
    /// legality, most of a step's work) in parallel on the mesh as it is,
    /// then walked in order exactly as `step_pass` would, contracting from
    /// the plans. A contraction changes nothing outside the closed
    /// one-rings of its two vertices, and a plan reads nothing outside the
    /// closed one-rings of its pair; so each contraction marks its new
    /// one-ring (and the deleted triangles' corners), and a pair with a
    /// marked vertex is planned again, serially, when its turn comes.
    /// Pass boundaries and candidates beyond the sorted part go through
    /// `step_pass` itself.
    fn walk_batch(&mut self, factor: f32) -> Result<(), StopReason> {
        /// On a batch index: the pair is planned in order only.
        const LATER: u32 = 1 << 31;
        /// At most this many pairs are planned at once (the batch is one
        /// pair per 64 live triangles: enough to amortise the fork, few
        /// enough that a plan is rarely invalidated).
        const MAX_BATCH: usize = 1024;
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
        let n = pass.number;
        let mut batch = std::mem::take(&mut self.scratch);
        batch.clear();
        let mut scan = pass.cursor;
        // A pair sharing a vertex with an earlier pair of the batch is
        // nearly always skipped (that vertex is touched once the earlier
        // pair contracts): it is not planned ahead (`LATER` on its index),
        // only in order, in the rare case it is still wanted then.
        let claim = self.next_generation();
        let (pass, mark) = (&self.pass, &mut self.mark);
        while scan < end && batch.len() < want {
            let e = pass.queue[scan];
            let (a, b) = (e.a as usize, e.b as usize);
            if pass.touched[a] != n && pass.touched[b] != n {
                let later = mark[a] == claim || mark[b] == claim;
                (mark[a], mark[b]) = (claim, claim);
                debug_assert!(scan < LATER as usize);
                batch.push(scan as u32 | if later { LATER } else { 0 });
            }
            scan += 1;
        }
        let mut plans = std::mem::take(&mut self.plan_scratch);
        let this = &*self;
        // Plans wait on memory: the pairs are in cost order, so each one's
        // neighbourhood is cold, and its fan → triangle → vertex loads
        // depend on each other. Each thread plans a run of pairs and
        // prefetches ahead: the vertex data of the pair four on, the fan
        // lists of the pair two on, the triangles of the next pair.
        let pair = |k: usize| {
            let e = this.pass.queue[(batch[k] & !LATER) as usize];
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
                    this.prefetch_vertices(a, b);
                }
                if k + 2 < len && ahead(k + 2) {
                    let (a, b) = pair(k + 2);
                    this.vtris.prefetch_fan(a);
                    this.vtris.prefetch_fan(b);
                }
                if k + 1 < len && ahead(k + 1) {
                    let (a, b) = pair(k + 1);
                    this.prefetch_triangles(a);
                    this.prefetch_triangles(b);
                }
                ahead(k).then(|| {
                    let (a, b) = pair(k);
                    this.plan(a, b)
                })
            })
            .collect_into_vec(&mut plans);
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
                self.scratch = batch;
                self.plan_scratch = plans;
                return Err(StopReason::Target);
            }
            let pass = &mut self.pass;
            let e = pass.queue[i as usize];
            if e.cost > pass.cost_limit && pass.removed > pass.goal / 6 {
                pass.cursor = pass.queue.len();
                self.scratch = batch;
                self.plan_scratch = plans;
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
                Err(r) => {
                    if r == Rejected::Error {
                        self.pass.error_rejections += 1;
                    }
                    self.stats.rejected.count(r);
                }
            }
        }
        // the rest of the scanned range was touched: skipped, as step_pass would
        self.pass.cursor = self.pass.cursor.max(scan);
        self.scratch = batch;
        self.plan_scratch = plans;
        Ok(())
    }

    /// Mark with `g` every vertex whose plan a contraction into `v1` may
    /// have changed: `v1`'s new one-ring (which holds the removed vertex's
    /// old one), the corners of the deleted triangles, and `v1`'s feature
    /// neighbours (whose feature kind `Features::contract` recounted).
    fn mark_changed(&mut self, v1: u32, removed: &[u32], g: u32) {
        self.mark[v1 as usize] = g;
        for &t in self.vtris.fan(v1).iter().chain(removed) {
            for &x in &self.tris[t as usize] {
                self.mark[x as usize] = g;
            }
        }
        if let Some(f) = &self.features {
            for &x in &f.nbrs[v1 as usize] {
                self.mark[x as usize] = g;
            }
        }
    }

    fn next_generation(&mut self) -> u32 {
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.mark.fill(0);
            self.generation = 1;
        }
        self.generation
    }

    /// Legality of contracting `v0` into `v1` at `p`, cheapest test first.
    /// On success returns the triangles the contraction deletes.
    fn check(&self, v0: u32, v1: u32, p: DVec3) -> Result<SmallVec<[u32; 2]>, Rejected> {
        let (i0, i1) = (v0 as usize, v1 as usize);
        if self.locked[i0] && self.locked[i1] {
            return Err(Rejected::Locked);
        }
        if let Some(f) = &self.features {
            f.allows(v0, v1)?;
        }
        let faces = Faces {
            tris: &self.tris,
            alive: &self.tri_alive,
            vtris: &self.vtris,
            pos: &self.pos,
        };
        let Link {
            shared,
            opposite,
            common,
        } = link(faces, v0, v1);
        if shared.len() == 2 && self.boundary[i0] && self.boundary[i1] {
            return Err(Rejected::BoundaryPinch);
        }
        if shared.len() > 2 {
            return Err(Rejected::Link);
        }
        if common != shared.len() || (opposite.len() == 2 && opposite[0] == opposite[1]) {
            return Err(Rejected::Link);
        }
        moved_faces_ok(faces, v0, v1, p, &opposite)?;
        Ok(shared)
    }

    /// Contract `v0` into `v1` at `p`, record it, and re-queue `v1`'s pairs.
    fn contract(&mut self, plan: Plan) {
        let Plan {
            v0,
            v1,
            p,
            error,
            removed,
        } = plan;
        let (i0, i1) = (v0 as usize, v1 as usize);
        let merged = fv(p);
        let edits = self.features.as_ref().map(|f| {
            let e = f.wedge_edits(
                [v0, v1],
                &self.tris,
                self.vtris.fan(v0),
                self.vtris.fan(v1),
                &self.tri_alive,
                &removed,
            );
            (e, f.wedges.is_some())
        });
        let mut record = Contraction {
            v0,
            v1,
            p1: self.pos[i1],
            removed: Removed::new(&removed),
            moved: self.log.mark()..self.log.mark(),
            error,
        };
        for &t in &record.removed {
            self.tri_alive[t as usize] = false;
        }
        self.live_tris -= record.removed.len();
        // v1's new fan: its live triangles, then v0's moved ones
        let mut into = std::mem::take(&mut self.fan_scratch);
        into.clear();
        into.extend(
            self.vtris
                .fan(v1)
                .iter()
                .copied()
                .filter(|&t| self.tri_alive[t as usize]),
        );
        for &t in self.vtris.fan(v0) {
            if !self.tri_alive[t as usize] {
                continue;
            }
            let tri = &mut self.tris[t as usize];
            if let Some(k) = tri.iter().position(|&x| x == v0) {
                tri[k] = v1;
                self.log.push_corner(Corner {
                    triangle: t,
                    slot: k as u8,
                });
                into.push(t);
                if let (Some((edits, true)), Some(f)) = (&edits, &mut self.features) {
                    let e = edits.iter().find(|e| e.0 == t).map_or([0; 2], |e| e.1);
                    if let Some(w) = f.wedges.as_mut() {
                        w[t as usize][k] = e[1];
                    }
                    self.log.wedges.push(e);
                }
            }
        }
        self.vtris.set(v1, &into);
        self.fan_scratch = into;
        self.pos[i1] = merged;
        let q0 = self.quadric[i0];
        self.quadric[i1] += q0;
        self.alive[i0] = false;
        if let Some(v) = self.version.get_mut(i1) {
            *v = v.wrapping_add(1);
        }
        self.boundary[i1] |= self.boundary[i0];
        if let Some(f) = &mut self.features {
            f.contract(v0, v1);
        }
        if let Some(at) = &mut self.attributes {
            let w = self.features.as_ref().and_then(|f| f.wedges.as_deref());
            let e = edits.as_ref().map_or(&[][..], |e| &e.0[..]);
            at.contract(v0, v1, &record.removed, e, &self.tris, w);
        }
        if !self.partners(v0).is_empty() || !self.partners(v1).is_empty() {
            let mut p = std::mem::take(&mut self.partners[i0]);
            p.append(&mut self.partners[i1]);
            p.retain(|&x| x != v1 && x != v0 && self.alive[x as usize]);
            p.sort_unstable();
            p.dedup();
            self.partners[i1] = p;
        }
        record.moved.end = self.log.mark();
        self.log.records.push(record);
        self.stats.collapses += 1;
        if self.opts.schedule != Schedule::Greedy {
            return;
        }

        // Re-queue every pair of v1: its edge neighbours and τ partners.
        let g = self.next_generation();
        let mut ns = std::mem::take(&mut self.scratch);
        ns.clear();
        if self.vtris.bloated() {
            self.vtris.rebuild(&self.tris, &self.tri_alive);
        }
        for &t in self.vtris.fan(v1) {
            for &x in &self.tris[t as usize] {
                if x != v1 && self.mark[x as usize] != g {
                    self.mark[x as usize] = g;
                    ns.push(x);
                }
            }
        }
        for &x in self.partners.get(i1).map_or(&[][..], |p| &p[..]) {
            if self.mark[x as usize] != g {
                self.mark[x as usize] = g;
                ns.push(x);
            }
        }
        for &x in &ns {
            if !(self.locked[i1] && self.locked[x as usize]) {
                let e = self.entry(v1, x);
                self.heap.push(e);
            }
        }
        self.scratch = ns;
    }

    /// The current mesh in the input's numbering.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            positions: self.pos.clone(),
            triangles: (0..self.tris.len())
                .filter(|&t| self.tri_alive[t])
                .map(|t| (t as u32, self.tris[t]))
                .collect(),
        }
    }

    /// Turn the log into the progressive mesh.
    pub fn finish(mut self) -> (ProgressiveMesh, Stats) {
        let t0 = Instant::now();
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
        let pm = ProgressiveMesh::from_log(
            &self.pos,
            &self.tris,
            &self.alive,
            &self.tri_alive,
            &self.log,
            self.features.as_ref().and_then(|f| f.wedges.as_deref()),
        );
        self.stats.output_triangles = self.live_tris;
        self.stats.output_vertices = pm.base.positions.len();
        self.stats.time.log = t0.elapsed();
        (pm, self.stats)
    }
}

/// One vertex's classification and quadric (`Simplifier::new`).
struct VertexInfo {
    quadric: Quadric,
    /// On an open border edge.
    boundary: bool,
    /// On a non-manifold edge, or where several fans meet.
    locked: bool,
}

/// Classify `v` from its fan `ts`: each edge `(v, x)` is a border (one
/// use), interior (one use in each direction) or non-manifold (anything
/// else: locked); interior edges join the fan's triangles, and more than
/// one fan locks `v` too. The quadric sums `v`'s face planes and, for each
/// border edge, the constraint plane through it (GH97 §6.1).
fn classify_vertex(
    mesh: &Mesh,
    planes: &[Plane],
    ts: &[u32],
    v: u32,
    opts: &SimplifyOptions,
    boundary_weight: f64,
) -> VertexInfo {
    let mut quadric = Quadric::default();
    for &t in ts {
        let [nx, ny, nz, d, w] = planes[t as usize];
        if w > 0.0 {
            quadric += Quadric::from_plane(DVec3::new(nx, ny, nz), d, w);
        }
    }
    // each triangle's two other corners, in winding order: the edge to the
    // first leaves v, the edge from the second enters it
    let others = |t: u32| {
        let [a, b, c] = mesh.triangles[t as usize];
        if a == v {
            (b, c)
        } else if b == v {
            (c, a)
        } else {
            (a, b)
        }
    };
    if ts.len() <= DISK_MAX {
        let (mut leave, mut enter) = ([u32::MAX; DISK_MAX], [u32::MAX; DISK_MAX]);
        for (i, &t) in ts.iter().enumerate() {
            (leave[i], enter[i]) = others(t);
        }
        if closed_disk(&leave, &enter, ts.len()) {
            // the usual interior vertex: no border, one fan
            return VertexInfo {
                quadric,
                boundary: false,
                locked: false,
            };
        }
    }
    // neighbour << 32 | (1 = edge leaves v) << 31 | fan slot: one integer
    // per use sorts as the tuple (neighbour, direction, slot) would
    let mut uses: SmallVec<[u64; 32]> = SmallVec::new();
    let edge_use =
        |x: u32, leaves: u64, slot: usize| u64::from(x) << 32 | leaves << 31 | slot as u64;
    for (i, &t) in ts.iter().enumerate() {
        let (l, e) = others(t);
        uses.push(edge_use(l, 1, i));
        uses.push(edge_use(e, 0, i));
    }
    uses.sort_unstable();
    let mut parent: SmallVec<[u32; 16]> = (0..ts.len() as u32).collect();
    fn root(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            parent[i as usize] = parent[parent[i as usize] as usize];
            i = parent[i as usize];
        }
        i
    }
    let (mut boundary, mut locked) = (false, false);
    let neighbour = |u: u64| (u >> 32) as u32;
    let leaves = |u: u64| u >> 31 & 1;
    let slot = |u: u64| (u & 0x7fff_ffff) as u32;
    for run in uses.chunk_by(|&a, &b| neighbour(a) == neighbour(b)) {
        match *run {
            [u] => {
                let (x, s) = (neighbour(u), slot(u));
                boundary = true;
                if boundary_weight > 0.0 {
                    let t = mesh.triangles[ts[s as usize] as usize];
                    let (pa, pb) = (
                        dv(mesh.positions[v as usize]),
                        dv(mesh.positions[x as usize]),
                    );
                    let e = pb - pa;
                    let c = e.cross(face_normal(&mesh.positions, &t));
                    let len = c.length();
                    if len > 0.0 {
                        let c = c / len;
                        let w = boundary_weight
                            * if opts.area_weighted {
                                e.length_squared()
                            } else {
                                1.0
                            };
                        // constraint planes shape the cost, not the
                        // mean-distance normalisation
                        quadric += Quadric {
                            weight: 0.0,
                            ..Quadric::from_plane(c, -c.dot(pa), w)
                        };
                    }
                }
            }
            [a, b] if leaves(a) != leaves(b) => {
                let (ra, rb) = (root(&mut parent, slot(a)), root(&mut parent, slot(b)));
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
            _ => locked = true,
        }
    }
    if !locked {
        let fans = (0..ts.len() as u32)
            .filter(|&i| root(&mut parent, i) == i)
            .count();
        locked = fans > 1;
    }
    VertexInfo {
        quadric,
        boundary,
        locked,
    }
}

/// Fans up to this size are tried with [`closed_disk`] first.
const DISK_MAX: usize = 16;

/// Whether the first `d` triangles of a fan, triangle `i` leaving `v`
/// towards `leave[i]` and entering it from `enter[i]` (the rest of both
/// arrays `u32::MAX`), make one closed disk: each neighbour left once and
/// entered once (so every edge is interior), and "the triangle entering
/// from where triangle `i` leaves to" is one cycle through all `d` (one
/// fan). The general path of `classify_vertex` (sorting the edge uses)
/// gives the same answer; this is the quick one for the usual vertex, and
/// `false` leaves the vertex to the general path.
fn closed_disk(leave: &[u32; DISK_MAX], enter: &[u32; DISK_MAX], d: usize) -> bool {
    if d < 2 {
        return false;
    }
    // next[i]: the (sum of the) triangles entering from leave[i], and how
    // many there are; without branches, so that it vectorises
    let mut next = [0u32; DISK_MAX];
    let mut single = true;
    for i in 0..d {
        let (mut count, mut at) = (0u32, 0u32);
        for (j, &e) in enter.iter().enumerate() {
            let hit = u32::from(e == leave[i]);
            count += hit;
            at += hit * j as u32;
        }
        single &= count == 1;
        next[i] = at;
    }
    if !single {
        return false;
    }
    // one entering triangle each: `next` is a function on 0..d, and a
    // cycle through all d from 0 makes it a bijection (leaves distinct,
    // and with one match each, enters distinct too)
    let mut i = 0;
    for _ in 1..d {
        i = next[i] as usize;
        if i == 0 {
            return false;
        }
    }
    next[i] == 0
}

/// A face's plane `[n.x, n.y, n.z, d, weight]` (unit normal, `n·x + d =
/// 0`), weight 0 when the face has no area.
type Plane = [f64; 5];

/// The plane of triangle `t`, weighted by its area or 1.
fn face_plane(positions: &[[f32; 3]], t: &[u32; 3], area_weighted: bool) -> Plane {
    let [p0, p1, p2] = t.map(|x| dv(positions[x as usize]));
    let n = (p1 - p0).cross(p2 - p0);
    let len = n.length();
    if len > 0.0 {
        let unit = n / len;
        let w = if area_weighted { 0.5 * len } else { 1.0 };
        [unit.x, unit.y, unit.z, -unit.dot(p0), w]
    } else {
        [0.0; 5]
    }
}

fn face_normal(positions: &[[f32; 3]], t: &[u32; 3]) -> DVec3 {
    let [p0, p1, p2] = t.map(|v| dv(positions[v as usize]));
    (p1 - p0).cross(p2 - p0).normalize_or_zero()
}

/// The mesh state the legality tests read (shared by `Simplifier` and the
/// curvature-adaptive sweeps).
pub(crate) struct Faces<'a, F: FanLookup + ?Sized> {
    pub tris: &'a [[u32; 3]],
    pub alive: &'a [bool],
    pub vtris: &'a F,
    pub pos: &'a [[f32; 3]],
}

// (by hand: a derive would ask `F: Copy`, and `F` is only borrowed)
impl<F: FanLookup + ?Sized> Clone for Faces<'_, F> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<F: FanLookup + ?Sized> Copy for Faces<'_, F> {}

/// What the link condition of contracting `v0` into `v1` reads: the live
/// triangles on both (deleted by the contraction), their third vertices,
/// and how many distinct vertices besides the two are on both one-rings.
/// The condition holds when `common == shared.len()` and the opposite
/// vertices differ.
pub(crate) struct Link {
    pub shared: SmallVec<[u32; 2]>,
    pub opposite: SmallVec<[u32; 2]>,
    pub common: usize,
}

/// The [`Link`] of `v0` and `v1` (on this thread's vertex marks: it only
/// reads the mesh, so that the batched walk can run it on many pairs).
pub(crate) fn link<F: FanLookup + ?Sized>(f: Faces<'_, F>, v0: u32, v1: u32) -> Link {
    let mut shared: SmallVec<[u32; 2]> = SmallVec::new();
    let mut opposite: SmallVec<[u32; 2]> = SmallVec::new();
    let common = with_marks(f.pos.len(), |mark, g| {
        // the one-ring of v0 gets g, its vertices also on v1's get g + 1
        for &t in f.vtris.fan(v0) {
            if !f.alive[t as usize] {
                continue;
            }
            let tri = f.tris[t as usize];
            if tri.contains(&v1) {
                shared.push(t);
                if let Some(&o) = tri.iter().find(|&&x| x != v0 && x != v1) {
                    opposite.push(o);
                }
            }
            for &x in &tri {
                mark[x as usize] = g;
            }
        }
        if shared.len() > 2 {
            return 0; // fails anyway
        }
        let mut common = 0;
        for &t in f.vtris.fan(v1) {
            if !f.alive[t as usize] {
                continue;
            }
            for &x in &f.tris[t as usize] {
                if x != v1 && x != v0 && mark[x as usize] == g {
                    mark[x as usize] = g + 1; // count each once
                    common += 1;
                }
            }
        }
        common
    });
    Link {
        shared,
        opposite,
        common,
    }
}

/// The geometric legality of contracting `v0` into `v1` at `p`, `shared`
/// being the triangles on both (deleted) and `opposite` their third
/// vertices, once the link condition holds: no moved face may flip (turn
/// by more than [`FLIP_MIN_COS`]) or collapse to a sliver
/// ([`DEGENERATE_AREA_RATIO_SQ`]), and no moved face may land on an
/// existing one (a tetrahedron or small closed part flattening into a
/// sheet).
pub(crate) fn moved_faces_ok<F: FanLookup + ?Sized>(
    f: Faces<'_, F>,
    v0: u32,
    v1: u32,
    p: DVec3,
    opposite: &[u32],
) -> Result<(), Rejected> {
    for (moving, other) in [(v0, v1), (v1, v0)] {
        let pm = dv(f.pos[moving as usize]);
        if pm == p {
            continue; // (a half-edge survivor) its faces do not move
        }
        for &t in f.vtris.fan(moving) {
            if !f.alive[t as usize] {
                continue;
            }
            let tri = f.tris[t as usize];
            // the two other corners, in the triangle's winding order
            let (b, c) = match tri {
                [x, b, c] | [c, x, b] | [b, c, x] if x == moving => (b, c),
                _ => continue, // (not on `moving`: a dead vertex's stale list)
            };
            if b == other || c == other {
                continue;
            }
            let (b, c) = (dv(f.pos[b as usize]), dv(f.pos[c as usize]));
            let bc = c - b;
            let n_old = (b - pm).cross(bc);
            let n_new = (b - p).cross(bc);
            let (l_old, l_new) = (n_old.length_squared(), n_new.length_squared());
            if l_old > 0.0 {
                if l_new <= DEGENERATE_AREA_RATIO_SQ * l_old {
                    return Err(Rejected::Degenerate);
                }
                // cos < FLIP_MIN_COS, without a square root: a negative
                // dot product is a flip, else compare squares
                let d = n_old.dot(n_new);
                if d < 0.0 || d * d < FLIP_MIN_COS * FLIP_MIN_COS * (l_old * l_new) {
                    return Err(Rejected::Flip);
                }
            }
        }
    }
    // With the link condition, a moved face `v0 x y` can only land on an
    // existing `v1 x y` when x and y are the two opposite vertices.
    if let &[o1, o2] = opposite {
        let has_face = |v: u32| {
            f.vtris.fan(v).iter().any(|&t| {
                let tri = f.tris[t as usize];
                f.alive[t as usize] && tri.contains(&o1) && tri.contains(&o2)
            })
        };
        if has_face(v0) && has_face(v1) {
            return Err(Rejected::Duplicate);
        }
    }
    Ok(())
}

/// Edge-connected fans of triangles around `v` (1 for a manifold vertex).
pub(crate) fn fan_count(tris: &[[u32; 3]], v: u32, ts: &[u32]) -> usize {
    let n = ts.len();
    if n <= 1 {
        return n;
    }
    let others = |t: u32| -> [u32; 2] {
        let tri = tris[t as usize];
        let k = tri.iter().position(|&x| x == v).unwrap_or(0);
        [tri[(k + 1) % 3], tri[(k + 2) % 3]]
    };
    let mut comp: SmallVec<[u32; 16]> = (0..n as u32).collect();
    let mut changed = true;
    while changed {
        changed = false;
        for i in 0..n {
            let oi = others(ts[i]);
            for j in i + 1..n {
                let oj = others(ts[j]);
                if oi.iter().any(|x| oj.contains(x)) && comp[i] != comp[j] {
                    let m = comp[i].min(comp[j]);
                    comp[i] = m;
                    comp[j] = m;
                    changed = true;
                }
            }
        }
    }
    comp.sort_unstable();
    comp.dedup();
    comp.len()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A fan around vertex 0 as `(leave, enter)` per triangle: kind 0 a
    /// closed disk, 1 two disks on distinct neighbours, 2 a disk with one
    /// triangle turned over, 3 an open fan (a border), 4 random corners
    /// from a few neighbours; then shuffled.
    fn fan(kind: u8, d: usize, seed: u64) -> Vec<(u32, u32)> {
        let mut rng = seed | 1;
        let mut next = move || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            rng
        };
        let ring = |n: usize, base: u32| -> Vec<(u32, u32)> {
            (0..n as u32)
                .map(|i| (base + i, base + (i + 1) % n as u32))
                .collect()
        };
        let mut f = match kind {
            0 => ring(d, 1),
            1 => [ring(d.max(4) / 2, 1), ring(d.max(4) - d.max(4) / 2, 100)].concat(),
            2 => {
                let mut f = ring(d, 1);
                let (l, e) = f[0];
                f[0] = (e, l);
                f
            }
            3 => ring(d + 1, 1)[..d].to_vec(),
            _ => (0..d)
                .map(|_| {
                    let l = 1 + (next() % 5) as u32;
                    (l, 1 + (l + (next() % 4) as u32) % 5)
                })
                .collect(),
        };
        for i in (1..f.len()).rev() {
            f.swap(i, (next() % (i as u64 + 1)) as usize);
        }
        f
    }

    /// What a closed disk is, by counting: every neighbour left once and
    /// entered once, and the triangles joined across shared edges are one
    /// component.
    fn is_closed_disk(f: &[(u32, u32)]) -> bool {
        let n = |x: u32, side: fn(&(u32, u32)) -> u32| f.iter().filter(|t| side(t) == x).count();
        let edges_ok = f.iter().all(|&(l, e)| {
            n(l, |t| t.0) == 1 && n(l, |t| t.1) == 1 && n(e, |t| t.0) == 1 && n(e, |t| t.1) == 1
        });
        let mut comp: Vec<usize> = (0..f.len()).collect();
        for _ in 0..f.len() {
            for i in 0..f.len() {
                for j in 0..f.len() {
                    if f[i].0 == f[j].1 {
                        let m = comp[i].min(comp[j]);
                        (comp[i], comp[j]) = (m, m);
                    }
                }
            }
        }
        edges_ok && f.len() >= 2 && comp.iter().all(|&c| c == 0)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// `closed_disk` is the quick path of `classify_vertex`: it must say
        /// "closed disk" exactly when the fan is one.
        #[test]
        fn closed_disk_is_exactly_a_closed_disk(kind in 0u8..5, d in 1usize..=DISK_MAX, seed in any::<u64>()) {
            let f = fan(kind, d, seed);
            prop_assume!(f.len() <= DISK_MAX);
            let (mut leave, mut enter) = ([u32::MAX; DISK_MAX], [u32::MAX; DISK_MAX]);
            for (i, &(l, e)) in f.iter().enumerate() {
                (leave[i], enter[i]) = (l, e);
            }
            prop_assert_eq!(closed_disk(&leave, &enter, f.len()), is_closed_disk(&f), "{:?}", f);
        }
    }
}
