//! The Python extension module `lodgen._lodgen` (cargo feature `python`,
//! built by maturin from `crates/lodgen/pyproject.toml`). The Python package
//! `lodgen` (crates/lodgen/python/lodgen) wraps it: keyword options become
//! the command line's flags, parsed here by the CLI's own [`BuildArgs`], so
//! options, defaults and error messages are the command's.
//!
//! Every call copies its NumPy inputs, then releases the GIL
//! (`Python::detach`) for the work. Errors raise `lodgen.LodgenError` (a
//! `ValueError`) with the CLI's message, causes joined by ": ". The long
//! calls (`simplify`, `progressive`, `build`, `batch`) run their work on a
//! thread of their own while the calling thread keeps running Python's
//! signal handlers ([`interruptible`]): Ctrl-C raises `KeyboardInterrupt`
//! within moments instead of after the work, and stops the work.

use crate::cli::{self, BuildArgs};
use crate::lod;
use crate::scene::{Primitive, Scene, SourceMesh};
use clap::Parser;
use lodgen_pm::metric::measure::{measure as measure_meshes, ErrorReport, MeasureOptions};
use lodgen_pm::metric::MeshRef;
use lodgen_pm::{Cursor, Mesh, ProgressiveMesh};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::mpsc::{channel, RecvTimeoutError};
use std::sync::Arc;
use std::time::Duration;

pyo3::create_exception!(
    lodgen,
    LodgenError,
    PyValueError,
    "A mesh, option or file lodgen cannot use; the message is the command line's."
);

/// The command line's build arguments, parsed from `argv` (without the
/// program name).
#[derive(Parser, Debug)]
#[command(name = "lodgen")]
struct Options {
    #[command(flatten)]
    build: BuildArgs,
}

fn parse(argv: Vec<String>) -> PyResult<BuildArgs> {
    let args = std::iter::once("lodgen".to_string()).chain(argv);
    Options::try_parse_from(args).map(|o| o.build).map_err(|e| {
        let text = e.to_string();
        let first = text.lines().next().unwrap_or_default();
        LodgenError::new_err(first.trim_start_matches("error: ").to_string())
    })
}

/// The CLI's error chain on one line, without repeats
/// ([`crate::cli::error_line`]).
fn error(e: anyhow::Error) -> PyErr {
    LodgenError::new_err(crate::cli::error_line(&e))
}

/// How often a long call's waiting thread runs Python's signal handlers.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Runs `work` with the GIL released (as `py.detach` does) on a thread of
/// its own, while this thread runs Python's signal handlers every
/// [`SIGNAL_POLL`] (`PyErr_CheckSignals`, which does so on the main thread
/// only). The first exception a handler raises (`KeyboardInterrupt` on
/// Ctrl-C) cancels `meter` — the simplification stops at its next batch
/// or round, the build before its next phase, a batch before its next
/// file — and is raised once `work` has returned, whatever it returned.
fn interruptible<T, F>(py: Python<'_>, meter: &lodgen_pm::Meter, work: F) -> PyResult<T>
where
    F: FnOnce() -> T + Send,
    T: Send,
{
    py.detach(|| {
        std::thread::scope(|s| {
            let (done, finished) = channel::<()>();
            // (the stack of a main thread: the work ran on the caller's)
            let worker = std::thread::Builder::new()
                .stack_size(8 << 20)
                .spawn_scoped(s, move || {
                    let out = work();
                    let _ = done.send(());
                    out
                })
                .map_err(|e| LodgenError::new_err(format!("starting a thread: {e}")))?;
            let mut raised = None;
            // (a panic drops `done`: Disconnected, then join passes it on)
            while let Err(RecvTimeoutError::Timeout) = finished.recv_timeout(SIGNAL_POLL) {
                if raised.is_none() {
                    if let Err(e) = Python::attach(|py| py.check_signals()) {
                        meter.cancel();
                        raised = Some(e);
                    }
                }
            }
            let out = worker
                .join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p));
            raised.map_or(Ok(out), Err)
        })
    })
}

type Arrays<'py> = (
    Bound<'py, numpy::PyArray2<f32>>,
    Bound<'py, numpy::PyArray2<u32>>,
);

