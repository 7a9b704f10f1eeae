//! Times the metric as `lodgen` uses it: one [`Reference`] of the prepared mesh, then the
//! levels at 50, 10 and 2 % of one simplification measured against it, on one thread (thread
//! CPU time, so figures survive a loaded machine), and prints every figure in full so two
//! builds can be compared bit for bit.
//!
//! `cargo run --release -p lodgen-pm --example time_metric [path/to/mesh.obj] [subdivisions] [runs] [bounded|dense|dense:N|metro]`
//! (`bounded`: [`MeasureOptions::BOUNDED`], `dense`: METRO at 64 samples per triangle, `dense:N`
//! at N, `metro`: [`MeasureOptions::METRO`], instead of the default)

use std::time::Instant;

use lodgen_pm::metric::{MeasureOptions, MeshRef, Reference};
use lodgen_pm::{simplify, SimplifyOptions};

#[path = "common/mod.rs"]
mod common;
use common::{mesh_from_args, thread_cpu_ms};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let runs: usize = args.get(3).map_or(3, |s| s.parse().unwrap());
    let mopts = match args.get(4).map(String::as_str) {
        Some("bounded") => MeasureOptions::BOUNDED,
        Some("dense") => MeasureOptions::METRO.with_samples_per_triangle(64.0),
        Some("metro") => MeasureOptions::METRO,
        Some(d) if d.starts_with("floor:") => {
            MeasureOptions::DEFAULT.with_min_samples(d[6..].parse().unwrap())
        }
        Some(d) if d.starts_with("dense:") => {
            MeasureOptions::METRO.with_samples_per_triangle(d[6..].parse().unwrap())
        }
        _ => MeasureOptions::DEFAULT,
    };
    let m = mesh_from_args(&args);
    let indices: Vec<u32> = m.triangles.iter().flatten().copied().collect();
    let full = lodgen_pm::mesh::prepare(&m.positions, &indices)
        .unwrap()
        .mesh;
    drop(m);
    let opts = SimplifyOptions::DEFAULT.with_target_ratio(0.02);
    let out = simplify(&full.positions, &indices_of(&full), &opts).unwrap();
    let n = full.triangles.len();
    let levels: Vec<_> = [0.5, 0.1, 0.02]
        .iter()
        .map(|r| {
            out.pm
                .mesh_at_splits(out.pm.splits_for_triangles((r * n as f64) as usize))
        })
        .collect();
    println!("{n} triangles, {runs} runs, one thread");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut best = [f64::INFINITY; 4];
    for run in 0..runs {
        let t = pool.install(|| {
            let mut t = [0.0; 4];
            let t0 = thread_cpu_ms();
            let r = Reference::new(MeshRef::new(&full.positions, &full.triangles)).unwrap();
            t[0] = thread_cpu_ms() - t0;
            for (k, l) in levels.iter().enumerate() {
                let t0 = thread_cpu_ms();
                let e = r
                    .measure(
                        MeshRef::new(&l.positions, &l.triangles),
                        &mopts,
                    )
                    .unwrap();
                t[k + 1] = thread_cpu_ms() - t0;
                if run == 0 {
                    println!(
                        "level {k}: {} tris  A→B {:e} ≤{:e} {:e} {:e} ({})  B→A {:e} ≤{:e} {:e} {:e} ({})",
                        l.triangles.len(),
                        e.a_to_b.max,
                        e.a_to_b.max_bound,
                        e.a_to_b.mean,
                        e.a_to_b.rms,
                        e.a_to_b.samples,
                        e.b_to_a.max,
                        e.b_to_a.max_bound,
                        e.b_to_a.mean,
                        e.b_to_a.rms,
                        e.b_to_a.samples
                    );
                }
            }
            t
        });
        for k in 0..4 {
            best[k] = best[k].min(t[k]);
        }
    }
    let wall = Instant::now();
    let r = Reference::new(MeshRef::new(&full.positions, &full.triangles)).unwrap();
    for l in &levels {
        r.measure(MeshRef::new(&l.positions, &l.triangles), &mopts)
            .unwrap();
    }
    println!(
        "CPU ms (min of {runs}): reference {:.1}, levels {:.1} {:.1} {:.1}, total {:.1}; all threads ({}): {:.1} ms wall",
        best[0],
        best[1],
        best[2],
        best[3],
        best.iter().sum::<f64>(),
        rayon::current_num_threads(),
        wall.elapsed().as_secs_f64() * 1e3
    );
}

fn indices_of(m: &lodgen_pm::Mesh) -> Vec<u32> {
    m.triangles.iter().flatten().copied().collect()
}
