//! What users see of a build: the progress spinner, the level table, the
//! stop note, the `--report` JSON (with [`crate::summary`]'s additions) and
//! its atomic write.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use serde_json::json;

use crate::lod::MeshBuild;
use crate::summary;

use super::args::{default_output, BuildArgs};
use super::job::{build_file, build_file_metered, same_place, BuiltFile};
use super::progress::Spinner;

impl BuiltFile {
    /// The JSON `--report` of this file.
    pub fn report_json(&self, input: &Path) -> serde_json::Value {
        let mut report = report_json(input, &self.output, &self.builds, &self.level_bytes);
        summary::extend_report(&mut report, self);
        let warnings: Vec<String> = self.warnings.iter().map(|w| w.to_string()).collect();
        report["warnings"] = warnings.into();
        report
    }
}

/// The main job. Prints the table (unless quiet) and writes the report;
/// returns the number of warnings (each printed to stderr as `warning: …`).
pub fn build(input: &Path, args: &BuildArgs, show_progress: bool) -> Result<usize> {
    let output = args.output.clone().unwrap_or_else(|| default_output(input));
    check_report_targets(args, input, &output)?;
    let t0 = Instant::now();
    let built = if show_progress {
        with_spinner(input, &output, args)?
    } else {
        build_file(input, &output, args, &mut |_| {})?
    };
    let elapsed = t0.elapsed();
    let BuiltFile {
        builds,
        level_bytes,
        ..
    } = &built;
    // (with `--report -` standard output is the report's)
    let table_out = !args.quiet && !report_to_stdout(args);
    if table_out {
        print!("{}", table(builds, level_bytes));
    }
    if !args.quiet && args.verbose {
        eprint!("{}", summary::verbose(&built, elapsed));
    }
    if table_out {
        println!(
            "wrote {} in {:.2} s",
            output.display(),
            elapsed.as_secs_f64()
        );
    }
    if let Some(path) = &args.report {
        write_report(path, &built.report_json(input))?;
    }
    for w in &built.warnings {
        eprintln!("warning: {}: {w}", input.display());
    }
    Ok(built.warnings.len())
}

/// [`build_file`] with the progress line on stderr: build events set it,
/// and a second thread polls the simplification's meter.
fn with_spinner(input: &Path, output: &Path, args: &BuildArgs) -> Result<BuiltFile> {
    let spinner = Spinner::new();
    let meter = Some(Arc::clone(&spinner.meter));
    let built = std::thread::scope(|scope| {
        scope.spawn(|| spinner.poll());
        let mut on_progress = |p| spinner.on_progress(p, input, output);
        let built = build_file_metered(input, output, args, &mut on_progress, meter);
        spinner
            .done
            .store(true, std::sync::atomic::Ordering::Relaxed);
        built
    });
    spinner.finish();
    built
}

/// Why a simplification stopped short of its target, in words: where it
/// stopped, and the refusals that stopped it, most frequent first.
pub fn stop_note(stop: lodgen_pm::StopReason, stats: &lodgen_pm::Stats) -> String {
    let r = &stats.rejected;
    let mut why: Vec<(usize, &str)> = vec![
        (
            r.feature,
            "would move a seam, hard edge or material border off its line",
        ),
        (r.link, "would make the surface non-manifold"),
        (r.flip, "would flip a face"),
        (
            r.duplicate,
            "would flatten a closed part into a double-sided sheet",
        ),
        (r.degenerate, "would leave a sliver"),
        (r.boundary_pinch, "would pinch two borders together"),
        (
            r.locked,
            "would join two locked vertices (non-manifold input, or --boundary locked)",
        ),
        (r.error, "would exceed --max-error"),
    ];
    why.retain(|w| w.0 > 0);
    why.sort_by_key(|w| std::cmp::Reverse(w.0));
    let reasons: Vec<String> = why.iter().map(|(n, w)| format!("{n} {w}")).collect();
    let head = match stop {
        lodgen_pm::StopReason::MaxError => "every remaining contraction exceeds the error bound",
        _ => "no legal contraction is left",
    };
    // (the refusals the option relaxes: it can only help when they stopped the run)
    let relaxable = r.link + r.boundary_pinch + r.duplicate + r.feature + r.flip + r.degenerate;
    let hint = if stop != lodgen_pm::StopReason::Exhausted || relaxable == 0 {
        ""
    } else if stats.relaxed.feature + stats.relaxed.flip + stats.relaxed.degenerate > 0 {
        "; --allow-topology-change went no further"
    } else if stats.relaxed.total() > 0 {
        "; run again with joins and flattening allowed, it went no further; \
         --allow-topology-change also lets seams, hard edges and faces go"
    } else {
        "; --allow-topology-change reaches it, at the price of the surface's topology"
    };
    format!(
        "simplification stopped at {} triangles, before the coarsest requested level: {head}{}{hint}; \
         coarser levels would repeat this one and are not written",
        stats.output_triangles,
        if reasons.is_empty() {
            String::new()
        } else {
            format!(" (of the candidates refused, {})", reasons.join(", "))
        }
    )
}

