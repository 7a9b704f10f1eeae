//! PLY reader: `ascii`, `binary_little_endian` and `binary_big_endian`,
//! every scalar type (`char`/`int8` ... `double`/`float64`).
//!
//! Read: element `vertex` with `x y z`, optional `nx ny nz`, optional
//! texture coordinates named `u v`, `s t`, `texture_u texture_v` or
//! `texture_s texture_t`, optional colours `red green blue` (`alpha`;
//! integers full-range, `uchar` 255 = 1, floats as they are: `COLOR_0`);
//! element `face` with a list `vertex_indices` (or
//! `vertex_index`) of any count and index type, polygons fan-triangulated;
//! element `tristrips` with a list `vertex_indices` of strips separated by
//! `-1`. Every other element and property is skipped (by size in binary
//! files). The result is one mesh named after the file stem with one
//! primitive; unreferenced vertices are dropped (numbering by first use)
//! and `v` is flipped to glTF's convention (`1 - v`).
//!
//! Error places: header and ascii-body errors name the line; binary-body
//! errors name the element instance (`face 12`).

use std::path::Path;

use super::common::{check_not_empty, compact, file_stem, Recentre};
use super::error::{ErrorKind, Location, ReadError};
use super::ply_binary;
use super::ply_header::{decode, invalid, parse_header, Element, Encoding, Kind, Role, Scalar};
use crate::scene::{Primitive, Scene, SourceMesh, Warning};

/// Reads a PLY file from its bytes; `path` names it in errors.
pub fn read_ply(src: &[u8], path: &Path) -> Result<Scene, ReadError> {
    read_ply_with(src, path, true)
}

/// [`read_ply`]; `fast`: binary vertices and faces through `ply_binary`
/// (else record by record, the reference the tests compare it with).
fn read_ply_with(src: &[u8], path: &Path, fast: bool) -> Result<Scene, ReadError> {
    let (encoding, elements, body_start, header_lines) = parse_header(src, path)?;
    let vertex_count = elements
        .iter()
        .find(|e| e.name == "vertex")
        .map(|e| e.count)
        .ok_or_else(|| invalid(path, Location::File, "no `vertex` element in the header"))?;
    let mut body = Body::new(encoding, &src[body_start..], header_lines, path);
    // Capacities are bounded by the data actually present.
    let cap = vertex_count.min(src.len() / 3);
    let mut positions: Vec<[f32; 3]> = Vec::with_capacity(cap);
    let mut normals: Vec<[f32; 3]> = Vec::new();
    let mut texcoords: Vec<[f32; 2]> = Vec::new();
    let mut colors: Vec<[f32; 4]> = Vec::new();
    let mut indices: Vec<u32> = Vec::new();
    let mut list: Vec<f64> = Vec::new();
    let mut resolved: Vec<u32> = Vec::new();
    let mut recentre = Recentre::default();
    let mut invalid: Vec<u32> = Vec::new();
    // (an ascii body's invalid vertices' lines, for the error)
    let mut lines: Vec<usize> = Vec::new();

    for element in &elements {
        let roles = if element.name == "vertex" {
            vertex_roles(element, path)?
        } else {
            vec![Role::Skip; element.props.len()]
        };
        let has_normals = roles.iter().any(|r| matches!(r, Role::Normal(_)));
        let has_uv = roles.iter().any(|r| matches!(r, Role::Uv(_)));
        let has_colors = roles.iter().any(|r| matches!(r, Role::Color(_)));
        let index_list = index_list_of(element, path)?;
        if fast && encoding != Encoding::Ascii {
            // fixed-size vertices and face lists: the record loop without
            // per-value calls (same values, same errors)
            let big = encoding == Encoding::Big;
            let rest = &body.bytes[body.pos..];
            let all_scalar = element
                .props
                .iter()
                .enumerate()
                .all(|(i, p)| Some(i) == index_list || matches!(p.kind, Kind::Scalar(_)));
            if element.name == "vertex" && all_scalar {
                let out = ply_binary::VertexArrays {
                    positions: &mut positions,
                    recentre: &mut recentre,
                    invalid: &mut invalid,
                    normals: has_normals.then_some(&mut normals),
                    texcoords: has_uv.then_some(&mut texcoords),
                    colors: has_colors.then_some(&mut colors),
                };
                body.pos += ply_binary::vertices(rest, element, &roles, big, path, out)?;
                continue;
            }
            if let (Some(list), "face", true) = (index_list, element.name.as_str(), all_scalar) {
                let at = (element, list, vertex_count);
                body.pos += ply_binary::faces(rest, at, big, path, &mut indices)?;
                continue;
            }
        }
        for index in 0..element.count {
            body.begin(&element.name, index)?;
            let (p, n, uv, c) =
                read_record(&mut body, element, index, &roles, index_list, &mut list)?;
            body.end(&element.name, index)?;
            if element.name == "vertex" {
                let p = recentre.apply(p).map(|x| x as f32);
                // (an invalid point, attributes and all: an error only if a face uses it)
                let bad = p.iter().any(|x| !x.is_finite());
                if bad {
                    invalid.push(index as u32);
                    if encoding == Encoding::Ascii {
                        lines.push(body.line);
                    }
                }
                positions.push(p);
                let finite3 = |v: [f64; 3], what: &str| match bad {
                    true => Ok(v.map(|x| x as f32)),
                    false => finite3(v, &body, index, what),
                };
                if has_normals {
                    normals.push(finite3(n, "normal")?);
                }
                if has_uv {
                    let t = finite3([uv[0], uv[1], 0.0], "texture coordinate")?;
                    texcoords.push([t[0], 1.0 - t[1]]);
                }
                if has_colors {
                    let [r, g, b] = finite3([c[0], c[1], c[2]], "colour")?;
                    let [a, ..] = finite3([c[3], 0.0, 0.0], "colour")?;
                    colors.push([r, g, b, a]);
                }
            } else if index_list.is_some() {
                let at = (&body, element, index);
                add_indices(at, &list, vertex_count, &mut resolved, &mut indices)?;
            }
        }
    }
    debug_assert_eq!(positions.len(), vertex_count);
    check_used_finite((&invalid, &lines), &positions, &indices, body.path)?;
    let primitive = compact(Primitive {
        material: None,
        normals: (!normals.is_empty()).then_some(normals),
        texcoords: (!texcoords.is_empty()).then_some(texcoords),
        colors: (!colors.is_empty()).then_some(colors),
        positions,
        indices,
        ..Primitive::default()
    });
    one_mesh_scene(primitive, &body, recentre, path)
}

