//! The readers' memory cap (`lodgen::io::DECODED_BYTES_PER_INPUT_BYTE`):
//! counts a file declares are checked before anything is allocated for
//! them. Each case is a small file lying about a count (glTF accessors,
//! GLB chunk lengths, `EXT_meshopt_compression` views); reading it must fail
//! with an error naming the place while this thread's allocations stay
//! small (a counting allocator, per thread so parallel tests do not mix).

mod support;

use std::path::Path;

use lodgen::gltf_out::{write_lods, Compression, WriteOptions};
use lodgen::io::{read_gltf, read_scene, ReadError};
use lodgen::scene::{LodLevel, LodMesh, Primitive, Scene, SourceMesh};
use serde_json::{json, Value};
use support::alloc::peak_of;
use support::gltf::base64;

#[global_allocator]
static ALLOCATOR: support::alloc::Counting = support::alloc::Counting;

const MB: usize = 1 << 20;

fn expect_error(r: Result<Scene, ReadError>) -> String {
    match r {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

/// A one-triangle glTF document with its buffer as a data URI.
fn triangle_gltf(edit: impl FnOnce(&mut Value)) -> Vec<u8> {
    let bin: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": 36, "uri": uri}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}]
    });
    edit(&mut doc);
    serde_json::to_vec(&doc).unwrap()
}

#[test]
fn the_unedited_triangle_reads() {
    let s = read_gltf(&triangle_gltf(|_| {}), Path::new("t.gltf")).unwrap();
    assert_eq!(s.meshes[0].primitives[0].triangle_count(), 1);
}

#[test]
fn accessor_counts_are_checked_before_allocating() {
    // a count far past its buffer view: the view check refuses it
    let bytes = triangle_gltf(|doc| doc["accessors"][0]["count"] = json!(4_000_000_000u64));
    let (e, peak) = peak_of(|| expect_error(read_gltf(&bytes, Path::new("a.gltf"))));
    assert!(e.contains("do not fit in bufferView 0"), "{e}");
    assert!(peak < MB, "{peak} bytes");
    // no buffer view (zeros plus sparse values): only the cap bounds it
    let sparse = |doc: &mut Value| {
        let a = doc["accessors"][0].as_object_mut().unwrap();
        a.remove("bufferView");
        a.insert(
            "sparse".into(),
            json!({"count": 1, "indices": {"bufferView": 0, "componentType": 5125},
                   "values": {"bufferView": 0, "byteOffset": 12}}),
        );
    };
    let bytes = triangle_gltf(|doc| {
        sparse(doc);
        doc["accessors"][0]["count"] = json!(1_000_000_000u64);
    });
    let (e, peak) = peak_of(|| expect_error(read_gltf(&bytes, Path::new("b.gltf"))));
    assert!(
        e.contains("accessors[0]") && e.contains("memory cap"),
        "{e}"
    );
    assert!(peak < MB, "{peak} bytes");
    // within the cap it is read (zeros, vertex 0 set by the sparse value)
    let s = read_gltf(&triangle_gltf(sparse), Path::new("c.gltf")).unwrap();
    let p = &s.meshes[0].primitives[0].positions;
    assert_eq!(p, &[[1.0, 0.0, 0.0], [0.0; 3], [0.0; 3]]);
}

/// A GLB of `json` and `bin` with the chunk lengths as given.
fn glb(json: &[u8], json_len: u32, bin: &[u8], bin_len: u32, total: u32) -> Vec<u8> {
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total.to_le_bytes());
    out.extend_from_slice(&json_len.to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(json);
    out.extend_from_slice(&bin_len.to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(bin);
    out
}

#[test]
fn glb_chunk_lengths_are_checked_before_allocating() {
    let mut json = br#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":36}]}"#.to_vec();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let bin = [0u8; 36];
    let total = (12 + 8 + json.len() + 8 + bin.len()) as u32;
    let jl = json.len() as u32;
    for (what, bytes) in [
        ("JSON chunk", glb(&json, u32::MAX, &bin, 36, total)),
        ("BIN chunk", glb(&json, jl, &bin, 4_000_000_000, total)),
        ("total length", glb(&json, jl, &bin, 36, u32::MAX)),
    ] {
        let (e, peak) = peak_of(|| expect_error(read_gltf(&bytes, Path::new("c.glb"))));
        assert!(e.contains("file ends early"), "{what}: {e}");
        assert!(peak < MB, "{what}: {peak} bytes");
    }
}

/// A meshopt-compressed GLB written by lodgen, split into JSON and BIN.
fn meshopt_glb(dir: &Path) -> (Value, Vec<u8>) {
    let m = lodgen_pm::shapes::torus(1.0, 0.4, 8, 6);
    let prim = Primitive {
        positions: m.positions.clone(),
        indices: m.triangles.iter().flatten().copied().collect(),
        ..Primitive::default()
    };
    let scene = Scene {
        meshes: vec![SourceMesh {
            name: "torus".into(),
            primitives: vec![prim.clone()],
        }],
        ..Scene::default()
    };
    let lods = [LodMesh {
        source: 0,
        name: "torus".into(),
        levels: vec![LodLevel {
            primitives: vec![prim],
            hausdorff: 0.0,
            rms: 0.0,
            screen_coverage: 0.5,
        }],
    }];
    let path = dir.join("m.glb");
    let opts = WriteOptions {
        compression: Compression::Meshopt,
        ..WriteOptions::default()
    };
    write_lods(&path, &scene, &lods, &opts).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let jl = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let json: Value = serde_json::from_slice(&bytes[20..20 + jl]).unwrap();
    (json, bytes[20 + jl + 8..].to_vec())
}

#[test]
fn meshopt_sizes_are_checked_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let (json, bin) = meshopt_glb(dir.path());
    let pack = |json: &Value| {
        let mut j = serde_json::to_vec(json).unwrap();
        while j.len() % 4 != 0 {
            j.push(b' ');
        }
        let total = (12 + 8 + j.len() + 8 + bin.len()) as u32;
        glb(&j, j.len() as u32, &bin, bin.len() as u32, total)
    };
    let path = dir.path().join("edited.glb");
    std::fs::write(&path, pack(&json)).unwrap();
    read_scene(&path).unwrap();
    // a vertex view claiming 2 GB of decoded data from a few hundred bytes
    let mut lying = json.clone();
    let view = lying["bufferViews"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|v| {
            v.pointer("/extensions/EXT_meshopt_compression/mode") == Some(&json!("ATTRIBUTES"))
        })
        .unwrap();
    let ext = &mut view["extensions"]["EXT_meshopt_compression"];
    let stride = ext["byteStride"].as_u64().unwrap();
    ext["count"] = json!((1u64 << 31) / stride);
    std::fs::write(&path, pack(&lying)).unwrap();
    let (e, peak) = peak_of(|| expect_error(read_scene(&path)));
    assert!(
        e.contains("bufferViews[") && e.contains("memory cap"),
        "{e}"
    );
    assert!(peak < 4 * MB, "{peak} bytes");
}
