//! The glTF writer on glTF input: the input's hierarchy, materials,
//! images and animations kept around the LOD chains (plain and
//! `--quantize`), skins on every LOD node unless quantized.

mod support;

use lodgen::gltf_out::{write_lods, Compression, WriteOptions};
use lodgen::scene::{LodMesh, Material, Origin, Primitive, Scene, SourceMesh};
use support::gltf::PNG_2X2;
use support::written::*;

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
    let mut data = vec![0u8; 4];
    data.extend_from_slice(&PNG_2X2);
    data.resize(80, 0);
    for v in KEYS.iter().chain(TRANSLATIONS.iter().flatten()) {
        data.extend_from_slice(&v.to_le_bytes());
    }
    let materials = vec![Material {
        name: "tex".into(),
        base_color: None,
    }];
    gltf_origin_chain("sphere", prim, materials, json, data)
}

#[test]
fn gltf_origin_keeps_hierarchy_materials_and_images() {
    let (scene, lod) = gltf_scene();
    let dir = scratch("origin");
    let path = dir.join("scene.glb");
    let (json, buffers, summary) =
        write_and_load(&path, &scene, &lod, &WriteOptions::default(), "gltf_origin");
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
    let (json, _, _) = write_and_load(&path, &scene, &lod, &opts, "gltf_origin_quantized");
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
    let data: Vec<u8> = IBM.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    let materials = Vec::new();
    gltf_origin_chain("skinned", prim, materials, json, data)
}

#[test]
fn skins_survive_on_every_lod_node_unless_quantized() {
    let (scene, lod) = skinned_scene();
    let dir = scratch("skinned");
    let path = dir.join("skinned.glb");
    let (json, buffers, _) = write_and_load(
        &path,
        &scene,
        &lod,
        &WriteOptions::default(),
        "gltf_skinned",
    );
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
    // ignores, so the skin goes, and with it the levels' joints and weights
    // (a skinned mesh without its skin is what the glTF-Validator warns of)
    let path = dir.join("skinned_q.glb");
    let opts = WriteOptions {
        quantize: true,
        compression: Compression::None,
    };
    let summary = write_lods(&path, &scene, std::slice::from_ref(&lod), &opts).unwrap();
    let (json, _) = load_raw(&path);
    assert!(json.get("skins").is_none());
    assert!(json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .all(|n| n.get("skin").is_none()));
    for m in json["meshes"].as_array().unwrap() {
        let attributes = &m["primitives"][0]["attributes"];
        assert!(attributes.get("JOINTS_0").is_none() && attributes.get("WEIGHTS_0").is_none());
    }
    let w: Vec<String> = summary.warnings.iter().map(|w| w.to_string()).collect();
    assert!(
        w.iter().any(|w| w.contains("JOINTS_n / WEIGHTS_n")),
        "{w:?}"
    );
}

/// A one-mesh scene read from `in.gltf` (its JSON `json`, one buffer
/// `data`) and the mesh's chain at 40 % and 10 %.
fn gltf_origin_chain(
    name: &str,
    prim: Primitive,
    materials: Vec<Material>,
    json: serde_json::Value,
    data: Vec<u8>,
) -> (Scene, LodMesh) {
    let doc: gltf_json::Root = serde_json::from_value(json.clone()).unwrap();
    let scene = Scene {
        meshes: vec![SourceMesh {
            name: name.into(),
            primitives: vec![prim.clone()],
        }],
        materials,
        origin: Origin::Gltf {
            path: "in.gltf".into(),
            document: Box::new(doc),
            json: Box::new(json),
            buffers: vec![data],
        },
        warnings: Vec::new(),
    };
    let lod = chain(name, 0, prim, &[0.4, 0.1]);
    (scene, lod)
}

