//! Closest-point queries against a triangle mesh: a bounding-volume hierarchy over its triangles.
//!
//! This module owns [`TriangleBvh`]. It reads a [`MeshRef`] once, copies the triangles into leaf
//! order and never looks at the input again; it knows nothing about sampling or error statistics
//! (that is [`super::measure()`]). The exact point–triangle distance,
//! [`closest_point_on_triangle`], is re-exported from the metric's geometry module.
//!
//! - Build: a linear BVH over the triangles sorted along the Z-order curve of their centroids
//!   (T. Karras, "Maximizing parallelism in the construction of BVHs, octrees, and k-d trees",
//!   HPG 2012: each node's range splits where its highest differing Morton bit flips), into a
//!   binary tree, then collapsed into a 4-wide tree (each node holds the boxes of up to
//!   four children, structure of arrays; the child of largest area is opened first, as in
//!   H. Dammertz, J. Hanika, A. Keller, "Shallow bounding volume hierarchies for fast SIMD ray
//!   tracing of incoherent rays", EGSR 2008). The sort is shared with the sampling (the
//!   samples are taken along the same curve); the build is one pass over the sorted codes
//!   and one over the nodes, ~10× cheaper than the binned surface-area heuristic it replaced
//!   (I. Wald, IEEE RT 2007) for queries of about the same cost (measured in
//!   docs/performance.md). `build.rs` collapses the binary tree a chunk at a time, so the
//!   whole of it (≈ 41 bytes a triangle) never lives beside the 4-wide nodes.
//! - Query: depth-first branch and bound, nearer children first, a subtree skipped when its box
//!   is no closer than the best triangle found so far. The four box distances of a node are
//!   computed side by side in `f32` (one SIMD lane each); they are only used to *skip* boxes,
//!   against a bound widened by more than their rounding error, so a query visits every box
//!   that could hold the closest point and its answer is exactly the brute-force minimum over
//!   triangles of the `f64` point–triangle distance.
//!
//! Bounds are stored as `f32`; since the input positions are `f32`, the min/max of a set of them
//! is exact, so the boxes are tight and conservative. Triangle distances are `f64`.

mod build;
mod node;

use build::{leaf_order_indices, wide_tree};
use node::{max32, Node, NO_NODE};

use super::triangle::closest_point_on_triangle_flat;
use super::triangle::widen;
pub use super::triangle::{closest_point_on_triangle, distance_squared};
use super::zorder::{self, ZOrder};
use super::{MeshError, MeshRef};

/// The binary tree's depth at most: every Morton split lowers the highest differing bit of
/// a 63-bit code, then ranges of equal codes halve (< 2³² triangles): 63 + 32 splits below
/// the root. The 4-wide tree is no deeper, and a query's stack (at most 3 entries per level,
/// plus one) fits in [`STACK`] entries without allocating. Trees of real meshes are far
/// shallower (the bunny's binary tree is about 20 levels).
const MAX_DEPTH: usize = 96;

/// Traversal stack size; see [`MAX_DEPTH`].
const STACK: usize = 3 * MAX_DEPTH + 1;

/// A bounding-volume hierarchy over the triangles of one mesh, for exact closest-point queries.
///
/// Triangles of zero area are kept: geometrically they are segments or points and a query
/// measures the distance to those. Triangles are numbered as in the input mesh.
#[derive(Clone, Debug)]
pub struct TriangleBvh {
    /// Largest absolute coordinate of the root box: the scale of the `f32` rounding error.
    magnitude: f64,
    /// The root as a child reference (see [`Node`]): a leaf when the mesh has at most
    /// [`MAX_LEAF`] triangles, else internal node 0.
    root_first: u32,
    root_count: u32,
    /// Internal nodes, depth first.
    nodes: Vec<Node>,
    /// Levels of the binary tree (0 without triangles, 1 when the root is a leaf).
    depth: usize,
    /// Triangles in leaf order, as indices into `points` (12 bytes a triangle instead of the
    /// 36 of their corners: the tree's largest part).
    tris: Vec<[u32; 3]>,
    /// The positions the triangles use, numbered by first use in leaf order (so a leaf's
    /// corners are near each other in memory).
    points: Vec<[f32; 3]>,
    /// Input triangle index of each slot of `tris`.
    ids: Vec<u32>,
    /// Two triangles share a Morton code: their leaf order is their numbering's.
    tied: bool,
}

