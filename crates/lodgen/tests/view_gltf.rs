//! `lodgen IN -o OUT --progressive` end to end: the written `.glb` / `.gltf`
//! carries `LODGEN_progressive` on the coarsest level (in `extensionsUsed`
//! only), `lodgen view` loads it, and after each level's record count the
//! stream's mesh has that MSFT_lod level's triangle count. When the Khronos
//! validator is installed (`tests/js/node_modules/gltf-validator`), both
//! files must validate with 0 errors.

mod support;

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

/// A textured OBJ through `lodgen --progressive`: the embedded stream carries
/// the UVs (channel `TEXCOORD_0`, wedges), and fully refined it has exactly
/// the input's corner UVs (as the reader gives them), corner for corner.
#[test]
fn progressive_output_streams_the_input_uvs() {
    let dir = root().join(format!("target/test-out/view-uv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // a sphere with a longitude UV seam: vertices on the seam get two UVs
    let m = icosphere(3);
    let mut text = String::new();
    let mut vt = Vec::new();
    for p in &m.positions {
        text += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for t in &m.triangles {
        let mut f = String::from("f");
        // the triangle's longitudes, unwrapped across the seam at ±π
        let lon: Vec<f32> = t
            .iter()
            .map(|&v| m.positions[v as usize][2].atan2(m.positions[v as usize][0]))
            .collect();
        let wrap = lon.iter().any(|&a| a > 2.0) && lon.iter().any(|&a| a < -2.0);
        for (k, &v) in t.iter().enumerate() {
            let p = m.positions[v as usize];
            let mut u = lon[k];
            if wrap && u < 0.0 {
                u += std::f32::consts::TAU;
            }
            let uv = (u / std::f32::consts::TAU + 0.5, p[1] * 0.5 + 0.5);
            vt.push(uv);
            text += &format!("vt {} {}\n", uv.0, uv.1);
            f += &format!(" {}/{}", v + 1, vt.len());
        }
        text += &f;
        text += "\n";
    }
    let input = dir.join("uvsphere.obj");
    std::fs::write(&input, text).unwrap();
    let out = dir.join("uvsphere.glb");
    let status = Command::new(env!("CARGO_BIN_EXE_lodgen"))
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .args(["--levels", "50%,10%", "--progressive", "--quiet"])
        .status()
        .unwrap();
    assert!(status.success());

    let data = ViewData::load(&out).unwrap();
    assert_eq!(data.source, "gltf");
    assert_eq!(
        data.level_summary().unwrap()["channels"],
        serde_json::json!(["TEXCOORD_0"])
    );
    let d = lodgen_pm::stream::decode_with_attributes(&data.stream).unwrap();
    let a = d.attributes.as_ref().unwrap();
    let mut c = d.pm.cursor();
    c.seek(d.pm.len());
    let bits = |uv: &[f32]| (uv[0].to_bits(), uv[1].to_bits());
    let mut got: Vec<_> = c
        .wedges()
        .unwrap()
        .iter()
        .flatten()
        .map(|&w| bits(a.wedge(w)))
        .collect();
    // the reader's UVs, corner by corner
    let scene = lodgen::io::read_scene(&input).unwrap();
    let p = &scene.meshes[0].primitives[0];
    let uvs = p.texcoords.as_ref().unwrap();
    // through the stream's encoding: u runs past 1 across the seam, so
    // unorm16 over the UVs' range
    let enc = lodgen_pm::stream::decode_header(&data.stream)
        .unwrap()
        .wedges
        .unwrap()
        .encodings[0];
    assert!(
        matches!(enc, lodgen_pm::stream::AttrEncoding::Unorm16Range(_)),
        "{enc:?}"
    );
    let want_uv = |i: u32| uvs[i as usize].map(|x| enc.round_trip(x));
    let mut want: Vec<_> = p.indices.iter().map(|&i| bits(&want_uv(i))).collect();
    got.sort_unstable();
    want.sort_unstable();
    assert_eq!(got.len(), m.triangles.len() * 3);
    assert_eq!(got, want);
    // and in the coarsest level no triangle spans the seam: no triangle's u
    // range is wider than the widest of the input's (the pole fans); one
    // across the seam would span nearly the whole [0, 1]
    let spread = |u: [f32; 3]| {
        u.iter().cloned().fold(f32::MIN, f32::max) - u.iter().cloned().fold(f32::MAX, f32::min)
    };
    let widest = p
        .indices
        .chunks_exact(3)
        .map(|t| spread([0, 1, 2].map(|k| uvs[t[k] as usize][0])))
        .fold(0.0, f32::max);
    assert!(widest < 0.75, "{widest}");
    c.seek(0);
    for w in c.wedges().unwrap() {
        let u = w.map(|x| a.wedge(x)[0]);
        assert!(
            spread(u) <= widest,
            "a coarse triangle spans the UV seam: {u:?}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The stream's size on spot.obj (UVs) with and without its attributes,
/// against the finest level alone as plain buffers (skipped when the shared asset
/// is absent). `cargo test --release -p lodgen --test view_gltf spot -- --nocapture`
#[test]
fn spot_stream_with_uvs_is_within_a_quarter_of_plain_buffers() {
    let Some(path) = lodgen::assets::shared_asset("spot.obj") else {
        return;
    };
    let scene = lodgen::io::read_scene(&path).unwrap();
    let mesh = &scene.meshes[0];
    let attributes = lodgen::lod::stream_attributes(mesh);
    let data = ViewData::from_source_mesh("spot".into(), mesh, &attributes).unwrap();
    let d = lodgen_pm::stream::decode_with_attributes(&data.stream).unwrap();
    let plain = lodgen_pm::stream::encode(&d.pm, &data.levels, Default::default());
    let a = d.attributes.as_ref().unwrap();
    let fine = d.pm.mesh_at_splits(d.pm.len());
    // the finest level as glTF buffers: one vertex per wedge (position +
    // UV), u32 indices
    let buffers = a.count * (12 + 8) + 12 * fine.triangles.len();
    eprintln!(
        "spot: {} triangles, {} vertices, {} wedges; stream {} B with UVs, {} B positions only; \
         plain f32 buffers {buffers} B (stream = {:.3}×)",
        fine.triangles.len(),
        fine.positions.len(),
        a.count,
        data.stream.len(),
        plain.len(),
        data.stream.len() as f64 / buffers as f64,
    );
    assert!(data.stream.len() > plain.len());
    // the same bound as the bunny's positions-only stream (lodgen-pm
    // tests/stream.rs): every level, exact UVs, at most 1.25× one level
    assert!(data.stream.len() as f64 <= 1.25 * buffers as f64);
}

/// `lodgen view` of a glTF whose scene draws one mesh through two nodes
/// under a scaled parent (one mirrored and turned): the viewer shows the
/// scene in its own space, each node's copy where its world transform puts
/// it, both turned outwards (the mirrored copy's winding turned back).
/// (It used to show the mesh once, at its own origin.)
#[test]
fn a_scene_is_viewed_through_its_node_transforms() {
    let dir = tempfile::tempdir().unwrap();
    let m = icosphere(2);
    let mut doc = support::gltf::Doc::new();
    let pos = doc.floats(&m.positions, true);
    let idx = doc.indices(&m.triangles);
    doc.push(
        "meshes",
        serde_json::json!({"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}),
    );
    // a quarter turn about z: (x, y) -> (-y, x)
    let h = std::f32::consts::FRAC_1_SQRT_2;
    doc.json["nodes"] = serde_json::json!([
        {"scale": [2.0, 2.0, 2.0], "children": [1, 2]},
        {"mesh": 0, "translation": [3.0, 0.0, 0.0]},
        {"mesh": 0, "translation": [0.0, -3.0, 0.0], "rotation": [0.0, 0.0, h, h],
         "scale": [-1.0, 1.0, 1.0]},
    ]);
    doc.json["scenes"] = serde_json::json!([{"nodes": [0]}]);
    doc.json["scene"] = 0.into();
    let path = dir.path().join("two.glb");
    std::fs::write(&path, doc.glb()).unwrap();

    let data = ViewData::load(&path).unwrap();
    let (pm, _) = lodgen_pm::stream::decode(&data.stream).unwrap();
    let full = pm.mesh_at_splits(pm.len());
    assert_eq!(full.positions.len(), 2 * m.positions.len());
    assert_eq!(full.triangles.len(), 2 * m.triangles.len());
    let range = |k: usize| {
        full.positions
            .iter()
            .fold((f32::MAX, f32::MIN), |(lo, hi), p| {
                (lo.min(p[k]), hi.max(p[k]))
            })
    };
    // copy 1: x in 2·(3 ± 1); copy 2: y in 2·(-3 ± 1), x in 2·(±1)
    let close = |a: f32, b: f32| (a - b).abs() < 0.02;
    let (x, y) = (range(0), range(1));
    assert!(close(x.0, -2.0) && close(x.1, 8.0), "x {x:?}");
    assert!(close(y.0, -8.0) && close(y.1, 2.0), "y {y:?}");
    // both copies enclose a positive volume (8 × the sphere's each)
    let volume = |positions: &[[f32; 3]], triangles: &[[u32; 3]]| -> f64 {
        triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| glam::DVec3::from(positions[i as usize].map(f64::from)));
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    };
    let sphere = volume(&m.positions, &m.triangles);
    assert!(sphere > 0.0);
    let v = volume(&full.positions, &full.triangles);
    assert!((v / (16.0 * sphere) - 1.0).abs() < 0.01, "{v} vs {sphere}");
}

#[test]
fn viewing_a_missing_file_or_a_directory_prints_one_line_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["nope.glb", "nope.obj", ""] {
        let path = dir.path().join(name);
        for extra in [&[][..], &["--print-levels"][..]] {
            let out = Command::new(env!("CARGO_BIN_EXE_lodgen"))
                .arg("view")
                .args(extra)
                .arg(&path)
                .output()
                .unwrap();
            assert_eq!(out.status.code(), Some(1));
            let err = String::from_utf8_lossy(&out.stderr);
            let lines: Vec<&str> = err.lines().collect();
            assert_eq!(lines.len(), 1, "{err}");
            let want = format!("error: viewing {}: ", path.display());
            assert!(lines[0].starts_with(&want), "{err}");
            let why = if name.is_empty() {
                "is a directory"
            } else {
                "(os error 2)"
            };
            assert!(lines[0].ends_with(why), "{err}");
        }
    }
}
