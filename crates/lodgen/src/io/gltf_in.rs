//! glTF 2.0 reader (`.gltf` with external or `data:` buffers, and `.glb`).
//!
//! The JSON is parsed and validated by the `gltf` crate; the GLB container,
//! the buffers and the accessors are read here with every offset, length
//! and index checked, so a hostile file yields a [`ReadError`] naming the
//! JSON path (`meshes[0].primitives[1].indices[6]`) instead of a panic.
//!
//! Every primitive of every mesh is read: `POSITION`, `NORMAL`, `TANGENT`,
//! `TEXCOORD_n`, `COLOR_n`, `JOINTS_n`, `WEIGHTS_n` (every set, up to the
//! first missing one)
//! (float, or integer with `normalized`), indices (`u8`/`u16`/`u32`, or
//! sequential when absent), sparse accessors, and the material index.
//! `TRIANGLES`, `TRIANGLE_STRIP` and `TRIANGLE_FAN` become triangle lists.
//! `POINTS` and `LINE*` primitives, and triangle primitives with no complete
//! triangle, are left out of [`SourceMesh::primitives`]; a mesh left with no
//! triangle at all is an error naming it, so `Scene::meshes[i]` is always
//! glTF mesh `i`. Vertices are kept as stored (no compaction), texture
//! coordinates keep glTF's convention. The parsed document, the JSON as
//! written and the buffers go to [`Origin::Gltf`] for the writer. A required
//! extension is accepted when the reader handles it or it changes no mesh
//! data (material, texture and light extensions).

use std::path::{Path, PathBuf};

use gltf::json::mesh::{Mode, Semantic};
use gltf::json::validation::Checked;
use gltf::json::Root;

use super::common::{check_not_empty, ReadOptions};
use super::error::{ErrorKind, Location, ReadError};
use super::gltf_data::{decode_base64, fan_to_list, percent_decode, strip_to_list};
use crate::scene::{Material, MorphTarget, Origin, Primitive, Scene, SourceMesh, Warning};

/// Required extensions this reader supports although the `gltf` crate's
/// validation does not: quantized attributes are plain integer accessors.
const HANDLED_EXTENSIONS: &[&str] = &["KHR_mesh_quantization", super::meshopt_in::EXTENSION];

/// Whether a required extension leaves the mesh data as the core spec reads
/// it: material, texture, light and animation-pointer extensions, which the
/// writer copies untouched (and keeps required). Any other unknown required extension
/// (`KHR_draco_mesh_compression`, a vendor's) is refused by name.
fn passes_through(extension: &str) -> bool {
    HANDLED_EXTENSIONS.contains(&extension)
        || ["KHR_materials_", "KHR_texture_", "EXT_texture_"]
            .iter()
            .any(|p| extension.starts_with(p))
        || ["KHR_lights_punctual", "KHR_animation_pointer"].contains(&extension)
}

/// The typed document of `json` (parsed as `raw`). Animation channels
/// without a target node (`KHR_animation_pointer`), which the `gltf` crate
/// cannot represent, are left out of it; the writer decides about them
/// from `raw`.
fn typed_root(json: &[u8], raw: &serde_json::Value) -> Result<Root, serde_json::Error> {
    let nodeless = |c: &serde_json::Value| c.pointer("/target/node").is_none();
    let animations = raw.get("animations").and_then(serde_json::Value::as_array);
    let has_nodeless = animations.into_iter().flatten().any(|a| {
        let channels = a.get("channels").and_then(serde_json::Value::as_array);
        channels.into_iter().flatten().any(nodeless)
    });
    if !has_nodeless {
        return gltf::json::deserialize::from_slice(json);
    }
    let mut edited = raw.clone();
    for a in edited["animations"].as_array_mut().into_iter().flatten() {
        if let Some(channels) = a
            .get_mut("channels")
            .and_then(serde_json::Value::as_array_mut)
        {
            channels.retain(|c| !nodeless(c));
        }
    }
    serde_json::from_value(edited)
}

/// Reads a `.gltf` or `.glb` from its bytes. Relative buffer URIs are
/// resolved against the directory of `path`. What cannot be read in one
/// primitive or mesh is left out with a warning in [`Scene::warnings`].
pub fn read_gltf(src: &[u8], path: &Path) -> Result<Scene, ReadError> {
    read_gltf_with(src, path, &ReadOptions::default())
}

