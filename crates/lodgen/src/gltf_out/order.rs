//! The triangle order of a written primitive: meshopt's vertex cache
//! optimisation, on every core for a large primitive.
//!
//! meshopt's `optimizeVertexCache` is one sequential walk: on the 4.4M-
//! triangle bunny the 50 % level (2.2M triangles, its triangles in the
//! progressive mesh's order, scattered over the surface) took the writer's
//! whole phase on one core. A primitive of more than `CHUNKED_MIN`
//! triangles is therefore cut into spatially compact chunks of `CHUNK`
//! triangles (triangles sorted by the Morton code of their centroid in the
//! primitive's box, ties by triangle number), each chunk's vertices
//! numbered apart (in order of first use) and optimised alone, in parallel, and the chunks
//! concatenated in Morton order. The cut depends on the primitive only,
//! never on the thread count, so the output is the same for any thread
//! count. What a chunk boundary costs (a vertex shared by two chunks is
//! fetched by both): `chunked_order_keeps_the_cache_efficiency`.
//! Smaller primitives keep meshopt's order of the whole index buffer.

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

/// Primitives of more triangles than this are ordered in chunks.
const CHUNKED_MIN: usize = 1 << 18;

/// Triangles per chunk.
const CHUNK: usize = 1 << 16;

/// `indices` (a triangle list over `positions`) in vertex cache order.
pub(super) fn vertex_cache_order(indices: &[u32], positions: &[[f32; 3]]) -> Vec<u32> {
    let n = positions.len();
    if indices.len() / 3 <= CHUNKED_MIN {
        return meshopt::optimize_vertex_cache(indices, n);
    }
    chunked(indices, positions, CHUNK)
}

/// The chunked order, `chunk` triangles a chunk (`indices` valid for
/// `positions`, checked by the writer's validation before).
fn chunked(indices: &[u32], positions: &[[f32; 3]], chunk: usize) -> Vec<u32> {
    let tris: Vec<[u32; 3]> = indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    let order = morton_order(&tris, positions);
    let n = positions.len();
    let pieces: Vec<Vec<u32>> = order
        .par_chunks(chunk)
        // (a global → local map per worker, reset after each chunk)
        .map_init(
            || vec![u32::MAX; n],
            |local_of, ids| {
                // the chunk's vertices numbered in order of first use
                let mut verts: Vec<u32> = Vec::new();
                let mut local: Vec<u32> = Vec::with_capacity(ids.len() * 3);
                for &v in ids.iter().flat_map(|&t| &tris[t as usize]) {
                    let l = &mut local_of[v as usize];
                    if *l == u32::MAX {
                        *l = verts.len() as u32;
                        verts.push(v);
                    }
                    local.push(*l);
                }
                for &v in &verts {
                    local_of[v as usize] = u32::MAX;
                }
                meshopt::optimize_vertex_cache(&local, verts.len())
                    .into_iter()
                    .map(|l| verts[l as usize])
                    .collect()
            },
        )
        .collect();
    pieces.concat()
}

