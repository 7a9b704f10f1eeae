//! Feature edges and wedges: what keeps seams, material borders and hard
//! edges in place while the welded mesh is simplified.
//!
//! Topology runs on welded positions; attributes live on triangle corners.
//! A *wedge* (Hoppe 1999, "New quadric metric for simplifying meshes with
//! appearance attributes") is a caller's attribute id at a corner: a UV seam
//! or a hard edge is two wedges at one position. An edge is a *feature edge*
//! when the wedges differ across it at either end, when the caller says so
//! (`Simplifier::set_feature_edges`), or, once features are on (a seam or a
//! caller's feature edge), when it is an open border. Wedges without a seam
//! (one per vertex) turn no feature on.
//!
//! Vertices are classified by their number of feature edges, as in
//! meshoptimizer's `kCanCollapse` (manifold / border / seam / locked):
//!
//! | feature edges | kind | may be removed |
//! |---|---|---|
//! | 0 | [`Kind::Free`] | into any neighbour (pulled onto it if it is not free) |
//! | 1 | [`Kind::End`] | along its feature edge into the other end, or into a neighbour on a feature edge to that end |
//! | 2 | [`Kind::Line`] | only along one of its two feature edges, into the other end |
//! | 3+ | [`Kind::Corner`] | never (seam junctions stay put) |
//!
//! So a seam collapses only along itself, both sides at once (one welded
//! vertex carries both sides' corners), and two feature vertices joined by a
//! non-feature edge never merge (that would pinch the seam). A seam's end
//! shortens it: the end goes into its one feature neighbour, the seam stays
//! on its line; or it folds its seam onto another one from the same vertex
//! (`x–v0` onto `x–v1`, both feature edges, their triangle deleted). Held in
//! place, the ends starved a UV sphere, whose every pole triangle has a UV
//! of its own: each vertex of the rings next to the poles is the end of one
//! seam, and the rest of the sphere was cut down around those 2 × 32 fixed
//! vertices (14.7 % of the diagonal at 130 of 960 triangles, 1.2 % without
//! the UVs; meshoptimizer collapses them too: to it they are border
//! vertices). The corners of the removed end take the wedges of the other
//! end, sector by sector; an edge across which they now differ becomes a
//! feature edge (`Features::mark_seams`).
//!
//! Wedge tracking: when `v0` is contracted into `v1`, each corner of `v0`
//! takes the wedge `v1` has in the deleted triangle of its *sector* (the
//! triangles of `v0`'s fan reachable without crossing a feature edge). The
//! old and new wedge of each moved corner go into the log, so a replay
//! restores every corner's wedge exactly.
//!
//! Attribute error: Hoppe 1999 attribute quadrics per wedge, in
//! `attrquadric` (re-exported here as `AttributeCost`).
//!
//! Owns `Features` and [`Kind`]. The contraction rules
//! that consult them are in `collapse` (`target_of`, `check`, `contract`,
//! `entry`).

pub(crate) use crate::simplify::attrquadric::AttributeCost;
use crate::simplify::legality::Rejected;
use smallvec::SmallVec;

/// How a vertex may move, from its feature-edge count (module table).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Free,
    End,
    Line,
    Corner,
}

impl Kind {
    fn of(feature_edges: usize) -> Kind {
        match feature_edges {
            0 => Kind::Free,
            1 => Kind::End,
            2 => Kind::Line,
            _ => Kind::Corner,
        }
    }
}

/// Feature classification plus, optionally, per-corner wedges.
#[derive(Clone, Debug)]
pub(crate) struct Features {
    /// Vertex → its feature neighbours (feature and border edges).
    pub nbrs: Nbrs,
    pub kind: Vec<Kind>,
    /// Triangle → the wedge of each corner, when tracked and not
    /// `corners_implied`. Dead triangles keep the wedges they had when
    /// they died.
    pub wedges: Option<Vec<[u32; 3]>>,
    /// Wedges are tracked but not stored per corner: every corner's wedge
    /// is `vertex_wedge` of its vertex (`tris`), live or dead (a dead
    /// triangle's corners are never edited again). Saves 12 bytes per
    /// triangle (53 MB on a 4.4M-triangle scan) until a corner takes
    /// another wedge or something needs the array ([`Features::store_wedges`]).
    pub corners_implied: bool,
    /// Vertex → its wedge, when all corners of each vertex share one
    /// (positions-only input, no seam). It stays so: a contraction gives
    /// each corner of `v0` the wedge of `v1`, so `wedge_edits` needs no
    /// sectors and reads no corner's wedge.
    pub vertex_wedge: Option<Vec<u32>>,
    /// While every wedge edit so far was `[vertex_wedge[v0],
    /// vertex_wedge[v1]]`, the log stores none: they follow from
    /// `vertex_wedge` (≈ 4.5 edits of 8 bytes per contraction, 78 MB on a
    /// 4.4M-triangle scan). The first edit that differs writes them out
    /// (`Log::spell_out_wedges`) and clears this.
    pub edits_implied: bool,
}

