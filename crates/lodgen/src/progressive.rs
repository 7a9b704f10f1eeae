//! The `LODGEN_progressive` glTF extension (spec: `docs/LODGEN_progressive.md`):
//! the vertex-split stream of [`lodgen_pm::stream`] stored in a glTF file, on
//! the coarsest `MSFT_lod` level's primitive.
//!
//! Owns [`attach`] (used by the glTF writer on the document it is building:
//! adds the stream's buffer / buffer view, the primitive extension and the
//! `extensionsUsed` entry) and [`read_file`] / [`read_glb`] / [`find`] (find
//! and slice the stream in a parsed document). Works on `serde_json::Value`
//! so it depends on nothing else in this crate; decoding is the core's.

use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The extension's name, as it appears in `extensionsUsed` and on the
/// primitive.
pub const EXTENSION: &str = "LODGEN_progressive";

/// Where [`attach`] puts the stream bytes.
#[derive(Debug)]
pub enum Placement<'a> {
    /// At the end of the GLB binary chunk being built (buffer 0, which must
    /// be the GLB-stored buffer), 4-byte aligned; `buffers[0].byteLength` is
    /// updated (the buffer is created when the document has none).
    Glb { bin: &'a mut Vec<u8> },
    /// In a buffer of its own whose `uri` is `uri`; the caller writes the
    /// stream bytes to that file (relative to the `.gltf`).
    External { uri: String },
}

/// Why the extension could not be added or read.
#[derive(Debug, Error)]
pub enum ProgressiveError {
    #[error("{path}: {what}")]
    Json { path: String, what: String },
    #[error("not a GLB file: {0}")]
    Glb(String),
    #[error("reading {path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("parsing the glTF JSON")]
    Parse(#[from] serde_json::Error),
    #[error("the LODGEN_progressive stream")]
    Stream(#[from] lodgen_pm::stream::StreamError),
    #[error("encoding the LODGEN_progressive stream")]
    Encode(#[from] lodgen_pm::stream::EncodeError),
}

fn json_err(path: impl Into<String>, what: impl Into<String>) -> ProgressiveError {
    ProgressiveError::Json {
        path: path.into(),
        what: what.into(),
    }
}

fn array_mut<'a>(root: &'a mut Value, key: &str) -> Result<&'a mut Vec<Value>, ProgressiveError> {
    let obj = root
        .as_object_mut()
        .ok_or_else(|| json_err("/", "the document root is not an object"))?;
    obj.entry(key)
        .or_insert_with(|| Value::Array(Vec::new()))
        .as_array_mut()
        .ok_or_else(|| json_err(format!("/{key}"), "not an array"))
}

/// Add the stream to the document: a buffer view (on a buffer chosen by
/// `placement`), `meshes[mesh].primitives[primitive].extensions.LODGEN_progressive
/// = { bufferView, levels }` and `"LODGEN_progressive"` in `extensionsUsed`
/// (never `extensionsRequired`: the file stays loadable without it).
///
/// `levels[i]` is the record count reproducing the i-th level of the
/// `MSFT_lod` chain, finest first (the node carrying `MSFT_lod`, then its
/// `ids` in order), and should equal the stream header's own level table.
/// Returns the buffer view index.
pub fn attach(
    root: &mut Value,
    mesh: usize,
    primitive: usize,
    stream: &[u8],
    levels: &[usize],
    placement: Placement,
) -> Result<usize, ProgressiveError> {
    // check the stream and the primitive first so that an error leaves
    // `root` unchanged
    let header = lodgen_pm::stream::decode_header(stream)?;
    let chunks: Vec<usize> = (1..=header.chunks.len())
        .map(|i| header.chunk_offset(i))
        .collect();
    let prim_path = format!("/meshes/{mesh}/primitives/{primitive}");
    if root
        .pointer(&prim_path)
        .and_then(Value::as_object)
        .is_none()
    {
        return Err(json_err(prim_path, "no such primitive"));
    }
    let (buffer, offset) = match placement {
        Placement::Glb { bin } => {
            let buffers = array_mut(root, "buffers")?;
            if buffers.is_empty() {
                buffers.push(json!({ "byteLength": 0 }));
            }
            if buffers[0].get("uri").is_some() {
                return Err(json_err(
                    "/buffers/0",
                    "has a uri: not the GLB-stored buffer",
                ));
            }
            while bin.len() % 4 != 0 {
                bin.push(0);
            }
            let offset = bin.len();
            bin.extend_from_slice(stream);
            while bin.len() % 4 != 0 {
                bin.push(0);
            }
            buffers[0]["byteLength"] = bin.len().into();
            (0, offset)
        }
        Placement::External { uri } => {
            let buffers = array_mut(root, "buffers")?;
            buffers.push(json!({ "byteLength": stream.len(), "uri": uri }));
            (buffers.len() - 1, 0)
        }
    };
    let views = array_mut(root, "bufferViews")?;
    views.push(json!({ "buffer": buffer, "byteOffset": offset, "byteLength": stream.len() }));
    let view = views.len() - 1;
    let prim = root
        .pointer_mut(&prim_path)
        .and_then(Value::as_object_mut)
        .ok_or_else(|| json_err(prim_path.clone(), "no such primitive"))?;
    let ext = prim
        .entry("extensions")
        .or_insert_with(|| json!({}))
        .as_object_mut()
        .ok_or_else(|| json_err(format!("{prim_path}/extensions"), "not an object"))?;
    ext.insert(
        EXTENSION.into(),
        json!({ "version": lodgen_pm::stream::VERSION, "bufferView": view, "levels": levels,
                "chunks": chunks }),
    );
    let used = array_mut(root, "extensionsUsed")?;
    if !used.iter().any(|u| u == EXTENSION) {
        used.push(EXTENSION.into());
    }
    Ok(view)
}

/// The extension as found in a document.
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    pub mesh: usize,
    pub primitive: usize,
    pub buffer_view: usize,
    pub levels: Vec<usize>,
    /// `(buffer, byteOffset, byteLength)` of the buffer view.
    pub range: (usize, usize, usize),
    /// The `MSFT_lod` chain holding `mesh`, finest first, as mesh indices,
    /// with its `extras.MSFT_screencoverage` (empty when absent); just
    /// `[mesh]` when no node lists it.
    pub lod_meshes: Vec<usize>,
    pub screen_coverage: Vec<f64>,
    /// Streams in the document, this one included (one per chain that
    /// carries one: `lodgen --progressive` on a scene of several meshes).
    pub streams: usize,
}