fn arrays<'py>(
    py: Python<'py>,
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
) -> PyResult<Arrays<'py>> {
    let v =
        PyArray1::from_vec(py, positions.as_flattened().to_vec()).reshape([positions.len(), 3])?;
    let f =
        PyArray1::from_vec(py, triangles.as_flattened().to_vec()).reshape([triangles.len(), 3])?;
    Ok((v, f))
}

/// Vertices (n, 3) float32 and faces (m, 3) int64 (C-contiguous; the
/// Python side converts) into the core's types.
fn mesh_in(
    vertices: &PyReadonlyArray2<'_, f32>,
    faces: &PyReadonlyArray2<'_, i64>,
) -> PyResult<(Vec<[f32; 3]>, Vec<u32>)> {
    if vertices.shape()[1] != 3 || faces.shape()[1] != 3 {
        return Err(LodgenError::new_err(format!(
            "vertices must have shape (n, 3) and faces (m, 3), not {:?} and {:?}",
            vertices.shape(),
            faces.shape()
        )));
    }
    let v = vertices
        .as_slice()
        .map_err(|e| LodgenError::new_err(e.to_string()))?;
    let f = faces
        .as_slice()
        .map_err(|e| LodgenError::new_err(e.to_string()))?;
    let n = v.len() / 3;
    let mut indices = Vec::with_capacity(f.len());
    for (k, &i) in f.iter().enumerate() {
        // The readers check indices before the LOD builder sees them; so
        // does this (the core's message).
        if i < 0 || i >= n as i64 {
            return Err(LodgenError::new_err(format!(
                "triangle {} refers to vertex {i}, but there are only {n} vertices",
                k / 3
            )));
        }
        indices.push(i as u32);
    }
    Ok((
        v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        indices,
    ))
}

/// An error report as the tuple the Python side names: diagonal, then
/// symmetric Hausdorff, mean, RMS, then A→B max, mean, RMS, samples, then
/// B→A max, mean, RMS, samples (mesh units).
fn report_tuple(r: &ErrorReport) -> Vec<f64> {
    vec![
        r.diagonal,
        r.hausdorff(),
        r.mean(),
        r.rms(),
        r.a_to_b.max,
        r.a_to_b.mean,
        r.a_to_b.rms,
        r.a_to_b.samples as f64,
        r.b_to_a.max,
        r.b_to_a.mean,
        r.b_to_a.rms,
        r.b_to_a.samples as f64,
    ]
}

type LevelOut<'py> = (
    Bound<'py, numpy::PyArray2<f32>>,
    Bound<'py, numpy::PyArray2<u32>>,
    Vec<f64>,
    usize,
);

