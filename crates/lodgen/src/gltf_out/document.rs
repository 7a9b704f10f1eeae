//! Document assembly: the root JSON of the output, either a new document
//! for flat input (materials, one root node per chain) or the input glTF
//! document kept (nodes, hierarchy, materials, skins, animations, images)
//! with each mesh's node given its LOD chain.

use std::path::Path;

use serde_json::{json, Map, Value};

use crate::scene::{LodMesh, Scene, Warning};

use super::builder::Builder;
use super::error::WriteError;
use super::input::{embed_images, input_err, keep_animations, keep_skins, take_array};
use super::msft_lod::{add_lod_nodes, dequant_transform, moved};
use super::prepare::PreparedChain;

pub(super) fn flat_document(
    scene: &Scene,
    chains: &[PreparedChain],
    chain_meshes: &[Vec<usize>],
    offset: [f64; 3],
    out: &mut Builder,
) -> Map<String, Value> {
    let materials: Vec<Value> = scene
        .materials
        .iter()
        .map(|m| {
            let mut pbr = json!({"metallicFactor": 0.0});
            if let Some(c) = m.base_color {
                pbr["baseColorFactor"] = json!(c);
            }
            json!({"name": m.name, "pbrMetallicRoughness": pbr})
        })
        .collect();
    let mut nodes = Vec::new();
    let mut roots = Vec::new();
    for (chain, meshes) in chains.iter().zip(chain_meshes) {
        let transform = moved(dequant_transform(chain, out.opts.quantize), offset);
        let mut node = transform.clone();
        node.insert("name".into(), chain.name.clone().into());
        nodes.push(Value::Object(node));
        let first = nodes.len() - 1;
        roots.push(first);
        add_lod_nodes(
            &mut nodes,
            first,
            &chain.name,
            meshes,
            &chain.coverages,
            &transform,
        );
    }
    let mut root = Map::new();
    root.insert(
        "asset".into(),
        json!({"version": "2.0", "generator": "lodgen"}),
    );
    if !materials.is_empty() {
        root.insert("materials".into(), materials.into());
    }
    root.insert("nodes".into(), nodes.into());
    root.insert("scene".into(), 0.into());
    root.insert("scenes".into(), json!([{ "nodes": roots }]));
    root
}

/// Mesh-data extensions of the input that no longer apply to the output.
const DROPPED_EXTENSIONS: &[&str] = &[
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_mesh_quantization",
    "MSFT_lod",
    "EXT_mesh_gpu_instancing",
];

/// The input document with its meshes replaced by the LOD chains, its
/// skins, animations and images carried into the output's non-LOD range.
/// The input glTF as [`crate::scene::Origin::Gltf`] holds it.
pub(super) struct InputGltf<'a> {
    /// The input file (relative image URIs).
    pub path: &'a Path,
    /// The parsed document: its buffer views point into `buffers`
    /// (decoded `EXT_meshopt_compression` views included).
    pub document: &'a gltf_json::Root,
    /// The JSON as written, which the output copies untouched.
    pub json: &'a Value,
    pub buffers: &'a [Vec<u8>],
}

pub(super) fn gltf_document(
    input: &InputGltf<'_>,
    lods: &[LodMesh],
    chains: &[PreparedChain],
    chain_meshes: &[Vec<usize>],
    out: &mut Builder,
) -> Result<Map<String, Value>, WriteError> {
    let InputGltf {
        path: input_path,
        document,
        json,
        buffers,
    } = *input;
    let mut root = match json {
        Value::Object(m) => m.clone(),
        _ => return Err(input_err("/".into(), "not a JSON object".into())),
    };
    let in_accessors = take_array(&mut root, "accessors");
    let in_buffer_views = match serde_json::to_value(&document.buffer_views)? {
        Value::Array(views) => views,
        _ => Vec::new(),
    };
    for key in ["buffers", "bufferViews", "meshes"] {
        root.remove(key);
    }
    keep_skins(&mut root, &in_accessors, &in_buffer_views, buffers, out)?;
    keep_animations(&mut root, &in_accessors, &in_buffer_views, buffers, out);
    for key in ["extensionsUsed", "extensionsRequired"] {
        if let Some(Value::Array(list)) = root.get_mut(key) {
            list.retain(|v| v.as_str().is_some_and(|s| !DROPPED_EXTENSIONS.contains(&s)));
        }
    }
    if let Some(asset) = root.get_mut("asset").and_then(Value::as_object_mut) {
        asset.insert("generator".into(), "lodgen".into());
    }
    embed_images(&mut root, input_path, document, buffers, out)?;
    let quantize = out.opts.quantize;
    let warnings = &mut out.warnings;
    attach_chains(
        &mut root,
        document,
        lods,
        chains,
        chain_meshes,
        quantize,
        warnings,
    )?;
    Ok(root)
}

