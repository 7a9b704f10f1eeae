//! The vertex-split log (Hoppe 1996, "Progressive Meshes"; OpenMesh's
//! collapse-diamond names: `v0` removed by the collapse, `v1` kept) and the
//! [`ProgressiveMesh`] that replays it.
//!
//! Numbering: vertices and triangles are numbered in the order they *appear*
//! during refinement. The base mesh M_g holds vertices `0..nb` and triangles
//! `0..tb`; split `i` (coarse → fine) appends vertex `nb + i` and the
//! triangles it restores. So every level is a prefix of one vertex list and
//! one triangle list, plus corner edits: extraction, streaming and the glTF
//! writer all rely on this.
//!
//! Owns [`VertexSplit`], [`ProgressiveMesh`], [`Cursor`] and the conversion
//! from the simplifier's contraction log. No simplification logic here.
//!
//! ```
//! use lodgen_pm::levels::{splits_for, LevelSpec};
//! use lodgen_pm::{shapes, simplify, SimplifyOptions};
//! let m = shapes::icosphere(3); // 1,280 triangles
//! let opts = SimplifyOptions::DEFAULT.with_target_ratio(0.1);
//! let out = simplify(&m.positions, &m.indices(), &opts).unwrap();
//! let mut cursor = out.pm.cursor(); // at the base mesh
//! cursor.seek(splits_for(&out.pm, LevelSpec::Ratio(0.5)));
//! assert!(cursor.mesh().triangles.len() <= 640);
//! cursor.seek(out.pm.len()); // every split: the full mesh again
//! assert_eq!(cursor.mesh().triangles.len(), 1280);
//! ```

pub mod attrfit;
pub mod levels;
mod log;
mod split;
#[allow(missing_docs)] // (documented by its owner, issue 15 stream work)
pub mod stream;
mod wedgelog;

pub use split::{Corner, CornerIter, Corners, VertexSplit};
pub use wedgelog::{SplitWedges, WedgeLog};

pub(crate) use log::{Contraction, Log, Removed};

use crate::mesh::Mesh;
use crate::util::prefetch;
use rayon::prelude::*;

/// The whole sequence M_n … M_g: the base mesh plus the splits that refine it
/// back to the (welded) input.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ProgressiveMesh {
    /// M_g, the coarsest mesh.
    pub base: Mesh,
    /// Coarse → fine.
    pub splits: Vec<VertexSplit>,
    /// Progressive vertex index → vertex of the welded input.
    pub vertex_origin: Vec<u32>,
    /// Progressive triangle index → triangle of the welded input.
    pub triangle_origin: Vec<u32>,
    /// Every corner's wedge at every step, when the simplifier tracked
    /// wedges (`Simplifier::set_wedges`); `None` on the position-only path.
    pub wedges: Option<WedgeLog>,
}

/// Splits built between two frees of the log's records they read (7 MB of
/// splits; each chunk is one parallel pass). Five in the unit tests, so
/// that their small meshes take many chunks.
const SPLIT_CHUNK: usize = if cfg!(test) { 5 } else { 1 << 16 };

/// Meshes after fewer splits are replayed on one core
/// ([`ProgressiveMesh::mesh_at_splits`]).
const PARALLEL_MIN_SPLITS: usize = 1 << 16;

