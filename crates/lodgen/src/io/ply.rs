//! PLY reader: `ascii`, `binary_little_endian` and `binary_big_endian`,
//! every scalar type (`char`/`int8` ... `double`/`float64`).
//!
//! Read: element `vertex` with `x y z`, optional `nx ny nz`, optional
//! texture coordinates named `u v`, `s t`, `texture_u texture_v` or
//! `texture_s texture_t`; element `face` with a list `vertex_indices` (or
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

use super::common::{check_not_empty, compact, file_stem};
use super::error::{ErrorKind, Location, ReadError};
use crate::scene::{Origin, Primitive, Scene, SourceMesh};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

/// What the reader does with each property of the `vertex` element.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Skip,
    Position(usize),
    Normal(usize),
    Uv(usize),
}

/// Reads a PLY file from its bytes; `path` names it in errors.
pub fn read_ply(src: &[u8], path: &Path) -> Result<Scene, ReadError> {
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
    let mut indices: Vec<u32> = Vec::new();
    let mut list: Vec<f64> = Vec::new();
    let mut resolved: Vec<u32> = Vec::new();

    for element in &elements {
        let roles = if element.name == "vertex" {
            vertex_roles(element, path)?
        } else {
            vec![Role::Skip; element.props.len()]
        };
        let has_normals = roles.iter().any(|r| matches!(r, Role::Normal(_)));
        let has_uv = roles.iter().any(|r| matches!(r, Role::Uv(_)));
        let index_list = index_list_of(element, path)?;
        for index in 0..element.count {
            body.begin(&element.name, index)?;
            let (p, n, uv) = read_record(&mut body, element, index, &roles, index_list, &mut list)?;
            body.end(&element.name, index)?;
            if element.name == "vertex" {
                positions.push(finite3(p, &body, index, "vertex coordinate")?);
                if has_normals {
                    normals.push(finite3(n, &body, index, "normal")?);
                }
                if has_uv {
                    let t = finite3([uv[0], uv[1], 0.0], &body, index, "texture coordinate")?;
                    texcoords.push([t[0], 1.0 - t[1]]);
                }
            } else if index_list.is_some() {
                let at = (&body, element, index);
                add_indices(at, &list, vertex_count, &mut resolved, &mut indices)?;
            }
        }
    }
    debug_assert_eq!(positions.len(), vertex_count);
    let primitive = compact(Primitive {
        material: None,
        normals: (!normals.is_empty()).then_some(normals),
        texcoords: (!texcoords.is_empty()).then_some(texcoords),
        positions,
        indices,
        ..Primitive::default()
    });
    let scene = Scene {
        meshes: vec![SourceMesh {
            name: file_stem(path),
            primitives: vec![primitive],
        }],
        materials: Vec::new(),
        origin: Origin::Flat,
        warnings: Vec::new(),
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
type Record = ([f64; 3], [f64; 3], [f64; 2]);

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
    for (pi, prop) in element.props.iter().enumerate() {
        match prop.kind {
            Kind::Scalar(ty) => {
                let value = body.scalar(ty, &element.name, index)?;
                match roles[pi] {
                    Role::Skip => {}
                    Role::Position(k) => p[k] = value,
                    Role::Normal(k) => n[k] = value,
                    Role::Uv(k) => uv[k] = value,
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
    Ok((p, n, uv))
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

fn invalid(path: &Path, location: Location, message: &str) -> ReadError {
    ReadError::new(path, location, ErrorKind::Invalid(message.to_owned()))
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

/// Parses the header; returns the encoding, the elements, the byte offset
/// of the body and the number of header lines.
fn parse_header(
    src: &[u8],
    path: &Path,
) -> Result<(Encoding, Vec<Element>, usize, usize), ReadError> {
    let mut pos = 0;
    let mut line_no = 0;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(len) = src[pos..].iter().position(|&b| b == b'\n') else {
            return Err(ReadError::new(
                path,
                Location::Line(line_no + 1),
                ErrorKind::Truncated("the header has no `end_header` line".to_owned()),
            ));
        };
        line_no += 1;
        let raw = &src[pos..pos + len];
        pos += len + 1;
        let line = String::from_utf8_lossy(raw);
        let line = line.trim_end_matches('\r');
        let here = Location::Line(line_no);
        let syntax = |expected: &str| {
            ReadError::new(
                path,
                here.clone(),
                ErrorKind::Syntax {
                    expected: expected.to_owned(),
                    found: line.to_owned(),
                },
            )
        };
        let mut tokens = line.split_ascii_whitespace();
        if line_no == 1 {
            if line != "ply" {
                return Err(syntax("`ply` on the first line"));
            }
            continue;
        }
        match tokens.next() {
            Some("format") => {
                encoding = Some(match (tokens.next(), tokens.next()) {
                    (Some("ascii"), Some(_)) => Encoding::Ascii,
                    (Some("binary_little_endian"), Some(_)) => Encoding::Little,
                    (Some("binary_big_endian"), Some(_)) => Encoding::Big,
                    _ => {
                        return Err(syntax(
                            "`format ascii|binary_little_endian|binary_big_endian 1.0`",
                        ))
                    }
                });
            }
            Some("element") => {
                let (Some(name), Some(count), None) = (tokens.next(), tokens.next(), tokens.next())
                else {
                    return Err(syntax("`element NAME COUNT`"));
                };
                let count: usize = count.parse().map_err(|_| syntax("`element NAME COUNT`"))?;
                elements.push(Element {
                    name: name.to_owned(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let Some(element) = elements.last_mut() else {
                    return Err(syntax("`element` before `property`"));
                };
                let words: Vec<&str> = tokens.collect();
                let kind_and_name = match words.as_slice() {
                    ["list", count, item, name] => Scalar::parse(count)
                        .zip(Scalar::parse(item))
                        .filter(|(c, _)| c.is_integer())
                        .map(|(count, item)| (Kind::List { count, item }, name)),
                    [ty, name] => Scalar::parse(ty).map(|t| (Kind::Scalar(t), name)),
                    _ => None,
                };
                let Some((kind, name)) = kind_and_name else {
                    return Err(syntax(
                        "`property TYPE NAME` or `property list COUNT_TYPE TYPE NAME`",
                    ));
                };
                element.props.push(Property {
                    name: (*name).to_owned(),
                    kind,
                });
            }
            Some("end_header") => break,
            Some("comment") | Some("obj_info") | None => {}
            Some(_) => return Err(syntax("a PLY header line")),
        }
    }
    let encoding =
        encoding.ok_or_else(|| invalid(path, Location::File, "the header has no `format` line"))?;
    Ok((encoding, elements, pos, line_no))
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
        let big = self.encoding == Encoding::Big;
        let mut a = [0u8; 8];
        a[..size].copy_from_slice(b);
        if big {
            a[..size].reverse();
        }
        Ok(match ty {
            Scalar::I8 => a[0] as i8 as f64,
            Scalar::U8 => a[0] as f64,
            Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(a),
        })
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
