//! Levels measured while the walk goes on (a small mesh's levels by ratio
//! or count). The walk leaves the second core idle: on the bunny a run
//! with one thread takes the two-thread run's wall time. So the walk hands
//! each level's mesh over the moment it reaches it ([`Watch`]), and the
//! thread that built the original's hierarchy beside the walk measures it
//! there, in a pool of its own (one thread: the walk's pool is left to
//! the walk). A level the walk reaches as it ends is measured after it on
//! every core, and the walk's last level is not watched: it is measured
//! as before.
//!
//! A level's report is then the measurement of the walk's mesh, in the
//! welded input's numbering, against the original in that numbering. It
//! is the level's geometry (checked: [`Reached::fingerprint`] equals the
//! extracted level's), so the same distances; only what follows the
//! numbering may differ from a measurement of the extracted level: which
//! triangle a max-seeking climb starts in, which border edges' midpoints
//! are measured, ties along the Morton curve. Every watched level is
//! measured that way however the threads run, so the output is the same
//! for every thread count and every run.

use std::sync::mpsc::{channel, Receiver};
use std::sync::{Arc, Weak};
use std::time::{Duration, Instant};

use lodgen_pm::levels::LevelSpec;
use lodgen_pm::metric::{ErrorReport, MeasureOptions, MeshRef, Reference};
use lodgen_pm::{Mesh, Snapshot, Watch};

use super::extract::Extracted;
use super::options::{BuildOptions, LevelRequest};

/// The watch of a build's levels and the end its states arrive at.
pub(super) struct Watched {
    pub(super) watch: Arc<Watch>,
    pub(super) states: Receiver<Snapshot>,
}

/// The watch of `opts`'s levels by ratio or count (`None` for levels by
/// error, which are searched for after the walk).
pub(super) fn watch_levels(opts: &BuildOptions) -> Option<Watched> {
    let LevelRequest::Specs(specs) = &opts.levels else {
        return None;
    };
    let specs = specs.clone();
    let (to, states) = channel();
    let watch = Watch::new(
        move |n| {
            specs
                .iter()
                .filter_map(|s| match *s {
                    // (as `select.rs` counts them, of the welded mesh)
                    LevelSpec::Ratio(r) => Some((r.clamp(0.0, 1.0) * n as f64).floor() as usize),
                    LevelSpec::Triangles(t) => Some(t),
                    LevelSpec::MaxError(_) => None,
                })
                .filter(|&c| 5 * c >= 2 * n)
                .collect()
        },
        move |s| {
            // (the receiver gone: the level is measured after the walk)
            let _ = to.send(s);
        },
    );
    Some(Watched {
        watch: Arc::new(watch),
        states,
    })
}

/// A level the walk handed over, measured.
pub(super) struct Reached {
    /// [`fingerprint`] of its triangles.
    fingerprint: (usize, u64),
    report: ErrorReport,
}

/// The levels the walk hands over, measured against `reference` (the
/// original in the welded numbering) as they arrive, while the walk runs
/// (`alive`: the watch, gone when the walk is over), on a thread outside
/// the walk's pool in a one-thread pool of its own; the states that arrive
/// after the walk are measured on every core. Also returns the time spent.
///
/// (Outside the pool: a pool thread waiting on another pool steals the
/// walk's jobs meanwhile, and the walk then waits for them behind the
/// measurement on a shared core: the bunny's walk took 30-60 ms longer.)
pub(super) fn measure_reached(
    reference: &Reference<'_>,
    watched: (Weak<Watch>, Receiver<Snapshot>),
    mopts: &MeasureOptions,
) -> (Vec<Reached>, Duration) {
    let (alive, states) = watched;
    let t = Instant::now();
    let measure = |level: &Mesh| {
        let report = reference.measure(MeshRef::new(&level.positions, &level.triangles), mopts);
        // (a state is a walk's mesh: valid as its input was)
        report.ok().map(|report| Reached {
            fingerprint: fingerprint(level),
            report,
        })
    };
    let measure = &measure;
    let beside = move || {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().ok();
        let (mut out, mut after) = (Vec::new(), Vec::new());
        for s in states.iter() {
            let level = compact(&s);
            match &pool {
                Some(p) if alive.strong_count() > 0 => out.extend(p.install(|| measure(&level))),
                _ => after.push(level),
            }
        }
        (out, after)
    };
    let (mut out, after) = std::thread::scope(|scope| {
        let side = std::thread::Builder::new().spawn_scoped(scope, beside);
        side.ok().and_then(|h| h.join().ok())
    })
    .unwrap_or_default();
    out.extend(after.iter().filter_map(measure));
    (out, t.elapsed())
}

/// The measured report of every extracted level that is a level the walk
/// handed over (same triangles: [`fingerprint`]), set as its report.
pub(super) fn take_reports(extracted: &mut [Extracted], reached: &[Reached]) {
    if reached.is_empty() {
        return;
    }
    for e in extracted.iter_mut().filter(|e| e.report.is_none()) {
        let Some(mesh) = &e.mesh else { continue };
        let f = fingerprint(mesh);
        if let Some(r) = reached.iter().find(|r| r.fingerprint == f) {
            e.report = Some(r.report);
        }
    }
}

