//! The indexed triangle mesh the core works on, and its preparation from
//! user input: validation (typed errors naming the triangle or vertex),
//! welding of vertices with identical positions, and removal of unused
//! vertices, degenerate and duplicate triangles.
//!
//! Owns [`Mesh`], [`Prepared`], [`MeshError`]. Never panics on user input.
//!
//! ```
//! use lodgen_pm::{prepare, MeshError};
//! // two triangles sharing an edge, its two corners given twice
//! let positions = [
//!     [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
//!     [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0],
//! ];
//! let p = prepare(&positions, &[0, 1, 2, 3, 4, 5]).unwrap();
//! assert_eq!(p.mesh.positions.len(), 4);
//! assert_eq!(p.stats.welded_vertices, 2);
//! assert_eq!(p.vertex_map, [0, 1, 2, 1, 3, 2]);
//! // user input never panics: a typed error names the place
//! assert!(matches!(
//!     prepare(&positions, &[0, 1, 9]),
//!     Err(MeshError::IndexOutOfRange { triangle: 0, index: 9, .. })
//! ));
//! ```

pub(crate) mod adjacency;

use rayon::prelude::*;
use thiserror::Error;

/// An indexed triangle mesh: `f32` positions, `u32` corner indices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Counter-clockwise corner indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
}

/// Why user input was refused.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    /// The index list's length is not a multiple of 3.
    #[error("the index count {0} is not a multiple of 3")]
    IndexCount(usize),
    /// A corner names a vertex that does not exist.
    #[error(
        "triangle {triangle} refers to vertex {index}, but there are only {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// The triangle (in input order).
        triangle: usize,
        /// The index it holds.
        index: u32,
        /// How many vertices there are.
        vertex_count: usize,
    },
    /// A vertex that a triangle uses has a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite coordinate {value:?}")]
    NonFinite {
        /// The vertex (in input order).
        vertex: usize,
        /// Its coordinates.
        value: [f32; 3],
    },
    /// No triangle left (the text says after what).
    #[error("the mesh has no triangles{0}")]
    Empty(&'static str),
    /// More vertices than `u32` indices address.
    #[error("the mesh has {0} vertices; at most 2^32 - 1 are supported")]
    TooLarge(usize),
    /// More triangles than the log's numbering holds.
    #[error("the mesh has {0} triangles; at most 2^30 - 1 are supported")]
    TooManyTriangles(usize),
    /// The attribute slice is not `dims` values per vertex.
    #[error("{len} attribute values for {vertex_count} vertices of {dims} components")]
    AttributeCount {
        /// Values given.
        len: usize,
        /// Components per vertex.
        dims: usize,
        /// How many vertices there are.
        vertex_count: usize,
    },
}

/// The result of [`prepare`]: the welded mesh the simplifier runs on and the
/// maps back to the input.
#[derive(Clone, Debug, Default)]
pub struct Prepared {
    /// The welded, cleaned mesh.
    pub mesh: Mesh,
    /// Input vertex → welded vertex (`u32::MAX` for vertices no kept
    /// triangle uses).
    pub vertex_map: Vec<u32>,
    /// Welded triangle → input triangle.
    pub triangle_map: Vec<u32>,
    /// What was welded and removed.
    pub stats: PrepareStats,
}

/// What [`prepare`] removed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PrepareStats {
    /// Vertices given.
    pub input_vertices: usize,
    /// Triangles given.
    pub input_triangles: usize,
    /// Vertices merged into another with the identical position.
    pub welded_vertices: usize,
    /// Vertices no triangle refers to.
    pub unused_vertices: usize,
    /// Triangles with a repeated corner (after welding).
    pub degenerate_triangles: usize,
    /// Triangles on the same three vertices as an earlier one (either
    /// orientation).
    pub duplicate_triangles: usize,
}

impl Mesh {
    /// Build a mesh from flat indices, validating but not welding.
    pub fn from_indices(positions: Vec<[f32; 3]>, indices: &[u32]) -> Result<Mesh, MeshError> {
        if indices.len() % 3 != 0 {
            return Err(MeshError::IndexCount(indices.len()));
        }
        let triangles = indices
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        let mesh = Mesh {
            positions,
            triangles,
        };
        mesh.validate()?;
        Ok(mesh)
    }

