//! Wavefront OBJ reader (plus the `Kd`/`d` part of MTL).
//!
//! Statements read: `v x y z` (a trailing `w` or vertex colour is ignored),
//! `vt u [v]`, `vn x y z`, `f` with corners `v`, `v/vt`, `v//vn` or
//! `v/vt/vn` (negative indices are relative to the vertices defined so far),
//! `o name`, `usemtl name`, `mtllib file...`. Every other statement (`g`,
//! `s`, `l`, `p`, `vp`, `cstype`, ...) is ignored. Line continuations (`\`)
//! are not supported.
//!
//! Scene layout:
//! - one [`SourceMesh`] per `o` object, in file order; faces before the first
//!   `o` go to a mesh named after the file stem. Objects without faces are
//!   dropped. `g` groups do not split meshes: groups are face sets that may
//!   overlap, and splitting by them would tear the surface.
//! - within a mesh, one [`Primitive`] per material (`usemtl`), in order of
//!   first use; faces before any `usemtl` form a primitive without material.
//! - a corner's `(v, vt, vn)` triple is one primitive vertex; vertices are
//!   numbered in order of first use and unreferenced `v` lines are dropped.
//! - texture coordinates are converted to glTF's convention (`v' = 1 - v`,
//!   origin at the top left). A primitive has texcoords when any of its
//!   corners has one (corners without get `[0, 0]`) and normals only when
//!   all of its corners have one (else the writer recomputes them).
//! - positive indices must refer to vertices defined above the face.
//!
//! Materials: [`Scene::materials`] lists the `usemtl` names in order of first
//! use. `mtllib` files are looked up beside the OBJ; a missing or unreadable
//! library is not an error (the material then has no base colour) but a
//! [`Scene::warnings`] entry, as is each texture map (`map_Kd`…) of a used
//! material, which lodgen does not carry. `Kd` becomes the base colour, with
//! alpha from `d` (or `1 - Tr`); malformed MTL lines are ignored. A UTF-8
//! byte order mark before the first line is skipped ([`super::read_scene`]).

use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

use super::common::far_offset;
use super::common::{check_not_empty, file_stem, lines};
use super::error::{ErrorKind, Location, ReadError};
use super::obj_parse::{first_vertex, parse_batch, Chunk, Counts, Event, CHUNK_BYTES, NONE};
use crate::scene::{Material, Origin, Primitive, Scene, SourceMesh, Warning};

/// How much of a file is read and parsed at once (whole lines; a longer
/// line grows it).
const BATCH_BYTES: usize = 32 << 20;

/// Reads an OBJ file; `mtllib` files are read from the directory of `path`.
pub fn read_obj(src: &[u8], path: &Path) -> Result<Scene, ReadError> {
    read_obj_with_materials(src, path, mtl_beside(path))
}

/// Reads an OBJ file, asking `load_mtl` for the bytes of each `mtllib`
/// file name; `None` means the library is missing (not an error).
pub fn read_obj_with_materials(
    src: &[u8],
    path: &Path,
    load_mtl: impl FnMut(&str) -> Option<Vec<u8>>,
) -> Result<Scene, ReadError> {
    let mut b = Builder::new(path, load_mtl);
    b.offset = first_vertex(src).and_then(far_offset);
    let (chunks, _) = parse_batch(src, Counts::default(), CHUNK_BYTES, path, b.offset);
    b.add_chunks(chunks)?;
    b.finish()
}

/// Reads an OBJ file from `file` whose first bytes, `head`, were read
/// already, a batch of lines at a time (the file is never held whole).
pub(super) fn read_obj_file(
    head: Vec<u8>,
    file: impl Read + Send,
    path: &Path,
) -> Result<Scene, ReadError> {
    read_obj_batches(head, file, path, BATCH_BYTES, CHUNK_BYTES)
}

/// Whole lines read from the file: `buf[..cut]`, the rest carried to the
/// next batch.
struct Batch {
    buf: Vec<u8>,
    cut: usize,
    end_of_file: bool,
}