/// Triangle numbers sorted by the Morton code of their centroid in the
/// box of the used positions (21 bits an axis), ties by number.
fn morton_order(tris: &[[u32; 3]], positions: &[[f32; 3]]) -> Vec<u32> {
    let (lo, hi) = used_box(tris, positions);
    let scale: [f64; 3] = std::array::from_fn(|k| {
        let extent = hi[k] as f64 - lo[k] as f64;
        if extent > 0.0 {
            ((1u32 << 21) - 1) as f64 / extent
        } else {
            0.0
        }
    });
    let mut keyed: Vec<(u64, u32)> = tris
        .par_iter()
        .enumerate()
        .map(|(i, t)| {
            // (each corner read once: the corners lie anywhere in memory)
            let p = t.map(|v| positions[v as usize]);
            let cell: [u64; 3] = std::array::from_fn(|k| {
                let c = p.iter().map(|q| q[k] as f64).sum::<f64>() / 3.0;
                // (in [0, 2^21 - 1]: the centroid lies in the box)
                ((c - lo[k] as f64) * scale[k]).clamp(0.0, ((1u32 << 21) - 1) as f64) as u64
            });
            (lodgen_pm::metric::interleave3(cell), i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// The box of the positions `tris` use: the used vertices marked, then
/// their positions read in order (exact, so the box of the corners).
fn used_box(tris: &[[u32; 3]], positions: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let used: Vec<AtomicBool> = positions.iter().map(|_| AtomicBool::new(false)).collect();
    tris.par_iter().for_each(|t| {
        for &v in t {
            used[v as usize].store(true, Ordering::Relaxed);
        }
    });
    positions
        .par_iter()
        .zip(&used)
        .filter(|(_, u)| u.load(Ordering::Relaxed))
        .map(|(p, _)| (*p, *p))
        .reduce(
            || ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
            |(a, b), (c, d)| {
                (
                    std::array::from_fn(|k| a[k].min(c[k])),
                    std::array::from_fn(|k| b[k].max(d[k])),
                )
            },
        )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `side` × `side` grid of squares (two triangles each), its vertices
    /// and triangles shuffled (the progressive mesh's scattered order).
    fn shuffled_grid(side: u32) -> (Vec<[f32; 3]>, Vec<u32>) {
        let m = lodgen_pm::shapes::grid(side, side, |x, y| (x * 3.0).sin() * (y * 2.0).cos());
        let nv = m.positions.len();
        // a fixed permutation: multiplication by an odd constant mod 2^k
        // restricted to 0..n (cycle walking)
        let perm = |n: usize, a: u64| -> Vec<u32> {
            let bits = (n as u64).next_power_of_two();
            (0..n as u64)
                .map(|i| {
                    let mut x = i;
                    loop {
                        x = (x.wrapping_mul(a).wrapping_add(12345)) & (bits - 1);
                        if x < n as u64 {
                            break x as u32;
                        }
                    }
                })
                .collect()
        };
        let vp = perm(nv, 2_654_435_761);
        let mut positions = vec![[0.0f32; 3]; nv];
        for (v, p) in m.positions.iter().enumerate() {
            positions[vp[v] as usize] = *p;
        }
        let tp = perm(m.triangles.len(), 40_503);
        let mut tris = vec![[0u32; 3]; m.triangles.len()];
        for (t, tri) in m.triangles.iter().enumerate() {
            tris[tp[t] as usize] = tri.map(|v| vp[v as usize]);
        }
        (positions, tris.into_iter().flatten().collect())
    }

    fn sorted_triangles(indices: &[u32]) -> Vec<[u32; 3]> {
        let mut t: Vec<[u32; 3]> = indices
            .chunks_exact(3)
            .map(|t| {
                // the same triangle whichever corner comes first
                let r = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
                [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
            })
            .collect();
        t.sort_unstable();
        t
    }

    #[test]
    fn morton_codes_interleave_the_bits() {
        for x in [0u64, 1, 2, 5, 0x1f_ffff, 0x15_5555, 123_456] {
            let s = lodgen_pm::metric::interleave3([x, 0, 0]);
            for b in 0..21 {
                assert_eq!((s >> (3 * b)) & 1, (x >> b) & 1, "bit {b} of {x}");
            }
            assert_eq!(s & !0x1249_2492_4924_9249, 0, "{x}: only every third bit");
        }
    }

    #[test]
    fn chunked_order_keeps_every_triangle_and_its_winding() {
        let (positions, indices) = shuffled_grid(100);
        let out = chunked(&indices, &positions, 1000);
        assert_eq!(out.len(), indices.len());
        assert_eq!(sorted_triangles(&out), sorted_triangles(&indices));
    }

    #[test]
    fn chunked_order_keeps_the_cache_efficiency() {
        // 80,000 triangles in chunks of 4,096: more boundary per triangle
        // than the writer's chunks of 65,536
        let (positions, indices) = shuffled_grid(200);
        let n = positions.len();
        let acmr = |ix: &[u32]| meshopt::analyze_vertex_cache(ix, n, 16, 0, 0).acmr;
        let whole = acmr(&meshopt::optimize_vertex_cache(&indices, n));
        let chunked = acmr(&chunked(&indices, &positions, 4096));
        let scattered = acmr(&indices);
        assert!(scattered > 2.0 * whole, "{scattered} vs {whole}");
        assert!(
            chunked <= whole * 1.03,
            "chunked {chunked} vs whole {whole}"
        );
    }

    #[test]
    fn small_primitives_keep_the_whole_buffer_order() {
        let (positions, indices) = shuffled_grid(30);
        assert_eq!(
            vertex_cache_order(&indices, &positions),
            meshopt::optimize_vertex_cache(&indices, positions.len())
        );
    }
}
