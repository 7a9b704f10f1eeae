//! Batch mode: `lodgen INPUT... --out-dir DIR [--jobs N] [--force]`.
//!
//! Inputs are files, directories (walked recursively for the formats lodgen
//! reads) and glob patterns; each output keeps its input's path relative to
//! the directory (or the glob's fixed prefix) it was found under, with
//! `.glb`. Files run on `--jobs` worker threads (largest input first, so no
//! worker is left alone with a big file at the end), each with its own rayon
//! pool of `cores / jobs` threads, so the machine is not oversubscribed;
//! every file runs exactly the single-file build ([`cli::build_file`]), so
//! its bytes are those of `lodgen INPUT -o OUTPUT`. A failing file (even a
//! panic) is reported and never stops the others.
//!
//! Incremental: `DIR/.lodgen-manifest.json` records, per output, the BLAKE3
//! hash of its input (with the files it refers to: a `.gltf`'s buffers and
//! images, an `.obj`'s `mtllib`) and of the options; an output whose input,
//! options and file are unchanged is skipped (`--force` rebuilds).

use crate::cli::{self, BuildArgs};
use anyhow::{bail, Context, Result};
use clap::Args;
use lodgen_pm::Meter;
use serde_json::json;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

mod inputs;

use inputs::{clashes, file_hash, has_glob_chars, key};
pub use inputs::{expand_inputs, input_hash, BatchInput, MESH_EXTENSIONS};

use crate::manifest::Running;
pub use crate::manifest::{Manifest, ManifestEntry, MANIFEST};

/// The batch flags of `lodgen INPUT...`.
#[derive(Args, Debug, Clone, Default)]
pub struct BatchFlags {
    /// Batch mode: build every INPUT (files, directories walked recursively
    /// for .obj/.ply/.smf/.gltf/.glb, glob patterns) into this directory,
    /// keeping each file's path relative to the directory it was found
    /// under, with .glb. A manifest (.lodgen-manifest.json) there lets a
    /// re-run skip files whose input and options are unchanged.
    #[arg(long, value_name = "DIR", conflicts_with = "output")]
    pub out_dir: Option<PathBuf>,

    /// Batch mode: files built in parallel. Each file's own threads are the
    /// cores divided by this (at least 1). Default 1 (files one after
    /// another, each on every core).
    #[arg(short = 'j', long, value_name = "N", default_value_t = 1)]
    pub jobs: usize,

    /// Batch mode: rebuild every file, even unchanged ones. Off by default
    /// (files whose input and options match the manifest are skipped).
    #[arg(long)]
    pub force: bool,
}

/// BLAKE3 of every option that changes the output: all build arguments
/// except the inputs, the output and report paths, the batch flags and
/// what only changes printing; plus lodgen's version.
pub fn options_hash(args: &BuildArgs) -> String {
    let mut a = args.clone();
    a.inputs.clear();
    a.output = None;
    a.report = None;
    a.quiet = false;
    a.verbose = false;
    a.batch = BatchFlags::default();
    // the levels as they are built: finest first, once each, whatever the
    // spelling (`50%,10%` = `0.1,0.5` = `0.5,0.1,0.1`)
    if let Ok(mut specs) = cli::parse_levels(&a.levels) {
        let key = |s: &lodgen_pm::levels::LevelSpec| format!("{s:?}");
        specs.sort_by_key(key);
        specs.dedup();
        a.levels = format!("{specs:?}");
    }
    if let Some(Ok(mut bounds)) = a.max_error.as_deref().map(cli::parse_max_errors) {
        bounds.sort_by(f64::total_cmp);
        bounds.dedup();
        a.max_error = Some(format!("{bounds:?}"));
    }
    let text = format!("lodgen {} {:?}", env!("CARGO_PKG_VERSION"), a);
    blake3::hash(text.as_bytes()).to_hex().to_string()
}

/// What happened to one file.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    Built,
    /// Unchanged input and options: the output was left as it was.
    Skipped,
    Failed(String),
}

/// One file's outcome.
#[derive(Clone, Debug)]
pub struct FileOutcome {
    pub input: PathBuf,
    pub output: PathBuf,
    pub status: Status,
    pub seconds: f64,
    /// The file's report (`--report` of a single run), when built or skipped.
    pub report: Option<serde_json::Value>,
    /// Manifest entry to record (built files).
    entry: Option<(String, ManifestEntry)>,
}