/// Fills `buf` (which holds the previous batch's unfinished line) up to
/// `capacity` bytes and cuts after its last line end; a line longer than
/// the buffer doubles `capacity`.
fn read_batch(
    mut buf: Vec<u8>,
    file: &mut impl Read,
    capacity: &mut usize,
) -> std::io::Result<Batch> {
    loop {
        // (`read_to_end` fills spare capacity without zeroing it first)
        let want = capacity.saturating_sub(buf.len());
        buf.reserve(want);
        let n = file.take(want as u64).read_to_end(&mut buf)?;
        if n < want {
            let cut = buf.len();
            return Ok(Batch {
                buf,
                cut,
                end_of_file: true,
            });
        }
        match memchr::memrchr(b'\n', &buf) {
            Some(i) => {
                return Ok(Batch {
                    buf,
                    cut: i + 1,
                    end_of_file: false,
                })
            }
            None => *capacity = (*capacity * 2).max(1), // one line longer than the buffer
        }
    }
}

/// The batches in a pipeline: while one batch is parsed (on every core),
/// the previous batch's chunks go into the primitives and the next batch
/// is read. Errors come in file order: a batch's parse error before a
/// read error after it.
fn read_obj_batches(
    buf: Vec<u8>,
    mut file: impl Read + Send,
    path: &Path,
    batch_bytes: usize,
    chunk_bytes: usize,
) -> Result<Scene, ReadError> {
    let io_err = |e| ReadError::new(path, Location::File, ErrorKind::Io).with_source(e);
    let mut b = Builder::new(path, mtl_beside(path));
    let mut counts = Counts::default();
    let mut capacity = batch_bytes.max(buf.len());
    let mut batch = read_batch(buf, &mut file, &mut capacity).map_err(io_err)?;
    // (a file whose first `v` is beyond the first batch is read where it is)
    b.offset = first_vertex(&batch.buf[..batch.cut]).and_then(far_offset);
    let offset = b.offset;
    let mut pending: Option<Vec<Chunk>> = None;
    let mut spare: Vec<u8> = Vec::new();
    loop {
        let Batch {
            buf,
            cut,
            end_of_file,
        } = batch;
        let ((added, next), (chunks, after)) = rayon::join(
            || {
                let added = pending.take().map_or(Ok(()), |c| b.add_chunks(c));
                let next = (!end_of_file && added.is_ok()).then(|| {
                    let mut carried = std::mem::take(&mut spare);
                    carried.clear();
                    carried.extend_from_slice(&buf[cut..]);
                    read_batch(carried, &mut file, &mut capacity)
                });
                (added, next)
            },
            || parse_batch(&buf[..cut], counts, chunk_bytes, path, offset),
        );
        added?;
        counts = after;
        spare = buf;
        match next {
            None => {
                pending = Some(chunks);
                break;
            }
            Some(Ok(next)) => {
                pending = Some(chunks);
                batch = next;
            }
            Some(Err(e)) => {
                // this batch's own error comes first
                b.add_chunks(chunks)?;
                return Err(io_err(e));
            }
        }
    }
    drop(spare);
    if let Some(chunks) = pending {
        b.add_chunks(chunks)?;
    }
    b.finish()
}

/// `mtllib` files beside the OBJ.
fn mtl_beside(path: &Path) -> impl FnMut(&str) -> Option<Vec<u8>> {
    let dir = path.parent().map(Path::to_path_buf);
    move |name| {
        let dir = dir.as_deref()?;
        std::fs::read(dir.join(name)).ok()
    }
}

/// The text after the keyword, trimmed (names may contain spaces).
fn rest_of_line(line: &str, keyword: &str) -> String {
    let start = line.find(keyword).map_or(0, |i| i + keyword.len());
    line[start..].trim().to_owned()
}

