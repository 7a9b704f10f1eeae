//! Closest-point queries against a triangle mesh: a bounding-volume hierarchy over its triangles.
//!
//! This module owns [`TriangleBvh`]. It reads a [`MeshRef`] once, copies the triangles into leaf
//! order and never looks at the input again; it knows nothing about sampling or error statistics
//! (that is [`super::measure()`]). The exact point–triangle distance,
//! [`closest_point_on_triangle`], is re-exported from the metric's geometry module.
//!
//! - Build: binned surface-area heuristic, I. Wald, "On fast construction of SAH-based bounding
//!   volume hierarchies", IEEE Symposium on Interactive Ray Tracing 2007 (16 bins along the
//!   axis of largest centroid spread, object-median fallback when every centroid coincides),
//!   into a binary tree, then collapsed into a 4-wide tree (each node holds the boxes of up to
//!   four children, structure of arrays; the child of largest area is opened first, as in
//!   H. Dammertz, J. Hanika, A. Keller, "Shallow bounding volume hierarchies for fast SIMD ray
//!   tracing of incoherent rays", EGSR 2008).
//! - Query: depth-first branch and bound, nearer children first, a subtree skipped when its box
//!   is no closer than the best triangle found so far. The four box distances of a node are
//!   computed side by side in `f32` (one SIMD lane each); they are only used to *skip* boxes,
//!   against a bound widened by more than their rounding error, so a query visits every box
//!   that could hold the closest point and its answer is exactly the brute-force minimum over
//!   triangles of the `f64` point–triangle distance.
//!
//! Bounds are stored as `f32`; since the input positions are `f32`, the min/max of a set of them
//! is exact, so the boxes are tight and conservative. Triangle distances are `f64`.

use super::triangle::widen;
pub use super::triangle::{closest_point_on_triangle, distance_squared};
use super::{MeshError, MeshRef};

/// Triangles per leaf at most. Each child of a node has its own box, so small leaves mean a
/// box test (4 lanes at once) before most triangle tests.
const MAX_LEAF: usize = 2;

/// Bins for the binned SAH. Wald (2007) bins into a small fixed number of buckets (16 there)
/// and finds the trees close to a full SAH sweep at a fraction of the build time.
const BINS: usize = 16;

/// Below this depth the build splits by SAH; deeper, by object median, which halves the count
/// at every level. So the binary depth never exceeds `MAX_SAH_DEPTH + 32` (for < 2³²
/// triangles); the 4-wide tree is no deeper, and a query's stack (at most 3 entries per level,
/// plus one) fits in [`STACK`] entries without allocating. SAH trees of real meshes are far
/// shallower (the bunny's binary tree is about 20 levels).
const MAX_SAH_DEPTH: usize = 48;

/// Traversal stack size; see [`MAX_SAH_DEPTH`].
const STACK: usize = 3 * (MAX_SAH_DEPTH + 33) + 1;

/// `count` of a child that does not exist.
const EMPTY: u8 = u8::MAX;

/// A node of the binary tree during the build: an axis-aligned box and either two children
/// (`count == 0`, children at `first` and `first + 1`) or a leaf (`count > 0`, triangle slots
/// `first..first + count`).
#[derive(Clone, Copy, Debug)]
struct BuildNode {
    min: [f32; 3],
    max: [f32; 3],
    first: u32,
    count: u32,
}

/// An internal node as queried: the boxes of its (up to) four children, structure of arrays
/// (`lo[axis][child]`), so the four box distances are one SIMD computation. Child `c` is a leaf
/// with slots `first[c]..first[c] + count[c]` when `0 < count[c] < EMPTY`, the internal node
/// `first[c]` when `count[c] == 0`, and absent when `count[c] == EMPTY` (its box is empty:
/// `lo = +∞`, `hi = −∞`, so its distance is infinite).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Node {
    lo: [[f32; 4]; 3],
    hi: [[f32; 4]; 3],
    first: [u32; 4],
    count: [u8; 4],
}