/// One moved corner's wedge edit: `(triangle, [wedge before, wedge after])`.
pub(crate) type WedgeEdits = SmallVec<[(u32, [u32; 2]); 16]>;

impl Features {
    /// The border edges `borders` (`(a, b)`, `a < b`, sorted: the order
    /// the neighbour lists are filled in) as the first feature edges.
    /// `Simplifier::border_edges` finds them from the vertex fans.
    pub fn with_borders(nv: usize, borders: &[(u32, u32)]) -> Features {
        let mut f = Features {
            nbrs: Nbrs::new(nv),
            kind: vec![Kind::Free; nv],
            wedges: None,
            corners_implied: false,
            vertex_wedge: None,
            edits_implied: false,
        };
        for &(a, b) in borders {
            f.add(a, b);
        }
        f
    }

    /// Border edges of `tris` (edges of one use) as the first feature
    /// edges, by sorting every edge: the reference `with_borders` is
    /// checked against.
    #[cfg(test)]
    pub fn new(nv: usize, tris: &[[u32; 3]]) -> Features {
        Features::with_borders(nv, &sorted_borders(tris))
    }

    /// The feature state of the vertices `verts` (global ids, increasing)
    /// as a simplifier of those vertices alone numbers them (a cluster of
    /// `partition`): each keeps its kind and its feature neighbours among
    /// `verts`. Wedges are not carried (the cluster's log records none:
    /// with one wedge per vertex its edits are implied).
    pub fn restricted(&self, verts: &[u32]) -> Features {
        let mut nbrs = Nbrs::new(verts.len());
        for (i, &g) in verts.iter().enumerate() {
            for &x in &self.nbrs[g] {
                if let Ok(j) = verts.binary_search(&x) {
                    nbrs.push(i as u32, j as u32);
                }
            }
        }
        Features {
            nbrs,
            kind: verts.iter().map(|&g| self.kind[g as usize]).collect(),
            wedges: None,
            corners_implied: false,
            vertex_wedge: None,
            edits_implied: false,
        }
    }

    /// Mark `a–b` as a feature edge; `false` if it already was one.
    pub fn add(&mut self, a: u32, b: u32) -> bool {
        if a == b || self.nbrs[a].contains(&b) {
            return false;
        }
        self.nbrs.push(a, b);
        self.nbrs.push(b, a);
        for v in [a, b] {
            self.kind[v as usize] = Kind::of(self.nbrs[v].len());
        }
        true
    }