/// `f64::max` without its NaN handling (one `maxsd`); inputs are finite.
#[inline(always)]
fn max64(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// Squared distances, in `f32`, from `p` to the boxes of the four children of `n` (infinite for
/// an absent child). Written lane by lane so that it compiles to packed SIMD.
#[inline(always)]
fn child_distances_squared(n: &Node, p: [f32; 3]) -> [f32; 4] {
    let mut acc = [0.0f32; 4];
    for ((lo, hi), &pk) in n.lo.iter().zip(&n.hi).zip(&p) {
        for ((a, &l), &h) in acc.iter_mut().zip(lo).zip(hi) {
            let d = max32(max32(l - pk, pk - h), 0.0);
            *a += d * d;
        }
    }
    acc
}

/// The children whose squared box distance `d` is within `bound`, as bits (one SIMD compare).
#[inline(always)]
fn within(d: &[f32; 4], bound: f32) -> u32 {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE is part of x86_64; the load reads the four lanes of `d`.
    unsafe {
        use std::arch::x86_64::{_mm_cmple_ps, _mm_loadu_ps, _mm_movemask_ps, _mm_set1_ps};
        _mm_movemask_ps(_mm_cmple_ps(_mm_loadu_ps(d.as_ptr()), _mm_set1_ps(bound))) as u32
    }
    #[cfg(not(target_arch = "x86_64"))]
    d.iter()
        .enumerate()
        .fold(0, |m, (c, &x)| m | u32::from(x <= bound) << c)
}

/// Asks for node `i`'s two cache lines ahead of its visit (a hint, no effect on results).
#[inline(always)]
fn prefetch(nodes: &[Node], i: u32) {
    #[cfg(target_arch = "x86_64")]
    if let Some(n) = nodes.get(i as usize) {
        let p = (n as *const Node).cast::<i8>();
        // SAFETY: prefetching reads nothing; the address is that of a live node.
        unsafe {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            _mm_prefetch::<_MM_HINT_T0>(p);
            _mm_prefetch::<_MM_HINT_T0>(p.add(64));
        }
    }
}

/// Sorts four keys, smallest first: a network of five compare-exchanges (`min`/`max`, no
/// branches: which children of a node are near a query is not predictable).
#[inline(always)]
fn sort4(k: &mut [u64; 4]) {
    let mut swap = |i: usize, j: usize| {
        let (a, b) = (k[i], k[j]);
        k[i] = a.min(b);
        k[j] = a.max(b);
    };
    swap(0, 1);
    swap(2, 3);
    swap(0, 2);
    swap(1, 3);
    swap(1, 2);
}

/// Relative size of the slack added to a query's bound before boxes are skipped by their `f32`
/// distance: the rounding of the query point to `f32` and of the box distance arithmetic
/// (a few units of 2⁻²⁴ of the largest coordinate involved) stays far below it.
const SLACK: f64 = 1.0 / (1u64 << 16) as f64;

/// The `f32` value a box's squared distance must exceed to be skipped, for a best squared
/// distance `best` so far: `(√best + slack)²`, rounded up, infinite when out of `f32` range.
#[inline]
fn skip_bound(best: f64, slack: f64) -> f32 {
    let b = best.sqrt() + slack;
    let b2 = b * b * (1.0 + SLACK);
    if b2 < f64::from(f32::MAX) / 4.0 {
        b2 as f32
    } else {
        f32::INFINITY
    }
}

impl TriangleBvh {
    /// Builds the hierarchy over the triangles of `mesh`.
    ///
    /// # Errors
    /// [`MeshError`] when a triangle refers to a vertex past the end of `positions`, or to a
    /// vertex with a NaN or infinite coordinate. A mesh with no triangles is valid: its
    /// hierarchy is empty and every query returns `None`.
    pub fn new(mesh: MeshRef<'_>) -> Result<TriangleBvh, MeshError> {
        mesh.validate()?;
        Ok(Self::build_validated(mesh))
    }

    /// Build for a mesh that [`MeshRef::validate`] accepted.
    pub(crate) fn build_validated(mesh: MeshRef<'_>) -> TriangleBvh {
        Self::from_zorder(mesh, zorder::triangles(mesh))
    }

    /// Build for a validated mesh whose triangles' Z-order is `z`
    /// ([`zorder::triangles`]): the leaves hold the triangles in that order, and each node
    /// splits its range where the highest Morton bit that differs in it flips (an octree cell's
    /// halves; halves of the range when every code is equal). A sort and a linear pass instead
    /// of a surface-area sweep per level: ~10× cheaper to build, and the queries of sorted
    /// sample points walk neighbouring leaves.
    pub(super) fn from_zorder(mesh: MeshRef<'_>, z: ZOrder) -> TriangleBvh {
        debug_assert!(
            u32::try_from(z.ids.len()).is_ok(),
            "more than u32::MAX triangles"
        );
        let corners = |slot: usize| {
            mesh.prefetch_along(&z.ids, slot);
            mesh.triangles[z.ids[slot] as usize].map(|v| mesh.positions[v as usize])
        };
        // (the 4-wide tree directly, a chunk of the binary tree at a time: the whole binary
        // tree, 41 bytes a triangle, beside the 4-wide nodes was the measurement's peak)
        let wide = wide_tree(&z.codes, corners);
        let tied = z.tied();
        // (the codes are not read again: freed before the leaves are copied)
        let ZOrder { ids, codes } = z;
        drop(codes);
        let (tris, points) = leaf_order_indices(mesh, &ids);
        let Some(root) = wide.root else {
            return TriangleBvh {
                magnitude: 0.0,
                root_first: 0,
                root_count: 0,
                nodes: Vec::new(),
                depth: 0,
                tris,
                points,
                ids: Vec::new(),
                tied,
            };
        };
        TriangleBvh {
            magnitude: root
                .min
                .iter()
                .chain(&root.max)
                .fold(0.0, |m, &x| max64(m, f64::from(x).abs())),
            root_first: if root.count > 0 { root.first } else { 0 },
            root_count: root.count,
            nodes: wide.nodes,
            depth: wide.depth,
            tris,
            points,
            ids,
            tied,
        }
    }

    /// The hierarchy of the same triangles numbered anew (`triangle_new[t]` the new number of
    /// triangle `t`; corners and positions unchanged): the one built over the renumbered mesh,
    /// bit for bit, unless two triangles share a Morton code (`None`: their leaf order would
    /// follow the new numbering).
    pub(super) fn renumbered(mut self, triangle_new: &[u32]) -> Option<TriangleBvh> {
        if self.tied {
            return None;
        }
        for t in &mut self.ids {
            *t = *triangle_new.get(*t as usize)?;
        }
        Some(self)
    }

    /// Triangle indices in leaf order: the Z-order of their centroids ([`zorder::triangles`]).
    pub(super) fn order(&self) -> &[u32] {
        &self.ids
    }

    /// Number of triangles in the hierarchy.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// Levels of the binary tree the 4-wide one was collapsed from: 0 without triangles, 1 when
    /// a single leaf holds them all. At most 96 (`MAX_DEPTH`), however the triangles are
    /// placed.
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// True when the mesh had no triangles; then every query returns `None`.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Bytes held by the hierarchy (nodes, triangles, positions, ids).
    pub fn heap_bytes(&self) -> usize {
        // (the nodes' unused capacity is never written: not resident)
        self.nodes.len() * std::mem::size_of::<Node>()
            + self.tris.capacity() * std::mem::size_of::<[u32; 3]>()
            + self.points.capacity() * std::mem::size_of::<[f32; 3]>()
            + self.ids.capacity() * std::mem::size_of::<u32>()
    }

    /// The closest point to `p` on the mesh surface: `(squared distance, triangle index, point)`,
    /// or `None` when the mesh has no triangles. When several triangles are equally close (the
    /// same `f64` squared distance), the one returned is the first in the hierarchy's leaf
    /// order (the Z-order of the triangles' centroids, equal codes by triangle index), whatever
    /// order the search meets them in.
    pub fn closest_point(&self, p: [f64; 3]) -> Option<(f64, u32, [f64; 3])> {
        self.closest_slot(p, None)
            .map(|(d2, h, q)| (d2, self.ids[h.slot as usize], q))
    }

    /// [`Self::closest_point`] with the answer's [`Hint`], starting from `hint` (the answer to
    /// a nearby previous query): the same answer, found faster when queries come in spatial
    /// order.
    #[inline]
    pub(crate) fn closest_point_from(
        &self,
        p: [f64; 3],
        hint: Option<Hint>,
    ) -> Option<(f64, u32, [f64; 3], Hint)> {
        self.closest_slot(p, hint)
            .map(|(d2, h, q)| (d2, self.ids[h.slot as usize], q, h))
    }

    /// Like [`Self::closest_point`], but first measures the triangle of `hint` (the answer to
    /// a nearby previous query), whose distance bounds the search from the start, and searches
    /// upwards from its leaf. Returns where the answer lies (its slot, not its triangle
    /// index). Neither the distance nor the triangle (ties: the first slot) depends on the
    /// hint.
    #[inline]
    pub(crate) fn closest_slot(
        &self,
        p: [f64; 3],
        hint: Option<Hint>,
    ) -> Option<(f64, Hint, [f64; 3])> {
        self.closest_slot_until(p, hint, -1.0)
    }

    /// Like [`Self::closest_slot`], but the search stops at the first triangle whose squared
    /// distance is at most `stop` (then the answer is that triangle, not necessarily the
    /// closest); an answer above `stop` is the exact closest.
    #[inline]
    fn closest_slot_until(
        &self,
        p: [f64; 3],
        hint: Option<Hint>,
        stop: f64,
    ) -> Option<(f64, Hint, [f64; 3])> {
        if self.tris.is_empty() {
            return None;
        }
        let mut best = Best {
            d2: f64::INFINITY,
            hint: Hint {
                slot: 0,
                node: NO_NODE,
            },
            q: [f64::NAN; 3],
        };
        if self.root_count > 0 {
            // (the root is a leaf: no search)
            self.test_leaf(p, self.root_first, self.root_count, NO_NODE, &mut best);
        } else if let Some(h) = hint {
            debug_assert!((h.slot as usize) < self.tris.len() && h.node != NO_NODE);
            self.test_leaf(p, h.slot, 1, h.node, &mut best);
            if stop < 0.0 {
                // (an exact answer: top-down, nearest boxes first, tightens the bound
                // faster than searching the hint's surroundings first)
                let query = Query::new(p, self.magnitude, h.slot, stop);
                self.search::<false>(&query, 0, NO_NODE, &mut best);
            } else if best.d2 > stop && !self.search_up_within(p, h, stop, &mut best) {
                // (nothing within `stop`, which is rare for a maximum's points: the exact
                // answer, top-down from the hint's bound as above)
                let query = Query::new(p, self.magnitude, h.slot, -1.0);
                self.search::<false>(&query, 0, NO_NODE, &mut best);
            }
        } else {
            let query = Query::new(p, self.magnitude, u32::MAX, stop);
            self.search::<false>(&query, 0, NO_NODE, &mut best);
        }
        debug_assert!(
            best.d2.is_finite(),
            "a non-empty hierarchy always has an answer"
        );
        Some((best.d2, best.hint, best.q))
    }

    /// Corners of the triangle in leaf slot `slot` (a slot returned by a query).
    #[inline]
    pub(crate) fn slot_triangle(&self, slot: u32) -> [[f64; 3]; 3] {
        self.tris[slot as usize].map(|v| widen(self.points[v as usize]))
    }

    /// Squared distance from `p` to the triangle in leaf slot `slot` (a slot returned by a
    /// query), without searching.
    #[inline]
    pub(crate) fn slot_distance_squared(&self, p: [f64; 3], slot: u32) -> f64 {
        let [a, b, c] = self.slot_triangle(slot);
        distance_squared(p, closest_point_on_triangle(p, a, b, c))
    }

    /// The squared distance from `p` to the surface when it exceeds `floor` (a squared
    /// distance), else `None`; with where the answer lies, or the first triangle found within
    /// `floor` (`hint`'s first, then its leaf's neighbours: then nothing else is searched). For
    /// a maximum over many points: the points nearer than the running maximum cost one
    /// triangle test each when the previous answer settles them, else a search upwards from it
    /// within `floor` only, which stops at the first triangle near enough, usually in the
    /// hint's own node; only a point farther than `floor` is then searched exactly.
    /// `None` also for an empty hierarchy.
    #[inline]
    pub(crate) fn farther_than(
        &self,
        p: [f64; 3],
        floor: f64,
        hint: Option<Hint>,
    ) -> (Option<f64>, Option<Hint>) {
        match self.closest_slot_until(p, hint, floor) {
            Some((d2, h, _)) => ((d2 > floor).then_some(d2), Some(h)),
            None => (None, None),
        }
    }

    /// The search from a hint for a triangle within squared distance `stop`, bottom-up: the
    /// subtrees of the hint's node, then those of each ancestor except the one just searched,
    /// up to the root, only boxes within `stop` entered (so it ends near the leaf it started
    /// from, and cheaply at the root when there is none: then the caller needs the exact
    /// distance). True, with `best` that triangle, when one nearer than `stop` was found.
    /// Which triangle is found depends on the visiting order, never whether one is.
    fn search_up_within(&self, p: [f64; 3], h: Hint, stop: f64, best: &mut Best) -> bool {
        let query = Query::new(p, self.magnitude, h.slot, stop);
        // (bounded by `stop` rather than by the hint's distance: a box farther than `stop`
        // cannot hold what is looked for, and any triangle nearer is the first found)
        let mut probe = Best { d2: stop, ..*best };
        let (mut node, mut came) = (h.node, NO_NODE);
        loop {
            self.search::<true>(&query, node, came, &mut probe);
            if probe.d2 < stop {
                *best = probe;
                return true;
            }
            if node == 0 {
                return false;
            }
            came = node;
            node = self.nodes[node as usize].parent;
        }
    }

    /// Depth-first branch and bound from internal node `start`, nearer children first (equal
    /// distances by child index), the child node `came` of `start` left out (`UP`: a search
    /// upwards from a hint; top-down searches leave nothing out); stops at the first triangle
    /// within squared distance `query.stop` (−1: never). At each node the leaf children within
    /// the bound are measured first, nearest first; then the search goes on into the nearest
    /// internal child still within the bound, the others stacked (farthest first), each
    /// skipped when popped if the bound has fallen below its distance. Children are sets of
    /// bits, so the common nodes (one or two children near the query) take no sort.
    #[inline]
    fn search<const UP: bool>(&self, query: &Query, start: u32, came: u32, best: &mut Best) {
        let mut bound = skip_bound(best.d2, query.slack);
        // (uninitialised: zeroing its 2 KB per query was 2 % of a measurement's profile)
        let mut stack = [const { std::mem::MaybeUninit::<(u32, f32)>::uninit() }; STACK];
        let mut len = 0;
        let mut ni = start;
        let mut left_out = 0u32;
        if UP {
            let node = &self.nodes[start as usize];
            for c in 0..4 {
                if node.count[c] == 0 && node.first[c] == came {
                    left_out |= 1 << c;
                }
            }
        }
        'nodes: loop {
            let node = &self.nodes[ni as usize];
            let d = child_distances_squared(node, query.p32);
            let near = within(&d, bound) & u32::from(node.present) & !left_out;
            left_out = 0;
            let leaves = near & u32::from(node.leaves);
            if leaves != 0 && self.test_leaves(query, node, ni, &d, leaves, &mut bound, best) {
                return;
            }
            let inner = near & !u32::from(node.leaves) & within(&d, bound);
            let key = |c: usize| u64::from(d[c].to_bits()) << 2 | c as u64;
            match inner.count_ones() {
                0 => {}
                1 => {
                    ni = node.first[inner.trailing_zeros() as usize];
                    continue 'nodes;
                }
                2 => {
                    let (a, b) = (inner.trailing_zeros(), 31 - inner.leading_zeros());
                    let (a, b) = (a as usize, b as usize);
                    let (first, second) = if key(a) < key(b) { (a, b) } else { (b, a) };
                    debug_assert!(len < STACK, "tree deeper than MAX_DEPTH allows");
                    stack[len].write((node.first[second], d[second]));
                    len += 1;
                    prefetch(&self.nodes, node.first[second]);
                    ni = node.first[first];
                    continue 'nodes;
                }
                _ => {
                    let mut keys = [u64::MAX; 4];
                    for (c, k) in keys.iter_mut().enumerate() {
                        if inner & 1 << c != 0 {
                            *k = key(c);
                        }
                    }
                    sort4(&mut keys);
                    for &k in keys[1..].iter().rev() {
                        if k != u64::MAX {
                            let c = (k & 3) as usize;
                            debug_assert!(len < STACK, "tree deeper than MAX_DEPTH allows");
                            stack[len].write((node.first[c], d[c]));
                            len += 1;
                            prefetch(&self.nodes, node.first[c]);
                        }
                    }
                    ni = node.first[(keys[0] & 3) as usize];
                    continue 'nodes;
                }
            }
            while len > 0 {
                len -= 1;
                // SAFETY: entries below `len` were written.
                let (n, nd2) = unsafe { stack[len].assume_init() };
                if nd2 <= bound {
                    ni = n;
                    continue 'nodes;
                }
            }
            return;
        }
    }

    /// Measures the leaf children `leaves` (bits) of `node` (internal node `ni`, child box
    /// distances `d`) that are within the bound, nearest first (equal distances by child
    /// index), tightening `bound`; true when a triangle within `query.stop` was found.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn test_leaves(
        &self,
        query: &Query,
        node: &Node,
        ni: u32,
        d: &[f32; 4],
        leaves: u32,
        bound: &mut f32,
        best: &mut Best,
    ) -> bool {
        let mut rest = leaves;
        while rest != 0 {
            let mut c = rest.trailing_zeros() as usize;
            let mut others = rest & (rest - 1);
            while others != 0 {
                let k = others.trailing_zeros() as usize;
                if d[k].to_bits() < d[c].to_bits() {
                    c = k;
                }
                others &= others - 1;
            }
            rest &= !(1 << c);
            if d[c] <= *bound {
                let before = best.d2;
                self.test_leaf_except(query, node.first[c], u32::from(node.count[c]), ni, best);
                if best.d2 < before {
                    if best.d2 <= query.stop {
                        return true;
                    }
                    *bound = skip_bound(best.d2, query.slack);
                }
            }
        }
        false
    }

    /// Measures slots `first..first + count` of the leaf under internal node `node`, keeping
    /// the closest in `best`.
    #[inline(always)]
    fn test_leaf(&self, p: [f64; 3], first: u32, count: u32, node: u32, best: &mut Best) {
        for slot in first..first + count {
            let [a, b, c] = self.slot_triangle(slot);
            let q = closest_point_on_triangle_flat(p, a, b, c);
            let d2 = distance_squared(p, q);
            // (of equally close triangles the first in leaf order, whatever order they are met
            // in: neither the nodes' layout nor the hint decides the answer)
            if d2 < best.d2 || (d2 == best.d2 && slot < best.hint.slot) {
                *best = Best {
                    d2,
                    hint: Hint { slot, node },
                    q,
                };
            }
        }
    }

    /// [`Self::test_leaf`] except the query's hint slot (measured once, first).
    #[inline(always)]
    fn test_leaf_except(&self, query: &Query, first: u32, count: u32, node: u32, best: &mut Best) {
        for slot in first..first + count {
            if slot != query.skip {
                self.test_leaf(query.p, slot, 1, node, best);
            }
        }
    }
}