/// The summary of a batch.
pub struct BatchOutcome {
    pub files: Vec<FileOutcome>,
    pub seconds: f64,
    /// Why the manifest could not be written (the outputs were; a re-run
    /// rebuilds them): the command still prints the table and the report.
    pub manifest_error: Option<String>,
}

impl BatchOutcome {
    pub fn failed(&self) -> usize {
        self.count(|s| matches!(s, Status::Failed(_)))
    }
    pub fn skipped(&self) -> usize {
        self.count(|s| *s == Status::Skipped)
    }
    pub fn built(&self) -> usize {
        self.count(|s| *s == Status::Built)
    }
    /// Warnings of every built (or unchanged) file, from its report.
    pub fn warnings(&self) -> usize {
        self.files.iter().map(|f| file_warnings(f).len()).sum()
    }
    fn count(&self, f: impl Fn(&Status) -> bool) -> usize {
        self.files.iter().filter(|o| f(&o.status)).count()
    }

    /// The `--report` JSON of a batch.
    pub fn report_json(&self) -> serde_json::Value {
        json!({
            "files": self.files.iter().map(|f| {
                let (status, error) = match &f.status {
                    Status::Built => ("built", None),
                    Status::Skipped => ("skipped", None),
                    Status::Failed(e) => ("failed", Some(e.clone())),
                };
                json!({
                    "input": f.input.display().to_string(),
                    "output": f.output.display().to_string(),
                    "status": status,
                    "error": error,
                    "seconds": f.seconds,
                    "report": f.report,
                })
            }).collect::<Vec<_>>(),
            "built": self.built(),
            "skipped": self.skipped(),
            "failed": self.failed(),
            "seconds": self.seconds,
        })
    }

    /// The summary table: file, meshes, triangles in → per level, worst
    /// error, time, status; failures' messages below it.
    pub fn table(&self) -> String {
        let rows: Vec<[String; 6]> = self
            .files
            .iter()
            .map(|f| {
                let r = f.report.as_ref();
                let meshes = r
                    .and_then(|r| r["meshes"].as_array())
                    .map(|m| m.as_slice())
                    .unwrap_or_default();
                let tris_in: u64 = meshes
                    .iter()
                    .filter_map(|m| m["input_triangles"].as_u64())
                    .sum();
                let per_level = per_level_triangles(meshes);
                let worst = meshes
                    .iter()
                    .filter_map(|m| m["levels"].as_array())
                    .flatten()
                    .filter_map(|l| l["hausdorff_percent"].as_f64())
                    .fold(None, |a: Option<f64>, e| Some(a.map_or(e, |a| a.max(e))));
                let mut status = match &f.status {
                    Status::Built => "built".to_string(),
                    Status::Skipped => "unchanged".to_string(),
                    Status::Failed(_) => "FAILED".to_string(),
                };
                match file_warnings(f).len() {
                    0 => {}
                    1 => status += ", 1 warning",
                    n => status += &format!(", {n} warnings"),
                }
                [
                    f.input.display().to_string(),
                    if r.is_some() {
                        meshes.len().to_string()
                    } else {
                        "-".into()
                    },
                    if r.is_some() {
                        format!(
                            "{tris_in} → {}",
                            per_level
                                .iter()
                                .map(u64::to_string)
                                .collect::<Vec<_>>()
                                .join(" / ")
                        )
                    } else {
                        "-".into()
                    },
                    worst.map_or("-".into(), |w| format!("{w:.4}")),
                    format!("{:.2}", f.seconds),
                    status,
                ]
            })
            .collect();
        let head = [
            "file",
            "meshes",
            "triangles in → per level",
            "worst hausdorff %",
            "time s",
            "status",
        ];
        let mut width: Vec<usize> = head.iter().map(|h| h.chars().count()).collect();
        for r in &rows {
            for (w, c) in width.iter_mut().zip(r) {
                *w = (*w).max(c.chars().count());
            }
        }
        let line = |cells: &[String]| {
            let mut s = String::new();
            for (k, (c, w)) in cells.iter().zip(&width).enumerate() {
                let pad = w - c.chars().count();
                if k == 0 || k == 2 {
                    s += c;
                    s += &" ".repeat(pad);
                } else {
                    s += &" ".repeat(pad);
                    s += c;
                }
                s += "  ";
            }
            s.trim_end().to_string() + "\n"
        };
        let mut s = line(&head.map(String::from));
        for r in &rows {
            s += &line(r);
        }
        s += &format!(
            "{} files: {} built, {} unchanged, {} failed in {:.2} s\n",
            self.files.len(),
            self.built(),
            self.skipped(),
            self.failed(),
            self.seconds
        );
        for f in &self.files {
            if let Status::Failed(e) = &f.status {
                s += &format!("FAILED {}: {e}\n", f.input.display());
            }
            for w in file_warnings(f) {
                s += &format!("warning: {}: {w}\n", f.input.display());
            }
        }
        s
    }
}

