//! A generated 1,000-mesh scene, as a game level would give it: mostly
//! tiny meshes (1 to 20 triangles: cards, quads, boxes), some medium ones,
//! three big ones (a 100,000-triangle torus, a 20,000-triangle skinned tube,
//! a 20,480-triangle sphere with two morph targets), small skinned and
//! morphed meshes among them, a skeleton, and an animation of node
//! translation / rotation / scale and of morph weights. `lodgen` must write
//! it with every mesh at every level of its chain, the targets and skins on
//! every level, JOINTS / WEIGHTS valid and following the contractions, every
//! animation channel kept and pointing where it pointed, and the
//! glTF-Validator must find 0 errors in the input and the output.

mod support;

use std::f32::consts::TAU;

use serde_json::{json, Value};
use support::gltf::{glb_json, Doc};
use support::written::{accessor_values, load_raw};

const MESHES: usize = 1000;
/// Joints of the skeleton: a chain up the y axis, one unit apart.
const JOINTS: usize = 4;
const KEYS: [f32; 3] = [0.0, 1.0, 2.0];

#[derive(Clone, Copy, PartialEq, Debug)]
enum Kind {
    Plain,
    /// Morph targets (their count).
    Morph(usize),
    Skinned,
}

/// A tube of radius `r` along y from 0 to `height`: `n` around, `m` along
/// (`2·n·m` triangles), welded, open at both ends.
fn tube(n: u32, m: u32, r: f32, height: f32) -> lodgen_pm::Mesh {
    let mut positions = Vec::new();
    for j in 0..=m {
        for i in 0..n {
            let a = TAU * i as f32 / n as f32;
            positions.push([r * a.cos(), height * j as f32 / m as f32, r * a.sin()]);
        }
    }
    let mut triangles = Vec::new();
    for j in 0..m {
        for i in 0..n {
            let (a, b) = (j * n + i, j * n + (i + 1) % n);
            triangles.push([a, b + n, b]);
            triangles.push([a, a + n, b + n]);
        }
    }
    lodgen_pm::Mesh {
        positions,
        triangles,
    }
}

/// Mesh `i` of the scene and its kind.
fn shape(i: usize) -> (lodgen_pm::Mesh, Kind) {
    use lodgen_pm::shapes::{cube, grid, icosphere, tetrahedron, torus};
    match i {
        0 => (torus(1.0, 0.3, 400, 125), Kind::Plain),
        1 => (tube(100, 100, 0.3, 3.0), Kind::Skinned),
        2 => (icosphere(5), Kind::Morph(2)),
        _ => match i % 20 {
            3 => (
                tube(4 + (i % 7) as u32, 2 + (i % 5) as u32, 0.2, 3.0),
                Kind::Skinned,
            ),
            4 => (icosphere(1 + (i % 2) as u32), Kind::Morph(1 + i % 2)),
            5 => (torus(1.0, 0.3, 40, 16), Kind::Plain),
            _ => match i % 6 {
                0 => (
                    lodgen_pm::Mesh {
                        positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                        triangles: vec![[0, 1, 2]],
                    },
                    Kind::Plain,
                ),
                1 => (grid(1, 1, |_, _| 0.0), Kind::Plain),
                2 => (tetrahedron(), Kind::Plain),
                3 => (cube([0.0; 3], [1.0; 3], 1), Kind::Plain),
                4 => (icosphere(0), Kind::Plain),
                _ => (grid(3, 2, |x, y| 0.1 * x * y), Kind::Plain),
            },
        },
    }
}

/// Per-vertex joints and weights of a tube of height 3 on the joint chain:
/// blended between the two joints around the vertex's height.
fn skin_weights(positions: &[[f32; 3]]) -> (Vec<[u8; 4]>, Vec<[f32; 4]>) {
    positions
        .iter()
        .map(|p| {
            let h = p[1].clamp(0.0, 3.0);
            let j = (h.floor() as u8).min(3);
            let t = h - j as f32;
            // unused slots: joint 0, weight 0 (the validator's convention)
            if t == 0.0 {
                ([j, 0, 0, 0], [1.0, 0.0, 0.0, 0.0])
            } else if j == 0 {
                ([0, 1, 0, 0], [1.0 - t, t, 0.0, 0.0])
            } else {
                ([j, j + 1, 0, 0], [1.0 - t, t, 0.0, 0.0])
            }
        })
        .unzip()
}