/// The scene of a PLY file: its one primitive, with the body's warning (data after the
/// declared elements), if it draws anything.
fn one_mesh_scene(
    primitive: Primitive,
    body: &Body<'_>,
    recentre: Recentre,
    path: &Path,
) -> Result<Scene, ReadError> {
    let scene = Scene {
        meshes: vec![SourceMesh {
            name: file_stem(path),
            primitives: vec![primitive],
        }],
        materials: Vec::new(),
        origin: recentre.origin(),
        warnings: body.trailing().into_iter().collect(),
    };
    check_not_empty(&scene, path)?;
    Ok(scene)
}

/// Which property of `element` lists its vertex indices (`face`: required;
/// `tristrips`: if any; other elements: none).
fn index_list_of(element: &Element, path: &Path) -> Result<Option<usize>, ReadError> {
    let list = |name_ok: &dyn Fn(&str) -> bool| {
        element
            .props
            .iter()
            .position(|p| name_ok(&p.name) && matches!(p.kind, Kind::List { .. }))
    };
    Ok(match element.name.as_str() {
        "face" => Some(
            list(&|n| n == "vertex_indices" || n == "vertex_index").ok_or_else(|| {
                invalid(
                    path,
                    Location::File,
                    "`face` element has no `vertex_indices` list",
                )
            })?,
        ),
        "tristrips" => list(&|n| n == "vertex_indices"),
        _ => None,
    })
}

/// A vertex record's position, normal and texture coordinate.
type Record = ([f64; 3], [f64; 3], [f64; 2], [f64; 4]);

