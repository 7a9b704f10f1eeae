//! Buffers, views and accessors: the [`Builder`] collects every level's
//! vertex and index data into per-level segments (segment 0: non-LOD data),
//! one buffer view per attribute (meshopt-compressed when asked) and the
//! accessors and meshes that point at them.

use serde_json::{json, Map, Value};

use super::codec::{
    encode_attribute, f32_bytes, min_max, other_attributes, BYTE, FLOAT, I16_ONE, SHORT,
    UNSIGNED_INT, UNSIGNED_SHORT,
};
use super::error::WriteError;
use super::options::{Compression, WriteOptions};
use super::prepare::{Prepared, PreparedChain};

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// Segment 0 holds non-LOD data; segment `1 + k` holds level `k`.
pub(super) const SHARED: usize = 0;

pub(super) struct View {
    pub(super) segment: usize,
    pub(super) offset: usize,
    pub(super) length: usize,
    pub(super) stride: Option<usize>,
    pub(super) target: Option<u32>,
    pub(super) meshopt: Option<MeshoptView>,
}

pub(super) struct MeshoptView {
    /// Offset and length of the uncompressed data in the fallback buffer.
    pub(super) fallback_offset: usize,
    pub(super) uncompressed_length: usize,
    pub(super) stride: usize,
    pub(super) count: usize,
    pub(super) mode: &'static str,
}