fn has_targets(chain: &PreparedChain) -> bool {
    chain.levels.iter().flatten().any(|p| !p.targets.is_empty())
}

/// `weights` animation channels follow the mesh to the node it moved to;
/// those whose node draws no morph targets are dropped with a warning (and
/// an animation left without a channel).
fn retarget_weight_channels(
    root: &mut Map<String, Value>,
    moved_to: &[(usize, usize)],
    morphed: &[usize],
    warnings: &mut Vec<Warning>,
) {
    let Some(Value::Array(animations)) = root.get_mut("animations") else {
        return;
    };
    for (a, animation) in animations.iter_mut().enumerate() {
        let Some(channels) = animation.get_mut("channels").and_then(Value::as_array_mut) else {
            continue;
        };
        channels.retain_mut(|c| {
            if c.pointer("/target/path").and_then(Value::as_str) != Some("weights") {
                return true;
            }
            let node = c
                .pointer("/target/node")
                .and_then(Value::as_u64)
                .unwrap_or(u64::MAX);
            let to = moved_to
                .iter()
                .find(|(from, _)| *from as u64 == node)
                .map_or(node, |&(_, to)| to as u64);
            if morphed.iter().any(|&m| m as u64 == to) {
                c["target"]["node"] = to.into();
                return true;
            }
            warnings.push(Warning::new(
                format!("animations[{a}]"),
                format!(
                    "a weights channel of node {node}, whose mesh has no morph targets, dropped"
                ),
            ));
            false
        });
    }
    animations.retain(|a| {
        a.get("channels")
            .and_then(Value::as_array)
            .is_some_and(|c| !c.is_empty())
    });
    if animations.is_empty() {
        root.remove("animations");
    }
}

/// Node extensions that point at mesh data (instancing accessors) or at the
/// input's own LOD chains no longer apply: they go, each named in a warning
/// (the input's own MSFT_lod chains are replaced, not lost).
fn drop_mesh_node_extensions(nodes: &mut [Value], warnings: &mut Vec<Warning>) {
    for (i, node) in nodes.iter_mut().enumerate() {
        // Node extensions that point at mesh data (instancing accessors) or
        // at the input's own LOD chains no longer apply.
        if let Some(Value::Object(ext)) = node.get_mut("extensions") {
            // (the input's own MSFT_lod chains are replaced, not lost)
            let lost = |k: &&String| DROPPED_EXTENSIONS.contains(&k.as_str()) && *k != "MSFT_lod";
            for k in ext.keys().filter(lost) {
                warnings.push(Warning::new(
                    format!("nodes[{i}]"),
                    format!("{k} dropped (it refers to the input's mesh data)"),
                ));
            }
            ext.retain(|k, _| !DROPPED_EXTENSIONS.contains(&k.as_str()));
            if ext.is_empty() {
                if let Some(obj) = node.as_object_mut() {
                    obj.remove("extensions");
                }
            }
        }
    }
}