    /// The interior edges across which the wedges of `wedges` differ, by
    /// sorting every edge: the reference `Simplifier::seam_edges` is
    /// checked against.
    #[cfg(test)]
    pub fn seams(tris: &[[u32; 3]], wedges: &[[u32; 3]]) -> Vec<(u32, u32)> {
        let mut half = edge_uses(tris);
        half.sort_unstable();
        let wedge_at = |t: u32, v: u32| {
            let tri = tris[t as usize];
            let k = tri.iter().position(|&x| x == v).unwrap_or(0);
            wedges[t as usize][k]
        };
        let mut out = Vec::new();
        for run in half.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
            let (a, b) = (run[0].0, run[0].1);
            let differ = run[1..].iter().any(|u| {
                wedge_at(u.2, a) != wedge_at(run[0].2, a)
                    || wedge_at(u.2, b) != wedge_at(run[0].2, b)
            });
            if run.len() > 1 && differ {
                out.push((a, b));
            }
        }
        out
    }

    /// `v` never moves to a new position (it is on a feature line).
    #[inline]
    pub fn pinned(&self, v: u32) -> bool {
        self.kind[v as usize] != Kind::Free
    }

    /// `v` may not be the removed vertex of any contraction.
    #[inline]
    pub fn fixed(&self, v: u32) -> bool {
        self.kind[v as usize] == Kind::Corner
    }

    /// The feature rule for removing `v0` into `v1`.
    pub fn allows(&self, v0: u32, v1: u32) -> Result<(), Rejected> {
        match self.kind[v0 as usize] {
            Kind::Free => Ok(()),
            Kind::End | Kind::Line if self.nbrs[v0].contains(&v1) => Ok(()),
            // an end folds its seam onto a neighbour's: `v1` on a feature edge to the end's
            // one feature neighbour (the contraction deletes their triangle, or the link
            // test refuses it)
            Kind::End if self.nbrs[v1].contains(&self.nbrs[v0][0]) => Ok(()),
            Kind::End | Kind::Line | Kind::Corner => Err(Rejected::Feature),
        }
    }

    /// The new wedge of every corner of `v0` (contracted into `v1`) in the live, not removed
    /// triangles of `fan0` (sector by sector, module docs). Call before the
    /// contraction edits anything. Empty when wedges are not tracked.
    pub fn wedge_edits(
        &self,
        [v0, v1]: [u32; 2],
        tris: &[[u32; 3]],
        fan0: &[u32],
        fan1: &[u32],
        alive: &[bool],
        removed: &[u32],
    ) -> WedgeEdits {
        let mut out = WedgeEdits::new();
        if !self.tracked() {
            return out;
        }
        if let Some(vw) = &self.vertex_wedge {
            return uniform_edits(vw, [v0, v1], tris, fan0, fan1, alive, removed);
        }
        let Some(w) = &self.wedges else {
            return out;
        };
        let slot = |t: u32, v: u32| tris[t as usize].iter().position(|&x| x == v);
        let wedge = |t: u32, v: u32| slot(t, v).map(|k| w[t as usize][k]);
        let fan: SmallVec<[u32; 16]> = fan0
            .iter()
            .copied()
            .filter(|&t| alive[t as usize])
            .collect();
        // v1's wedge in each deleted triangle: what the corners of v0 take.
        let mut sector_wedge: SmallVec<[(usize, u32); 2]> = fan
            .iter()
            .enumerate()
            .filter(|(_, t)| removed.contains(t))
            .filter_map(|(i, &t)| wedge(t, v1).map(|x| (i, x)))
            .collect();
        // With one wedge among them every sector gets it (or, with none,
        // the fallback below), so the sectors are only needed when they
        // differ: the usual case without seams skips the union-find.
        let comp = if sector_wedge.windows(2).all(|p| p[0].1 == p[1].1) {
            SmallVec::new()
        } else {
            let comp = sectors(&fan, tris, v0, &self.nbrs[v0]);
            for s in &mut sector_wedge {
                s.0 = comp[s.0];
            }
            comp
        };
        // A sector without a deleted triangle (a τ-pair): v1's first wedge.
        let fallback = sector_wedge.first().map(|s| s.1).or_else(|| {
            fan1.iter()
                .filter(|&&t| alive[t as usize])
                .find_map(|&t| wedge(t, v1))
        });
        for (i, &t) in fan.iter().enumerate() {
            if removed.contains(&t) {
                continue;
            }
            let Some(old) = wedge(t, v0) else { continue };
            let new = comp
                .get(i)
                .and_then(|c| sector_wedge.iter().find(|s| s.0 == *c))
                .map(|s| s.1)
                .or(fallback)
                .unwrap_or(old);
            out.push((t, [old, new]));
        }
        out
    }

    /// Whether wedges are tracked (stored per corner or implied).
    pub fn tracked(&self) -> bool {
        self.wedges.is_some() || self.corners_implied
    }

    /// Tracked wedges from now on stored per corner: `wedges` is `Some`
    /// whenever they are tracked.
    pub fn store_wedges(&mut self, tris: &[[u32; 3]]) {
        if let (true, Some(vw)) = (self.corners_implied, &self.vertex_wedge) {
            self.wedges = Some(tris.iter().map(|t| t.map(|v| vw[v as usize])).collect());
            self.corners_implied = false;
        }
    }

    /// Corner `k` of triangle `t` (at vertex `tris[t][k]`) takes wedge `w`.
    pub fn set_corner_wedge(&mut self, tris: &[[u32; 3]], t: u32, k: usize, w: u32) {
        let v = tris[t as usize][k];
        if self.corners_implied && self.vertex_wedge.as_ref().map(|vw| vw[v as usize]) != Some(w) {
            self.store_wedges(tris);
        }
        if let Some(ws) = self.wedges.as_mut() {
            ws[t as usize][k] = w;
        }
    }

    /// Update the feature lines after `v0` merged into `v1`.
    pub fn contract(&mut self, v0: u32, v1: u32) {
        let moved = self.nbrs.take(v0);
        self.kind[v0 as usize] = Kind::Free;
        self.nbrs.retain(v1, |x| x != v0);
        for x in moved {
            if x == v1 {
                continue;
            }
            self.nbrs.retain(x, |y| y != v0);
            if !self.nbrs[x].contains(&v1) {
                self.nbrs.push(x, v1);
            }
            self.kind[x as usize] = Kind::of(self.nbrs[x].len());
            if !self.nbrs[v1].contains(&x) {
                self.nbrs.push(v1, x);
            }
        }
        self.kind[v1 as usize] = Kind::of(self.nbrs[v1].len());
    }

    /// `v` is the end of a seam or feature line (one feature edge).
    #[inline]
    pub fn is_end(&self, v: u32) -> bool {
        self.kind[v as usize] == Kind::End
    }

    /// After a seam's end went into `v1` (its corners took `v1`'s wedges, module docs): each
    /// edge of `v1`'s live fan `fan` across which the wedges now differ, at either end,
    /// becomes a feature edge, so the seam the corners' new wedges draw is held like any
    /// other. Nothing to do without wedges per corner (one wedge per vertex: no seam).
    pub fn mark_seams(&mut self, v1: u32, tris: &[[u32; 3]], fan: &[u32]) {
        let Some(w) = &self.wedges else {
            return;
        };
        let slot = |t: u32, v: u32| tris[t as usize].iter().position(|&x| x == v);
        let wedge = |t: u32, v: u32| slot(t, v).map(|k| w[t as usize][k]);
        let mut found: SmallVec<[u32; 4]> = SmallVec::new();
        for (i, &t) in fan.iter().enumerate() {
            for y in tris[t as usize] {
                if y == v1 || found.contains(&y) || self.nbrs[v1].contains(&y) {
                    continue;
                }
                let differ = fan[i + 1..].iter().any(|&u| {
                    slot(u, y).is_some()
                        && (wedge(u, y) != wedge(t, y) || wedge(u, v1) != wedge(t, v1))
                });
                if differ {
                    found.push(y);
                }
            }
        }
        for y in found {
            self.add(v1, y);
        }
    }

    /// After a contraction closed the triangular hole `v0 v1 o` (see
    /// `legality::closing_hole`), the merged edge `v1 o` is interior: it
    /// stops being a feature edge unless it can be a seam (wedges that
    /// differ within a vertex), so the closed hole's vertices may go on to
    /// be removed like any other.
    pub fn close_hole(&mut self, v1: u32, o: u32) {
        if self.wedges.is_some() && self.vertex_wedge.is_none() {
            return;
        }
        self.nbrs.retain(v1, |x| x != o);
        self.nbrs.retain(o, |x| x != v1);
        self.kind[v1 as usize] = Kind::of(self.nbrs[v1].len());
        self.kind[o as usize] = Kind::of(self.nbrs[o].len());
    }
}

