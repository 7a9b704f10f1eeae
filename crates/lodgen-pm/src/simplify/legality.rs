//! Legality of a contraction, shared by [`super::Simplifier`] and the
//! curvature-adaptive sweeps: the link condition (the result stays
//! manifold), no flipped or sliver faces, no duplicate faces. Owns
//! [`Rejected`], which the feature rules use too.

use crate::mesh::adjacency::FanLookup;
use crate::util::with_marks;
use glam::DVec3;
use smallvec::SmallVec;

#[inline]
fn dv(p: [f32; 3]) -> DVec3 {
    DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]))
}

/// A moved triangle whose new normal is turned more than ≈75.5° from its old
/// one (cos < 0.25) counts as flipped. A pure 90° test (cos < 0) lets chains
/// of collapses that each turn a face by 80–89° fold the surface over.
pub const FLIP_MIN_COS: f64 = 0.25;

/// A moved triangle whose area shrinks below this fraction of its old area
/// (squared-normal ratio 1e-12 ≈ area ratio 1e-6) becomes a sliver that
/// breaks normals and later flip tests.
pub const DEGENERATE_AREA_RATIO_SQ: f64 = 1e-12;

/// Why a candidate contraction was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rejected {
    /// Both vertices are locked (boundary lock, non-manifold).
    Locked,
    /// The link condition fails: the one-rings share a vertex that is not
    /// opposite the edge (the result would be non-manifold).
    Link,
    /// Two border vertices joined by an interior edge (would pinch).
    BoundaryPinch,
    /// A moved triangle's normal turns by more than the flip threshold.
    Flip,
    /// A moved triangle would lose (nearly) all its area.
    Degenerate,
    /// A moved triangle would land on an existing one: a tetrahedron or a
    /// small closed component flattening into a double-sided sheet.
    Duplicate,
    /// The contraction's error exceeds `max_error`.
    Error,
    /// A feature vertex (seam, material border, hard edge) would leave its
    /// feature line, or a seam junction would be removed (see `features`).
    Feature,
}

/// How far [`crate::SimplifyOptions::topology_change`] has relaxed
/// the rules of a run that found no legal contraction: each stage lets one
/// more kind of refusal pass, and those of the stages before it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Relax {
    /// Every rule holds.
    #[default]
    None,
    /// Non-manifold joins: [`Rejected::Link`], [`Rejected::BoundaryPinch`].
    Joins,
    /// Closed parts flattened into sheets: [`Rejected::Duplicate`].
    Sheets,
    /// Feature vertices off their lines: [`Rejected::Feature`].
    Features,
    /// Faces turned over or collapsed: [`Rejected::Flip`],
    /// [`Rejected::Degenerate`].
    Flips,
}

impl Relax {
    /// The stage after this one (`None` after the last).
    pub fn next(self) -> Option<Relax> {
        match self {
            Relax::None => Some(Relax::Joins),
            Relax::Joins => Some(Relax::Sheets),
            Relax::Sheets => Some(Relax::Features),
            Relax::Features => Some(Relax::Flips),
            Relax::Flips => None,
        }
    }

    /// Whether a contraction refused for `r` may go on at this stage
    /// (never for [`Rejected::Locked`] or [`Rejected::Error`]: the user's
    /// locked border and error bound hold).
    pub fn allows(self, r: Rejected) -> bool {
        self >= match r {
            Rejected::Link | Rejected::BoundaryPinch => Relax::Joins,
            Rejected::Duplicate => Relax::Sheets,
            Rejected::Feature => Relax::Features,
            Rejected::Flip | Rejected::Degenerate => Relax::Flips,
            Rejected::Locked | Rejected::Error => return false,
        }
    }
}

/// The mesh state the legality tests read (shared by `Simplifier` and the
/// curvature-adaptive sweeps).
pub(crate) struct Faces<'a, F: FanLookup + ?Sized> {
    pub tris: &'a [[u32; 3]],
    pub alive: &'a [bool],
    pub vtris: &'a F,
    pub pos: &'a [[f32; 3]],
}

// (by hand: a derive would ask `F: Copy`, and `F` is only borrowed)
impl<F: FanLookup + ?Sized> Clone for Faces<'_, F> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<F: FanLookup + ?Sized> Copy for Faces<'_, F> {}