    /// Check indices and coordinates.
    pub fn validate(&self) -> Result<(), MeshError> {
        validate_parts(&self.positions, self.triangles.iter().copied())
    }

    /// Axis-aligned bounds `(min, max)`; `None` when there are no vertices.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let first = *self.positions.first()?;
        Some(self.positions.iter().fold((first, first), |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
                [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
            )
        }))
    }

    /// Length of the bounding-box diagonal (0 for an empty mesh).
    pub fn diagonal(&self) -> f64 {
        self.bounds().map_or(0.0, |(lo, hi)| {
            let d = [0, 1, 2].map(|i| f64::from(hi[i]) - f64::from(lo[i]));
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        })
    }

    /// Flat index list.
    pub fn indices(&self) -> Vec<u32> {
        self.triangles.iter().flatten().copied().collect()
    }
}

/// The key positions are welded by: bit patterns, with -0.0 folded into 0.0.
fn weld_key(p: &[f32; 3]) -> [u32; 3] {
    p.map(|c| if c == 0.0 { 0 } else { c.to_bits() })
}

/// [`Mesh::validate`] on borrowed data.
fn validate_parts(
    positions: &[[f32; 3]],
    triangles: impl Iterator<Item = [u32; 3]>,
) -> Result<(), MeshError> {
    if positions.len() >= u32::MAX as usize {
        return Err(MeshError::TooLarge(positions.len()));
    }
    for (vertex, p) in positions.iter().enumerate() {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(MeshError::NonFinite { vertex, value: *p });
        }
    }
    let n = positions.len();
    let mut count = 0;
    for (triangle, t) in triangles.enumerate() {
        count = triangle + 1;
        for index in t {
            if index as usize >= n {
                return Err(MeshError::IndexOutOfRange {
                    triangle,
                    index,
                    vertex_count: n,
                });
            }
        }
    }
    if count >= 1 << 30 {
        // the log packs (triangle, corner slot) into one u32
        return Err(MeshError::TooManyTriangles(count));
    }
    Ok(())
}

/// `items` (indices into `positions`, increasing) in z-order: the key
/// interleaves 10 bits per axis of the position in the items' bounding box
/// (a 1024³ grid is fine enough), ties keep index order. A stable LSD radix
/// sort, 10 bits a pass (a comparison sort of the keys was 25M
/// instructions on the bunny, this is 2M).
fn morton_order(positions: &[[f32; 3]], items: &[u32]) -> Vec<u32> {
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for &i in items {
        for (k, &x) in positions[i as usize].iter().enumerate() {
            lo[k] = lo[k].min(f64::from(x));
            hi[k] = hi[k].max(f64::from(x));
        }
    }
    let extent = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let scale = if extent > 0.0 { 1023.0 / extent } else { 0.0 };
    // spread the low 10 bits of x to every third bit
    let spread = |x: u32| {
        let mut x = x & 0x3ff;
        x = (x | x << 16) & 0x0300_00ff;
        x = (x | x << 8) & 0x0300_f00f;
        x = (x | x << 4) & 0x030c_30c3;
        (x | x << 2) & 0x0924_9249
    };
    let key = |i: u32| {
        let p = positions[i as usize];
        let q = |k: usize| ((f64::from(p[k]) - lo[k]) * scale).clamp(0.0, 1023.0) as u32;
        spread(q(0)) | spread(q(1)) << 1 | spread(q(2)) << 2
    };
    let mut cur: Vec<(u32, u32)> = items.iter().map(|&i| (key(i), i)).collect();
    let mut next = vec![(0, 0); cur.len()];
    for shift in [0, 10, 20] {
        let digit = |k: u32| (k >> shift & 0x3ff) as usize;
        let mut start = [0usize; 1025];
        for &(k, _) in &cur {
            start[digit(k) + 1] += 1;
        }
        for d in 0..1024 {
            start[d + 1] += start[d];
        }
        for &e in &cur {
            let slot = &mut start[digit(e.0)];
            next[*slot] = e;
            *slot += 1;
        }
        std::mem::swap(&mut cur, &mut next);
    }
    cur.into_iter().map(|(_, i)| i).collect()
}

