//! The clusters' states written back into the whole mesh on every core, a
//! batch of clusters at a time (each batch's simplifiers freed once
//! written). A cluster writes its interior vertices (which no other
//! cluster has) and its own triangles (inside a run of the whole mesh's,
//! disjoint from every other cluster's run), so the writes are disjoint:
//! the triangle arrays are cut at the clusters' runs, the vertex arrays
//! into parts of the vertex range, each part writing the interior vertices
//! of every cluster of the batch that fall in it. The same values land
//! where one core's loop put them, for any thread count.

use super::{add_rejections, Done, Held, Local, Tris};
use crate::simplify::quadric::Quadric;
use crate::simplify::stats::Rejections;
use crate::simplify::Simplifier;
use rayon::prelude::*;

/// Clusters written back at once: a batch's simplifiers are freed before
/// the next batch is written (bunny-4m: 271 clusters of ~1.2 MB each).
const WRITE_BATCH: usize = 16;

/// Parts the vertex range is cut into for a batch's writes (or the held
/// vertices'): a few per core.
const PARTS: usize = 8;

/// A cluster's stats, added to the whole mesh's.
type Counts = (usize, usize, usize, Rejections);

/// One part of the whole mesh's per-vertex arrays: vertices `lo..`.
struct Verts<'a> {
    lo: usize,
    pos: &'a mut [[f32; 3]],
    quadric: &'a mut [Quadric],
    alive: &'a mut [bool],
    boundary: &'a mut [bool],
    corner: &'a mut [bool],
}

/// The whole mesh's triangles of one cluster's run: triangles `lo..`.
struct Tri<'a> {
    lo: usize,
    tris: &'a mut [[u32; 3]],
    alive: &'a mut [bool],
    /// Each corner's wedge (with one wedge per vertex: its vertex's).
    wedges: Option<&'a mut [[u32; 3]]>,
}

impl Simplifier {
    /// Write every cluster's state back (its interior vertices and its
    /// triangles as they are now), a batch of `WRITE_BATCH` clusters at a
    /// time on every core, and keep what the merge reads.
    pub(super) fn write_back(&mut self, locals: Vec<Local>) -> Vec<Done> {
        let mut done = Vec::with_capacity(locals.len());
        let mut locals = locals.into_iter();
        loop {
            let batch: Vec<Local> = locals.by_ref().take(WRITE_BATCH).collect();
            if batch.is_empty() {
                break;
            }
            self.write_batch(&batch);
            // (the simplifiers freed on every core too)
            let kept: Vec<(Done, Counts)> = batch.into_par_iter().map(into_done).collect();
            for (d, (removed, collapses, passes, rejected)) in kept {
                self.live_tris -= removed;
                self.stats.collapses += collapses;
                // (the clusters made the same rounds: count them once)
                self.stats.passes = self.stats.passes.max(passes);
                add_rejections(&mut self.stats.rejected, &rejected);
                done.push(d);
            }
        }
        done
    }

    /// `batch`'s interior vertices and triangles written into the whole
    /// mesh, the vertices by parts of the vertex range beside the
    /// triangles cluster by cluster; then the lift bits that changed, on
    /// one core (they share words; few change).
    fn write_batch(&mut self, batch: &[Local]) {
        let bounds = part_bounds(batch, self.pos.len());
        let Simplifier {
            pos,
            quadric,
            alive,
            boundary,
            corner,
            lifted,
            tris,
            tri_alive,
            features,
            ..
        } = self;
        let verts = split_vertices(&bounds, pos, quadric, alive, boundary, corner);
        let (wedges, vertex_wedge) = match features {
            Some(f) => (f.wedges.as_deref_mut(), f.vertex_wedge.as_deref()),
            None => (None, None),
        };
        // (one wedge per vertex: each corner's wedge is its vertex's; a
        // dead triangle's as it died: its corners stay as they were)
        let vw = vertex_wedge.filter(|_| wedges.is_some());
        let runs = split_runs(batch, tris, tri_alive, wedges.filter(|_| vw.is_some()));
        let now = &*lifted;
        let (flips, ()) = rayon::join(
            || {
                verts
                    .into_par_iter()
                    .map(|mut part| {
                        let mut flips = Vec::new();
                        for l in batch {
                            part.write(l, |g| now.get(g), &mut flips);
                        }
                        flips
                    })
                    .collect::<Vec<Vec<(u32, bool)>>>()
            },
            || {
                runs.into_par_iter()
                    .zip(batch)
                    .for_each(|(run, l)| run.write(l, vw))
            },
        );
        for (v, on) in flips.into_iter().flatten() {
            lifted.set(v, on);
        }
    }