/// What the link condition of contracting `v0` into `v1` reads: the live
/// triangles on both (deleted by the contraction), their third vertices,
/// and how many distinct vertices besides the two are on both one-rings.
/// The condition holds when `common == shared.len()` and the opposite
/// vertices differ ([`Link::holds`]): the common neighbours are exactly the
/// opposite vertices, for an edge of any number of faces (two inside a
/// surface, one on its border, three or more where sheets meet along a
/// non-manifold edge).
pub(crate) struct Link {
    pub shared: SmallVec<[u32; 2]>,
    pub opposite: SmallVec<[u32; 2]>,
    pub common: usize,
}

impl Link {
    /// The vertex half of the link condition (Dey et al. 1999, "Topology
    /// preserving edge contraction"): the one-rings of `v0` and `v1` share
    /// the opposite vertices and nothing else, and these are distinct (two
    /// faces on the edge with one third vertex are a duplicate face). The
    /// edge half (no edge `o_i o_j` on both one-rings, or two moved faces
    /// would coincide) is `moved_faces_ok`'s duplicate test, and the border
    /// half (both ends on a border, joined by an edge that is not a border
    /// edge, would pinch) is the caller's.
    pub fn holds(&self) -> bool {
        let o = &self.opposite;
        self.common == self.shared.len() && (1..o.len()).all(|i| !o[..i].contains(&o[i]))
    }
}

/// The [`Link`] of `v0` and `v1` (on this thread's vertex marks: it only
/// reads the mesh, so that the batched walk can run it on many pairs).
pub(crate) fn link<F: FanLookup + ?Sized>(f: Faces<'_, F>, v0: u32, v1: u32) -> Link {
    let mut shared: SmallVec<[u32; 2]> = SmallVec::new();
    let mut opposite: SmallVec<[u32; 2]> = SmallVec::new();
    let common = with_marks(f.pos.len(), |mark, g| {
        // the one-ring of v0 gets g, its vertices also on v1's get g + 1
        for &t in f.vtris.fan(v0) {
            if !f.alive[t as usize] {
                continue;
            }
            let tri = f.tris[t as usize];
            if tri.contains(&v1) {
                shared.push(t);
                if let Some(&o) = tri.iter().find(|&&x| x != v0 && x != v1) {
                    opposite.push(o);
                }
            }
            for &x in &tri {
                mark[x as usize] = g;
            }
        }
        let mut common = 0;
        for &t in f.vtris.fan(v1) {
            if !f.alive[t as usize] {
                continue;
            }
            for &x in &f.tris[t as usize] {
                if x != v1 && x != v0 && mark[x as usize] == g {
                    mark[x as usize] = g + 1; // count each once
                    common += 1;
                }
            }
        }
        common
    });
    // a triangular hole v0 v1 o: o is on both one-rings without a face on
    // the edge, and closing the hole keeps the surface manifold
    let common = if shared.len() == 1 && common == 2 && closing_hole(f, v0, v1).is_some() {
        1
    } else {
        common
    };
    Link {
        shared,
        opposite,
        common,
    }
}

/// The third vertex `o` of a triangular hole `v0 v1 o` that contracting the
/// border edge `v0 v1` closes, if it does: the edge has one live face, whose
/// third vertex is not `o`; `v0 o` and `v1 o` are border edges (one live face
/// each) whose faces' third vertices differ (else the two faces would land
/// on each other). The merged edge `v1 o` then has two faces: the result is
/// manifold, one border loop fewer. The link condition refuses this (`o` is
/// on both one-rings, not opposite the edge), so without it every hole kept
/// at least three border vertices: beetle.obj's 23 border loops stopped its
/// 2 % level at 166–174 triangles with Hausdorff 10.7–12.2 % of the
/// diagonal, where meshoptimizer closes its small holes and spends the
/// triangles on the large border (2.26 % at 165 triangles).
pub(crate) fn closing_hole<F: FanLookup + ?Sized>(
    f: Faces<'_, F>,
    v0: u32,
    v1: u32,
) -> Option<u32> {
    // (third vertex of each live face on v, as (other corner, third) pairs)
    let faces_of = |v: u32| {
        f.vtris.fan(v).iter().filter_map(move |&t| {
            let tri = f.tris[t as usize];
            (f.alive[t as usize] && tri.contains(&v)).then_some(tri)
        })
    };
    let mut opposite = None;
    for tri in faces_of(v0).filter(|tri| tri.contains(&v1)) {
        if opposite.is_some() {
            return None; // an interior edge
        }
        opposite = tri.iter().copied().find(|&x| x != v0 && x != v1);
    }
    let opposite = opposite?;
    // the faces on the edge (v, o): Some(third vertex) when exactly one
    let single = |v: u32, o: u32| -> Option<u32> {
        let mut it = faces_of(v).filter(|tri| tri.contains(&o));
        let tri = it.next()?;
        if it.next().is_some() {
            return None;
        }
        tri.iter().copied().find(|&x| x != v && x != o)
    };
    let mut found = None;
    for tri in faces_of(v0) {
        for o in tri {
            if o == v0 || o == v1 || o == opposite || found == Some(o) {
                continue;
            }
            let Some(y0) = single(v0, o) else { continue };
            let Some(y1) = single(v1, o) else { continue };
            if y0 != y1 && y0 != v1 && y1 != v0 {
                if found.is_some() {
                    return None;
                }
                found = Some(o);
            }
        }
    }
    found
}

