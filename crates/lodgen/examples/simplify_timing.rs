//! The Rust side of the Python benchmark (crates/lodgen/python/bench):
//! `simplify_timing MESH LEVELS ROUNDS` reads MESH as `lodgen.read` does
//! (every drawn mesh merged, positions and triangles only), then times
//! `lod::build_lods` with `--levels LEVELS` — exactly the work
//! `lodgen.simplify(vertices, faces, levels=...)` does — ROUNDS times and
//! prints one JSON line per round: seconds and triangles per level.

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
    let (path, levels, rounds) = match a.as_slice() {
        [_, p, l, r] => (p.clone(), l.clone(), r.parse::<usize>()?),
        _ => anyhow::bail!("usage: simplify_timing MESH LEVELS ROUNDS"),
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
    let args = Options::try_parse_from(["lodgen", "--levels", levels.as_str()])?.build;
    let opts = args.build_options()?;
    for _ in 0..rounds {
        let t0 = Instant::now();
        let builds = lodgen::lod::build_lods(&scene, &opts, &mut |_| {})?;
        let s = t0.elapsed().as_secs_f64();
        let tris: Vec<usize> = builds[0]
            .lod
            .levels
            .iter()
            .map(|l| l.triangle_count())
            .collect();
        println!("{{\"seconds\": {s}, \"triangles\": {tris:?}}}");
    }
    Ok(())
}
