//! The 4-wide node of [`super::TriangleBvh`] as built ([`super::build`]) and queried, and
//! the `f32` minimum and maximum both use.

/// Triangles per leaf at most. Each child of a node has its own box, so small leaves mean a
/// box test (4 lanes at once) before most triangle tests; but nodes are 128 bytes, and with
/// two a leaf they were 38 bytes a triangle, most of the hierarchy (bunny-4m: the original's
/// 237 MB, 168 MB with four). Four measured no slower (bunny-4m's measure phase 7.4 / 7.2 →
/// 6.8 / 6.5 s, alternating; the bunny's whole run equal) and answers the same: each query's
/// nearest triangle does not depend on the tree's shape.
pub(super) const MAX_LEAF: usize = 4;

/// `count` of a child that does not exist.
pub(super) const EMPTY: u8 = u8::MAX;

const _: () = assert!(std::mem::size_of::<Node>() == 128);

/// The root's parent, and the node of a hint when the root is a leaf.
pub(super) const NO_NODE: u32 = u32::MAX;

/// An internal node as queried: the boxes of its (up to) four children, structure of arrays
/// (`lo[axis][child]`), so the four box distances are one SIMD computation. Child `c` is a leaf
/// with slots `first[c]..first[c] + count[c]` when `0 < count[c] < EMPTY`, the internal node
/// `first[c]` when `count[c] == 0`, and absent when `count[c] == EMPTY` (its box is empty:
/// `lo = +∞`, `hi = −∞`, so its distance is infinite).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct Node {
    pub(super) lo: [[f32; 4]; 3],
    pub(super) hi: [[f32; 4]; 3],
    pub(super) first: [u32; 4],
    pub(super) count: [u8; 4],
    /// The node this one is a child of ([`NO_NODE`] for the root), for searches upwards from a
    /// hint (in what would be padding: the node stays 128 bytes).
    pub(super) parent: u32,
    /// Bit `c` set when child `c` exists ([`Node::set_masks`], from `count`; padding too).
    pub(super) present: u8,
    /// Bit `c` set when child `c` is a leaf.
    pub(super) leaves: u8,
}

impl Node {
    /// Sets [`Node::present`] and [`Node::leaves`] from `count`.
    pub(super) fn set_masks(&mut self) {
        let bits =
            |f: &dyn Fn(u8) -> bool| (0..4).fold(0u8, |m, c| m | u8::from(f(self.count[c])) << c);
        self.present = bits(&|n| n != EMPTY);
        self.leaves = bits(&|n| n != EMPTY && n != 0);
    }
}

/// `f32::min` without its NaN handling (positions are validated finite): one instruction.
#[inline(always)]
pub(super) fn min32(a: f32, b: f32) -> f32 {
    if b < a {
        b
    } else {
        a
    }
}

#[inline(always)]
pub(super) fn max32(a: f32, b: f32) -> f32 {
    if b > a {
        b
    } else {
        a
    }
}
