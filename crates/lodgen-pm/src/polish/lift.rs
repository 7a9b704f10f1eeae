//! The lift: every vertex of a written level moved by one damped Newton
//! step on its cluster's quadric ([`Quadric::lifted`]), the default polish of
//! the levels (no query, no sample: the quadrics the simplifier started
//! from, summed over each level vertex's cluster).
//!
//! Why: where a pair's fans are nearly flat the quadric's 3×3 system is
//! nearly singular and the simplifier places the merged vertex at the best
//! point of the pair's segment (`Quadric::placement`), which lies on the
//! chord: on a convex patch inside the surface, on a concave one outside.
//! The level's faces then sit off the surface on one side, and their RMS
//! distance carries that offset. The lift moves such a vertex along the
//! well-determined direction of its quadric (the patch's normal) to where its
//! planes are closest, and barely sideways (the damping). A vertex the
//! simplifier placed at its quadric's minimum does not move.
//!
//! Where it applies: the written levels only (`lodgen`'s levels of the QEM
//! method with optimal placement, and the quality table's), like
//! [`crate::polish_clusters`]: the vertex-split log,
//! the progressive stream and a replayed level keep the simplifier's
//! positions, and the contraction order is the simplifier's. (Lifting inside
//! the simplifier, at every segment placement, lowered the 50 % levels' RMS
//! as much but changed the order of the contractions: the 2 % levels'
//! Hausdorff distances moved by −17 to +111 %; docs/quality.md.)
//!
//! Deterministic: the clusters' quadrics are summed in vertex order, each
//! vertex moved on its own.

use rayon::prelude::*;

use crate::mesh::Mesh;
use crate::simplify::quadric::Quadric;
use crate::simplify::{vertex_quadrics, SimplifyOptions};
use glam::DVec3;

/// The quadrics of the original's vertices (face planes, border constraint
/// planes as `opts` weigh them), for [`lift`].
#[derive(Clone, Debug)]
pub struct LiftQuadrics(Vec<Quadric>);

impl LiftQuadrics {
    /// `original` in the progressive numbering (the mesh the simplifier
    /// ran on, `ProgressiveMesh::mesh_at_splits(len)`).
    pub fn new(original: &Mesh, opts: &SimplifyOptions) -> LiftQuadrics {
        LiftQuadrics(vertex_quadrics(original, opts))
    }
}

/// Lift the vertices of `level` (a level of the progressive mesh, numbered
/// as the original's vertices) whose clusters `reps` gives
/// (`ProgressiveMesh::representatives`: original vertex → level vertex).
/// Returns how many moved.
pub fn lift(quadrics: &LiftQuadrics, level: &mut Mesh, reps: &[u32]) -> usize {
    let n = level.positions.len();
    let mut sum = vec![Quadric::default(); n];
    for (q, &r) in quadrics.0.iter().zip(reps) {
        if let Some(s) = sum.get_mut(r as usize) {
            *s += *q;
        }
    }
    level
        .positions
        .par_iter_mut()
        .zip(&sum)
        .map(|(p, q)| {
            if q.weight <= 0.0 {
                return 0;
            }
            let s = DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
            match q.lifted(s) {
                Some(x) => {
                    *p = [x.x as f32, x.y as f32, x.z as f32];
                    1
                }
                None => 0,
            }
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::{MeasureOptions, MeshRef};
    use crate::{simplify, SimplifyOptions};

    /// A UV sphere of radius 1.
    fn sphere(rings: u32, segments: u32) -> (Vec<[f32; 3]>, Vec<u32>) {
        let mut pos = vec![[0.0, 0.0, 1.0]];
        for r in 1..rings {
            let th = std::f64::consts::PI * f64::from(r) / f64::from(rings);
            for s in 0..segments {
                let ph = 2.0 * std::f64::consts::PI * f64::from(s) / f64::from(segments);
                pos.push([
                    (th.sin() * ph.cos()) as f32,
                    (th.sin() * ph.sin()) as f32,
                    th.cos() as f32,
                ]);
            }
        }
        pos.push([0.0, 0.0, -1.0]);
        let last = pos.len() as u32 - 1;
        let at = |r: u32, s: u32| 1 + (r - 1) * segments + s % segments;
        let mut idx = Vec::new();
        for s in 0..segments {
            idx.extend([0, at(1, s), at(1, s + 1)]);
            idx.extend([last, at(rings - 1, s + 1), at(rings - 1, s)]);
        }
        for r in 1..rings - 1 {
            for s in 0..segments {
                let (a, b, c, d) = (at(r, s), at(r, s + 1), at(r + 1, s), at(r + 1, s + 1));
                idx.extend([a, c, b, b, c, d]);
            }
        }
        (pos, idx)
    }

    #[test]
    fn a_sphere_level_is_lifted_towards_the_sphere() {
        let (pos, idx) = sphere(120, 240);
        let opts = SimplifyOptions::DEFAULT.with_target_ratio(0.5);
        let out = simplify(&pos, &idx, &opts).expect("a sphere simplifies");
        let pm = &out.pm;
        let k = pm.splits_for_triangles(idx.len() / 3 / 2);
        let full = pm.mesh_at_splits(pm.len());
        let mut cursor = pm.cursor();
        cursor.seek(k);
        let level = cursor.mesh().clone();
        let quadrics = LiftQuadrics::new(&full, &opts);
        let mut lifted = level.clone();
        let moved = lift(&quadrics, &mut lifted, &pm.representatives(k));
        assert!(moved > 0, "nothing lifted");
        // the RMS distance to the sphere's mesh, both ways, lower lifted
        let original = MeshRef::new(&full.positions, &full.triangles);
        let rms = |m: &Mesh| {
            crate::metric::measure(
                original,
                MeshRef::new(&m.positions, &m.triangles),
                &MeasureOptions::DEFAULT,
            )
            .expect("measurable")
            .rms_percent()
        };
        let (before, after) = (rms(&level), rms(&lifted));
        assert!(after < before * 0.97, "RMS {before} -> {after} %");
        assert_eq!(level.triangles, lifted.triangles);
        // the same bits on one thread
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("a pool");
        let mut again = level.clone();
        pool.install(|| lift(&quadrics, &mut again, &pm.representatives(k)));
        assert_eq!(again.positions, lifted.positions);
    }
}
