//! lodgen's three.js loader (`crates/lodgen/web/three`) in headless Chromium
//! (`tests/js/three-lod.mjs`): writes the bunny (or, without the shared
//! asset, the generated knot) with `--progressive --quantize --compress
//! meshopt` and runs the script, which loads it progressively with three.js,
//! GLTFLoader and MeshoptDecoder from npm and checks every level's drawn
//! triangles and index hash against `lodgen view --print-levels`, stopping
//! at a level, non-blank screenshots (`target/test-out/three/`), and the same
//! file through three-gltf-extensions' MSFT_lod plugin with the
//! `coverageDistance` hook; with the shared assets, spot.obj's stream (UVs
//! as wedges) drawn with its attributes, each level's corner attribute hash
//! against Rust's.
//!
//! Needs `node`, Chromium and `tests/js/node_modules`; without them the test
//! says so and passes, unless `LODGEN_BROWSER_TEST=1` or `CI=true`.

mod support;

use std::process::Command;

use support::{browser, root};

#[test]
fn three_loader_streams_every_level_in_headless_chromium() {
    let packages = [
        "playwright-core",
        "three",
        "meshoptimizer",
        "three-gltf-extensions",
    ];
    if !browser::ready("three.js browser test", &packages) {
        return;
    }
    let input =
        lodgen::assets::shared_asset("bunny.obj").unwrap_or_else(|| root().join("assets/knot.obj"));
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("model.glb");
    let bin = env!("CARGO_BIN_EXE_lodgen");
    let status = Command::new(bin)
        .arg(&input)
        .arg("-o")
        .arg(&glb)
        .args(["--levels", "100%,50%,10%,2%", "--progressive", "--quantize"])
        .args(["--compress", "meshopt", "--quiet"])
        .status()
        .unwrap();
    assert!(status.success());
    // a stream with wedges (spot.obj's UVs), drawn with its attributes
    let spot = dir.path().join("spot.glb");
    let mut extra = Vec::new();
    if let Some(input) = lodgen::assets::shared_asset("spot.obj") {
        let status = Command::new(bin)
            .arg(&input)
            .arg("-o")
            .arg(&spot)
            .args(["--levels", "100%,50%,10%,2%", "--progressive", "--quantize"])
            .args(["--compress", "meshopt", "--quiet"])
            .status()
            .unwrap();
        assert!(status.success());
        extra = vec!["--attributes", spot.to_str().unwrap()];
    }
    let out = root().join("target/test-out/three");
    std::fs::create_dir_all(&out).unwrap();
    let args = [
        "--lodgen",
        bin,
        glb.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    browser::run_script("three-lod.mjs", &[&args[..], &extra].concat());
}