/// What the relaxed topology rules let the run do (the default's second
/// run, `--allow-topology-change`), in words (`None`: nothing).
pub fn topology_note(stats: &lodgen_pm::Stats) -> Option<String> {
    let r = &stats.relaxed;
    if r.total() == 0 {
        return None;
    }
    let kinds: Vec<String> = [
        (r.link + r.boundary_pinch, "joined sheets or borders"),
        (r.duplicate, "flattened a closed part"),
        (
            r.feature,
            "moved a seam, hard edge or material border off its line",
        ),
        (r.flip + r.degenerate, "turned a face over or left a sliver"),
    ]
    .iter()
    .filter(|k| k.0 > 0)
    .map(|(n, w)| format!("{n} {w}"))
    .collect();
    Some(format!(
        "{} contractions changed the topology ({}; \
         --keep-topology turns this off)",
        r.total(),
        kinds.join(", ")
    ))
}

/// The per-mesh table printed on stdout.
pub fn table(builds: &[MeshBuild], bytes: &[Vec<u64>]) -> String {
    let mut s = String::new();
    for (i, b) in builds.iter().enumerate() {
        let st = &b.simplified;
        s += &format!(
            "{} ({} triangles, {} vertices after welding)\n",
            if b.lod.name.is_empty() {
                format!("mesh {i}")
            } else {
                b.lod.name.clone()
            },
            st.stats.input_triangles,
            st.stats.input_vertices
        );
        if st.stop != lodgen_pm::StopReason::Target {
            s += &format!("  note: {}\n", stop_note(st.stop, &st.stats));
        }
        if let Some(n) = topology_note(&st.stats) {
            s += &format!("  note: {n}\n");
        }
        for n in &b.notes {
            s += &format!("  note: {n}\n");
        }
        s += "  level  triangles  vertices  hausdorff %  rms %     coverage    bytes\n";
        for (k, (l, e)) in b.lod.levels.iter().zip(&b.errors).enumerate() {
            let verts: usize = l.primitives.iter().map(|p| p.positions.len()).sum();
            // --measure off: the quadric's estimate, marked ≈; RMS unknown
            let (h, rms) = if b.measured {
                (
                    format!("{:.4}", e.hausdorff_percent()),
                    format!("{:.4}", e.rms_percent()),
                )
            } else {
                (format!("≈{:.4}", e.hausdorff_percent()), "—".to_string())
            };
            s += &format!(
                "  {k:>5}  {:>9}  {:>8}  {h:>11}  {rms:>8}  {:>10.3e}  {:>8}\n",
                l.triangle_count(),
                verts,
                l.screen_coverage,
                bytes.get(i).and_then(|b| b.get(k)).copied().unwrap_or(0),
            );
        }
    }
    s
}

