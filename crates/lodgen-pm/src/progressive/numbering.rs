//! The refinement numbering of a log and the splits' merged positions,
//! built on every core. Both were walks of the log on one core (bunny-4m:
//! ~345 ms at load 6, session 22). Each map from the simplifier's numbers
//! to the refinement's is the inverse of a list; it is written in parts of
//! its range, each part scanning the whole list for the entries that land
//! in it (the same values for any number of parts). The merged positions
//! are found by parts of the vertex range likewise, each keeping the
//! current position of its own vertices while it walks the log.

use super::log::{Contraction, Log};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// No number (a vertex or triangle in no list).
const NONE: u32 = u32::MAX;

/// The refinement numbering of a log: the base mesh's live vertices and
/// triangles in id order, then each split's vertex and restored triangles,
/// newest contraction first.
pub(super) struct Numbering {
    /// Simplifier vertex → refinement number.
    pub vnew: Vec<u32>,
    /// Simplifier triangle → refinement number.
    pub tnew: Vec<u32>,
    /// Refinement number → simplifier vertex.
    pub vertex_origin: Vec<u32>,
    /// Refinement number → simplifier triangle.
    pub triangle_origin: Vec<u32>,
    pub base_vertices: usize,
    pub base_triangles: usize,
}

impl Numbering {
    /// The numbering of `log` over the final state's live vertices and
    /// triangles, on every core.
    pub fn of(vertex_alive: &[bool], triangle_alive: &[bool], log: &Log) -> Numbering {
        Numbering::of_in(vertex_alive, triangle_alive, log, parts())
    }

