//! glTF documents built in code: [`Doc`] appends buffer views and
//! accessors over one binary buffer and writes the document as `.gltf`
//! (buffer as a `data:` URI) or `.glb`; [`glb_bytes`] / [`glb_json`] pack and
//! unpack a GLB.

use std::path::Path;

use serde_json::{json, Value};

/// Standard base64 with padding (for `data:` URIs).
pub fn base64(bytes: &[u8]) -> String {
    lodgen::io::encode_base64(bytes)
}

/// Little-endian bytes of `f32`s.
pub fn f32_bytes(v: impl IntoIterator<Item = f32>) -> Vec<u8> {
    v.into_iter().flat_map(f32::to_le_bytes).collect()
}

/// A GLB container of `doc` (its `buffers[0]` is the BIN chunk) and `bin`.
pub fn glb_bytes(doc: &Value, bin: &[u8]) -> Vec<u8> {
    lodgen::progressive::write_glb(doc, bin).unwrap()
}

/// The JSON chunk of a GLB file.
pub fn glb_json(path: &Path) -> Value {
    let bytes = std::fs::read(path).unwrap();
    assert!(bytes.starts_with(b"glTF"), "{}: not a GLB", path.display());
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

/// A glTF document under construction: the JSON and its one binary buffer.
pub struct Doc {
    /// The root object (`buffers` is filled in by [`Doc::glb`] / [`Doc::gltf`]).
    pub json: Value,
    /// The data of `buffers[0]`.
    pub bin: Vec<u8>,
}

impl Default for Doc {
    fn default() -> Self {
        Self::new()
    }
}

impl Doc {
    /// An empty document (`asset` only).
    pub fn new() -> Self {
        Doc {
            json: json!({"asset": {"version": "2.0"}}),
            bin: Vec::new(),
        }
    }

    /// Appends `value` to the top-level array `key`; its index.
    pub fn push(&mut self, key: &str, value: Value) -> usize {
        let list = self.json[key].as_array_mut();
        match list {
            Some(list) => {
                list.push(value);
                list.len() - 1
            }
            None => {
                self.json[key] = json!([value]);
                0
            }
        }
    }

    /// `bytes` as a new buffer view (4-byte aligned in the buffer); its index.
    pub fn view(&mut self, bytes: &[u8]) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let at = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.push(
            "bufferViews",
            json!({"buffer": 0, "byteOffset": at, "byteLength": bytes.len()}),
        )
    }

    /// An accessor of `count` elements of `ty` (`SCALAR`, `VEC3`, …) and
    /// `component` (5126 float, 5125 u32, …) over a new view of `bytes`;
    /// `extra`'s keys (min, max, normalized) are added. Its index.
    pub fn accessor(
        &mut self,
        bytes: &[u8],
        component: u32,
        count: usize,
        ty: &str,
        extra: Value,
    ) -> usize {
        let view = self.view(bytes);
        let mut acc =
            json!({"bufferView": view, "componentType": component, "count": count, "type": ty});
        if let Value::Object(extra) = extra {
            for (k, v) in extra {
                acc[k] = v;
            }
        }
        self.push("accessors", acc)
    }

    /// A float accessor of `N`-component elements (1: SCALAR, 2–4: VECn,
    /// 16: MAT4), with `min` / `max` when `bounds`.
    pub fn floats<const N: usize>(&mut self, data: &[[f32; N]], bounds: bool) -> usize {
        let ty = match N {
            1 => "SCALAR",
            2 => "VEC2",
            3 => "VEC3",
            4 => "VEC4",
            16 => "MAT4",
            _ => panic!("{N} components"),
        };
        let extra = if bounds {
            let lo: Vec<f32> = (0..N)
                .map(|k| data.iter().map(|v| v[k]).fold(f32::INFINITY, f32::min))
                .collect();
            let hi: Vec<f32> = (0..N)
                .map(|k| data.iter().map(|v| v[k]).fold(f32::NEG_INFINITY, f32::max))
                .collect();
            json!({"min": lo, "max": hi})
        } else {
            json!({})
        };
        let bytes = f32_bytes(data.iter().flatten().copied());
        self.accessor(&bytes, 5126, data.len(), ty, extra)
    }

    /// A SCALAR float accessor with bounds (animation keyframe times).
    pub fn times(&mut self, t: &[f32]) -> usize {
        let v: Vec<[f32; 1]> = t.iter().map(|&x| [x]).collect();
        self.floats(&v, true)
    }

    /// Triangle indices: `u16` when every index fits, else `u32`.
    pub fn indices(&mut self, triangles: &[[u32; 3]]) -> usize {
        let flat = triangles.iter().flatten().copied();
        let count = triangles.len() * 3;
        if triangles.iter().flatten().all(|&i| i < 65535) {
            let bytes: Vec<u8> = flat.flat_map(|i| (i as u16).to_le_bytes()).collect();
            self.accessor(&bytes, 5123, count, "SCALAR", json!({}))
        } else {
            let bytes: Vec<u8> = flat.flat_map(u32::to_le_bytes).collect();
            self.accessor(&bytes, 5125, count, "SCALAR", json!({}))
        }
    }

    /// A `u8` VEC4 accessor (JOINTS_n).
    pub fn joints(&mut self, data: &[[u8; 4]]) -> usize {
        let bytes: Vec<u8> = data.iter().flatten().copied().collect();
        self.accessor(&bytes, 5121, data.len(), "VEC4", json!({}))
    }

    fn with_buffer(&self, uri: Option<String>) -> Value {
        let mut json = self.json.clone();
        if !self.bin.is_empty() {
            let mut buffer = json!({"byteLength": self.bin.len()});
            if let Some(uri) = uri {
                buffer["uri"] = uri.into();
            }
            json["buffers"] = json!([buffer]);
        }
        json
    }

    /// The document as a GLB.
    pub fn glb(&self) -> Vec<u8> {
        glb_bytes(&self.with_buffer(None), &self.bin)
    }

    /// The document as `.gltf` JSON with the buffer as a `data:` URI.
    pub fn gltf(&self) -> Vec<u8> {
        let uri = format!("data:application/octet-stream;base64,{}", base64(&self.bin));
        serde_json::to_vec(&self.with_buffer(Some(uri))).unwrap()
    }
}

/// A 2×2 RGB PNG.
pub const PNG_2X2: [u8; 75] = [
    137, 80, 78, 71, 13, 10, 26, 10, 0, 0, 0, 13, 73, 72, 68, 82, 0, 0, 0, 2, 0, 0, 0, 2, 8, 2, 0,
    0, 0, 253, 212, 154, 115, 0, 0, 0, 18, 73, 68, 65, 84, 120, 156, 99, 248, 207, 192, 192, 0,
    194, 12, 255, 65, 0, 0, 38, 232, 6, 250, 18, 64, 95, 204, 0, 0, 0, 0, 73, 69, 78, 68, 174, 66,
    96, 130,
];
