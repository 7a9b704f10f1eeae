//! Binary PLY bodies without a call per value: a `vertex` element of
//! scalars only is a run of fixed-size records, read field by field at
//! known offsets; a `face` element whose only list is its index list reads
//! each record's count, then its indices (triangles: three at once). Values,
//! checks and errors (element, index and kind) are those of the record by
//! record reader in `ply.rs`, in the same order.

use std::path::Path;

use super::common::Recentre;
use super::error::{ErrorKind, Location, ReadError};
use super::ply_header::{decode, Element, Kind, Role, Scalar};

/// Where the vertex values go (`None`: the file has no such property).
pub(super) struct VertexArrays<'a> {
    pub positions: &'a mut Vec<[f32; 3]>,
    /// Where positions are moved to (far from the origin).
    pub recentre: &'a mut Recentre,
    /// The vertices whose position is not finite (a range scan's invalid pixels): an error
    /// only when a face uses one (`ply::check_used_finite`).
    pub invalid: &'a mut Vec<u32>,
    pub normals: Option<&'a mut Vec<[f32; 3]>>,
    pub texcoords: Option<&'a mut Vec<[f32; 2]>>,
    /// RGBA in [0, 1] (alpha 1 when the file has none).
    pub colors: Option<&'a mut Vec<[f32; 4]>>,
}

fn at(path: &Path, element: &Element, index: usize, kind: ErrorKind) -> ReadError {
    let location = Location::Element {
        element: element.name.clone(),
        index,
    };
    ReadError::new(path, location, kind)
}

fn truncated(path: &Path, element: &Element, index: usize) -> ReadError {
    let kind = ErrorKind::Truncated(format!("inside {} {index}", element.name));
    at(path, element, index, kind)
}

/// `v` as `f32`, every component finite (else the first one that is not).
fn finite<const N: usize>(
    v: [f64; N],
    (path, element, index): (&Path, &Element, usize),
    what: &str,
) -> Result<[f32; N], ReadError> {
    let out = v.map(|x| x as f32);
    match out.iter().find(|x| !x.is_finite()) {
        None => Ok(out),
        Some(&value) => {
            let kind = ErrorKind::NonFinite {
                what: what.to_owned(),
                value,
            };
            Err(at(path, element, index, kind))
        }
    }
}

/// [`finite`], or `v` as it is for an invalid point (`bad`: its position is not finite).
fn unless<const N: usize>(
    bad: bool,
    v: [f64; N],
    here: (&Path, &Element, usize),
    what: &str,
) -> Result<[f32; N], ReadError> {
    if bad {
        Ok(v.map(|x| x as f32))
    } else {
        finite(v, here, what)
    }
}

/// Reads `element` (every property a scalar) from the start of `bytes`;
/// returns the bytes it took.
pub(super) fn vertices(
    bytes: &[u8],
    element: &Element,
    roles: &[Role],
    big: bool,
    path: &Path,
    out: VertexArrays<'_>,
) -> Result<usize, ReadError> {
    let mut fields: Vec<(usize, Scalar, Role)> = Vec::new();
    let mut stride = 0;
    for (prop, &role) in element.props.iter().zip(roles) {
        let Kind::Scalar(ty) = prop.kind else {
            unreachable!("only called for elements of scalars")
        };
        if role != Role::Skip {
            fields.push((stride, ty, role));
        }
        stride += ty.size();
    }
    // (x, y and z make the stride at least 3)
    let whole = bytes.len() / stride;
    let present = element.count.min(whole);
    let VertexArrays {
        positions,
        recentre,
        invalid,
        mut normals,
        mut texcoords,
        mut colors,
    } = out;
    positions.reserve(present);
    let le_f32_xyz = !big
        && fields.len() == 3
        && fields
            .iter()
            .all(|&(_, ty, r)| ty == Scalar::F32 && matches!(r, Role::Position(_)));
    for index in 0..present {
        let record = &bytes[index * stride..(index + 1) * stride];
        let here = (path, element, index);
        if le_f32_xyz {
            // the scanners' layout: read the three floats directly
            let mut p = [0.0f32; 3];
            for &(offset, _, role) in &fields {
                let Role::Position(k) = role else { continue };
                let b = &record[offset..offset + 4];
                p[k] = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            }
            let p = recentre.apply(p.map(f64::from)).map(|x| x as f32);
            if p.iter().any(|x| !x.is_finite()) {
                invalid.push(index as u32);
            }
            positions.push(p);
            continue;
        }
        let (mut p, mut n, mut uv) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3]);
        let mut c = [0.0, 0.0, 0.0, 1.0f64];
        for &(offset, ty, role) in &fields {
            let value = decode(ty, big, &record[offset..]);
            match role {
                Role::Position(k) => p[k] = value,
                Role::Normal(k) => n[k] = value,
                Role::Uv(k) => uv[k] = value,
                Role::Color(k) => c[k] = value * ty.color_scale(),
                Role::Skip => {}
            }
        }
        let p = recentre.apply(p).map(|x| x as f32);
        // (an invalid point's attributes are not checked either: it goes, or fails the file)
        let bad = p.iter().any(|x| !x.is_finite());
        if bad {
            invalid.push(index as u32);
        }
        positions.push(p);
        if let Some(normals) = normals.as_deref_mut() {
            normals.push(unless(bad, n, here, "normal")?);
        }
        if let Some(texcoords) = texcoords.as_deref_mut() {
            let t = unless(bad, uv, here, "texture coordinate")?;
            texcoords.push([t[0], 1.0 - t[1]]);
        }
        if let Some(colors) = colors.as_deref_mut() {
            colors.push(unless(bad, c, here, "colour")?);
        }
    }
    if present < element.count {
        return Err(truncated(path, element, present));
    }
    Ok(present * stride)
}