impl ProgressiveMesh {
    /// Build from the simplifier's final state and log (collapse order).
    /// `wedges`: every corner's wedge, when tracked and stored; `implied`:
    /// each vertex's one wedge when the log left every wedge edit implied
    /// by it (`Features::edits_implied`) — then `wedges` may be `None`,
    /// every corner having its vertex's wedge (`Features::corners_implied`).
    /// The log is emptied as its splits are built (its memory returned).
    pub(crate) fn from_log(
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
        vertex_alive: &[bool],
        triangle_alive: &[bool],
        log: &mut Log,
        wedges: Option<&[[u32; 3]]>,
        implied: Option<&[u32]>,
    ) -> ProgressiveMesh {
        let records = &log.records;
        let n = records.len();
        let Numbering {
            vnew,
            tnew,
            vertex_origin,
            triangle_origin,
            base_vertices,
            base_triangles,
        } = Numbering::of(vertex_alive, triangle_alive, log);
        let map = |t: &[u32; 3]| t.map(|v| vnew[v as usize]);
        // The final state's corners, and the corners as they were when each
        // removed triangle died, are both in `triangles` (dead triangles are
        // never edited again).
        let base = Mesh {
            positions: vertex_origin[..base_vertices]
                .iter()
                .map(|&v| positions[v as usize])
                .collect(),
            triangles: triangle_origin[..base_triangles]
                .iter()
                .map(|&t| map(&triangles[t as usize]))
                .collect(),
        };
        // the merged positions need the log in order; the rest of each
        // split only reads shared maps, so splits are built in parallel
        let p_merged = merged_positions(positions, records);
        // one wedge per vertex (no seam, no attribute): the per-split
        // edits follow from it and are not stored (wedgelog.rs)
        let per_vertex = match implied {
            // what one_wedge_per_vertex finds from the written-out edits
            Some(vw) => Some(implied_per_vertex(vw, vertex_alive.len())),
            None => {
                wedges.and_then(|w| one_wedge_per_vertex(triangles, w, log, vertex_alive.len()))
            }
        };
        let explicit = wedges.is_some() && per_vertex.is_none();
        // Split k undoes record n - 1 - k: the splits are built newest record
        // first, a chunk at a time, and the log's records and corners that
        // a chunk read are freed before the next (peak memory: at 4.4M
        // triangles the whole log beside the splits, 112 bytes each, was
        // the simplification's peak).
        let mut splits: Vec<VertexSplit> = Vec::with_capacity(n);
        let mut split_wedges: Vec<SplitWedges> = Vec::new();
        if explicit {
            split_wedges.reserve(n);
        }
        for k0 in (0..n).step_by(SPLIT_CHUNK) {
            let k1 = (k0 + SPLIT_CHUNK).min(n);
            let b = SplitBuilder {
                positions,
                triangles,
                log,
                // (read for the explicit edits only)
                wedges: wedges.filter(|_| explicit),
                vnew: &vnew,
                tnew: &tnew,
            };
            let item = |k: usize| {
                b.prefetch_ahead(k, n);
                (&log.records[n - 1 - k], &p_merged[k])
            };
            if explicit {
                let (s, w): (Vec<VertexSplit>, Vec<SplitWedges>) = (k0..k1)
                    .into_par_iter()
                    .map_init(Vec::new, |buf, k| {
                        let (s, w) = b.build(buf, item(k));
                        (s, w.unwrap_or_default())
                    })
                    .unzip();
                splits.extend(s);
                split_wedges.extend(w);
            } else {
                splits.par_extend(
                    (k0..k1)
                        .into_par_iter()
                        .map_init(Vec::new, |buf, k| b.build(buf, item(k)).0),
                );
            }
            log.free_from(n - k1);
        }
        // the corners' wedges: stored, or each corner its vertex's
        let corner_wedges = |t: u32| match (wedges, implied) {
            (Some(w), _) => w[t as usize],
            (None, Some(vw)) => triangles[t as usize].map(|v| vw[v as usize]),
            (None, None) => [0; 3],
        };
        let tracked = wedges.is_some() || implied.is_some();
        let wedges = tracked.then(|| WedgeLog {
            base: triangle_origin[..base_triangles]
                .iter()
                .map(|&t| corner_wedges(t))
                .collect(),
            splits: split_wedges,
            per_vertex: per_vertex
                .as_ref()
                .map(|w| vertex_origin.iter().map(|&v| w[v as usize]).collect()),
        });
        ProgressiveMesh {
            base,
            splits,
            vertex_origin,
            triangle_origin,
            wedges,
        }
    }

    /// Number of splits: the finest level is `mesh_at_splits(len())`.
    pub fn len(&self) -> usize {
        self.splits.len()
    }

    /// No vertex split: the base mesh is the full mesh.
    pub fn is_empty(&self) -> bool {
        self.splits.is_empty()
    }

