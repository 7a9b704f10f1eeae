//! `--quantize` texture coordinates that leave [0, 1] (glTF input):
//! TEXCOORD_0 as normalized `u16` over the values' range, the range given
//! back by `KHR_texture_transform` (`offset`, `scale`) on every texture of
//! the material that reads TEXCOORD_0. The range and the rounding are the
//! `LODGEN_progressive` stream's ([`Range::around`],
//! [`AttrEncoding::Unorm16Range`]), so a streamed UV equals the file's.
//!
//! Per material, over every primitive of every chain and level drawn with
//! it; only where the transform has somewhere to live and nothing to
//! compose with: the material has a texture reading TEXCOORD_0 and no
//! texture of it has a `KHR_texture_transform` already. Anything else keeps
//! `f32` (flat input's materials have no textures, primitives without a
//! material none either).

use lodgen_pm::stream::{AttrEncoding, Range};
use serde_json::{json, Map, Value};

use super::prepare::PreparedChain;

/// The extension's name.
pub(super) const EXTENSION: &str = "KHR_texture_transform";

/// The texture infos of a material: every object under a key ending in
/// `Texture` with an `index` (core and extension textures alike).
fn texture_infos(v: &Value, out: &mut Vec<Vec<String>>, path: &mut Vec<String>) {
    let Value::Object(m) = v else { return };
    for (k, x) in m {
        path.push(k.clone());
        if k.ends_with("Texture") && x.get("index").is_some() {
            out.push(path.clone());
        } else {
            texture_infos(x, out, path);
        }
        path.pop();
    }
}

fn at<'a>(v: &'a Value, path: &[String]) -> Option<&'a Value> {
    path.iter().try_fold(v, |v, k| v.get(k))
}

/// The texture infos of `material` reading TEXCOORD_0, or `None` when the
/// material cannot take a range (none reads TEXCOORD_0, or one of its
/// textures has a transform already).
fn uv0_infos(material: &Value) -> Option<Vec<Vec<String>>> {
    let mut all = Vec::new();
    texture_infos(material, &mut all, &mut Vec::new());
    let info = |p: &Vec<String>| at(material, p).cloned().unwrap_or(Value::Null);
    if all.iter().any(|p| {
        info(p)
            .pointer(&format!("/extensions/{EXTENSION}"))
            .is_some()
    }) {
        return None;
    }
    let uv0: Vec<_> = all
        .into_iter()
        .filter(|p| info(p).get("texCoord").and_then(Value::as_u64).unwrap_or(0) == 0)
        .collect();
    (!uv0.is_empty()).then_some(uv0)
}

/// Per material of `materials` (the output document's), the range its
/// TEXCOORD_0 is quantized over (`None`: as before, unorm16 within [0, 1]
/// or `f32`). Empty without `quantize`.
pub(super) fn material_ranges(
    materials: &[Value],
    chains: &[PreparedChain],
    quantize: bool,
) -> Vec<Option<Range>> {
    if !quantize {
        return Vec::new();
    }
    (0..materials.len())
        .map(|m| {
            uv0_infos(&materials[m])?;
            let uv = chains
                .iter()
                .flat_map(|c| c.levels.iter().flatten())
                .filter(|p| p.material == Some(m))
                .filter_map(|p| p.texcoords.as_ref())
                .flatten()
                .flatten()
                .copied();
            if uv.clone().all(|c| (0.0..=1.0).contains(&c)) {
                return None;
            }
            Range::around(uv)
        })
        .collect()
}

/// TEXCOORD_0 of a material with a range: normalized `u16` bytes.
pub(super) fn encode(uv: &[[f32; 2]], range: Range) -> Vec<u8> {
    let enc = AttrEncoding::Unorm16Range(range);
    uv.iter()
        .flatten()
        .flat_map(|&c| enc.quantize(c).to_le_bytes())
        .collect()
}

/// Adds `KHR_texture_transform` to every TEXCOORD_0 texture of each
/// material with a range; whether any was added.
pub(super) fn add_transforms(root: &mut Map<String, Value>, ranges: &[Option<Range>]) -> bool {
    let Some(Value::Array(materials)) = root.get_mut("materials") else {
        return false;
    };
    let mut any = false;
    for (material, range) in materials.iter_mut().zip(ranges) {
        let (Some(r), Some(infos)) = (range, uv0_infos(material)) else {
            continue;
        };
        for p in infos {
            let Some(Value::Object(info)) = p
                .iter()
                .try_fold(&mut *material, |v, k| v.get_mut(k.as_str()))
            else {
                continue;
            };
            let ext = info.entry("extensions").or_insert_with(|| json!({}));
            if let Value::Object(ext) = ext {
                ext.insert(
                    EXTENSION.into(),
                    json!({"offset": [r.offset, r.offset], "scale": [r.scale, r.scale]}),
                );
                any = true;
            }
        }
    }
    any
}
