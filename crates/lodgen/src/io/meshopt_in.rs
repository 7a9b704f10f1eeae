//! `EXT_meshopt_compression` on input: buffer views whose data is
//! compressed by meshoptimizer's codecs (what `gltfpack -cc` and
//! `lodgen --compress meshopt` write) are decoded once, before any accessor
//! is read, into buffers of their own; the views are pointed at them, so the
//! rest of the reader (and the writer copying skins or images) sees plain
//! data. Fallback buffers (`"fallback": true`, often without data) are
//! never read.
//!
//! Every length is checked before meshoptimizer's decoders run (they are
//! safe on untrusted bytes given correct sizes); a bad view is an error
//! naming it.

use gltf::json::validation::USize64;
use gltf::json::Root;
use serde_json::Value;

/// The extension's name.
pub const EXTENSION: &str = "EXT_meshopt_compression";

/// Indices of the buffers marked `"fallback": true` in the raw JSON.
pub fn fallback_buffers(raw: &Value) -> Vec<usize> {
    raw.get("buffers")
        .and_then(Value::as_array)
        .map(|b| {
            b.iter()
                .enumerate()
                .filter(|(_, b)| {
                    b.pointer(&format!("/extensions/{EXTENSION}/fallback"))
                        .and_then(Value::as_bool)
                        == Some(true)
                })
                .map(|(i, _)| i)
                .collect()
        })
        .unwrap_or_default()
}