    /// [`Numbering::of`] with the maps written in `parts` parts.
    fn of_in(vertex_alive: &[bool], triangle_alive: &[bool], log: &Log, parts: usize) -> Numbering {
        let records = &log.records;
        let live = |alive: &[bool]| {
            let mut origin = Vec::with_capacity(alive.len());
            origin.par_extend(
                alive
                    .par_iter()
                    .enumerate()
                    .filter(|a| *a.1)
                    .map(|a| a.0 as u32),
            );
            origin
        };
        let (mut vertex_origin, mut triangle_origin) =
            rayon::join(|| live(vertex_alive), || live(triangle_alive));
        let base_vertices = vertex_origin.len();
        let base_triangles = triangle_origin.len();
        rayon::join(
            || vertex_origin.par_extend(records.par_iter().rev().map(|c| c.v0)),
            || {
                triangle_origin.par_extend(
                    records
                        .par_iter()
                        .rev()
                        .flat_map_iter(|c| log.removed(c).iter().copied()),
                )
            },
        );
        let (vnew, tnew) = rayon::join(
            || inverse(&vertex_origin, vertex_alive.len(), parts),
            || inverse(&triangle_origin, triangle_alive.len(), parts),
        );
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

/// Parts a map is written in: one per core (the values do not depend on
/// it).
fn parts() -> usize {
    rayon::current_num_threads().max(1)
}

/// `inv[origin[i]] = i` over `0..n` (`NONE` where no entry lands; the last
/// entry where several do), written in `parts` parts of `0..n`, each
/// scanning the whole of `origin`.
fn inverse(origin: &[u32], n: usize, parts: usize) -> Vec<u32> {
    let mut inv = vec![NONE; n];
    let size = n.div_ceil(parts.max(1)).max(1);
    inv.par_chunks_mut(size).enumerate().for_each(|(p, part)| {
        let lo = p * size;
        for (i, &x) in origin.iter().enumerate() {
            if let Some(slot) = part.get_mut((x as usize).wrapping_sub(lo)) {
                *slot = i as u32;
            }
        }
    });
    inv
}

/// The merged position of each split (newest contraction first): `v1`'s
/// position after the contraction, i.e. the `p1` of the next contraction
/// into `v1`, or its final (or last) position in `positions`.
pub(super) struct MergedPositions(Vec<[AtomicU32; 3]>);

impl MergedPositions {
    /// The merged positions of `records`' splits, on every core.
    pub fn of(positions: &[[f32; 3]], records: &[Contraction]) -> MergedPositions {
        MergedPositions::of_in(positions, records, parts())
    }

    /// [`MergedPositions::of`] in `parts` parts of the vertex range: each
    /// walks the whole log newest first and keeps the positions of its own
    /// vertices, writing the splits whose `v1` is one of them (each split
    /// written by exactly one part).
    fn of_in(positions: &[[f32; 3]], records: &[Contraction], parts: usize) -> MergedPositions {
        let n = records.len();
        let out: Vec<[AtomicU32; 3]> = (0..n)
            .into_par_iter()
            .map(|_| [0, 0, 0].map(AtomicU32::new))
            .collect();
        let size = positions.len().div_ceil(parts.max(1)).max(1);
        positions.par_chunks(size).enumerate().for_each(|(p, own)| {
            let lo = p * size;
            let mut current = own.to_vec();
            for (k, c) in records.iter().rev().enumerate() {
                if let Some(at) = current.get_mut((c.v1 as usize).wrapping_sub(lo)) {
                    for (o, x) in out[k].iter().zip(*at) {
                        o.store(x.to_bits(), Relaxed);
                    }
                    *at = c.p1;
                }
            }
        });
        MergedPositions(out)
    }

    /// Split `k`'s merged position.
    #[inline]
    pub fn get(&self, k: usize) -> [f32; 3] {
        self.0[k]
            .each_ref()
            .map(|x| f32::from_bits(x.load(Relaxed)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The maps and lists of a numbering, and the merged positions.
    type Serial = (Vec<u32>, Vec<u32>, Vec<u32>, Vec<u32>, Vec<[f32; 3]>);

    /// The numbering and the merged positions on one core, as `from_log`
    /// made them before they were split into parts.
    fn serial(
        positions: &[[f32; 3]],
        vertex_alive: &[bool],
        triangle_alive: &[bool],
        log: &Log,
    ) -> Serial {
        let mut vnew = vec![NONE; vertex_alive.len()];
        let mut tnew = vec![NONE; triangle_alive.len()];
        let (mut vo, mut to) = (Vec::new(), Vec::new());
        for (v, _) in vertex_alive.iter().enumerate().filter(|a| *a.1) {
            vnew[v] = vo.len() as u32;
            vo.push(v as u32);
        }
        for (t, _) in triangle_alive.iter().enumerate().filter(|a| *a.1) {
            tnew[t] = to.len() as u32;
            to.push(t as u32);
        }
        for c in log.records.iter().rev() {
            vnew[c.v0 as usize] = vo.len() as u32;
            vo.push(c.v0);
            for &t in log.removed(c) {
                tnew[t as usize] = to.len() as u32;
                to.push(t);
            }
        }
        let mut current = positions.to_vec();
        let merged = log
            .records
            .iter()
            .rev()
            .map(|c| std::mem::replace(&mut current[c.v1 as usize], c.p1))
            .collect();
        (vnew, tnew, vo, to, merged)
    }

    /// On real logs (a sphere simplified to 40 triangles, and a grid of 72
    /// clusters simplified partitioned, whose log is the clusters' merged),
    /// with the simplifier's final state, the numbering and the merged
    /// positions built in parts are the one-core walk's for any number of
    /// parts, more parts than vertices too, and on every core. Fails when a
    /// part drops an entry of its range, keeps an earlier one where the
    /// list holds two, or a split reads a position another part owns.
    #[test]
    fn numbering_in_parts_is_the_serial_walks() {
        let sphere = crate::shapes::icosphere(3);
        let grid = crate::shapes::grid(120, 120, |x, y| 0.1 * (7.0 * x).sin() * (5.0 * y).cos());
        let cases = [
            (
                sphere,
                crate::SimplifyOptions::DEFAULT.with_target_triangles(40),
            ),
            (
                grid,
                crate::SimplifyOptions::DEFAULT
                    .with_target_ratio(0.015)
                    .with_partition(Some(400)),
            ),
        ];
        for (m, opts) in cases {
            let mut s = crate::simplify::Simplifier::new(&m, &opts).expect("a clean mesh");
            s.run();
            let (pos, alive, tri_alive, log) = s.final_state();
            assert!(log.records.len() > pos.len() / 2);
            in_parts_is_serial(pos, alive, tri_alive, log);
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(3)
                .build()
                .expect("a thread pool");
            pool.install(|| in_parts_is_serial(pos, alive, tri_alive, log));
        }
    }

    fn in_parts_is_serial(pos: &[[f32; 3]], alive: &[bool], tri_alive: &[bool], log: &Log) {
        let (vnew, tnew, vo, to, merged) = serial(pos, alive, tri_alive, log);
        for parts in [1, 2, 3, 7, 5000, parts()] {
            let n = Numbering::of_in(alive, tri_alive, log, parts);
            assert_eq!((n.vnew, n.tnew), (vnew.clone(), tnew.clone()), "{parts}");
            assert_eq!(
                (n.vertex_origin, n.triangle_origin),
                (vo.clone(), to.clone())
            );
            assert_eq!(n.base_vertices, alive.iter().filter(|&&a| a).count());
            assert_eq!(n.base_triangles, tri_alive.iter().filter(|&&a| a).count());
            let p = MergedPositions::of_in(pos, &log.records, parts);
            let got: Vec<[f32; 3]> = (0..merged.len()).map(|k| p.get(k)).collect();
            assert_eq!(got, merged, "{parts} parts");
        }
        // a vertex contracted into more than once: a split's merged
        // position is the next one's p1, not the final position
        let mut into = vec![0; pos.len()];
        log.records.iter().for_each(|c| into[c.v1 as usize] += 1);
        assert!(into.iter().any(|&k| k > 1));
    }

    /// The inverse keeps the last of repeated entries and leaves
    /// unreached numbers `NONE`, in any number of parts.
    #[test]
    fn inverse_keeps_the_last_entry() {
        let origin = [3, 0, 3, 5];
        for parts in [1, 2, 4, 9] {
            assert_eq!(
                inverse(&origin, 7, parts),
                [1, NONE, NONE, 2, NONE, 3, NONE]
            );
        }
        assert!(inverse(&[], 0, 2).is_empty());
    }
}
