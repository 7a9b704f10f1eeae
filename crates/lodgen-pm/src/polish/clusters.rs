//! The polish's pairs found from the simplification itself, without a
//! hierarchy or a search: every original vertex was merged into exactly one
//! level vertex (its representative, [`ProgressiveMesh::representatives`]),
//! so
//!
//! * A → B: each original vertex (a third of the area of its faces) is
//!   paired with its closest point on the level faces around its
//!   representative;
//! * B → A: each of the three points on a level face is paired with the
//!   closest point on the original faces around the original vertex nearest
//!   to it among the clusters of the face's corners (the original vertices
//!   merged into each).
//!
//! The pairs are approximate (a closest point just outside those faces is
//! missed), which a fit tolerates: the measurement that follows is exact.
//! Each pass is linear in the original's size, with a small constant.
//!
//! [`ProgressiveMesh::representatives`]: crate::ProgressiveMesh::representatives

use rayon::prelude::*;

use super::{
    add_border_planes, add_pairs, apply, barycentric, compatible, face_normals, guard, solve_all,
    unit_normal, Acc, Pair, PolishOptions, PolishStats, Topology, BLOCK, LEVEL_POINTS,
};
use crate::mesh::Mesh;
use crate::metric::triangle::{closest_point_on_triangle, distance_squared, widen};
use crate::metric::MeshRef;

/// Compressed lists: the items of `k` are `items[offsets[k]..offsets[k + 1]]`.
struct Lists {
    offsets: Vec<u32>,
    items: Vec<u32>,
}

impl Lists {
    /// `count` lists from `(list, item)` pairs, each list's items in the
    /// order given.
    fn new(count: usize, pairs: impl Iterator<Item = (u32, u32)> + Clone) -> Lists {
        let mut offsets = vec![0u32; count + 1];
        for (k, _) in pairs.clone() {
            offsets[k as usize + 1] += 1;
        }
        for k in 0..count {
            offsets[k + 1] += offsets[k];
        }
        let mut next = offsets.clone();
        let mut items = vec![0u32; offsets[count] as usize];
        for (k, item) in pairs {
            let slot = &mut next[k as usize];
            items[*slot as usize] = item;
            *slot += 1;
        }
        Lists { offsets, items }
    }

    fn of(&self, k: u32) -> &[u32] {
        let k = k as usize;
        &self.items[self.offsets[k] as usize..self.offsets[k + 1] as usize]
    }
}

/// No face across an edge: a border, or an edge of three or more faces.
const NONE: u32 = u32::MAX;
/// Across an edge of three or more faces.
const MANY: u32 = u32::MAX - 1;

/// For every face of `triangles`, the face across each of its edges (edge
/// `k` from corner `k` to corner `k + 1`): [`NONE`] on a border, [`MANY`]
/// on an edge of three or more faces.
fn neighbours(vertices: usize, triangles: &[[u32; 3]]) -> Adjacency {
    let fans = Lists::new(
        vertices,
        triangles
            .iter()
            .enumerate()
            .flat_map(|(f, t)| t.map(|v| (v, f as u32))),
    );
    let across = triangles
        .par_iter()
        .enumerate()
        .map(|(f, t)| {
            [0, 1, 2].map(|k| {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let mut across = NONE;
                for &g in fans.of(a) {
                    if g as usize != f && triangles[g as usize].contains(&b) {
                        across = if across == NONE { g } else { MANY };
                    }
                }
                across
            })
        })
        .collect();
    Adjacency { fans, across }
}

/// The faces around each vertex, and the face across each edge.
struct Adjacency {
    fans: Lists,
    across: Vec<[u32; 3]>,
}

/// Most faces a walk visits before it gives up ([`walk`]).
const MAX_STEPS: usize = 24;

/// A closest point found by [`walk`]: squared distance, face, point.
type Hit = (f64, u32, [f64; 3]);

