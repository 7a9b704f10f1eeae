//! The bytes on disk: segments laid out as buffers (GLB BIN chunk or one
//! `.bin` per level), meshopt fallback buffers, the root's `bufferViews`,
//! `buffers` and extension lists, the GLB container, and the atomic write.

use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};

use super::builder::{Builder, SHARED};
use super::error::WriteError;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Format {
    Glb,
    Gltf,
}

/// A file to write: its bytes as parts written one after the other (the
/// segments are moved in, never copied into one buffer).
pub(super) struct OutFile {
    pub(super) path: PathBuf,
    pub(super) parts: Vec<Vec<u8>>,
}

impl OutFile {
    pub(super) fn len(&self) -> usize {
        self.parts.iter().map(Vec::len).sum()
    }
}

/// Where each segment went: per segment (buffer index, base offset in that
/// buffer), the buffers, the side files of `.gltf` output and the GLB BIN
/// chunk's parts and length (a multiple of 4).
struct Placement {
    place: Vec<(usize, usize)>,
    buffers: Vec<Value>,
    files: Vec<OutFile>,
    bin: Vec<Vec<u8>>,
    bin_len: usize,
}

/// Zero bytes that bring `len` to a multiple of 4.
fn padding(len: usize) -> Vec<u8> {
    vec![0; len.next_multiple_of(4) - len]
}

impl Builder {
    /// Lays out the segments, fills `accessors`, `bufferViews`, `buffers`,
    /// `meshes` and the extension lists of `root`, and returns the files to
    /// write (main file first).
    pub(super) fn finish(
        mut self,
        root: &mut Map<String, Value>,
        format: Format,
        path: &Path,
        stem: &str,
    ) -> Result<Vec<OutFile>, WriteError> {
        let levels = self.segments.len() - 1;
        // Segment order: shared, then levels coarsest first.
        let order: Vec<usize> = std::iter::once(SHARED).chain((1..=levels).rev()).collect();
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let segments = std::mem::take(&mut self.segments);
        let Placement {
            place,
            mut buffers,
            mut files,
            bin,
            bin_len,
        } = place_segments(segments, &order, format, &dir, stem);
        let fallback = self.fallback_buffers(&order, &mut buffers);
        let views = self.buffer_views(&place, &fallback);
        self.fill_root(root, levels, views, buffers);
        let root = Value::Object(std::mem::take(root));
        let parts = match format {
            Format::Gltf => {
                let mut json = serde_json::to_vec_pretty(&root)?;
                json.push(b'\n');
                vec![json]
            }
            Format::Glb => glb(&serde_json::to_vec(&root)?, bin, bin_len)?,
        };
        files.insert(
            0,
            OutFile {
                path: path.to_path_buf(),
                parts,
            },
        );
        Ok(files)
    }

    /// With meshopt compression, one placeholder fallback buffer per segment
    /// that has compressed views; returns each segment's fallback buffer
    /// index (`usize::MAX`: none).
    fn fallback_buffers(&self, order: &[usize], buffers: &mut Vec<Value>) -> Vec<usize> {
        let mut fallback = vec![usize::MAX; self.fallback_len.len()];
        if self.compress() {
            for &s in order {
                if self.fallback_len[s] > 0 {
                    fallback[s] = buffers.len();
                    buffers.push(json!({
                        "byteLength": self.fallback_len[s],
                        "extensions": {"EXT_meshopt_compression": {"fallback": true}},
                    }));
                }
            }
        }
        fallback
    }

