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

    #[test]
    fn fraction_is_the_share_of_the_goal() {
        let m = Meter::default();
        m.begin(1000, 200);
        m.set_live(600);
        assert_eq!(m.fraction(), Some(0.5));
    }
}