/// Triangles of each level summed over the meshes (levels counted finest
/// first; meshes with fewer levels add nothing to the coarser ones).
fn per_level_triangles(meshes: &[serde_json::Value]) -> Vec<u64> {
    let mut out: Vec<u64> = Vec::new();
    for m in meshes {
        for (k, l) in m["levels"].as_array().into_iter().flatten().enumerate() {
            if out.len() <= k {
                out.push(0);
            }
            out[k] += l["triangles"].as_u64().unwrap_or(0);
        }
    }
    out
}

/// The error chain of `e` on one line, as the CLI prints it.
fn message(e: &anyhow::Error) -> String {
    cli::error_line(e)
}

/// Threads each job's rayon pool gets with `jobs` jobs.
pub fn threads_per_job(jobs: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    (cores / jobs.max(1)).max(1)
}

/// The order files are taken in: largest input first (ties in batch
/// order), so with several jobs no worker is left with a big file at the
/// end while the others idle. Results keep the batch order.
fn largest_first(inputs: &[BatchInput]) -> Vec<usize> {
    let size = |i: &BatchInput| std::fs::metadata(&i.input).map_or(0, |m| m.len());
    let mut order: Vec<(std::cmp::Reverse<u64>, usize)> = inputs
        .iter()
        .enumerate()
        .map(|(k, i)| (std::cmp::Reverse(size(i)), k))
        .collect();
    order.sort_unstable();
    order.into_iter().map(|(_, k)| k).collect()
}

/// Run a batch: build (or skip) every input into `out_dir`, update the
/// manifest. `on_done` is called after each file (from worker threads).
pub fn run_batch(
    inputs: &[BatchInput],
    out_dir: &Path,
    args: &BuildArgs,
    on_done: &(dyn Fn(usize, &FileOutcome) + Sync),
) -> Result<BatchOutcome> {
    let outcome = run_batch_watched(inputs, out_dir, args, &|_| {}, on_done, None)?;
    if let Some(e) = &outcome.manifest_error {
        bail!("{e}");
    }
    Ok(outcome)
}

