//! The sweep engine of Algorithm 4: triangles visited flattest first,
//! collapsed with the chosen operator when legal, defects rolled back, every
//! operation recorded in the core's vertex-split log.

use super::curvature::{
    boundary_vertices, cross_normal, deviation, dv, fixed_vertices, fv, threshold_value,
    vertex_triangles,
};
use super::options::{
    AdaptiveOptions, AdaptiveReport, AdaptiveStop, Method, Reclassify, Repairs, PYRAMID_MAX_COS,
    REVERSED_MAX_COS,
};
use crate::mesh::Mesh;
use crate::progressive::{Log, ProgressiveMesh};
use crate::simplify::legality::{link, moved_faces_ok, Faces, Link, Rejected};
use crate::simplify::quadric::Quadric;
use crate::simplify::stats::{PhaseTimes, Rejections, Stats};
use glam::DVec3;
use smallvec::SmallVec;
use std::time::Instant;

/// The sweep engine: the live mesh (tombstoned triangles, per-vertex
/// triangle lists that keep dead entries until the next sweep so an
/// operation can be rolled back), quadrics (only to record each split's error
/// in the core's units), and the contraction log.
pub(super) struct Engine {
    method: Method,
    opts: AdaptiveOptions,
    target: usize,
    pos: Vec<[f32; 3]>,
    quadric: Vec<Quadric>,
    tris: Vec<[u32; 3]>,
    tri_alive: Vec<bool>,
    vtris: Vec<Vec<u32>>,
    alive: Vec<bool>,
    fixed: Vec<bool>,
    live_tris: usize,
    log: Log,
    /// `v1`'s quadric before each logged contraction (for rollback).
    saved_quadric: Vec<Quadric>,
    report: AdaptiveReport,
    stats: Stats,
}

impl Engine {
    pub(super) fn new(
        mesh: &Mesh,
        method: Method,
        opts: &AdaptiveOptions,
        target: usize,
    ) -> Engine {
        let t0 = Instant::now();
        let nv = mesh.positions.len();
        let vtris = vertex_triangles(mesh);
        let fixed = fixed_vertices(mesh, &vtris);
        let mut quadric = vec![Quadric::default(); nv];
        for t in &mesh.triangles {
            let n = cross_normal(&mesh.positions, t);
            let len = n.length();
            if len > 0.0 {
                let unit = n / len;
                let q = Quadric::from_plane(
                    unit,
                    -unit.dot(dv(mesh.positions[t[0] as usize])),
                    0.5 * len,
                );
                for &v in t {
                    quadric[v as usize] += q;
                }
            }
        }
        let fixed_count = fixed.iter().filter(|&&f| f).count();
        let stats = Stats {
            input_vertices: nv,
            input_triangles: mesh.triangles.len(),
            boundary_vertices: boundary_vertices(mesh).iter().filter(|&&b| b).count(),
            locked_vertices: fixed_count,
            time: PhaseTimes {
                setup: t0.elapsed(),
                ..PhaseTimes::default()
            },
            ..Stats::default()
        };
        Engine {
            method,
            opts: *opts,
            target,
            pos: mesh.positions.clone(),
            quadric,
            tris: mesh.triangles.clone(),
            tri_alive: vec![true; mesh.triangles.len()],
            vtris,
            alive: vec![true; nv],
            fixed,
            live_tris: mesh.triangles.len(),
            log: Log::default(),
            saved_quadric: Vec::new(),
            report: AdaptiveReport {
                method,
                stop: AdaptiveStop::Target,
                sweeps: 0,
                operations: 0,
                threshold: 0.0,
                high_curvature_vertices: 0,
                last_interior: 0,
                last_high: 0,
                last_candidates: 0,
                fixed_vertices: fixed_count,
                prevented: Rejections::default(),
                repaired: Repairs::default(),
            },
            stats,
        }
    }