/// `simplify(vertices, faces, argv)`: the CLI's LOD build of one mesh.
/// Returns per level (vertices, faces, error tuple, splits), the
/// progressive mesh the levels were cut from, the stop note (empty
/// when every level was reached) and whether the errors were measured
/// (false with `--measure off`: the quadric's estimates, mean and RMS NaN).
#[pyfunction]
fn simplify<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f32>,
    faces: PyReadonlyArray2<'py, i64>,
    argv: Vec<String>,
) -> PyResult<(Vec<LevelOut<'py>>, PyProgressiveMesh, String, bool)> {
    let args = parse(argv)?;
    let (positions, indices) = mesh_in(&vertices, &faces)?;
    let triangles = indices.len() / 3;
    let scene = Scene {
        meshes: vec![SourceMesh {
            name: String::new(),
            primitives: vec![Primitive {
                positions,
                indices,
                ..Primitive::default()
            }],
        }],
        ..Scene::default()
    };
    let meter = Arc::new(lodgen_pm::Meter::default());
    let build = interruptible(py, &meter, || -> anyhow::Result<lod::MeshBuild> {
        let mut opts = args.build_options()?;
        opts.meter = Some(Arc::clone(&meter));
        if opts.measured {
            cli::check_sample_count(&opts.measure, triangles, triangles)?;
        }
        let builds = lod::build_lods(&scene, &opts, &mut |_| {})
            .map_err(anyhow::Error::from)
            .map_err(|e| e.context("simplifying"))?;
        builds
            .into_iter()
            .next()
            .ok_or_else(|| anyhow::anyhow!("simplifying: the mesh has no triangles"))
    })?
    .map_err(error)?;
    let mut levels = Vec::new();
    for ((l, e), s) in build
        .lod
        .levels
        .iter()
        .zip(&build.errors)
        .zip(&build.level_splits)
    {
        let mut positions: Vec<[f32; 3]> = Vec::new();
        let mut triangles: Vec<[u32; 3]> = Vec::new();
        for p in &l.primitives {
            let off = positions.len() as u32;
            positions.extend_from_slice(&p.positions);
            triangles.extend(
                p.indices
                    .chunks_exact(3)
                    .map(|c| [c[0] + off, c[1] + off, c[2] + off]),
            );
        }
        let (v, f) = arrays(py, &positions, &triangles)?;
        levels.push((v, f, report_tuple(e), *s));
    }
    // (what the command prints under the mesh's table: why the run stopped
    // short, and the build's notes — levels raised to the floor, levels
    // that coincide)
    let st = &build.simplified;
    let mut notes = Vec::new();
    if st.stop != lodgen_pm::StopReason::Target {
        notes.push(cli::stop_note(st.stop, &st.stats));
    }
    notes.extend(build.notes.iter().cloned());
    let note = notes.join("; ");
    let measured = build.measured;
    let simplified = build.simplified;
    Ok((
        levels,
        PyProgressiveMesh::new(
            simplified.pm,
            simplified.vertex_map,
            simplified.triangle_map,
        ),
        note,
        measured,
    ))
}

/// `progressive(vertices, faces, argv, target_triangles)`: simplify as far
/// as possible (or to the target) and keep the whole vertex-split log.
#[pyfunction]
#[pyo3(signature = (vertices, faces, argv, target_triangles=None))]
fn progressive<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f32>,
    faces: PyReadonlyArray2<'py, i64>,
    argv: Vec<String>,
    target_triangles: Option<usize>,
) -> PyResult<PyProgressiveMesh> {
    let args = parse(argv)?;
    let (positions, indices) = mesh_in(&vertices, &faces)?;
    let meter = Arc::new(lodgen_pm::Meter::default());
    let s = interruptible(py, &meter, || -> anyhow::Result<lodgen_pm::Simplified> {
        let mut opts = args.build_options()?.simplify;
        if let Some(t) = target_triangles {
            opts = opts.with_target_triangles(t);
        }
        let m = Some(Arc::clone(&meter));
        lodgen_pm::simplify_metered(&positions, &indices, &opts, m)
            .map_err(|e| anyhow::Error::from(e).context("simplifying"))
    })?
    .map_err(error)?;
    Ok(PyProgressiveMesh::new(s.pm, s.vertex_map, s.triangle_map))
}

/// `measure(av, af, bv, bf, samples)`: the distance between two meshes,
/// as the tuple of [`report_tuple`].
#[pyfunction]
fn measure<'py>(
    py: Python<'py>,
    av: PyReadonlyArray2<'py, f32>,
    af: PyReadonlyArray2<'py, i64>,
    bv: PyReadonlyArray2<'py, f32>,
    bf: PyReadonlyArray2<'py, i64>,
    samples: f64,
) -> PyResult<Vec<f64>> {
    if !(samples > 0.0 && samples.is_finite()) {
        return Err(LodgenError::new_err("--samples must be positive"));
    }
    let (ap, ai) = mesh_in(&av, &af)?;
    let (bp, bi) = mesh_in(&bv, &bf)?;
    let tri =
        |i: &[u32]| -> Vec<[u32; 3]> { i.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect() };
    let (at, bt) = (tri(&ai), tri(&bi));
    let opts = MeasureOptions::DEFAULT.with_samples_per_triangle(samples);
    cli::check_sample_count(&opts, at.len(), bt.len()).map_err(error)?;
    // (no distance to measure, rather than an infinite one; as the
    // command's "no triangles")
    for (name, t) in [("a", &at), ("b", &bt)] {
        if t.is_empty() {
            return Err(LodgenError::new_err(format!(
                "measuring: mesh {name} has no triangles"
            )));
        }
    }
    let r = py
        .detach(|| measure_meshes(MeshRef::new(&ap, &at), MeshRef::new(&bp, &bt), &opts))
        .map_err(|e| error(anyhow::Error::from(e).context("measuring")))?;
    Ok(report_tuple(&r))
}

