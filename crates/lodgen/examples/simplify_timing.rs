//! The Rust side of the Python benchmark (crates/lodgen/python/bench):
//! `simplify_timing MESH LEVELS ROUNDS [FLAGS...]` reads MESH as
//! `lodgen.read` does (every drawn mesh merged, positions and triangles
//! only), then times `lod::build_lods` with `--levels LEVELS FLAGS...` —
//! exactly the work `lodgen.simplify(vertices, faces, levels=..., **flags)`
//! does — ROUNDS times and prints one JSON line per round: wall seconds,
//! CPU seconds of the process (every thread) and triangles per level.

use anyhow::{Context, Result};
use clap::Parser;
use lodgen::cli::BuildArgs;
use lodgen::scene::{Primitive, Scene, SourceMesh};
use std::time::Instant;

#[derive(Parser)]
struct Options {
    #[command(flatten)]
    build: BuildArgs,
}

fn main() -> Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let (path, levels, rounds, flags) = match a.as_slice() {
        [_, p, l, r, flags @ ..] => (p.clone(), l.clone(), r.parse::<usize>()?, flags),
        _ => anyhow::bail!("usage: simplify_timing MESH LEVELS ROUNDS [FLAGS...]"),
    };
    let scene = lodgen::io::read_scene(path.as_ref()).with_context(|| format!("reading {path}"))?;
    let m = lodgen::cli::merged_mesh(&scene);
    let scene = Scene {
        meshes: vec![SourceMesh {
            name: String::new(),
            primitives: vec![Primitive {
                positions: m.positions.clone(),
                indices: m.triangles.as_flattened().to_vec(),
                ..Primitive::default()
            }],
        }],
        ..Scene::default()
    };
    let argv = ["lodgen", "--levels", levels.as_str()]
        .into_iter()
        .chain(flags.iter().map(String::as_str));
    let args = Options::try_parse_from(argv)?.build;
    let opts = args.build_options()?;
    for _ in 0..rounds {
        let (t0, c0) = (Instant::now(), cpu_seconds());
        let builds = lodgen::lod::build_lods(&scene, &opts, &mut |_| {})?;
        let (s, cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
        let tris: Vec<usize> = builds[0]
            .lod
            .levels
            .iter()
            .map(|l| l.triangle_count())
            .collect();
        println!("{{\"seconds\": {s}, \"cpu_seconds\": {cpu}, \"triangles\": {tris:?}}}");
    }
    Ok(())
}

/// User + system CPU time of the whole process (every thread), as
/// Python's `time.process_time()` (NaN off Unix).
#[cfg(unix)]
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage only writes the struct it is given.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } != 0 {
        return f64::NAN;
    }
    let t = |v: libc::timeval| v.tv_sec as f64 + v.tv_usec as f64 * 1e-6;
    t(u.ru_utime) + t(u.ru_stime)
}

#[cfg(not(unix))]
fn cpu_seconds() -> f64 {
    f64::NAN
}