/// The morph targets of a unit sphere: `count` (POSITION, NORMAL) displacements.
fn morph_targets(positions: &[[f32; 3]], count: usize) -> Vec<[Vec<[f32; 3]>; 2]> {
    (0..count)
        .map(|t| {
            let pos = positions
                .iter()
                .map(|p| {
                    if t == 0 {
                        let s = 0.2 * (1.0 + p[1]);
                        [p[0] * s, p[1] * s, p[2] * s]
                    } else {
                        [0.3 * p[1], 0.0, 0.0]
                    }
                })
                .collect();
            let nrm = positions.iter().map(|_| [0.0, 0.0, 0.01]).collect();
            [pos, nrm]
        })
        .collect()
}

fn unit(p: [f32; 3]) -> [f32; 3] {
    let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    [p[0] / l, p[1] / l, p[2] / l]
}

/// The scene as a GLB, and each mesh's kind and triangle count.
fn scene() -> (Vec<u8>, Vec<(Kind, usize)>) {
    let mut doc = Doc::new();
    let mut kinds = Vec::with_capacity(MESHES);
    let mut roots = Vec::new();
    let mut morph_nodes = Vec::new();
    for i in 0..MESHES {
        let (mesh, kind) = shape(i);
        kinds.push((kind, mesh.triangles.len()));
        let pos = doc.floats(&mesh.positions, true);
        let indices = doc.indices(&mesh.triangles);
        let mut prim = json!({"attributes": {"POSITION": pos}, "indices": indices});
        let mut gltf_mesh = json!({"name": format!("mesh{i}"), "primitives": []});
        match kind {
            Kind::Plain => {}
            Kind::Morph(count) => {
                let normals: Vec<[f32; 3]> = mesh.positions.iter().map(|&p| unit(p)).collect();
                prim["attributes"]["NORMAL"] = doc.floats(&normals, false).into();
                let targets: Vec<Value> = morph_targets(&mesh.positions, count)
                    .iter()
                    .map(|[p, n]| {
                        json!({"POSITION": doc.floats(p, true), "NORMAL": doc.floats(n, false)})
                    })
                    .collect();
                prim["targets"] = targets.into();
                gltf_mesh["weights"] = json!(vec![0.0; count]);
                gltf_mesh["extras"] =
                    json!({"targetNames": (0..count).map(|t| format!("t{t}")).collect::<Vec<_>>()});
            }
            Kind::Skinned if i % 40 == 23 => {
                // u16 joints, normalized u8 weights (summing to 255)
                let (joints, weights) = skin_weights(&mesh.positions);
                let j: Vec<u8> = joints
                    .iter()
                    .flatten()
                    .flat_map(|&j| u16::from(j).to_le_bytes())
                    .collect();
                let w: Vec<u8> = weights
                    .iter()
                    .flat_map(|w| {
                        let a = (w[0] * 255.0).round() as u8;
                        [a, 255 - a, 0, 0]
                    })
                    .collect();
                let n = joints.len();
                prim["attributes"]["JOINTS_0"] =
                    doc.accessor(&j, 5123, n, "VEC4", json!({})).into();
                prim["attributes"]["WEIGHTS_0"] = doc
                    .accessor(&w, 5121, n, "VEC4", json!({"normalized": true}))
                    .into();
            }
            Kind::Skinned => {
                let (joints, weights) = skin_weights(&mesh.positions);
                prim["attributes"]["JOINTS_0"] = doc.joints(&joints).into();
                prim["attributes"]["WEIGHTS_0"] = doc.floats(&weights, false).into();
            }
        }
        gltf_mesh["primitives"] = json!([prim]);
        let m = doc.push("meshes", gltf_mesh);
        let mut node = json!({"name": format!("node{i}"), "mesh": m});
        if kind == Kind::Skinned {
            // skinned meshes: root nodes without a transform of their own
            node["skin"] = 0.into();
        } else {
            node["translation"] = json!([(i % 32) as f32 * 3.0, 0.0, (i / 32) as f32 * 3.0]);
        }
        let n = doc.push("nodes", node);
        assert_eq!(n, i, "node i draws mesh i");
        if matches!(kind, Kind::Morph(_)) {
            morph_nodes.push((n, kind));
        }
        roots.push(n);
    }
    // the skeleton: joints 0..4 a chain up y; their inverse bind matrices
    let first_joint = doc.json["nodes"].as_array().unwrap().len();
    for k in 0..JOINTS {
        let mut joint = json!({"name": format!("joint{k}")});
        if k > 0 {
            joint["translation"] = json!([0.0, 1.0, 0.0]);
        }
        if k + 1 < JOINTS {
            joint["children"] = json!([first_joint + k + 1]);
        }
        doc.push("nodes", joint);
    }
    roots.push(first_joint);
    let ibm: Vec<[f32; 16]> = (0..JOINTS)
        .map(|k| {
            let mut m = [0.0; 16];
            (m[0], m[5], m[10], m[15]) = (1.0, 1.0, 1.0, 1.0);
            m[13] = -(k as f32);
            m
        })
        .collect();
    let ibm = doc.floats(&ibm, false);
    doc.push(
        "skins",
        json!({"joints": (first_joint..first_joint + JOINTS).collect::<Vec<_>>(),
               "inverseBindMatrices": ibm, "skeleton": first_joint}),
    );
    animation(&mut doc, first_joint, &morph_nodes);
    doc.json["scene"] = 0.into();
    doc.json["scenes"] = json!([{"nodes": roots}]);
    (doc.glb(), kinds)
}

