//! Times `lodgen_pm::metric::measure` on the bunny against a crude ~1.4k-triangle copy made by
//! vertex clustering (Rossignac–Borrel), the size of a 2% level.
//!
//! `cargo run --release -p lodgen-pm --example measure_bunny [path/to/bunny.obj] [runs] [cells] [densities]`

use std::time::Instant;

use lodgen_pm::metric::bvh::TriangleBvh;
use lodgen_pm::metric::{measure, one_sided, MeasureOptions, MeshRef};
use lodgen_pm::Mesh;

#[path = "common/mod.rs"]
mod common;
use common::{load_obj, thread_cpu_ms};

/// Vertex clustering on a grid of `cells` cells along the longest side: every vertex moves to
/// the mean of its cell; triangles that lose a corner are dropped.
fn cluster(v: &[[f32; 3]], f: &[[u32; 3]], cells: f32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in v {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let side = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f32::max) / cells;
    let key =
        |p: &[f32; 3]| -> [i32; 3] { std::array::from_fn(|k| ((p[k] - lo[k]) / side) as i32) };
    let mut order: Vec<u32> = (0..v.len() as u32).collect();
    order.sort_by_key(|&i| key(&v[i as usize]));
    let mut id = vec![0u32; v.len()];
    let mut out: Vec<[f32; 3]> = Vec::new();
    let mut count: Vec<f32> = Vec::new();
    let mut last = None;
    for &i in &order {
        let k = key(&v[i as usize]);
        if last != Some(k) {
            out.push([0.0; 3]);
            count.push(0.0);
            last = Some(k);
        }
        let c = out.len() - 1;
        id[i as usize] = c as u32;
        for j in 0..3 {
            out[c][j] += v[i as usize][j];
        }
        count[c] += 1.0;
    }
    for (p, n) in out.iter_mut().zip(&count) {
        *p = p.map(|x| x / n);
    }
    let tris = f
        .iter()
        .map(|t| t.map(|i| id[i as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    (out, tris)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .cloned()
        .unwrap_or_else(|| "/work/shared/assets/bunny.obj".into());
    let runs: usize = args.get(2).map_or(10, |s| s.parse().unwrap());
    let Mesh {
        positions: v,
        triangles: f,
    } = load_obj(&path);
    let cells: f32 = args.get(3).map_or(15.0, |s| s.parse().unwrap());
    let (cv, cf) = cluster(&v, &f, cells);
    let a = MeshRef::new(&v, &f);
    let b = MeshRef::new(&cv, &cf);
    let opts = MeasureOptions::DEFAULT;
    println!(
        "A: {} triangles, B: {} triangles, threads: {}",
        f.len(),
        cf.len(),
        rayon::current_num_threads()
    );
    let mut times = Vec::new();
    let mut report = None;
    for _ in 0..runs {
        let t = Instant::now();
        report = Some(measure(a, b, &opts).unwrap());
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    let r = report.unwrap();
    println!(
        "measure: min {:.1} ms, median {:.1} ms over {runs} runs",
        times[0],
        times[runs / 2]
    );
    println!(
        "A→B: max {:.6} mean {:.6} rms {:.6} ({} samples)",
        r.a_to_b.max, r.a_to_b.mean, r.a_to_b.rms, r.a_to_b.samples
    );
    println!(
        "B→A: max {:.6} mean {:.6} rms {:.6} ({} samples)",
        r.b_to_a.max, r.b_to_a.mean, r.b_to_a.rms, r.b_to_a.samples
    );
    println!(
        "Hausdorff {:.4}% RMS {:.4}% of diagonal {:.4}",
        r.hausdorff_percent(),
        r.rms_percent(),
        r.diagonal
    );
    // Phases, sequentially on one thread, in thread CPU time.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut best = [f64::INFINITY; 5];
    for _ in 0..runs {
        let t = pool.install(|| {
            let t0 = thread_cpu_ms();
            let bvh_a = TriangleBvh::new(a).unwrap();
            let t1 = thread_cpu_ms();
            let bvh_b = TriangleBvh::new(b).unwrap();
            let t2 = thread_cpu_ms();
            one_sided(a, &bvh_b, &opts).unwrap();
            let t3 = thread_cpu_ms();
            one_sided(b, &bvh_a, &opts).unwrap();
            let t4 = thread_cpu_ms();
            measure(a, b, &opts).unwrap();
            let t5 = thread_cpu_ms();
            [t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4]
        });
        for k in 0..5 {
            best[k] = best[k].min(t[k]);
        }
    }
    println!(
        "one thread, CPU ms (min of {runs}): build A {:.1}, build B {:.1}, A→B {:.1}, B→A {:.1}; whole measure {:.1}",
        best[0], best[1], best[2], best[3], best[4]
    );
    // Sensitivity of the estimate to density, for the record.
    let densities: &[f64] = if args.get(4).is_some_and(|s| s == "densities") {
        &[1.0, 4.0, 8.0, 32.0]
    } else {
        &[]
    };
    for &per in densities {
        let t = Instant::now();
        let r = measure(a, b, &opts.with_samples_per_triangle(per)).unwrap();
        println!(
            "{per} per triangle: {:.1} ms, Hausdorff {:.4}% RMS {:.4}% (A→B max {:.6}, B→A max {:.6})",
            t.elapsed().as_secs_f64() * 1e3,
            r.hausdorff_percent(),
            r.rms_percent(),
            r.a_to_b.max,
            r.b_to_a.max
        );
    }
}
