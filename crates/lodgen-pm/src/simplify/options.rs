//! [`SimplifyOptions`]: what to simplify to and how. Units are stated on each
//! field; `SimplifyOptions::DEFAULT` documents every default.

/// Default weight of the boundary constraint planes, relative to the face
/// planes (GH97 §6.1 suggests a large penalty; 1 lets borders slide along
/// themselves but barely away from them once scaled by edge length²).
pub const DEFAULT_BOUNDARY_WEIGHT: f64 = 10.0;

/// How open boundaries are treated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Boundary {
    /// Add a constraint plane through each boundary edge, perpendicular to
    /// its face, with this weight (× edge length² when area-weighted).
    Weighted(f64),
    /// Boundary vertices never move; interior vertices may still collapse
    /// onto them.
    Locked,
}

/// Where a contracted pair's new vertex goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    /// The quadric-optimal point (3×3 solve, segment fallback).
    Optimal,
    /// The better of the two endpoints (half-edge collapse): every level's
    /// positions are a subset of the input's.
    HalfEdge,
}

/// What a run may do to the surface's topology to reach its target
/// ([`SimplifyOptions::topology_change`]). The topology rules refuse joins
/// that make the surface non-manifold (the link condition, two borders
/// pinched together, two edges of three faces fused), closed parts
/// flattened into double-sided sheets (duplicate faces), feature vertices
/// (seams, hard edges, material borders) leaving their lines, and faces
/// turning over or collapsing to slivers. A mesh whose topology holds its
/// triangles (beetle.obj: 47 edges of three faces, 23 border loops) runs out
/// of legal contractions above its target, or reaches it only through
/// contractions that the rules force to be costly (docs/quality.md,
/// "Reaching the count"). Relaxed contractions are vertex splits of the log
/// like any other (replay stays exact); `Stats::relaxed` counts them by the
/// rule they broke. Locked vertices ([`Boundary::Locked`]) stay locked and
/// `max_error` still binds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TopologyChange {
    /// Every rule holds: a mesh whose topology holds its triangles stops
    /// above its target ([`crate::StopReason::Exhausted`]).
    Never,
    /// The default: every rule holds, and when that stops the run above its
    /// target on refusals [`TopologyChange::Joins`] relaxes, `simplify` and
    /// `simplify_with_wedges` run it again from the start with
    /// [`TopologyChange::Joins`]. A mesh that reaches its target keeps its
    /// topology and the same output as with [`TopologyChange::Never`]; one
    /// that does not costs a second run. (`Simplifier` alone runs
    /// it as [`TopologyChange::Never`].) Measured on beetle.obj, positions
    /// only (`target/release/xtask quality --quick`): the run stopped at 92
    /// triangles for its 2 % level (41), Hausdorff 16.81 % / RMS 4.02 % of
    /// the diagonal; run again it reaches 40 at 6.05 / 1.72 %, and its 10 %
    /// level goes from 2.50 / 0.461 to 2.34 / 0.337 %.
    WhenShort,
    /// Joins and flattening allowed: with [`Schedule::Passes`], a pass
    /// whose candidates the topology rules held (refused more than a
    /// quarter as many as it contracted) is followed by one that lets joins
    /// and flattening pass, so the topology changes where that is cheapest
    /// instead of after costly forced contractions; a run stuck before its
    /// target lets joins, then flattening pass (in cost order, back to
    /// every rule after a pass that made a contraction).
    Joins,
    /// [`TopologyChange::Joins`], and a run still stuck lets feature
    /// vertices leave their lines, then faces turn over or collapse,
    /// one kind more each time it is stuck again; at least one face stays
    /// (`lodgen --allow-topology-change`).
    All,
}

/// In which order contractions are made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Schedule {
    /// GH97 literally: one heap of all pairs, always the cheapest next; the
    /// pairs around the survivor are re-costed after every contraction.
    Greedy,
    /// Passes (as meshoptimizer does): cost every pair once, sort, then
    /// contract in that order every pair whose vertices have not moved yet
    /// in this pass, up to `factor ×` the cost of the pass's goal-th pair;
    /// then start a new pass. Costs read in a pass are exact (a pair is
    /// skipped once either vertex moved), only the re-ranking waits for the
    /// next pass. Several times faster than `Greedy` and measured as good
    /// (README, "Performance").
    Passes {
        /// The cost limit, as a multiple of the cost of the pass's
        /// goal-th pair.
        factor: f32,
    },
}