    /// Triangle count after `k` splits, for every `k` in `0..=len()`
    /// (non-decreasing).
    pub fn triangle_counts(&self) -> Vec<usize> {
        let mut out = Vec::with_capacity(self.splits.len() + 1);
        let mut n = self.base.triangles.len();
        out.push(n);
        for s in &self.splits {
            n += s.faces.len();
            out.push(n);
        }
        out
    }

    /// The largest split count whose mesh has at most `triangles` triangles
    /// (0 when even the base mesh has more).
    pub fn splits_for_triangles(&self, triangles: usize) -> usize {
        let counts = self.triangle_counts();
        counts
            .partition_point(|&c| c <= triangles)
            .saturating_sub(1)
    }

    /// The mesh after `k` splits (clamped to `len()`): exactly the mesh the
    /// simplifier had `len() - k` contractions into its run.
    ///
    /// Built in parts on every core: each part owns a run of vertices and
    /// of triangles and replays every split in order on those alone (the
    /// splits are read once per part, the scattered writes split between
    /// them), so the mesh is the cursor's whatever the number of parts.
    pub fn mesh_at_splits(&self, k: usize) -> Mesh {
        let parts = if k < PARALLEL_MIN_SPLITS {
            1
        } else {
            rayon::current_num_threads()
        };
        self.mesh_at_splits_in(k, parts)
    }

    /// [`Self::mesh_at_splits`] in `parts` parts (at least one).
    fn mesh_at_splits_in(&self, k: usize, parts: usize) -> Mesh {
        let splits = &self.splits[..k.min(self.len())];
        let nv = self.base.positions.len() + splits.len();
        let nt = self.base.triangles.len() + splits.iter().map(|s| s.faces.len()).sum::<usize>();
        let mut positions = vec![[0.0; 3]; nv];
        let mut triangles = vec![[0; 3]; nt];
        let (pv, pt) = (
            nv.div_ceil(parts.max(1)).max(1),
            nt.div_ceil(parts.max(1)).max(1),
        );
        let mut vs: Vec<(usize, &mut [[f32; 3]])> = positions.chunks_mut(pv).enumerate().collect();
        let mut ts: Vec<(usize, &mut [[u32; 3]])> = triangles.chunks_mut(pt).enumerate().collect();
        // (one part may own vertices and no triangle, or the other way)
        vs.resize_with(vs.len().max(ts.len()), || (usize::MAX, &mut []));
        ts.resize_with(vs.len(), || (usize::MAX, &mut []));
        vs.into_par_iter().zip(ts).for_each(|((i, pos), (j, tri))| {
            self.replay_part((i.wrapping_mul(pv), pos), (j.wrapping_mul(pt), tri), splits);
        });
        Mesh {
            positions,
            triangles,
        }
    }

    /// The base mesh refined by `splits`, on the vertices from `v0` (`pos`)
    /// and the triangles from `t0` (`tri`) only: what the cursor leaves there.
    fn replay_part(
        &self,
        (v0, pos): (usize, &mut [[f32; 3]]),
        (t0, tri): (usize, &mut [[u32; 3]]),
        splits: &[VertexSplit],
    ) {
        let vs = v0..v0.saturating_add(pos.len());
        let ts = t0..t0.saturating_add(tri.len());
        let nb = self.base.positions.len();
        // (the base's part of each run)
        let (bv, bt) = (vs.start.min(nb)..vs.end.min(nb), {
            let tb = self.base.triangles.len();
            ts.start.min(tb)..ts.end.min(tb)
        });
        pos[..bv.len()].copy_from_slice(&self.base.positions[bv]);
        tri[..bt.len()].copy_from_slice(&self.base.triangles[bt]);
        let mut next = self.base.triangles.len();
        for (i, s) in splits.iter().enumerate() {
            if vs.contains(&(s.v1 as usize)) {
                pos[s.v1 as usize - v0] = s.p1;
            }
            if vs.contains(&(nb + i)) {
                pos[nb + i - v0] = s.p0;
            }
            for f in &s.faces {
                if ts.contains(&next) {
                    tri[next - t0] = *f;
                }
                next += 1;
            }
            for c in &s.corners {
                if ts.contains(&(c.triangle as usize)) {
                    tri[c.triangle as usize - t0][c.slot as usize] = s.v0;
                }
            }
        }
    }