    /// The held vertices' quadrics and positions (sorted by vertex) put
    /// back, by parts of the vertex range on every core.
    pub(super) fn restore_held(&mut self, held: Vec<Held>) {
        let nv = self.pos.len();
        let chunk = held.len().div_ceil(PARTS).max(1);
        // (a part from each chunk's first vertex to the next's)
        let mut bounds = vec![0];
        bounds.extend(held.iter().step_by(chunk).skip(1).map(|h| h.0));
        bounds.push(nv);
        let Simplifier {
            pos,
            quadric,
            alive,
            boundary,
            corner,
            ..
        } = self;
        let verts = split_vertices(&bounds, pos, quadric, alive, boundary, corner);
        verts
            .into_par_iter()
            .zip(held.par_chunks(chunk))
            .for_each(|(part, held)| {
                for &(v, q, p) in held {
                    part.quadric[v - part.lo] = q;
                    part.pos[v - part.lo] = p;
                }
            });
    }
}

impl Verts<'_> {
    /// Cluster `l`'s interior vertices in this part written from its
    /// simplifier; `(vertex, bit)` pushed to `flips` where its lift bit
    /// differs from the whole mesh's (`lifted`).
    fn write(&mut self, l: &Local, lifted: impl Fn(u32) -> bool, flips: &mut Vec<(u32, bool)>) {
        let hi = self.lo + self.pos.len();
        let from = l.verts.partition_point(|&g| (g as usize) < self.lo);
        let to = l.verts.partition_point(|&g| (g as usize) < hi);
        let s = &l.s;
        for i in from..to {
            if l.held[i] {
                continue;
            }
            let g = l.verts[i];
            let k = g as usize - self.lo;
            self.pos[k] = s.pos[i];
            self.quadric[k] = s.quadric[i];
            self.alive[k] = s.alive[i];
            self.boundary[k] = s.boundary[i];
            self.corner[k] = s.corner[i];
            let on = s.lifted.get(i as u32);
            if on != lifted(g) {
                flips.push((g, on));
            }
        }
    }
}

impl Tri<'_> {
    /// Cluster `l`'s triangles as they are now, in the whole mesh's
    /// numbering (and, given `vw`, each corner's wedge its vertex's).
    fn write(mut self, l: &Local, vw: Option<&[u32]>) {
        let s = &l.s;
        for (t, tri) in s.tris.iter().enumerate() {
            let k = l.tris.global(t as u32) as usize - self.lo;
            let tri = tri.map(|x| l.verts[x as usize]);
            self.tris[k] = tri;
            self.alive[k] = s.tri_alive[t];
            if let (Some(w), Some(vw)) = (self.wedges.as_deref_mut(), vw) {
                w[k] = tri.map(|v| vw[v as usize]);
            }
        }
    }
}

/// What the merge keeps of a cluster, and its stats.
fn into_done(l: Local) -> (Done, Counts) {
    let s = l.s;
    let counts = (
        s.tris.len() - s.live_tris,
        s.stats.collapses,
        s.stats.passes,
        s.stats.rejected,
    );
    let d = Done {
        verts: l.verts,
        tris: l.tris,
        rounds: l.rounds,
        log: s.log,
    };
    (d, counts)
}

