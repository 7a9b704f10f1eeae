//! `--quantize` (KHR_mesh_quantization) and `--compress meshopt`
//! (EXT_meshopt_compression): decoded data must equal the plain output's
//! within quantization error, vertex streams must use codec version 0.

mod support;

use lodgen::gltf_out::{write_lods, Compression, WriteOptions};
use lodgen::scene::{Primitive, Scene};
use serde_json::Value;
use support::written::*;

fn textured_scene() -> (Scene, lodgen::scene::LodMesh) {
    let center = [10.0, 0.0, -4.0];
    let (positions, indices) = icosphere(3, 3.0, center);
    let uv = sphere_uvs(&positions, center);
    let prim = Primitive {
        material: Some(0),
        positions,
        normals: None,
        texcoords: Some(uv),
        indices,
        ..Primitive::default()
    };
    let scene = one_mesh_scene("ball", prim.clone(), "m", [0.2, 0.4, 0.6, 1.0]);
    let lod = chain("ball", 0, prim, &[0.5, 0.1]);
    (scene, lod)
}

/// Per level (finest first): (node, accessor indices of POSITION, NORMAL,
/// TEXCOORD_0, indices) of the single chain.
fn levels(json: &Value) -> Vec<(usize, [usize; 4])> {
    let nodes = json["nodes"].as_array().unwrap();
    let head = nodes
        .iter()
        .position(|n| n.pointer("/extensions/MSFT_lod").is_some())
        .unwrap();
    let ids = nodes[head]["extensions"]["MSFT_lod"]["ids"]
        .as_array()
        .unwrap();
    std::iter::once(head)
        .chain(ids.iter().map(|v| v.as_u64().unwrap() as usize))
        .map(|n| {
            let m = nodes[n]["mesh"].as_u64().unwrap() as usize;
            let p = &json["meshes"][m]["primitives"][0];
            let a = |k: &str| p["attributes"][k].as_u64().unwrap() as usize;
            (
                n,
                [
                    a("POSITION"),
                    a("NORMAL"),
                    a("TEXCOORD_0"),
                    p["indices"].as_u64().unwrap() as usize,
                ],
            )
        })
        .collect()
}

fn write(name: &str, opts: WriteOptions) -> (Value, Vec<Vec<u8>>, lodgen::gltf_out::WriteSummary) {
    let (scene, lod) = textured_scene();
    let dir = scratch(name);
    let file = if name.ends_with("gltf") {
        "ball.gltf"
    } else {
        "ball.glb"
    };
    let summary = write_lods(&dir.join(file), &scene, &[lod], &opts).unwrap();
    publish_summary(name, &summary);
    let (json, buffers) = load_raw(&dir.join(file));
    (json, buffers, summary)
}

fn has(json: &Value, key: &str, ext: &str) -> bool {
    json[key]
        .as_array()
        .is_some_and(|a| a.iter().any(|e| e == ext))
}

