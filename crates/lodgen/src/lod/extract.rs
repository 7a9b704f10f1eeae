//! Extraction: a level of the progressive mesh turned back into the
//! source's primitives, attributes transferred corner by corner from each
//! corner's wedge (skin and morph targets from that source vertex as they
//! are), then the fitted values.

use lodgen_pm::metric::{ErrorReport, MeasureOptions};
use lodgen_pm::polish::{Original, WorstOptions};
use lodgen_pm::{Mesh, Simplified};

use crate::scene::{Primitive, SourceMesh};

use super::error::BuildError;
use super::fit::{FitSource, Fitted};
use super::flat::{locate, Flat};
use super::measure::Measurer;
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

/// A level cut from the sequence: its primitives, and its mesh while it
/// waits to be measured.
pub(super) struct Extracted {
    pub(super) primitives: Vec<Primitive>,
    /// `None` when the level is not measured: no measurement, or the
    /// level is the original (its error is 0); kept for a level below the
    /// input when `deferred`.
    pub(super) mesh: Option<Mesh>,
    /// `Some(material)`: the primitives are made from the mesh once it is
    /// measured ([`deferred_primitives`]; `primitives` is empty until then).
    pub(super) deferred: Option<Option<usize>>,
    /// The level's error when it was measured already (its worst spot
    /// fixed, [`extract_levels`]'s `fix`).
    pub(super) report: Option<ErrorReport>,
}

/// How [`extract_levels`] fixes each level's worst spot
/// ([`super::options::BuildOptions::fix_worst`]): the measurer of the
/// levels, its options and the fix's.
pub(super) type Fix<'m, 'a> = (&'m Measurer<'a>, &'m MeasureOptions, &'m WorstOptions);

