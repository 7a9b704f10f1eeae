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
//! library is not an error (the material then has no base colour). `Kd`
//! becomes the base colour, with alpha from `d` (or `1 - Tr`); malformed MTL
//! lines are ignored.

use std::collections::BTreeMap;
use std::path::Path;

use super::common::{check_not_empty, file_stem, lines, parse_coords, parse_f32};
use super::error::{ErrorKind, Location, ReadError};
use crate::scene::{Material, Origin, Primitive, Scene, SourceMesh};

const NONE: u32 = u32::MAX;

/// Reads an OBJ file; `mtllib` files are read from the directory of `path`.
pub fn read_obj(src: &[u8], path: &Path) -> Result<Scene, ReadError> {
    let dir = path.parent().map(Path::to_path_buf);
    read_obj_with_materials(src, path, |name| {
        let dir = dir.as_deref()?;
        std::fs::read(dir.join(name)).ok()
    })
}

/// Reads an OBJ file, asking `load_mtl` for the bytes of each `mtllib`
/// file name; `None` means the library is missing (not an error).
pub fn read_obj_with_materials(
    src: &[u8],
    path: &Path,
    mut load_mtl: impl FnMut(&str) -> Option<Vec<u8>>,
) -> Result<Scene, ReadError> {
    let text = String::from_utf8_lossy(src);
    let mut b = Builder::new(path);
    for (line_no, line) in lines(&text) {
        let mut tokens = line.split_ascii_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let p: [f32; 3] = parse_coords(&mut tokens, path, line_no, "vertex coordinate")?;
                b.positions.push(p);
                b.head.push(NONE);
            }
            "vt" => {
                let u = parse_coords::<1>(&mut tokens, path, line_no, "texture coordinate")?[0];
                let v = match tokens.next() {
                    Some(t) if !t.starts_with('#') => {
                        parse_f32(t, path, line_no, "texture coordinate")?
                    }
                    _ => 0.0,
                };
                b.texcoords.push([u, 1.0 - v]);
            }
            "vn" => {
                let n: [f32; 3] = parse_coords(&mut tokens, path, line_no, "normal")?;
                b.normals.push(n);
            }
            "f" => b.face(tokens, line_no)?,
            "o" => {
                b.pending_name = Some(rest_of_line(line, keyword));
                b.current_mesh = None;
                b.current_prim = None;
            }
            "usemtl" => {
                let name = rest_of_line(line, keyword);
                let next = b.materials.len();
                let index = *b.material_ids.entry(name.clone()).or_insert(next);
                if index == next {
                    b.materials.push(name);
                }
                b.current_material = Some(index);
                b.current_prim = None;
            }
            "mtllib" => {
                for file in tokens.take_while(|t| !t.starts_with('#')) {
                    if let Some(bytes) = load_mtl(file) {
                        parse_mtl(&String::from_utf8_lossy(&bytes), &mut b.mtl_colors);
                    }
                }
            }
            _ => {}
        }
    }
    let scene = b.finish();
    check_not_empty(&scene, path)?;
    Ok(scene)
}

/// The text after the keyword, trimmed (names may contain spaces).
fn rest_of_line(line: &str, keyword: &str) -> String {
    let start = line.find(keyword).map_or(0, |i| i + keyword.len());
    line[start..].trim().to_owned()
}

/// Collects `Kd` (and `d`/`Tr` for alpha) per `newmtl`.
fn parse_mtl(text: &str, colors: &mut BTreeMap<String, [f32; 4]>) {
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
    /// Per local vertex: indices into the global `v`, `vt`, `vn` pools.
    verts: Vec<[u32; 3]>,
    indices: Vec<u32>,
}

struct MeshBuilder {
    name: String,
    prims: Vec<usize>,
}

struct Builder<'a> {
    path: &'a Path,
    positions: Vec<[f32; 3]>,
    texcoords: Vec<[f32; 2]>,
    normals: Vec<[f32; 3]>,
    /// Per `v`: first wedge of its chain, or `NONE`.
    head: Vec<u32>,
    wedges: Vec<Wedge>,
    prims: Vec<PrimBuilder>,
    meshes: Vec<MeshBuilder>,
    materials: Vec<String>,
    material_ids: BTreeMap<String, usize>,
    mtl_colors: BTreeMap<String, [f32; 4]>,
    pending_name: Option<String>,
    current_material: Option<usize>,
    current_mesh: Option<usize>,
    current_prim: Option<usize>,
    /// Scratch: the local vertices of the face being read.
    face: Vec<u32>,
}