/// A bounding-volume hierarchy over the triangles of one mesh, for exact closest-point queries.
///
/// Triangles of zero area are kept: geometrically they are segments or points and a query
/// measures the distance to those. Triangles are numbered as in the input mesh.
#[derive(Clone, Debug)]
pub struct TriangleBvh {
    /// Box of the whole mesh.
    root_lo: [f32; 3],
    root_hi: [f32; 3],
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
    /// Triangle corners in leaf order.
    tris: Vec<[[f32; 3]; 3]>,
    /// Input triangle index of each slot of `tris`.
    ids: Vec<u32>,
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

/// Squared distance from `p` to the box `lo..hi` (0 inside), in `f64`.
#[inline(always)]
fn box_distance_squared(lo: [f32; 3], hi: [f32; 3], p: [f64; 3]) -> f64 {
    let mut d2 = 0.0;
    for (k, &pk) in p.iter().enumerate() {
        let d = max64(max64(f64::from(lo[k]) - pk, pk - f64::from(hi[k])), 0.0);
        d2 += d * d;
    }
    d2
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

/// `f32::min` without its NaN handling (positions are validated finite): one instruction.
#[inline(always)]
fn min32(a: f32, b: f32) -> f32 {
    if b < a {
        b
    } else {
        a
    }
}

#[inline(always)]
fn max32(a: f32, b: f32) -> f32 {
    if b > a {
        b
    } else {
        a
    }
}

/// Running bounds of a set of triangles or centroids.
#[derive(Clone, Copy, Debug)]
struct Aabb {
    min: [f32; 3],
    max: [f32; 3],
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        min: [f32::INFINITY; 3],
        max: [f32::NEG_INFINITY; 3],
    };

    #[inline]
    fn grow(&mut self, other: &Aabb) {
        for k in 0..3 {
            self.min[k] = min32(self.min[k], other.min[k]);
            self.max[k] = max32(self.max[k], other.max[k]);
        }
    }

    #[inline]
    fn grow_point(&mut self, p: [f32; 3]) {
        for (k, &pk) in p.iter().enumerate() {
            self.min[k] = min32(self.min[k], pk);
            self.max[k] = max32(self.max[k], pk);
        }
    }

    /// Half the surface area (the SAH only compares areas), in f64 to avoid f32 overflow.
    #[inline]
    fn half_area(&self) -> f64 {
        if self.min[0] > self.max[0] {
            return 0.0;
        }
        let d = [
            f64::from(self.max[0]) - f64::from(self.min[0]),
            f64::from(self.max[1]) - f64::from(self.min[1]),
            f64::from(self.max[2]) - f64::from(self.min[2]),
        ];
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
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
        let n = mesh.triangles.len();
        debug_assert!(u32::try_from(n).is_ok(), "more than u32::MAX triangles");
        // Bounds, centroid and id travel together through the partitions, so every pass of
        // the build reads memory sequentially.
        let mut items: Vec<Item> = mesh
            .triangles
            .iter()
            .enumerate()
            .map(|(id, t)| {
                let mut b = Aabb::EMPTY;
                t.iter()
                    .for_each(|&v| b.grow_point(mesh.positions[v as usize]));
                Item { b, id: id as u32 }
            })
            .collect();
        let blank = BuildNode {
            min: [0.0; 3],
            max: [0.0; 3],
            first: 0,
            count: 0,
        };
        let mut max_depth = 0;
        let mut nodes: Vec<BuildNode> = Vec::with_capacity(if n == 0 { 0 } else { 2 * n - 1 });
        if n > 0 {
            nodes.push(blank);
            // Work list of (node index, first slot, slot count); explicit, so a badly
            // unbalanced input cannot overflow the call stack.
            let mut work: Vec<(usize, usize, usize, usize)> = vec![(0, 0, n, 0)];
            while let Some((ni, first, count, depth)) = work.pop() {
                max_depth = max_depth.max(depth + 1);
                let slots = &mut items[first..first + count];
                let mut bb = Aabb::EMPTY;
                let mut cb = Aabb::EMPTY;
                for it in slots.iter() {
                    bb.grow(&it.b);
                    cb.grow_point(it.centroid());
                }
                nodes[ni].min = bb.min;
                nodes[ni].max = bb.max;
                if count <= MAX_LEAF {
                    nodes[ni].first = first as u32;
                    nodes[ni].count = count as u32;
                    continue;
                }
                let mid = if depth < MAX_SAH_DEPTH {
                    split(slots, &cb)
                } else {
                    median_split(slots, &cb)
                };
                debug_assert!(0 < mid && mid < count);
                let left = nodes.len();
                nodes[ni].first = left as u32;
                nodes[ni].count = 0;
                nodes.push(blank);
                nodes.push(blank);
                work.push((left + 1, first + mid, count - mid, depth + 1));
                work.push((left, first, mid, depth + 1));
            }
        }
        // Free the build's scratch before the triangles are copied out: the 4-wide nodes,
        // then the ids, then the corners (peak ≈ 70 instead of 120 bytes per triangle).
        let root = nodes.first().copied();
        let query_nodes = if nodes.is_empty() {
            Vec::new()
        } else {
            collapse(&nodes)
        };
        drop(nodes);
        let ids: Vec<u32> = items.iter().map(|it| it.id).collect();
        drop(items);
        let tris = ids
            .iter()
            .map(|&id| mesh.triangles[id as usize].map(|v| mesh.positions[v as usize]))
            .collect();
        let Some(root) = root else {
            return TriangleBvh {
                root_lo: [0.0; 3],
                root_hi: [0.0; 3],
                magnitude: 0.0,
                root_first: 0,
                root_count: 0,
                nodes: Vec::new(),
                depth: 0,
                tris,
                ids,
            };
        };
        TriangleBvh {
            root_lo: root.min,
            root_hi: root.max,
            magnitude: root
                .min
                .iter()
                .chain(&root.max)
                .fold(0.0, |m, &x| max64(m, f64::from(x).abs())),
            root_first: if root.count > 0 { root.first } else { 0 },
            root_count: root.count,
            nodes: query_nodes,
            depth: max_depth,
            tris,
            ids,
        }
    }

    /// Number of triangles in the hierarchy.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// Levels of the binary tree the 4-wide one was collapsed from: 0 without triangles, 1 when
    /// a single leaf holds them all. At most `MAX_SAH_DEPTH + 33`, however the triangles are
    /// placed.
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// True when the mesh had no triangles; then every query returns `None`.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Bytes held by the hierarchy (nodes, triangle corners, ids).
    pub fn heap_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<Node>()
            + self.tris.capacity() * std::mem::size_of::<[[f32; 3]; 3]>()
            + self.ids.capacity() * std::mem::size_of::<u32>()
    }

