//! `lodgen view FILE`: a local HTTP server (127.0.0.1 only, `tiny_http`)
//! for the WebGL2 progressive-mesh viewer in `crates/lodgen/web/`.
//!
//! Owns loading what the viewer shows ([`ViewData`]: the split stream, its
//! level table and screen coverage), the routes, and the per-level summary
//! tests compare the browser against ([`ViewData::level_summary`]).
//!
//! Input: a glTF / GLB carrying `LODGEN_progressive` (see
//! [`crate::progressive`]; `lodgen IN -o OUT.glb --progressive` writes one);
//! or any mesh [`crate::io`] reads (a glTF without the extension too), run
//! through an in-memory pipeline: simplify to 2 %, levels 100 / 50 / 10 /
//! 2 %, stream-encoded. A glTF's scene is drawn in its own space: each
//! mesh once per node that draws it, through the nodes' world transforms
//! ([`world_mesh`]), as one mesh of their primitives. A mesh with vertex
//! attributes (UVs, normals, colours, …) or several primitives goes
//! through the wedge pipeline (seams kept, attributes in the stream);
//! other files are merged and streamed as positions.
//!
//! Routes: `/` (page), `/viewer.js`, `/info.json` (name, levels, coverage,
//! stream size), `/stream.bin` (the stream, honouring single `Range:
//! bytes=a-b` requests with 206 Partial Content so the page can fetch it in
//! chunks).

use crate::scene::{Origin, Primitive, Scene, SourceMesh};
use crate::{cli, io, progressive};
use anyhow::Context;
use glam::{Mat3, Mat4, Quat, Vec3};
use lodgen_pm::levels::{splits_for, LevelSpec};
use lodgen_pm::stream::{
    decode, decode_with_attributes, encode, encode_with_attributes, EncodeError, EncodeOptions,
    WedgeAttributes,
};
use lodgen_pm::{simplify, ProgressiveMesh, SimplifyOptions};
use serde_json::{json, Value};
use std::io::Cursor as IoCursor;
use std::path::Path;
use std::sync::Arc;
use tiny_http::{Header, Method, Request, Response, Server, StatusCode};

const INDEX_HTML: &str = include_str!("../web/index.html");
const VIEWER_JS: &str = include_str!("../web/viewer.js");
const LGPM_JS: &str = include_str!("../web/three/lgpm.js");
/// meshoptimizer's decoder (npm `meshoptimizer`, MIT), which decodes the
/// stream's columns.
const MESHOPT_DECODER_JS: &str = include_str!("../web/meshopt_decoder.mjs");

/// Bytes the page asks for per Range request unless `?chunk=` says
/// otherwise: small enough that the bunny arrives in a few dozen steps.
pub const DEFAULT_CHUNK: usize = 32 * 1024;

/// Reference viewport of the screen-coverage model (the glTF writer's: a
/// level may be drawn while its error projects to at most one pixel on a
/// 1920 × 1080 screen, coverage = projected bounding-sphere area / screen
/// area).
const REFERENCE_PIXELS: f64 = 1920.0 * 1080.0;

/// What the viewer shows.
#[derive(Clone, Debug)]
pub struct ViewData {
    pub name: String,
    /// The `LODGEN_progressive` stream.
    pub stream: Vec<u8>,
    /// Record count of each level, finest first (the `MSFT_lod` order).
    pub levels: Vec<usize>,
    /// `MSFT_screencoverage` values, finest first (may be empty).
    pub screen_coverage: Vec<f64>,
    /// `"gltf"` or `"pipeline"`.
    pub source: &'static str,
}

/// FNV-1a (32 bit) over the indices as little-endian `u32`: the hash the
/// page's `indexHash()` computes.
pub fn index_hash(triangles: &[[u32; 3]]) -> u32 {
    let mut h: u32 = 0x811c_9dc5;
    for &i in triangles.iter().flatten() {
        for b in i.to_le_bytes() {
            h ^= u32::from(b);
            h = h.wrapping_mul(0x0100_0193);
        }
    }
    h
}