/// One record of `element`: its position, normal and texture coordinate
/// (as `roles` assign them; zeros otherwise), and the index list (property
/// `index_list`) into `list`.
fn read_record(
    body: &mut Body<'_>,
    element: &Element,
    index: usize,
    roles: &[Role],
    index_list: Option<usize>,
    list: &mut Vec<f64>,
) -> Result<Record, ReadError> {
    let mut p = [0.0f64; 3];
    let mut n = [0.0f64; 3];
    let mut uv = [0.0f64; 2];
    let mut c = [0.0, 0.0, 0.0, 1.0f64];
    for (pi, prop) in element.props.iter().enumerate() {
        match prop.kind {
            Kind::Scalar(ty) => {
                let value = body.scalar(ty, &element.name, index)?;
                match roles[pi] {
                    Role::Skip => {}
                    Role::Position(k) => p[k] = value,
                    Role::Normal(k) => n[k] = value,
                    Role::Uv(k) => uv[k] = value,
                    Role::Color(k) => c[k] = value * ty.color_scale(),
                }
            }
            Kind::List { count, item } => {
                let len = body.scalar(count, &element.name, index)?;
                if !(len >= 0.0 && len.fract() == 0.0) {
                    return Err(body.error(
                        &element.name,
                        index,
                        ErrorKind::Invalid(format!("list length {len} of `{}`", prop.name)),
                    ));
                }
                let len = len as usize;
                if Some(pi) == index_list {
                    list.clear();
                    for _ in 0..len {
                        list.push(body.scalar(item, &element.name, index)?);
                    }
                } else {
                    body.skip(item, len, &element.name, index)?;
                }
            }
        }
    }
    Ok((p, n, uv, c))
}

/// Checks the index list of record `index` of a `face` (fanned) or
/// `tristrips` (strips split at -1) element and appends its triangles.
fn add_indices(
    (body, element, index): (&Body<'_>, &Element, usize),
    list: &[f64],
    vertex_count: usize,
    resolved: &mut Vec<u32>,
    indices: &mut Vec<u32>,
) -> Result<(), ReadError> {
    let face = element.name == "face";
    resolved.clear();
    for &raw in list {
        if raw == -1.0 && !face {
            resolved.push(u32::MAX);
            continue;
        }
        if !(raw >= 0.0 && raw.fract() == 0.0 && (raw as usize) < vertex_count) {
            return Err(body.error(
                &element.name,
                index,
                ErrorKind::IndexOutOfRange {
                    what: if face { "face" } else { "strip" },
                    target: "vertex",
                    index: raw as i64,
                    count: vertex_count,
                },
            ));
        }
        resolved.push(raw as u32);
    }
    if face {
        if resolved.len() < 3 {
            return Err(body.error(
                &element.name,
                index,
                ErrorKind::Invalid(format!(
                    "face has {} corners, needs at least 3",
                    resolved.len()
                )),
            ));
        }
        for i in 1..resolved.len() - 1 {
            indices.extend_from_slice(&[resolved[0], resolved[i], resolved[i + 1]]);
        }
    } else {
        for strip in resolved.split(|&i| i == u32::MAX) {
            for i in 0..strip.len().saturating_sub(2) {
                let (b, c) = if i % 2 == 0 {
                    (i + 1, i + 2)
                } else {
                    (i + 2, i + 1)
                };
                indices.extend_from_slice(&[strip[i], strip[b], strip[c]]);
            }
        }
    }
    Ok(())
}

/// The first vertex of `invalid` (positions not finite: a range scan's invalid pixels) that
/// a face uses, as an error; the others go with the vertices no face uses (`compact`).
fn check_used_finite(
    (invalid, lines): (&[u32], &[usize]),
    positions: &[[f32; 3]],
    indices: &[u32],
    path: &Path,
) -> Result<(), ReadError> {
    if invalid.is_empty() {
        return Ok(());
    }
    let mut bad = vec![false; positions.len()];
    for &v in invalid {
        bad[v as usize] = true;
    }
    let Some(&v) = indices.iter().find(|&&i| bad[i as usize]) else {
        return Ok(());
    };
    let value = positions[v as usize]
        .into_iter()
        .find(|x| !x.is_finite())
        .unwrap_or(f32::NAN);
    let what = "vertex coordinate (of a vertex a face uses)".to_owned();
    // (an ascii body: the vertex's line; binary: its number)
    let at = match invalid.binary_search(&v).ok().and_then(|k| lines.get(k)) {
        Some(&line) => Location::Line(line),
        None => Location::Element {
            element: "vertex".to_owned(),
            index: v as usize,
        },
    };
    Err(ReadError::new(
        path,
        at,
        ErrorKind::NonFinite { what, value },
    ))
}

fn finite3(v: [f64; 3], body: &Body<'_>, index: usize, what: &str) -> Result<[f32; 3], ReadError> {
    let out = v.map(|x| x as f32);
    if let Some(&bad) = out.iter().find(|x| !x.is_finite()) {
        return Err(body.error(
            "vertex",
            index,
            ErrorKind::NonFinite {
                what: what.to_owned(),
                value: bad,
            },
        ));
    }
    Ok(out)
}

fn vertex_roles(element: &Element, path: &Path) -> Result<Vec<Role>, ReadError> {
    let find = |name: &str| element.props.iter().position(|p| p.name == name);
    let mut roles = vec![Role::Skip; element.props.len()];
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        let i = find(name).ok_or_else(|| {
            invalid(
                path,
                Location::File,
                &format!("`vertex` element has no `{name}` property"),
            )
        })?;
        if !matches!(element.props[i].kind, Kind::Scalar(_)) {
            return Err(invalid(
                path,
                Location::File,
                &format!("vertex `{name}` is a list"),
            ));
        }
        roles[i] = Role::Position(k);
    }
    let scalar = |i: usize| matches!(element.props[i].kind, Kind::Scalar(_));
    if let (Some(a), Some(b), Some(c)) = (find("nx"), find("ny"), find("nz")) {
        if scalar(a) && scalar(b) && scalar(c) {
            roles[a] = Role::Normal(0);
            roles[b] = Role::Normal(1);
            roles[c] = Role::Normal(2);
        }
    }
    // (`diffuse_red`…: the Stanford scanning repository's and some scanners' names)
    let named = |c: &str| find(c).or_else(|| find(&format!("diffuse_{c}")));
    let rgb = [named("red"), named("green"), named("blue")];
    if let [Some(r), Some(g), Some(b)] = rgb {
        if scalar(r) && scalar(g) && scalar(b) {
            roles[r] = Role::Color(0);
            roles[g] = Role::Color(1);
            roles[b] = Role::Color(2);
            if let Some(a) = named("alpha").filter(|&a| scalar(a)) {
                roles[a] = Role::Color(3);
            }
        }
    }
    for (u, v) in [
        ("u", "v"),
        ("s", "t"),
        ("texture_u", "texture_v"),
        ("texture_s", "texture_t"),
    ] {
        if let (Some(a), Some(b)) = (find(u), find(v)) {
            if scalar(a) && scalar(b) {
                roles[a] = Role::Uv(0);
                roles[b] = Role::Uv(1);
                break;
            }
        }
    }
    Ok(roles)
}