/// "The first item with the same key": an open-addressing hash table of
/// item indices, probed linearly. Items must be offered in increasing
/// order; the result is then independent of the hash (deterministic).
/// (Sorting the keys instead was 8 % of a bunny simplification.)
struct FirstOf {
    slots: Vec<u32>,
    mask: usize,
}

impl FirstOf {
    const EMPTY: u32 = u32::MAX;

    fn new(items: usize) -> FirstOf {
        let size = (2 * items).next_power_of_two().max(16);
        FirstOf {
            slots: vec![Self::EMPTY; size],
            mask: size - 1,
        }
    }

    /// The first item offered so far whose key equals `item`'s (`item`
    /// itself if none; it is then remembered).
    fn first(&mut self, item: u32, key: impl Fn(u32) -> [u32; 3]) -> u32 {
        let k = key(item);
        self.first_hashed(item, k, hash(k), key)
    }

    /// [`Self::first`] with the key `k` of `item` and its [`hash`] `h`.
    fn first_hashed(
        &mut self,
        item: u32,
        k: [u32; 3],
        h: u64,
        key: impl Fn(u32) -> [u32; 3],
    ) -> u32 {
        let mut h = h as usize;
        loop {
            let slot = &mut self.slots[h & self.mask];
            if *slot == Self::EMPTY {
                *slot = item;
                return item;
            }
            if key(*slot) == k {
                return *slot;
            }
            h = h.wrapping_add(1);
        }
    }
}

