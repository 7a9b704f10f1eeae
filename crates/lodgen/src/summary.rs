//! What a run did, for people and for programs: the `-v` tables (time per
//! phase with its share, refusals by reason in words, what preparation
//! removed) and the same data in the `--report` JSON
//! (docs/report-schema.md). Formatting only: the figures come from
//! [`crate::cli::build_file`] and the core's statistics.

use std::fmt::Write as _;
use std::time::Duration;

use lodgen_pm::{PrepareStats, Rejections, StopReason};
use serde_json::{json, Value};

use crate::cli::job::BuiltFile;
pub use crate::cli::job::FileTimes;

/// One row of the phase table: name, indent level, time.
struct Phase {
    name: &'static str,
    depth: usize,
    time: Duration,
}

/// The phases of a file's run, in order, with the core's own phase clock
/// under "simplify" (its rows may overlap: part of the ordering runs
/// inside the contraction loop). Mesh builds are summed over meshes.
fn phases(built: &BuiltFile) -> Vec<Phase> {
    let sum = |f: &dyn Fn(&crate::lod::MeshBuild) -> Duration| -> Duration {
        built.builds.iter().map(f).sum()
    };
    let simplify = sum(&|b| b.times.simplify);
    let measure = sum(&|b| b.times.measure);
    let total = sum(&|b| b.times.total);
    let core =
        |f: &dyn Fn(&lodgen_pm::PhaseTimes) -> Duration| sum(&|b| f(&b.simplified.stats.time));
    let (setup, pairs, heap, collapse, log) = (
        core(&|t| t.setup),
        core(&|t| t.pairs),
        core(&|t| t.heap),
        core(&|t| t.collapse),
        core(&|t| t.log),
    );
    let p = |name, depth, time| Phase { name, depth, time };
    vec![
        p("read", 0, built.times.read),
        p("simplify", 0, simplify),
        p("adjacency, quadrics", 1, setup),
        p("pairs", 1, pairs),
        p("costs and ordering", 1, heap),
        p("contractions", 1, collapse),
        p("vertex-split log", 1, log),
        p("measure", 0, measure),
        p(
            "levels (extract, fit)",
            0,
            total.saturating_sub(simplify + measure),
        ),
        p("write", 0, built.times.write),
    ]
}

/// The refusals of candidate contractions, most frequent first:
/// `(json key, count, reason in words)`.
pub fn refusals(r: &Rejections) -> Vec<(&'static str, usize, &'static str)> {
    let mut v = vec![
        (
            "feature",
            r.feature,
            "would move a seam, hard edge or material border off its line",
        ),
        ("link", r.link, "would make the surface non-manifold"),
        ("flip", r.flip, "would flip a face"),
        (
            "duplicate",
            r.duplicate,
            "would flatten a closed part into a double-sided sheet",
        ),
        ("degenerate", r.degenerate, "would leave a sliver"),
        (
            "boundary_pinch",
            r.boundary_pinch,
            "would pinch two borders together",
        ),
        (
            "locked",
            r.locked,
            "would join two locked vertices (non-manifold input, or --boundary locked)",
        ),
        ("error", r.error, "would exceed --max-error"),
    ];
    v.sort_by_key(|w| std::cmp::Reverse(w.1));
    v
}

/// What preparation removed: `(json key, count, in words)`.
fn removed(p: &PrepareStats) -> [(&'static str, usize, &'static str); 4] {
    [
        (
            "welded_vertices",
            p.welded_vertices,
            "vertices merged into another at the same position",
        ),
        (
            "unused_vertices",
            p.unused_vertices,
            "vertices no triangle uses",
        ),
        (
            "degenerate_triangles",
            p.degenerate_triangles,
            "triangles with a repeated corner",
        ),
        (
            "duplicate_triangles",
            p.duplicate_triangles,
            "triangles repeating another's three vertices",
        ),
    ]
}