    /// The finest mesh of the sequence with at most `triangles` triangles
    /// (the base mesh if it has more).
    pub fn mesh_at(&self, triangles: usize) -> Mesh {
        self.mesh_at_splits(self.splits_for_triangles(triangles))
    }

    /// A cursor at the base mesh, to refine and coarsen incrementally.
    pub fn cursor(&self) -> Cursor<'_> {
        Cursor {
            pm: self,
            mesh: self.base.clone(),
            wedges: self.wedges.as_ref().map(|w| w.base.clone()),
            applied: 0,
        }
    }

    /// For every vertex of the full mesh, the vertex of the mesh after `k`
    /// splits (clamped to `len()`) it is merged into there: itself when
    /// that mesh has it (below `base + k`), else the representative of the
    /// vertex its split came from (`v1`).
    pub fn representatives(&self, k: usize) -> Vec<u32> {
        let k = k.min(self.len());
        let nb = self.base.positions.len() as u32;
        let mut rep: Vec<u32> = (0..nb + self.len() as u32).collect();
        for s in &self.splits[k..] {
            rep[s.v0 as usize] = rep[s.v1 as usize];
        }
        rep
    }

    /// The fully refined mesh in the welded input's own vertex and triangle
    /// numbering: equal, index for index, to the mesh that was simplified.
    pub fn full_in_input_order(&self) -> Mesh {
        let fine = self.mesh_at_splits(self.len());
        let mut positions = vec![[0.0; 3]; fine.positions.len()];
        for (i, p) in fine.positions.iter().enumerate() {
            positions[self.vertex_origin[i] as usize] = *p;
        }
        let mut triangles = vec![[0; 3]; fine.triangles.len()];
        for (i, t) in fine.triangles.iter().enumerate() {
            triangles[self.triangle_origin[i] as usize] = t.map(|v| self.vertex_origin[v as usize]);
        }
        Mesh {
            positions,
            triangles,
        }
    }
}

/// A position in the sequence that moves one split at a time.
#[derive(Clone, Debug)]
pub struct Cursor<'a> {
    pm: &'a ProgressiveMesh,
    mesh: Mesh,
    /// The current corners' wedges, when the log has them.
    wedges: Option<Vec<[u32; 3]>>,
    applied: usize,
}

impl<'a> Cursor<'a> {
    /// Splits applied so far.
    pub fn applied(&self) -> usize {
        self.applied
    }

    /// The current mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The current mesh, taken over.
    pub fn into_mesh(self) -> Mesh {
        self.mesh
    }

    /// The wedge of every corner of `mesh()`, when the log has wedges.
    pub fn wedges(&self) -> Option<&[[u32; 3]]> {
        self.wedges.as_deref()
    }

    /// Apply up to `n` more splits; returns how many were applied.
    pub fn refine(&mut self, n: usize) -> usize {
        let end = (self.applied + n).min(self.pm.splits.len());
        let done = end - self.applied;
        if let (Some(cw), Some(log)) = (self.wedges.as_mut(), self.pm.wedges.as_ref()) {
            for i in self.applied..end {
                log.refine(cw, i, &self.pm.splits[i]);
            }
        }
        for s in &self.pm.splits[self.applied..end] {
            debug_assert_eq!(s.v0 as usize, self.mesh.positions.len());
            self.mesh.positions[s.v1 as usize] = s.p1;
            self.mesh.positions.push(s.p0);
            self.mesh.triangles.extend_from_slice(&s.faces);
            for c in &s.corners {
                let corner = &mut self.mesh.triangles[c.triangle as usize][c.slot as usize];
                debug_assert_eq!(*corner, s.v1);
                *corner = s.v0;
            }
        }
        self.applied = end;
        done
    }