    /// The closest point to `p` on the mesh surface: `(squared distance, triangle index, point)`,
    /// or `None` when the mesh has no triangles. When several triangles are equally close, which
    /// one is returned is deterministic but otherwise unspecified.
    pub fn closest_point(&self, p: [f64; 3]) -> Option<(f64, u32, [f64; 3])> {
        self.closest_slot(p, None)
            .map(|(d2, slot, q)| (d2, self.ids[slot as usize], q))
    }

    /// Like [`Self::closest_point`], but first measures the triangle in leaf slot `hint` (the
    /// answer to a nearby previous query), whose distance bounds the search from the start.
    /// Returns the slot, not the triangle index. The distance does not depend on the hint.
    #[inline]
    pub(crate) fn closest_slot(
        &self,
        p: [f64; 3],
        hint: Option<u32>,
    ) -> Option<(f64, u32, [f64; 3])> {
        self.closest_slot_until(p, hint, -1.0)
    }

    /// Like [`Self::closest_slot`], but the search stops at the first triangle whose squared
    /// distance is at most `stop` (then the answer is that triangle, not necessarily the
    /// closest); an answer above `stop` is the exact closest.
    #[inline]
    fn closest_slot_until(
        &self,
        p: [f64; 3],
        hint: Option<u32>,
        stop: f64,
    ) -> Option<(f64, u32, [f64; 3])> {
        if self.tris.is_empty() {
            return None;
        }
        let mut best = (f64::INFINITY, 0u32, [f64::NAN; 3]);
        if let Some(h) = hint {
            debug_assert!((h as usize) < self.tris.len());
            self.test_leaf(p, h, 1, u32::MAX, &mut best);
            if best.0 <= stop {
                return Some(best);
            }
        }
        // (the hint's leaf skips it: measured once)
        let skip = hint.unwrap_or(u32::MAX);
        if box_distance_squared(self.root_lo, self.root_hi, p) < best.0 {
            if self.root_count > 0 {
                self.test_leaf(p, self.root_first, self.root_count, skip, &mut best);
            } else {
                self.search(p, skip, stop, &mut best);
            }
        }
        debug_assert!(
            best.0.is_finite(),
            "a non-empty hierarchy always has an answer"
        );
        Some(best)
    }

