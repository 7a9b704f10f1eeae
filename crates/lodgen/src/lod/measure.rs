//! A level's error: measured against the original (its hierarchy built
//! once per mesh, at the first measurement), or without measurement the
//! quadric's estimate; the time spent measuring is counted.
//!
//! The measurer does not hold the progressive mesh: the builder frees it
//! once the levels are extracted, before the original's hierarchy is built
//! (peak memory: at 4.4M triangles the two together were the run's peak).
//! A small mesh's hierarchy is built beside its simplification, over the
//! welded input, and renumbered (handed in with [`Measurer::set_reference`]),
//! or while the
//! levels are extracted ([`Measurer::prepare`] on another thread), and its
//! levels are measured side by side ([`Measurer::measure_levels`]): the
//! measurer is `Sync`.

use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

use rayon::prelude::*;

use lodgen_pm::metric::{
    Distance, ErrorReport, MeasureError, MeasureOptions, MeshRef, Reference, Spots,
};
use lodgen_pm::polish::{fix_worst, WorstOptions};
use lodgen_pm::{Mesh, ProgressiveMesh};

use super::error::BuildError;

/// Measures the levels of one mesh's progressive mesh.
pub(super) struct Measurer<'a> {
    /// The fully refined mesh, the original every level is measured against.
    full: &'a Mesh,
    /// Splits of the whole sequence: a level with as many is the original.
    splits: usize,
    /// Without measurement: for each split count k, the largest recorded
    /// contraction error of splits k.. (the quadric's estimate); empty when
    /// measuring.
    estimates: Vec<f32>,
    measured: bool,
    diagonal: f64,
    /// The original's hierarchy and sample order, built at the first
    /// measurement (or by [`Self::prepare`]) and used for every level.
    reference: OnceLock<Reference<'a>>,
    time: Mutex<Duration>,
    index: usize,
    name: &'a str,
}

