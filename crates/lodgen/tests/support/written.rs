//! Writer tests' helpers: a generated icosphere, LOD chains made with
//! `meshopt::simplify`, scratch directories, a minimal accessor decoder
//! (plain, quantized and meshopt-compressed data) and copies of every
//! output into `$LODGEN_TEST_OUT` for the glTF-Validator CI step.

use std::path::Path;

use lodgen::coverage::assign_screen_coverages;
use lodgen::gltf_out::{write_lods, WriteOptions, WriteSummary};
use lodgen::scene::{LodLevel, LodMesh, Material, Origin, Primitive, Scene, SourceMesh};
use serde_json::Value;

/// An icosphere of radius `r` around `center`, subdivided `n` times
/// (20 * 4^n triangles), welded: `lodgen_pm::shapes::icosphere`, moved.
pub fn icosphere(n: u32, r: f32, center: [f32; 3]) -> (Vec<[f32; 3]>, Vec<u32>) {
    let m = lodgen_pm::shapes::icosphere(n);
    let pos = m
        .positions
        .iter()
        .map(|p| [0, 1, 2].map(|k| center[k] + r * p[k]))
        .collect();
    (pos, m.indices())
}

/// A scene of one mesh `name` drawing `prim`, with one material
/// `material` of colour `base_color` (no transforms, no warnings).
pub fn one_mesh_scene(name: &str, prim: Primitive, material: &str, base_color: [f32; 4]) -> Scene {
    Scene {
        meshes: vec![SourceMesh {
            name: name.into(),
            primitives: vec![prim],
        }],
        materials: vec![Material {
            name: material.into(),
            base_color: Some(base_color),
        }],
        origin: Origin::Flat,
        warnings: Vec::new(),
    }
}

/// Spherical UVs in [0, 1].
pub fn sphere_uvs(pos: &[[f32; 3]], center: [f32; 3]) -> Vec<[f32; 2]> {
    pos.iter()
        .map(|p| {
            let d = [p[0] - center[0], p[1] - center[1], p[2] - center[2]];
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let u = 0.5 + d[2].atan2(d[0]) / (2.0 * std::f32::consts::PI);
            let v = 0.5 - (d[1] / l).clamp(-1.0, 1.0).asin() / std::f32::consts::PI;
            [u.clamp(0.0, 1.0), v.clamp(0.0, 1.0)]
        })
        .collect()
}

/// A chain: level 0 = `prim`, then `meshopt::simplify` to each ratio (the
/// coarser levels keep the full vertex arrays). Hausdorff errors come from
/// meshopt's relative error; coverages from `assign_screen_coverages`.
pub fn chain(name: &str, source: usize, prim: Primitive, ratios: &[f64]) -> LodMesh {
    let bytes: Vec<u8> = prim
        .positions
        .iter()
        .flatten()
        .flat_map(|c| c.to_le_bytes())
        .collect();
    let adapter = meshopt::VertexDataAdapter::new(&bytes, 12, 0).unwrap();
    let mut levels = vec![LodLevel {
        primitives: vec![prim.clone()],
        ..Default::default()
    }];
    for &ratio in ratios {
        let target = ((prim.indices.len() as f64 * ratio) as usize / 3) * 3;
        let mut error = 0.0f32;
        let indices = meshopt::simplify(
            &prim.indices,
            &adapter,
            target,
            1.0,
            meshopt::SimplifyOptions::None,
            Some(&mut error),
        );
        assert!(
            indices.len() < prim.indices.len(),
            "simplify made no progress"
        );
        levels.push(LodLevel {
            primitives: vec![Primitive {
                indices,
                ..prim.clone()
            }],
            hausdorff: (error as f64).max(1e-4) * (levels.len() as f64),
            ..Default::default()
        });
    }
    let mut lod = LodMesh {
        source,
        name: name.into(),
        levels,
    };
    assign_screen_coverages(&mut lod);
    lod
}

/// A fresh empty scratch directory for one test, removed when dropped.
pub struct Scratch(tempfile::TempDir);

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

