//! What every reader shares: the memory cap, the read options, text
//! tokenizing with located errors, and the clean-up of a read primitive.

use std::path::Path;

use super::error::{ErrorKind, Location, ReadError};
use crate::scene::{Primitive, Scene};

/// The memory cap of the readers: decoded data allocated from counts a
/// file declares (glTF accessors, `EXT_meshopt_compression` views) may take
/// at most this many bytes per byte of input (the file and its buffers),
/// plus [`DECODED_BYTES_FLOOR`]. Every count is checked against the bytes
/// that hold its data and against this cap *before* anything is allocated,
/// so a lying count fails at once with an error naming it. The PLY reader
/// sizes its arrays by the file's length. OBJ and SMF declare no counts:
/// their arrays grow with the lines read, at most 14 bytes per input byte
/// (a huge polygon's fan) plus one [`Primitive`] and a few hundred bytes
/// per OBJ object (`tests/read_limits_text.rs` checks the worst cases).
pub const DECODED_BYTES_PER_INPUT_BYTE: u64 = 64;

/// The part of the memory cap every file gets whatever its size (64 MiB).
pub const DECODED_BYTES_FLOOR: u64 = 64 << 20;

/// How to read.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// A part of the file that would be left out with a warning (a glTF
    /// primitive that cannot be read, points and lines, a mesh with no
    /// triangle) is an error instead (`--strict`).
    pub strict: bool,
}

/// Name of a mesh read from a single-mesh file: the file stem.
pub(super) fn file_stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "mesh".to_owned())
}

/// Parses one number token of a text format.
pub(super) fn parse_f32(
    token: &str,
    path: &Path,
    line: usize,
    what: &str,
) -> Result<f32, ReadError> {
    let value: f32 = token.parse().map_err(|_| {
        ReadError::new(
            path,
            Location::Line(line),
            ErrorKind::Syntax {
                expected: format!("a number for {what}"),
                found: token.to_owned(),
            },
        )
    })?;
    if !value.is_finite() {
        return Err(ReadError::new(
            path,
            Location::Line(line),
            ErrorKind::NonFinite {
                what: what.to_owned(),
                value,
            },
        ));
    }
    Ok(value)
}

/// Parses the next `N` coordinates of a text line; missing ones are a
/// syntax error, extra ones are ignored by the caller.
pub(super) fn parse_coords<'a, const N: usize>(
    tokens: &mut impl Iterator<Item = &'a str>,
    path: &Path,
    line: usize,
    what: &str,
) -> Result<[f32; N], ReadError> {
    let mut out = [0.0f32; N];
    for slot in &mut out {
        let token = tokens.next().ok_or_else(|| {
            ReadError::new(
                path,
                Location::Line(line),
                ErrorKind::Syntax {
                    expected: format!("{N} coordinates for {what}"),
                    found: "end of line".to_owned(),
                },
            )
        })?;
        *slot = parse_f32(token, path, line, what)?;
    }
    Ok(out)
}

/// Fails with [`ErrorKind::EmptyMesh`] when no mesh has a triangle.
pub(super) fn check_not_empty(scene: &Scene, path: &Path) -> Result<(), ReadError> {
    let triangles = scene.triangle_count();
    if triangles == 0 {
        return Err(ReadError::new(path, Location::File, ErrorKind::EmptyMesh));
    }
    Ok(())
}

/// Splits text into `(1-based line number, line without "\r\n")`.
pub(super) fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.split('\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l)))
}

