//! Per-level preparation: validates every primitive of every level (typed
//! [`LevelProblem`]s), computes missing normals, applies meshopt's vertex
//! cache (`order`) and fetch order, and the chain's dequantization box.

use std::collections::BTreeMap;
use std::sync::Mutex;

use rayon::prelude::*;

use crate::scene::{LodMesh, MorphTarget, Origin, Primitive, Scene};

use super::error::{LevelProblem, WriteError};

/// One primitive after validation and the meshopt post-pass.
pub(super) struct Prepared {
    pub(super) material: Option<usize>,
    pub(super) positions: Vec<[f32; 3]>,
    pub(super) normals: Vec<[f32; 3]>,
    pub(super) texcoords: Option<Vec<[f32; 2]>>,
    pub(super) tangents: Option<Vec<[f32; 4]>>,
    pub(super) extra_texcoords: Vec<Vec<[f32; 2]>>,
    pub(super) colors: Option<Vec<[f32; 4]>>,
    pub(super) joints: Option<Vec<[u16; 4]>>,
    pub(super) weights: Option<Vec<[f32; 4]>>,
    pub(super) extra_colors: Vec<Vec<[f32; 4]>>,
    pub(super) extra_joints: Vec<Vec<[u16; 4]>>,
    pub(super) extra_weights: Vec<Vec<[f32; 4]>>,
    pub(super) targets: Vec<MorphTarget>,
    pub(super) indices: Vec<u32>,
}

pub(super) struct PreparedChain {
    pub(super) name: String,
    pub(super) source: usize,
    /// Per level: its non-empty primitives.
    pub(super) levels: Vec<Vec<Prepared>>,
    pub(super) coverages: Vec<f64>,
    /// Dequantization (center, uniform half extent) over all levels.
    pub(super) dequant: ([f64; 3], f64),
    /// Properties of the input mesh every level's mesh carries (`weights`,
    /// `extras` with `targetNames`, `extensions`); empty for flat input.
    pub(super) carried: serde_json::Map<String, serde_json::Value>,
}

/// Levels prepared before the write: each level's primitives validated and
/// put in vertex cache and fetch order, normals computed, while the build
/// measures other levels ([`crate::lod::LevelHook`], what the CLI gives
/// [`crate::lod::BuildOptions::level_ready`]); [`super::write_lods_prepared`]
/// then takes them instead of preparing the levels again. The same function
/// of the same primitives: the same bytes.
pub struct PreparedLevels {
    /// The material count the levels were validated against.
    material_count: usize,
    /// Per (source mesh, level): each primitive prepared.
    levels: Mutex<BTreeMap<(usize, usize), Vec<PreparedPrimitive>>>,
}

/// One primitive prepared, `None` without triangles, or why it cannot be.
type PreparedPrimitive = Result<Option<Prepared>, LevelProblem>;

impl PreparedLevels {
    /// Nothing prepared yet, for the meshes of `scene` (validated against
    /// its materials, as the writer does).
    pub fn for_scene(scene: &Scene) -> Self {
        PreparedLevels {
            material_count: material_count(scene),
            levels: Mutex::new(BTreeMap::new()),
        }
    }

    /// Prepares level `level` of source mesh `mesh` (its primitives in
    /// parallel) and keeps it for the write.
    pub fn prepare(&self, mesh: usize, level: usize, primitives: &[Primitive]) {
        let count = self.material_count;
        let done: Vec<PreparedPrimitive> =
            primitives.par_iter().map(|p| prepare(p, count)).collect();
        self.lock().insert((mesh, level), done);
    }

    /// Drops what was prepared for the meshes `keep` refuses (those whose
    /// build failed, written unsimplified instead).
    pub fn retain_meshes(&self, keep: impl Fn(usize) -> bool) {
        self.lock().retain(|&(mesh, _), _| keep(mesh));
    }

