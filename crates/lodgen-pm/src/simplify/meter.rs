//! [`Meter`]: how far a run has got, for a progress display. The core never
//! prints; a caller shares a `Meter` with the run and reads it from another
//! thread (relaxed atomics: a snapshot may be a step behind).

use std::sync::atomic::{AtomicU8, AtomicUsize, Ordering::Relaxed};

/// What a metered simplification is doing now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Not started, or done.
    Idle,
    /// Welding and cleaning the input (`prepare`), classification,
    /// quadrics.
    Preparing,
    /// Contracting pairs: [`Meter::fraction`] says how far.
    Contracting,
    /// Turning the log into the progressive mesh.
    Finishing,
    /// Cutting a large mesh into the clusters (or groups of clusters) it
    /// is simplified in first, between contractions ([`Meter::fraction`]
    /// says how far those went).
    Clustering,
}

/// Progress of one simplification, shared with an observer.
#[derive(Debug, Default)]
pub struct Meter {
    stage: AtomicU8,
    start: AtomicUsize,
    target: AtomicUsize,
    live: AtomicUsize,
}

impl Meter {
    /// What the run is doing now.
    pub fn stage(&self) -> Stage {
        match self.stage.load(Relaxed) {
            1 => Stage::Preparing,
            2 => Stage::Contracting,
            3 => Stage::Finishing,
            4 => Stage::Clustering,
            _ => Stage::Idle,
        }
    }

    /// Share of the triangles to remove that are removed, in `[0, 1]`
    /// (`None` before contracting starts).
    pub fn fraction(&self) -> Option<f64> {
        let start = self.start.load(Relaxed);
        let target = self.target.load(Relaxed);
        let live = self.live.load(Relaxed);
        if start == 0 {
            return None;
        }
        let goal = start.saturating_sub(target).max(1);
        Some((start.saturating_sub(live) as f64 / goal as f64).min(1.0))
    }

    /// Sets the stage (the run sets it; a caller sets `Idle` after a run that
    /// failed).
    pub fn set_stage(&self, s: Stage) {
        let v = match s {
            Stage::Idle => 0,
            Stage::Preparing => 1,
            Stage::Contracting => 2,
            Stage::Finishing => 3,
            Stage::Clustering => 4,
        };
        self.stage.store(v, Relaxed);
    }

    pub(crate) fn begin(&self, live: usize, target: usize) {
        self.target.store(target, Relaxed);
        self.live.store(live, Relaxed);
        self.start.store(live, Relaxed);
        self.set_stage(Stage::Contracting);
    }

    pub(crate) fn set_live(&self, live: usize) {
        self.live.store(live, Relaxed);
    }

    /// `n` more triangles removed (the clustered rounds: each cluster
    /// counts its own off as its walk ends).
    pub(crate) fn remove(&self, n: usize) {
        let _ = self
            .live
            .fetch_update(Relaxed, Relaxed, |l| Some(l.saturating_sub(n)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{shapes, Simplifier, SimplifyOptions, StopReason};
    use std::sync::Arc;

    #[test]
    fn a_run_reports_its_target_reached() {
        let mesh = shapes::icosphere(3); // 1280 triangles
        let opts = SimplifyOptions::DEFAULT.with_target_triangles(320);
        let mut s = Simplifier::new(&mesh, &opts).unwrap();
        let meter = Arc::new(Meter::default());
        assert_eq!(meter.fraction(), None);
        s.set_meter(Arc::clone(&meter));
        assert_eq!(s.run(), StopReason::Target);
        assert_eq!(meter.fraction(), Some(1.0));
        assert_eq!(meter.stage(), Stage::Contracting);
        let _ = s.finish();
        assert_eq!(meter.stage(), Stage::Idle);
    }

    /// The clustered rounds of a large mesh move the meter as they go
    /// (they used to leave it at 0 % until the whole-mesh walk: bunny-1m's
    /// progress line stood at 0 % for seconds): after the partitioned
    /// stages alone it counts every triangle they removed.
    #[test]
    fn clustered_rounds_move_the_meter() {
        let mesh = shapes::grid(120, 120, |x, y| 0.1 * (7.0 * x).sin() * (5.0 * y).cos());
        let opts = SimplifyOptions::DEFAULT
            .with_target_ratio(0.015)
            .with_partition(Some(400));
        let mut s = Simplifier::new(&mesh, &opts).unwrap();
        let meter = Arc::new(Meter::default());
        s.set_meter(Arc::clone(&meter));
        let start = s.live_tris;
        meter.begin(start, s.target);
        let size = s.partition_size().expect("a partitioned run");
        s.run_partitioned(size);
        assert!(s.live_tris < start / 4, "the rounds ran");
        assert_eq!(meter.live.load(Relaxed), s.live_tris);
        assert_eq!(meter.stage(), Stage::Contracting);
        let f = meter.fraction().unwrap();
        assert!(f > 0.5 && f < 1.0, "{f}");
    }

    #[test]
    fn fraction_is_the_share_of_the_goal() {
        let m = Meter::default();
        m.begin(1000, 200);
        m.set_live(600);
        assert_eq!(m.fraction(), Some(0.5));
    }
}