fn report_json(
    input: &Path,
    output: &Path,
    builds: &[MeshBuild],
    bytes: &[Vec<u64>],
) -> serde_json::Value {
    json!({
        "input": input.display().to_string(),
        "output": output.display().to_string(),
        "meshes": builds.iter().enumerate().map(|(i, b)| json!({
            "name": b.lod.name,
            "source_mesh": b.lod.source,
            "input_triangles": b.input_triangles,
            "welded_triangles": b.simplified.stats.input_triangles,
            "measured": b.measured,
            "stop": format!("{:?}", b.simplified.stop),
            "stop_note": (b.simplified.stop != lodgen_pm::StopReason::Target)
                .then(|| stop_note(b.simplified.stop, &b.simplified.stats)),
            "topology_changes": b.simplified.stats.relaxed.total(),
            "notes": b.notes,
            "levels": b.lod.levels.iter().zip(&b.errors).zip(&b.level_splits).enumerate().map(|(k, ((l, e), s))| json!({
                "triangles": l.triangle_count(),
                "vertices": l.primitives.iter().map(|p| p.positions.len()).sum::<usize>(),
                "splits": s,
                "hausdorff_percent": e.hausdorff_percent(),
                "rms_percent": e.rms_percent(),
                "mean_percent": e.mean_percent(),
                "original_to_level_percent": e.percent(e.a_to_b.max),
                "level_to_original_percent": e.percent(e.b_to_a.max),
                "screen_coverage": l.screen_coverage,
                "bytes": bytes.get(i).and_then(|b| b.get(k)).copied().unwrap_or(0),
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    })
}

/// Whether `--report -` sends the report to standard output (in place of
/// the table).
pub fn report_to_stdout(args: &BuildArgs) -> bool {
    args.report.as_deref() == Some(Path::new("-"))
}

/// Whether `--report PATH` can be written: its directory exists and it is
/// no directory (checked before the work, so that a build is not thrown
/// away, or its output left behind, for a mistyped report path).
pub fn check_report_path(args: &BuildArgs) -> Result<()> {
    let Some(path) = args.report.as_deref().filter(|p| *p != Path::new("-")) else {
        return Ok(());
    };
    if path.is_dir() {
        bail!("writing the report {}: it is a directory", path.display());
    }
    check_parent_dir(path, "the report")
}

/// `path`'s directory exists and takes a new file (`what` names the file in the error): a
/// read-only directory is found before the work, not after it.
pub fn check_parent_dir(path: &Path, what: &str) -> Result<()> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
    if let Some(dir) = dir {
        if !dir.is_dir() {
            bail!(
                "writing {what} {}: the directory {} does not exist",
                path.display(),
                dir.display()
            );
        }
    }
    let dir = dir.unwrap_or(Path::new("."));
    let probe = dir.join(format!(".lodgen-probe-{}", std::process::id()));
    let made = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe);
    match made {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        // (another run's probe of the same name: the directory takes files)
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => bail!(
            "writing {what} {}: cannot create a file in {}: {e}",
            path.display(),
            dir.display()
        ),
    }
}

/// The `--report` path names neither the input nor the output (the report would replace
/// it: `--report scan.ply`, `--report x.glb -o x.glb`).
pub fn check_report_targets(args: &BuildArgs, input: &Path, output: &Path) -> Result<()> {
    let Some(path) = args.report.as_deref().filter(|p| *p != Path::new("-")) else {
        return Ok(());
    };
    for (what, other) in [("input", input), ("output", output)] {
        if same_place(path, other) {
            bail!(
                "the report {} would overwrite the {what} {}",
                path.display(),
                other.display()
            );
        }
    }
    Ok(())
}

/// The `--report` JSON to `path`, or to standard output for `-`.
pub fn write_report(path: &Path, json: &serde_json::Value) -> Result<()> {
    let text = serde_json::to_string_pretty(json)?;
    if path == Path::new("-") {
        println!("{text}");
        return Ok(());
    }
    write_atomically(path, text.as_bytes())
        .with_context(|| format!("writing the report {}", path.display()))
}

/// Write `bytes` to a temporary file beside `path`, then rename (removed
/// on error or interrupt: [`crate::interrupt`]).
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    crate::interrupt::write_atomically(path, &[bytes])
}
