//! The glTF writer read back with the `gltf` crate: per-level triangles and
//! positions, MSFT_lod structure, buffers per level, glTF-origin scenes,
//! determinism, atomic failure and `inspect`.

mod support;

use std::path::Path;

use lodgen::gltf_out::{write_lods, Compression, LevelProblem, WriteError, WriteOptions};
use lodgen::scene::{LodLevel, LodMesh, Material, Origin, Primitive, Scene, SourceMesh};
use serde_json::Value;
use support::gltf::PNG_2X2;
use support::written::*;

fn sphere_scene(n: u32) -> (Scene, Primitive) {
    let (positions, indices) = icosphere(n, 2.0, [1.0, -3.0, 0.5]);
    let prim = Primitive {
        material: Some(0),
        positions,
        normals: None,
        texcoords: None,
        indices,
        ..Primitive::default()
    };
    let scene = Scene {
        meshes: vec![SourceMesh {
            name: "ball".into(),
            primitives: vec![prim.clone()],
        }],
        materials: vec![Material {
            name: "red".into(),
            base_color: Some([1.0, 0.0, 0.0, 1.0]),
        }],
        origin: Origin::Flat,
        warnings: Vec::new(),
    };
    (scene, prim)
}

/// The MSFT_lod head node and its ids.
fn lod_head(json: &Value) -> (usize, Vec<usize>) {
    let nodes = json["nodes"].as_array().unwrap();
    let head = nodes
        .iter()
        .position(|n| n.pointer("/extensions/MSFT_lod").is_some())
        .expect("a node with MSFT_lod");
    let ids = nodes[head]["extensions"]["MSFT_lod"]["ids"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    (head, ids)
}

/// Reads `path` with `gltf::import` and checks every level of the single
/// chain against `lod`: triangle count, triangles by position, normals unit,
/// POSITION min/max, MSFT_lod ids, coverage, scene membership.
fn check_round_trip(path: &Path, lod: &LodMesh) {
    let (doc, buffers, _) = gltf::import(path).expect("gltf crate reads the output");
    let (json, _) = load_raw(path);
    let (head, ids) = lod_head(&json);
    assert_eq!(ids.len(), lod.levels.len() - 1);
    let coverage: Vec<f64> = json["nodes"][head]["extras"]["MSFT_screencoverage"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let expected: Vec<f64> = lod.levels.iter().map(|l| l.screen_coverage).collect();
    assert_eq!(coverage, expected);
    assert!(coverage.windows(2).all(|w| w[0] > w[1]), "{coverage:?}");
    let used = json["extensionsUsed"].as_array().unwrap();
    assert!(used.iter().any(|e| e == "MSFT_lod"));
    let required = json["extensionsRequired"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    assert!(!required.iter().any(|e| e == "MSFT_lod"));
    let in_scene = scene_nodes(&json);
    assert!(in_scene.contains(&head));
    for id in &ids {
        assert!(!in_scene.contains(id), "coarser node {id} is in a scene");
    }

    let chain: Vec<usize> = std::iter::once(head).chain(ids).collect();
    for (k, &n) in chain.iter().enumerate() {
        let node = doc.nodes().nth(n).unwrap();
        let mesh = node.mesh().expect("level node has a mesh");
        let mut got = Vec::new();
        let mut got_positions = Vec::new();
        let mut triangles = 0;
        for prim in mesh.primitives() {
            let reader = prim.reader(|b| Some(&buffers[b.index()]));
            let positions: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
            let normals: Vec<[f32; 3]> = reader.read_normals().expect("normals").collect();
            assert_eq!(normals.len(), positions.len());
            for nrm in &normals {
                let len = (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]).sqrt();
                assert!((len - 1.0).abs() < 1e-5);
            }
            let indices: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
            triangles += indices.len() / 3;
            let bb = prim.bounding_box();
            for p in &positions {
                let inside = (0..3).all(|a| p[a] >= bb.min[a] && p[a] <= bb.max[a]);
                assert!(inside, "{p:?} outside POSITION min/max");
            }
            let base = got_positions.len() as u32;
            got_positions.extend(positions);
            got.extend(indices.iter().map(|i| i + base));
        }
        let level = &lod.levels[k];
        assert_eq!(triangles, level.triangle_count(), "level {k}");
        let want_prim = &level.primitives[0];
        assert_eq!(
            canonical_triangles(&got_positions, &got),
            canonical_triangles(&want_prim.positions, &want_prim.indices),
            "level {k} triangles differ"
        );
    }
}

#[test]
fn glb_round_trips_every_level() {
    let (scene, prim) = sphere_scene(3);
    let lod = chain("ball", 0, prim, &[0.5, 0.1]);
    let dir = scratch("glb");
    let path = dir.join("ball.glb");
    let summary = write_lods(
        &path,
        &scene,
        std::slice::from_ref(&lod),
        &WriteOptions::default(),
    )
    .unwrap();
    publish_summary("glb_round_trip", &summary);
    check_round_trip(&path, &lod);
    assert_eq!(summary.meshes[0].level_bytes.len(), 3);
    assert!(summary.meshes[0]
        .level_bytes
        .windows(2)
        .all(|w| w[0] > w[1]));

    // Each level's views form one contiguous range; coarsest range first.
    let (json, _) = load_raw(&path);
    let (head, ids) = lod_head(&json);
    let mut ranges = Vec::new();
    for n in std::iter::once(head).chain(ids) {
        let mesh = &json["meshes"][json["nodes"][n]["mesh"].as_u64().unwrap() as usize];
        let mut views = Vec::new();
        for p in mesh["primitives"].as_array().unwrap() {
            let mut accs: Vec<u64> = p["attributes"]
                .as_object()
                .unwrap()
                .values()
                .map(|v| v.as_u64().unwrap())
                .collect();
            accs.push(p["indices"].as_u64().unwrap());
            for a in accs {
                views.push(
                    json["accessors"][a as usize]["bufferView"]
                        .as_u64()
                        .unwrap() as usize,
                );
            }
        }
        let spans: Vec<(u64, u64)> = views
            .iter()
            .map(|&v| {
                let bv = &json["bufferViews"][v];
                assert_eq!(bv["buffer"], 0);
                let o = bv["byteOffset"].as_u64().unwrap_or(0);
                assert_eq!(o % 4, 0, "4-byte alignment");
                (o, o + bv["byteLength"].as_u64().unwrap())
            })
            .collect();
        let lo = spans.iter().map(|s| s.0).min().unwrap();
        let hi = spans.iter().map(|s| s.1).max().unwrap();
        let covered: u64 = spans.iter().map(|s| s.1 - s.0).sum();
        assert!(
            hi - lo - covered < 4 * spans.len() as u64,
            "level range has foreign data"
        );
        ranges.push((lo, hi));
    }
    for w in ranges.windows(2) {
        assert!(
            w[1].1 <= w[0].0,
            "coarser level must come before finer: {ranges:?}"
        );
    }
}

#[test]
fn gltf_writes_one_bin_per_level() {
    let (scene, prim) = sphere_scene(2);
    let lod = chain("ball", 0, prim, &[0.5, 0.2]);
    let dir = scratch("gltf");
    let path = dir.join("ball.gltf");
    let summary = write_lods(
        &path,
        &scene,
        std::slice::from_ref(&lod),
        &WriteOptions::default(),
    )
    .unwrap();
    publish_summary("gltf_per_level_bins", &summary);
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "ball.gltf",
            "ball.lod0.bin",
            "ball.lod1.bin",
            "ball.lod2.bin"
        ]
    );
    check_round_trip(&path, &lod);
    let (json, _) = load_raw(&path);
    let (head, ids) = lod_head(&json);
    for (k, n) in std::iter::once(head).chain(ids).enumerate() {
        let mesh = &json["meshes"][json["nodes"][n]["mesh"].as_u64().unwrap() as usize];
        let p = &mesh["primitives"][0];
        let view = json["accessors"][p["indices"].as_u64().unwrap() as usize]["bufferView"]
            .as_u64()
            .unwrap();
        let buffer = json["bufferViews"][view as usize]["buffer"]
            .as_u64()
            .unwrap();
        assert_eq!(
            json["buffers"][buffer as usize]["uri"],
            format!("ball.lod{k}.bin")
        );
    }
}