/// Nodes: each node with a mesh gets that mesh's chain (with `quantize`, on
/// a new child node that carries the dequantization; a node with children
/// too, on a new child with no transform).
fn attach_chains(
    root: &mut Map<String, Value>,
    document: &gltf_json::Root,
    lods: &[LodMesh],
    chains: &[PreparedChain],
    chain_meshes: &[Vec<usize>],
    quantize: bool,
    warnings: &mut Vec<Warning>,
) -> Result<(), WriteError> {
    let mut chain_of = vec![usize::MAX; document.meshes.len()];
    for (c, lod) in lods.iter().enumerate() {
        if let Some(slot) = chain_of.get_mut(lod.source) {
            *slot = c;
        }
    }
    let mut nodes = match root.remove("nodes") {
        Some(Value::Array(n)) => n,
        _ => Vec::new(),
    };
    drop_mesh_node_extensions(&mut nodes, warnings);
    let original_count = nodes.len();
    // the node whose mesh moves to a new child (`quantize`, or children):
    // its morph weights (and their animation channels) go with the mesh
    let mut moved_to: Vec<(usize, usize)> = Vec::new();
    // the nodes that draw a mesh with morph targets, as written
    let mut morphed: Vec<usize> = Vec::new();
    for i in 0..original_count {
        let Some(mesh) = nodes[i].get("mesh").and_then(Value::as_u64) else {
            continue;
        };
        let Some(&c) = chain_of.get(mesh as usize).filter(|&&c| c != usize::MAX) else {
            // the reader left the mesh out (and said so): the node stays in
            // the tree without it and what needs it (a skin, morph weights)
            if let Some(obj) = nodes[i].as_object_mut() {
                for key in ["mesh", "skin", "weights"] {
                    obj.remove(key);
                }
            }
            continue;
        };
        let chain = &chains[c];
        debug_assert_eq!(chain.source, mesh as usize);
        let name = nodes[i]
            .get("name")
            .and_then(Value::as_str)
            .map_or_else(|| chain.name.clone(), String::from);
        // A node with children keeps them (and its transform) and gets its
        // chain on a new child: an MSFT_lod level replaces its node with its
        // whole subtree, so LOD nodes beside the node would draw the
        // children at level 0 only (a car's wheels gone at a distance).
        let has_children = nodes[i]
            .get("children")
            .and_then(Value::as_array)
            .is_some_and(|c| !c.is_empty());
        if quantize || has_children {
            // The dequantization (with `quantize`) lives on new child nodes.
            let (mut weights, mut skin) = (None, None);
            if let Some(obj) = nodes[i].as_object_mut() {
                obj.remove("mesh");
                skin = obj.remove("skin");
                weights = obj.remove("weights");
            }
            let mut transform = if quantize {
                dequant_transform(chain, true)
            } else {
                Map::new()
            };
            if let (false, Some(s)) = (quantize, skin) {
                transform.insert("skin".into(), s);
            }
            if let Some(w) = weights.filter(|_| quantize || has_targets(chain)) {
                transform.insert("weights".into(), w);
            }
            let mut node = transform.clone();
            node.insert("name".into(), format!("{name}_LOD0").into());
            nodes.push(Value::Object(node));
            let first = nodes.len() - 1;
            moved_to.push((i, first));
            if has_targets(chain) {
                morphed.push(first);
            }
            match nodes[i].get_mut("children") {
                Some(Value::Array(children)) => children.push(first.into()),
                _ => nodes[i]["children"] = json!([first]),
            }
            add_lod_nodes(
                &mut nodes,
                first,
                &name,
                &chain_meshes[c],
                &chain.coverages,
                &transform,
            );
        } else {
            if has_targets(chain) {
                morphed.push(i);
            } else if let Some(obj) = nodes[i].as_object_mut() {
                obj.remove("weights");
            }
            let template = nodes[i].as_object().cloned().unwrap_or_default();
            add_lod_nodes(
                &mut nodes,
                i,
                &name,
                &chain_meshes[c],
                &chain.coverages,
                &template,
            );
        }
    }
    retarget_weight_channels(root, &moved_to, &morphed, warnings);
    if !nodes.is_empty() {
        root.insert("nodes".into(), nodes.into());
    }
    Ok(())
}