/// [`run_batch`], with `on_start` called as each file begins (from worker
/// threads); a manifest that cannot be written is not an error here but
/// [`BatchOutcome::manifest_error`] ([`run_batch`] returns it as one).
/// Every file's simplification reports to `meter` when given; once it is
/// [cancelled](Meter::cancel) no file starts, and the files being built
/// stop (failed, "cancelled").
pub fn run_batch_watched(
    inputs: &[BatchInput],
    out_dir: &Path,
    args: &BuildArgs,
    on_start: &(dyn Fn(&BatchInput) + Sync),
    on_done: &(dyn Fn(usize, &FileOutcome) + Sync),
    meter: Option<Arc<Meter>>,
) -> Result<BatchOutcome> {
    let t0 = Instant::now();
    // Options are checked once, before any file: a bad flag is not a
    // per-file failure.
    args.build_options()?;
    std::fs::create_dir_all(out_dir)
        .with_context(|| format!("creating the output directory {}", out_dir.display()))?;
    let clashes = clashes(inputs, out_dir);
    let manifest = Manifest::load(out_dir);
    let options_hash = options_hash(args);
    let jobs = args.batch.jobs.max(1).min(inputs.len().max(1));
    let threads = threads_per_job(jobs);
    let mut order = largest_first(inputs);
    order.retain(|&k| clashes[k].is_none());
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<FileOutcome>>> = Mutex::new(vec![None; inputs.len()]);
    // inputs that would write one output fail, each alone
    for (k, clash) in clashes.into_iter().enumerate() {
        let Some(why) = clash else { continue };
        let item = &inputs[k];
        let outcome = FileOutcome {
            input: item.input.clone(),
            output: out_dir.join(&item.relative_output),
            status: Status::Failed(why),
            seconds: 0.0,
            report: None,
            entry: None,
        };
        on_done(done.fetch_add(1, Ordering::Relaxed) + 1, &outcome);
        results.lock().unwrap_or_else(|p| p.into_inner())[k] = Some(outcome);
    }
    // (on disk as files finish: an interrupted batch keeps what it built)
    let running = Running::new(out_dir, &manifest);
    let worker = || -> Result<()> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .context("starting a worker's thread pool")?;
        loop {
            if meter.as_ref().is_some_and(|m| m.is_cancelled()) {
                return Ok(());
            }
            let Some(&k) = order.get(next.fetch_add(1, Ordering::Relaxed)) else {
                return Ok(());
            };
            let item = &inputs[k];
            on_start(item);
            let file = (&manifest, options_hash.as_str(), meter.clone());
            let outcome = pool.install(|| one_file(item, out_dir, args, file));
            if let (Status::Built, Some((k, e))) = (&outcome.status, &outcome.entry) {
                running.built(k, e);
            }
            on_done(done.fetch_add(1, Ordering::Relaxed) + 1, &outcome);
            results.lock().unwrap_or_else(|p| p.into_inner())[k] = Some(outcome);
        }
    };
    std::thread::scope(|s| -> Result<()> {
        let handles: Vec<_> = (0..jobs).map(|_| s.spawn(worker)).collect();
        for h in handles {
            h.join()
                .map_err(|_| anyhow::anyhow!("a batch worker thread panicked"))??;
        }
        Ok(())
    })?;
    let files: Vec<FileOutcome> = results
        .into_inner()
        .unwrap_or_else(|p| p.into_inner())
        .into_iter()
        .flatten()
        .collect();
    // The manifest keeps entries of outputs not in this batch, records the
    // built ones and drops the failed ones (their output is stale).
    let mut next_manifest = Manifest {
        lodgen_version: env!("CARGO_PKG_VERSION").to_string(),
        outputs: manifest.outputs.clone(),
    };
    for (f, i) in files.iter().zip(inputs) {
        let k = key(&i.relative_output);
        match (&f.status, &f.entry) {
            (Status::Built, Some((k, e))) => {
                next_manifest.outputs.insert(k.clone(), e.clone());
            }
            (Status::Failed(_), _) => {
                next_manifest.outputs.remove(&k);
            }
            _ => {}
        }
    }
    let manifest_error = if next_manifest != manifest {
        next_manifest
            .save(out_dir)
            .err()
            .map(|e| cli::error_line(&e))
    } else {
        None
    };
    Ok(BatchOutcome {
        files,
        seconds: t0.elapsed().as_secs_f64(),
        manifest_error,
    })
}

/// One file of the batch, with the batch's manifest and options hash, and
/// its meter.
fn one_file(
    item: &BatchInput,
    out_dir: &Path,
    args: &BuildArgs,
    (manifest, options_hash, meter): (&Manifest, &str, Option<Arc<Meter>>),
) -> FileOutcome {
    let t0 = Instant::now();
    let output = out_dir.join(&item.relative_output);
    let k = key(&item.relative_output);
    let run = || -> Result<(Status, serde_json::Value, Option<ManifestEntry>)> {
        let hash =
            input_hash(&item.input).with_context(|| format!("reading {}", item.input.display()))?;
        if !args.batch.force && output.is_file() {
            if let Some(e) = manifest.outputs.get(&k) {
                if e.input_hash == hash
                    && e.options_hash == options_hash
                    && file_hash(&output).is_ok_and(|h| h == e.output_hash)
                {
                    return Ok((Status::Skipped, e.report.clone(), None));
                }
            }
        }
        if let Some(parent) = output.parent() {
            std::fs::create_dir_all(parent)
                .with_context(|| format!("creating {}", parent.display()))?;
        }
        let built = cli::build_file_metered(&item.input, &output, args, &mut |_| {}, meter)?;
        let report = built.report_json(&item.input);
        let entry = ManifestEntry {
            input: item.input.display().to_string(),
            input_hash: hash,
            options_hash: options_hash.to_string(),
            output_hash: file_hash(&output)
                .with_context(|| format!("reading back {}", output.display()))?,
            report: report.clone(),
        };
        Ok((Status::Built, report, Some(entry)))
    };
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(run)).unwrap_or_else(|p| {
        let what = p
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        Err(anyhow::anyhow!(
            "internal error while building {}: {what}",
            item.input.display()
        ))
    });
    let seconds = t0.elapsed().as_secs_f64();
    match result {
        Ok((status, report, entry)) => FileOutcome {
            input: item.input.clone(),
            output,
            status,
            seconds,
            report: Some(report),
            entry: entry.map(|e| (k, e)),
        },
        Err(e) => FileOutcome {
            input: item.input.clone(),
            output,
            status: Status::Failed(message(&e)),
            seconds,
            report: None,
            entry: None,
        },
    }
}