#[test]
fn several_meshes_u16_and_u32_indices() {
    // Mesh 0: 163 842 vertices (u32 indices) and a quarter of it (u16).
    let (p0, i0) = icosphere(7, 1.0, [0.0; 3]);
    let big = Primitive {
        material: None,
        positions: p0,
        normals: None,
        texcoords: None,
        indices: i0,
        ..Primitive::default()
    };
    let quarter = Primitive {
        indices: big.indices[..big.indices.len() / 4].to_vec(),
        ..big.clone()
    };
    let (scene_b, small) = sphere_scene(1);
    let scene = Scene {
        meshes: vec![
            SourceMesh {
                name: "big".into(),
                primitives: vec![big.clone()],
            },
            scene_b.meshes[0].clone(),
        ],
        materials: scene_b.materials.clone(),
        origin: Origin::Flat,
        warnings: Vec::new(),
    };
    let mut lod_big = LodMesh {
        source: 0,
        name: "big".into(),
        levels: vec![
            LodLevel {
                primitives: vec![big],
                ..Default::default()
            },
            LodLevel {
                primitives: vec![quarter],
                hausdorff: 0.3,
                ..Default::default()
            },
        ],
    };
    lodgen::coverage::assign_screen_coverages(&mut lod_big);
    let lod_small = chain("small", 1, small, &[0.5]);
    let dir = scratch("multi");
    let path = dir.join("multi.glb");
    let summary = write_lods(
        &path,
        &scene,
        &[lod_big, lod_small],
        &WriteOptions::default(),
    )
    .unwrap();
    publish_summary("multi", &summary);
    let (json, _) = load_raw(&path);
    let itype = |mesh: usize| {
        let a = json["meshes"][mesh]["primitives"][0]["indices"]
            .as_u64()
            .unwrap() as usize;
        json["accessors"][a]["componentType"].as_u64().unwrap()
    };
    assert_eq!(itype(0), 5125, "163 842 vertices need u32");
    assert_eq!(itype(1), 5123, "a quarter fits u16");
    assert_eq!(json["scenes"][0]["nodes"].as_array().unwrap().len(), 2);
    let heads = json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|n| n.pointer("/extensions/MSFT_lod").is_some())
        .count();
    assert_eq!(heads, 2);
    gltf::import(&path).expect("valid for the gltf crate");
}