/// FNV-1a (32 bit) over every vertex's position (`f32` bits, x y z), as
/// little-endian `u32`: the hash the page's `positionHash()` computes from
/// the positions it draws.
pub fn position_hash(positions: &[[f32; 3]]) -> u32 {
    let words: Vec<[u32; 3]> = positions.iter().map(|p| p.map(f32::to_bits)).collect();
    index_hash(&words)
}

/// FNV-1a (32 bit) over every corner's wedge group and values (`f32` bits),
/// as little-endian `u32`, corners in index order: the hash the page's
/// `attributeHash()` computes.
pub fn attribute_hash(wedges: &[[u32; 3]], attributes: &WedgeAttributes) -> u32 {
    let mut h: u32 = 0x811c_9dc5;
    let mut put = |x: u32| {
        for b in x.to_le_bytes() {
            h ^= u32::from(b);
            h = h.wrapping_mul(0x0100_0193);
        }
    };
    for &w in wedges.iter().flatten() {
        put(attributes.group(w));
        for v in attributes.wedge(w) {
            put(v.to_bits());
        }
    }
    h
}

/// Largest coverage at which an error of `h` (fraction of the bounding-box
/// diagonal) stays within one reference pixel: `π / (4 N h²)`.
fn coverage_for_error(h: f64) -> f64 {
    if h.is_nan() || h <= 0.0 {
        return f64::INFINITY;
    }
    std::f64::consts::PI / (4.0 * REFERENCE_PIXELS * h * h)
}

/// Screen coverage per level (finest first) from the recorded split
/// errors: level k's error is the largest error among the splits it lacks;
/// `s[k] = C(h[k+1])`, the last value the cull threshold `C(1)`; clamped to
/// `[0, 1]`, non-increasing.
fn pipeline_coverage(pm: &ProgressiveMesh, levels: &[usize], diagonal: f64) -> Vec<f64> {
    let mut suffix = vec![0.0f64; pm.len() + 1];
    for k in (0..pm.len()).rev() {
        suffix[k] = suffix[k + 1].max(f64::from(pm.splits[k].error));
    }
    let h: Vec<f64> = levels
        .iter()
        .map(|&k| suffix[k.min(pm.len())] / diagonal.max(f64::MIN_POSITIVE))
        .collect();
    let mut out: Vec<f64> = (0..h.len())
        .map(|k| {
            h.get(k + 1)
                .map_or(coverage_for_error(1.0), |&x| coverage_for_error(x))
        })
        .map(|c| c.clamp(0.0, 1.0))
        .collect();
    for k in 1..out.len() {
        out[k] = out[k].min(out[k - 1]);
    }
    out
}

/// The pipeline's levels, finest first (ratios of the input).
const PIPELINE_RATIOS: [f64; 4] = [1.0, 0.5, 0.1, 0.02];

/// The pipeline's [`ViewData`] of `pm`: its levels at [`PIPELINE_RATIOS`],
/// their screen coverage, and the stream `encode` makes with them.
fn pipeline_data(
    name: String,
    pm: &ProgressiveMesh,
    encode: impl FnOnce(&ProgressiveMesh, &[usize]) -> Result<Vec<u8>, EncodeError>,
) -> anyhow::Result<ViewData> {
    let levels: Vec<usize> = PIPELINE_RATIOS
        .iter()
        .map(|&r| splits_for(pm, LevelSpec::Ratio(r)))
        .collect();
    let diagonal = pm.mesh_at_splits(pm.len()).diagonal();
    let screen_coverage = pipeline_coverage(pm, &levels, diagonal);
    let stream = encode(pm, &levels).with_context(|| format!("encoding the stream of {name}"))?;
    Ok(ViewData {
        name,
        stream,
        levels,
        screen_coverage,
        source: "pipeline",
    })
}

