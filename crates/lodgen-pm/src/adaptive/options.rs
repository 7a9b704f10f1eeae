//! The adaptive methods' options, stop reasons and report.

use crate::simplify::{Rejections, StopReason};
use crate::Simplified;

/// The paper's umbrella depth: "se usan las tres capas de la vecindad".
pub const DEFAULT_K_RING: usize = 3;

/// The paper's statistical threshold: θ above mean + 2σ is high curvature.
pub const DEFAULT_SIGMA: f64 = 2.0;

/// Hybrid weight `w` in `1 + w · θ / θ_max`: the flattest pair keeps its QEM
/// cost, the most curved one costs 5× as much. Large enough to reorder pairs
/// whose QEM costs are close, small enough that a nearly free collapse on a
/// curved patch still beats an expensive one on a flat patch (a pure curvature
/// order — w → ∞ — throws away QEM's error ranking).
pub const DEFAULT_HYBRID_WEIGHT: f64 = 4.0;

/// A valence-3 vertex is a "pyramid" (Algorithm 5, step 2) when one of its
/// three faces turns more than 90° (cos < 0) from both others.
pub const PYRAMID_MAX_COS: f64 = 0.0;

/// A face whose normal makes more than 90° (cos < 0) with the area-weighted
/// normal of the umbrella it lies in is reversed (Algorithm 5, step 3). Only
/// low-curvature umbrellas are ever edited, where every face should agree.
pub const REVERSED_MAX_COS: f64 = 0.0;

/// Which simplification method to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Method {
    /// The core GH97 quadric pair contraction ([`crate::simplify()`]).
    Qem,
    /// Curvature-adaptive full edge collapse to the midpoint (§2.2.1).
    Edge,
    /// Curvature-adaptive half-edge collapse onto one endpoint (§2.2.2).
    HalfEdge,
    /// Curvature-adaptive triangle collapse to the centroid (§2.2.3).
    Triangle,
    /// QEM with pair costs scaled by the normal deviation.
    QemCurvature,
}

impl Method {
    /// Every method, in the order the comparison lists them.
    pub const ALL: [Method; 5] = [
        Method::Qem,
        Method::QemCurvature,
        Method::Edge,
        Method::HalfEdge,
        Method::Triangle,
    ];

    /// The CLI spelling (`--method`).
    pub fn name(self) -> &'static str {
        match self {
            Method::Qem => "qem",
            Method::Edge => "edge",
            Method::HalfEdge => "half-edge",
            Method::Triangle => "triangle",
            Method::QemCurvature => "qem-curvature",
        }
    }

    /// Whether this is one of the paper's sweep methods (as opposed to QEM).
    pub fn is_adaptive(self) -> bool {
        matches!(self, Method::Edge | Method::HalfEdge | Method::Triangle)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Method, String> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                format!("unknown method {s:?}; expected one of qem, edge, half-edge, triangle, qem-curvature")
            })
    }
}

/// How θ is split into low (removable) and high curvature. A vertex is high
/// when θ is strictly above the threshold angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Threshold {
    /// Threshold at mean + s·σ of θ (the paper's first strategy, s = 2).
    Sigma(f64),
    /// Threshold at the (lower) median: at least half the vertices are
    /// removable (the paper's second strategy). Same as `Fraction(0.5)`.
    Median,
    /// Threshold at the θ of rank `⌈f·n⌉` in increasing order (f in [0, 1]):
    /// at least that fraction is removable (exactly, when θ values differ).
    Fraction(f64),
}

/// When the threshold angle is recomputed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reclassify {
    /// The angle comes from the input's θ distribution; θ is re-measured
    /// every sweep and compared with it. Stops when all that is left is
    /// curved at that level of detail.
    FixedThreshold,
    /// The angle comes from each sweep's own θ distribution (the paper's
    /// Step 4 taken literally): some vertices are always removable.
    EverySweep,
}

/// Options of the curvature methods. `AdaptiveOptions::DEFAULT` documents
/// every default.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct AdaptiveOptions {
    /// Depth of the umbrella the region normal is averaged over (≥ 1).
    /// Default value: [`DEFAULT_K_RING`] = 3.
    pub k_ring: usize,
    /// Default value: `Sigma(DEFAULT_SIGMA)` (mean + 2σ).
    pub threshold: Threshold,
    /// Default value: `FixedThreshold`.
    pub reclassify: Reclassify,
    /// `w` of the hybrid's cost scale `1 + w · θ / θ_max` (≥ 0).
    /// Default value: [`DEFAULT_HYBRID_WEIGHT`].
    pub hybrid_weight: f64,
}

