//! What lodgen does not simplify it copies untouched: cameras,
//! `KHR_lights_punctual`, `name`s and `extras` of the scene, nodes, meshes,
//! materials, textures, samplers and images, material and texture
//! extensions (`KHR_materials_emissive_strength`, `KHR_texture_transform`,
//! a vendor one), `extensionsUsed` / `extensionsRequired` as in the input,
//! animations (a `KHR_animation_pointer` channel into a material too);
//! TANGENT morph targets reach every level. What cannot follow a level
//! (primitive extras and extensions, such as `KHR_materials_variants`
//! mappings; an animation pointer into mesh data) is named in a warning. The glTF-Validator finds 0 errors in
//! the input and the output.

mod support;

use serde_json::{json, Value};
use support::gltf::{base64, glb_json, Doc, PNG_2X2};

/// The input: a textured sphere with NORMAL, TANGENT, TEXCOORD_0 and one
/// POSITION + NORMAL + TANGENT morph target under a group node, a
/// perspective and an orthographic camera, a point and a spot light, all
/// with names and extras.
fn scene() -> Value {
    let m = lodgen_pm::shapes::icosphere(3);
    let n = m.positions.len();
    let mut doc = Doc::new();
    let pos = doc.floats(&m.positions, true);
    let normals: Vec<[f32; 3]> = m.positions.clone();
    let nrm = doc.floats(&normals, false);
    // tangent: around the y axis (unit, orthogonal to the normal)
    let tangents: Vec<[f32; 4]> = m
        .positions
        .iter()
        .map(|p| {
            let l = (p[0] * p[0] + p[2] * p[2]).sqrt();
            if l < 1e-6 {
                [1.0, 0.0, 0.0, 1.0]
            } else {
                [-p[2] / l, 0.0, p[0] / l, 1.0]
            }
        })
        .collect();
    let tan = doc.floats(&tangents, false);
    let uv: Vec<[f32; 2]> = m
        .positions
        .iter()
        .map(|p| [0.5 + 0.5 * p[0], 0.5 + 0.5 * p[1]])
        .collect();
    let uv = doc.floats(&uv, false);
    let idx = doc.indices(&m.triangles);
    let dp: Vec<[f32; 3]> = m
        .positions
        .iter()
        .map(|p| [0.0, 0.2 * p[1].max(0.0), 0.0])
        .collect();
    let dp = doc.floats(&dp, true);
    let dn = doc.floats(&vec![[0.0, 0.01, 0.0]; n], false);
    let dt = doc.floats(&vec![[0.0, 0.0, 0.01]; n], false);
    let keys = doc.times(&[0.0, 1.0]);
    let colors = doc.floats(&[[1.0, 1.0, 1.0, 1.0], [1.0, 0.2, 0.2, 1.0]], false);
    let moves = doc.floats(&[[0.0, 1.0, 0.0], [0.0, 2.0, 0.0]], false);
    let mut json = doc.json.clone();
    let extras = |what: &str| json!({"what": what, "tags": [1, 2.5, "x"], "nested": {"ok": true}});
    json["asset"] = json!({"version": "2.0", "copyright": "CC0", "extras": extras("asset")});
    json["animations"] = json!([{
        "name": "pulse",
        "extras": extras("pulse"),
        "samplers": [{"input": keys, "output": colors}, {"input": keys, "output": moves, "interpolation": "STEP"}],
        "channels": [
            {"sampler": 1, "target": {"node": 0, "path": "translation"}},
            {"sampler": 0, "target": {"path": "pointer", "extensions": {"KHR_animation_pointer":
                {"pointer": "/materials/0/pbrMetallicRoughness/baseColorFactor"}}}}
        ]
    }]);
    json["extensionsUsed"] = json!([
        "KHR_animation_pointer",
        "KHR_lights_punctual",
        "KHR_materials_emissive_strength",
        "KHR_texture_transform",
        "VENDOR_materials_custom"
    ]);
    json["extensionsRequired"] = json!(["KHR_texture_transform"]);
    json["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"name": "bulb", "type": "point", "color": [1.0, 0.5, 0.25], "intensity": 20.0, "range": 8.0,
         "extras": extras("bulb")},
        {"name": "torch", "type": "spot", "intensity": 3.0,
         "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.5}}
    ]}});
    json["extras"] = extras("root");
    json["scene"] = 0.into();
    json["scenes"] = json!([{"name": "level", "nodes": [0, 3, 4, 5], "extras": extras("scene")}]);
    json["nodes"] = json!([
        {"name": "group", "children": [1, 2], "translation": [0.0, 1.0, 0.0], "extras": extras("group")},
        {"name": "ball", "mesh": 0, "rotation": [0.0, 0.6, 0.0, 0.8], "extras": extras("ball")},
        {"name": "lamp", "translation": [0.0, 3.0, 0.0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "eye", "camera": 0, "translation": [0.0, 0.0, 5.0], "extras": extras("eye")},
        {"name": "map", "camera": 1, "rotation": [-0.70710677, 0.0, 0.0, 0.70710677]},
        {"name": "spot", "extensions": {"KHR_lights_punctual": {"light": 1}}}
    ]);
    json["cameras"] = json!([
        {"name": "main", "type": "perspective", "extras": extras("main"),
         "perspective": {"yfov": 0.8, "znear": 0.05, "zfar": 100.0, "aspectRatio": 1.5}},
        {"name": "top", "type": "orthographic",
         "orthographic": {"xmag": 4.0, "ymag": 3.0, "znear": 0.01, "zfar": 50.0}}
    ]);
    json["meshes"] = json!([{
        "name": "sphere",
        "extras": {"targetNames": ["bulge"], "lod": "source"},
        "weights": [0.5],
        "primitives": [{
            "attributes": {"POSITION": pos, "NORMAL": nrm, "TANGENT": tan, "TEXCOORD_0": uv},
            "indices": idx,
            "material": 0,
            "targets": [{"POSITION": dp, "NORMAL": dn, "TANGENT": dt}]
        }]
    }]);
    json["materials"] = json!([{
        "name": "glow",
        "extras": extras("glow"),
        "emissiveFactor": [1.0, 0.5, 0.0],
        "pbrMetallicRoughness": {
            "baseColorFactor": [0.8, 0.7, 0.6, 1.0],
            "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": {
                "offset": [0.25, 0.5], "rotation": 0.125, "scale": [2.0, 2.0]}}},
            "metallicFactor": 0.25
        },
        "extensions": {
            "KHR_materials_emissive_strength": {"emissiveStrength": 4.5},
            "VENDOR_materials_custom": {"grain": 0.3, "mode": "soft"}
        }
    }]);
    json["textures"] =
        json!([{"name": "checker", "sampler": 0, "source": 0, "extras": extras("texture")}]);
    json["samplers"] =
        json!([{"name": "nearest", "magFilter": 9728, "minFilter": 9728, "wrapS": 33071}]);
    json["images"] = json!([{"name": "checker.png",
        "uri": format!("data:image/png;base64,{}", base64(&PNG_2X2))}]);
    json["buffers"] = json!([{"byteLength": doc.bin.len(),
        "uri": format!("data:application/octet-stream;base64,{}", base64(&doc.bin))}]);
    json
}