#[test]
fn quantized_data_matches_plain_within_quantization_error() {
    let (pj, pb, _) = write("q-plain-glb", WriteOptions::default());
    let (qj, qb, _) = write(
        "q-glb",
        WriteOptions {
            quantize: true,
            compression: Compression::None,
        },
    );
    assert!(has(&qj, "extensionsUsed", "KHR_mesh_quantization"));
    assert!(has(&qj, "extensionsRequired", "KHR_mesh_quantization"));
    assert!(!has(&pj, "extensionsUsed", "KHR_mesh_quantization"));
    for ((_, pa), (qn, qa)) in levels(&pj).into_iter().zip(levels(&qj)) {
        let node = &qj["nodes"][qn];
        let t: Vec<f64> = (0..3)
            .map(|i| node["translation"][i].as_f64().unwrap())
            .collect();
        let s = node["scale"][0].as_f64().unwrap();
        assert_eq!(
            node["scale"][1].as_f64().unwrap(),
            s,
            "uniform dequantization scale"
        );
        let pos = &qj["accessors"][qa[0]];
        assert_eq!(
            (pos["componentType"].as_u64(), pos["normalized"].as_bool()),
            (Some(5122), Some(true))
        );
        assert!(pos.get("min").is_some() && pos.get("max").is_some());
        assert_eq!(qj["accessors"][qa[1]]["componentType"], 5120);
        assert_eq!(qj["accessors"][qa[2]]["componentType"], 5123);

        let plain = accessor_values(&pj, &pb, pa[0]);
        let quant = accessor_values(&qj, &qb, qa[0]);
        assert_eq!(plain.len(), quant.len());
        let tol = s / 32767.0 * 0.5 + 1e-5;
        for (p, q) in plain.iter().zip(&quant) {
            for a in 0..3 {
                let world = t[a] + s * q[a];
                assert!((world - p[a]).abs() <= tol, "{world} vs {}", p[a]);
            }
        }
        for (p, q) in accessor_values(&pj, &pb, pa[1])
            .iter()
            .zip(accessor_values(&qj, &qb, qa[1]))
        {
            for a in 0..3 {
                assert!((p[a] - q[a]).abs() <= 0.5 / 127.0 + 1e-6);
            }
        }
        for (p, q) in accessor_values(&pj, &pb, pa[2])
            .iter()
            .zip(accessor_values(&qj, &qb, qa[2]))
        {
            for a in 0..2 {
                assert!((p[a] - q[a]).abs() <= 0.5 / 65535.0 + 1e-6);
            }
        }
        assert_eq!(
            accessor_values(&pj, &pb, pa[3]),
            accessor_values(&qj, &qb, qa[3])
        );
    }
}

/// Every accessor of `compressed` decodes to the same values as in `plain`.
fn assert_same_decoded(pj: &Value, pb: &[Vec<u8>], cj: &Value, cb: &[Vec<u8>]) {
    for ((_, pa), (_, ca)) in levels(pj).into_iter().zip(levels(cj)) {
        for (p, c) in pa[..3].iter().zip(&ca[..3]) {
            let same = accessor_values(pj, pb, *p) == accessor_values(cj, cb, *c);
            assert!(
                same,
                "accessor {c} decodes differently from plain accessor {p}"
            );
        }
        // The triangle codec may rotate a triangle's corners (keeping its
        // winding); triangle order and contents are exact.
        let rotated = |v: Vec<Vec<f64>>| -> Vec<[u64; 3]> {
            v.chunks_exact(3)
                .map(|t| {
                    let t = [t[0][0] as u64, t[1][0] as u64, t[2][0] as u64];
                    let m = (0..3).min_by_key(|&i| t[i]).unwrap();
                    [t[m], t[(m + 1) % 3], t[(m + 2) % 3]]
                })
                .collect()
        };
        let same =
            rotated(accessor_values(pj, pb, pa[3])) == rotated(accessor_values(cj, cb, ca[3]));
        assert!(same, "triangles of accessor {} differ", ca[3]);
    }
}

fn check_meshopt_structure(json: &Value) {
    assert!(has(json, "extensionsUsed", "EXT_meshopt_compression"));
    assert!(has(json, "extensionsRequired", "EXT_meshopt_compression"));
    let buffers = json["buffers"].as_array().unwrap();
    let mut compressed_views = 0;
    for bv in json["bufferViews"].as_array().unwrap() {
        if let Some(m) = bv.pointer("/extensions/EXT_meshopt_compression") {
            compressed_views += 1;
            let fallback = &buffers[bv["buffer"].as_u64().unwrap() as usize];
            assert_eq!(
                fallback["extensions"]["EXT_meshopt_compression"]["fallback"],
                true
            );
            assert!(fallback.get("uri").is_none());
            assert_eq!(
                bv["byteLength"].as_u64().unwrap(),
                m["byteStride"].as_u64().unwrap() * m["count"].as_u64().unwrap()
            );
            let real = &buffers[m["buffer"].as_u64().unwrap() as usize];
            assert!(real
                .pointer("/extensions/EXT_meshopt_compression")
                .is_none());
        }
    }
    assert_eq!(compressed_views, 3 * 4, "4 streams per level, 3 levels");
}

