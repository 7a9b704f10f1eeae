//! The original's hierarchy built over the welded input's numbering and
//! renumbered to the progressive mesh's, the build over the progressive
//! numbering bit for bit ([`Reference::renumbered`]).
//!
//! Why: the progressive mesh numbers the original's vertices and triangles
//! in the order they appear during refinement, which scatters neighbours
//! over the whole mesh, while the welded input numbers them along a Z-order
//! curve. Every pass of the hierarchy's build over the original (its box,
//! its Z-order, its leaves' boxes, its sample set) reads the positions of
//! each triangle's corners: at 4.4M triangles nearly every such read missed
//! the caches (`MeshRef::bbox_diagonal` alone 560 ms over the progressive
//! numbering, 70 ms over the welded one).

use std::time::{Duration, Instant};

use rayon::prelude::*;

use lodgen_pm::metric::{MeshRef, Reference};
use lodgen_pm::Mesh;

use super::measure::Measurer;

/// `new[origin[i]] = i`: the inverse of a one-to-one map (entries out of
/// range are skipped, and numbers no entry maps to stay `u32::MAX`).
pub(super) fn inverse(origin: &[u32]) -> Vec<u32> {
    let mut new = vec![u32::MAX; origin.len()];
    for (i, &o) in origin.iter().enumerate() {
        if let Some(n) = new.get_mut(o as usize) {
            *n = i as u32;
        }
    }
    new
}

/// [`inverse`] of `origin`, in `origin`'s own block when it is a
/// permutation (peak memory: at 4.4M triangles the triangle map and its
/// inverse, 18 MB each, were held together beside both copies of the
/// original and its hierarchy, the measurement's peak): each cycle is
/// walked once, its entries pointed back, with the top bit marking those
/// done. Other maps are inverted into a new block.
pub(super) fn inverted(mut origin: Vec<u32>) -> Vec<u32> {
    const DONE: u32 = 1 << 31;
    let n = origin.len();
    let mut seen = vec![false; n];
    let permutation = n < DONE as usize
        && origin.iter().all(|&o| {
            let o = o as usize;
            o < n && !std::mem::replace(&mut seen[o], true)
        });
    if !permutation {
        return inverse(&origin);
    }
    drop(seen);
    for start in 0..n {
        if origin[start] & DONE != 0 {
            continue;
        }
        // origin[prev] = cur along the cycle: new[cur] = prev
        let (mut prev, mut cur) = (start, origin[start] as usize);
        while cur != start {
            let next = origin[cur] as usize;
            origin[cur] = prev as u32 | DONE;
            (prev, cur) = (cur, next);
        }
        origin[start] = prev as u32 | DONE;
    }
    for o in &mut origin {
        *o &= !DONE;
    }
    origin
}

/// `full` (the progressive mesh fully refined, whose vertex `i` is the
/// welded input's `vertex_origin[i]` and triangle `t` its
/// `triangle_origin[t]`) in the welded input's numbering; `None` when the
/// maps are not one-to-one onto `full`'s vertices and triangles.
pub(super) fn in_input_order(
    full: &Mesh,
    vertex_origin: &[u32],
    triangle_origin: &[u32],
) -> Option<Mesh> {
    if vertex_origin.len() != full.positions.len() || triangle_origin.len() != full.triangles.len()
    {
        return None;
    }
    // (a gather in the welded order, on every core: the reads scatter, the
    // writes do not)
    let positions = inverse(vertex_origin)
        .par_iter()
        .map(|&i| full.positions.get(i as usize).copied())
        .collect::<Option<_>>()?;
    let triangles = inverse(triangle_origin)
        .par_iter()
        .map(|&i| {
            let c = full.triangles.get(i as usize)?;
            let map = |v: u32| vertex_origin.get(v as usize).copied();
            Some([map(c[0])?, map(c[1])?, map(c[2])?])
        })
        .collect::<Option<_>>()?;
    Some(Mesh {
        positions,
        triangles,
    })
}

/// The inverse of [`in_input_order`]: `welded` back in the progressive
/// numbering (`vertex_new`: the inverse of `vertex_origin`). The maps are
/// those `welded` was made with, so every index is in range.
pub(super) fn in_progressive_order(
    welded: &Mesh,
    vertex_origin: &[u32],
    triangle_origin: &[u32],
    vertex_new: &[u32],
) -> Mesh {
    Mesh {
        positions: vertex_origin
            .par_iter()
            .map(|&w| welded.positions[w as usize])
            .collect(),
        triangles: triangle_origin
            .par_iter()
            .map(|&w| welded.triangles[w as usize].map(|v| vertex_new[v as usize]))
            .collect(),
    }
}

