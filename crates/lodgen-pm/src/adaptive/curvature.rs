//! The paper's classification: borders (Algorithm 2), the average normal
//! deviation θ over the k-ring umbrella (Algorithm 3, Eqs. 1–3) and its
//! threshold.

use super::options::Threshold;
use crate::mesh::Mesh;
use crate::simplify::legality::fan_count;
use glam::DVec3;
use rayon::prelude::*;

#[inline]
pub(super) fn dv(p: [f32; 3]) -> DVec3 {
    DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]))
}

#[inline]
pub(super) fn fv(p: DVec3) -> [f32; 3] {
    [p.x as f32, p.y as f32, p.z as f32]
}

/// Twice-area normal of a triangle.
#[inline]
pub(super) fn cross_normal(pos: &[[f32; 3]], t: &[u32; 3]) -> DVec3 {
    let [a, b, c] = t.map(|v| dv(pos[v as usize]));
    (b - a).cross(c - a)
}

pub(super) fn vertex_triangles(mesh: &Mesh) -> Vec<Vec<u32>> {
    let mut vt = vec![Vec::new(); mesh.positions.len()];
    for (i, t) in mesh.triangles.iter().enumerate() {
        for &v in t {
            vt[v as usize].push(i as u32);
        }
    }
    vt
}

/// Algorithm 2: a vertex is on the border when its umbrella is incomplete,
/// i.e. some neighbour appears in exactly one of its triangles (or it has no
/// triangle at all). Indices must be in range (a validated mesh).
pub fn boundary_vertices(mesh: &Mesh) -> Vec<bool> {
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(mesh.triangles.len() * 6);
    for t in &mesh.triangles {
        for k in 0..3 {
            pairs.push((t[k], t[(k + 1) % 3]));
            pairs.push((t[k], t[(k + 2) % 3]));
        }
    }
    pairs.sort_unstable();
    let mut border = vec![true; mesh.positions.len()];
    for v in pairs.iter().map(|p| p.0) {
        border[v as usize] = false;
    }
    for run in pairs.chunk_by(|a, b| a == b) {
        if run.len() == 1 {
            border[run[0].0 as usize] = true;
        }
    }
    border
}

/// Vertices the adaptive methods never move: border ones (Algorithm 2), and
/// those on an edge with more than two triangles or where several fans meet.
pub(super) fn fixed_vertices(mesh: &Mesh, vtris: &[Vec<u32>]) -> Vec<bool> {
    let mut fixed = boundary_vertices(mesh);
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(mesh.triangles.len() * 3);
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            pairs.push((a.min(b), a.max(b)));
        }
    }
    pairs.sort_unstable();
    for run in pairs.chunk_by(|a, b| a == b) {
        if run.len() > 2 {
            fixed[run[0].0 as usize] = true;
            fixed[run[0].1 as usize] = true;
        }
    }
    for (v, ts) in vtris.iter().enumerate() {
        if !fixed[v] && fan_count(&mesh.triangles, v as u32, ts) > 1 {
            fixed[v] = true;
        }
    }
    fixed
}

/// Algorithm 3: the average normal deviation θ (radians, in [0, π]) of every
/// vertex over its `k_ring`-deep umbrella (k = 0 is treated as 1). A vertex
/// with no triangle gets 0; one whose vertex or region normal vanishes (a
/// fan that folds back on itself) gets π, so it is never removable.
pub fn normal_deviation(mesh: &Mesh, k_ring: usize) -> Vec<f64> {
    let vtris = vertex_triangles(mesh);
    let alive = vec![true; mesh.triangles.len()];
    deviation(
        &mesh.positions,
        &mesh.triangles,
        &alive,
        &vtris,
        None,
        k_ring,
    )
}

/// θ over the live part of a mesh; `only` restricts which vertices are
/// measured (the others get 0).
pub(super) fn deviation(
    pos: &[[f32; 3]],
    tris: &[[u32; 3]],
    tri_alive: &[bool],
    vtris: &[Vec<u32>],
    only: Option<&[bool]>,
    k_ring: usize,
) -> Vec<f64> {
    let k = k_ring.max(1);
    let normals: Vec<DVec3> = tris
        .par_iter()
        .zip(tri_alive.par_iter())
        .map(|(t, &a)| if a { cross_normal(pos, t) } else { DVec3::ZERO })
        .collect();
    (0..pos.len())
        .into_par_iter()
        .map_init(
            || (Vec::<u32>::new(), Vec::<u32>::new(), Vec::<u32>::new()),
            |(ring, frontier, faces), v| {
                if only.is_some_and(|m| !m[v]) {
                    return 0.0;
                }
                let own: DVec3 = vtris[v]
                    .iter()
                    .filter(|&&t| tri_alive[t as usize])
                    .map(|&t| normals[t as usize].normalize_or_zero())
                    .sum();
                if vtris[v].iter().all(|&t| !tri_alive[t as usize]) {
                    return 0.0;
                }
                ring.clear();
                ring.push(v as u32);
                frontier.clear();
                frontier.push(v as u32);
                faces.clear();
                for _ in 0..k {
                    let mut next: Vec<u32> = Vec::new();
                    for &u in frontier.iter() {
                        for &t in &vtris[u as usize] {
                            if tri_alive[t as usize] {
                                faces.push(t);
                                next.extend_from_slice(&tris[t as usize]);
                            }
                        }
                    }
                    next.sort_unstable();
                    next.dedup();
                    next.retain(|x| ring.binary_search(x).is_err());
                    ring.extend_from_slice(&next);
                    ring.sort_unstable();
                    *frontier = next;
                }
                faces.sort_unstable();
                faces.dedup();
                let region: DVec3 = faces.iter().map(|&t| normals[t as usize]).sum();
                let (a, b) = (own.normalize_or_zero(), region.normalize_or_zero());
                if a == DVec3::ZERO || b == DVec3::ZERO {
                    return std::f64::consts::PI;
                }
                a.dot(b).clamp(-1.0, 1.0).acos()
            },
        )
        .collect()
}

/// The threshold angle of `t` over the θ values `theta` (0 when empty).
/// Non-finite values are ignored.
pub fn threshold_value(theta: &[f64], t: Threshold) -> f64 {
    let vals: Vec<f64> = theta.iter().copied().filter(|x| x.is_finite()).collect();
    if vals.is_empty() {
        return 0.0;
    }
    let n = vals.len() as f64;
    let quantile = |f: f64| {
        let mut s = vals.clone();
        s.sort_unstable_by(f64::total_cmp);
        let f = if f.is_nan() { 0.5 } else { f.clamp(0.0, 1.0) };
        let rank = (f * n).ceil() as usize;
        if rank == 0 {
            // nothing is removable: below the smallest value
            s[0] - 1.0
        } else {
            s[rank - 1]
        }
    };
    match t {
        Threshold::Sigma(s) => {
            let mean = vals.iter().sum::<f64>() / n;
            let var = vals.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n;
            mean + s * var.sqrt()
        }
        Threshold::Median => quantile(0.5),
        Threshold::Fraction(f) => quantile(f),
    }
}

/// Low/high classification: `true` where θ is above the threshold of `t`
/// (high curvature). Returns the flags and the threshold angle.
pub fn classify(theta: &[f64], t: Threshold) -> (Vec<bool>, f64) {
    let limit = threshold_value(theta, t);
    (
        theta.iter().map(|&x| x > limit || x.is_nan()).collect(),
        limit,
    )
}