impl ViewData {
    /// Load `path`: a glTF/GLB with `LODGEN_progressive`, or any readable
    /// mesh through the in-memory pipeline.
    pub fn load(path: &Path) -> anyhow::Result<ViewData> {
        // a file that cannot be opened: one message naming it, which the
        // caller's `viewing FILE` context joins into one line
        match std::fs::metadata(path) {
            Err(e) => anyhow::bail!("{}: {e}", path.display()),
            Ok(m) if m.is_dir() => anyhow::bail!("{}: is a directory", path.display()),
            Ok(m) if m.is_file() => {
                if let Err(e) = std::fs::File::open(path) {
                    anyhow::bail!("{}: {e}", path.display());
                }
            }
            Ok(_) => {}
        }
        let name = path
            .file_name()
            .map_or_else(|| "mesh".into(), |n| n.to_string_lossy().into_owned());
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        if ext == "glb" || ext == "gltf" {
            let found = progressive::read_file(path)
                .with_context(|| format!("reading {}", path.display()))?;
            if let Some((found, stream)) = found {
                decode(&stream)
                    .with_context(|| format!("{}: decoding the stream", path.display()))?;
                if found.streams > 1 {
                    // (the viewer streams one chain)
                    eprintln!(
                        "lodgen view: {} carries {} streams (one per mesh); showing the first, \
                         mesh {}'s; the others are not shown",
                        path.display(),
                        found.streams,
                        found.mesh
                    );
                }
                return Ok(ViewData {
                    name,
                    stream,
                    levels: found.levels,
                    screen_coverage: found.screen_coverage,
                    source: "gltf",
                });
            }
        }
        // any other mesh (or a glTF without the extension): the pipeline, on
        // every mesh the file's scene draws, merged (a glTF's: each
        // primitive once per node that draws it, in the scene's space)
        let scene = io::read_scene(path).with_context(|| format!("reading {}", path.display()))?;
        let world = world_mesh(&scene);
        let one = match (&world, scene.meshes.as_slice()) {
            (Some(w), _) => Some(w),
            (None, [mesh]) => Some(mesh),
            _ => None,
        };
        if let Some(mesh) = one {
            let attributes = crate::lod::stream_attributes(mesh);
            if !attributes.channels.is_empty() || mesh.primitives.len() > 1 {
                return Self::from_source_mesh(name, mesh, &attributes);
            }
            if let [p] = mesh.primitives.as_slice() {
                return Self::from_mesh(name, &p.positions, &p.indices);
            }
        }
        let mesh = cli::merged_mesh(&scene);
        Self::from_mesh(name, &mesh.positions, &mesh.indices())
    }

    /// The wedge pipeline for one mesh with attributes: QEM with the default
    /// attribute weights, levels as in [`Self::from_mesh`], every corner's
    /// attributes in the stream (`attributes` from
    /// [`crate::lod::stream_attributes`]).
    pub fn from_source_mesh(
        name: String,
        mesh: &crate::scene::SourceMesh,
        attributes: &WedgeAttributes,
    ) -> anyhow::Result<ViewData> {
        let out = crate::lod::simplify_mesh(
            mesh,
            &SimplifyOptions::DEFAULT.with_target_ratio(PIPELINE_RATIOS[3]),
            &crate::lod::AttributeWeights::DEFAULT,
        )
        .with_context(|| format!("simplifying {name}"))?;
        pipeline_data(name, &out.pm, |pm, levels| {
            encode_with_attributes(pm, levels, EncodeOptions::DEFAULT, attributes)
        })
    }

    /// The in-memory pipeline: simplify to 2 %, levels 100 / 50 / 10 / 2 %
    /// (finest first), 16-bit stream.
    pub fn from_mesh(
        name: String,
        positions: &[[f32; 3]],
        indices: &[u32],
    ) -> anyhow::Result<ViewData> {
        let out = simplify(
            positions,
            indices,
            &SimplifyOptions::DEFAULT.with_target_ratio(PIPELINE_RATIOS[3]),
        )
        .with_context(|| format!("simplifying {name}"))?;
        pipeline_data(name, &out.pm, |pm, levels| {
            Ok(encode(pm, levels, EncodeOptions::DEFAULT))
        })
    }