/// The body cursor: lines and tokens for ascii, bytes for binary.
struct Body<'a> {
    encoding: Encoding,
    path: &'a Path,
    bytes: &'a [u8],
    pos: usize,
    /// Ascii: remaining text, the current line's tokens and its number.
    text: &'a str,
    tokens: std::str::SplitAsciiWhitespace<'a>,
    line: usize,
}

impl<'a> Body<'a> {
    fn new(encoding: Encoding, bytes: &'a [u8], header_lines: usize, path: &'a Path) -> Self {
        // Invalid UTF-8 in an ascii body can only be a syntax error; keep
        // the valid prefix so the error names the right line.
        let text = if encoding == Encoding::Ascii {
            match std::str::from_utf8(bytes) {
                Ok(t) => t,
                Err(e) => std::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or(""),
            }
        } else {
            ""
        };
        Body {
            encoding,
            path,
            bytes,
            pos: 0,
            text,
            tokens: "".split_ascii_whitespace(),
            line: header_lines,
        }
    }

    /// A warning when data follows the last element the header declares (its counts too
    /// small: what follows is not read).
    fn trailing(&self) -> Option<Warning> {
        let left = match self.encoding {
            Encoding::Ascii => self.text.lines().filter(|l| !l.trim().is_empty()).count(),
            _ => self.bytes.len().saturating_sub(self.pos),
        };
        let unit = match (self.encoding == Encoding::Ascii, left == 1) {
            (true, true) => "line",
            (true, false) => "lines",
            (false, true) => "byte",
            (false, false) => "bytes",
        };
        (left > 0).then(|| {
            Warning::new(
                "body",
                format!(
                    "{left} {unit} after the last element the header declares are not read \
                     (does it count fewer vertices or faces than the file holds?)"
                ),
            )
        })
    }

    fn location(&self, element: &str, index: usize) -> Location {
        match self.encoding {
            Encoding::Ascii => Location::Line(self.line),
            _ => Location::Element {
                element: element.to_owned(),
                index,
            },
        }
    }

