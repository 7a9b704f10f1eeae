//! One vertex split ([`VertexSplit`]) and the corners it moves,
//! [`Corners`]: packed as one `u32` per corner (`triangle << 2 | slot`),
//! inline up to six. A list of [`Corner`]s took 56 bytes in every split (a
//! quarter of the progressive mesh of a scan); this takes 32. Triangles are
//! below 2^30 (`Mesh::validate`, the stream header), so the packing is
//! exact.

use smallvec::SmallVec;

/// A triangle corner: `triangles[triangle][slot]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Corner {
    /// The triangle.
    pub triangle: u32,
    /// Which of its three corners (0, 1 or 2).
    pub slot: u8,
}

/// One vertex split: the exact inverse of one contraction.
///
/// Applying it to the mesh with `v0` vertices and `t` triangles:
/// 1. set `v1`'s position to `p1` and append vertex `v0` at `p0`;
/// 2. append `faces` as triangles `t, t + 1, …`;
/// 3. set every corner in `corners` (currently `v1`) to `v0`.
///
/// Undoing it (a collapse) reverses the three steps, putting `v1` at
/// `p_merged`.
#[derive(Clone, Debug, PartialEq)]
pub struct VertexSplit {
    /// The vertex that stays (it exists before the split).
    pub v1: u32,
    /// The vertex the split restores: always the next vertex index.
    pub v0: u32,
    /// `v1`'s position after the split (before the contraction).
    pub p1: [f32; 3],
    /// `v1`'s position before the split: the contraction's result.
    pub p_merged: [f32; 3],
    /// `v0`'s position.
    pub p0: [f32; 3],
    /// The triangles the contraction deleted, restored by the split in this
    /// order: two for an interior edge (`fl`, `fr`), one on a border, none
    /// for a non-edge (τ) pair, `k ≥ 3` for an edge of `k` faces (where
    /// sheets meet along a non-manifold edge; rare, inline up to two).
    pub faces: SmallVec<[[u32; 3]; 2]>,
    /// The corners that go from `v1` back to `v0`, sorted (packed, inline
    /// up to six, which is most splits: no allocation per split).
    pub corners: Corners,
    /// The contraction's quadric error: root mean squared distance from the
    /// new vertex to the planes it carries (mesh units).
    pub error: f32,
}

/// The corners a split moves from `v1` to `v0`, in [`Corner`] order.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Corners(SmallVec<[u32; 6]>);

fn pack(c: Corner) -> u32 {
    debug_assert!(c.triangle < 1 << 30 && c.slot < 3);
    c.triangle << 2 | u32::from(c.slot)
}

fn unpack(k: u32) -> Corner {
    Corner {
        triangle: k >> 2,
        slot: (k & 3) as u8,
    }
}

impl Corners {
    /// No corner.
    pub fn new() -> Corners {
        Corners::default()
    }

    /// Number of corners.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// No corner moves.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Appends `c` (keep the order: corners are compared sorted).
    pub fn push(&mut self, c: Corner) {
        self.0.push(pack(c));
    }

    /// The corners in order.
    pub fn iter(&self) -> CornerIter<'_> {
        CornerIter(self.0.iter())
    }

    /// Where `c` is (`Ok`) or would be inserted (`Err`), as
    /// `slice::binary_search` on sorted corners.
    pub fn binary_search(&self, c: &Corner) -> Result<usize, usize> {
        self.0.binary_search(&pack(*c))
    }
}

impl FromIterator<Corner> for Corners {
    fn from_iter<I: IntoIterator<Item = Corner>>(iter: I) -> Corners {
        Corners(iter.into_iter().map(pack).collect())
    }
}

impl<'a> IntoIterator for &'a Corners {
    type Item = Corner;
    type IntoIter = CornerIter<'a>;
    fn into_iter(self) -> CornerIter<'a> {
        self.iter()
    }
}

/// The corners of a [`Corners`], by value.
#[derive(Clone, Debug)]
pub struct CornerIter<'a>(std::slice::Iter<'a, u32>);

impl Iterator for CornerIter<'_> {
    type Item = Corner;
    fn next(&mut self) -> Option<Corner> {
        self.0.next().map(|&k| unpack(k))
    }
    fn size_hint(&self) -> (usize, Option<usize>) {
        self.0.size_hint()
    }
}

impl DoubleEndedIterator for CornerIter<'_> {
    fn next_back(&mut self) -> Option<Corner> {
        self.0.next_back().map(|&k| unpack(k))
    }
}

impl ExactSizeIterator for CornerIter<'_> {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packing_keeps_corners_and_their_order() {
        let cs = [(0, 2), (5, 0), (5, 1), ((1 << 30) - 1, 2)]
            .map(|(triangle, slot)| Corner { triangle, slot });
        let packed: Corners = cs.iter().copied().collect();
        assert_eq!(packed.iter().collect::<Vec<_>>(), cs);
        for (i, c) in cs.iter().enumerate() {
            assert_eq!(packed.binary_search(c), Ok(i));
        }
        let absent = Corner {
            triangle: 5,
            slot: 2,
        };
        assert_eq!(packed.binary_search(&absent), Err(3));
        assert_eq!(std::mem::size_of::<Corners>(), 32);
    }
}