/// One animation: translation of node 0 (the torus), rotation of joint 1,
/// scale of joint 2, and the weights of every morphed node.
fn animation(doc: &mut Doc, first_joint: usize, morph_nodes: &[(usize, Kind)]) {
    let input = doc.times(&KEYS);
    let mut samplers = Vec::new();
    let mut channels = Vec::new();
    let mut add = |output: usize, node: usize, path: &str| {
        samplers.push(json!({"input": input, "output": output}));
        channels
            .push(json!({"sampler": samplers.len() - 1, "target": {"node": node, "path": path}}));
    };
    let t = doc.floats(&[[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]], false);
    add(t, 0, "translation");
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let r = doc.floats(
        &[[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, h, h], [0.0, 0.0, 0.0, 1.0]],
        false,
    );
    add(r, first_joint + 1, "rotation");
    let s = doc.floats(&[[1.0; 3], [1.5, 1.0, 1.5], [1.0; 3]], false);
    add(s, first_joint + 2, "scale");
    for &(node, kind) in morph_nodes {
        let Kind::Morph(count) = kind else { continue };
        let w: Vec<[f32; 1]> = KEYS
            .iter()
            .flat_map(|&k| (0..count).map(move |c| [(k * 0.5 + c as f32 * 0.1).min(1.0)]))
            .collect();
        let w = doc.floats(&w, false);
        add(w, node, "weights");
    }
    doc.push(
        "animations",
        json!({"name": "level", "samplers": samplers, "channels": channels}),
    );
}

/// The meshes of node `n`'s chain (finest first) and the chain's nodes.
fn chain(json: &Value, n: usize) -> (Vec<usize>, Vec<usize>) {
    let node = &json["nodes"][n];
    let mut nodes = vec![n];
    if let Some(ids) = node
        .pointer("/extensions/MSFT_lod/ids")
        .and_then(Value::as_array)
    {
        nodes.extend(ids.iter().map(|v| v.as_u64().unwrap() as usize));
    }
    let meshes = nodes
        .iter()
        .map(|&k| {
            json["nodes"][k]["mesh"]
                .as_u64()
                .expect("an LOD node draws a mesh") as usize
        })
        .collect();
    (meshes, nodes)
}

fn attr(p: &Value, name: &str) -> Option<usize> {
    p["attributes"][name].as_u64().map(|a| a as usize)
}

