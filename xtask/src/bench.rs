//! `cargo xtask bench`: lodgen against meshoptimizer (the `meshopt` crate's
//! `simplify`) on `bunny.obj` (69,451 triangles) and on the bunny subdivided
//! twice by midpoints (1,111,216 triangles), to 50 %, 10 % and 2 %.
//!
//! Every measurement runs in a child process (`xtask bench-child`), so peak
//! memory is the child's own: the peak resident set is reset
//! (`/proc/self/clear_refs`) once the input mesh is built, and the figure
//! reported is the growth above that during the first run, per input
//! triangle — what one `lodgen` invocation costs. (Later runs in the same
//! process reuse a heap that glibc shaped after the first: its mmap
//! threshold grows to the largest block freed, so big buffers stop going
//! back to the system and the peak drifts up by ~5 % for either tool.) Times are the median of several runs;
//! the ratio is also taken run by run with both tools alternating in one
//! process (`bench-child pairs`), which a shared machine's load swings
//! affect far less than two medians taken minutes apart. lodgen's time is ONE pass
//! down to 2 % that yields all three levels (vertex-split log and level
//! extraction included); meshopt's is its single call to 2 % (its 50 % and
//! 10 % levels are separate calls, timed too). Errors use lodgen's metric
//! (`lodgen_pm::metric`, symmetric, % of the bbox diagonal) on both.

use anyhow::{bail, Context, Result};
use lodgen_pm::metric::{measure, MeasureOptions, MeshRef};
use lodgen_pm::shapes::subdivide;
use lodgen_pm::{simplify, Mesh, SimplifyOptions};
use serde_json::{json, Value};
use std::process::Command;
use std::time::Instant;

const RATIOS: [f64; 3] = [0.5, 0.1, 0.02];

fn read_bunny() -> Result<Mesh> {
    let path = crate::shared_assets()?.join("bunny.obj");
    let scene =
        lodgen::io::read_scene(&path).with_context(|| format!("reading {}", path.display()))?;
    Ok(lodgen::cli::merged_mesh(&scene))
}

fn input(id: &str) -> Result<Mesh> {
    let bunny = read_bunny()?;
    Ok(match id {
        "bunny" => bunny,
        "bunny-1m" => subdivide(&subdivide(&bunny)),
        other => bail!("unknown bench mesh {other:?}"),
    })
}

fn status_kb(field: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(field))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse().ok())
        })
        .unwrap_or(0)
}

fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn errors(full: &Mesh, levels: &[Mesh]) -> Vec<Value> {
    levels
        .iter()
        .map(|l| {
            let r = measure(
                MeshRef::new(&full.positions, &full.triangles),
                MeshRef::new(&l.positions, &l.triangles),
                &MeasureOptions::DEFAULT,
            )
            .expect("bench meshes are valid");
            json!({"triangles": l.triangles.len(), "hausdorff_percent": r.hausdorff_percent(), "rms_percent": r.rms_percent()})
        })
        .collect()
}

/// `xtask bench-child TOOL MESH RUNS`: prints one JSON line.
/// One lodgen run: simplify to 2 % and extract the three levels. Returns
/// the time in ms and the levels (50, 10, 2 %).
fn lodgen_once(m: &Mesh, indices: &[u32]) -> Result<(f64, Vec<Mesh>)> {
    let n = m.triangles.len();
    let t = Instant::now();
    let opts = SimplifyOptions::DEFAULT.with_target_ratio(RATIOS[2]);
    let out = simplify(&m.positions, indices, &opts)?;
    let mut c = out.pm.cursor();
    let mut got = Vec::new();
    for r in RATIOS.iter().rev() {
        c.seek(out.pm.splits_for_triangles((r * n as f64) as usize));
        got.push(c.mesh().clone());
    }
    let ms = t.elapsed().as_secs_f64() * 1e3;
    got.reverse();
    Ok((ms, got))
}