/// The closest point to `x` on the surface of `triangles`, walking from
/// face `start` across the edge the closest point lies on while the face
/// across is closer: `(hit, converged)`, converged when the walk stopped at
/// a local minimum (a face's inside, or an edge or corner with no closer
/// face across) within [`MAX_STEPS`] faces.
fn walk(
    x: [f64; 3],
    start: u32,
    triangles: &[[u32; 3]],
    point: impl Fn(u32) -> [f64; 3],
    adjacency: &Adjacency,
) -> (Hit, bool) {
    let across = &adjacency.across;
    let test = |f: u32| -> Hit {
        let [a, b, c] = triangles[f as usize].map(&point);
        let q = closest_point_on_triangle(x, a, b, c);
        (distance_squared(x, q), f, q)
    };
    let mut best = test(start);
    for _ in 0..MAX_STEPS {
        let (_, f, q) = best;
        let t = triangles[f as usize];
        let Some(bary) = barycentric(q, t.map(&point)) else {
            return (best, true);
        };
        let mut next: Option<Hit> = None;
        // at a corner: every face around it
        if let Some(k) = (0..3).find(|&k| bary[k] >= 1.0 - 1e-9) {
            for &g in adjacency.fans.of(t[k]) {
                let h = test(g);
                if h.0 < best.0 && next.is_none_or(|n| h.0 < n.0) {
                    next = Some(h);
                }
            }
        }
        for k in 0..3 {
            // edge k (corners k, k + 1) holds the point when the third
            // corner's weight is 0
            let g = across[f as usize][k];
            if bary[(k + 2) % 3] > 1e-9 || g == NONE || g == MANY {
                continue;
            }
            let h = test(g);
            if h.0 < best.0 && next.is_none_or(|n| h.0 < n.0) {
                next = Some(h);
            }
        }
        match next {
            Some(h) => best = h,
            None => return (best, true),
        }
    }
    (best, false)
}

/// What the polish reads of the original, once for all its levels: the
/// face across each edge, each face's unit normal, each vertex's share of
/// the area, its normal and one of its faces.
pub struct Original<'a> {
    mesh: MeshRef<'a>,
    adjacency: Adjacency,
    normals: Vec<[f64; 3]>,
    /// Per vertex: a third of the area of its faces, and their area-weighted
    /// unit normal.
    vertices: Vec<(f64, [f64; 3])>,
}