    /// Per level (finest first): record count, triangle and vertex counts
    /// and the [`index_hash`] and [`position_hash`] of the mesh the page must
    /// show after that many records, and with attributes the [`attribute_hash`] of its corners.
    /// What `lodgen view --print-levels` prints and the browser test asserts.
    pub fn level_summary(&self) -> anyhow::Result<Value> {
        let d = decode_with_attributes(&self.stream).context("decoding the stream")?;
        let mut cursor = d.pm.cursor();
        let levels: Vec<Value> = self
            .levels
            .iter()
            .map(|&k| {
                cursor.seek(k);
                let m = cursor.mesh();
                let mut level = json!({
                    "records": k,
                    "triangles": m.triangles.len(),
                    "vertices": m.positions.len(),
                    "indexHash": index_hash(&m.triangles),
                    "positionHash": position_hash(&m.positions),
                });
                if let (Some(a), Some(w)) = (&d.attributes, cursor.wedges()) {
                    level["attributeHash"] = json!(attribute_hash(w, a));
                }
                level
            })
            .collect();
        let channels: Vec<&str> = d
            .attributes
            .as_ref()
            .map(|a| a.channels.iter().map(|c| c.name.as_str()).collect())
            .unwrap_or_default();
        Ok(json!({
            "name": self.name,
            "splits": d.pm.len(),
            "streamBytes": self.stream.len(),
            "channels": channels,
            "levels": levels,
        }))
    }

    fn info(&self) -> Value {
        json!({
            "name": self.name,
            "source": self.source,
            "levels": self.levels,
            "screenCoverage": self.screen_coverage,
            "streamBytes": self.stream.len(),
            "chunkBytes": DEFAULT_CHUNK,
        })
    }
}

/// A glTF scene's drawn primitives in the scene's space, as one mesh: each
/// mesh's primitives once per node that draws it, through the node
/// hierarchy's world transforms (positions transformed, normals by the
/// inverse transpose, tangents' directions by the transform, normalised;
/// a mirroring transform turns the triangles' winding back). Morph
/// targets are left out. `None` for other formats (one space already).
fn world_mesh(scene: &Scene) -> Option<SourceMesh> {
    let Origin::Gltf { document, .. } = &scene.origin else {
        return None;
    };
    let roots: Vec<usize> = document
        .scenes
        .get(document.scene.map_or(0, |s| s.value()))
        .map(|s| s.nodes.iter().map(|n| n.value()).collect())
        .unwrap_or_default();
    let mut primitives = Vec::new();
    // depth first, in document order; a node is visited once (the
    // hierarchy is a forest; a broken one does not loop)
    let mut seen = vec![false; document.nodes.len()];
    let mut stack: Vec<(usize, Mat4)> = roots.iter().rev().map(|&n| (n, Mat4::IDENTITY)).collect();
    while let Some((n, parent)) = stack.pop() {
        let Some(node) = document
            .nodes
            .get(n)
            .filter(|_| !std::mem::replace(&mut seen[n], true))
        else {
            continue;
        };
        let world = parent * local_transform(node);
        if let Some(mesh) = node.mesh.and_then(|m| scene.meshes.get(m.value())) {
            primitives.extend(mesh.primitives.iter().map(|p| transformed(p, &world)));
        }
        for c in node.children.iter().flatten().rev() {
            stack.push((c.value(), world));
        }
    }
    Some(SourceMesh {
        name: String::new(),
        primitives,
    })
}

/// A node's transform: its matrix, or translation · rotation · scale.
fn local_transform(node: &gltf_json::Node) -> Mat4 {
    if let Some(m) = node.matrix {
        return Mat4::from_cols_array(&m);
    }
    let t = node.translation.map_or(Vec3::ZERO, Vec3::from);
    let r = node
        .rotation
        .map_or(Quat::IDENTITY, |q| Quat::from_array(q.0).normalize());
    let s = node.scale.map_or(Vec3::ONE, Vec3::from);
    Mat4::from_scale_rotation_translation(s, r, t)
}

/// `p` through `m` (see [`world_mesh`]).
fn transformed(p: &Primitive, m: &Mat4) -> Primitive {
    let normal = Mat3::from_mat4(*m).inverse().transpose();
    let linear = Mat3::from_mat4(*m);
    let mirror = linear.determinant() < 0.0;
    let unit = |v: Vec3| v.normalize_or_zero().to_array();
    let mut out = Primitive {
        positions: p
            .positions
            .iter()
            .map(|&x| m.transform_point3(Vec3::from(x)).to_array())
            .collect(),
        normals: p
            .normals
            .as_ref()
            .map(|n| n.iter().map(|&x| unit(normal * Vec3::from(x))).collect()),
        tangents: p.tangents.as_ref().map(|t| {
            t.iter()
                .map(|&[x, y, z, w]| {
                    let [x, y, z] = unit(linear * Vec3::new(x, y, z));
                    [x, y, z, if mirror { -w } else { w }]
                })
                .collect()
        }),
        targets: Vec::new(),
        ..p.clone()
    };
    if mirror {
        for c in out.indices.chunks_exact_mut(3) {
            c.swap(1, 2);
        }
    }
    out
}

