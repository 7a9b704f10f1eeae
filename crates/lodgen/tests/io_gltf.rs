//! glTF reader: a small document built here (JSON + base64 data URI, and
//! the same as GLB) with indexed triangles, a triangle strip, a fan, a
//! points primitive, two meshes on a node hierarchy; then broken variants.

mod support;

use std::path::Path;

use lodgen::io::{
    read_gltf, read_gltf_with, read_scene, ErrorKind, Location, ReadError, ReadOptions,
};
use lodgen::scene::{Origin, Scene};
use serde_json::{json, Value};
use support::gltf::{base64, glb_bytes};

const POSITIONS: [[f32; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
    [2.0, 2.0, 0.0],
];

/// The binary buffer (180 bytes) and the JSON document without buffer URI.
fn document() -> (Value, Vec<u8>) {
    let mut bin = Vec::new();
    for p in POSITIONS {
        p.iter()
            .for_each(|x| bin.extend_from_slice(&x.to_le_bytes()));
    }
    for _ in 0..5 {
        [0.0f32, 0.0, 1.0]
            .iter()
            .for_each(|x| bin.extend_from_slice(&x.to_le_bytes()));
    }
    for p in POSITIONS {
        [p[0] / 2.0, p[1] / 2.0]
            .iter()
            .for_each(|x| bin.extend_from_slice(&x.to_le_bytes()));
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    bin.extend_from_slice(&[0u8, 1, 2, 3, 4]);
    bin.resize(180, 0);
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"mesh": 0, "translation": [1.0, 2.0, 3.0], "children": [1]},
            {"mesh": 1, "scale": [2.0, 2.0, 2.0]}
        ],
        "materials": [
            {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.0, 0.0, 1.0]}},
            {"name": "plain"}
        ],
        "meshes": [
            {"name": "multi", "primitives": [
                {"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3, "material": 0},
                {"attributes": {"POSITION": 0}, "indices": 4, "mode": 5, "material": 1},
                {"attributes": {"POSITION": 0}, "mode": 0},
                {"attributes": {"POSITION": 0}, "mode": 6}
            ]},
            {"name": "plain", "primitives": [{"attributes": {"POSITION": 5}}]}
        ],
        "buffers": [{"byteLength": 180}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 60},
            {"buffer": 0, "byteOffset": 60, "byteLength": 60},
            {"buffer": 0, "byteOffset": 120, "byteLength": 40},
            {"buffer": 0, "byteOffset": 160, "byteLength": 12},
            {"buffer": 0, "byteOffset": 172, "byteLength": 5}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [2.0, 2.0, 0.0]},
            {"bufferView": 1, "componentType": 5126, "count": 5, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 5, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"},
            {"bufferView": 4, "componentType": 5121, "count": 5, "type": "SCALAR"},
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}
        ]
    });
    (doc, bin)
}

fn gltf_bytes(mut doc: Value, bin: &[u8]) -> Vec<u8> {
    doc["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        base64(bin)
    ));
    serde_json::to_vec_pretty(&doc).unwrap()
}

fn check_scene(s: &Scene) {
    assert_eq!(s.meshes.len(), 2);
    let multi = &s.meshes[0];
    assert_eq!(multi.name, "multi");
    // The POINTS primitive is left out.
    assert_eq!(multi.primitives.len(), 3);
    let tri = &multi.primitives[0];
    assert_eq!(tri.positions, POSITIONS.to_vec());
    assert_eq!(tri.indices, vec![0, 1, 2, 0, 2, 3]);
    assert_eq!(tri.normals.as_deref(), Some(&[[0.0, 0.0, 1.0]; 5][..]));
    assert_eq!(tri.texcoords.as_ref().unwrap()[4], [1.0, 1.0]);
    assert_eq!(tri.material, Some(0));
    let strip = &multi.primitives[1];
    // glTF 2.0: triangle i is (v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]).
    assert_eq!(strip.indices, vec![0, 1, 2, 1, 3, 2, 2, 3, 4]);
    assert_eq!(strip.material, Some(1));
    assert!(strip.normals.is_none() && strip.texcoords.is_none());
    let fan = &multi.primitives[2];
    assert_eq!(fan.indices, vec![1, 2, 0, 2, 3, 0, 3, 4, 0]);
    assert_eq!(fan.material, None);
    let plain = &s.meshes[1].primitives;
    assert_eq!(plain.len(), 1);
    assert_eq!(plain[0].indices, vec![0, 1, 2]);
    assert_eq!(plain[0].positions, POSITIONS[..3].to_vec());

    assert_eq!(s.materials.len(), 2);
    assert_eq!(s.materials[0].name, "red");
    assert_eq!(s.materials[0].base_color, Some([1.0, 0.0, 0.0, 1.0]));
    assert_eq!(s.materials[1].base_color, Some([1.0; 4]));

    let Origin::Gltf {
        document, buffers, ..
    } = &s.origin
    else {
        panic!("glTF origin expected");
    };
    assert_eq!(document.nodes.len(), 2);
    assert_eq!(document.nodes[0].translation, Some([1.0, 2.0, 3.0]));
    assert_eq!(document.nodes[0].children.as_ref().map(Vec::len), Some(1));
    assert_eq!(buffers.len(), 1);
    assert_eq!(buffers[0].len(), 180);
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert_eq!(s.warnings[0].at, "meshes[0].primitives[2] (mesh `multi`)");
}