/// Whether contracting `v0` into `v1` would merge two edges of three or
/// more faces into one: `(v0, o)` and `(v1, o)` for an opposite vertex `o`
/// (a triangle `v0 v1 o` with sheets meeting along both other edges). The
/// link condition allows it, but the merged edge gets the faces of both
/// (four or more: beetle.obj's chains of edges of three faces that turn
/// around a triangle would fuse), so the contraction is refused.
pub(crate) fn fuses_odd_edges<F: FanLookup + ?Sized>(
    f: Faces<'_, F>,
    v0: u32,
    v1: u32,
    opposite: &[u32],
) -> bool {
    let faces_on = |v: u32, o: u32| {
        f.vtris
            .fan(v)
            .iter()
            .filter(|&&t| {
                let tri = f.tris[t as usize];
                f.alive[t as usize] && tri.contains(&v) && tri.contains(&o)
            })
            .count()
    };
    opposite
        .iter()
        .any(|&o| faces_on(v0, o) >= 3 && faces_on(v1, o) >= 3)
}

/// Whether a face of `v0` that does not hold `v1` would land on a face of
/// `v1` once `v0` is contracted into `v1`: a face `v0 x y` beside a
/// `v1 x y`, for any `x` and `y` (the general duplicate test, for a
/// contraction the link condition does not hold for; with it,
/// `moved_faces_ok` tests the opposite vertices only).
pub(crate) fn lands_on_any<F: FanLookup + ?Sized>(f: Faces<'_, F>, v0: u32, v1: u32) -> bool {
    let live = |v: u32| {
        f.vtris.fan(v).iter().filter_map(move |&t| {
            let tri = f.tris[t as usize];
            (f.alive[t as usize] && tri.contains(&v)).then_some(tri)
        })
    };
    live(v0).filter(|tri| !tri.contains(&v1)).any(|tri| {
        let mut o = tri.iter().copied().filter(|&x| x != v0);
        let (x, y) = (o.next(), o.next());
        live(v1).any(|u| x.is_some_and(|x| u.contains(&x)) && y.is_some_and(|y| u.contains(&y)))
    })
}

/// Whether `v` has an open border edge (one live face) in its fan.
pub(crate) fn on_border<F: FanLookup + ?Sized>(f: Faces<'_, F>, v: u32) -> bool {
    let live: SmallVec<[[u32; 3]; 16]> = f
        .vtris
        .fan(v)
        .iter()
        .filter(|&&t| f.alive[t as usize] && f.tris[t as usize].contains(&v))
        .map(|&t| f.tris[t as usize])
        .collect();
    live.iter().any(|tri| {
        tri.iter()
            .filter(|&&x| x != v)
            .any(|&x| live.iter().filter(|t| t.contains(&x)).count() == 1)
    })
}

/// Whether a face with corners `b`, `c` and a corner moving from `from` to
/// `to` keeps its orientation (turns by less than [`FLIP_MIN_COS`]) and
/// its area ([`DEGENERATE_AREA_RATIO_SQ`]).
#[inline]
pub(crate) fn turn_ok(from: DVec3, to: DVec3, b: DVec3, c: DVec3) -> Result<(), Rejected> {
    let bc = c - b;
    let n_old = (b - from).cross(bc);
    let n_new = (b - to).cross(bc);
    let (l_old, l_new) = (n_old.length_squared(), n_new.length_squared());
    if l_old > 0.0 {
        if l_new <= DEGENERATE_AREA_RATIO_SQ * l_old {
            return Err(Rejected::Degenerate);
        }
        // cos < FLIP_MIN_COS, without a square root: a negative dot
        // product is a flip, else compare squares
        let d = n_old.dot(n_new);
        if d < 0.0 || d * d < FLIP_MIN_COS * FLIP_MIN_COS * (l_old * l_new) {
            return Err(Rejected::Flip);
        }
    }
    Ok(())
}