/// MTL statements naming a texture map (or a bump / displacement map).
const MTL_MAPS: [&str; 12] = [
    "map_Ka", "map_Kd", "map_Ks", "map_Ns", "map_d", "map_Bump", "map_bump", "bump", "disp",
    "decal", "refl", "norm",
];

/// Collects `Kd` (and `d`/`Tr` for alpha) per `newmtl`, and the texture
/// maps each names (`map_Kd file`…: `maps`, which lodgen does not carry).
fn parse_mtl(
    text: &str,
    colors: &mut BTreeMap<String, [f32; 4]>,
    maps: &mut BTreeMap<String, Vec<String>>,
) {
    let mut current: Option<String> = None;
    let mut alpha: Option<f32> = None;
    let mut seen_d = false;
    for (_, line) in lines(text) {
        let mut tokens = line.split_ascii_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        let number = |t: Option<&str>| {
            t.and_then(|t| t.parse::<f32>().ok())
                .filter(|x| x.is_finite())
        };
        match keyword {
            "newmtl" => {
                current = Some(rest_of_line(line, keyword));
                alpha = None;
                seen_d = false;
            }
            "Kd" => {
                let (r, g, bl) = (
                    number(tokens.next()),
                    number(tokens.next()),
                    number(tokens.next()),
                );
                if let (Some(name), Some(r), Some(g), Some(bl)) = (&current, r, g, bl) {
                    colors.insert(name.clone(), [r, g, bl, alpha.unwrap_or(1.0)]);
                }
            }
            k if MTL_MAPS.contains(&k) => {
                if let Some(name) = &current {
                    let file = line.split_ascii_whitespace().last().unwrap_or("");
                    maps.entry(name.clone())
                        .or_default()
                        .push(format!("{k} {file}"));
                }
            }
            "d" | "Tr" => {
                if let Some(x) = number(tokens.next()) {
                    if keyword == "d" {
                        alpha = Some(x);
                        seen_d = true;
                    } else if !seen_d {
                        alpha = Some(1.0 - x);
                    }
                    if let (Some(c), Some(a)) =
                        (current.as_ref().and_then(|n| colors.get_mut(n)), alpha)
                    {
                        c[3] = a;
                    }
                }
            }
            _ => {}
        }
    }
}

/// One corner record in the per-position chain: which primitive, which
/// `vt`/`vn`, the primitive-local vertex and the next record of the chain.
struct Wedge {
    prim: u32,
    vt: u32,
    vn: u32,
    local: u32,
    next: u32,
}

struct PrimBuilder {
    material: Option<usize>,
    /// Per local vertex: index into the global `v` pool, and into `vt` /
    /// `vn` (empty while no corner of the primitive had one).
    verts: Vec<u32>,
    verts_vt: Vec<u32>,
    verts_vn: Vec<u32>,
    indices: Vec<u32>,
}

struct MeshBuilder {
    name: String,
    prims: Vec<usize>,
}

/// Puts the parsed chunks' corners into primitives, in file order.
struct Builder<'a, L> {
    path: &'a Path,
    load_mtl: L,
    positions: Vec<[f32; 3]>,
    /// Per `v`, its `v x y z r g b` colour (empty: no `v` has one).
    colors: Vec<[f32; 3]>,
    texcoords: Vec<[f32; 2]>,
    normals: Vec<[f32; 3]>,
    /// Per `v`: first wedge of its chain, or `NONE`; while `simple`, the
    /// vertex of the one primitive instead.
    head: Vec<u32>,
    /// One primitive so far and no corner with `vt` / `vn`: a corner is its
    /// `v` alone and `head` maps it to its vertex without wedges.
    simple: bool,
    wedges: Vec<Wedge>,
    prims: Vec<PrimBuilder>,
    meshes: Vec<MeshBuilder>,
    materials: Vec<String>,
    material_ids: BTreeMap<String, usize>,
    mtl_colors: BTreeMap<String, [f32; 4]>,
    /// Per material, the texture maps its library names (not carried).
    mtl_maps: BTreeMap<String, Vec<String>>,
    /// What the scene will not carry (missing libraries, texture maps).
    warnings: Vec<Warning>,
    /// Subtracted from every position (far from the origin: `Origin::Moved`).
    offset: Option<[f64; 3]>,
    pending_name: Option<String>,
    current_material: Option<usize>,
    current_mesh: Option<usize>,
    current_prim: Option<usize>,
}

