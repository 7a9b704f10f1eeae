//! A cancelled [`lodgen_pm::Meter`] stops the library's builds: one mesh's
//! LOD build fails with `BuildError::Cancelled` (never kept as an
//! unsimplified mesh with a warning), and a batch starts no file.

use std::sync::Arc;

use clap::Parser;
use lodgen::batch::{expand_inputs, run_batch_watched};
use lodgen::lod::{build_lods, build_lods_isolated, BuildError, BuildOptions, LevelRequest};
use lodgen::scene::{Primitive, Scene, SourceMesh};
use lodgen_pm::levels::LevelSpec;
use lodgen_pm::Meter;

#[derive(Parser)]
struct Options {
    #[command(flatten)]
    build: lodgen::cli::BuildArgs,
}

fn torus_scene() -> Scene {
    let m = lodgen_pm::shapes::torus(1.0, 0.35, 96, 48);
    Scene {
        meshes: vec![SourceMesh {
            name: "torus".into(),
            primitives: vec![Primitive {
                positions: m.positions.clone(),
                indices: m.triangles.as_flattened().to_vec(),
                ..Primitive::default()
            }],
        }],
        ..Scene::default()
    }
}

fn options(meter: &Arc<Meter>) -> BuildOptions {
    let mut opts = BuildOptions {
        levels: LevelRequest::Specs(vec![LevelSpec::Ratio(0.5), LevelSpec::Ratio(0.1)]),
        ..BuildOptions::default()
    };
    opts.meter = Some(Arc::clone(meter));
    opts
}

#[test]
fn a_cancelled_build_fails_as_cancelled() {
    let scene = torus_scene();
    let live = Arc::new(Meter::default());
    let built = build_lods(&scene, &options(&live), &mut |_| {}).unwrap();
    assert_eq!(built[0].lod.levels.len(), 2, "two levels");

    let meter = Arc::new(Meter::default());
    meter.cancel();
    let err = build_lods(&scene, &options(&meter), &mut |_| {}).unwrap_err();
    assert!(matches!(err, BuildError::Cancelled), "{err}");
    assert_eq!(err.to_string(), "cancelled");
    // (the isolating build does not keep the mesh as a warning)
    let mut scene = torus_scene();
    let err = build_lods_isolated(&mut scene, &options(&meter), &mut |_| {}).unwrap_err();
    assert!(matches!(err, BuildError::Cancelled), "{err}");
}

#[test]
fn a_cancelled_batch_starts_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in");
    std::fs::create_dir_all(&input).unwrap();
    let m = lodgen_pm::shapes::torus(1.0, 0.35, 48, 24);
    let mut text = String::new();
    for p in &m.positions {
        text += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for t in &m.triangles {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    for name in ["a.obj", "b.obj"] {
        std::fs::write(input.join(name), &text).unwrap();
    }
    let out = dir.path().join("out");
    let inputs = expand_inputs(&[input], Some(&out)).unwrap();
    let args = Options::try_parse_from(["lodgen", "-q"]).unwrap().build;
    let meter = Arc::new(Meter::default());
    meter.cancel();
    let done = run_batch_watched(&inputs, &out, &args, &|_| {}, &|_, _| {}, Some(meter)).unwrap();
    assert!(done.files.is_empty(), "{:?}", done.files);
    assert!(!out.join("a.glb").exists() && !out.join("b.glb").exists());

    let done = run_batch_watched(&inputs, &out, &args, &|_| {}, &|_, _| {}, None).unwrap();
    assert_eq!(done.files.len(), 2);
    assert!(out.join("a.glb").is_file() && out.join("b.glb").is_file());
}
