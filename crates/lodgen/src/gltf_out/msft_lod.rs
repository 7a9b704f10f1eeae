//! The `MSFT_lod` chain in the node tree: the finest level's node gets
//! `MSFT_lod.ids` and `MSFT_screencoverage`, the coarser levels become
//! sibling nodes outside the scene, with the chain's dequantization transform
//! when quantizing (or the finest node's transform, skin and morph weights).

use serde_json::{json, Map, Value};

use super::prepare::PreparedChain;

/// The `MSFT_lod` node of level 0 plus its coarser siblings: sets
/// `ids`/`MSFT_screencoverage` on `nodes[first]` and appends the coarser
/// nodes (`template` gives their transform keys). Returns nothing: the coarser
/// nodes are appended to `nodes`.
pub(super) fn add_lod_nodes(
    nodes: &mut Vec<Value>,
    first: usize,
    name: &str,
    meshes: &[usize],
    coverages: &[f64],
    template: &Map<String, Value>,
) {
    let mut ids = Vec::with_capacity(meshes.len().saturating_sub(1));
    for (k, &mesh) in meshes.iter().enumerate().skip(1) {
        let mut node = Map::new();
        for key in [
            "matrix",
            "translation",
            "rotation",
            "scale",
            "skin",
            "weights",
        ] {
            if let Some(v) = template.get(key) {
                node.insert(key.into(), v.clone());
            }
        }
        node.insert("name".into(), format!("{name}_LOD{k}").into());
        node.insert("mesh".into(), mesh.into());
        nodes.push(Value::Object(node));
        ids.push(nodes.len() - 1);
    }
    let node = &mut nodes[first];
    node["mesh"] = meshes[0].into();
    if ids.is_empty() {
        return;
    }
    let extensions = node
        .as_object_mut()
        .map(|o| o.entry("extensions").or_insert_with(|| json!({})));
    if let Some(ext) = extensions {
        if !ext.is_object() {
            *ext = json!({});
        }
        ext["MSFT_lod"] = json!({ "ids": ids });
    }
    let coverage = Value::from(coverages.to_vec());
    match node.get_mut("extras") {
        Some(Value::Object(extras)) => {
            extras.insert("MSFT_screencoverage".into(), coverage);
        }
        _ => node["extras"] = json!({ "MSFT_screencoverage": coverage }),
    }
}

/// `transform` (a node's) moved by `offset` ([`crate::scene::Origin::Moved`]): its
/// translation plus `offset`, in `f64` (unchanged for a zero offset).
pub(super) fn moved(mut transform: Map<String, Value>, offset: [f64; 3]) -> Map<String, Value> {
    if offset == [0.0; 3] {
        return transform;
    }
    let t = transform.get("translation").and_then(Value::as_array);
    let at = |k: usize| {
        t.and_then(|t| t.get(k))
            .and_then(Value::as_f64)
            .unwrap_or(0.0)
    };
    let moved: [f64; 3] = std::array::from_fn(|k| at(k) + offset[k]);
    transform.insert("translation".into(), json!(moved));
    transform
}

pub(super) fn dequant_transform(chain: &PreparedChain, quantize: bool) -> Map<String, Value> {
    let mut m = Map::new();
    if quantize {
        let (c, s) = chain.dequant;
        m.insert("translation".into(), json!(c));
        m.insert("scale".into(), json!([s, s, s]));
    }
    m
}