impl<'a> Builder<'a> {
    fn new(path: &'a Path) -> Self {
        Builder {
            path,
            positions: Vec::new(),
            texcoords: Vec::new(),
            normals: Vec::new(),
            head: Vec::new(),
            wedges: Vec::new(),
            prims: Vec::new(),
            meshes: Vec::new(),
            materials: Vec::new(),
            material_ids: BTreeMap::new(),
            mtl_colors: BTreeMap::new(),
            pending_name: None,
            current_material: None,
            current_mesh: None,
            current_prim: None,
            face: Vec::new(),
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
        let p = existing.unwrap_or_else(|| {
            self.prims.push(PrimBuilder {
                material,
                verts: Vec::new(),
                indices: Vec::new(),
            });
            self.meshes[mesh].prims.push(self.prims.len() - 1);
            self.prims.len() - 1
        });
        self.current_prim = Some(p);
        p
    }

    /// Resolves one OBJ index (1-based or negative) against `count` items.
    fn resolve(
        &self,
        token: &str,
        count: usize,
        target: &'static str,
        line: usize,
    ) -> Result<u32, ReadError> {
        let err = |kind| ReadError::new(self.path, Location::Line(line), kind);
        let index: i64 = token.parse().map_err(|_| {
            err(ErrorKind::Syntax {
                expected: format!("a {target} index"),
                found: token.to_owned(),
            })
        })?;
        let resolved = match index {
            0 => return Err(err(ErrorKind::ObjIndexZero { target })),
            i if i > 0 => i - 1,
            i => count as i64 + i,
        };
        if resolved < 0 || resolved >= count as i64 {
            return Err(err(ErrorKind::IndexOutOfRange {
                what: "face",
                target,
                index,
                count,
            }));
        }
        Ok(resolved as u32)
    }

    fn face<'t>(
        &mut self,
        tokens: impl Iterator<Item = &'t str>,
        line: usize,
    ) -> Result<(), ReadError> {
        let prim = self.prim();
        let mut face = std::mem::take(&mut self.face);
        face.clear();
        for corner in tokens.take_while(|t| !t.starts_with('#')) {
            let mut parts = corner.split('/');
            let v = parts.next().unwrap_or("");
            let vt = parts.next().filter(|s| !s.is_empty());
            let vn = parts.next().filter(|s| !s.is_empty());
            let v = self.resolve(v, self.positions.len(), "vertex", line)?;
            let vt = match vt {
                Some(t) => self.resolve(t, self.texcoords.len(), "texture coordinate", line)?,
                None => NONE,
            };
            let vn = match vn {
                Some(t) => self.resolve(t, self.normals.len(), "normal", line)?,
                None => NONE,
            };
            face.push(self.corner(prim, v, vt, vn));
        }
        if face.len() < 3 {
            return Err(ReadError::new(
                self.path,
                Location::Line(line),
                ErrorKind::Invalid(format!("face has {} corners, needs at least 3", face.len())),
            ));
        }
        let indices = &mut self.prims[prim].indices;
        for i in 1..face.len() - 1 {
            indices.extend_from_slice(&[face[0], face[i], face[i + 1]]);
        }
        self.face = face;
        Ok(())
    }

    /// The primitive-local vertex of corner `(v, vt, vn)`, created on first use.
    fn corner(&mut self, prim: usize, v: u32, vt: u32, vn: u32) -> u32 {
        let prim32 = prim as u32;
        let mut w = self.head[v as usize];
        while w != NONE {
            let wedge = &self.wedges[w as usize];
            if wedge.prim == prim32 && wedge.vt == vt && wedge.vn == vn {
                return wedge.local;
            }
            w = wedge.next;
        }
        let verts = &mut self.prims[prim].verts;
        let local = verts.len() as u32;
        verts.push([v, vt, vn]);
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

    fn finish(self) -> Scene {
        let materials = self
            .materials
            .into_iter()
            .map(|name| Material {
                base_color: self.mtl_colors.get(&name).copied(),
                name,
            })
            .collect();
        let mut prims: Vec<Option<PrimBuilder>> = self.prims.into_iter().map(Some).collect();
        let meshes =
            self.meshes
                .into_iter()
                .map(|m| {
                    // (sized exactly: `filter_map(..).collect()` reserves four `Primitive`s, ~1.6 KB,
                    // which made an object per face cost 160 bytes per input byte)
                    let mut primitives = Vec::with_capacity(m.prims.len());
                    primitives.extend(m.prims.iter().filter_map(|&p| prims[p].take()).map(|p| {
                        build_primitive(p, &self.positions, &self.texcoords, &self.normals)
                    }));
                    SourceMesh {
                        name: m.name,
                        primitives,
                    }
                })
                .collect();
        Scene {
            meshes,
            materials,
            origin: Origin::Flat,
            warnings: Vec::new(),
        }
    }
}

fn build_primitive(
    p: PrimBuilder,
    positions: &[[f32; 3]],
    texcoords: &[[f32; 2]],
    normals: &[[f32; 3]],
) -> Primitive {
    let has_uv = p.verts.iter().any(|v| v[1] != NONE);
    let has_normals = p.verts.iter().all(|v| v[2] != NONE);
    Primitive {
        material: p.material,
        positions: p.verts.iter().map(|v| positions[v[0] as usize]).collect(),
        texcoords: has_uv.then(|| {
            p.verts
                .iter()
                .map(|v| texcoords.get(v[1] as usize).copied().unwrap_or([0.0; 2]))
                .collect()
        }),
        normals: has_normals.then(|| p.verts.iter().map(|v| normals[v[2] as usize]).collect()),
        indices: p.indices,
        ..Primitive::default()
    }
}
