//! Times the polish of the levels at 50, 10 and 2 % of one simplification,
//! as `lodgen` runs it ([`lodgen_pm::polish_clusters`], pairs from the
//! simplification's clusters) and the hierarchy's way ([`lodgen_pm::polish`]),
//! on one thread (thread CPU time), and measures each level before and
//! after (Hausdorff / RMS in % of the diagonal).
//!
//! `cargo run --release -p lodgen-pm --example time_polish [path/to/mesh.obj] [subdivisions] [runs]`

use std::time::Instant;

use lodgen_pm::metric::{MeasureOptions, MeshRef, Reference};
use lodgen_pm::polish::Original;
use lodgen_pm::{polish, polish_clusters, prepare, simplify, Mesh, PolishOptions, SimplifyOptions};

#[path = "common/mod.rs"]
mod common;
use common::{mesh_from_args, thread_cpu_ms};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let runs: usize = args.get(3).map_or(3, |s| s.parse().unwrap());
    let raw = mesh_from_args(&args);
    let m = prepare(&raw.positions, &raw.indices()).unwrap().mesh;
    let n = m.triangles.len();
    let ratios = [0.5, 0.1, 0.02];
    let out = simplify(
        &m.positions,
        &m.indices(),
        &SimplifyOptions::DEFAULT.with_target_ratio(0.02),
    )
    .unwrap();
    let pm = out.pm;
    let full = pm.mesh_at_splits(pm.len());
    let full_ref = MeshRef::new(&full.positions, &full.triangles);
    let reference = Reference::new(full_ref).unwrap();
    let mopts = MeasureOptions::DEFAULT;
    let err = |l: &Mesh| {
        let e = reference
            .measure(MeshRef::new(&l.positions, &l.triangles), &mopts)
            .unwrap();
        format!("{:.4} / {:.5}", e.hausdorff_percent(), e.rms_percent())
    };
    let popts = PolishOptions::DEFAULT;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        let t = thread_cpu_ms();
        let original = Original::new(full_ref);
        println!("original's adjacency: {:.1} ms", thread_cpu_ms() - t);
        for r in ratios {
            let k = pm.splits_for_triangles((r * n as f64) as usize);
            let level = pm.mesh_at_splits(k);
            let mut clusters = level.clone();
            let mut exact = level.clone();
            let mut times = (Vec::new(), Vec::new());
            for _ in 0..runs {
                clusters.clone_from(&level);
                let t = thread_cpu_ms();
                let rep = pm.representatives(k);
                polish_clusters(&original, &mut clusters, &rep, &popts);
                times.0.push(thread_cpu_ms() - t);
                exact.clone_from(&level);
                let t = thread_cpu_ms();
                polish(full_ref, reference.bvh(), &mut exact, &popts);
                times.1.push(thread_cpu_ms() - t);
            }
            let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
            let _ = Instant::now();
            println!(
                "{:>4} % {:>8} tris: none {} | clusters {} ({:.1} ms) | exact {} ({:.1} ms)",
                r * 100.0,
                level.triangles.len(),
                err(&level),
                err(&clusters),
                min(&times.0),
                err(&exact),
                min(&times.1),
            );
        }
    });
}
