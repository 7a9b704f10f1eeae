//! Extraction: a level of the progressive mesh turned back into the
//! source's primitives, attributes transferred corner by corner from each
//! corner's wedge (skin and morph targets from that source vertex as they
//! are), then the fitted values.

use lodgen_pm::{Mesh, Simplified};

use crate::scene::{Primitive, SourceMesh};

use super::fit::Fitted;
use super::flat::{locate, Flat};
use super::unit::{normalize3, normalize_weights, orthogonal_tangent};

/// Turn a level of the progressive mesh back into the source's primitives,
/// transferring attributes corner by corner from each corner's wedge
/// (`wedges`, flat vertex ids; without them, from the level vertex's first
/// source vertex), then the fitted values where there are some.
pub(super) fn extract(
    source: &SourceMesh,
    flat: &Flat,
    s: &Simplified,
    level: &Mesh,
    wedges: Option<&[[u32; 3]]>,
    fitted: Option<&Fitted>,
) -> Vec<Primitive> {
    let pm = &s.pm;
    // First input vertex of each welded vertex.
    let mut first_input = vec![u32::MAX; pm.vertex_origin.len()];
    for (iv, &w) in s.vertex_map.iter().enumerate() {
        if w != u32::MAX && first_input[w as usize] == u32::MAX {
            first_input[w as usize] = iv as u32;
        }
    }
    let mut prims: Vec<Primitive> = source
        .primitives
        .iter()
        .map(|p| Primitive {
            material: p.material,
            normals: p.normals.as_ref().map(|_| Vec::new()),
            texcoords: p.texcoords.as_ref().map(|_| Vec::new()),
            tangents: p.tangents.as_ref().map(|_| Vec::new()),
            extra_texcoords: vec![Vec::new(); p.extra_texcoords.len()],
            colors: p.colors.as_ref().map(|_| Vec::new()),
            joints: p.joints.as_ref().map(|_| Vec::new()),
            weights: p.weights.as_ref().map(|_| Vec::new()),
            extra_colors: vec![Vec::new(); p.extra_colors.len()],
            extra_joints: vec![Vec::new(); p.extra_joints.len()],
            extra_weights: vec![Vec::new(); p.extra_weights.len()],
            targets: p.targets.iter().map(|t| t.empty_like()).collect(),
            ..Primitive::default()
        })
        .collect();
    // (primitive, level vertex, wedge) → output vertex, numbered in order
    // of first use
    let mut remap = Remap::new(level.positions.len());
    for (t, tri) in level.triangles.iter().enumerate() {
        let input_tri = s.triangle_map[pm.triangle_origin[t] as usize] as usize;
        let pi = flat.prim_of_triangle(input_tri);
        for (slot, &v) in tri.iter().enumerate() {
            let src = match wedges {
                Some(w) => w[t][slot],
                None => first_input[pm.vertex_origin[v as usize] as usize],
            };
            let next = prims[pi as usize].positions.len() as u32;
            let out = remap.get_or_insert(v, (pi, src), || {
                let prim = &mut prims[pi as usize];
                prim.positions.push(level.positions[v as usize]);
                // the source vertex may belong to another primitive
                let (sp, local) = locate(flat, src);
                let from = &source.primitives[sp];
                push_attributes(prim, from, local);
                if let Some(f) = fitted {
                    if let Some(values) = f.values.get(v, src) {
                        f.channels.apply(prim, from, values);
                    }
                }
                next
            });
            prims[pi as usize].indices.push(out);
        }
    }
    // a material can vanish from a coarse level
    prims.retain(|p| !p.indices.is_empty());
    prims
}

/// (primitive, level vertex, wedge) → output vertex: per level vertex a
/// chain of its (primitive, wedge) pairs, almost always one (a map keyed
/// by the triple took 5 % of a scan's run).
struct Remap {
    /// Per level vertex: its first entry + 1, or 0.
    head: Vec<u32>,
    /// (primitive, wedge), output vertex, next entry of the chain + 1.
    entries: Vec<((u32, u32), u32, u32)>,
}

impl Remap {
    fn new(vertices: usize) -> Remap {
        Remap {
            head: vec![0; vertices],
            entries: Vec::with_capacity(vertices),
        }
    }

    /// The output vertex of `key` at level vertex `v`; on first use, the
    /// one `insert` makes.
    fn get_or_insert(&mut self, v: u32, key: (u32, u32), insert: impl FnOnce() -> u32) -> u32 {
        let mut e = self.head[v as usize];
        while e != 0 {
            let (k, out, after) = self.entries[e as usize - 1];
            if k == key {
                return out;
            }
            e = after;
        }
        let out = insert();
        self.entries.push((key, out, self.head[v as usize]));
        self.head[v as usize] = self.entries.len() as u32;
        out
    }
}

/// Append vertex `v` of `from`'s attributes to `to` (defaults where `from`
/// lacks one `to` has), normalised as the module docs say.
fn push_attributes(to: &mut Primitive, from: &Primitive, v: usize) {
    let normal = from.normals.as_ref().map(|a| normalize3(a[v]));
    if let Some(n) = to.normals.as_mut() {
        n.push(normal.unwrap_or([0.0, 0.0, 1.0]));
    }
    if let Some(uv) = to.texcoords.as_mut() {
        uv.push(from.texcoords.as_ref().map_or([0.0; 2], |a| a[v]));
    }
    if let Some(t) = to.tangents.as_mut() {
        let raw = from
            .tangents
            .as_ref()
            .map_or([1.0, 0.0, 0.0, 1.0], |a| a[v]);
        t.push(orthogonal_tangent(raw, normal));
    }
    for (i, uv) in to.extra_texcoords.iter_mut().enumerate() {
        uv.push(from.extra_texcoords.get(i).map_or([0.0; 2], |a| a[v]));
    }
    if let Some(c) = to.colors.as_mut() {
        c.push(from.colors.as_ref().map_or([1.0; 4], |a| a[v]));
    }
    for (i, c) in to.extra_colors.iter_mut().enumerate() {
        c.push(from.extra_colors.get(i).map_or([1.0; 4], |a| a[v]));
    }
    // JOINTS_n and WEIGHTS_n: all sets from the same source vertex, the
    // weights of all sets together renormalised to sum 1
    if let Some(j) = to.joints.as_mut() {
        j.push(from.joints.as_ref().map_or([0; 4], |a| a[v]));
    }
    for (i, j) in to.extra_joints.iter_mut().enumerate() {
        j.push(from.extra_joints.get(i).map_or([0; 4], |a| a[v]));
    }
    let mut sets: Vec<[f32; 4]> = Vec::with_capacity(1 + to.extra_weights.len());
    if to.weights.is_some() {
        sets.push(from.weights.as_ref().map_or([1.0, 0.0, 0.0, 0.0], |a| a[v]));
    }
    for i in 0..to.extra_weights.len() {
        sets.push(from.extra_weights.get(i).map_or([0.0; 4], |a| a[v]));
    }
    normalize_weights(&mut sets);
    let mut sets = sets.into_iter();
    if let Some(w) = to.weights.as_mut() {
        w.extend(sets.next());
    }
    for w in to.extra_weights.iter_mut() {
        w.extend(sets.next());
    }
    // morph targets: the displacements of the same source vertex (part of
    // the wedge key, so they follow the contractions like the skin)
    for (i, t) in to.targets.iter_mut().enumerate() {
        match from.targets.get(i) {
            Some(f) => t.push_from(f, v),
            None => t.push_from(&crate::scene::MorphTarget::default(), v),
        }
    }
}
