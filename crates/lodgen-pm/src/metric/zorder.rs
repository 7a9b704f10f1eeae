//! The Z-order (Morton order) of a mesh's triangles and vertices, computed once per mesh: the
//! hierarchy's leaves are built along it ([`super::bvh`], splits at the Morton bits) and the
//! samples are taken along it (`sampling.rs`), so one sort serves both. Pure geometry:
//! depends on the triangle helpers only.

use super::triangle::widen;
use super::{MeshRef, AHEAD};

/// Spreads the low 21 bits of `x` to every third bit (Morton code helper).
fn spread3(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | x << 32) & 0x001f_0000_0000_ffff;
    x = (x | x << 16) & 0x001f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// Morton (Z-order) code of a point quantised on a 2²¹ grid over the box `lo..hi` (63 bits).
#[inline]
fn morton(p: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> u64 {
    let q = |k: usize| {
        let extent = hi[k] - lo[k];
        if extent > 0.0 {
            (((p[k] - lo[k]) / extent) * 2_097_151.0) as u64
        } else {
            0
        }
    };
    spread3(q(0)) | spread3(q(1)) << 1 | spread3(q(2)) << 2
}

/// Box of the vertices the triangles of the validated `mesh` use.
fn used_box(mesh: MeshRef<'_>) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (i, t) in mesh.triangles.iter().enumerate() {
        mesh.prefetch_corners(i + AHEAD / 2);
        for &v in t {
            let p = widen(mesh.positions[v as usize]);
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    (lo, hi)
}

/// Items sorted along the Z-order curve: `ids[i]` has the `i`-th smallest `(code, id)`.
#[derive(Clone, Debug, Default)]
pub(super) struct ZOrder {
    pub ids: Vec<u32>,
    /// Morton code of each item, in the same order (non-decreasing).
    pub codes: Vec<u64>,
}

/// The Z-order of the triangles of the validated `mesh` by centroid, over the box of the
/// vertices they use (ties by triangle index).
pub(super) fn triangles(mesh: MeshRef<'_>) -> ZOrder {
    let (lo, hi) = used_box(mesh);
    sorted(
        mesh.triangles
            .iter()
            .enumerate()
            .map(|(i, t)| {
                mesh.prefetch_corners(i + AHEAD / 2);
                let [a, b, c] = t.map(|v| widen(mesh.positions[v as usize]));
                morton(std::array::from_fn(|k| (a[k] + b[k] + c[k]) / 3.0), lo, hi)
            })
            .collect::<Vec<u64>>(),
    )
}

/// The vertices the triangles of the validated `mesh` use, in Z-order over their box (ties by
/// index), and whether two of them share a code (then the order depends on their numbering).
pub(super) fn vertices(mesh: MeshRef<'_>) -> (Vec<u32>, bool) {
    let (lo, hi) = used_box(mesh);
    let mut used = vec![false; mesh.positions.len()];
    for t in mesh.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let z = sorted(
        (0..mesh.positions.len())
            .filter(|&v| used[v])
            .map(|v| (morton(widen(mesh.positions[v]), lo, hi), v as u32))
            .collect::<Vec<_>>(),
    );
    let tied = z.tied();
    (z.ids, tied)
}

impl ZOrder {
    /// Whether two items share a code (then their order is their numbering's).
    pub fn tied(&self) -> bool {
        self.codes.windows(2).any(|w| w[0] == w[1])
    }
}

/// Conversion of the two inputs of [`sorted`]: codes of items `0..n`, or `(code, id)` pairs.
trait Keyed {
    fn into_pairs(self) -> Vec<(u64, u32)>;
}

impl Keyed for Vec<u64> {
    fn into_pairs(self) -> Vec<(u64, u32)> {
        self.into_iter()
            .enumerate()
            .map(|(i, c)| (c, i as u32))
            .collect()
    }
}

impl Keyed for Vec<(u64, u32)> {
    fn into_pairs(self) -> Vec<(u64, u32)> {
        self
    }
}

/// Radix digit width: 8 passes of 8 bits cover a 63-bit code; a pass whose digit is the same
/// for every key is skipped (the top bits of a flat mesh's codes).
const DIGIT: u32 = 8;

/// Below this many items a comparison sort is cheaper than the radix passes.
const SMALL: usize = 256;

/// Sorts items by `(code, id)`; ids arrive in increasing order, and the least-significant-digit
/// radix sort is stable, so equal codes stay in id order: the order of a comparison sort on the
/// pairs, whatever the input.
fn sorted(items: impl Keyed) -> ZOrder {
    let mut a = items.into_pairs();
    if a.len() < SMALL {
        a.sort_unstable();
    } else {
        let mut b = a.clone();
        let buckets = 1usize << DIGIT;
        for shift in (0..64).step_by(DIGIT as usize) {
            let digit = |c: u64| ((c >> shift) as usize) & (buckets - 1);
            let mut count = vec![0usize; buckets];
            for &(c, _) in &a {
                count[digit(c)] += 1;
            }
            if count.contains(&a.len()) {
                continue;
            }
            let mut sum = 0;
            for n in &mut count {
                let here = *n;
                *n = sum;
                sum += here;
            }
            for &x in &a {
                let d = digit(x.0);
                b[count[d]] = x;
                count[d] += 1;
            }
            std::mem::swap(&mut a, &mut b);
        }
    }
    ZOrder {
        ids: a.iter().map(|x| x.1).collect(),
        codes: a.iter().map(|x| x.0).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The radix sort orders like a comparison sort of `(code, id)`, ties included; fails when
    /// a pass is skipped wrongly or the scatter is unstable.
    #[test]
    fn radix_sort_matches_a_comparison_sort() {
        let mut x = 0x1234_5678_9abc_def0u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        for n in [0, 1, 255, 256, 5000] {
            // few distinct codes (ties) in some, wide ones in others
            for mask in [0x7u64, 0x7fff_ffff_ffff_ffff, 0x00f0_0000_0000_ff00] {
                let codes: Vec<u64> = (0..n).map(|_| next() & mask).collect();
                let mut want: Vec<(u64, u32)> = codes
                    .iter()
                    .enumerate()
                    .map(|(i, &c)| (c, i as u32))
                    .collect();
                want.sort_unstable();
                let got = sorted(codes);
                assert_eq!(got.ids, want.iter().map(|w| w.1).collect::<Vec<_>>());
                assert_eq!(got.codes, want.iter().map(|w| w.0).collect::<Vec<_>>());
            }
        }
    }
}