impl<'a, L: FnMut(&str) -> Option<Vec<u8>>> Builder<'a, L> {
    fn new(path: &'a Path, load_mtl: L) -> Self {
        Builder {
            path,
            load_mtl,
            positions: Vec::new(),
            colors: Vec::new(),
            texcoords: Vec::new(),
            normals: Vec::new(),
            head: Vec::new(),
            simple: true,
            wedges: Vec::new(),
            prims: Vec::new(),
            meshes: Vec::new(),
            materials: Vec::new(),
            material_ids: BTreeMap::new(),
            mtl_colors: BTreeMap::new(),
            mtl_maps: BTreeMap::new(),
            warnings: Vec::new(),
            offset: None,
            pending_name: None,
            current_material: None,
            current_mesh: None,
            current_prim: None,
        }
    }

    /// Adds the chunks of a batch in order; the first chunk's error is the
    /// file's error.
    fn add_chunks(&mut self, mut chunks: Vec<Chunk>) -> Result<(), ReadError> {
        if let Some(e) = chunks.iter_mut().find_map(|c| c.error.take()) {
            return Err(e);
        }
        for chunk in chunks {
            self.add_chunk(chunk);
        }
        Ok(())
    }

    fn add_chunk(&mut self, mut c: Chunk) {
        // (colours, once a `v` has one: white for the positions without)
        if !c.colors.is_empty() || !self.colors.is_empty() {
            self.colors.resize(self.positions.len(), [1.0; 3]);
            c.colors.resize(c.positions.len(), [1.0; 3]);
            self.colors.append(&mut c.colors);
        }
        self.positions.append(&mut c.positions);
        self.head.resize(self.positions.len(), NONE);
        self.texcoords.append(&mut c.texcoords);
        self.normals.append(&mut c.normals);
        let mut at = 0;
        for (corner, event) in std::mem::take(&mut c.events) {
            self.corners(&c, at..corner);
            at = corner;
            self.event(event);
        }
        self.corners(&c, at..c.v.len());
    }

    fn event(&mut self, event: Event) {
        match event {
            Event::Object(name) => {
                self.pending_name = Some(name);
                self.current_mesh = None;
                self.current_prim = None;
            }
            Event::Material(name) => {
                let next = self.materials.len();
                let index = *self.material_ids.entry(name.clone()).or_insert(next);
                if index == next {
                    self.materials.push(name);
                }
                self.current_material = Some(index);
                self.current_prim = None;
            }
            Event::Library(files) => {
                for file in files {
                    match (self.load_mtl)(&file) {
                        Some(bytes) => parse_mtl(
                            &String::from_utf8_lossy(&bytes),
                            &mut self.mtl_colors,
                            &mut self.mtl_maps,
                        ),
                        None => self.warnings.push(Warning::new(
                            format!("mtllib {file}"),
                            "material library not found beside the OBJ: its materials are \
                             written without their colours",
                        )),
                    }
                }
            }
        }
    }

    /// The corners `range` of chunk `c` (whole triangles) into the current
    /// primitive.
    fn corners(&mut self, c: &Chunk, range: std::ops::Range<usize>) {
        if range.is_empty() {
            return;
        }
        let prim = self.prim();
        if self.simple && c.vt.is_empty() && c.vn.is_empty() {
            let p = &mut self.prims[prim];
            p.indices.reserve(range.len());
            for &v in &c.v[range] {
                let local = &mut self.head[v as usize];
                if *local == NONE {
                    *local = p.verts.len() as u32;
                    p.verts.push(v);
                }
                p.indices.push(*local);
            }
            return;
        }
        for i in range {
            let vt = c.vt.get(i).copied().unwrap_or(NONE);
            let vn = c.vn.get(i).copied().unwrap_or(NONE);
            let local = self.corner(prim, c.v[i], vt, vn);
            self.prims[prim].indices.push(local);
        }
    }

