//! Nothing dropped silently, and one bad mesh never fails a scene: a glTF
//! with a morph-target mesh, target names, node extras and a `weights`
//! animation keeps all of it at every level (plain and `--quantize`); a
//! mesh whose triangles are all degenerate is written unsimplified with a
//! warning and exit code 3, and `--strict` makes it an error that writes
//! nothing. Outputs go to `$LODGEN_TEST_OUT` for the glTF-Validator;
//! Babylon.js in headless Chromium plays the weight animation.

mod support;

use serde_json::{json, Value};
use support::gltf::{base64, f32_bytes as f32s, glb_json};
use support::{lodgen, publish};

/// A torus "Head" with one POSITION + NORMAL morph target ("inflate"), mesh
/// weights, node extras and an animation of the weight; with `broken`, a
/// second mesh whose two triangles are degenerate.
fn morph_scene(broken: bool) -> Value {
    let m = lodgen_pm::shapes::torus(1.0, 0.35, 32, 16);
    let n = m.positions.len();
    let mut bin = f32s(m.positions.iter().flatten().copied());
    // inflate: outward from the ring, more on top
    let disp: Vec<[f32; 3]> = m
        .positions
        .iter()
        .map(|p| {
            let r = (p[0] * p[0] + p[1] * p[1]).sqrt().max(1e-6);
            let s = 0.2 + 0.1 * p[2];
            [p[0] / r * s, p[1] / r * s, 0.1]
        })
        .collect();
    let disp_at = bin.len();
    bin.extend(f32s(disp.iter().flatten().copied()));
    let ndisp_at = bin.len();
    bin.extend(f32s((0..n).flat_map(|_| [0.0, 0.0, 0.05])));
    let idx_at = bin.len();
    bin.extend(m.triangles.iter().flatten().flat_map(|i| i.to_le_bytes()));
    let keys_at = bin.len();
    bin.extend(f32s([0.0, 0.5, 1.0]));
    let values_at = bin.len();
    bin.extend(f32s([0.0, 1.0, 0.0]));
    let degenerate_at = bin.len();
    bin.extend(f32s([5.0, 0.0, 0.0].repeat(3)));
    let (lo, hi) = disp
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), d| {
            (
                std::array::from_fn(|k| lo[k].min(d[k])),
                std::array::from_fn(|k| hi[k].max(d[k])),
            )
        });
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "Head", "mesh": 0, "extras": {"id": 7}}],
        "meshes": [{
            "name": "face",
            "primitives": [{
                "attributes": {"POSITION": 0},
                "indices": 3,
                "targets": [{"POSITION": 1, "NORMAL": 2}]
            }],
            "weights": [0.25],
            "extras": {"targetNames": ["inflate"]}
        }],
        "animations": [{
            "name": "breathe",
            "samplers": [{"input": 4, "output": 5}],
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]
        }],
        "buffers": [{"byteLength": bin.len(), "uri": format!("data:application/octet-stream;base64,{}", base64(&bin))}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 12 * n},
            {"buffer": 0, "byteOffset": disp_at, "byteLength": 12 * n},
            {"buffer": 0, "byteOffset": ndisp_at, "byteLength": 12 * n},
            {"buffer": 0, "byteOffset": idx_at, "byteLength": 12 * m.triangles.len()},
            {"buffer": 0, "byteOffset": keys_at, "byteLength": 12},
            {"buffer": 0, "byteOffset": values_at, "byteLength": 12},
            {"buffer": 0, "byteOffset": degenerate_at, "byteLength": 36}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3",
             "min": [-1.35, -1.35, -0.35], "max": [1.35, 1.35, 0.35]},
            {"bufferView": 1, "componentType": 5126, "count": n, "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 2, "componentType": 5126, "count": n, "type": "VEC3"},
            {"bufferView": 3, "componentType": 5125, "count": 3 * m.triangles.len(), "type": "SCALAR"},
            {"bufferView": 4, "componentType": 5126, "count": 3, "type": "SCALAR", "min": [0.0], "max": [1.0]},
            {"bufferView": 5, "componentType": 5126, "count": 3, "type": "SCALAR"},
            {"bufferView": 6, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [5.0, 0.0, 0.0], "max": [5.0, 0.0, 0.0]}
        ]
    });
    if broken {
        doc["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!({"name": "Sliver", "mesh": 1}));
        doc["scenes"][0]["nodes"] = json!([0, 1]);
        doc["meshes"].as_array_mut().unwrap().push(json!({
            "name": "sliver",
            "primitives": [{"attributes": {"POSITION": 6}, "mode": 4}]
        }));
    }
    doc
}

