//! The input mesh flattened for the core: every primitive's vertices one
//! after the other, all triangles in one index list. A mesh of one
//! primitive is borrowed, not copied (peak memory: the flat copy of a
//! scanned mesh was 22 bytes per triangle for the whole build).

use std::borrow::Cow;

use crate::scene::SourceMesh;

/// The input mesh flattened for the core: all primitives in one index list.
pub(super) struct Flat<'a> {
    pub(super) positions: Cow<'a, [[f32; 3]]>,
    pub(super) indices: Cow<'a, [u32]>,
    /// Input triangle → primitive; empty when there is one primitive.
    prim_of_triangle: Vec<u32>,
    /// First flat vertex of each primitive.
    pub(super) vertex_offset: Vec<u32>,
}

impl Flat<'_> {
    /// The primitive of input triangle `t`.
    pub(super) fn prim_of_triangle(&self, t: usize) -> u32 {
        self.prim_of_triangle.get(t).copied().unwrap_or(0)
    }

    /// The same flattening without its positions and indices (the
    /// primitives and vertex offsets extraction reads), borrowing nothing:
    /// the input's geometry can then be freed.
    pub(super) fn without_geometry(self) -> Flat<'static> {
        Flat {
            positions: Cow::Owned(Vec::new()),
            indices: Cow::Owned(Vec::new()),
            prim_of_triangle: self.prim_of_triangle,
            vertex_offset: self.vertex_offset,
        }
    }
}

pub(super) fn flatten(mesh: &SourceMesh) -> Flat<'_> {
    if let [p] = mesh.primitives.as_slice() {
        return Flat {
            positions: Cow::Borrowed(&p.positions),
            indices: Cow::Borrowed(&p.indices),
            prim_of_triangle: Vec::new(),
            vertex_offset: vec![0],
        };
    }
    let vertices = mesh.primitives.iter().map(|p| p.positions.len()).sum();
    let corners = mesh.primitives.iter().map(|p| p.indices.len()).sum();
    let mut positions = Vec::with_capacity(vertices);
    let mut indices = Vec::with_capacity(corners);
    let mut prim_of_triangle = Vec::with_capacity(corners / 3);
    let mut vertex_offset = Vec::with_capacity(mesh.primitives.len());
    for (pi, p) in mesh.primitives.iter().enumerate() {
        let off = positions.len() as u32;
        vertex_offset.push(off);
        positions.extend_from_slice(&p.positions);
        indices.extend(p.indices.iter().map(|&i| i + off));
        prim_of_triangle.extend(std::iter::repeat_n(pi as u32, p.indices.len() / 3));
    }
    Flat {
        positions: Cow::Owned(positions),
        indices: Cow::Owned(indices),
        prim_of_triangle,
        vertex_offset,
    }
}

/// Flat vertex → (primitive, local vertex).
pub(super) fn locate(flat: &Flat, v: u32) -> (usize, usize) {
    let p = flat.vertex_offset.partition_point(|&o| o <= v) - 1;
    (p, (v - flat.vertex_offset[p]) as usize)
}