#[test]
fn meshopt_glb_decodes_to_the_plain_data() {
    let (pj, pb, ps) = write("m-plain-glb", WriteOptions::default());
    let (cj, cb, cs) = write(
        "m-glb",
        WriteOptions {
            quantize: false,
            compression: Compression::Meshopt,
        },
    );
    check_meshopt_structure(&cj);
    assert_same_decoded(&pj, &pb, &cj, &cb);
    for (p, c) in ps.meshes[0]
        .level_bytes
        .iter()
        .zip(&cs.meshes[0].level_bytes)
    {
        assert!(c < p, "compressed level {c} >= plain {p}");
    }
}

#[test]
fn meshopt_quantized_gltf_decodes_to_the_quantized_data() {
    let q = WriteOptions {
        quantize: true,
        compression: Compression::None,
    };
    let qc = WriteOptions {
        quantize: true,
        compression: Compression::Meshopt,
    };
    let (pj, pb, _) = write("mq-plain-gltf", q);
    let (cj, cb, _) = write("mq-gltf", qc);
    check_meshopt_structure(&cj);
    assert!(has(&cj, "extensionsRequired", "KHR_mesh_quantization"));
    assert_same_decoded(&pj, &pb, &cj, &cb);
}

/// A ball with every kind of attribute: tangents, two UV sets, two colour
/// sets, eight skin influences (two JOINTS / WEIGHTS sets).
fn attribute_scene() -> (Scene, lodgen::scene::LodMesh) {
    let center = [0.0, 1.0, 0.0];
    let (positions, indices) = icosphere(2, 1.0, center);
    let n = positions.len();
    let uv = sphere_uvs(&positions, center);
    let d = |v: usize| [0, 1, 2].map(|k| positions[v][k] - center[k]);
    let tangents = (0..n)
        .map(|v| {
            let p = d(v);
            let l = (p[0] * p[0] + p[2] * p[2]).sqrt();
            let w = if v % 2 == 0 { 1.0 } else { -1.0 };
            if l < 1e-6 {
                [1.0, 0.0, 0.0, w] // at a pole
            } else {
                [-p[2] / l, 0.0, p[0] / l, w]
            }
        })
        .collect();
    let colors = (0..n)
        .map(|v| d(v).map(|c| 0.5 + 0.5 * c))
        .map(|c| [c[0], c[1], c[2], 1.0])
        .collect();
    let joints = (0..n)
        .map(|v| [v as u16 % 7, 7, 8 + v as u16 % 3, 11])
        .collect();
    let joints1 = (0..n).map(|v| [12, 13, 14, 15 + v as u16 % 2]).collect();
    let (mut w0, mut w1) = (Vec::new(), Vec::new());
    for v in 0..n {
        let raw = [1.0 + v as f32 % 5.0, 0.3, 0.2, 0.1, 0.07, 0.05, 0.02, 0.01];
        let s: f32 = raw.iter().sum();
        w0.push([raw[0] / s, raw[1] / s, raw[2] / s, raw[3] / s]);
        w1.push([raw[4] / s, raw[5] / s, raw[6] / s, raw[7] / s]);
    }
    let prim = Primitive {
        material: Some(0),
        positions,
        texcoords: Some(uv.clone()),
        tangents: Some(tangents),
        extra_texcoords: vec![uv.iter().map(|t| [t[1], t[0]]).collect()],
        colors: Some(colors),
        extra_colors: vec![(0..n)
            .map(|v| [0.25, (v % 9) as f32 / 8.0, 0.75, 0.5])
            .collect()],
        joints: Some(joints),
        extra_joints: vec![joints1],
        weights: Some(w0),
        extra_weights: vec![w1],
        indices,
        ..Primitive::default()
    };
    let scene = one_mesh_scene("ball", prim.clone(), "m", [0.2, 0.4, 0.6, 1.0]);
    let lod = chain("ball", 0, prim, &[0.25]);
    (scene, lod)
}