    /// Corners of the triangle in leaf slot `slot` (a slot returned by a query).
    #[inline]
    pub(crate) fn slot_triangle(&self, slot: u32) -> [[f64; 3]; 3] {
        self.tris[slot as usize].map(widen)
    }

    /// Squared distance from `p` to the triangle in leaf slot `slot` (a slot returned by a
    /// query), without searching.
    #[inline]
    pub(crate) fn slot_distance_squared(&self, p: [f64; 3], slot: u32) -> f64 {
        let [a, b, c] = self.tris[slot as usize].map(widen);
        distance_squared(p, closest_point_on_triangle(p, a, b, c))
    }

    /// The squared distance from `p` to the surface when it exceeds `floor` (a squared
    /// distance), else `None`; with the slot of the answer, or of the first triangle found within
    /// `floor` (`hint`'s first: then nothing else is searched). For a maximum over many points:
    /// the points nearer than the running maximum cost one triangle test each when the previous
    /// answer settles them, else a search that stops at the first triangle near enough.
    /// `None` also for an empty hierarchy.
    #[inline]
    pub(crate) fn farther_than(
        &self,
        p: [f64; 3],
        floor: f64,
        hint: Option<u32>,
    ) -> (Option<f64>, Option<u32>) {
        match self.closest_slot_until(p, hint, floor) {
            Some((d2, slot, _)) => ((d2 > floor).then_some(d2), Some(slot)),
            None => (None, None),
        }
    }

    /// Depth-first branch and bound from internal node 0, nearer children first; stops at the
    /// first triangle within squared distance `stop` (−1: never).
    #[inline]
    fn search(&self, p: [f64; 3], skip: u32, stop: f64, best: &mut (f64, u32, [f64; 3])) {
        let p32 = p.map(|x| x as f32);
        let scale = p.iter().fold(self.magnitude, |m, &x| max64(m, x.abs()));
        let slack = SLACK * scale;
        let mut bound = skip_bound(best.0, slack);
        // (uninitialised: zeroing its 2 KB per query was 2 % of a measurement's profile)
        let mut stack = [const { std::mem::MaybeUninit::<(u32, f32)>::uninit() }; STACK];
        stack[0].write((0, 0.0));
        let mut len = 1;
        while len > 0 {
            len -= 1;
            // SAFETY: entries below `len` were written.
            let (ni, nd2) = unsafe { stack[len].assume_init() };
            if nd2 > bound {
                continue;
            }
            let node = &self.nodes[ni as usize];
            let d = child_distances_squared(node, p32);
            // The children within the bound, nearest first (insertion sort of at most 4).
            let mut order = [0usize; 4];
            let mut n = 0;
            for c in 0..4 {
                // (an absent child's distance is infinite, but so is the bound before the first
                // triangle is measured)
                if d[c] <= bound && node.count[c] != EMPTY {
                    let mut i = n;
                    while i > 0 && d[order[i - 1]] > d[c] {
                        order[i] = order[i - 1];
                        i -= 1;
                    }
                    order[i] = c;
                    n += 1;
                }
            }
            // Internal children go on the stack, the farthest first so the nearest is popped
            // first; leaf children are searched at once, the nearest first.
            for &c in order[..n].iter().rev() {
                if node.count[c] == 0 {
                    debug_assert!(len < STACK, "tree deeper than MAX_SAH_DEPTH allows");
                    stack[len].write((node.first[c], d[c]));
                    len += 1;
                }
            }
            for &c in &order[..n] {
                let count = node.count[c];
                if count > 0 && d[c] <= bound {
                    let before = best.0;
                    self.test_leaf(p, node.first[c], u32::from(count), skip, best);
                    if best.0 < before {
                        if best.0 <= stop {
                            return;
                        }
                        bound = skip_bound(best.0, slack);
                    }
                }
            }
        }
    }