/// The geometric legality of contracting `v0` into `v1` at `p`, `shared`
/// being the triangles on both (deleted) and `opposite` their third
/// vertices, once the link condition holds: no moved face may flip (turn
/// by more than [`FLIP_MIN_COS`]) or collapse to a sliver
/// ([`DEGENERATE_AREA_RATIO_SQ`]), and no moved face may land on an
/// existing one (a tetrahedron or small closed part flattening into a
/// sheet).
///
/// `p` is taken as stored (rounded to `f32`), so that the test holds for
/// the positions the mesh and its log keep. `logged` gives the position the
/// log records for a vertex whose logged position differs from its working
/// one (a lifted vertex, `lift.rs`), else `None`: a moved face with such a
/// corner is tested in the logged positions too (the log's levels must
/// hold the rule, not only the simplifier's working mesh).
pub(crate) fn moved_faces_ok<F: FanLookup + ?Sized>(
    f: Faces<'_, F>,
    v0: u32,
    v1: u32,
    p: DVec3,
    opposite: &[u32],
    logged: impl Fn(u32) -> Option<DVec3>,
) -> Result<(), Rejected> {
    let p = dv(p.as_vec3().to_array());
    for (moving, other) in [(v0, v1), (v1, v0)] {
        let pm = dv(f.pos[moving as usize]);
        let lm = logged(moving);
        if pm == p && lm.is_none() {
            continue; // (a half-edge survivor) its faces do not move
        }
        for &t in f.vtris.fan(moving) {
            if !f.alive[t as usize] {
                continue;
            }
            let tri = f.tris[t as usize];
            // the two other corners, in the triangle's winding order
            let (b, c) = match tri {
                [x, b, c] | [c, x, b] | [b, c, x] if x == moving => (b, c),
                _ => continue, // (not on `moving`: a dead vertex's stale list)
            };
            if b == other || c == other {
                continue;
            }
            let (lb, lc) = (logged(b), logged(c));
            let (b, c) = (dv(f.pos[b as usize]), dv(f.pos[c as usize]));
            if pm != p {
                turn_ok(pm, p, b, c)?;
            }
            if lm.is_some() || lb.is_some() || lc.is_some() {
                turn_ok(lm.unwrap_or(pm), p, lb.unwrap_or(b), lc.unwrap_or(c))?;
            }
        }
    }
    // With the link condition, a moved face `v0 x y` can only land on an
    // existing `v1 x y` when x and y are two of the opposite vertices.
    let lands = |o1: u32, o2: u32| {
        let has_face = |v: u32| {
            f.vtris.fan(v).iter().any(|&t| {
                let tri = f.tris[t as usize];
                f.alive[t as usize] && tri.contains(&o1) && tri.contains(&o2)
            })
        };
        has_face(v0) && has_face(v1)
    };
    let duplicate = match *opposite {
        [] | [_] => false,
        // (the usual interior edge, apart: the loop below cost +6 % here)
        [o1, o2] => lands(o1, o2),
        _ => {
            (0..opposite.len()).any(|i| opposite[i + 1..].iter().any(|&o2| lands(opposite[i], o2)))
        }
    };
    if duplicate {
        return Err(Rejected::Duplicate);
    }
    Ok(())
}

/// Edge-connected fans of triangles around `v` (1 for a manifold vertex).
pub(crate) fn fan_count(tris: &[[u32; 3]], v: u32, ts: &[u32]) -> usize {
    let n = ts.len();
    if n <= 1 {
        return n;
    }
    let others = |t: u32| -> [u32; 2] {
        let tri = tris[t as usize];
        let k = tri.iter().position(|&x| x == v).unwrap_or(0);
        [tri[(k + 1) % 3], tri[(k + 2) % 3]]
    };
    let mut comp: SmallVec<[u32; 16]> = (0..n as u32).collect();
    let mut changed = true;
    while changed {
        changed = false;
        for i in 0..n {
            let oi = others(ts[i]);
            for j in i + 1..n {
                let oj = others(ts[j]);
                if oi.iter().any(|x| oj.contains(x)) && comp[i] != comp[j] {
                    let m = comp[i].min(comp[j]);
                    comp[i] = m;
                    comp[j] = m;
                    changed = true;
                }
            }
        }
    }
    comp.sort_unstable();
    comp.dedup();
    comp.len()
}
