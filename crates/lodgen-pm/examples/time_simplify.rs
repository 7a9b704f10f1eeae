//! Median wall time of `simplify` to 2 % plus the 50/10/2 % level
//! extraction (what `xtask bench` times for lodgen), and a digest of the
//! progressive mesh, to check that a change leaves the output unchanged.
//!
//! `cargo run --release -p lodgen-pm --example time_simplify [mesh.obj] [subdivisions] [runs]`

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::time::Instant;

use lodgen_pm::{simplify, SimplifyOptions};

#[path = "common/mod.rs"]
mod common;
use common::mesh_from_args;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let runs: usize = args.get(3).map_or(9, |s| s.parse().unwrap());
    let m = mesh_from_args(&args);
    let indices = m.indices();
    let n = m.triangles.len();
    let mut times = Vec::new();
    let mut digest = 0;
    for _ in 0..runs {
        let t = Instant::now();
        let opts = SimplifyOptions::DEFAULT.with_target_ratio(0.02);
        let out = simplify(&m.positions, &indices, &opts).unwrap();
        let mut c = out.pm.cursor();
        let mut got = Vec::new();
        for r in [0.02, 0.1, 0.5] {
            c.seek(out.pm.splits_for_triangles((r * n as f64) as usize));
            got.push(c.mesh().clone());
        }
        times.push(t.elapsed().as_secs_f64() * 1e3);
        let mut h = DefaultHasher::new();
        for l in &got {
            l.triangles.hash(&mut h);
            for p in &l.positions {
                p.map(f32::to_bits).hash(&mut h);
            }
        }
        out.pm.splits.len().hash(&mut h);
        digest = h.finish();
    }
    times.sort_by(f64::total_cmp);
    println!(
        "{n} tris: median {:.1} ms (min {:.1}), digest {digest:016x}",
        times[times.len() / 2],
        times[0]
    );
}