/// [`read_gltf`] with options: with `strict`, the first primitive or mesh
/// that would be left out with a warning is an error instead.
pub fn read_gltf_with(src: &[u8], path: &Path, opts: &ReadOptions) -> Result<Scene, ReadError> {
    let r = Reader {
        path,
        strict: opts.strict,
        budget: std::cell::Cell::new(0),
    };
    let (json, blob) = r.split(src)?;
    // The JSON as written: what the writer copies (the typed document
    // widens f32 numbers and drops what it has no field for), and the
    // EXT_meshopt_compression data, which the typed document lacks
    let raw: serde_json::Value = serde_json::from_slice(json).map_err(|e| {
        r.err(
            Location::File,
            ErrorKind::Invalid(format!("invalid glTF JSON: {e}")),
        )
    })?;
    let root = typed_root(json, &raw).map_err(|e| {
        r.err(
            Location::File,
            ErrorKind::Invalid(format!("invalid glTF JSON: {e}")),
        )
    })?;
    // The gltf crate refuses required extensions it does not know, among
    // them some this reader handles itself; validate without those and
    // put the list back.
    let mut root = root;
    let required = std::mem::take(&mut root.extensions_required);
    root.extensions_required = required
        .iter()
        .filter(|e| !passes_through(e))
        .cloned()
        .collect();
    let material_warnings = missing_materials(&r, &mut root)?;
    // the gltf crate's validation indexes POSITION accessors unchecked
    for (mi, mesh) in root.meshes.iter().enumerate() {
        for (pi, prim) in mesh.primitives.iter().enumerate() {
            let position = prim.attributes.get(&Checked::Valid(Semantic::Positions));
            if let Some(a) = position.filter(|a| a.value() >= root.accessors.len()) {
                return Err(r.json_err(
                    &format!("meshes[{mi}].primitives[{pi}].attributes.POSITION"),
                    format!("accessor {} does not exist", a.value()),
                ));
            }
        }
    }
    let document = gltf::Document::from_json(root).map_err(|e| match e {
        gltf::Error::Validation(errors) => match errors.first() {
            Some((json_path, error)) => r.err(
                Location::Json(json_path.0.clone()),
                ErrorKind::Invalid(format!("{error}")),
            ),
            None => r.err(
                Location::File,
                ErrorKind::Invalid("invalid glTF".to_owned()),
            ),
        },
        other => r.err(
            Location::File,
            ErrorKind::Invalid(format!("invalid glTF: {other}")),
        ),
    })?;
    let mut root = document.into_json();
    root.extensions_required = required;
    let compressed = root
        .extensions_used
        .iter()
        .any(|e| e == super::meshopt_in::EXTENSION);
    let fallback = if compressed {
        super::meshopt_in::fallback_buffers(&raw)
    } else {
        Vec::new()
    };
    let mut buffers = r.load_buffers(&root, blob, &fallback)?;
    // the memory cap: decoded data per byte of input (file and buffers)
    let input = src.len() as u64 + buffers.iter().map(|b| b.len() as u64).sum::<u64>();
    let mut budget = super::common::DECODED_BYTES_FLOOR
        .saturating_add(input.saturating_mul(super::common::DECODED_BYTES_PER_INPUT_BYTE));
    if compressed {
        super::meshopt_in::decompress(&raw, &mut root, &mut buffers, &mut budget)
            .map_err(|(at, message)| r.json_err(&at, message))?;
    }
    r.budget.set(budget);

    let materials = root
        .materials
        .iter()
        .map(|m| Material {
            name: m.name.clone().unwrap_or_default(),
            base_color: Some(m.pbr_metallic_roughness.base_color_factor.0),
        })
        .collect();
    let mut warnings = material_warnings;
    let replaced = lod_level_meshes(&raw, root.meshes.len());
    let meshes = r.meshes(&root, &buffers, &replaced, &mut warnings)?;
    let scene = Scene {
        meshes,
        materials,
        origin: Origin::Gltf {
            path: path.to_path_buf(),
            document: Box::new(root),
            json: Box::new(raw),
            buffers,
        },
        warnings,
    };
    check_not_empty(&scene, path).map_err(|e| match scene.warnings.first() {
        // nothing could be read: the first reason is the error
        Some(w) => r.err(
            Location::Json(w.at.clone()),
            ErrorKind::Invalid(w.message.clone()),
        ),
        None => e,
    })?;
    Ok(scene)
}

