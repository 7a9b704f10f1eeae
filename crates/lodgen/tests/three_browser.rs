//! lodgen's three.js loader (`crates/lodgen/web/three`) in headless Chromium
//! (`tests/js/three-lod.mjs`): writes the bunny (or, without the shared
//! asset, the generated knot) with `--progressive --quantize --compress
//! meshopt` and runs the script, which loads it progressively with three.js,
//! GLTFLoader and MeshoptDecoder from npm and checks every level's drawn
//! triangles and index hash against `lodgen view --print-levels`, stopping
//! at a level, non-blank screenshots (`target/test-out/three/`), and the same
//! file through three-gltf-extensions' MSFT_lod plugin with the
//! `coverageDistance` hook.
//!
//! Needs `node`, Chromium and `tests/js/node_modules`; without them the test
//! says so and passes, unless `LODGEN_BROWSER_TEST=1` or `CI=true`.

use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn missing_tools() -> Vec<String> {
    let mut missing = Vec::new();
    if Command::new("node").arg("--version").output().is_err() {
        missing.push("node".to_string());
    }
    let chromium = std::env::var("LODGEN_CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    if !std::path::Path::new(&chromium).exists() {
        missing.push(chromium);
    }
    for pkg in [
        "playwright-core",
        "three",
        "meshoptimizer",
        "three-gltf-extensions",
    ] {
        let p = root().join("tests/js/node_modules").join(pkg);
        if !p.exists() {
            missing.push(format!("{} (npm ci in tests/js)", p.display()));
        }
    }
    missing
}

#[test]
fn three_loader_streams_every_level_in_headless_chromium() {
    let missing = missing_tools();
    if !missing.is_empty() {
        let required = std::env::var("LODGEN_BROWSER_TEST").is_ok_and(|v| v == "1")
            || std::env::var("CI").as_deref() == Ok("true");
        assert!(
            !required,
            "LODGEN_BROWSER_TEST=1 or CI=true, but missing: {missing:?}"
        );
        eprintln!("three.js browser test skipped, missing: {missing:?}");
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
    let out = root().join("target/test-out/three");
    std::fs::create_dir_all(&out).unwrap();
    let result = Command::new("node")
        .arg(root().join("tests/js/three-lod.mjs"))
        .args(["--lodgen", bin])
        .arg(&glb)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("running node");
    let log = format!(
        "{}{}",
        String::from_utf8_lossy(&result.stdout),
        String::from_utf8_lossy(&result.stderr)
    );
    eprintln!("{log}");
    assert!(result.status.success(), "three-lod.mjs failed:\n{log}");
}