impl<'a> Measurer<'a> {
    /// `full` is `pm` fully refined; `index` and `name` name the mesh in
    /// errors. `pm` is read here only.
    pub(super) fn new(
        pm: &ProgressiveMesh,
        full: &'a Mesh,
        measured: bool,
        index: usize,
        name: &'a str,
    ) -> Measurer<'a> {
        let mut estimates = Vec::new();
        if !measured {
            estimates = vec![0.0f32; pm.len() + 1];
            for (k, s) in pm.splits.iter().enumerate().rev() {
                estimates[k] = estimates[k + 1].max(s.error);
            }
        }
        Measurer {
            full,
            splits: pm.len(),
            estimates,
            measured,
            diagonal: full.diagonal(),
            reference: OnceLock::new(),
            time: Mutex::new(Duration::ZERO),
            index,
            name,
        }
    }

    /// [`Self::new`] for levels that are measured, made without the
    /// progressive mesh (which may be freed by then): `splits` is its
    /// length.
    pub(super) fn measured(
        splits: usize,
        full: &'a Mesh,
        index: usize,
        name: &'a str,
    ) -> Measurer<'a> {
        Measurer {
            full,
            splits,
            estimates: Vec::new(),
            measured: true,
            diagonal: full.diagonal(),
            reference: OnceLock::new(),
            time: Mutex::new(Duration::ZERO),
            index,
            name,
        }
    }

    /// The original's hierarchy, built at the first call.
    fn reference(&self) -> Result<&Reference<'a>, BuildError> {
        if let Some(r) = self.reference.get() {
            return Ok(r);
        }
        let t = Instant::now();
        let full = self.full;
        let r = Reference::new(MeshRef::new(&full.positions, &full.triangles))
            .map_err(|e| measure_err(self.index, self.name, MeasureError::A(e)))?;
        self.add_time(t.elapsed());
        Ok(self.reference.get_or_init(|| r))
    }

    /// Takes the original's hierarchy built elsewhere (beside the
    /// simplification, in `took`), over the mesh this measurer was made
    /// with.
    pub(super) fn set_reference(&self, r: Reference<'a>, took: Duration) {
        self.add_time(took);
        // (a measurer is given at most one, before any measurement)
        let _ = self.reference.set(r);
    }

    /// Builds the original's hierarchy now when the levels are measured
    /// (nothing otherwise), so that it can be built beside other work.
    pub(super) fn prepare(&self) -> Result<(), BuildError> {
        if self.measured && self.splits > 0 {
            self.reference()?;
        }
        Ok(())
    }

    fn add_time(&self, t: Duration) {
        // (a poisoned lock only means another measurement panicked)
        let mut time = self.time.lock().unwrap_or_else(|e| e.into_inner());
        *time += t;
    }

    /// The original (the fully refined mesh) the levels are measured
    /// against.
    pub(super) fn full(&self) -> &'a Mesh {
        self.full
    }

    /// The original's bounding-box diagonal.
    pub(super) fn diagonal(&self) -> f64 {
        self.diagonal
    }

    /// Time spent measuring so far (the hierarchy included; wall time, also
    /// when it overlapped other work).
    pub(super) fn time(&self) -> Duration {
        *self.time.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Without measurement (`measured == false`), a level's error is the
    /// largest recorded contraction error still in it (the quadric's
    /// estimate): the mesh after k splits still carries contractions k..
    fn estimate(&self, k: usize) -> ErrorReport {
        let e = f64::from(self.estimates[k.min(self.splits)]);
        let d = Distance {
            max: e,
            max_bound: f64::INFINITY,
            mean: f64::NAN,
            rms: f64::NAN,
            samples: 0,
            at: None,
            spots: Spots::NONE,
        };
        ErrorReport {
            a_to_b: d,
            b_to_a: d,
            diagonal: self.diagonal,
        }
    }

    /// The error of a level that is the original: 0 exactly, no samples
    /// needed (a scene of many small meshes kept whole spent most of its
    /// time measuring them against themselves).
    fn exact_zero(&self) -> ErrorReport {
        ErrorReport {
            a_to_b: Distance::NONE,
            b_to_a: Distance::NONE,
            diagonal: self.diagonal,
        }
    }

    /// The error of `m`, the mesh after `k` splits.
    pub(super) fn measure(
        &self,
        m: &Mesh,
        k: usize,
        mopts: &MeasureOptions,
    ) -> Result<ErrorReport, BuildError> {
        if !self.measured {
            return Ok(self.estimate(k));
        }
        if k >= self.splits {
            // every split applied: the level is the original itself (a
            // mesh below --min-triangles, a level at 100 %), its error 0
            return Ok(self.exact_zero());
        }
        let reference = self.reference()?;
        let t = Instant::now();
        let r = reference
            .measure(MeshRef::new(&m.positions, &m.triangles), mopts)
            .map_err(|e| measure_err(self.index, self.name, MeasureError::B(e)));
        self.add_time(t.elapsed());
        r
    }

    /// Fixes the worst spot of each of `levels` (a mesh and its split
    /// count) in place ([`lodgen_pm::polish::fix_worst`]), the levels side
    /// by side (each fix is its own: the results are those of one level
    /// after the other), and returns the error of each as it is left
    /// (measured); `None` when nothing is measured or the level is the
    /// original (nothing to fix: its error is 0).
    pub(super) fn fix_worst(
        &self,
        levels: &mut [(usize, Mesh)],
        mopts: &MeasureOptions,
        wopts: &WorstOptions,
    ) -> Result<Vec<Option<ErrorReport>>, BuildError> {
        if !self.measured || levels.iter().all(|&(k, _)| k >= self.splits) {
            return Ok(levels.iter().map(|_| None).collect());
        }
        let reference = self.reference()?;
        let t = Instant::now();
        let full = MeshRef::new(&self.full.positions, &self.full.triangles);
        let fixed = levels
            .par_iter_mut()
            .map(|(k, m)| {
                if *k >= self.splits {
                    return Ok(None);
                }
                fix_worst(reference, full, m, mopts, wopts)
                    .map(|f| Some(f.error))
                    .map_err(|e| measure_err(self.index, self.name, MeasureError::B(e)))
            })
            .collect();
        self.add_time(t.elapsed());
        fixed
    }

    /// The errors of `levels` (each a mesh and its split count, as for
    /// [`Self::measure`]), measured side by side: one level's sequential
    /// steps (its Z-order, its hierarchy's build) overlap another's queries.
    /// Each report is the one [`Self::measure`] gives, bit for bit.
    pub(super) fn measure_levels(
        &self,
        levels: &[(&Mesh, usize)],
        mopts: &MeasureOptions,
    ) -> Result<Vec<ErrorReport>, BuildError> {
        if !self.measured || levels.iter().all(|&(_, k)| k >= self.splits) {
            return levels
                .iter()
                .map(|&(m, k)| self.measure(m, k, mopts))
                .collect();
        }
        let reference = self.reference()?;
        let t = Instant::now();
        let r = levels
            .par_iter()
            .map(|&(m, k)| {
                if k >= self.splits {
                    return Ok(self.exact_zero());
                }
                reference
                    .measure(MeshRef::new(&m.positions, &m.triangles), mopts)
                    .map_err(|e| measure_err(self.index, self.name, MeasureError::B(e)))
            })
            .collect();
        self.add_time(t.elapsed());
        r
    }

    /// The error of the mesh after `k` splits of `pm` (the sequence this
    /// measurer was made for).
    pub(super) fn measure_at(
        &self,
        pm: &ProgressiveMesh,
        k: usize,
        mopts: &MeasureOptions,
    ) -> Result<ErrorReport, BuildError> {
        self.measure(&pm.mesh_at_splits(k), k, mopts)
    }
}