impl AdaptiveOptions {
    /// The paper's settings: k = 3, mean + 2σ, fixed threshold, hybrid weight 4.
    pub const DEFAULT: AdaptiveOptions = AdaptiveOptions {
        k_ring: DEFAULT_K_RING,
        threshold: Threshold::Sigma(DEFAULT_SIGMA),
        reclassify: Reclassify::FixedThreshold,
        hybrid_weight: DEFAULT_HYBRID_WEIGHT,
    };
    /// Umbrella depth for the region normal (≥ 1).
    pub fn with_k_ring(mut self, k: usize) -> Self {
        self.k_ring = k;
        self
    }
    /// How θ is split into low and high curvature.
    pub fn with_threshold(mut self, t: Threshold) -> Self {
        self.threshold = t;
        self
    }
    /// Whether the threshold is recomputed every sweep.
    pub fn with_reclassify(mut self, r: Reclassify) -> Self {
        self.reclassify = r;
        self
    }
    /// The curvature weight `w` of [`Method::QemCurvature`].
    pub fn with_hybrid_weight(mut self, w: f64) -> Self {
        self.hybrid_weight = w;
        self
    }
}

impl Default for AdaptiveOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why an adaptive run stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdaptiveStop {
    /// The triangle target was reached.
    Target,
    /// No triangle (edge, for the edge operators) has all its vertices
    /// removable: what is left is border, non-manifold or high-curvature.
    Locked,
    /// Candidates remained, but every operation on them was illegal or had
    /// to be rolled back.
    Illegal,
    /// A QEM method stopped early with this core reason.
    Qem(StopReason),
}

impl AdaptiveStop {
    /// The core's reason for the same stop (`Exhausted` for both early
    /// adaptive stops).
    pub fn core(self) -> StopReason {
        match self {
            AdaptiveStop::Target => StopReason::Target,
            AdaptiveStop::Locked | AdaptiveStop::Illegal => StopReason::Exhausted,
            AdaptiveStop::Qem(r) => r,
        }
    }
}

/// Algorithm 5 defects found after a legal operation and repaired by rolling
/// the operation back.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Repairs {
    /// Two triangles on the same three vertices ("espigas").
    pub spikes: usize,
    /// A valence-3 vertex with one face folded over the other two.
    pub pyramids: usize,
    /// A face reversed against its umbrella.
    pub reversed: usize,
}

impl Repairs {
    /// All rollbacks, whatever the defect.
    pub fn total(&self) -> usize {
        self.spikes + self.pyramids + self.reversed
    }
}

/// What a curvature method did, beyond the core [`Stats`](crate::Stats).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveReport {
    /// The method that ran.
    pub method: Method,
    /// Why it stopped.
    pub stop: AdaptiveStop,
    /// Classify → decimate sweeps run (0 for the QEM methods).
    pub sweeps: usize,
    /// Operator applications (a triangle collapse is one operation, two
    /// splits).
    pub operations: usize,
    /// The first sweep's threshold angle (radians); for the hybrid, θ_max.
    pub threshold: f64,
    /// Vertices classified high curvature in the input.
    pub high_curvature_vertices: usize,
    /// In the last sweep: interior vertices still alive, those of them
    /// above the threshold (high curvature, locked), and the candidate
    /// triangles the operator was tried on (0 for the QEM methods).
    pub last_interior: usize,
    /// (see `last_interior`)
    pub last_high: usize,
    /// (see `last_interior`)
    pub last_candidates: usize,
    /// Vertices that never move: border (Algorithm 2) and non-manifold.
    pub fixed_vertices: usize,
    /// Operations refused by the legality rules (Algorithm 5 prevented).
    pub prevented: Rejections,
    /// Operations rolled back because they produced an Algorithm 5 defect.
    pub repaired: Repairs,
}

/// A method's result: the core [`Simplified`] (same shape as
/// [`crate::simplify()`]'s) and the curvature report.
#[derive(Clone, Debug)]
pub struct Adaptive {
    /// The progressive mesh, maps and core statistics.
    pub simplified: Simplified,
    /// What the curvature method did.
    pub report: AdaptiveReport,
}
