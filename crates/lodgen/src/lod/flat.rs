//! The input mesh flattened for the core: every primitive's vertices one
//! after the other, all triangles in one index list.

use crate::scene::SourceMesh;

/// The input mesh flattened for the core: all primitives in one index list.
pub(super) struct Flat {
    pub(super) positions: Vec<[f32; 3]>,
    pub(super) indices: Vec<u32>,
    /// Input triangle → primitive.
    pub(super) prim_of_triangle: Vec<u32>,
    /// First flat vertex of each primitive.
    pub(super) vertex_offset: Vec<u32>,
}

pub(super) fn flatten(mesh: &SourceMesh) -> Flat {
    let mut f = Flat {
        positions: Vec::new(),
        indices: Vec::new(),
        prim_of_triangle: Vec::new(),
        vertex_offset: Vec::new(),
    };
    for (pi, p) in mesh.primitives.iter().enumerate() {
        let off = f.positions.len() as u32;
        f.vertex_offset.push(off);
        f.positions.extend_from_slice(&p.positions);
        f.indices.extend(p.indices.iter().map(|&i| i + off));
        f.prim_of_triangle
            .extend(std::iter::repeat_n(pi as u32, p.indices.len() / 3));
    }
    f
}

/// Flat vertex → (primitive, local vertex).
pub(super) fn locate(flat: &Flat, v: u32) -> (usize, usize) {
    let p = flat.vertex_offset.partition_point(|&o| o <= v) - 1;
    (p, (v - flat.vertex_offset[p]) as usize)
}