/// A state's live triangles over the vertices they use (numbered in order
/// of first use).
fn compact(s: &Snapshot) -> Mesh {
    let mut new = vec![u32::MAX; s.positions.len()];
    let mut positions = Vec::new();
    let triangles = s
        .triangles
        .iter()
        .map(|(_, t)| {
            t.map(|v| {
                let n = &mut new[v as usize];
                if *n == u32::MAX {
                    *n = positions.len() as u32;
                    positions.push(s.positions[v as usize]);
                }
                *n
            })
        })
        .collect();
    Mesh {
        positions,
        triangles,
    }
}

/// A mesh's triangles as a multiset of corner positions in corner order
/// (the bits of each): their count and the wrapping sum of a 64-bit hash
/// of each, which no numbering of the vertices or triangles changes.
fn fingerprint(m: &Mesh) -> (usize, u64) {
    let sum = m.triangles.iter().fold(0u64, |sum, t| {
        let h = t
            .iter()
            .flat_map(|&v| m.positions[v as usize])
            .fold(0x9e37_79b9_7f4a_7c15u64, |h, x| {
                mix(h ^ u64::from(x.to_bits()))
            });
        sum.wrapping_add(h)
    });
    (m.triangles.len(), sum)
}

/// SplitMix64's finaliser (Steele, Lea, Flood 2014).
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The whole path on a knot, default levels (50/10/2 %): the walk hands
    /// over the 50 % level only (10 % and 2 % are reached too late to hide
    /// their measurement), measured beside the walk; the extracted level
    /// takes that report, which is the measurement of the extracted level
    /// itself (distances, not numbering: maxima, RMS and means equal to
    /// 1e-12); the 10 % level takes none. Fails if the walk hands over the
    /// wrong state (no fingerprint matches), if the state's positions are
    /// not the level's, or if the watch keeps the measuring thread waiting
    /// after the walk (the test hangs).
    #[test]
    fn the_walks_level_takes_its_measured_report() {
        let knot = lodgen_pm::shapes::torus_knot(2, 3, 240, 20, 0.01);
        let n = knot.triangles.len();
        let opts = BuildOptions::default();
        let watched = watch_levels(&opts).expect("levels by ratio are watched");
        let states = (Arc::downgrade(&watched.watch), watched.states);
        let hooks = (None, Some(watched.watch));
        let indices: Vec<u32> = knot.triangles.iter().flatten().copied().collect();
        let sopts = lodgen_pm::SimplifyOptions::DEFAULT.with_target_triangles(n / 50);
        let mopts = MeasureOptions::DEFAULT;
        let mut welded = None;
        let (simplified, reached) = lodgen_pm::simplify_with_wedges_beside(
            &knot.positions,
            &indices,
            &[],
            0,
            &sopts,
            hooks,
            &mut welded,
            |w| {
                let r = Reference::new(MeshRef::new(&w.positions, &w.triangles)).unwrap();
                measure_reached(&r, states, &mopts).0
            },
        )
        .unwrap();
        assert_eq!(reached.len(), 1, "the 50 % level only");
        let pm = &simplified.pm;
        let counts = pm.triangle_counts();
        let full = pm.mesh_at_splits(pm.len());
        let original = Reference::new(MeshRef::new(&full.positions, &full.triangles)).unwrap();
        let mut levels: Vec<Extracted> = [n / 2, n / 10]
            .iter()
            .map(|&t| Extracted {
                primitives: Vec::new(),
                mesh: Some(pm.mesh_at_splits(counts.partition_point(|&c| c <= t) - 1)),
                deferred: None,
                report: None,
            })
            .collect();
        take_reports(&mut levels, &reached);
        let got = levels[0].report.expect("the 50 % level's report");
        assert!(levels[1].report.is_none());
        let level = levels[0].mesh.as_ref().unwrap();
        let want = original
            .measure(MeshRef::new(&level.positions, &level.triangles), &mopts)
            .unwrap();
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-30);
        for (a, b) in [(got.a_to_b, want.a_to_b), (got.b_to_a, want.b_to_a)] {
            assert!(a.max > 0.0);
            assert!(close(a.max, b.max) && close(a.rms, b.rms) && close(a.mean, b.mean));
            assert_eq!(a.samples, b.samples);
        }
    }

    /// The fingerprint follows the geometry, not the numbering: the same
    /// triangles renumbered (vertices and triangles permuted) match; a
    /// moved vertex, a rotated triangle or a missing one do not.
    #[test]
    fn fingerprints_tell_geometry_not_numbering() {
        let m = lodgen_pm::shapes::icosphere(1);
        let nv = m.positions.len();
        // vertices reversed, triangles reversed
        let positions: Vec<[f32; 3]> = m.positions.iter().rev().copied().collect();
        let triangles: Vec<[u32; 3]> = m
            .triangles
            .iter()
            .rev()
            .map(|t| t.map(|v| (nv - 1) as u32 - v))
            .collect();
        let renumbered = Mesh {
            positions,
            triangles,
        };
        assert_eq!(fingerprint(&m), fingerprint(&renumbered));
        let mut moved = m.clone();
        moved.positions[3][1] += 1e-6;
        assert_ne!(fingerprint(&m), fingerprint(&moved));
        let mut rotated = m.clone();
        rotated.triangles[0].rotate_left(1);
        assert_ne!(fingerprint(&m), fingerprint(&rotated));
        let mut fewer = m.clone();
        fewer.triangles.pop();
        assert_ne!(fingerprint(&m), fingerprint(&fewer));
    }
}
