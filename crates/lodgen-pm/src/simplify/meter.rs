//! [`Meter`]: how far a run has got, for a progress display, and a way to
//! stop it. The core never prints; a caller shares a `Meter` with the run
//! and reads it from another thread (relaxed atomics: a snapshot may be a
//! step behind), or [cancels](Meter::cancel) the run from there.

use std::sync::atomic::{AtomicBool, AtomicU8, AtomicUsize, Ordering::Relaxed};

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
    cancelled: AtomicBool,
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

    /// Asks the runs sharing this meter to stop: a QEM run stops between
    /// batches of its walk and between rounds of its clusters, with
    /// [`crate::StopReason::Cancelled`] (its log so far is still a valid
    /// chain). What the run was given stays cancelled: a meter is not
    /// reset.
    pub fn cancel(&self) {
        self.cancelled.store(true, Relaxed);
    }

    /// Whether [`Meter::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.cancelled.load(Relaxed)
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

    /// A cancelled meter stops the walk and the clustered rounds before
    /// they contract anything, and the log stays a valid chain.
    #[test]
    fn a_cancelled_meter_stops_the_run() {
        let wavy = |x: f64, y: f64| 0.1 * (7.0 * x).sin() * (5.0 * y).cos();
        for partition in [None, Some(400)] {
            let mesh = shapes::grid(120, 120, wavy);
            let opts = SimplifyOptions::DEFAULT
                .with_target_ratio(0.015)
                .with_partition(partition);
            let mut s = Simplifier::new(&mesh, &opts).unwrap();
            let start = s.live_tris;
            let meter = Arc::new(Meter::default());
            meter.cancel();
            assert!(meter.is_cancelled());
            s.set_meter(Arc::clone(&meter));
            assert_eq!(s.run(), StopReason::Cancelled, "{partition:?}");
            assert_eq!(s.live_tris, start, "{partition:?}");
            let (pm, _) = s.finish();
            assert_eq!(pm.mesh_at_splits(pm.len()).triangles.len(), start);
        }
    }

    /// Cancelled from another thread while it runs, a walk stops short of
    /// its target (the meter is polled after every batch).
    #[test]
    fn a_meter_cancelled_mid_run_stops_it_early() {
        let mesh = shapes::icosphere(7); // 327,680 triangles
        let opts = SimplifyOptions::DEFAULT
            .with_target_triangles(100)
            .with_partition(None);
        let mut s = Simplifier::new(&mesh, &opts).unwrap();
        let meter = Arc::new(Meter::default());
        s.set_meter(Arc::clone(&meter));
        let watcher = Arc::clone(&meter);
        let stop = std::thread::scope(|scope| {
            scope.spawn(move || {
                while watcher.fraction().is_none_or(|f| f < 0.2) {
                    std::thread::yield_now();
                }
                watcher.cancel();
            });
            s.run()
        });
        // (the run may only reach its target if it got there before the
        // watcher saw 20 %: it cannot, a batch is far smaller than 80 %)
        assert_eq!(stop, StopReason::Cancelled);
        assert!(s.live_tris > 100, "{}", s.live_tris);
    }

    #[test]
    fn fraction_is_the_share_of_the_goal() {
        let m = Meter::default();
        m.begin(1000, 200);
        m.set_live(600);
        assert_eq!(m.fraction(), Some(0.5));
    }
}