    /// Algorithm 1, steps 2–4: classify, decimate, repeat.
    pub(super) fn run(&mut self) {
        let t0 = Instant::now();
        let mut limit = None;
        loop {
            if self.live_tris <= self.target {
                self.report.stop = AdaptiveStop::Target;
                break;
            }
            for ts in &mut self.vtris {
                ts.retain(|&t| self.tri_alive[t as usize]);
            }
            let movable: Vec<bool> = (0..self.pos.len())
                .map(|v| self.alive[v] && !self.fixed[v] && !self.vtris[v].is_empty())
                .collect();
            let theta = deviation(
                &self.pos,
                &self.tris,
                &self.tri_alive,
                &self.vtris,
                Some(&movable),
                self.opts.k_ring,
            );
            let thr = match (limit, self.opts.reclassify) {
                (Some(l), Reclassify::FixedThreshold) => l,
                _ => {
                    let vals: Vec<f64> = (0..theta.len())
                        .filter(|&v| movable[v])
                        .map(|v| theta[v])
                        .collect();
                    let l = threshold_value(&vals, self.opts.threshold);
                    if limit.is_none() {
                        self.report.threshold = l;
                        self.report.high_curvature_vertices =
                            vals.iter().filter(|&&x| x > l).count();
                    }
                    l
                }
            };
            limit = Some(thr);
            let removable: Vec<bool> = (0..theta.len())
                .map(|v| movable[v] && theta[v] <= thr)
                .collect();
            self.report.last_interior = movable.iter().filter(|&&m| m).count();
            self.report.last_high =
                self.report.last_interior - removable.iter().filter(|&&r| r).count();
            let key = |t: &[u32; 3]| t.iter().map(|&v| theta[v as usize]).fold(0.0, f64::max);
            let mut order: Vec<(f64, u32)> = (0..self.tris.len())
                .filter(|&t| self.tri_alive[t])
                .filter(|&t| {
                    let r = self.tris[t].map(|v| removable[v as usize]);
                    match self.method {
                        Method::Triangle => r.iter().all(|&x| x),
                        // two removable corners make a removable edge
                        _ => r.iter().filter(|&&x| x).count() >= 2,
                    }
                })
                .map(|t| (key(&self.tris[t]), t as u32))
                .collect();
            self.report.last_candidates = order.len();
            if order.is_empty() {
                self.report.stop = AdaptiveStop::Locked;
                break;
            }
            order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            self.report.sweeps += 1;
            let mut touched = vec![false; self.pos.len()];
            let mut done = 0;
            for &(_, t) in &order {
                if self.live_tris <= self.target {
                    break;
                }
                let t = t as usize;
                if !self.tri_alive[t] || self.tris[t].iter().any(|&v| touched[v as usize]) {
                    continue; // deleted, or frozen until the next sweep
                }
                if let Some(s) = self.operate(t, &removable, &theta) {
                    touched[s as usize] = true;
                    done += 1;
                }
            }
            self.report.operations += done;
            if done == 0 {
                self.report.stop = AdaptiveStop::Illegal;
                break;
            }
        }
        self.stats.time.collapse = t0.elapsed();
    }