#[test]
fn gltf_with_data_uri() {
    let (doc, bin) = document();
    let s =
        read_gltf(&gltf_bytes(doc, &bin), Path::new("t.gltf")).unwrap_or_else(|e| panic!("{e}"));
    check_scene(&s);
}

/// A file that is neither GLB nor JSON says so (not "invalid glTF JSON:
/// expected value at line 1 column 1"); a JSON document after a UTF-8 byte
/// order mark reads.
#[test]
fn not_gltf_at_all_says_so_and_a_byte_order_mark_reads() {
    for bytes in [&b"\x89PNG\r\n\x1a\n...."[..], b"", b"solid cube\n"] {
        let e = read_gltf(bytes, Path::new("x.glb")).unwrap_err();
        assert_eq!(e.location, Location::File);
        let text = e.to_string();
        assert!(
            text.starts_with("x.glb: not a glTF file: neither the GLB magic"),
            "{text}"
        );
    }
    let (doc, bin) = document();
    let mut bytes = b"\xEF\xBB\xBF".to_vec();
    bytes.extend(gltf_bytes(doc, &bin));
    let s = read_gltf(&bytes, Path::new("bom.gltf")).unwrap_or_else(|e| panic!("{e}"));
    check_scene(&s);
}

#[test]
fn glb_from_file_and_external_bin() {
    let (doc, bin) = document();
    let dir = std::env::temp_dir().join(format!("lodgen-io-gltf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let glb = dir.join("t.GLB");
    std::fs::write(&glb, glb_bytes(&doc, &bin)).unwrap();
    let mut external = doc.clone();
    external["buffers"][0]["uri"] = json!("my%20data.bin");
    std::fs::write(dir.join("my data.bin"), &bin).unwrap();
    let sep = dir.join("sep.gltf");
    std::fs::write(&sep, serde_json::to_vec(&external).unwrap()).unwrap();
    let from_glb = read_scene(&glb);
    let from_sep = read_scene(&sep);
    std::fs::remove_dir_all(&dir).unwrap();
    let from_glb = from_glb.unwrap_or_else(|e| panic!("{e}"));
    check_scene(&from_glb);
    check_scene(&from_sep.unwrap_or_else(|e| panic!("{e}")));
    let Origin::Gltf { path, .. } = &from_glb.origin else {
        panic!("glTF origin expected");
    };
    assert_eq!(path, &glb);
}

/// The error of reading the edited document with `--strict` (the points
/// primitive, which would be left out with a warning, removed first).
fn broken(edit: impl FnOnce(&mut Value, &mut Vec<u8>)) -> ReadError {
    let (mut doc, mut bin) = document();
    doc["meshes"][0]["primitives"]
        .as_array_mut()
        .unwrap()
        .remove(2);
    edit(&mut doc, &mut bin);
    let strict = ReadOptions { strict: true };
    match read_gltf_with(&gltf_bytes(doc, &bin), Path::new("b.gltf"), &strict) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e,
    }
}

/// Without `--strict`, a primitive that cannot be read is left out with a
/// warning naming it and the cause; the rest of the file is read.
#[test]
fn a_broken_primitive_is_left_out_with_a_warning() {
    let (mut doc, mut bin) = document();
    bin[164..166].copy_from_slice(&7u16.to_le_bytes());
    doc["meshes"][0]["primitives"][1]["attributes"]["_BLEND"] = json!(0);
    let s =
        read_gltf(&gltf_bytes(doc, &bin), Path::new("w.gltf")).unwrap_or_else(|e| panic!("{e}"));
    let texts: Vec<String> = s.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(
        texts,
        [
            "meshes[0].primitives[0] (mesh `multi`): cannot be read, left out: \
             meshes[0].primitives[0].indices[2]: index refers to vertex 7, but only 5 are defined",
            "meshes[0].primitives[1] (mesh `multi`): attributes _BLEND are not carried into the output",
            "meshes[0].primitives[2] (mesh `multi`): points or lines: left out (lodgen writes triangles)",
        ]
    );
    // the strip and the fan are still read, and the other mesh
    assert_eq!(s.meshes[0].primitives.len(), 2);
    assert_eq!(s.meshes[1].primitives.len(), 1);
}

#[test]
fn index_out_of_range_names_the_accessor_element() {
    let e = broken(|_, bin| bin[164..166].copy_from_slice(&7u16.to_le_bytes()));
    assert_eq!(
        e.location,
        Location::Json("meshes[0].primitives[0].indices[2]".to_owned())
    );
    assert_eq!(
        e.to_string(),
        "b.gltf: meshes[0].primitives[0].indices[2]: index refers to vertex 7, but only 5 are defined"
    );
}

#[test]
fn nan_position_names_the_vertex() {
    let e = broken(|_, bin| bin[16..20].copy_from_slice(&f32::NAN.to_le_bytes()));
    assert_eq!(
        e.location,
        Location::Json("meshes[0].primitives[0].attributes.POSITION[1]".to_owned())
    );
    assert!(matches!(*e.kind, ErrorKind::NonFinite { .. }), "{e}");
}

#[test]
fn mesh_of_only_points_and_lines_is_left_out_with_a_warning() {
    let points_and_lines = |doc: &mut Value| {
        doc["meshes"][1]["primitives"] = json!([{"attributes": {"POSITION": 5}, "mode": 0}, {"attributes": {"POSITION": 5}, "mode": 1}]);
    };
    let s = read_edited(points_and_lines);
    assert!(s.meshes[1].primitives.is_empty());
    let last: Vec<String> = s.warnings[1..].iter().map(|w| w.to_string()).collect();
    assert_eq!(
        last,
        [
            "meshes[1].primitives[0] (mesh `plain`): points or lines: left out (lodgen writes triangles)",
            "meshes[1].primitives[1] (mesh `plain`): points or lines: left out (lodgen writes triangles)",
            "meshes[1] (mesh `plain`): no triangles left: the mesh is left out of the output",
        ]
    );
    let e = broken(|doc, _| points_and_lines(doc));
    assert_eq!(
        e.location,
        Location::Json("meshes[1].primitives[0]".to_owned())
    );
    assert!(e.to_string().contains("points or lines"), "{e}");
}

#[test]
fn accessor_past_its_buffer_view_is_reported() {
    let e = broken(|doc, _| doc["accessors"][1]["count"] = json!(6));
    assert_eq!(
        e.location,
        Location::Json("meshes[0].primitives[0].attributes.NORMAL (accessors[1])".to_owned())
    );
    assert!(matches!(*e.kind, ErrorKind::Truncated(_)), "{e}");
    let e = broken(|doc, _| doc["accessors"][0]["byteOffset"] = json!(u32::MAX));
    assert!(matches!(*e.kind, ErrorKind::Truncated(_)), "{e}");
}

#[test]
fn short_buffer_and_bad_references() {
    let e = broken(|_, bin| bin.truncate(100));
    assert_eq!(e.location, Location::Json("buffers[0]".to_owned()));
    let e = broken(|doc, _| doc["meshes"][0]["primitives"][0]["indices"] = json!(42));
    assert_eq!(
        e.location,
        Location::Json("meshes[0].primitives[0].indices".to_owned())
    );
    let e = broken(|doc, _| doc["meshes"][0]["primitives"][1]["attributes"] = json!({"NORMAL": 1}));
    assert!(e.to_string().contains("POSITION"), "{e}");
    let e =
        broken(|doc, _| doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(5));
    assert!(matches!(*e.kind, ErrorKind::Invalid(_)), "{e}");
}

#[test]
fn broken_containers() {
    let bad = |bytes: &[u8]| read_gltf(bytes, Path::new("c.glb")).unwrap_err();
    let (doc, bin) = document();
    let glb = glb_bytes(&doc, &bin);
    assert!(matches!(
        *bad(&glb[..glb.len() - 10]).kind,
        ErrorKind::Truncated(_)
    ));
    assert!(matches!(*bad(&glb[..6]).kind, ErrorKind::Truncated(_)));
    let mut v1 = glb.clone();
    v1[4] = 1;
    assert!(matches!(*bad(&v1).kind, ErrorKind::Unsupported(_)));
    let e = read_gltf(b"{\"asset\": ", Path::new("j.gltf")).unwrap_err();
    assert!(
        e.to_string().starts_with("j.gltf: invalid glTF JSON"),
        "{e}"
    );
    let e = read_gltf(br#"{"asset": {"version": "2.0"}}"#, Path::new("j.gltf")).unwrap_err();
    assert_eq!(*e.kind, ErrorKind::EmptyMesh);
}

fn read_edited(edit: impl FnOnce(&mut Value)) -> Scene {
    let (mut doc, bin) = document();
    edit(&mut doc);
    read_gltf(&gltf_bytes(doc, &bin), Path::new("e.gltf")).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn sparse_accessor_overrides_base_values() {
    let s = read_edited(|doc| {
        // Element 2 of accessor 5 takes vertex 4 of the buffer: the sparse
        // index is byte 2 of the strip indices (value 2), the value sits at
        // byte 48 of the positions view.
        doc["accessors"][5]["sparse"] = json!({
            "count": 1,
            "indices": {"bufferView": 4, "byteOffset": 2, "componentType": 5121},
            "values": {"bufferView": 0, "byteOffset": 48}
        });
        doc["accessors"][5]["max"] = json!([2.0, 2.0, 0.0]);
    });
    let p = &s.meshes[1].primitives[0];
    assert_eq!(p.positions, vec![POSITIONS[0], POSITIONS[1], POSITIONS[4]]);
}

#[test]
fn quantized_normalized_texcoords_with_required_extension() {
    let s = read_edited(|doc| {
        doc["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
        doc["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
        let n = doc["accessors"].as_array().unwrap().len();
        doc["accessors"]
            .as_array_mut()
            .unwrap()
            .push(json!({"bufferView": 3, "componentType": 5123, "normalized": true, "count": 3, "type": "VEC2"}));
        doc["meshes"][1]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(n);
    });
    let uv = s.meshes[1].primitives[0].texcoords.clone().unwrap();
    let q = |x: u16| x as f32 / 65535.0;
    assert_eq!(uv, vec![[q(0), q(1)], [q(2), q(0)], [q(2), q(3)]]);
    let Origin::Gltf { document, .. } = &s.origin else {
        panic!("glTF origin expected");
    };
    assert_eq!(document.extensions_required, ["KHR_mesh_quantization"]);
}

#[test]
fn unsupported_required_extension_is_named() {
    let e = broken(|doc, _| doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]));
    assert!(
        matches!(&e.location, Location::Json(p) if p.starts_with("extensionsRequired[0]")),
        "{e}"
    );
}

#[test]
fn nan_normal_names_the_vertex() {
    let e = broken(|_, bin| {
        bin[60 + 12 * 3 + 8..60 + 12 * 3 + 12].copy_from_slice(&f32::INFINITY.to_le_bytes())
    });
    assert_eq!(
        e.location,
        Location::Json("meshes[0].primitives[0].attributes.NORMAL[3]".to_owned())
    );
    assert!(
        e.to_string()
            .contains("NORMAL of vertex 3 (accessor 1) is not finite (inf)"),
        "{e}"
    );
}

/// Every prefix and a few thousand single-byte corruptions of a GLB give
/// `Ok` or a `ReadError`, never a panic.
#[test]
fn truncations_and_corruptions_never_panic() {
    let (doc, bin) = document();
    let glb = glb_bytes(&doc, &bin);
    for len in 0..glb.len() {
        assert!(
            read_gltf(&glb[..len], Path::new("cut.glb")).is_err(),
            "prefix {len}"
        );
    }
    let mut seed = 0x9e37_79b9_u32;
    for _ in 0..3000 {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        let mut bytes = glb.clone();
        // Corrupt the binary chunk and the GLB/JSON headers, not the JSON
        // text (whose corruptions serde_json rejects).
        let json_len = u32::from_le_bytes([glb[12], glb[13], glb[14], glb[15]]) as usize;
        let targets = [
            seed as usize % 20,
            20 + json_len + (seed as usize % (glb.len() - 20 - json_len)),
        ];
        let at = targets[(seed >> 31) as usize];
        bytes[at] = (seed >> 16) as u8;
        let _ = read_gltf(&bytes, Path::new("flip.glb"));
    }
}

/// A primitive naming a material that does not exist is read without one,
/// with a warning naming it (an error with `--strict`), instead of the
/// whole file refused. (Fails when the index fails the file.)
#[test]
fn a_missing_material_is_a_warning_not_an_error() {
    let s = read_edited(|doc| doc["meshes"][1]["primitives"][0]["material"] = json!(9));
    let w: Vec<String> = s.warnings.iter().map(|w| w.to_string()).collect();
    assert!(
        w.iter()
            .any(|w| w.starts_with("meshes[1].primitives[0].material: material 9 does not exist")),
        "{w:?}"
    );
    assert_eq!(s.meshes[1].primitives[0].material, None);
    let e = broken(|doc, _| doc["meshes"][1]["primitives"][0]["material"] = json!(9));
    assert!(e.to_string().contains("material 9 does not exist"), "{e}");
}