    /// The `bufferViews` array.
    fn buffer_views(&self, place: &[(usize, usize)], fallback: &[usize]) -> Vec<Value> {
        self.views
            .iter()
            .map(|v| {
                let (buffer, base) = place[v.segment];
                let mut out = match &v.meshopt {
                    None => json!({"buffer": buffer, "byteOffset": base + v.offset,
                                   "byteLength": v.length}),
                    Some(m) => json!({
                        "buffer": fallback[v.segment],
                        "byteOffset": m.fallback_offset,
                        "byteLength": m.uncompressed_length,
                        "extensions": {"EXT_meshopt_compression": {
                            "buffer": buffer,
                            "byteOffset": base + v.offset,
                            "byteLength": v.length,
                            "byteStride": m.stride,
                            "count": m.count,
                            "mode": m.mode,
                        }},
                    }),
                };
                if let Some(stride) = v.stride {
                    out["byteStride"] = stride.into();
                }
                if let Some(target) = v.target {
                    out["target"] = target.into();
                }
                out
            })
            .collect()
    }

    /// Extension lists, `accessors`, `bufferViews`, `buffers` and `meshes`
    /// of `root` (empty arrays left out).
    fn fill_root(
        self,
        root: &mut Map<String, Value>,
        levels: usize,
        views: Vec<Value>,
        buffers: Vec<Value>,
    ) {
        // Some node carries MSFT_lod exactly when some chain has 2+ levels.
        let mut used: Vec<String> = Vec::new();
        if levels > 1 {
            used.push("MSFT_lod".into());
        }
        let mut required: Vec<String> = Vec::new();
        if self.opts.quantize {
            used.push("KHR_mesh_quantization".into());
            required.push("KHR_mesh_quantization".into());
        }
        if self.texture_transform {
            // the quantized UVs are wrong without it
            used.push(super::uvrange::EXTENSION.into());
            required.push(super::uvrange::EXTENSION.into());
        }
        if self.compress() {
            used.push("EXT_meshopt_compression".into());
            required.push("EXT_meshopt_compression".into());
        }
        merge_extension_list(root, "extensionsUsed", used);
        merge_extension_list(root, "extensionsRequired", required);
        root.insert("accessors".into(), self.accessors.into());
        root.insert("bufferViews".into(), views.into());
        root.insert("buffers".into(), buffers.into());
        root.insert("meshes".into(), self.meshes.into());
        for key in ["accessors", "bufferViews", "buffers", "meshes"] {
            if root[key].as_array().is_some_and(Vec::is_empty) {
                root.remove(key);
            }
        }
    }
}

/// `segments` in `order` as one BIN chunk (`.glb`) or one file each
/// (`.gltf`, empty segments skipped), moved into the parts, 4-byte aligned.
fn place_segments(
    mut segments: Vec<Vec<u8>>,
    order: &[usize],
    format: Format,
    dir: &Path,
    stem: &str,
) -> Placement {
    let mut files: Vec<OutFile> = Vec::new();
    let mut buffers: Vec<Value> = Vec::new();
    let mut place = vec![(0usize, 0usize); segments.len()];
    let mut bin = Vec::new();
    let mut bin_len = 0;
    match format {
        Format::Glb => {
            for &s in order {
                let data = std::mem::take(&mut segments[s]);
                let pad = padding(bin_len);
                bin_len += pad.len();
                place[s] = (0, bin_len);
                bin_len += data.len();
                bin.extend([pad, data]);
            }
            let pad = padding(bin_len);
            bin_len += pad.len();
            bin.push(pad);
            if bin_len > 0 {
                buffers.push(json!({"byteLength": bin_len}));
            }
        }
        Format::Gltf => {
            for &s in order {
                let data = std::mem::take(&mut segments[s]);
                if data.is_empty() {
                    continue;
                }
                let pad = padding(data.len());
                let len = data.len() + pad.len();
                let name = if s == SHARED {
                    format!("{stem}.bin")
                } else {
                    format!("{stem}.lod{}.bin", s - 1)
                };
                place[s] = (buffers.len(), 0);
                buffers.push(json!({"byteLength": len, "uri": uri_escape(&name)}));
                files.push(OutFile {
                    path: dir.join(&name),
                    parts: vec![data, pad],
                });
            }
        }
    }
    Placement {
        place,
        buffers,
        files,
        bin,
        bin_len,
    }
}