    /// Measures slots `first..first + count` except `skip`, keeping the closest in `best`.
    #[inline(always)]
    fn test_leaf(
        &self,
        p: [f64; 3],
        first: u32,
        count: u32,
        skip: u32,
        best: &mut (f64, u32, [f64; 3]),
    ) {
        for slot in first..first + count {
            if slot == skip {
                continue;
            }
            let [a, b, c] = self.tris[slot as usize].map(widen);
            let q = closest_point_on_triangle(p, a, b, c);
            let d2 = distance_squared(p, q);
            if d2 < best.0 {
                *best = (d2, slot, q);
            }
        }
    }
}

/// Collapses the binary build tree into 4-wide query nodes, depth first: each node takes its
/// two children and keeps opening the internal one of largest area until it has four.
fn collapse(build: &[BuildNode]) -> Vec<Node> {
    if build[0].count > 0 {
        return Vec::new(); // the root is a leaf
    }
    let blank = Node {
        lo: [[f32::INFINITY; 4]; 3],
        hi: [[f32::NEG_INFINITY; 4]; 3],
        first: [0; 4],
        count: [EMPTY; 4],
    };
    let mut nodes: Vec<Node> = Vec::with_capacity(build.len() / 3 + 1);
    nodes.push(blank);
    // (build index of an internal node, its query index)
    let mut work: Vec<(usize, usize)> = vec![(0, 0)];
    let area = |i: usize| {
        let b = &build[i];
        Aabb {
            min: b.min,
            max: b.max,
        }
        .half_area()
    };
    while let Some((bi, ni)) = work.pop() {
        debug_assert_eq!(build[bi].count, 0);
        let l = build[bi].first as usize;
        let mut kids = [l, l + 1, 0, 0];
        let mut n = 2;
        while n < 4 {
            let open = (0..n)
                .filter(|&i| build[kids[i]].count == 0)
                .max_by(|&i, &j| area(kids[i]).total_cmp(&area(kids[j])).then(j.cmp(&i)));
            let Some(i) = open else { break };
            let f = build[kids[i]].first as usize;
            kids.copy_within(i + 1..n, i + 2);
            kids[i] = f;
            kids[i + 1] = f + 1;
            n += 1;
        }
        let mut node = blank;
        for (c, &k) in kids[..n].iter().enumerate() {
            let b = &build[k];
            for a in 0..3 {
                node.lo[a][c] = b.min[a];
                node.hi[a][c] = b.max[a];
            }
            if b.count > 0 {
                node.first[c] = b.first;
                node.count[c] = b.count as u8;
            } else {
                let new = nodes.len();
                nodes.push(blank); // placeholder, written when popped
                node.first[c] = new as u32;
                node.count[c] = 0;
                work.push((k, new));
            }
        }
        nodes[ni] = node;
    }
    nodes.shrink_to_fit();
    nodes
}

/// A triangle during the build: its box and index (the centroid is the box's centre, computed
/// when needed: 28 bytes instead of 40 per triangle at the build's peak).
#[derive(Clone, Copy, Debug)]
struct Item {
    b: Aabb,
    id: u32,
}

