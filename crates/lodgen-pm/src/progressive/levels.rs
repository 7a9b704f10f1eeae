//! Choosing levels on the vertex-split log: by triangle count, ratio, or
//! recorded error. Owns no geometry; measuring real error is `measure`'s job.

use crate::progressive::ProgressiveMesh;

/// A requested level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LevelSpec {
    /// Fraction of the full mesh's triangles (0.5 = 50 %).
    Ratio(f64),
    /// At most this many triangles.
    Triangles(usize),
    /// The coarsest prefix whose recorded contraction errors (mesh units)
    /// are all at most this.
    MaxError(f64),
}

/// The split count of the level `spec` asks for.
pub fn splits_for(pm: &ProgressiveMesh, spec: LevelSpec) -> usize {
    let full = pm.base.triangles.len() + pm.splits.iter().map(|s| s.faces.len()).sum::<usize>();
    match spec {
        LevelSpec::Ratio(r) => {
            pm.splits_for_triangles((r.clamp(0.0, 1.0) * full as f64).floor() as usize)
        }
        LevelSpec::Triangles(t) => pm.splits_for_triangles(t),
        LevelSpec::MaxError(e) => {
            // the mesh after k splits still carries contractions k.. (coarse
            // → fine order); its error is their maximum: a suffix maximum,
            // non-increasing in k.
            let mut k = pm.splits.len();
            while k > 0 && f64::from(pm.splits[k - 1].error) <= e {
                k -= 1;
            }
            k
        }
    }
}

/// The triangle target the simplifier must reach so that every spec can be
/// cut from one log: the smallest requested count. `None` for error specs
/// (the simplifier must then run to its error bound).
pub fn triangle_target(full_triangles: usize, specs: &[LevelSpec]) -> Option<usize> {
    specs
        .iter()
        .map(|s| match *s {
            LevelSpec::Ratio(r) => {
                Some((r.clamp(0.0, 1.0) * full_triangles as f64).floor() as usize)
            }
            LevelSpec::Triangles(t) => Some(t),
            LevelSpec::MaxError(_) => None,
        })
        .try_fold(usize::MAX, |m, t| t.map(|t| m.min(t)))
}