/// A primitive's material that does not exist: the primitive is read
/// without one, with a warning (`--strict`: an error), not the file refused.
fn missing_materials(r: &Reader<'_>, root: &mut Root) -> Result<Vec<Warning>, ReadError> {
    let mut material_warnings = Vec::new();
    let material_count = root.materials.len();
    for (mi, mesh) in root.meshes.iter_mut().enumerate() {
        for (pi, prim) in mesh.primitives.iter_mut().enumerate() {
            let Some(m) = prim.material.filter(|m| m.value() >= material_count) else {
                continue;
            };
            let at = format!("meshes[{mi}].primitives[{pi}].material");
            let what = format!(
                "material {} does not exist ({material_count} defined): the primitive is \
                 written without a material",
                m.value()
            );
            if r.strict {
                return Err(r.json_err(&at, what));
            }
            prim.material = None;
            material_warnings.push(Warning::new(at, what));
        }
    }
    Ok(material_warnings)
}

/// Per mesh, when every node that draws it is a coarser level of another
/// node's `MSFT_lod` chain (a file lodgen or another tool made LODs of):
/// that node (one of them, if several). Such meshes are not read: the
/// chain is made again from its finest level.
fn lod_level_meshes(raw: &serde_json::Value, meshes: usize) -> Vec<Option<usize>> {
    let nodes = raw
        .get("nodes")
        .and_then(serde_json::Value::as_array)
        .map_or(&[][..], Vec::as_slice);
    let mut level_of: Vec<Option<usize>> = vec![None; nodes.len()];
    for (n, node) in nodes.iter().enumerate() {
        let ids = node.pointer("/extensions/MSFT_lod/ids");
        for id in ids
            .and_then(serde_json::Value::as_array)
            .into_iter()
            .flatten()
        {
            let slot = id.as_u64().and_then(|i| level_of.get_mut(i as usize));
            if let Some(slot @ None) = slot {
                *slot = Some(n);
            }
        }
    }
    let mut out: Vec<Option<Option<usize>>> = vec![None; meshes];
    for (n, node) in nodes.iter().enumerate() {
        let Some(m) = node.get("mesh").and_then(serde_json::Value::as_u64) else {
            continue;
        };
        let Some(slot) = out.get_mut(m as usize) else {
            continue;
        };
        // (a level node that is also some chain's finest, or a plain node,
        // keeps the mesh)
        *slot = match (*slot, level_of[n]) {
            (None, owner) | (Some(Some(_)), owner @ Some(_)) if owner != Some(n) => Some(owner),
            _ => Some(None),
        };
    }
    out.into_iter().map(Option::flatten).collect()
}

pub(super) struct Reader<'a> {
    pub(super) path: &'a Path,
    /// A primitive or mesh that cannot be read is an error, not a warning.
    strict: bool,
    /// Bytes the reader may still allocate for decoded accessors (the
    /// memory cap, [`super::common::DECODED_BYTES_PER_INPUT_BYTE`]).
    pub(super) budget: std::cell::Cell<u64>,
}

fn le_u32(b: &[u8], at: usize) -> Option<u32> {
    let s = b.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
}