/// Adds `names` to the root's extension list `key`, sorted, without duplicates.
fn merge_extension_list(root: &mut Map<String, Value>, key: &str, names: Vec<String>) {
    let mut list: Vec<String> = root
        .get(key)
        .and_then(Value::as_array)
        .map(|a| {
            a.iter()
                .filter_map(|v| v.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    list.extend(names);
    list.sort();
    list.dedup();
    if list.is_empty() {
        root.remove(key);
    } else {
        root.insert(key.into(), list.into());
    }
}

/// Percent-escapes the characters a URI reference cannot hold verbatim.
fn uri_escape(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for b in name.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

/// The GLB container's parts: header and JSON chunk, then the BIN chunk's
/// header and `bin` (`bin_len` bytes, a multiple of 4) when not empty.
fn glb(json: &[u8], bin: Vec<Vec<u8>>, bin_len: usize) -> Result<Vec<Vec<u8>>, WriteError> {
    let mut json = json.to_vec();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + if bin_len == 0 { 0 } else { 8 + bin_len };
    let total = u32::try_from(total).map_err(|_| WriteError::TooLarge)?;
    let mut head = Vec::with_capacity(12 + 8 + json.len() + 8);
    head.extend_from_slice(b"glTF");
    head.extend_from_slice(&2u32.to_le_bytes());
    head.extend_from_slice(&total.to_le_bytes());
    head.extend_from_slice(&(json.len() as u32).to_le_bytes());
    head.extend_from_slice(b"JSON");
    head.extend_from_slice(&json);
    let mut parts = vec![head];
    if bin_len > 0 {
        let mut chunk = Vec::with_capacity(8);
        chunk.extend_from_slice(&(bin_len as u32).to_le_bytes());
        chunk.extend_from_slice(b"BIN\0");
        parts.push(chunk);
        parts.extend(bin);
    }
    Ok(parts)
}

/// Writes every file to a temporary name in its directory, then renames them
/// (the main file, first in `files`, last). On error, removes whatever it
/// created. Every file stays recorded as unfinished ([`crate::interrupt`])
/// until the main file is in place, so an interrupt removes them all.
pub(super) fn write_atomically(files: &[OutFile]) -> Result<(), WriteError> {
    use crate::interrupt;
    let temp_of = |p: &Path| {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        p.with_file_name(format!(".{name}.{}.lodgen-tmp", std::process::id()))
    };
    let mut temps: Vec<PathBuf> = Vec::with_capacity(files.len());
    for file in files {
        let temp = temp_of(&file.path);
        if let Err(source) = write_parts(&temp, &file.parts) {
            temps.push(temp);
            interrupt::discard(&temps);
            return Err(WriteError::Io {
                path: file.path.clone(),
                source,
            });
        }
        temps.push(temp);
    }
    let mut done: Vec<PathBuf> = Vec::with_capacity(files.len());
    // Side files first (still unfinished until the main file is in place),
    // the main file last.
    let order = (1..files.len()).chain(std::iter::once(0));
    for i in order {
        let path = &files[i].path;
        if let Err(source) = interrupt::rename(&temps[i], path, i != 0) {
            let pending: Vec<PathBuf> = temps
                .iter()
                .enumerate()
                .filter(|(j, _)| !done.contains(&files[*j].path))
                .map(|(_, t)| t.clone())
                .chain(done.iter().cloned())
                .collect();
            interrupt::discard(&pending);
            return Err(WriteError::Io {
                path: path.clone(),
                source,
            });
        }
        done.push(path.clone());
    }
    interrupt::finished(&done);
    Ok(())
}

/// Creates (or truncates) `path`, recorded as unfinished, and writes
/// `parts` one after the other.
fn write_parts(path: &Path, parts: &[Vec<u8>]) -> std::io::Result<()> {
    use std::io::Write;
    let mut file = crate::interrupt::create(path)?;
    for part in parts {
        file.write_all(part)?;
    }
    Ok(())
}