/// `value` without the keys lodgen adds (`MSFT_lod` and its coverage).
fn without_lod(value: &Value) -> Value {
    let mut v = value.clone();
    if let Some(ext) = v.get_mut("extensions").and_then(Value::as_object_mut) {
        ext.remove("MSFT_lod");
        if ext.is_empty() {
            v.as_object_mut().unwrap().remove("extensions");
        }
    }
    if let Some(extras) = v.get_mut("extras").and_then(Value::as_object_mut) {
        extras.remove("MSFT_screencoverage");
    }
    v
}

#[test]
fn cameras_lights_names_extras_and_extensions_are_copied_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let input_json = scene();
    let input = dir.path().join("props.gltf");
    std::fs::write(&input, serde_json::to_vec(&input_json).unwrap()).unwrap();
    let out = dir.path().join("props.glb");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let run = support::lodgen(&[i, "-o", o, "--levels", "50%,10%", "-q"]);
    let stderr = support::stderr(&run);
    assert_eq!(run.status.code(), Some(0), "{stderr}");
    assert!(stderr.is_empty(), "nothing left out: {stderr}");
    let json = glb_json(&out);
    for key in [
        "cameras",
        "materials",
        "textures",
        "samplers",
        "scenes",
        "scene",
        "extras",
        "extensions",
    ] {
        assert_eq!(json[key], input_json[key], "{key}");
    }
    assert_eq!(json["extensionsRequired"], input_json["extensionsRequired"]);
    let mut used = input_json["extensionsUsed"].as_array().unwrap().clone();
    used.push("MSFT_lod".into());
    let mut got = json["extensionsUsed"].as_array().unwrap().clone();
    let key = |v: &Value| v.as_str().unwrap().to_owned();
    used.sort_by_key(key);
    got.sort_by_key(key);
    assert_eq!(got, used, "extensionsUsed: the input's and MSFT_lod");
    assert_eq!(json["asset"]["copyright"], "CC0");
    assert_eq!(json["asset"]["extras"], input_json["asset"]["extras"]);
    // the animation: channels (a KHR_animation_pointer one too), name, extras
    let (a, b) = (&json["animations"][0], &input_json["animations"][0]);
    for key in ["name", "extras", "channels"] {
        assert_eq!(a[key], b[key], "animation {key}");
    }
    assert_eq!(a["samplers"][1]["interpolation"], "STEP");
    // images: the data URI's PNG embedded in the GLB, the name kept
    let image = &json["images"][0];
    assert_eq!(image["name"], "checker.png");
    assert_eq!(image["mimeType"], "image/png");
    assert!(
        image["bufferView"].is_u64() && image.get("uri").is_none(),
        "{image}"
    );
    // every input node as it was (the mesh node also carries its chain)
    for (k, node) in input_json["nodes"].as_array().unwrap().iter().enumerate() {
        assert_eq!(without_lod(&json["nodes"][k]), *node, "node {k}");
    }
    // every level: the mesh's extras and weights, and the TANGENT target
    let ids = json["nodes"][1]["extensions"]["MSFT_lod"]["ids"]
        .as_array()
        .unwrap();
    assert_eq!(ids.len(), 1, "50 % and 10 %: one coarser level");
    let nodes = [1]
        .into_iter()
        .chain(ids.iter().map(|v| v.as_u64().unwrap() as usize));
    for (level, node) in nodes.enumerate() {
        let mesh = &json["meshes"][json["nodes"][node]["mesh"].as_u64().unwrap() as usize];
        assert_eq!(
            mesh["extras"], input_json["meshes"][0]["extras"],
            "level {level}"
        );
        assert_eq!(mesh["weights"], json!([0.5]), "level {level}");
        let p = &mesh["primitives"][0];
        assert_eq!(p["material"], 0);
        let count =
            &json["accessors"][p["attributes"]["POSITION"].as_u64().unwrap() as usize]["count"];
        assert!(p["attributes"]["TANGENT"].is_u64(), "level {level}: {p}");
        for a in ["POSITION", "NORMAL", "TANGENT"] {
            let t = p["targets"][0][a]
                .as_u64()
                .unwrap_or_else(|| panic!("level {level}: {a} target"));
            assert_eq!(
                &json["accessors"][t as usize]["count"], count,
                "level {level} {a}"
            );
        }
    }
    std::fs::copy(&input, dir.path().join("props-in.gltf")).unwrap();
    std::fs::remove_file(&input).unwrap();
    if let Some(log) = support::validate(dir.path()) {
        assert!(
            log.contains("props.glb: 0 errors") && log.contains("props-in.gltf: 0 errors"),
            "{log}"
        );
    }
}