#[test]
fn quantized_attributes_use_compact_formats() {
    let (scene, lod) = attribute_scene();
    let dir = scratch("q-attributes");
    let mut read = Vec::new();
    for (name, quantize, compression) in [
        ("plain.glb", false, Compression::None),
        ("quantized.glb", true, Compression::None),
        ("quantized-meshopt.glb", true, Compression::Meshopt),
    ] {
        let path = dir.join(name);
        let opts = WriteOptions {
            quantize,
            compression,
        };
        let (json, _, _) = write_and_load(&path, &scene, &lod, &opts, "q-attributes");
        let prim = &json["meshes"][0]["primitives"][0]["attributes"];
        let format = |a: &str| {
            let acc = &json["accessors"][prim[a].as_u64().unwrap() as usize];
            (
                acc["componentType"].as_u64().unwrap(),
                acc["normalized"].as_bool().unwrap_or(false),
            )
        };
        let expect: [(&str, (u64, bool)); 9] = if quantize {
            [
                ("TANGENT", (5120, true)),
                ("TEXCOORD_1", (5123, true)),
                ("COLOR_0", (5121, true)),
                ("COLOR_1", (5121, true)),
                ("WEIGHTS_0", (5121, true)),
                ("WEIGHTS_1", (5121, true)),
                ("JOINTS_0", (5121, false)),
                ("JOINTS_1", (5121, false)),
                ("TEXCOORD_0", (5123, true)),
            ]
        } else {
            [
                ("TANGENT", (5126, false)),
                ("TEXCOORD_1", (5126, false)),
                ("COLOR_0", (5126, false)),
                ("COLOR_1", (5126, false)),
                ("WEIGHTS_0", (5126, false)),
                ("WEIGHTS_1", (5126, false)),
                ("JOINTS_0", (5123, false)),
                ("JOINTS_1", (5123, false)),
                ("TEXCOORD_0", (5126, false)),
            ]
        };
        for (a, f) in expect {
            assert_eq!(format(a), f, "{name} {a}");
        }
        // (the reader does not decode EXT_meshopt_compression; the
        // validator checks that file)
        if compression == Compression::None {
            read.push(lodgen::io::read_scene(&path).unwrap());
        }
    }
    // same vertex order in every file (the post-pass does not depend on
    // the encoding): compare vertex by vertex
    let plain = &read[0].meshes[0].primitives[0];
    for scene in &read[1..] {
        let q = &scene.meshes[0].primitives[0];
        let n = plain.positions.len();
        assert_eq!(q.positions.len(), n);
        let close =
            |a: &[f32], b: &[f32], tol: f32| a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol);
        for v in 0..n {
            let (pt, qt) = (
                plain.tangents.as_ref().unwrap()[v],
                q.tangents.as_ref().unwrap()[v],
            );
            assert!(
                close(&pt[..3], &qt[..3], 0.5 / 127.0 + 1e-6),
                "{pt:?} {qt:?}"
            );
            assert_eq!(pt[3], qt[3]);
            let (pc, qc) = (
                plain.colors.as_ref().unwrap()[v],
                q.colors.as_ref().unwrap()[v],
            );
            assert!(close(&pc, &qc, 0.5 / 255.0 + 1e-6), "{pc:?} {qc:?}");
            assert!(close(
                &plain.extra_colors[0][v],
                &q.extra_colors[0][v],
                0.5 / 255.0 + 1e-6
            ));
            assert!(close(
                &plain.extra_texcoords[0][v],
                &q.extra_texcoords[0][v],
                0.5 / 65535.0 + 1e-6
            ));
            assert_eq!(
                plain.joints.as_ref().unwrap()[v],
                q.joints.as_ref().unwrap()[v]
            );
            assert_eq!(plain.extra_joints[0][v], q.extra_joints[0][v]);
            let (pw, qw) = (
                plain.weights.as_ref().unwrap()[v],
                q.weights.as_ref().unwrap()[v],
            );
            assert!(close(&pw, &qw, 2.5 / 255.0), "{pw:?} {qw:?}");
            assert!(close(
                &plain.extra_weights[0][v],
                &q.extra_weights[0][v],
                2.5 / 255.0
            ));
            let sum: f32 = qw.iter().chain(&q.extra_weights[0][v]).sum();
            assert!((sum - 1.0).abs() < 1e-5, "vertex {v}: weights sum {sum}");
        }
    }
}

