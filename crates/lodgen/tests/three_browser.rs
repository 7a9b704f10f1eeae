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
//! against Rust's; the same input without `--quantize` (f32 positions, which
//! the loader computes from the records' grid points), every level's hashes.
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
    // f32 positions (no --quantize): the loader computes them from the
    // records' grid points
    let float = dir.path().join("float.glb");
    let status = Command::new(bin)
        .arg(&input)
        .arg("-o")
        .arg(&float)
        .args(["--levels", "100%,50%,10%,2%", "--progressive", "--quiet"])
        .status()
        .unwrap();
    assert!(status.success());
    let mut extra = vec!["--float".to_string(), float.to_str().unwrap().to_string()];
    // a stream with wedges (spot.obj's UVs), drawn with its attributes
    let spot = dir.path().join("spot.glb");
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
        extra.extend([
            "--attributes".to_string(),
            spot.to_str().unwrap().to_string(),
        ]);
        let uv = dir.path().join("uvrange.glb");
        textured_spot_quantized(&input, &uv);
        extra.extend(["--uv-range".to_string(), uv.to_str().unwrap().to_string()]);
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
    let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
    browser::run_script("three-lod.mjs", &[&args[..], &extra].concat());
}

/// spot.obj as glTF input with a textured material (its UVs leave [0, 1]),
/// written to `out` with `--progressive --quantize --compress meshopt`:
/// TEXCOORD_0 normalized u16 over the UVs' range, KHR_texture_transform on
/// the material's texture.
fn textured_spot_quantized(spot: &std::path::Path, out: &std::path::Path) {
    let bin = env!("CARGO_BIN_EXE_lodgen");
    let plain = out.with_file_name("spot-plain.glb");
    let run = |input: &std::path::Path, output: &std::path::Path, args: &[&str]| {
        let status = Command::new(bin)
            .arg(input)
            .arg("-o")
            .arg(output)
            .args(args)
            .arg("--quiet")
            .status()
            .unwrap();
        assert!(status.success());
    };
    run(spot, &plain, &["--levels", "100%"]);
    let bytes = std::fs::read(&plain).unwrap();
    let (mut root, data) = lodgen::progressive::parse_glb(&bytes).unwrap();
    let png = support::gltf::base64(&support::gltf::PNG_2X2);
    root["images"] = serde_json::json!([{ "uri": format!("data:image/png;base64,{png}") }]);
    root["textures"] = serde_json::json!([{ "source": 0 }]);
    root["materials"] =
        serde_json::json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
    for mesh in root["meshes"].as_array_mut().unwrap() {
        for p in mesh["primitives"].as_array_mut().unwrap() {
            p["material"] = 0.into();
        }
    }
    let textured = out.with_file_name("spot-textured.glb");
    let glb = lodgen::progressive::write_glb(&root, data).unwrap();
    std::fs::write(&textured, glb).unwrap();
    let levels = ["--levels", "100%,50%,10%,2%", "--progressive", "--quantize"];
    run(
        &textured,
        out,
        &[&levels[..], &["--compress", "meshopt"]].concat(),
    );
}
