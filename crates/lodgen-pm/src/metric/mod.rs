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
//!   samples, vertices, centroids, the max-seeking search) and the chunked,
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
        for (triangle, t) in self.triangles.iter().enumerate() {
            for &index in t {
                let Some(p) = self.positions.get(index as usize) else {
                    return Err(MeshError::IndexOutOfRange {
                        triangle,
                        index,
                        vertex_count,
                    });
                };
                if !p.iter().all(|c| c.is_finite()) {
                    return Err(MeshError::NonFinite {
                        triangle,
                        vertex: index,
                    });
                }
            }
        }
        Ok(())
    }

    /// Diagonal of the bounding box of the vertices the triangles use; 0 without triangles.
    pub fn bbox_diagonal(&self) -> f64 {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for t in self.triangles {
            for &v in t {
                let Some(p) = self.positions.get(v as usize) else {
                    continue;
                };
                for k in 0..3 {
                    lo[k] = lo[k].min(f64::from(p[k]));
                    hi[k] = hi[k].max(f64::from(p[k]));
                }
            }
        }
        if lo[0] > hi[0] {
            return 0.0;
        }
        (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
    }
}