/// `build(input, output, argv, threads)`: `lodgen INPUT -o OUTPUT
/// FLAGS...` without printing, on a pool of `threads` threads (default: all
/// cores); returns the file's `--report` JSON.
#[pyfunction]
#[pyo3(signature = (input, output, argv, threads=None))]
fn build(
    py: Python<'_>,
    input: PathBuf,
    output: Option<PathBuf>,
    argv: Vec<String>,
    threads: Option<usize>,
) -> PyResult<String> {
    let args = parse(argv)?;
    let output = output.unwrap_or_else(|| cli::default_output(&input));
    let meter = Arc::new(lodgen_pm::Meter::default());
    interruptible(py, &meter, || -> anyhow::Result<String> {
        // (a report that cannot be written would leave the output behind)
        cli::check_report_path(&args)?;
        cli::check_report_targets(&args, &input, &output)?;
        if let Some(parent) = output.parent().filter(|p| !p.as_os_str().is_empty()) {
            anyhow::Context::with_context(std::fs::create_dir_all(parent), || {
                format!(
                    "writing {}: creating {}",
                    output.display(),
                    parent.display()
                )
            })?;
        }
        let m = || Some(Arc::clone(&meter));
        let run = || cli::build_file_metered(&input, &output, &args, &mut |_| {}, m());
        let built = match threads {
            Some(n) => rayon::ThreadPoolBuilder::new()
                .num_threads(n.max(1))
                .build()?
                .install(run)?,
            None => run()?,
        };
        if let Some(path) = &args.report {
            cli::write_report(path, &built.report_json(&input))?;
        }
        Ok(serde_json::to_string(&built.report_json(&input))?)
    })?
    .map_err(error)
}

/// `batch(inputs, out_dir, argv)`: `lodgen INPUTS... --out-dir DIR` without
/// printing; returns the batch `--report` JSON (failures are in it).
#[pyfunction]
fn batch(
    py: Python<'_>,
    inputs: Vec<PathBuf>,
    out_dir: PathBuf,
    argv: Vec<String>,
) -> PyResult<String> {
    let mut args = parse(argv)?;
    args.inputs = inputs;
    args.batch.out_dir = Some(out_dir.clone());
    let meter = Arc::new(lodgen_pm::Meter::default());
    interruptible(py, &meter, || -> anyhow::Result<String> {
        if args.batch.jobs == 0 {
            anyhow::bail!("--jobs must be at least 1");
        }
        let inputs = crate::batch::expand_inputs(&args.inputs, Some(&out_dir))?;
        let m = Some(Arc::clone(&meter));
        let outcome =
            crate::batch::run_batch_watched(&inputs, &out_dir, &args, &|_| {}, &|_, _| {}, m)?;
        if let Some(e) = &outcome.manifest_error {
            anyhow::bail!("{e}");
        }
        Ok(serde_json::to_string(&outcome.report_json())?)
    })?
    .map_err(error)
}