/// Decode every compressed view of `raw` (the document's JSON) into a new
/// buffer appended to `buffers`, and point `root`'s view at it. Each
/// decoded size is taken from `budget` (bytes the reader may still
/// allocate, see [`super::common::DECODED_BYTES_PER_INPUT_BYTE`]) before it is
/// allocated. Errors are `(JSON path, message)`.
pub fn decompress(
    raw: &Value,
    root: &mut Root,
    buffers: &mut Vec<Vec<u8>>,
    budget: &mut u64,
) -> Result<(), (String, String)> {
    let Some(views) = raw.get("bufferViews").and_then(Value::as_array) else {
        return Ok(());
    };
    for (i, v) in views.iter().enumerate() {
        let Some(ext) = v.pointer(&format!("/extensions/{EXTENSION}")) else {
            continue;
        };
        let at = format!("bufferViews[{i}].extensions.{EXTENSION}");
        let bad = |m: String| (at.clone(), m);
        let spec = Spec::parse(ext).map_err(bad)?;
        let src = buffers
            .get(spec.buffer)
            .and_then(|b| b.get(spec.offset..spec.offset.checked_add(spec.length)?))
            .ok_or_else(|| {
                bad(format!(
                    "bytes {}..+{} of buffer {} do not exist",
                    spec.offset, spec.length, spec.buffer
                ))
            })?;
        let size = spec
            .count
            .checked_mul(spec.stride)
            .filter(|&s| s <= 1 << 31)
            .ok_or_else(|| {
                bad(format!(
                    "{} × {} bytes is too large",
                    spec.count, spec.stride
                ))
            })?;
        if size as u64 > *budget {
            return Err(bad(format!(
                "decoding {size} bytes would pass the reader's memory cap ({} bytes left)",
                *budget
            )));
        }
        *budget -= size as u64;
        let bytes = spec.decode(src, size).map_err(bad)?;
        let view = root
            .buffer_views
            .get_mut(i)
            .ok_or_else(|| bad(format!("bufferView {i} does not exist")))?;
        view.buffer = gltf::json::Index::new(buffers.len() as u32);
        view.byte_offset = Some(USize64(0));
        view.byte_length = USize64(size as u64);
        view.extensions = None;
        buffers.push(bytes);
        root.buffers.push(gltf::json::Buffer {
            byte_length: USize64(size as u64),
            name: None,
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
    }
    Ok(())
}

/// One compressed view's extension object.
struct Spec<'a> {
    buffer: usize,
    offset: usize,
    length: usize,
    stride: usize,
    count: usize,
    mode: &'a str,
    filter: &'a str,
}

impl<'a> Spec<'a> {
    fn parse(ext: &'a Value) -> Result<Spec<'a>, String> {
        let int = |key: &str, default: Option<u64>| -> Result<usize, String> {
            match ext.get(key) {
                Some(x) => x
                    .as_u64()
                    .and_then(|x| usize::try_from(x).ok())
                    .ok_or_else(|| format!("{key} is not a non-negative integer")),
                None => default
                    .map(|d| d as usize)
                    .ok_or_else(|| format!("{key} is missing")),
            }
        };
        Ok(Spec {
            buffer: int("buffer", None)?,
            offset: int("byteOffset", Some(0))?,
            length: int("byteLength", None)?,
            stride: int("byteStride", None)?,
            count: int("count", None)?,
            mode: ext.get("mode").and_then(Value::as_str).unwrap_or(""),
            filter: ext.get("filter").and_then(Value::as_str).unwrap_or("NONE"),
        })
    }

    /// Decodes `src` into `size` (= count × stride) bytes, filter applied.
    fn decode(&self, src: &[u8], size: usize) -> Result<Vec<u8>, String> {
        let (count, stride, mode) = (self.count, self.stride, self.mode);
        // u32 words: the filters work on aligned 16- and 32-bit components
        let mut dst = vec![0u32; size.div_ceil(4)];
        let out = dst.as_mut_ptr().cast::<std::ffi::c_void>();
        let code = match mode {
            "ATTRIBUTES" => {
                if stride == 0 || stride % 4 != 0 || stride > 256 {
                    return Err(format!(
                        "byteStride {stride} (ATTRIBUTES: 4..=256, a multiple of 4)"
                    ));
                }
                // SAFETY: `dst` holds count × stride bytes, `src` its length.
                unsafe {
                    meshopt::ffi::meshopt_decodeVertexBuffer(
                        out,
                        count,
                        stride,
                        src.as_ptr(),
                        src.len(),
                    )
                }
            }
            "TRIANGLES" | "INDICES" => {
                if stride != 2 && stride != 4 {
                    return Err(format!("byteStride {stride} ({mode}: 2 or 4)"));
                }
                if mode == "TRIANGLES" && count % 3 != 0 {
                    return Err(format!("count {count} is not a multiple of 3"));
                }
                let decode = if mode == "TRIANGLES" {
                    meshopt::ffi::meshopt_decodeIndexBuffer
                } else {
                    meshopt::ffi::meshopt_decodeIndexSequence
                };
                // SAFETY: as above, index size `stride`.
                unsafe { decode(out, count, stride, src.as_ptr(), src.len()) }
            }
            other => return Err(format!("unknown mode {other:?}")),
        };
        if code != 0 {
            return Err(format!("meshoptimizer could not decode it (error {code})"));
        }
        self.filter(&mut dst)?;
        let mut bytes: Vec<u8> = dst.iter().flat_map(|w| w.to_ne_bytes()).collect();
        bytes.truncate(size);
        Ok(bytes)
    }

    /// Applies the view's filter to the decoded words in place.
    fn filter(&self, dst: &mut [u32]) -> Result<(), String> {
        let (count, stride, filter) = (self.count, self.stride, self.filter);
        if self.mode != "ATTRIBUTES" {
            return match filter {
                "NONE" => Ok(()),
                _ => Err(format!("filter {filter} on {}", self.mode)),
            };
        }
        let ok = match filter {
            "NONE" => true,
            "OCTAHEDRAL" | "COLOR" => stride == 4 || stride == 8,
            "QUATERNION" => stride == 8,
            "EXPONENTIAL" => true,
            _ => return Err(format!("unknown filter {filter:?}")),
        };
        if !ok {
            return Err(format!("filter {filter} with byteStride {stride}"));
        }
        debug_assert!(dst.len() * 4 >= count * stride);
        let out = dst.as_mut_ptr().cast::<std::ffi::c_void>();
        // SAFETY: `dst` is u32-aligned and holds count × stride bytes.
        unsafe {
            match filter {
                "OCTAHEDRAL" => meshopt::ffi::meshopt_decodeFilterOct(out, count, stride),
                "COLOR" => meshopt::ffi::meshopt_decodeFilterColor(out, count, stride),
                "QUATERNION" => meshopt::ffi::meshopt_decodeFilterQuat(out, count, stride),
                "EXPONENTIAL" => meshopt::ffi::meshopt_decodeFilterExp(out, count, stride),
                _ => {}
            }
        }
        Ok(())
    }
}