/// A fresh empty scratch directory for one test (removed at its end).
pub fn scratch(test: &str) -> Scratch {
    Scratch(
        tempfile::Builder::new()
            .prefix(&format!("lodgen-gltf-out-{test}-"))
            .tempdir()
            .unwrap(),
    )
}

/// Writes `scene` with its one chain `lod` at `path`, publishes the summary
/// as `name` ([`publish_summary`]) and returns what was written
/// ([`load_raw`]) with the summary.
pub fn write_and_load(
    path: &Path,
    scene: &Scene,
    lod: &LodMesh,
    opts: &WriteOptions,
    name: &str,
) -> (Value, Vec<Vec<u8>>, WriteSummary) {
    let summary = write_lods(path, scene, std::slice::from_ref(lod), opts).unwrap();
    publish_summary(name, &summary);
    let (json, buffers) = load_raw(path);
    (json, buffers, summary)
}

/// Copies every written file into `$LODGEN_TEST_OUT/<prefix>/` when set.
pub fn publish_summary(prefix: &str, summary: &WriteSummary) {
    let Some(out) = std::env::var_os("LODGEN_TEST_OUT") else {
        return;
    };
    let dir = Path::new(&out).join(prefix);
    std::fs::create_dir_all(&dir).unwrap();
    for (file, _) in &summary.files {
        std::fs::copy(file, dir.join(file.file_name().unwrap())).unwrap();
    }
}