/// `read(path)`: every mesh a file's scene draws, merged (as `lodgen
/// measure` reads it): positions and triangles.
#[pyfunction]
fn read(py: Python<'_>, path: PathBuf) -> PyResult<Arrays<'_>> {
    let m = py
        .detach(|| -> anyhow::Result<Mesh> {
            let scene = crate::io::read_scene(&path).map_err(|e| {
                anyhow::Error::from(e).context(format!("reading {}", path.display()))
            })?;
            Ok(cli::merged_mesh(&scene))
        })
        .map_err(error)?;
    arrays(py, &m.positions, &m.triangles)
}

/// `expand(inputs, out_dir)`: batch mode's inputs (files, directories,
/// globs) with each output's path relative to `out_dir`, in batch order.
#[pyfunction]
fn expand(inputs: Vec<PathBuf>, out_dir: PathBuf) -> PyResult<Vec<(PathBuf, PathBuf)>> {
    let list = crate::batch::expand_inputs(&inputs, Some(&out_dir)).map_err(error)?;
    Ok(list
        .into_iter()
        .map(|i| (i.input, i.relative_output))
        .collect())
}

self_cell::self_cell!(
    struct PmCell {
        owner: ProgressiveMesh,
        #[covariant]
        dependent: Cursor,
    }
);

/// A progressive mesh with a cursor (native part of
/// `lodgen.ProgressiveMesh`).
///
/// Shared between Python threads: every call takes the object's lock with
/// the GIL released (a call that waited for it holding the GIL would keep
/// the thread inside from finishing), and works under it; so calls from
/// several threads run one after the other, never into a borrow error.
#[pyclass(module = "lodgen._lodgen", name = "ProgressiveMesh")]
pub struct PyProgressiveMesh {
    cell: std::sync::Mutex<PmCell>,
    vertex_map: Vec<u32>,
    triangle_map: Vec<u32>,
}

impl PyProgressiveMesh {
    fn new(pm: ProgressiveMesh, vertex_map: Vec<u32>, triangle_map: Vec<u32>) -> Self {
        PyProgressiveMesh {
            cell: std::sync::Mutex::new(PmCell::new(pm, |pm| pm.cursor())),
            vertex_map,
            triangle_map,
        }
    }

    /// `f` on the progressive mesh and its cursor, under the lock, the GIL
    /// released.
    fn locked<R: Send>(&self, py: Python<'_>, f: impl FnOnce(&mut PmCell) -> R + Send) -> R {
        py.detach(|| {
            let mut cell = self.cell.lock().unwrap_or_else(|e| e.into_inner());
            f(&mut cell)
        })
    }
}

fn u32s<'py>(py: Python<'py>, v: &[u32]) -> Bound<'py, PyArray1<u32>> {
    PyArray1::from_vec(py, v.to_vec())
}

#[pymethods]
impl PyProgressiveMesh {
    fn __len__(&self, py: Python<'_>) -> usize {
        self.locked(py, |c| c.borrow_owner().len())
    }

    /// Splits applied at the cursor.
    #[getter]
    fn applied(&self, py: Python<'_>) -> usize {
        self.locked(py, |c| c.borrow_dependent().applied())
    }

    fn triangle_counts<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u64>> {
        let c: Vec<u64> = self.locked(py, |c| {
            let counts = c.borrow_owner().triangle_counts();
            counts.into_iter().map(|n| n as u64).collect()
        });
        PyArray1::from_vec(py, c)
    }

    fn splits_for_triangles(&self, py: Python<'_>, triangles: usize) -> usize {
        self.locked(py, |c| c.borrow_owner().splits_for_triangles(triangles))
    }

