//! Quantization and compression codecs: component types, normalized integer
//! encodings (`snorm8`, `unorm8`, `unorm16`, skin weights summing to 255),
//! the encoding of every attribute but POSITION / NORMAL / TEXCOORD_0, and
//! meshopt's vertex codec.

use super::error::WriteError;
use super::prepare::Prepared;

pub(super) const BYTE: u32 = 5120;
pub(super) const UNSIGNED_BYTE: u32 = 5121;
pub(super) const SHORT: u32 = 5122;
pub(super) const UNSIGNED_SHORT: u32 = 5123;
pub(super) const UNSIGNED_INT: u32 = 5125;
pub(super) const FLOAT: u32 = 5126;
/// Largest signed-normalized 16-bit value (`1.0`).
pub(super) const I16_ONE: f64 = 32767.0;

/// One vertex attribute, encoded.
pub(super) struct Encoded {
    pub(super) name: String,
    pub(super) bytes: Vec<u8>,
    pub(super) stride: usize,
    pub(super) component: u32,
    pub(super) normalized: bool,
    pub(super) kind: &'static str,
}

impl Encoded {
    fn new(
        name: &str,
        bytes: Vec<u8>,
        stride: usize,
        component: u32,
        normalized: bool,
        kind: &'static str,
    ) -> Encoded {
        Encoded {
            name: name.into(),
            bytes,
            stride,
            component,
            normalized,
            kind,
        }
    }
}

/// `x` in [-1, 1] as a signed normalized byte.
fn snorm8(x: f32) -> i8 {
    (f64::from(x) * 127.0).round().clamp(-127.0, 127.0) as i8
}

/// `x` in [0, 1] as an unsigned normalized byte.
fn unorm8(x: f32) -> u8 {
    (f64::from(x) * 255.0).round().clamp(0.0, 255.0) as u8
}

/// `x` in [0, 1] as an unsigned normalized short.
fn unorm16(x: f32) -> u16 {
    (f64::from(x) * 65535.0).round().clamp(0.0, 65535.0) as u16
}

/// One vertex's skin weights (all sets) as unsigned normalized bytes summing
/// to exactly 255, as glTF requires: rounded, the rounding error given to
/// the largest weight (all on the first when they sum to 0).
fn unorm8_weights(w: &[f32]) -> Vec<u8> {
    let clean: Vec<f64> = w
        .iter()
        .map(|&x| {
            if x.is_finite() {
                f64::from(x).max(0.0)
            } else {
                0.0
            }
        })
        .collect();
    let sum: f64 = clean.iter().sum();
    let mut q: Vec<i32> = if sum > 0.0 {
        clean
            .iter()
            .map(|x| (x / sum * 255.0).round() as i32)
            .collect()
    } else {
        (0..w.len()).map(|i| if i == 0 { 255 } else { 0 }).collect()
    };
    let total: i32 = q.iter().sum();
    let largest = (0..q.len()).max_by_key(|&i| (q[i], std::cmp::Reverse(i)));
    if let Some(i) = largest {
        q[i] = (q[i] + 255 - total).clamp(0, 255);
    }
    q.into_iter().map(|x| x as u8).collect()
}

/// Set 0 (when present) and sets 1, 2, … with their set numbers.
fn sets<'a, T>(
    first: &'a Option<Vec<T>>,
    extra: &'a [Vec<T>],
) -> impl Iterator<Item = (usize, &'a Vec<T>)> {
    first
        .iter()
        .map(|v| (0, v))
        .chain(extra.iter().enumerate().map(|(i, v)| (i + 1, v)))
}