/// Triangles as position triples, each rotated to start at its smallest
/// corner, sorted: equal for two index buffers drawing the same triangles.
pub fn canonical_triangles(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[[u32; 3]; 3]> {
    let key = |i: u32| positions[i as usize].map(f32::to_bits);
    let mut out: Vec<[[u32; 3]; 3]> = indices
        .chunks_exact(3)
        .map(|t| {
            let c = [key(t[0]), key(t[1]), key(t[2])];
            let m = (0..3).min_by_key(|&i| c[i]).unwrap();
            [c[m], c[(m + 1) % 3], c[(m + 2) % 3]]
        })
        .collect();
    out.sort();
    out
}

/// The JSON and binary buffers of a written file (`.glb`: BIN chunk is
/// buffer 0; `.gltf`: buffers from their URIs; placeholder buffers empty).
pub fn load_raw(path: &Path) -> (Value, Vec<Vec<u8>>) {
    let bytes = std::fs::read(path).unwrap();
    if bytes.starts_with(b"glTF") {
        let glb = gltf::Glb::from_slice(&bytes).unwrap();
        let json: Value = serde_json::from_slice(&glb.json).unwrap();
        let n = json["buffers"].as_array().map_or(0, Vec::len);
        let mut buffers = vec![Vec::new(); n];
        if n > 0 {
            buffers[0] = glb.bin.unwrap().into_owned();
        }
        (json, buffers)
    } else {
        let json: Value = serde_json::from_slice(&bytes).unwrap();
        let buffers = json["buffers"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| match b["uri"].as_str() {
                Some(uri) => std::fs::read(path.parent().unwrap().join(uri)).unwrap(),
                None => Vec::new(),
            })
            .collect();
        (json, buffers)
    }
}

/// The bytes of a buffer view, decompressing `EXT_meshopt_compression` with
/// meshopt's decoders (and checking the vertex codec version byte 0xa0).
pub fn view_bytes(json: &Value, buffers: &[Vec<u8>], view: usize) -> Vec<u8> {
    let v = &json["bufferViews"][view];
    if let Some(m) = v.pointer("/extensions/EXT_meshopt_compression") {
        let buf = &buffers[m["buffer"].as_u64().unwrap() as usize];
        let off = m["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = m["byteLength"].as_u64().unwrap() as usize;
        let data = &buf[off..off + len];
        let count = m["count"].as_u64().unwrap() as usize;
        let stride = m["byteStride"].as_u64().unwrap() as usize;
        match m["mode"].as_str().unwrap() {
            "ATTRIBUTES" => {
                assert_eq!(data[0], 0xa0, "vertex stream must use codec version 0");
                fn dec<T: Clone + Default + AsRef<[u8]>>(data: &[u8], count: usize) -> Vec<u8> {
                    meshopt::decode_vertex_buffer::<T>(data, count)
                        .unwrap()
                        .iter()
                        .flat_map(|e| e.as_ref().to_vec())
                        .collect()
                }
                match stride {
                    4 => dec::<[u8; 4]>(data, count),
                    8 => dec::<[u8; 8]>(data, count),
                    12 => dec::<[u8; 12]>(data, count),
                    s => panic!("stride {s}"),
                }
            }
            "TRIANGLES" => {
                assert_eq!(data[0], 0xe1, "triangle codec header");
                if stride == 2 {
                    meshopt::decode_index_buffer::<u16>(data, count)
                        .unwrap()
                        .into_iter()
                        .flat_map(u16::to_le_bytes)
                        .collect()
                } else {
                    meshopt::decode_index_buffer::<u32>(data, count)
                        .unwrap()
                        .into_iter()
                        .flat_map(u32::to_le_bytes)
                        .collect()
                }
            }
            m => panic!("mode {m}"),
        }
    } else {
        let buf = &buffers[v["buffer"].as_u64().unwrap() as usize];
        let off = v["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = v["byteLength"].as_u64().unwrap() as usize;
        buf[off..off + len].to_vec()
    }
}

/// Decodes an accessor to f64 components (normalized integers mapped to
/// [-1, 1] / [0, 1]; indices as their integer values).
pub fn accessor_values(json: &Value, buffers: &[Vec<u8>], accessor: usize) -> Vec<Vec<f64>> {
    let a = &json["accessors"][accessor];
    let view = a["bufferView"].as_u64().unwrap() as usize;
    let data = view_bytes(json, buffers, view);
    let count = a["count"].as_u64().unwrap() as usize;
    let comps = match a["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" => 4,
        "MAT4" => 16,
        t => panic!("type {t}"),
    };
    let ctype = a["componentType"].as_u64().unwrap();
    let normalized = a["normalized"].as_bool().unwrap_or(false);
    let size = match ctype {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        _ => 4,
    };
    let stride = json["bufferViews"][view]["byteStride"]
        .as_u64()
        .map_or(size * comps, |s| s as usize);
    let off = a["byteOffset"].as_u64().unwrap_or(0) as usize;
    (0..count)
        .map(|i| {
            (0..comps)
                .map(|c| {
                    let at = off + i * stride + c * size;
                    let b = &data[at..at + size];
                    match (ctype, normalized) {
                        (5126, _) => f32::from_le_bytes(b.try_into().unwrap()) as f64,
                        (5125, false) => u32::from_le_bytes(b.try_into().unwrap()) as f64,
                        (5123, false) => u16::from_le_bytes(b.try_into().unwrap()) as f64,
                        (5121, false) => b[0] as f64,
                        (5121, true) => b[0] as f64 / 255.0,
                        (5123, true) => u16::from_le_bytes(b.try_into().unwrap()) as f64 / 65535.0,
                        (5122, true) => {
                            (i16::from_le_bytes(b.try_into().unwrap()) as f64 / 32767.0).max(-1.0)
                        }
                        (5120, true) => ((b[0] as i8) as f64 / 127.0).max(-1.0),
                        t => panic!("component type {t:?}"),
                    }
                })
                .collect()
        })
        .collect()
}

/// Node indices reachable from any scene.
pub fn scene_nodes(json: &Value) -> Vec<usize> {
    let mut seen = Vec::new();
    let mut stack: Vec<usize> = json["scenes"]
        .as_array()
        .into_iter()
        .flatten()
        .flat_map(|s| {
            s["nodes"]
                .as_array()
                .unwrap()
                .iter()
                .map(|n| n.as_u64().unwrap() as usize)
        })
        .collect();
    while let Some(n) = stack.pop() {
        if seen.contains(&n) {
            continue;
        }
        seen.push(n);
        if let Some(c) = json["nodes"][n]["children"].as_array() {
            stack.extend(c.iter().map(|v| v.as_u64().unwrap() as usize));
        }
    }
    seen.sort();
    seen
}

/// The MSFT_lod head node and its ids.
pub fn lod_head(json: &Value) -> (usize, Vec<usize>) {
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
pub fn check_round_trip(path: &Path, lod: &LodMesh) {
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
