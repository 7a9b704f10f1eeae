//! The PLY header: elements, properties and their scalar types, the
//! encoding; and decoding one binary scalar.

use std::path::Path;

use super::error::{ErrorKind, Location, ReadError};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Scalar {
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
    /// The factor that takes a colour component stored as this type to
    /// [0, 1]: integers are full-range (`uchar` 255 = 1), floats as they are.
    pub(super) fn color_scale(self) -> f64 {
        match self {
            Scalar::I8 => 1.0 / 127.0,
            Scalar::U8 => 1.0 / 255.0,
            Scalar::I16 => 1.0 / 32767.0,
            Scalar::U16 => 1.0 / 65535.0,
            Scalar::I32 => 1.0 / f64::from(i32::MAX),
            Scalar::U32 => 1.0 / f64::from(u32::MAX),
            Scalar::F32 | Scalar::F64 => 1.0,
        }
    }

    pub(super) fn parse(name: &str) -> Option<Scalar> {
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

    pub(super) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    pub(super) fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
pub(super) struct Property {
    pub name: String,
    pub kind: Kind,
}

#[derive(Debug)]
pub(super) struct Element {
    pub name: String,
    pub count: usize,
    pub props: Vec<Property>,
}

/// What the reader does with each property of the `vertex` element.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Role {
    Skip,
    Position(usize),
    Normal(usize),
    Uv(usize),
    /// `red green blue alpha`, component `k`.
    Color(usize),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Encoding {
    Ascii,
    Little,
    Big,
}

/// Parses the header; returns the encoding, the elements, the byte offset
/// of the body and the number of header lines.
pub(super) fn parse_header(
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

pub(super) fn invalid(path: &Path, location: Location, message: &str) -> ReadError {
    ReadError::new(path, location, ErrorKind::Invalid(message.to_owned()))
}

/// One binary scalar of type `ty` from `b` (`ty.size()` bytes), as `f64`
/// (exact for every PLY type).
#[inline]
pub(super) fn decode(ty: Scalar, big: bool, b: &[u8]) -> f64 {
    let mut a = [0u8; 8];
    let size = ty.size();
    a[..size].copy_from_slice(&b[..size]);
    if big {
        a[..size].reverse();
    }
    match ty {
        Scalar::I8 => a[0] as i8 as f64,
        Scalar::U8 => a[0] as f64,
        Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
        Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
        Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
        Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
        Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
        Scalar::F64 => f64::from_le_bytes(a),
    }
}