#[test]
fn morph_targets_names_extras_and_weight_animations_reach_every_level() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("head.gltf");
    std::fs::write(&input, serde_json::to_vec(&morph_scene(false)).unwrap()).unwrap();
    for (name, extra) in [("plain", &[][..]), ("quantized", &["--quantize"][..])] {
        let out = dir.path().join(format!("morph-{name}.glb"));
        let mut args = vec![
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--levels",
            "50%,10%",
            "-q",
        ];
        args.extend_from_slice(extra);
        let r = lodgen(&args);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(0), "{name}: {stderr}");
        assert!(stderr.is_empty(), "{name}: no warning expected: {stderr}");
        let json = glb_json(&out);
        let meshes = json["meshes"].as_array().unwrap();
        assert_eq!(meshes.len(), 2, "{name}: one mesh per level");
        for m in meshes {
            assert_eq!(m["weights"], json!([0.25]), "{name}");
            assert_eq!(m["extras"]["targetNames"], json!(["inflate"]), "{name}");
            for p in m["primitives"].as_array().unwrap() {
                let t = &p["targets"][0];
                assert!(
                    t["POSITION"].is_u64() && t["NORMAL"].is_u64(),
                    "{name}: {p}"
                );
                let acc = &json["accessors"][t["POSITION"].as_u64().unwrap() as usize];
                assert_eq!(
                    acc["count"],
                    json["accessors"][p["attributes"]["POSITION"].as_u64().unwrap() as usize]
                        ["count"]
                );
            }
        }
        // the animated node is the one drawing LOD 0
        let channel = &json["animations"][0]["channels"][0];
        assert_eq!(channel["target"]["path"], "weights");
        let node = &json["nodes"][channel["target"]["node"].as_u64().unwrap() as usize];
        assert_eq!(node["mesh"], 0, "{name}: {node}");
        assert_eq!(json["nodes"][0]["extras"]["id"], 7, "{name}");
        assert_eq!(json["nodes"][0]["name"], "Head");
        publish(&out, &format!("morph-{name}.glb"));
    }
}

#[test]
fn a_degenerate_mesh_is_written_unsimplified_with_a_warning_unless_strict() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scene.gltf");
    std::fs::write(&input, serde_json::to_vec(&morph_scene(true)).unwrap()).unwrap();
    let out = dir.path().join("faults.glb");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let r = lodgen(&[i, "-o", o, "--levels", "50%", "-q"]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(3), "written, with warnings: {stderr}");
    assert!(
        stderr.contains("warning: ")
            && stderr.contains("scene.gltf: meshes[1] (mesh `sliver`): written unsimplified"),
        "{stderr}"
    );
    let json = glb_json(&out);
    let names: Vec<&str> = json["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["face_LOD0", "sliver_LOD0"]);
    publish(&out, "faults.glb");
    // --strict: an error naming the mesh, nothing written
    std::fs::remove_file(&out).unwrap();
    let r = lodgen(&[i, "-o", o, "--levels", "50%", "-q", "--strict"]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("sliver"), "{stderr}");
    assert!(!out.exists());
}

/// Babylon.js in headless Chromium (`tests/js/babylon-morph.mjs`) loads the
/// morphed head (every MSFT_lod level, plain and `--quantize`) and plays
/// `breathe`: the shown level has the target `inflate`, and its influence
/// follows the file's keyframes, with no page or console error.
#[test]
fn babylon_animates_the_morph_weight_in_headless_chromium() {
    if !support::browser::ready(
        "Babylon.js morph test",
        &[
            "playwright-core",
            "@babylonjs/core",
            "@babylonjs/loaders",
            "esbuild",
        ],
    ) {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("head.gltf");
    std::fs::write(&input, serde_json::to_vec(&morph_scene(false)).unwrap()).unwrap();
    for (name, extra) in [("plain", &[][..]), ("quantized", &["--quantize"][..])] {
        let out = dir.path().join(format!("head-{name}.glb"));
        let mut args = vec![input.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"];
        args.extend_from_slice(extra);
        let r = lodgen(&args);
        assert_eq!(r.status.code(), Some(0), "{}", support::stderr(&r));
        let json = glb_json(&out);
        let node = json["animations"][0]["channels"][0]["target"]["node"].to_string();
        let log = support::browser::run_script(
            "babylon-morph.mjs",
            &[out.to_str().unwrap(), "breathe", &node],
        );
        assert!(
            log.contains("babylon-morph: head-") && log.contains(": ok"),
            "{log}"
        );
    }
}