    /// Undo up to `n` splits; returns how many were undone.
    pub fn coarsen(&mut self, n: usize) -> usize {
        let start = self.applied.saturating_sub(n);
        let done = self.applied - start;
        if let (Some(cw), Some(log)) = (self.wedges.as_mut(), self.pm.wedges.as_ref()) {
            for i in (start..self.applied).rev() {
                log.coarsen(cw, i, &self.pm.splits[i]);
            }
        }
        for s in self.pm.splits[start..self.applied].iter().rev() {
            for c in &s.corners {
                self.mesh.triangles[c.triangle as usize][c.slot as usize] = s.v1;
            }
            let t = self.mesh.triangles.len() - s.faces.len();
            self.mesh.triangles.truncate(t);
            self.mesh.positions.pop();
            self.mesh.positions[s.v1 as usize] = s.p_merged;
        }
        self.applied = start;
        done
    }

    /// Move to exactly `k` splits.
    pub fn seek(&mut self, k: usize) {
        if k >= self.applied {
            self.refine(k - self.applied);
        } else {
            self.coarsen(self.applied - k);
        }
    }
}

/// The refinement numbering of a log: the base mesh's live vertices and
/// triangles in id order, then each split's vertex and restored triangles,
/// newest contraction first.
struct Numbering {
    /// Simplifier vertex → refinement number.
    vnew: Vec<u32>,
    /// Simplifier triangle → refinement number.
    tnew: Vec<u32>,
    /// Refinement number → simplifier vertex.
    vertex_origin: Vec<u32>,
    /// Refinement number → simplifier triangle.
    triangle_origin: Vec<u32>,
    base_vertices: usize,
    base_triangles: usize,
}

impl Numbering {
    fn of(vertex_alive: &[bool], triangle_alive: &[bool], log: &Log) -> Numbering {
        const NONE: u32 = u32::MAX;
        let mut vnew = vec![NONE; vertex_alive.len()];
        let mut tnew = vec![NONE; triangle_alive.len()];
        let mut vertex_origin = Vec::with_capacity(vertex_alive.len());
        let mut triangle_origin = Vec::with_capacity(triangle_alive.len());
        for (v, &alive) in vertex_alive.iter().enumerate() {
            if alive {
                vnew[v] = vertex_origin.len() as u32;
                vertex_origin.push(v as u32);
            }
        }
        for (t, &alive) in triangle_alive.iter().enumerate() {
            if alive {
                tnew[t] = triangle_origin.len() as u32;
                triangle_origin.push(t as u32);
            }
        }
        let base_vertices = vertex_origin.len();
        let base_triangles = triangle_origin.len();
        for c in log.records.iter().rev() {
            vnew[c.v0 as usize] = vertex_origin.len() as u32;
            vertex_origin.push(c.v0);
            for &t in log.removed(c) {
                tnew[t as usize] = triangle_origin.len() as u32;
                triangle_origin.push(t);
            }
        }
        debug_assert!(vnew.iter().all(|&v| v != NONE));
        Numbering {
            vnew,
            tnew,
            vertex_origin,
            triangle_origin,
            base_vertices,
            base_triangles,
        }
    }
}

/// The merged position of each split (newest contraction first): every
/// vertex's position after the contraction being renumbered, walking the
/// log backwards, where `v1` goes back to `p1`.
fn merged_positions(positions: &[[f32; 3]], records: &[Contraction]) -> Vec<[f32; 3]> {
    let mut current = positions.to_vec();
    records
        .iter()
        .rev()
        .map(|c| {
            let p = current[c.v1 as usize];
            current[c.v1 as usize] = c.p1;
            p
        })
        .collect()
}

/// What building one vertex split reads (shared by the threads).
struct SplitBuilder<'a> {
    positions: &'a [[f32; 3]],
    triangles: &'a [[u32; 3]],
    log: &'a Log,
    wedges: Option<&'a [[u32; 3]]>,
    vnew: &'a [u32],
    tnew: &'a [u32],
}

