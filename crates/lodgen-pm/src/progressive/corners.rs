//! The corners a vertex split moves, packed: one `u32` per corner
//! (`triangle << 2 | slot`), inline up to six. A list of [`Corner`]s took
//! 56 bytes in every split (a quarter of the progressive mesh of a scan);
//! this takes 32. Triangles are below 2^30 (`Mesh::validate`, the stream
//! header), so the packing is exact.

use smallvec::SmallVec;

use super::Corner;

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
