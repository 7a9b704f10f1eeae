//! The wedge payload of the vertex-split log: every corner's wedge at every
//! step, as explicit per-split edits ([`SplitWedges`]) or, when each vertex
//! has one wedge throughout the sequence, as one wedge per vertex from
//! which the edits follow.
//!
//! The second form is what a mesh without seams or attributes (a scan)
//! produces: its explicit edits took ~120 bytes per split, about half the
//! progressive mesh, where one `u32` per vertex says the same. It is chosen
//! in `from_log` only after checking (`one_wedge_per_vertex` in mod.rs) that every corner of the log, alive or
//! dead, agrees with it, so both forms give the same wedges everywhere.

use std::borrow::Cow;

use smallvec::SmallVec;

use super::split::VertexSplit;

/// The wedge payload of the log, parallel to the geometry: the caller's
/// attribute ids per corner, so a replay restores attributes exactly by
/// looking them up. Read a split's edits with [`WedgeLog::split`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WedgeLog {
    /// The wedges of `base.triangles`, corner by corner.
    pub base: Vec<[u32; 3]>,
    /// Parallel to `ProgressiveMesh::splits`; empty when `per_vertex` holds
    /// the log.
    pub splits: Vec<SplitWedges>,
    /// When every vertex has one wedge at every step: the wedge of each
    /// progressive vertex (a split's new faces take their vertices' wedges,
    /// its moved corners go from `v1`'s wedge to `v0`'s), and `splits` is
    /// empty.
    pub per_vertex: Option<Vec<u32>>,
}

/// The wedge edits of one vertex split.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SplitWedges {
    /// The wedges of the split's `faces`.
    pub faces: SmallVec<[[u32; 3]; 2]>,
    /// Parallel to the split's `corners`: `[wedge before the split (the
    /// collapsed state), wedge after it]`.
    pub corners: Vec<[u32; 2]>,
}

impl WedgeLog {
    /// The wedge edits of split `i` (`s`, the `i`-th split of the
    /// progressive mesh this log belongs to).
    pub fn split(&self, i: usize, s: &VertexSplit) -> Cow<'_, SplitWedges> {
        match &self.per_vertex {
            None => Cow::Borrowed(&self.splits[i]),
            Some(w) => Cow::Owned(SplitWedges {
                faces: s.faces.iter().map(|f| f.map(|v| w[v as usize])).collect(),
                corners: vec![[w[s.v1 as usize], w[s.v0 as usize]]; s.corners.len()],
            }),
        }
    }

    /// Applies split `i` (`s`) to the corners' wedges `cw`.
    pub(super) fn refine(&self, cw: &mut Vec<[u32; 3]>, i: usize, s: &VertexSplit) {
        match &self.per_vertex {
            None => {
                let e = &self.splits[i];
                cw.extend_from_slice(&e.faces);
                for (c, e) in s.corners.iter().zip(&e.corners) {
                    cw[c.triangle as usize][c.slot as usize] = e[1];
                }
            }
            Some(w) => {
                cw.extend(s.faces.iter().map(|f| f.map(|v| w[v as usize])));
                for c in &s.corners {
                    cw[c.triangle as usize][c.slot as usize] = w[s.v0 as usize];
                }
            }
        }
    }

    /// Undoes split `i` (`s`) on the corners' wedges `cw`.
    pub(super) fn coarsen(&self, cw: &mut Vec<[u32; 3]>, i: usize, s: &VertexSplit) {
        let before = |k: usize| match &self.per_vertex {
            None => self.splits[i].corners[k][0],
            Some(w) => w[s.v1 as usize],
        };
        for (k, c) in s.corners.iter().enumerate() {
            cw[c.triangle as usize][c.slot as usize] = before(k);
        }
        cw.truncate(cw.len() - s.faces.len());
    }
}
