//! The error metric: sampled point–surface distances between two meshes
//! (Hausdorff, mean, RMS, both directions), over a BVH of triangles.
//!
//! * `triangle.rs`: the exact point–triangle distance (pure geometry).
//! * `zorder.rs`: the Z-order of a mesh's triangles and vertices (one radix
//!   sort per mesh, shared by the hierarchy and the sampling).
//! * [`bvh`]: closest point on a triangle mesh (a 4-wide BVH built along the
//!   Z-order, `f32` SIMD box tests, exact `f64` answers); knows nothing about
//!   sampling.
//! * `sampling.rs`: where the measured points come from (stratified area
//!   samples, vertices, centroids, edge midpoints, the max-seeking search) and the chunked,
//!   in-order folds that measure them.
//! * [`measure`](mod@measure): which points each direction measures and the
//!   statistics, as a fraction or percentage of the original's bounding-box
//!   diagonal; [`Reference`] prepares an original once for measuring several
//!   levels.
//!
//! All take meshes as plain slices ([`MeshRef`], defined here so that
//! none depends on another's types); the files depend on each other in
//! that order only.
//!
//! ```
//! use lodgen_pm::metric::{measure, MeasureOptions, MeshRef};
//! let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
//! let t = [[0u32, 1, 2]];
//! let mesh = MeshRef::new(&p, &t);
//! let e = measure(mesh, mesh, &MeasureOptions::default()).unwrap();
//! assert!(e.hausdorff() < 1e-9); // (a mesh against itself: 0 up to rounding)
//! ```

use rayon::prelude::*;
use thiserror::Error;

mod bounded;
pub mod bvh;
pub mod measure;
mod options;
mod sampling;
pub(crate) mod triangle;
mod zorder;

pub use bvh::TriangleBvh;
pub use measure::*;
pub use zorder::interleave3;

/// Asks for `items[i]`'s cache line ahead of its use (nothing when `i` is out of range): a
/// hint, no effect on results. The metric reads meshes along the Z-order, which scatters over
/// a mesh numbered otherwise (the progressive numbering), so each read would wait for memory.
#[inline(always)]
pub(crate) fn prefetch<T>(items: &[T], i: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(x) = items.get(i) {
        // SAFETY: prefetching reads nothing; the address is that of a live item.
        unsafe {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            _mm_prefetch::<_MM_HINT_T0>((x as *const T).cast::<i8>());
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (items, i);
}

/// How far ahead (items along the Z-order) [`prefetch`] asks for a mesh's triangles; their
/// corners' positions are asked for half as far ahead, from the triangles asked for before.
pub(crate) const AHEAD: usize = 16;

/// A triangle mesh seen as plain slices. Triangles are triples of indices into `positions`;
/// vertices no triangle refers to are ignored.
#[derive(Clone, Copy, Debug)]
pub struct MeshRef<'a> {
    pub positions: &'a [[f32; 3]],
    pub triangles: &'a [[u32; 3]],
}

/// What is wrong with a mesh given to the metric.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum MeshError {
    #[error("triangle {triangle} refers to vertex {index}, but there are {vertex_count} vertices")]
    IndexOutOfRange {
        triangle: usize,
        index: u32,
        vertex_count: usize,
    },
    #[error("triangle {triangle} uses vertex {vertex}, whose position is not finite")]
    NonFinite { triangle: usize, vertex: u32 },
}

impl<'a> MeshRef<'a> {
    pub fn new(positions: &'a [[f32; 3]], triangles: &'a [[u32; 3]]) -> Self {
        MeshRef {
            positions,
            triangles,
        }
    }

    /// [`prefetch`]es for a pass over this validated mesh's triangles along `order`, at
    /// `order[i]`: the triangle [`AHEAD`] steps on, the corners of the one half as far.
    #[inline(always)]
    pub(crate) fn prefetch_along(&self, order: &[u32], i: usize) {
        if let Some(&t) = order.get(i + AHEAD) {
            prefetch(self.triangles, t as usize);
        }
        self.prefetch_corners(order.get(i + AHEAD / 2).map_or(usize::MAX, |&t| t as usize));
    }

    /// [`prefetch`]es the corners' positions of triangle `t` (nothing when out of range).
    #[inline(always)]
    pub(crate) fn prefetch_corners(&self, t: usize) {
        if let Some(tri) = self.triangles.get(t) {
            for &v in tri {
                prefetch(self.positions, v as usize);
            }
        }
    }

    /// Checks that every index is in range and every used position is finite.
    ///
    /// # Errors
    /// The first offending triangle, in triangle order.
    pub fn validate(&self) -> Result<(), MeshError> {
        let vertex_count = self.positions.len();
        let check = |(triangle, t): (usize, &[u32; 3])| {
            for &index in t {
                let Some(p) = self.positions.get(index as usize) else {
                    return Some(MeshError::IndexOutOfRange {
                        triangle,
                        index,
                        vertex_count,
                    });
                };
                if !p.iter().all(|c| c.is_finite()) {
                    return Some(MeshError::NonFinite {
                        triangle,
                        vertex: index,
                    });
                }
            }
            None
        };
        // (on every core: a pass over a large mesh's corners; the first
        // offending triangle in triangle order whatever the split)
        match self
            .triangles
            .par_iter()
            .enumerate()
            .with_min_len(PAR_MIN)
            .find_map_first(check)
        {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Diagonal of the bounding box of the vertices the triangles use; 0 without triangles.
    pub fn bbox_diagonal(&self) -> f64 {
        let positions = self.positions;
        let (lo, hi) = corner_box(self.triangles, |v| {
            positions.get(v as usize).map(|p| p.map(f64::from))
        });
        if lo[0] > hi[0] {
            return 0.0;
        }
        (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
    }
}

/// Triangles per piece of a pass over a mesh's corners split across the
/// cores (a small mesh's passes stay on one).
pub(crate) const PAR_MIN: usize = 1 << 14;

/// The box (lowest, highest coordinates) of the points `at` gives for the
/// corners of `triangles` (a corner it gives none for is left out); an
/// empty box (lowest above highest) without points. On every core: min and
/// max are exact, so the box does not depend on the split.
pub(crate) fn corner_box(
    triangles: &[[u32; 3]],
    at: impl Fn(u32) -> Option<[f64; 3]> + Sync,
) -> ([f64; 3], [f64; 3]) {
    let empty = || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    triangles
        .par_iter()
        .with_min_len(PAR_MIN)
        .fold(empty, |(mut lo, mut hi), t| {
            for p in t.iter().filter_map(|&v| at(v)) {
                for k in 0..3 {
                    // (one compare each, not `f64::min`'s NaN handling: a NaN is left out
                    // either way, and a zero's sign moves no code, extent or diagonal)
                    if p[k] < lo[k] {
                        lo[k] = p[k];
                    }
                    if p[k] > hi[k] {
                        hi[k] = p[k];
                    }
                }
            }
            (lo, hi)
        })
        .reduce(empty, |(a, b), (c, d)| {
            (
                std::array::from_fn(|k| a[k].min(c[k])),
                std::array::from_fn(|k| b[k].max(d[k])),
            )
        })
}