/// A bound server; [`ViewServer::run`] answers until [`Stopper::stop`] (from [`ViewServer::stopper`]).
pub struct ViewServer {
    server: Arc<Server>,
    data: Arc<ViewData>,
    port: u16,
}

impl ViewServer {
    /// Bind 127.0.0.1:`port` (0 = any free port).
    pub fn bind(data: ViewData, port: u16) -> anyhow::Result<ViewServer> {
        let server = Server::http(("127.0.0.1", port))
            .map_err(|e| anyhow::anyhow!("binding 127.0.0.1:{port}: {e}"))?;
        let port = server
            .server_addr()
            .to_ip()
            .map(|a| a.port())
            .context("the server has no IP address")?;
        Ok(ViewServer {
            server: Arc::new(server),
            data: Arc::new(data),
            port,
        })
    }

    pub fn port(&self) -> u16 {
        self.port
    }

    pub fn url(&self) -> String {
        format!("http://127.0.0.1:{}/", self.port)
    }

    /// A handle that stops [`ViewServer::run`] from another thread.
    pub fn stopper(&self) -> Stopper {
        Stopper(Arc::clone(&self.server))
    }

    /// Answer requests until stopped.
    pub fn run(&self) {
        for request in self.server.incoming_requests() {
            // a client that hung up is not the server's problem
            let _ = respond(&self.data, request);
        }
    }
}

/// Stops a running [`ViewServer`].
#[derive(Clone)]
pub struct Stopper(Arc<Server>);

impl Stopper {
    pub fn stop(&self) {
        self.0.unblock();
    }
}

/// Add `Name: value` headers (malformed ones, which the constants and
/// numbers used here never are, are skipped rather than panicking).
fn with_headers<R: std::io::Read>(mut r: Response<R>, headers: &[String]) -> Response<R> {
    for h in headers {
        if let Ok(h) = h.parse::<Header>() {
            r.add_header(h);
        }
    }
    r
}

/// Parse a single `bytes=a-b`, `bytes=a-` or `bytes=-n` range against a body
/// of `len` bytes: `Some(Ok(start..end))`, `Some(Err(()))` when
/// unsatisfiable, `None` to serve the whole body (absent or multi-range).
fn parse_range(value: &str, len: usize) -> Option<Result<std::ops::Range<usize>, ()>> {
    let spec = value.trim().strip_prefix("bytes=")?;
    if spec.contains(',') {
        return None;
    }
    let (a, b) = spec.split_once('-')?;
    let (a, b) = (a.trim(), b.trim());
    let range = if a.is_empty() {
        let n: usize = b.parse().ok()?;
        len.saturating_sub(n)..len
    } else {
        let start: usize = a.parse().ok()?;
        let end = if b.is_empty() {
            len
        } else {
            let last = b.parse::<usize>().ok()?;
            // (last before first: an invalid range, so the header is
            // ignored — RFC 9110 §14.1.1)
            if last < start {
                return None;
            }
            last.saturating_add(1).min(len)
        };
        start..end
    };
    Some(if range.start < range.end {
        Ok(range)
    } else {
        Err(())
    })
}