/// The whole mesh's triangle range a cluster's triangles lie in.
fn run_of(l: &Local) -> (usize, usize) {
    match &l.tris {
        Tris::Run(start) => (*start as usize, *start as usize + l.s.tris.len()),
        Tris::List(ids) => match (ids.first(), ids.last()) {
            (Some(&a), Some(&b)) => (a as usize, b as usize + 1),
            _ => (0, 0),
        },
    }
}

/// The triangle arrays cut at `batch`'s runs (increasing and disjoint:
/// the clusters are cut from consecutive runs in order).
fn split_runs<'a>(
    batch: &[Local],
    mut tris: &'a mut [[u32; 3]],
    mut alive: &'a mut [bool],
    mut wedges: Option<&'a mut [[u32; 3]]>,
) -> Vec<Tri<'a>> {
    let mut at = 0;
    let mut runs = Vec::with_capacity(batch.len());
    for l in batch {
        let (lo, hi) = run_of(l);
        debug_assert!(at <= lo && lo <= hi, "the clusters' runs are in order");
        cut(&mut tris, lo - at);
        cut(&mut alive, lo - at);
        let w = wedges.as_mut().map(|w| {
            cut(w, lo - at);
            cut(w, hi - lo)
        });
        runs.push(Tri {
            lo,
            tris: cut(&mut tris, hi - lo),
            alive: cut(&mut alive, hi - lo),
            wedges: w,
        });
        at = hi;
    }
    runs
}

/// The vertex arrays cut at `bounds` (increasing, from 0 to their length).
fn split_vertices<'a>(
    bounds: &[usize],
    mut pos: &'a mut [[f32; 3]],
    mut quadric: &'a mut [Quadric],
    mut alive: &'a mut [bool],
    mut boundary: &'a mut [bool],
    mut corner: &'a mut [bool],
) -> Vec<Verts<'a>> {
    bounds
        .windows(2)
        .map(|w| {
            let n = w[1] - w[0];
            Verts {
                lo: w[0],
                pos: cut(&mut pos, n),
                quadric: cut(&mut quadric, n),
                alive: cut(&mut alive, n),
                boundary: cut(&mut boundary, n),
                corner: cut(&mut corner, n),
            }
        })
        .collect()
}

/// The first `n` elements of `s` (at most all), `s` left with the rest.
fn cut<'a, T>(s: &mut &'a mut [T], n: usize) -> &'a mut [T] {
    let n = n.min(s.len());
    let (a, b) = std::mem::take(s).split_at_mut(n);
    *s = b;
    a
}