impl<'a> Original<'a> {
    /// `mesh`'s adjacency, normals and areas (its indices must be valid).
    pub fn new(mesh: MeshRef<'a>) -> Original<'a> {
        let n = mesh.positions.len();
        let faces: Vec<([f64; 3], f64)> = mesh
            .triangles
            .par_iter()
            .map(|&t| unit_normal(mesh, t))
            .collect();
        let mut vertices = vec![(0.0, [0.0; 3]); n];
        for (t, &(u, a2)) in mesh.triangles.iter().zip(&faces) {
            for v in t {
                let s = &mut vertices[*v as usize];
                s.0 += a2 / 6.0;
                for (sk, uk) in s.1.iter_mut().zip(u) {
                    *sk += a2 * uk;
                }
            }
        }
        for s in &mut vertices {
            let l = (s.1[0] * s.1[0] + s.1[1] * s.1[1] + s.1[2] * s.1[2]).sqrt();
            if l > 0.0 {
                s.1 = s.1.map(|x| x / l);
            }
        }
        Original {
            mesh,
            adjacency: neighbours(n, mesh.triangles),
            normals: faces.into_iter().map(|f| f.0).collect(),
            vertices,
        }
    }

    fn point(&self, v: u32) -> [f64; 3] {
        widen(self.mesh.positions[v as usize])
    }

    /// [`walk`] on the original from its face `start`.
    fn walk(&self, x: [f64; 3], start: u32) -> (Hit, bool) {
        walk(
            x,
            start,
            self.mesh.triangles,
            |v| self.point(v),
            &self.adjacency,
        )
    }
}

/// Polishes `level` against `original` (module docs of [`super`]; the
/// pairs: this module's docs). `level` must be the mesh after some splits
/// of a progressive mesh whose full mesh is `original`, and
/// `representatives` that progressive mesh's
/// [`representatives`](crate::ProgressiveMesh::representatives) at that
/// level: level triangle `t` is original triangle `t` with its corners
/// merged. Vertices no triangle uses are left as they are.
///
/// # Panics
/// When `representatives` is shorter than the original's vertices, names a
/// vertex the level does not have, or the level has more triangles than
/// the original.
pub fn polish_clusters(
    original: &Original<'_>,
    level: &mut Mesh,
    representatives: &[u32],
    opts: &PolishOptions,
) -> PolishStats {
    let mut stats = PolishStats::default();
    let n = level.positions.len();
    let faces = level.triangles.len();
    if faces == 0 || original.mesh.triangles.is_empty() {
        return stats;
    }
    assert!(representatives.len() >= original.mesh.positions.len());
    assert!(faces <= original.mesh.triangles.len());
    let level_across = neighbours(n, &level.triangles);
    let topo = topology(level, &level_across.across);
    let start = walk_starts(original, level, representatives);
    stats.samples = original.mesh.positions.len();
    for _ in 0..opts.iterations {
        let pos: Vec<[f64; 3]> = level.positions.iter().map(|&p| widen(p)).collect();
        let normals = face_normals(&pos, level);
        let mut acc = vec![Acc::default(); n];
        let mut add = |pairs: Vec<Option<Pair>>| add_pairs(&mut acc, &pos, level, &normals, pairs);
        // A → B: each original vertex and its closest level point
        let nv = original.mesh.positions.len() as u32;
        for block in (0..nv).step_by(BLOCK) {
            let end = (block + BLOCK as u32).min(nv);
            let pairs: Vec<Option<Pair>> = (block..end)
                .into_par_iter()
                .map(|v| {
                    let (weight, normal) = original.vertices[v as usize];
                    let s = start[v as usize];
                    if weight <= 0.0 || s == NONE {
                        return None;
                    }
                    let x = original.point(v);
                    let ((_, face, q), true) =
                        walk(x, s, &level.triangles, |w| pos[w as usize], &level_across)
                    else {
                        return None;
                    };
                    if !compatible(normal, normals[face as usize]?) {
                        return None;
                    }
                    let t = level.triangles[face as usize];
                    let bary = barycentric(q, t.map(|w| pos[w as usize]))?;
                    Some(Pair {
                        face,
                        bary,
                        target: x,
                        weight,
                    })
                })
                .collect();
            add(pairs);
        }
        // B → A: points on each level face and their closest original
        // points, walking from the original face of the same number
        let per = LEVEL_POINTS.len();
        for block in (0..faces).step_by(BLOCK / per) {
            let end = (block + BLOCK / per).min(faces);
            let pairs: Vec<Option<Pair>> = (block * per..end * per)
                .into_par_iter()
                .map(|i| {
                    let face = (i / per) as u32;
                    let bary = LEVEL_POINTS[i % per];
                    let t = level.triangles[face as usize];
                    let [a, b, c] = t.map(|v| pos[v as usize]);
                    let q = [0, 1, 2].map(|k| bary[0] * a[k] + bary[1] * b[k] + bary[2] * c[k]);
                    let n = super::area_vector(&pos, t);
                    let area = 0.5 * n.iter().map(|x| x * x).sum::<f64>().sqrt();
                    let ((_, tri, target), true) = original.walk(q, face) else {
                        return None;
                    };
                    if !compatible(original.normals[tri as usize], normals[face as usize]?) {
                        return None;
                    }
                    Some(Pair {
                        face,
                        bary,
                        target,
                        weight: area / per as f64,
                    })
                })
                .collect();
            add(pairs);
        }
        add_border_planes(&pos, &topo, &normals, &mut acc);
        let mut target = solve_all(&pos, &acc, &topo);
        // (a vertex's distance to the original: walked from the original
        // face of one of its level faces; an upper bound when the walk
        // gives up)
        guard(&pos, &mut target, &acc, |v, x| {
            let s = start[v];
            if s == NONE {
                return 0.0;
            }
            original.walk(x, s).0 .0
        });
        if !apply(&pos, &target, level, &mut stats) {
            break;
        }
    }
    stats
}

/// Where each walk starts: for an original vertex, a level face around
/// its representative, one that is one of its own faces if any is left
/// (level triangle `t` is original triangle `t`); [`NONE`] for a vertex of
/// no face.
fn walk_starts(original: &Original<'_>, level: &Mesh, representatives: &[u32]) -> Vec<u32> {
    let faces = level.triangles.len();
    let mut start = vec![NONE; original.mesh.positions.len()];
    for (f, t) in original.mesh.triangles.iter().enumerate().take(faces) {
        for &v in t {
            if start[v as usize] == NONE {
                start[v as usize] = f as u32;
            }
        }
    }
    for (f, t) in level.triangles.iter().enumerate() {
        for &r in t {
            if start[r as usize] == NONE {
                start[r as usize] = f as u32;
            }
        }
    }
    for v in 0..start.len() {
        if start[v] == NONE {
            start[v] = start[representatives[v] as usize];
        }
    }
    start
}

/// The level's [`Topology`] from the faces across its edges: an edge with
/// no face across is a border, the ends of an edge of three or more faces
/// are fixed.
fn topology(level: &Mesh, across: &[[u32; 3]]) -> Topology {
    let mut movable = vec![false; level.positions.len()];
    for t in &level.triangles {
        for &v in t {
            movable[v as usize] = true;
        }
    }
    let mut border = Vec::new();
    for (f, (t, g)) in level.triangles.iter().zip(across).enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            match g[k] {
                NONE => border.push((a.min(b), a.max(b), f as u32)),
                MANY => {
                    movable[a as usize] = false;
                    movable[b as usize] = false;
                }
                _ => {}
            }
        }
    }
    Topology { movable, border }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// From a face a few faces away (its centroid 0.15–0.3 from the point,
    /// on a torus of tube radius 0.35: as far as a coarse level's cluster),
    /// the walk reaches the closest point a search of every face finds, for
    /// points just off the surface (the pairs the polish makes). Fails when the walk stops at a corner
    /// without looking at the faces around it, or steps to a farther face.
    #[test]
    fn walk_reaches_the_closest_point() {
        let m = crate::shapes::torus(1.0, 0.35, 48, 24);
        let adjacency = neighbours(m.positions.len(), &m.triangles);
        let point = |v: u32| widen(m.positions[v as usize]);
        let brute = |x: [f64; 3]| {
            m.triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(point);
                    distance_squared(x, closest_point_on_triangle(x, a, b, c))
                })
                .fold(f64::INFINITY, f64::min)
        };
        let mut reached = 0;
        for (f, t) in m.triangles.iter().enumerate().step_by(7) {
            // a point 0.02 off the face's centroid, along its normal
            let [a, b, c] = t.map(point);
            let n = unit_normal(MeshRef::new(&m.positions, &m.triangles), *t).0;
            let x = [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0 + 0.02 * n[k]);
            let centroid = |t: &[u32; 3]| {
                let [a, b, c] = t.map(point);
                [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0)
            };
            let start = m
                .triangles
                .iter()
                .position(|t| (0.0225..0.09).contains(&distance_squared(centroid(t), x)))
                .expect("a face at that distance") as u32;
            let _ = f;
            let ((d, _, _), converged) = walk(x, start, &m.triangles, point, &adjacency);
            if converged && d <= brute(x) * (1.0 + 1e-9) + 1e-18 {
                reached += 1;
            }
        }
        let tried = m.triangles.len().div_ceil(7);
        assert_eq!(
            reached, tried,
            "{reached} of {tried} walks reached the closest point"
        );
    }
}