fn respond(data: &ViewData, request: Request) -> std::io::Result<()> {
    if *request.method() != Method::Get && *request.method() != Method::Head {
        return request.respond(Response::from_string("method not allowed").with_status_code(405));
    }
    let path = request.url().split('?').next().unwrap_or("/").to_string();
    let (body, kind): (Vec<u8>, &str) = match path.as_str() {
        "/" | "/index.html" => (INDEX_HTML.as_bytes().to_vec(), "text/html; charset=utf-8"),
        "/viewer.js" => (
            VIEWER_JS.as_bytes().to_vec(),
            "text/javascript; charset=utf-8",
        ),
        "/three/lgpm.js" => (
            LGPM_JS.as_bytes().to_vec(),
            "text/javascript; charset=utf-8",
        ),
        "/meshopt_decoder.mjs" => (
            MESHOPT_DECODER_JS.as_bytes().to_vec(),
            "text/javascript; charset=utf-8",
        ),
        "/info.json" => (data.info().to_string().into_bytes(), "application/json"),
        "/stream.bin" => {
            let len = data.stream.len();
            let range = request
                .headers()
                .iter()
                .find(|h| h.field.equiv("Range"))
                .and_then(|h| parse_range(h.value.as_str(), len));
            return match range {
                Some(Ok(r)) => {
                    let part = data.stream[r.clone()].to_vec();
                    let n = part.len();
                    let resp = Response::new(
                        StatusCode(206),
                        Vec::new(),
                        IoCursor::new(part),
                        Some(n),
                        None,
                    );
                    request.respond(with_headers(
                        resp,
                        &[
                            "Content-Type: application/octet-stream".into(),
                            format!("Content-Range: bytes {}-{}/{len}", r.start, r.end - 1),
                            "Accept-Ranges: bytes".into(),
                            "Cache-Control: no-store".into(),
                        ],
                    ))
                }
                Some(Err(())) => request.respond(with_headers(
                    Response::from_string("range not satisfiable").with_status_code(416),
                    &[format!("Content-Range: bytes */{len}")],
                )),
                None => request.respond(with_headers(
                    Response::from_data(data.stream.clone()),
                    &[
                        "Content-Type: application/octet-stream".into(),
                        "Accept-Ranges: bytes".into(),
                        "Cache-Control: no-store".into(),
                    ],
                )),
            };
        }
        // browsers ask for it unprompted: answer "no icon", not an error
        "/favicon.ico" => return request.respond(Response::empty(204)),
        _ => return request.respond(Response::from_string("not found").with_status_code(404)),
    };
    request.respond(with_headers(
        Response::from_data(body),
        &[
            format!("Content-Type: {kind}"),
            "Cache-Control: no-store".into(),
        ],
    ))
}

/// `lodgen view FILE --port N`: load, bind 127.0.0.1, print the URL to
/// stderr and serve until the process ends.
pub fn serve(path: &Path, port: u16) -> anyhow::Result<()> {
    let data = ViewData::load(path)?;
    let server = ViewServer::bind(data, port)?;
    eprintln!(
        "lodgen view: serving {} on {}",
        path.display(),
        server.url()
    );
    server.run();
    Ok(())
}

/// `lodgen view --print-levels FILE`: the [`ViewData::level_summary`] JSON.
pub fn print_levels(path: &Path) -> anyhow::Result<String> {
    let data = ViewData::load(path)?;
    Ok(serde_json::to_string_pretty(&data.level_summary()?)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse_like_rfc_9110() {
        assert_eq!(parse_range("bytes=0-9", 100), Some(Ok(0..10)));
        assert_eq!(parse_range("bytes=90-", 100), Some(Ok(90..100)));
        assert_eq!(parse_range("bytes=-5", 100), Some(Ok(95..100)));
        assert_eq!(parse_range("bytes=50-500", 100), Some(Ok(50..100)));
        assert_eq!(parse_range("bytes=100-", 100), Some(Err(())));
        assert_eq!(parse_range("bytes=0-1,5-6", 100), None);
        assert_eq!(parse_range("items=0-1", 100), None);
        assert_eq!(parse_range("bytes=x-1", 100), None);
        assert_eq!(parse_range("bytes=5-2", 100), None);
    }

    #[test]
    fn fnv_matches_the_reference_values() {
        // FNV-1a 32 of the empty input and of the bytes 00 00 00 00
        assert_eq!(index_hash(&[]), 0x811c_9dc5);
        let mut h: u32 = 0x811c_9dc5;
        for _ in 0..12 {
            h = h.wrapping_mul(0x0100_0193);
        }
        assert_eq!(index_hash(&[[0, 0, 0]]), h);
    }

    #[test]
    fn coverage_follows_the_one_pixel_model() {
        // C(h) = π / (4 N h²); h = 0.001 → 0.3788 (the writer's worked example)
        assert!((coverage_for_error(0.001) - std::f64::consts::PI / 8.2944).abs() < 1e-9);
        assert_eq!(coverage_for_error(0.0), f64::INFINITY);
    }
}