#[test]
fn what_cannot_follow_a_level_is_named_in_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let mut input_json = scene();
    let prim = &mut input_json["meshes"][0]["primitives"][0];
    prim["extras"] = json!({"painted": true});
    prim["extensions"] =
        json!({"KHR_materials_variants": {"mappings": [{"material": 0, "variants": [0]}]}});
    input_json["extensions"]["KHR_materials_variants"] = json!({"variants": [{"name": "night"}]});
    input_json["extensionsUsed"]
        .as_array_mut()
        .unwrap()
        .push("KHR_materials_variants".into());
    let input = dir.path().join("variants.gltf");
    std::fs::write(&input, serde_json::to_vec(&input_json).unwrap()).unwrap();
    let out = dir.path().join("variants.glb");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let run = support::lodgen(&[i, "-o", o, "--levels", "50%", "-q"]);
    let stderr = support::stderr(&run);
    assert_eq!(
        run.status.code(),
        Some(3),
        "written, with warnings: {stderr}"
    );
    assert!(
        stderr.contains(
            "meshes[0].primitives[0] (mesh `sphere`): extras, KHR_materials_variants not carried"
        ),
        "{stderr}"
    );
    let r = support::lodgen(&[i, "-o", o, "--levels", "50%", "-q", "--strict"]);
    assert_eq!(r.status.code(), Some(1), "{}", support::stderr(&r));
}

/// A `KHR_animation_pointer` channel into mesh data (the morph weights of
/// mesh 0, which the levels replace) cannot follow: named in a warning; the
/// channels into a node and a material stay.
#[test]
fn an_animation_pointer_into_mesh_data_is_named_in_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let mut input_json = scene();
    let into_mesh = json!({"sampler": 0, "target": {"path": "pointer", "extensions":
        {"KHR_animation_pointer": {"pointer": "/meshes/0/weights"}}}});
    input_json["animations"][0]["channels"]
        .as_array_mut()
        .unwrap()
        .push(into_mesh);
    let input = dir.path().join("pointer.gltf");
    std::fs::write(&input, serde_json::to_vec(&input_json).unwrap()).unwrap();
    let out = dir.path().join("pointer.glb");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let run = support::lodgen(&[i, "-o", o, "--levels", "50%", "-q"]);
    let stderr = support::stderr(&run);
    assert_eq!(run.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains("pointer.gltf: animations[0]: 1 channel(s) dropped"),
        "{stderr}"
    );
    let json = glb_json(&out);
    let channels = &input_json["animations"][0]["channels"].as_array().unwrap()[..2];
    assert_eq!(
        json["animations"][0]["channels"].as_array().unwrap(),
        channels
    );
}