/// Write `opts` to `dir/file` and read it back with lodgen's own reader.
fn write_and_read(dir: &std::path::Path, file: &str, opts: WriteOptions) -> Scene {
    let (scene, lod) = textured_scene();
    let path = dir.join(file);
    write_lods(&path, &scene, &[lod], &opts).unwrap();
    lodgen::io::read_scene(&path).unwrap()
}

/// Each mesh's positions, UVs and triangles (corners rotated to start at
/// the lowest index: the triangle codec may rotate them).
type Content = (Vec<[f32; 3]>, Option<Vec<[f32; 2]>>, Vec<[u32; 3]>);

fn content(s: &Scene) -> Vec<Content> {
    s.meshes
        .iter()
        .flat_map(|m| &m.primitives)
        .map(|p| {
            let tris = p
                .indices
                .chunks_exact(3)
                .map(|t| {
                    let m = (0..3).min_by_key(|&i| t[i]).unwrap();
                    [t[m], t[(m + 1) % 3], t[(m + 2) % 3]]
                })
                .collect();
            (p.positions.clone(), p.texcoords.clone(), tris)
        })
        .collect()
}

#[test]
fn lodgen_reads_meshopt_compressed_files_back() {
    let dir = scratch("m-read");
    for quantize in [false, true] {
        for ext in ["glb", "gltf"] {
            let plain = write_and_read(
                &dir,
                &format!("plain-{quantize}.{ext}"),
                WriteOptions {
                    quantize,
                    compression: Compression::None,
                },
            );
            let packed = write_and_read(
                &dir,
                &format!("packed-{quantize}.{ext}"),
                WriteOptions {
                    quantize,
                    compression: Compression::Meshopt,
                },
            );
            assert_eq!(plain.meshes.len(), 3, "one mesh per level");
            assert_eq!(
                content(&packed),
                content(&plain),
                "quantize {quantize}, .{ext}"
            );
        }
    }
}