impl Reader<'_> {
    pub(super) fn err(&self, location: Location, kind: ErrorKind) -> ReadError {
        ReadError::new(self.path, location, kind)
    }

    pub(super) fn json_err(&self, at: &str, message: String) -> ReadError {
        self.err(Location::Json(at.to_owned()), ErrorKind::Invalid(message))
    }

    /// Splits a GLB container into its JSON chunk and optional BIN chunk.
    /// The JSON and the GLB's binary chunk (if any) of a file: a GLB, or a
    /// JSON object (after a UTF-8 byte order mark, which some editors
    /// write); anything else is an error saying so.
    fn split<'s>(&self, src: &'s [u8]) -> Result<(&'s [u8], Option<&'s [u8]>), ReadError> {
        let src = src.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(src);
        if src.starts_with(b"glTF") {
            return self.split_glb(src);
        }
        if !src.trim_ascii_start().starts_with(b"{") {
            // (a .glb that is not one, or text that is no JSON object)
            let head = &src[..src.len().min(4)];
            return Err(self.err(
                Location::File,
                ErrorKind::Invalid(format!(
                    "not a glTF file: neither the GLB magic `glTF` nor a JSON object at the \
                     start (first bytes {head:02x?})"
                )),
            ));
        }
        Ok((src, None))
    }

    fn split_glb<'s>(&self, src: &'s [u8]) -> Result<(&'s [u8], Option<&'s [u8]>), ReadError> {
        let truncated =
            |what: &str| self.err(Location::File, ErrorKind::Truncated(what.to_owned()));
        let version = le_u32(src, 4).ok_or_else(|| truncated("GLB header"))?;
        if version != 2 {
            return Err(self.err(
                Location::File,
                ErrorKind::Unsupported(format!("GLB version {version} (only 2)")),
            ));
        }
        let length = le_u32(src, 8).ok_or_else(|| truncated("GLB header"))? as usize;
        if length > src.len() {
            return Err(truncated(&format!(
                "GLB header says {length} bytes, file has {}",
                src.len()
            )));
        }
        let data = &src[..length];
        let mut pos = 12;
        let mut json = None;
        let mut bin = None;
        while pos < data.len() {
            let (Some(len), Some(kind)) = (le_u32(data, pos), le_u32(data, pos + 4)) else {
                return Err(truncated(&format!("GLB chunk header at byte {pos}")));
            };
            let start = pos + 8;
            let Some(chunk) = data.get(start..start.saturating_add(len as usize)) else {
                return Err(truncated(&format!("GLB chunk at byte {pos} ({len} bytes)")));
            };
            match kind {
                0x4E4F_534A if json.is_none() => json = Some(chunk),
                0x004E_4942 if bin.is_none() => bin = Some(chunk),
                _ => {}
            }
            pos = start + chunk.len();
        }
        let json = json.ok_or_else(|| {
            self.err(
                Location::File,
                ErrorKind::Invalid("GLB has no JSON chunk".to_owned()),
            )
        })?;
        Ok((json, bin))
    }

    /// Loads every buffer: the GLB BIN chunk, `data:` URIs, relative files;
    /// `fallback` buffers (`EXT_meshopt_compression`) are never read: empty.
    fn load_buffers(
        &self,
        root: &Root,
        blob: Option<&[u8]>,
        fallback: &[usize],
    ) -> Result<Vec<Vec<u8>>, ReadError> {
        let mut out = Vec::with_capacity(root.buffers.len());
        for (i, buffer) in root.buffers.iter().enumerate() {
            if fallback.contains(&i) && !(buffer.uri.is_none() && i == 0 && blob.is_some()) {
                out.push(Vec::new());
                continue;
            }
            let at = format!("buffers[{i}]");
            let data = match &buffer.uri {
                None => match blob {
                    Some(b) if i == 0 => b.to_vec(),
                    _ => {
                        return Err(
                            self.json_err(&at, "buffer has no uri and no GLB BIN chunk".to_owned())
                        )
                    }
                },
                Some(uri) => {
                    if let Some(rest) = uri.strip_prefix("data:") {
                        let Some((_, payload)) = rest.split_once(";base64,") else {
                            return Err(self.json_err(&at, "data URI is not base64".to_owned()));
                        };
                        decode_base64(payload).ok_or_else(|| {
                            self.json_err(&at, "invalid base64 in data URI".to_owned())
                        })?
                    } else if uri.contains(':') {
                        return Err(self.err(
                            Location::Json(format!("{at}.uri")),
                            ErrorKind::Unsupported(format!("URI scheme in `{uri}`")),
                        ));
                    } else {
                        let rel = percent_decode(uri).ok_or_else(|| {
                            self.json_err(&format!("{at}.uri"), format!("invalid URI `{uri}`"))
                        })?;
                        let file: PathBuf = self.path.parent().unwrap_or(Path::new("")).join(rel);
                        std::fs::read(&file).map_err(|e| {
                            self.err(
                                Location::Json(format!("{at}.uri")),
                                ErrorKind::Invalid(format!(
                                    "cannot read buffer file {}",
                                    file.display()
                                )),
                            )
                            .with_source(e)
                        })?
                    }
                }
            };
            let declared = buffer.byte_length.0;
            if (data.len() as u64) < declared {
                return Err(self.err(
                    Location::Json(at),
                    ErrorKind::Truncated(format!(
                        "buffer has {} bytes, byteLength says {declared}",
                        data.len()
                    )),
                ));
            }
            out.push(data);
        }
        Ok(out)
    }

    /// Every mesh, `meshes[i]` being glTF mesh `i`. A primitive that cannot
    /// be read, points and lines, and attributes this reader does not know
    /// are left out with a warning naming them; so is a mesh left with no
    /// triangle (its `primitives` empty: the builder skips it and the writer
    /// drops it from its nodes).
    fn meshes(
        &self,
        root: &Root,
        buffers: &[Vec<u8>],
        replaced: &[Option<usize>],
        warnings: &mut Vec<Warning>,
    ) -> Result<Vec<SourceMesh>, ReadError> {
        let mut meshes = Vec::with_capacity(root.meshes.len());
        for (mi, mesh) in root.meshes.iter().enumerate() {
            let name = mesh.name.clone().unwrap_or_else(|| format!("mesh{mi}"));
            let mut primitives = Vec::new();
            if let Some(&Some(node)) = replaced.get(mi) {
                // (lodgen on its own output: the old levels give way to new)
                warnings.push(Warning::new(
                    format!("meshes[{mi}] (mesh `{name}`)"),
                    format!(
                        "a level of node {node}'s MSFT_lod chain in the input: left out, \
                         replaced by the levels lodgen makes of its finest"
                    ),
                ));
                if self.strict {
                    let w = &warnings[warnings.len() - 1];
                    return Err(self.json_err(&format!("meshes[{mi}]"), w.message.clone()));
                }
                meshes.push(SourceMesh { name, primitives });
                continue;
            }
            for (pi, prim) in mesh.primitives.iter().enumerate() {
                let at = format!("meshes[{mi}].primitives[{pi}]");
                let place = format!("{at} (mesh `{name}`)");
                match self.primitive(root, buffers, prim, &at) {
                    Ok(Some(p)) if p.triangle_count() > 0 => {
                        let unread = PrimitiveReader {
                            r: self,
                            root,
                            buffers,
                            prim,
                            at: &at,
                        }
                        .unread(&p);
                        if !unread.is_empty() {
                            warnings.push(Warning::new(
                                place,
                                format!(
                                    "attributes {} are not carried into the output",
                                    unread.join(", ")
                                ),
                            ));
                        }
                        primitives.push(p)
                    }
                    Ok(Some(_)) => {
                        warnings.push(Warning::new(place, "no complete triangle: left out"))
                    }
                    Ok(None) => warnings.push(Warning::new(
                        place,
                        "points or lines: left out (lodgen writes triangles)",
                    )),
                    Err(e) if self.strict => return Err(e),
                    Err(e) => {
                        let reason = match &e.location {
                            Location::Json(p) if p != &at => format!("{p}: {}", e.kind),
                            _ => e.kind.to_string(),
                        };
                        warnings.push(Warning::new(
                            place,
                            format!("cannot be read, left out: {reason}"),
                        ))
                    }
                }
            }
            if primitives.is_empty() {
                warnings.push(Warning::new(
                    format!("meshes[{mi}] (mesh `{name}`)"),
                    "no triangles left: the mesh is left out of the output",
                ));
            }
            if let (true, Some(w)) = (self.strict, warnings.first()) {
                let at = w.at.split(' ').next().unwrap_or("").to_owned();
                return Err(self.json_err(&at, w.message.clone()));
            }
            meshes.push(SourceMesh { name, primitives });
        }
        Ok(meshes)
    }

    /// Reads one primitive; `None` for points and lines. The steps:
    /// [`PrimitiveReader::attributes`], [`PrimitiveReader::indices`],
    /// [`PrimitiveReader::targets`], [`PrimitiveReader::material`].
    fn primitive(
        &self,
        root: &Root,
        buffers: &[Vec<u8>],
        prim: &gltf::json::mesh::Primitive,
        at: &str,
    ) -> Result<Option<Primitive>, ReadError> {
        let mode = match prim.mode {
            Checked::Valid(m) => m,
            Checked::Invalid => {
                return Err(self.json_err(&format!("{at}.mode"), "invalid mode".to_owned()))
            }
        };
        if matches!(
            mode,
            Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip
        ) {
            return Ok(None);
        }
        let p = PrimitiveReader {
            r: self,
            root,
            buffers,
            prim,
            at,
        };
        let positions: Vec<[f32; 3]> = match p.attribute(&Semantic::Positions) {
            Some(a) => self.vectors(root, buffers, a, &format!("{at}.attributes.POSITION"))?,
            None => return Err(self.json_err(at, "primitive has no POSITION attribute".to_owned())),
        };
        let n = positions.len();
        let mut out = Primitive {
            positions,
            ..Primitive::default()
        };
        p.attributes(&mut out)?;
        out.indices = p.indices(mode, n)?;
        out.targets = p.targets(n)?;
        out.material = p.material()?;
        Ok(Some(out))
    }
}