/// Why the simplification stopped, in words.
pub fn stop_words(stop: StopReason) -> &'static str {
    match stop {
        StopReason::Target => "reached the target",
        StopReason::MaxError => "every remaining contraction exceeds the error bound",
        StopReason::Exhausted => "no legal contraction is left",
        StopReason::Cancelled => "cancelled",
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// The `-v` tables of one file, `elapsed` being the whole run's wall time.
pub fn verbose(built: &BuiltFile, elapsed: Duration) -> String {
    let mut s = String::new();
    let whole = elapsed.as_secs_f64().max(f64::MIN_POSITIVE);
    let _ = writeln!(s, "time by phase (wall clock, all meshes)");
    let _ = writeln!(s, "  {:<26} {:>10}  {:>6}", "phase", "time", "share");
    for p in phases(built) {
        let name = format!("{}{}", "  ".repeat(p.depth), p.name);
        let _ = writeln!(
            s,
            "  {name:<26} {:>7.1} ms  {:>5.1} %",
            ms(p.time),
            100.0 * p.time.as_secs_f64() / whole
        );
    }
    let _ = writeln!(
        s,
        "  {:<26} {:>7.1} ms  {:>5.1} %",
        "total",
        ms(elapsed),
        100.0
    );
    for (i, b) in built.builds.iter().enumerate() {
        let name = if b.lod.name.is_empty() {
            format!("mesh {i}")
        } else {
            b.lod.name.clone()
        };
        let st = &b.simplified.stats;
        let _ = writeln!(
            s,
            "{name}: {} → {} triangles in {} contractions ({} passes); stopped: {}",
            st.input_triangles,
            st.output_triangles,
            st.collapses,
            st.passes,
            stop_words(b.simplified.stop)
        );
        let _ = writeln!(
            s,
            "  vertices: {} on open borders, {} locked",
            st.boundary_vertices, st.locked_vertices
        );
        let refused = refusals(&st.rejected);
        if st.rejected.total() == 0 {
            let _ = writeln!(s, "  candidates refused: none");
        } else {
            let _ = writeln!(s, "  candidates refused: {}", st.rejected.total());
            for (_, n, words) in refused.iter().filter(|r| r.1 > 0) {
                let _ = writeln!(s, "    {n:>9}  {words}");
            }
        }
        if st.lifted + st.lift_refused > 0 {
            let _ = writeln!(
                s,
                "  lifted off their chords: {} vertices ({} refused: a face would turn)",
                st.lifted, st.lift_refused
            );
        }
        let prep = &b.simplified.prepare;
        let gone: Vec<_> = removed(prep).into_iter().filter(|r| r.1 > 0).collect();
        if gone.is_empty() {
            let _ = writeln!(
                s,
                "  preparation removed nothing ({} vertices, {} triangles in)",
                prep.input_vertices, prep.input_triangles
            );
        } else {
            let _ = writeln!(
                s,
                "  preparation removed ({} vertices, {} triangles in):",
                prep.input_vertices, prep.input_triangles
            );
            for (_, n, words) in gone {
                let _ = writeln!(s, "    {n:>9}  {words}");
            }
        }
    }
    s
}

/// Adds the `-v` data to a file's `--report` object: `phases_ms` at the
/// top, and `stop_reason`, `refusals`, `prepare` and `contractions` per
/// mesh (docs/report-schema.md).
pub fn extend_report(report: &mut Value, built: &BuiltFile) {
    let phases: serde_json::Map<String, Value> = phases(built)
        .iter()
        .map(|p| {
            let key = match p.name {
                "read" => "read",
                "simplify" => "simplify",
                "adjacency, quadrics" => "simplify.setup",
                "pairs" => "simplify.pairs",
                "costs and ordering" => "simplify.ordering",
                "contractions" => "simplify.contractions",
                "vertex-split log" => "simplify.log",
                "measure" => "measure",
                "levels (extract, fit)" => "levels",
                _ => "write",
            };
            (key.to_string(), json!(ms(p.time)))
        })
        .collect();
    report["phases_ms"] = Value::Object(phases);
    let Some(meshes) = report["meshes"].as_array_mut() else {
        return;
    };
    for (m, b) in meshes.iter_mut().zip(&built.builds) {
        let st = &b.simplified.stats;
        m["stop_reason"] = json!(stop_words(b.simplified.stop));
        m["contractions"] = json!(st.collapses);
        m["passes"] = json!(st.passes);
        m["boundary_vertices"] = json!(st.boundary_vertices);
        m["locked_vertices"] = json!(st.locked_vertices);
        m["refusals"] = Value::Object(
            refusals(&st.rejected)
                .into_iter()
                .map(|(k, n, _)| (k.to_string(), json!(n)))
                .collect(),
        );
        let prep = &b.simplified.prepare;
        let mut p: serde_json::Map<String, Value> = removed(prep)
            .into_iter()
            .map(|(k, n, _)| (k.to_string(), json!(n)))
            .collect();
        p.insert("input_vertices".into(), json!(prep.input_vertices));
        p.insert("input_triangles".into(), json!(prep.input_triangles));
        m["prepare"] = Value::Object(p);
    }
}