#[test]
fn corrupt_meshopt_data_is_an_error_naming_the_view() {
    let dir = scratch("m-corrupt");
    let (scene, lod) = textured_scene();
    let path = dir.join("ball.gltf");
    let opts = WriteOptions {
        quantize: false,
        compression: Compression::Meshopt,
    };
    write_lods(&path, &scene, &[lod], &opts).unwrap();
    let (json, _) = load_raw(&path);
    // every compressed view's source bytes zeroed in turn: decoding must
    // fail with the view's JSON path, or succeed, but never panic
    let views = json["bufferViews"].as_array().unwrap();
    let mut errors = 0;
    for (i, v) in views.iter().enumerate() {
        let Some(m) = v.pointer("/extensions/EXT_meshopt_compression") else {
            continue;
        };
        let uri = json["buffers"][m["buffer"].as_u64().unwrap() as usize]["uri"]
            .as_str()
            .unwrap();
        let bin = dir.join(uri);
        let original = std::fs::read(&bin).unwrap();
        let mut bad = original.clone();
        let start = m["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = m["byteLength"].as_u64().unwrap() as usize;
        bad[start..start + len].fill(0xff);
        std::fs::write(&bin, &bad).unwrap();
        if let Err(e) = lodgen::io::read_scene(&path) {
            errors += 1;
            let text = format!("{e:#}");
            assert!(
                text.contains(&format!("bufferViews[{i}]")),
                "view {i}: {text}"
            );
        }
        std::fs::write(&bin, &original).unwrap();
    }
    assert!(
        errors > 0,
        "garbage in every compressed view decoded silently"
    );
}

/// A hand-made file as gltfpack writes them: normals as octahedral-filtered
/// `i8` (EXT_meshopt_compression filter OCTAHEDRAL), positions as
/// exponential-filtered floats, both compressed; read back within the
/// filters' precision.
#[test]
fn filtered_meshopt_attributes_decode() {
    use meshopt::encoding::{
        encode_filter_exp, encode_filter_oct, encode_vertex_buffer, EncodeExpMode,
    };
    let dir = scratch("m-filters");
    let positions = [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.5],
    ];
    let normals = [
        [0.0f32, 0.0, 1.0, 0.0],
        [0.6, 0.0, 0.8, 0.0],
        [0.0, -0.6, 0.8, 0.0],
        [0.48, 0.6, 0.64, 0.0],
    ];
    let oct: Vec<[i8; 4]> = encode_filter_oct(&normals, 8);
    let exp: Vec<[u32; 3]> = encode_filter_exp::<3>(&positions, 15, EncodeExpMode::Separate);
    let n_enc = encode_vertex_buffer(&oct).unwrap();
    let p_enc = encode_vertex_buffer(&exp).unwrap();
    let indices: [u16; 6] = [0, 1, 2, 2, 1, 3];
    let mut bin: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
    let p_at = bin.len();
    bin.extend_from_slice(&p_enc);
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let n_at = bin.len();
    bin.extend_from_slice(&n_enc);
    std::fs::write(dir.join("f.bin"), &bin).unwrap();
    let ext = |at: usize, len: usize, stride: usize, filter: &str| {
        serde_json::json!({"EXT_meshopt_compression": {
            "buffer": 0, "byteOffset": at, "byteLength": len, "byteStride": stride,
            "count": 4, "mode": "ATTRIBUTES", "filter": filter}})
    };
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["EXT_meshopt_compression"],
        "extensionsRequired": ["EXT_meshopt_compression"],
        "buffers": [
            {"uri": "f.bin", "byteLength": bin.len()},
            {"byteLength": 64, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 12},
            {"buffer": 1, "byteOffset": 0, "byteLength": 48, "byteStride": 12,
             "extensions": ext(p_at, p_enc.len(), 12, "EXPONENTIAL")},
            {"buffer": 1, "byteOffset": 48, "byteLength": 16, "byteStride": 4,
             "extensions": ext(n_at, n_enc.len(), 4, "OCTAHEDRAL")}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5123, "count": 6, "type": "SCALAR"},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0.5]},
            {"bufferView": 2, "componentType": 5120, "normalized": true, "count": 4, "type": "VEC3"}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 1, "NORMAL": 2}, "indices": 0}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0
    });
    let path = dir.join("f.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let scene = lodgen::io::read_scene(&path).unwrap();
    let p = &scene.meshes[0].primitives[0];
    assert_eq!(p.indices, [0, 1, 2, 2, 1, 3]);
    for (got, want) in p.positions.iter().zip(&positions) {
        for a in 0..3 {
            assert!((got[a] - want[a]).abs() < 1e-4, "{got:?} vs {want:?}");
        }
    }
    for (got, want) in p.normals.as_ref().unwrap().iter().zip(&normals) {
        for a in 0..3 {
            assert!((got[a] - want[a]).abs() < 0.03, "{got:?} vs {want:?}");
        }
    }
}