    /// Leaves the simple form: a wedge for every vertex of primitive 0.
    fn leave_simple(&mut self) {
        if !self.simple {
            return;
        }
        self.simple = false;
        for h in &mut self.head {
            if *h != NONE {
                self.wedges.push(Wedge {
                    prim: 0,
                    vt: NONE,
                    vn: NONE,
                    local: *h,
                    next: NONE,
                });
                *h = (self.wedges.len() - 1) as u32;
            }
        }
    }

    /// The primitive that receives faces now, created on first use.
    fn prim(&mut self) -> usize {
        if let Some(p) = self.current_prim {
            return p;
        }
        let mesh = match self.current_mesh {
            Some(m) => m,
            None => {
                let name = self
                    .pending_name
                    .take()
                    .filter(|n| !n.is_empty())
                    .unwrap_or_else(|| file_stem(self.path));
                self.meshes.push(MeshBuilder {
                    name,
                    prims: Vec::new(),
                });
                self.meshes.len() - 1
            }
        };
        self.current_mesh = Some(mesh);
        let material = self.current_material;
        let existing = self.meshes[mesh]
            .prims
            .iter()
            .copied()
            .find(|&p| self.prims[p].material == material);
        let p = match existing {
            Some(p) => p,
            None => {
                if !self.prims.is_empty() {
                    self.leave_simple();
                }
                self.prims.push(PrimBuilder {
                    material,
                    verts: Vec::new(),
                    verts_vt: Vec::new(),
                    verts_vn: Vec::new(),
                    indices: Vec::new(),
                });
                self.meshes[mesh].prims.push(self.prims.len() - 1);
                self.prims.len() - 1
            }
        };
        self.current_prim = Some(p);
        p
    }

    /// The primitive-local vertex of corner `(v, vt, vn)`, created on first use.
    fn corner(&mut self, prim: usize, v: u32, vt: u32, vn: u32) -> u32 {
        if vt != NONE || vn != NONE {
            self.leave_simple();
        }
        if self.simple {
            let local = &mut self.head[v as usize];
            let p = &mut self.prims[prim];
            if *local == NONE {
                *local = p.verts.len() as u32;
                p.verts.push(v);
            }
            return *local;
        }
        let prim32 = prim as u32;
        let mut w = self.head[v as usize];
        while w != NONE {
            let wedge = &self.wedges[w as usize];
            if wedge.prim == prim32 && wedge.vt == vt && wedge.vn == vn {
                return wedge.local;
            }
            w = wedge.next;
        }
        let p = &mut self.prims[prim];
        let local = p.verts.len() as u32;
        p.verts.push(v);
        for (list, value) in [(&mut p.verts_vt, vt), (&mut p.verts_vn, vn)] {
            if value != NONE || !list.is_empty() {
                list.resize(local as usize, NONE);
                list.push(value);
            }
        }
        self.wedges.push(Wedge {
            prim: prim32,
            vt,
            vn,
            local,
            next: self.head[v as usize],
        });
        self.head[v as usize] = (self.wedges.len() - 1) as u32;
        local
    }

