//! The glTF scene seed: a small `.gltf` (buffer as a base64 data URI) with
//! what the writer carries over besides meshes, so that mutations reach
//! that code too: a morphed mesh (POSITION / NORMAL targets, weights,
//! target names), a skinned strip (JOINTS_0 / WEIGHTS_0, a skin with
//! inverse bind matrices), joints, a camera, a `KHR_lights_punctual`
//! light, a material with `KHR_texture_transform` and
//! `KHR_materials_emissive_strength`, a texture with a data-URI PNG, and an
//! animation of a joint's translation, the morph weights and (by
//! `KHR_animation_pointer`) the material's colour.

use crate::io::encode_base64;
use serde_json::{json, Value};

/// A 2×2 RGB PNG.
const PNG_2X2: [u8; 75] = [
    137, 80, 78, 71, 13, 10, 26, 10, 0, 0, 0, 13, 73, 72, 68, 82, 0, 0, 0, 2, 0, 0, 0, 2, 8, 2, 0,
    0, 0, 253, 212, 154, 115, 0, 0, 0, 18, 73, 68, 65, 84, 120, 156, 99, 248, 207, 192, 192, 0,
    194, 12, 255, 65, 0, 0, 38, 232, 6, 250, 18, 64, 95, 204, 0, 0, 0, 0, 73, 69, 78, 68, 174, 66,
    96, 130,
];

/// One buffer with a view and an accessor per array.
#[derive(Default)]
struct Data {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Data {
    /// `values` (`width` floats an element) as an accessor of `ty`, with
    /// min / max when `bounds`; its index.
    fn floats(&mut self, values: &[f32], width: usize, ty: &str, bounds: bool) -> usize {
        let mut acc = json!({"componentType": 5126, "count": values.len() / width, "type": ty});
        if bounds {
            let column = |k: usize| values.iter().skip(k).step_by(width).copied();
            let lo: Vec<f32> = (0..width)
                .map(|k| column(k).fold(f32::MAX, f32::min))
                .collect();
            let hi: Vec<f32> = (0..width)
                .map(|k| column(k).fold(f32::MIN, f32::max))
                .collect();
            acc["min"] = json!(lo);
            acc["max"] = json!(hi);
        }
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.add(&bytes, acc)
    }

