//! A level's error: measured against the original (its hierarchy built
//! once per mesh), or without measurement the quadric's estimate; the time
//! spent measuring is counted.

use std::cell::Cell;
use std::time::{Duration, Instant};

use lodgen_pm::metric::{Distance, ErrorReport, MeasureError, MeasureOptions, MeshRef, Reference};
use lodgen_pm::{Mesh, ProgressiveMesh};

use super::error::BuildError;

/// Measures the levels of one mesh's progressive mesh.
pub(super) struct Measurer<'a> {
    pm: &'a ProgressiveMesh,
    diagonal: f64,
    /// The original's hierarchy and sample order, built once for every
    /// level; `None` without measurement.
    reference: Option<Reference<'a>>,
    time: Cell<Duration>,
    index: usize,
    name: &'a str,
}

impl<'a> Measurer<'a> {
    /// `full` is `pm` fully refined; `index` and `name` name the mesh in
    /// errors.
    pub(super) fn new(
        pm: &'a ProgressiveMesh,
        full: &'a Mesh,
        measured: bool,
        index: usize,
        name: &'a str,
    ) -> Result<Measurer<'a>, BuildError> {
        let diagonal = full.diagonal();
        let t_measure = Instant::now();
        let reference = if measured {
            Some(
                Reference::new(MeshRef::new(&full.positions, &full.triangles))
                    .map_err(|e| measure_err(index, name, MeasureError::A(e)))?,
            )
        } else {
            None
        };
        Ok(Measurer {
            pm,
            diagonal,
            reference,
            time: Cell::new(t_measure.elapsed()),
            index,
            name,
        })
    }

    /// The original's bounding-box diagonal.
    pub(super) fn diagonal(&self) -> f64 {
        self.diagonal
    }

    /// Time spent measuring so far (the hierarchy included).
    pub(super) fn time(&self) -> Duration {
        self.time.get()
    }

    /// Without measurement (`measured == false`), a level's error is the
    /// largest recorded contraction error still in it (the quadric's
    /// estimate): the mesh after k splits still carries contractions k..
    fn estimate(&self, k: usize) -> ErrorReport {
        let pm = self.pm;
        let e = pm.splits[k.min(pm.splits.len())..]
            .iter()
            .map(|s| f64::from(s.error))
            .fold(0.0, f64::max);
        let d = Distance {
            max: e,
            max_bound: f64::INFINITY,
            mean: f64::NAN,
            rms: f64::NAN,
            samples: 0,
            at: None,
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
        let Some(reference) = &self.reference else {
            return Ok(self.estimate(k));
        };
        if k >= self.pm.splits.len() {
            // every split applied: the level is the original itself (a
            // mesh below --min-triangles, a level at 100 %), its error 0
            return Ok(self.exact_zero());
        }
        let t = Instant::now();
        let r = reference
            .measure(MeshRef::new(&m.positions, &m.triangles), mopts)
            .map_err(|e| measure_err(self.index, self.name, MeasureError::B(e)));
        self.time.set(self.time.get() + t.elapsed());
        r
    }

    /// The error of the mesh after `k` splits.
    pub(super) fn measure_at(
        &self,
        k: usize,
        mopts: &MeasureOptions,
    ) -> Result<ErrorReport, BuildError> {
        self.measure(&self.pm.mesh_at_splits(k), k, mopts)
    }
}

fn measure_err(index: usize, name: &str, source: MeasureError) -> BuildError {
    BuildError::Measure {
        index,
        name: name.to_string(),
        source,
    }
}