/// The original's hierarchy built over `full` in the welded input's
/// numbering ([`in_input_order`]), `full` freed meanwhile and made again
/// ([`in_progressive_order`]), the hierarchy renumbered onto it
/// ([`Reference::renumbered`]: the build over `full` bit for bit), and the
/// wall time that took; with `full` (the same mesh) to borrow beside it.
/// `None` (and `full` unchanged) when the maps are not a renumbering of
/// `full`; `None` after the build when it fails (an invalid mesh: the
/// caller's own build then names the triangle in its numbering) or when two
/// triangles' centroids or two vertices share a Morton code: then build over
/// `full` itself.
pub(super) fn reference_in_input_order<'f>(
    full: &'f mut Mesh,
    vertex_origin: Vec<u32>,
    triangle_origin: Vec<u32>,
) -> (&'f Mesh, Option<(Reference<'f>, Duration)>) {
    let t = Instant::now();
    let Some(welded) = in_input_order(full, &vertex_origin, &triangle_origin) else {
        return (full, None);
    };
    // (the two copies never live beside the build's buffers)
    *full = Mesh::default();
    let reference = Reference::new(MeshRef::new(&welded.positions, &welded.triangles));
    let vertex_new = inverse(&vertex_origin);
    *full = in_progressive_order(&welded, &vertex_origin, &triangle_origin, &vertex_new);
    // (the maps freed, or inverted in place, before the renumbering, which
    // holds both copies)
    drop(vertex_origin);
    let triangle_new = inverted(triangle_origin);
    let full: &'f Mesh = full;
    let r = reference.ok().and_then(|r| {
        r.renumbered(
            MeshRef::new(&full.positions, &full.triangles),
            &vertex_new,
            &triangle_new,
        )
    });
    (full, r.map(|r| (r, t.elapsed())))
}

/// A progressive mesh's `vertex_origin`, `triangle_origin` and length.
pub(super) type Origins = (Vec<u32>, Vec<u32>, usize);

/// The measurer of a mesh whose levels are measured, `full` its original
/// (the progressive mesh of `splits` splits fully refined, numbered by
/// `vertex_origin` and `triangle_origin`; the maps are freed once used), with the original's
/// hierarchy built by [`reference_in_input_order`] (or, where that cannot
/// be, left to the measurer's own build), and `full` to borrow beside it;
/// `index` and `name` name the mesh in errors.
pub(super) fn measurer_in_input_order<'f>(
    full: &'f mut Mesh,
    (vertex_origin, triangle_origin, splits): Origins,
    (index, name): (usize, &'f str),
) -> (&'f Mesh, Measurer<'f>) {
    let (full, built) = reference_in_input_order(full, vertex_origin, triangle_origin);
    let m = Measurer::measured(splits, full, index, name);
    if let Some((r, took)) = built {
        m.set_reference(r, took);
    }
    (full, m)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The renumbered hierarchy measures every level as the one built over
    /// the progressive numbering does, bit for bit, and maps that are not
    /// one-to-one are refused. Fails when the copy's corners are left in the
    /// progressive numbering (the renumbering check then refuses it).
    #[test]
    fn the_input_order_reference_measures_as_the_direct_one() {
        let m = lodgen_pm::shapes::torus_knot(2, 3, 160, 12, 0.02);
        let indices: Vec<u32> = m.triangles.iter().flatten().copied().collect();
        let opts = lodgen_pm::SimplifyOptions::DEFAULT.with_target_ratio(0.02);
        let pm = lodgen_pm::simplify(&m.positions, &indices, &opts)
            .unwrap()
            .pm;
        let fine = pm.mesh_at_splits(pm.len());
        let mut full = fine.clone();
        let maps = (pm.vertex_origin.clone(), pm.triangle_origin.clone());
        let (full, r) = reference_in_input_order(&mut full, maps.0, maps.1);
        let r = r.unwrap().0;
        // (made again as it was)
        assert_eq!(full, &fine);
        let direct = Reference::new(MeshRef::new(&fine.positions, &fine.triangles)).unwrap();
        let mopts = lodgen_pm::metric::MeasureOptions::DEFAULT;
        for k in [pm.len() / 2, pm.len() / 8, 0] {
            let level = pm.mesh_at_splits(k);
            let b = MeshRef::new(&level.positions, &level.triangles);
            assert_eq!(r.measure(b, &mopts), direct.measure(b, &mopts));
        }
        // (maps that are not one-to-one: refused)
        let mut bad = pm.vertex_origin.clone();
        bad[1] = bad[0];
        assert!(in_input_order(&fine, &bad, &pm.triangle_origin).is_none());
    }

    /// `inverted` gives `inverse`'s map for permutations (inverted in
    /// place: one cycle, many, fixed points) and for maps that are not
    /// (repeated or out-of-range entries). Fails when a cycle is walked
    /// the wrong way round (the inverse of a 3-cycle is the other one).
    #[test]
    fn inverted_in_place_is_the_inverse() {
        let mut rng = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            rng
        };
        let mut maps: Vec<Vec<u32>> = vec![
            vec![],
            vec![0],
            vec![1, 2, 0],
            vec![2, 0, 1, 3],
            vec![1, 1, 0],
            vec![0, 5, 1],
        ];
        for n in [10usize, 257, 4096] {
            let mut p: Vec<u32> = (0..n as u32).collect();
            for i in (1..n).rev() {
                p.swap(i, (next() % (i as u64 + 1)) as usize);
            }
            maps.push(p);
        }
        for m in maps {
            let want = inverse(&m);
            assert_eq!(inverted(m.clone()), want, "{m:?}");
            if m.len() == 3 && m[0] == 1 && m[1] == 2 {
                assert_eq!(want, vec![2, 0, 1]);
            }
        }
    }
}