/// Every level at `splits`: attributes fitted below the input (module
/// docs), extracted into primitives; its mesh kept when `measured` and the
/// level is below the input. With `deferred` (a mesh of one positions-only
/// primitive whose input was freed, `build.rs`'s `frees_input_early`) only
/// the meshes are kept, the primitives made after their measurement. With
/// `polish` the level's positions are polished, then with `fix` its worst
/// spot is fixed, which measures it (the report is kept: the level is not
/// measured again).
pub(super) fn extract_levels(
    mesh: &SourceMesh,
    flat: &Flat,
    simplified: &Simplified,
    splits: &[usize],
    (measured, deferred): (bool, bool),
    polish: Option<(&Original<'_>, &lodgen_pm::PolishOptions)>,
    fix: Option<Fix<'_, '_>>,
) -> Result<Vec<Extracted>, BuildError> {
    let pm = &simplified.pm;
    let mut cursor = pm.cursor();
    let fit_source = FitSource::new(mesh, flat, simplified);
    let mut out: Vec<Option<Extracted>> = splits.iter().map(|_| None).collect();
    let mut moved = Mesh::default();
    // (coarse to fine: the cursor applies each split once, where seeking
    // the levels finest first refined to the finest, then undid most of it)
    let mut order: Vec<usize> = (0..splits.len()).collect();
    order.sort_by_key(|&i| splits[i]);
    let mut fixed = match fix {
        Some(fix) => fixed_levels(simplified, splits, &order, polish, fix)?,
        None => Vec::new(),
    };
    for i in order {
        let k = splits[i];
        if deferred && polish.is_none() && fix.is_none() {
            // (only the level's mesh, replayed on every core: no cursor,
            // which would replay it on one and then be cloned)
            let material = mesh.primitives.first().and_then(|p| p.material);
            out[i] = Some(Extracted {
                primitives: Vec::new(),
                mesh: (k < pm.len()).then(|| pm.mesh_at_splits(k)),
                deferred: Some(material),
                report: None,
            });
            continue;
        }
        cursor.seek(k);
        // (the written level moved: [`BuildOptions::polish`], then
        // [`BuildOptions::fix_worst`])
        let own = k < pm.len() && (polish.is_some() || fix.is_some());
        let mut report = None;
        if let Some((m, r)) = fixed.get_mut(i).and_then(Option::take) {
            (moved, report) = (m, r);
        } else if own {
            moved.clone_from(cursor.mesh());
            if let Some((original, popts)) = polish {
                lodgen_pm::polish_clusters(original, &mut moved, &pm.representatives(k), popts);
            }
        }
        let m = if own { &moved } else { cursor.mesh() };
        if deferred {
            let material = mesh.primitives.first().and_then(|p| p.material);
            out[i] = Some(Extracted {
                primitives: Vec::new(),
                mesh: (k < pm.len()).then(|| m.clone()),
                deferred: Some(material),
                report,
            });
            continue;
        }
        // a level below the input gets fitted values (module docs)
        let fitted = match (&fit_source, cursor.wedges()) {
            (Some(f), Some(w)) if k < pm.len() => Some(f.fit(m, w)),
            _ => None,
        };
        out[i] = Some(Extracted {
            primitives: extract(mesh, flat, simplified, m, cursor.wedges(), fitted.as_ref()),
            mesh: (measured && report.is_none() && k < pm.len()).then(|| m.clone()),
            deferred: None,
            report,
        });
    }
    Ok(out.into_iter().flatten().collect())
}

/// The levels below the input at `splits` (visited in `order`), each
/// polished when `polish` is set, with their worst spots fixed (`fix`) side
/// by side ([`Measurer::fix_worst`]: the fix's pattern search runs on one
/// thread, so the levels share the cores). Indexed like `splits`; `None` for a
/// level at the input.
#[allow(clippy::type_complexity)]
fn fixed_levels(
    simplified: &Simplified,
    splits: &[usize],
    order: &[usize],
    polish: Option<(&Original<'_>, &lodgen_pm::PolishOptions)>,
    (measurer, mopts, wopts): Fix<'_, '_>,
) -> Result<Vec<Option<(Mesh, Option<ErrorReport>)>>, BuildError> {
    let pm = &simplified.pm;
    let mut cursor = pm.cursor();
    let (mut at, mut levels) = (Vec::new(), Vec::new());
    for &i in order {
        let k = splits[i];
        if k < pm.len() {
            cursor.seek(k);
            let mut m = cursor.mesh().clone();
            if let Some((original, popts)) = polish {
                lodgen_pm::polish_clusters(original, &mut m, &pm.representatives(k), popts);
            }
            at.push(i);
            levels.push((k, m));
        }
    }
    drop(cursor);
    let reports = measurer.fix_worst(&mut levels, mopts, wopts)?;
    let mut out: Vec<Option<(Mesh, Option<ErrorReport>)>> = splits.iter().map(|_| None).collect();
    for ((i, (_, m)), r) in at.into_iter().zip(levels).zip(reports) {
        out[i] = Some((m, r));
    }
    Ok(out)
}

/// The one primitive of a level of a mesh of one positions-only primitive
/// (`frees_input_early` in `build.rs`): what [`extract`] makes of it (every level
/// vertex one output vertex, numbered in order of first use by the
/// triangles; no primitive without triangles), from the level's mesh alone.
pub(super) fn deferred_primitives(material: Option<usize>, level: &Mesh) -> Vec<Primitive> {
    if level.triangles.is_empty() {
        return Vec::new();
    }
    let mut out_of = vec![u32::MAX; level.positions.len()];
    let mut positions = Vec::new();
    let mut indices = Vec::with_capacity(3 * level.triangles.len());
    for &v in level.triangles.iter().flatten() {
        let o = &mut out_of[v as usize];
        if *o == u32::MAX {
            *o = positions.len() as u32;
            positions.push(level.positions[v as usize]);
        }
        indices.push(*o);
    }
    vec![Primitive {
        material,
        positions,
        indices,
        ..Primitive::default()
    }]
}