fn index(v: &Value, path: &str) -> Result<usize, ProgressiveError> {
    v.as_u64()
        .map(|x| x as usize)
        .ok_or_else(|| json_err(path, "expected a non-negative integer"))
}

/// The first primitive carrying the extension, in mesh order.
pub fn find(root: &Value) -> Result<Option<Found>, ProgressiveError> {
    let Some(meshes) = root.get("meshes").and_then(Value::as_array) else {
        return Ok(None);
    };
    for (m, mesh) in meshes.iter().enumerate() {
        let Some(prims) = mesh.get("primitives").and_then(Value::as_array) else {
            continue;
        };
        for (p, prim) in prims.iter().enumerate() {
            let Some(ext) = prim.pointer(&format!("/extensions/{EXTENSION}")) else {
                continue;
            };
            let path = format!("/meshes/{m}/primitives/{p}/extensions/{EXTENSION}");
            let view = index(
                ext.get("bufferView").unwrap_or(&Value::Null),
                &format!("{path}/bufferView"),
            )?;
            let levels = ext
                .get("levels")
                .and_then(Value::as_array)
                .ok_or_else(|| json_err(format!("{path}/levels"), "expected an array"))?
                .iter()
                .enumerate()
                .map(|(i, v)| index(v, &format!("{path}/levels/{i}")))
                .collect::<Result<Vec<_>, _>>()?;
            let vpath = format!("/bufferViews/{view}");
            let bv = root
                .pointer(&vpath)
                .ok_or_else(|| json_err(&vpath, "no such buffer view"))?;
            let range = (
                index(
                    bv.get("buffer").unwrap_or(&Value::Null),
                    &format!("{vpath}/buffer"),
                )?,
                bv.get("byteOffset")
                    .map_or(Ok(0), |v| index(v, &format!("{vpath}/byteOffset")))?,
                index(
                    bv.get("byteLength").unwrap_or(&Value::Null),
                    &format!("{vpath}/byteLength"),
                )?,
            );
            let (lod_meshes, screen_coverage) = lod_chain(root, m);
            let streams = meshes
                .iter()
                .filter_map(|mesh| mesh.get("primitives").and_then(Value::as_array))
                .flatten()
                .filter(|prim| prim.pointer(&format!("/extensions/{EXTENSION}")).is_some())
                .count();
            return Ok(Some(Found {
                mesh: m,
                primitive: p,
                buffer_view: view,
                levels,
                range,
                lod_meshes,
                screen_coverage,
                streams,
            }));
        }
    }
    Ok(None)
}