/// Default error slack of [`Schedule::Passes`]: a pass stops at 1.5× the
/// cost of its goal-th cheapest pair (meshoptimizer's figure; the bench
/// measured 1.25 and 2 no better).
pub const DEFAULT_PASS_FACTOR: f32 = 1.5;

/// Default cluster size of [`SimplifyOptions::partition`], in triangles
/// (meshoptimizer's clusterlod and Nanite-style schemes use 10–50 k; on
/// the 1.1M-triangle bench mesh this gives 68 clusters).
pub const DEFAULT_CLUSTER_TRIANGLES: usize = 16_384;

/// The factor of [`SimplifyOptions::reach`] (its default). Measured by `cargo
/// xtask quality --quick` over 0.7–4 (geometric mean of lodgen / best peer
/// over 21 cells; off: Hausdorff 1.172, RMS 1.055): 1.0 gives 1.116 /
/// 1.034, 1.05 1.063 / 1.034, 1.1 1.012 / 1.032, 1.2 1.069 / 1.036, 4
/// defers nothing. At 1.1: cow 50 % Hausdorff 0.562 → 0.244 % of the
/// diagonal (the tail tip), 10 % 2.15 → 1.13 %, teapot 50 % 0.140 → 0.089 %
/// (the spout tip), bunny 2 % 0.64 → 0.51 %; worse: rocker-arm 2 % 0.97 →
/// 1.38 %, fandisk 2 % 0.32 → 0.33 %, beetle 50 % 0.61 → 0.64 %.
pub const DEFAULT_REACH_FACTOR: f64 = 1.1;

/// The factor of [`SimplifyOptions::reach_faces`] (its default). Measured
/// by `cargo xtask quality --quick --reach-faces` (session 17, the test in
/// every pass, docs/quality.md "The new faces' reach"): geometric mean of
/// lodgen / best peer over 20 cells Hausdorff 0.922 → 0.886 at 1.2 (0.880
/// at 0.8, 0.909 at 1, 0.941 at 1.5, 0.922 at 2), RMS 0.948 → 0.940; at
/// 0.8 teapot 2 % 2.08 → 4.61 %, cow 2 % 5.90 → 7.01 %. Since session 18
/// (midpoints only, the test only while a tenth of the input lives): over
/// 21 cells 0.910 / 0.933 → 0.874 / 0.928, but bunny 2 % 0.517 → 0.706 %.
pub const DEFAULT_REACH_FACES_FACTOR: f64 = 1.2;

/// The pair-distance threshold τ of GH97 (non-edge pairs closer than τ may
/// contract too).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tau {
    /// In the mesh's units.
    Absolute(f64),
    /// As a fraction (0.005 = 0.5 %) of the bounding-box diagonal.
    DiagonalFraction(f64),
}