/// Bounds cutting the vertex range `0..nv` into `PARTS` parts of about
/// as many of `batch`'s vertices each (from every 64th of each cluster's).
fn part_bounds(batch: &[Local], nv: usize) -> Vec<usize> {
    let mut sample: Vec<u32> = batch
        .iter()
        .flat_map(|l| l.verts.iter().step_by(64).copied())
        .collect();
    sample.sort_unstable();
    let mut bounds = vec![0];
    for p in 1..PARTS {
        if let Some(&v) = sample.get(p * sample.len() / PARTS) {
            let at = bounds.last().copied().unwrap_or(0);
            bounds.push((v as usize).clamp(at, nv));
        }
    }
    bounds.push(nv);
    bounds
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simplify::Schedule;
    use crate::{shapes, SimplifyOptions};

    /// The write-back as one core made it before it was split into parts:
    /// cluster by cluster, every interior vertex and own triangle.
    fn write_back_serial(s: &mut Simplifier, locals: Vec<Local>) -> Vec<Done> {
        let mut done = Vec::new();
        for l in locals {
            for (i, &g) in l.verts.iter().enumerate() {
                let g = g as usize;
                if !l.held[i] {
                    s.pos[g] = l.s.pos[i];
                    s.quadric[g] = l.s.quadric[i];
                    s.alive[g] = l.s.alive[i];
                    s.boundary[g] = l.s.boundary[i];
                    s.corner[g] = l.s.corner[i];
                    s.lifted.set(g as u32, l.s.lifted.get(i as u32));
                }
            }
            for (t, tri) in l.s.tris.iter().enumerate() {
                let g = l.tris.global(t as u32) as usize;
                s.tris[g] = tri.map(|x| l.verts[x as usize]);
                s.tri_alive[g] = l.s.tri_alive[t];
            }
            if let Some(f) = &mut s.features {
                if let (Some(w), Some(vw)) = (&mut f.wedges, &f.vertex_wedge) {
                    for t in 0..l.s.tris.len() as u32 {
                        let g = l.tris.global(t) as usize;
                        w[g] = s.tris[g].map(|v| vw[v as usize]);
                    }
                }
            }
            let (d, (removed, collapses, passes, rejected)) = into_done(l);
            s.live_tris -= removed;
            s.stats.collapses += collapses;
            s.stats.passes = s.stats.passes.max(passes);
            add_rejections(&mut s.stats.rejected, &rejected);
            done.push(d);
        }
        done
    }

    /// Everything the write-backs and the held vertices' restore write.
    #[derive(Debug, PartialEq)]
    struct State {
        pos: Vec<[f32; 3]>,
        quadric: Vec<Quadric>,
        flags: Vec<[bool; 4]>,
        tris: Vec<[u32; 3]>,
        tri_alive: Vec<bool>,
        wedges: Option<Vec<[u32; 3]>>,
        counts: (usize, usize, usize, Rejections),
    }

    fn state(s: &Simplifier) -> State {
        let v = 0..s.pos.len();
        State {
            pos: s.pos.clone(),
            quadric: s.quadric.clone(),
            flags: v
                .map(|v| {
                    let lifted = s.lifted.get(v as u32);
                    [s.alive[v], s.boundary[v], s.corner[v], lifted]
                })
                .collect(),
            tris: s.tris.clone(),
            tri_alive: s.tri_alive.clone(),
            wedges: s.features.as_ref().and_then(|f| f.wedges.clone()),
            counts: (
                s.live_tris,
                s.stats.collapses,
                s.stats.passes,
                s.stats.rejected,
            ),
        }
    }

    /// `a` and `b` equal, else a panic naming the first field and element
    /// that differ (the arrays are too long to print).
    fn same(a: &State, b: &State, what: &str) {
        fn first<T: PartialEq + std::fmt::Debug>(what: &str, x: &[T], y: &[T]) {
            assert_eq!(x.len(), y.len(), "{what}: lengths");
            if let Some(i) = (0..x.len()).find(|&i| x[i] != y[i]) {
                panic!("{what}: element {i}: {:?} vs {:?}", x[i], y[i]);
            }
        }
        first(&format!("{what} positions"), &a.pos, &b.pos);
        first(&format!("{what} quadrics"), &a.quadric, &b.quadric);
        first(&format!("{what} vertex flags"), &a.flags, &b.flags);
        first(&format!("{what} triangles"), &a.tris, &b.tris);
        first(
            &format!("{what} live triangles"),
            &a.tri_alive,
            &b.tri_alive,
        );
        let none = Vec::new();
        let (wa, wb) = (a.wedges.as_ref(), b.wedges.as_ref());
        assert_eq!(wa.is_some(), wb.is_some(), "{what} wedges");
        first(
            &format!("{what} wedges"),
            wa.unwrap_or(&none),
            wb.unwrap_or(&none),
        );
        assert_eq!(a.counts, b.counts, "{what} counts");
        assert!(a == b, "{what}");
    }

    /// A cluster's vertices, triangles (a run's start or the list), log
    /// lengths at each round's end, and log length.
    type Kept = (Vec<u32>, Vec<u32>, Vec<u32>, usize);

    /// What the merge reads of each cluster.
    fn kept(done: &[Done]) -> Vec<Kept> {
        done.iter()
            .map(|d| {
                let tris = match &d.tris {
                    Tris::Run(start) => vec![*start],
                    Tris::List(ids) => ids.clone(),
                };
                (d.verts.clone(), tris, d.rounds.clone(), d.log.records.len())
            })
            .collect()
    }

    /// A grid of 72 clusters (five batches) to 1.5 %, with features and
    /// one wedge per vertex, the corners' wedges stored or not.
    fn simplifier(stored: bool) -> (Simplifier, usize, f32) {
        let m = shapes::grid(120, 120, |x, y| 0.1 * (7.0 * x).sin() * (5.0 * y).cos());
        let opts = SimplifyOptions::DEFAULT
            .with_target_ratio(0.015)
            .with_partition(Some(400));
        let mut s = Simplifier::new(&m, &opts).expect("a clean grid");
        s.set_feature_edges(&[]);
        s.set_wedges(m.triangles.clone());
        if stored {
            let f = s.features.as_mut().expect("features on");
            f.store_wedges(&m.triangles);
            assert!(f.wedges.is_some());
        }
        let size = s.partition_size().expect("a partitioned run");
        let Schedule::Passes { factor } = s.opts.schedule else {
            panic!("the pass schedule");
        };
        (s, size, factor)
    }

    /// Both stages' write-backs on every core (one thread and three) leave
    /// the whole mesh as the one-core loop does, and keep the same logs for
    /// the merge. Fails when a part misses the interior vertices at its
    /// bounds, a lift bit that changed is not set (or one is set that did
    /// not change), a triangle run is cut off by one, or a held vertex is
    /// not put back.
    #[test]
    fn write_back_is_the_one_core_loops() {
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a thread pool");
            for stored in [false, true] {
                pool.install(|| compare_write_backs(stored));
            }
        }
    }

    fn compare_write_backs(stored: bool) {
        let (mut a, size, factor) = simplifier(stored);
        let (mut b, ..) = simplifier(stored);
        let (la, ha) = a.first_stage(size, factor);
        let (lb, hb) = b.first_stage(size, factor);
        assert!(la.len() > 4 * WRITE_BATCH, "{} clusters", la.len());
        assert!(!ha.is_empty());
        // the clusters lifted some of their interior vertices
        let lifts = la
            .iter()
            .any(|l| (0..l.verts.len() as u32).any(|i| l.s.lifted.get(i)));
        assert!(lifts);
        let da = a.write_back(la);
        a.restore_held(ha);
        let db = write_back_serial(&mut b, lb);
        for (v, q, p) in hb {
            b.quadric[v] = q;
            b.pos[v] = p;
        }
        assert_eq!(kept(&da), kept(&db));
        same(
            &state(&a),
            &state(&b),
            &format!("first stage, stored {stored}:"),
        );
        a.merged(da);
        b.merged(db);
        // the coarse stage: lists of live triangles, lift bits set before
        let la = a.coarse_stage(size, factor).expect("a coarse stage");
        let lb = b.coarse_stage(size, factor).expect("a coarse stage");
        assert!(la.len() >= 4 && la.iter().all(|l| matches!(l.tris, Tris::List(_))));
        let da = a.write_back(la);
        let db = write_back_serial(&mut b, lb);
        assert_eq!(kept(&da), kept(&db));
        same(
            &state(&a),
            &state(&b),
            &format!("coarse stage, stored {stored}:"),
        );
    }

    /// The parts' bounds increase from 0 to the vertex count, also for a
    /// batch without vertices.
    #[test]
    fn part_bounds_cover_the_vertex_range() {
        let (mut s, size, factor) = simplifier(false);
        let nv = s.pos.len();
        let (locals, _) = s.first_stage(size, factor);
        for batch in locals.chunks(WRITE_BATCH) {
            let b = part_bounds(batch, nv);
            assert_eq!((b.len(), b[0], b[PARTS]), (PARTS + 1, 0, nv));
            assert!(b.windows(2).all(|w| w[0] <= w[1]), "{b:?}");
            // the batch's vertices are spread over several parts
            assert!(b.windows(2).filter(|w| w[0] < w[1]).count() > 2, "{b:?}");
        }
        assert_eq!(part_bounds(&[], nv), [0, nv]);
    }
}
