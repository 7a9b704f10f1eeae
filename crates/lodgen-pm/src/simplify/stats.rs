//! What a simplification did and why it stopped: counts, rejections by
//! reason, time per phase.

use super::legality::Rejected;
use std::time::Duration;

/// Rejections counted by reason.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Rejections {
    /// [`Rejected::Locked`].
    pub locked: usize,
    /// [`Rejected::Link`].
    pub link: usize,
    /// [`Rejected::BoundaryPinch`].
    pub boundary_pinch: usize,
    /// [`Rejected::Flip`].
    pub flip: usize,
    /// [`Rejected::Degenerate`].
    pub degenerate: usize,
    /// [`Rejected::Duplicate`].
    pub duplicate: usize,
    /// [`Rejected::Error`].
    pub error: usize,
    /// [`Rejected::Feature`].
    pub feature: usize,
}

impl Rejections {
    pub(crate) fn count(&mut self, r: Rejected) {
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

    /// All rejections.
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
    /// ([`Schedule::Greedy`](super::Schedule::Greedy)), or every pass's sorted list
    /// ([`Schedule::Passes`](super::Schedule::Passes)).
    pub heap: Duration,
    /// The contraction loop (without `heap`).
    pub collapse: Duration,
    /// Renumbering the log into the progressive mesh.
    pub log: Duration,
}

/// What a simplification did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Vertices of the (welded) input.
    pub input_vertices: usize,
    /// Triangles of the (welded) input.
    pub input_triangles: usize,
    /// Vertices of the base mesh.
    pub output_vertices: usize,
    /// Triangles of the base mesh.
    pub output_triangles: usize,
    /// Contractions made (vertex splits in the log).
    pub collapses: usize,
    /// Passes made ([`Schedule::Passes`](super::Schedule::Passes); 0 when greedy).
    pub passes: usize,
    /// Non-edge pairs within τ at the start.
    pub near_pairs: usize,
    /// Vertices on an open border.
    pub boundary_vertices: usize,
    /// Vertices that never move: non-manifold ones (which may still be
    /// removed into a neighbour) and, with `Boundary::Locked`, the border.
    pub locked_vertices: usize,
    /// Candidates refused, by reason.
    pub rejected: Rejections,
    /// Contractions made only because
    /// [`SimplifyOptions::topology_change`](super::SimplifyOptions::topology_change)
    /// is on, by the rule each broke (the first the usual checks would
    /// have refused it for).
    pub relaxed: Rejections,
    /// Vertices the log records lifted off their simplified positions
    /// ([`SimplifyOptions::lift`](super::SimplifyOptions::lift)), counted
    /// when each is made.
    pub lifted: usize,
    /// Lifts refused because the lifted point would turn or collapse a
    /// face of the vertex's fan (the simplifier's point logged).
    pub lift_refused: usize,
    /// Wall time per phase.
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
    /// The run's [`crate::Meter`] was cancelled.
    Cancelled,
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