impl SplitBuilder<'_> {
    /// The split undoing contraction `c`, whose merged position was
    /// `p_merged` (and its wedges, when tracked); `corners` is scratch.
    #[inline]
    fn build(
        &self,
        corners: &mut Vec<(Corner, [u32; 2])>,
        (c, &p_merged): (&Contraction, &[f32; 3]),
    ) -> (VertexSplit, Option<SplitWedges>) {
        let (log, tracked) = (self.log, !self.log.wedges.is_empty());
        let map = |t: &[u32; 3]| t.map(|v| self.vnew[v as usize]);
        corners.clear();
        let range = c.moved.start as usize..c.moved.end as usize;
        corners.extend(log.moved(c).zip(range).map(|(k, i)| {
            let corner = Corner {
                triangle: self.tnew[k.triangle as usize],
                slot: k.slot,
            };
            // a split undoes the contraction: after ↔ before
            let w = if tracked {
                let w = log.wedges[i];
                [w[1], w[0]]
            } else {
                [0; 2]
            };
            (corner, w)
        }));
        // by triangle (each is on one corner of a split: the same order
        // as sorting the whole tuples, for less)
        corners.sort_unstable_by_key(|c| c.0.triangle);
        let split_wedges = self.wedges.map(|w| SplitWedges {
            faces: log.removed(c).iter().map(|&t| w[t as usize]).collect(),
            corners: corners.iter().map(|c| c.1).collect(),
        });
        let split = VertexSplit {
            v1: self.vnew[c.v1 as usize],
            v0: self.vnew[c.v0 as usize],
            p1: c.p1,
            p_merged,
            p0: self.positions[c.v0 as usize],
            faces: log
                .removed(c)
                .iter()
                .map(|&t| map(&self.triangles[t as usize]))
                .collect(),
            corners: corners.iter().map(|c| c.0).collect(),
            error: c.error,
        };
        (split, split_wedges)
    }

    /// Split k undoes the k-th newest contraction. The log is in
    /// contraction order, so each split's triangles and vertices are cold:
    /// a split prefetches what the one eight on reads directly, and the
    /// maps of the triangle corners of the one four on.
    #[inline]
    fn prefetch_ahead(&self, k: usize, n: usize) {
        let (records, vnew) = (&self.log.records, self.vnew);
        if k + 8 < n {
            let c = &records[n - 1 - (k + 8)];
            for &t in self.log.removed(c) {
                prefetch(&self.triangles[t as usize]);
            }
            for x in self.log.moved(c) {
                prefetch(&self.tnew[x.triangle as usize]);
            }
            prefetch(&self.positions[c.v0 as usize]);
            prefetch(&vnew[c.v0 as usize]);
            prefetch(&vnew[c.v1 as usize]);
        }
        if k + 4 < n {
            for &t in self.log.removed(&records[n - 1 - (k + 4)]) {
                for &x in &self.triangles[t as usize] {
                    prefetch(&vnew[x as usize]);
                }
            }
        }
    }
}

/// The wedge of each simplifier vertex when every corner of the log agrees
/// with one wedge per vertex: the final and dying triangles' corners
/// (`wedges`, parallel to `triangles`) and every moved corner's edit (from
/// `v0`'s wedge to `v1`'s). `None` when some vertex has two wedges at some
/// step. A vertex without any corner gets 0 (no corner ever reads it).
fn one_wedge_per_vertex(
    triangles: &[[u32; 3]],
    wedges: &[[u32; 3]],
    log: &Log,
    vertices: usize,
) -> Option<Vec<u32>> {
    const UNSET: u32 = u32::MAX;
    if log.wedges.len() != log.corners.len() {
        return None;
    }
    let mut of = vec![UNSET; vertices];
    let mut agree = |v: u32, w: u32| {
        let slot = &mut of[v as usize];
        if *slot == UNSET {
            *slot = w;
        }
        *slot == w && w != UNSET
    };
    for (t, w) in triangles.iter().zip(wedges) {
        for k in 0..3 {
            if !agree(t[k], w[k]) {
                return None;
            }
        }
    }
    for c in &log.records {
        for e in moved_wedges(log, c) {
            if !agree(c.v0, e[0]) || !agree(c.v1, e[1]) {
                return None;
            }
        }
    }
    for w in &mut of {
        if *w == UNSET {
            *w = 0;
        }
    }
    Some(of)
}

/// [`one_wedge_per_vertex`] when the log left every edit implied by one
/// wedge per vertex (`vw`, `u32::MAX` for a vertex in no triangle): every
/// corner agrees with it, and a vertex without any corner gets 0.
fn implied_per_vertex(vw: &[u32], vertices: usize) -> Vec<u32> {
    let mut of: Vec<u32> = vw
        .iter()
        .map(|&w| if w == u32::MAX { 0 } else { w })
        .collect();
    of.resize(vertices, 0);
    of
}