/// The hash of a weld key [`FirstOf`] probes from (its low bits) and
/// [`first_of_each_position`] shards by (its top bits).
fn hash(k: [u32; 3]) -> u64 {
    let mut x = (u64::from(k[0]) << 32 | u64::from(k[1])) ^ u64::from(k[2]).rotate_left(17);
    // splitmix64's finaliser
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// Positions from which [`first_of_each_position`] runs on every core.
const PAR_POSITIONS: usize = 1 << 16;

/// Shards of [`first_of_each_position`]: the top bits of the hash.
const SHARD_BITS: u32 = 4;

/// For every position, the first (lowest) index of a position with the
/// same bits (`0.0` and `-0.0` one value): the representative `prepare`
/// welds it into, and what a positions-only wedge key finds. A large mesh's
/// positions are hashed on every core and looked up shard by shard (a
/// shard is the positions whose hash has the same top bits, so equal
/// positions meet in one shard, offered in increasing order there): the
/// same answer as one table.
pub fn first_of_each_position(positions: &[[f32; 3]]) -> Vec<u32> {
    let key = |j: u32| weld_key(&positions[j as usize]);
    if positions.len() < PAR_POSITIONS {
        let mut table = FirstOf::new(positions.len());
        return (0..positions.len() as u32)
            .map(|i| table.first(i, key))
            .collect();
    }
    let hashes: Vec<u64> = positions
        .par_iter()
        .with_min_len(1 << 14)
        .map(|p| hash(weld_key(p)))
        .collect();
    let shard = |h: u64| (h >> (64 - SHARD_BITS)) as usize;
    // (each shard's later copies of a position: rare in a scan)
    let copies: Vec<Vec<(u32, u32)>> = (0..1usize << SHARD_BITS)
        .into_par_iter()
        .map(|s| {
            let count = hashes.iter().filter(|&&h| shard(h) == s).count();
            let mut table = FirstOf::new(count);
            let mut copies = Vec::new();
            for (i, &h) in hashes.iter().enumerate() {
                if shard(h) == s {
                    let i = i as u32;
                    let f = table.first_hashed(i, key(i), h, key);
                    if f != i {
                        copies.push((i, f));
                    }
                }
            }
            copies
        })
        .collect();
    drop(hashes);
    let mut first: Vec<u32> = (0..positions.len() as u32).into_par_iter().collect();
    for (i, f) in copies.into_iter().flatten() {
        first[i as usize] = f;
    }
    first
}

/// Validate `positions` + triangle `indices`, weld identical positions, drop
/// unused vertices and degenerate / duplicate triangles.
///
/// Welded vertices are numbered along a Z-order curve through their bounding
/// box (ties by input index), kept triangles are ordered by their lowest
/// welded corner, then input order, and keep their corner order: so the
/// result is a pure function of the input, and neighbours are near each
/// other in memory (see the comment inside).
pub fn prepare(positions: &[[f32; 3]], indices: &[u32]) -> Result<Prepared, MeshError> {
    if indices.len() % 3 != 0 {
        return Err(MeshError::IndexCount(indices.len()));
    }
    // read in place, not copied (peak memory)
    let input_count = indices.len() / 3;
    let input_triangles = || indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]);
    validate_parts(positions, input_triangles())?;
    if input_count == 0 {
        return Err(MeshError::Empty(""));
    }
    let mut stats = PrepareStats {
        input_vertices: positions.len(),
        input_triangles: input_count,
        ..PrepareStats::default()
    };

    // Canonical representative of each position: the lowest input index.
    let canonical = first_of_each_position(positions);

    let mut tris = canonical_triangles(indices, &canonical);
    let (mut vertex_map, welded_positions) = renumber(positions, &tris, &mut stats);
    let keys = sorted_keys(&mut tris, &vertex_map);
    let kept = first_of_each_vertex_set(&keys, welded_positions.len());
    // (the keys freed first: peak memory)
    drop(keys);
    let count = kept.iter().map(|k| k.0.len()).sum();
    let mut triangles = Vec::with_capacity(count);
    let mut triangle_map = Vec::with_capacity(count);
    for (map, d) in kept {
        triangles.extend(map.iter().map(|&ti| tris[ti as usize]));
        triangle_map.extend_from_slice(&map);
        stats.duplicate_triangles += d;
    }
    drop(tris);
    for i in 0..positions.len() {
        let c = canonical[i] as usize;
        vertex_map[i] = vertex_map[c];
        if c != i && vertex_map[c] != NONE {
            stats.welded_vertices += 1;
        }
    }
    stats.unused_vertices = positions.len() - stats.welded_vertices - welded_positions.len();
    if triangles.is_empty() {
        return Err(MeshError::Empty(
            " left after dropping degenerate triangles",
        ));
    }
    Ok(Prepared {
        mesh: Mesh {
            positions: welded_positions,
            triangles,
        },
        vertex_map,
        triangle_map,
        stats,
    })
}

/// A triangle or vertex of none (degenerate, unused).
const NONE: u32 = u32::MAX;

/// Each triangle's corners as canonical vertices, `[NONE; 3]` when two are
/// on one position (degenerate).
fn canonical_triangles(indices: &[u32], canonical: &[u32]) -> Vec<[u32; 3]> {
    indices
        .par_chunks_exact(3)
        .map(|c| {
            let k = [c[0], c[1], c[2]].map(|i| canonical[i as usize]);
            if k[0] != k[1] && k[1] != k[2] && k[0] != k[2] {
                k
            } else {
                [NONE; 3]
            }
        })
        .collect()
}

/// Number the used vertices (those on a non-degenerate triangle) along a
/// z-order (Morton) curve through their bounding box, ties by input index:
/// canonical vertex → new number (`NONE` if unused), and the new numbering's
/// positions. Counts the degenerate triangles.
///
/// With the kept triangles ordered by their lowest corner, a vertex's
/// neighbours and triangles are then near it in memory. The simplifier
/// reads one-rings in cost order, and its costing and walk wait on memory
/// (first-use numbering of a scanned mesh puts a third of the bunny's edges
/// 512+ vertices apart); this order made it 10 % faster.
fn renumber(
    positions: &[[f32; 3]],
    tris: &[[u32; 3]],
    stats: &mut PrepareStats,
) -> (Vec<u32>, Vec<[f32; 3]>) {
    let mut vertex_map = vec![NONE; positions.len()];
    for t in tris {
        if t[0] == NONE {
            stats.degenerate_triangles += 1;
        } else {
            for &c in t {
                vertex_map[c as usize] = 0;
            }
        }
    }
    let used: Vec<u32> = (0..positions.len() as u32)
        .filter(|&c| vertex_map[c as usize] == 0)
        .collect();
    let order = morton_order(positions, &used);
    let welded_positions: Vec<[f32; 3]> = order.iter().map(|&c| positions[c as usize]).collect();
    for (i, &c) in order.iter().enumerate() {
        vertex_map[c as usize] = i as u32;
    }
    (vertex_map, welded_positions)
}