/// The `MSFT_lod` chain (finest first, as mesh indices) that contains mesh
/// `m`, with its screen coverage values.
fn lod_chain(root: &Value, m: usize) -> (Vec<usize>, Vec<f64>) {
    let nodes = root.get("nodes").and_then(Value::as_array);
    let node_mesh =
        |n: usize| -> Option<usize> { nodes?.get(n)?.get("mesh")?.as_u64().map(|x| x as usize) };
    for node in nodes.into_iter().flatten() {
        let Some(ids) = node
            .pointer("/extensions/MSFT_lod/ids")
            .and_then(Value::as_array)
        else {
            continue;
        };
        let mut chain: Vec<usize> = node
            .get("mesh")
            .and_then(Value::as_u64)
            .map(|x| x as usize)
            .into_iter()
            .collect();
        chain.extend(ids.iter().filter_map(|i| node_mesh(i.as_u64()? as usize)));
        if chain.contains(&m) {
            let cov = node
                .pointer("/extras/MSFT_screencoverage")
                .and_then(Value::as_array)
                .map(|a| a.iter().filter_map(Value::as_f64).collect())
                .unwrap_or_default();
            return (chain, cov);
        }
    }
    (vec![m], Vec::new())
}

/// A GLB split into its JSON document and binary chunk.
pub fn parse_glb(bytes: &[u8]) -> Result<(Value, &[u8]), ProgressiveError> {
    let u32_at = |at: usize| -> Result<u32, ProgressiveError> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| ProgressiveError::Glb(format!("truncated at byte {at}")))
    };
    if bytes.get(..4) != Some(b"glTF") {
        return Err(ProgressiveError::Glb("bad magic".into()));
    }
    if u32_at(4)? != 2 {
        return Err(ProgressiveError::Glb("not version 2".into()));
    }
    let mut at = 12;
    let mut json = None;
    let mut bin: &[u8] = &[];
    while at + 8 <= bytes.len() {
        let len = u32_at(at)? as usize;
        let kind = u32_at(at + 4)?;
        let body = bytes.get(at + 8..at + 8 + len).ok_or_else(|| {
            ProgressiveError::Glb(format!("chunk at byte {at} overruns the file"))
        })?;
        match kind {
            0x4E4F534A if json.is_none() => json = Some(serde_json::from_slice(body)?),
            0x004E4942 if bin.is_empty() => bin = body,
            _ => {}
        }
        at += 8 + len;
    }
    let json = json.ok_or_else(|| ProgressiveError::Glb("no JSON chunk".into()))?;
    Ok((json, bin))
}

/// The extension and its stream bytes found in a GLB.
pub fn read_glb(bytes: &[u8]) -> Result<Option<(Found, Vec<u8>)>, ProgressiveError> {
    let (root, bin) = parse_glb(bytes)?;
    let Some(found) = find(&root)? else {
        return Ok(None);
    };
    let (buffer, off, len) = found.range;
    if buffer != 0 || root.pointer("/buffers/0/uri").is_some() {
        return Err(json_err(
            format!("/bufferViews/{}", found.buffer_view),
            "the stream of a GLB must be in its binary chunk (buffer 0)",
        ));
    }
    let data = slice(bin, off, len, found.buffer_view)?.to_vec();
    Ok(Some((found, data)))
}

fn slice(buf: &[u8], off: usize, len: usize, view: usize) -> Result<&[u8], ProgressiveError> {
    off.checked_add(len)
        .and_then(|end| buf.get(off..end))
        .ok_or_else(|| json_err(format!("/bufferViews/{view}"), "range outside its buffer"))
}