pub(super) enum Payload<'a> {
    /// Vertex attribute elements of `stride` bytes each.
    Attribute { bytes: Vec<u8>, stride: usize },
    /// Vertex attribute elements of `stride` bytes each, as `f32`s (written
    /// straight into the segment, little-endian).
    Floats { values: &'a [f32], stride: usize },
    /// A triangle list.
    Indices { indices: &'a [u32], wide: bool },
    /// Opaque bytes (images).
    Raw(Vec<u8>),
}

pub(super) struct Builder {
    pub(super) opts: WriteOptions,
    pub(super) segments: Vec<Vec<u8>>,
    pub(super) fallback_len: Vec<usize>,
    pub(super) views: Vec<View>,
    pub(super) accessors: Vec<Value>,
    pub(super) meshes: Vec<Value>,
    /// What of the input is not carried into the output, in words.
    pub(super) warnings: Vec<crate::scene::Warning>,
    /// Per material, the range its TEXCOORD_0 is quantized over
    /// (`uvrange`; empty: none).
    pub(super) uv_ranges: Vec<Option<lodgen_pm::stream::Range>>,
    /// Whether some material got `KHR_texture_transform`.
    pub(super) texture_transform: bool,
    /// The input's skins are dropped (`--quantize`): the levels' JOINTS_n
    /// and WEIGHTS_n are not written either.
    pub(super) drop_skinning: bool,
}

pub(super) fn align4(v: &mut Vec<u8>) {
    while v.len() % 4 != 0 {
        v.push(0);
    }
}

/// An attribute view's bytes (meshopt-encoded when `compress`), stride,
/// target and compression record.
type ViewBytes = (Vec<u8>, Option<usize>, Option<u32>, Option<MeshoptView>);

fn attribute(bytes: Vec<u8>, stride: usize, compress: bool) -> Result<ViewBytes, WriteError> {
    debug_assert!(stride % 4 == 0 && bytes.len() % stride == 0);
    let count = bytes.len() / stride;
    Ok(if compress {
        let encoded = encode_attribute(&bytes, stride)?;
        let m = MeshoptView {
            fallback_offset: 0,
            uncompressed_length: bytes.len(),
            stride,
            count,
            mode: "ATTRIBUTES",
        };
        (encoded, Some(stride), Some(ARRAY_BUFFER), Some(m))
    } else {
        (bytes, Some(stride), Some(ARRAY_BUFFER), None)
    })
}

/// `indices` appended to `out` as little-endian `u32`, or `u16` unless `wide`.
fn append_indices(out: &mut Vec<u8>, indices: &[u32], wide: bool) {
    if wide {
        out.reserve(indices.len() * 4);
        for &i in indices {
            out.extend_from_slice(&i.to_le_bytes());
        }
    } else {
        out.reserve(indices.len() * 2);
        for &i in indices {
            debug_assert!(i < 65535);
            out.extend_from_slice(&(i as u16).to_le_bytes());
        }
    }
}

impl Builder {
    pub(super) fn new(level_count: usize, opts: &WriteOptions) -> Self {
        Builder {
            opts: *opts,
            segments: vec![Vec::new(); 1 + level_count],
            fallback_len: vec![0; 1 + level_count],
            views: Vec::new(),
            accessors: Vec::new(),
            meshes: Vec::new(),
            warnings: Vec::new(),
            uv_ranges: Vec::new(),
            texture_transform: false,
            drop_skinning: false,
        }
    }

    pub(super) fn compress(&self) -> bool {
        self.opts.compression == Compression::Meshopt
    }

    /// Appends a buffer view; returns its index and the bytes it occupies.
    pub(super) fn view(
        &mut self,
        segment: usize,
        payload: Payload<'_>,
    ) -> Result<(usize, usize), WriteError> {
        let compress = self.compress() && segment != SHARED;
        // uncompressed floats and indices go straight into the segment
        let payload = match payload {
            Payload::Floats { values, stride } if !compress => {
                let data = &mut self.segments[segment];
                align4(data);
                let offset = data.len();
                data.reserve(values.len() * 4);
                for v in values {
                    data.extend_from_slice(&v.to_le_bytes());
                }
                return Ok(self.push_view(segment, offset, Some(stride), Some(ARRAY_BUFFER)));
            }
            Payload::Indices { indices, wide } if !compress => {
                let data = &mut self.segments[segment];
                align4(data);
                let offset = data.len();
                append_indices(data, indices, wide);
                return Ok(self.push_view(segment, offset, None, Some(ELEMENT_ARRAY_BUFFER)));
            }
            p => p,
        };
        let (bytes, stride, target, meshopt) = match payload {
            Payload::Raw(bytes) => (bytes, None, None, None),
            Payload::Attribute { bytes, stride } => attribute(bytes, stride, compress)?,
            Payload::Floats { values, stride } => {
                attribute(f32_bytes(values.iter()), stride, compress)?
            }
            Payload::Indices { indices, wide } => {
                let stride = if wide { 4 } else { 2 };
                if compress {
                    let vertex_count = indices.iter().max().map_or(0, |&m| m as usize + 1);
                    let encoded = meshopt::encode_index_buffer(indices, vertex_count)
                        .map_err(|e| WriteError::Compress(e.to_string()))?;
                    let m = MeshoptView {
                        fallback_offset: 0,
                        uncompressed_length: indices.len() * stride,
                        stride,
                        count: indices.len(),
                        mode: "TRIANGLES",
                    };
                    (encoded, None, Some(ELEMENT_ARRAY_BUFFER), Some(m))
                } else {
                    let mut bytes = Vec::new();
                    append_indices(&mut bytes, indices, wide);
                    (bytes, None, Some(ELEMENT_ARRAY_BUFFER), None)
                }
            }
        };
        let data = &mut self.segments[segment];
        align4(data);
        let offset = data.len();
        data.extend_from_slice(&bytes);
        let meshopt = meshopt.map(|mut m| {
            let fallback = &mut self.fallback_len[segment];
            m.fallback_offset = *fallback;
            *fallback += m.uncompressed_length.div_ceil(4) * 4;
            m
        });
        self.views.push(View {
            segment,
            offset,
            length: bytes.len(),
            stride,
            target,
            meshopt,
        });
        Ok((self.views.len() - 1, bytes.len()))
    }

    /// A view of the bytes of `segment` from `offset` to its end (written
    /// there already, uncompressed); its index and length.
    fn push_view(
        &mut self,
        segment: usize,
        offset: usize,
        stride: Option<usize>,
        target: Option<u32>,
    ) -> (usize, usize) {
        let length = self.segments[segment].len() - offset;
        self.views.push(View {
            segment,
            offset,
            length,
            stride,
            target,
            meshopt: None,
        });
        (self.views.len() - 1, length)
    }

    pub(super) fn accessor(&mut self, value: Value) -> usize {
        self.accessors.push(value);
        self.accessors.len() - 1
    }

    /// Adds one glTF mesh per level; returns their indices and each level's
    /// byte count.
    pub(super) fn add_chain(
        &mut self,
        chain: &PreparedChain,
    ) -> Result<(Vec<usize>, Vec<u64>), WriteError> {
        let mut meshes = Vec::with_capacity(chain.levels.len());
        let mut level_bytes = Vec::with_capacity(chain.levels.len());
        for (k, level) in chain.levels.iter().enumerate() {
            let segment = 1 + k;
            let mut bytes = 0usize;
            let mut primitives = Vec::with_capacity(level.len());
            for p in level {
                let (value, b) = self.add_primitive(segment, p, chain.dequant)?;
                bytes += b;
                primitives.push(value);
            }
            let mut mesh = chain.carried.clone();
            mesh.insert("name".into(), format!("{}_LOD{k}", chain.name).into());
            mesh.insert("primitives".into(), primitives.into());
            self.meshes.push(Value::Object(mesh));
            meshes.push(self.meshes.len() - 1);
            level_bytes.push(bytes as u64);
        }
        Ok((meshes, level_bytes))
    }

    fn add_primitive(
        &mut self,
        segment: usize,
        p: &Prepared,
        dequant: ([f64; 3], f64),
    ) -> Result<(Value, usize), WriteError> {
        let count = p.positions.len();
        let mut total = 0;
        let mut attributes = Map::new();

        let (position, b) = self.add_position(segment, p, dequant)?;
        total += b;
        attributes.insert("POSITION".into(), self.accessor(position).into());

        let (normal, b) = self.add_normal(segment, p)?;
        total += b;
        attributes.insert("NORMAL".into(), self.accessor(normal).into());

        if let Some(uv) = &p.texcoords {
            let (accessor, b) = self.add_texcoord0(segment, uv, count, p.material)?;
            total += b;
            attributes.insert("TEXCOORD_0".into(), self.accessor(accessor).into());
        }

        // TANGENT, TEXCOORD_1.., COLOR_n, WEIGHTS_n, JOINTS_n: floats and
        // u16 joints, or with `quantize` the compact formats the core spec
        // and KHR_mesh_quantization allow (module docs).
        for a in other_attributes(p, self.opts.quantize) {
            if self.drop_skinning
                && (a.name.starts_with("JOINTS_") || a.name.starts_with("WEIGHTS_"))
            {
                continue;
            }
            let (view, b) = self.view(
                segment,
                Payload::Attribute {
                    bytes: a.bytes,
                    stride: a.stride,
                },
            )?;
            total += b;
            let mut acc = json!({"bufferView": view, "componentType": a.component,
                                 "count": count, "type": a.kind});
            if a.normalized {
                acc["normalized"] = true.into();
            }
            attributes.insert(a.name, self.accessor(acc).into());
        }

        // Indices: u16 when every index fits below the primitive-restart value.
        let wide = count > 65535;
        let (view, b) = self.view(
            segment,
            Payload::Indices {
                indices: &p.indices,
                wide,
            },
        )?;
        total += b;
        let indices = self.accessor(json!({
            "bufferView": view,
            "componentType": if wide { UNSIGNED_INT } else { UNSIGNED_SHORT },
            "count": p.indices.len(),
            "type": "SCALAR",
        }));
        let mut prim = json!({"attributes": attributes, "indices": indices, "mode": 4});
        if let Some(m) = p.material {
            prim["material"] = m.into();
        }
        if !p.targets.is_empty() {
            let (targets, b) = self.add_targets(segment, p, dequant.1)?;
            total += b;
            prim["targets"] = targets;
        }
        Ok((prim, total))
    }

    /// The morph targets: float VEC3 displacements (POSITION with min/max;
    /// with `quantize` in the dequantization cube's units, `1 / half`).
    fn add_targets(
        &mut self,
        segment: usize,
        p: &Prepared,
        half: f64,
    ) -> Result<(Value, usize), WriteError> {
        let scale = if self.opts.quantize {
            (1.0 / half.max(f64::MIN_POSITIVE)) as f32
        } else {
            1.0
        };
        let mut total = 0;
        let mut targets = Vec::with_capacity(p.targets.len());
        for t in &p.targets {
            let mut target = Map::new();
            for (name, d) in t.channels() {
                let scaled: Vec<[f32; 3]> = match name {
                    "POSITION" => d.iter().map(|v| v.map(|c| c * scale)).collect(),
                    _ => d.clone(),
                };
                let bytes = scaled
                    .iter()
                    .flatten()
                    .flat_map(|c| c.to_le_bytes())
                    .collect();
                let (view, b) = self.view(segment, Payload::Attribute { bytes, stride: 12 })?;
                total += b;
                let mut acc = json!({"bufferView": view, "componentType": FLOAT,
                                     "count": scaled.len(), "type": "VEC3"});
                if name == "POSITION" {
                    let mut min = [f32::INFINITY; 3];
                    let mut max = [f32::NEG_INFINITY; 3];
                    for v in &scaled {
                        for k in 0..3 {
                            min[k] = min[k].min(v[k]);
                            max[k] = max[k].max(v[k]);
                        }
                    }
                    acc["min"] = json!(min);
                    acc["max"] = json!(max);
                }
                target.insert(name.into(), self.accessor(acc).into());
            }
            targets.push(Value::Object(target));
        }
        Ok((targets.into(), total))
    }

    /// POSITION: `i16` normalized in the chain's dequantization cube with
    /// `quantize`, else floats. Returns the accessor and its bytes.
    fn add_position(
        &mut self,
        segment: usize,
        p: &Prepared,
        (center, half): ([f64; 3], f64),
    ) -> Result<(Value, usize), WriteError> {
        let count = p.positions.len();
        Ok(if self.opts.quantize {
            let q: Vec<[i16; 3]> = p
                .positions
                .iter()
                .map(|v| {
                    [0, 1, 2].map(|a| {
                        ((v[a] as f64 - center[a]) / half * I16_ONE)
                            .round()
                            .clamp(-I16_ONE, I16_ONE) as i16
                    })
                })
                .collect();
            let (lo, hi) = min_max(q.iter().map(|v| v.map(f64::from)));
            let mut bytes = Vec::with_capacity(count * 8);
            for v in &q {
                for c in v.iter().chain(&[0i16]) {
                    bytes.extend_from_slice(&c.to_le_bytes());
                }
            }
            let (view, b) = self.view(segment, Payload::Attribute { bytes, stride: 8 })?;
            let accessor = json!({"bufferView": view, "componentType": SHORT, "normalized": true,
                                  "count": count, "type": "VEC3", "min": lo, "max": hi});
            (accessor, b)
        } else {
            let (lo, hi) = min_max(p.positions.iter().map(|v| v.map(f64::from)));
            let (view, b) = self.view(
                segment,
                Payload::Floats {
                    values: p.positions.as_flattened(),
                    stride: 12,
                },
            )?;
            let accessor = json!({"bufferView": view, "componentType": FLOAT, "count": count,
                                  "type": "VEC3", "min": lo, "max": hi});
            (accessor, b)
        })
    }

    /// NORMAL: `i8` normalized with `quantize`, else floats.
    fn add_normal(&mut self, segment: usize, p: &Prepared) -> Result<(Value, usize), WriteError> {
        let count = p.positions.len();
        Ok(if self.opts.quantize {
            let mut bytes = Vec::with_capacity(count * 4);
            for n in &p.normals {
                for c in n {
                    bytes.push(((*c as f64 * 127.0).round().clamp(-127.0, 127.0) as i8) as u8);
                }
                bytes.push(0);
            }
            let (view, b) = self.view(segment, Payload::Attribute { bytes, stride: 4 })?;
            let accessor = json!({"bufferView": view, "componentType": BYTE, "normalized": true,
                                  "count": count, "type": "VEC3"});
            (accessor, b)
        } else {
            let (view, b) = self.view(
                segment,
                Payload::Floats {
                    values: p.normals.as_flattened(),
                    stride: 12,
                },
            )?;
            let accessor =
                json!({"bufferView": view, "componentType": FLOAT, "count": count, "type": "VEC3"});
            (accessor, b)
        })
    }

    /// TEXCOORD_0: `u16` normalized with `quantize` when within [0, 1] or
    /// over the material's range (`uvrange`), else floats.
    fn add_texcoord0(
        &mut self,
        segment: usize,
        uv: &[[f32; 2]],
        count: usize,
        material: Option<usize>,
    ) -> Result<(Value, usize), WriteError> {
        let unit = uv.iter().flatten().all(|c| (0.0..=1.0).contains(c));
        let range = material.and_then(|m| self.uv_ranges.get(m).copied().flatten());
        Ok(if let Some(r) = range {
            let bytes = super::uvrange::encode(uv, r);
            let (view, b) = self.view(segment, Payload::Attribute { bytes, stride: 4 })?;
            let accessor = json!({"bufferView": view, "componentType": UNSIGNED_SHORT,
                                  "normalized": true, "count": count, "type": "VEC2"});
            (accessor, b)
        } else if self.opts.quantize && unit {
            let mut bytes = Vec::with_capacity(count * 4);
            for c in uv.iter().flatten() {
                let q = (*c as f64 * 65535.0).round().clamp(0.0, 65535.0) as u16;
                bytes.extend_from_slice(&q.to_le_bytes());
            }
            let (view, b) = self.view(segment, Payload::Attribute { bytes, stride: 4 })?;
            let accessor = json!({"bufferView": view, "componentType": UNSIGNED_SHORT,
                                  "normalized": true, "count": count, "type": "VEC2"});
            (accessor, b)
        } else {
            let (view, b) = self.view(
                segment,
                Payload::Attribute {
                    bytes: f32_bytes(uv.iter().flatten()),
                    stride: 8,
                },
            )?;
            let accessor =
                json!({"bufferView": view, "componentType": FLOAT, "count": count, "type": "VEC2"});
            (accessor, b)
        })
    }
}