    /// Apply the method's operator to triangle `t`; returns the surviving
    /// vertex on success.
    fn operate(&mut self, t: usize, removable: &[bool], theta: &[f64]) -> Option<u32> {
        let tri = self.tris[t];
        if self.method == Method::Triangle {
            let [a, b, c] = tri;
            let d =
                (dv(self.pos[a as usize]) + dv(self.pos[b as usize]) + dv(self.pos[c as usize]))
                    / 3.0;
            let mark = self.log.records.len();
            if self.try_contract(a, b, d) && self.try_contract(c, b, d) {
                if self.defects_ok(b, mark) {
                    return Some(b);
                }
            } else {
                self.rollback(mark);
            }
            return None;
        }
        // Edges of the triangle, shortest first (least displacement).
        let mut edges: SmallVec<[(f64, u32, u32); 3]> = (0..3)
            .map(|k| (tri[k], tri[(k + 1) % 3]))
            .filter(|&(x, y)| removable[x as usize] && removable[y as usize])
            .map(|(x, y)| {
                let l = (dv(self.pos[x as usize]) - dv(self.pos[y as usize])).length_squared();
                (l, x, y)
            })
            .collect();
        edges.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then((a.1, a.2).cmp(&(b.1, b.2))));
        for &(_, x, y) in &edges {
            let tries: SmallVec<[(u32, u32, DVec3); 2]> = match self.method {
                Method::Edge => {
                    let mid = (dv(self.pos[x as usize]) + dv(self.pos[y as usize])) * 0.5;
                    smallvec::smallvec![(y, x, mid)]
                }
                // remove the flatter endpoint first (it carries less shape),
                // the other one if that is illegal
                _ => {
                    let (keep, gone) = if theta[x as usize] < theta[y as usize] {
                        (y, x)
                    } else {
                        (x, y)
                    };
                    smallvec::smallvec![
                        (gone, keep, dv(self.pos[keep as usize])),
                        (keep, gone, dv(self.pos[gone as usize]))
                    ]
                }
            };
            for (v0, v1, p) in tries {
                let mark = self.log.records.len();
                if self.try_contract(v0, v1, p) && self.defects_ok(v1, mark) {
                    return Some(v1);
                }
            }
        }
        None
    }

    /// Check and, when legal, contract `v0` into `v1` at `p`.
    fn try_contract(&mut self, v0: u32, v1: u32, p: DVec3) -> bool {
        match self.check(v0, v1, p) {
            Ok(removed) => {
                self.contract(v0, v1, p, removed);
                true
            }
            Err(r) => {
                self.report.prevented.count(r);
                false
            }
        }
    }

    /// The core's legality rules, in its order: the edge must be interior
    /// with two triangles, link condition, flip ([`FLIP_MIN_COS`](crate::simplify::FLIP_MIN_COS)) and
    /// degeneracy ([`DEGENERATE_AREA_RATIO_SQ`](crate::simplify::DEGENERATE_AREA_RATIO_SQ)) of every moved triangle, no
    /// moved triangle landing on an existing one.
    fn check(&mut self, v0: u32, v1: u32, p: DVec3) -> Result<SmallVec<[u32; 2]>, Rejected> {
        let (i0, i1) = (v0 as usize, v1 as usize);
        if self.fixed[i0] || self.fixed[i1] {
            return Err(Rejected::Locked);
        }
        let faces = Faces {
            tris: &self.tris,
            alive: &self.tri_alive,
            vtris: self.vtris.as_slice(),
            pos: &self.pos,
        };
        let Link {
            shared,
            opposite,
            common,
        } = link(faces, v0, v1);
        if shared.len() != 2 || common != 2 || opposite[0] == opposite[1] {
            return Err(Rejected::Link);
        }
        moved_faces_ok(faces, v0, v1, p, &opposite, |_| None)?;
        Ok(shared)
    }

    /// Contract `v0` into `v1` at `p` and log it. `v0`'s triangle list is
    /// kept (for rollback); moved triangles are appended to `v1`'s.
    fn contract(&mut self, v0: u32, v1: u32, p: DVec3, removed: SmallVec<[u32; 2]>) {
        let (i0, i1) = (v0 as usize, v1 as usize);
        let q = self.quadric[i0] + self.quadric[i1];
        let cost = q.eval(p);
        let error = q.distance(cost);
        let mut record = self.log.begin(v0, v1, self.pos[i1], &removed, error as f32);
        for &t in &removed {
            self.tri_alive[t as usize] = false;
        }
        self.live_tris -= removed.len();
        for k in 0..self.vtris[i0].len() {
            let t = self.vtris[i0][k];
            if !self.tri_alive[t as usize] {
                continue;
            }
            if self
                .log
                .move_corner(&mut self.tris[t as usize], t, v0, v1)
                .is_some()
            {
                self.vtris[i1].push(t);
            }
        }
        self.pos[i1] = fv(p);
        self.saved_quadric.push(self.quadric[i1]);
        self.quadric[i1] = q;
        self.alive[i0] = false;
        record.moved.end = self.log.mark();
        self.log.records.push(record);
    }

    /// Undo the contractions logged after `mark`, newest first.
    fn rollback(&mut self, mark: usize) {
        while self.log.records.len() > mark {
            let Some(c) = self.log.records.last().cloned() else {
                break;
            };
            let (i0, i1) = (c.v0 as usize, c.v1 as usize);
            for k in self.log.moved(&c) {
                self.tris[k.triangle as usize][k.slot as usize] = c.v0;
            }
            for &t in self.log.removed(&c) {
                self.tri_alive[t as usize] = true;
            }
            self.live_tris += c.removed.len();
            self.log.pop();
            let keep = self.vtris[i1].len() - c.moved.len();
            self.vtris[i1].truncate(keep);
            self.pos[i1] = c.p1;
            self.alive[i0] = true;
            if let Some(q) = self.saved_quadric.pop() {
                self.quadric[i1] = q;
            }
        }
    }

    /// Algorithm 5 after an operation with survivor `s`: look for spikes,
    /// pyramids and reversed faces around it; if any, roll back to `mark`,
    /// count the repair and return false.
    fn defects_ok(&mut self, s: u32, mark: usize) -> bool {
        let live: SmallVec<[u32; 16]> = self.vtris[s as usize]
            .iter()
            .copied()
            .filter(|&t| self.tri_alive[t as usize])
            .collect();
        // spikes: two triangles on the same three vertices
        let mut keys: SmallVec<[[u32; 3]; 16]> = live
            .iter()
            .map(|&t| {
                let mut k = self.tris[t as usize];
                k.sort_unstable();
                k
            })
            .collect();
        keys.sort_unstable();
        if keys.windows(2).any(|w| w[0] == w[1]) {
            self.rollback(mark);
            self.report.repaired.spikes += 1;
            return false;
        }
        // reversed: a face against its umbrella's area-weighted normal
        let normals: SmallVec<[DVec3; 16]> = live
            .iter()
            .map(|&t| cross_normal(&self.pos, &self.tris[t as usize]))
            .collect();
        let umbrella: DVec3 = normals.iter().copied().sum();
        if normals
            .iter()
            .any(|n| n.dot(umbrella) < REVERSED_MAX_COS * n.length() * umbrella.length())
        {
            self.rollback(mark);
            self.report.repaired.reversed += 1;
            return false;
        }
        // pyramids: the survivor or a neighbour left with three faces, one
        // folded over the other two
        let mut ring: SmallVec<[u32; 16]> =
            live.iter().flat_map(|&t| self.tris[t as usize]).collect();
        ring.sort_unstable();
        ring.dedup();
        for &v in &ring {
            if self.fixed[v as usize] {
                continue;
            }
            let fan: SmallVec<[DVec3; 4]> = self.vtris[v as usize]
                .iter()
                .filter(|&&t| self.tri_alive[t as usize])
                .take(4)
                .map(|&t| cross_normal(&self.pos, &self.tris[t as usize]).normalize_or_zero())
                .collect();
            if fan.len() == 3
                && (0..3).any(|i| {
                    let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                    fan[i].dot(fan[j]) < PYRAMID_MAX_COS && fan[i].dot(fan[k]) < PYRAMID_MAX_COS
                })
            {
                self.rollback(mark);
                self.report.repaired.pyramids += 1;
                return false;
            }
        }
        true
    }

    pub(super) fn finish(mut self) -> (ProgressiveMesh, Stats, AdaptiveReport) {
        let t0 = Instant::now();
        self.stats.collapses = self.log.records.len();
        let pm = ProgressiveMesh::from_log(
            &self.pos,
            &self.tris,
            &self.alive,
            &self.tri_alive,
            &mut self.log,
            None,
            None,
        );
        self.stats.output_triangles = self.live_tris;
        self.stats.output_vertices = pm.base.positions.len();
        self.stats.rejected = self.report.prevented;
        self.stats.time.log = t0.elapsed();
        (pm, self.stats, self.report)
    }
}