/// One primitive being read, and where it is (`meshes[m].primitives[p]`).
struct PrimitiveReader<'a> {
    r: &'a Reader<'a>,
    root: &'a Root,
    buffers: &'a [Vec<u8>],
    prim: &'a gltf::json::mesh::Primitive,
    at: &'a str,
}

impl PrimitiveReader<'_> {
    fn attribute(&self, s: &Semantic) -> Option<usize> {
        self.prim
            .attributes
            .get(&Checked::Valid(s.clone()))
            .map(|i| i.value())
    }

    /// Attribute `name` as `N`-component vectors, `n` of them; `None` when absent.
    fn vectors<const N: usize>(
        &self,
        s: Semantic,
        name: &str,
        n: usize,
    ) -> Result<Option<Vec<[f32; N]>>, ReadError> {
        let Some(a) = self.attribute(&s) else {
            return Ok(None);
        };
        let here = format!("{}.attributes.{name}", self.at);
        let v = self.r.vectors(self.root, self.buffers, a, &here)?;
        self.r.same_count(v, n, self.at, name).map(Some)
    }

    /// A four-component attribute (TANGENT, COLOR_n, JOINTS_n, WEIGHTS_n);
    /// an RGB colour gets alpha 1.
    fn vec4(&self, s: Semantic, name: &str, n: usize) -> Result<Option<Vec<[f32; 4]>>, ReadError> {
        let Some(a) = self.attribute(&s) else {
            return Ok(None);
        };
        let here = format!("{}.attributes.{name}", self.at);
        let (values, dims) = self.r.accessor(self.root, self.buffers, a, &here)?;
        let v: Vec<[f32; 4]> = match dims {
            3 if name.starts_with("COLOR") => values
                .chunks_exact(3)
                .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, 1.0])
                .collect(),
            4 => self.r.vectors(self.root, self.buffers, a, &here)?,
            d => return Err(self.r.json_err(&here, format!("{name} has {d} components"))),
        };
        self.r.same_count(v, n, self.at, name).map(Some)
    }

    /// `JOINTS_set`, checked to hold u16 joint indices.
    fn joints(&self, set: u32, n: usize) -> Result<Option<Vec<[u16; 4]>>, ReadError> {
        let name = format!("JOINTS_{set}");
        let Some(j) = self.vec4(Semantic::Joints(set), &name, n)? else {
            return Ok(None);
        };
        if let Some(i) = j.iter().position(|q| {
            q.iter()
                .any(|&x| !(0.0..=65535.0).contains(&x) || x.fract() != 0.0)
        }) {
            return Err(self.r.json_err(
                &format!("{}.attributes.{name}", self.at),
                format!("vertex {i} has a joint index that is not a u16: {:?}", j[i]),
            ));
        }
        Ok(Some(j.iter().map(|q| q.map(|x| x as u16)).collect()))
    }

    /// Every attribute besides POSITION, each set up to the first missing one.
    fn attributes(&self, out: &mut Primitive) -> Result<(), ReadError> {
        let n = out.positions.len();
        out.normals = self.vectors(Semantic::Normals, "NORMAL", n)?;
        out.texcoords = self.vectors(Semantic::TexCoords(0), "TEXCOORD_0", n)?;
        out.tangents = self.vec4(Semantic::Tangents, "TANGENT", n)?;
        out.colors = self.vec4(Semantic::Colors(0), "COLOR_0", n)?;
        out.weights = self.vec4(Semantic::Weights(0), "WEIGHTS_0", n)?;
        out.joints = self.joints(0, n)?;
        let next = |len: usize| len as u32 + 1;
        while let Some(c) = self.vec4(
            Semantic::Colors(next(out.extra_colors.len())),
            &format!("COLOR_{}", next(out.extra_colors.len())),
            n,
        )? {
            out.extra_colors.push(c);
        }
        while let Some(j) = self.joints(next(out.extra_joints.len()), n)? {
            out.extra_joints.push(j);
        }
        while let Some(w) = self.vec4(
            Semantic::Weights(next(out.extra_weights.len())),
            &format!("WEIGHTS_{}", next(out.extra_weights.len())),
            n,
        )? {
            out.extra_weights.push(w);
        }
        while let Some(t) = self.vectors(
            Semantic::TexCoords(next(out.extra_texcoords.len())),
            &format!("TEXCOORD_{}", next(out.extra_texcoords.len())),
            n,
        )? {
            out.extra_texcoords.push(t);
        }
        Ok(())
    }

    /// The attributes of the primitive that [`Self::attributes`] did not
    /// read (application-specific `_NAME`s, a set after a gap), by name.
    fn unread(&self, p: &Primitive) -> Vec<String> {
        let read = |s: &Semantic| match s {
            Semantic::Positions | Semantic::Normals | Semantic::Tangents => true,
            Semantic::TexCoords(i) => (*i as usize) <= p.extra_texcoords.len(),
            Semantic::Colors(i) => (*i as usize) <= p.extra_colors.len(),
            Semantic::Joints(i) => (*i as usize) <= p.extra_joints.len(),
            Semantic::Weights(i) => (*i as usize) <= p.extra_weights.len(),
            _ => false,
        };
        self.prim
            .attributes
            .keys()
            .filter_map(|k| match k {
                Checked::Valid(s) if read(s) => None,
                Checked::Valid(s) => Some(s.to_string()),
                Checked::Invalid => Some("(invalid)".to_owned()),
            })
            .collect()
    }

    /// The triangle list: the index accessor (or `0..n`), each index
    /// checked, strips and fans unrolled.
    fn indices(&self, mode: Mode, n: usize) -> Result<Vec<u32>, ReadError> {
        let ind_at = format!("{}.indices", self.at);
        let raw: Vec<u32> = match self.prim.indices {
            Some(acc) => {
                let (values, dims) =
                    self.r
                        .accessor(self.root, self.buffers, acc.value(), &ind_at)?;
                if dims != 1 {
                    return Err(self.r.json_err(
                        &ind_at,
                        format!("index accessor {} is not SCALAR", acc.value()),
                    ));
                }
                let mut out = Vec::with_capacity(values.len());
                for (k, v) in values.into_iter().enumerate() {
                    if !(v >= 0.0 && v.fract() == 0.0 && v < n as f64) {
                        return Err(self.r.err(
                            Location::Json(format!("{ind_at}[{k}]")),
                            ErrorKind::IndexOutOfRange {
                                what: "index",
                                target: "vertex",
                                index: v as i64,
                                count: n,
                            },
                        ));
                    }
                    out.push(v as u32);
                }
                out
            }
            None => (0..n as u32).collect(),
        };
        match mode {
            Mode::TriangleStrip => Ok(strip_to_list(&raw)),
            Mode::TriangleFan => Ok(fan_to_list(&raw)),
            _ if raw.len() % 3 != 0 => Err(self.r.json_err(
                &ind_at,
                format!("{} indices is not a multiple of 3 for TRIANGLES", raw.len()),
            )),
            _ => Ok(raw),
        }
    }

    /// The morph targets: POSITION / NORMAL / TANGENT displacements, `n`
    /// each.
    fn targets(&self, n: usize) -> Result<Vec<MorphTarget>, ReadError> {
        let Some(targets) = &self.prim.targets else {
            return Ok(Vec::new());
        };
        let mut out = Vec::with_capacity(targets.len());
        for (t, target) in targets.iter().enumerate() {
            let read = |acc: Option<gltf::json::Index<gltf::json::Accessor>>, name: &str| {
                let Some(acc) = acc else {
                    return Ok(None);
                };
                let here = format!("{}.targets[{t}].{name}", self.at);
                let v: Vec<[f32; 3]> =
                    self.r
                        .vectors(self.root, self.buffers, acc.value(), &here)?;
                if v.len() != n {
                    return Err(self.r.json_err(
                        &here,
                        format!("{name} has {} entries, POSITION has {n}", v.len()),
                    ));
                }
                Ok(Some(v))
            };
            out.push(MorphTarget {
                positions: read(target.positions, "POSITION")?,
                normals: read(target.normals, "NORMAL")?,
                tangents: read(target.tangents, "TANGENT")?,
            });
        }
        Ok(out)
    }

    fn material(&self) -> Result<Option<usize>, ReadError> {
        let material = self.prim.material.map(|m| m.value());
        match material {
            Some(m) if m >= self.root.materials.len() => Err(self.r.json_err(
                &format!("{}.material", self.at),
                format!("material {m} does not exist"),
            )),
            _ => Ok(material),
        }
    }
}