/// Options of [`crate::simplify()`]. Stopping: whichever target is reached
/// first.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct SimplifyOptions {
    /// Stop at or below this many triangles. Default value: none.
    pub target_triangles: Option<usize>,
    /// Stop at or below this fraction of the (welded) input's triangles.
    /// Default value: none. Neither target set means "as far as possible".
    pub target_ratio: Option<f64>,
    /// Stop before a contraction whose quadric error (root mean squared
    /// distance to its planes, mesh units) exceeds this. Default value: none.
    pub max_error: Option<f64>,
    /// Non-edge pair threshold. Default value: `Absolute(0.0)` (edges only).
    pub tau: Tau,
    /// Weight face planes by triangle area (GH97 §6.3) instead of 1 each.
    /// Default value: `true`.
    pub area_weighted: bool,
    /// Default value: `Weighted(DEFAULT_BOUNDARY_WEIGHT)`.
    pub boundary: Boundary,
    /// Default value: `Optimal`.
    pub placement: Placement,
    /// Default value: `Passes { factor: DEFAULT_PASS_FACTOR }`.
    pub schedule: Schedule,
    /// Partitioned simplification (`Simplifier::run` only): cut the mesh
    /// into clusters of about this many consecutive triangles, simplify
    /// their interiors in parallel with the clusters' shared borders held,
    /// then continue on the whole mesh. Taken by pass runs without τ
    /// pairs or attribute quadrics, position only or with one wedge per
    /// vertex (feature edges allowed: a scan's open borders), to at most
    /// 7.5 % of the input, on meshes of at least eight clusters (131,072
    /// triangles by default); the result depends on this value, never on
    /// the thread count. `None`: the whole-mesh walk throughout. Default
    /// value: `Some(DEFAULT_CLUSTER_TRIANGLES)`: on the 1.1M bench mesh
    /// every level of 50 / 10 / 2 % keeps its Hausdorff distance (2 %:
    /// 0.1167 %) and its RMS error within 2 %, the clusters' rounds use
    /// every core, and the run's peak memory stays under the measurement's
    /// (docs/performance.md).
    pub partition: Option<usize>,
    /// [`Schedule::Passes`]: also defer to a later pass a contraction that
    /// moves the surface farther than this factor × the pass's spread bound
    /// (the old position of either vertex from every face it moves, or the
    /// new position from every face of the old fans; tested only on pairs
    /// whose error² is at least 0.1 × the limit): the quadric cost
    /// underrates contractions at the tips of thin parts (a tail, a horn,
    /// a spout), whose faces are nearly parallel to the way the tip moves.
    /// Default value: `Some(DEFAULT_REACH_FACTOR)` (`None` turns it off):
    /// it lowers the error against the other simplifiers (`cargo xtask
    /// quality --quick`, geometric mean of lodgen / best peer over the
    /// quick run's cells: Hausdorff 1.14 → 0.92, RMS 1.03 → 0.96, see
    /// docs/quality.md) for ≈ 11 % more simplification instructions on
    /// the bunny (the reach test of every planned pair; +2–5 % of a whole
    /// CLI run's CPU with measurement; docs/performance.md).
    pub reach: Option<f64>,
    /// With [`SimplifyOptions::reach`] on, a pass also defers a pair one
    /// of whose new faces leaves the old surface farther than this factor
    /// × the reach distance: the midpoints of the new edges (from the
    /// merged vertex) against the two old fans (reach tests vertices only,
    /// so a new face can bridge a dent or cut a bump between vertices that
    /// stay close), while at least a tenth of the input's triangles live
    /// (below, the long new edges would change the last passes more than
    /// they keep the surface). Off by default (`None`; suggested value
    /// [`DEFAULT_REACH_FACES_FACTOR`]): it lowers the Hausdorff distance
    /// of most 50 % and 10 % levels (positions only: bunny 10 % 0.246 →
    /// 0.187 %, cow 50 % 0.266 → 0.204 %, beetle 50 % 0.650 → 0.413 %,
    /// spot 10 % 0.963 → 0.915 %) but raises the bunny's 2 % one (0.517 →
    /// 0.706 %), for +3–6 % of the bunny run's CPU (docs/quality.md, "The
    /// new faces' reach, cheaper").
    pub reach_faces: Option<f64>,
    /// What the run may do to the surface's topology to reach its target
    /// ([`TopologyChange`]; default [`TopologyChange::WhenShort`]).
    pub topology_change: TopologyChange,
    /// With optimal placement, log each vertex a contraction of two free
    /// vertices makes lifted off its pair's chord: one damped Newton step
    /// on its cluster's quadric (`Quadric::lifted`), where the summed
    /// quadric was too flat for its own minimiser. The contraction order
    /// and the topology are the same either way; the progressive mesh,
    /// its stream and every level carry the lifted positions (RMS geomean
    /// against the best peer 0.933 → 0.88, docs/quality.md "Lift in the
    /// log"). Default value: `true`.
    pub lift: bool,
}