/// JOINTS_0 / WEIGHTS_0 of a written skinned primitive: valid for the
/// validator (normalized, non-negative, joints in the skin, no joint twice,
/// unused slots 0) and following the contractions: each vertex keeps the
/// weights of an input vertex (only input values occur) whose height is
/// close to its own (the weights encode the height on the joint chain).
fn check_skin(json: &Value, bufs: &[Vec<u8>], p: &Value, inputs: &[Vec<f64>], what: &str) {
    let pos = accessor_values(json, bufs, attr(p, "POSITION").unwrap());
    let joints = accessor_values(json, bufs, attr(p, "JOINTS_0").expect(what));
    let weights = accessor_values(json, bufs, attr(p, "WEIGHTS_0").expect(what));
    assert_eq!(
        (joints.len(), weights.len()),
        (pos.len(), pos.len()),
        "{what}"
    );
    for ((p, j), w) in pos.iter().zip(&joints).zip(&weights) {
        let sum: f64 = w.iter().sum();
        assert!(
            (sum - 1.0).abs() < 1e-6,
            "{what}: weights {w:?} sum to {sum}"
        );
        let mut used = Vec::new();
        for (&j, &w) in j.iter().zip(w) {
            assert!(
                w >= 0.0 && (j as usize) < JOINTS,
                "{what}: joint {j} weight {w}"
            );
            if w > 0.0 {
                assert!(!used.contains(&j), "{what}: joint {j} twice in {:?}", j);
                used.push(j);
            } else {
                assert_eq!(j, 0.0, "{what}: an unused slot has joint {j}");
            }
        }
        let mut key = j.clone();
        key.extend_from_slice(w);
        let close = |k: &Vec<f64>| k.iter().zip(&key).all(|(a, b)| (a - b).abs() < 1e-6);
        assert!(
            inputs.iter().any(close),
            "{what}: {j:?} {w:?} is no input vertex's"
        );
        let height: f64 = j.iter().zip(w).map(|(j, w)| j * w).sum();
        assert!(
            (height - p[1]).abs() < 0.75,
            "{what}: a vertex at height {} has the weights of height {height}",
            p[1]
        );
    }
}

