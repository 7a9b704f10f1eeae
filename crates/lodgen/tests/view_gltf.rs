//! `lodgen IN -o OUT --progressive` end to end: the written `.glb` / `.gltf`
//! carries `LODGEN_progressive` on the coarsest level (in `extensionsUsed`
//! only), `lodgen view` loads it, and after each level's record count the
//! stream's mesh has that MSFT_lod level's triangle count. When the Khronos
//! validator is installed (`tests/js/node_modules/gltf-validator`), both
//! files must validate with 0 errors.

use lodgen::progressive::{parse_glb, EXTENSION};
use lodgen::view::ViewData;
use lodgen_pm::shapes::icosphere;
use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Triangle count of each level of the first MSFT_lod chain, finest first.
fn chain_triangles(doc: &Value) -> Vec<usize> {
    let node = doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n.pointer("/extensions/MSFT_lod").is_some())
        .expect("an MSFT_lod node");
    let mut meshes = vec![node["mesh"].as_u64().unwrap() as usize];
    for id in node["extensions"]["MSFT_lod"]["ids"].as_array().unwrap() {
        meshes.push(
            doc["nodes"][id.as_u64().unwrap() as usize]["mesh"]
                .as_u64()
                .unwrap() as usize,
        );
    }
    meshes
        .iter()
        .map(|&m| {
            doc["meshes"][m]["primitives"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| {
                    doc["accessors"][p["indices"].as_u64().unwrap() as usize]["count"]
                        .as_u64()
                        .unwrap() as usize
                        / 3
                })
                .sum()
        })
        .collect()
}

#[test]
fn progressive_output_loads_in_the_viewer_and_validates() {
    let dir = root().join(format!("target/test-out/view-gltf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let m = icosphere(4);
    let mut text = String::new();
    for p in &m.positions {
        text += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for t in &m.triangles {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    let input = dir.join("ico.obj");
    std::fs::write(&input, text).unwrap();

    for out in ["ico.glb", "ico.gltf"] {
        let out = dir.join(out);
        let status = Command::new(env!("CARGO_BIN_EXE_lodgen"))
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .args(["--levels", "50%,10%,2%", "--progressive", "--quiet"])
            .status()
            .unwrap();
        assert!(status.success());
        let doc: Value = if out.extension().unwrap() == "glb" {
            parse_glb(&std::fs::read(&out).unwrap()).unwrap().0
        } else {
            serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap()
        };
        assert!(doc["extensionsUsed"]
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e == EXTENSION));
        let required = doc.get("extensionsRequired").and_then(Value::as_array);
        assert!(!required.is_some_and(|r| r.iter().any(|e| e == EXTENSION)));
        let tris = chain_triangles(&doc);
        // --levels 50%,10%,2%: three levels, finest first
        assert_eq!(tris.len(), 3);

        let data = ViewData::load(&out).unwrap();
        assert_eq!(data.source, "gltf");
        let s = data.level_summary().unwrap();
        let got: Vec<usize> = s["levels"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| l["triangles"].as_u64().unwrap() as usize)
            .collect();
        assert_eq!(got, tris, "{}", out.display());
        // the extension sits on the coarsest level's mesh
        let coarsest = doc["meshes"]
            .as_array()
            .unwrap()
            .iter()
            .position(|m| {
                m["primitives"][0]
                    .pointer(&format!("/extensions/{EXTENSION}"))
                    .is_some()
            })
            .unwrap();
        assert!(doc["meshes"][coarsest]["name"]
            .as_str()
            .unwrap()
            .ends_with("_LOD2"));
    }

    let validator = root().join("tests/js/node_modules/gltf-validator");
    if validator.exists() {
        let out = Command::new("node")
            .arg(root().join("tests/js/validate.mjs"))
            .args(["--require", "--verbose"])
            .arg(&dir)
            .output()
            .unwrap();
        let log = String::from_utf8_lossy(&out.stdout).into_owned()
            + &String::from_utf8_lossy(&out.stderr);
        eprintln!("{log}");
        assert!(out.status.success(), "gltf-validator:\n{log}");
    } else {
        eprintln!("gltf-validator not installed (npm ci in tests/js): validation skipped");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