impl SimplifyOptions {
    /// The defaults: see each field.
    pub const DEFAULT: SimplifyOptions = SimplifyOptions {
        target_triangles: None,
        target_ratio: None,
        max_error: None,
        tau: Tau::Absolute(0.0),
        area_weighted: true,
        boundary: Boundary::Weighted(DEFAULT_BOUNDARY_WEIGHT),
        placement: Placement::Optimal,
        schedule: Schedule::Passes {
            factor: DEFAULT_PASS_FACTOR,
        },
        partition: Some(DEFAULT_CLUSTER_TRIANGLES),
        reach: Some(DEFAULT_REACH_FACTOR),
        reach_faces: None,
        topology_change: TopologyChange::WhenShort,
        lift: true,
    };
    /// Stop at `n` triangles.
    pub fn with_target_triangles(mut self, n: usize) -> Self {
        self.target_triangles = Some(n);
        self
    }
    /// Stop at this fraction of the input's triangles.
    pub fn with_target_ratio(mut self, r: f64) -> Self {
        self.target_ratio = Some(r);
        self
    }
    /// Never contract a pair whose error exceeds `e` (mesh units).
    pub fn with_max_error(mut self, e: f64) -> Self {
        self.max_error = Some(e);
        self
    }
    /// Also pair vertices closer than τ (GH97 non-edge pairs).
    pub fn with_tau(mut self, t: Tau) -> Self {
        self.tau = t;
        self
    }
    /// Weight face planes by area.
    pub fn with_area_weighted(mut self, on: bool) -> Self {
        self.area_weighted = on;
        self
    }
    /// How open borders are treated.
    pub fn with_boundary(mut self, b: Boundary) -> Self {
        self.boundary = b;
        self
    }
    /// Where a contracted pair's vertex goes.
    pub fn with_placement(mut self, p: Placement) -> Self {
        self.placement = p;
        self
    }
    /// The contraction order.
    pub fn with_schedule(mut self, s: Schedule) -> Self {
        self.schedule = s;
        self
    }

    /// Simplify in clusters of about `n` triangles first (`None`: never).
    pub fn with_partition(mut self, n: Option<usize>) -> Self {
        self.partition = n;
        self
    }

    /// Defer contractions that move the surface by more than `f` × the
    /// pass's spread bound (`None`: never).
    pub fn with_reach(mut self, f: Option<f64>) -> Self {
        self.reach = f;
        self
    }

    /// Defer contractions whose new faces leave the old surface farther
    /// than `f` × the reach distance ([`SimplifyOptions::reach_faces`];
    /// `None`: never; no effect with reach off).
    pub fn with_reach_faces(mut self, f: Option<f64>) -> Self {
        self.reach_faces = f;
        self
    }

    /// Log lifted vertices ([`SimplifyOptions::lift`]) or the
    /// simplifier's own positions.
    pub fn with_lift(mut self, on: bool) -> Self {
        self.lift = on;
        self
    }

    /// What the run may do to the topology ([`TopologyChange`]).
    pub fn with_topology_change(mut self, t: TopologyChange) -> Self {
        self.topology_change = t;
        self
    }

    /// `true`: [`TopologyChange::All`]; `false`: [`TopologyChange::Never`].
    pub fn with_allow_topology_change(mut self, on: bool) -> Self {
        self.topology_change = if on {
            TopologyChange::All
        } else {
            TopologyChange::Never
        };
        self
    }

    /// The triangle count to stop at for an input of `n` triangles.
    pub fn target_for(&self, n: usize) -> usize {
        let by_ratio = self
            .target_ratio
            .map(|r| (r.clamp(0.0, 1.0) * n as f64).floor() as usize);
        match (self.target_triangles, by_ratio) {
            (Some(a), Some(b)) => a.max(b),
            (Some(a), None) | (None, Some(a)) => a,
            (None, None) => 0,
        }
    }

    /// τ in mesh units for a mesh of bounding-box diagonal `diagonal`.
    pub fn tau_for(&self, diagonal: f64) -> f64 {
        match self.tau {
            Tau::Absolute(t) => t,
            Tau::DiagonalFraction(f) => f * diagonal,
        }
    }
}

impl Default for SimplifyOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}
