//! The Z-order (Morton order) of a mesh's triangles and vertices, computed once per mesh: the
//! hierarchy's leaves are built along it ([`super::bvh`], splits at the Morton bits) and the
//! samples are taken along it (`sampling.rs`), so one sort serves both. Pure geometry:
//! depends on the triangle helpers only.

use rayon::prelude::*;

use super::triangle::widen;
use super::{corner_box, MeshRef, PAR_MIN};

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
    interleave3([q(0), q(1), q(2)])
}

/// Morton (Z-order) code of a cell of a 2²¹ grid: the low 21 bits of each
/// coordinate interleaved, x in bit 0, y in bit 1, z in bit 2 (63 bits).
/// Public for the writer's vertex-cache order (`lodgen`'s gltf_out).
#[inline]
pub fn interleave3(cell: [u64; 3]) -> u64 {
    spread3(cell[0]) | spread3(cell[1]) << 1 | spread3(cell[2]) << 2
}

/// Box of the vertices the triangles of the validated `mesh` use.
fn used_box(mesh: MeshRef<'_>) -> ([f64; 3], [f64; 3]) {
    corner_box(mesh.triangles, |v| Some(widen(mesh.positions[v as usize])))
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
    // (the codes on every core: one pass over the corners)
    sorted(
        mesh.triangles
            .par_iter()
            .with_min_len(PAR_MIN)
            .map(|t| {
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
    // (the used vertices picked on one core, their codes written in place on every core: a
    // parallel filter collects into pieces and copies them, twice the pairs at its peak)
    let mut pairs: Vec<(u64, u32)> = (0..mesh.positions.len() as u32)
        .filter(|&v| used[v as usize])
        .map(|v| (0, v))
        .collect();
    pairs
        .par_iter_mut()
        .with_min_len(PAR_MIN)
        .for_each(|(code, v)| *code = morton(widen(mesh.positions[*v as usize]), lo, hi));
    let z = sorted(pairs);
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
        self.into_par_iter()
            .with_min_len(PAR_MIN)
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

/// Sorts items by `(code, id)`; ids arrive in increasing order, and the radix passes are
/// stable, so equal codes stay in id order: the order of a comparison sort on the pairs,
/// whatever the input (and whatever the thread count).
fn sorted(items: impl Keyed) -> ZOrder {
    let mut a = items.into_pairs();
    if a.len() < SMALL {
        a.sort_unstable();
    } else {
        a = radix_sorted(a);
    }
    ZOrder {
        ids: a.par_iter().with_min_len(PAR_MIN).map(|x| x.1).collect(),
        codes: a.par_iter().with_min_len(PAR_MIN).map(|x| x.0).collect(),
    }
}

/// `a` sorted by code, stably: one counting pass on the highest digit in which the codes
/// differ, then each of its buckets (whose higher digits are all equal) sorted by the digits
/// below it ([`msd_sort`]), the buckets on every core (the passes over 4.4M
/// triangles' codes were a one-core stretch of the original's hierarchy).
fn radix_sorted(a: Vec<(u64, u32)>) -> Vec<(u64, u32)> {
    let Some(&(first, _)) = a.first() else {
        return a;
    };
    let differ = a
        .par_iter()
        .with_min_len(PAR_MIN)
        .map(|x| x.0 ^ first)
        .reduce(|| 0, |x, y| x | y);
    if differ == 0 {
        return a; // one code: already in id order
    }
    let top = (63 - differ.leading_zeros()) / DIGIT * DIGIT;
    let (mut starts, _) = counts(&a, top);
    let mut b = vec![(0u64, 0u32); a.len()];
    let ends: Vec<usize> = starts.iter().skip(1).copied().chain([a.len()]).collect();
    for &x in &a {
        let d = digit(x.0, top);
        b[starts[d]] = x;
        starts[d] += 1;
    }
    // (`a` is the buckets' scratch: cut both at the bucket ends)
    let mut a = a;
    let mut pieces = Vec::with_capacity(ends.len());
    let (mut rest_b, mut rest_a) = (&mut b[..], &mut a[..]);
    let mut at = 0;
    for &end in &ends {
        let (x, more_b) = rest_b.split_at_mut(end - at);
        let (scratch, more_a) = rest_a.split_at_mut(end - at);
        if x.len() > 1 {
            pieces.push((x, scratch));
        }
        (rest_b, rest_a, at) = (more_b, more_a, end);
    }
    pieces
        .into_par_iter()
        .for_each(|(x, scratch)| msd_sort(x, scratch, top));
    b
}

/// The digit of `code` at `shift`.
fn digit(code: u64, shift: u32) -> usize {
    ((code >> shift) as usize) & ((1 << DIGIT) - 1)
}

/// Where each digit's run starts once `a` is ordered by its digit at `shift`, and whether
/// every item has the same digit there.
fn counts(a: &[(u64, u32)], shift: u32) -> ([usize; 1 << DIGIT], bool) {
    let mut count = [0usize; 1 << DIGIT];
    for &(c, _) in a {
        count[digit(c, shift)] += 1;
    }
    let one = count.contains(&a.len());
    let mut sum = 0;
    for n in &mut count {
        let here = *n;
        *n = sum;
        sum += here;
    }
    (count, one)
}

/// `x` sorted by its codes' digits below `below` (its codes agree above it), ids breaking
/// ties, `scratch` as long as `x`: most significant digit first — one counting pass and a
/// scatter into `scratch` and back, then each of the digit's buckets alike — and a bucket of
/// fewer than [`SMALL`] items by comparison. (Least significant first, every bucket took a
/// pass per digit below its top one, seven for a 63-bit code however few items it held: 2.4 %
/// of a bunny run's instructions, most of its metric's Z-orders.) `x` arrives in id order
/// within equal codes and the scatter is stable, so the order is the stable one either way.
fn msd_sort(x: &mut [(u64, u32)], scratch: &mut [(u64, u32)], below: u32) {
    if x.len() < SMALL || below == 0 {
        // (ids are distinct: the stable order)
        x.sort_unstable();
        return;
    }
    let shift = below.saturating_sub(DIGIT);
    let (starts, one) = counts(x, shift);
    if one {
        msd_sort(x, scratch, shift);
        return;
    }
    let mut next = starts;
    for &item in x.iter() {
        let d = digit(item.0, shift);
        scratch[next[d]] = item;
        next[d] += 1;
    }
    x.copy_from_slice(scratch);
    // (after the scatter `next[d]` is where bucket d ends)
    let mut at = 0;
    for &end in &next {
        if end - at > 1 {
            msd_sort(&mut x[at..end], &mut scratch[at..end], shift);
        }
        at = end;
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
        for n in [0, 1, 255, 256, 5000, 200_000] {
            // few distinct codes (ties) in some, wide ones in others; buckets of hundreds of
            // equal codes below digits they all share (the most significant first sort's
            // skipped digits and its last digit's ties)
            for mask in [
                0x7u64,
                0x7fff_ffff_ffff_ffff,
                0x00f0_0000_0000_ff00,
                0x3000_0000_0300_0000,
                0x7f00_0000_0000_0301,
            ] {
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