/// Every attribute but POSITION, NORMAL and TEXCOORD_0, encoded (with
/// `quantize`, the compact formats of the module docs).
pub(super) fn other_attributes(p: &Prepared, quantize: bool) -> Vec<Encoded> {
    let q = quantize;
    let mut out = Vec::new();
    if let Some(t) = &p.tangents {
        out.push(if q {
            // signed normalized bytes; w = ±1 exactly
            let bytes = t.iter().flatten().map(|&c| snorm8(c) as u8).collect();
            Encoded::new("TANGENT", bytes, 4, BYTE, true, "VEC4")
        } else {
            Encoded::new(
                "TANGENT",
                f32_bytes(t.iter().flatten()),
                16,
                FLOAT,
                false,
                "VEC4",
            )
        });
    }
    for (i, uv) in p.extra_texcoords.iter().enumerate() {
        let name = format!("TEXCOORD_{}", i + 1);
        out.push(
            if q && uv.iter().flatten().all(|c| (0.0..=1.0).contains(c)) {
                let bytes = uv
                    .iter()
                    .flatten()
                    .flat_map(|&c| unorm16(c).to_le_bytes())
                    .collect();
                Encoded::new(&name, bytes, 4, UNSIGNED_SHORT, true, "VEC2")
            } else {
                Encoded::new(
                    &name,
                    f32_bytes(uv.iter().flatten()),
                    8,
                    FLOAT,
                    false,
                    "VEC2",
                )
            },
        );
    }
    for (i, c) in sets(&p.colors, &p.extra_colors) {
        let name = format!("COLOR_{i}");
        out.push(
            if q && c.iter().flatten().all(|x| (0.0..=1.0).contains(x)) {
                let bytes = c.iter().flatten().map(|&x| unorm8(x)).collect();
                Encoded::new(&name, bytes, 4, UNSIGNED_BYTE, true, "VEC4")
            } else {
                Encoded::new(
                    &name,
                    f32_bytes(c.iter().flatten()),
                    16,
                    FLOAT,
                    false,
                    "VEC4",
                )
            },
        );
    }
    let weights: Vec<(usize, &Vec<[f32; 4]>)> = sets(&p.weights, &p.extra_weights).collect();
    if q && !weights.is_empty() {
        // u8 per weight, each vertex's sets summing to exactly 255
        let mut bytes = vec![Vec::with_capacity(4 * p.positions.len()); weights.len()];
        for v in 0..p.positions.len() {
            let all: Vec<f32> = weights.iter().flat_map(|(_, w)| w[v]).collect();
            let quantized = unorm8_weights(&all);
            for (s, chunk) in quantized.chunks_exact(4).enumerate() {
                bytes[s].extend_from_slice(chunk);
            }
        }
        for ((i, _), b) in weights.iter().zip(bytes) {
            let name = format!("WEIGHTS_{i}");
            out.push(Encoded::new(&name, b, 4, UNSIGNED_BYTE, true, "VEC4"));
        }
    } else {
        for (i, w) in weights {
            let name = format!("WEIGHTS_{i}");
            out.push(Encoded::new(
                &name,
                f32_bytes(w.iter().flatten()),
                16,
                FLOAT,
                false,
                "VEC4",
            ));
        }
    }
    let joints: Vec<(usize, &Vec<[u16; 4]>)> = sets(&p.joints, &p.extra_joints).collect();
    let small = joints
        .iter()
        .all(|(_, j)| j.iter().flatten().all(|&x| x < 256));
    for (i, j) in joints {
        let name = format!("JOINTS_{i}");
        out.push(if q && small {
            let bytes = j.iter().flatten().map(|&x| x as u8).collect();
            Encoded::new(&name, bytes, 4, UNSIGNED_BYTE, false, "VEC4")
        } else {
            let bytes = j.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
            Encoded::new(&name, bytes, 8, UNSIGNED_SHORT, false, "VEC4")
        });
    }
    out
}

pub(super) fn encode_attribute(bytes: &[u8], stride: usize) -> Result<Vec<u8>, WriteError> {
    fn enc<const N: usize>(bytes: &[u8]) -> Result<Vec<u8>, WriteError> {
        let elements: Vec<[u8; N]> = bytes
            .chunks_exact(N)
            .map(|c| {
                let mut a = [0u8; N];
                a.copy_from_slice(c);
                a
            })
            .collect();
        // Version 0 (header 0xa0): the version EXT_meshopt_compression and
        // Babylon.js's decoder accept; meshoptimizer 1.x defaults to 1.
        meshopt::encode_vertex_buffer_level(&elements, 2, Some(0))
            .map_err(|e| WriteError::Compress(e.to_string()))
    }
    let encoded = match stride {
        4 => enc::<4>(bytes)?,
        8 => enc::<8>(bytes)?,
        12 => enc::<12>(bytes)?,
        16 => enc::<16>(bytes)?,
        _ => return Err(WriteError::Compress(format!("unsupported stride {stride}"))),
    };
    debug_assert_eq!(encoded.first(), Some(&0xa0));
    Ok(encoded)
}

pub(super) fn f32_bytes<'a>(values: impl Iterator<Item = &'a f32>) -> Vec<u8> {
    values.flat_map(|v| v.to_le_bytes()).collect()
}

pub(super) fn min_max(values: impl Iterator<Item = [f64; 3]>) -> (Vec<f64>, Vec<f64>) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in values {
        for a in 0..3 {
            lo[a] = lo[a].min(v[a]);
            hi[a] = hi[a].max(v[a]);
        }
    }
    (lo.to_vec(), hi.to_vec())
}