/// The warnings in a file's report (`report.warnings`).
fn file_warnings(f: &FileOutcome) -> Vec<&str> {
    f.report
        .as_ref()
        .and_then(|r| r["warnings"].as_array())
        .map(|w| w.iter().filter_map(|w| w.as_str()).collect())
        .unwrap_or_default()
}

/// Whether these arguments ask for batch mode: `--out-dir`, several inputs,
/// a directory or a glob pattern.
pub fn is_batch(args: &BuildArgs) -> bool {
    args.batch.out_dir.is_some()
        || args.inputs.len() > 1
        || args
            .inputs
            .first()
            .is_some_and(|i| i.is_dir() || (!i.exists() && has_glob_chars(&i.to_string_lossy())))
}

/// `lodgen INPUT... --out-dir DIR`: run the batch, print progress (stderr)
/// and the summary table (stdout) unless quiet, write `--report`; an error
/// when any file failed; else the number of warnings.
pub fn run(args: &BuildArgs) -> Result<usize> {
    let Some(out_dir) = &args.batch.out_dir else {
        // (a stray value, `--levels 50%, 10%`, was named by `BuildArgs::check`)
        bail!("several inputs or a directory need --out-dir DIR (batch mode)");
    };
    if args.inputs.is_empty() {
        bail!("no input mesh given (try `lodgen --help`)");
    }
    let inputs = expand_inputs(&args.inputs, Some(out_dir))?;
    for i in &inputs {
        let output = out_dir.join(&i.relative_output);
        cli::check_report_targets(args, &i.input, &output)?;
    }
    let total = inputs.len();
    let quiet = args.quiet;
    // on a terminal, a line saying which files are being built
    let line = (!quiet && std::io::stderr().is_terminal()).then(|| cli::BatchProgress::new(total));
    let line = line.as_ref();
    let on_start = |i: &BatchInput| {
        if let Some(l) = line {
            l.start(&i.input);
        }
    };
    let on_done = move |n: usize, f: &FileOutcome| {
        if !quiet || matches!(f.status, Status::Failed(_)) {
            let status = match &f.status {
                Status::Built => "built".to_string(),
                Status::Skipped => "unchanged".to_string(),
                Status::Failed(e) => format!("FAILED: {e}"),
            };
            let text = format!(
                "[{n}/{total}] {} ({:.2} s) {status}",
                f.input.display(),
                f.seconds
            );
            match line {
                Some(l) => l.done(&f.input, &text),
                None => eprintln!("{text}"),
            }
        }
    };
    let outcome = run_batch_watched(&inputs, out_dir, args, &on_start, &on_done, None);
    if let Some(l) = line {
        l.finish();
    }
    let outcome = outcome?;
    if !args.quiet && !cli::report_to_stdout(args) {
        print!("{}", outcome.table());
    }
    if let Some(path) = &args.report {
        cli::write_report(path, &outcome.report_json())?;
    }
    if let Some(e) = &outcome.manifest_error {
        if outcome.failed() == 0 {
            bail!("{e}");
        }
        eprintln!("error: {e}");
    }
    if outcome.failed() > 0 {
        bail!(
            "{} of {} files failed (the others were built)",
            outcome.failed(),
            outcome.files.len()
        );
    }
    Ok(outcome.warnings())
}
