//! Wedges and the attribute term of the cost: which flat vertices are one
//! wedge (same primitive, position and attribute bits), the weighted
//! attribute vector per flat vertex, and QEM run on wedges.

use std::sync::Arc;

use lodgen_pm::{
    prepare_with_wedges, simplify_with_wedges_metered, Mesh, MeshError, Meter, Ready, Simplified,
    SimplifyOptions,
};
use rustc_hash::FxHashMap;

use crate::scene::{Primitive, SourceMesh};

use super::flat::{flatten, Flat};
use super::options::AttributeWeights;
use super::unit::normalize3;

/// Appends the bit pattern of every attribute of vertex `v` of `p` to
/// `k`: within a primitive, equal keys are one wedge (every key of a
/// primitive has the same length: its attribute set).
fn push_wedge_key(k: &mut Vec<u32>, p: &Primitive, v: usize) {
    let mut put = |xs: &[f32]| k.extend(xs.iter().map(|x| if *x == 0.0 { 0 } else { x.to_bits() }));
    put(&p.positions[v]);
    if let Some(a) = &p.normals {
        put(&a[v]);
    }
    if let Some(a) = &p.texcoords {
        put(&a[v]);
    }
    if let Some(a) = &p.tangents {
        put(&a[v]);
    }
    for a in &p.extra_texcoords {
        put(&a[v]);
    }
    if let Some(a) = &p.colors {
        put(&a[v]);
    }
    if let Some(a) = &p.weights {
        put(&a[v]);
    }
    for a in &p.extra_colors {
        put(&a[v]);
    }
    for a in &p.extra_weights {
        put(&a[v]);
    }
    // morph displacements: a vertex whose targets move it differently from
    // its neighbour at the same position is another wedge
    for t in &p.targets {
        for (_, d) in t.channels() {
            put(&d[v]);
        }
    }
    if let Some(a) = &p.joints {
        k.extend(a[v].map(u32::from));
    }
    for a in &p.extra_joints {
        k.extend(a[v].map(u32::from));
    }
}

/// The weighted attribute vector of every flat vertex for the cost, and its
/// length: normal, every UV set, every colour set, each present when some
/// primitive has it and its weight is not 0 (vertices of primitives without
/// it get zeros, white for colours). Tangents follow the UV charts and are
/// not priced; joints and weights are never interpolated.
fn weighted_attributes(mesh: &SourceMesh, flat: &Flat, w: &AttributeWeights) -> (Vec<f32>, usize) {
    let any = |f: &dyn Fn(&Primitive) -> bool| mesh.primitives.iter().any(f);
    let most = |f: &dyn Fn(&Primitive) -> usize| mesh.primitives.iter().map(f).max().unwrap_or(0);
    let normal = w.normal != 0.0 && any(&|p| p.normals.is_some());
    // every UV set under the `uv` weight, every colour set under `color`
    let uv = w.uv != 0.0 && any(&|p| p.texcoords.is_some());
    let extra_uv = if w.uv != 0.0 {
        most(&|p| p.extra_texcoords.len())
    } else {
        0
    };
    let color = w.color != 0.0 && any(&|p| p.colors.is_some());
    let extra_color = if w.color != 0.0 {
        most(&|p| p.extra_colors.len())
    } else {
        0
    };
    let dims = 3 * usize::from(normal)
        + 2 * (usize::from(uv) + extra_uv)
        + 4 * (usize::from(color) + extra_color);
    let mut out = Vec::with_capacity(dims * flat.positions.len());
    if dims == 0 {
        return (out, 0);
    }
    for p in &mesh.primitives {
        for v in 0..p.positions.len() {
            if normal {
                let n = p.normals.as_ref().map_or([0.0; 3], |a| normalize3(a[v]));
                out.extend(n.map(|x| x * w.normal));
            }
            if uv {
                let t = p.texcoords.as_ref().map_or([0.0; 2], |a| a[v]);
                out.extend(t.map(|x| x * w.uv));
            }
            for k in 0..extra_uv {
                let t = p.extra_texcoords.get(k).map_or([0.0; 2], |a| a[v]);
                out.extend(t.map(|x| x * w.uv));
            }
            if color {
                let c = p.colors.as_ref().map_or([1.0; 4], |a| a[v]);
                out.extend(c.map(|x| x * w.color));
            }
            for k in 0..extra_color {
                let c = p.extra_colors.get(k).map_or([1.0; 4], |a| a[v]);
                out.extend(c.map(|x| x * w.color));
            }
        }
    }
    (out, dims)
}

/// Flat vertex → its wedge's representative (the lowest flat vertex with
/// the same primitive, position and attributes), so duplicated vertices
/// with identical attributes do not make false seams. Primitive by
/// primitive (vertices of two primitives are never one wedge), their keys
/// in one array: a key per vertex on the heap was ≈ 64 bytes per vertex,
/// and its freed blocks stayed resident for the whole build.
pub(super) fn wedge_of_vertex(mesh: &SourceMesh, flat: &Flat) -> Vec<u32> {
    let mut out = vec![0; flat.positions.len()];
    let mut keys = Vec::new();
    for (p, &offset) in mesh.primitives.iter().zip(&flat.vertex_offset) {
        let n = p.positions.len();
        let first = if positions_only(p) {
            // (the key is the position's bits: the weld's own map, on every
            // core; a scan's 2.2M vertices were a one-core stretch)
            lodgen_pm::mesh::first_of_each_position(&p.positions)
        } else {
            first_by_key(p, &mut keys)
        };
        for (o, f) in out[offset as usize..][..n].iter_mut().zip(first) {
            *o = offset + f;
        }
    }
    out
}