/// Read a `.glb` or `.gltf` (external buffers resolved beside it) and return
/// the extension and its stream bytes, or `None` when it has none.
pub fn read_file(path: &Path) -> Result<Option<(Found, Vec<u8>)>, ProgressiveError> {
    let io = |p: &Path| {
        let p = p.to_path_buf();
        move |source| ProgressiveError::Io { path: p, source }
    };
    let bytes = std::fs::read(path).map_err(io(path))?;
    if bytes.starts_with(b"glTF") {
        return read_glb(&bytes);
    }
    let root: Value = serde_json::from_slice(&bytes)?;
    let Some(found) = find(&root)? else {
        return Ok(None);
    };
    let (buffer, off, len) = found.range;
    let bpath = format!("/buffers/{buffer}/uri");
    let uri = root
        .pointer(&bpath)
        .and_then(Value::as_str)
        .ok_or_else(|| json_err(&bpath, "the stream's buffer has no uri"))?;
    if uri.starts_with("data:") || uri.contains("://") {
        return Err(json_err(&bpath, "only relative file URIs are supported"));
    }
    let file = path
        .parent()
        .unwrap_or(Path::new(""))
        .join(percent_decode(uri));
    let data = std::fs::read(&file).map_err(io(&file))?;
    let data = slice(&data, off, len, found.buffer_view)?.to_vec();
    Ok(Some((found, data)))
}

/// `%XX` escapes of a relative URI back to bytes.
fn percent_decode(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// One mesh's stream for [`embed`]: the chain's name as the writer used it
/// (its level meshes are named `{name}_LOD{k}`, `k = 0` the finest), the
/// stream, and the record count of each level, finest first.
#[derive(Clone, Debug)]
pub struct ChainStream {
    pub name: String,
    pub levels: Vec<usize>,
    pub stream: Vec<u8>,
}

impl ChainStream {
    /// The stream of one [`crate::lod::MeshBuild`] of `mesh`: its whole
    /// progressive mesh (every primitive of the mesh, flattened) with its
    /// level split counts, on the 16-bit grid of [`level_grid`]; with every corner's
    /// wedge and every input vertex attribute
    /// ([`crate::lod::stream_attributes`], the wedge group = the primitive)
    /// when the build tracked wedges (QEM; the curvature-adaptive methods
    /// stream positions only) and the mesh has attributes or several
    /// primitives (else positions only: the wedges would say nothing).
    pub fn from_build(
        b: &crate::lod::MeshBuild,
        mesh: &crate::scene::SourceMesh,
    ) -> Result<ChainStream, ProgressiveError> {
        use lodgen_pm::stream::{encode, encode_with_attributes, EncodeOptions};
        let pm = &b.simplified.pm;
        let opts = EncodeOptions::DEFAULT.with_grid(level_grid(&b.lod));
        let attributes = crate::lod::stream_attributes(mesh);
        // wedges without values or groups would only repeat the topology
        let informative =
            !attributes.channels.is_empty() || attributes.groups.iter().any(|&g| g > 0);
        let stream = if pm.wedges.is_some() && informative {
            encode_with_attributes(pm, &b.level_splits, opts, &attributes)?
        } else {
            encode(pm, &b.level_splits, opts)
        };
        Ok(ChainStream {
            name: b.lod.name.clone(),
            levels: b.level_splits.clone(),
            stream,
        })
    }
}

/// The 16-bit grid over the box of every position the chain's levels use
/// (each primitive's referenced vertices): the `KHR_mesh_quantization`
/// grid the glTF writer's `--quantize` puts the same chain on, so the
/// stream's positions equal the quantized file's.
pub fn level_grid(lod: &crate::scene::LodMesh) -> lodgen_pm::stream::Grid {
    let used = lod.levels.iter().flat_map(|l| &l.primitives).flat_map(|p| {
        p.indices
            .iter()
            .filter_map(|&i| p.positions.get(i as usize))
    });
    lodgen_pm::stream::Grid::around(used, 16)
}

/// Serialize a GLB from its JSON document and binary chunk.
pub fn write_glb(root: &Value, bin: &[u8]) -> Result<Vec<u8>, ProgressiveError> {
    let mut json = serde_json::to_vec(root)?;
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = u32::try_from(total).map_err(|_| ProgressiveError::Glb("over 4 GiB".into()))?;
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total.to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
        out.extend_from_slice(&bin);
    }
    Ok(out)
}

fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), ProgressiveError> {
    crate::interrupt::write_atomically(path, &[bytes]).map_err(|source| ProgressiveError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The byte ranges in buffer 0 of bufferView `v`'s data: its own and, with
/// `EXT_meshopt_compression`, its compressed data's, as JSON pointers to
/// their `byteOffset` with `(offset, length)`.
fn buffer0_ranges(root: &Value, v: usize) -> Vec<(String, usize, usize)> {
    let at = |p: String| {
        let o = root.pointer(&p)?;
        let len = o.get("byteLength")?.as_u64()? as usize;
        let off = o.get("byteOffset").map_or(Some(0), Value::as_u64)? as usize;
        (o.get("buffer")?.as_u64()? == 0).then_some((format!("{p}/byteOffset"), off, len))
    };
    let view = format!("/bufferViews/{v}");
    let mo = format!("{view}/extensions/EXT_meshopt_compression");
    [at(view), at(mo)].into_iter().flatten().collect()
}

/// Move the stream of buffer view `view` (appended at the end of the GLB
/// binary chunk `bin`) to right after the data of `mesh` (the coarsest
/// level), shifting the data behind it: a client reading the file from its
/// start gets the JSON, the coarsest level and the stream, in that order.
/// Left at the end when a range of buffer 0 straddles that point.
fn hoist_stream(root: &mut Value, bin: &mut [u8], view: usize, mesh: usize) {
    let views = root["bufferViews"].as_array().map_or(0, Vec::len);
    let accessor_view = |a: &Value| {
        let i = a.as_u64()? as usize;
        root.pointer(&format!("/accessors/{i}/bufferView"))?
            .as_u64()
    };
    let mut mesh_views: Vec<usize> = Vec::new();
    for prim in root["meshes"][mesh]["primitives"]
        .as_array()
        .into_iter()
        .flatten()
    {
        let attrs = prim["attributes"]
            .as_object()
            .into_iter()
            .flat_map(|a| a.values());
        for a in attrs.chain(prim.get("indices")) {
            mesh_views.extend(accessor_view(a).map(|v| v as usize));
        }
    }
    let end = mesh_views.iter().flat_map(|&v| buffer0_ranges(root, v));
    let at = end
        .map(|(_, o, l)| o + l)
        .max()
        .unwrap_or(0)
        .next_multiple_of(4);
    let Some((ptr, off, len)) = buffer0_ranges(root, view).into_iter().next() else {
        return;
    };
    let others: Vec<_> = (0..views)
        .filter(|&v| v != view)
        .flat_map(|v| buffer0_ranges(root, v))
        .collect();
    if at >= off || others.iter().any(|&(_, o, l)| o < at && at < o + l) {
        return;
    }
    let shift = len.next_multiple_of(4);
    let stream: Vec<u8> = bin[off..off + len].to_vec();
    bin.copy_within(at..off, at + shift);
    bin[at..at + len].copy_from_slice(&stream);
    bin[at + len..at + shift].fill(0);
    for (p, o, _) in others.into_iter().filter(|&(_, o, _)| o >= at) {
        *root.pointer_mut(&p).expect("found above") = (o + shift).into();
    }
    *root.pointer_mut(&ptr).expect("found above") = at.into();
}

/// Add `LODGEN_progressive` to a `.glb` / `.gltf` the glTF writer has just
/// written: [`embed_bytes`] on the file's bytes, then the stream files and
/// the file replaced atomically.
pub fn embed(path: &Path, chains: &[ChainStream]) -> Result<(), ProgressiveError> {
    let io = |source| ProgressiveError::Io {
        path: path.to_path_buf(),
        source,
    };
    let bytes = std::fs::read(path).map_err(io)?;
    let (out, files) = embed_bytes(path, &bytes, chains)?;
    for (p, data) in &files {
        write_atomically(p, data)?;
    }
    write_atomically(path, &out)
}

/// `LODGEN_progressive` added to the bytes of a `.glb` / `.gltf` the glTF
/// writer made for `path`: each chain's stream goes on primitive 0 of its
/// coarsest level's mesh (`{name}_LOD{levels.len() - 1}`), in the GLB
/// binary chunk right after that mesh's data (before the finer levels'),
/// or for `.gltf` in `STEM.stream.bin` (`STEM.streamI.bin` when several
/// meshes carry one). Returns the new bytes and the stream files to write
/// beside them (none for a GLB); a pure function of the inputs. A chain
/// whose coarsest mesh is not found is an error.
pub fn embed_bytes(
    path: &Path,
    bytes: &[u8],
    chains: &[ChainStream],
) -> Result<crate::gltf_out::Added, ProgressiveError> {
    let glb = bytes.starts_with(b"glTF");
    let (mut root, mut bin) = if glb {
        let (root, bin) = parse_glb(bytes)?;
        (root, bin.to_vec())
    } else {
        (serde_json::from_slice(bytes)?, Vec::new())
    };
    let mut files = Vec::new();
    for (i, c) in chains.iter().enumerate() {
        let want = format!("{}_LOD{}", c.name, c.levels.len().saturating_sub(1));
        let mesh = root
            .get("meshes")
            .and_then(Value::as_array)
            .and_then(|m| {
                m.iter()
                    .position(|m| m.get("name").and_then(Value::as_str) == Some(&want))
            })
            .ok_or_else(|| json_err("/meshes", format!("no mesh named {want:?}")))?;
        let placement = if glb {
            Placement::Glb { bin: &mut bin }
        } else {
            let stem = path
                .file_stem()
                .map_or_else(|| "out".into(), |s| s.to_string_lossy().into_owned());
            let name = if chains.len() == 1 {
                format!("{stem}.stream.bin")
            } else {
                format!("{stem}.stream{i}.bin")
            };
            let uri: String = name
                .bytes()
                .map(|b| match b {
                    b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'_' | b'.' | b'~' => {
                        (b as char).to_string()
                    }
                    _ => format!("%{b:02X}"),
                })
                .collect();
            files.push((path.with_file_name(&name), c.stream.clone()));
            Placement::External { uri }
        };
        let view = attach(&mut root, mesh, 0, &c.stream, &c.levels, placement)?;
        if glb {
            hoist_stream(&mut root, &mut bin, view, mesh);
        }
    }
    let out = if glb {
        write_glb(&root, &bin)?
    } else {
        let mut json = serde_json::to_vec_pretty(&root)?;
        json.push(b'\n');
        json
    };
    Ok((out, files))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc() -> Value {
        json!({
            "asset": {"version": "2.0"},
            "buffers": [{"byteLength": 8}],
            "bufferViews": [{"buffer": 0, "byteLength": 8}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]},
                       {"primitives": [{"attributes": {"POSITION": 0}}]}],
            "nodes": [{"mesh": 0, "extensions": {"MSFT_lod": {"ids": [1]}},
                       "extras": {"MSFT_screencoverage": [0.5, 0.01]}},
                      {"mesh": 1}],
            "extensionsUsed": ["MSFT_lod"],
        })
    }

    /// A real stream: an icosphere's log with levels [all, none].
    fn stream() -> (Vec<u8>, Vec<usize>) {
        let m = lodgen_pm::shapes::icosphere(1);
        let opts = lodgen_pm::SimplifyOptions::DEFAULT.with_target_triangles(8);
        let pm = lodgen_pm::simplify(&m.positions, &m.indices(), &opts)
            .unwrap()
            .pm;
        let levels = vec![pm.len(), 0];
        let bytes = lodgen_pm::stream::encode(&pm, &levels, Default::default());
        (bytes, levels)
    }

    #[test]
    fn attach_then_find_in_a_glb_chunk() {
        let (s, levels) = stream();
        let mut root = doc();
        let mut bin = vec![1u8; 6];
        let view = attach(
            &mut root,
            1,
            0,
            &s,
            &levels,
            Placement::Glb { bin: &mut bin },
        )
        .unwrap();
        assert_eq!(view, 1);
        assert_eq!(bin.len(), 8 + s.len().div_ceil(4) * 4);
        assert_eq!(&bin[8..8 + s.len()], &s[..]);
        assert_eq!(root["buffers"][0]["byteLength"], bin.len());
        assert_eq!(root["extensionsUsed"], json!(["MSFT_lod", EXTENSION]));
        assert!(root.get("extensionsRequired").is_none());
        let ext = &root["meshes"][1]["primitives"][0]["extensions"][EXTENSION];
        let h = lodgen_pm::stream::decode_header(&s).unwrap();
        assert_eq!(ext["version"], 7);
        assert_eq!(ext["chunks"], json!([h.chunk_offset(1), s.len()]));
        let f = find(&root).unwrap().unwrap();
        assert_eq!((f.mesh, f.primitive, f.buffer_view), (1, 0, 1));
        assert_eq!(f.range, (0, 8, s.len()));
        assert_eq!(f.levels, levels);
        assert_eq!(f.lod_meshes, vec![0, 1]);
        assert_eq!(f.screen_coverage, vec![0.5, 0.01]);
    }

    #[test]
    fn the_stream_moves_to_right_after_the_coarsest_level() {
        let (s, levels) = stream();
        let mut root = doc();
        root["accessors"] = json!([{"bufferView": 0}, {"bufferView": 1}]);
        root["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 1.into();
        root["bufferViews"] = json!([{"buffer": 0, "byteLength": 6},
            {"buffer": 0, "byteOffset": 8, "byteLength": 8}]);
        let mut bin = [vec![1u8; 6], vec![0; 2], vec![2u8; 8]].concat();
        let view = attach(
            &mut root,
            1,
            0,
            &s,
            &levels,
            Placement::Glb { bin: &mut bin },
        )
        .unwrap();
        hoist_stream(&mut root, &mut bin, view, 1);
        let shift = s.len().div_ceil(4) * 4;
        assert_eq!(find(&root).unwrap().unwrap().range, (0, 8, s.len()));
        assert_eq!(&bin[8..8 + s.len()], &s[..]);
        assert_eq!(root["bufferViews"][1]["byteOffset"], 8 + shift);
        assert_eq!(&bin[8 + shift..], &[2u8; 8]);
        assert_eq!(&bin[..6], &[1u8; 6]);
        // a range across the insertion point: the stream stays at the end
        let mut root = doc();
        root["accessors"] = json!([{"bufferView": 0}]);
        root["bufferViews"] = json!([{"buffer": 0, "byteLength": 6},
            {"buffer": 0, "byteOffset": 4, "byteLength": 8}]);
        let mut bin = vec![3u8; 12];
        let view = attach(
            &mut root,
            1,
            0,
            &s,
            &levels,
            Placement::Glb { bin: &mut bin },
        )
        .unwrap();
        let before = (root.clone(), bin.clone());
        hoist_stream(&mut root, &mut bin, view, 1);
        assert_eq!((root, bin), before);
    }

    #[test]
    fn attach_to_an_external_buffer() {
        let (s, levels) = stream();
        let mut root = doc();
        let uri = "x.stream.bin".to_string();
        attach(&mut root, 1, 0, &s, &levels, Placement::External { uri }).unwrap();
        assert_eq!(
            root["buffers"][1],
            json!({"byteLength": s.len(), "uri": "x.stream.bin"})
        );
        assert_eq!(
            root["bufferViews"][1],
            json!({"buffer": 1, "byteOffset": 0, "byteLength": s.len()})
        );
    }

    #[test]
    fn a_missing_primitive_or_a_bad_stream_is_an_error_and_changes_nothing() {
        let (s, levels) = stream();
        let mut root = doc();
        let before = root.clone();
        let mut bin = Vec::new();
        assert!(attach(
            &mut root,
            5,
            0,
            &s,
            &levels,
            Placement::Glb { bin: &mut bin }
        )
        .is_err());
        assert!(attach(&mut root, 1, 0, b"x", &[], Placement::Glb { bin: &mut bin }).is_err());
        assert_eq!(root, before);
        assert!(bin.is_empty());
    }

    #[test]
    fn bad_glb_is_an_error() {
        assert!(parse_glb(b"glTF").is_err());
        assert!(parse_glb(b"nope").is_err());
        let mut v = b"glTF".to_vec();
        v.extend_from_slice(&2u32.to_le_bytes());
        v.extend_from_slice(&100u32.to_le_bytes());
        v.extend_from_slice(&50u32.to_le_bytes());
        v.extend_from_slice(&0x4E4F534Au32.to_le_bytes());
        assert!(parse_glb(&v).is_err());
    }

    #[test]
    fn percent_escapes_decode() {
        assert_eq!(percent_decode("a%20b.bin"), "a b.bin");
        assert_eq!(percent_decode("a%2"), "a%2");
        assert_eq!(percent_decode("%zz"), "%zz");
    }
}
