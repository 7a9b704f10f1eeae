//! What is carried over from an input glTF document: accessors copied
//! tightly packed into the non-LOD range (skins' inverse bind matrices,
//! animation keyframes), image bytes (buffer views, external files) with
//! their MIME type, and the errors that name the input's JSON path.

use std::path::Path;

use serde_json::{Map, Value};

use super::builder::{Builder, Payload, SHARED};
use super::error::WriteError;
use super::prepare::PreparedChain;
use crate::io::decode_base64;
use crate::scene::Warning;

/// An error in the input document at JSON path `path`.
pub(super) fn input_err(path: String, reason: String) -> WriteError {
    WriteError::InputDocument { path, reason }
}

pub(super) fn take_array(root: &mut Map<String, Value>, key: &str) -> Vec<Value> {
    match root.remove(key) {
        Some(Value::Array(a)) => a,
        _ => Vec::new(),
    }
}

/// Copies input accessor `a` (dense, with a buffer view) tightly packed into
/// the non-LOD range; returns the new accessor index, `None` when it cannot be
/// copied that way.
pub(super) fn copy_accessor(
    a: usize,
    accessors: &[Value],
    views: &[Value],
    buffers: &[Vec<u8>],
    out: &mut Builder,
) -> Option<usize> {
    let acc = accessors.get(a)?;
    if acc.get("sparse").is_some() {
        return None;
    }
    let size = match acc.get("componentType")?.as_u64()? {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        5125 | 5126 => 4,
        _ => return None,
    };
    let comps = match acc.get("type")?.as_str()? {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" => 4,
        // Matrices of 1- and 2-byte components have padded columns.
        "MAT4" if size == 4 => 16,
        _ => return None,
    };
    let elem = size * comps;
    let view = views.get(acc.get("bufferView")?.as_u64()? as usize)?;
    let data = buffers.get(view.get("buffer")?.as_u64()? as usize)?;
    let stride = view
        .get("byteStride")
        .and_then(Value::as_u64)
        .map_or(elem, |s| s as usize);
    let start = view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
    let start =
        start.checked_add(acc.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize)?;
    let count = acc.get("count")?.as_u64()? as usize;
    let mut bytes = Vec::with_capacity(count.checked_mul(elem)?);
    for i in 0..count {
        let at = start.checked_add(i.checked_mul(stride)?)?;
        bytes.extend_from_slice(data.get(at..at.checked_add(elem)?)?);
    }
    let (new_view, _) = out.view(SHARED, Payload::Raw(bytes)).ok()?;
    let mut copy = acc.clone();
    let obj = copy.as_object_mut()?;
    obj.remove("byteOffset");
    obj.insert("bufferView".into(), new_view.into());
    Some(out.accessor(copy))
}

pub(super) fn sniff_mime(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some("image/png")
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        Some("image/jpeg")
    } else if bytes.len() >= 12 && &bytes[0..4] == b"RIFF" && &bytes[8..12] == b"WEBP" {
        Some("image/webp")
    } else if bytes.starts_with(b"\xabKTX 20\xbb\r\n\x1a\n") {
        Some("image/ktx2")
    } else {
        None
    }
}

