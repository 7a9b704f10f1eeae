//! A level's error: measured against the original (its hierarchy built
//! once per mesh, at the first measurement), or without measurement the
//! quadric's estimate; the time spent measuring is counted.
//!
//! The measurer does not hold the progressive mesh: the builder frees it
//! once the levels are extracted, before the original's hierarchy is built
//! (peak memory: at 4.4M triangles the two together were the run's peak).

use std::cell::{Cell, OnceCell};
use std::time::{Duration, Instant};

use lodgen_pm::metric::{Distance, ErrorReport, MeasureError, MeasureOptions, MeshRef, Reference};
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
    /// measurement and used for every level.
    reference: OnceCell<Reference<'a>>,
    time: Cell<Duration>,
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
            reference: OnceCell::new(),
            time: Cell::new(Duration::ZERO),
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
        self.time.set(self.time.get() + t.elapsed());
        Ok(self.reference.get_or_init(|| r))
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
        let e = f64::from(self.estimates[k.min(self.splits)]);
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
        self.time.set(self.time.get() + t.elapsed());
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