/// `quantize` on glTF input whose UVs leave [0, 1] (here [-1, 2]) under a
/// textured material: TEXCOORD_0 is normalized `u16` over the UVs' range
/// and every texture of the material reading TEXCOORD_0 gets that range as
/// `KHR_texture_transform` (required); each UV so decoded lies within half
/// a step of the `f32` file's (fails when the range or the rounding
/// differs from the stream's `Unorm16Range`), and glTF-Validator passes.
#[test]
fn quantized_uvs_leaving_the_unit_square_take_a_texture_transform() {
    let (mut scene, mut lod) = gltf_scene();
    for p in lod.levels.iter_mut().flat_map(|l| &mut l.primitives) {
        for t in p.texcoords.iter_mut().flatten() {
            *t = t.map(|c| c * 3.0 - 1.0);
        }
    }
    if let Origin::Gltf { json, .. } = &mut scene.origin {
        json["materials"][0]["occlusionTexture"] = serde_json::json!({"index": 0});
    }
    let dir = scratch("uv-range");
    let q = WriteOptions {
        quantize: true,
        compression: Compression::None,
    };
    let (qjson, qbuf, _) = write_and_load(&dir.join("q.glb"), &scene, &lod, &q, "uv_range_q");
    let f = WriteOptions::default();
    let (fjson, fbuf, _) = write_and_load(&dir.join("f.glb"), &scene, &lod, &f, "uv_range_f");
    let material = &qjson["materials"][0];
    let transform = &material["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]
        ["KHR_texture_transform"];
    assert_eq!(
        material["occlusionTexture"]["extensions"]["KHR_texture_transform"],
        *transform
    );
    for key in ["extensionsUsed", "extensionsRequired"] {
        assert!(qjson[key]
            .as_array()
            .unwrap()
            .contains(&"KHR_texture_transform".into()));
    }
    let offset = transform["offset"][0].as_f64().unwrap();
    let scale = transform["scale"][0].as_f64().unwrap();
    assert_eq!(transform["offset"][1], transform["offset"][0]);
    assert_eq!(transform["scale"][1], transform["scale"][0]);
    assert!(offset <= -1.0 + 1e-6 && offset + scale >= 2.0 - 1e-6);
    let step = scale / 65535.0;
    for mesh in 0..lod.levels.len() {
        let uv = |json: &serde_json::Value| {
            json["meshes"][mesh]["primitives"][0]["attributes"]["TEXCOORD_0"]
                .as_u64()
                .unwrap() as usize
        };
        let a = &qjson["accessors"][uv(&qjson)];
        assert_eq!(
            (a["componentType"].as_u64(), a["normalized"].as_bool()),
            (Some(5123), Some(true))
        );
        let got = accessor_values(&qjson, &qbuf, uv(&qjson));
        let want = accessor_values(&fjson, &fbuf, uv(&fjson));
        assert_eq!(got.len(), want.len());
        let worst = got
            .iter()
            .flatten()
            .zip(want.iter().flatten())
            .map(|(q, f)| (offset + scale * q - f).abs())
            .fold(0.0, f64::max);
        assert!(
            worst <= step * 0.5 + 1e-6,
            "level {mesh}: UV off by {worst} (step {step})"
        );
    }
    support::validate(&dir);
}

/// A node with a mesh and children (a car body and its wheels) keeps its
/// transform and children and takes its chain on a new child: an MSFT_lod
/// level replaces its node with the node's whole subtree, so LOD nodes
/// beside the node left its children at level 0 only (three.js dropped the
/// wheels at a distance). Plain and quantized alike. (Fails when the chain
/// sits on the node itself.)
#[test]
fn a_mesh_node_with_children_keeps_them_at_every_level() {
    let (positions, indices) = icosphere(2, 1.0, [0.0; 3]);
    let prim = Primitive {
        positions,
        indices,
        ..Primitive::default()
    };
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"name": "body", "mesh": 0, "children": [1], "translation": [1.0, 2.0, 3.0]},
            {"name": "wheel", "translation": [0.0, -1.0, 0.0]}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"componentType": 5126, "count": 3, "type": "VEC3"}]
    });
    let (scene, lod) = gltf_origin_chain("body", prim, Vec::new(), json, Vec::new());
    let dir = scratch("children");
    for (name, quantize, summary) in [
        ("plain.glb", false, "children_plain"),
        ("q.glb", true, "children_q"),
    ] {
        let opts = WriteOptions {
            quantize,
            compression: Compression::None,
        };
        let (json, _, _) = write_and_load(&dir.join(name), &scene, &lod, &opts, summary);
        let nodes = json["nodes"].as_array().unwrap();
        let body = &nodes[0];
        assert!(body.get("mesh").is_none(), "{name}: {body}");
        assert_eq!(body["translation"], serde_json::json!([1.0, 2.0, 3.0]));
        let children: Vec<u64> = body["children"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_u64().unwrap())
            .collect();
        assert_eq!(children[0], 1, "{name}: the wheel stays");
        let lod0 = &nodes[children[1] as usize];
        assert!(lod0.get("mesh").is_some(), "{name}: {lod0}");
        let ids = lod0["extensions"]["MSFT_lod"]["ids"].as_array().unwrap();
        assert_eq!(ids.len(), 2, "{name}");
        for id in ids {
            let n = &nodes[id.as_u64().unwrap() as usize];
            assert!(
                n.get("mesh").is_some() && n.get("children").is_none(),
                "{name}"
            );
        }
    }
}