    fn mesh_at_splits<'py>(&self, py: Python<'py>, k: usize) -> PyResult<Arrays<'py>> {
        let m: Mesh = self.locked(py, |c| c.borrow_owner().mesh_at_splits(k));
        arrays(py, &m.positions, &m.triangles)
    }

    fn full_in_input_order<'py>(&self, py: Python<'py>) -> PyResult<Arrays<'py>> {
        let m: Mesh = self.locked(py, |c| c.borrow_owner().full_in_input_order());
        arrays(py, &m.positions, &m.triangles)
    }

    fn mesh<'py>(&self, py: Python<'py>) -> PyResult<Arrays<'py>> {
        let (p, t) = self.locked(py, |c| {
            let m = c.borrow_dependent().mesh();
            (m.positions.clone(), m.triangles.clone())
        });
        arrays(py, &p, &t)
    }

    fn refine(&self, py: Python<'_>, n: usize) -> usize {
        self.locked(py, |cell| cell.with_dependent_mut(|_, c| c.refine(n)))
    }

    fn coarsen(&self, py: Python<'_>, n: usize) -> usize {
        self.locked(py, |cell| cell.with_dependent_mut(|_, c| c.coarsen(n)))
    }

    fn seek(&self, py: Python<'_>, k: usize) {
        self.locked(py, |cell| {
            let len = cell.borrow_owner().len();
            cell.with_dependent_mut(|_, c| c.seek(k.min(len)))
        })
    }

    #[getter]
    fn vertex_origin<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_vec(
            py,
            self.locked(py, |c| c.borrow_owner().vertex_origin.clone()),
        )
    }

    #[getter]
    fn triangle_origin<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_vec(
            py,
            self.locked(py, |c| c.borrow_owner().triangle_origin.clone()),
        )
    }

    #[getter]
    fn vertex_map<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        u32s(py, &self.vertex_map)
    }

    #[getter]
    fn triangle_map<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        u32s(py, &self.triangle_map)
    }

    /// The splits as columns: v1, v0 (u32), p1, p_merged, p0 (n×3 f32 flat),
    /// every split's restored faces one after the other (F×3 u32 flat), its
    /// moved corners likewise (C×2 u32 flat: triangle, slot), n_faces and
    /// n_corners per split (u32), error (f32).
    #[allow(clippy::type_complexity)]
    fn split_columns<'py>(
        &self,
        py: Python<'py>,
    ) -> (
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray1<f32>>,
        Bound<'py, PyArray1<f32>>,
        Bound<'py, PyArray1<f32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray1<f32>>,
    ) {
        let c = self.locked(py, |c| SplitColumns::of(&c.borrow_owner().splits));
        (
            PyArray1::from_vec(py, c.v1),
            PyArray1::from_vec(py, c.v0),
            PyArray1::from_vec(py, c.p1),
            PyArray1::from_vec(py, c.pm),
            PyArray1::from_vec(py, c.p0),
            PyArray1::from_vec(py, c.faces),
            PyArray1::from_vec(py, c.corners),
            PyArray1::from_vec(py, c.nf),
            PyArray1::from_vec(py, c.nc),
            PyArray1::from_vec(py, c.err),
        )
    }
}

/// The splits as columns ([`PyProgressiveMesh::split_columns`]).
struct SplitColumns {
    v1: Vec<u32>,
    v0: Vec<u32>,
    p1: Vec<f32>,
    pm: Vec<f32>,
    p0: Vec<f32>,
    faces: Vec<u32>,
    corners: Vec<u32>,
    nf: Vec<u32>,
    nc: Vec<u32>,
    err: Vec<f32>,
}

impl SplitColumns {
    fn of(s: &[lodgen_pm::VertexSplit]) -> SplitColumns {
        let n = s.len();
        let (mut v1, mut v0) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let (mut p1, mut pm, mut p0) = (
            Vec::with_capacity(3 * n),
            Vec::with_capacity(3 * n),
            Vec::with_capacity(3 * n),
        );
        // every split's restored faces and moved corners, one after the
        // other (most splits restore two faces and move a few corners)
        let (mut faces, mut corners) = (Vec::with_capacity(6 * n), Vec::with_capacity(8 * n));
        let (mut nf, mut nc, mut err) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        for x in s {
            v1.push(x.v1);
            v0.push(x.v0);
            p1.extend_from_slice(&x.p1);
            pm.extend_from_slice(&x.p_merged);
            p0.extend_from_slice(&x.p0);
            for f in &x.faces {
                faces.extend_from_slice(f);
            }
            for c in &x.corners {
                corners.extend_from_slice(&[c.triangle, u32::from(c.slot)]);
            }
            nf.push(x.faces.len() as u32);
            nc.push(x.corners.len() as u32);
            err.push(x.error);
        }
        SplitColumns {
            v1,
            v0,
            p1,
            pm,
            p0,
            faces,
            corners,
            nf,
            nc,
            err,
        }
    }
}

/// The native module: `lodgen._lodgen`.
#[pymodule]
fn _lodgen(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("LodgenError", m.py().get_type::<LodgenError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<PyProgressiveMesh>()?;
    m.add_function(wrap_pyfunction!(simplify, m)?)?;
    m.add_function(wrap_pyfunction!(progressive, m)?)?;
    m.add_function(wrap_pyfunction!(measure, m)?)?;
    m.add_function(wrap_pyfunction!(build, m)?)?;
    m.add_function(wrap_pyfunction!(batch, m)?)?;
    m.add_function(wrap_pyfunction!(expand, m)?)?;
    m.add_function(wrap_pyfunction!(read, m)?)?;
    Ok(())
}
