//! The glTF writer read back with the `gltf` crate: per-level triangles and
//! positions, MSFT_lod structure, buffers per level, determinism, atomic
//! failure and `inspect` (glTF input: `gltf_out_input.rs`).

mod support;

use std::path::Path;

use lodgen::gltf_out::{write_lods, Compression, LevelProblem, WriteError, WriteOptions};
use lodgen::scene::{LodLevel, LodMesh, Origin, Primitive, Scene, SourceMesh};
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
    let scene = one_mesh_scene("ball", prim.clone(), "red", [1.0, 0.0, 0.0, 1.0]);
    (scene, prim)
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