/// Each kept triangle in the new numbering (rewritten in place), and its
/// corners sorted (the key that finds duplicates), once.
fn sorted_keys(tris: &mut [[u32; 3]], vertex_map: &[u32]) -> Vec<[u32; 3]> {
    tris.par_iter_mut()
        .map(|t| {
            if t[0] == NONE {
                return [NONE; 3];
            }
            *t = t.map(|c| vertex_map[c as usize]);
            // sorted by a min / max network (branch-free)
            let [a, b, c] = *t;
            let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
            [lo, a ^ b ^ c ^ lo ^ hi, hi]
        })
        .collect()
}

/// Group the triangles by their lowest corner (a counting sort; a group is
/// one vertex's fan, so the memory traffic stays local, unlike a hash table
/// of all triangles), sort each group by the other two corners (stably:
/// then input order), and keep the first triangle on each vertex set
/// (duplicates dropped): per run of vertices, the kept triangles in the new
/// order and the duplicates dropped.
fn first_of_each_vertex_set(keys: &[[u32; 3]], nv: usize) -> Vec<(Vec<u32>, usize)> {
    let mut start = vec![0u32; nv + 1];
    for k in keys {
        if k[0] != NONE {
            start[k[0] as usize + 1] += 1;
        }
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    let mut group = vec![0u32; start[nv] as usize];
    let mut next = start.clone();
    for (ti, k) in keys.iter().enumerate() {
        if k[0] != NONE {
            let slot = &mut next[k[0] as usize];
            group[*slot as usize] = ti as u32;
            *slot += 1;
        }
    }
    drop(next);
    // in parallel over runs of vertices (their groups are disjoint runs of
    // `group`), concatenated in order
    const RUN: usize = 4096;
    let mut runs = Vec::with_capacity(nv.div_ceil(RUN));
    let mut rest = &mut group[..];
    for lo in (0..nv).step_by(RUN) {
        let hi = (lo + RUN).min(nv);
        let (head, tail) = rest.split_at_mut((start[hi] - start[lo]) as usize);
        runs.push((lo, hi, head));
        rest = tail;
    }
    let others = |ti: u32| {
        let k = keys[ti as usize];
        u64::from(k[1]) << 32 | u64::from(k[2])
    };
    runs.into_par_iter()
        .map(|(lo, hi, run)| {
            let (mut kept, mut duplicates) = (Vec::new(), 0);
            let base = start[lo];
            for v in lo..hi {
                let g = &mut run[(start[v] - base) as usize..(start[v + 1] - base) as usize];
                if g.len() > 1 {
                    g.sort_by_key(|&ti| others(ti));
                }
                let mut last = None;
                for &ti in g.iter() {
                    let k = others(ti);
                    if last == Some(k) {
                        duplicates += 1;
                    } else {
                        last = Some(k);
                        kept.push(ti);
                    }
                }
            }
            (kept, duplicates)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welds_split_vertices_and_drops_bad_triangles() {
        // two triangles of a quad with the shared edge's vertices duplicated,
        // one degenerate triangle, one duplicate (reversed), one unused vertex
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [9.0, 9.0, 9.0],
            [-0.0, 0.0, 0.0],
        ];
        let idx = [0, 1, 2, 3, 4, 5, 0, 3, 1, 2, 1, 0, 7, 4, 5];
        let r = prepare(&p, &idx).unwrap();
        assert_eq!(r.mesh.positions.len(), 4);
        // numbered along the z-order curve: (0,0) (1,0) (0,1) (1,1)
        assert_eq!(r.mesh.triangles, vec![[0, 1, 3], [0, 3, 2]]);
        assert_eq!(r.mesh.positions[2], [0.0, 1.0, 0.0]);
        assert_eq!(r.triangle_map, vec![0, 1]);
        assert_eq!(r.stats.degenerate_triangles, 1);
        assert_eq!(r.stats.duplicate_triangles, 2);
        assert_eq!(r.stats.unused_vertices, 1);
        assert_eq!(r.stats.welded_vertices, 3);
        assert_eq!(r.vertex_map[6], u32::MAX);
        assert_eq!(r.vertex_map[7], 0);
    }

    /// Large enough for several parallel runs of the duplicate search: the
    /// first of each set of triangles on the same three vertices is kept,
    /// whichever run it falls in, with its winding, and the kept triangles
    /// come out ordered by lowest corner.
    #[test]
    fn keeps_the_first_of_each_duplicate_across_runs() {
        let n = 120u32; // 14,400 vertices: four runs
        let p: Vec<[f32; 3]> = (0..n * n)
            .map(|i| [(i % n) as f32, (i / n) as f32, ((i * 7) % 5) as f32])
            .collect();
        let mut idx = Vec::new();
        for y in 0..n - 1 {
            for x in 0..n - 1 {
                let v = y * n + x;
                idx.extend([v, v + 1, v + n + 1, v, v + n + 1, v + n]);
            }
        }
        // duplicates (rotated, reversed) and degenerates, spread over the mesh
        let base = idx.len() / 3;
        let mut rng = 12345u64;
        for _ in 0..3000 {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let t = (rng >> 33) as usize % base;
            let [a, b, c] = [idx[3 * t], idx[3 * t + 1], idx[3 * t + 2]];
            match rng >> 62 {
                0 => idx.extend([b, c, a]),
                1 => idx.extend([a, c, b]),
                2 => idx.extend([a, a, b]),
                _ => idx.extend([c, a, b]),
            }
        }
        let r = prepare(&p, &idx).unwrap();
        // the reference: first occurrence of each vertex set, in input order
        let mut first = std::collections::BTreeMap::new();
        let (mut degenerate, mut duplicates) = (0, 0);
        for (t, c) in idx.chunks_exact(3).enumerate() {
            let mut k = [c[0], c[1], c[2]];
            k.sort_unstable();
            if k[0] == k[1] || k[1] == k[2] {
                degenerate += 1;
            } else if let std::collections::btree_map::Entry::Vacant(e) = first.entry(k) {
                e.insert(t as u32);
            } else {
                duplicates += 1;
            }
        }
        assert_eq!(r.stats.degenerate_triangles, degenerate);
        assert_eq!(r.stats.duplicate_triangles, duplicates);
        let mut kept = r.triangle_map.clone();
        kept.sort_unstable();
        let mut want: Vec<u32> = first.into_values().collect();
        want.sort_unstable();
        assert_eq!(kept, want);
        for (tri, &t) in r.mesh.triangles.iter().zip(&r.triangle_map) {
            let input = [0, 1, 2].map(|k| r.vertex_map[idx[3 * t as usize + k] as usize]);
            assert_eq!(*tri, input, "input triangle {t}: corners and winding kept");
        }
        let lowest: Vec<u32> = r
            .mesh
            .triangles
            .iter()
            .map(|t| t[0].min(t[1]).min(t[2]))
            .collect();
        assert!(lowest.windows(2).all(|w| w[0] <= w[1]));
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(matches!(
            prepare(&p, &[0, 1, 2, 0, 1, 3]),
            Err(MeshError::IndexOutOfRange {
                triangle: 1,
                index: 3,
                vertex_count: 3
            })
        ));
        let nan = [[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(matches!(
            prepare(&nan, &[0, 1, 2]),
            Err(MeshError::NonFinite { vertex: 1, .. })
        ));
        assert!(matches!(
            prepare(&p, &[0, 1]),
            Err(MeshError::IndexCount(2))
        ));
        assert!(matches!(prepare(&p, &[]), Err(MeshError::Empty(_))));
        assert!(matches!(prepare(&p, &[0, 0, 1]), Err(MeshError::Empty(_))));
    }
}