pub(super) fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Skins are kept (their inverse bind matrices copied into the non-LOD
/// range) without quantization: every level carries JOINTS / WEIGHTS.
/// Quantized positions put the dequantization into node transforms,
/// which skinning ignores, so quantized output drops skins.
pub(super) fn keep_skins(
    root: &mut Map<String, Value>,
    in_accessors: &[Value],
    in_buffer_views: &[Value],
    buffers: &[Vec<u8>],
    out: &mut Builder,
) -> Result<(), WriteError> {
    let mut skins = take_array(root, "skins");
    if out.opts.quantize && !skins.is_empty() {
        out.warnings.push(Warning::new(
            "skins",
            format!(
                "{} skin(s) dropped, with the levels' JOINTS_n / WEIGHTS_n: --quantize puts the \
                 dequantization in node transforms, which skinning ignores (write without \
                 --quantize to keep them)",
                skins.len()
            ),
        ));
        skins.clear();
    }
    for (k, skin) in skins.iter_mut().enumerate() {
        if let Some(a) = skin.get("inverseBindMatrices").and_then(Value::as_u64) {
            let copied = copy_accessor(a as usize, in_accessors, in_buffer_views, buffers, out)
                .ok_or_else(|| {
                    input_err(
                        format!("/skins/{k}/inverseBindMatrices"),
                        format!("accessor {a} cannot be copied (missing or sparse)"),
                    )
                })?;
            skin["inverseBindMatrices"] = copied.into();
        }
    }
    if !skins.is_empty() {
        root.insert("skins".into(), skins.into());
    }
    Ok(())
}

/// Whether an animation channel can be kept: it targets a node (node
/// indices are kept), or it is a `KHR_animation_pointer` into something
/// copied as it was (a node's transform, a material, a camera, a light),
/// not into mesh data, which is new.
fn channel_kept(c: &Value) -> bool {
    if c.pointer("/target/node").is_some() {
        return true;
    }
    let pointer = c.pointer("/target/extensions/KHR_animation_pointer/pointer");
    pointer.and_then(Value::as_str).is_some_and(|p| {
        let data = ["/meshes/", "/accessors/", "/bufferViews/", "/buffers/"];
        p.starts_with('/') && !data.iter().any(|d| p.starts_with(d)) && !p.ends_with("/weights")
    })
}

/// Animations are kept with their keyframe data copied into the non-LOD
/// range (`weights` channels are retargeted by `document`); channels
/// [`channel_kept`] refuses and animations whose data cannot be copied as a
/// plain dense accessor (sparse, missing) are dropped with a warning.
pub(super) fn keep_animations(
    root: &mut Map<String, Value>,
    in_accessors: &[Value],
    in_buffer_views: &[Value],
    buffers: &[Vec<u8>],
    out: &mut Builder,
) {
    let mut animations = take_array(root, "animations");
    let mut kept = Vec::with_capacity(animations.len());
    for (i, mut animation) in animations.drain(..).enumerate() {
        let at = format!("animations[{i}]");
        if let Some(Value::Array(channels)) = animation.get_mut("channels") {
            let before = channels.len();
            channels.retain(channel_kept);
            if channels.len() < before {
                out.warnings.push(Warning::new(
                    at.clone(),
                    format!(
                        "{} channel(s) dropped: no target node, nor a KHR_animation_pointer \
                         outside mesh data",
                        before - channels.len()
                    ),
                ));
            }
        }
        let has_channels = animation
            .get("channels")
            .and_then(Value::as_array)
            .is_some_and(|c| !c.is_empty());
        let copied = match animation.get_mut("samplers") {
            Some(Value::Array(samplers)) => samplers.iter_mut().all(|sampler| {
                ["input", "output"].iter().all(|key| {
                    let copied = sampler.get(*key).and_then(Value::as_u64).and_then(|a| {
                        copy_accessor(a as usize, in_accessors, in_buffer_views, buffers, out)
                    });
                    copied.map(|new| sampler[*key] = new.into()).is_some()
                })
            }),
            _ => false,
        };
        if has_channels && copied {
            kept.push(animation);
        } else {
            out.warnings.push(Warning::new(
                at,
                "dropped: no channel left, or a sampler's data cannot be copied (sparse or missing)",
            ));
        }
    }
    if !kept.is_empty() {
        root.insert("animations".into(), kept.into());
    }
}

/// Every level's mesh of a chain carries the input mesh's `weights`,
/// `extras` (with `targetNames`) and `extensions`; primitive-level extras
/// and extensions cannot follow (a level's primitives are new) and are
/// named in a warning, as are `weights` that no longer match the targets.
pub(super) fn carry_mesh_properties(
    json: &Value,
    chains: &mut [PreparedChain],
    warnings: &mut Vec<Warning>,
) {
    for chain in chains {
        let Some(Value::Object(mesh)) = json.pointer(&format!("/meshes/{}", chain.source)) else {
            continue;
        };
        let mut mesh = mesh.clone();
        let (m, name) = (chain.source, &chain.name);
        let at = format!("meshes[{m}] (mesh `{name}`)");
        for key in ["weights", "extras", "extensions"] {
            if let Some(v) = mesh.remove(key) {
                chain.carried.insert(key.into(), v);
            }
        }
        let targets = chain.levels[0].first().map_or(0, |p| p.targets.len());
        let weights = chain
            .carried
            .get("weights")
            .and_then(Value::as_array)
            .map(Vec::len);
        if weights.is_some_and(|w| w != targets) {
            chain.carried.remove("weights");
            warnings.push(Warning::new(
                at.clone(),
                format!("weights dropped: {targets} morph target(s) were read"),
            ));
        }
        for (i, p) in mesh
            .get("primitives")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .enumerate()
        {
            let mut lost: Vec<&str> = Vec::new();
            if p.get("extras").is_some_and(|e| !e.is_null()) {
                lost.push("extras");
            }
            if let Some(Value::Object(ext)) = p.get("extensions") {
                lost.extend(ext.keys().map(String::as_str));
            }
            if !lost.is_empty() {
                warnings.push(Warning::new(
                    format!("meshes[{m}].primitives[{i}] (mesh `{name}`)"),
                    format!(
                        "{} not carried (a level's primitives are new)",
                        lost.join(", ")
                    ),
                ));
            }
        }
    }
}

/// Images: copies buffer-view images and embeds external files and base64
/// data URIs into the non-LOD range (other data URIs stay as they are).
pub(super) fn embed_images(
    root: &mut Map<String, Value>,
    input_path: &Path,
    document: &gltf_json::Root,
    buffers: &[Vec<u8>],
    out: &mut Builder,
) -> Result<(), WriteError> {
    let in_views = &document.buffer_views;
    if let Some(Value::Array(images)) = root.get_mut("images") {
        for (i, image) in images.iter_mut().enumerate() {
            let Some(obj) = image.as_object_mut() else {
                continue;
            };
            let at = format!("/images/{i}");
            let bytes = if let Some(v) = obj.get("bufferView").and_then(Value::as_u64) {
                let view = in_views.get(v as usize).ok_or_else(|| {
                    input_err(at.clone(), format!("bufferView {v} does not exist"))
                })?;
                let data = buffers.get(view.buffer.value()).ok_or_else(|| {
                    input_err(
                        at.clone(),
                        format!("buffer {} has no data", view.buffer.value()),
                    )
                })?;
                let start = view.byte_offset.map_or(0, |o| o.0);
                let end = start.saturating_add(view.byte_length.0);
                usize::try_from(start)
                    .ok()
                    .zip(usize::try_from(end).ok())
                    .and_then(|(start, end)| data.get(start..end))
                    .ok_or_else(|| input_err(at.clone(), "bufferView exceeds its buffer".into()))?
                    .to_vec()
            } else if let Some(uri) = obj.get("uri").and_then(Value::as_str) {
                if let Some(data) = uri.strip_prefix("data:") {
                    // base64 image data goes into a buffer view too (a GLB
                    // should hold no data URI); anything else stays as it is
                    match data
                        .split_once(";base64,")
                        .and_then(|(_, b)| decode_base64(b))
                        .filter(|bytes| sniff_mime(bytes).is_some())
                    {
                        Some(bytes) => bytes,
                        None => continue,
                    }
                } else {
                    let file = input_path
                        .parent()
                        .unwrap_or(Path::new(""))
                        .join(percent_decode(uri));
                    std::fs::read(&file).map_err(|e| {
                        input_err(at.clone(), format!("reading image {}: {e}", file.display()))
                    })?
                }
            } else {
                return Err(input_err(at, "image has neither uri nor bufferView".into()));
            };
            if !obj.contains_key("mimeType") {
                let mime = sniff_mime(&bytes).ok_or_else(|| {
                    input_err(
                        at.clone(),
                        "unknown image format (not PNG, JPEG, WebP or KTX2)".into(),
                    )
                })?;
                obj.insert("mimeType".into(), mime.into());
            }
            let (view, _) = out.view(SHARED, Payload::Raw(bytes))?;
            obj.remove("uri");
            obj.insert("bufferView".into(), view.into());
        }
    }
    Ok(())
}