/// Vertex → its feature neighbours, stored for the vertices that have
/// some: a slot per vertex (4 bytes) and a list per vertex with features,
/// where a list per vertex took 24 bytes each (53 MB on a 4.4M-triangle
/// scan, whose vertices have none).
#[derive(Clone, Debug)]
pub(crate) struct Nbrs {
    /// Vertex → its list in `lists`, `NO_LIST` while it has none.
    slot: Vec<u32>,
    lists: Vec<SmallVec<[u32; 4]>>,
}

const NO_LIST: u32 = u32::MAX;

impl Nbrs {
    fn new(nv: usize) -> Nbrs {
        Nbrs {
            slot: vec![NO_LIST; nv],
            lists: Vec::new(),
        }
    }

    fn list_mut(&mut self, v: u32) -> &mut SmallVec<[u32; 4]> {
        let s = &mut self.slot[v as usize];
        if *s == NO_LIST {
            *s = self.lists.len() as u32;
            self.lists.push(SmallVec::new());
        }
        &mut self.lists[*s as usize]
    }

    fn push(&mut self, v: u32, x: u32) {
        self.list_mut(v).push(x);
    }

    /// `v`'s neighbours, leaving it none.
    fn take(&mut self, v: u32) -> SmallVec<[u32; 4]> {
        match self.slot[v as usize] {
            NO_LIST => SmallVec::new(),
            s => std::mem::take(&mut self.lists[s as usize]),
        }
    }

    fn retain(&mut self, v: u32, keep: impl Fn(u32) -> bool) {
        if let Some(&s) = self.slot.get(v as usize).filter(|&&s| s != NO_LIST) {
            self.lists[s as usize].retain(|x| keep(*x));
        }
    }
}

impl std::ops::Index<u32> for Nbrs {
    type Output = [u32];
    fn index(&self, v: u32) -> &[u32] {
        match self.slot[v as usize] {
            NO_LIST => &[],
            s => &self.lists[s as usize],
        }
    }
}