fn all_files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().into_string().unwrap(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

#[test]
fn output_is_byte_identical_across_runs() {
    let (scene, prim) = sphere_scene(3);
    let lod = chain("ball", 0, prim, &[0.5, 0.1]);
    for (name, opts) in [
        ("d.glb", WriteOptions::default()),
        ("d.gltf", WriteOptions::default()),
        (
            "d.glb",
            WriteOptions {
                quantize: true,
                compression: Compression::Meshopt,
            },
        ),
    ] {
        let a = scratch("det-a");
        let b = scratch("det-b");
        write_lods(&a.join(name), &scene, std::slice::from_ref(&lod), &opts).unwrap();
        write_lods(&b.join(name), &scene, std::slice::from_ref(&lod), &opts).unwrap();
        let (fa, fb) = (all_files(&a), all_files(&b));
        assert!(!fa.is_empty());
        assert_eq!(fa, fb, "{name} {opts:?}");
    }
}

#[test]
fn failures_leave_no_file() {
    let (scene, prim) = sphere_scene(1);
    let lod = chain("ball", 0, prim.clone(), &[0.5]);
    let dir = scratch("fail");
    let missing = dir.join("no-such-dir").join("x.glb");
    let err = write_lods(
        &missing,
        &scene,
        std::slice::from_ref(&lod),
        &WriteOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(err, WriteError::Io { .. }), "{err}");
    assert!(!dir.join("no-such-dir").exists());

    // A valid file exists; a failing rewrite leaves it untouched and no temp.
    let path = dir.join("x.gltf");
    write_lods(
        &path,
        &scene,
        std::slice::from_ref(&lod),
        &WriteOptions::default(),
    )
    .unwrap();
    let before = all_files(&dir);
    let mut bad = lod.clone();
    bad.levels[1].primitives[0].indices[4] = 10_000;
    let err = write_lods(&path, &scene, &[bad], &WriteOptions::default()).unwrap_err();
    match err {
        WriteError::InvalidLevel {
            level: 1,
            primitive: 0,
            problem: LevelProblem::IndexOutOfRange { index: 10_000, .. },
            ..
        } => {}
        e => panic!("unexpected {e}"),
    }
    assert_eq!(all_files(&dir), before);

    let mut nan = lod.clone();
    nan.levels[0].primitives[0].positions[3][1] = f32::NAN;
    let err = write_lods(&dir.join("y.glb"), &scene, &[nan], &WriteOptions::default()).unwrap_err();
    assert!(
        matches!(
            err,
            WriteError::InvalidLevel {
                problem: LevelProblem::NonFinite { vertex: 3, .. },
                ..
            }
        ),
        "{err}"
    );
    let mut rising = lod.clone();
    rising.levels[1].screen_coverage = rising.levels[0].screen_coverage * 2.0 + 0.1;
    assert!(write_lods(
        &dir.join("y.glb"),
        &scene,
        &[rising],
        &WriteOptions::default()
    )
    .is_err());
    let err = write_lods(
        &dir.join("y.obj"),
        &scene,
        std::slice::from_ref(&lod),
        &WriteOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(err, WriteError::UnknownFormat { .. }));
    assert_eq!(all_files(&dir), before, "no partial or temporary files");
}

const KEYS: [f32; 2] = [0.0, 1.0];
const TRANSLATIONS: [[f32; 3]; 2] = [[1.0, 2.0, 3.0], [1.0, 5.0, 3.0]];

/// A glTF input: Parent (translated) → Child (rotated, mesh 0), a textured
/// material, a sampler and a PNG in a buffer view.
fn gltf_scene() -> (Scene, LodMesh) {
    let (positions, indices) = icosphere(2, 1.0, [0.0; 3]);
    let uv = sphere_uvs(&positions, [0.0; 3]);
    let prim = Primitive {
        material: Some(0),
        positions,
        normals: None,
        texcoords: Some(uv),
        indices,
        ..Primitive::default()
    };
    let json = serde_json::json!({
        "asset": {"version": "2.0", "copyright": "test"},
        "extensionsUsed": ["EXT_mesh_gpu_instancing"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"name": "Parent", "translation": [1.0, 2.0, 3.0], "children": [1]},
            {"name": "Child", "rotation": [0.0, 0.6, 0.0, 0.8], "mesh": 0,
             "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 0}}}}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [
            {"componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0.0], "max": [1.0]},
            {"bufferView": 2, "componentType": 5126, "count": 2, "type": "VEC3"}
        ],
        "animations": [{
            "channels": [
                {"sampler": 0, "target": {"node": 0, "path": "translation"}},
                {"sampler": 0, "target": {"node": 1, "path": "weights"}}
            ],
            "samplers": [{"input": 1, "output": 2}]
        }],
        "materials": [{"name": "tex", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9728, "minFilter": 9728}],
        "images": [{"bufferView": 0, "mimeType": "image/png"}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 4, "byteLength": PNG_2X2.len()},
            {"buffer": 0, "byteOffset": 80, "byteLength": 8},
            {"buffer": 0, "byteOffset": 88, "byteLength": 24}
        ],
        "buffers": [{"byteLength": 112}]
    });
    let doc: gltf_json::Root = serde_json::from_value(json.clone()).unwrap();
    let mut data = vec![0u8; 4];
    data.extend_from_slice(&PNG_2X2);
    data.resize(80, 0);
    for v in KEYS.iter().chain(TRANSLATIONS.iter().flatten()) {
        data.extend_from_slice(&v.to_le_bytes());
    }
    let scene = Scene {
        meshes: vec![SourceMesh {
            name: "sphere".into(),
            primitives: vec![prim.clone()],
        }],
        materials: vec![Material {
            name: "tex".into(),
            base_color: None,
        }],
        origin: Origin::Gltf {
            path: "in.gltf".into(),
            document: Box::new(doc),
            json: Box::new(json),
            buffers: vec![data],
        },
        warnings: Vec::new(),
    };
    let lod = chain("sphere", 0, prim, &[0.4, 0.1]);
    (scene, lod)
}

#[test]
fn gltf_origin_keeps_hierarchy_materials_and_images() {
    let (scene, lod) = gltf_scene();
    let dir = scratch("origin");
    let path = dir.join("scene.glb");
    let summary = write_lods(
        &path,
        &scene,
        std::slice::from_ref(&lod),
        &WriteOptions::default(),
    )
    .unwrap();
    publish_summary("gltf_origin", &summary);
    let (json, buffers) = load_raw(&path);
    assert_eq!(json["asset"]["copyright"], "test");
    let nodes = json["nodes"].as_array().unwrap();
    assert_eq!(nodes[0]["name"], "Parent");
    assert_eq!(nodes[0]["translation"], serde_json::json!([1.0, 2.0, 3.0]));
    assert_eq!(nodes[0]["children"], serde_json::json!([1]));
    assert_eq!(nodes[1]["name"], "Child");
    assert_eq!(
        nodes[1]["extensions"]["MSFT_lod"]["ids"],
        serde_json::json!([2, 3])
    );
    let ext: Vec<&String> = nodes[1]["extensions"].as_object().unwrap().keys().collect();
    assert_eq!(
        ext,
        ["MSFT_lod"],
        "the input's instancing accessors are gone"
    );
    assert_eq!(json["extensionsUsed"], serde_json::json!(["MSFT_lod"]));
    for n in [2, 3] {
        assert_eq!(
            nodes[n]["rotation"], nodes[1]["rotation"],
            "coarser node keeps the transform"
        );
        assert!(nodes[n].get("children").is_none());
    }
    assert_eq!(scene_nodes(&json), [0, 1]);
    assert_eq!(
        json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"],
        0
    );
    assert_eq!(json["samplers"][0]["magFilter"], 9728);
    let image_view = json["images"][0]["bufferView"].as_u64().unwrap() as usize;
    assert_eq!(view_bytes(&json, &buffers, image_view), PNG_2X2);
    // Non-LOD data (image, keyframes) comes before every level's range.
    let mesh_views: Vec<u64> = json["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|m| m["primitives"].as_array().unwrap().iter())
        .flat_map(|p| {
            let mut a: Vec<u64> = p["attributes"]
                .as_object()
                .unwrap()
                .values()
                .map(|v| v.as_u64().unwrap())
                .collect();
            a.push(p["indices"].as_u64().unwrap());
            a
        })
        .map(|a| {
            json["accessors"][a as usize]["bufferView"]
                .as_u64()
                .unwrap()
        })
        .collect();
    let span = |v: usize| {
        let bv = &json["bufferViews"][v];
        let o = bv["byteOffset"].as_u64().unwrap_or(0);
        (o, o + bv["byteLength"].as_u64().unwrap())
    };
    let views = json["bufferViews"].as_array().unwrap().len();
    let shared_end = (0..views)
        .filter(|v| !mesh_views.contains(&(*v as u64)))
        .map(|v| span(v).1)
        .max()
        .unwrap();
    assert!(!mesh_views.contains(&(image_view as u64)));
    for &v in &mesh_views {
        assert!(
            span(v as usize).0 >= shared_end,
            "level data before non-LOD data"
        );
    }
    let prim = &json["meshes"][0]["primitives"][0];
    assert!(prim["attributes"].get("TEXCOORD_0").is_some());
    assert_eq!(prim["material"], 0);
    let animation = &json["animations"][0];
    assert_eq!(
        animation["channels"].as_array().unwrap().len(),
        1,
        "weights channel dropped (the mesh has no morph targets)"
    );
    // nothing dropped without a word: the instancing extension and the
    // weights channel are named
    let warnings: Vec<String> = summary.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(
        warnings,
        [
            "nodes[1]: EXT_mesh_gpu_instancing dropped (it refers to the input's mesh data)",
            "animations[0]: a weights channel of node 1, whose mesh has no morph targets, dropped",
        ]
    );
    assert_eq!(animation["channels"][0]["target"]["path"], "translation");
    let sampler = &animation["samplers"][0];
    let keys = accessor_values(&json, &buffers, sampler["input"].as_u64().unwrap() as usize);
    assert_eq!(keys, [[0.0], [1.0]]);
    let values = accessor_values(
        &json,
        &buffers,
        sampler["output"].as_u64().unwrap() as usize,
    );
    let want: Vec<Vec<f64>> = TRANSLATIONS
        .iter()
        .map(|t| t.iter().map(|&c| c as f64).collect())
        .collect();
    assert_eq!(values, want);
    let (_, _, images) = gltf::import(&path).expect("gltf crate reads it and decodes the PNG");
    assert_eq!((images[0].width, images[0].height), (2, 2));
    check_round_trip(&path, &lod);
}

#[test]
fn quantized_gltf_origin_puts_lods_on_a_child() {
    let (scene, lod) = gltf_scene();
    let dir = scratch("origin-q");
    let path = dir.join("scene.gltf");
    let opts = WriteOptions {
        quantize: true,
        compression: Compression::None,
    };
    let summary = write_lods(&path, &scene, std::slice::from_ref(&lod), &opts).unwrap();
    publish_summary("gltf_origin_quantized", &summary);
    let (json, _) = load_raw(&path);
    let nodes = json["nodes"].as_array().unwrap();
    assert!(nodes[1].get("mesh").is_none());
    assert_eq!(nodes[1]["children"], serde_json::json!([2]));
    assert_eq!(
        nodes[2]["extensions"]["MSFT_lod"]["ids"],
        serde_json::json!([3, 4])
    );
    assert_eq!(scene_nodes(&json), [0, 1, 2]);
    for n in [2, 3, 4] {
        assert_eq!(nodes[n]["scale"], nodes[2]["scale"]);
        assert!(nodes[n]["scale"][0].as_f64().unwrap() > 0.9);
    }
}

#[test]
fn inspect_reports_levels_and_coverage() {
    let (scene, prim) = sphere_scene(3);
    let lod = chain("ball", 0, prim, &[0.5, 0.1]);
    let dir = scratch("inspect");
    let path = dir.join("ball.glb");
    write_lods(
        &path,
        &scene,
        std::slice::from_ref(&lod),
        &WriteOptions {
            quantize: true,
            compression: Compression::Meshopt,
        },
    )
    .unwrap();
    let report = lodgen::inspect::inspect(&path).unwrap();
    assert_eq!(report.chains.len(), 1);
    let levels = &report.chains[0].levels;
    assert_eq!(levels.len(), 3);
    for (k, level) in levels.iter().enumerate() {
        assert_eq!(level.triangles as usize, lod.levels[k].triangle_count());
        assert_eq!(level.screen_coverage, Some(lod.levels[k].screen_coverage));
        assert_eq!(level.in_scene, k == 0);
    }
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    let text = report.to_string();
    assert!(text.contains("LOD chain 0"), "{text}");
    assert!(
        text.contains(&lod.levels[2].triangle_count().to_string()),
        "{text}"
    );
    assert!(text.contains("KHR_mesh_quantization"), "{text}");

    std::fs::write(
        dir.join("bad.gltf"),
        br#"{"nodes":[{"mesh":7,"extensions":{"MSFT_lod":{"ids":[0]}}}]}"#,
    )
    .unwrap();
    assert!(lodgen::inspect::inspect(&dir.join("bad.gltf")).is_err());
    assert!(lodgen::inspect::inspect(&dir.join("missing.glb")).is_err());
}

#[test]
fn single_level_chain_has_no_msft_lod() {
    let (scene, prim) = sphere_scene(1);
    let lod = chain("ball", 0, prim, &[]);
    let dir = scratch("single");
    let path = dir.join("one.glb");
    let summary = write_lods(&path, &scene, &[lod], &WriteOptions::default()).unwrap();
    publish_summary("single_level", &summary);
    let (json, _) = load_raw(&path);
    assert!(
        json.get("extensionsUsed").is_none(),
        "{}",
        json["extensionsUsed"]
    );
    assert!(json["nodes"][0].get("extensions").is_none());
    assert_eq!(json["nodes"].as_array().unwrap().len(), 1);
    gltf::import(&path).unwrap();
}

/// Inverse bind matrices of the skinned test scene: identity, and a
/// translation by -1 along y.
const IBM: [[f32; 16]; 2] = [
    [
        1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    ],
    [
        1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 1.0,
    ],
];

/// A skinned glTF input: Root (joint) → Bone (joint), and a node with mesh 0
/// and skin 0; the sphere's upper half follows Bone.
fn skinned_scene() -> (Scene, LodMesh) {
    let (positions, indices) = icosphere(2, 1.0, [0.0; 3]);
    let joints = positions.iter().map(|_| [0, 1, 0, 0]).collect();
    let weights = positions
        .iter()
        .map(|p| {
            let w = (0.5 + 0.5 * p[1]).clamp(0.0, 1.0);
            [1.0 - w, w, 0.0, 0.0]
        })
        .collect();
    let prim = Primitive {
        positions,
        joints: Some(joints),
        weights: Some(weights),
        indices,
        ..Primitive::default()
    };
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 2]}],
        "nodes": [
            {"name": "Root", "children": [1]},
            {"name": "Bone", "translation": [0.0, 1.0, 0.0]},
            {"name": "Skinned", "mesh": 0, "skin": 0}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 1}}]}],
        "skins": [{"joints": [0, 1], "skeleton": 0, "inverseBindMatrices": 0}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 2, "type": "MAT4"},
            {"componentType": 5126, "count": 3, "type": "VEC3"}
        ],
        "bufferViews": [{"buffer": 0, "byteLength": 128}],
        "buffers": [{"byteLength": 128}]
    });
    let doc: gltf_json::Root = serde_json::from_value(json.clone()).unwrap();
    let data: Vec<u8> = IBM.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    let scene = Scene {
        meshes: vec![SourceMesh {
            name: "skinned".into(),
            primitives: vec![prim.clone()],
        }],
        materials: Vec::new(),
        origin: Origin::Gltf {
            path: "in.gltf".into(),
            document: Box::new(doc),
            json: Box::new(json),
            buffers: vec![data],
        },
        warnings: Vec::new(),
    };
    let lod = chain("skinned", 0, prim, &[0.4, 0.1]);
    (scene, lod)
}