    /// Whether no level is kept.
    pub fn is_empty(&self) -> bool {
        self.lock().is_empty()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, BTreeMap<(usize, usize), Vec<PreparedPrimitive>>> {
        // (a panic while another thread held the lock leaves whole entries)
        self.levels.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// What was prepared for this level, if it was prepared from these
    /// primitives (their number and index counts: a guard against a level
    /// that changed after it was given) against `material_count`.
    fn take(
        &self,
        (mesh, level): (usize, usize),
        primitives: &[Primitive],
        material_count: usize,
    ) -> Option<Vec<PreparedPrimitive>> {
        let done = self.lock().remove(&(mesh, level))?;
        let same = |(d, p): (&PreparedPrimitive, &Primitive)| match d {
            Ok(Some(q)) => q.indices.len() == p.indices.len(),
            Ok(None) => p.indices.is_empty(),
            Err(_) => true,
        };
        let matches = material_count == self.material_count
            && done.len() == primitives.len()
            && done.iter().zip(primitives).all(same);
        matches.then_some(done)
    }
}

/// The materials a level's primitives may name: the scene's, or the input
/// glTF document's.
pub(super) fn material_count(scene: &Scene) -> usize {
    match &scene.origin {
        Origin::Flat | Origin::Moved { .. } => scene.materials.len(),
        Origin::Gltf { document, .. } => document.materials.len(),
    }
}

/// Every chain's levels prepared (validated, ordered, normals), the levels
/// found in `ready` taken from there.
pub(super) fn prepare_chains(
    scene: &Scene,
    lods: &[LodMesh],
    material_count: usize,
    ready: Option<&PreparedLevels>,
) -> Result<Vec<PreparedChain>, WriteError> {
    let mut seen = vec![false; scene.meshes.len()];
    let mut chains = Vec::with_capacity(lods.len());
    for lod in lods {
        let invalid = |reason: String| WriteError::InvalidChain {
            mesh: lod.name.clone(),
            reason,
        };
        match seen.get_mut(lod.source) {
            None => {
                return Err(invalid(format!(
                    "source mesh {} does not exist ({} meshes)",
                    lod.source,
                    scene.meshes.len()
                )))
            }
            Some(true) => {
                return Err(invalid(format!(
                    "source mesh {} has a second LOD chain",
                    lod.source
                )))
            }
            Some(s) => *s = true,
        }
        if lod.levels.is_empty() {
            return Err(invalid("no levels".into()));
        }
        // every level's primitives at once (vertex cache and fetch order,
        // normals); the checks below then go in order, so the first
        // problem is reported as before
        let mut prepared: Vec<Vec<PreparedPrimitive>> = lod
            .levels
            .par_iter()
            .enumerate()
            .map(|(k, level)| {
                let taken =
                    ready.and_then(|r| r.take((lod.source, k), &level.primitives, material_count));
                taken.unwrap_or_else(|| {
                    level
                        .primitives
                        .par_iter()
                        .map(|p| prepare(p, material_count))
                        .collect()
                })
            })
            .collect();
        let mut levels = Vec::with_capacity(lod.levels.len());
        let mut coverages = Vec::with_capacity(lod.levels.len());
        for (k, level) in lod.levels.iter().enumerate() {
            let bad = |primitive: usize, problem: LevelProblem| WriteError::InvalidLevel {
                mesh: lod.name.clone(),
                level: k,
                primitive,
                problem,
            };
            let value = level.screen_coverage;
            let previous = coverages.last().copied().unwrap_or(1.0);
            if !(0.0..=1.0).contains(&value) || value > previous {
                return Err(bad(0, LevelProblem::Coverage { value }));
            }
            coverages.push(value);
            let mut prims = Vec::with_capacity(level.primitives.len());
            for (i, p) in std::mem::take(&mut prepared[k]).into_iter().enumerate() {
                if let Some(p) = p.map_err(|e| bad(i, e))? {
                    prims.push(p);
                }
            }
            if prims.is_empty() {
                return Err(bad(0, LevelProblem::Empty));
            }
            levels.push(prims);
        }
        let dequant = dequantization(&levels);
        chains.push(PreparedChain {
            name: lod.name.clone(),
            source: lod.source,
            levels,
            coverages,
            dequant,
            carried: serde_json::Map::new(),
        });
    }
    Ok(chains)
}

/// Validates `p`, computes missing normals and applies meshopt's vertex cache
/// and vertex fetch optimizations. `None` for a primitive without triangles.
fn prepare(p: &Primitive, material_count: usize) -> Result<Option<Prepared>, LevelProblem> {
    validate(p, material_count)?;
    if p.indices.is_empty() {
        return Ok(None);
    }
    let n = p.positions.len();
    let mut indices = super::order::vertex_cache_order(&p.indices, &p.positions);
    // Vertex fetch order on an identity stream: `order[new] = old`, which then
    // reorders every attribute the same way (unused vertices are dropped).
    let identity: Vec<u32> = (0..n as u32).collect();
    let order = meshopt::optimize_vertex_fetch(&mut indices, &identity);
    let pick = |v: &[[f32; 3]]| -> Vec<[f32; 3]> { order.iter().map(|&o| v[o as usize]).collect() };
    let positions = pick(&p.positions);
    let computed = area_weighted_normals(&positions, &indices);
    let normals = match &p.normals {
        None => computed,
        Some(given) => pick(given)
            .iter()
            .zip(&computed)
            .map(|(g, c)| normalized(*g).unwrap_or(*c))
            .collect(),
    };
    fn reorder<T: Copy>(v: &[T], order: &[u32]) -> Vec<T> {
        order.iter().map(|&o| v[o as usize]).collect()
    }
    Ok(Some(Prepared {
        material: p.material,
        positions,
        normals,
        texcoords: p.texcoords.as_deref().map(|v| reorder(v, &order)),
        tangents: p.tangents.as_deref().map(|v| reorder(v, &order)),
        extra_texcoords: p
            .extra_texcoords
            .iter()
            .map(|v| reorder(v, &order))
            .collect(),
        colors: p.colors.as_deref().map(|v| reorder(v, &order)),
        joints: p.joints.as_deref().map(|v| reorder(v, &order)),
        weights: p.weights.as_deref().map(|v| reorder(v, &order)),
        extra_colors: p.extra_colors.iter().map(|v| reorder(v, &order)).collect(),
        extra_joints: p.extra_joints.iter().map(|v| reorder(v, &order)).collect(),
        extra_weights: p.extra_weights.iter().map(|v| reorder(v, &order)).collect(),
        targets: p
            .targets
            .iter()
            .map(|t| MorphTarget {
                positions: t.positions.as_deref().map(|v| reorder(v, &order)),
                normals: t.normals.as_deref().map(|v| reorder(v, &order)),
                tangents: t.tangents.as_deref().map(|v| reorder(v, &order)),
            })
            .collect(),
        indices,
    }))
}

/// The checks of [`prepare`]: index count, vertex count, material, index
/// range, every attribute's length and finiteness, finite positions.
fn validate(p: &Primitive, material_count: usize) -> Result<(), LevelProblem> {
    let n = p.positions.len();
    if p.indices.len() % 3 != 0 {
        return Err(LevelProblem::IndexCount(p.indices.len()));
    }
    if u32::try_from(n).is_err() {
        return Err(LevelProblem::TooManyVertices);
    }
    if let Some(material) = p.material {
        if material >= material_count {
            return Err(LevelProblem::MaterialOutOfRange {
                material,
                count: material_count,
            });
        }
    }
    if let Some((i, &index)) = p.indices.iter().enumerate().find(|(_, &v)| v as usize >= n) {
        return Err(LevelProblem::IndexOutOfRange {
            triangle: i / 3,
            index,
            vertex_count: n,
        });
    }
    let check_len = |attribute: &'static str, len: usize| {
        if len == n {
            Ok(())
        } else {
            Err(LevelProblem::AttributeLength {
                attribute,
                len,
                vertex_count: n,
            })
        }
    };
    if let Some(normals) = &p.normals {
        check_len("NORMAL", normals.len())?;
    }
    if let Some(uv) = &p.texcoords {
        check_len("TEXCOORD_0", uv.len())?;
        if let Some(vertex) = uv.iter().position(|t| t.iter().any(|c| !c.is_finite())) {
            return Err(LevelProblem::NonFinite {
                attribute: "TEXCOORD_0",
                vertex,
            });
        }
    }
    fn finite<const N: usize>(
        v: &Option<Vec<[f32; N]>>,
        attribute: &'static str,
        check_len: &dyn Fn(&'static str, usize) -> Result<(), LevelProblem>,
    ) -> Result<(), LevelProblem> {
        if let Some(v) = v {
            check_len(attribute, v.len())?;
            if let Some(vertex) = v.iter().position(|t| t.iter().any(|c| !c.is_finite())) {
                return Err(LevelProblem::NonFinite { attribute, vertex });
            }
        }
        Ok(())
    }
    finite(&p.tangents, "TANGENT", &check_len)?;
    finite(&p.colors, "COLOR_0", &check_len)?;
    finite(&p.weights, "WEIGHTS_0", &check_len)?;
    for uv in &p.extra_texcoords {
        finite(&Some(uv.clone()), "TEXCOORD_n", &check_len)?;
    }
    if let Some(j) = &p.joints {
        check_len("JOINTS_0", j.len())?;
    }
    for c in &p.extra_colors {
        finite(&Some(c.clone()), "COLOR_n", &check_len)?;
    }
    for w in &p.extra_weights {
        finite(&Some(w.clone()), "WEIGHTS_n", &check_len)?;
    }
    for j in &p.extra_joints {
        check_len("JOINTS_n", j.len())?;
    }
    for (_, d) in p.targets.iter().flat_map(MorphTarget::channels) {
        finite(&Some(d.clone()), "morph target", &check_len)?;
    }
    if let Some(vertex) = p
        .positions
        .iter()
        .position(|v| v.iter().any(|c| !c.is_finite()))
    {
        return Err(LevelProblem::NonFinite {
            attribute: "POSITION",
            vertex,
        });
    }
    Ok(())
}

fn normalized(v: [f32; 3]) -> Option<[f32; 3]> {
    let len = (v[0] as f64).hypot(v[1] as f64).hypot(v[2] as f64);
    if len.is_finite() && len > 1e-20 {
        Some([
            (v[0] as f64 / len) as f32,
            (v[1] as f64 / len) as f32,
            (v[2] as f64 / len) as f32,
        ])
    } else {
        None
    }
}

/// Per-vertex normals as the sum of the incident triangles' unnormalized
/// normals (weights = twice the areas), normalized; `+Z` where that sum is 0.
///
/// On every core: each task owns a range of vertices and walks every
/// triangle, adding the normals of those with a corner in its range, so
/// each vertex still sums its triangles in index order (the same bits for
/// any number of tasks).
fn area_weighted_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let tasks = if indices.len() < PARALLEL_NORMALS_MIN {
        1
    } else {
        rayon::current_num_threads()
    };
    normals_in_tasks(positions, indices, tasks)
}

/// [`area_weighted_normals`] with the vertices split between `tasks` tasks.
fn normals_in_tasks(positions: &[[f32; 3]], indices: &[u32], tasks: usize) -> Vec<[f32; 3]> {
    let n = positions.len();
    let tasks = tasks.max(1);
    let span = n.div_ceil(tasks).max(1);
    let mut acc = vec![[0.0f64; 3]; n];
    acc.par_chunks_mut(span).enumerate().for_each(|(k, acc)| {
        let owned = k * span..k * span + acc.len();
        let mine = |i: u32| owned.contains(&(i as usize));
        for t in indices.chunks_exact(3) {
            if !(mine(t[0]) || mine(t[1]) || mine(t[2])) {
                continue;
            }
            let n = doubled_area_normal(positions, t);
            for &i in t {
                if mine(i) {
                    for (s, d) in acc[i as usize - owned.start].iter_mut().zip(n) {
                        *s += d;
                    }
                }
            }
        }
    });
    acc.par_iter()
        .map(|n| {
            let len = n[0].hypot(n[1]).hypot(n[2]);
            if len > 0.0 && len.is_finite() {
                [
                    (n[0] / len) as f32,
                    (n[1] / len) as f32,
                    (n[2] / len) as f32,
                ]
            } else {
                [0.0, 0.0, 1.0]
            }
        })
        .collect()
}

/// Cross product of triangle `t`'s edges in f64: its normal, twice its area long.
fn doubled_area_normal(positions: &[[f32; 3]], t: &[u32]) -> [f64; 3] {
    let p = |i: u32| positions[i as usize].map(f64::from);
    let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

/// Index count from which [`area_weighted_normals`] splits the vertices
/// between tasks.
const PARALLEL_NORMALS_MIN: usize = 3 << 16;

/// Center and uniform half extent of the chain's bounding box (half extent 1
/// for a degenerate box): [`lodgen_pm::stream::Grid::around`], the one
/// computation `lodgen::progressive::level_grid` puts the stream on too.
fn dequantization(levels: &[Vec<Prepared>]) -> ([f64; 3], f64) {
    let used = levels.iter().flatten().flat_map(|p| &p.positions);
    let grid = lodgen_pm::stream::Grid::around(used, 16);
    (grid.center, grid.half)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The normals one task adds up (the writer's code before it split them).
    fn sequential(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
        let mut acc = vec![[0.0f64; 3]; positions.len()];
        for t in indices.chunks_exact(3) {
            let n = doubled_area_normal(positions, t);
            for &i in t {
                for (s, d) in acc[i as usize].iter_mut().zip(n) {
                    *s += d;
                }
            }
        }
        acc.iter()
            .map(|n| {
                let len = n[0].hypot(n[1]).hypot(n[2]);
                if len > 0.0 && len.is_finite() {
                    n.map(|c| (c / len) as f32)
                } else {
                    [0.0, 0.0, 1.0]
                }
            })
            .collect()
    }

    #[test]
    fn split_normals_have_the_bits_of_one_task() {
        let m = lodgen_pm::shapes::torus_knot(2, 3, 200, 24, 0.05);
        // triangles in a scrambled order, so that a vertex's fan lies
        // anywhere in the list and the sums' order matters
        let k = m.triangles.len();
        let tris: Vec<[u32; 3]> = (0..k).map(|i| m.triangles[(i * 7919) % k]).collect();
        let indices: Vec<u32> = tris.into_iter().flatten().collect();
        let expected = sequential(&m.positions, &indices);
        // an unused vertex keeps +Z
        let mut positions = m.positions.clone();
        positions.push([1.0, 2.0, 3.0]);
        let mut expected = expected;
        expected.push([0.0, 0.0, 1.0]);
        for tasks in [1, 2, 3, 7, 64] {
            let got = normals_in_tasks(&positions, &indices, tasks);
            let bits = |v: &[[f32; 3]]| -> Vec<[u32; 3]> {
                v.iter().map(|n| n.map(f32::to_bits)).collect()
            };
            assert_eq!(bits(&got), bits(&expected), "{tasks} tasks");
        }
    }
}