fn measure_err(index: usize, name: &str, source: MeasureError) -> BuildError {
    BuildError::Measure {
        index,
        name: name.to_string(),
        source,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The side-by-side measurement gives each level the report measuring it
    /// alone gives, bit for bit, in the levels' order (fails if the reports
    /// are paired with the wrong level, e.g. collected out of order, or if a
    /// level that is the original is measured instead of given 0).
    #[test]
    fn levels_measured_side_by_side_match_one_by_one() {
        let m = lodgen_pm::shapes::grid(24, 24, |x, y| 0.1 * (7.0 * x).sin() * (5.0 * y).cos());
        let indices: Vec<u32> = m.triangles.iter().flatten().copied().collect();
        let opts = lodgen_pm::SimplifyOptions::DEFAULT.with_target_ratio(0.05);
        let pm = lodgen_pm::simplify(&m.positions, &indices, &opts)
            .unwrap()
            .pm;
        let full = pm.mesh_at_splits(pm.len());
        let measurer = Measurer::new(&pm, &full, true, 0, "grid");
        let splits = [pm.len(), pm.len() / 2, pm.len() / 8, 0];
        let meshes: Vec<Mesh> = splits.iter().map(|&k| pm.mesh_at_splits(k)).collect();
        let levels: Vec<(&Mesh, usize)> = meshes.iter().zip(splits).collect();
        let mopts = MeasureOptions::DEFAULT;
        let together = measurer.measure_levels(&levels, &mopts).unwrap();
        let alone: Vec<ErrorReport> = levels
            .iter()
            .map(|&(m, k)| measurer.measure(m, k, &mopts).unwrap())
            .collect();
        assert_eq!(together, alone);
        assert_eq!(together[0].hausdorff(), 0.0);
        // the levels differ, so a mix-up shows
        assert!(together[1].hausdorff() < together[2].hausdorff());
        assert!(together[2].hausdorff() < together[3].hausdorff());
    }
}