    fn finish(mut self) -> Result<Scene, ReadError> {
        // what the primitives no longer need goes first
        self.head = Vec::new();
        self.wedges = Vec::new();
        for name in &self.materials {
            for map in self.mtl_maps.get(name).map_or(&[][..], Vec::as_slice) {
                self.warnings.push(Warning::new(
                    format!("material `{name}`"),
                    format!("{map}: texture maps are not carried (the base colour is)"),
                ));
            }
        }
        let materials = self
            .materials
            .into_iter()
            .map(|name| Material {
                base_color: self.mtl_colors.get(&name).copied(),
                name,
            })
            .collect();
        let mut prims: Vec<Option<PrimBuilder>> = self.prims.into_iter().map(Some).collect();
        let meshes = self
            .meshes
            .into_iter()
            .map(|m| {
                // (sized exactly: `filter_map(..).collect()` reserves four `Primitive`s, ~1.6 KB,
                // which made an object per face cost 160 bytes per input byte)
                let mut primitives = Vec::with_capacity(m.prims.len());
                primitives.extend(m.prims.iter().filter_map(|&p| prims[p].take()).map(|p| {
                    let colors = (!self.colors.is_empty()).then_some(&self.colors[..]);
                    build_primitive(p, &self.positions, colors, &self.texcoords, &self.normals)
                }));
                SourceMesh {
                    name: m.name,
                    primitives,
                }
            })
            .collect();
        let scene = Scene {
            meshes,
            materials,
            origin: match self.offset {
                Some(offset) => Origin::Moved { offset },
                None => Origin::Flat,
            },
            warnings: self.warnings,
        };
        check_not_empty(&scene, self.path)?;
        Ok(scene)
    }
}