impl Item {
    /// Centre of the box along `axis`.
    #[inline(always)]
    fn centre(&self, axis: usize) -> f32 {
        0.5 * self.b.min[axis] + 0.5 * self.b.max[axis]
    }

    #[inline(always)]
    fn centroid(&self) -> [f32; 3] {
        std::array::from_fn(|k| self.centre(k))
    }
}

/// Splits `slots` in place into a left and right part and returns the size of the left part
/// (`0 < mid < slots.len()`): binned SAH along the axis where the centroids spread most (as in
/// Wald 2007), object median when every centroid coincides or no bin boundary separates them.
fn split(slots: &mut [Item], cb: &Aabb) -> usize {
    let count = slots.len();
    let extent: [f64; 3] = std::array::from_fn(|k| f64::from(cb.max[k]) - f64::from(cb.min[k]));
    let axis = if extent[0] >= extent[1] && extent[0] >= extent[2] {
        0
    } else if extent[1] >= extent[2] {
        1
    } else {
        2
    };
    if extent[axis] > 0.0 {
        let lo = cb.min[axis];
        let scale = (BINS as f64 / extent[axis]) as f32;
        let mut bin_box = [Aabb::EMPTY; BINS];
        let mut bin_n = [0usize; BINS];
        for it in slots.iter() {
            let b = bin_of(it.centre(axis), lo, scale);
            bin_box[b].grow(&it.b);
            bin_n[b] += 1;
        }
        // Sweep from the right for suffix areas, then from the left.
        let mut right_area = [0.0f64; BINS];
        let mut right_n = [0usize; BINS];
        let mut acc = Aabb::EMPTY;
        let mut n = 0;
        for b in (1..BINS).rev() {
            acc.grow(&bin_box[b]);
            n += bin_n[b];
            right_area[b] = acc.half_area();
            right_n[b] = n;
        }
        let mut best: Option<(f64, usize)> = None; // (cost, first bin on the right)
        let mut acc = Aabb::EMPTY;
        let mut n = 0;
        for b in 1..BINS {
            acc.grow(&bin_box[b - 1]);
            n += bin_n[b - 1];
            if n == 0 || right_n[b] == 0 {
                continue;
            }
            let cost = acc.half_area() * n as f64 + right_area[b] * right_n[b] as f64;
            if best.is_none_or(|(c, _)| cost < c) {
                best = Some((cost, b));
            }
        }
        if let Some((_, boundary)) = best {
            let mid = partition(slots, |it| bin_of(it.centre(axis), lo, scale) < boundary);
            if 0 < mid && mid < count {
                return mid;
            }
        }
    }
    // All centroids equal (or rounding put them in one bin): any split is as good as another.
    count / 2
}

/// Object-median split along the axis of largest centroid spread: the left half gets the
/// `len / 2` smallest centroids (ties broken by triangle id, so the result is deterministic).
fn median_split(slots: &mut [Item], cb: &Aabb) -> usize {
    let axis = (0..3)
        .max_by(|&i, &j| {
            let e = |k: usize| f64::from(cb.max[k]) - f64::from(cb.min[k]);
            e(i).total_cmp(&e(j)).then(j.cmp(&i))
        })
        .unwrap_or(0);
    let mid = slots.len() / 2;
    slots.select_nth_unstable_by(mid, |x, y| {
        x.centre(axis)
            .total_cmp(&y.centre(axis))
            .then(x.id.cmp(&y.id))
    });
    mid
}

#[inline]
fn bin_of(c: f32, lo: f32, scale: f32) -> usize {
    // (`as` saturates: a centre rounding below `lo` goes to bin 0)
    (((c - lo) * scale) as usize).min(BINS - 1)
}

/// In-place partition: elements satisfying `left` first; returns how many did.
fn partition(slots: &mut [Item], left: impl Fn(&Item) -> bool) -> usize {
    let mut i = 0;
    let mut j = slots.len();
    while i < j {
        if left(&slots[i]) {
            i += 1;
        } else {
            j -= 1;
            slots.swap(i, j);
        }
    }
    i
}