    fn error(&self, element: &str, index: usize, kind: ErrorKind) -> ReadError {
        ReadError::new(self.path, self.location(element, index), kind)
    }

    fn truncated(&self, element: &str, index: usize) -> ReadError {
        let kind = ErrorKind::Truncated(format!("inside {element} {index}"));
        match self.encoding {
            Encoding::Ascii => ReadError::new(self.path, Location::Line(self.line), kind),
            _ => self.error(element, index, kind),
        }
    }

    /// Ascii: moves to the next non-blank line.
    fn begin(&mut self, element: &str, index: usize) -> Result<(), ReadError> {
        if self.encoding != Encoding::Ascii {
            return Ok(());
        }
        loop {
            if self.text.is_empty() {
                return Err(self.truncated(element, index));
            }
            let (line, rest) = self.text.split_once('\n').unwrap_or((self.text, ""));
            self.text = rest;
            self.line += 1;
            self.tokens = line.split_ascii_whitespace();
            if !line.trim().is_empty() {
                return Ok(());
            }
        }
    }

    /// Ascii: the line must hold exactly the declared values.
    fn end(&mut self, element: &str, index: usize) -> Result<(), ReadError> {
        if self.encoding == Encoding::Ascii {
            if let Some(extra) = self.tokens.next() {
                return Err(self.error(
                    element,
                    index,
                    ErrorKind::Syntax {
                        expected: format!("end of {element} {index}"),
                        found: extra.to_owned(),
                    },
                ));
            }
        }
        Ok(())
    }

    fn scalar(&mut self, ty: Scalar, element: &str, index: usize) -> Result<f64, ReadError> {
        if self.encoding == Encoding::Ascii {
            let Some(token) = self.tokens.next() else {
                return Err(self.error(
                    element,
                    index,
                    ErrorKind::Syntax {
                        expected: format!("more values for {element} {index}"),
                        found: "end of line".to_owned(),
                    },
                ));
            };
            let value = if ty.is_integer() {
                token.parse::<i64>().map(|v| v as f64).ok()
            } else {
                token.parse::<f64>().ok()
            };
            return value.ok_or_else(|| {
                self.error(
                    element,
                    index,
                    ErrorKind::Syntax {
                        expected: format!("a {ty:?} value"),
                        found: token.to_owned(),
                    },
                )
            });
        }
        let size = ty.size();
        let Some(b) = self.bytes.get(self.pos..self.pos + size) else {
            return Err(self.truncated(element, index));
        };
        self.pos += size;
        Ok(decode(ty, self.encoding == Encoding::Big, b))
    }