fn build_primitive(
    p: PrimBuilder,
    positions: &[[f32; 3]],
    colors: Option<&[[f32; 3]]>,
    texcoords: &[[f32; 2]],
    normals: &[[f32; 3]],
) -> Primitive {
    let has_uv = p.verts_vt.iter().any(|&t| t != NONE);
    // (a corner without `vn` would have made the list)
    let has_normals = !p.verts_vn.is_empty() && p.verts_vn.iter().all(|&n| n != NONE);
    Primitive {
        material: p.material,
        positions: p.verts.iter().map(|&v| positions[v as usize]).collect(),
        texcoords: has_uv.then(|| {
            p.verts_vt
                .iter()
                .map(|&t| texcoords.get(t as usize).copied().unwrap_or([0.0; 2]))
                .collect()
        }),
        normals: has_normals.then(|| p.verts_vn.iter().map(|&n| normals[n as usize]).collect()),
        colors: colors.map(|c| {
            let at = |v: u32| c.get(v as usize).copied().unwrap_or([1.0; 3]);
            p.verts
                .iter()
                .map(|&v| at(v))
                .map(|[r, g, b]| [r, g, b, 1.0])
                .collect()
        }),
        indices: p.indices,
        ..Primitive::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file using every statement, polygons, relative indices, objects,
    /// materials, and faces before and after the first corner with `vt`.
    fn sample() -> String {
        let mut s = String::from("# sample\nmtllib none.mtl\n");
        for i in 0..40 {
            let (x, y) = ((i % 7) as f32 * 0.5, (i / 7) as f32 * 0.25);
            s += &format!("v {x} {y} {}\nv {} {y} 0.5\n", i % 3, x + 1.0);
        }
        s += "f 1 2 3\nf 2 3 4 5\nf -1 -2 -3\n";
        s += "vt 0 0\nvt 1 0.5\nvn 0 0 1\n";
        for i in 0..30 {
            let a = i + 1;
            match i % 6 {
                0 => s += &format!("o part{i}\n"),
                1 => s += &format!("usemtl m{}\n", i % 4),
                2 => s += "g group\ns off\n",
                _ => {}
            }
            s += &format!(
                "f {a} {} {}\nf {a}/1 {}/2 {}/1/1 {}\nf -3//1 -2//1 -1//1\n",
                a + 1,
                a + 2,
                a + 1,
                a + 2,
                a + 3
            );
        }
        s
    }

    fn read(text: &str, batch: usize, chunk: usize) -> Result<Scene, ReadError> {
        let cursor = std::io::Cursor::new(text.as_bytes().to_vec());
        read_obj_batches(Vec::new(), cursor, Path::new("t.obj"), batch, chunk)
    }

    fn same(a: &Result<Scene, ReadError>, b: &Result<Scene, ReadError>) -> bool {
        match (a, b) {
            (Ok(a), Ok(b)) => a.meshes == b.meshes && a.materials == b.materials,
            (Err(a), Err(b)) => a.to_string() == b.to_string(),
            _ => false,
        }
    }

    /// Chunks and batches of any size read what one chunk reads: the same
    /// meshes, and for a bad line anywhere the same error at the same line.
    /// (Fails when a chunk starts at the wrong counts or line, or when an
    /// event lands between the wrong corners.)
    #[test]
    fn any_cut_reads_what_one_chunk_reads() {
        let text = sample();
        let all = text.len() + 1;
        let whole = read(&text, all, all);
        assert!(whole.is_ok());
        let sizes = [(1, 1), (7, 3), (64, 16), (100, 1), (4096, 50), (all, 33)];
        for (batch, chunk) in sizes {
            let r = read(&text, batch, chunk);
            assert!(
                same(&whole, &r),
                "{batch} {chunk} {:?} {:?}",
                whole.as_ref().map(|s| &s.meshes),
                r.as_ref().map(|s| &s.meshes)
            );
        }
        let lines: Vec<&str> = text.lines().collect();
        for (i, bad) in [
            (5, "v 1 x 2"),
            (90, "f 1 2 999"),
            (100, "f 0 1 2"),
            (120, "vt"),
        ]
        .into_iter()
        .chain((0..lines.len()).step_by(37).map(|i| (i, "f 1 2")))
        {
            let mut broken = lines.clone();
            broken[i] = bad;
            let broken = broken.join("\n");
            let one = read(&broken, all, all);
            assert_eq!(one.as_ref().err().and_then(|e| e.line()), Some(i + 1));
            for (batch, chunk) in sizes {
                assert!(
                    same(&one, &read(&broken, batch, chunk)),
                    "{bad} {batch} {chunk}"
                );
            }
        }
    }

    /// Fails every read once `limit` bytes were given.
    struct FailAfter {
        data: Vec<u8>,
        at: usize,
        limit: usize,
    }

    impl Read for FailAfter {
        fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
            if self.at >= self.limit {
                return Err(std::io::Error::other("the disk went away"));
            }
            let n = out.len().min(self.limit - self.at);
            let n = n.min(self.data.len() - self.at.min(self.data.len()));
            out[..n].copy_from_slice(&self.data[self.at..self.at + n]);
            self.at += n;
            Ok(n)
        }
    }

    /// A read error is the file's error unless a line before it is bad
    /// (batches are read while the one before is parsed).
    #[test]
    fn a_bad_line_before_a_read_error_is_the_error() {
        let text = sample();
        let lines: Vec<&str> = text.lines().collect();
        let read_failing = |text: &str, limit: usize, batch: usize| {
            let r = FailAfter {
                data: text.as_bytes().to_vec(),
                at: 0,
                limit,
            };
            read_obj_batches(Vec::new(), r, Path::new("t.obj"), batch, 16)
        };
        let half = text.len() / 2;
        for batch in [64, 300, 4096] {
            let e = read_failing(&text, half, batch).err();
            assert!(
                e.as_ref().is_some_and(|e| *e.kind == ErrorKind::Io),
                "{batch}: {e:?}"
            );
            let mut broken = lines.clone();
            broken[2] = "v 1 x 2";
            let broken = broken.join("\n");
            let e = read_failing(&broken, half, batch).err();
            // (a first batch that cannot be read whole is the read error)
            let expected = if batch < half { Some(3) } else { None };
            assert_eq!(e.and_then(|e| e.line()), expected, "{batch}");
            let mut late = lines.clone();
            let last = late.len() - 1;
            late[last] = "v 1 x 2";
            let late = late.join("\n");
            let e = read_failing(&late, half, batch).err();
            assert!(
                e.as_ref().is_some_and(|e| *e.kind == ErrorKind::Io),
                "{batch}: {e:?}"
            );
        }
    }
}