/// Drops vertices no triangle refers to and renumbers the rest in order of
/// first use. Every index must already be `< positions.len()`. The indices
/// are renumbered in place, and vertices already in that order stay where
/// they are.
pub(super) fn compact(mut p: Primitive) -> Primitive {
    const UNSEEN: u32 = u32::MAX;
    let mut remap = vec![UNSEEN; p.positions.len()];
    let mut order: Vec<u32> = Vec::new();
    for i in &mut p.indices {
        debug_assert!((*i as usize) < remap.len());
        let r = &mut remap[*i as usize];
        if *r == UNSEEN {
            *r = order.len() as u32;
            order.push(*i);
        }
        *i = *r;
    }
    drop(remap);
    if order.len() == p.positions.len() && order.iter().enumerate().all(|(k, &i)| k == i as usize) {
        return p;
    }
    fn pick<T: Copy>(values: &[T], order: &[u32]) -> Vec<T> {
        order.iter().map(|&i| values[i as usize]).collect()
    }
    Primitive {
        material: p.material,
        positions: pick(&p.positions, &order),
        normals: p.normals.as_deref().map(|n| pick(n, &order)),
        texcoords: p.texcoords.as_deref().map(|t| pick(t, &order)),
        tangents: p.tangents.as_deref().map(|t| pick(t, &order)),
        extra_texcoords: p.extra_texcoords.iter().map(|t| pick(t, &order)).collect(),
        colors: p.colors.as_deref().map(|c| pick(c, &order)),
        joints: p.joints.as_deref().map(|j| pick(j, &order)),
        weights: p.weights.as_deref().map(|w| pick(w, &order)),
        extra_colors: p.extra_colors.iter().map(|c| pick(c, &order)).collect(),
        extra_joints: p.extra_joints.iter().map(|j| pick(j, &order)).collect(),
        extra_weights: p.extra_weights.iter().map(|w| pick(w, &order)).collect(),
        targets: p
            .targets
            .iter()
            .map(|t| crate::scene::MorphTarget {
                positions: t.positions.as_deref().map(|v| pick(v, &order)),
                normals: t.normals.as_deref().map(|v| pick(v, &order)),
                tangents: t.tangents.as_deref().map(|v| pick(v, &order)),
            })
            .collect(),
        indices: p.indices,
    }
}

/// A text or binary mesh whose first vertex has a coordinate this far from the origin (in
/// the file's units) is read moved to that vertex, rounded to whole units
/// ([`crate::scene::Origin::Moved`]): below it `f32` still steps by less than a thousandth
/// of a unit (2⁻¹¹ at 8,192), above it scans in UTM or earth-centred coordinates lost their
/// detail and, merged and flattened by the rounding, took minutes to measure.
pub const FAR_COORDINATE: f64 = 8192.0;

/// The offset a file whose first vertex is `first` is read moved by ([`FAR_COORDINATE`]):
/// `first` rounded to whole units, or `None` near the origin.
pub fn far_offset(first: [f64; 3]) -> Option<[f64; 3]> {
    let far = first.iter().any(|x| x.abs() >= FAR_COORDINATE);
    far.then(|| first.map(f64::round))
}

/// Where a reader's positions are moved to, decided at the first vertex ([`FAR_COORDINATE`]).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Recentre {
    decided: bool,
    offset: Option<[f64; 3]>,
}

impl Recentre {
    /// Decided from `first`, the first vertex's coordinates.
    pub fn from_first(first: [f64; 3]) -> Recentre {
        Recentre {
            decided: true,
            offset: far_offset(first),
        }
    }

    /// `p` moved (the first finite point given decides, when nothing has: a range scan's
    /// first pixels may be invalid).
    #[inline]
    pub fn apply(&mut self, p: [f64; 3]) -> [f64; 3] {
        if !self.decided && p.iter().all(|x| x.is_finite()) {
            *self = Recentre::from_first(p);
        }
        match self.offset {
            Some(o) => [p[0] - o[0], p[1] - o[1], p[2] - o[2]],
            None => p,
        }
    }

    /// The scene's origin: moved, or flat.
    pub fn origin(&self) -> crate::scene::Origin {
        match self.offset {
            Some(offset) => crate::scene::Origin::Moved { offset },
            None => crate::scene::Origin::Flat,
        }
    }
}