#[test]
fn skins_survive_on_every_lod_node_unless_quantized() {
    let (scene, lod) = skinned_scene();
    let dir = scratch("skinned");
    let path = dir.join("skinned.glb");
    let summary = write_lods(
        &path,
        &scene,
        std::slice::from_ref(&lod),
        &WriteOptions::default(),
    )
    .unwrap();
    publish_summary("gltf_skinned", &summary);
    let (json, buffers) = load_raw(&path);
    let skin = &json["skins"][0];
    assert_eq!(skin["joints"], serde_json::json!([0, 1]));
    let ibm = accessor_values(
        &json,
        &buffers,
        skin["inverseBindMatrices"].as_u64().unwrap() as usize,
    );
    let want: Vec<Vec<f64>> = IBM
        .iter()
        .map(|m| m.iter().map(|&c| c as f64).collect())
        .collect();
    assert_eq!(ibm, want);
    let nodes = json["nodes"].as_array().unwrap();
    let ids: Vec<usize> = nodes[2]["extensions"]["MSFT_lod"]["ids"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    assert_eq!(ids.len(), 2);
    for n in std::iter::once(2).chain(ids) {
        assert_eq!(nodes[n]["skin"], 0, "node {n} keeps its skin");
        let mesh = nodes[n]["mesh"].as_u64().unwrap() as usize;
        let attributes = &json["meshes"][mesh]["primitives"][0]["attributes"];
        assert!(attributes.get("JOINTS_0").is_some() && attributes.get("WEIGHTS_0").is_some());
    }
    check_round_trip(&path, &lod);

    // quantized: the dequantization is a node transform, which skinning
    // ignores, so the skin goes
    let path = dir.join("skinned_q.glb");
    let opts = WriteOptions {
        quantize: true,
        compression: Compression::None,
    };
    write_lods(&path, &scene, std::slice::from_ref(&lod), &opts).unwrap();
    let (json, _) = load_raw(&path);
    assert!(json.get("skins").is_none());
    assert!(json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .all(|n| n.get("skin").is_none()));
}