/// Reads a `face` element whose properties are scalars but for the index
/// list `list` from the start of `bytes`, fan-triangulating into
/// `indices`; returns the bytes it took.
pub(super) fn faces(
    bytes: &[u8],
    (element, list, vertex_count): (&Element, usize, usize),
    big: bool,
    path: &Path,
    indices: &mut Vec<u32>,
) -> Result<usize, ReadError> {
    let Kind::List {
        count: count_ty,
        item,
    } = element.props[list].kind
    else {
        unreachable!("the index list is a list")
    };
    let size = |props: &[super::ply_header::Property]| -> usize {
        props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(ty) => ty.size(),
                Kind::List { .. } => unreachable!("only the index list is a list"),
            })
            .sum()
    };
    let (before, after) = (
        size(&element.props[..list]),
        size(&element.props[list + 1..]),
    );
    let (cs, is) = (count_ty.size(), item.size());
    // triangles are the rule: room for as many as the bytes can hold
    indices.reserve(
        3 * element
            .count
            .min(bytes.len() / (before + cs + 3 * is + after)),
    );
    let fast_triangles =
        !big && count_ty == Scalar::U8 && matches!(item, Scalar::I32 | Scalar::U32);
    let mut corners: Vec<u32> = Vec::new();
    let mut pos = 0;
    for index in 0..element.count {
        let Some(head) = bytes.get(pos + before..pos + before + cs) else {
            return Err(truncated(path, element, index));
        };
        let len = decode(count_ty, big, head);
        // (the header makes the count an integer type)
        if len < 0.0 {
            let name = &element.props[list].name;
            let kind = ErrorKind::Invalid(format!("list length {len} of `{name}`"));
            return Err(at(path, element, index, kind));
        }
        let start = pos + before + cs;
        let end = (len as usize)
            .checked_mul(is)
            .and_then(|n| n.checked_add(start + after))
            .filter(|&end| end <= bytes.len())
            .ok_or_else(|| truncated(path, element, index))?;
        let items = &bytes[start..end - after];
        pos = end;
        let out_of_range = |raw: f64| {
            let kind = ErrorKind::IndexOutOfRange {
                what: "face",
                target: "vertex",
                index: raw as i64,
                count: vertex_count,
            };
            at(path, element, index, kind)
        };
        if fast_triangles && len == 3.0 {
            let mut t = [0u32; 3];
            for (k, b) in items.chunks_exact(4).enumerate() {
                let raw = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                let in_range = if item == Scalar::I32 {
                    (raw as i32) >= 0 && (raw as usize) < vertex_count
                } else {
                    (raw as usize) < vertex_count
                };
                if !in_range {
                    return Err(out_of_range(decode(item, false, b)));
                }
                t[k] = raw;
            }
            indices.extend_from_slice(&t);
            continue;
        }
        corners.clear();
        for b in items.chunks_exact(is) {
            let raw = decode(item, big, b);
            let whole = item.is_integer() || raw.fract() == 0.0;
            if !(raw >= 0.0 && whole && (raw as usize) < vertex_count) {
                return Err(out_of_range(raw));
            }
            corners.push(raw as u32);
        }
        if corners.len() < 3 {
            let kind = ErrorKind::Invalid(format!(
                "face has {} corners, needs at least 3",
                corners.len()
            ));
            return Err(at(path, element, index, kind));
        }
        for i in 1..corners.len() - 1 {
            indices.extend_from_slice(&[corners[0], corners[i], corners[i + 1]]);
        }
    }
    Ok(pos)
}