    fn skip(
        &mut self,
        ty: Scalar,
        count: usize,
        element: &str,
        index: usize,
    ) -> Result<(), ReadError> {
        if self.encoding == Encoding::Ascii {
            for _ in 0..count {
                self.scalar(ty, element, index)?;
            }
            return Ok(());
        }
        let end = count
            .checked_mul(ty.size())
            .and_then(|n| n.checked_add(self.pos))
            .filter(|&end| end <= self.bytes.len())
            .ok_or_else(|| self.truncated(element, index))?;
        self.pos = end;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A binary PLY: `vertex_props` / `face_props` are (type, name) with
    /// `list` for the index list; values from a small deterministic mesh
    /// (quads and triangles), extra properties filled with their index.
    fn file(big: bool, vertex_props: &[(&str, &str)], face_props: &[(&str, &str)]) -> Vec<u8> {
        let format = if big { "big" } else { "little" };
        let mut h = format!("ply\nformat binary_{format}_endian 1.0\nelement vertex 9\n");
        for (ty, name) in vertex_props {
            h += &format!("property {ty} {name}\n");
        }
        h += "element face 5\n";
        for (ty, name) in face_props {
            h += &format!("property {ty} {name}\n");
        }
        h += "end_header\n";
        let mut out = h.into_bytes();
        let put = |out: &mut Vec<u8>, ty: &str, v: f64| {
            let mut b = match ty {
                "char" => vec![v as i8 as u8],
                "uchar" => vec![v as u8],
                "short" => (v as i16).to_le_bytes().to_vec(),
                "ushort" => (v as u16).to_le_bytes().to_vec(),
                "int" => (v as i32).to_le_bytes().to_vec(),
                "uint" => (v as u32).to_le_bytes().to_vec(),
                "float" => (v as f32).to_le_bytes().to_vec(),
                "double" => v.to_le_bytes().to_vec(),
                _ => unreachable!("{ty}"),
            };
            if big {
                b.reverse();
            }
            out.extend_from_slice(&b);
        };
        for i in 0..9 {
            for (k, (ty, name)) in vertex_props.iter().enumerate() {
                let v = match *name {
                    "x" => (i % 3) as f64 * 0.5,
                    "y" => (i / 3) as f64 * 0.25,
                    "z" | "u" => (i % 2) as f64,
                    "nz" | "v" => 1.0 - (i % 2) as f64 * 0.5,
                    _ => k as f64,
                };
                put(&mut out, ty, v);
            }
        }
        let faces: [&[u32]; 5] = [
            &[0, 1, 4],
            &[1, 2, 5, 4],
            &[3, 4, 7, 6],
            &[4, 5, 8],
            &[8, 7, 6, 3],
        ];
        for f in faces {
            for (k, (ty, _)) in face_props.iter().enumerate() {
                if let Some(types) = ty.strip_prefix("list ") {
                    let (count, item) = types.split_once(' ').unwrap();
                    put(&mut out, count, f.len() as f64);
                    for &i in f {
                        put(&mut out, item, i as f64);
                    }
                } else {
                    put(&mut out, ty, k as f64);
                }
            }
        }
        out
    }

    /// (type, name) of each property.
    type Props<'a> = Vec<(&'a str, &'a str)>;

    fn same(a: &Result<Scene, ReadError>, b: &Result<Scene, ReadError>) -> bool {
        match (a, b) {
            (Ok(a), Ok(b)) => a.meshes == b.meshes,
            (Err(a), Err(b)) => a.to_string() == b.to_string() && a.location == b.location,
            _ => false,
        }
    }

    /// The fast binary paths read what the record-by-record reader reads,
    /// for every prefix of each file and for each byte of its body set to
    /// 0xff or 0x80 (NaNs, negative and huge indices and counts): the same
    /// mesh or the same error at the same element. (Fails when a fast path
    /// skips a check, reports another record, or misreads a type.)
    #[test]
    fn fast_binary_paths_read_what_the_record_reader_reads() {
        let xyz = [("float", "x"), ("float", "y"), ("float", "z")];
        let layouts: Vec<(Props, Props)> = vec![
            (xyz.to_vec(), vec![("list uchar int", "vertex_indices")]),
            (xyz.to_vec(), vec![("list uchar uint", "vertex_indices")]),
            (
                vec![
                    ("double", "x"),
                    ("uchar", "flag"),
                    ("double", "y"),
                    ("double", "z"),
                    ("float", "nx"),
                    ("float", "ny"),
                    ("float", "nz"),
                    ("float", "u"),
                    ("float", "v"),
                ],
                vec![
                    ("short", "a"),
                    ("list ushort short", "vertex_indices"),
                    ("float", "b"),
                ],
            ),
            (
                vec![("int", "z"), ("short", "y"), ("char", "x")],
                vec![("list int uchar", "vertex_index"), ("uint", "c")],
            ),
        ];
        let path = Path::new("t.ply");
        for big in [false, true] {
            for (vertex, face) in &layouts {
                let bytes = file(big, vertex, face);
                let body = bytes
                    .windows(11)
                    .position(|w| w == b"end_header\n")
                    .unwrap()
                    + 11;
                let reference = read_ply_with(&bytes, path, false);
                assert!(reference.is_ok(), "{vertex:?} {face:?}");
                assert!(same(&reference, &read_ply_with(&bytes, path, true)));
                for len in body..bytes.len() {
                    let cut = &bytes[..len];
                    let (a, b) = (
                        read_ply_with(cut, path, false),
                        read_ply_with(cut, path, true),
                    );
                    assert!(same(&a, &b), "cut at {len}: {:?} / {:?}", a.err(), b.err());
                }
                for at in body..bytes.len() {
                    for value in [0xff, 0x80] {
                        let mut bad = bytes.clone();
                        bad[at] = value;
                        let (a, b) = (
                            read_ply_with(&bad, path, false),
                            read_ply_with(&bad, path, true),
                        );
                        assert!(
                            same(&a, &b),
                            "byte {at} = {value}: {:?} / {:?}",
                            a.err(),
                            b.err()
                        );
                    }
                }
            }
        }
    }
}