    fn add(&mut self, bytes: &[u8], mut accessor: Value) -> usize {
        let at = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        self.views
            .push(json!({"buffer": 0, "byteOffset": at, "byteLength": bytes.len()}));
        accessor["bufferView"] = json!(self.views.len() - 1);
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }
}

/// The morphed box (12 triangles) and the skinned strip (8 triangles):
/// their `meshes` entries.
fn meshes(d: &mut Data) -> Value {
    let m = lodgen_pm::shapes::cube([-0.5; 3], [0.5; 3], 1);
    let pos: Vec<f32> = m.positions.iter().flatten().copied().collect();
    let normals: Vec<f32> = m
        .positions
        .iter()
        .flat_map(|p| {
            let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            p.map(|c| c / l)
        })
        .collect();
    let grow: Vec<f32> = pos.iter().map(|c| c * 0.25).collect();
    let tilt: Vec<f32> = m
        .positions
        .iter()
        .flat_map(|p| [0.0, 0.0, 0.1 * p[0]])
        .collect();
    let bend: Vec<f32> = m.positions.iter().flat_map(|_| [0.0, 0.05, 0.0]).collect();
    let box_idx: Vec<u8> = m
        .triangles
        .iter()
        .flatten()
        .flat_map(|&i| (i as u16).to_le_bytes())
        .collect();
    let box_prim = json!({
        "attributes": {"POSITION": d.floats(&pos, 3, "VEC3", true), "NORMAL": d.floats(&normals, 3, "VEC3", false)},
        "indices": d.add(&box_idx, json!({"componentType": 5123, "count": 36, "type": "SCALAR"})),
        "targets": [
            {"POSITION": d.floats(&grow, 3, "VEC3", true), "NORMAL": d.floats(&bend, 3, "VEC3", false)},
            {"POSITION": d.floats(&tilt, 3, "VEC3", true), "NORMAL": d.floats(&bend, 3, "VEC3", false)}
        ]
    });
    // the strip: 2 × 5 vertices along y, weights blending joint 0 into 1
    let strip = lodgen_pm::shapes::grid(1, 4, |_, _| 0.0);
    let spos: Vec<f32> = strip
        .positions
        .iter()
        .flat_map(|p| [p[0], 2.0 * p[1], 0.0])
        .collect();
    let uv: Vec<f32> = strip.positions.iter().flat_map(|p| [p[0], p[1]]).collect();
    // (a joint of weight 0 is joint 0, as the validator likes it)
    let blend = |y: f32| {
        if y <= 0.0 {
            ([0, 0, 0, 0], [1.0, 0.0, 0.0, 0.0])
        } else if y >= 1.0 {
            ([1, 0, 0, 0], [1.0, 0.0, 0.0, 0.0])
        } else {
            ([0, 1, 0, 0], [1.0 - y, y, 0.0, 0.0])
        }
    };
    let joints: Vec<u8> = strip.positions.iter().flat_map(|p| blend(p[1]).0).collect();
    let weights: Vec<f32> = strip.positions.iter().flat_map(|p| blend(p[1]).1).collect();
    let strip_idx: Vec<u8> = strip.triangles.iter().flatten().map(|&i| i as u8).collect();
    let strip_prim = json!({
        "attributes": {
            "POSITION": d.floats(&spos, 3, "VEC3", true),
            "TEXCOORD_0": d.floats(&uv, 2, "VEC2", false),
            "JOINTS_0": d.add(&joints, json!({"componentType": 5121, "count": 10, "type": "VEC4"})),
            "WEIGHTS_0": d.floats(&weights, 4, "VEC4", false)
        },
        "indices": d.add(&strip_idx, json!({"componentType": 5121, "count": strip_idx.len(), "type": "SCALAR"})),
        "material": 0
    });
    json!([
        {"name": "box", "primitives": [box_prim], "weights": [0.0, 0.5],
         "extras": {"targetNames": ["grow", "tilt"]}},
        {"name": "strip", "primitives": [strip_prim]}
    ])
}

/// The animation `move`: joint 1's translation, the box's weights, and the
/// material's base colour through `KHR_animation_pointer`.
fn animation(d: &mut Data) -> Value {
    let t = d.floats(&[0.0, 0.5, 1.0], 1, "SCALAR", true);
    let moves = d.floats(
        &[0.0, 1.0, 0.0, 0.5, 1.0, 0.0, 0.0, 1.0, 0.0],
        3,
        "VEC3",
        false,
    );
    let weights = d.floats(&[0.0, 0.0, 1.0, 0.5, 0.0, 1.0], 1, "SCALAR", false);
    let colors = d.floats(
        &[1.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0],
        4,
        "VEC4",
        false,
    );
    let pointer = "/materials/0/pbrMetallicRoughness/baseColorFactor";
    json!({
        "name": "move",
        "samplers": [{"input": t, "output": moves}, {"input": t, "output": weights},
                     {"input": t, "output": colors, "interpolation": "STEP"}],
        "channels": [
            {"sampler": 0, "target": {"node": 3, "path": "translation"}},
            {"sampler": 1, "target": {"node": 0, "path": "weights"}},
            {"sampler": 2, "target": {"path": "pointer",
             "extensions": {"KHR_animation_pointer": {"pointer": pointer}}}}
        ]
    })
}

/// The seed's `.gltf` bytes.
pub(super) fn scene_gltf() -> Vec<u8> {
    let mut d = Data::default();
    let meshes = meshes(&mut d);
    let animation = animation(&mut d);
    let ibm: Vec<f32> = [0.0, -1.0]
        .iter()
        .flat_map(|&y| {
            [
                1.0, 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., y, 0., 1.,
            ]
        })
        .collect();
    let ibm = d.floats(&ibm, 16, "MAT4", false);
    let doc = json!({
        "asset": {"version": "2.0", "extras": {"seed": "scene"}},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_texture_transform",
                           "KHR_materials_emissive_strength", "KHR_animation_pointer"],
        "extensionsRequired": ["KHR_texture_transform"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 5.0}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 4, 5]}],
        "nodes": [
            {"name": "box", "mesh": 0, "translation": [2.0, 0.0, 0.0], "extras": {"id": 1}},
            {"name": "strip", "mesh": 1, "skin": 0},
            {"name": "root", "children": [3]},
            {"name": "bone", "translation": [0.0, 1.0, 0.0]},
            {"name": "eye", "camera": 0, "translation": [0.0, 1.0, 6.0]},
            {"name": "lamp", "extensions": {"KHR_lights_punctual": {"light": 0}}}
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
        "skins": [{"joints": [2, 3], "inverseBindMatrices": ibm, "skeleton": 2}],
        "meshes": meshes,
        "animations": [animation],
        "materials": [{
            "name": "paint",
            "emissiveFactor": [0.2, 0.2, 0.2],
            "pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
                "extensions": {"KHR_texture_transform": {"scale": [2.0, 2.0]}}}},
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0}}
        }],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9728}],
        "images": [{"uri": format!("data:image/png;base64,{}", encode_base64(&PNG_2X2))}],
        "buffers": [{"byteLength": d.bin.len(),
                     "uri": format!("data:application/octet-stream;base64,{}", encode_base64(&d.bin))}],
        "bufferViews": d.views,
        "accessors": d.accessors
    });
    serde_json::to_vec_pretty(&doc).unwrap_or_default()
}