/// One meshopt run: a `simplify` call per level. Returns the time of the
/// 2 % call in ms, the times of the others, and the levels.
fn meshopt_once(m: &Mesh, indices: &[u32]) -> Result<(f64, Vec<f64>, Vec<Mesh>)> {
    let n = m.triangles.len();
    let adapter = meshopt::VertexDataAdapter::new(meshopt::typed_to_bytes(&m.positions), 12, 0)?;
    let mut got = Vec::new();
    let mut t2 = 0.0;
    let mut extra = Vec::new();
    for (i, r) in RATIOS.iter().enumerate() {
        let t = Instant::now();
        let idx = meshopt::simplify(
            indices,
            &adapter,
            (r * n as f64) as usize * 3,
            1.0,
            meshopt::SimplifyOptions::None,
            None,
        );
        let dt = t.elapsed().as_secs_f64() * 1e3;
        if i == 2 {
            t2 = dt;
        } else {
            extra.push(dt);
        }
        got.push(Mesh {
            positions: m.positions.clone(),
            triangles: idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        });
    }
    Ok((t2, extra, got))
}

pub fn child(args: &[String]) -> Result<()> {
    if let Some((tool, rest)) = args.split_first() {
        if matches!(
            tool.as_str(),
            "meshopt-e2e" | "meshopt-errors" | "e2e-run" | "mesh"
        ) {
            return crate::e2e::child(tool, rest);
        }
    }
    let [tool, id, runs] = args else {
        bail!("usage: xtask bench-child lodgen|meshopt|pairs MESH RUNS");
    };
    let runs: usize = runs.parse()?;
    let m = input(id)?;
    let indices = m.indices();
    let n = m.triangles.len();
    if tool == "pairs" {
        // lodgen and meshopt alternately in one process: the ratio of each
        // pair is taken under the same machine load, so a noisy machine
        // (a shared VM) moves both sides of it alike
        let mut ratios = Vec::new();
        for _ in 0..runs {
            let (l, _) = lodgen_once(&m, &indices)?;
            let (o, _, _) = meshopt_once(&m, &indices)?;
            ratios.push(l / o);
        }
        ratios.sort_by(f64::total_cmp);
        let q = |f: f64| ratios[((ratios.len() - 1) as f64 * f).round() as usize];
        println!(
            "{}",
            json!({"mesh": id, "pairs": runs, "ratio_median": q(0.5), "ratio_q1": q(0.25), "ratio_q3": q(0.75)})
        );
        return Ok(());
    }
    let rss_before = status_kb("VmRSS:");
    reset_peak();
    let mut times = Vec::new();
    let mut levels: Vec<Mesh> = Vec::new();
    let mut extra = Vec::new();
    let mut first_peak = None;
    let mut note_peak = || {
        if first_peak.is_none() {
            first_peak = Some(status_kb("VmHWM:"));
        }
    };
    for _ in 0..runs {
        let (ms, got) = match tool.as_str() {
            "lodgen" => lodgen_once(&m, &indices)?,
            "meshopt" => {
                let (ms, e, got) = meshopt_once(&m, &indices)?;
                extra.extend(e);
                (ms, got)
            }
            other => bail!("unknown tool {other:?}"),
        };
        times.push(ms);
        note_peak();
        levels = got;
    }
    let peak = first_peak.unwrap_or_else(|| status_kb("VmHWM:"));
    let growth_bytes = peak.saturating_sub(rss_before) * 1024;
    let line = json!({
        "tool": tool, "mesh": id, "triangles": n,
        "time_ms": median(times),
        "other_calls_ms": extra,
        "peak_mb": peak as f64 / 1024.0,
        "growth_bytes_per_triangle": growth_bytes as f64 / n as f64,
        "levels": errors(&m, &levels),
    });
    println!("{line}");
    Ok(())
}

