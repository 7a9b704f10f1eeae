//! The walk's mesh handed to a caller on the way down: [`Watch`], set with
//! [`Simplifier::set_watch`]. A caller that will measure the levels at
//! chosen triangle counts gets each level's mesh the moment the walk
//! reaches it, and can measure it on a core the walk leaves idle instead
//! of after the walk.

use std::sync::Arc;

use super::stats::Snapshot;
use super::Simplifier;

/// Which states of the walk to hand over, and to whom.
///
/// `counts(n)` gives, from the triangle count `n` the simplification starts
/// with, the live triangle counts to watch; the first time the live
/// triangles fall to or below each (after a contraction), `reached` gets
/// the mesh as [`Simplifier::snapshot`] gives it. That state is the
/// progressive mesh's level with the most splits and at most that many
/// triangles, as the log will record it. Counts the run starts at or below,
/// or at or below its target (the state the run ends in), are not watched;
/// nor are the states of the clustered rounds (`partition`): a count
/// crossed there is skipped.
///
/// A [`crate::TopologyChange::WhenShort`] run that starts again hands over
/// the second run's states too: the caller tells them apart by comparing
/// with the levels it gets in the end.
pub struct Watch {
    counts: Box<dyn Fn(usize) -> Vec<usize> + Send + Sync>,
    reached: Box<dyn Fn(Snapshot) + Send + Sync>,
}

impl Watch {
    /// A watch of the counts `counts` gives, handing each state to
    /// `reached`.
    pub fn new(
        counts: impl Fn(usize) -> Vec<usize> + Send + Sync + 'static,
        reached: impl Fn(Snapshot) + Send + Sync + 'static,
    ) -> Watch {
        Watch {
            counts: Box::new(counts),
            reached: Box::new(reached),
        }
    }
}

/// A simplifier's watch: the counts still to reach, largest first.
pub(super) struct Watching {
    watch: Arc<Watch>,
    counts: Vec<usize>,
    next: usize,
}

impl Simplifier {
    /// Hands the walk's mesh to `watch` at its counts ([`Watch`]).
    pub fn set_watch(&mut self, watch: Arc<Watch>) {
        let mut counts: Vec<usize> = (watch.counts)(self.live_tris)
            .into_iter()
            .filter(|&c| c > self.target)
            .collect();
        counts.sort_unstable_by(|a, b| b.cmp(a));
        counts.dedup();
        self.watching = Some(Watching {
            watch,
            counts,
            next: 0,
        });
        self.watch_below = 0;
    }

    /// Starts watching (before the whole-mesh walk): counts already
    /// reached are skipped.
    pub(super) fn arm_watch(&mut self) {
        self.advance_watch();
    }

    /// After a contraction that took the live triangles below
    /// `watch_below`: the state handed over.
    #[cold]
    pub(super) fn hand_over(&mut self) {
        if let Some(w) = &self.watching {
            (w.watch.reached)(self.snapshot());
        }
        self.advance_watch();
    }

    /// The next count above which nothing is handed over (`watch_below`
    /// one above it; 0 when none is left).
    fn advance_watch(&mut self) {
        self.watch_below = 0;
        if let Some(w) = &mut self.watching {
            while w.counts.get(w.next).is_some_and(|&c| c >= self.live_tris) {
                w.next += 1;
            }
            if let Some(&c) = w.counts.get(w.next) {
                self.watch_below = c + 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Mutex;

    use super::*;
    use crate::{shapes, SimplifyOptions, StopReason};

    /// The handed-over states are the progressive mesh's levels at the
    /// watched counts: the same triangles (corner positions, in order) as
    /// `mesh_at_splits` of the largest split count with at most that many
    /// triangles; a count above the start or at the target is not handed
    /// over. Fails if a state is taken before its contraction is complete
    /// (lifted positions unsettled) or at the wrong contraction.
    #[test]
    fn handed_over_states_are_the_levels() {
        let mesh = shapes::torus_knot(2, 3, 120, 16, 0.01);
        let n = mesh.triangles.len();
        let target = n / 20;
        let got = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&got);
        let watch = Watch::new(
            move |start| vec![start + 5, start / 2, start / 5, start / 5, target],
            move |s| sink.lock().unwrap().push(s),
        );
        let opts = SimplifyOptions::DEFAULT.with_target_triangles(target);
        let mut s = Simplifier::new(&mesh, &opts).unwrap();
        s.set_watch(Arc::new(watch));
        assert_eq!(s.run(), StopReason::Target);
        let (pm, _) = s.finish();
        let got = got.lock().unwrap();
        assert_eq!(got.len(), 2, "one state per count between start and target");
        let counts = pm.triangle_counts();
        for (snap, want) in got.iter().zip([n / 2, n / 5]) {
            let k = counts.partition_point(|&c| c <= want) - 1;
            let level = pm.mesh_at_splits(k);
            let bits = |p: [f32; 3]| p.map(f32::to_bits);
            let mut a: Vec<_> = snap
                .triangles
                .iter()
                .map(|(_, t)| t.map(|v| bits(snap.positions[v as usize])))
                .collect();
            let mut b: Vec<_> = level
                .triangles
                .iter()
                .map(|t| t.map(|v| bits(level.positions[v as usize])))
                .collect();
            a.sort_unstable();
            b.sort_unstable();
            assert!(
                a.len() <= want && a.len() + 3 > want,
                "{} for {want}",
                a.len()
            );
            assert_eq!(a, b, "the state at {want} triangles");
        }
    }
}
