//! Level selection: the split count of every requested level (ratios and
//! counts of the welded mesh, or measured error bounds by binary search),
//! raised to the triangle floor, finest first without repeats.

use lodgen_pm::levels::{self, LevelSpec};
use lodgen_pm::ProgressiveMesh;

use super::error::BuildError;
use super::measure::Measurer;
use super::options::{BuildOptions, LevelRequest};

/// The split count of every level of `opts.levels`, finest first without
/// repeats, and the notes for the table. `measuring(level, of)` reports
/// progress while searching levels by error.
pub(super) fn select_splits(
    pm: &ProgressiveMesh,
    opts: &BuildOptions,
    measurer: &Measurer<'_>,
    measuring: &mut dyn FnMut(usize, usize),
) -> Result<(Vec<usize>, Vec<String>), BuildError> {
    // (levels by error measured first: the counts do not wait beside
    // the measurement)
    let by_error = match &opts.levels {
        LevelRequest::MaxErrors(bounds) => {
            Some(splits_by_error(pm, bounds, opts, measurer, measuring)?)
        }
        LevelRequest::Specs(_) => None,
    };
    // (once: each count walks every split, 2.2M of them at 4.4M triangles)
    let counts = pm.triangle_counts();
    let welded = counts.last().copied().unwrap_or(0);
    // the largest split count whose mesh has at most `t` triangles
    let splits_for_triangles = |t: usize| counts.partition_point(|&c| c <= t).saturating_sub(1);
    // Requested levels whose triangle count is below the floor.
    let floor = opts.min_triangles.max(1);
    let below_floor = match &opts.levels {
        LevelRequest::Specs(specs) => specs
            .iter()
            .filter(|s| match **s {
                LevelSpec::Ratio(r) => {
                    ((r.clamp(0.0, 1.0) * welded as f64).floor() as usize) < floor
                }
                LevelSpec::Triangles(t) => t < floor,
                LevelSpec::MaxError(_) => false,
            })
            .count(),
        LevelRequest::MaxErrors(_) => 0,
    };
    // Split counts, finest first, without repeats.
    let mut splits: Vec<usize> = match (&opts.levels, by_error) {
        (_, Some(splits)) => splits,
        (LevelRequest::Specs(specs), None) => specs
            .iter()
            .map(|s| match *s {
                // ratios of the welded mesh's triangles
                LevelSpec::Ratio(r) => {
                    splits_for_triangles((r.clamp(0.0, 1.0) * welded as f64).floor() as usize)
                }
                LevelSpec::Triangles(t) => splits_for_triangles(t),
                other => levels::splits_for(pm, other),
            })
            .collect(),
        (LevelRequest::MaxErrors(_), None) => Vec::new(),
    };
    let notes = apply_floor(&counts, opts.min_triangles, &mut splits, below_floor);
    Ok((splits, notes))
}

/// Per bound (a fraction of the diagonal): the coarsest k whose measured
/// error is within it, by binary search with a lighter sampling while
/// searching (without measurement, by the recorded errors).
fn splits_by_error(
    pm: &ProgressiveMesh,
    bounds: &[f64],
    opts: &BuildOptions,
    measurer: &Measurer<'_>,
    measuring: &mut dyn FnMut(usize, usize),
) -> Result<Vec<usize>, BuildError> {
    let coarse = opts
        .measure
        .with_samples_per_triangle((opts.measure.samples_per_triangle / 4.0).max(0.25));
    let mut out = Vec::new();
    for (li, &b) in bounds.iter().enumerate() {
        measuring(li, bounds.len());
        let bound = b * measurer.diagonal();
        if !opts.measured {
            out.push(levels::splits_for(pm, LevelSpec::MaxError(bound)));
            continue;
        }
        let (mut lo, mut hi) = (0usize, pm.len());
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if measurer.measure_at(pm, mid, &coarse)?.hausdorff() <= bound {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        out.push(lo);
    }
    Ok(out)
}

/// Raise every level to the triangle floor (`min_triangles`, at least 1, at
/// most the whole mesh: a level is never empty), then order the split counts
/// finest first without repeats. `below` counts the requested levels known
/// to ask for fewer triangles than the floor. Returns the notes for the
/// table.
fn apply_floor(
    counts: &[usize],
    min_triangles: usize,
    splits: &mut Vec<usize>,
    below: usize,
) -> Vec<String> {
    let full = counts.last().copied().unwrap_or(0);
    let floor = min_triangles.max(1).min(full);
    // counts never decrease with k: the first k with enough triangles
    let k_floor = counts.partition_point(|&c| c < floor);
    let requested = splits.len();
    let mut raised = 0;
    for k in splits.iter_mut() {
        if *k < k_floor {
            *k = k_floor;
            raised += 1;
        }
    }
    splits.sort_unstable_by(|a, b| b.cmp(a));
    splits.dedup();
    let mut notes = Vec::new();
    let below = below.max(raised);
    if below > 0 {
        let kept = counts.get(k_floor).copied().unwrap_or(full);
        notes.push(format!(
            "{below} of {requested} requested levels ask for fewer than {} triangles \
             (--min-triangles) and keep {kept}{}; levels that coincide are written once: \
             {} of {requested} written",
            min_triangles.max(1),
            if kept == full { ", the whole mesh" } else { "" },
            splits.len()
        ));
    }
    notes
}
