//! Building [`super::TriangleBvh`]'s tree: the binary tree over the triangles in Z-order,
//! split at the Morton bits (T. Karras, HPG 2012), collapsed into 4-wide nodes — a chunk of
//! the binary tree at a time, never the whole of it — and the triangles copied into leaf
//! order. See the parent module for the method.

use super::node::{max32, min32, Node, EMPTY, MAX_LEAF, NO_NODE};
use crate::metric::MeshRef;

/// A node of the binary tree during the build: an axis-aligned box and either two children
/// (`count == 0`, children at `first` and `first + 1`) or a leaf (`count > 0`, triangle slots
/// `first..first + count`).
#[derive(Clone, Copy, Debug)]
pub(super) struct BuildNode {
    pub(super) min: [f32; 3],
    pub(super) max: [f32; 3],
    pub(super) first: u32,
    pub(super) count: u32,
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

/// The triangles of the validated `mesh` in the order `ids`, as indices into the positions they
/// use, those numbered by first use along that order; and the positions. (A map of the mesh's
/// vertex count lives while this runs.)
pub(super) fn leaf_order_indices(mesh: MeshRef<'_>, ids: &[u32]) -> (Vec<[u32; 3]>, Vec<[f32; 3]>) {
    let mut number = vec![u32::MAX; mesh.positions.len()];
    let mut points: Vec<[f32; 3]> = Vec::new();
    let tris = ids
        .iter()
        .enumerate()
        .map(|(i, &t)| {
            mesh.prefetch_along(ids, i);
            mesh.triangles[t as usize].map(|v| {
                let n = &mut number[v as usize];
                if *n == u32::MAX {
                    // (at most 3 × u32::MAX triangles' corners, but the numbers are of
                    // distinct vertices of `positions`, whose indices are u32)
                    *n = points.len() as u32;
                    points.push(mesh.positions[v as usize]);
                }
                *n
            })
        })
        .collect();
    points.shrink_to_fit();
    (tris, points)
}

/// Ranges of at most this many triangles get their binary tree built whole ([`morton_tree`]),
/// collapsed and freed (≈ 5.4 MB of scratch); above it [`wide_tree`] finds the few binary nodes
/// it opens one at a time. So the whole binary tree (≈ 41 bytes a triangle, as much as the
/// 4-wide nodes) never exists. (2¹⁶ until session 23: a mesh just above it, the bunny's 69,451
/// triangles, had its triangles' corners scanned three more times for the boxes above the
/// chunks, 1.5 % of a bunny run's instructions; the tree is the same for any size.)
const CHUNK: usize = 1 << 17;

/// The 4-wide query nodes, and what the binary tree they were collapsed from had at its root.
pub(super) struct Wide {
    pub(super) nodes: Vec<Node>,
    /// The binary root: its box, and its slots when it is a leaf (`None` without triangles).
    pub(super) root: Option<BuildNode>,
    pub(super) depth: usize,
}

/// A node of the binary tree above the chunks, where [`wide_tree`] decides: its slots, box and
/// depth (the root 0).
#[derive(Clone, Copy)]
struct Range {
    first: usize,
    count: usize,
    depth: usize,
    b: Aabb,
}

/// The 4-wide tree of [`morton_tree`]'s binary tree collapsed by [`collapse_into`], node for
/// node (same boxes, children, order and numbering), without building the binary tree whole:
/// a node of more than [`CHUNK`] triangles is collapsed here, from boxes of binary nodes found
/// by splitting its range (memoised above [`CHUNK`], a linear scan below, the same `f32`
/// minima and maxima), and a smaller one by building its binary subtree alone. The work list
/// is a stack, as in the collapse, so a subtree is numbered whole once its root is taken.
pub(super) fn wide_tree(codes: &[u64], corners: impl Fn(usize) -> [[f32; 3]; 3]) -> Wide {
    let mut wide = wide_tree_in(codes, corners, CHUNK);
    for n in &mut wide.nodes {
        n.set_masks();
    }
    wide
}

/// [`wide_tree`] with chunks of at most `chunk` triangles.
fn wide_tree_in(codes: &[u64], corners: impl Fn(usize) -> [[f32; 3]; 3], chunk: usize) -> Wide {
    let n = codes.len();
    let scan = |first: usize, count: usize| {
        let mut b = Aabb::EMPTY;
        (first..first + count).for_each(|s| corners(s).iter().for_each(|&p| b.grow_point(p)));
        b
    };
    let mut memo = std::collections::BTreeMap::new();
    // (a root of at most `chunk` triangles gets its box from its binary tree below: a scan
    // of every corner fewer)
    let mut root_box = if n > chunk || n <= MAX_LEAF {
        range_box(codes, &scan, &mut memo, chunk, 0, n)
    } else {
        Aabb::EMPTY
    };
    if n <= MAX_LEAF {
        let root = (n > 0).then_some(BuildNode {
            min: root_box.min,
            max: root_box.max,
            first: 0,
            count: n as u32,
        });
        let depth = usize::from(n > 0);
        return Wide {
            nodes: Vec::new(),
            root,
            depth,
        };
    }
    // (room for more nodes than a Morton tree's 4-wide collapse makes, ≈ 0.3 a triangle)
    let mut nodes = Vec::with_capacity(n / 2);
    nodes.push(BLANK);
    let mut depth = 0;
    let mut work = vec![(0, n, 0, 0, NO_NODE)]; // (first, count, its depth, query index, parent)
    while let Some((first, count, d, ni, parent)) = work.pop() {
        if count <= chunk {
            let (build, levels) = morton_tree(&codes[first..first + count], |s| corners(first + s));
            if count == n {
                // (the same `f32` minima and maxima as a scan: see `range_box`)
                root_box = Aabb {
                    min: build[0].min,
                    max: build[0].max,
                };
            }
            collapse_into(&build, &mut nodes, ni, parent, first as u32);
            depth = depth.max(d + levels);
            continue;
        }
        let range = |first: usize, count: usize, depth: usize, memo: &mut _| Range {
            first,
            count,
            depth,
            b: range_box(codes, &scan, memo, chunk, first, count),
        };
        let mid = split_point(&codes[first..first + count]);
        let mut kids = [range(first, mid, d + 1, &mut memo); 4];
        kids[1] = range(first + mid, count - mid, d + 1, &mut memo);
        let mut k = 2;
        while k < 4 {
            let open = (0..k)
                .filter(|&i| kids[i].count > MAX_LEAF)
                .max_by(|&i, &j| {
                    (kids[i].b.half_area().total_cmp(&kids[j].b.half_area())).then(j.cmp(&i))
                });
            let Some(i) = open else { break };
            let Range {
                first,
                count,
                depth,
                ..
            } = kids[i];
            let mid = split_point(&codes[first..first + count]);
            kids.copy_within(i + 1..k, i + 2);
            kids[i] = range(first, mid, depth + 1, &mut memo);
            kids[i + 1] = range(first + mid, count - mid, depth + 1, &mut memo);
            k += 1;
        }
        let mut node = Node { parent, ..BLANK };
        for (c, kid) in kids[..k].iter().enumerate() {
            for a in 0..3 {
                node.lo[a][c] = kid.b.min[a];
                node.hi[a][c] = kid.b.max[a];
            }
            if kid.count <= MAX_LEAF {
                node.first[c] = kid.first as u32;
                node.count[c] = kid.count as u8;
                depth = depth.max(kid.depth + 1);
            } else {
                node.first[c] = nodes.len() as u32;
                node.count[c] = 0;
                work.push((kid.first, kid.count, kid.depth, nodes.len(), ni as u32));
                nodes.push(BLANK); // placeholder, written when popped
            }
        }
        nodes[ni] = node;
    }
    // (not shrunk to fit: a `Node` is 64-byte aligned, and the system allocator shrinks such a
    // block by copying it, which was the build's peak; the capacity never written is never
    // resident)
    let root = Some(BuildNode {
        min: root_box.min,
        max: root_box.max,
        first: 0,
        count: 0,
    });
    Wide { nodes, root, depth }
}

/// The box of the binary node over slots `first..first + count`: the union of its two halves'
/// (memoised in `memo`) above `chunk` triangles, `scan` below (the same minima and maxima:
/// `f32` min and max keep the first of equal values, as the union of the left half with the
/// right one does).
fn range_box(
    codes: &[u64],
    scan: &impl Fn(usize, usize) -> Aabb,
    memo: &mut std::collections::BTreeMap<(usize, usize), Aabb>,
    chunk: usize,
    first: usize,
    count: usize,
) -> Aabb {
    if count <= chunk {
        return scan(first, count);
    }
    if let Some(b) = memo.get(&(first, count)) {
        return *b;
    }
    let mid = split_point(&codes[first..first + count]);
    let mut b = range_box(codes, scan, memo, chunk, first, mid);
    b.grow(&range_box(
        codes,
        scan,
        memo,
        chunk,
        first + mid,
        count - mid,
    ));
    memo.insert((first, count), b);
    b
}

/// Where the binary node over the sorted Morton codes `range` (more than [`MAX_LEAF`]) splits:
/// at the first code with the highest differing bit set, or halves when every code is equal.
fn split_point(range: &[u64]) -> usize {
    let count = range.len();
    let differ = range[0] ^ range[count - 1];
    // Codes share every bit above the highest differing one, so the first code with that
    // bit set is a partition point; each split lowers that bit, then equal codes halve.
    let mid = if differ == 0 {
        count / 2
    } else {
        let bit = 1u64 << (63 - differ.leading_zeros());
        range.partition_point(|&c| c & bit == 0)
    };
    debug_assert!(0 < mid && mid < count);
    mid
}

/// An internal node with no child yet.
const BLANK: Node = Node {
    lo: [[f32::INFINITY; 4]; 3],
    hi: [[f32::NEG_INFINITY; 4]; 3],
    first: [0; 4],
    count: [EMPTY; 4],
    parent: NO_NODE,
    present: 0,
    leaves: 0,
};

/// Collapses the binary tree `build` (internal root) into 4-wide query nodes appended to
/// `nodes`, depth first, its root at `nodes[root]` (a placeholder) under `parent`, leaf slots
/// shifted by `offset`: each node takes its two children and keeps opening the internal one of
/// largest area until it has four.
fn collapse_into(
    build: &[BuildNode],
    nodes: &mut Vec<Node>,
    root: usize,
    parent: u32,
    offset: u32,
) {
    debug_assert_eq!(build[0].count, 0);
    // (build index of an internal node, its query index, its parent's)
    let mut work: Vec<(usize, usize, u32)> = vec![(0, root, parent)];
    let area = |i: usize| {
        let b = &build[i];
        Aabb {
            min: b.min,
            max: b.max,
        }
        .half_area()
    };
    while let Some((bi, ni, parent)) = work.pop() {
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
        let mut node = Node { parent, ..BLANK };
        for (c, &k) in kids[..n].iter().enumerate() {
            let b = &build[k];
            for a in 0..3 {
                node.lo[a][c] = b.min[a];
                node.hi[a][c] = b.max[a];
            }
            if b.count > 0 {
                node.first[c] = b.first + offset;
                node.count[c] = b.count as u8;
            } else {
                let new = nodes.len();
                nodes.push(BLANK); // placeholder, written when popped
                node.first[c] = new as u32;
                node.count[c] = 0;
                work.push((k, new, ni as u32));
            }
        }
        nodes[ni] = node;
    }
}

/// The binary tree over the triangles whose Morton codes are `codes` (sorted) and corners
/// `corners(slot)`: each node's range of slots split where the highest Morton bit differing in
/// it flips (halved when all codes are equal), down to at most [`MAX_LEAF`] slots. Nodes in
/// depth-first order, children after their parent; and the number of levels.
///
/// (Leaves of exactly two consecutive slots instead, 10 % fewer nodes, made 1.5× more box and
/// 1.8× more triangle tests: a pair across a jump of the curve has a loose box.)
fn morton_tree(codes: &[u64], corners: impl Fn(usize) -> [[f32; 3]; 3]) -> (Vec<BuildNode>, usize) {
    let n = codes.len();
    if n == 0 {
        return (Vec::new(), 0);
    }
    let blank = BuildNode {
        min: [0.0; 3],
        max: [0.0; 3],
        first: 0,
        count: 0,
    };
    let mut nodes: Vec<BuildNode> = Vec::with_capacity(2 * n.div_ceil(MAX_LEAF));
    nodes.push(blank);
    let mut max_depth = 0;
    // Work list of (node index, first slot, slot count, depth); explicit, so a badly
    // unbalanced input cannot overflow the call stack.
    let mut work: Vec<(usize, usize, usize, usize)> = vec![(0, 0, n, 0)];
    while let Some((ni, first, count, depth)) = work.pop() {
        max_depth = max_depth.max(depth + 1);
        if count <= MAX_LEAF {
            let mut b = Aabb::EMPTY;
            for slot in first..first + count {
                corners(slot).iter().for_each(|&p| b.grow_point(p));
            }
            nodes[ni] = BuildNode {
                min: b.min,
                max: b.max,
                first: first as u32,
                count: count as u32,
            };
            continue;
        }
        let mid = split_point(&codes[first..first + count]);
        let left = nodes.len();
        nodes[ni].first = left as u32;
        nodes[ni].count = 0;
        nodes.push(blank);
        nodes.push(blank);
        work.push((left + 1, first + mid, count - mid, depth + 1));
        work.push((left, first, mid, depth + 1));
    }
    // Children come after their parent: boxes bottom-up in one backward pass.
    for i in (0..nodes.len()).rev() {
        if nodes[i].count == 0 {
            let l = nodes[i].first as usize;
            let mut b = Aabb {
                min: nodes[l].min,
                max: nodes[l].max,
            };
            b.grow(&Aabb {
                min: nodes[l + 1].min,
                max: nodes[l + 1].max,
            });
            nodes[i].min = b.min;
            nodes[i].max = b.max;
        }
    }
    (nodes, max_depth)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::zorder;

    /// A bumpy grid of `n × n` quads plus a few repeated triangles (equal Morton codes).
    fn grid(n: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
                positions.push([x, y, 0.1 * (7.0 * x).sin() * (5.0 * y).cos()]);
            }
        }
        let mut triangles = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let v = j * (n + 1) + i;
                triangles.push([v, v + 1, v + n + 2]);
                triangles.push([v, v + n + 2, v + n + 1]);
            }
        }
        for k in 0..9 {
            triangles.push(triangles[k * 7]);
        }
        (positions, triangles)
    }

    fn same(a: &Node, b: &Node) -> bool {
        let bits = |x: &[[f32; 4]; 3]| x.map(|r| r.map(f32::to_bits));
        bits(&a.lo) == bits(&b.lo)
            && bits(&a.hi) == bits(&b.hi)
            && a.first == b.first
            && a.count == b.count
            && a.parent == b.parent
    }

    /// The chunked build is the whole binary tree's collapse, node for node (boxes, children,
    /// numbering, parents) and depth, whatever the chunk size. Fails when a chunk is numbered
    /// out of the collapse's depth-first order, a box above the chunks is computed otherwise,
    /// or the opening order differs.
    #[test]
    fn chunked_build_is_the_whole_trees_collapse() {
        let (positions, triangles) = grid(30);
        let mesh = MeshRef::new(&positions, &triangles);
        let z = zorder::triangles(mesh);
        let corners = |s: usize| triangles[z.ids[s] as usize].map(|v| positions[v as usize]);
        let (build, depth) = morton_tree(&z.codes, corners);
        let mut whole = vec![BLANK];
        collapse_into(&build, &mut whole, 0, NO_NODE, 0);
        for chunk in [3, 8, 61, 500, 1 << 20] {
            let wide = wide_tree_in(&z.codes, corners, chunk);
            assert_eq!(wide.depth, depth, "chunk {chunk}");
            assert_eq!(wide.nodes.len(), whole.len(), "chunk {chunk}");
            for (i, (a, b)) in wide.nodes.iter().zip(&whole).enumerate() {
                assert!(same(a, b), "chunk {chunk}: node {i} {a:?} vs {b:?}");
            }
            let root = wide.root.expect("triangles");
            assert_eq!((root.min, root.max), (build[0].min, build[0].max));
        }
    }
}