/// The `[before, after]` wedges of `c`'s moved corners.
fn moved_wedges<'a>(log: &'a Log, c: &Contraction) -> &'a [[u32; 2]] {
    log.wedges
        .get(c.moved.start as usize..c.moved.end as usize)
        .unwrap_or(&[])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn implied_wedge_edits_are_spelled_out_corner_by_corner() {
        // two logged contractions (2 and 0 moved corners), then one in
        // progress with 3 corners moved, the last one's edit left to the
        // caller
        let vw = [10, 11, 12, 13, 14];
        let mut log = Log::with_capacity(4);
        for (v0, v1, corners) in [(0u32, 1u32, 2u32), (2, 1, 0)] {
            let mut c = log.begin(v0, v1, [0.0; 3], &[], 0.0);
            for t in 0..corners {
                log.push_corner(Corner {
                    triangle: t,
                    slot: 0,
                });
            }
            c.moved.end = log.mark();
            log.records.push(c);
        }
        for t in 0..3 {
            log.push_corner(Corner {
                triangle: t,
                slot: 1,
            });
        }
        log.spell_out_wedges(&vw, [3, 4]);
        assert_eq!(log.wedges, [[10, 11], [10, 11], [13, 14], [13, 14]]);
        assert_eq!(implied_per_vertex(&[5, u32::MAX, 7], 4), [5, 0, 7, 0]);
    }

    /// The mesh after `k` splits replayed in parts (each part owning a run
    /// of vertices and triangles) is the cursor's, for any number of parts,
    /// including more parts than vertices. Fails when a part skips a write
    /// into its run (a face, a corner edit, a position) or applies them out
    /// of order (a corner moved twice keeps the later split's vertex).
    #[test]
    fn meshes_replayed_in_parts_are_the_cursors() {
        let m = crate::shapes::icosphere(3);
        let indices: Vec<u32> = m.triangles.iter().flatten().copied().collect();
        let opts = crate::SimplifyOptions::DEFAULT.with_target_ratio(0.01);
        let pm = crate::simplify(&m.positions, &indices, &opts)
            .expect("a clean sphere")
            .pm;
        let mut cursor = pm.cursor();
        for k in [0, 1, 2, pm.len() / 3, pm.len() - 1, pm.len()] {
            cursor.seek(k);
            for parts in [1, 2, 3, 7, 5000] {
                assert_eq!(
                    &pm.mesh_at_splits_in(k, parts),
                    cursor.mesh(),
                    "{k} splits, {parts} parts"
                );
            }
        }
        // a corner moved by more than one split
        let mut seen = std::collections::BTreeSet::new();
        let twice = pm
            .splits
            .iter()
            .flat_map(|s| s.corners.iter())
            .any(|c| !seen.insert(c));
        assert!(twice);
    }

    /// The splits are built five at a time here, the log's records and
    /// corners freed behind each chunk: the fully refined mesh is still the
    /// input, index for index, and every level has its count of triangles.
    /// Fails when a chunk frees records or corners not yet read (a panic
    /// or another mesh).
    #[test]
    fn splits_built_in_chunks_refine_to_the_input() {
        let m = crate::shapes::icosphere(3);
        let indices: Vec<u32> = m.triangles.iter().flatten().copied().collect();
        let opts = crate::SimplifyOptions {
            target_triangles: Some(40),
            ..Default::default()
        };
        let s = crate::simplify(&m.positions, &indices, &opts).expect("a clean sphere");
        let pm = &s.pm;
        assert!(pm.len() > 20 * SPLIT_CHUNK, "{} splits", pm.len());
        let input = crate::prepare(&m.positions, &indices).expect("clean").mesh;
        assert_eq!(pm.full_in_input_order(), input);
        let counts = pm.triangle_counts();
        for k in (0..=pm.len()).step_by(7) {
            assert_eq!(pm.mesh_at_splits(k).triangles.len(), counts[k]);
        }
    }
}