/// Each vertex of `p`'s first vertex with the same [`push_wedge_key`] key
/// (`keys` the scratch they are put in).
fn first_by_key(p: &Primitive, keys: &mut Vec<u32>) -> Vec<u32> {
    let n = p.positions.len();
    keys.clear();
    for v in 0..n {
        push_wedge_key(keys, p, v);
    }
    let len = keys.len() / n.max(1);
    // each vertex's first vertex with the same key (a hash map: a sort
    // of the keys was 3 % of a bunny's whole run)
    let mut first: FxHashMap<&[u32], u32> =
        FxHashMap::with_capacity_and_hasher(n, Default::default());
    keys.chunks_exact(len.max(1))
        .take(n)
        .enumerate()
        .map(|(v, k)| *first.entry(k).or_insert(v as u32))
        .collect()
}

/// Whether [`push_wedge_key`] puts only the position's bits in `p`'s keys.
fn positions_only(p: &Primitive) -> bool {
    p.normals.is_none()
        && p.texcoords.is_none()
        && p.tangents.is_none()
        && p.extra_texcoords.is_empty()
        && p.colors.is_none()
        && p.weights.is_none()
        && p.extra_colors.is_empty()
        && p.extra_weights.is_empty()
        && p.targets.is_empty()
        && p.joints.is_none()
        && p.extra_joints.is_empty()
}

/// QEM on `mesh`'s wedges: topology on welded positions, every primitive
/// and attribute seam kept, attribute quadrics weighted by `weights`. The
/// log's wedge ids are flat vertex ids (see [`stream_attributes`]).
pub fn simplify_mesh(
    mesh: &SourceMesh,
    opts: &SimplifyOptions,
    weights: &AttributeWeights,
) -> Result<Simplified, MeshError> {
    simplify_wedged(mesh, &flatten(mesh), opts, weights, None)
}

pub(super) fn simplify_wedged(
    mesh: &SourceMesh,
    flat: &Flat,
    opts: &SimplifyOptions,
    weights: &AttributeWeights,
    meter: Option<Arc<Meter>>,
) -> Result<Simplified, MeshError> {
    let wedged = wedged_indices(mesh, flat);
    let (values, dims) = weighted_attributes(mesh, flat, weights);
    simplify_with_wedges_metered(&flat.positions, &wedged, &values, dims, opts, meter)
}

/// [`simplify_wedged`] up to the run: the simplification [`Ready`] to run,
/// which no longer reads `mesh` or `flat`.
pub(super) fn prepare_wedged(
    mesh: &SourceMesh,
    flat: &Flat,
    opts: &SimplifyOptions,
    weights: &AttributeWeights,
    meter: Option<Arc<Meter>>,
) -> Result<Ready, MeshError> {
    let wedged = wedged_indices(mesh, flat);
    let (values, dims) = weighted_attributes(mesh, flat, weights);
    prepare_with_wedges(&flat.positions, &wedged, &values, dims, opts, meter)
}

/// [`simplify_wedged`], with `beside` run on another thread during the
/// simplification on a copy of the prepared (welded) mesh, put in `welded`
/// ([`lodgen_pm::simplify_with_wedges_beside`]).
pub(super) fn simplify_wedged_beside<'m, R: Send>(
    mesh: &SourceMesh,
    flat: &Flat,
    opts: &SimplifyOptions,
    weights: &AttributeWeights,
    meter: Option<Arc<Meter>>,
    welded: &'m mut Option<Mesh>,
    beside: impl FnOnce(&'m Mesh) -> R + Send,
) -> Result<(Simplified, R), MeshError> {
    let wedged = wedged_indices(mesh, flat);
    let (values, dims) = weighted_attributes(mesh, flat, weights);
    lodgen_pm::simplify_with_wedges_beside(
        &flat.positions,
        &wedged,
        &values,
        dims,
        opts,
        meter,
        welded,
        beside,
    )
}

/// The flat indices with every vertex replaced by its wedge's
/// representative ([`wedge_of_vertex`]).
fn wedged_indices<'f>(mesh: &SourceMesh, flat: &'f Flat) -> std::borrow::Cow<'f, [u32]> {
    let wedge = wedge_of_vertex(mesh, flat);
    // every vertex its own wedge (a scan without attributes): the indices
    // as they are, not a copy (peak memory)
    let identity = wedge.iter().enumerate().all(|(v, &w)| w as usize == v);
    if identity {
        std::borrow::Cow::Borrowed(&flat.indices)
    } else {
        flat.indices.iter().map(|&i| wedge[i as usize]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A positions-only primitive's wedges (the weld's map) are what its
    /// keys give, copies and signed zeros included, above and below the
    /// size from which the map is made on every core. Fails if a copy is
    /// sent to a later copy or to another position, or if -0.0 and 0.0
    /// are told apart.
    #[test]
    fn positions_only_wedges_are_the_keys_first_vertices() {
        for n in [1000u32, 150_000] {
            let positions: Vec<[f32; 3]> = (0..n)
                .map(|i| {
                    // every 7th a copy of an earlier position (some of them
                    // through -0.0)
                    let j = if i % 7 == 3 { i / 3 } else { i };
                    let z = if j % 5 == 0 {
                        if i % 2 == 0 {
                            0.0
                        } else {
                            -0.0
                        }
                    } else {
                        1.0
                    };
                    [(j % 613) as f32, (j / 613) as f32, z]
                })
                .collect();
            let p = Primitive {
                positions,
                ..Primitive::default()
            };
            assert!(positions_only(&p));
            let fast = lodgen_pm::mesh::first_of_each_position(&p.positions);
            let by_key = first_by_key(&p, &mut Vec::new());
            assert_eq!(fast, by_key);
            assert!(fast.iter().enumerate().any(|(i, &f)| f as usize != i));
        }
    }
}