/// [`Features::wedge_edits`] when every vertex has one wedge `vw[v]`:
/// the same edits (each live corner of `v0` but the removed triangles'
/// takes `v1`'s wedge; `v1`'s wedge too when no deleted triangle gives
/// one, if `v1` has a live triangle), without reading any corner's wedge.
fn uniform_edits(
    vw: &[u32],
    [v0, v1]: [u32; 2],
    tris: &[[u32; 3]],
    fan0: &[u32],
    fan1: &[u32],
    alive: &[bool],
    removed: &[u32],
) -> WedgeEdits {
    let old = vw[v0 as usize];
    let has_v1 = !removed.is_empty() || fan1.iter().any(|&t| alive[t as usize]);
    let new = if has_v1 { vw[v1 as usize] } else { old };
    fan0.iter()
        .filter(|&&t| alive[t as usize] && !removed.contains(&t))
        .filter(|&&t| tris[t as usize].contains(&v0))
        .map(|&t| (t, [old, new]))
        .collect()
}

/// Vertex → its wedge when all corners of each vertex share one (no seam
/// anywhere: positions-only input), else `None`. A vertex in no triangle
/// gets `u32::MAX`.
pub(crate) fn vertex_wedges(tris: &[[u32; 3]], wedges: &[[u32; 3]]) -> Option<Vec<u32>> {
    let nv = tris.iter().flatten().max().map_or(0, |&v| v as usize + 1);
    let mut first: Vec<u32> = vec![u32::MAX; nv];
    for (t, w) in tris.iter().zip(wedges) {
        for (&v, &x) in t.iter().zip(w) {
            match &mut first[v as usize] {
                slot if *slot == u32::MAX => *slot = x,
                y if *y != x => return None,
                _ => {}
            }
        }
    }
    Some(first)
}

/// The sectors of `v0`'s live fan: union-find over the fan's triangles,
/// joined across edges (v0, y) that are not feature edges (`feature`: v0's
/// feature neighbours); each triangle's label is its sector's lowest
/// index. Fans are small: a quadratic scan is cheapest.
fn sectors(fan: &[u32], tris: &[[u32; 3]], v0: u32, feature: &[u32]) -> SmallVec<[usize; 16]> {
    let mut comp: SmallVec<[usize; 16]> = (0..fan.len()).collect();
    let mut changed = true;
    while changed {
        changed = false;
        for i in 0..fan.len() {
            for j in i + 1..fan.len() {
                if comp[i] == comp[j] {
                    continue;
                }
                let (ti, tj) = (tris[fan[i] as usize], tris[fan[j] as usize]);
                let joined = ti
                    .iter()
                    .any(|&y| y != v0 && tj.contains(&y) && !feature.contains(&y));
                if joined {
                    let m = comp[i].min(comp[j]);
                    comp[i] = m;
                    comp[j] = m;
                    changed = true;
                }
            }
        }
    }
    comp
}

/// Every triangle edge as `(min, max, triangle)`.
/// The edges of one use in `tris`, `(a, b)`, `a < b`, sorted, by sorting
/// every edge (the reference for `Simplifier::border_edges`).
#[cfg(test)]
pub(crate) fn sorted_borders(tris: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut half = edge_uses(tris);
    half.sort_unstable();
    half.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1))
        .filter(|run| run.len() == 1)
        .map(|run| (run[0].0, run[0].1))
        .collect()
}

#[cfg(test)]
fn edge_uses(tris: &[[u32; 3]]) -> Vec<(u32, u32, u32)> {
    let mut half = Vec::with_capacity(3 * tris.len());
    for (i, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            half.push((a.min(b), a.max(b), i as u32));
        }
    }
    half
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn implied_corner_wedges_are_stored_once_a_corner_differs() {
        // two triangles on the quad 0-1-2-3, one wedge per vertex (10 + v)
        let mut tris = vec![[0, 1, 2], [0, 2, 3]];
        let mut f = Features::new(4, &tris);
        f.vertex_wedge = Some(vec![10, 11, 12, 13]);
        f.corners_implied = true;
        // corner 0 of triangle 1 moves to vertex 1 and takes vertex 1's
        // wedge: still implied, nothing stored
        tris[1][0] = 1;
        f.set_corner_wedge(&tris, 1, 0, 11);
        assert!(f.tracked() && f.wedges.is_none());
        // corner 2 of triangle 0 moves to vertex 3 but keeps its old wedge
        // (12, not 13): the array is stored, that corner edited
        tris[0][2] = 3;
        f.set_corner_wedge(&tris, 0, 2, 12);
        assert!(f.tracked() && !f.corners_implied);
        assert_eq!(f.wedges.as_deref(), Some(&[[10, 11, 12], [11, 12, 13]][..]));
    }
}