/// `xtask bench-child TOOL MESH RUNS` in a process of its own; its JSON line.
fn run_child(exe: &std::path::Path, tool: &str, mesh: &str, runs: usize) -> Result<Value> {
    let out = Command::new(exe)
        .args(["bench-child", tool, mesh, &runs.to_string()])
        .output()?;
    if !out.status.success() {
        bail!(
            "bench-child {tool} {mesh} failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    Ok(serde_json::from_slice(&out.stdout)?)
}

pub fn run(args: &[String]) -> Result<()> {
    if args.iter().any(|a| a == "--python") {
        return crate::py_bench::run_python(args);
    }
    if let Some(other) = args
        .iter()
        .find(|a| !matches!(a.as_str(), "--quick" | "--e2e" | "--huge"))
    {
        bail!("unknown bench option {other:?} (expected --quick, --e2e, --huge or --python)");
    }
    if crate::rerun_in_release("bench", args)? {
        return Ok(());
    }
    let quick = args.iter().any(|a| a == "--quick");
    let exe = std::env::current_exe()?;
    let huge = args.iter().any(|a| a == "--huge");
    if args.iter().any(|a| a == "--e2e") {
        return crate::e2e::run(&exe, quick, huge);
    }
    println!("lodgen vs meshopt (meshoptimizer 1.3), symmetric errors by lodgen's metric, % of bbox diagonal");
    println!("time: lodgen = one pass to 2% yielding 50/10/2%; meshopt = its single call to 2%\n");
    println!(
        "{:<9} {:<8} {:>9} {:>9} {:>8} {:>8} {:>10} {:>10} {:>10} {:>9}",
        "mesh",
        "tool",
        "triangles",
        "time ms",
        "peak MB",
        "B/tri",
        "H 50%",
        "H 10%",
        "H 2%",
        "RMS 2%"
    );
    let meshes: &[(&str, usize)] = if quick {
        &[("bunny", 3)]
    } else {
        &[("bunny", 7), ("bunny-1m", 3)]
    };
    for &(id, runs) in meshes {
        let mut results = Vec::new();
        for tool in ["lodgen", "meshopt"] {
            let v = run_child(&exe, tool, id, runs)?;
            let h = |i: usize| {
                v["levels"][i]["hausdorff_percent"]
                    .as_f64()
                    .unwrap_or(f64::NAN)
            };
            println!(
                "{:<9} {:<8} {:>9} {:>9.1} {:>8.1} {:>8.1} {:>10.4} {:>10.4} {:>10.4} {:>9.4}",
                id,
                tool,
                v["triangles"],
                v["time_ms"].as_f64().unwrap_or(f64::NAN),
                v["peak_mb"].as_f64().unwrap_or(f64::NAN),
                v["growth_bytes_per_triangle"].as_f64().unwrap_or(f64::NAN),
                h(0),
                h(1),
                h(2),
                v["levels"][2]["rms_percent"].as_f64().unwrap_or(f64::NAN),
            );
            results.push(v);
        }
        let ratio = results[0]["time_ms"].as_f64().unwrap_or(f64::NAN)
            / results[1]["time_ms"].as_f64().unwrap_or(f64::NAN);
        let p = run_child(&exe, "pairs", id, 2 * runs + 1)?;
        println!(
            "{id}: time lodgen / meshopt = {ratio:.2} (medians above); interleaved, run by run: {:.2} (quartiles {:.2}–{:.2}, {} pairs)",
            p["ratio_median"].as_f64().unwrap_or(f64::NAN),
            p["ratio_q1"].as_f64().unwrap_or(f64::NAN),
            p["ratio_q3"].as_f64().unwrap_or(f64::NAN),
            p["pairs"],
        );
        // the simplification alone at 1 and 2 threads, run by run
        for threads in ["1", "2"] {
            let out = Command::new(&exe)
                .args(["bench-child", "pairs", id, &(2 * runs + 1).to_string()])
                .env("RAYON_NUM_THREADS", threads)
                .output()?;
            let p: Value = serde_json::from_slice(&out.stdout).unwrap_or(Value::Null);
            println!(
                "{id}: {threads} thread(s): time lodgen / meshopt 2 % call, run by run: {:.2} (quartiles {:.2}–{:.2})",
                p["ratio_median"].as_f64().unwrap_or(f64::NAN),
                p["ratio_q1"].as_f64().unwrap_or(f64::NAN),
                p["ratio_q3"].as_f64().unwrap_or(f64::NAN),
            );
        }
    }
    crate::e2e::run(&exe, quick, huge)?;
    Ok(())
}
