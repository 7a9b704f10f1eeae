//! Wall and CPU time (all of the process's threads) of one simplification
//! to a ratio, run after run, with a digest of the progressive mesh: the
//! figures to compare two builds on a loaded machine (minimum and median
//! CPU time), and the check that a change leaves the output unchanged.
//!
//! `cargo run --release -p lodgen-pm --example cpu_simplify [mesh.obj] [subdivisions] [runs] [plain|wedges] [ratio] [cluster triangles]`
//!
//! `plain` is `simplify` (position only, what `xtask bench` times);
//! `wedges` is `simplify_with_wedges` with every vertex its own wedge and
//! no attributes (what the CLI and the Python module run on a scan).
//! `cluster triangles` sets `SimplifyOptions::partition` (0: off; default:
//! the library's default).
//! The environment variable `REACH=F` sets `SimplifyOptions::reach` to
//! `Some(F)`, `REACH=off` to `None` (unset: the library's default,
//! `Some(DEFAULT_REACH_FACTOR)`).

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::time::Instant;

use lodgen_pm::metric::{measure, MeasureOptions, MeshRef};
use lodgen_pm::{simplify, simplify_with_wedges, SimplifyOptions};

#[path = "common/mod.rs"]
mod common;
use common::mesh_from_args;

/// CPU time of every thread of this process so far, in ms (Linux
/// schedstat; 0 elsewhere).
fn cpu_ms() -> f64 {
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return 0.0;
    };
    dir.filter_map(|e| e.ok())
        .filter_map(|e| std::fs::read_to_string(e.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .sum::<f64>()
        / 1e6
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let runs: usize = args.get(3).map_or(9, |s| s.parse().unwrap());
    let wedges = args.get(4).is_some_and(|s| s == "wedges");
    let ratio: f64 = args.get(5).map_or(0.02, |s| s.parse().unwrap());
    let m = mesh_from_args(&args);
    let indices = m.indices();
    let n = m.triangles.len();
    // (default: the library's; 0 = the whole-mesh walk throughout)
    let partition = args.get(6).map_or(SimplifyOptions::DEFAULT.partition, |s| {
        Some(s.parse::<usize>().unwrap())
    });
    let opts = SimplifyOptions::DEFAULT
        .with_target_ratio(ratio)
        .with_partition(partition)
        .with_reach(match std::env::var("REACH") {
            Err(_) => SimplifyOptions::DEFAULT.reach,
            Ok(s) if s == "off" => None,
            Ok(s) => Some(s.parse().expect("REACH: a number or off")),
        });
    let (mut wall, mut cpu) = (Vec::new(), Vec::new());
    let mut digest = 0;
    let mut last = None;
    for _ in 0..runs {
        let (t, c) = (Instant::now(), cpu_ms());
        let out = if wedges {
            simplify_with_wedges(&m.positions, &indices, &[], 0, &opts)
        } else {
            simplify(&m.positions, &indices, &opts)
        }
        .unwrap();
        cpu.push(cpu_ms() - c);
        wall.push(t.elapsed().as_secs_f64() * 1e3);
        let mut h = DefaultHasher::new();
        out.pm.base.triangles.hash(&mut h);
        for p in &out.pm.base.positions {
            p.map(f32::to_bits).hash(&mut h);
        }
        for s in &out.pm.splits {
            format!("{s:?}").hash(&mut h);
        }
        digest = h.finish();
        last = Some(out.pm.base);
    }
    let stat = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (v[0], v[v.len() / 2])
    };
    let ((wmin, wmed), (cmin, cmed)) = (stat(&mut wall), stat(&mut cpu));
    let base = last.expect("at least one run");
    let e = measure(
        MeshRef::new(&m.positions, &m.triangles),
        MeshRef::new(&base.positions, &base.triangles),
        &MeasureOptions::DEFAULT,
    )
    .unwrap();
    println!(
        "{n} tris: wall min {wmin:.1} med {wmed:.1} ms, cpu min {cmin:.1} med {cmed:.1} ms, digest {digest:016x}; {} tris H {:.4} % RMS {:.4} %",
        base.triangles.len(),
        e.hausdorff_percent(),
        e.rms_percent()
    );
}
