//! Phase times of one simplification (prepare, setup, pairs, heap, loop,
//! log, level extraction), to see where the time goes.
//!
//! `cargo run --release -p lodgen-pm --example profile_simplify [path/to/mesh.obj] [subdivisions] [ratio] [greedy|pass factor]`
//!
//! Ends with the symmetric Hausdorff distance of the last run's coarsest
//! level, so schedules can be compared on time and quality at once.

use std::time::Instant;

use lodgen_pm::metric::{measure, MeasureOptions, MeshRef};
use lodgen_pm::{prepare, Schedule, Simplifier, SimplifyOptions};

#[path = "common/mod.rs"]
mod common;
use common::mesh_from_args;

/// Peak resident memory (kB) since the last `reset_peak`.
fn peak_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse().ok())
        })
        .unwrap_or(0)
}

fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let ratio: f64 = args.get(3).map_or(0.02, |s| s.parse().unwrap());
    let m = mesh_from_args(&args);
    let indices = m.indices();
    let n = m.triangles.len();
    let schedule = match args.get(4).map(String::as_str) {
        None => SimplifyOptions::DEFAULT.schedule,
        Some("greedy") => Schedule::Greedy,
        Some(f) => Schedule::Passes {
            factor: f.parse().unwrap(),
        },
    };
    let opts = SimplifyOptions::DEFAULT
        .with_target_ratio(ratio)
        .with_schedule(schedule);
    let mut last = None;
    for run in 0..3 {
        reset_peak();
        let base = peak_kb();
        let per_tri = |kb: u64| (kb.saturating_sub(base) * 1024) as f64 / n as f64;
        let t = Instant::now();
        let p = prepare(&m.positions, &indices).unwrap();
        let t_prepare = t.elapsed();
        let m_prepare = per_tri(peak_kb());
        let mut s = Simplifier::from_mesh(p.mesh, &opts).unwrap();
        let m_new = per_tri(peak_kb());
        s.run();
        let m_run = per_tri(peak_kb());
        let (pm, stats) = s.finish();
        let m_finish = per_tri(peak_kb());
        println!(
            "peak bytes/triangle after prepare {m_prepare:.0}, new {m_new:.0}, run {m_run:.0}, finish {m_finish:.0}"
        );
        let t_levels = Instant::now();
        let mut c = pm.cursor();
        let mut tris = 0;
        for r in [0.02, 0.1, 0.5] {
            c.seek(pm.splits_for_triangles((r * n as f64) as usize));
            tris += c.mesh().triangles.len();
        }
        let t_levels = t_levels.elapsed();
        let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
        println!(
            "run {run}: {n} tris, total {:.1} ms = prepare {:.1} + setup {:.1} + pairs {:.1} + heap {:.1} + loop {:.1} + log {:.1} + levels {:.1} ({} collapses in {} passes, {} rejected, {tris} level tris)",
            ms(t.elapsed()),
            ms(t_prepare),
            ms(stats.time.setup),
            ms(stats.time.pairs),
            ms(stats.time.heap),
            ms(stats.time.collapse.saturating_sub(stats.time.heap)),
            ms(stats.time.log),
            ms(t_levels),
            stats.collapses,
            stats.passes,
            stats.rejected.total(),
        );
        last = Some(pm.base);
    }
    if let Some(base) = last {
        let r = measure(
            MeshRef::new(&m.positions, &m.triangles),
            MeshRef::new(&base.positions, &base.triangles),
            &MeasureOptions::DEFAULT,
        )
        .unwrap();
        println!(
            "{:?}: {} triangles, Hausdorff {:.4} %, RMS {:.4} % of the diagonal",
            schedule,
            base.triangles.len(),
            r.hausdorff_percent(),
            r.rms_percent()
        );
    }
}
