//! One contraction: `v0` into `v1`, recorded in the vertex-split log, with
//! fans, features, attribute quadrics, τ partners and (greedy) the heap
//! brought up to date.

use super::{fv, Plan, Simplifier};
use crate::mesh::adjacency::FanLookup;
use crate::simplify::features::WedgeEdits;
use crate::simplify::legality::{closing_hole, on_border, Faces};
use crate::simplify::Schedule;

impl Simplifier {
    /// Contract `v0` into `v1` at `p`, record it, and re-queue `v1`'s pairs.
    pub(super) fn contract(&mut self, plan: Plan) {
        let Plan {
            v0,
            v1,
            p,
            error,
            removed,
            broke,
            ..
        } = plan;
        if let Some(r) = broke {
            self.stats.relaxed.count(r);
            self.pass.refused += 1;
        }
        let (i0, i1) = (v0 as usize, v1 as usize);
        let merged = fv(p);
        let edits = self.features.as_ref().map(|f| {
            let e = f.wedge_edits(
                [v0, v1],
                &self.tris,
                self.vtris.fan(v0),
                self.vtris.fan(v1),
                &self.tri_alive,
                &removed,
            );
            (e, f.tracked())
        });
        // a border edge whose contraction closes a triangular hole
        let hole = if removed.len() == 1 && self.boundary[i0] && self.boundary[i1] {
            closing_hole(self.faces(), v0, v1)
        } else {
            None
        };
        // (the positions the log records: `lift.rs`)
        let liftable = self.liftable(v0, v1);
        let logged = [v0, v1].map(|v| self.logged_position(v));
        let mut record = self.log.begin(v0, v1, logged[1], &removed, error);
        for &t in &removed {
            self.tri_alive[t as usize] = false;
        }
        self.live_tris -= removed.len();
        // (`v1`'s faces before `v0`'s in its new fan: `settle_lift`)
        let own = if liftable {
            let fan = self.vtris.fan(v1).iter();
            fan.filter(|&&t| self.tri_alive[t as usize]).count()
        } else {
            0
        };
        self.move_fan(v0, v1, &edits);
        self.pos[i1] = merged;
        let q0 = self.quadric[i0];
        self.quadric[i1] += q0;
        self.alive[i0] = false;
        if let Some(v) = self.version.get_mut(i1) {
            *v = v.wrapping_add(1);
        }
        self.boundary[i1] |= self.boundary[i0];
        self.corner[i1] |= self.corner[i0];
        if let Some(f) = &mut self.features {
            let end = f.is_end(v0);
            f.contract(v0, v1);
            if end {
                f.mark_seams(v1, &self.tris, self.vtris.fan(v1));
            }
        }
        if let Some(o) = hole {
            if let Some(f) = &mut self.features {
                f.close_hole(v1, o);
            }
            self.boundary[i1] = on_border(self.faces(), v1);
            self.boundary[o as usize] = on_border(self.faces(), o);
        }
        if let Some(at) = &mut self.attributes {
            let w = self.features.as_ref().and_then(|f| f.wedges.as_deref());
            let e = edits.as_ref().map_or(&[][..], |e| &e.0[..]);
            at.contract(v0, v1, &removed, e, &self.tris, w);
        }
        self.merge_partners(v0, v1);
        self.settle_lift(v0, logged, v1, liftable, own);
        record.moved.end = self.log.mark();
        self.log.records.push(record);
        self.stats.collapses += 1;
        if self.opts.schedule == Schedule::Greedy {
            self.requeue(v1);
        }
    }

    /// `v1`'s new fan: its live triangles, then `v0`'s moved ones (whose
    /// `v0` corner becomes `v1`, logged with its wedge edit if wedges are
    /// tracked).
    fn move_fan(&mut self, v0: u32, v1: u32, edits: &Option<(WedgeEdits, bool)>) {
        // v1's new fan: its live triangles, then v0's moved ones
        let mut into = std::mem::take(&mut self.fan_scratch);
        into.clear();
        into.extend(
            self.vtris
                .fan(v1)
                .iter()
                .copied()
                .filter(|&t| self.tri_alive[t as usize]),
        );
        // (the edits are in the order of the corners moved here: the live
        // triangles of v0's fan but the removed ones, on v0)
        let mut next = 0;
        for &t in self.vtris.fan(v0) {
            if !self.tri_alive[t as usize] {
                continue;
            }
            if let Some(k) = self.log.move_corner(&mut self.tris[t as usize], t, v0, v1) {
                into.push(t);
                if let (Some((edits, true)), Some(f)) = (&edits, &mut self.features) {
                    let e = match edits.get(next) {
                        Some(e) if e.0 == t => e.1,
                        _ => edits.iter().find(|e| e.0 == t).map_or([0; 2], |e| e.1),
                    };
                    next += 1;
                    f.set_corner_wedge(&self.tris, t, k, e[1]);
                    match (&f.vertex_wedge, f.edits_implied) {
                        (Some(vw), true) if e == [vw[v0 as usize], vw[v1 as usize]] => {}
                        (Some(vw), true) => {
                            self.log.spell_out_wedges(vw, [v0, v1]);
                            f.edits_implied = false;
                            self.log.wedges.push(e);
                        }
                        _ => self.log.wedges.push(e),
                    }
                }
            }
        }
        self.vtris.set(v1, &into);
        self.fan_scratch = into;
    }

    /// `v1` takes `v0`'s τ partners (but themselves and dead ones).
    fn merge_partners(&mut self, v0: u32, v1: u32) {
        let (i0, i1) = (v0 as usize, v1 as usize);
        if !self.partners(v0).is_empty() || !self.partners(v1).is_empty() {
            let mut p = std::mem::take(&mut self.partners[i0]);
            p.append(&mut self.partners[i1]);
            p.retain(|&x| x != v1 && x != v0 && self.alive[x as usize]);
            p.sort_unstable();
            p.dedup();
            self.partners[i1] = p;
        }
    }

    /// [`Schedule::Greedy`]: re-queue every pair of `v1`, its edge
    /// neighbours and τ partners.
    fn requeue(&mut self, v1: u32) {
        let i1 = v1 as usize;
        let g = self.next_generation();
        let mut ns = std::mem::take(&mut self.scratch);
        ns.clear();
        if self.vtris.bloated() {
            self.vtris.rebuild(&self.tris, &self.tri_alive);
        }
        for &t in self.vtris.fan(v1) {
            for &x in &self.tris[t as usize] {
                if x != v1 && self.mark[x as usize] != g {
                    self.mark[x as usize] = g;
                    ns.push(x);
                }
            }
        }
        for &x in self.partners.get(i1).map_or(&[][..], |p| &p[..]) {
            if self.mark[x as usize] != g {
                self.mark[x as usize] = g;
                ns.push(x);
            }
        }
        for &x in &ns {
            if !(self.locked[i1] && self.locked[x as usize]) {
                let e = self.entry(v1, x);
                self.heap.push(e);
            }
        }
        self.scratch = ns;
    }

    /// The mesh state the legality tests read.
    pub(super) fn faces(&self) -> Faces<'_, crate::mesh::adjacency::Fans> {
        Faces {
            tris: &self.tris,
            alive: &self.tri_alive,
            vtris: &self.vtris,
            pos: &self.pos,
        }
    }
}