#[test]
fn a_thousand_mesh_scene_keeps_every_mesh_skin_target_and_channel() {
    let dir = tempfile::tempdir().unwrap();
    let (glb, kinds) = scene();
    let input = dir.path().join("level.glb");
    let out = dir.path().join("level.lod.glb");
    let report = dir.path().join("level.report.json");
    std::fs::write(&input, &glb).unwrap();
    let (i, o, r) = (
        input.to_str().unwrap(),
        out.to_str().unwrap(),
        report.to_str().unwrap(),
    );
    // --measure off: the measured error samples at least 10,000 points per
    // mesh and level (8 s of CPU for this scene in a test build); measured
    // levels of small meshes are small_meshes.rs's
    let run = support::lodgen(&[i, "-o", o, "--report", r, "-q", "--measure", "off"]);
    let stderr = support::stderr(&run);
    assert_eq!(run.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.is_empty(),
        "nothing left out, so no warning: {stderr}"
    );

    let in_json = glb_json(&input);
    let (json, bufs) = load_raw(&out);
    let report: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(report["meshes"].as_array().unwrap().len(), MESHES);
    // the skinned tube's input (joints ++ weights) per vertex
    let (in_json_full, in_bufs) = load_raw(&input);
    let skinned_inputs: Vec<Vec<Vec<f64>>> = (0..MESHES)
        .map(|m| {
            let p = &in_json_full["meshes"][m]["primitives"][0];
            match (attr(p, "JOINTS_0"), attr(p, "WEIGHTS_0")) {
                (Some(j), Some(w)) => accessor_values(&in_json_full, &in_bufs, j)
                    .into_iter()
                    .zip(accessor_values(&in_json_full, &in_bufs, w))
                    .map(|(mut j, w)| {
                        j.extend(w);
                        j
                    })
                    .collect(),
                _ => Vec::new(),
            }
        })
        .collect();
    let mut levels_total = 0;
    for (n, &(kind, triangles)) in kinds.iter().enumerate() {
        let (meshes, nodes) = chain(&json, n);
        let reported = report["meshes"][n]["levels"].as_array().unwrap();
        assert_eq!(meshes.len(), reported.len(), "mesh {n}: levels");
        assert_eq!(json["nodes"][n]["name"], format!("node{n}"));
        levels_total += meshes.len();
        if triangles >= 1000 {
            assert_eq!(
                meshes.len(),
                3,
                "mesh {n} ({triangles} triangles) has every level"
            );
        }
        for (level, &m) in meshes.iter().enumerate() {
            let what = format!("mesh {n} ({kind:?}, {triangles} triangles) level {level}");
            let mesh = &json["meshes"][m];
            assert_eq!(mesh["name"], format!("mesh{n}_LOD{level}"), "{what}");
            let prims = mesh["primitives"].as_array().unwrap();
            let drawn: u64 = prims
                .iter()
                .map(|p| {
                    json["accessors"][p["indices"].as_u64().unwrap() as usize]["count"]
                        .as_u64()
                        .unwrap()
                        / 3
                })
                .sum();
            assert!(drawn > 0, "{what}: empty");
            assert_eq!(
                drawn,
                reported[level]["triangles"].as_u64().unwrap(),
                "{what}"
            );
            for p in prims {
                match kind {
                    Kind::Morph(count) => {
                        let targets = p["targets"].as_array().expect(&what);
                        assert_eq!(targets.len(), count, "{what}");
                        let vertices = &json["accessors"][attr(p, "POSITION").unwrap()]["count"];
                        for t in targets {
                            for a in ["POSITION", "NORMAL"] {
                                let acc = t[a].as_u64().expect(&what) as usize;
                                assert_eq!(&json["accessors"][acc]["count"], vertices, "{what}");
                            }
                        }
                        assert_eq!(mesh["weights"], json!(vec![0.0; count]), "{what}");
                        assert_eq!(mesh["extras"], in_json["meshes"][n]["extras"], "{what}");
                    }
                    Kind::Skinned => {
                        assert_eq!(json["nodes"][nodes[level]]["skin"], 0, "{what}");
                        check_skin(&json, &bufs, p, &skinned_inputs[n], &what);
                    }
                    Kind::Plain => assert!(p.get("targets").is_none(), "{what}"),
                }
            }
        }
    }
    assert!(
        levels_total > MESHES,
        "the larger meshes have coarser levels"
    );
    // the skin, and every channel, still where they were
    assert_eq!(json["skins"][0]["joints"], in_json["skins"][0]["joints"]);
    let ibm = json["skins"][0]["inverseBindMatrices"].as_u64().unwrap() as usize;
    assert_eq!(accessor_values(&json, &bufs, ibm).len(), JOINTS);
    let (a, b) = (&json["animations"][0], &in_json["animations"][0]);
    assert_eq!(
        a["channels"], b["channels"],
        "every channel kept, same targets"
    );
    for (s, (sa, sb)) in a["samplers"]
        .as_array()
        .unwrap()
        .iter()
        .zip(b["samplers"].as_array().unwrap())
        .enumerate()
    {
        for key in ["input", "output"] {
            let (x, y) = (
                sa[key].as_u64().unwrap() as usize,
                sb[key].as_u64().unwrap() as usize,
            );
            assert_eq!(
                accessor_values(&json, &bufs, x),
                accessor_values(&in_json_full, &in_bufs, y),
                "sampler {s} {key}"
            );
        }
    }
    quantized(&input, &in_json);
    // the glTF-Validator: 0 errors in the input and the outputs
    if let Some(log) = support::validate(dir.path()) {
        for file in ["level.glb", "level.lod.glb", "level.q.glb"] {
            assert!(log.contains(&format!("{file}: 0 errors")), "{log}");
        }
    }
}

/// The same scene with `--quantize`: written with one warning (the skin
/// cannot follow a quantized mesh), every mesh's chain on a child of its
/// node (levels never empty), every channel kept (`weights` channels moved
/// to the node that draws the morphed mesh).
fn quantized(input: &std::path::Path, in_json: &Value) {
    let out = input.with_file_name("level.q.glb");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let run = support::lodgen(&[i, "-o", o, "-q", "--measure", "off", "--quantize"]);
    let stderr = support::stderr(&run);
    assert_eq!(run.status.code(), Some(3), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("skins: 1 skin(s) dropped"), "{stderr}");
    let (json, _) = load_raw(&out);
    for n in 0..MESHES {
        let children = json["nodes"][n]["children"].as_array().unwrap();
        let lod0 = children.last().unwrap().as_u64().unwrap() as usize;
        let (meshes, _) = chain(&json, lod0);
        for m in meshes {
            let p = &json["meshes"][m]["primitives"][0];
            let count =
                json["accessors"][p["indices"].as_u64().unwrap() as usize]["count"].as_u64();
            assert!(count.unwrap() >= 3, "mesh {n}: {p}");
        }
    }
    let (a, b) = (
        &json["animations"][0]["channels"],
        &in_json["animations"][0]["channels"],
    );
    assert_eq!(a.as_array().unwrap().len(), b.as_array().unwrap().len());
}