/// Where an answer lies: its leaf slot and the internal node whose child holds it
/// ([`NO_NODE`] when the root is a leaf). A query started from a nearby answer's hint measures
/// that triangle first and searches upwards from its node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Hint {
    pub slot: u32,
    node: u32,
}

/// The closest triangle found so far.
#[derive(Clone, Copy, Debug)]
struct Best {
    d2: f64,
    hint: Hint,
    q: [f64; 3],
}

/// A query point with what every node visit needs.
#[derive(Clone, Copy, Debug)]
struct Query {
    p: [f64; 3],
    p32: [f32; 3],
    /// Widening of the skip bound covering the `f32` box arithmetic (see [`SLACK`]).
    slack: f64,
    /// A slot already measured (the hint's), or `u32::MAX`.
    skip: u32,
    stop: f64,
}

impl Query {
    #[inline]
    fn new(p: [f64; 3], magnitude: f64, skip: u32, stop: f64) -> Query {
        let scale = p.iter().fold(magnitude, |m, &x| max64(m, x.abs()));
        Query {
            p,
            p32: p.map(|x| x as f32),
            slack: SLACK * scale,
            skip,
            stop,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    /// `farther_than` (the vertex pass's query) against brute force: from the previous answer's
    /// hint, as the pass chains them, a point nearer than the floor is settled (`None`), a
    /// farther one gets its exact squared distance; floors from none to all of the points
    /// settled. Fails when a point that no triangle within the floor settles is answered with
    /// the search's bound instead of its exact distance, or when a settled point is reported.
    #[test]
    fn farther_than_is_exact_above_the_floor() {
        let to = shapes::torus_knot(2, 3, 90, 12, 0.01);
        let from = shapes::torus_knot(2, 3, 40, 8, 0.0);
        let bvh = TriangleBvh::new(MeshRef::new(&to.positions, &to.triangles)).unwrap();
        let brute = |p: [f64; 3]| {
            to.triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|v| widen(to.positions[v as usize]));
                    distance_squared(p, closest_point_on_triangle(p, a, b, c))
                })
                .fold(f64::INFINITY, f64::min)
        };
        let points: Vec<[f64; 3]> = from.positions.iter().map(|&q| widen(q)).collect();
        let exact: Vec<f64> = points.iter().map(|&p| brute(p)).collect();
        let mut sorted = exact.clone();
        sorted.sort_by(f64::total_cmp);
        let (mut settled, mut above) = (0, 0);
        for k in [0, sorted.len() / 4, sorted.len() / 2, 3 * sorted.len() / 4] {
            let floor = sorted[k];
            let mut hint = None;
            for (&p, &d2) in points.iter().zip(&exact) {
                let (got, h) = bvh.farther_than(p, floor, hint);
                hint = h;
                if d2 > floor {
                    assert_eq!(got, Some(d2), "floor {floor}: a point above it");
                    above += 1;
                } else {
                    assert_eq!(got, None, "floor {floor}: a point within it");
                    settled += 1;
                }
            }
        }
        assert!(
            settled > 300 && above > 300,
            "{settled} settled, {above} above"
        );
    }

    /// Of equally close triangles the first in leaf order is the answer, whichever the search
    /// meets first and whatever the hint: queries at the mesh's own vertices (every triangle of
    /// the fan at distance 0) and just off them, on a knot whose triangles are numbered in
    /// shuffled order, each from no hint and from a hint at every triangle of the answer's fan.
    /// Fails when the first of equal distances met is kept (the hint's, when it is in the fan).
    #[test]
    fn ties_go_to_the_first_slot() {
        let mut mesh = shapes::torus_knot(2, 3, 60, 10, 0.0);
        let n = mesh.triangles.len();
        let mut order: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            let r = (i as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 40;
            order.swap(i, r as usize % (i + 1));
        }
        mesh.triangles = order.iter().map(|&t| mesh.triangles[t]).collect();
        let bvh = TriangleBvh::new(MeshRef::new(&mesh.positions, &mesh.triangles)).unwrap();
        // (every leaf slot's hint: the internal node whose child holds it)
        let mut hints = vec![None; n];
        for (i, node) in bvh.nodes.iter().enumerate() {
            for c in 0..4 {
                if node.count[c] != 0 && node.count[c] != node::EMPTY {
                    for slot in node.first[c]..node.first[c] + u32::from(node.count[c]) {
                        let node = i as u32;
                        hints[bvh.ids[slot as usize] as usize] = Some(Hint { slot, node });
                    }
                }
            }
        }
        let brute = |p: [f64; 3]| {
            let d = |t: &[u32; 3]| {
                let [a, b, c] = t.map(|v| widen(mesh.positions[v as usize]));
                distance_squared(p, closest_point_on_triangle(p, a, b, c))
            };
            let best = mesh.triangles.iter().map(d).fold(f64::INFINITY, f64::min);
            let mut tied: Vec<u32> = (0..n as u32)
                .filter(|&t| d(&mesh.triangles[t as usize]) == best)
                .collect();
            tied.sort_by_key(|&t| hints[t as usize].map(|h: Hint| h.slot));
            (best, tied)
        };
        let mut with_ties = 0;
        for (v, &q) in mesh.positions.iter().enumerate() {
            for off in [0.0, 1e-3] {
                let p = widen(q).map(|x| x + off * (v % 3) as f64);
                let (d2, tied) = brute(p);
                let (got, t, _) = bvh.closest_point(p).unwrap();
                assert_eq!((got, t), (d2, tied[0]), "vertex {v} offset {off}");
                with_ties += usize::from(tied.len() > 1);
                for &h in &tied {
                    let (got, slot, _) = bvh.closest_slot(p, hints[h as usize]).unwrap();
                    let t = bvh.ids[slot.slot as usize];
                    assert_eq!((got, t), (d2, tied[0]), "vertex {v} from hint {h}");
                }
            }
        }
        assert!(with_ties > 500, "{with_ties} queries with ties");
    }
}
